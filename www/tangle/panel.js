// "Tangle": pen-and-ink tangle drawings grown from group grammars (MISSION
// T9, the paper's §6 "User control" and Fig. 13). Pick a shipped grammar or
// edit one, choose where it starts (the grammar's own start, a rectangle, a
// typed word, an SVG file, a polygon drawn on the canvas), and the core grows
// the tangle in a worker. A step slider walks the history; clicking a shape
// selects the step that made it (clicking again walks further back), whose
// parameters can then be edited or which can be re-expanded with a new
// random draw.
//
// The document IS the request: grammar, start, seed, ink settings and the
// user's edits in order ({step, params}); the core replays the edits, so the
// page keeps no tangle state of its own and undo is just the previous
// document. History, autosave, project files and links come from the
// document controller (app/document.js); the schema is src/tangle/state.rs.
// Its requests carry `keep` and go to one worker (affinity), which keeps the
// expansion: an edit then regrows only its step's subtree there.
// A curve or shape drawn on the canvas is added to the grammar text as a
// `curve`/`shape` polyline definition for split and place rules.
//
// Drawing (draw.js): a step's picture is a few Path2D parts from a
// segment tree over the steps, built lazily; heavy parts shown by many steps
// are kept as bitmaps of the current view, so a slider drag redraws only the
// small parts that changed, and idle time draws the heaviest parts' bitmaps
// ahead of a jump. While an edit's answer is due, the canvas keeps the last
// picture (and its highlight) until the answer repaints it.
// During a pan or zoom the last full picture is moved as a bitmap and
// redrawn sharp once the gesture pauses, so 18k shapes stay smooth.
// An answer after an edit keeps the last answer's unchanged shapes (same
// group, id and points: their Path2Ds), and a repaint after an edit or a
// selection redraws only the canvas tiles the changed shapes touch
// (`changedRegion`); `testHooks.tangle.options.incremental = false` turns all
// of that off (the latency bench's "before").
import { shippedExamples, shareByExample } from '../ui/examples.js';
import { createCodeEditor, preloadCodeEditor } from '../ui/code-editor.js';
import { download } from '../app/project.js';
import { prepareTangle, paintBatches, drawThumbnail, createLayers, prebuildLayer, LAYER_VERTICES } from './draw.js';

const RUN_DELAY_MS = 120;
const BUSY_DELAY_MS = 150; // a run shows it is busy after this long
const TYPING_DELAY_MS = 600;
const WORD_DELAY_MS = 400; // a typed start word applies once the typing pauses this long
// The core's limits on what a dropped file may hold (src/tangle/state.rs).
const MAX_GRAMMAR_BYTES = 256 * 1024;
const MAX_SVG_BYTES = 1024 * 1024;
const SHARP_DELAY_MS = 120;
const THUMB = { width: 96, height: 72 };
// A thumbnail grows only this far (its grammar runs once, cached for the page's life).
const THUMB_REQUEST = { max_steps: 400, max_shapes: 2500, resolution: 4 };
const START_KINDS = [
  ['grammar', "the grammar's start"],
  ['rect', 'a rectangle'],
  ['text', 'a typed word'],
  ['svg', 'an SVG file'],
  ['polygon', 'a polygon drawn here'],
];
const HIGHLIGHT = 'rgba(255, 122, 0, 0.38)';
const HIGHLIGHT_LINE = '#e06000';

// Shipped grammars and their thumbnails: fetched and drawn once per page.
const examples = shippedExamples('tangle-examples');
const thumbnails = new Map(); // name → canvas

const html = `
  <div class="tangle-layout">
    <section class="card tangle-stage" aria-label="Tangle drawing">
      <div class="toolbar" role="toolbar" aria-label="Tangle">
        <span class="group">
          <button type="button" class="primary" data-act="generate" title="Grow the tangle from the grammar (Ctrl+Enter in the editor)">Generate</button>
          <button type="button" data-act="cancel" disabled>Cancel</button>
        </span>
        <span class="group">
          <label class="inline">Seed <input type="number" name="seed" min="0" step="1" data-field="seed" data-testid="tangle-seed"></label>
          <button type="button" data-act="new-seed" title="New seed" aria-label="New seed">⟳</button>
        </span>
        <span class="group">
          <button type="button" data-act="zoom-out" aria-label="Zoom out">−</button>
          <button type="button" data-act="zoom-fit" title="Fit the drawing">Fit</button>
          <button type="button" data-act="zoom-in" aria-label="Zoom in">+</button>
        </span>
      </div>
      <div class="tangle-viewport" data-testid="tangle-viewport">
        <canvas data-testid="tangle-canvas" role="img" aria-label="tangle drawing: click a shape to select the step that made it; drag to pan, wheel to zoom"></canvas>
        <div class="tangle-draw-bar" hidden>
          <span>Click to add points (<span data-testid="tangle-draw-count">0</span>)</span>
          <button type="button" class="primary" data-act="draw-finish">Use this polygon</button>
          <button type="button" data-act="draw-cancel">Cancel</button>
        </div>
      </div>
      <div class="tangle-steps">
        <button type="button" data-act="play" aria-label="Play the growth" title="Play / pause">▶</button>
        <input type="range" name="step" min="0" max="0" value="0" step="1" aria-label="Step in the history" data-testid="tangle-step">
        <output class="tangle-count" data-testid="tangle-count" aria-live="polite">—</output>
      </div>
      <div class="status muted" data-testid="tangle-status" aria-live="polite"></div>
    </section>
    <aside class="card tangle-side">
      <h3>Selected step</h3>
      <div class="tangle-selected muted" data-testid="tangle-selected">Click a shape to select the step that made it; click it again to go further back.</div>
      <form class="tangle-params" data-testid="tangle-params"></form>
      <h3 id="tangle-steps-title">Steps</h3>
      <ol class="tangle-step-list" role="listbox" tabindex="0" aria-labelledby="tangle-steps-title" data-testid="tangle-step-list"
        title="Arrow keys, Home and End choose a step; Escape deselects"></ol>
      <div class="row-buttons">
        <button type="button" data-act="reexpand" disabled title="Undo this step and everything grown from it, and expand it again with a new random draw">Re-expand</button>
        <button type="button" data-act="select-back" disabled title="The step that made this step's shapes">◂ Earlier step</button>
        <button type="button" data-act="select-none" disabled>Deselect</button>
      </div>
      <h3>Grammar</h3>
      <ul class="tangle-examples" data-testid="tangle-examples" aria-label="Shipped grammars"></ul>
      <details class="tangle-program" open>
        <summary>Grammar text</summary>
        <div class="tangle-editor"></div>
        <div class="row-buttons">
          <button type="button" data-act="draw-curve" title="Draw a polyline on the canvas; it is added to the grammar as a curve for regularSplit">Draw a curve</button>
          <button type="button" data-act="draw-shape" title="Draw a closed outline on the canvas; it is added to the grammar as a shape for place">Draw a shape</button>
        </div>
      </details>
      <h3>Start from</h3>
      <div class="tangle-start">
        <select name="start-kind" data-field="start" aria-label="Start from"></select>
        <span class="tangle-start-rect" hidden>
          <label class="inline">w <input type="number" name="start-width" min="1" max="1000000" value="800" data-field="start.width"></label>
          <label class="inline">h <input type="number" name="start-height" min="1" max="1000000" value="600" data-field="start.height"></label>
        </span>
        <span class="tangle-start-text" hidden>
          <input type="text" name="start-text" maxlength="200" value="Tangle" aria-label="Word" data-field="start.text">
          <label class="inline">height <input type="number" name="start-text-height" min="1" max="1000000" value="300"></label>
        </span>
        <span class="tangle-start-svg" hidden>
          <input type="file" accept=".svg,image/svg+xml" name="start-svg" aria-label="SVG file" data-field="start.svg"
            title="What the file draws: shapes inside shapes become holes, overlapping shapes one shape, white fills holes; scaled to the grammar's start size">
        </span>
        <span class="tangle-start-polygon" hidden>
          <button type="button" data-act="draw-start">Draw a polygon</button>
        </span>
      </div>
      <h3>Ink</h3>
      <div class="tangle-ink">
        <label>Wobble <input type="range" name="wobble" min="0" max="10" step="0.1" data-field="wobble"><output></output></label>
        <label>Pen width <input type="range" name="stroke_width" min="0" max="6" step="0.1" data-field="stroke_width"><output></output></label>
      </div>
      <h3>Export</h3>
      <div class="row-buttons">
        <button type="button" data-act="export-svg">Export SVG</button>
        <label class="inline">PNG <select name="png-width"><option>800</option><option selected>1600</option><option>3200</option></select> px</label>
        <button type="button" data-act="export-png">Export PNG</button>
      </div>
    </aside>
  </div>`;

