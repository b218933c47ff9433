// "Micro": multiscale microstructures as implicit functions (MISSION M7,
// S8–S10). Pick a shipped scene or edit its JSON, and the core sphere-traces
// it in a worker (`micro-render`) or samples the field on a plane
// (`micro-slice`). Drag the image to orbit, shift-drag (or the middle
// button) to pan, wheel or +/− to zoom: the camera distance multiplies, so
// one zoom path goes from the macro- to the microscale with nothing
// precomputed. The "Parameters" list has a number field for every number
// of every node of the scene (an edit rewrites the JSON, like typing). While a gesture runs the image is
// rendered at a quarter of its size; it is rendered at full size once the
// gesture pauses. A new render cancels the one before.
//
// With WebGL2 the interactive view runs on the GPU instead (gl.js,
// a shader the core generates from the same scene, `micro-glsl`): every
// camera change draws a coarse frame at once (its size adapted to keep
// frames short), then, once the camera rests, finer frames and the full size
// in bands of rows. Slices, exports, views deeper than 32-bit floats resolve,
// and browsers without WebGL2 (said in plain words) use the CPU path.
//
// The CPU picture is rendered in tiles (`micro-render` with `tile`), one
// job per tile over the worker pool, each drawn as it arrives; a tile's
// pixels are bit for bit those of the one-job render. Path tracing (spp >
// 0, CPU only) runs in progressive passes of 1, 1, 2, 4, … samples per pixel
// (`sample_start`), each pass's summed radiance added in and the average
// shown with the pass count.
//
// The document is {example, scene, camera, steps, view, z, shading,
// roughness, specular, absorption, spp, max_depth} (version 2; version 1
// documents get the request's defaults); its schema is
// src/micro/state.rs. History, autosave, project files and links come from
// the document controller (app/document.js).
import { shippedExamples, shareByExample } from '../ui/examples.js';
import { createCodeEditor, preloadCodeEditor } from '../ui/code-editor.js';
import { download } from '../app/project.js';
import { mountReconstruct } from './fit.js';
import { MicroGl, unavailable, usable } from './gl.js';

const RUN_DELAY_MS = 60;
const TYPING_DELAY_MS = 600;
const SHARP_DELAY_MS = 200;
const FULL_SIDE = 384; // full render, pixels a side (at most)
const PREVIEW_DIV = 4; // while dragging: 1/4 of the full side
const ZOOM_STEP = 1.5; // one + / − press multiplies the distance by this
const ORBIT_DEG_PER_PX = 0.4;
const CAMERA_FOV = 40; // the request's default vertical field of view (degrees)
const PAN_KEY_PX = 20; // one shift+arrow press pans this many pixels
const TARGET = [-1e6, 1e6]; // the request's range for camera.target
const GPU_REFINE_DELAY_MS = 120; // the camera rests this long before refining
const GPU_FRAME_MS = 30; // aim for frames (and refinement slices) this long
const GPU_MAX_DIV = 16;
// A picture whose GPU work (shader compile, coarse frame, refinement) passes this is slow
// (a software GPU takes 20–110 s): the panel says so and offers the CPU renderer.
const SLOW_GPU_MS = 2000;
const RENDERER_KEY = 'filigree-micro-renderer'; // sessionStorage: 'cpu' | 'gpu' (the user's choice)
const DEFAULT_CAMERA = { yaw: 35, pitch: 28, distance: 3.6, target: [0, 0, 0] };
const DISTANCE = [1e-6, 1e5];
const TILE_GRID = 4; // the full CPU picture: TILE_GRID² tiles
const MAX_SCENE_BYTES = 256 * 1024; // the core's MAX_MICRO_SCENE_BYTES (src/core/limits.rs)
const PASS_MAX = 256; // most samples per pixel in one progressive pass
const SHADING_DEFAULTS = { shading: 'lambert', roughness: 0.35, specular: 0.04, absorption: 0, spp: 0, max_depth: 4 };
const SPP_CHOICES = [0, 4, 16, 64, 256, 1024];
const STEP_MODES = [
  ['fixed', 'Fixed steps'],
  ['bisection', 'Bisection'],
  ['adaptive', 'Adaptive'],
];

// Shipped scenes: fetched once per page, their JSON pretty-printed (two
// spaces, a key a line) so the editor shows one field a line; the numbers
// read back as the same numbers.
const shipped = shippedExamples('micro-examples');
let prettyOf = null; // {list: the core's list, pretty: the same, pretty-printed}
const prettyScene = (text) => {
  try { return JSON.stringify(JSON.parse(text), null, 2); } catch { return text; }
};
const examples = (run) => shipped(run).then((list) => {
  if (prettyOf?.list !== list) prettyOf = { list, pretty: list.map((ex) => ({ ...ex, scene: prettyScene(ex.scene) })) };
  return prettyOf.pretty;
});

