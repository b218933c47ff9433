// Files out: the result as a PNG, scaled up by whole pixels.
import { download } from '../ui/download.js';

/** Export PNG (the button in the side panel) of the shown result (`live`: state.js). */
export function attachExport(ctx, { q, live }) {
  const state = () => ctx.state();
  q('[data-act=export-png]').onclick = async () => {
    const { result, resultBitmap } = live;
    if (!result) { ctx.error(new Error('nothing to export yet: load an example or a source and an element sheet')); return; }
    const s = Number(q('[name=export-scale]').value);
    const c = document.createElement('canvas');
    c.width = result.width * s;
    c.height = result.height * s;
    const x = c.getContext('2d');
    x.imageSmoothingEnabled = false;
    x.drawImage(resultBitmap, 0, 0, c.width, c.height);
    const blob = await new Promise((r) => c.toBlob(r, 'image/png'));
    const base = (state().names?.source || 'pixel').replace(/\.[^.]+$/, '');
    download(`${base}-textured${s > 1 ? `@${s}x` : ''}.png`, blob);
  };
}
