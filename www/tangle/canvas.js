// The Tangle canvas: the view transform and every paint of it. A step's
// picture is a few Path2D parts from a segment tree over the steps, built
// lazily (draw.js); heavy parts shown by many steps
// are kept as bitmaps of the current view, so a slider drag redraws only
// the small parts that changed, and idle time draws the heaviest parts'
// bitmaps ahead of a jump. A repaint after an edit or a selection redraws
// only the canvas tiles the changed shapes touch (`changedRegion`,
// tiles.js). During a pan or zoom the last full picture is moved as a
// bitmap and redrawn sharp once the gesture pauses, so 18k shapes stay
// smooth. The selected step is highlighted; the polyline being drawn
// (polygon-draw.js) is painted over the rest by `overlay`.
import { paintBatches, createLayers, prebuildLayer, LAYER_VERTICES } from './draw.js';
import { changedTiles, tileClip, touchesTiles } from './tiles.js';
import { noteDrawn } from './timing.js';

const SHARP_DELAY_MS = 120;
const PREBUILD_DELAY_MS = 250; // after the last paint: not while a slider or a pan is moving
const HIGHLIGHT = 'rgba(255, 122, 0, 0.38)';
export const HIGHLIGHT_LINE = '#e06000';

/**
 * The painter of `canvas` in `viewport`, showing `live.T` at step `live.k`
 * (state.js createLive). `overlay`: `{active(), paint(g)}`, the polyline
 * being drawn; `timing`, `options`: timing.js.
 */
