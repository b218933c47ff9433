// The Texture index and the model list, once per page. The trained index
// (assets/texture-index.bin) is fetched once per page, only when this tool
// opens, and parsed once per worker (`texture-index`): analysis and
// retrieval go to the worker that holds it (`affinity`), and a worker that
// does not (replaced after a crash, or another one) answers an error on
// field `index`, so the index is sent again and the request retried.

const INDEX_URL = new URL('../../assets/texture-index.bin', import.meta.url);
const AFFINITY = 'texture-index';

let indexBytes = null; // Promise<Uint8Array>
let indexInfo = null; // Promise<{id, models, scales, samples, bytes}>
let modelList = null; // Promise<[{id, name, family, params}]>

export class IndexError extends Error {
  constructor(message, cause) {
    super(message);
    this.name = 'IndexError';
    this.kind = cause?.kind;
    this.cause = cause;
  }
}

function fetchIndex() {
  if (!indexBytes) {
    indexBytes = (async () => {
      let res;
      try {
        res = await fetch(INDEX_URL);
      } catch (err) {
        throw new IndexError(`the texture index (assets/texture-index.bin) could not be fetched: ${err.message}`);
      }
      if (!res.ok) throw new IndexError(`the texture index (assets/texture-index.bin) could not be fetched: HTTP ${res.status}`);
      return new Uint8Array(await res.arrayBuffer());
    })();
    indexBytes.catch(() => { indexBytes = null; });
  }
  return indexBytes;
}

/** Send the index to a worker (the one `affinity` picks); the bytes are copied, not transferred. */
async function sendIndex(run, signal) {
  const bytes = await fetchIndex();
  try {
    return await run('texture-index', { bytes }, { affinity: AFFINITY, transfer: [], signal });
  } catch (err) {
    if (err?.kind === 'cancelled' || err?.kind === 'crash') throw err;
    throw new IndexError(`the texture index (assets/texture-index.bin) is unusable: ${err.message}`, err);
  }
}

export function loadIndex(run) {
  if (!indexInfo) {
    indexInfo = sendIndex(run);
    indexInfo.catch(() => { indexInfo = null; });
  }
  return indexInfo;
}

/** Run an index request on the worker holding the index; re-send it once when that worker lost it. */
export async function withIndex(run, kind, payload, opts = {}) {
  const info = await loadIndex(run);
  const go = () => run(kind, { ...payload, index: info.id }, { ...opts, affinity: AFFINITY });
  try {
    return await go();
  } catch (err) {
    if (err?.field !== 'index') throw err;
    await sendIndex(run, opts.signal);
    return go();
  }
}

export function models(run) {
  if (!modelList) {
    modelList = run('texture-models', {});
    modelList.catch(() => { modelList = null; });
  }
  return modelList;
}
