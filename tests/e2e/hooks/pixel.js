// Pixel's test hooks (a test page's init script, harness.mjs; never shipped).
// From the panel's raw parts (www/pixel/panel.js: ctx.expose): the document,
// the last result, and whether a run is due or going (or the source is
// being decoded).
(globalThis.__filigreeHookBuilders ??= {}).pixel = ({ state, live, runner }) => ({
  state,
  result: () => live.result,
  pending: () => runner.pending() || live.sourceLoading !== null,
});
