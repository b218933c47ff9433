// Pointer gestures on the Tangle canvas: a drag pans, two fingers pinch to
// zoom, the wheel zooms at the pointer, and a press that does not move is a
// click (`onTap`: pick a shape, or add a point to the polyline being drawn).
// Every move of the view paints quickly (canvas.js quickPaint).

/**
 * The gestures on `painter`'s canvas (canvas.js); `onTap(x, y)` gets a
 * click in CSS px from the canvas's corner. Returns `zoomAt(cx, cy, f)`,
 * which scales the view by f about a point, and `zoomCentre(f)`.
 */
export function attachGestures(painter, { onTap }) {
  const { canvas, viewport, view } = painter;
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
    painter.quickPaint();
  });
  const up = (e) => {
    if (!pointers.has(e.pointerId)) return;
    pointers.delete(e.pointerId);
    const gst = gesture;
    if (pointers.size) return;
    gesture = null;
    if (!gst || gst.moved || e.type === 'pointercancel') return;
    const [x, y] = local(e);
    onTap(x, y);
  };
  canvas.addEventListener('pointerup', up);
  canvas.addEventListener('pointercancel', up);
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const [x, y] = local(e);
    zoomAt(x, y, Math.exp(-e.deltaY * (e.deltaMode === 1 ? 0.05 : 0.0015)));
  }, { passive: false });

  function zoomAt(cx, cy, f) {
    const s = Math.max(1e-4, Math.min(1e4, view.s * f));
    const [wx, wy] = painter.toWorld(cx, cy);
    view.s = s;
    view.tx = cx - wx * s;
    view.ty = cy - wy * s;
    painter.quickPaint();
  }
  const zoomCentre = (f) => zoomAt(viewport.clientWidth / 2, viewport.clientHeight / 2, f);

  return { zoomAt, zoomCentre };
}
