// "Texture": perceptual procedural-texture retrieval (MISSION X7, S8–S10;
// the paper's Fig. 2/6). Give an example — drop, paste or choose an image,
// or render one of the procedural models — and the core predicts its model
// and its twelve perceptual scales (`texture-analyse`). The scales are
// sliders: moving one asks the core for a texture near the request in the
// perceptual space (`texture-retrieve`: of the nearest few, the one whose
// scales are nearest; debounced, a stale request cancelled), rendered live from its model and parameters. A bar chart
// compares the requested and retrieved scales (with their cosine
// similarity); the retrieved parameters can be edited (re-rendered with
// `texture-render`); the preview tiles 2×2; PNG and JSON export.
//
// The scales are computational estimates, not human ratings (see
// src/texture/scales.rs; `filigree build-index --ratings` replaces them):
// an example's scales are measured on it (its four corner windows), and
// only an index built on ratings predicts them with its classifiers.
//
// The trained index (assets/texture-index.bin) is fetched once per page,
// only when this tool opens, and parsed once per worker (`texture-index`):
// analysis and retrieval go to the worker that holds it (`affinity`), and a
// worker that does not (replaced after a crash, or another one) answers an
// error on field `index`, so the index is sent again and the request
// retried. A missing, corrupt or wrong-version index is said in the panel;
// the rest of the page keeps working (models still render).
//
// The document is {source, predicted, scales, sameModel, retrieved}; its
// schema is src/texture/state.rs. History, autosave, project files and
// links come from the document controller (app/document.js).
import { acceptFiles } from '../ui/file-input.js';
import { download } from '../app/project.js';

const INDEX_URL = new URL('../../assets/texture-index.bin', import.meta.url);
const AFFINITY = 'texture-index';
const SIDE = 256; // rendered textures, pixels a side (the index's size)
const EXAMPLE_SIDE = 256; // a dropped example is shrunk to at most this
const MAX_SOURCE_PNG = 256 * 1024; // src/texture/state.rs
const RETRIEVE_DELAY_MS = 60;
const EDIT_DELAY_MS = 250;
const SCALES = ['contrast', 'repetition', 'granularity', 'randomness', 'roughness', 'feature_density',
  'directionality', 'structural_complexity', 'coarseness', 'regularity', 'local_orientation', 'uniformity'];
const label = (name) => name.replace(/_/g, ' ').replace(/^./, (c) => c.toUpperCase());
const SHORT = ['Con', 'Rep', 'Gra', 'Ran', 'Rou', 'Den', 'Dir', 'Cpx', 'Coa', 'Reg', 'Ori', 'Uni'];
const DEFAULT_MODEL = 'texton-regular';

// ---- the index and the models, once per page -------------------------------------------

let indexBytes = null; // Promise<Uint8Array>
let indexInfo = null; // Promise<{id, models, scales, samples, bytes}>
let modelList = null; // Promise<[{id, name, family, params}]>

