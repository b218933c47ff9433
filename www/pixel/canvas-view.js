// Layered canvases for a panel's main view (pixel art, targets), built so a
// brush drag repaints one small rectangle per frame and never re-lays out.
//
//   const view = new CanvasView(container, { integer: true, maxZoom: 32, onPaint });
//   view.setImage(source, width, height)   base layer: an ImageBitmap, canvas, image
//                                          or ImageData of width×height pixels
//   view.setMask(mask, rgba = [127, 209, 199, 90])   overlay from {width, height,
//                                          bits: Uint8Array (1 = inside)}; drawn while
//                                          view.showMask is true
//   view.maskChanged(rect)                 bits changed inside rect (image pixels): that
//                                          rectangle of the overlay is rebuilt in an
//                                          ImageData and put with ONE putImageData in
//                                          the next animation frame
//   view.invalidate(rect?, layer?)         repaint rect (image pixels; default all) of
//                                          'base' | 'overlay' | 'strokes' (default all)
//                                          in the next animation frame; calls coalesce
//   view.setZoom('fit' | n)                'fit' (the default) follows the container's
//                                          width and the window's height below it, less
//                                          `reserve` px; `integer` rounds zooms ≥ 1 down
//                                          to whole numbers (crisp pixel art)
//   view.zoom, view.fitting                current zoom, and whether it follows the container
//   view.toImage(event) → [x, y]           pointer → image pixels (floats), from the
//                                          geometry cached at pointerdown / resize /
//                                          scroll: pointermove does no layout work
//   view.element                           the stack; attach pointer listeners to it
//   view.destroy()
//
// onPaint(ctx, zoom, rect) draws the stroke layer (strokes, grid, arrows): ctx is
// transformed so one unit is one image pixel, clipped to rect and cleared there.
//
// Why this shape: the browser re-composites a changed canvas in proportion to its
// backing size (a 20×20 putImageData costs 0.7 s a frame on a 4096² canvas in
// headless Chromium, 38 ms on a 600² one). So only the base layer, which changes
// when a new result arrives, holds the image at its own resolution (scaled by CSS
// with `image-rendering: pixelated`); the overlay and stroke layers, which change
// on every brush move, cover just the visible part of the view at screen
// resolution and are redrawn whole only when that part scrolls or zooms.

export class CanvasView {
  constructor(container, { integer = false, minZoom = 1 / 64, maxZoom = 32, onPaint = null, reserve = 24, minFitHeight = 160 } = {}) {
    Object.assign(this, { container, integer, minZoom, maxZoom, onPaint, reserve, minFitHeight });
    this.width = 0;
    this.height = 0;
    this.zoom = 1;
    this.fitting = true;
    this.showMask = false;
    this.source = null;
    this.mask = null;
    this.maskRgba = [127, 209, 199, 90];
    this.visible = { x: 0, y: 0, w: 0, h: 0 }; // CSS px of the stack covered by the top layers
    this.dirty = { base: null, overlay: null, strokes: null };
    this.frame = 0;
    this.geometry = null;

    this.element = document.createElement('div');
    this.element.className = 'canvas-view';
    const layer = (cls) => {
      const c = document.createElement('canvas');
      c.className = `canvas-view-layer ${cls}`;
      c.width = c.height = 0;
      this.element.append(c);
      return c;
    };
    this.base = layer('base');
    this.overlay = layer('overlay');
    this.strokes = layer('strokes');
    this.baseCtx = this.base.getContext('2d');
    this.overlayCtx = this.overlay.getContext('2d');
    this.strokeCtx = this.strokes.getContext('2d');
    container.append(this.element);

    this.element.addEventListener('pointerdown', () => this.measure(), { capture: true });
    this.resizer = new ResizeObserver(() => {
      if (this.fitting) this.applyZoom(this.fitZoom());
      this.relayout();
    });
    this.resizer.observe(container);
    // Scrolling moves the stack: re-cover the visible part, measure again at the next pointer event.
    this.onScroll = () => {
      this.geometry = null;
      if (!this.scrollFrame) {
        this.scrollFrame = requestAnimationFrame(() => { this.scrollFrame = 0; this.relayout(); });
      }
    };
    addEventListener('scroll', this.onScroll, { capture: true, passive: true });
  }

