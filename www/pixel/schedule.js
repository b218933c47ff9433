// When the core textures the document: a change runs it shortly after (a
// drag sends one request a pause, not one a move), a newer run cancels the
// one before, and the last good result stays on screen until the next one.
const RUN_DELAY_MS = 120;

/**
 * The runs of a mounted panel: `live` (state.js) takes each result,
 * `picture` (picture.js) shows it; returns {schedule(), pending(), abort()}.
 */
export function createRunner(ctx, { q, live, picture, statusEl, status }) {
  const state = () => ctx.state();
  let running = null; // AbortController of the job in flight
  let runTimer = null;

  function scheduleRun() {
    ctx.clearTimeout(runTimer);
    runTimer = ctx.setTimeout(() => { runTimer = null; run(); }, RUN_DELAY_MS);
  }

  async function run() {
    const doc = state();
    if (!doc || !(doc.sheet || doc.sprite)) return;
    running?.abort();
    const ctrl = new AbortController();
    running = ctrl;
    status('texturing…');
    // The figures on screen belong to the previous run: clear them while this one works.
    q('.stats').replaceChildren();
    const t0 = performance.now();
    try {
      const r = await ctx.run('pixel', {
        source: doc.source.slice(), sheet: doc.sheet?.slice(), sprite: doc.sprite?.slice(),
        mask: { width: doc.mask.width, height: doc.mask.height, bits: doc.mask.bits.slice() },
        strokes: doc.strokes, params: doc.params,
      }, {
        signal: ctrl.signal,
        onProgress: (p) => {
          if (running !== ctrl) return;
          const pct = Number.isFinite(p.fraction) ? ` ${Math.round(p.fraction * 100)}%` : '';
          status(`texturing: ${p.stage}${pct}`);
        },
      });
      if (running !== ctrl) return;
      const bitmap = await ctx.bitmap(new ImageData(new Uint8ClampedArray(r.rgba), r.width, r.height));
      if (running !== ctrl) { ctx.release(bitmap); return; }
      live.result = r;
      live.resultFor = doc.source;
      ctx.release(live.resultBitmap);
      live.resultBitmap = bitmap;
      ctx.clearError('run');
      status(`done in ${Math.round(performance.now() - t0)} ms`);
      showStats(r);
      picture.drawBase();
      picture.drawStrokes();
      // Counts finished runs, so a test (or a person) can tell two results apart.
      statusEl.dataset.runs = String(Number(statusEl.dataset.runs || 0) + 1);
    } catch (err) {
      if (err.kind === 'cancelled') return;
      // Keep the last good result on screen; say what is wrong now.
      ctx.error(err, { source: 'run' });
      status('');
    } finally {
      if (running === ctrl) running = null;
    }
  }

  function showStats(r) {
    const rows = [
      ['Elements placed', r.placed], ['Colours before', r.colours_before], ['Colours after', r.colours_after],
      ['Colour map', r.colour_map_used],
    ];
    q('.stats').replaceChildren(...rows.flatMap(([k, v]) => {
      const dt = document.createElement('dt'); dt.textContent = k;
      const dd = document.createElement('dd'); dd.textContent = String(v); dd.dataset.stat = k;
      return [dt, dd];
    }));
  }

  return {
    schedule: scheduleRun,
    /** Whether a run is due or going. */
    pending: () => runTimer !== null || running !== null,
    abort: () => running?.abort(),
  };
}
