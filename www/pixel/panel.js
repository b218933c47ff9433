// "Pixel": texture pixel art with oriented elements (MISSION P1–P6).
// The user loads a source, a mask and an element sheet (or one click on an
// example), paints the mask, draws orientation strokes on a zoomable pixel
// grid, and moves parameters; the core re-runs in a worker after each change
// (debounced, the previous run cancelled). History, autosave, project files
// and links come from the document controller (app/document.js).
//
// This file wires the panel's parts together; each is one module here:
//   state.js     the document (examples, links), what is derived from it (`live`)
//   layout.js    the markup
//   inputs.js    files in: examples, source, mask, elements (and their preview)
//   schedule.js  when the core textures the document
//   picture.js   the picture: base, mask overlay, strokes and arrows (canvas-view.js)
//   gestures.js  strokes and mask painting on the picture
//   toolbar.js   brush, zoom, layer toggles
//   controls.js  the parameter form
//   export.js    the result as a PNG
// Tests read the panel through `ctx.expose` (tests/e2e/hooks/pixel.js).
import { pixelState, createLive } from './state.js';
import { html } from './layout.js';
import { createInputs } from './inputs.js';
import { createRunner } from './schedule.js';
import { createPicture } from './picture.js';
import { attachGestures } from './gestures.js';
import { attachToolbar } from './toolbar.js';
import { createControls } from './controls.js';
import { attachExport } from './export.js';

function mount(el, ctx) {
  el.innerHTML = html;
  const q = (s) => el.querySelector(s);
  const statusEl = q('[data-testid=pixel-status]');
  const status = (text) => { statusEl.textContent = text; };
  const state = () => ctx.state();
  const live = createLive();

  const picture = createPicture(ctx, { q, live });
  const runner = createRunner(ctx, { q, live, picture, statusEl, status });
  attachGestures(ctx, { live, picture });
  const controls = createControls(ctx, q('form.params'));
  const inputs = createInputs(ctx, { el, q, status });
  const toolbar = attachToolbar(ctx, { el, q, live, picture, loadExample: inputs.loadExample });
  attachExport(ctx, { q, live });

  // For the e2e tests: the raw parts (tests/e2e/hooks/pixel.js reads them).
  ctx.expose({ state, live, runner });

  const inputsOf = (s) => [s.source, s.sheet, s.sprite, s.mask, s.strokes, s.params];
  return {
    render(s, prev) {
      if (!s) return;
      // The example the document is (none once your own source is in).
      for (const b of el.querySelectorAll('[data-example]')) b.setAttribute('aria-pressed', String(b.dataset.example === s.example));
      if (s.source !== live.sourceOf && s.source !== live.loadingFor) picture.loadSource(s);
      else if (live.sourceImg) {
        if (!prev || s.mask !== prev.mask) picture.drawMaskFull();
        if (!prev || s.strokes !== prev.strokes) picture.drawStrokes();
      }
      if (!prev || s.sheet !== prev.sheet || s.sprite !== prev.sprite) inputs.showElements(s);
      controls.sync(s.params);
      if (!prev || inputsOf(s).some((v, i) => v !== inputsOf(prev)[i])) runner.schedule();
    },
    keys: { s: () => toolbar.setMode('stroke'), m: () => toolbar.setMode('paint'), e: () => toolbar.setMode('erase') },
    unmount() {
      picture.canvas.destroy();
      inputs.detach();
      toolbar.detach();
      runner.abort();
    },
  };
}

export default { id: 'pixel', title: 'Pixel', state: pixelState, mount };
