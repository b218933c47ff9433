// "Tangle": pen-and-ink tangle drawings grown from group grammars (MISSION
// T9, the paper's §6 "User control" and Fig. 13). Pick a shipped grammar or
// edit one, choose where it starts (the grammar's own start, a rectangle, a
// typed word, an SVG file, a polygon drawn on the canvas), and the core grows
// the tangle in a worker. A step slider walks the history; clicking a shape
// selects the step that made it (clicking again walks further back), whose
// parameters can then be edited or which can be re-expanded with a new
// random draw. A curve or shape drawn on the canvas is added to the grammar
// text as a `curve`/`shape` polyline definition for split and place rules.
//
// This file wires the panel's parts together; each is one module here:
//   state.js         the document (the request), what is derived from it (`live`)
//   layout.js        the markup
//   grammar-editor.js  the grammar text
//   start.js         "Start from"
//   schedule.js      when the core grows the document (a job of the document)
//   canvas.js        the view transform and every paint (tiles.js: partial repaints;
//                    draw.js: a step's picture as Path2D parts and their bitmaps)
//   gestures.js      pan, pinch, wheel and clicks on the canvas
//   polygon-draw.js  a polyline drawn on the canvas
//   timeline.js      the step slider and Play
//   selection.js     the selected step, its parameters and edits (step-list.js: the list)
//   thumbnails.js    the shipped grammars' cards
//   export.js, drop.js  files out and in
//   timing.js        figures of the last paint and answer, the highlight switch
// Tests read the panel through `ctx.expose` (tests/e2e/hooks/tangle.js).
// While an edit's answer is due, the canvas keeps the last picture (and its
// highlight) until the answer repaints it. A request names the answer shown
// (`base`); the worker that kept its expansion answers with what changed
// (delta.js applies it: the kept shapes keep their Path2Ds, and the repaint
// covers only the changed shapes' tiles); any other worker answers in full.
import { preloadCodeEditor } from '../ui/code-editor.js';
import { prepareTangle } from './draw.js';
import { applyDelta } from './delta.js';
import { tangleState, createLive, sameRequest } from './state.js';
import { html } from './layout.js';
import { createGrammarEditor } from './grammar-editor.js';
import { createStartForm } from './start.js';
import { createRunner } from './schedule.js';
import { createPainter } from './canvas.js';
import { attachGestures } from './gestures.js';
import { createPolygonDraw } from './polygon-draw.js';
import { createTimeline } from './timeline.js';
import { createSelection } from './selection.js';
import { createExamplePicker } from './thumbnails.js';
import { createExport } from './export.js';
import { createDrop } from './drop.js';
import { createTiming, createOptions, answerBytes } from './timing.js';

export { requestOf } from './state.js';

