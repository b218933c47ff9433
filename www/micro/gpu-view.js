// Micro's GPU view: with WebGL2 the interactive view runs on the GPU (gl.js,
// a shader the core generates from the same scene, `micro-glsl`): every
// camera change draws a coarse frame at once (its size adapted to keep
// frames short), then, once the camera rests, finer frames and the full
// size in bands of rows. Slices, exports, path tracing, views deeper than
// 32-bit floats resolve, and browsers without WebGL2 (said in plain words)
// use the CPU path (schedule.js); so does a slow GPU when the user says so
// (renderer.js).
import { MicroGl, unavailable, usable } from './gl.js';
import { DEFAULT_CAMERA, shadingOf, clamp } from './state.js';
import { PREVIEW_DIV } from './picture.js';
import { addStats } from './tiles.js';
import { createRendererChoice } from './renderer.js';

const GPU_REFINE_DELAY_MS = 120; // the camera rests this long before refining
const GPU_FRAME_MS = 30; // aim for frames (and refinement slices) this long
const GPU_MAX_DIV = 16;

/**
 * The GPU view of a mounted panel: it paints on `picture` (picture.js) and
 * tells `live` (state.js) what it shows; `cpu()` is the CPU runner
 * (schedule.js), which draws what the GPU does not.
 */
export function createGpuView(ctx, { q, live, picture, editor, statusEl, status, cpu }) {
  const state = () => ctx.state();
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
  const tune = { gpuDiv: PREVIEW_DIV }; // coarse frames: 1/gpuDiv of the full side
  let msPerPixel = 0; // measured
  const scratch = document.createElement('canvas');

  const shaderRequest = (doc) => ({ scene: doc.scene, steps: doc.steps, width: 16, height: 16, ...shadingOf(doc) });
  const shaderKey = (doc) => JSON.stringify(shaderRequest(doc));

  /** Whether the GPU draws this document. */
  function onGpu(doc) {
    return !!gpu && !gpu.lost && renderer.choice() !== 'cpu' && doc.view === 'render' && !(doc.spp > 0) && !gpuFailed.has(shaderKey(doc)) && usable(doc.camera, picture.fullSide());
  }

  const renderer = createRendererChoice(ctx, {
    q,
    gpuOn: () => !!gpu && !gpu.lost,
    onChoose(v) {
      const doc = state();
      if (!doc) return;
      if (onGpu(doc)) gpuRun(doc);
      else if (v === 'cpu') { stopGpu(); cpu().run(false); }
    },
  });

  /** Say why a render is drawn on the CPU although the GPU view is on. */
  const cpuNote = q('[data-testid=micro-cpu-note]');
  function noteCpu(doc) {
    let why = null;
    if (gpu && !gpu.lost && doc.view === 'render') {
      if (doc.spp > 0) why = 'path tracing runs on the CPU only';
      else if (gpuFailed.has(shaderKey(doc))) why = 'the GPU cannot draw this scene';
      else if (!usable(doc.camera, picture.fullSide())) why = 'this zoom is deeper than the GPU’s 32-bit floats resolve';
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
    cpu().cancel();
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
    // A compile failure (not a job's error), or a scene the GPU cannot
    // draw that the CPU can (numbers beyond 32-bit floats).
    if (err && (!err.kind || err.kind === 'unsupported')) {
      gpuFailed.set(shaderKey(doc), err.message);
      noteGpu(`GPU view off for this scene: ${err.message}; drawing on the CPU.`);
    }
    cpu().run(false);
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
    const full = picture.fullSide();
    const side = Math.max(8, Math.round(full / tune.gpuDiv));
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
    renderer.guardSlow(job, compileMs + ms);
    msPerPixel = ms / (side * side);
    // Keep the next coarse frame near GPU_FRAME_MS.
    if (ms > GPU_FRAME_MS && tune.gpuDiv < GPU_MAX_DIV) tune.gpuDiv *= 2;
    else if (ms < GPU_FRAME_MS / 4 && tune.gpuDiv > 1) tune.gpuDiv /= 2;
    scratch.width = side;
    scratch.height = side;
    scratch.getContext('2d').putImageData(new ImageData(r.rgba, side, side), 0, 0);
    const { canvas, g } = picture;
    if (canvas.width !== full || canvas.height !== full) { canvas.width = full; canvas.height = full; }
    g.imageSmoothingEnabled = true;
    g.drawImage(scratch, 0, 0, full, full);
    live.bitmap?.close?.();
    live.bitmap = null;
    live.last = { kind: 'micro-render', width: side, height: side, preview: side < full, stats: null, gpu: true };
    status(`${side}×${side} (preview, GPU) in ${Math.round(ms)} ms`);
    statusEl.dataset.previews = String(Number(statusEl.dataset.previews || 0) + 1);
    ctx.clearError('run');
    editor.clearError();
    if (side >= full) { gpuDone(job, r.stats, ms, full); return; }
    // Refine once the camera rests.
    gpuTimer = ctx.setTimeout(() => {
      gpuTimer = null;
      if (gpuJob?.token !== token) return;
      job.y = 0;
      job.stats = null;
      job.ms = 0;
      gpuFrame = requestAnimationFrame(() => { gpuFrame = 0; gpuRefine(token); });
    }, live.gesture ? GPU_REFINE_DELAY_MS * 2 : GPU_REFINE_DELAY_MS);
  }

  /** One slice of rows of the full-size picture per animation frame. */
  function gpuRefine(token) {
    const job = gpuJob;
    if (!job || job.token !== token || !ctx.alive()) return;
    const full = picture.fullSide();
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
    renderer.guardSlow(job, ms);
    msPerPixel = 0.5 * msPerPixel + 0.5 * ms / (rows * full);
    job.ms += ms;
    picture.paintRows(r.rgba, full, job.y, rows);
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
    live.last = { kind: 'micro-render', width: full, height: full, preview: false, stats, gpu: true };
    const s = stats;
    status(`${full}×${full} on the GPU, ${doc.steps} steps: ${s.hits.toLocaleString('en')} of ${s.rays.toLocaleString('en')} rays hit, `
      + `${s.steps.toLocaleString('en')} steps (${(s.steps / s.rays).toFixed(1)} per ray), ${s.sdf_evals.toLocaleString('en')} field evaluations`
      + `${s.gradient_checks ? `, ${s.gradient_checks.toLocaleString('en')} gradient checks` : ''}`
      + `${s.exhausted ? `, ${s.exhausted.toLocaleString('en')} rays out of steps` : ''} in ${Math.round(ms)} ms of GPU frames — zoom ×${(DEFAULT_CAMERA.distance / doc.camera.distance).toPrecision(3)}`);
    statusEl.dataset.runs = String(Number(statusEl.dataset.runs || 0) + 1);
  }

  return {
    onGpu,
    run: gpuRun,
    stop: stopGpu,
    noteCpu,
    /** Whether a GPU frame sequence is under way. */
    busy: () => gpuJob !== null,
    /** Whether the GPU view is on (WebGL2, not lost). */
    on: () => !!gpu && !gpu.lost,
    /** Why the GPU view is off, or null. */
    note: () => (gpuNote.hidden ? null : gpuNote.textContent),
    /** `gpuDiv`: coarse frames at 1/gpuDiv of the full side. */
    tune,
    /** The slow-GPU guard (renderer.js; `renderer.tune.slowGpuMs` its threshold). */
    renderer,
  };
}
