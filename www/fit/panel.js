// "Fit": find the parameters of a pattern program that best match a target
// (MISSION F10). Pick or edit a program, draw the target with a brush in the
// program's colours, upload (or drop, or paste) an image, or make a target
// from chosen values; the fit runs in workers with a live loss plot and the
// best pattern so far drawn over the target. History, autosave, project
// files and links come from the document controller (app/document.js).
import { acceptFiles, putRgba, hex } from '../ui/file-input.js';
import { download } from '../app/project.js';
import { LossPlot } from '../ui/loss-plot.js';
import { createCodeEditor } from '../ui/code-editor.js';
import { radioGroup } from '../ui/radio-group.js';

// The target's longer side (a drawn target is square; an upload keeps its
// aspect, and the fit's canvas follows it: src/pattern/state.rs).
const TARGET_SIZE = 256;
// A target made from known values is drawn anti-aliased, as a user's image
// of the design would be: the target's fields read the outline from the
// edge pixels' coverage, to a fraction of a pixel.
const TARGET_SUPERSAMPLE = 4;
const rgbOf = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16));
const PREVIEW_EVERY_MS = 250;
const BUDGETS = ['quick', 'paper'];
const LOSSES = ['sdf', 'l1', 'pyramid', 'image'];

const html = `
  <div class="fit-layout">
    <section class="card fit-program" aria-label="Pattern program">
      <label class="inline">Generator <select name="generator" data-testid="fit-generator" data-field="generator"></select></label>
      <div class="muted program-facts" data-testid="fit-facts"></div>
      <button type="button" class="link" data-act="show-program" aria-controls="fit-program-text">Edit the program ↓</button>
      <h3>Parameters</h3>
      <form class="sliders" data-testid="fit-sliders"></form>
      <div class="row-buttons">
        <button type="button" data-act="make-target">Make target from these values</button>
      </div>
    </section>
    <section class="card fit-target" aria-label="Target">
      <div class="toolbar">
        <span class="swatches-inline" role="radiogroup" aria-label="Brush colour" data-testid="fit-brush-colours"></span>
        <label class="inline">size <input type="number" name="brush" min="1" max="64" value="12"></label>
        <button type="button" data-act="clear-target">Clear</button>
      </div>
      <p class="fit-legend muted">Solid: the target. <span class="fit-key">Pink outlines</span>: the pattern of the current values.</p>
      <div class="stack checker">
        <canvas class="target" width="${TARGET_SIZE}" height="${TARGET_SIZE}" data-testid="fit-target" aria-label="target: draw here, or drop an image"></canvas>
        <canvas class="overlay" width="${TARGET_SIZE}" height="${TARGET_SIZE}" data-testid="fit-overlay" aria-hidden="true"></canvas>
      </div>
      <label class="inline">overlay <input type="range" name="overlay" min="0" max="1" step="0.05" value="0.6"></label>
    </section>
    <section class="card fit-run" aria-label="Fitting">
      <div class="fit-settings">
        <label class="inline">Budget <select name="budget" data-field="settings.budget"><option value="quick">quick</option><option value="paper">paper</option></select></label>
        <label class="inline">Loss <select name="loss" data-field="settings.loss">
          <option value="sdf">SDF (paper)</option><option value="l1">L1</option>
          <option value="pyramid">Gaussian pyramid</option><option value="image">image L2</option></select></label>
        <label class="inline">Seed <input type="number" name="seed" min="0" value="1" data-field="settings.seed"></label>
      </div>
      <div class="row-buttons">
        <button type="button" class="primary" data-act="fit" aria-describedby="fit-why">Run fit</button>
        <button type="button" data-act="cancel" disabled title="Stop the fit; its best values so far can then be applied">Stop</button>
        <button type="button" data-act="apply-fit" data-testid="fit-apply" disabled title="Put the stopped fit's best values so far into the document">Apply fitted values</button>
      </div>
      <p class="fit-why" id="fit-why" data-testid="fit-why" hidden></p>
      <progress max="1" value="0"></progress>
      <div class="status muted" data-testid="fit-status" aria-live="polite"></div>
      <canvas class="plot" data-testid="fit-plot" aria-label="loss plot"></canvas>
      <table class="results" data-testid="fit-results"><thead><tr><th>parameter</th><th>fitted</th><th>truth</th></tr></thead><tbody></tbody></table>
      <div class="row-buttons">
        <button type="button" data-act="export-svg">Export SVG</button>
        <button type="button" data-act="export-json">Export JSON</button>
      </div>
    </section>
    <section class="card fit-editor" id="fit-program-text" aria-label="Program text">
      <details class="program">
        <summary>Program</summary>
        <div class="program-editor"></div>
        <div class="row-buttons"><button type="button" data-act="apply-program">Apply program</button></div>
      </details>
    </section>
  </div>`;