function mount(el, ctx) {
  el.innerHTML = html;
  preloadCodeEditor();
  const q = (s) => el.querySelector(s);
  const statusEl = q('[data-testid=tangle-status]');
  const status = (t) => { statusEl.textContent = t; };
  const state = () => ctx.state();
  const live = createLive(state);
  const timing = createTiming();
  const options = createOptions();

  // The parts; a few call each other back (through arrows, once all are made).
  const editor = createGrammarEditor(ctx, q('.tangle-editor'), {
    details: q('details.tangle-program'), live, generate: () => generate(),
  });
  const painter = createPainter(ctx, {
    canvas: q('[data-testid=tangle-canvas]'), viewport: q('.tangle-viewport'), live, timing, options,
    overlay: { active: () => drawer.active(), paint: (g) => drawer.paintOn(g) },
  });
  const runner = createRunner(ctx, {
    cancel: q('[data-act=cancel]'), status, timing, base: () => live.T, onAnswer: showAnswer, onFailed: () => painter.paint(),
  });
  const timeline = createTimeline({
    slider: q('[name=step]'), playBtn: q('[data-act=play]'), out: q('[data-testid=tangle-count]'), live, paint: painter.paint,
  });
  const selection = createSelection(ctx, { q, live, painter, runner, status });
  const gestures = attachGestures(painter, { onTap: (x, y) => (drawer.active() ? drawer.addPoint(x, y) : selection.pickAt(x, y)) });
  const startForm = createStartForm(ctx, { q, live, drawPolygon: () => drawer.begin() });
  const drawer = createPolygonDraw(ctx, {
    q, live, painter, status, grammarText: editor.text, setStart: startForm.setStart, stopPlay: timeline.stopPlay,
    onCancel: startForm.reset,
  });
  const picker = createExamplePicker(ctx, q('[data-testid=tangle-examples]'), { pick: loadExample });

  function generate() {
    if (!editor.apply()) runner.run();
  }

  /**
   * Show answer `r` of document `doc` (its run started at t0); `baseT`: the prepared answer
   * its request named as its base (a delta answer is applied to it).
   */
  function showAnswer(r, doc, t0, baseT) {
    const t1 = performance.now();
    timing.answeredAt = t1;
    timing.answer = {
      delta: r.base != null, added: r.shapes.count, removed: r.removed.byteLength / 4, dirty: r.dirty ?? null, bytes: answerBytes(r),
    };
    let link = null;
    if (r.base != null) {
      const d = applyDelta(baseT.r, r);
      link = { T: baseT, oldOf: d.oldOf, added: d.added, removed: d.removed };
      r = d.r;
    }
    live.T = prepareTangle(r, link);
    painter.layers.clear();
    live.shownFor = doc;
    painter.dropHighlight();
    live.lastPick = -1;
    timing.run = performance.now() - t0;
    timing.prepare = performance.now() - t1;
    timeline.setSteps(live.T.steps);
    timeline.setStep(live.T.steps, false);
    if (live.refit) { live.refit = false; painter.fitView(); }
    ctx.clearError('run');
    const why = r.stopped ? ` — stopped: ${r.stopped}` : '';
    status(`${r.stats.steps.toLocaleString('en')} steps, ${r.stats.shapes.toLocaleString('en')} shapes, ${r.stats.vertices.toLocaleString('en')} vertices in ${Math.round(timing.run)} ms${why}`);
    statusEl.dataset.runs = String(Number(statusEl.dataset.runs || 0) + 1);
    selection.resolveSelection();
    selection.showSelected();
    // Painted now, not at the next animation frame: the answer is what the user waits
    // for, and a loaded machine may start that frame late (the browser shows the canvas
    // at its next frame either way). An answer's full repaint draws heavy parts directly
    // instead of first making their bitmaps (a second pass: the layers were just cleared,
    // and which parts a later slider move needs is unknown); idle time makes them afterwards.
    painter.paintChangedNow({ newBitmaps: false });
    timing.paintEndAt = performance.now();
    picker.loadThumbnails();
  }

  /** Whether a run for document `s`, which the canvas does not show yet, is due or under way. */
  const awaitingAnswer = (s) => !!live.T && !!live.shownFor && !sameRequest(live.shownFor, s) && runner.busy();

  function loadExample(ex) {
    const doc = state();
    if (!doc) return;
    live.refit = true;
    live.lastPick = -1;
    // A grammar typed less than a pause ago is dropped: the example replaces it, in the
    // document and in the editor.
    editor.dropTyping();
    ctx.commit({ ...doc, example: ex.name, grammar: ex.grammar, start: null, edits: [], selected: null });
  }

  // ---- seed, ink, toolbar ----------------------------------------------------------------

  const setSeed = (v) => {
    const doc = state();
    if (!doc || !Number.isFinite(v)) return;
    ctx.commit({ ...doc, seed: Math.max(0, Math.round(v)), edits: [], selected: null });
  };
  q('[name=seed]').onchange = (e) => setSeed(Number(e.target.value));
  q('[data-act=new-seed]').onclick = () => setSeed((state()?.seed ?? 0) + 1);
  for (const name of ['wobble', 'stroke_width']) {
    const input = q(`[name=${name}]`);
    input.oninput = () => {
      const doc = state();
      if (doc) ctx.commit({ ...doc, [name]: Number(input.value) }, { coalesce: `tangle-${name}` });
    };
    input.onchange = () => ctx.seal();
  }
  q('[data-act=zoom-in]').onclick = () => gestures.zoomCentre(1.5);
  q('[data-act=zoom-out]').onclick = () => gestures.zoomCentre(1 / 1.5);
  q('[data-act=zoom-fit]').onclick = () => painter.fitView();
  q('[data-act=generate]').onclick = generate;
  q('[data-act=cancel]').onclick = runner.cancel;
  // A growth of this document under way (it went on while the tool was away): show it busy.
  if (ctx.job('grow')?.running) { q('[data-act=cancel]').disabled = false; status('growing…'); }

  const exportAs = createExport(ctx, { q, status });

  // For the e2e tests and the latency bench: the raw parts (tests/e2e/hooks/tangle.js reads them).
  ctx.expose({ state, live, painter, timing, options, runner, editor, startForm, exportAs });

  return {
    drop: createDrop(ctx, { live, editor, status }),
    render(s, prev) {
      if (!s) return;
      editor.render(s, prev);
      q('[name=seed]').value = String(s.seed);
      for (const name of ['wobble', 'stroke_width']) {
        const input = q(`[name=${name}]`);
        if (Number(input.value) !== s[name]) input.value = String(s[name]);
        input.nextElementSibling.textContent = String(s[name]);
      }
      startForm.render(s, drawer.active());
      picker.mark(s);
      if (!prev || !sameRequest(s, prev)) {
        if (!prev || prev.grammar !== s.grammar || prev.start !== s.start) live.refit = true;
        runner.schedule();
      } else if (prev.stroke_width !== s.stroke_width) painter.paint();
      if (!prev || prev.selected !== s.selected || !sameRequest(s, prev)) {
        painter.dropHighlight();
        if (live.shownFor && sameRequest(live.shownFor, s)) selection.showSelected();
        // An edit of the selected step is answered soon: until then the canvas keeps the
        // last picture and its highlight. Repainting now would only take the highlight off,
        // and its raster would take the CPU from the worker growing the answer. (A new
        // document without a selection drops the highlight at once.)
        if (!(s.selected != null && awaitingAnswer(s))) painter.paint();
      }
    },
    markError: editor.markError,
    keys: {
      g: () => generate(),
      r: () => selection.reexpand(),
    },
    unmount() {
      painter.stop();
      timeline.stopPlay();
      runner.detach(); // its growth goes on: it is the document's (ctx.startJob)
    },
  };
}

export default { id: 'tangle', title: 'Tangle', state: tangleState, mount };
