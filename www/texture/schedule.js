// When the core answers Texture's document: a scale moved asks for the
// texture nearest the new scales shortly after (`texture-retrieve`;
// debounced, a stale request cancelled), and a new example is analysed
// (`texture-analyse`) and its nearest texture retrieved as one undoable
// step. A slider's drag is one history step, sealed once its last
// retrieval lands. A missing, corrupt or wrong-version index is said in
// the panel; the rest of the page keeps working (models still render).
import { IndexError, loadIndex, withIndex } from './index-loader.js';
import { grayImage } from './pictures.js';
import { SIDE, same, keyOf, predictedOf, retrievedOf } from './state.js';

const RETRIEVE_DELAY_MS = 60;

/**
 * The core's jobs of a mounted panel (`live`: state.js; `counters`: the
 * status element's dataset, counting retrievals for tests and people).
 */
export function createRunner(ctx, { live, status, counters }) {
  const state = () => ctx.state();
  let retrieving = null; // AbortController of the retrieval in flight
  let retrieveTimer = null;
  let working = null; // AbortController of an example being analysed
  let holding = false; // a slider is held (pointer down)
  let sealAfter = false; // seal the history once the pending retrieval lands

  function indexFailed(err) {
    live.indexOk = false;
    status('no index: the scales cannot be analysed or retrieved (models still render)');
    ctx.error(err, { prefix: err instanceof IndexError ? 'Texture index' : 'Texture', source: 'index' });
  }

  loadIndex(ctx.run).then((info) => {
    if (!ctx.alive()) return;
    live.indexOk = true;
    status(`index: ${info.samples.toLocaleString('en')} textures, ${(info.bytes / 1048576).toFixed(1)} MB`);
    ctx.clearError('index');
  }).catch((err) => { if (err?.kind !== 'cancelled') indexFailed(err); });

  // ---- retrieval -------------------------------------------------------------------------

  function scheduleRetrieve() {
    ctx.clearTimeout(retrieveTimer);
    retrieveTimer = ctx.setTimeout(() => { retrieveTimer = null; retrieve(); }, RETRIEVE_DELAY_MS);
  }

  async function retrieve() {
    const doc = state();
    if (!doc) return;
    retrieving?.abort();
    const ctrl = new AbortController();
    retrieving = ctrl;
    const model = doc.sameModel && doc.predicted ? doc.predicted.model : '';
    const t0 = performance.now();
    try {
      const r = await withIndex(ctx.run, 'texture-retrieve', { scales: doc.scales, model, size: SIDE }, { signal: ctrl.signal });
      if (retrieving !== ctrl || !ctx.alive()) return;
      const ms = performance.now() - t0;
      const now = state();
      // The answer is for the scales asked; a later move has its own request.
      if (!now || !same(now.scales, doc.scales) || now.sameModel !== doc.sameModel) return;
      const retrieved = retrievedOf(r);
      if (r.image) live.shown = { key: keyOf(retrieved), image: grayImage(r.image.gray, r.image.size) };
      counters.retrievals = String(Number(counters.retrievals) + 1);
      ctx.commit({ ...now, retrieved }, { coalesce: 'texture-scales' });
      if (sealAfter && !holding && retrieveTimer === null) { sealAfter = false; ctx.seal(); }
      status(`retrieved sample ${r.sample} in ${Math.round(ms)} ms`);
      ctx.clearError('run');
    } catch (err) {
      if (retrieving !== ctrl || err?.kind === 'cancelled') return;
      if (err instanceof IndexError) indexFailed(err);
      else ctx.error(err, { prefix: 'Retrieve', source: 'run' });
    } finally {
      if (retrieving === ctrl) retrieving = null;
    }
  }

  /** Analyse example `png` (bytes) as `source`, retrieve its nearest texture: one undoable step.
   * Resolves true when the document took it (false: it said why, and the document is unchanged). */
  async function useExample(source, png) {
    const doc = state();
    if (!doc) return;
    working?.abort();
    retrieving?.abort();
    ctx.clearTimeout(retrieveTimer);
    retrieveTimer = null;
    const ctrl = new AbortController();
    working = ctrl;
    status('analysing the example…');
    try {
      const a = await withIndex(ctx.run, 'texture-analyse', { bytes: png }, { signal: ctrl.signal, transfer: [] });
      if (working !== ctrl) return;
      const scales = [...a.scales];
      const model = doc.sameModel ? a.model : '';
      const r = await withIndex(ctx.run, 'texture-retrieve', { scales, model, size: SIDE }, { signal: ctrl.signal });
      if (working !== ctrl || !ctx.alive()) return;
      const retrieved = retrievedOf(r);
      if (r.image) live.shown = { key: keyOf(retrieved), image: grayImage(r.image.gray, r.image.size) };
      counters.retrievals = String(Number(counters.retrievals) + 1);
      ctx.commit({ ...state(), source, predicted: predictedOf(a), scales, retrieved });
      ctx.seal();
      status(`${a.close === false ? 'no close model' : `predicted ${a.model_name}`}; retrieved sample ${r.sample}`);
      ctx.clearError();
      return true;
    } catch (err) {
      if (working !== ctrl || err?.kind === 'cancelled') return false;
      if (err instanceof IndexError) indexFailed(err);
      else ctx.error(err, { prefix: 'Example', source: 'run' });
      status('the example could not be analysed (see above)');
      return false;
    } finally {
      if (working === ctrl) working = null;
    }
  }

  return {
    schedule: scheduleRetrieve,
    useExample,
    /** A slider let go: seal the history now, or once the retrieval due lands. */
    seal() { if (retrieveTimer !== null || retrieving) sealAfter = true; else ctx.seal(); },
    /** Seal the history once the next retrieval lands. */
    sealAfterAnswer() { sealAfter = true; },
    /** Whether a slider is held (pointer down): its retrieval does not seal. */
    hold(on) { holding = on; },
    /** Whether a retrieval or an analysis is due or going. */
    pending: () => retrieveTimer !== null || retrieving !== null || working !== null,
    abort() { retrieving?.abort(); working?.abort(); },
  };
}
