// The Micro tool's "Reconstruct" section (issue 12 item 3, paper §6):
// pick numbers of the scene to fit, give a target — the current scene with
// other values (a synthetic exemplar) or an uploaded slice image — and the
// core fits them with the Fourier loss (`micro-fit`), sharded over the
// worker pool exactly as one fit (src/micro/fit_api.rs). The loss falls on
// a live plot; "Apply" puts the fitted values into the scene as one
// undoable change of the document.
//
// A reconstruction is a job of the document (ctx.startJob, issue 35 item
// 4): it runs on when the user opens another tool, the tool bar shows its
// progress, and this section shows it again on coming back, with the form
// as the user left it (ctx.memory: ticks, targets, ranges, settings, open).
// Stop keeps the best values so far for "Apply fitted values".
//
// mountReconstruct(el, ctx) → {render(doc), unmount()}; el is an empty
// element inside the Micro panel. The request's defaults come from the
// core (`defaults` for `micro-fit`), never from here. Its markup is
// fit-layout.js; the scene's numbers (JSON pointers, ranges) scene-numbers.js.
import { LossPlot } from '../ui/loss-plot.js';
import { coreDefaults } from '../app/core-state.js';
import { html } from './fit-layout.js';
import { numbersOf, setPointer, rangeOf } from './scene-numbers.js';

const OPTIMIZERS = [['cmaes', 'CMA-ES'], ['nelder-mead', 'Nelder–Mead'], ['powell', 'Powell']];

/** An image file scaled to side×side grey, as PNG bytes. */
async function slicePng(file, side) {
  const bmp = await createImageBitmap(file);
  try {
    const c = new OffscreenCanvas(side, side);
    const g = c.getContext('2d');
    g.drawImage(bmp, 0, 0, side, side);
    const blob = await c.convertToBlob({ type: 'image/png' });
    return new Uint8Array(await blob.arrayBuffer());
  } finally {
    bmp.close?.();
  }
}

