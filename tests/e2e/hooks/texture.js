// Texture's test hooks (a test page's init script, harness.mjs; never
// shipped). From the panel's raw parts (www/texture/panel.js: ctx.expose):
// the document, whether a retrieval, an analysis or a render is due or
// going, and whether the index loaded.
(globalThis.__filigreeHookBuilders ??= {}).texture = ({ state, live, runner, view }) => ({
  state,
  pending: () => runner.pending() || view.rendering(),
  indexOk: () => live.indexOk,
});
