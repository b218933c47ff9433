// "Micro": multiscale microstructures as implicit functions (MISSION M7,
// S8–S10). Pick a shipped scene or edit its JSON, and the core sphere-traces
// it in a worker (`micro-render`) or samples the field on a plane
// (`micro-slice`). Drag the image to orbit, wheel or +/− to zoom: the camera
// distance multiplies, so one zoom path goes from the macro- to the
// microscale with nothing precomputed. While a gesture runs the image is
// rendered at a quarter of its size; it is rendered at full size once the
// gesture pauses. A new render cancels the one before.
//
// With WebGL2 the interactive view runs on the GPU instead (www/micro-gl.js,
// a shader the core generates from the same scene, `micro-glsl`): every
// camera change draws a coarse frame at once (its size adapted to keep
// frames short), then, once the camera rests, finer frames and the full size
// in bands of rows. Slices, exports, views deeper than 32-bit floats resolve,
// and browsers without WebGL2 (said in plain words) use the CPU path.
//
// The document is {example, scene, camera, steps, view, z}; its schema is
// src/micro/state.rs. History, autosave, project files and links come from
// the document controller (document.js).
import { shippedExamples, shareByExample } from './examples.js';
import { createCodeEditor, preloadCodeEditor } from './code-editor.js';
import { download } from './project.js';
import { mountReconstruct } from './micro-fit.js';
import { MicroGl, unavailable, usable } from './micro-gl.js';

const RUN_DELAY_MS = 60;
const TYPING_DELAY_MS = 600;
const SHARP_DELAY_MS = 200;
const FULL_SIDE = 384; // full render, pixels a side (at most)
const PREVIEW_DIV = 4; // while dragging: 1/4 of the full side
const ZOOM_STEP = 1.5; // one + / − press multiplies the distance by this
const ORBIT_DEG_PER_PX = 0.4;
const GPU_REFINE_DELAY_MS = 120; // the camera rests this long before refining
const GPU_FRAME_MS = 30; // aim for frames (and refinement slices) this long
const GPU_MAX_DIV = 16;
const DEFAULT_CAMERA = { yaw: 35, pitch: 28, distance: 3.6, target: [0, 0, 0] };
const DISTANCE = [1e-6, 1e5];
const STEP_MODES = [
  ['fixed', 'Fixed steps'],
  ['bisection', 'Bisection'],
  ['adaptive', 'Adaptive'],
];