export function mountReconstruct(el, ctx) {
  el.innerHTML = html;
  const q = (s) => el.querySelector(s);
  const statusEl = q('[data-testid=micro-fit-status]');
  const status = (t) => { statusEl.textContent = t; };
  // The loss is a log MSE (it may be negative): a linear axis of the very numbers the status shows.
  const plot = new LossPlot(q('[data-testid=micro-fit-plot]'), { log: false, format: (v) => v.toFixed(3) });
  const paramsEl = q('[data-testid=micro-fit-params]');
  const optSel = q('[name=fit-optimizer]');
  for (const [v, label] of OPTIMIZERS) {
    const o = document.createElement('option');
    o.value = v;
    o.textContent = label;
    optSel.append(o);
  }
  const budgetIn = q('[name=fit-budget]');
  const gridSel = q('[name=fit-grid]');
  const c2fIn = q('[name=fit-c2f]');
  const fileIn = q('[name=fit-slice]');
  const runBtn = q('[data-act=fit-run]');
  const stopBtn = q('[data-act=fit-stop]');
  const applyBtn = q('[data-act=fit-apply]');

  let defaults = null;
  coreDefaults(ctx.pool, 'micro-fit').then((d) => {
    defaults = d;
    if (!ctx.alive()) return;
    optSel.value = memo.optimizer ?? d.optimizer;
    budgetIn.value = memo.budget ?? String(Math.min(d.budget, 400));
    gridSel.value = memo.grid ?? String(Math.min(d.grid, 16));
    c2fIn.checked = memo.c2f ?? d.coarse_to_fine;
  }).catch((err) => ctx.error(err, { prefix: 'Reconstruct' }));

  let scene = null; // the scene text the rows were built from
  let rows = []; // [{pointer, value, integer, el}]
  let slice = null; // {name, file}
  let job = null; // the reconstruction this section shows (running or the last one)
  let unfollow = null;
  let plotted = 0;
  // The form as the user left it, kept while they are in another tool.
  const memo = ctx.memory.reconstruct ??= {};

  fileIn.onchange = () => {
    const f = fileIn.files?.[0];
    slice = f ? { name: f.name, file: f } : null;
    if (slice) status(`target: slice image ${slice.name}`);
    remember();
  };
  for (const r of el.querySelectorAll('[name=fit-target]')) {
    r.onchange = () => {
      fileIn.hidden = r.value !== 'slice' || !r.checked;
      if (r.value === 'slice' && r.checked && !slice) fileIn.click();
    };
  }

  function remember() {
    memo.open = el.open;
    memo.target = q('[name=fit-target]:checked')?.value;
    memo.slice = slice;
    if (defaults) Object.assign(memo, { optimizer: optSel.value, budget: budgetIn.value, grid: gridSel.value, c2f: c2fIn.checked });
    if (scene !== null) {
      memo.scene = scene;
      memo.rows = Object.fromEntries(rows.map((r) => [r.pointer, Object.fromEntries(['fit-truth', 'fit-lo', 'fit-hi'].map((n) => [n, r.el.querySelector(`[name=${n}]`).value]).concat([['on', r.el.querySelector('[name=fit-on]').checked]]))]));
    }
  }
  el.addEventListener('input', remember);
  el.addEventListener('change', remember);
  el.addEventListener('toggle', remember);
  if (memo.open) el.open = true;
  if (memo.slice) slice = memo.slice;
  if (memo.target) {
    const radio = q(`[name=fit-target][value="${memo.target}"]`);
    if (radio) { radio.checked = true; fileIn.hidden = memo.target !== 'slice'; }
  }

  function buildRows(text) {
    scene = text;
    let json;
    try { json = JSON.parse(text); } catch { paramsEl.replaceChildren(); rows = []; return; }
    rows = numbersOf(json).map((n, i) => {
      const [lo, hi] = rangeOf(n.value);
      const row = document.createElement('div');
      row.className = 'micro-fit-row';
      row.style.cssText = 'display:flex;flex-wrap:wrap;gap:.3rem;align-items:center;margin:.2rem 0';
      row.dataset.pointer = n.pointer;
      row.innerHTML = `
        <label class="inline"><input type="checkbox" name="fit-on"> <code></code> = <span class="now"></span></label>
        <label class="inline">target <input type="number" name="fit-truth" step="any" style="width:6rem"></label>
        <label class="inline">from <input type="number" name="fit-lo" step="any" style="width:5rem"></label>
        <label class="inline">to <input type="number" name="fit-hi" step="any" style="width:5rem"></label>`;
      row.querySelector('code').textContent = n.pointer;
      row.querySelector('.now').textContent = String(n.value);
      row.querySelector('[name=fit-truth]').value = String(n.value);
      row.querySelector('[name=fit-lo]').value = String(lo);
      row.querySelector('[name=fit-hi]').value = String(hi);
      row.querySelector('[name=fit-on]').dataset.testid = `micro-fit-on-${i}`;
      return { ...n, el: row };
    });
    paramsEl.replaceChildren(...rows.map((r) => r.el));
    // The ticks and targets the user left for this scene.
    if (memo.scene === text && memo.rows) {
      for (const r of rows) {
        const m = memo.rows[r.pointer];
        if (!m) continue;
        r.el.querySelector('[name=fit-on]').checked = m.on;
        for (const n of ['fit-truth', 'fit-lo', 'fit-hi']) r.el.querySelector(`[name=${n}]`).value = m[n];
      }
    }
  }

  const num = (row, name) => Number(row.el.querySelector(`[name=${name}]`).value);

  async function request() {
    const doc = ctx.state();
    const chosen = rows.filter((r) => r.el.querySelector('[name=fit-on]').checked);
    if (!chosen.length) throw Object.assign(new Error('Tick at least one number of the scene to fit.'), { kind: 'invalid-input', field: 'params' });
    const params = chosen.map((r) => ({ pointer: r.pointer, lo: num(r, 'fit-lo'), hi: num(r, 'fit-hi') }));
    const grid = Number(gridSel.value);
    let target;
    if (q('[name=fit-target]:checked').value === 'slice') {
      if (!slice) throw Object.assign(new Error('Choose a slice image to fit to.'), { kind: 'invalid-input', field: 'target' });
      target = { kind: 'slices', pngs: [await slicePng(slice.file, grid)], range: 1 };
    } else {
      const t = JSON.parse(doc.scene);
      for (const r of chosen) setPointer(t, r.pointer, r.integer ? Math.round(num(r, 'fit-truth')) : num(r, 'fit-truth'));
      target = { kind: 'scene', scene: JSON.stringify(t) };
    }
    return {
      ...defaults,
      scene: doc.scene,
      params,
      target,
      grid,
      optimizer: optSel.value,
      coarse_to_fine: c2fIn.checked,
      budget: Math.max(2, Math.round(Number(budgetIn.value) || defaults.budget)),
    };
  }

  const running = () => !!job?.running;
  const valuesText = (pointers, values) => pointers.map((p, i) => `${p.pointer} = ${Number(values[i].toPrecision(6))}`).join(', ');

  /** The scene text `from` with the fitted `values` at `params` (integers rounded). */
  function sceneWith(from, params, values) {
    const t = JSON.parse(from);
    params.forEach((p, i) => setPointer(t, p.pointer, p.integer ? Math.round(values[i]) : values[i]));
    return JSON.stringify(t, null, 2);
  }

  /** What Apply puts in the scene: a finished fit's scene, or a stopped one's best so far. */
  function applicable() {
    if (!job || job.data.applied || job.data.from !== ctx.state()?.scene) return null;
    if (job.status === 'done') return job.result.scene;
    if (job.status === 'stopped' && job.best) return sceneWith(job.data.from, job.data.params, job.best.values);
    return null;
  }

  function setRunning(on) {
    runBtn.disabled = on;
    stopBtn.disabled = !on;
    applyBtn.disabled = on || !applicable();
  }

  async function run() {
    if (!defaults) return;
    ctx.clearError('fit');
    let payload;
    try {
      payload = await request();
    } catch (err) {
      status('the reconstruction failed (see above)');
      ctx.error(err, { prefix: 'Reconstruct', source: 'fit' });
      return;
    }
    const from = ctx.state().scene;
    const params = payload.params.map((p) => ({ pointer: p.pointer, integer: !!rows.find((r) => r.pointer === p.pointer)?.integer }));
    // One fit sharded over the pool (all workers but one, which stays
    // free for the view); the core merges, so this is one fit's result.
    const n = Math.max(1, (ctx.pool.slots?.length ?? 2) - 1);
    const started = ctx.startJob('reconstruct', { label: 'Reconstruct' }, async (j) => {
      const fractions = Array(n).fill(0);
      j.report({ stage: 'sampling the target', fraction: 0 });
      return j.runSharded('micro-fit', payload, {
        shards: n,
        onProgress: (p, k) => {
          fractions[k] = p.fraction;
          if (k !== 0) return;
          const f = fractions.reduce((a, b) => a + b, 0) / n;
          const loss = p.figure != null && Number.isFinite(p.figure) ? p.figure : null;
          j.report({ fraction: f, stage: p.stage, figure: loss }, {
            point: loss === null ? null : [f, loss],
            ...(loss !== null && p.values ? { best: { values: [...p.values], loss } } : {}),
          });
        },
      });
    });
    started.data = { from, params, workers: n };
    attach(started);
  }

  /** Show reconstruction `j` here (a new one, or one found on coming back). */
  function attach(j) {
    unfollow?.();
    job = j;
    plot.clear();
    plotted = 0;
    unfollow = ctx.follow(j, showJob);
    showJob(j);
  }

  function showJob(j) {
    if (j !== job || !ctx.alive()) return;
    const pct = Math.round(100 * j.progress.fraction);
    const loss = j.progress.figure;
    if (j.running) {
      for (; plotted < j.points.length; plotted++) plot.push(...j.points[plotted]);
      status(`${j.progress.stage}: ${pct}%${loss != null ? ` — loss ${loss.toFixed(3)}` : ''}${j.data.workers > 1 ? ` (${j.data.workers} workers)` : ''}`);
    } else if (j.status === 'done') {
      const r = j.result;
      // From the scene as given (the status's first number) to the best (its last).
      plot.points = [[0, r.initial_loss], ...r.history.map((l, i) => [r.history_evaluations[i] / r.evaluations, l])].filter((p) => Number.isFinite(p[1]));
      plot.draw();
      const secs = (j.endedAt - j.startedAt) / 1000;
      status(`fitted in ${secs.toFixed(1)} s: ${valuesText(j.data.params, r.values)}; loss ${r.initial_loss.toFixed(3)} → ${r.loss.toFixed(3)} after ${r.evaluations} evaluations`
        + `${r.validation != null ? `, validation error ${r.validation.toPrecision(3)}` : ''}`);
      statusEl.dataset.initial = String(r.initial_loss);
      statusEl.dataset.loss = String(r.loss);
      statusEl.dataset.fits = String(Number(statusEl.dataset.fits || 0) + 1);
    } else {
      for (; plotted < j.points.length; plotted++) plot.push(...j.points[plotted]);
      if (j.status === 'stopped') {
        status(j.best
          ? `stopped at ${pct}% — Apply fitted values puts in the best so far: ${valuesText(j.data.params, j.best.values)} (loss ${j.best.loss.toFixed(3)})`
          : `stopped at ${pct}%, before any candidate`);
      } else if (j.status === 'cancelled') {
        status(`cancelled at ${pct}% (${j.reason})`);
      } else if (j.status === 'failed') {
        status('the reconstruction failed (see above)');
        ctx.error(j.error, { prefix: 'Reconstruct', source: 'fit' });
      }
    }
    setRunning(j.running);
  }

  runBtn.onclick = () => run();
  stopBtn.onclick = () => job?.stop();
  applyBtn.onclick = () => {
    const doc = ctx.state();
    const next = applicable();
    if (!next || !doc) return;
    const what = job.status === 'done' ? 'the fitted' : 'the best so far';
    if (!ctx.commit({ ...doc, scene: next, example: null })) return;
    job.data.applied = true;
    status(`applied: ${what} ${job.data.params.length === 1 ? 'value' : 'values'} written into the scene (undo restores them)`);
    setRunning(false);
  };

  // For the e2e tests: the raw parts (tests/e2e/hooks/micro.js reads them).
  ctx.expose({ rows: () => rows, job: () => job, running, plot, request }, 'micro-fit');
  // A reconstruction of this document that ran (or runs on) while the tool was away.
  if (ctx.job('reconstruct')) attach(ctx.job('reconstruct'));

  return {
    render(doc) {
      if (!doc) return;
      if (doc.scene !== scene) buildRows(doc.scene);
      if (!running()) setRunning(false);
    },
    unmount() {
      unfollow?.(); // the reconstruction runs on: it is the document's
    },
  };
}