const html = `
  <div class="micro-layout">
    <section class="card micro-stage" aria-label="Micro view">
      <div class="toolbar" role="toolbar" aria-label="Micro">
        <span class="group">
          <button type="button" data-act="zoom-out" aria-label="Zoom out" title="Zoom out (−)">−</button>
          <button type="button" data-act="zoom-reset" title="Back to the whole sample">Reset view</button>
          <button type="button" data-act="zoom-in" aria-label="Zoom in" title="Zoom in (+)">+</button>
        </span>
        <span class="group">
          <label class="inline">Steps <select name="steps" data-field="steps" data-testid="micro-steps"></select></label>
        </span>
        <span class="group">
          <label class="inline"><input type="checkbox" name="slice" data-field="view" data-testid="micro-slice-toggle"> Slice view</label>
          <label class="inline micro-z">z <input type="range" name="z" min="-1" max="1" step="0.01" data-field="z" data-testid="micro-z"><output></output></label>
        </span>
        <span class="group">
          <button type="button" data-act="export-png">Export PNG</button>
          <button type="button" data-act="export-json" data-testid="micro-export-json">Export scene JSON</button>
        </span>
      </div>
      <div class="toolbar micro-shading" role="group" aria-label="Shading">
        <span class="group">
          <label class="inline">Surface <select name="shading" data-field="shading" data-testid="micro-shading">
            <option value="lambert">Lambert</option><option value="ggx">GGX</option></select></label>
          <label class="inline" data-ggx>Roughness <input type="range" name="roughness" min="0.02" max="1" step="0.01" data-field="roughness" data-testid="micro-roughness"><output></output></label>
          <label class="inline" data-ggx>Specular <input type="range" name="specular" min="0" max="1" step="0.01" data-field="specular" data-testid="micro-specular"><output></output></label>
        </span>
        <span class="group">
          <label class="inline">Absorption <input type="range" name="absorption" min="0" max="5" step="0.05" data-field="absorption" data-testid="micro-absorption"><output></output></label>
        </span>
        <span class="group">
          <label class="inline">Path tracing <select name="spp" data-field="spp" data-testid="micro-spp"></select></label>
          <label class="inline">Max depth <input type="number" name="max_depth" min="1" max="64" step="1" data-field="max_depth" data-testid="micro-max-depth"></label>
        </span>
      </div>
      <div class="micro-viewport" data-testid="micro-viewport">
        <canvas data-testid="micro-canvas" tabindex="0" role="img" aria-label="microstructure: drag or arrow keys to orbit, shift-drag or shift-arrow keys to pan, wheel or + and − to zoom"></canvas>
      </div>
      <div class="status muted" data-testid="micro-status" aria-live="polite"></div>
      <div class="status muted" data-testid="micro-gpu-note" hidden></div>
      <div class="status muted" data-testid="micro-cpu-note" hidden></div>
      <div class="status micro-renderer" data-testid="micro-renderer" role="status" hidden>
        <span></span>
        <button type="button" data-act="use-cpu" hidden>Draw on the CPU</button>
        <button type="button" data-act="keep-gpu" hidden>Keep the GPU</button>
        <button type="button" data-act="use-gpu" hidden>Use the GPU again</button>
      </div>
    </section>
    <aside class="card micro-side">
      <h3>Scene</h3>
      <ul class="micro-examples" data-testid="micro-examples" aria-label="Shipped scenes"></ul>
      <details class="micro-params" data-testid="micro-params">
        <summary>Parameters</summary>
        <div class="micro-param-list"></div>
      </details>
      <details class="micro-fit" data-testid="micro-fit"></details>
    </aside>
    <section class="card micro-editor-card" aria-label="Scene JSON">
      <details class="micro-program" open>
        <summary>Scene JSON</summary>
        <div class="micro-editor"></div>
      </details>
    </section>
  </div>`;


const microState = {
  version: 2,
  async defaults(ctx) {
    const list = await examples(ctx.run);
    const ex = list.find((e) => e.name === 'gyroid') || list[0];
    return { example: ex.name, scene: ex.scene, camera: { ...DEFAULT_CAMERA, target: [...DEFAULT_CAMERA.target] }, steps: 'fixed', view: 'render', z: 0, ...SHADING_DEFAULTS };
  },
  // Version 1 had no shading fields: the request's defaults (what it drew).
  migrate: (raw, version) => (version < 2 && raw && typeof raw === 'object' && !Array.isArray(raw) ? { ...SHADING_DEFAULTS, ...raw } : raw),
  fileName: (s) => s.example || 'micro',
  // A shipped scene travels by name.
  ...shareByExample(examples, 'scene', { tool: 'Micro', what: 'scene' }),
};

const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
const sameCamera = (a, b) => a === b || (a.yaw === b.yaw && a.pitch === b.pitch && a.distance === b.distance
  && a.target.every((v, i) => v === b.target[i]));
/** Whether documents a and b draw the same picture. */
const sameShading = (a, b) => a.shading === b.shading && a.roughness === b.roughness && a.specular === b.specular
  && a.absorption === b.absorption && a.spp === b.spp && a.max_depth === b.max_depth;
const samePicture = (a, b) => a.scene === b.scene && a.steps === b.steps && a.view === b.view
  && (a.view === 'render' ? sameCamera(a.camera, b.camera) && sameShading(a, b) : a.z === b.z && sameCamera(a.camera, b.camera));
/** The shading fields of a `micro-render` request. */
const shadingOf = (doc) => ({
  shading: doc.shading ?? 'lambert', roughness: doc.roughness ?? 0.35, specular: doc.specular ?? 0.04, absorption: doc.absorption ?? 0,
});

/** TILE_GRID × TILE_GRID tiles covering a side × side image (fewer when it is tiny). */
export function tilesOf(side, grid = TILE_GRID) {
  const n = Math.max(1, Math.min(grid, side));
  const cut = (i) => Math.floor((side * i) / n);
  const out = [];
  for (let j = 0; j < n; j++) for (let i = 0; i < n; i++) out.push({ x: cut(i), y: cut(j), w: cut(i + 1) - cut(i), h: cut(j + 1) - cut(j) });
  return out;
}

/** Progressive passes for `spp` samples: [first sample, samples] of 1, 1, 2, 4, … (at most PASS_MAX). */
export function passesOf(spp) {
  const out = [];
  let start = 0;
  while (start < spp) {
    const n = Math.min(spp - start, Math.max(1, Math.min(start, PASS_MAX)));
    out.push([start, n]);
    start += n;
  }
  return out;
}

