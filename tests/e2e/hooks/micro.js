// Micro's test hooks and its Reconstruct section's (a test page's init
// script, harness.mjs; never shipped). From the panels' raw parts
// (www/micro/panel.js and www/micro/fit.js: ctx.expose).
(globalThis.__filigreeHookBuilders ??= {}).micro = ({ state, live, runner, editor, gpu, picture, requestOf }) => ({
  state,
  /** What the canvas shows: kind, size, preview or not, counters, GPU or not, tiles and passes. */
  last() {
    const last = live.last;
    return last ? { kind: last.kind, width: last.width, height: last.height, preview: last.preview, stats: last.stats, gpu: last.gpu, tiles: last.tiles ?? 1, passes: last.passes ?? 1 } : null;
  },
  /** The `micro-render` request of the full picture now (what the tiles split). */
  request: () => (state() ? requestOf(state(), picture.fullSide())[1] : null),
  /** The last tiled CPU picture's pixels (RGBA) as base64. */
  frame() {
    const d = live.last?.frame?.data;
    if (!d) return null;
    let bin = '';
    for (let i = 0; i < d.length; i += 0x8000) bin += String.fromCharCode.apply(null, d.subarray(i, i + 0x8000));
    return btoa(bin);
  },
  /** Whether a run, a typed change or a GPU frame sequence is due or under way. */
  pending: () => runner.pending() || editor.typing() || gpu.busy(),
  gpu: () => (gpu.on() ? { note: gpu.note() } : null),
  /** Coarse GPU frames at 1/n of the full side (1: what a fast GPU reaches). */
  gpuPreviewDiv: (n) => { gpu.tune.gpuDiv = n; },
  /** The slow-GPU guard's threshold (ms of GPU work for one picture). */
  slowGpuMs: (ms) => { gpu.renderer.tune.slowGpuMs = ms; },
});

globalThis.__filigreeHookBuilders['micro-fit'] = ({ rows, job, running, plot, request }) => ({
  rows: () => rows().map((r) => ({ pointer: r.pointer, value: r.value })),
  result: () => (job()?.status === 'done' ? { scene: job().result.scene, values: job().result.values } : null),
  running,
  job,
  plotted: () => plot.points.length,
  request: () => request(),
});