export function createPainter(ctx, { canvas, viewport, live, timing, options, overlay }) {
  const g = canvas.getContext('2d');
  const state = () => ctx.state();
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
  // What the canvas shows (set by every sharp paint; null after a pan frame):
  // a repaint then redraws only the rectangle where the picture differs.
  let shown = null; // {T, k, key, w, h, hl, drawing}
  let lastParts = new Set(); // the parts of the step tree the last full repaint drew
  const maskCanvas = document.createElement('canvas'); // one pixel a tile (tiles.js)

  // ---- the view transform -------------------------------------------------------------

  function resize() {
    dpr = window.devicePixelRatio || 1;
    const w = Math.max(1, Math.round(viewport.clientWidth * dpr));
    const h = Math.max(1, Math.round(viewport.clientHeight * dpr));
    if (canvas.width !== w || canvas.height !== h) {
      canvas.width = w;
      canvas.height = h;
      sharpView = null; // a resized canvas is blank until its next paint
      // A view the user has not moved since it was fitted follows the viewport's size.
      if (live.refit || !live.T || fitted === viewKey()) fitView(); else paint();
    }
  }
  const ro = new ResizeObserver(() => resize());
  ro.observe(viewport);

  /** The drawing's extent: the answer's bounds, or a default sheet before any answer. */
  const extent = () => (live.T && live.T.n ? live.T.r.bounds : [0, 0, 800, 600]);

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
  /** The view in device pixels (tiles.js). */
  const deviceView = () => [dpr * view.s, dpr * view.tx, dpr * view.ty];

  const lineWidth = () => {
    const sw = state()?.stroke_width ?? 1;
    return sw > 0 ? Math.max(sw, 0.5 / view.s) : 0;
  };
  const viewKey = () => `${view.s} ${view.tx} ${view.ty} ${dpr} ${lineWidth()}`;

  // ---- sharp paints ---------------------------------------------------------------------

  /** Repaint sharp at the next frame: only the rectangle that changed when that is known. */
  function paint() {
    if (frame) return;
    frame = requestAnimationFrame(() => { frame = 0; paintChanged(); });
  }

  /** The canvas now shows the current step, view and highlight. */
  function recordShown() {
    const { T, k } = live;
    if (T) T.from = null; // a delta's base is compared once, then dropped
    shown = { T, k, key: viewKey(), w: canvas.width, h: canvas.height, hl: T && T.n ? currentHl() : null, drawing: overlay.active() };
  }

  /**
   * Where the picture to paint differs from what the canvas shows:
   * `{tiles, cols, rows, count, sum}` (tiles.js changedTiles), null when
   * nowhere, or false when that is unknown or most of the canvas (then
   * everything is repainted).
   */
  function changedRegion() {
    const { T, k } = live;
    timing.why = 'state';
    if (!shown || !T || !T.n || overlay.active() || shown.drawing || !shown.T) return false;
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
    const changed = new Path2D();
    for (const i of ch.added) changed.addPath(T.path(i));
    for (const j of ch.removed) changed.addPath(shown.T.path(j));
    return changedTiles(maskCanvas, canvas.width, canvas.height, deviceView(), lineWidth(), changed, hls);
  }

  function paintChanged({ newBitmaps = true } = {}) {
    timing.paintAt = performance.now();
    const region = changedRegion();
    if (region === false) paintNow({ newBitmaps });
    else if (region) paintRegion(region);
    else { timing.paint = 0; timing.region = 0; recordShown(); }
  }

  /** paintChanged now instead of at the next frame (a pending frame is dropped). */
  function paintChangedNow(opts) {
    cancelAnimationFrame(frame);
    frame = 0;
    paintChanged(opts);
  }

  /**
   * Repaint the tiles of `region` only (changedRegion): clipped to them, the
   * shapes that reach into them are drawn as a full repaint draws them (the
   * same parts in the same order), then the highlight.
   */
  function paintRegion(region) {
    const { T, k } = live;
    const { cols, rows, count } = region;
    const t0 = performance.now();
    noteDrawn(timing, t0);
    const { clip, bx, by, bw, bh } = tileClip(region, canvas.width, canvas.height);
    g.save();
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.clip(clip);
    g.fillStyle = '#fff';
    g.fillRect(bx, by, bw, bh);
    g.setTransform(dpr * view.s, 0, 0, dpr * view.s, dpr * view.tx, dpr * view.ty);
    const lw = lineWidth();
    // A shape is drawn when its box, grown by half a pen and a pixel, touches a marked tile.
    const touches = touchesTiles(region, T.box, deviceView(), lw / 2 + 1 / view.s);
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

  function paintNow({ newBitmaps = true } = {}) {
    const { T, k } = live;
    const t0 = performance.now();
    noteDrawn(timing, t0);
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
      // bitmap of one (a canvas made, drawn and copied) costs more than drawing it.
      const last = lastParts;
      const shared = (part) => part.span * 16 >= T.steps || last.has(part);
      paintBatches(g, b, lineWidth(), layers, key, (part) => (newBitmaps ? shared(part) : layers.has(part, key, w, h)));
      lastParts = new Set(b.parts);
      paintHighlight();
    }
    overlay.paint(g);
    g.setTransform(1, 0, 0, 1, 0, 0);
    // Kept for quick pans and zooms (copied when one starts).
    sharpView = { ...view };
    snapStale = true;
    recordShown();
    schedulePrebuild();
    timing.region = 1;
    timing.paint = performance.now() - t0;
  }

  // ---- bitmaps ahead of need --------------------------------------------------------------
  // In idle time after a sharp paint, the heaviest parts of the step tree are drawn as
  // bitmaps of the current view (heaviest first, while the layer budget has room), so a
  // slider jump to a far step copies them instead of rasterising them (draw.js).

  let prebuildHandle = 0;
  let prebuildTimer = null;
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
    if (!live.T || !live.T.n || !ctx.alive()) return;
    const key = viewKey(), w = canvas.width, h = canvas.height, from = live.T;
    const m = new DOMMatrix([dpr * view.s, 0, 0, dpr * view.s, dpr * view.tx, dpr * view.ty]);
    let todo = null;
    let at = 0;
    const work = (deadline) => {
      prebuildHandle = 0;
      if (live.T !== from || viewKey() !== key || canvas.width !== w || canvas.height !== h || !ctx.alive()) return;
      todo ??= live.T.heavyParts();
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

  // ---- quick paints during a pan or zoom --------------------------------------------------

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

  // ---- the selected step's highlight ------------------------------------------------------

  /** The highlight of the selected step at the shown step (null: none): kept until either changes. */
  function currentHl() {
    const { T, k } = live;
    const sel = live.selected();
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

  return {
    canvas, viewport, g, view, layers,
    get dpr() { return dpr; },
    fitView, toWorld, toCss, paint, paintNow, paintChangedNow, quickPaint,
    /** Forget the highlight (a new answer or selection makes it anew). */
    dropHighlight() { hl = null; },
    /** Whether idle-time layer building is done (or off) for the current view. */
    prebuilt: () => prebuildHandle === 0 && prebuildTimer === null,
    /** The panel is left: no more frames or idle work. */
    stop() {
      ro.disconnect();
      if (prebuildHandle) cancelIdle(prebuildHandle);
      cancelAnimationFrame(frame);
    },
  };
}
