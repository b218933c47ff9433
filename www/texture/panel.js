// "Texture": perceptual procedural-texture retrieval (MISSION X7, S8–S10;
// the paper's Fig. 2/6). Give an example — drop, paste or choose an image,
// or render one of the procedural models — and the core predicts its model
// and its twelve perceptual scales (`texture-analyse`). The scales are
// sliders: moving one asks the core for a texture near the request in the
// perceptual space (`texture-retrieve`: of the nearest few, the one whose
// scales are nearest; debounced, a stale request cancelled), rendered live
// from its model and parameters. A bar chart compares the requested and
// retrieved scales (with their cosine similarity); the retrieved parameters
// can be edited (re-rendered with `texture-render`); the preview tiles 2×2;
// PNG and JSON export.
//
// This file wires the panel's parts together; each is one module here:
//   state.js         the document (schema: src/texture/state.rs), what is derived from it (`live`)
//   index-loader.js  the index and the model list, once per page
//   pictures.js      grey pictures: ImageData, PNG, a dropped image shrunk
//   link.js          the example in a link
//   layout.js        the markup
//   schedule.js      the core's jobs: retrieval after a move, analysis of an example
//   sliders.js       the twelve scales and "Stay within the predicted model"
//   example.js       the example: dropped, pasted, chosen or rendered
//   view.js          the retrieved texture (tiled)
//   readout.js       the prediction and the retrieval in words
//   params.js        the retrieved parameters, editable
//   chart.js         requested vs retrieved scales
//   export.js        PNG and JSON out
// Tests read the panel through `ctx.expose` (tests/e2e/hooks/texture.js).
import { models } from './index-loader.js';
import { textureState, createLive, DEFAULT_MODEL } from './state.js';
import { html } from './layout.js';
import { createRunner } from './schedule.js';
import { createSliders } from './sliders.js';
import { createExample } from './example.js';
import { createView } from './view.js';
import { createReadout } from './readout.js';
import { createParams } from './params.js';
import { createChart } from './chart.js';
import { attachExport } from './export.js';

function mount(el, ctx) {
  el.innerHTML = html;
  const q = (s) => el.querySelector(s);
  const state = () => ctx.state();
  const statusEl = q('[data-testid=texture-status]');
  const status = (t) => { statusEl.textContent = t; };
  const modelSel = q('[name=example-model]');
  const live = createLive();

  const counters = statusEl.dataset;
  counters.retrievals = '0';
  counters.renders = '0';

  const runner = createRunner(ctx, { live, status, counters });
  const sliders = createSliders(ctx, { q, sameBox: q('[name=same-model]'), runner });
  const example = createExample(ctx, { q, live, runner, status, modelSel });
  const view = createView(ctx, { q, live, counters });
  const readout = createReadout({ q, live });
  const params = createParams(ctx, { q, live });
  const chart = createChart(ctx, { el, q });
  attachExport(ctx, { q, live, view, status });

  models(ctx.run).then((ms) => {
    if (!ctx.alive()) return;
    live.list = ms;
    modelSel.replaceChildren(...ms.map((m) => {
      const o = document.createElement('option');
      o.value = m.id;
      o.textContent = m.name;
      return o;
    }));
    const s = state();
    modelSel.value = s?.source?.kind === 'model' ? s.source.model : DEFAULT_MODEL;
    if (s) paint(s, null);
  }).catch((err) => ctx.error(err, { prefix: 'The texture models' }));

  function paint(s) {
    sliders.sync(s);
    readout.show(s);
    params.buildParams(s.retrieved);
    chart.drawChart(s);
  }

  // For the e2e tests: the raw parts (tests/e2e/hooks/texture.js reads them).
  ctx.expose({ state, live, runner, view });

  return {
    render(s, prev) {
      if (!s) return;
      paint(s, prev);
      example.drawExample(s.source).catch((err) => { if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Example' }); });
      view.renderRetrieved(s.retrieved);
      // Undo/redo or a loaded document changed the request: its texture is the stored one.
    },
    unmount() {
      chart.detach();
      example.detach();
      runner.abort();
      view.abort();
    },
  };
}

export default { id: 'texture', title: 'Texture', state: textureState, mount };
