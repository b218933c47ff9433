// Fit's markup: the program (generator, sliders), the target with the
// pattern's overlay, the fit (settings, run, loss plot, results, export),
// the program text.
import { TARGET_SIZE } from './state.js';

export const html = `
  <div class="fit-layout">
    <section class="card fit-program" aria-label="Pattern program">
      <label class="inline">Generator <select name="generator" data-testid="fit-generator" data-field="generator"></select></label>
      <div class="muted program-facts" data-testid="fit-facts"></div>
      <button type="button" class="link" data-act="show-program" aria-controls="fit-program-text">Edit the program ↓</button>
      <h3>Parameters</h3>
      <form class="sliders" data-testid="fit-sliders"></form>
      <div class="row-buttons">
        <button type="button" data-act="make-target">Make target from these values</button>
      </div>
    </section>
    <section class="card fit-target" aria-label="Target">
      <div class="toolbar">
        <span class="swatches-inline" role="radiogroup" aria-label="Brush colour" data-testid="fit-brush-colours"></span>
        <label class="inline">size <input type="number" name="brush" min="1" max="64" value="12"></label>
        <button type="button" data-act="clear-target">Clear</button>
      </div>
      <p class="fit-legend muted">Solid: the target. <span class="fit-key">Pink outlines</span>: the pattern of the current values.</p>
      <div class="stack checker">
        <canvas class="target" width="${TARGET_SIZE}" height="${TARGET_SIZE}" data-testid="fit-target" aria-label="target: draw here, or drop an image"></canvas>
        <canvas class="overlay" width="${TARGET_SIZE}" height="${TARGET_SIZE}" data-testid="fit-overlay" aria-hidden="true"></canvas>
      </div>
      <label class="inline">overlay <input type="range" name="overlay" min="0" max="1" step="0.05" value="0.6"></label>
    </section>
    <section class="card fit-run" aria-label="Fitting">
      <div class="fit-settings">
        <label class="inline">Budget <select name="budget" data-field="settings.budget"><option value="quick">quick</option><option value="paper">paper</option></select></label>
        <label class="inline">Loss <select name="loss" data-field="settings.loss">
          <option value="sdf">SDF (paper)</option><option value="l1">L1</option>
          <option value="pyramid">Gaussian pyramid</option><option value="image">image L2</option></select></label>
        <label class="inline">Seed <input type="number" name="seed" min="0" value="1" data-field="settings.seed"></label>
      </div>
      <div class="row-buttons">
        <button type="button" class="primary" data-act="fit" aria-describedby="fit-why">Run fit</button>
        <button type="button" data-act="cancel" disabled title="Stop the fit; its best values so far can then be applied">Stop</button>
        <button type="button" data-act="apply-fit" data-testid="fit-apply" disabled title="Put the stopped fit's best values so far into the document">Apply fitted values</button>
      </div>
      <p class="fit-why" id="fit-why" data-testid="fit-why" hidden></p>
      <progress max="1" value="0"></progress>
      <div class="status muted" data-testid="fit-status" aria-live="polite"></div>
      <canvas class="plot" data-testid="fit-plot" aria-label="loss plot"></canvas>
      <table class="results" data-testid="fit-results"><thead><tr><th>parameter</th><th>fitted</th><th>truth</th></tr></thead><tbody></tbody></table>
      <div class="row-buttons">
        <button type="button" data-act="export-svg">Export SVG</button>
        <button type="button" data-act="export-json">Export JSON</button>
      </div>
    </section>
    <section class="card fit-editor" id="fit-program-text" aria-label="Program text">
      <details class="program">
        <summary>Program</summary>
        <div class="program-editor"></div>
        <div class="row-buttons"><button type="button" data-act="apply-program">Apply program</button></div>
      </details>
    </section>
  </div>`;
