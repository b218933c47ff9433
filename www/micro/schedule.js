// When the CPU draws Micro's document: a change runs it shortly after, a
// drag runs a small preview now and the full picture once it pauses, and a
// new run cancels the one before. A slice or a preview is one job; the
// full render is rendered in tiles over the worker pool (tiles.js), each
// drawn as it arrives. The GPU view (gpu-view.js) draws instead when it can.
import { DEFAULT_CAMERA, requestOf } from './state.js';
import { PREVIEW_DIV } from './picture.js';
import { tilesOf, passesOf, addStats, createTileReader, addRadiance, putTile } from './tiles.js';

const RUN_DELAY_MS = 60;
const SHARP_DELAY_MS = 200;

/**
 * The CPU runs of a mounted panel: the picture goes to `live` (state.js)
 * and `picture` (picture.js); `gpu` (gpu-view.js) stops when they start.
 */
export function createRunner(ctx, { live, picture, gpu, editor, statusEl, status }) {
  const state = () => ctx.state();
  let running = null; // the AbortController of the request in flight
  let runTimer = null;
  let sharpTimer = null;
  const pngPixels = createTileReader();
  const comp = document.createElement('canvas'); // the full tiled picture, tile by tile
  const compG = comp.getContext('2d', { willReadFrequently: true });

  function scheduleRun() {
    ctx.clearTimeout(runTimer);
    runTimer = ctx.setTimeout(() => { runTimer = null; run(false); }, RUN_DELAY_MS);
  }

  /** During a gesture: a small image now, the full one once it pauses. */
  function preview() {
    run(true);
    ctx.clearTimeout(sharpTimer);
    sharpTimer = ctx.setTimeout(() => { sharpTimer = null; run(false); }, SHARP_DELAY_MS);
  }

  const renderStatus = (doc, r, extra, ms) => {
    const s = r.stats;
    return `${r.width}×${r.height}${extra}, ${doc.steps} steps: ${s.hits.toLocaleString('en')} of ${s.rays.toLocaleString('en')} rays hit, `
      + `${s.steps.toLocaleString('en')} steps, ${s.sdf_evals.toLocaleString('en')} field evaluations`
      + `${s.gradient_checks ? `, ${s.gradient_checks.toLocaleString('en')} gradient checks` : ''}`
      + `${s.exhausted ? `, ${s.exhausted.toLocaleString('en')} rays out of steps` : ''} in ${Math.round(ms)} ms — zoom ×${(DEFAULT_CAMERA.distance / doc.camera.distance).toPrecision(3)}`;
  };

  async function run(small) {
    const doc = state();
    if (!doc) return;
    ctx.clearTimeout(runTimer);
    runTimer = null;
    if (!small) { ctx.clearTimeout(sharpTimer); sharpTimer = null; }
    gpu.stop();
    running?.abort();
    const ctrl = new AbortController();
    running = ctrl;
    const full = picture.fullSide();
    const side = small ? Math.max(8, Math.round(full / PREVIEW_DIV)) : full;
    const [kind, payload] = requestOf(doc, side);
    gpu.noteCpu(doc);
    // A preview while dragging: one sample per pixel when path tracing.
    if (small && payload.spp > 1) payload.spp = 1;
    if (!small && kind === 'micro-render') return runTiles(doc, payload, ctrl);
    if (!small) status(kind === 'micro-slice' ? 'slicing…' : 'tracing…');
    const t0 = performance.now();
    try {
      const r = await ctx.run(kind, payload, {
        signal: ctrl.signal,
        onProgress: (p) => {
          if (running !== ctrl || small) return;
          status(`${p.stage || 'working'}: ${Math.round((p.fraction ?? 0) * 100)}%`);
        },
      });
      if (running !== ctrl) return;
      const ms = performance.now() - t0;
      const png = r.png instanceof Uint8Array ? r.png : new Uint8Array(r.png);
      const bmp = await createImageBitmap(new Blob([png], { type: 'image/png' }));
      if (running !== ctrl || !ctx.alive()) { bmp.close?.(); return; }
      if (live.bitmap !== comp) live.bitmap?.close?.();
      live.bitmap = bmp;
      live.last = { png, width: r.width, height: r.height, kind, preview: small, stats: r.stats, r, gpu: false };
      picture.paint();
      ctx.clearError('run');
      editor.clearError();
      const size = `${r.width}×${r.height}`;
      if (kind === 'micro-slice') {
        status(`slice z = ${doc.z}: ${size}, field from ${r.min.toPrecision(3)} to ${r.max.toPrecision(3)}, ${(r.inside * 100).toFixed(1)}% inside${small ? ' (preview)' : ''} in ${Math.round(ms)} ms`);
      } else {
        status(renderStatus(doc, r, small ? ' (preview)' : '', ms));
      }
      if (!small) statusEl.dataset.runs = String(Number(statusEl.dataset.runs || 0) + 1);
      statusEl.dataset.previews = String(Number(statusEl.dataset.previews || 0) + (small ? 1 : 0));
    } catch (err) {
      if (running !== ctrl) return;
      if (err?.kind === 'cancelled') { status('cancelled'); return; }
      status(kind === 'micro-slice' ? 'the slice failed (see above)' : 'the scene could not be rendered (see above)');
      ctx.error(err, { prefix: 'Micro', source: 'run' }); // marks the editor (markError)
    } finally {
      if (running === ctrl) running = null;
    }
  }

  /**
   * The full picture as TILE_GRID² `micro-render` jobs over the pool, each
   * tile painted as it arrives; path tracing in progressive passes whose
   * summed radiance is added up here and shown averaged.
   */
  async function runTiles(doc, payload, ctrl) {
    const side = payload.width;
    const tiles = tilesOf(side);
    const spp = payload.spp;
    const passes = spp > 0 ? passesOf(spp) : [[0, 0]];
    const frame = new ImageData(side, side);
    const acc = spp > 0 ? new Float64Array(side * side * 3) : null;
    // Keep what is shown until the tiles replace it (a scene the core refuses
    // replaces nothing: the last good picture stays, the error says why).
    const resized = comp.width !== side || comp.height !== side;
    if (live.bitmap && live.bitmap !== comp) { if (resized) { comp.width = side; comp.height = side; } compG.imageSmoothingEnabled = true; compG.drawImage(live.bitmap, 0, 0, side, side); live.bitmap.close?.(); } else if (!live.bitmap || resized) {
      // The GPU drew straight on the canvas (or the size changed): start from what it shows.
      const shownNow = document.createElement('canvas');
      shownNow.width = picture.canvas.width;
      shownNow.height = picture.canvas.height;
      shownNow.getContext('2d').drawImage(picture.canvas, 0, 0);
      comp.width = side;
      comp.height = side;
      compG.imageSmoothingEnabled = true;
      compG.drawImage(shownNow, 0, 0, side, side);
    }
    live.bitmap = comp;
    const t0 = performance.now();
    let stats = null;
    let tilesDone = 0;
    statusEl.dataset.passes = '0';
    status(spp > 0 ? `path tracing on the CPU: pass 1 of ${passes.length}…` : `tracing ${tiles.length} tiles…`);
    try {
      for (let p = 0; p < passes.length; p++) {
        const [start, n] = passes[p];
        const total = start + n;
        await Promise.all(tiles.map(async (t) => {
          const r = await ctx.run('micro-render', { ...payload, tile: t, spp: n, sample_start: start, radiance: n > 0 }, { signal: ctrl.signal });
          if (running !== ctrl || !ctx.alive()) return;
          if (n > 0) {
            addRadiance(frame, acc, t, r.radiance instanceof Uint8Array ? r.radiance : new Uint8Array(r.radiance), side, total);
          } else {
            const png = r.png instanceof Uint8Array ? r.png : new Uint8Array(r.png);
            const px = await pngPixels(png, t.w, t.h);
            if (running !== ctrl || !ctx.alive()) return;
            putTile(frame, t, px, side);
          }
          compG.putImageData(frame, 0, 0, t.x, t.y, t.w, t.h);
          if (live.bitmap === comp) picture.paint();
          stats = addStats(stats, r.stats);
          tilesDone++;
          if (!spp) status(`tracing on the CPU: ${tilesDone} of ${tiles.length} tiles`);
        }));
        if (running !== ctrl || !ctx.alive()) return;
        statusEl.dataset.passes = String(p + 1);
        if (spp > 0 && p + 1 < passes.length) {
          status(`path tracing on the CPU: pass ${p + 1} of ${passes.length} done, ${total} of ${spp} samples per pixel…`);
        }
      }
      const ms = performance.now() - t0;
      live.last = { width: side, height: side, kind: 'micro-render', preview: false, stats, gpu: false, tiles: tiles.length, passes: passes.length, frame };
      ctx.clearError('run');
      editor.clearError();
      const extra = spp > 0 ? `, path traced on the CPU, ${spp} samples per pixel in ${passes.length} passes` : `, on the CPU in ${tiles.length} tiles`;
      status(renderStatus(doc, { width: side, height: side, stats }, extra, ms));
      statusEl.dataset.runs = String(Number(statusEl.dataset.runs || 0) + 1);
    } catch (err) {
      if (running !== ctrl) return;
      if (err?.kind === 'cancelled') { status('cancelled'); return; }
      status('the scene could not be rendered (see above)');
      ctx.error(err, { prefix: 'Micro', source: 'run' });
    } finally {
      if (running === ctrl) { running = null; ctrl.abort(); }
    }
  }

  return {
    schedule: scheduleRun,
    preview,
    run,
    /** A drag ended: the full picture now. */
    sharp() { ctx.clearTimeout(sharpTimer); sharpTimer = null; run(false); },
    /** Stop the run in flight and the one due (the GPU draws instead). */
    cancel() {
      running?.abort();
      running = null;
      ctx.clearTimeout(runTimer);
      runTimer = null;
    },
    /** Whether a run is due or going. */
    pending: () => runTimer !== null || running !== null || sharpTimer !== null,
    abort: () => running?.abort(),
  };
}
