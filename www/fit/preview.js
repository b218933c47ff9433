// The overlay: the pattern of the document's values (or, while a fit runs,
// of its best values so far) drawn over the target, so it cannot pass for
// it: `render-pattern` at most every PREVIEW_EVERY_MS, the last one asked
// for winning.
import { putRgba } from '../ui/file-input.js';
import { named, rgbOf } from './program.js';
import { sizeOf } from './state.js';

const PREVIEW_EVERY_MS = 250;

// Its shapes' outlines in a colour of no program's palette, their fill faint.
const OUTLINE = [255, 43, 214];
const FILL_ALPHA = 80;
/** In place: `rgba` (w × h) with background `bg` transparent, shapes outlined. */
export function overlayLook(rgba, w, h, [br, bg, bb]) {
  const on = new Uint8Array(w * h);
  for (let i = 0, k = 0; k < on.length; i += 4, k++) on[k] = rgba[i] === br && rgba[i + 1] === bg && rgba[i + 2] === bb ? 0 : 1;
  for (let y = 0; y < h; y++) {
    for (let x = 0; x < w; x++) {
      const k = y * w + x, i = 4 * k;
      if (!on[k]) { rgba[i + 3] = 0; continue; }
      const edge = x === 0 || y === 0 || x === w - 1 || y === h - 1 || !on[k - 1] || !on[k + 1] || !on[k - w] || !on[k + w];
      if (edge) { rgba[i] = OUTLINE[0]; rgba[i + 1] = OUTLINE[1]; rgba[i + 2] = OUTLINE[2]; rgba[i + 3] = 255; } else rgba[i + 3] = FILL_ALPHA;
    }
  }
}

/** The overlay of the panel (`live`: state.js): `show(values)` draws `values` of the document's program. */
export function createPreview(ctx, { q, live }) {
  const overlay = q('canvas.overlay');
  const doc = () => ctx.state();
  let busy = false;
  let wanted = null;
  let lastAt = 0;

  function show(values) {
    wanted = values;
    if (busy || !live.info) return;
    const wait = Math.max(0, PREVIEW_EVERY_MS - (performance.now() - lastAt));
    busy = true;
    ctx.setTimeout(async () => {
      const vals = wanted;
      wanted = null;
      lastAt = performance.now();
      try {
        if (vals.length !== live.info.params.length) return;
        // On the target's canvas, at its size: the overlay is not stretched.
        const r = await ctx.run('render-pattern', { program: doc().program, params: named(live.info, vals), ...sizeOf(doc().target) });
        // Only the shapes, outlined: background pixels become transparent, so
        // the target shows through wherever the pattern has nothing.
        overlayLook(r.rgba, r.width, r.height, rgbOf(live.info.colours[0]));
        putRgba(overlay, r.width, r.height, r.rgba);
        overlay.dataset.values = JSON.stringify(vals);
      } catch (err) {
        ctx.error(err);
      } finally {
        busy = false;
        if (wanted) show(wanted);
      }
    }, wait);
  }

  overlay.style.opacity = q('[name=overlay]').value;
  q('[name=overlay]').oninput = (e) => { overlay.style.opacity = e.target.value; };
  return { show };
}