// ---- program facts, shared by the view and the state's conversions ------------------

/** The integer values of `values` by name, as pattern-info and fit want them. */
function named(info, values, { integersOnly = false } = {}) {
  return Object.fromEntries(info.params
    .map((p, i) => [p.name, values[i], p.integer])
    .filter(([, , integer]) => !integersOnly || integer)
    .map(([n, v]) => [n, v]));
}

/** pattern-info of `program` with the integer parameters among `values` (when they belong to it). */
function programInfo(run, program, ints = {}) {
  return run('pattern-info', { program, params: ints });
}

function backgroundTarget(info) {
  const [r, g, b] = rgbOf(info.colours[0]);
  const rgba = new Uint8Array(TARGET_SIZE * TARGET_SIZE * 4);
  for (let i = 0; i < rgba.length; i += 4) { rgba[i] = r; rgba[i + 1] = g; rgba[i + 2] = b; rgba[i + 3] = 255; }
  return { width: TARGET_SIZE, height: TARGET_SIZE, rgba };
}

/** Whether target `t` is blank: one colour everywhere (nothing to fit to). */
const blankTargets = new WeakMap();
function isBlank(t) {
  if (!t?.rgba) return true;
  if (!blankTargets.has(t)) {
    const px = new Uint32Array(t.rgba.buffer, t.rgba.byteOffset, t.rgba.length >> 2);
    let blank = true;
    for (let i = 1; i < px.length && blank; i++) blank = px[i] === px[0];
    blankTargets.set(t, blank);
  }
  return blankTargets.get(t);
}

// The overlay is the pattern of the current (or, while fitting, the best)
// values drawn so it cannot pass for the target: its shapes' outlines in a
// colour of no program's palette, their fill faint.
const OUTLINE = [255, 43, 214];
const FILL_ALPHA = 80;
/** In place: `rgba` (w × h) with background `bg` transparent, shapes outlined. */
function overlayLook(rgba, w, h, [br, bg, bb]) {
  const on = new Uint8Array(w * h);
  for (let i = 0, k = 0; k < on.length; i += 4, k++) on[k] = rgba[i] === br && rgba[i + 1] === bg && rgba[i + 2] === bb ? 0 : 1;
  for (let y = 0; y < h; y++) {
    for (let x = 0; x < w; x++) {
      const k = y * w + x, i = 4 * k;
      if (!on[k]) { rgba[i + 3] = 0; continue; }
      const edge = x === 0 || y === 0 || x === w - 1 || y === h - 1 || !on[k - 1] || !on[k + 1] || !on[k - w] || !on[k + w];
      if (edge) { rgba[i] = OUTLINE[0]; rgba[i + 1] = OUTLINE[1]; rgba[i + 2] = OUTLINE[2]; rgba[i + 3] = 255; } else rgba[i + 3] = FILL_ALPHA;
    }
  }
}

/** A fresh document for generator `g` (values at its defaults, an empty target). */
async function generatorDoc(run, g, base) {
  const info = await programInfo(run, g.source);
  return {
    ...base, generator: g.name, program: g.source, values: info.params.map((p) => p.default),
    target: backgroundTarget(info), truth: null, result: null,
  };
}

// ---- the state's schema ----------------------------------------------------------

function invalid(field, why) {
  const e = new Error(`${field} ${why}`);
  e.field = field;
  return e;
}

const finiteList = (v, field, max = 1000) => {
  if (!Array.isArray(v) || v.length > max || !v.every(Number.isFinite)) throw invalid(field, `must be a list of at most ${max} finite numbers`);
  return [...v];
};

// The state's schema (every field, its rules and messages) is the core's:
// src/pattern/state.rs, applied by the document controller (`check-state`).

/** A target as palette indices (a hand-drawn one has a few colours, so a link stays small). */
function indexTarget(t) {
  const px = new Uint32Array(t.rgba.buffer, t.rgba.byteOffset, t.rgba.length / 4);
  const palette = [];
  const index = new Map();
  const out = new Uint8Array(px.length);
  for (let i = 0; i < px.length; i++) {
    let k = index.get(px[i]);
    if (k === undefined) {
      if (palette.length === 256) return null;
      k = palette.length;
      index.set(px[i], k);
      palette.push(px[i]);
    }
    out[i] = k;
  }
  return { palette: new Uint8Array(new Uint32Array(palette).buffer), indices: out, width: t.width, height: t.height };
}

