// Fit's test hooks (a test page's init script, harness.mjs; never shipped).
// From the panel's raw parts (www/fit/panel.js: ctx.expose): the document,
// the program's facts (`pattern-info`), the loss plot, whether a fit runs,
// and the fit the panel shows (app/document.js DocJob).
(globalThis.__filigreeHookBuilders ??= {}).fit = ({ state, live, plot }) => ({
  state,
  info: () => live.info,
  plot,
  running: () => !!live.job?.running,
  job: () => live.job,
});