// ---- the state ---------------------------------------------------------------------
// Schema (every field, its rules and messages): src/tangle/state.rs, applied by the
// document controller (`check-state`).


// The panel's own requests ask the worker to keep the expansion (`keep`) and
// go to the worker that kept it, so an edit regrows only its step's subtree
// there instead of the whole tangle (src/tangle/api.rs, app/client.js).
const KEEP_AFFINITY = 'tangle';

// What a polyline drawn on the canvas becomes.
const DRAW_PURPOSES = {
  start: { what: 'a start polygon', finish: 'Use this polygon', min: 3 },
  curve: { what: 'a curve', finish: 'Add this curve', min: 2 },
  shape: { what: 'a shape', finish: 'Add this shape', min: 3 },
};

/** The `tangle` request of document `s` (the core's defaults for the rest). */
export const requestOf = (s) => ({
  grammar: s.grammar, start: s.start, seed: s.seed, wobble: s.wobble, stroke_width: s.stroke_width, edits: s.edits,
});

const tangleState = {
  version: 1,
  async defaults(ctx) {
    const [list, d] = await Promise.all([examples(ctx.run), ctx.coreDefaults()]);
    const ex = list.find((e) => e.name === 'leaf') || list[0];
    return {
      example: ex.name, grammar: ex.grammar, seed: d.seed, start: null,
      wobble: d.wobble, stroke_width: d.stroke_width, edits: [], selected: null,
    };
  },
  migrate: (raw) => raw,
  fileName: (s) => s.example || 'tangle',
  // A shipped grammar travels by name.
  ...shareByExample(examples, 'grammar', { tool: 'Tangle', what: 'grammar' }),
};

// ---- the view ----------------------------------------------------------------------