// Shipped scenes: fetched once per page.
const examples = shippedExamples('micro-examples');

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
        </span>
      </div>
      <div class="micro-viewport" data-testid="micro-viewport">
        <canvas data-testid="micro-canvas" tabindex="0" role="img" aria-label="microstructure: drag or arrow keys to orbit, wheel or + and − to zoom"></canvas>
      </div>
      <div class="status muted" data-testid="micro-status" aria-live="polite"></div>
      <div class="status muted" data-testid="micro-gpu-note" hidden></div>
    </section>
    <aside class="card micro-side">
      <h3>Scene</h3>
      <ul class="micro-examples" data-testid="micro-examples" aria-label="Shipped scenes"></ul>
      <details class="micro-program" open>
        <summary>Scene JSON</summary>
        <div class="micro-editor"></div>
      </details>
      <details class="micro-fit" data-testid="micro-fit"></details>
    </aside>
  </div>`;


const microState = {
  version: 1,
  async defaults(ctx) {
    const list = await examples(ctx.run);
    const ex = list.find((e) => e.name === 'gyroid') || list[0];
    return { example: ex.name, scene: ex.scene, camera: { ...DEFAULT_CAMERA, target: [...DEFAULT_CAMERA.target] }, steps: 'fixed', view: 'render', z: 0 };
  },
  migrate: (raw) => raw,
  fileName: (s) => s.example || 'micro',
  // A shipped scene travels by name.
  ...shareByExample(examples, 'scene', { tool: 'Micro', what: 'scene' }),
};

const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
const sameCamera = (a, b) => a === b || (a.yaw === b.yaw && a.pitch === b.pitch && a.distance === b.distance
  && a.target.every((v, i) => v === b.target[i]));
/** Whether documents a and b draw the same picture. */
const samePicture = (a, b) => a.scene === b.scene && a.steps === b.steps && a.view === b.view
  && (a.view === 'render' ? sameCamera(a.camera, b.camera) : a.z === b.z && sameCamera(a.camera, b.camera));

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
    }];
  }

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
      bitmap?.close?.();
      bitmap = bmp;
      last = { png, width: r.width, height: r.height, kind, preview: small, stats: r.stats, r, gpu: false };
      paint();
      ctx.clearError('run');
      editor?.clearError();
      const size = `${r.width}×${r.height}`;
      if (kind === 'micro-slice') {
        status(`slice z = ${doc.z}: ${size}, field from ${r.min.toPrecision(3)} to ${r.max.toPrecision(3)}, ${(r.inside * 100).toFixed(1)}% inside${small ? ' (preview)' : ''} in ${Math.round(ms)} ms`);
      } else {
        const s = r.stats;
        status(`${size}${small ? ' (preview)' : ''}, ${doc.steps} steps: ${s.hits.toLocaleString('en')} of ${s.rays.toLocaleString('en')} rays hit, `
          + `${s.steps.toLocaleString('en')} steps, ${s.sdf_evals.toLocaleString('en')} field evaluations`
          + `${s.gradient_checks ? `, ${s.gradient_checks.toLocaleString('en')} gradient checks` : ''}`
          + `${s.exhausted ? `, ${s.exhausted.toLocaleString('en')} rays out of steps` : ''} in ${Math.round(ms)} ms — zoom ×${(DEFAULT_CAMERA.distance / doc.camera.distance).toPrecision(3)}`);
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

  const shaderRequest = (doc) => ({ scene: doc.scene, steps: doc.steps, width: 16, height: 16 });
  const shaderKey = (doc) => JSON.stringify(shaderRequest(doc));

  /** Whether the GPU draws this document. */
  function onGpu(doc) {
    return !!gpu && !gpu.lost && doc.view === 'render' && !gpuFailed.has(shaderKey(doc)) && usable(doc.camera, fullSide());
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
    gpu.use(sh); // throws when the GPU cannot compile it
    return sh;
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
    try {
      await gpuShader(doc);
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
      r = gpu.draw(doc.camera, side, side);
    } catch (err) {
      gpuFallback(doc, err);
      return;
    }
    const ms = performance.now() - t;
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

  canvas.addEventListener('pointerdown', (e) => {
    if (e.button !== 0) return;
    canvas.setPointerCapture?.(e.pointerId);
    gesture = { x: e.clientX, y: e.clientY, id: e.pointerId };
  });
  canvas.addEventListener('pointermove', (e) => {
    if (!gesture || e.pointerId !== gesture.id) return;
    const dx = e.clientX - gesture.x, dy = e.clientY - gesture.y;
    if (!dx && !dy) return;
    gesture.x = e.clientX;
    gesture.y = e.clientY;
    gesture.moved = true;
    setCamera((c) => ({ yaw: c.yaw - dx * ORBIT_DEG_PER_PX, pitch: c.pitch + dy * ORBIT_DEG_PER_PX }), 'micro-orbit');
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
    if (orbit) {
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
      const side = FULL_SIDE * 2;
      const [kind, payload] = requestOf(doc, side);
      status('exporting PNG…');
      const r = await ctx.run(kind, payload);
      download(`${doc.example || 'micro'}-${doc.view}.png`, new Blob([r.png], { type: 'image/png' }));
      status(`exported PNG: ${r.width}×${r.height}`);
    } catch (err) {
      if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Export PNG' });
    }
  };

  // For tests and the console.
  const hooks = {
    state,
    last: () => (last ? { kind: last.kind, width: last.width, height: last.height, preview: last.preview, stats: last.stats, gpu: last.gpu } : null),
    pending: () => runTimer !== null || running !== null || typingTimer !== null || sharpTimer !== null || gpuJob !== null,
    gpu: () => (gpu && !gpu.lost ? { note: gpuNote.hidden ? null : gpuNote.textContent } : null),
  };
  window.filigreeMicro = hooks;

  return {
    render(s, prev) {
      if (!s) return;
      recon.render(s);
      if (editor && editor.getValue() !== s.scene && typingTimer === null) editor.setValue(s.scene);
      if (editor && prev && prev.scene !== s.scene) editor.clearError();
      stepsSel.value = s.steps;
      sliceBox.checked = s.view === 'slice';
      zInput.disabled = s.view !== 'slice';
      if (Number(zInput.value) !== s.z) zInput.value = String(s.z);
      zInput.nextElementSibling.textContent = s.z.toFixed(2);
      markExample(s);
      if (!prev || !samePicture(s, prev)) {
        if (onGpu(s)) { gpuRun(s); return; }
        const cameraOnly = prev && s.scene === prev.scene && s.steps === prev.steps && s.view === prev.view && s.z === prev.z;
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
      if (window.filigreeMicro === hooks) delete window.filigreeMicro;
    },
  };
}

export default { id: 'micro', title: 'Micro', state: microState, mount };
