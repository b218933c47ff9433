// Pixel's document and what a mounted panel derives from it. The document is
// {example, source, sheet, sprite, mask, strokes, params, names}; its schema
// (every field, its rules and messages) is the core's: src/pixel/state.rs,
// applied by the document controller (`check-state`). History, autosave,
// project files and links come from the controller (app/document.js). Its
// images are PNG (the Pixel module reads no other format): a file the user
// gives is turned into PNG as it comes in (inputs.js), and a document from
// outside (an autosave, a project file or a link saved before) by `toCore`.
import { pngOf } from '../ui/file-input.js';

const ASSETS = new URL('../../assets/pixel/', import.meta.url);
const EXAMPLES = ['fish', 'trunk'];
const MAX_SIDE = 4096;

async function fetchBytes(url) {
  const res = await fetch(url);
  if (!res.ok) throw new Error(`${url.pathname}: ${res.status}`);
  return new Uint8Array(await res.arrayBuffer());
}

let casesPromise = null;
const cases = () => (casesPromise ??= fetch(new URL('cases.json', ASSETS)).then((r) => r.json()).catch((e) => { casesPromise = null; throw e; }));

/** The source bytes of example `name`. */
async function exampleSource(name) {
  const ex = (await cases())[name];
  return fetchBytes(new URL(ex.source, ASSETS));
}

/** A whole document for example `name`; `ctx` gives run() and coreDefaults(). */
export async function exampleDoc(name, ctx) {
  // The same cases (files, parameters, strokes) the native benchmark runs.
  const ex = (await cases())[name];
  const [source, maskPng, sheet, strokesJson] = await Promise.all(
    [ex.source, ex.mask, ex.sheet, ex.strokes].map((f) => fetchBytes(new URL(f, ASSETS))),
  );
  const [mask, defaults] = await Promise.all([ctx.run('pixel-mask', { bytes: maskPng }), ctx.coreDefaults()]);
  return {
    example: name, source, sheet, sprite: null, mask,
    strokes: JSON.parse(new TextDecoder().decode(strokesJson)).strokes,
    params: { ...defaults.params, ...ex.params },
    names: { source: ex.source, sheet: ex.sheet },
  };
}



function invalid(field, why) {
  const e = new Error(`${field} ${why}`);
  e.field = field;
  return e;
}

function packBits(bits) {
  const out = new Uint8Array(Math.ceil(bits.length / 8));
  for (let i = 0; i < bits.length; i++) if (bits[i]) out[i >> 3] |= 1 << (i & 7);
  return out;
}

function unpackBits(packed, n) {
  if (!(packed instanceof Uint8Array) || packed.length !== Math.ceil(n / 8)) throw invalid('mask', 'is cut short');
  const out = new Uint8Array(n);
  for (let i = 0; i < n; i++) out[i] = (packed[i >> 3] >> (i & 7)) & 1;
  return out;
}

export const pixelState = {
  version: 1,
  defaults: (ctx) => exampleDoc('fish', ctx),
  migrate: (raw) => raw,
  // Before the core checks a document from outside: its images as PNG (one
  // saved before the Pixel module read PNG only may hold a JPEG, GIF, WebP or
  // BMP source or sheet). Bytes the browser cannot read as an image stay as
  // they are, for the core to refuse in its words, naming the field.
  async toCore(s) {
    if (!s || typeof s !== 'object' || Array.isArray(s)) return s;
    const out = { ...s };
    for (const k of ['source', 'sheet', 'sprite']) {
      if (s[k] instanceof Uint8Array && s[k].length) out[k] = await pngOf(s[k]).catch(() => s[k]);
    }
    return out;
  },
  fileName: (s) => s.names?.source || 'pixel',
  // A link carries everything but an example's source (named instead) and
  // packs the mask's bits; a big source or mask makes it too big for a link.
  toShare(s) {
    return {
      example: s.example, source: s.example ? null : s.source, sheet: s.sheet, sprite: s.sprite,
      mask: { width: s.mask.width, height: s.mask.height, packed: packBits(s.mask.bits) },
      strokes: s.strokes, params: s.params, names: s.names,
    };
  },
  async fromShare(x) {
    if (!x || typeof x !== 'object' || Array.isArray(x)) throw invalid('state', 'is not a Pixel document');
    let source = x.source;
    if (x.example != null) {
      if (!EXAMPLES.includes(x.example)) throw invalid('example', `must be one of ${EXAMPLES.join(', ')}`);
      source = await exampleSource(x.example);
    }
    const m = x.mask;
    if (!m || !Number.isInteger(m.width) || !Number.isInteger(m.height) || m.width < 1 || m.height < 1 || m.width > MAX_SIDE || m.height > MAX_SIDE) {
      throw invalid('mask', 'has no valid size');
    }
    return { ...x, source, mask: { width: m.width, height: m.height, bits: unpackBits(m.packed, m.width * m.height) } };
  },
};

/**
 * What a mounted panel derives from the document (not saved), shared by its
 * parts: view settings, the decoded source, the last result, the drag.
 */
export function createLive() {
  return {
    view: { mode: 'stroke', brush: 3, showResult: true, showMask: false, showStrokes: true, showArrows: false },
    sourceImg: null, // {width, height} of the decoded source
    sourceBitmap: null,
    sourceOf: null, // the source bytes sourceImg was decoded from
    sourceLoading: null, // the decoding under way (a promise)
    loadingFor: null, // the source bytes being decoded
    result: null, // the core's answer for the current state, or the last good one
    resultFor: null, // the source bytes that result was made from
    resultBitmap: null,
    drawing: null, // the stroke or mask edit in progress
  };
}
