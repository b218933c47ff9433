// "Micro": multiscale microstructures as implicit functions (MISSION M7,
// S8–S10). Pick a shipped scene or edit its JSON, and the core sphere-traces
// it in a worker (`micro-render`) or samples the field on a plane
// (`micro-slice`). Drag the image to orbit, shift-drag (or the middle
// button) to pan, wheel or +/− to zoom. The "Parameters" list has a number
// field for every number of every node of the scene (an edit rewrites the
// JSON, like typing). While a gesture runs the image is rendered at a
// quarter of its size; it is rendered at full size once the gesture
// pauses. A new render cancels the one before. With WebGL2 the interactive
// view runs on the GPU instead.
//
// This file wires the panel's parts together; each is one module here:
//   state.js     the document (schema: src/micro/state.rs), its request, what is derived (`live`)
//   layout.js    the markup
//   editor.js    the scene JSON editor
//   schedule.js  when the CPU draws: previews, one job, or tiles over the pool (tiles.js)
//   gpu-view.js  the GPU view (gl.js: WebGL2), and its slow-GPU guard (renderer.js)
//   picture.js   the canvas and its CPU picture
//   gestures.js  orbit, pan and zoom
//   settings.js  steps, slice view, shading and path tracing
//   scenes.js    the shipped scenes
//   params.js    a number field for every number of the scene
//   export.js, drop.js  files out and in
//   fit.js       the "Reconstruct" section
// Tests read the panel through `ctx.expose` (tests/e2e/hooks/micro.js).
import { preloadCodeEditor } from '../ui/code-editor.js';
import { microState, createLive, requestOf, samePicture, sameShading } from './state.js';
import { html } from './layout.js';
import { createSceneEditor } from './editor.js';
import { createRunner } from './schedule.js';
import { createGpuView } from './gpu-view.js';
import { createPicture } from './picture.js';
import { attachGestures } from './gestures.js';
import { createSettings } from './settings.js';
import { createScenePicker } from './scenes.js';
import { createParams } from './params.js';
import { attachExport } from './export.js';
import { createDrop } from './drop.js';
import { mountReconstruct } from './fit.js';

function mount(el, ctx) {
  el.innerHTML = html;
  preloadCodeEditor();
  const q = (s) => el.querySelector(s);
  const statusEl = q('[data-testid=micro-status]');
  const status = (t) => { statusEl.textContent = t; };
  const state = () => ctx.state();
  const live = createLive();
  const recon = mountReconstruct(q('.micro-fit'), ctx);

  // The parts; the GPU view and the CPU runner call each other back (through arrows, once both are made).
  const editor = createSceneEditor(ctx, { q });
  const picture = createPicture({
    q, live,
    // A resize without a CPU picture: the GPU draws the new size.
    onResize() {
      const s = state();
      if (live.last?.gpu && s && gpu.onGpu(s) && picture.canvas.width !== picture.fullSide()) gpu.run(s);
    },
  });
  const gpu = createGpuView(ctx, { q, live, picture, editor, statusEl, status, cpu: () => runner });
  const runner = createRunner(ctx, { live, picture, gpu, editor, statusEl, status });
  const gestures = attachGestures(ctx, { q, canvas: picture.canvas, live, runner, gpu });
  const settings = createSettings(ctx, { root: el, q });
  const scenes = createScenePicker(ctx, { q, editor });
  const params = createParams(ctx, { q });
  attachExport(ctx, { q, status });

  // For the e2e tests: the raw parts (tests/e2e/hooks/micro.js reads them).
  ctx.expose({ state, live, runner, editor, gpu, picture, requestOf });

  return {
    drop: createDrop(ctx, { editor, status }),
    render(s, prev) {
      if (!s) return;
      recon.render(s);
      params.render(s);
      editor.render(s, prev);
      settings.render(s);
      scenes.mark(s);
      if (!prev || !samePicture(s, prev)) {
        if (gpu.onGpu(s)) { gpu.run(s); return; }
        const cameraOnly = prev && s.scene === prev.scene && s.steps === prev.steps && s.view === prev.view && s.z === prev.z && sameShading(s, prev);
        if (cameraOnly && live.gesture) runner.preview();
        else runner.schedule();
      }
    },
    markError(err) { editor.markError(err); },
    keys: {
      '+': gestures.zoomIn,
      '=': gestures.zoomIn,
      '-': gestures.zoomOut,
    },
    unmount() {
      recon.unmount();
      picture.detach();
      runner.abort();
      gpu.stop();
      live.bitmap?.close?.();
    },
  };
}

export default { id: 'micro', title: 'Micro', state: microState, mount };
