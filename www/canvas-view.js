// Layered canvases for a panel's main view (pixel art, targets), built so a
// brush drag repaints one small rectangle per frame and never re-lays out.
//
//   const view = new CanvasView(container, { integer: true, maxZoom: 32, onPaint });
//   view.setImage(source, width, height)   base layer: an ImageBitmap, canvas,
//                                          image or ImageData of width×height pixels
//   view.setMask(mask, rgba = [127, 209, 199, 90])   overlay from {width, height,
//                                          bits: Uint8Array (1 = inside)}; shown when
//                                          view.showMask is true
//   view.maskChanged(rect)                 bits changed inside rect (image pixels):
//                                          the overlay's ImageData is updated there and
//                                          that rectangle repainted next frame with ONE
//                                          putImageData
//   view.invalidate(rect?, layer?)         repaint rect (image pixels; default all) of
//                                          'base' | 'overlay' | 'strokes' | all layers
//                                          in the next animation frame; calls coalesce
//   view.setZoom('fit' | n)                'fit' (the default) follows the container's
//                                          width and the window's height below it, less
//                                          `reserve` px; `integer` rounds zoom down to whole
//                                          numbers ≥ 1 (crisp pixel art)
//   view.zoom, view.fitting                current zoom and whether it follows the container
//   view.toImage(event) → [x, y]           pointer → image pixels (floats); uses the
//                                          geometry cached at pointerdown / resize, so
//                                          pointermove does no layout work
//   view.element                           the stack to attach pointer listeners to
//   view.destroy()
//
// onPaint(ctx, zoom, rect) draws the stroke layer (strokes, grid, arrows): ctx is
// scaled so one unit is one image pixel and clipped to rect, already cleared.
// Base and overlay canvases hold the image at its own resolution and are scaled
// by CSS (`image-rendering: pixelated`); only the stroke layer is drawn at screen
// resolution (capped at MAX_STROKE_SIDE pixels a side).

const MAX_STROKE_SIDE = 4096;

export class CanvasView {
  constructor(container, { integer = false, minZoom = 1 / 64, maxZoom = 32, onPaint = null, reserve = 24, minFitHeight = 160 } = {}) {
    this.reserve = reserve;
    this.minFitHeight = minFitHeight;
    this.container = container;
    this.integer = integer;
    this.minZoom = minZoom;
    this.maxZoom = maxZoom;
    this.onPaint = onPaint;
    this.width = 0;
    this.height = 0;
    this.zoom = 1;
    this.fitting = true;
    this.showMask = false;
    this.source = null;
    this.mask = null;
    this.maskImage = null;
    this.maskRgba = [127, 209, 199, 90];
    this.dirty = { base: null, overlay: null, strokes: null };
    this.frame = 0;

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

    this.geometry = null;
    this.element.addEventListener('pointerdown', () => this.measure(), { capture: true });
    this.resizer = new ResizeObserver(() => {
      if (this.fitting) this.applyZoom(this.fitZoom());
      this.geometry = null;
    });
    this.resizer.observe(container);
    // Scrolling moves the stack: measure again at the next pointer event.
    this.onScroll = () => { this.geometry = null; };
    addEventListener('scroll', this.onScroll, { capture: true, passive: true });
  }

  setImage(source, width, height) {
    const resized = width !== this.width || height !== this.height;
    this.source = source;
    this.width = width;
    this.height = height;
    if (resized) {
      for (const c of [this.base, this.overlay]) { c.width = width; c.height = height; }
      this.maskImage = null;
      this.applyZoom(this.fitting ? this.fitZoom() : this.zoom, true);
    }
    this.invalidate(null, 'base');
  }

  setMask(mask, rgba = this.maskRgba) {
    this.mask = mask;
    this.maskRgba = rgba;
    this.maskImage = null;
    this.invalidate(null, 'overlay');
  }

  maskChanged(rect) {
    this.invalidate(rect, 'overlay');
  }

  setZoom(z) {
    this.fitting = z === 'fit';
    this.applyZoom(this.fitting ? this.fitZoom() : z);
  }

  /** The zoom that shows the whole image inside the container. */
  fitZoom() {
    if (!this.width || !this.height) return 1;
    // Width: the container's. Height: what is left of the window below the
    // container's top (less `reserve` px for what follows it), so the whole
    // image is visible without scrolling.
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
    const w = Math.round(this.width * zoom), h = Math.round(this.height * zoom);
    this.element.style.width = `${w}px`;
    this.element.style.height = `${h}px`;
    // Stroke layer: screen resolution, capped.
    const dpr = Math.min(2, globalThis.devicePixelRatio || 1);
    const s = Math.min(dpr, MAX_STROKE_SIDE / Math.max(1, w), MAX_STROKE_SIDE / Math.max(1, h));
    this.strokeScale = zoom * s;
    this.strokes.width = Math.max(1, Math.round(this.width * this.strokeScale));
    this.strokes.height = Math.max(1, Math.round(this.height * this.strokeScale));
    this.geometry = null;
    this.element.dispatchEvent(new CustomEvent('zoom', { detail: { zoom } }));
    this.invalidate(null, 'strokes');
  }

  /** Cache the stack's position (done at pointerdown and after resizes, never on pointermove). */
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
    for (const name of layer ? [layer] : ['base', 'overlay', 'strokes']) {
      this.dirty[name] = union(this.dirty[name], r);
    }
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
    if (strokes && this.onPaint) {
      const ctx = this.strokeCtx;
      const s = this.strokeScale;
      // One image pixel of margin: strokes are wider than the pixels they cross.
      const px = Math.max(0, Math.floor(strokes.x - 1) * s), py = Math.max(0, Math.floor(strokes.y - 1) * s);
      ctx.setTransform(1, 0, 0, 1, 0, 0);
      ctx.save();
      ctx.beginPath();
      ctx.rect(px, py, Math.ceil((strokes.w + 2) * s), Math.ceil((strokes.h + 2) * s));
      ctx.clip();
      ctx.clearRect(px, py, Math.ceil((strokes.w + 2) * s), Math.ceil((strokes.h + 2) * s));
      ctx.setTransform(s, 0, 0, s, 0, 0);
      this.onPaint(ctx, this.zoom, strokes);
      ctx.restore();
    }
  }

  paintOverlay({ x, y, w, h }) {
    const m = this.mask;
    if (!m || !this.showMask || m.width !== this.width || m.height !== this.height) {
      this.overlayCtx.clearRect(x, y, w, h);
      return;
    }
    if (!this.maskImage) {
      this.maskImage = new ImageData(this.width, this.height);
      ({ x, y, w, h } = { x: 0, y: 0, w: this.width, h: this.height });
    }
    const data = this.maskImage.data;
    const [r, g, b, a] = this.maskRgba;
    for (let j = y; j < y + h; j++) {
      let k = j * this.width + x;
      for (let i = 0; i < w; i++, k++) {
        const o = 4 * k;
        if (m.bits[k]) { data[o] = r; data[o + 1] = g; data[o + 2] = b; data[o + 3] = a; } else data[o + 3] = 0;
      }
    }
    this.overlayCtx.putImageData(this.maskImage, 0, 0, x, y, w, h);
  }

  destroy() {
    cancelAnimationFrame(this.frame);
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
