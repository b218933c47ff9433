// Pixel's picture, a CanvasView (canvas-view.js), so a brush drag never
// re-lays out or redraws it all: the base layer holds the source or the
// result at its own resolution (scaled by CSS); the mask overlay and the
// stroke layer cover only the visible part at screen resolution, and each
// animation frame repaints just the rectangle the brush or the new stroke
// segment touched. The pixel grid is a CSS background.
import { CanvasView } from './canvas-view.js';

const MASK_RGBA = [127, 209, 199, 90];

/**
 * The picture of a mounted panel, drawn from `live` (state.js): returns
 * {canvas, stack, loadSource(doc), drawBase(), drawMaskFull(), drawStrokes()}.
 */
export function createPicture(ctx, { q, live }) {
  const state = () => ctx.state();

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

  /** Decode the document's source and size every layer for it. */
  function loadSource(doc) {
    const bytes = doc.source;
    live.loadingFor = bytes;
    const job = (async () => {
      const img = await ctx.run('decode-image', { bytes: bytes.slice() });
      const bitmap = await ctx.bitmap(new ImageData(new Uint8ClampedArray(img.rgba), img.width, img.height));
      if (state()?.source !== bytes) { ctx.release(bitmap); return; }
      ctx.release(live.sourceBitmap);
      live.sourceBitmap = bitmap;
      live.sourceImg = { width: img.width, height: img.height };
      live.sourceOf = bytes;
      // The old result belongs to the old source. A run of this source
      // can finish before its decode (a slow machine): that result stays.
      if (live.resultFor !== bytes) {
        live.result = null;
        ctx.release(live.resultBitmap);
        live.resultBitmap = null;
        q('.stats').replaceChildren();
      }
      canvas.setImage(live.sourceBitmap, img.width, img.height);
      canvas.setMask(state().mask);
      drawBase();
      q('.empty').hidden = true;
    })().catch((err) => ctx.error(err, { prefix: 'Source image' })).finally(() => {
      if (live.sourceLoading === job) { live.sourceLoading = null; live.loadingFor = null; }
    });
    live.sourceLoading = job;
  }

  function showZoom() {
    const z = canvas.zoom;
    q('[data-testid=zoom]').textContent = `×${z >= 1 ? z : Number(z.toFixed(2))}`;
    stack.style.setProperty('--cell', `${z}px`);
    stack.classList.toggle('grid', z >= 8);
  }

  function drawBase() {
    if (!live.sourceImg) return;
    const base = live.view.showResult && live.resultBitmap ? live.resultBitmap : live.sourceBitmap;
    if (base) canvas.setImage(base, live.sourceImg.width, live.sourceImg.height);
  }

  function maskVisible() {
    return live.view.showMask || live.view.mode !== 'stroke';
  }

  /** The mask overlay: the drag's working copy while painting, else the document's. */
  function drawMaskFull() {
    const m = live.drawing?.kind === 'mask' ? live.drawing.mask : state()?.mask;
    canvas.showMask = maskVisible();
    canvas.setMask(m && live.sourceImg && m.width === live.sourceImg.width && m.height === live.sourceImg.height ? m : null);
  }

  /** Repaint the whole stroke layer (strokes, arrows) at the next frame. */
  function drawStrokes() {
    canvas.invalidate(null, 'strokes');
  }

  // The stroke layer's painter (CanvasView onPaint): `g` draws in image pixels,
  // clipped to `r`, the rectangle to repaint.
  function paintStrokes(g, zoom, r) {
    const doc = state();
    if (!doc || !live.sourceImg) return;
    if (live.view.showArrows && live.result?.field && live.result.width === live.sourceImg.width) drawArrows(g, live.result.field, live.sourceImg.width, live.sourceImg.height, r);
    if (live.view.showStrokes) {
      for (const st of doc.strokes) drawStroke(g, st, '#ff5db1');
      if (live.drawing?.kind === 'stroke') drawStroke(g, live.drawing.points, '#ffd166', false);
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

  return { canvas, stack, loadSource, drawBase, drawMaskFull, drawStrokes };
}
