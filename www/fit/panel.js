// "Fit": find the parameters of a pattern program that best match a target
// (MISSION F10). Pick or edit a program, draw the target with a brush in the
// program's colours, upload (or drop, or paste) an image, or make a target
// from chosen values; the fit runs in workers with a live loss plot and the
// best pattern so far drawn over the target. History, autosave, project
// files and links come from the document controller (app/document.js).
//
// This file wires the panel's parts together; each is one module here:
//   state.js     the document (defaults, links), what is derived from it (`live`)
//   program.js   program facts (`pattern-info`), values by name
//   layout.js    the markup
//   editor.js    the generator picker and the program text, its error marks
//   sliders.js   the program's facts and a slider a parameter
//   target.js    the target: brush and colours, upload, make from values, clear
//   preview.js   the overlay: the pattern of the values over the target
//   run.js       the fit: settings, run, stop, apply, loss plot, results
//   export.js    SVG and JSON out
// Tests read the panel through `ctx.expose` (tests/e2e/hooks/fit.js).
import { fitState, createLive } from './state.js';
import { createProgramFacts, keyOf } from './program.js';
import { html } from './layout.js';
import { createProgramEditor } from './editor.js';
import { createSliders } from './sliders.js';
import { createTarget } from './target.js';
import { createPreview } from './preview.js';
import { createFitRun } from './run.js';
import { attachExport } from './export.js';

function mount(el, ctx) {
  el.innerHTML = html;
  const q = (s) => el.querySelector(s);
  const statusEl = q('[data-testid=fit-status]');
  const status = (t) => { statusEl.textContent = t; };
  const state = () => ctx.state();
  const live = createLive();
  const factsOf = createProgramFacts(ctx.run);

  const preview = createPreview(ctx, { q, live });
  const target = createTarget(ctx, { q, live, status });
  const sliders = createSliders(ctx, { q, live });
  const run = createFitRun(ctx, { q, live, preview, status });
  const editor = createProgramEditor(ctx, { q, live, stopFit: run.stop });
  attachExport(ctx, { q, live });

  /** Bring program facts, sliders, brush colours and the overlay in line with document `d`. */
  let infoJob = 0;
  async function syncProgram(d) {
    const job = ++infoJob;
    let next;
    try {
      next = await factsOf(d);
    } catch (err) {
      if (job === infoJob) ctx.error(err);
      return;
    }
    if (job !== infoJob || !ctx.alive()) return;
    live.info = next;
    live.infoKey = keyOf(state(), next);
    editor.sync(state());
    sliders.build(state());
    target.showColours();
    run.renderResults(state());
    preview.show(state().values);
  }

  // For the e2e tests: the raw parts (tests/e2e/hooks/fit.js reads them).
  ctx.expose({ state, live, plot: run.plot });

  return {
    render(d, prev) {
      if (!d) return;
      run.sync(d);
      if (!prev || d.target !== prev.target) { target.draw(d.target); run.setRunning(run.running()); }
      else if (live.job && !live.job.running) run.setRunning(false); // Apply fitted values follows the document
      if (!live.info || keyOf(d, live.info) !== live.infoKey) {
        // A program or integer change: re-read the program (async), then sliders and preview.
        editor.generatorsReady.then(() => ctx.alive() && syncProgram(d));
      } else {
        sliders.sync(d);
        run.renderResults(d);
        if (!prev || d.values !== prev.values) preview.show(d.values);
      }
    },
    markError: editor.markError,
    unmount() {
      target.detach();
      // The fit runs on: it is the document's (ctx.startJob).
    },
  };
}

export default { id: 'fit', title: 'Fit', state: fitState, mount };
