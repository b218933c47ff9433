// Pointer input on Pixel's picture: a drag draws an orientation stroke or
// paints (erases) the mask with the brush, each drag one undoable step.

/** Strokes and mask painting on the picture (`picture`: picture.js; `live`: state.js). */
export function attachGestures(ctx, { live, picture }) {
  const state = () => ctx.state();
  const { canvas, stack } = picture;

  // Image coordinates of a pointer event, kept inside the image (a drag may leave the canvas).
  const clamp = (v, hi) => Math.max(0, Math.min(hi, v));
  const toPixel = (e) => {
    const [x, y] = canvas.toImage(e);
    return [clamp(x, live.sourceImg.width), clamp(y, live.sourceImg.height)];
  };

  function paintAt([fx, fy], on) {
    const m = live.drawing.mask;
    const r = live.view.brush / 2;
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
    if (!state() || !live.sourceImg || e.button > 0 || ctx.readOnly) return;
    stack.setPointerCapture(e.pointerId);
    const p = toPixel(e);
    if (live.view.mode === 'stroke') {
      live.drawing = { kind: 'stroke', points: [p] };
    } else {
      const m = state().mask;
      live.drawing = { kind: 'mask', mask: { width: m.width, height: m.height, bits: m.bits.slice() } };
      canvas.setMask(live.drawing.mask);
      paintAt(p, live.view.mode === 'paint');
    }
  });

  stack.addEventListener('pointermove', (e) => {
    if (!live.drawing) return;
    const events = e.getCoalescedEvents?.().length ? e.getCoalescedEvents() : [e];
    for (const ev of events) {
      const p = toPixel(ev);
      if (live.drawing.kind === 'stroke') {
        const last = live.drawing.points[live.drawing.points.length - 1];
        if (Math.hypot(p[0] - last[0], p[1] - last[1]) < 0.25) continue;
        live.drawing.points.push(p);
        // Repaint only around the new segment (the layer adds its own margin for the line width).
        const x = Math.min(last[0], p[0]), y = Math.min(last[1], p[1]);
        canvas.invalidate({ x, y, w: Math.abs(p[0] - last[0]), h: Math.abs(p[1] - last[1]) }, 'strokes');
      } else {
        paintAt(p, live.view.mode === 'paint');
      }
    }
  });

  const endDrawing = () => {
    if (!live.drawing) return;
    const d = live.drawing;
    live.drawing = null;
    if (d.kind === 'stroke') {
      if (d.points.length >= 2) {
        const pts = d.points.map(([x, y]) => [Math.round(x * 100) / 100, Math.round(y * 100) / 100]);
        ctx.commit({ ...state(), strokes: [...state().strokes, pts] });
      } else picture.drawStrokes();
    } else {
      // The whole brush drag is one undo step.
      ctx.commit({ ...state(), mask: d.mask });
    }
  };
  stack.addEventListener('pointerup', endDrawing);
  stack.addEventListener('pointercancel', endDrawing);
}
