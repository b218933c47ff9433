// Files out: the retrieved texture as a PNG (tiled as shown) and as JSON
// (model, parameters, seed, the requested and retrieved scales).
import { download } from '../ui/download.js';
import { pngOf } from './pictures.js';
import { SCALES, keyOf } from './state.js';
import { drawTiled } from './view.js';

/** Export PNG and Export JSON of a mounted panel (`view`: view.js; `live`: state.js). */
export function attachExport(ctx, { q, live, view, status }) {
  const state = () => ctx.state();

  q('[data-act=export-png]').onclick = async () => {
    const r = state()?.retrieved;
    if (!r) { ctx.error(new Error('there is no retrieved texture to export yet')); return; }
    try {
      await view.renderRetrieved(r);
      if (live.shown?.key !== keyOf(r)) return;
      const c = document.createElement('canvas');
      drawTiled(c, live.shown.image, view.tile());
      download(`texture-${r.model}-${r.seed}.png`, new Blob([await pngOf(c)], { type: 'image/png' }));
      status(`exported PNG: ${c.width}×${c.height}`);
    } catch (err) {
      if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Export PNG' });
    }
  };

  q('[data-act=export-json]').onclick = () => {
    const doc = state();
    const r = doc?.retrieved;
    if (!r) { ctx.error(new Error('there is no retrieved texture to export yet')); return; }
    const m = live.list.find((x) => x.id === r.model);
    const json = {
      model: r.model,
      model_name: m?.name ?? r.model,
      params: Object.fromEntries((m?.params ?? []).map((p, i) => [p.name, r.params[i]])),
      seed: r.seed,
      scales: Object.fromEntries(SCALES.map((n, i) => [n, doc.scales[i]])),
      retrieved_scales: r.scales ? Object.fromEntries(SCALES.map((n, i) => [n, r.scales[i]])) : null,
      cosine: r.cosine,
      edited: r.edited,
      note: 'scales are computational estimates, not human ratings',
    };
    download(`texture-${r.model}-${r.seed}.json`, new Blob([JSON.stringify(json, null, 2)], { type: 'application/json' }));
  };
}
