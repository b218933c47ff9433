// The fit: settings, Run / Stop / Apply fitted values, its progress, the
// loss plot and the table of fitted values.
//
// A fit is a job of the document (ctx.startJob): switching tools does not
// stop it, the tool bar shows its progress, and this panel shows it again
// when it comes back: its plot, its status, its best so far. Stop keeps
// the best values so far for "Apply fitted values"; a fit that ends goes
// into the document it started from (program unchanged), mounted or not.
// The fit draws its own pictures (`preview`): each new best so far and the
// fitted values come with their pixels, which the overlay shows.
import { LossPlot } from '../ui/loss-plot.js';
import { named } from './program.js';
import { isBlank } from './state.js';

const fmt = (v) => (Math.abs(v) >= 100 ? v.toFixed(1) : v.toFixed(3));
const same = (a, b) => a && b && a.length === b.length && a.every((v, i) => v === b[i]);

/** The fit part of the panel (`live`: state.js; `preview`: preview.js). */
export function createFitRun(ctx, { q, live, preview, status }) {
  const doc = () => ctx.state();
  const plot = new LossPlot(q('canvas.plot'));
  let unfollow = null;
  let plotted = 0; // job.points already on the plot
  let pictured = null; // the job's best picture the overlay has

  const running = () => !!live.job?.running;
  const applicable = () => {
    const { job } = live;
    return job?.status === 'stopped' && !!job.best && !job.data.appliedBest && doc()?.program === job.data.program;
  };

  // A blank target has nothing to fit to (every pattern is as far from it):
  // Run fit waits for a target and says how to make one.
  function setRunning(on) {
    q('[data-act=cancel]').disabled = !on;
    q('[data-act=apply-fit]').disabled = on || !applicable();
    const blank = isBlank(doc()?.target);
    q('[data-act=fit]').disabled = on || blank;
    const why = q('[data-testid=fit-why]');
    why.hidden = on || !blank;
    why.textContent = blank ? 'The target is empty, so there is nothing to fit yet: draw on it in the pattern’s colours, upload an image, or press “Make target from these values”.' : '';
  }

  /** A change that makes the running fit meaningless cancels it, saying why. */
  function stop(reason = 'the program changed') {
    live.job?.stop(reason);
    setRunning(false);
  }

  function fit() {
    const d = doc();
    if (!d?.target || !live.info || isBlank(d.target)) return;
    ctx.clearError();
    // The figures of the last fit are stale from here on.
    q('.results tbody').querySelectorAll('[data-col=fitted]').forEach((td) => { td.textContent = '…'; });
    const fitInfo = live.info;
    const floatIdx = fitInfo.params.map((p, i) => (p.integer ? -1 : i)).filter((i) => i >= 0);
    const full = (floats) => {
      const values = [...d.values];
      floatIdx.forEach((k, j) => { values[k] = floats[j]; });
      return values;
    };
    // A fresh payload per request: its pixel buffer is transferred to a worker.
    // `preview`: the fit draws its best values so far and its answer at the
    // target's size, as the overlay's `render-pattern` would.
    const payload = () => ({
      program: d.program, params: named(fitInfo, d.values, { integersOnly: true }),
      target_rgba: { ...d.target, rgba: d.target.rgba.slice() },
      budget: d.settings.budget, loss: d.settings.loss, seed: d.settings.seed, preview: true,
    });
    const started = ctx.startJob('fit', { label: 'Fit' }, async (j) => {
      // One fit sharded across the worker pool (all workers but one, which
      // stays free for other jobs). The pool relays the shards' exchanges and
      // the core merges them, so the result is exactly that of one fit
      // (tests/fit.rs checks this with the native driver).
      const n = Math.max(1, ctx.pool.slots.length - 1);
      const fractions = Array(n).fill(0);
      const losses = Array(n).fill(Infinity);
      const r = await j.runSharded('fit', payload(), {
        shards: n,
        onProgress: (p, k) => {
          fractions[k] = p.fraction;
          if (p.figure != null) losses[k] = p.figure;
          const loss = Math.min(...losses);
          const fraction = fractions.reduce((a, b) => a + b, 0) / n;
          // The global stage (spectra, then the phase sweep) has no loss to
          // plot until its sweep: the plot shades how far it has come.
          if (/^global search/.test(p.stage)) j.data.global = Math.max(j.data.global ?? 0, fraction);
          const holds = p.values && losses[k] === loss;
          const better = holds && loss < (j.best?.loss ?? Infinity);
          // A picture of the best comes with it, or (at most every few
          // hundred ms of the fit's work: PREVIEW_EVERY_STEPS) a little later.
          const picture = holds && p.picture && (better || same(p.values, j.best?.params)) ? p.picture : null;
          let best;
          if (better) best = { values: full(p.values), params: [...p.values], loss, picture };
          else if (picture) best = { ...j.best, picture };
          j.report({ fraction, stage: n > 1 ? `${p.stage} (${n} workers)` : p.stage, figure: loss }, {
            point: Number.isFinite(loss) ? [fraction, loss] : null,
            ...(best ? { best } : {}),
          });
        },
      });
      // The fitted values' picture, before they reach the document (whose
      // overlay then needs no `render-pattern`).
      j.data.fitted = { values: full(r.params), picture: r.picture };
      preview.showPicture(d.program, j.data.fitted.values, r.picture, { documentValues: true });
      // A fit finishes into the document it started from, or not at all.
      j.data.applied = j.commit((cur) => (cur.program !== d.program ? null : {
        ...cur, values: full(r.params).map((v, i) => (floatIdx.includes(i) ? v : cur.values[i])),
        result: { params: r.params, loss: r.loss, names: r.names, evaluations: r.evaluations },
      }));
      j.report({ fraction: 1 }, { point: [1, r.loss] });
      return r;
    });
    started.data = { program: d.program };
    attach(started);
  }

  /** Show job `j` in this panel (a new fit, or one found on coming back). */
  function attach(j) {
    unfollow?.();
    live.job = j;
    plot.clear();
    plotted = 0;
    pictured = null;
    unfollow = ctx.follow(j, show);
    show(j);
  }

  function show(j) {
    if (j !== live.job || !ctx.alive()) return;
    if (j.data?.global) plot.shade(j.data.global, 'global search');
    for (; plotted < j.points.length; plotted++) plot.push(...j.points[plotted]);
    const pct = Math.round(100 * j.progress.fraction);
    q('progress').value = j.status === 'done' ? 1 : j.progress.fraction;
    const loss = j.progress.figure;
    if (j.running) {
      status(`${j.progress.stage} ${pct}% — loss ${Number.isFinite(loss) ? loss.toPrecision(4) : '…'}`);
      // The best candidate so far over the target, as the fit drew it.
      if (j.best?.picture && j.best.picture !== pictured) {
        pictured = j.best.picture;
        preview.showPicture(j.data.program, j.best.values, j.best.picture);
      }
    } else if (j.status === 'done') {
      const r = j.result;
      const secs = ((j.endedAt - j.startedAt) / 1000).toFixed(1);
      // One loss, named (the polish's image-space loss is a different one).
      status(`fitted in ${secs} s — loss ${r.loss.toPrecision(4)} (${r.loss_name}) after ${r.evaluations} evaluations${j.data.applied ? '' : ' (not applied: the program changed meanwhile)'}`);
      if (j.data.fitted) preview.showPicture(j.data.program, j.data.fitted.values, j.data.fitted.picture, { documentValues: true });
    } else if (j.status === 'stopped') {
      status(j.best
        ? `stopped at ${pct}% — the values from before the fit are kept; Apply fitted values puts in the best so far (loss ${j.best.loss.toPrecision(4)})`
        : `stopped at ${pct}% — no candidate yet; the values from before the fit are kept`);
    } else if (j.status === 'cancelled') {
      status(`cancelled at ${pct}% (${j.reason}) — the values from before the fit are kept`);
    } else if (j.status === 'failed') {
      status('the fit failed (see above)');
      ctx.error(j.error);
    }
    if (!j.running) {
      // The overlay showed the fit's candidates: back to the document's values.
      if (doc()) preview.show(doc().values);
      renderResults(doc());
    }
    setRunning(j.running);
  }

  function apply() {
    if (!applicable()) return;
    const { job } = live;
    const { best } = job;
    if (best.picture) preview.showPicture(job.data.program, best.values, best.picture, { documentValues: true });
    if (ctx.commit({ ...doc(), values: best.values, result: { params: best.params, loss: best.loss, names: null, evaluations: null } })) {
      status(`applied: the stopped fit's best values (loss ${best.loss.toPrecision(4)}); Undo puts the earlier ones back`);
      job.data.appliedBest = true;
      setRunning(false);
    }
  }

  function renderResults(d) {
    const { info } = live;
    if (!info || !d || info.params.length !== d.values.length) return;
    q('.results tbody').replaceChildren(...info.params.filter((p) => !p.integer).map((p) => {
      const i = info.params.indexOf(p);
      const tr = document.createElement('tr');
      tr.dataset.param = p.name;
      const cells = [p.name, d.result ? fmt(d.values[i]) : '—', d.truth ? fmt(d.truth[i]) : '—'];
      tr.replaceChildren(...cells.map((text, k) => {
        const td = document.createElement('td');
        td.textContent = text;
        if (k) td.dataset.col = k === 1 ? 'fitted' : 'truth';
        return td;
      }));
      return tr;
    }));
  }

  q('[data-act=fit]').onclick = fit;
  q('[data-act=cancel]').onclick = () => live.job?.stop();
  q('[data-act=apply-fit]').onclick = apply;
  for (const name of ['budget', 'loss', 'seed']) {
    q(`[name=${name}]`).onchange = (e) => {
      const v = name === 'seed' ? Math.max(0, Math.round(Number(e.target.value) || 0)) : e.target.value;
      ctx.commit({ ...doc(), settings: { ...doc().settings, [name]: v } });
    };
  }
  // A fit of this document that ran (or ran on) while the panel was away.
  if (ctx.job('fit')) attach(ctx.job('fit'));

  return {
    plot, running, stop, setRunning, renderResults,
    /** The settings' controls follow document `d`. */
    sync(d) {
      for (const name of ['budget', 'loss', 'seed']) q(`[name=${name}]`).value = d.settings[name];
    },
  };
}