// (A link from before uploads kept their aspect has no width and height: square.)
function unindexTarget(x) {
  const width = x?.width ?? TARGET_SIZE;
  const height = x?.height ?? TARGET_SIZE;
  if (!(x?.palette instanceof Uint8Array) || x.palette.length % 4 || !(x.indices instanceof Uint8Array)
    || !Number.isInteger(width) || !Number.isInteger(height) || x.indices.length !== width * height) {
    throw invalid('target', 'is damaged');
  }
  const rgba = new Uint8Array(width * height * 4);
  const n = x.palette.length / 4;
  for (let i = 0; i < x.indices.length; i++) {
    const k = x.indices[i];
    if (k >= n) throw invalid('target', 'is damaged');
    rgba.set(x.palette.subarray(4 * k, 4 * k + 4), 4 * i);
  }
  return { width, height, rgba };
}

/** The `render-pattern` size fields of a picture `k` times the target's, on the target's canvas. */
const sizeOf = (t, k = 1) => (t ? { size: k * t.width, height: k * t.height } : { size: k * TARGET_SIZE });

const fitState = {
  version: 1,
  async defaults(ctx) {
    const [generators, d] = await Promise.all([ctx.run('pattern-generators', {}), ctx.coreDefaults()]);
    const g = generators.find((x) => x.name === 'circles-grid') || generators[0];
    const settings = {
      budget: BUDGETS.includes(d.budget) ? d.budget : 'quick',
      loss: LOSSES.includes(d.loss) ? d.loss : 'sdf',
      seed: Number.isInteger(d.seed) ? d.seed : 1,
    };
    return generatorDoc(ctx.run, g, { settings });
  },
  migrate: (raw) => raw,
  fileName: (s) => s.generator || 'pattern',
  // A target made from known values travels as those values (re-rendered on
  // arrival, pixel for pixel); a drawn one as palette indices.
  toShare(s) {
    const { target, ...rest } = s;
    if (!target) return { ...rest, target: null };
    if (s.truth) return { ...rest, target: 'truth' };
    const indexed = indexTarget(target);
    return { ...rest, target: indexed ? { indexed } : target };
  },
  async fromShare(x, ctx) {
    if (!x || typeof x !== 'object' || Array.isArray(x)) throw invalid('state', 'is not a Fit document');
    let target = x.target ?? null;
    if (target === 'truth') {
      const truth = finiteList(x.truth, 'truth');
      if (typeof x.program !== 'string') throw invalid('program', 'is missing');
      const info = await programInfo(ctx.run, x.program);
      const full = await programInfo(ctx.run, x.program, named(info, truth, { integersOnly: true }));
      const r = await ctx.run('render-pattern', { program: x.program, params: named(full, truth), size: TARGET_SIZE, supersample: TARGET_SUPERSAMPLE });
      target = { width: r.width, height: r.height, rgba: r.rgba };
    } else if (target?.indexed) target = unindexTarget(target.indexed);
    return { ...x, target };
  },
};

// ---- the view -------------------------------------------------------------------------

