// Files out: the full-size picture of the document as a PNG, and the scene
// JSON.
import { download } from '../ui/download.js';
import { requestOf } from './state.js';
import { FULL_SIDE } from './picture.js';

/** Export PNG and Export scene JSON of a mounted panel. */
export function attachExport(ctx, { q, status }) {
  const state = () => ctx.state();

  q('[data-act=export-png]').onclick = async () => {
    const doc = state();
    if (!doc) return;
    try {
      // Always the full-size picture of the current document.
      // (Path tracing at the panel's size: samples × pixels are bounded.)
      const side = doc.view === 'render' && doc.spp > 0 ? FULL_SIDE : FULL_SIDE * 2;
      const [kind, payload] = requestOf(doc, side);
      status('exporting PNG…');
      const r = await ctx.run(kind, payload);
      download(`${doc.example || 'micro'}-${doc.view}.png`, new Blob([r.png], { type: 'image/png' }));
      status(`exported PNG: ${r.width}×${r.height}`);
    } catch (err) {
      if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Export PNG' });
    }
  };

  q('[data-act=export-json]').onclick = () => {
    const doc = state();
    if (!doc) return;
    download(`${doc.example || 'micro'}.json`, doc.scene, 'application/json');
    status('exported the scene JSON');
  };
}
