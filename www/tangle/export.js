// Export: the core draws the document as SVG (pen-and-ink paths) or PNG at
// the chosen width, on the worker that keeps its expansion, and the page
// downloads it as `<example>-seed<seed>.svg|png`.
import { download } from '../ui/download.js';
import { requestOf, KEEP_AFFINITY } from './state.js';

/** The export buttons of a mounted panel (`q` finds its elements); returns `exportAs(format)`. */
export function createExport(ctx, { q, status }) {
  const state = () => ctx.state();

  /** The core's answer with `format` ('svg' | 'png') of the document, or null (said in status/errors). */
  async function exportAs(format) {
    const doc = state();
    if (!doc) return null;
    const pngWidth = Number(q('[name=png-width]').value) || 1600;
    status(`exporting ${format.toUpperCase()}…`);
    try {
      const r = await ctx.run('tangle', { ...requestOf(doc), export: format, png_width: pngWidth, keep: true },
        { affinity: KEEP_AFFINITY });
      status(`exported ${format.toUpperCase()}: ${r.stats.shapes.toLocaleString('en')} shapes`);
      return r;
    } catch (err) {
      ctx.error(err, { prefix: `Export ${format.toUpperCase()}` });
      status('');
      return null;
    }
  }
  const base = () => state()?.example || 'tangle';
  q('[data-act=export-svg]').onclick = async () => {
    const r = await exportAs('svg');
    if (r) download(`${base()}-seed${state().seed}.svg`, new Blob([r.svg], { type: 'image/svg+xml' }));
  };
  q('[data-act=export-png]').onclick = async () => {
    const r = await exportAs('png');
    if (r) download(`${base()}-seed${state().seed}.png`, new Blob([r.png], { type: 'image/png' }));
  };

  return exportAs;
}