function mount(el, ctx) {
  el.innerHTML = html;
  const q = (s) => el.querySelector(s);
  // The program editor (CodeMirror, lazily loaded; a textarea without the bundle).
  let editor = null;
  const editorReady = createCodeEditor(q('.program-editor'), {
    language: 'filigree', label: 'pattern program', attributes: { 'data-testid': 'fit-program', 'data-field': 'program' },
  }).then((ed) => {
    editor = ed;
    if (ctx.state()) ed.setValue(ctx.state().program);
    return ed;
  });
  const targetCanvas = q('canvas.target');
  const stack = q('.stack');
  const tctx = targetCanvas.getContext('2d', { willReadFrequently: true });
  const overlay = q('canvas.overlay');
  const plot = new LossPlot(q('canvas.plot'));
  const statusEl = q('[data-testid=fit-status]');

  let info = null; // pattern-info of the rendered document's program
  let infoKey = null;
  let infoJob = 0;
  let generators = [];
  let brush = 0; // index into the brush colours (last = background)
  let previewBusy = false;
  let previewWanted = null;
  let lastPreviewAt = 0;
  const infoCache = new Map();

  const doc = () => ctx.state();
  const palette = () => info.colours.map(rgbOf);
  const status = (t) => { statusEl.textContent = t; };
  const fmt = (v) => (Math.abs(v) >= 100 ? v.toFixed(1) : v.toFixed(3));

  // The key of a document's program facts: the program and its integer values.
  const keyOf = (d, i) => `${d.program}\u0000${i ? JSON.stringify(named(i, d.values, { integersOnly: true })) : ''}`;

  async function infoFor(program, ints) {
    const key = `${program}\u0000${JSON.stringify(ints)}`;
    if (!infoCache.has(key)) {
      const p = programInfo(ctx.run, program, ints);
      infoCache.set(key, p);
      p.catch(() => infoCache.delete(key));
    }
    return infoCache.get(key);
  }

  // ---- program ------------------------------------------------------------------------

  /** Bring program facts, sliders and brush colours in line with document `d`. */
  async function syncProgram(d) {
    const job = ++infoJob;
    let next;
    try {
      // Integer parameters shape the program (how many shapes it draws).
      const base = await infoFor(d.program, {});
      next = base.params.some((p) => p.integer) ? await infoFor(d.program, named(base, d.values, { integersOnly: true })) : base;
    } catch (err) {
      if (job === infoJob) ctx.error(err);
      return;
    }
    if (job !== infoJob || !ctx.alive()) return;
    info = next;
    infoKey = keyOf(doc(), info);
    renderProgramUi(doc());
    schedulePreview(doc().values);
  }

  function renderProgramUi(d) {
    if (editor && editor.getValue() !== d.program) editor.setValue(d.program);
    q('[name=generator]').value = generators.some((g) => g.name === d.generator) ? d.generator : '';
    q('[data-testid=fit-facts]').textContent =
      `${info.params.filter((p) => !p.integer).length} parameters to fit, ${info.shapes} shapes, ${info.colours.length - 1} colour${info.colours.length === 2 ? '' : 's'} on ${info.colours[0]}`;
    const form = q('form.sliders');
    const values = d.values.length === info.params.length ? d.values : info.params.map((p) => p.default);
    form.replaceChildren(...info.params.map((p, i) => {
      const row = document.createElement('div');
      row.className = 'row';
      row.dataset.param = p.name;
      const label = document.createElement('label');
      label.textContent = p.integer ? `${p.name} (int)` : p.name;
      const input = document.createElement('input');
      Object.assign(input, { type: 'range', min: p.lo, max: p.hi, step: p.integer ? 1 : (p.hi - p.lo) / 1000 });
      input.value = values[i];
      input.setAttribute('aria-label', p.name);
      input.dataset.field = `params.${p.name}`;
      const out = document.createElement('output');
      out.textContent = fmt(values[i]);
      const set = (opts) => {
        const vals = [...currentValues()];
        vals[i] = Number(input.value);
        ctx.commit({ ...doc(), values: vals }, opts);
      };
      // An integer shapes the program (re-read on release); a float previews as it moves.
      input.oninput = () => {
        out.textContent = fmt(Number(input.value));
        if (!p.integer) set({ coalesce: `param-${p.name}` });
      };
      input.onchange = () => {
        if (p.integer) set();
        ctx.seal();
      };
      row.append(label, input, out);
      return row;
    }));
    // Brush colours: the program's colours, then the background (an eraser).
    const sw = q('[data-testid=fit-brush-colours]');
    const colours = [...palette().slice(1), palette()[0]];
    brush = Math.min(brush, colours.length - 1);
    sw.replaceChildren(...colours.map((c, i) => {
      const b = document.createElement('button');
      b.type = 'button';
      b.className = 'swatch-button';
      b.style.background = hex([...c, 255]);
      b.title = i === colours.length - 1 ? `background ${hex([...c, 255])} (erase)` : hex([...c, 255]);
      b.setAttribute('aria-label', b.title);
      b.setAttribute('role', 'radio');
      b.setAttribute('aria-checked', String(i === brush));
      b.onclick = () => { brush = i; sw.querySelectorAll('button').forEach((x, j) => x.setAttribute('aria-checked', String(j === i))); };
      return b;
    }));
    renderResults(d);
  }

  const currentValues = () => {
    const d = doc();
    return info && d.values.length === info.params.length ? d.values : info.params.map((p) => p.default);
  };

  function syncSliders(d) {
    for (const [i, p] of info.params.entries()) {
      const row = q(`form.sliders [data-param="${CSS.escape(p.name)}"]`);
      if (!row || d.values[i] === undefined) continue;
      const input = row.querySelector('input');
      if (Number(input.value) !== d.values[i]) input.value = d.values[i];
      row.querySelector('output').textContent = fmt(d.values[i]);
    }
  }

  // ---- preview: the pattern for the current values, over the target --------------------

  function schedulePreview(values) {
    previewWanted = values;
    if (previewBusy || !info) return;
    const wait = Math.max(0, PREVIEW_EVERY_MS - (performance.now() - lastPreviewAt));
    previewBusy = true;
    ctx.setTimeout(async () => {
      const vals = previewWanted;
      previewWanted = null;
      lastPreviewAt = performance.now();
      try {
        if (vals.length !== info.params.length) return;
        // On the target's canvas, at its size: the overlay is not stretched.
        const r = await ctx.run('render-pattern', { program: doc().program, params: named(info, vals), ...sizeOf(doc().target) });
        // Only the shapes, outlined: background pixels become transparent, so
        // the target shows through wherever the pattern has nothing.
        overlayLook(r.rgba, r.width, r.height, palette()[0]);
        putRgba(overlay, r.width, r.height, r.rgba);
        overlay.dataset.values = JSON.stringify(vals);
      } catch (err) {
        ctx.error(err);
      } finally {
        previewBusy = false;
        if (previewWanted) schedulePreview(previewWanted);
      }
    }, wait);
  }

  // ---- target: drawing, upload, make from values ----------------------------------------

  function storeTarget(extra = {}) {
    const { width, height } = targetCanvas;
    const rgba = new Uint8Array(tctx.getImageData(0, 0, width, height).data.buffer);
    ctx.commit({ ...doc(), ...extra, target: { width, height, rgba } });
  }

  // The target at its own size and aspect; the overlay takes the same.
  function drawTarget(t) {
    if (!t) return;
    if (targetCanvas.width !== t.width || targetCanvas.height !== t.height) {
      targetCanvas.width = overlay.width = t.width;
      targetCanvas.height = overlay.height = t.height;
    }
    stack.style.aspectRatio = `${t.width} / ${t.height}`;
    tctx.putImageData(new ImageData(new Uint8ClampedArray(t.rgba), t.width, t.height), 0, 0);
  }

  // Paint exact palette colours (no anti-aliasing): a disc of `size` pixels.
  function dab(x, y) {
    const colours = [...palette().slice(1), palette()[0]];
    const [r, g, b] = colours[brush];
    const size = Number(q('[name=brush]').value) || 8;
    const rad = size / 2;
    const x0 = Math.max(0, Math.floor(x - rad)), y0 = Math.max(0, Math.floor(y - rad));
    const x1 = Math.min(targetCanvas.width, Math.ceil(x + rad)), y1 = Math.min(targetCanvas.height, Math.ceil(y + rad));
    if (x1 <= x0 || y1 <= y0) return;
    const img = tctx.getImageData(x0, y0, x1 - x0, y1 - y0);
    for (let j = 0; j < y1 - y0; j++) {
      for (let i = 0; i < x1 - x0; i++) {
        if (Math.hypot(x0 + i + 0.5 - x, y0 + j + 0.5 - y) > rad) continue;
        const k = 4 * (j * (x1 - x0) + i);
        img.data[k] = r; img.data[k + 1] = g; img.data[k + 2] = b; img.data[k + 3] = 255;
      }
    }
    tctx.putImageData(img, x0, y0);
  }

  let painting = null;
  let box = null;
  const toTarget = (e) => [(e.clientX - box.left) / box.width * targetCanvas.width, (e.clientY - box.top) / box.height * targetCanvas.height];
  stack.addEventListener('pointerdown', (e) => {
    if (!info || e.button > 0 || ctx.readOnly) return;
    stack.setPointerCapture(e.pointerId);
    box = targetCanvas.getBoundingClientRect();
    painting = toTarget(e);
    dab(...painting);
  });
  stack.addEventListener('pointermove', (e) => {
    if (!painting) return;
    const p = toTarget(e);
    const steps = Math.ceil(Math.hypot(p[0] - painting[0], p[1] - painting[1]) / 2);
    for (let s = 1; s <= steps; s++) dab(painting[0] + (p[0] - painting[0]) * s / steps, painting[1] + (p[1] - painting[1]) * s / steps);
    painting = p;
  });
  const endPaint = () => {
    if (!painting) return;
    painting = null;
    storeTarget({ truth: null });
  };
  stack.addEventListener('pointerup', endPaint);
  stack.addEventListener('pointercancel', endPaint);

  async function makeTarget() {
    const d = doc();
    try {
      const r = await ctx.run('render-pattern', { program: d.program, params: named(info, d.values), size: TARGET_SIZE, supersample: TARGET_SUPERSAMPLE });
      ctx.commit({ ...doc(), target: { width: r.width, height: r.height, rgba: r.rgba }, truth: [...d.values] });
    } catch (err) {
      ctx.error(err);
    }
  }

  async function uploadTarget(file) {
    ctx.clearError();
    try {
      const bytes = new Uint8Array(await file.arrayBuffer());
      const r = await ctx.run('pattern-snap', { program: doc().program, params: named(info, doc().values), bytes, size: TARGET_SIZE });
      ctx.commit({ ...doc(), target: { width: r.width, height: r.height, rgba: r.rgba }, truth: null });
      status(`${file.name}: snapped to the program's colours (${Math.round(r.unmatched * 100)}% of pixels were far from all of them)`);
    } catch (err) {
      ctx.error(err, { prefix: file.name });
    }
  }

  // ---- fitting ----------------------------------------------------------------------------

  // A fit is a job of the document (ctx.startJob): switching tools does not
  // stop it, the tool bar shows its progress, and this panel shows it again
  // when it comes back: its plot, its status, its best so far. Stop keeps
  // the best values so far for "Apply fitted values"; a fit that ends goes
  // into the document it started from (program unchanged), mounted or not.
  let job = null; // the fit this panel shows (running or the last one)
  let unfollow = null;
  let plotted = 0; // job.points already on the plot
  let previewedLoss = Infinity;

  const running = () => !!job?.running;
  const applicable = () => job?.status === 'stopped' && !!job.best && !job.data.appliedBest && doc()?.program === job.data.program;

  // A blank target has nothing to fit to (every pattern is as far from it):
  // Run fit waits for a target and says how to make one.
  function setRunning(on) {
    q('[data-act=cancel]').disabled = !on;
    q('[data-act=apply-fit]').disabled = on || !applicable();
    const blank = isBlank(doc()?.target);
    q('[data-act=fit]').disabled = on || blank;
    const why = q('[data-testid=fit-why]');
    why.hidden = on || !blank;
    why.textContent = blank ? 'The target is empty, so there is nothing to fit yet: draw on it in the pattern’s colours, upload an image, or press “Make target from these values”.' : '';
  }

  /** A change that makes the running fit meaningless cancels it, saying why. */
  function stopFit(reason = 'the program changed') {
    job?.stop(reason);
    setRunning(false);
  }

  function fit() {
    const d = doc();
    if (!d?.target || !info || isBlank(d.target)) return;
    ctx.clearError();
    // The figures of the last fit are stale from here on.
    q('.results tbody').querySelectorAll('[data-col=fitted]').forEach((td) => { td.textContent = '…'; });
    const fitInfo = info;
    const floatIdx = fitInfo.params.map((p, i) => (p.integer ? -1 : i)).filter((i) => i >= 0);
    const full = (floats) => {
      const values = [...d.values];
      floatIdx.forEach((k, j) => { values[k] = floats[j]; });
      return values;
    };
    // A fresh payload per request: its pixel buffer is transferred to a worker.
    const payload = () => ({
      program: d.program, params: named(fitInfo, d.values, { integersOnly: true }),
      target_rgba: { ...d.target, rgba: d.target.rgba.slice() },
      budget: d.settings.budget, loss: d.settings.loss, seed: d.settings.seed,
    });
    const started = ctx.startJob('fit', { label: 'Fit' }, async (j) => {
      // One fit sharded across the worker pool (all workers but one, which
      // stays free for previews). The pool relays the shards' exchanges and
      // the core merges them, so the result is exactly that of one fit
      // (tests/fit.rs checks this with the native driver).
      const n = Math.max(1, ctx.pool.slots.length - 1);
      const fractions = Array(n).fill(0);
      const losses = Array(n).fill(Infinity);
      const r = await j.runSharded('fit', payload(), {
        shards: n,
        onProgress: (p, k) => {
          fractions[k] = p.fraction;
          if (p.figure != null) losses[k] = p.figure;
          const loss = Math.min(...losses);
          const fraction = fractions.reduce((a, b) => a + b, 0) / n;
          // The global stage (spectra, then the phase sweep) has no loss to
          // plot until its sweep: the plot shades how far it has come.
          if (/^global search/.test(p.stage)) j.data.global = Math.max(j.data.global ?? 0, fraction);
          const better = p.values && losses[k] === loss && loss < (j.best?.loss ?? Infinity);
          j.report({ fraction, stage: n > 1 ? `${p.stage} (${n} workers)` : p.stage, figure: loss }, {
            point: Number.isFinite(loss) ? [fraction, loss] : null,
            ...(better ? { best: { values: full(p.values), params: [...p.values], loss } } : {}),
          });
        },
      });
      // A fit finishes into the document it started from, or not at all.
      j.data.applied = j.commit((cur) => (cur.program !== d.program ? null : {
        ...cur, values: full(r.params).map((v, i) => (floatIdx.includes(i) ? v : cur.values[i])),
        result: { params: r.params, loss: r.loss, names: r.names, evaluations: r.evaluations },
      }));
      j.report({ fraction: 1 }, { point: [1, r.loss] });
      return r;
    });
    started.data = { program: d.program };
    attach(started);
  }

  /** Show job `j` in this panel (a new fit, or one found on coming back). */
  function attach(j) {
    unfollow?.();
    job = j;
    plot.clear();
    plotted = 0;
    previewedLoss = Infinity;
    unfollow = ctx.follow(j, showJob);
    showJob(j);
  }

  function showJob(j) {
    if (j !== job || !ctx.alive()) return;
    if (j.data?.global) plot.shade(j.data.global, 'global search');
    for (; plotted < j.points.length; plotted++) plot.push(...j.points[plotted]);
    const pct = Math.round(100 * j.progress.fraction);
    q('progress').value = j.status === 'done' ? 1 : j.progress.fraction;
    const loss = j.progress.figure;
    if (j.running) {
      status(`${j.progress.stage} ${pct}% — loss ${Number.isFinite(loss) ? loss.toPrecision(4) : '…'}`);
      // The best candidate so far over the target.
      if (j.best && j.best.loss < previewedLoss) { previewedLoss = j.best.loss; schedulePreview(j.best.values); }
    } else if (j.status === 'done') {
      const r = j.result;
      const secs = ((j.endedAt - j.startedAt) / 1000).toFixed(1);
      // One loss, named (the polish's image-space loss is a different one).
      status(`fitted in ${secs} s — loss ${r.loss.toPrecision(4)} (${r.loss_name}) after ${r.evaluations} evaluations${j.data.applied ? '' : ' (not applied: the program changed meanwhile)'}`);
    } else if (j.status === 'stopped') {
      status(j.best
        ? `stopped at ${pct}% — the values from before the fit are kept; Apply fitted values puts in the best so far (loss ${j.best.loss.toPrecision(4)})`
        : `stopped at ${pct}% — no candidate yet; the values from before the fit are kept`);
    } else if (j.status === 'cancelled') {
      status(`cancelled at ${pct}% (${j.reason}) — the values from before the fit are kept`);
    } else if (j.status === 'failed') {
      status('the fit failed (see above)');
      ctx.error(j.error);
    }
    if (!j.running) {
      // The overlay showed the fit's candidates: back to the document's values.
      if (j.status !== 'done' && doc()) schedulePreview(doc().values);
      renderResults(doc());
    }
    setRunning(j.running);
  }

  function applyFit() {
    if (!applicable()) return;
    const { best } = job;
    if (ctx.commit({ ...doc(), values: best.values, result: { params: best.params, loss: best.loss, names: null, evaluations: null } })) {
      status(`applied: the stopped fit's best values (loss ${best.loss.toPrecision(4)}); Undo puts the earlier ones back`);
      job.data.appliedBest = true;
      setRunning(false);
    }
  }

  function renderResults(d) {
    if (!info || info.params.length !== d.values.length) return;
    q('.results tbody').replaceChildren(...info.params.filter((p) => !p.integer).map((p) => {
      const i = info.params.indexOf(p);
      const tr = document.createElement('tr');
      tr.dataset.param = p.name;
      const cells = [p.name, d.result ? fmt(d.values[i]) : '—', d.truth ? fmt(d.truth[i]) : '—'];
      tr.replaceChildren(...cells.map((text, j) => {
        const td = document.createElement('td');
        td.textContent = text;
        if (j) td.dataset.col = j === 1 ? 'fitted' : 'truth';
        return td;
      }));
      return tr;
    }));
  }

  // ---- controls -------------------------------------------------------------------------------

  q('[name=generator]').onchange = async (e) => {
    const g = generators.find((x) => x.name === e.target.value);
    if (!g) return;
    // A new generator ends the fit of the old one: its values would not fit the new sliders.
    stopFit('the generator changed');
    try {
      ctx.commit(await generatorDoc(ctx.run, g, doc()));
    } catch (err) {
      ctx.error(err);
      q('[name=generator]').value = doc()?.generator ?? '';
    }
  };
  q('[data-act=apply-program]').onclick = async () => {
    const program = editor ? editor.getValue() : doc().program;
    const d = doc();
    try {
      const next = await programInfo(ctx.run, program);
      ctx.clearError();
      editor?.clearError();
      const same = info && next.params.length === info.params.length && next.params.every((p, i) => p.name === info.params[i].name);
      if (program !== d.program) stopFit();
      ctx.commit({
        ...d, program, generator: null,
        values: same ? d.values : next.params.map((p) => p.default),
        truth: same ? d.truth : null, result: null,
      });
    } catch (err) {
      // Keep the last good program running; say where this one is wrong.
      ctx.error(err);
    }
  };
  q('[data-act=make-target]').onclick = () => makeTarget();
  q('[data-act=show-program]').onclick = () => {
    q('details.program').open = true;
    q('.fit-editor').scrollIntoView({ block: 'start', behavior: 'smooth' });
    editorReady.then((ed) => ctx.alive() && ed.focus());
  };
  q('[data-act=clear-target]').onclick = () => info && ctx.commit({ ...doc(), target: backgroundTarget(info), truth: null });
  q('[data-act=fit]').onclick = fit;
  q('[data-act=cancel]').onclick = () => job?.stop();
  q('[data-act=apply-fit]').onclick = applyFit;
  q('[name=overlay]').oninput = (e) => { overlay.style.opacity = e.target.value; };
  overlay.style.opacity = q('[name=overlay]').value;
  for (const name of ['budget', 'loss', 'seed']) {
    q(`[name=${name}]`).onchange = (e) => {
      const v = name === 'seed' ? Math.max(0, Math.round(Number(e.target.value) || 0)) : e.target.value;
      ctx.commit({ ...doc(), settings: { ...doc().settings, [name]: v } });
    };
  }
  // The target takes a dropped, pasted or picked image like Pixel's source does.
  const detachFiles = acceptFiles(q('.fit-target'), uploadTarget, { pickerLabel: 'Upload target…' });
  const detachRadios = radioGroup(q('[data-testid=fit-brush-colours]'));
  q('.fit-target input[type=file]').dataset.input = 'target';

  const baseName = () => doc()?.generator || 'pattern';
  q('[data-act=export-svg]').onclick = async () => {
    try {
      // Twice the target's size, on its canvas (512 px along the longer side).
      const r = await ctx.run('render-pattern', { program: doc().program, params: named(info, doc().values), ...sizeOf(doc().target, 2) });
      download(`${baseName()}.svg`, r.svg, 'image/svg+xml');
    } catch (err) {
      ctx.error(err);
    }
  };
  q('[data-act=export-json]').onclick = () => {
    const d = doc();
    const params = Object.fromEntries(info.params.map((p, i) => [p.name, d.values[i]]));
    // The program travels with its values: the file alone re-renders the pattern (`filigree render`).
    download(`${baseName()}-params.json`, JSON.stringify({ generator: d.generator, program: d.program, params, loss: d.result?.loss ?? null }, null, 2), 'application/json');
  };

  const generatorsReady = ctx.run('pattern-generators', {}).then((list) => {
    generators = list;
    q('[name=generator]').replaceChildren(
      new Option('(custom program)', ''),
      ...generators.map((g) => new Option(g.paper ? `${g.name} — ${g.paper}` : g.name, g.name)),
    );
    const d = doc();
    if (d) q('[name=generator]').value = generators.some((g) => g.name === d.generator) ? d.generator : '';
  }).catch((err) => ctx.error(err));

  // For the e2e tests (ctx.expose): the document, the program's parameters, the loss plot.
  ctx.expose({ state: doc, info: () => info, plot, running, job: () => job });
  // A fit of this document that ran (or ran on) while the panel was away.
  if (ctx.job('fit')) attach(ctx.job('fit'));

  return {
    render(d, prev) {
      if (!d) return;
      for (const name of ['budget', 'loss', 'seed']) q(`[name=${name}]`).value = d.settings[name];
      if (!prev || d.target !== prev.target) { drawTarget(d.target); setRunning(running()); }
      else if (job && !job.running) setRunning(false); // Apply fitted values follows the document
      if (!info || keyOf(d, info) !== infoKey) {
        // A program or integer change: re-read the program (async), then sliders and preview.
        generatorsReady.then(() => ctx.alive() && syncProgram(d));
      } else {
        syncSliders(d);
        renderResults(d);
        if (!prev || d.values !== prev.values) schedulePreview(d.values);
      }
    },
    markError(err) {
      if (err.field !== 'program' && err.kind !== 'syntax') return;
      q('details.program').open = true;
      // line/column come with the error (or, from an older core, in its message).
      const m = /line (\d+), column (\d+)/.exec(err.message || '');
      const at = Number.isInteger(err.line) ? [err.line, err.column ?? 1] : m && [Number(m[1]), Number(m[2])];
      if (at) editorReady.then((ed) => ctx.alive() && ed.markError(at[0], at[1], err.message));
    },
    unmount() {
      detachFiles();
      detachRadios();
      // The fit runs on: it is the document's (ctx.startJob).
    },
  };
}

export default { id: 'fit', title: 'Fit', state: fitState, mount };