  setImage(source, width, height) {
    const resized = width !== this.width || height !== this.height;
    this.source = source;
    this.width = width;
    this.height = height;
    if (resized) {
      this.base.width = width;
      this.base.height = height;
      this.applyZoom(this.fitting ? this.fitZoom() : this.zoom, true);
    }
    this.invalidate(null, 'base');
  }

  setMask(mask, rgba = this.maskRgba) {
    this.mask = mask;
    this.maskRgba = rgba;
    this.invalidate(null, 'overlay');
  }

  maskChanged(rect) {
    this.invalidate(rect, 'overlay');
  }

  setZoom(z) {
    this.fitting = z === 'fit';
    this.applyZoom(this.fitting ? this.fitZoom() : z);
  }

  /** The zoom that shows the whole image: the container's width, the window's height below it. */
  fitZoom() {
    if (!this.width || !this.height) return 1;
    const cw = this.container.clientWidth;
    const top = this.container.getBoundingClientRect().top + (globalThis.scrollY || 0);
    const ch = Math.max(this.minFitHeight, innerHeight - Math.max(0, top) - this.reserve);
    const z = Math.min(cw / this.width, ch / this.height);
    return Number.isFinite(z) && z > 0 ? z : 1;
  }

  applyZoom(z, force = false) {
    let zoom = Math.max(this.minZoom, Math.min(this.maxZoom, z));
    if (this.integer && zoom >= 1) zoom = Math.floor(zoom);
    if (zoom === this.zoom && !force) return;
    this.zoom = zoom;
    this.element.style.width = `${Math.round(this.width * zoom)}px`;
    this.element.style.height = `${Math.round(this.height * zoom)}px`;
    this.element.dispatchEvent(new CustomEvent('zoom', { detail: { zoom } }));
    this.relayout();
  }

  /** Place the overlay and stroke layers over the visible part of the stack and redraw them. */
  relayout() {
    this.geometry = null;
    const W = Math.round(this.width * this.zoom), H = Math.round(this.height * this.zoom);
    const s = this.element.getBoundingClientRect();
    const c = this.container.getBoundingClientRect();
    // Visible = the stack ∩ the container's box ∩ the window, in stack CSS px.
    const x0 = Math.max(0, Math.max(c.left, 0) - s.left), y0 = Math.max(0, Math.max(c.top, 0) - s.top);
    const x1 = Math.min(W, Math.min(c.right, innerWidth) - s.left), y1 = Math.min(H, Math.min(c.bottom, innerHeight) - s.top);
    const v = { x: Math.floor(x0), y: Math.floor(y0), w: Math.max(0, Math.ceil(x1) - Math.floor(x0)), h: Math.max(0, Math.ceil(y1) - Math.floor(y0)) };
    this.visible = v;
    this.dpr = Math.min(2, globalThis.devicePixelRatio || 1);
    for (const [cv, scale] of [[this.overlay, 1], [this.strokes, this.dpr]]) {
      Object.assign(cv.style, { left: `${v.x}px`, top: `${v.y}px`, width: `${v.w}px`, height: `${v.h}px` });
      cv.width = Math.max(1, Math.round(v.w * scale));
      cv.height = Math.max(1, Math.round(v.h * scale));
    }
    this.invalidate(null, 'overlay');
    this.invalidate(null, 'strokes');
  }

  /** Cache the stack's position (at pointerdown and after resizes or scrolls, never on pointermove). */
  measure() {
    const r = this.element.getBoundingClientRect();
    this.geometry = { left: r.left, top: r.top, sx: this.width / (r.width || 1), sy: this.height / (r.height || 1) };
    return this.geometry;
  }

  toImage(e) {
    const g = this.geometry || this.measure();
    return [(e.clientX - g.left) * g.sx, (e.clientY - g.top) * g.sy];
  }

  invalidate(rect = null, layer = null) {
    const full = { x: 0, y: 0, w: this.width, h: this.height };
    const r = rect ? clip(rect, full) : full;
    if (!r) return;
    for (const name of layer ? [layer] : ['base', 'overlay', 'strokes']) this.dirty[name] = union(this.dirty[name], r);
    if (!this.frame) this.frame = requestAnimationFrame(() => this.paint());
  }

