// "Pixel": texture pixel art with oriented elements (MISSION P1–P6).
// The user loads a source, a mask and an element sheet (or one click on an
// example), paints the mask, draws orientation strokes on a zoomable pixel
// grid, and moves parameters; the core re-runs in a worker after each change
// (debounced, the previous run cancelled). History, autosave, project files
// and links come from the document controller (app/document.js).
//
// The picture is a CanvasView (canvas-view.js), so a brush drag never re-lays
// out or redraws it all: the base layer holds the source or the result at
// its own resolution (scaled by CSS); the mask overlay and the stroke layer
// cover only the visible part at screen resolution, and each animation frame
// repaints just the rectangle the brush or the new stroke segment touched.
// The pixel grid is a CSS background.
import { acceptFiles, putRgba, hex } from '../ui/file-input.js';
import { radioGroup } from '../ui/radio-group.js';
import { CanvasView } from './canvas-view.js';
import { download } from '../app/project.js';

const ASSETS = new URL('../../assets/pixel/', import.meta.url);
const EXAMPLES = ['fish', 'trunk'];
const DIRECTIONS = ['up', 'up-right', 'right', 'down-right', 'down', 'down-left', 'left', 'up-left'];
const RUN_DELAY_MS = 120;
const MAX_SIDE = 4096;
const MASK_RGBA = [127, 209, 199, 90];

/** Parameter controls, generated into the side panel. Keys are the core's PixelParams fields. */
const CONTROLS = [
  { key: 'positions', label: 'Positions', type: 'select', options: ['random', 'packed'] },
  { key: 'density', label: 'Density ρ', type: 'range', min: 0, max: 1, step: 0.01, show: (v) => `${Math.round(v * 100)}%` },
  { key: 'margins', label: 'Margins mx, my', type: 'ints', n: 2, min: -8, max: 16 },
  { key: 'partial', label: 'Partial elements at the mask edge', type: 'checkbox' },
  { key: 'colour', label: 'Colour map', type: 'select', options: ['auto', 'border', 'difference', 'hsv'] },
  { key: 'd_max', label: 'd_max (auto)', type: 'range', min: 0, max: 150, step: 1, show: (v) => String(v) },
  { key: 'hsv', label: 'HSV shift h°, s, v', type: 'ints', n: 3, min: -180, max: 180 },
  { key: 'exclude', label: 'Excluded colours', type: 'colours' },
  { key: 'element_colour', label: 'Element colour', type: 'select', options: ['region', 'pixel'] },
  { key: 'annotation_scale', label: 'Annotation scale K', type: 'range', min: 1, max: 32, step: 1, show: (v) => `×${v}` },
  { key: 'default_direction', label: 'Direction without strokes', type: 'select', options: DIRECTIONS },
  { key: 'seed', label: 'Seed', type: 'seed' },
];