function mount(el, ctx) {
  el.innerHTML = html;
  preloadCodeEditor();
  const q = (s) => el.querySelector(s);
  const canvas = q('[data-testid=micro-canvas]');
  const g = canvas.getContext('2d');
  const viewport = q('.micro-viewport');
  const statusEl = q('[data-testid=micro-status]');
  const status = (t) => { statusEl.textContent = t; };
  const state = () => ctx.state();
  const recon = mountReconstruct(q('.micro-fit'), ctx);

  let running = null; // the AbortController of the request in flight
  let runTimer = null;
  let sharpTimer = null;
  let typingTimer = null;
  let gesture = null; // a drag in progress: {x, y, id}
  let last = null; // {png: Uint8Array, width, height, kind, preview, stats}
  let bitmap = null;

  // ---- the scene editor ----------------------------------------------------------------

  let editor = null;
  const editorReady = createCodeEditor(q('.micro-editor'), {
    language: 'json', label: 'scene JSON',
    attributes: { 'data-testid': 'micro-scene', 'data-field': 'scene' },
    onChange: () => {
      ctx.clearTimeout(typingTimer);
      typingTimer = ctx.setTimeout(applyEditor, TYPING_DELAY_MS);
    },
  }).then((ed) => {
    editor = ed;
    if (state()) ed.setValue(state().scene);
    return ed;
  });

  function applyEditor() {
    ctx.clearTimeout(typingTimer);
    typingTimer = null;
    const doc = state();
    if (!editor || !doc) return false;
    const text = editor.getValue();
    if (text === doc.scene) return false;
    ctx.commit({ ...doc, scene: text, example: null }, { coalesce: 'scene-typing' });
    return true;
  }

  // ---- running the core ---------------------------------------------------------------

  /** Pixels a side of the full image (the canvas's size on screen, capped). */
  function fullSide() {
    const dpr = window.devicePixelRatio || 1;
    const w = viewport.clientWidth || FULL_SIDE;
    return clamp(Math.round(w * dpr), 16, FULL_SIDE);
  }

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

  function requestOf(doc, side) {
    if (doc.view === 'slice') {
      // The slice looks at the camera's target; its half width follows the zoom.
      const half = doc.camera.distance / DEFAULT_CAMERA.distance;
      return ['micro-slice', { scene: doc.scene, z: doc.z, center: [doc.camera.target[0], doc.camera.target[1]], half, width: side, height: side }];
    }
    return ['micro-render', {
      scene: doc.scene, width: side, height: side, steps: doc.steps,
      camera: { yaw: doc.camera.yaw, pitch: doc.camera.pitch, distance: doc.camera.distance, target: doc.camera.target },
      ...shadingOf(doc), spp: doc.spp ?? 0, max_depth: doc.max_depth ?? 4,
    }];
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
    stopGpu();
    running?.abort();
    const ctrl = new AbortController();
    running = ctrl;
    const full = fullSide();
    const side = small ? Math.max(8, Math.round(full / PREVIEW_DIV)) : full;
    const [kind, payload] = requestOf(doc, side);
    noteCpu(doc);
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
      if (bitmap !== comp) bitmap?.close?.();
      bitmap = bmp;
      last = { png, width: r.width, height: r.height, kind, preview: small, stats: r.stats, r, gpu: false };
      paint();
      ctx.clearError('run');
      editor?.clearError();
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

  // ---- the CPU picture in tiles over the worker pool --------------------------------------

  const comp = document.createElement('canvas'); // the full picture, tile by tile
  const compG = comp.getContext('2d', { willReadFrequently: true });
  const tileCanvas = document.createElement('canvas');
  const tileG = tileCanvas.getContext('2d', { willReadFrequently: true });

  /** A tile's PNG as pixels (RGBA, row order). */
  async function pngPixels(bytes, w, h) {
    const bmp = await createImageBitmap(new Blob([bytes], { type: 'image/png' }), { premultiplyAlpha: 'none', colorSpaceConversion: 'none' });
    tileCanvas.width = w;
    tileCanvas.height = h;
    tileG.clearRect(0, 0, w, h);
    tileG.drawImage(bmp, 0, 0);
    bmp.close?.();
    return tileG.getImageData(0, 0, w, h).data;
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
    if (bitmap && bitmap !== comp) { if (resized) { comp.width = side; comp.height = side; } compG.imageSmoothingEnabled = true; compG.drawImage(bitmap, 0, 0, side, side); bitmap.close?.(); } else if (!bitmap || resized) {
      // The GPU drew straight on the canvas (or the size changed): start from what it shows.
      const shownNow = document.createElement('canvas');
      shownNow.width = canvas.width;
      shownNow.height = canvas.height;
      shownNow.getContext('2d').drawImage(canvas, 0, 0);
      comp.width = side;
      comp.height = side;
      compG.imageSmoothingEnabled = true;
      compG.drawImage(shownNow, 0, 0, side, side);
    }
    bitmap = comp;
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
            const rad = r.radiance instanceof Uint8Array ? r.radiance : new Uint8Array(r.radiance);
            const dv = new DataView(rad.buffer, rad.byteOffset, rad.byteLength);
            const k = 255 / total;
            for (let y = 0; y < t.h; y++) {
              for (let x = 0; x < t.w; x++) {
                const px = (t.y + y) * side + t.x + x;
                const src = ((y * t.w + x) * 3) * 4;
                for (let c = 0; c < 3; c++) {
                  const v = (acc[px * 3 + c] += dv.getFloat32(src + c * 4, true));
                  frame.data[px * 4 + c] = Math.min(255, Math.max(0, Math.round(v * k)));
                }
                frame.data[px * 4 + 3] = 255;
              }
            }
          } else {
            const png = r.png instanceof Uint8Array ? r.png : new Uint8Array(r.png);
            const px = await pngPixels(png, t.w, t.h);
            if (running !== ctrl || !ctx.alive()) return;
            for (let y = 0; y < t.h; y++) frame.data.set(px.subarray(y * t.w * 4, (y + 1) * t.w * 4), ((t.y + y) * side + t.x) * 4);
          }
          compG.putImageData(frame, 0, 0, t.x, t.y, t.w, t.h);
          if (bitmap === comp) paint();
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
      last = { width: side, height: side, kind: 'micro-render', preview: false, stats, gpu: false, tiles: tiles.length, passes: passes.length, frame };
      ctx.clearError('run');
      editor?.clearError();
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

  // ---- the GPU view ----------------------------------------------------------------------

  const gpuNote = q('[data-testid=micro-gpu-note]');
  const noteGpu = (t) => { gpuNote.hidden = !t; gpuNote.textContent = t || ''; };
  let gpu = null;
  {
    const why = unavailable();
    if (why) noteGpu(`GPU view off: ${why}; the pictures are drawn on the CPU (slower).`);
    else {
      try { gpu = new MicroGl(); } catch (err) { noteGpu(`GPU view off: ${err.message}; the pictures are drawn on the CPU (slower).`); }
    }
  }
  const shaders = new Map(); // shader request JSON → Promise<response>
  const gpuFailed = new Map(); // shader request JSON → message
  let gpuJob = null; // {doc, token, ...} the GPU frame sequence in flight
  let gpuToken = 0;
  let gpuFrame = 0; // requestAnimationFrame id
  let gpuTimer = null;
  let gpuDiv = PREVIEW_DIV; // coarse frames: 1/gpuDiv of the full side
  let msPerPixel = 0; // measured
  const scratch = document.createElement('canvas');

  const shaderRequest = (doc) => ({ scene: doc.scene, steps: doc.steps, width: 16, height: 16, ...shadingOf(doc) });
  const shaderKey = (doc) => JSON.stringify(shaderRequest(doc));

  /** Whether the GPU draws this document. */
  function onGpu(doc) {
    return !!gpu && !gpu.lost && choice !== 'cpu' && doc.view === 'render' && !(doc.spp > 0) && !gpuFailed.has(shaderKey(doc)) && usable(doc.camera, fullSide());
  }

  // ---- the slow-GPU guard: the user may choose the CPU renderer -------------------------
  //
  // A picture whose GPU time passes `slowGpuMs` (SLOW_GPU_MS; a test hook sets it
  // lower) is said to be slow in the status, with an offer of the CPU renderer (the
  // tiled `micro-render` path). The choice holds for the tab's session, reloads
  // included (sessionStorage; the panel's memory where storage is blocked), and
  // "Use the GPU again" undoes it.
  const rendererEl = q('[data-testid=micro-renderer]');
  let slowGpuMs = SLOW_GPU_MS;
  let slowOffer = null; // the GPU time (ms) of the slow picture while the offer is shown
  const readChoice = () => {
    try { return sessionStorage.getItem(RENDERER_KEY); } catch { return ctx.memory.renderer ?? null; }
  };
  const writeChoice = (v) => {
    ctx.memory.renderer = v;
    try { sessionStorage.setItem(RENDERER_KEY, v); } catch { /* blocked storage: the panel's memory holds it */ }
  };
  let choice = readChoice(); // 'cpu', 'gpu' (the GPU kept: no more offers) or null

  function showRenderer() {
    const say = (text, acts) => {
      rendererEl.hidden = !text;
      rendererEl.querySelector('span').textContent = text;
      for (const b of rendererEl.querySelectorAll('button')) b.hidden = !acts.includes(b.dataset.act);
    };
    if (!gpu || gpu.lost) say('', []);
    else if (choice === 'cpu') say('Drawn on the CPU, as you chose (the GPU was slow here).', ['use-gpu']);
    else if (slowOffer !== null) {
      say(`The GPU is slow here: this picture took ${(slowOffer / 1000).toFixed(1)} s of GPU work (a software renderer?), `
        + 'and the page waits while it draws. The CPU renderer draws in tiles over the workers and may be faster.', ['use-cpu', 'keep-gpu']);
    } else say('', []);
  }

  /** After a slice of GPU work for `job`: offer the CPU once the picture has taken too long. */
  function guardSlow(job, ms) {
    job.gpuMs = (job.gpuMs || 0) + ms;
    if (choice || slowOffer !== null || job.gpuMs <= slowGpuMs) return;
    slowOffer = job.gpuMs;
    showRenderer();
  }

  function chooseRenderer(v) {
    choice = v;
    slowOffer = null;
    writeChoice(v);
    showRenderer();
    const doc = state();
    if (!doc) return;
    if (onGpu(doc)) gpuRun(doc);
    else if (v === 'cpu') { stopGpu(); run(false); }
  }
  rendererEl.querySelector('[data-act=use-cpu]').onclick = () => chooseRenderer('cpu');
  rendererEl.querySelector('[data-act=keep-gpu]').onclick = () => { choice = 'gpu'; slowOffer = null; writeChoice('gpu'); showRenderer(); };
  rendererEl.querySelector('[data-act=use-gpu]').onclick = () => chooseRenderer('gpu');
  showRenderer();

  /** Say why a render is drawn on the CPU although the GPU view is on. */
  const cpuNote = q('[data-testid=micro-cpu-note]');
  function noteCpu(doc) {
    let why = null;
    if (gpu && !gpu.lost && doc.view === 'render') {
      if (doc.spp > 0) why = 'path tracing runs on the CPU only';
      else if (gpuFailed.has(shaderKey(doc))) why = 'the GPU cannot draw this scene';
      else if (!usable(doc.camera, fullSide())) why = 'this zoom is deeper than the GPU’s 32-bit floats resolve';
    }
    cpuNote.hidden = !why;
    cpuNote.textContent = why ? `Drawn on the CPU (in tiles over the workers): ${why}.` : '';
  }

  function stopGpu() {
    gpuToken++;
    gpuJob = null;
    if (gpuFrame) cancelAnimationFrame(gpuFrame);
    gpuFrame = 0;
    ctx.clearTimeout(gpuTimer);
    gpuTimer = null;
  }

  /** Draw `doc` on the GPU: a coarse frame in the next animation frame, refined once it rests. */
  function gpuRun(doc) {
    running?.abort();
    running = null;
    ctx.clearTimeout(runTimer);
    runTimer = null;
    stopGpu();
    noteCpu(doc);
    const token = gpuToken;
    gpuJob = { doc, token, t0: performance.now() };
    gpuFrame = requestAnimationFrame(() => { gpuFrame = 0; gpuCoarse(token); });
  }

  async function gpuShader(doc) {
    const key = shaderKey(doc);
    if (!shaders.has(key)) {
      if (shaders.size > 8) shaders.clear();
      const p = ctx.run('micro-glsl', shaderRequest(doc));
      shaders.set(key, p);
      p.catch(() => shaders.delete(key));
    }
    const sh = await shaders.get(key);
    const t = performance.now();
    gpu.use(sh); // throws when the GPU cannot compile it (at once when it is the one in use)
    return performance.now() - t;
  }

  /** The GPU could not draw: say why (a compile failure) and draw on the CPU. */
  function gpuFallback(doc, err) {
    stopGpu();
    // A compile failure, or numbers beyond 32-bit floats (the CPU still draws those).
    if (err && (!err.kind || /32-bit/.test(err.message || ''))) {
      gpuFailed.set(shaderKey(doc), err.message);
      noteGpu(`GPU view off for this scene: ${err.message}; drawing on the CPU.`);
    }
    run(false);
  }

  function paintRows(rgba, w, y0, rows) {
    const side = fullSide();
    if (canvas.width !== side || canvas.height !== side) { canvas.width = side; canvas.height = side; }
    g.putImageData(new ImageData(rgba, w, rows), 0, y0);
  }

  async function gpuCoarse(token) {
    const job = gpuJob;
    if (!job || job.token !== token) return;
    const doc = job.doc;
    let compileMs;
    try {
      compileMs = await gpuShader(doc);
    } catch (err) {
      if (gpuJob?.token === token) gpuFallback(doc, err);
      return;
    }
    if (gpuJob?.token !== token || !ctx.alive()) return;
    const full = fullSide();
    const side = Math.max(8, Math.round(full / gpuDiv));
    let r;
    const t = performance.now();
    try {
      // A full-size frame is the final picture: it needs its counters too.
      r = gpu.draw(doc.camera, side, side, { stats: side >= full });
    } catch (err) {
      gpuFallback(doc, err);
      return;
    }
    const ms = performance.now() - t;
    guardSlow(job, compileMs + ms);
    msPerPixel = ms / (side * side);
    // Keep the next coarse frame near GPU_FRAME_MS.
    if (ms > GPU_FRAME_MS && gpuDiv < GPU_MAX_DIV) gpuDiv *= 2;
    else if (ms < GPU_FRAME_MS / 4 && gpuDiv > 1) gpuDiv /= 2;
    scratch.width = side;
    scratch.height = side;
    scratch.getContext('2d').putImageData(new ImageData(r.rgba, side, side), 0, 0);
    if (canvas.width !== full || canvas.height !== full) { canvas.width = full; canvas.height = full; }
    g.imageSmoothingEnabled = true;
    g.drawImage(scratch, 0, 0, full, full);
    bitmap?.close?.();
    bitmap = null;
    last = { kind: 'micro-render', width: side, height: side, preview: side < full, stats: null, gpu: true };
    status(`${side}×${side} (preview, GPU) in ${Math.round(ms)} ms`);
    statusEl.dataset.previews = String(Number(statusEl.dataset.previews || 0) + 1);
    ctx.clearError('run');
    editor?.clearError();
    if (side >= full) { gpuDone(job, r.stats, ms, full); return; }
    // Refine once the camera rests.
    gpuTimer = ctx.setTimeout(() => {
      gpuTimer = null;
      if (gpuJob?.token !== token) return;
      job.y = 0;
      job.stats = null;
      job.ms = 0;
      gpuFrame = requestAnimationFrame(() => { gpuFrame = 0; gpuRefine(token); });
    }, gesture ? GPU_REFINE_DELAY_MS * 2 : GPU_REFINE_DELAY_MS);
  }

  /** One slice of rows of the full-size picture per animation frame. */
  function gpuRefine(token) {
    const job = gpuJob;
    if (!job || job.token !== token || !ctx.alive()) return;
    const full = fullSide();
    const rows = clamp(Math.floor(GPU_FRAME_MS / Math.max(msPerPixel, 1e-6) / full), 1, full - job.y);
    const t = performance.now();
    let r;
    try {
      r = gpu.draw(job.doc.camera, full, full, { y0: job.y, y1: job.y + rows, stats: true });
    } catch (err) {
      gpuFallback(job.doc, err);
      return;
    }
    const ms = performance.now() - t;
    guardSlow(job, ms);
    msPerPixel = 0.5 * msPerPixel + 0.5 * ms / (rows * full);
    job.ms += ms;
    paintRows(r.rgba, full, job.y, rows);
    job.stats = addStats(job.stats, r.stats);
    job.y += rows;
    if (job.y < full) {
      status(`refining on the GPU: ${Math.round((job.y / full) * 100)}%`);
      gpuFrame = requestAnimationFrame(() => { gpuFrame = 0; gpuRefine(token); });
      return;
    }
    gpuDone(job, job.stats, job.ms, full);
  }

  function gpuDone(job, stats, ms, full) {
    const doc = job.doc;
    gpuJob = null;
    last = { kind: 'micro-render', width: full, height: full, preview: false, stats, gpu: true };
    const s = stats;
    status(`${full}×${full} on the GPU, ${doc.steps} steps: ${s.hits.toLocaleString('en')} of ${s.rays.toLocaleString('en')} rays hit, `
      + `${s.steps.toLocaleString('en')} steps (${(s.steps / s.rays).toFixed(1)} per ray), ${s.sdf_evals.toLocaleString('en')} field evaluations`
      + `${s.gradient_checks ? `, ${s.gradient_checks.toLocaleString('en')} gradient checks` : ''}`
      + `${s.exhausted ? `, ${s.exhausted.toLocaleString('en')} rays out of steps` : ''} in ${Math.round(ms)} ms of GPU frames — zoom ×${(DEFAULT_CAMERA.distance / doc.camera.distance).toPrecision(3)}`);
    statusEl.dataset.runs = String(Number(statusEl.dataset.runs || 0) + 1);
  }

  function addStats(a, b) {
    if (!a) return { ...b };
    for (const k of Object.keys(b)) a[k] += b[k];
    return a;
  }

  function markSceneError(err) {
    if (err?.field !== 'scene' && err?.kind !== 'syntax') return false;
    const m = /line (\d+), column (\d+)/.exec(err.message || '');
    const at = Number.isInteger(err.line) ? [err.line, err.column ?? 1] : m && [Number(m[1]), Number(m[2])];
    q('details.micro-program').open = true;
    editorReady.then((ed) => ctx.alive() && ed.markError(at ? at[0] : 1, at ? at[1] : 1, err.message));
    return true;
  }

  // ---- drawing --------------------------------------------------------------------------

  function paint() {
    const side = fullSide();
    if (canvas.width !== side || canvas.height !== side) { canvas.width = side; canvas.height = side; }
    g.fillStyle = '#181a1e';
    g.fillRect(0, 0, side, side);
    if (!bitmap) return;
    g.imageSmoothingEnabled = true;
    g.drawImage(bitmap, 0, 0, side, side);
  }
  const ro = new ResizeObserver(() => {
    if (bitmap) paint();
    else if (last?.gpu && state() && onGpu(state()) && canvas.width !== fullSide()) gpuRun(state());
  });
  ro.observe(viewport);

  // ---- orbit and zoom -------------------------------------------------------------------

  function setCamera(change, coalesce) {
    const doc = state();
    if (!doc) return;
    const c = doc.camera;
    const next = { ...c, ...change(c) };
    next.pitch = clamp(next.pitch, -89, 89);
    next.distance = clamp(next.distance, DISTANCE[0], DISTANCE[1]);
    next.yaw = ((next.yaw % 360) + 360) % 360;
    if (sameCamera(next, c)) return;
    ctx.commit({ ...doc, camera: next }, { coalesce });
  }

  const zoomBy = (f, coalesce = 'micro-zoom') => setCamera((c) => ({ distance: c.distance / f }), coalesce);

  /**
   * Pan: move the target by (dx, dy) screen pixels in the view plane, so the
   * picture follows the pointer (the orbit camera's right and up vectors, as
   * src/micro/render.rs builds them).
   */
  function panBy(dx, dy, coalesce) {
    setCamera((c) => {
      const [yaw, pitch] = [c.yaw * Math.PI / 180, c.pitch * Math.PI / 180];
      const dir = [Math.cos(pitch) * Math.cos(yaw), Math.cos(pitch) * Math.sin(yaw), Math.sin(pitch)];
      const fwd = dir.map((v) => -v);
      let right = [fwd[1], -fwd[0], 0]; // fwd × z
      const n = Math.hypot(right[0], right[1]);
      right = n < 1e-9 ? [1, 0, 0] : [right[0] / n, right[1] / n, 0];
      const up = [right[1] * fwd[2] - right[2] * fwd[1], right[2] * fwd[0] - right[0] * fwd[2], right[0] * fwd[1] - right[1] * fwd[0]];
      const perPx = (2 * c.distance * Math.tan((CAMERA_FOV * Math.PI) / 360)) / Math.max(1, canvas.clientHeight || canvas.height);
      const target = c.target.map((v, i) => clamp(v + (-dx * right[i] + dy * up[i]) * perPx, TARGET[0], TARGET[1]));
      return { target };
    }, coalesce);
  }

  canvas.addEventListener('pointerdown', (e) => {
    if (e.button !== 0 && e.button !== 1) return;
    if (e.button === 1) e.preventDefault();
    canvas.setPointerCapture?.(e.pointerId);
    gesture = { x: e.clientX, y: e.clientY, id: e.pointerId, pan: e.shiftKey || e.button === 1 };
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!gesture || e.pointerId !== gesture.id) return;
    const dx = e.clientX - gesture.x, dy = e.clientY - gesture.y;
    if (!dx && !dy) return;
    gesture.x = e.clientX;
    gesture.y = e.clientY;
    gesture.moved = true;
    if (gesture.pan) panBy(dx, dy, 'micro-pan');
    else setCamera((c) => ({ yaw: c.yaw - dx * ORBIT_DEG_PER_PX, pitch: c.pitch + dy * ORBIT_DEG_PER_PX }), 'micro-orbit');
  });
  const endGesture = (e) => {
    if (!gesture || e.pointerId !== gesture.id) return;
    const moved = gesture.moved;
    gesture = null;
    ctx.seal();
    if (moved && !(state() && onGpu(state()))) { ctx.clearTimeout(sharpTimer); sharpTimer = null; run(false); }
  };
  canvas.addEventListener('pointerup', endGesture);
  canvas.addEventListener('pointercancel', endGesture);
  canvas.addEventListener('wheel', (e) => {
    e.preventDefault();
    const f = Math.exp(-clamp(e.deltaY, -300, 300) * 0.002);
    zoomBy(f, 'micro-wheel');
  }, { passive: false });
  canvas.addEventListener('keydown', (e) => {
    const orbit = { ArrowLeft: [-10, 0], ArrowRight: [10, 0], ArrowUp: [0, -10], ArrowDown: [0, 10] }[e.key];
    if (orbit && e.shiftKey) {
      e.preventDefault();
      panBy(-orbit[0] / 10 * PAN_KEY_PX, -orbit[1] / 10 * PAN_KEY_PX, 'micro-keys-pan');
    } else if (orbit) {
      e.preventDefault();
      setCamera((c) => ({ yaw: c.yaw - orbit[0] * ORBIT_DEG_PER_PX, pitch: c.pitch + orbit[1] * ORBIT_DEG_PER_PX }), 'micro-keys');
    } else if (e.key === '+' || e.key === '=') { e.preventDefault(); zoomBy(ZOOM_STEP); } else if (e.key === '-') { e.preventDefault(); zoomBy(1 / ZOOM_STEP); }
  });
  q('[data-act=zoom-in]').onclick = () => zoomBy(ZOOM_STEP, null);
  q('[data-act=zoom-out]').onclick = () => zoomBy(1 / ZOOM_STEP, null);
  q('[data-act=zoom-reset]').onclick = () => setCamera(() => ({ ...DEFAULT_CAMERA, target: [...DEFAULT_CAMERA.target] }), null);

  // ---- settings -------------------------------------------------------------------------

  const stepsSel = q('[name=steps]');
  for (const [v, label] of STEP_MODES) {
    const o = document.createElement('option');
    o.value = v;
    o.textContent = label;
    stepsSel.append(o);
  }
  stepsSel.onchange = () => { const doc = state(); if (doc) ctx.commit({ ...doc, steps: stepsSel.value }); };
  const sliceBox = q('[name=slice]');
  sliceBox.onchange = () => { const doc = state(); if (doc) ctx.commit({ ...doc, view: sliceBox.checked ? 'slice' : 'render' }); };
  const zInput = q('[name=z]');
  zInput.oninput = () => { const doc = state(); if (doc) ctx.commit({ ...doc, z: Number(zInput.value) }, { coalesce: 'micro-z' }); };
  zInput.onchange = () => ctx.seal();

  const shadingSel = q('[name=shading]');
  const sppSel = q('[name=spp]');
  const depthInput = q('[name=max_depth]');
  const sliders = ['roughness', 'specular', 'absorption'].map((k) => q(`[name=${k}]`));
  const sppLabel = (n) => (n ? `${n} samples per pixel` : 'off (direct shading)');
  const sppOptions = (cur) => {
    const want = [...new Set([...SPP_CHOICES, cur])].sort((a, b) => a - b);
    if (sppSel.options.length === want.length && [...sppSel.options].every((o, i) => Number(o.value) === want[i])) return;
    sppSel.replaceChildren(...want.map((n) => { const o = document.createElement('option'); o.value = String(n); o.textContent = sppLabel(n); return o; }));
  };
  sppOptions(0);
  const commitField = (k, v, coalesce) => { const doc = state(); if (doc && doc[k] !== v) ctx.commit({ ...doc, [k]: v }, coalesce ? { coalesce } : undefined); };
  shadingSel.onchange = () => commitField('shading', shadingSel.value);
  sppSel.onchange = () => commitField('spp', Number(sppSel.value));
  depthInput.onchange = () => {
    const v = Math.round(Number(depthInput.value));
    if (Number.isFinite(v)) commitField('max_depth', clamp(v, 1, 64));
    else depthInput.value = String(state()?.max_depth ?? 4);
  };
  for (const el of sliders) {
    el.oninput = () => commitField(el.name, Number(el.value), `micro-${el.name}`);
    el.onchange = () => ctx.seal();
  }

  // ---- scene picker -------------------------------------------------------------------

  const list = q('[data-testid=micro-examples]');
  examples(ctx.run).then((exs) => {
    if (!ctx.alive()) return;
    list.replaceChildren(...exs.map((ex) => {
      const li = document.createElement('li');
      const b = document.createElement('button');
      b.type = 'button';
      b.className = 'micro-example';
      b.dataset.example = ex.name;
      b.title = ex.about;
      b.textContent = ex.name;
      b.onclick = () => loadExample(ex);
      li.append(b);
      return li;
    }));
    markExample(state());
  }).catch((err) => ctx.error(err, { prefix: 'The shipped scenes' }));

  function markExample(s) {
    for (const b of list.querySelectorAll('[data-example]')) b.setAttribute('aria-pressed', String(b.dataset.example === s?.example));
  }

  function loadExample(ex) {
    const doc = state();
    if (!doc) return;
    ctx.clearTimeout(typingTimer);
    typingTimer = null;
    ctx.commit({ ...doc, example: ex.name, scene: ex.scene });
  }

  // ---- export ----------------------------------------------------------------------------

  q('[data-act=export-png]').onclick = async () => {
    const doc = state();
    if (!doc) return;
    try {
      // Always the full-size picture of the current document.
      // (Path tracing at the panel's size: samples × pixels are bounded.)
      const side = doc.view === 'render' && doc.spp > 0 ? FULL_SIDE : FULL_SIDE * 2;
      const [kind, payload] = requestOf(doc, side);
      status('exporting PNG…');
      const r = await ctx.run(kind, payload);
      download(`${doc.example || 'micro'}-${doc.view}.png`, new Blob([r.png], { type: 'image/png' }));
      status(`exported PNG: ${r.width}×${r.height}`);
    } catch (err) {
      if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Export PNG' });
    }
  };

  q('[data-act=export-json]').onclick = () => {
    const doc = state();
    if (!doc) return;
    download(`${doc.example || 'micro'}.json`, doc.scene, 'application/json');
    status('exported the scene JSON');
  };

  // ---- parameters: a number field for every number of every node --------------------

  const paramList = q('.micro-param-list');
  let paramScene = null; // the scene text the fields show
  const NODE_KEYS = new Set(['children', 'child', 'base', 'minus']);

  /** Every node of a parsed scene: {path (JSON pointer), type, fields: [{pointer, label, value}]}. */
  function nodesOf(root) {
    const out = [];
    const visit = (node, ptr) => {
      if (!node || typeof node !== 'object' || Array.isArray(node)) return;
      const fields = [];
      const leaves = (v, p, label) => {
        if (typeof v === 'number') fields.push({ pointer: p, label, value: v });
        else if (Array.isArray(v)) v.forEach((x, i) => leaves(x, `${p}/${i}`, `${label}[${i}]`));
        else if (v && typeof v === 'object') for (const [k, x] of Object.entries(v)) leaves(x, `${p}/${k}`, label ? `${label}.${k}` : k);
      };
      for (const [k, v] of Object.entries(node)) {
        if (NODE_KEYS.has(k)) continue;
        leaves(v, `${ptr}/${k}`, k);
      }
      out.push({ path: ptr || '/', type: String(node.type ?? '?'), fields });
      for (const k of NODE_KEYS) {
        const v = node[k];
        if (Array.isArray(v)) v.forEach((c, i) => visit(c, `${ptr}/${k}/${i}`));
        else if (v) visit(v, `${ptr}/${k}`);
      }
    };
    visit(root, '');
    return out;
  }

  function setPointer(root, pointer, value) {
    const keys = pointer.split('/').slice(1);
    let o = root;
    for (const k of keys.slice(0, -1)) o = o[k];
    o[keys[keys.length - 1]] = value;
  }

  function renderParams(doc) {
    if (doc.scene === paramScene) return;
    paramScene = doc.scene;
    let root;
    try { root = JSON.parse(doc.scene); } catch {
      paramList.replaceChildren(Object.assign(document.createElement('p'), { className: 'muted', textContent: 'The scene JSON does not parse; fix it in the editor.' }));
      return;
    }
    paramList.replaceChildren(...nodesOf(root).map((n) => {
      const fs = document.createElement('fieldset');
      fs.className = 'micro-node';
      fs.dataset.node = n.path;
      const legend = document.createElement('legend');
      legend.textContent = `${n.type}${n.path === '/' ? '' : ` (${n.path})`}`;
      fs.append(legend);
      for (const f of n.fields) {
        const label = document.createElement('label');
        label.className = 'inline';
        const input = document.createElement('input');
        input.type = 'number';
        input.step = 'any';
        input.value = String(f.value);
        input.dataset.pointer = f.pointer;
        input.onchange = () => {
          const v = Number(input.value);
          const cur = state();
          if (!cur || input.value.trim() === '' || !Number.isFinite(v)) { input.value = String(f.value); return; }
          let obj;
          try { obj = JSON.parse(cur.scene); } catch { return; }
          setPointer(obj, f.pointer, v);
          ctx.commit({ ...cur, scene: JSON.stringify(obj, null, 2), example: null });
        };
        label.append(`${f.label} `, input);
        fs.append(label);
      }
      return fs;
    }));
  }

  // For the e2e tests (ctx.expose).
  const hooks = {
    state,
    last: () => (last ? { kind: last.kind, width: last.width, height: last.height, preview: last.preview, stats: last.stats, gpu: last.gpu, tiles: last.tiles ?? 1, passes: last.passes ?? 1 } : null),
    /** The `micro-render` request of the full picture now (what the tiles split). */
    request: () => (state() ? requestOf(state(), fullSide())[1] : null),
    /** The last tiled CPU picture's pixels (RGBA) as base64, for tests. */
    frame: () => {
      const d = last?.frame?.data;
      if (!d) return null;
      let bin = '';
      for (let i = 0; i < d.length; i += 0x8000) bin += String.fromCharCode.apply(null, d.subarray(i, i + 0x8000));
      return btoa(bin);
    },
    pending: () => runTimer !== null || running !== null || typingTimer !== null || sharpTimer !== null || gpuJob !== null,
    gpu: () => (gpu && !gpu.lost ? { note: gpuNote.hidden ? null : gpuNote.textContent } : null),
    /** Coarse GPU frames at 1/n of the full side (1: what a fast GPU reaches). */
    gpuPreviewDiv: (n) => { gpuDiv = n; },
    /** The slow-GPU guard's threshold (ms of GPU work for one picture); SLOW_GPU_MS by default. */
    slowGpuMs: (ms) => { slowGpuMs = ms; },
  };
  ctx.expose(hooks);

  /**
   * A scene JSON file dropped anywhere in the window (document.js: view.drop):
   * read and traced once by the core (a 2×2 picture) before it replaces the
   * scene; a file the core refuses leaves the document as it is.
   */
  async function dropScene(file) {
    if (!/\.json$/i.test(file.name) && !/\bjson\b/i.test(file.type)) {
      throw new Error('Micro opens scene JSON files (like Export scene JSON writes) and Filigree projects');
    }
    if (file.size > MAX_SCENE_BYTES) throw new Error(`it is ${Math.ceil(file.size / 1024)} KB, more than a scene may be (${MAX_SCENE_BYTES / 1024} KB)`);
    const text = await file.text();
    try { JSON.parse(text); } catch (err) { throw new Error(`it is not JSON (${err.message})`); }
    const doc = state();
    if (!doc) throw new Error('the panel is still loading');
    const [kind, payload] = requestOf({ ...doc, scene: text, view: 'render', spp: 0 }, 2);
    await ctx.run(kind, payload);
    const now = state();
    if (!now || !ctx.alive()) return;
    ctx.clearTimeout(typingTimer);
    typingTimer = null;
    ctx.commit({ ...now, scene: prettyScene(text), example: null });
    status(`opened the scene ${file.name}`);
  }

  return {
    drop: dropScene,
    render(s, prev) {
      if (!s) return;
      recon.render(s);
      renderParams(s);
      if (editor && editor.getValue() !== s.scene && typingTimer === null) editor.setValue(s.scene);
      if (editor && prev && prev.scene !== s.scene) editor.clearError();
      stepsSel.value = s.steps;
      sliceBox.checked = s.view === 'slice';
      zInput.disabled = s.view !== 'slice';
      if (Number(zInput.value) !== s.z) zInput.value = String(s.z);
      zInput.nextElementSibling.textContent = s.z.toFixed(2);
      shadingSel.value = s.shading;
      for (const el of sliders) {
        if (Number(el.value) !== s[el.name]) el.value = String(s[el.name]);
        el.nextElementSibling.textContent = String(s[el.name]);
      }
      for (const l of el.querySelectorAll('[data-ggx]')) l.hidden = s.shading !== 'ggx';
      sppOptions(s.spp);
      sppSel.value = String(s.spp);
      depthInput.value = String(s.max_depth);
      depthInput.disabled = !(s.spp > 0);
      markExample(s);
      if (!prev || !samePicture(s, prev)) {
        if (onGpu(s)) { gpuRun(s); return; }
        const cameraOnly = prev && s.scene === prev.scene && s.steps === prev.steps && s.view === prev.view && s.z === prev.z && sameShading(s, prev);
        if (cameraOnly && gesture) preview();
        else scheduleRun();
      }
    },
    markError(err) { markSceneError(err); },
    keys: {
      '+': () => zoomBy(ZOOM_STEP, null),
      '=': () => zoomBy(ZOOM_STEP, null),
      '-': () => zoomBy(1 / ZOOM_STEP, null),
    },
    unmount() {
      recon.unmount();
      ro.disconnect();
      running?.abort();
      stopGpu();
      bitmap?.close?.();
    },
  };
}

export default { id: 'micro', title: 'Micro', state: microState, mount };