class IndexError extends Error {
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

function loadIndex(run) {
  if (!indexInfo) {
    indexInfo = sendIndex(run);
    indexInfo.catch(() => { indexInfo = null; });
  }
  return indexInfo;
}

/** Run an index request on the worker holding the index; re-send it once when that worker lost it. */
async function withIndex(run, kind, payload, opts = {}) {
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

function models(run) {
  if (!modelList) {
    modelList = run('texture-models', {});
    modelList.catch(() => { modelList = null; });
  }
  return modelList;
}

// ---- pictures ----------------------------------------------------------------------------

/** Grey bytes (side²) → RGBA ImageData. */
function grayImage(gray, side) {
  const g = gray instanceof Uint8Array ? gray : new Uint8Array(gray);
  const rgba = new Uint8ClampedArray(side * side * 4);
  for (let i = 0; i < side * side; i++) {
    const v = g[i];
    rgba[4 * i] = v; rgba[4 * i + 1] = v; rgba[4 * i + 2] = v; rgba[4 * i + 3] = 255;
  }
  return new ImageData(rgba, side, side);
}

async function pngOf(canvas) {
  const blob = await new Promise((resolve, reject) => canvas.toBlob((b) => (b ? resolve(b) : reject(new Error('the image could not be encoded as PNG'))), 'image/png'));
  return new Uint8Array(await blob.arrayBuffer());
}

/** A grey picture as PNG bytes. */
async function grayPng(gray, side) {
  const c = document.createElement('canvas');
  c.width = side;
  c.height = side;
  c.getContext('2d').putImageData(grayImage(gray, side), 0, 0);
  return pngOf(c);
}

// ---- the example in a link ---------------------------------------------------------------
//
// A kept example is a grey PNG from the browser's encoder, which writes grey
// as colour (a 256² example of fine grain is up to ~100 KB). A link carries its
// grey pixels instead, Paeth-filtered as PNG does and deflated with the rest
// of the link (share.js): at most 64 KB before deflating, so every example
// the page keeps fits the 96 KB a link holds. The recipient's page encodes
// the same pixels as its PNG. A colour PNG (from a project file) travels as
// its bytes.

const paeth = (a, b, c) => {
  const p = a + b - c;
  const pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
  return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
};

/** Grey pixels (width·height bytes) Paeth-filtered (`undo` = false) or restored (`undo` = true), in place of a copy. */
function paethFilter(px, width, height, undo) {
  const out = new Uint8Array(px.length);
  const src = undo ? out : px; // the neighbours are always original pixels
  for (let y = 0; y < height; y++) {
    for (let x = 0; x < width; x++) {
      const i = y * width + x;
      const a = x ? src[i - 1] : 0, b = y ? src[i - width] : 0, c = x && y ? src[i - width - 1] : 0;
      out[i] = (px[i] + (undo ? 1 : -1) * paeth(a, b, c)) & 255;
    }
  }
  return out;
}

/** A PNG's pixels as grey bytes, or null when it has colour or transparency (or does not decode). */
async function greyPixels(png) {
  let bmp;
  try {
    bmp = await createImageBitmap(new Blob([png], { type: 'image/png' }), { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
  } catch {
    return null;
  }
  const { width, height } = bmp;
  const c = new OffscreenCanvas(width, height);
  const g = c.getContext('2d');
  g.drawImage(bmp, 0, 0);
  bmp.close?.();
  const d = g.getImageData(0, 0, width, height).data;
  const grey = new Uint8Array(width * height);
  for (let i = 0; i < grey.length; i++) {
    const [r, gg, b, a] = [d[4 * i], d[4 * i + 1], d[4 * i + 2], d[4 * i + 3]];
    if (r !== gg || r !== b || a !== 255) return null;
    grey[i] = r;
  }
  return { width, height, grey };
}

/** The example of a link (`{grey: {width, height, filtered}}`) as the document's PNG. */
async function greyFromLink(x) {
  const { width, height, filtered } = x ?? {};
  if (!Number.isInteger(width) || !Number.isInteger(height) || width < 1 || height < 1 || width > 4096 || height > 4096
    || !(filtered instanceof Uint8Array) || filtered.length !== width * height) {
    throw Object.assign(new Error('source is damaged'), { field: 'source' });
  }
  const grey = paethFilter(filtered, width, height, true);
  const rgba = new Uint8ClampedArray(width * height * 4);
  for (let i = 0; i < grey.length; i++) {
    rgba[4 * i] = grey[i]; rgba[4 * i + 1] = grey[i]; rgba[4 * i + 2] = grey[i]; rgba[4 * i + 3] = 255;
  }
  const c = document.createElement('canvas');
  c.width = width;
  c.height = height;
  c.getContext('2d').putImageData(new ImageData(rgba, width, height), 0, 0);
  return pngOf(c);
}

/** A user's image file → a grey PNG at most `EXAMPLE_SIDE` a side (and at most MAX_SOURCE_PNG bytes). */
async function shrinkExample(file) {
  let bmp;
  if (!file.size) throw new Error(`${file.name || 'the file'} is empty (0 bytes): there is no picture in it`);
  try {
    bmp = await createImageBitmap(file);
  } catch {
    throw new Error(`${file.name || 'the file'} is not an image this browser can read (PNG, JPEG, WebP, GIF): it may be damaged`);
  }
  try {
    for (let side = EXAMPLE_SIDE; side >= 32; side = Math.round(side / 2)) {
      const s = Math.min(1, side / Math.max(bmp.width, bmp.height));
      const w = Math.max(1, Math.round(bmp.width * s)), h = Math.max(1, Math.round(bmp.height * s));
      const c = document.createElement('canvas');
      c.width = w;
      c.height = h;
      const g = c.getContext('2d');
      g.fillStyle = '#fff'; // transparent parts read as white, as the core does
      g.fillRect(0, 0, w, h);
      g.imageSmoothingQuality = 'high';
      g.drawImage(bmp, 0, 0, w, h);
      const d = g.getImageData(0, 0, w, h);
      for (let i = 0; i < d.data.length; i += 4) {
        const y = Math.round(0.2126 * d.data[i] + 0.7152 * d.data[i + 1] + 0.0722 * d.data[i + 2]);
        d.data[i] = y; d.data[i + 1] = y; d.data[i + 2] = y;
      }
      g.putImageData(d, 0, 0);
      const png = await pngOf(c);
      if (png.length <= MAX_SOURCE_PNG) return png;
    }
  } finally {
    bmp.close?.();
  }
  throw new Error('the example could not be kept small enough');
}

// ---- the document ------------------------------------------------------------------------

const same = (a, b) => a === b || (Array.isArray(a) && Array.isArray(b) && a.length === b.length && a.every((v, i) => v === b[i]));
const keyOf = (r) => (r ? `${r.model}|${r.params.join(',')}|${r.seed}` : '');
const sourceKey = (s) => (!s ? '' : s.kind === 'model' ? `m|${s.model}|${s.params.join(',')}|${s.seed}` : `i|${s.name}|${s.png.length}|${s.png.slice(0, 64).join(',')}|${s.png.slice(-64).join(',')}`);

/** The predicted part of a document from a `texture-analyse` answer: the model, the scale
 * estimates, the three likeliest models with their probabilities, and whether any is close. */
const predictedOf = (a) => {
  // The shape the core's document check gives back (state.rs): `top` left
  // out when empty and `close` when true, so a link or a project opens equal.
  const p = { model: a.model, scales: [...a.scales] };
  const top = (a.top || []).map((c) => ({ model: c.model, probability: c.probability }));
  if (top.length) p.top = top;
  if (a.close === false) p.close = false;
  return p;
};

/** The retrieved part of a document from a `texture-retrieve` answer. */
const retrievedOf = (r) => ({ model: r.model, params: r.params, seed: r.seed, sample: r.sample, scales: [...r.scales], cosine: r.cosine, edited: false });

const textureState = {
  version: 1,
  async defaults(ctx) {
    // The default example: a model rendered and analysed, its nearest texture retrieved.
    const list = await models(ctx.run);
    const m = list.find((x) => x.id === DEFAULT_MODEL) || list[0];
    const doc = { source: { kind: 'model', model: m.id, params: m.params.map((p) => p.default), seed: 1 }, predicted: null, scales: Array(12).fill(5), sameModel: false, retrieved: null };
    try {
      const img = await ctx.run('texture-render', { model: m.id, params: doc.source.params, seed: 1, size: SIDE });
      const a = await withIndex(ctx.run, 'texture-analyse', { bytes: await grayPng(img.gray, SIDE) }, { transfer: [] });
      doc.predicted = predictedOf(a);
      doc.scales = [...a.scales];
      const r = await withIndex(ctx.run, 'texture-retrieve', { scales: doc.scales, model: '', size: 0 });
      doc.retrieved = retrievedOf(r);
    } catch (err) {
      if (err?.kind === 'cancelled') throw err;
      ctx.error(err, { prefix: err instanceof IndexError ? 'Texture index' : 'Texture', source: 'index' });
    }
    return doc;
  },
  migrate: (raw) => raw,
  fileName: (s) => `texture-${s.retrieved?.model || s.source?.model || 'example'}`,
  // A link carries the example: its grey pixels (see greyPixels above), or
  // a colour PNG's bytes; one too big for a link leaves it out, and the page
  // says so before copying (document.js).
  async toShare(s) {
    if (s.source?.kind !== 'image') return s;
    const px = await greyPixels(s.source.png);
    if (!px) return s;
    const grey = { width: px.width, height: px.height, filtered: paethFilter(px.grey, px.width, px.height, false) };
    return { ...s, source: { kind: 'image', name: s.source.name, grey } };
  },
  async fromShare(x) {
    if (x?.source?.kind !== 'image' || !x.source.grey) return x;
    const { grey, ...source } = x.source;
    return { ...x, source: { ...source, png: await greyFromLink(grey) } };
  },
  shareLean: (s) => (s.source?.kind === 'image' ? { state: { ...s, source: null }, omits: 'the example' } : null),
};

const html = `
  <div class="texture-layout">
    <section class="card texture-example" aria-label="Example">
      <h3>Example</h3>
      <div class="texture-drop drop-zone-lite" data-testid="texture-drop">
        <canvas data-testid="texture-example" role="img" aria-label="the example texture" width="256" height="256"></canvas>
        <p class="muted">Drop or paste an image here, or</p>
      </div>
      <div class="texture-pick-model">
        <label class="inline">Model <select name="example-model" data-testid="texture-model-select"></select></label>
        <button type="button" data-act="render-example">Render as example</button>
      </div>
      <p class="texture-predicted" data-testid="texture-predicted" aria-live="polite"></p>
      <ol class="texture-top" data-testid="texture-top" aria-label="Likeliest models"></ol>
    </section>
    <section class="card texture-result" aria-label="Retrieved texture">
      <div class="toolbar" role="toolbar" aria-label="Texture">
        <label class="inline"><input type="checkbox" name="tile" data-testid="texture-tile"> Tile 2×2</label>
        <button type="button" data-act="export-png">Export PNG</button>
        <button type="button" data-act="export-json">Export JSON</button>
      </div>
      <div class="texture-view"><canvas data-testid="texture-canvas" role="img" aria-label="the retrieved texture"></canvas></div>
      <p class="texture-retrieved muted" data-testid="texture-retrieved" aria-live="polite"></p>
      <canvas class="texture-chart" data-testid="texture-chart" role="img" aria-label="requested and retrieved scales"></canvas>
      <p class="muted texture-legend"><span class="key req"></span> requested <span class="key got"></span> retrieved <span data-testid="texture-cosine"></span></p>
    </section>
    <section class="card texture-controls" aria-label="Perceptual scales">
      <h3>Perceptual scales</h3>
      <p class="muted texture-note" data-testid="texture-estimates-note">These are computational estimates from image measures, not human ratings (a ratings file replaces them when the index is built).</p>
      <div class="sliders texture-sliders" data-testid="texture-sliders"></div>
      <label class="inline texture-same"><input type="checkbox" name="same-model" data-field="sameModel" data-testid="texture-same-model"> Stay within the predicted model</label>
      <details class="texture-params" data-testid="texture-params" open>
        <summary>Parameters</summary>
        <div class="texture-param-list"></div>
      </details>
      <div class="status muted" data-testid="texture-status" aria-live="polite"></div>
    </section>
  </div>`;

function mount(el, ctx) {
  el.innerHTML = html;
  const q = (s) => el.querySelector(s);
  const state = () => ctx.state();
  const statusEl = q('[data-testid=texture-status]');
  const status = (t) => { statusEl.textContent = t; };
  const exampleCanvas = q('[data-testid=texture-example]');
  const view = q('[data-testid=texture-canvas]');
  const chart = q('[data-testid=texture-chart]');
  const tileBox = q('[name=tile]');
  const sameBox = q('[name=same-model]');
  const modelSel = q('[name=example-model]');
  const predictedEl = q('[data-testid=texture-predicted]');
  const topEl = q('[data-testid=texture-top]');
  const retrievedEl = q('[data-testid=texture-retrieved]');
  const cosineEl = q('[data-testid=texture-cosine]');
  const paramList = q('.texture-param-list');

  let list = []; // the models
  let shown = null; // {key, image: ImageData} of the retrieved texture drawn
  let exampleShown = '';
  let retrieving = null; // AbortController of the retrieval in flight
  let retrieveTimer = null;
  let rendering = null; // AbortController of the render in flight
  let editTimer = null;
  let working = null; // AbortController of an example being analysed
  let holding = false; // a slider is held (pointer down)
  let sealAfter = false; // seal the history once the pending retrieval lands
  let indexOk = false;

  const counters = statusEl.dataset;
  counters.retrievals = '0';
  counters.renders = '0';

  // ---- sliders --------------------------------------------------------------------------

  const sliders = SCALES.map((name, i) => {
    const row = document.createElement('div');
    row.className = 'row';
    const id = `texture-scale-${name}`;
    row.innerHTML = `<label for="${id}" title="${label(name)} (estimate)">${label(name)}</label>
      <input type="range" id="${id}" min="1" max="9" step="0.5" data-field="scales.${i}" data-testid="${id}" data-scale="${name}">
      <output for="${id}"></output>`;
    const input = row.querySelector('input');
    input.oninput = () => {
      const doc = state();
      if (!doc) return;
      const scales = [...doc.scales];
      scales[i] = Number(input.value);
      ctx.commit({ ...doc, scales }, { coalesce: 'texture-scales' });
      scheduleRetrieve();
    };
    input.onchange = () => { if (retrieveTimer !== null || retrieving) sealAfter = true; else ctx.seal(); };
    input.addEventListener('pointerdown', () => { holding = true; });
    input.addEventListener('pointerup', () => { holding = false; });
    q('.texture-sliders').append(row);
    return { input, out: row.querySelector('output'), row };
  });

  sameBox.onchange = () => {
    const doc = state();
    if (!doc) return;
    ctx.commit({ ...doc, sameModel: sameBox.checked }, { coalesce: 'texture-scales' });
    sealAfter = true;
    scheduleRetrieve();
  };
  tileBox.onchange = () => drawView();

  // ---- the index -------------------------------------------------------------------------

  function indexFailed(err) {
    indexOk = false;
    status('no index: the scales cannot be analysed or retrieved (models still render)');
    ctx.error(err, { prefix: err instanceof IndexError ? 'Texture index' : 'Texture', source: 'index' });
  }

  loadIndex(ctx.run).then((info) => {
    if (!ctx.alive()) return;
    indexOk = true;
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
      if (r.image) shown = { key: keyOf(retrieved), image: grayImage(r.image.gray, r.image.size) };
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

  // ---- the example ------------------------------------------------------------------------

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
      if (r.image) shown = { key: keyOf(retrieved), image: grayImage(r.image.gray, r.image.size) };
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

  async function onFile(file) {
    if (ctx.readOnly) return;
    try {
      status('reading the example…');
      const png = await shrinkExample(file);
      if (!ctx.alive()) return;
      const source = { kind: 'image', name: String(file.name || 'pasted image').slice(0, 200), png };
      await drawExample(source);
      // Refused (too small to read, say): the canvas shows the document's example again.
      if (!(await useExample(source, png)) && ctx.alive()) await drawExample(state()?.source);
    } catch (err) {
      // Nothing is being read any more: say so, and show the document's example again.
      if (!ctx.alive()) return;
      status('the example was not read (see above); the one before is kept');
      ctx.error(err, { prefix: 'Example' });
      await drawExample(state()?.source).catch(() => {});
    }
  }
  const dropZone = q('[data-testid=texture-drop]');
  const removeFiles = acceptFiles(dropZone, onFile, { pickerLabel: 'Choose an image…' });
  // A read-only embed keeps the author's example: no drop, no picker, and words that say so.
  if (ctx.readOnly) {
    dropZone.querySelector('p').textContent = 'The author\'s example.';
    dropZone.querySelector('.pick').hidden = true;
  }

  q('[data-act=render-example]').onclick = async () => {
    const m = list.find((x) => x.id === modelSel.value);
    if (!m) return;
    try {
      const source = { kind: 'model', model: m.id, params: m.params.map((p) => p.default), seed: 1 };
      const img = await ctx.run('texture-render', { model: m.id, params: source.params, seed: 1, size: SIDE });
      if (!ctx.alive()) return;
      exampleCanvas.width = SIDE;
      exampleCanvas.height = SIDE;
      exampleCanvas.getContext('2d').putImageData(grayImage(img.gray, SIDE), 0, 0);
      exampleShown = sourceKey(source);
      await useExample(source, await grayPng(img.gray, SIDE));
    } catch (err) {
      if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Render example' });
    }
  };

  async function drawExample(source) {
    const key = sourceKey(source);
    if (key === exampleShown) return;
    exampleShown = key;
    const g = exampleCanvas.getContext('2d');
    if (!source) {
      g.clearRect(0, 0, exampleCanvas.width, exampleCanvas.height);
      return;
    }
    if (source.kind === 'model') {
      const img = await ctx.run('texture-render', { model: source.model, params: source.params, seed: source.seed, size: SIDE });
      if (exampleShown !== key) return;
      exampleCanvas.width = SIDE;
      exampleCanvas.height = SIDE;
      g.putImageData(grayImage(img.gray, SIDE), 0, 0);
    } else {
      const bmp = await createImageBitmap(new Blob([source.png], { type: 'image/png' }));
      if (exampleShown !== key) { bmp.close?.(); return; }
      exampleCanvas.width = bmp.width;
      exampleCanvas.height = bmp.height;
      g.drawImage(bmp, 0, 0);
      bmp.close?.();
    }
  }

  // ---- the retrieved texture ---------------------------------------------------------------

  function drawView() {
    const tile = tileBox.checked ? 2 : 1;
    if (!shown) {
      view.width = SIDE;
      view.height = SIDE;
      view.getContext('2d').clearRect(0, 0, SIDE, SIDE);
      return;
    }
    const s = shown.image.width;
    view.width = s * tile;
    view.height = s * tile;
    const g = view.getContext('2d');
    for (let y = 0; y < tile; y++) for (let x = 0; x < tile; x++) g.putImageData(shown.image, x * s, y * s);
  }

  /** Render the retrieved model + parameters unless that picture is already shown. */
  async function renderRetrieved(r) {
    const key = keyOf(r);
    if (shown?.key === key) { drawView(); return; }
    rendering?.abort();
    if (!r) { shown = null; drawView(); return; }
    const ctrl = new AbortController();
    rendering = ctrl;
    try {
      const img = await ctx.run('texture-render', { model: r.model, params: r.params, seed: r.seed, size: SIDE }, { signal: ctrl.signal });
      if (rendering !== ctrl || !ctx.alive()) return;
      shown = { key, image: grayImage(img.gray, img.size) };
      counters.renders = String(Number(counters.renders) + 1);
      drawView();
      ctx.clearError('render');
    } catch (err) {
      if (rendering === ctrl && err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Render', source: 'render' });
    } finally {
      if (rendering === ctrl) rendering = null;
    }
  }

  // ---- parameters ------------------------------------------------------------------------------

  let paramsFor = ''; // model id the inputs are built for
  function buildParams(r) {
    const m = r && list.find((x) => x.id === r.model);
    if (!m) { paramList.replaceChildren(); paramsFor = ''; return; }
    if (paramsFor !== m.id) {
      paramsFor = m.id;
      paramList.replaceChildren(...m.params.map((p, i) => {
        const row = document.createElement('label');
        row.className = 'texture-param';
        const span = document.createElement('span');
        span.textContent = p.name.replace(/_/g, ' ');
        const input = document.createElement('input');
        input.type = 'number';
        input.min = String(p.lo);
        input.max = String(p.hi);
        input.step = p.integer ? '1' : 'any';
        input.dataset.field = `retrieved.params.${i}`;
        input.dataset.param = p.name;
        input.title = `${p.lo} to ${p.hi}${p.integer ? ', whole numbers' : ''}`;
        input.oninput = () => editParam(i, input);
        row.append(span, input);
        return row;
      }), (() => {
        const row = document.createElement('label');
        row.className = 'texture-param texture-seed';
        const span = document.createElement('span');
        span.textContent = 'seed';
        const input = document.createElement('input');
        input.type = 'number';
        input.min = '0';
        input.step = '1';
        input.dataset.field = 'retrieved.seed';
        input.dataset.param = 'seed';
        input.oninput = () => editParam(-1, input);
        row.append(span, input);
        return row;
      })());
    }
    const inputs = paramList.querySelectorAll('input');
    inputs.forEach((input, i) => {
      const v = i < r.params.length ? r.params[i] : r.seed;
      // Parameters at six significant digits; the seed exactly (an integer ≤ 2⁵³).
      const shown = i < r.params.length ? String(+v.toPrecision(6)) : String(v);
      // A new input's value is '' (which Number reads as 0): a parameter at
      // 0 must still be written.
      if (document.activeElement !== input && (input.value === '' || Number(input.value) !== v)) input.value = shown;
    });
  }

  function editParam(i, input) {
    const doc = state();
    const r = doc?.retrieved;
    const m = r && list.find((x) => x.id === r.model);
    if (!m || input.value === '') return;
    let v = Number(input.value);
    if (!Number.isFinite(v)) return;
    const next = { ...r, params: [...r.params], edited: true };
    if (i < 0) {
      if (!Number.isSafeInteger(v) || v < 0) return;
      next.seed = v;
    } else {
      const p = m.params[i];
      v = Math.min(p.hi, Math.max(p.lo, p.integer ? Math.round(v) : v));
      next.params[i] = v;
    }
    ctx.clearTimeout(editTimer);
    editTimer = ctx.setTimeout(() => { editTimer = null; ctx.seal(); }, EDIT_DELAY_MS);
    ctx.commit({ ...doc, retrieved: next }, { coalesce: `texture-param-${i}` });
  }

  // ---- the chart ----------------------------------------------------------------------------

  function drawChart(doc) {
    const dpr = window.devicePixelRatio || 1;
    const w = Math.max(200, Math.round(chart.clientWidth || 320));
    const h = Math.max(90, Math.round(chart.clientHeight || 120));
    chart.width = Math.round(w * dpr);
    chart.height = Math.round(h * dpr);
    const g = chart.getContext('2d');
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.clearRect(0, 0, w, h);
    const css = getComputedStyle(el);
    const accent = css.getPropertyValue('--accent').trim() || '#c9a2ff';
    const accent2 = css.getPropertyValue('--accent-2').trim() || '#7fd1c7';
    const muted = css.getPropertyValue('--muted').trim() || '#a49cb8';
    const top = 4, bottom = h - 16, slot = w / 12;
    const y = (v) => bottom - ((v - 0) / 9) * (bottom - top);
    g.strokeStyle = '#363047';
    g.lineWidth = 1;
    for (const v of [1, 5, 9]) { g.beginPath(); g.moveTo(0, y(v) + 0.5); g.lineTo(w, y(v) + 0.5); g.stroke(); }
    const got = doc?.retrieved?.scales;
    g.font = '10px system-ui, sans-serif';
    g.textAlign = 'center';
    for (let i = 0; i < 12; i++) {
      const x0 = i * slot, bw = Math.max(2, slot * 0.34);
      if (doc) { g.fillStyle = accent; g.fillRect(x0 + slot * 0.14, y(doc.scales[i]), bw, bottom - y(doc.scales[i])); }
      if (got) { g.fillStyle = accent2; g.fillRect(x0 + slot * 0.52, y(got[i]), bw, bottom - y(got[i])); }
      g.fillStyle = muted;
      g.fillText(SHORT[i], x0 + slot / 2, h - 4);
    }
    const desc = SCALES.map((n, i) => `${label(n)} ${doc ? doc.scales[i] : '–'} vs ${got ? got[i] : '–'}`).join(', ');
    chart.setAttribute('aria-label', `requested vs retrieved scales: ${desc}`);
  }

  const ro = new ResizeObserver(() => drawChart(state()));
  ro.observe(chart);

  // ---- export --------------------------------------------------------------------------------

  q('[data-act=export-png]').onclick = async () => {
    const r = state()?.retrieved;
    if (!r) { ctx.error(new Error('there is no retrieved texture to export yet')); return; }
    try {
      await renderRetrieved(r);
      if (shown?.key !== keyOf(r)) return;
      const c = document.createElement('canvas');
      const tile = tileBox.checked ? 2 : 1;
      const s = shown.image.width;
      c.width = s * tile;
      c.height = s * tile;
      const g = c.getContext('2d');
      for (let y = 0; y < tile; y++) for (let x = 0; x < tile; x++) g.putImageData(shown.image, x * s, y * s);
      download(`texture-${r.model}-${r.seed}.png`, new Blob([await pngOf(c)], { type: 'image/png' }));
      status(`exported PNG: ${c.width}×${c.height}`);
    } catch (err) {
      if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Export PNG' });
    }
  };

  q('[data-act=export-json]').onclick = () => {
    const doc = state();
    const r = doc?.retrieved;
    if (!r) { ctx.error(new Error('there is no retrieved texture to export yet')); return; }
    const m = list.find((x) => x.id === r.model);
    const json = {
      model: r.model,
      model_name: m?.name ?? r.model,
      params: Object.fromEntries((m?.params ?? []).map((p, i) => [p.name, r.params[i]])),
      seed: r.seed,
      scales: Object.fromEntries(SCALES.map((n, i) => [n, doc.scales[i]])),
      retrieved_scales: r.scales ? Object.fromEntries(SCALES.map((n, i) => [n, r.scales[i]])) : null,
      cosine: r.cosine,
      edited: r.edited,
      note: 'scales are computational estimates, not human ratings',
    };
    download(`texture-${r.model}-${r.seed}.json`, new Blob([JSON.stringify(json, null, 2)], { type: 'application/json' }));
  };

  // ---- models ---------------------------------------------------------------------------------

  const nameOf = (id) => list.find((x) => x.id === id)?.name ?? id;
  models(ctx.run).then((ms) => {
    if (!ctx.alive()) return;
    list = ms;
    modelSel.replaceChildren(...ms.map((m) => {
      const o = document.createElement('option');
      o.value = m.id;
      o.textContent = m.name;
      return o;
    }));
    const s = state();
    modelSel.value = s?.source?.kind === 'model' ? s.source.model : DEFAULT_MODEL;
    if (s) paint(s, null);
  }).catch((err) => ctx.error(err, { prefix: 'The texture models' }));

  function paint(s) {
    s.scales.forEach((v, i) => {
      const { input, out } = sliders[i];
      if (Number(input.value) !== v) input.value = String(v);
      const est = s.predicted ? s.predicted.scales[i] : null;
      out.textContent = String(v);
      out.title = est === null ? '' : `estimate of the example: ${est}`;
      input.setAttribute('aria-valuetext', `${v}${est === null ? '' : ` (the example's estimate: ${est})`}`);
    });
    sameBox.checked = !!s.sameModel;
    sameBox.disabled = !s.predicted;
    const p = s.predicted;
    if (p) {
      const close = p.close !== false;
      predictedEl.textContent = close
        ? `Predicted model: ${nameOf(p.model)}`
        : 'No close model: the example is far from every model in the index. The nearest are below.';
      predictedEl.dataset.model = p.model;
      predictedEl.dataset.close = String(close);
    } else {
      predictedEl.textContent = 'No prediction yet: give an example.';
      delete predictedEl.dataset.model;
      delete predictedEl.dataset.close;
    }
    topEl.replaceChildren(...(p?.top || []).map((c) => {
      const li = document.createElement('li');
      li.dataset.model = c.model;
      li.textContent = `${nameOf(c.model)} — ${(100 * c.probability).toFixed(c.probability < 0.1 ? 1 : 0)}%`;
      return li;
    }));
    topEl.hidden = !p?.top?.length;
    const r = s.retrieved;
    if (r) {
      retrievedEl.textContent = `${nameOf(r.model)}, seed ${r.seed}${r.sample === null ? '' : ` (sample ${r.sample})`}${r.edited ? ' — parameters edited' : ''}`;
      retrievedEl.dataset.model = r.model;
      cosineEl.textContent = r.cosine === null ? '' : `· cosine similarity ${r.cosine.toFixed(3)}${r.edited ? ' (before your edits)' : ''}`;
    } else {
      retrievedEl.textContent = 'Nothing retrieved yet.';
      delete retrievedEl.dataset.model;
      cosineEl.textContent = '';
    }
    buildParams(r);
    drawChart(s);
  }

  // For the e2e tests (ctx.expose).
  const hooks = {
    state,
    pending: () => retrieveTimer !== null || retrieving !== null || rendering !== null || working !== null,
    indexOk: () => indexOk,
  };
  ctx.expose(hooks);

  return {
    render(s, prev) {
      if (!s) return;
      paint(s, prev);
      drawExample(s.source).catch((err) => { if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Example' }); });
      renderRetrieved(s.retrieved);
      // Undo/redo or a loaded document changed the request: its texture is the stored one.
    },
    unmount() {
      ro.disconnect();
      removeFiles();
      retrieving?.abort();
      rendering?.abort();
      working?.abort();
    },
  };
}

export default { id: 'texture', title: 'Texture', state: textureState, mount };
