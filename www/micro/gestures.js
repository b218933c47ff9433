// Orbit, pan and zoom of Micro's camera: drag the image to orbit,
// shift-drag (or the middle button) to pan, wheel or +/− to zoom (the
// camera distance multiplies, so one zoom path goes from the macro- to the
// microscale with nothing precomputed); arrow keys orbit, shift+arrows pan.
// Each gesture commits the camera (a drag one coalesced step).
import { DEFAULT_CAMERA, clamp, sameCamera } from './state.js';

const ZOOM_STEP = 1.5; // one + / − press multiplies the distance by this
const ORBIT_DEG_PER_PX = 0.4;
const CAMERA_FOV = 40; // the request's default vertical field of view (degrees)
const PAN_KEY_PX = 20; // one shift+arrow press pans this many pixels
const TARGET = [-1e6, 1e6]; // the request's range for camera.target
const DISTANCE = [1e-6, 1e5];

/**
 * The camera gestures of a mounted panel on `canvas` (`live.gesture`: the
 * drag under way; a drag's end asks `runner` for the full CPU picture
 * unless `gpu` draws it); returns {zoomIn(), zoomOut()}.
 */
export function attachGestures(ctx, { q, canvas, live, runner, gpu }) {
  const state = () => ctx.state();

  function setCamera(change, coalesce) {
    const doc = state();
    if (!doc) return;
    const c = doc.camera;
    const next = { ...c, ...change(c) };
    next.pitch = clamp(next.pitch, -89, 89);
    next.distance = clamp(next.distance, DISTANCE[0], DISTANCE[1]);
    next.yaw = ((next.yaw % 360) + 360) % 360;
    if (sameCamera(next, c)) return;
    ctx.commit({ ...doc, camera: next }, { coalesce });
  }

  const zoomBy = (f, coalesce = 'micro-zoom') => setCamera((c) => ({ distance: c.distance / f }), coalesce);

  /**
   * Pan: move the target by (dx, dy) screen pixels in the view plane, so the
   * picture follows the pointer (the orbit camera's right and up vectors, as
   * src/micro/render.rs builds them).
   */
  function panBy(dx, dy, coalesce) {
    setCamera((c) => {
      const [yaw, pitch] = [c.yaw * Math.PI / 180, c.pitch * Math.PI / 180];
      const dir = [Math.cos(pitch) * Math.cos(yaw), Math.cos(pitch) * Math.sin(yaw), Math.sin(pitch)];
      const fwd = dir.map((v) => -v);
      let right = [fwd[1], -fwd[0], 0]; // fwd × z
      const n = Math.hypot(right[0], right[1]);
      right = n < 1e-9 ? [1, 0, 0] : [right[0] / n, right[1] / n, 0];
      const up = [right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2], right[0] * fwd[1] - right[1] * fwd[0]];
      const perPx = (2 * c.distance * Math.tan((CAMERA_FOV * Math.PI) / 360)) / Math.max(1, canvas.clientHeight || canvas.height);
      const target = c.target.map((v, i) => clamp(v + (-dx * right[i] + dy * up[i]) * perPx, TARGET[0], TARGET[1]));
      return { target };
    }, coalesce);
  }

  canvas.addEventListener('pointerdown', (e) => {
    if (e.button !== 0 && e.button !== 1) return;
    if (e.button === 1) e.preventDefault();
    canvas.setPointerCapture?.(e.pointerId);
    live.gesture = { x: e.clientX, y: e.clientY, id: e.pointerId, pan: e.shiftKey || e.button === 1 };
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!live.gesture || e.pointerId !== live.gesture.id) return;
    const dx = e.clientX - live.gesture.x, dy = e.clientY - live.gesture.y;
    if (!dx && !dy) return;
    live.gesture.x = e.clientX;
    live.gesture.y = e.clientY;
    live.gesture.moved = true;
    if (live.gesture.pan) panBy(dx, dy, 'micro-pan');
    else setCamera((c) => ({ yaw: c.yaw - dx * ORBIT_DEG_PER_PX, pitch: c.pitch + dy * ORBIT_DEG_PER_PX }), 'micro-orbit');
  });
  const endGesture = (e) => {
    if (!live.gesture || e.pointerId !== live.gesture.id) return;
    const moved = live.gesture.moved;
    live.gesture = null;
    ctx.seal();
    if (moved && !(state() && gpu.onGpu(state()))) runner.sharp();
  };
  canvas.addEventListener('pointerup', endGesture);
  canvas.addEventListener('pointercancel', endGesture);
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const f = Math.exp(-clamp(e.deltaY, -300, 300) * 0.002);
    zoomBy(f, 'micro-wheel');
  }, { passive: false });
  canvas.addEventListener('keydown', (e) => {
    const orbit = { ArrowLeft: [-10, 0], ArrowRight: [10, 0], ArrowUp: [0, -10], ArrowDown: [0, 10] }[e.key];
    if (orbit && e.shiftKey) {
      e.preventDefault();
      panBy(-orbit[0] / 10 * PAN_KEY_PX, -orbit[1] / 10 * PAN_KEY_PX, 'micro-keys-pan');
    } else if (orbit) {
      e.preventDefault();
      setCamera((c) => ({ yaw: c.yaw - orbit[0] * ORBIT_DEG_PER_PX, pitch: c.pitch + orbit[1] * ORBIT_DEG_PER_PX }), 'micro-keys');
    } else if (e.key === '+' || e.key === '=') { e.preventDefault(); zoomBy(ZOOM_STEP); } else if (e.key === '-') { e.preventDefault(); zoomBy(1 / ZOOM_STEP); }
  });
  q('[data-act=zoom-in]').onclick = () => zoomBy(ZOOM_STEP, null);
  q('[data-act=zoom-out]').onclick = () => zoomBy(1 / ZOOM_STEP, null);
  q('[data-act=zoom-reset]').onclick = () => setCamera(() => ({ ...DEFAULT_CAMERA, target: [...DEFAULT_CAMERA.target] }), null);

  return { zoomIn: () => zoomBy(ZOOM_STEP, null), zoomOut: () => zoomBy(1 / ZOOM_STEP, null) };
}
