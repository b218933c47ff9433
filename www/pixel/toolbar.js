// Pixel's toolbar and layer toggles: the examples, the brush (strokes, paint
// or erase the mask, and its size), zoom (buttons and ctrl+wheel), Clear
// strokes, and which layers show. View settings only (`live.view`), except
// an example and Clear strokes, which commit.
import { radioGroup } from '../ui/radio-group.js';

/** Wire the toolbar of `el`; returns {setMode(mode), detach()}. */
export function attachToolbar(ctx, { el, q, live, picture, loadExample }) {
  const state = () => ctx.state();
  const { view } = live;
  const { canvas } = picture;

  el.querySelectorAll('[data-example]').forEach((b) => { b.onclick = () => loadExample(b.dataset.example); });
  const setMode = (mode) => {
    view.mode = mode;
    el.querySelectorAll('[data-mode]').forEach((x) => x.setAttribute('aria-checked', String(x.dataset.mode === mode)));
    picture.drawMaskFull();
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
    if (!e.ctrlKey || !live.sourceImg) return;
    e.preventDefault();
    zoomBy(e.deltaY < 0 ? 1 : -1);
  }, { passive: false });
  q('[data-act=clear-strokes]').onclick = () => state()?.strokes.length && ctx.commit({ ...state(), strokes: [] });
  const toggles = { 'show-result': 'showResult', 'show-mask': 'showMask', 'show-strokes': 'showStrokes', 'show-arrows': 'showArrows' };
  for (const [name, key] of Object.entries(toggles)) {
    q(`[name=${name}]`).onchange = (e) => {
      view[key] = e.target.checked;
      if (key === 'showResult') picture.drawBase();
      else if (key === 'showMask') picture.drawMaskFull();
      else picture.drawStrokes();
    };
  }

  return { setMode, detach: detachRadios };
}
