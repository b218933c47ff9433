// When the core grows the document: a change runs it shortly after (a drag
// sends one request a pause, not one a move), Generate runs it at once,
// Cancel or a newer document stops it. The growth is a job of the document
// (ctx.startJob, issue 35 item 4): it grows on when the user opens another
// tool, the tool bar shows it once it takes a while, and coming back takes
// its answer (or waits for it) instead of growing it again. Its requests
// carry `keep` and go to one worker (affinity), which keeps the expansion:
// an edit then regrows only its step's subtree there. They name the answer
// shown as their `base`; the job keeps that answer, so a delta is applied to
// it whenever (and wherever) its answer is taken.
import { requestOf, sameRequest, KEEP_AFFINITY } from './state.js';

const RUN_DELAY_MS = 120;
const BUSY_DELAY_MS = 150; // a run shows it is busy after this long

/**
 * The runs of a mounted panel: `base()` is the prepared answer shown (or
 * null), `onAnswer(response, doc, t0, baseT)` shows an answer (t0: when its
 * run started; baseT: the answer its request named as its base),
 * `onFailed()` repaints what the canvas showed; `cancel` is the Cancel
 * button; `timing`: timing.js.
 */
export function createRunner(ctx, { cancel, status, timing, base, onAnswer, onFailed }) {
  let running = null; // the AbortController of the run under way
  let runTimer = null;

  function scheduleRun() {
    ctx.clearTimeout(runTimer);
    runTimer = ctx.setTimeout(() => { runTimer = null; run(); }, RUN_DELAY_MS);
  }

  async function run() {
    const doc = ctx.state();
    if (!doc) return;
    ctx.clearTimeout(runTimer);
    runTimer = null;
    // Already growing this very document (Generate after an edit): that growth answers.
    const growing = ctx.job('grow');
    if (running && growing?.running && growing.data.doc && sameRequest(growing.data.doc, doc)) return;
    running?.abort();
    const ctrl = new AbortController();
    running = ctrl;
    // A run says it is busy (status, Cancel) only when it takes a while: an edit's answer
    // comes within a few frames, and every change on the page makes the browser draw a
    // frame, which takes the CPU from the worker growing the answer.
    let busy = false;
    const showBusy = () => {
      if (running !== ctrl || busy) return;
      busy = true;
      cancel.disabled = false;
      status('growing…');
    };
    const busyTimer = ctx.setTimeout(showBusy, BUSY_DELAY_MS);
    const t0 = performance.now();
    timing.runAt = t0;
    try {
      let job = ctx.job('grow');
      if (!(job?.data.doc && sameRequest(job.data.doc, doc) && (job.running || job.status === 'done'))) {
        const baseT = base();
        const request = { ...requestOf(doc), keep: true, base: baseT?.r.answer ?? null };
        job = ctx.startJob('grow', { label: 'Tangle', quietMs: BUSY_DELAY_MS }, (j) => j.run('tangle', request, {
          affinity: KEEP_AFFINITY,
          onProgress: (p) => j.report({
            fraction: p.fraction, figure: p.figure,
            stage: p.figure != null ? `${Math.round(p.figure).toLocaleString('en')} shapes` : p.stage,
          }),
        }));
        job.data.doc = doc;
        job.data.baseT = baseT;
      }
      // Cancel, or a newer edit, ends it; leaving the panel does not.
      const stop = () => job.stop('cancelled');
      ctrl.signal.addEventListener('abort', stop, { once: true });
      const unfollow = ctx.follow(job, (j) => { if (running === ctrl && busy && j.running) status(`growing: ${j.progress.stage}`); });
      const ended = await job.promise;
      unfollow();
      ctrl.signal.removeEventListener('abort', stop);
      if (running !== ctrl || !ctx.alive()) return;
      if (ended.status !== 'done') throw ended.error ?? Object.assign(new Error('cancelled'), { kind: 'cancelled' });
      onAnswer(ended.result, doc, t0, job.data.baseT);
    } catch (err) {
      if (running !== ctrl) return;
      onFailed();
      status(err?.kind === 'cancelled' ? 'cancelled' : 'the tangle could not grow (see above)');
      if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Tangle', source: 'run' });
    } finally {
      ctx.clearTimeout(busyTimer);
      if (running === ctrl) {
        running = null;
        if (!cancel.disabled) cancel.disabled = true;
      }
    }
  }

  return {
    /** Run shortly (a newer change moves it later). */
    schedule: scheduleRun,
    /** Run now. */
    run,
    /** Whether a run is due (scheduled, not yet started). */
    due: () => runTimer !== null,
    /** Whether a run is due or under way. */
    busy: () => runTimer !== null || running !== null,
    /** Cancel: stop the run under way and the one due. */
    cancel() {
      running?.abort();
      ctx.job('grow')?.stop('cancelled');
      ctx.clearTimeout(runTimer);
      runTimer = null;
    },
    /** The panel is left: its growth goes on (it is the document's, ctx.startJob). */
    detach() { running = null; },
  };
}
