// Export: the core draws the document as SVG (pen-and-ink paths) on the
// worker that keeps its expansion; a PNG is drawn by the small `tangle-png`
// module (fetched on the first PNG export, so opening Tangle never loads a
// rasteriser): the page sends it the final shapes of the document's answer.
// The page downloads the file as `<example>-seed<seed>.svg|png`.
import { download } from '../ui/download.js';
import { requestOf, KEEP_AFFINITY } from './state.js';
import { shapeColumns, pointsOf } from './draw.js';

/**
 * The final shapes (`died` −1) of a full `tangle` answer as a `tangle-png`
 * request's drawing (src/tangle/api.rs `TanglePngRequest`): points, ring
 * lengths, rings per shape, fills and flags, each a Uint8Array of its
 * little-endian values.
 */
export function drawingOf(r) {
  const S = shapeColumns(r.shapes), pts = pointsOf(r.points);
  const finals = [];
  let nRings = 0, nPts = 0;
  for (let i = 0; i < S.count; i++) {
    if (S.died[i] !== -1) continue;
    finals.push(i);
    for (let q = S.ringFirst[i]; q < S.ringFirst[i + 1]; q++) { nRings++; nPts += S.rings[q]; }
  }
  const shapes = new Uint32Array(finals.length), fill = new Float32Array(finals.length);
  const flags = new Uint8Array(finals.length), rings = new Uint32Array(nRings), points = new Float32Array(2 * nPts);
  let ring = 0, at = 0;
  finals.forEach((i, k) => {
    shapes[k] = S.ringFirst[i + 1] - S.ringFirst[i];
    fill[k] = S.fill[i];
    flags[k] = S.flags[i];
    let len = 0;
    for (let q = S.ringFirst[i]; q < S.ringFirst[i + 1]; q++) { rings[ring++] = S.rings[q]; len += S.rings[q]; }
    points.set(pts.subarray(2 * S.first[i], 2 * (S.first[i] + len)), at);
    at += 2 * len;
  });
  const bytes = (a) => new Uint8Array(a.buffer, a.byteOffset, a.byteLength);
  return { points: bytes(points), rings: bytes(rings), shapes: bytes(shapes), fill: bytes(fill), flags };
}

/** The export buttons of a mounted panel (`q` finds its elements); returns `exportAs(format)`. */
export function createExport(ctx, { q, status }) {
  const state = () => ctx.state();

  /**
   * The document exported as `format` ('svg' | 'png'): `{svg}` or `{png}`
   * with the answer's `stats`, or null (said in status/errors).
   */
  async function exportAs(format) {
    const doc = state();
    if (!doc) return null;
    const pngWidth = Number(q('[name=png-width]').value) || 1600;
    const name = format.toUpperCase();
    status(`exporting ${name}…`);
    try {
      const req = { ...requestOf(doc), export: format === 'svg' ? 'svg' : 'none', keep: true };
      const r = await ctx.run('tangle', req, { affinity: KEEP_AFFINITY });
      const out = format === 'svg' ? { svg: r.svg, stats: r.stats } : {
        png: (await ctx.run('tangle-png', { ...drawingOf(r), stroke_width: req.stroke_width, png_width: pngWidth })).png,
        stats: r.stats,
      };
      status(`exported ${name}: ${r.stats.shapes.toLocaleString('en')} shapes`);
      return out;
    } catch (err) {
      ctx.error(err, { prefix: `Export ${name}` });
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
