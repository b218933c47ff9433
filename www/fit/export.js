// Files out: the pattern of the document's values as SVG (twice the
// target's size, on its canvas), and the values with their program as JSON.
import { download } from '../ui/download.js';
import { named } from './program.js';
import { sizeOf } from './state.js';

/** Export SVG / Export JSON (`live`: state.js). */
export function attachExport(ctx, { q, live }) {
  const doc = () => ctx.state();
  const baseName = () => doc()?.generator || 'pattern';
  q('[data-act=export-svg]').onclick = async () => {
    try {
      // 512 px along the longer side.
      const r = await ctx.run('render-pattern', { program: doc().program, params: named(live.info, doc().values), ...sizeOf(doc().target, 2) });
      download(`${baseName()}.svg`, r.svg, 'image/svg+xml');
    } catch (err) {
      ctx.error(err);
    }
  };
  q('[data-act=export-json]').onclick = () => {
    const d = doc();
    const params = Object.fromEntries(live.info.params.map((p, i) => [p.name, d.values[i]]));
    // The program travels with its values: the file alone re-renders the pattern (`filigree render`).
    download(`${baseName()}-params.json`, JSON.stringify({ generator: d.generator, program: d.program, params, loss: d.result?.loss ?? null }, null, 2), 'application/json');
  };
}
