// Micro's slow-GPU guard: the user may choose the CPU renderer. A picture
// whose GPU time passes `tune.slowGpuMs` (SLOW_GPU_MS; a test sets it
// lower) is said to be slow in the status, with an offer of the CPU
// renderer (the tiled `micro-render` path). The choice holds for the tab's
// session, reloads included (sessionStorage; the panel's memory where
// storage is blocked), and "Use the GPU again" undoes it.

// A picture whose GPU work (shader compile, coarse frame, refinement) passes this is slow
// (a software GPU takes 20–110 s): the panel says so and offers the CPU renderer.
const SLOW_GPU_MS = 2000;
const RENDERER_KEY = 'filigree-micro-renderer'; // sessionStorage: 'cpu' | 'gpu' (the user's choice)

/**
 * The guard of a mounted panel: `gpuOn()` whether the GPU view is on,
 * `onChoose(v)` redraws after the user chose 'cpu' or 'gpu'.
 */
export function createRendererChoice(ctx, { q, gpuOn, onChoose }) {
  const rendererEl = q('[data-testid=micro-renderer]');
  const tune = { slowGpuMs: SLOW_GPU_MS };
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
    if (!gpuOn()) say('', []);
    else if (choice === 'cpu') say('Drawn on the CPU, as you chose (the GPU was slow here).', ['use-gpu']);
    else if (slowOffer !== null) {
      say(`The GPU is slow here: this picture took ${(slowOffer / 1000).toFixed(1)} s of GPU work (a software renderer?), `
        + 'and the page waits while it draws. The CPU renderer draws in tiles over the workers and may be faster.', ['use-cpu', 'keep-gpu']);
    } else say('', []);
  }

  /** After a slice of GPU work for `job`: offer the CPU once the picture has taken too long. */
  function guardSlow(job, ms) {
    job.gpuMs = (job.gpuMs || 0) + ms;
    if (choice || slowOffer !== null || job.gpuMs <= tune.slowGpuMs) return;
    slowOffer = job.gpuMs;
    showRenderer();
  }

  function chooseRenderer(v) {
    choice = v;
    slowOffer = null;
    writeChoice(v);
    showRenderer();
    onChoose(v);
  }
  rendererEl.querySelector('[data-act=use-cpu]').onclick = () => chooseRenderer('cpu');
  rendererEl.querySelector('[data-act=keep-gpu]').onclick = () => { choice = 'gpu'; slowOffer = null; writeChoice('gpu'); showRenderer(); };
  rendererEl.querySelector('[data-act=use-gpu]').onclick = () => chooseRenderer('gpu');
  showRenderer();

  return {
    /** 'cpu', 'gpu' (the GPU kept: no more offers) or null. */
    choice: () => choice,
    guardSlow,
    tune,
  };
}