function mount(el, ctx) {
  el.innerHTML = html;
  preloadCodeEditor();
  const q = (s) => el.querySelector(s);
  const canvas = q('[data-testid=tangle-canvas]');
  const g = canvas.getContext('2d');
  const viewport = q('.tangle-viewport');
  const slider = q('[name=step]');
  const statusEl = q('[data-testid=tangle-status]');
  const status = (t) => { statusEl.textContent = t; };
  const state = () => ctx.state();

  // Derived, not saved: the last answer, the shown step, the view transform.
  let T = null; // prepareTangle(answer) of the current (or last good) document
  let shownFor = null; // the document T answers
  let k = 0; // shown step
  let running = null;
  let runTimer = null;
  let typingTimer = null;
  let refit = true;
  const view = { s: 1, tx: 0, ty: 0 };
  let fitted = null; // viewKey() of the last fitted view
  let dpr = 1;
  let frame = 0;
  let sharpTimer = null;
  const snap = document.createElement('canvas');
  const layers = createLayers(); // bitmaps of the heavy parts of recent steps (draw.js)
  let snapView = null;
  // The view of the last sharp paint; the canvas is copied to `snap` only when a pan starts
  // (a copy at every paint would make the browser rasterise the canvas there and then).
  let sharpView = null;
  let snapStale = true;
  let hl = null; // {sel, k, path, box}
  let lastPick = -1;
  let drag = null; // a parameter drag: {key, base, step, predicted, group}
  let pendingGroup = null; // after an edit: re-find the selected step by its group
  let pendingKey = null;
  let drawing = null; // the polyline being drawn: [[x, y], ...]
  let drawingFor = 'start'; // what it becomes: DRAW_PURPOSES
  let playing = 0;
  // Figures of the last paint/answer for tests and the latency bench: ms, `region` (the
  // repainted fraction of the canvas), `why` (why the last repaint could not be partial).
  const timing = { paint: 0, batches: 0, run: 0, prepare: 0, pan: 0, region: 1, why: '', paints: [] };
  // What the canvas shows (set by every sharp paint; null after a pan frame):
  // a repaint then redraws only the rectangle where the picture differs.
  let shown = null; // {T, k, key, w, h, hl, drawing}
  let lastParts = new Set(); // the parts of the step tree the last full repaint drew
  // `incremental: false` is the old path (a full repaint each time, a bitmap for every
  // heavy part, an edit repainted and shown busy at once, no shape kept from the last
  // answer): the latency bench measures both in one run.
  // `highlight: false` leaves the selected step's highlight out of a paint (tests compare
  // the picture with a fresh answer's).
  const options = { incremental: true, highlight: true };

  // ---- the grammar editor ------------------------------------------------------------

  let editor = null;
  const editorReady = createCodeEditor(q('.tangle-editor'), {
    language: 'tangle', label: 'tangle grammar',
    attributes: { 'data-testid': 'tangle-grammar', 'data-field': 'grammar' },
    onChange: () => {
      ctx.clearTimeout(typingTimer);
      typingTimer = ctx.setTimeout(applyEditor, TYPING_DELAY_MS);
    },
  }).then((ed) => {
    editor = ed;
    if (state()) ed.setValue(state().grammar);
    ed.getValue && q('.tangle-editor').addEventListener('keydown', (e) => {
      if (e.key === 'Enter' && (e.ctrlKey || e.metaKey)) { e.preventDefault(); generate(); }
    });
    return ed;
  });

  /** Commit the editor's text when it differs from the document's grammar. */
  function applyEditor() {
    ctx.clearTimeout(typingTimer);
    typingTimer = null;
    const doc = state();
    if (!editor || !doc) return false;
    const text = editor.getValue();
    if (text === doc.grammar) return false;
    refit = true;
    ctx.commit({ ...doc, grammar: text, example: null, edits: [], selected: null }, { coalesce: 'grammar-typing' });
    return true;
  }

  function generate() {
    if (!applyEditor()) run();
  }

  // ---- running the core -------------------------------------------------------------

  function scheduleRun() {
    ctx.clearTimeout(runTimer);
    runTimer = ctx.setTimeout(() => { runTimer = null; run(); }, RUN_DELAY_MS);
  }

  async function run() {
    const doc = state();
    if (!doc) return;
    ctx.clearTimeout(runTimer);
    runTimer = null;
    // Already growing this very document (Generate after an edit): that growth answers.
    const live = ctx.job('grow');
    if (running && live?.running && live.data.doc && sameRequest(live.data.doc, doc)) return;
    running?.abort();
    const ctrl = new AbortController();
    running = ctrl;
    // A run says it is busy (status, Cancel) only when it takes a while: an edit's answer
    // comes within a few frames, and every change on the page makes the browser draw a
    // frame, which takes the CPU from the worker growing the answer.
    let busy = false;
    const showBusy = () => {
      if (running !== ctrl || busy) return;
      busy = true;
      q('[data-act=cancel]').disabled = false;
      status('growing…');
    };
    const busyTimer = options.incremental ? ctx.setTimeout(showBusy, BUSY_DELAY_MS) : (showBusy(), null);
    const t0 = performance.now();
    timing.runAt = t0;
    try {
      // The growth is a job of the document (ctx.startJob, issue 35 item 4): it grows on
      // when the user opens another tool, the tool bar shows it once it takes a while, and
      // coming back takes its answer (or waits for it) instead of growing it again.
      let job = ctx.job('grow');
      if (!(job?.data.doc && sameRequest(job.data.doc, doc) && (job.running || job.status === 'done'))) {
        const request = { ...requestOf(doc), keep: true };
        job = ctx.startJob('grow', { label: 'Tangle', quietMs: BUSY_DELAY_MS }, (j) => j.run('tangle', request, {
          affinity: KEEP_AFFINITY,
          onProgress: (p) => j.report({
            fraction: p.fraction, figure: p.figure,
            stage: p.figure != null ? `${Math.round(p.figure).toLocaleString('en')} shapes` : p.stage,
          }),
        }));
        job.data.doc = doc;
      }
      // Cancel, or a newer edit, ends it; leaving the panel does not.
      const stop = () => job.stop('cancelled');
      ctrl.signal.addEventListener('abort', stop, { once: true });
      const unfollow = ctx.follow(job, (j) => { if (running === ctrl && busy && j.running) status(`growing: ${j.progress.stage}`); });
      const ended = await job.promise;
      unfollow();
      ctrl.signal.removeEventListener('abort', stop);
      if (running !== ctrl || !ctx.alive()) return;
      if (ended.status !== 'done') throw ended.error ?? Object.assign(new Error('cancelled'), { kind: 'cancelled' });
      const r = ended.result;
      const t1 = performance.now();
      timing.answeredAt = t1;
      // Only the edits differ from the last answer: its unchanged shapes keep their Path2Ds,
      // and the repaint covers only where the picture changed.
      const related = options.incremental && T && shownFor && shownFor.grammar === doc.grammar
        && shownFor.start === doc.start && shownFor.seed === doc.seed && shownFor.wobble === doc.wobble;
      T = prepareTangle(r, related ? T : null);
      layers.clear();
      shownFor = doc;
      hl = null;
      lastPick = -1;
      timing.run = performance.now() - t0;
      timing.prepare = performance.now() - t1;
      slider.max = String(T.steps);
      setStep(T.steps, false);
      if (refit) { refit = false; fitView(); }
      ctx.clearError('run');
      const why = r.stopped ? ` — stopped: ${r.stopped}` : '';
      status(`${r.stats.steps.toLocaleString('en')} steps, ${r.stats.shapes.toLocaleString('en')} shapes, ${r.stats.vertices.toLocaleString('en')} vertices in ${Math.round(timing.run)} ms${why}`);
      statusEl.dataset.runs = String(Number(statusEl.dataset.runs || 0) + 1);
      resolveSelection();
      showSelected();
      // Painted now, not at the next animation frame: the answer is what the user waits
      // for, and a loaded machine may start that frame late (the browser shows the canvas
      // at its next frame either way).
      if (options.incremental) {
        cancelAnimationFrame(frame);
        frame = 0;
        // An answer's full repaint draws heavy parts directly instead of first making
        // their bitmaps (a second pass: the layers were just cleared, and which parts a
        // later slider move needs is unknown); idle time makes them afterwards.
        paintChanged({ newBitmaps: false });
      } else paint();
      timing.paintEndAt = performance.now();
      loadThumbnails();
    } catch (err) {
      if (running !== ctrl) return;
      paint(); // the last answer, without the highlight of a document it does not answer
      status(err?.kind === 'cancelled' ? 'cancelled' : 'the tangle could not grow (see above)');
      if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Tangle', source: 'run' });
    } finally {
      ctx.clearTimeout(busyTimer);
      if (running === ctrl) {
        running = null;
        const cancel = q('[data-act=cancel]');
        if (!cancel.disabled) cancel.disabled = true;
      }
    }
  }

  /** Whether a run for document `s`, which the canvas does not show yet, is due or under way. */
  const awaitingAnswer = (s) => !!T && !!shownFor && !sameRequest(shownFor, s) && (runTimer !== null || running !== null);

  /** After an edit, the edited step was regrown at a new position: select it there. */
  function resolveSelection() {
    if (pendingGroup === null || !T) return;
    const group = pendingGroup, key = pendingKey;
    pendingGroup = pendingKey = null;
    const pos = T.r.steps.findIndex((s) => s.group === group);
    const doc = state();
    if (pos >= 0 && doc && doc.selected !== pos) ctx.commit({ ...doc, selected: pos }, { coalesce: key });
  }

  // ---- the view transform and painting ------------------------------------------------

  function resize() {
    dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(viewport.clientWidth * dpr));
    const h = Math.max(1, Math.round(viewport.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) {
      canvas.width = w;
      canvas.height = h;
      sharpView = null; // a resized canvas is blank until its next paint
      // A view the user has not moved since it was fitted follows the viewport's size.
      if (refit || !T || fitted === viewKey()) fitView(); else paint();
    }
  }
  const ro = new ResizeObserver(() => resize());
  ro.observe(viewport);

  /** The drawing's extent: the answer's bounds, or a default sheet before any answer. */
  const extent = () => (T && T.n ? T.r.bounds : [0, 0, 800, 600]);

  function fitView() {
    const [x0, y0, x1, y1] = extent();
    const w = viewport.clientWidth || 1, h = viewport.clientHeight || 1;
    const s = Math.min((w - 16) / Math.max(1e-6, x1 - x0), (h - 16) / Math.max(1e-6, y1 - y0));
    view.s = Number.isFinite(s) && s > 0 ? s : 1;
    view.tx = (w - view.s * (x1 - x0)) / 2 - view.s * x0;
    view.ty = (h - view.s * (y1 - y0)) / 2 - view.s * y0;
    fitted = viewKey();
    paint();
  }

  const toWorld = (cx, cy) => [(cx - view.tx) / view.s, (cy - view.ty) / view.s];
  const toCss = (x, y) => [x * view.s + view.tx, y * view.s + view.ty];

  /** Repaint sharp at the next frame: only the rectangle that changed when that is known. */
  function paint() {
    if (frame) return;
    frame = requestAnimationFrame(() => { frame = 0; paintChanged(); });
  }

  const lineWidth = () => {
    const sw = state()?.stroke_width ?? 1;
    return sw > 0 ? Math.max(sw, 0.5 / view.s) : 0;
  };
  const viewKey = () => `${view.s} ${view.tx} ${view.ty} ${dpr} ${lineWidth()}`;

  /** The canvas now shows the current step, view and highlight. */
  function recordShown() {
    if (T) T.from = null; // linked answers are compared once, then dropped
    shown = { T, k, key: viewKey(), w: canvas.width, h: canvas.height, hl: T && T.n ? currentHl() : null, drawing: !!drawing };
  }

  // A repaint of part of the canvas works on tiles of TILE device pixels: a
  // small mask canvas (one pixel a tile) gets the changed shapes drawn on it,
  // grown by the pen and a margin; the tiles it touches are cleared and
  // redrawn, clipped, from the shapes that reach into them.
  const TILE = 8;
  const maskCanvas = document.createElement('canvas');

  /**
   * Where the picture to paint differs from what the canvas shows:
   * `{tiles, cols, rows, count, sum}` (tiles: 1 where it differs; sum: its
   * summed-area table), null when nowhere, or false when that is unknown or
   * most of the canvas (then everything is repainted).
   */
  function changedRegion() {
    timing.why = 'state';
    if (!options.incremental || !shown || !T || !T.n || drawing || shown.drawing || !shown.T) return false;
    timing.why = 'view';
    if (shown.key !== viewKey() || shown.w !== canvas.width || shown.h !== canvas.height) return false;
    // A slider move repaints in full: its heavy parts come from bitmaps, which beats
    // clipping (measured: a 2% region of the village cost more than the full repaint).
    timing.why = 'step';
    if (shown.T === T && shown.k !== k) return false;
    timing.why = 'unrelated';
    const ch = T.changes(k, shown.T === T ? T : shown.T, shown.k);
    if (!ch) return false;
    const h = currentHl();
    const hls = h === shown.hl ? [] : [shown.hl, h].filter(Boolean);
    if (!ch.added.length && !ch.removed.length && !hls.length) return null;
    timing.why = 'big';
    // When the changed shapes are a good part of the picture, a full repaint (which copies
    // the heavy parts from bitmaps) is cheaper than finding and clipping the region.
    const vertsOf = (t, list) => {
      let v = 0;
      for (const i of list) v += t.vertices(i);
      return v;
    };
    if (vertsOf(T, ch.added) + vertsOf(shown.T, ch.removed) > 0.25 * T.batches(k).parts.reduce((a, b) => a + b.vertices, 0)
      + 4000) return false;
    const cols = Math.ceil(canvas.width / TILE), rows = Math.ceil(canvas.height / TILE);
    if (maskCanvas.width !== cols || maskCanvas.height !== rows) { maskCanvas.width = cols; maskCanvas.height = rows; }
    const mg = maskCanvas.getContext('2d', { willReadFrequently: true });
    mg.setTransform(1, 0, 0, 1, 0, 0);
    mg.clearRect(0, 0, cols, rows);
    const s = (dpr * view.s) / TILE;
    mg.setTransform(s, 0, 0, s, (dpr * view.tx) / TILE, (dpr * view.ty) / TILE);
    // A pen's half width past the outline, and anti-aliasing: grown by a tile below.
    mg.lineWidth = lineWidth() + 4 / (dpr * view.s);
    mg.lineJoin = 'round';
    mg.fillStyle = mg.strokeStyle = '#000';
    const changed = new Path2D();
    for (const i of ch.added) changed.addPath(T.path(i));
    for (const j of ch.removed) changed.addPath(shown.T.path(j));
    mg.fill(changed, 'nonzero');
    mg.stroke(changed);
    for (const x of hls) {
      mg.fill(x.path, 'nonzero');
      if (x.box) mg.strokeRect(x.box[0], x.box[1], x.box[2] - x.box[0], x.box[3] - x.box[1]);
    }
    const a = mg.getImageData(0, 0, cols, rows).data;
    // Marked tiles, grown by one (the mask's own anti-aliasing may miss an edge).
    const tiles = new Uint8Array(cols * rows);
    let count = 0;
    for (let y = 0; y < rows; y++) {
      for (let x = 0; x < cols; x++) {
        if (!a[4 * (y * cols + x) + 3]) continue;
        for (let v = Math.max(0, y - 1); v <= Math.min(rows - 1, y + 1); v++) {
          for (let u = Math.max(0, x - 1); u <= Math.min(cols - 1, x + 1); u++) {
            if (!tiles[v * cols + u]) { tiles[v * cols + u] = 1; count++; }
          }
        }
      }
    }
    if (!count) return null;
    if (count > 0.9 * cols * rows) return false;
    // Summed-area table: any marked tile within a box in O(1).
    const sum = new Int32Array((cols + 1) * (rows + 1));
    for (let y = 0; y < rows; y++) {
      let run = 0;
      for (let x = 0; x < cols; x++) {
        run += tiles[y * cols + x];
        sum[(y + 1) * (cols + 1) + x + 1] = sum[y * (cols + 1) + x + 1] + run;
      }
    }
    return { tiles, cols, rows, count, sum };
  }

  function paintChanged({ newBitmaps = true } = {}) {
    timing.paintAt = performance.now();
    const region = changedRegion();
    if (region === false) paintNow({ newBitmaps });
    else if (region) paintRegion(region);
    else { timing.paint = 0; timing.region = 0; recordShown(); }
  }

  /**
   * Repaint the tiles of `region` only (changedRegion): clipped to them, the
   * shapes that reach into them are drawn as a full repaint draws them (the
   * same parts in the same order), then the highlight.
   */
  function paintRegion({ tiles, cols, rows, count, sum }) {
    const t0 = performance.now();
    noteDrawn(t0);
    const clip = new Path2D();
    let x0 = cols, y0 = rows, x1 = 0, y1 = 0;
    for (let y = 0; y < rows; y++) {
      for (let x = 0; x < cols; x++) {
        if (!tiles[y * cols + x]) continue;
        let e = x;
        while (e + 1 < cols && tiles[y * cols + e + 1]) e++;
        clip.rect(x * TILE, y * TILE, (e - x + 1) * TILE, TILE);
        x0 = Math.min(x0, x); x1 = Math.max(x1, e + 1); y0 = Math.min(y0, y); y1 = Math.max(y1, y + 1);
        x = e;
      }
    }
    const bx = x0 * TILE, by = y0 * TILE, bw = Math.min(canvas.width, x1 * TILE) - bx, bh = Math.min(canvas.height, y1 * TILE) - by;
    g.save();
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.clip(clip);
    g.fillStyle = '#fff';
    g.fillRect(bx, by, bw, bh);
    g.setTransform(dpr * view.s, 0, 0, dpr * view.s, dpr * view.tx, dpr * view.ty);
    const lw = lineWidth();
    // A shape is drawn when its box, grown by half a pen and a pixel, touches a marked tile.
    const m = lw / 2 + 1 / view.s;
    const s = (dpr * view.s) / TILE, ox = (dpr * view.tx) / TILE, oy = (dpr * view.ty) / TILE;
    const box = T.box;
    const touches = (i) => {
      const u0 = Math.max(0, Math.floor(s * (box[4 * i] - m) + ox)), v0 = Math.max(0, Math.floor(s * (box[4 * i + 1] - m) + oy));
      const u1 = Math.min(cols, Math.floor(s * (box[4 * i + 2] + m) + ox) + 1), v1 = Math.min(rows, Math.floor(s * (box[4 * i + 3] + m) + oy) + 1);
      if (u1 <= u0 || v1 <= v0) return false;
      const w = cols + 1;
      return sum[v1 * w + u1] - sum[v0 * w + u1] - sum[v1 * w + u0] + sum[v0 * w + u0] > 0;
    };
    const tb = performance.now();
    const parts = T.regionParts(k, touches);
    timing.batches = performance.now() - tb;
    // A heavy part with a bitmap of this view is copied from it (as a full repaint does:
    // the same pixels); the rest is drawn.
    const key = viewKey();
    const full = T.batches(k).parts;
    for (let p = 0; p < parts.parts.length; p++) {
      const whole = full[parts.nodes[p]];
      if (whole.vertices >= LAYER_VERTICES && layers.has(whole, key, canvas.width, canvas.height)) parts.parts[p] = whole;
    }
    paintBatches(g, parts, lw, layers, key, (part) => layers.has(part, key, canvas.width, canvas.height));
    paintHighlight();
    g.restore();
    snapStale = true;
    recordShown();
    schedulePrebuild();
    timing.region = count / (cols * rows);
    timing.paint = performance.now() - t0;
  }

  /** When the canvas was last drawn (a few times kept, for the tests). */
  function noteDrawn(at) {
    timing.paints = [...timing.paints.slice(-15), at];
  }

  function paintNow({ newBitmaps = true } = {}) {
    const t0 = performance.now();
    noteDrawn(t0);
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.fillStyle = '#fff';
    g.fillRect(0, 0, canvas.width, canvas.height);
    if (T && T.n) {
      g.setTransform(dpr * view.s, 0, 0, dpr * view.s, dpr * view.tx, dpr * view.ty);
      const tb = performance.now();
      const b = T.batches(k);
      timing.batches = performance.now() - tb;
      const key = viewKey(), w = canvas.width, h = canvas.height;
      // A heavy part is copied from its bitmap when there is one; else it gets one when
      // other steps are likely to show it too (a part of the step tree shown by at least a
      // sixteenth of the steps) or the last paint showed it too (a drag), and is drawn
      // directly otherwise: a far jump shows a few deep parts no other step shows, and a
      // bitmap of one (a canvas made, drawn and copied) costs more than drawing it (the
      // old path: always a bitmap).
      const last = lastParts;
      const shared = (part) => !options.incremental || part.span * 16 >= T.steps || last.has(part);
      paintBatches(g, b, lineWidth(), layers, key, (part) => (newBitmaps ? shared(part) : layers.has(part, key, w, h)));
      lastParts = new Set(b.parts);
      paintHighlight();
    }
    paintDrawing();
    g.setTransform(1, 0, 0, 1, 0, 0);
    // Kept for quick pans and zooms (copied when one starts).
    sharpView = { ...view };
    snapStale = true;
    if (!options.incremental) takeSnap(); // the old path: a copy at every paint
    recordShown();
    schedulePrebuild();
    timing.region = 1;
    timing.paint = performance.now() - t0;
  }

  // In idle time after a sharp paint, the heaviest parts of the step tree are drawn as
  // bitmaps of the current view (heaviest first, while the layer budget has room), so a
  // slider jump to a far step copies them instead of rasterising them (draw.js).
  let prebuildHandle = 0;
  let prebuildTimer = null;
  const PREBUILD_DELAY_MS = 250; // after the last paint: not while a slider or a pan is moving
  const idle = window.requestIdleCallback
    ? (fn) => window.requestIdleCallback(fn)
    : (fn) => setTimeout(() => fn({ didTimeout: false, timeRemaining: () => 50 }), 50);
  const cancelIdle = (h) => (window.cancelIdleCallback ? window.cancelIdleCallback(h) : clearTimeout(h));
  function schedulePrebuild() {
    if (prebuildHandle) cancelIdle(prebuildHandle);
    prebuildHandle = 0;
    ctx.clearTimeout(prebuildTimer);
    prebuildTimer = null;
    timing.prebuilt = 0;
    if (!options.incremental || !T || !T.n || !ctx.alive()) return;
    const key = viewKey(), w = canvas.width, h = canvas.height, from = T;
    const m = new DOMMatrix([dpr * view.s, 0, 0, dpr * view.s, dpr * view.tx, dpr * view.ty]);
    let todo = null;
    let at = 0;
    const work = (deadline) => {
      prebuildHandle = 0;
      if (T !== from || viewKey() !== key || canvas.width !== w || canvas.height !== h || !ctx.alive()) return;
      todo ??= T.heavyParts();
      for (;;) {
        if (at >= todo.length || layers.size >= layers.capacity(w, h) - 2) { timing.prebuilt = at; return; }
        // A part only when the idle period has room for it (software raster: ~8k vertices a ms).
        if (deadline.timeRemaining() < Math.min(40, todo[at].vertices / 8000)) break;
        const part = todo[at++].part();
        if (!layers.has(part, key, w, h)) prebuildLayer(layers, part, key, w, h, m, lineWidth());
      }
      prebuildHandle = idle(work);
    };
    prebuildTimer = ctx.setTimeout(() => { prebuildTimer = null; prebuildHandle = idle(work); }, PREBUILD_DELAY_MS);
  }

  function takeSnap() {
    if (snap.width !== canvas.width || snap.height !== canvas.height) { snap.width = canvas.width; snap.height = canvas.height; }
    snap.getContext('2d').drawImage(canvas, 0, 0);
    snapView = sharpView;
    snapStale = false;
  }

  /** During a pan or zoom: move the last picture, and redraw it sharp when the gesture pauses. */
  function quickPaint() {
    if (!sharpView) { paint(); return; }
    cancelAnimationFrame(frame);
    frame = requestAnimationFrame(() => {
      frame = 0;
      const t0 = performance.now();
      if (snapStale) takeSnap(); // the canvas still shows the last sharp paint
      shown = null;
      const r = view.s / snapView.s;
      g.setTransform(1, 0, 0, 1, 0, 0);
      g.fillStyle = '#fff';
      g.fillRect(0, 0, canvas.width, canvas.height);
      g.setTransform(r, 0, 0, r, dpr * (view.tx - snapView.tx * r), dpr * (view.ty - snapView.ty * r));
      g.drawImage(snap, 0, 0);
      g.setTransform(1, 0, 0, 1, 0, 0);
      timing.pan = performance.now() - t0;
    });
    ctx.clearTimeout(sharpTimer);
    sharpTimer = ctx.setTimeout(() => { sharpTimer = null; paint(); }, SHARP_DELAY_MS);
  }

  function selectedStep() {
    const s = state()?.selected;
    return T && s != null && s < T.steps && shownFor && sameRequest(shownFor, state()) ? s : null;
  }

  /** The highlight of the selected step at the shown step (null: none): kept until either changes. */
  function currentHl() {
    const sel = selectedStep();
    if (sel === null) return null;
    if (!hl || hl.sel !== sel || hl.k !== k || hl.T !== T) {
      // The step's inputs while it has not run yet, else what it grew (still shown at step k).
      const step = T.r.steps[sel];
      const list = k <= sel ? step.inputs : [...T.subtree(sel)].filter((i) => T.visible(i, k));
      const path = new Path2D();
      for (const i of list) path.addPath(T.path(i));
      hl = { sel, k, T, path, box: T.bounds(step.inputs) };
    }
    return hl;
  }

  function paintHighlight() {
    const h = currentHl();
    if (!h || !options.highlight) return;
    g.fillStyle = HIGHLIGHT;
    g.fill(h.path, 'evenodd');
    if (h.box) {
      g.strokeStyle = HIGHLIGHT_LINE;
      g.lineWidth = 1.5 / view.s;
      g.setLineDash([4 / view.s, 3 / view.s]);
      const [x0, y0, x1, y1] = h.box;
      g.strokeRect(x0, y0, x1 - x0, y1 - y0);
      g.setLineDash([]);
    }
  }

  function paintDrawing() {
    if (!drawing) return;
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.strokeStyle = HIGHLIGHT_LINE;
    g.fillStyle = HIGHLIGHT_LINE;
    g.lineWidth = 2;
    g.beginPath();
    drawing.forEach(([x, y], i) => {
      const [cx, cy] = toCss(x, y);
      if (i) g.lineTo(cx, cy); else g.moveTo(cx, cy);
    });
    if (drawing.length > 2 && drawingFor !== 'curve') g.closePath();
    g.stroke();
    for (const [x, y] of drawing) {
      const [cx, cy] = toCss(x, y);
      g.fillRect(cx - 3, cy - 3, 6, 6);
    }
  }

  // ---- the step slider and play ---------------------------------------------------------

  function setStep(v, draw = true) {
    k = Math.max(0, Math.min(T ? T.steps : 0, Math.round(v)));
    slider.value = String(k);
    const n = T ? T.count(k) : 0;
    const out = q('[data-testid=tangle-count]');
    out.textContent = T ? `step ${k.toLocaleString('en')} / ${T.steps.toLocaleString('en')} · ${n.toLocaleString('en')} shapes` : '—';
    out.dataset.count = String(n);
    out.dataset.step = String(k);
    if (draw) paint();
  }
  slider.addEventListener('input', () => { stopPlay(); setStep(Number(slider.value)); });

  const playBtn = q('[data-act=play]');
  function stopPlay() {
    if (!playing) return;
    cancelAnimationFrame(playing);
    playing = 0;
    playBtn.textContent = '▶';
    playBtn.setAttribute('aria-label', 'Play the growth');
  }
  function play() {
    if (!T || !T.steps) return;
    if (k >= T.steps) setStep(0, false);
    playBtn.textContent = '❚❚';
    playBtn.setAttribute('aria-label', 'Pause');
    const per = Math.max(1, Math.round(T.steps / 180)); // about three seconds at 60 frames a second
    const tick = () => {
      if (!T || k >= T.steps) { stopPlay(); return; }
      setStep(k + per);
      playing = requestAnimationFrame(tick);
    };
    playing = requestAnimationFrame(tick);
  }
  playBtn.onclick = () => (playing ? stopPlay() : play());

  // ---- selection and edits ---------------------------------------------------------------

  const sameRequest = (a, b) => a.grammar === b.grammar && a.start === b.start && a.seed === b.seed
    && a.wobble === b.wobble && a.edits === b.edits;

  function select(next, opts = { coalesce: 'tangle-select' }) {
    const doc = state();
    if (!doc || doc.selected === next) return;
    ctx.commit({ ...doc, selected: next }, opts);
  }

  /** The step before `s`: the one that made its shapes (null: they are start shapes). */
  function parentStep(s) {
    const first = T.r.steps[s]?.inputs[0];
    if (first === undefined) return null;
    const b = T.born[first];
    return b >= 0 ? b : null;
  }

  function pickAt(cx, cy) {
    if (!T) return;
    const [x, y] = toWorld(cx, cy);
    const i = T.pick(x, y, k, g);
    const sel = selectedStep();
    if (i < 0) { lastPick = -1; return; }
    let next;
    if (i === lastPick && sel !== null) {
      next = parentStep(sel);
      if (next === null) { status('this is the first step that made these shapes'); next = sel; }
    } else {
      next = T.born[i] >= 0 ? T.born[i] : null;
      if (next === null) status('a start shape: no step made it');
    }
    lastPick = i;
    select(next);
  }

  /** Append edit {step: sel, params} (a drag replaces its own edit) and re-run. */
  function edit(sel, params, key) {
    const doc = state();
    if (!doc || !T) return;
    if (!drag || drag.key !== key) {
      drag = {
        key, base: doc.edits, step: sel, group: T.r.steps[sel].group,
        // The regrown step lands after the steps it does not touch.
        predicted: T.steps - T.dependents(sel).length,
      };
    }
    const edits = [...drag.base, { step: drag.step, params }];
    pendingGroup = drag.group;
    pendingKey = key;
    ctx.commit({ ...doc, edits, selected: drag.predicted }, { coalesce: key });
  }

  let editNo = 0;
  function reexpand() {
    const sel = selectedStep();
    if (sel === null) return;
    drag = null;
    edit(sel, {}, `tangle-reexpand-${++editNo}`);
    drag = null;
  }

  // ---- the step list: every step of the answer, a listbox in sync with the selection --------
  // Keyboard (WAI-ARIA listbox, selection follows focus): arrows, Home, End, Page keys;
  // Escape deselects. A click on a shape of the drawing selects the step here too.

  const stepList = q('[data-testid=tangle-step-list]');
  let listFor = null; // the answer the list shows
  function buildStepList() {
    if (listFor === T) return;
    listFor = T;
    if (!T) { stepList.replaceChildren(); return; }
    stepList.replaceChildren(...T.r.steps.map((st, i) => {
      const li = document.createElement('li');
      li.id = `tangle-step-${i}`;
      li.setAttribute('role', 'option');
      li.setAttribute('aria-selected', 'false');
      li.dataset.step = String(i);
      li.textContent = `${i + 1}. ${st.operator} · ${T.r.tags[st.tag] ?? st.tag} · ${st.inputs.length} → ${st.outputs.length}`;
      return li;
    }));
  }
  function syncStepList() {
    buildStepList();
    const sel = selectedStep();
    const was = stepList.querySelector('[aria-selected=true]');
    if (was && Number(was.dataset.step) !== sel) was.setAttribute('aria-selected', 'false');
    const opt = sel === null ? null : stepList.children[sel];
    if (!opt) { stepList.removeAttribute('aria-activedescendant'); return; }
    opt.setAttribute('aria-selected', 'true');
    stepList.setAttribute('aria-activedescendant', opt.id);
    // Into view inside the list only (the page does not jump).
    if (opt.offsetTop < stepList.scrollTop) stepList.scrollTop = opt.offsetTop;
    else if (opt.offsetTop + opt.offsetHeight > stepList.scrollTop + stepList.clientHeight) stepList.scrollTop = opt.offsetTop + opt.offsetHeight - stepList.clientHeight;
  }
  stepList.addEventListener('click', (e) => {
    const li = e.target.closest('[role=option]');
    if (!li) return;
    lastPick = -1;
    select(Number(li.dataset.step));
  });
  stepList.addEventListener('keydown', (e) => {
    if (!T || !T.steps || e.altKey || e.ctrlKey || e.metaKey) return;
    const sel = selectedStep();
    const page = Math.max(1, Math.floor(stepList.clientHeight / (stepList.firstElementChild?.offsetHeight || 20)) - 1);
    const at = sel ?? -1;
    const next = {
      ArrowDown: at + 1, ArrowUp: sel === null ? T.steps - 1 : at - 1, Home: 0, End: T.steps - 1,
      PageDown: at + page, PageUp: Math.max(0, at - page),
    }[e.key];
    if (e.key === 'Escape' && sel !== null) { e.preventDefault(); e.stopPropagation(); lastPick = -1; select(null); return; }
    if (next === undefined) return;
    e.preventDefault();
    lastPick = -1;
    select(Math.max(0, Math.min(T.steps - 1, next)));
  });

  function showSelected() {
    syncStepList();
    const sel = selectedStep();
    const box = q('[data-testid=tangle-selected]');
    const form = q('[data-testid=tangle-params]');
    for (const a of ['reexpand', 'select-back', 'select-none']) q(`[data-act=${a}]`).disabled = sel === null;
    if (sel === null) {
      box.textContent = 'Click a shape to select the step that made it; click it again to go further back.';
      box.classList.add('muted');
      delete box.dataset.step;
      form.replaceChildren();
      return;
    }
    const st = T.r.steps[sel];
    box.classList.remove('muted');
    box.dataset.step = String(sel);
    box.dataset.operator = st.operator;
    const tag = T.r.tags[st.tag] ?? st.tag;
    box.innerHTML = '';
    const b = document.createElement('b');
    b.textContent = `Step ${sel + 1} of ${T.steps}: ${st.operator}`;
    const facts = document.createElement('span');
    facts.className = 'muted';
    facts.textContent = ` — rule on line ${st.line}, tag ${tag}, group ${st.group}, ${st.inputs.length} in → ${st.outputs.length} out`;
    box.append(b, facts);
    if (drag) return; // keep the slider being dragged
    form.dataset.step = String(sel);
    form.replaceChildren(...st.params.map((p) => paramRow(sel, p)));
    if (!st.params.length) {
      const none = document.createElement('p');
      none.className = 'muted';
      none.textContent = `${st.operator} has no parameters; Re-expand draws its rule again.`;
      form.append(none);
    }
  }

  let dragNo = 0;
  function paramRow(sel, p) {
    const row = document.createElement('label');
    row.className = 'tangle-param';
    row.dataset.param = p.name;
    const name = document.createElement('span');
    name.textContent = p.name;
    const input = document.createElement('input');
    input.type = 'range';
    input.min = String(p.min);
    input.max = String(Math.max(p.max, p.value));
    input.step = p.integer ? '1' : String((p.max - p.min) / 400);
    input.value = String(p.value);
    input.dataset.testid = `tangle-param-${p.name}`;
    input.setAttribute('aria-label', `${p.name} of step ${sel + 1}`);
    const out = document.createElement('output');
    const show = (v) => { out.textContent = p.integer ? String(v) : v.toFixed(2).replace(/\.?0+$/, ''); };
    show(p.value);
    let key = null;
    input.oninput = () => {
      const v = p.integer ? Math.round(Number(input.value)) : Number(input.value);
      show(v);
      key ??= `tangle-param-${sel}-${p.name}-${++dragNo}`;
      edit(sel, { [p.name]: v }, key);
    };
    input.onchange = () => {
      ctx.seal();
      key = null;
      drag = null;
      if (runTimer !== null) run(); // released: no need to wait for more moves
      else if (shownFor === state()) showSelected();
    };
    row.append(name, input, out);
    return row;
  }

  q('[data-act=reexpand]').onclick = reexpand;
  q('[data-act=select-back]').onclick = () => {
    const sel = selectedStep();
    if (sel === null) return;
    const p = parentStep(sel);
    if (p === null) status('this is the first step that made these shapes');
    else select(p);
  };
  q('[data-act=select-none]').onclick = () => { lastPick = -1; select(null); };

  // ---- pointer: pan, zoom, pick, draw ---------------------------------------------------

  const pointers = new Map();
  let gesture = null;
  const local = (e) => {
    const r = canvas.getBoundingClientRect();
    return [e.clientX - r.left, e.clientY - r.top];
  };
  canvas.addEventListener('pointerdown', (e) => {
    if (e.button > 0) return;
    try { canvas.setPointerCapture(e.pointerId); } catch { /* a synthetic or already-ended pointer */ }
    pointers.set(e.pointerId, local(e));
    if (pointers.size === 2) {
      const [a, b] = [...pointers.values()];
      gesture = { pinch: Math.hypot(a[0] - b[0], a[1] - b[1]), s: view.s, moved: true };
    } else gesture = { start: local(e), tx: view.tx, ty: view.ty, moved: false };
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!pointers.has(e.pointerId) || !gesture) return;
    pointers.set(e.pointerId, local(e));
    if (gesture.pinch && pointers.size === 2) {
      const [a, b] = [...pointers.values()];
      const d = Math.hypot(a[0] - b[0], a[1] - b[1]);
      zoomAt((a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (gesture.s * d) / gesture.pinch / view.s);
      return;
    }
    if (!gesture.start) return;
    const [x, y] = local(e);
    const dx = x - gesture.start[0], dy = y - gesture.start[1];
    if (!gesture.moved && Math.hypot(dx, dy) < 4) return;
    gesture.moved = true;
    view.tx = gesture.tx + dx;
    view.ty = gesture.ty + dy;
    quickPaint();
  });
  const up = (e) => {
    if (!pointers.has(e.pointerId)) return;
    pointers.delete(e.pointerId);
    const gst = gesture;
    if (pointers.size) return;
    gesture = null;
    if (!gst || gst.moved || e.type === 'pointercancel') return;
    const [x, y] = local(e);
    if (drawing) { addDrawPoint(x, y); return; }
    pickAt(x, y);
  };
  canvas.addEventListener('pointerup', up);
  canvas.addEventListener('pointercancel', up);
  canvas.addEventListener('dblclick', (e) => { if (drawing) { e.preventDefault(); finishDrawing(); } });
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const [x, y] = local(e);
    zoomAt(x, y, Math.exp(-e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015)));
  }, { passive: false });

  function zoomAt(cx, cy, f) {
    const s = Math.max(1e-4, Math.min(1e4, view.s * f));
    const [wx, wy] = toWorld(cx, cy);
    view.s = s;
    view.tx = cx - wx * s;
    view.ty = cy - wy * s;
    quickPaint();
  }
  const zoomCentre = (f) => zoomAt(viewport.clientWidth / 2, viewport.clientHeight / 2, f);
  q('[data-act=zoom-in]').onclick = () => zoomCentre(1.5);
  q('[data-act=zoom-out]').onclick = () => zoomCentre(1 / 1.5);
  q('[data-act=zoom-fit]').onclick = () => fitView();

  // ---- start shapes ----------------------------------------------------------------------

  const kindSel = q('[name=start-kind]');
  for (const [v, label] of START_KINDS) kindSel.append(new Option(label, v));
  const startKind = (s) => s?.start?.kind ?? 'grammar';
  function showStartRows(kind) {
    for (const [v] of START_KINDS) {
      const row = q(`.tangle-start-${v}`);
      if (row) row.hidden = v !== kind;
    }
  }
  function setStart(start) {
    const doc = state();
    if (!doc) return;
    refit = true;
    lastPick = -1;
    ctx.commit({ ...doc, start, edits: [], selected: null });
  }
  const num = (name, lo, hi, d) => {
    const v = Number(q(`[name=${name}]`).value);
    return Number.isFinite(v) ? Math.max(lo, Math.min(hi, v)) : d;
  };
  const rectStart = () => ({ kind: 'rect', width: num('start-width', 1, 1e6, 800), height: num('start-height', 1, 1e6, 600) });
  const textStart = () => ({ kind: 'text', text: q('[name=start-text]').value.trim() || 'Tangle', height: num('start-text-height', 1, 1e6, 300) });
  kindSel.onchange = () => {
    const kind = kindSel.value;
    showStartRows(kind);
    if (kind === 'grammar') setStart(null);
    else if (kind === 'rect') setStart(rectStart());
    else if (kind === 'text') setStart(textStart());
    else if (kind === 'svg') q('[name=start-svg]').click();
    else if (kind === 'polygon') beginDrawing();
  };
  for (const n of ['start-width', 'start-height']) q(`[name=${n}]`).onchange = () => setStart(rectStart());
  // A typed word applies as you type, once the typing pauses (and at once on Enter or leaving the field).
  let wordTimer = null;
  const applyWord = () => {
    ctx.clearTimeout(wordTimer);
    wordTimer = null;
    const next = textStart();
    const cur = state()?.start;
    if (cur?.kind === 'text' && cur.text === next.text && cur.height === next.height) return;
    setStart(next);
  };
  for (const n of ['start-text', 'start-text-height']) {
    const input = q(`[name=${n}]`);
    input.onchange = applyWord;
    input.oninput = () => {
      ctx.clearTimeout(wordTimer);
      wordTimer = ctx.setTimeout(applyWord, WORD_DELAY_MS);
    };
  }
  q('[name=start-svg]').onchange = async (e) => {
    const file = e.target.files[0];
    e.target.value = '';
    if (!file) return;
    const svg = await file.text();
    setStart({ kind: 'svg', svg });
  };
  q('[data-act=draw-start]').onclick = () => beginDrawing();
  q('[data-act=draw-curve]').onclick = () => beginDrawing('curve');
  q('[data-act=draw-shape]').onclick = () => beginDrawing('shape');

  /** Start drawing a polyline on the canvas for `purpose` (DRAW_PURPOSES). */
  function beginDrawing(purpose = 'start') {
    drawing = [];
    drawingFor = purpose;
    stopPlay();
    const p = DRAW_PURPOSES[purpose];
    q('.tangle-draw-bar').hidden = false;
    q('[data-act=draw-finish]').textContent = p.finish;
    q('[data-testid=tangle-draw-count]').textContent = '0';
    status(`drawing ${p.what}: click to add points, double-click or "${p.finish}" to finish`);
    // The drawing area comes into view: the button may sit far down the side column.
    q('[data-testid=tangle-canvas]').scrollIntoView({ block: 'nearest' });
    paint();
  }
  function addDrawPoint(cx, cy) {
    const [x, y] = toWorld(cx, cy);
    drawing.push([Math.round(x * 100) / 100, Math.round(y * 100) / 100]);
    q('[data-testid=tangle-draw-count]').textContent = String(drawing.length);
    paint();
  }
  function finishDrawing() {
    const pts = drawing;
    endDrawing();
    // A double-click adds its point twice.
    const clean = pts.filter((p, i) => i === 0 || p[0] !== pts[i - 1][0] || p[1] !== pts[i - 1][1]);
    const p = DRAW_PURPOSES[drawingFor];
    if (clean.length < p.min) { status(`${p.what} needs at least ${p.min} points`); return; }
    if (drawingFor === 'start') setStart({ kind: 'polygon', points: clean });
    else addDefinition(drawingFor, clean);
  }

  /**
   * Add the drawn polyline to the grammar as `curve drawnN = polyline(...)` (or
   * `shape`), first in the text so every rule can name it. The core scales it
   * to what it cuts or fills, so only its form matters.
   */
  function addDefinition(kind, pts) {
    const doc = state();
    if (!doc) return;
    const text = editor ? editor.getValue() : doc.grammar;
    let k = 1;
    while (new RegExp(`\\bdrawn${k}\\b`).test(text)) k++;
    const name = `drawn${k}`;
    const x0 = Math.min(...pts.map((p) => p[0])), y0 = Math.min(...pts.map((p) => p[1]));
    const num = (v) => String(Math.round(v * 10) / 10);
    const line = `${kind} ${name} = polyline(${pts.map(([x, y]) => `${num(x - x0)} ${num(y - y0)}`).join(', ')})`;
    const use = kind === 'curve' ? `regularSplit(${name}, 40, 0) : tag -> [a]` : `place(20, 4, ${name}) : tag -> [a, b]`;
    refit = false;
    ctx.commit({ ...doc, grammar: `${line}\n${text}`, example: null, edits: [], selected: null });
    status(`added "${kind} ${name}" to the grammar; use it in a rule, e.g. ${use}`);
  }
  function endDrawing() {
    drawing = null;
    q('.tangle-draw-bar').hidden = true;
    paint();
  }
  q('[data-act=draw-finish]').onclick = finishDrawing;
  q('[data-act=draw-cancel]').onclick = () => { endDrawing(); kindSel.value = startKind(state()); showStartRows(kindSel.value); status(''); };

  // ---- grammar picker ------------------------------------------------------------------

  const list = q('[data-testid=tangle-examples]');
  examples(ctx.run).then((exs) => {
    if (!ctx.alive()) return;
    list.replaceChildren(...exs.map((ex) => {
      const li = document.createElement('li');
      const b = document.createElement('button');
      b.type = 'button';
      b.className = 'tangle-example';
      b.dataset.example = ex.name;
      b.title = ex.about;
      const c = document.createElement('canvas');
      c.width = THUMB.width;
      c.height = THUMB.height;
      c.setAttribute('aria-hidden', 'true');
      const name = document.createElement('span');
      name.textContent = ex.name;
      b.append(c, name);
      b.onclick = () => loadExample(ex);
      li.append(b);
      const cached = thumbnails.get(ex.name);
      if (cached) c.getContext('2d').drawImage(cached, 0, 0);
      else b.dataset.thumb = 'pending'; // its preview is still growing (styles.css dims the card)
      return li;
    }));
    markExample(state());
  }).catch((err) => ctx.error(err, { prefix: 'The shipped grammars' }));

  function markExample(s) {
    for (const b of list.querySelectorAll('[data-example]')) b.setAttribute('aria-pressed', String(b.dataset.example === s?.example));
  }

  function loadExample(ex) {
    const doc = state();
    if (!doc) return;
    refit = true;
    lastPick = -1;
    ctx.clearTimeout(typingTimer);
    ctx.commit({ ...doc, example: ex.name, grammar: ex.grammar, start: null, edits: [], selected: null });
  }

  // One at a time, after the main drawing, each at low settings; kept for the page's life.
  let thumbsBusy = false;
  async function loadThumbnails() {
    if (thumbsBusy) return;
    thumbsBusy = true;
    try {
      for (const ex of await examples(ctx.run)) {
        if (thumbnails.has(ex.name) || !ctx.alive()) continue;
        let r;
        try {
          r = await ctx.run('tangle', { grammar: ex.grammar, seed: 1, ...THUMB_REQUEST });
        } catch (err) {
          if (err?.kind === 'cancelled') throw err;
          // This grammar cannot grow here (its card says so); the others still get theirs.
          const b = list.querySelector(`[data-example="${CSS.escape(ex.name)}"]`);
          if (b) { b.title = `${ex.about} (no preview: ${err?.message || err})`; b.dataset.thumb = 'none'; }
          continue;
        }
        const c = document.createElement('canvas');
        c.width = THUMB.width;
        c.height = THUMB.height;
        drawThumbnail(c, r);
        thumbnails.set(ex.name, c);
        const card = list.querySelector(`[data-example="${CSS.escape(ex.name)}"]`);
        card?.querySelector('canvas').getContext('2d').drawImage(c, 0, 0);
        if (card) delete card.dataset.thumb;
      }
      list.dataset.thumbnails = 'ready';
    } catch (err) {
      if (err?.kind !== 'cancelled') console.warn('tangle thumbnails:', err?.message || err);
    } finally {
      thumbsBusy = false;
    }
  }

  // ---- seed, ink, toolbar ----------------------------------------------------------------

  const setSeed = (v) => {
    const doc = state();
    if (!doc || !Number.isFinite(v)) return;
    ctx.commit({ ...doc, seed: Math.max(0, Math.round(v)), edits: [], selected: null });
  };
  q('[name=seed]').onchange = (e) => setSeed(Number(e.target.value));
  q('[data-act=new-seed]').onclick = () => setSeed((state()?.seed ?? 0) + 1);
  for (const name of ['wobble', 'stroke_width']) {
    const input = q(`[name=${name}]`);
    input.oninput = () => {
      const doc = state();
      if (doc) ctx.commit({ ...doc, [name]: Number(input.value) }, { coalesce: `tangle-${name}` });
    };
    input.onchange = () => ctx.seal();
  }
  q('[data-act=generate]').onclick = generate;
  q('[data-act=cancel]').onclick = () => { running?.abort(); ctx.job('grow')?.stop('cancelled'); ctx.clearTimeout(runTimer); runTimer = null; };
  // A growth of this document under way (it went on while the tool was away): show it busy.
  if (ctx.job('grow')?.running) { q('[data-act=cancel]').disabled = false; status('growing…'); }

  // ---- export --------------------------------------------------------------------------

  async function exportAs(format) {
    const doc = state();
    if (!doc) return null;
    const pngWidth = Number(q('[name=png-width]').value) || 1600;
    status(`exporting ${format.toUpperCase()}…`);
    try {
      const r = await ctx.run('tangle', { ...requestOf(doc), export: format, png_width: pngWidth, keep: true },
        { affinity: KEEP_AFFINITY });
      status(`exported ${format.toUpperCase()}: ${r.stats.shapes.toLocaleString('en')} shapes`);
      return r;
    } catch (err) {
      ctx.error(err, { prefix: `Export ${format.toUpperCase()}` });
      status('');
      return null;
    }
  }
  const base = () => state()?.example || 'tangle';
  q('[data-act=export-svg]').onclick = async () => {
    const r = await exportAs('svg');
    if (r) download(`${base()}-seed${state().seed}.svg`, new Blob([r.svg], { type: 'image/svg+xml' }));
  };
  q('[data-act=export-png]').onclick = async () => {
    const r = await exportAs('png');
    if (r) download(`${base()}-seed${state().seed}.png`, new Blob([r.png], { type: 'image/png' }));
  };

  // For the e2e tests and benches (ctx.expose).
  const hooks = {
    state,
    result: () => T?.r ?? null,
    /** The shown answer's points (a Float32Array). */
    points: () => T?.pts ?? null,
    pending: () => runTimer !== null || running !== null || typingTimer !== null || wordTimer !== null,
    timing: () => ({ ...timing }),
    /** `{incremental}`: false switches the old path on (full repaints, nothing kept from the last answer). */
    options,
    /** Shapes the shown answer kept from the one before (their Path2Ds). */
    reused: () => T?.reused ?? 0,
    /** Forget every kept bitmap (the latency bench starts each pass from none). */
    clearLayers: () => layers.clear(),
    /** Whether idle-time layer building is done (or off) for the current view. */
    prebuilt: () => prebuildHandle === 0 && prebuildTimer === null,
    /** Vertices per part of what step `at` shows (draw.js batches). */
    parts: (at) => (T ? T.batches(at).parts.map((b) => b.vertices) : []),
    step: () => k,
    view: () => ({ ...view, dpr }),
    /** The selected step's input shapes' bounds in canvas pixels, or null. */
    selectedBox() {
      const sel = selectedStep();
      const b = sel !== null && T.bounds(T.r.steps[sel].inputs);
      if (!b) return null;
      const [x0, y0] = toCss(b[0], b[1]), [x1, y1] = toCss(b[2], b[3]);
      return [x0 * dpr, y0 * dpr, x1 * dpr, y1 * dpr];
    },
    /**
     * Where the selected step's input shapes cover the canvas (grown by `grow` CSS px),
     * one byte a canvas pixel (1: covered), or null: the only part an edit of it may redraw.
     */
    selectedMask(grow = 3) {
      const sel = selectedStep();
      if (sel === null) return null;
      const m = document.createElement('canvas');
      m.width = canvas.width;
      m.height = canvas.height;
      const mg = m.getContext('2d');
      mg.setTransform(dpr * view.s, 0, 0, dpr * view.s, dpr * view.tx, dpr * view.ty);
      mg.fillStyle = mg.strokeStyle = '#000';
      mg.lineWidth = (2 * grow) / view.s + (state().stroke_width || 0);
      mg.lineJoin = 'round';
      for (const i of T.r.steps[sel].inputs) {
        mg.fill(T.path(i), 'nonzero');
        mg.stroke(T.path(i));
      }
      const d = mg.getImageData(0, 0, m.width, m.height).data;
      const out = new Uint8Array(m.width * m.height);
      for (let i = 0; i < out.length; i++) out[i] = d[4 * i + 3] > 0 ? 1 : 0;
      return out;
    },
    /** A point (CSS px from the canvas's corner) where a click picks shape i at the shown step, or null. */
    pointIn(i) {
      const b = 4 * i;
      for (let n = 2; n <= 32; n *= 2) {
        for (let a = 1; a < n; a++) {
          for (let c = 1; c < n; c++) {
            const x = T.box[b] + ((T.box[b + 2] - T.box[b]) * a) / n, y = T.box[b + 1] + ((T.box[b + 3] - T.box[b + 1]) * c) / n;
            const [cx, cy] = toCss(x, y);
            if (cx < 2 || cy < 2 || cx > viewport.clientWidth - 2 || cy > viewport.clientHeight - 2) continue;
            const [wx, wy] = toWorld(cx, cy);
            if (T.pick(wx, wy, k, g) === i) return [cx, cy];
          }
        }
      }
      return null;
    },
    exportSvg: async () => (await exportAs('svg'))?.svg ?? null,
    paintNow,
  };
  ctx.expose(hooks);

  /**
   * A file dropped anywhere in the window (document.js: view.drop): an SVG
   * becomes the start shape, a grammar (.tangle, plain text) the grammar
   * text, once the core has read it with the rest of the document (one step
   * grown); a file it refuses leaves the document as it is.
   */
  async function dropFile(file) {
    const name = file.name.toLowerCase();
    const svg = /\.svg$/.test(name) || file.type === 'image/svg+xml';
    const grammar = !svg && /\.(tangle|txt)$/.test(name);
    if (!svg && !grammar) throw new Error('Tangle opens SVG files (a start shape), grammars (.tangle) and Filigree projects');
    const limit = svg ? MAX_SVG_BYTES : MAX_GRAMMAR_BYTES;
    if (file.size > limit) throw new Error(`it is ${Math.ceil(file.size / 1024)} KB, more than ${svg ? 'an SVG start' : 'a grammar'} may be (${limit / 1024} KB)`);
    const text = await file.text();
    const doc = state();
    if (!doc) throw new Error('the panel is still loading');
    const change = svg ? { start: { kind: 'svg', svg: text } } : { grammar: text, example: null };
    await ctx.run('tangle', { ...requestOf({ ...doc, ...change, edits: [] }), max_steps: 1 });
    const now = state();
    if (!now || !ctx.alive()) return;
    if (!svg) { ctx.clearTimeout(typingTimer); typingTimer = null; }
    refit = true;
    lastPick = -1;
    ctx.commit({ ...now, ...change, edits: [], selected: null });
    status(`opened ${svg ? 'the start shape' : 'the grammar'} ${file.name}`);
  }

  return {
    drop: dropFile,
    render(s, prev) {
      if (!s) return;
      if (editor && editor.getValue() !== s.grammar && typingTimer === null) editor.setValue(s.grammar);
      if (editor && (!prev || prev.grammar !== s.grammar)) editor.clearError();
      q('[name=seed]').value = String(s.seed);
      for (const name of ['wobble', 'stroke_width']) {
        const input = q(`[name=${name}]`);
        if (Number(input.value) !== s[name]) input.value = String(s[name]);
        input.nextElementSibling.textContent = String(s[name]);
      }
      if (!drawing) {
        kindSel.value = startKind(s);
        showStartRows(kindSel.value);
      }
      if (s.start?.kind === 'rect') { q('[name=start-width]').value = String(s.start.width); q('[name=start-height]').value = String(s.start.height); }
      if (s.start?.kind === 'text' && wordTimer === null) {
        // Not under the user's fingers: the field keeps what is typed (a trailing space, say).
        const word = q('[name=start-text]');
        if (document.activeElement !== word || word.value.trim() !== s.start.text) word.value = s.start.text;
        q('[name=start-text-height]').value = String(s.start.height);
      }
      markExample(s);
      if (!prev || !sameRequest(s, prev)) {
        if (!prev || prev.grammar !== s.grammar || prev.start !== s.start) refit = true;
        scheduleRun();
      } else if (prev.stroke_width !== s.stroke_width) paint();
      if (!prev || prev.selected !== s.selected || !sameRequest(s, prev)) {
        hl = null;
        if (shownFor && sameRequest(shownFor, s)) showSelected();
        // An edit of the selected step is answered soon: until then the canvas keeps the
        // last picture and its highlight. Repainting now would only take the highlight off,
        // and its raster would take the CPU from the worker growing the answer. (A new
        // document without a selection drops the highlight at once.)
        if (!(options.incremental && s.selected != null && awaitingAnswer(s))) paint();
      }
    },
    markError(err) {
      if (err.field !== 'grammar' && err.kind !== 'syntax') return;
      q('details.tangle-program').open = true;
      const m = /line (\d+), column (\d+)/.exec(err.message || '');
      const at = Number.isInteger(err.line) ? [err.line, err.column ?? 1] : m && [Number(m[1]), Number(m[2])];
      if (at) editorReady.then((ed) => ctx.alive() && ed.markError(at[0], at[1], err.message));
    },
    keys: {
      g: () => generate(),
      r: () => reexpand(),
    },
    unmount() {
      ro.disconnect();
      stopPlay();
      if (prebuildHandle) cancelIdle(prebuildHandle);
      cancelAnimationFrame(frame);
      running = null; // its growth goes on: it is the document's (ctx.startJob)
    },
  };
}

export default { id: 'tangle', title: 'Tangle', state: tangleState, mount };
