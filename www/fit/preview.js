// The overlay: the pattern of the document's values (or, while a fit runs,
// of its best values so far) drawn over the target, so it cannot pass for
// it. A fit's own pictures come with its answers (the `fit` request's
// `preview`: src/pattern/api.rs), so a fit runs no `render-pattern`; the
// document's values otherwise are drawn by `render-pattern`, at most every
// PREVIEW_EVERY_MS, the last one asked for winning.
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

/**
 * The overlay of the panel (`live`: state.js): `show(values)` draws the
 * document's values (from a picture it has, else by `render-pattern`, unless
 * a fit runs: the overlay is then the fit's), `showPicture(program, values,
 * picture)` draws a picture a fit answered.
 */
export function createPreview(ctx, { q, live }) {
  const overlay = q('canvas.overlay');
  const doc = () => ctx.state();
  let busy = false;
  let wanted = null;
  let lastAt = 0;
  let shown = null; // the key of what the overlay shows
  // The last picture of a document's values (`render-pattern`'s, or a fit's
  // answer), by key: drawn again when a stopped fit hands the overlay back.
  let kept = null;
  const keyOf = (program, values, t) => JSON.stringify([program, values, t?.width, t?.height]);

  function draw(key, values, pic) {
    // Only the shapes, outlined: background pixels become transparent, so
    // the target shows through wherever the pattern has nothing.
    const rgba = pic.rgba.slice();
    overlayLook(rgba, pic.width, pic.height, rgbOf(live.info.colours[0]));
    putRgba(overlay, pic.width, pic.height, rgba);
    overlay.dataset.values = JSON.stringify(values);
    shown = key;
  }

  /** Draw `picture` of `values` (all of them) of `program`, a fit's answer (a best so far, or the fitted values). */
  function showPicture(program, values, picture, { documentValues = false } = {}) {
    const d = doc();
    if (!ctx.alive() || !picture || program !== d?.program) return;
    const key = keyOf(program, values, d.target);
    if (documentValues) kept = { key, values, picture };
    if (live.info && key !== shown) draw(key, values, picture);
  }

  function show(values) {
    const { job } = live;
    if (job?.running) {
      // While a fit runs, the overlay is its best so far.
      if (job.best?.picture) showPicture(job.data.program, job.best.values, job.best.picture);
      return;
    }
    wanted = values;
    if (busy || !live.info) return;
    const d = doc();
    const key = keyOf(d.program, values, d.target);
    if (key === shown) { wanted = null; return; }
    if (kept?.key === key) { wanted = null; draw(key, values, kept.picture); return; }
    const wait = Math.max(0, PREVIEW_EVERY_MS - (performance.now() - lastAt));
    busy = true;
    ctx.setTimeout(async () => {
      const vals = wanted;
      wanted = null;
      lastAt = performance.now();
      try {
        if (!vals || vals.length !== live.info.params.length || live.job?.running) return;
        const cur = doc();
        // On the target's canvas, at its size: the overlay is not stretched.
        const r = await ctx.run('render-pattern', { program: cur.program, params: named(live.info, vals), ...sizeOf(cur.target) });
        const k = keyOf(cur.program, vals, cur.target);
        kept = { key: k, values: vals, picture: r };
        if (!live.job?.running) draw(k, vals, r);
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
  return { show, showPicture };
}