const html = `
  <div class="pixel-layout">
    <div class="card pixel-stage">
      <div class="toolbar" role="toolbar" aria-label="Pixel tools">
        <span class="group">
          <button type="button" data-example="fish" aria-pressed="false">Fish example</button>
          <button type="button" data-example="trunk" aria-pressed="false">Trunk example</button>
        </span>
        <span class="group" role="radiogroup" aria-label="Brush">
          <button type="button" data-mode="stroke" role="radio" aria-checked="true" title="Draw orientation strokes (S)">✎ Strokes</button>
          <button type="button" data-mode="paint" role="radio" aria-checked="false" title="Paint the mask (M)">▣ Paint mask</button>
          <button type="button" data-mode="erase" role="radio" aria-checked="false" title="Erase the mask (E)">▢ Erase mask</button>
        </span>
        <label class="inline">size <input type="number" name="brush" min="1" max="32" value="3"></label>
        <span class="group">
          <button type="button" data-act="zoom-out" aria-label="Zoom out">−</button>
          <span class="zoom" data-testid="zoom">×4</span>
          <button type="button" data-act="zoom-in" aria-label="Zoom in">+</button>
        </span>
        <span class="group">
          <button type="button" data-act="clear-strokes">Clear strokes</button>
        </span>
      </div>
      <div class="toggles">
        <label><input type="checkbox" name="show-result" checked> result</label>
        <label><input type="checkbox" name="show-mask"> mask</label>
        <label><input type="checkbox" name="show-strokes" checked> strokes</label>
        <label><input type="checkbox" name="show-arrows"> vector field</label>
        <span class="status muted" data-testid="pixel-status" aria-live="polite"></span>
      </div>
      <div class="viewport checker" data-testid="pixel-viewport">
        <div class="empty muted">Load an example, or drop a source image here.</div>
      </div>
      <dl class="stats" data-testid="pixel-stats"></dl>
    </div>
    <aside class="card pixel-side">
      <h3>Inputs</h3>
      <div class="inputs">
        <label>Source <input type="file" accept="image/*" data-input="source" data-field="source"></label>
        <label>Mask <input type="file" accept="image/*" data-input="mask" data-field="mask"></label>
        <label>Element sheet (3×3) <input type="file" accept="image/*" data-input="sheet" data-field="sheet"></label>
        <label>…or one sprite <input type="file" accept="image/*" data-input="sprite" data-field="sprite"></label>
        <div class="elements"><canvas class="sheet-preview pixelated" aria-label="elements"></canvas><span class="muted" data-field="elements"></span></div>
      </div>
      <h3>Parameters</h3>
      <form class="params" data-testid="pixel-params"></form>
      <h3>Export</h3>
      <div class="exports">
        <label class="inline">PNG scale <select name="export-scale"><option>1</option><option>2</option><option selected>4</option><option>8</option></select></label>
        <button type="button" data-act="export-png">Export PNG</button>
      </div>
    </aside>
  </div>`;

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
async function exampleDoc(name, ctx) {
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

// ---- the state's schema ----------------------------------------------------------

function invalid(field, why) {
  const e = new Error(`${field} ${why}`);
  e.field = field;
  return e;
}

// The state's schema (every field, its rules and messages) is the core's:
// src/pixel/state.rs, applied by the document controller (`check-state`).

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

const pixelState = {
  version: 1,
  defaults: (ctx) => exampleDoc('fish', ctx),
  migrate: (raw) => raw,
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

// ---- the view -----------------------------------------------------------------------

function mount(el, ctx) {
  el.innerHTML = html;
  const q = (s) => el.querySelector(s);
  const statusEl = q('[data-testid=pixel-status]');

  // Derived, not saved: decoded images, the last result, view settings.
  const view = { mode: 'stroke', brush: 3, showResult: true, showMask: false, showStrokes: true, showArrows: false };
  let sourceImg = null; // {width, height} of the decoded source
  let sourceBitmap = null;
  let sourceOf = null; // the source bytes sourceImg was decoded from
  let sourceLoading = null;
  let loadingFor = null; // the source bytes being decoded
  let result = null; // the core's answer for the current state, or the last good one
  let resultBitmap = null;
  let running = null; // AbortController of the job in flight
  let runTimer = null;
  let drawing = null; // the stroke or mask edit in progress

  // The picture: base (source or result), mask overlay, strokes and arrows.
  const canvas = new CanvasView(q('.viewport'), { integer: true, maxZoom: 32, onPaint: paintStrokes });
  const stack = canvas.element;
  stack.classList.add('layers');
  stack.dataset.testid = 'pixel-canvas';
  stack.setAttribute('role', 'img');
  stack.setAttribute('aria-label', 'pixel art: draw strokes or paint the mask here');
  canvas.overlay.classList.add('mask-layer');
  canvas.maskRgba = MASK_RGBA;
  stack.addEventListener('zoom', () => showZoom());

  const state = () => ctx.state();
  const status = (text) => { statusEl.textContent = text; };

  // ---- inputs -----------------------------------------------------------------------

  async function loadExample(name) {
    ctx.clearError();
    status(`loading the ${name} example…`);
    try {
      const doc = await exampleDoc(name, ctx);
      // Examples replace the work as an undoable step.
      ctx.commit(doc);
    } catch (err) {
      status('');
      ctx.error(err, { prefix: `The ${name} example` });
    }
  }

  async function loadInput(which, file) {
    ctx.clearError();
    const bytes = new Uint8Array(await file.arrayBuffer());
    const doc = state();
    try {
      if (which === 'source') {
        const img = await ctx.run('decode-image', { bytes: bytes.slice() });
        // An example's mask and strokes were drawn for the example's picture: your own
        // source starts with a full mask and no strokes. Over your own source, a new one
        // keeps the mask when the sizes agree (else a full one), and the strokes rescaled
        // to the new size so they stay on the same part of the picture.
        const own = doc && doc.example == null;
        const keepMask = own && doc.mask && doc.mask.width === img.width && doc.mask.height === img.height;
        const mask = keepMask ? doc.mask : { width: img.width, height: img.height, bits: new Uint8Array(img.width * img.height).fill(1) };
        const sx = own ? img.width / doc.mask.width : 1, sy = own ? img.height / doc.mask.height : 1;
        const strokes = (own ? doc.strokes : []).map((s) => s.map(([x, y]) => [Math.round(x * sx * 100) / 100, Math.round(y * sy * 100) / 100]));
        ctx.commit({
          ...doc, example: null, source: bytes, mask, strokes, names: { ...(doc?.names || {}), source: file.name },
        });
        return;
      }
      if (!doc) throw new Error('load a source image first');
      if (which === 'mask') {
        const mask = await ctx.run('pixel-mask', { bytes });
        if (mask.width !== doc.mask.width || mask.height !== doc.mask.height) {
          throw new Error(`the mask is ${mask.width}×${mask.height} pixels but the source image is ${doc.mask.width}×${doc.mask.height}; they must be the same size`);
        }
        ctx.commit({ ...doc, mask });
      } else {
        await ctx.run('decode-image', { bytes: bytes.slice() });
        ctx.commit({ ...doc, sheet: which === 'sheet' ? bytes : null, sprite: which === 'sprite' ? bytes : null, names: { ...doc.names, sheet: file.name } });
      }
    } catch (err) {
      if (!err.field) err.field = which;
      ctx.error(err, { prefix: file.name });
    }
  }

  async function showElements(doc) {
    const bytes = doc.sheet || doc.sprite;
    const c = q('.sheet-preview');
    if (!bytes) { c.width = c.height = 0; q('[data-field=elements]').textContent = 'no elements yet'; return; }
    try {
      const img = await ctx.run('decode-image', { bytes: bytes.slice() });
      putRgba(c, img.width, img.height, img.rgba);
      q('[data-field=elements]').textContent = `${doc.sheet ? 'sheet' : 'sprite'} ${img.width}×${img.height}`;
    } catch (err) {
      ctx.error(err, { prefix: 'Element sheet' });
    }
  }

  // ---- running the core ---------------------------------------------------------------

  function scheduleRun() {
    ctx.clearTimeout(runTimer);
    runTimer = ctx.setTimeout(() => { runTimer = null; run(); }, RUN_DELAY_MS);
  }

  async function run() {
    const doc = state();
    if (!doc || !(doc.sheet || doc.sprite)) return;
    running?.abort();
    const ctrl = new AbortController();
    running = ctrl;
    status('texturing…');
    // The figures on screen belong to the previous run: clear them while this one works.
    q('.stats').replaceChildren();
    const t0 = performance.now();
    try {
      const r = await ctx.run('pixel', {
        source: doc.source.slice(), sheet: doc.sheet?.slice(), sprite: doc.sprite?.slice(),
        mask: { width: doc.mask.width, height: doc.mask.height, bits: doc.mask.bits.slice() },
        strokes: doc.strokes, params: doc.params,
      }, {
        signal: ctrl.signal,
        onProgress: (p) => {
          if (running !== ctrl) return;
          const pct = Number.isFinite(p.fraction) ? ` ${Math.round(p.fraction * 100)}%` : '';
          status(`texturing: ${p.stage}${pct}`);
        },
      });
      if (running !== ctrl) return;
      const bitmap = await ctx.bitmap(new ImageData(new Uint8ClampedArray(r.rgba), r.width, r.height));
      if (running !== ctrl) { ctx.release(bitmap); return; }
      result = r;
      ctx.release(resultBitmap);
      resultBitmap = bitmap;
      ctx.clearError('run');
      status(`done in ${Math.round(performance.now() - t0)} ms`);
      showStats(r);
      drawBase();
      drawStrokes();
      // Counts finished runs, so a test (or a person) can tell two results apart.
      statusEl.dataset.runs = String(Number(statusEl.dataset.runs || 0) + 1);
    } catch (err) {
      if (err.kind === 'cancelled') return;
      // Keep the last good result on screen; say what is wrong now.
      ctx.error(err, { source: 'run' });
      status('');
    } finally {
      if (running === ctrl) running = null;
    }
  }

  function showStats(r) {
    const rows = [
      ['Elements placed', r.placed], ['Colours before', r.colours_before], ['Colours after', r.colours_after],
      ['Colour map', r.colour_map_used],
    ];
    q('.stats').replaceChildren(...rows.flatMap(([k, v]) => {
      const dt = document.createElement('dt'); dt.textContent = k;
      const dd = document.createElement('dd'); dd.textContent = String(v); dd.dataset.stat = k;
      return [dt, dd];
    }));
  }

  // ---- layers ---------------------------------------------------------------------------

  /** Decode the document's source and size every layer for it. */
  function loadSource(doc) {
    const bytes = doc.source;
    loadingFor = bytes;
    const job = (async () => {
      const img = await ctx.run('decode-image', { bytes: bytes.slice() });
      const bitmap = await ctx.bitmap(new ImageData(new Uint8ClampedArray(img.rgba), img.width, img.height));
      if (state()?.source !== bytes) { ctx.release(bitmap); return; }
      ctx.release(sourceBitmap);
      sourceBitmap = bitmap;
      sourceImg = { width: img.width, height: img.height };
      sourceOf = bytes;
      // The old result belongs to the old source.
      result = null;
      ctx.release(resultBitmap);
      resultBitmap = null;
      q('.stats').replaceChildren();
      canvas.setImage(sourceBitmap, img.width, img.height);
      canvas.setMask(state().mask);
      drawBase();
      q('.empty').hidden = true;
    })().catch((err) => ctx.error(err, { prefix: 'Source image' })).finally(() => {
      if (sourceLoading === job) { sourceLoading = null; loadingFor = null; }
    });
    sourceLoading = job;
  }

  function showZoom() {
    const z = canvas.zoom;
    q('[data-testid=zoom]').textContent = `×${z >= 1 ? z : Number(z.toFixed(2))}`;
    stack.style.setProperty('--cell', `${z}px`);
    stack.classList.toggle('grid', z >= 8);
  }

  function drawBase() {
    if (!sourceImg) return;
    const base = view.showResult && resultBitmap ? resultBitmap : sourceBitmap;
    if (base) canvas.setImage(base, sourceImg.width, sourceImg.height);
  }

  function maskVisible() {
    return view.showMask || view.mode !== 'stroke';
  }

  /** The mask overlay: the drag's working copy while painting, else the document's. */
  function drawMaskFull() {
    const m = drawing?.kind === 'mask' ? drawing.mask : state()?.mask;
    canvas.showMask = maskVisible();
    canvas.setMask(m && sourceImg && m.width === sourceImg.width && m.height === sourceImg.height ? m : null);
  }

  /** Repaint the whole stroke layer (strokes, arrows) at the next frame. */
  function drawStrokes() {
    canvas.invalidate(null, 'strokes');
  }

  // The stroke layer's painter (CanvasView onPaint): `g` draws in image pixels,
  // clipped to `r`, the rectangle to repaint.
  function paintStrokes(g, zoom, r) {
    const doc = state();
    if (!doc || !sourceImg) return;
    if (view.showArrows && result?.field && result.width === sourceImg.width) drawArrows(g, result.field, sourceImg.width, sourceImg.height, r);
    if (view.showStrokes) {
      for (const st of doc.strokes) drawStroke(g, st, '#ff5db1');
      if (drawing?.kind === 'stroke') drawStroke(g, drawing.points, '#ffd166', false);
    }
  }

  // Widths are in screen pixels; the layer draws in source pixels.
  const px = (css) => css / canvas.zoom;
  const strokeWidth = () => px(Math.max(1.5, canvas.zoom / 3));

  function drawStroke(g, points, colour, head = true) {
    if (points.length < 2) return;
    g.strokeStyle = colour;
    g.lineWidth = strokeWidth();
    g.lineCap = g.lineJoin = 'round';
    g.beginPath();
    points.forEach(([x, y], i) => (i ? g.lineTo(x, y) : g.moveTo(x, y)));
    g.stroke();
    if (!head) return;
    const [x1, y1] = points[points.length - 1];
    const [x0, y0] = points[Math.max(0, points.length - 4)];
    arrowHead(g, x0, y0, x1, y1, px(Math.max(6, canvas.zoom * 1.5)), colour);
  }

  function arrowHead(g, x0, y0, x1, y1, size, colour) {
    const a = Math.atan2(y1 - y0, x1 - x0);
    g.fillStyle = colour;
    g.beginPath();
    g.moveTo(x1, y1);
    g.lineTo(x1 - size * Math.cos(a - 0.45), y1 - size * Math.sin(a - 0.45));
    g.lineTo(x1 - size * Math.cos(a + 0.45), y1 - size * Math.sin(a + 0.45));
    g.fill();
  }

  // The diffused field as small arrows, one per cell of `step` pixels inside the mask (only the cells in `r`).
  function drawArrows(g, field, w, h, r) {
    const z = canvas.zoom;
    const step = Math.max(1, Math.ceil(12 / z));
    const mask = state().mask.bits;
    const colour = 'rgba(255, 255, 255, 0.85)';
    g.strokeStyle = colour;
    g.lineWidth = px(1);
    const first = (lo) => Math.floor(step / 2) + Math.max(0, Math.floor((lo - step) / step)) * step;
    for (let y = first(r.y); y < Math.min(h, r.y + r.h + step); y += step) {
      for (let x = first(r.x); x < Math.min(w, r.x + r.w + step); x += step) {
        if (!mask[y * w + x]) continue;
        const vx = field[2 * (y * w + x)], vy = field[2 * (y * w + x) + 1];
        const len = Math.hypot(vx, vy);
        if (len < 1e-6) continue;
        const L = step * 0.42;
        const cx = x + 0.5, cy = y + 0.5;
        const dx = (vx / len) * L, dy = (vy / len) * L;
        g.beginPath();
        g.moveTo(cx - dx, cy - dy);
        g.lineTo(cx + dx, cy + dy);
        g.stroke();
        arrowHead(g, cx - dx, cy - dy, cx + dx, cy + dy, Math.max(px(3), L * 0.5), colour);
      }
    }
  }

  // ---- pointer input: strokes and mask painting ----------------------------------------

  // Image coordinates of a pointer event, kept inside the image (a drag may leave the canvas).
  const clamp = (v, hi) => Math.max(0, Math.min(hi, v));
  const toPixel = (e) => {
    const [x, y] = canvas.toImage(e);
    return [clamp(x, sourceImg.width), clamp(y, sourceImg.height)];
  };

  function paintAt([fx, fy], on) {
    const m = drawing.mask;
    const r = view.brush / 2;
    const x0 = Math.max(0, Math.floor(fx - r)), x1 = Math.min(m.width - 1, Math.floor(fx + r));
    const y0 = Math.max(0, Math.floor(fy - r)), y1 = Math.min(m.height - 1, Math.floor(fy + r));
    if (x1 < x0 || y1 < y0) return;
    for (let y = y0; y <= y1; y++) {
      for (let x = x0; x <= x1; x++) {
        if (Math.hypot(x + 0.5 - fx, y + 0.5 - fy) > Math.max(r, 0.5)) continue;
        m.bits[y * m.width + x] = on ? 1 : 0;
      }
    }
    // The overlay repaints this rectangle at the next frame (coalesced with the other moves of the frame).
    canvas.maskChanged({ x: x0, y: y0, w: x1 - x0 + 1, h: y1 - y0 + 1 });
  }

  stack.addEventListener('pointerdown', (e) => {
    if (!state() || !sourceImg || e.button > 0 || ctx.readOnly) return;
    stack.setPointerCapture(e.pointerId);
    const p = toPixel(e);
    if (view.mode === 'stroke') {
      drawing = { kind: 'stroke', points: [p] };
    } else {
      const m = state().mask;
      drawing = { kind: 'mask', mask: { width: m.width, height: m.height, bits: m.bits.slice() } };
      canvas.setMask(drawing.mask);
      paintAt(p, view.mode === 'paint');
    }
  });

  stack.addEventListener('pointermove', (e) => {
    if (!drawing) return;
    const events = e.getCoalescedEvents?.().length ? e.getCoalescedEvents() : [e];
    for (const ev of events) {
      const p = toPixel(ev);
      if (drawing.kind === 'stroke') {
        const last = drawing.points[drawing.points.length - 1];
        if (Math.hypot(p[0] - last[0], p[1] - last[1]) < 0.25) continue;
        drawing.points.push(p);
        // Repaint only around the new segment (the layer adds its own margin for the line width).
        const x = Math.min(last[0], p[0]), y = Math.min(last[1], p[1]);
        canvas.invalidate({ x, y, w: Math.abs(p[0] - last[0]), h: Math.abs(p[1] - last[1]) }, 'strokes');
      } else {
        paintAt(p, view.mode === 'paint');
      }
    }
  });

  const endDrawing = () => {
    if (!drawing) return;
    const d = drawing;
    drawing = null;
    if (d.kind === 'stroke') {
      if (d.points.length >= 2) {
        const pts = d.points.map(([x, y]) => [Math.round(x * 100) / 100, Math.round(y * 100) / 100]);
        ctx.commit({ ...state(), strokes: [...state().strokes, pts] });
      } else drawStrokes();
    } else {
      // The whole brush drag is one undo step.
      ctx.commit({ ...state(), mask: d.mask });
    }
  };
  stack.addEventListener('pointerup', endDrawing);
  stack.addEventListener('pointercancel', endDrawing);

  // ---- controls -----------------------------------------------------------------------------

  const form = q('form.params');
  for (const c of CONTROLS) form.append(controlRow(c));

  function controlRow(c) {
    const row = document.createElement('div');
    row.className = 'row';
    row.dataset.key = c.key;
    const label = document.createElement('label');
    label.textContent = c.label;
    const id = `pixel-${c.key}`;
    label.htmlFor = id;
    row.append(label);
    const set = (value, opts) => {
      const doc = state();
      if (!doc) return;
      ctx.commit({ ...doc, params: { ...doc.params, [c.key]: value } }, opts);
    };
    let input;
    if (c.type === 'select') {
      input = document.createElement('select');
      for (const o of c.options) input.append(new Option(o, o));
      input.onchange = () => set(input.value);
    } else if (c.type === 'range') {
      input = document.createElement('input');
      Object.assign(input, { type: 'range', min: c.min, max: c.max, step: c.step });
      const out = document.createElement('output');
      row.append(out);
      input.oninput = () => set(Number(input.value), { coalesce: c.key });
      input.onchange = () => ctx.seal();
    } else if (c.type === 'checkbox') {
      input = document.createElement('input');
      input.type = 'checkbox';
      input.onchange = () => set(input.checked);
    } else if (c.type === 'ints') {
      input = document.createElement('span');
      input.className = 'ints';
      for (let i = 0; i < c.n; i++) {
        const n = document.createElement('input');
        Object.assign(n, { type: 'number', min: c.min, max: c.max, step: 1 });
        n.setAttribute('aria-label', `${c.label} ${i + 1}`);
        n.onchange = () => {
          const v = [...input.querySelectorAll('input')].map((x) => Math.max(c.min, Math.min(c.max, Math.round(Number(x.value) || 0))));
          set(v);
        };
        input.append(n);
      }
    } else if (c.type === 'colours') {
      input = document.createElement('input');
      input.type = 'text';
      input.placeholder = '#000000, #ffffff';
      input.onchange = () => {
        const parsed = parseColours(input.value);
        if (parsed.error) { ctx.error(Object.assign(new Error(`Excluded colours: ${parsed.error}`), { field: 'params.exclude' })); return; }
        ctx.clearError();
        set(parsed.colours);
      };
    } else if (c.type === 'seed') {
      input = document.createElement('span');
      input.className = 'ints';
      const n = document.createElement('input');
      Object.assign(n, { type: 'number', min: 0, step: 1 });
      n.setAttribute('aria-label', 'seed');
      n.onchange = () => set(Math.max(0, Math.round(Number(n.value) || 0)));
      const b = document.createElement('button');
      b.type = 'button';
      b.textContent = '⟳';
      b.title = 'New seed';
      b.setAttribute('aria-label', 'New seed');
      b.onclick = () => set((state()?.params.seed ?? 0) + 1);
      input.append(n, b);
    }
    input.id = id;
    input.dataset.field = `params.${c.key}`;
    row.insertBefore(input, row.children[1] || null);
    return row;
  }

  function syncControls(p) {
    for (const c of CONTROLS) {
      const row = form.querySelector(`[data-key=${c.key}]`);
      const v = p[c.key];
      if (c.type === 'select') row.querySelector('select').value = v;
      else if (c.type === 'range') {
        row.querySelector('input').value = v;
        row.querySelector('output').textContent = c.show(v);
      } else if (c.type === 'checkbox') row.querySelector('input').checked = v;
      else if (c.type === 'ints') row.querySelectorAll('input').forEach((x, i) => { x.value = v[i]; });
      else if (c.type === 'colours') row.querySelector('input').value = v.map((rgb) => hex([...rgb, 255])).join(', ');
      else if (c.type === 'seed') row.querySelector('input').value = v;
    }
    form.querySelector('[data-key=hsv]').classList.toggle('dim', p.colour !== 'hsv' && p.colour !== 'auto');
    form.querySelector('[data-key=d_max]').classList.toggle('dim', p.colour !== 'auto');
  }

  // ---- toolbar, toggles -----------------------------------------------------------------------

  el.querySelectorAll('[data-example]').forEach((b) => { b.onclick = () => loadExample(b.dataset.example); });
  const setMode = (mode) => {
    view.mode = mode;
    el.querySelectorAll('[data-mode]').forEach((x) => x.setAttribute('aria-checked', String(x.dataset.mode === mode)));
    drawMaskFull();
  };
  el.querySelectorAll('[data-mode]').forEach((b) => { b.onclick = () => setMode(b.dataset.mode); });
  const detachRadios = radioGroup(q('[role=radiogroup]'));
  q('[name=brush]').onchange = (e) => { view.brush = Math.max(1, Math.min(32, Number(e.target.value) || 1)); };
  // Whole steps from ×1 up (×2 steps from ×8); halves below ×1, for sources bigger than the window.
  const zoomBy = (dir) => {
    const z = canvas.zoom;
    const next = z < 1 || (z === 1 && dir < 0) ? (dir > 0 ? Math.min(1, z * 2) : z / 2) : z + dir * (z > 8 || (z === 8 && dir > 0) ? 2 : 1);
    canvas.setZoom(Math.max(1 / 64, Math.min(32, next)));
  };
  q('[data-act=zoom-in]').onclick = () => zoomBy(1);
  q('[data-act=zoom-out]').onclick = () => zoomBy(-1);
  q('.viewport').addEventListener('wheel', (e) => {
    if (!e.ctrlKey || !sourceImg) return;
    e.preventDefault();
    zoomBy(e.deltaY < 0 ? 1 : -1);
  }, { passive: false });
  q('[data-act=clear-strokes]').onclick = () => state()?.strokes.length && ctx.commit({ ...state(), strokes: [] });
  const toggles = { 'show-result': 'showResult', 'show-mask': 'showMask', 'show-strokes': 'showStrokes', 'show-arrows': 'showArrows' };
  for (const [name, key] of Object.entries(toggles)) {
    q(`[name=${name}]`).onchange = (e) => {
      view[key] = e.target.checked;
      if (key === 'showResult') drawBase();
      else if (key === 'showMask') drawMaskFull();
      else drawStrokes();
    };
  }

  el.querySelectorAll('input[data-input]').forEach((input) => {
    input.onchange = () => {
      if (input.files[0]) loadInput(input.dataset.input, input.files[0]);
      input.value = '';
    };
  });
  const detachFiles = acceptFiles(q('.viewport'), (file) => loadInput('source', file), { pickerLabel: 'Choose a source image…' });
  q('.viewport .pick').classList.add('overlay-pick');

  q('[data-act=export-png]').onclick = async () => {
    if (!result) { ctx.error(new Error('nothing to export yet: load an example or a source and an element sheet')); return; }
    const s = Number(q('[name=export-scale]').value);
    const c = document.createElement('canvas');
    c.width = result.width * s;
    c.height = result.height * s;
    const x = c.getContext('2d');
    x.imageSmoothingEnabled = false;
    x.drawImage(resultBitmap, 0, 0, c.width, c.height);
    const blob = await new Promise((r) => c.toBlob(r, 'image/png'));
    const base = (state().names?.source || 'pixel').replace(/\.[^.]+$/, '');
    download(`${base}-textured${s > 1 ? `@${s}x` : ''}.png`, blob);
  };

  // For the e2e tests (ctx.expose): the document, the last result, and whether a run is due or going.
  ctx.expose({
    state, result: () => result, pending: () => runTimer !== null || running !== null || sourceLoading !== null,
  });

  const inputsOf = (s) => [s.source, s.sheet, s.sprite, s.mask, s.strokes, s.params];
  return {
    render(s, prev) {
      if (!s) return;
      // The example the document is (none once your own source is in).
      for (const b of el.querySelectorAll('[data-example]')) b.setAttribute('aria-pressed', String(b.dataset.example === s.example));
      if (s.source !== sourceOf && s.source !== loadingFor) loadSource(s);
      else if (sourceImg) {
        if (!prev || s.mask !== prev.mask) drawMaskFull();
        if (!prev || s.strokes !== prev.strokes) drawStrokes();
      }
      if (!prev || s.sheet !== prev.sheet || s.sprite !== prev.sprite) showElements(s);
      syncControls(s.params);
      if (!prev || inputsOf(s).some((v, i) => v !== inputsOf(prev)[i])) scheduleRun();
    },
    keys: { s: () => setMode('stroke'), m: () => setMode('paint'), e: () => setMode('erase') },
    unmount() {
      canvas.destroy();
      detachFiles();
      detachRadios();
      running?.abort();
    },
  };
}

export default { id: 'pixel', title: 'Pixel', state: pixelState, mount };

/** '#000000, #fff' → {colours: [[0,0,0],[255,255,255]]} or {error}. */
export function parseColours(text) {
  const colours = [];
  for (const part of text.split(/[\s,;]+/).filter(Boolean)) {
    const m = /^#?([0-9a-f]{3}|[0-9a-f]{6})$/i.exec(part);
    if (!m) return { error: `'${part}' is not a colour like #1a2b3c` };
    const h = m[1].length === 3 ? [...m[1]].map((c) => c + c).join('') : m[1];
    colours.push([0, 2, 4].map((i) => parseInt(h.slice(i, i + 2), 16)));
  }
  return { colours };
}