  /** Repaint the dirty rectangles now (normally called by the animation frame). */
  paint() {
    this.frame = 0;
    const { base, overlay, strokes } = this.dirty;
    this.dirty = { base: null, overlay: null, strokes: null };
    if (base && this.source) {
      const { x, y, w, h } = base;
      if (this.source instanceof ImageData) this.baseCtx.putImageData(this.source, 0, 0, x, y, w, h);
      else {
        this.baseCtx.clearRect(x, y, w, h);
        this.baseCtx.drawImage(this.source, x, y, w, h, x, y, w, h);
      }
    }
    if (overlay) this.paintOverlay(overlay);
    if (strokes && this.onPaint) this.paintStrokes(strokes);
  }

  /** The screen pixels of the top layers that image rect `r` covers (clipped to the visible part). */
  screenRect(r, scale, margin = 0) {
    const v = this.visible, z = this.zoom;
    const u0 = Math.max(0, Math.floor(((r.x - margin) * z - v.x) * scale));
    const v0 = Math.max(0, Math.floor(((r.y - margin) * z - v.y) * scale));
    const u1 = Math.min(Math.round(v.w * scale), Math.ceil(((r.x + r.w + margin) * z - v.x) * scale));
    const v1 = Math.min(Math.round(v.h * scale), Math.ceil(((r.y + r.h + margin) * z - v.y) * scale));
    return u1 > u0 && v1 > v0 ? { x: u0, y: v0, w: u1 - u0, h: v1 - v0 } : null;
  }

  paintOverlay(r) {
    const m = this.mask;
    const sr = this.screenRect(r, 1);
    if (!sr) return;
    if (!m || !this.showMask || m.width !== this.width || m.height !== this.height) {
      this.overlayCtx.clearRect(sr.x, sr.y, sr.w, sr.h);
      return;
    }
    // Each screen pixel shows the mask bit of the image pixel under its centre.
    const img = new ImageData(sr.w, sr.h);
    const data = new Uint32Array(img.data.buffer);
    const [R, G, B, A] = this.maskRgba;
    const on = new Uint32Array(new Uint8ClampedArray([R, G, B, A]).buffer)[0];
    const z = this.zoom, v = this.visible;
    const cols = new Int32Array(sr.w);
    for (let i = 0; i < sr.w; i++) cols[i] = Math.min(this.width - 1, Math.floor((v.x + sr.x + i + 0.5) / z));
    for (let j = 0; j < sr.h; j++) {
      const row = Math.min(this.height - 1, Math.floor((v.y + sr.y + j + 0.5) / z)) * this.width;
      const o = j * sr.w;
      for (let i = 0; i < sr.w; i++) if (m.bits[row + cols[i]]) data[o + i] = on;
    }
    this.overlayCtx.putImageData(img, sr.x, sr.y);
  }

  paintStrokes(r) {
    const ctx = this.strokeCtx, s = this.dpr, v = this.visible;
    // One image pixel of margin (strokes are wider than the pixels they cross) plus a few screen pixels.
    const sr = this.screenRect(r, s, 1 + 4 / this.zoom);
    if (!sr) return;
    ctx.setTransform(1, 0, 0, 1, 0, 0);
    ctx.save();
    ctx.beginPath();
    ctx.rect(sr.x, sr.y, sr.w, sr.h);
    ctx.clip();
    ctx.clearRect(sr.x, sr.y, sr.w, sr.h);
    const k = this.zoom * s;
    ctx.setTransform(k, 0, 0, k, -v.x * s, -v.y * s);
    this.onPaint(ctx, this.zoom, r);
    ctx.restore();
  }

  destroy() {
    cancelAnimationFrame(this.frame);
    cancelAnimationFrame(this.scrollFrame);
    this.resizer.disconnect();
    removeEventListener('scroll', this.onScroll, { capture: true });
    this.element.remove();
  }
}

/** The integer rectangle covering `r` (floats allowed), clipped to `bounds`; null when empty. */
function clip(r, bounds) {
  const x0 = Math.max(bounds.x, Math.floor(r.x)), y0 = Math.max(bounds.y, Math.floor(r.y));
  const x1 = Math.min(bounds.x + bounds.w, Math.ceil(r.x + r.w)), y1 = Math.min(bounds.y + bounds.h, Math.ceil(r.y + r.h));
  return x1 > x0 && y1 > y0 ? { x: x0, y: y0, w: x1 - x0, h: y1 - y0 } : null;
}

function union(a, b) {
  if (!a) return b;
  const x = Math.min(a.x, b.x), y = Math.min(a.y, b.y);
  return { x, y, w: Math.max(a.x + a.w, b.x + b.w) - x, h: Math.max(a.y + a.h, b.y + b.h) - y };
}
