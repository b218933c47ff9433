// The Pixel panel's markup: the stage (toolbar, layer toggles, the viewport
// the picture goes in, the figures of the last run) and the side panel
// (input files, the parameter form controls.js fills, export).

export const html = `
  <div class="pixel-layout">
    <div class="card pixel-stage">
      <div class="toolbar" role="toolbar" aria-label="Pixel tools">
        <span class="group">
          <button type="button" data-example="fish" aria-pressed="false">Fish example</button>
          <button type="button" data-example="trunk" aria-pressed="false">Trunk example</button>
        </span>
        <span class="group" role="radiogroup" aria-label="Brush">
          <button type="button" data-mode="stroke" role="radio" aria-checked="true" title="Draw orientation strokes (S)">✎ Strokes</button>
          <button type="button" data-mode="paint" role="radio" aria-checked="false" title="Paint the mask (M)">▣ Paint mask</button>
          <button type="button" data-mode="erase" role="radio" aria-checked="false" title="Erase the mask (E)">▢ Erase mask</button>
        </span>
        <label class="inline">size <input type="number" name="brush" min="1" max="32" value="3"></label>
        <span class="group">
          <button type="button" data-act="zoom-out" aria-label="Zoom out">−</button>
          <span class="zoom" data-testid="zoom">×4</span>
          <button type="button" data-act="zoom-in" aria-label="Zoom in">+</button>
        </span>
        <span class="group">
          <button type="button" data-act="clear-strokes">Clear strokes</button>
        </span>
      </div>
      <div class="toggles">
        <label><input type="checkbox" name="show-result" checked> result</label>
        <label><input type="checkbox" name="show-mask"> mask</label>
        <label><input type="checkbox" name="show-strokes" checked> strokes</label>
        <label><input type="checkbox" name="show-arrows"> vector field</label>
        <span class="status muted" data-testid="pixel-status" aria-live="polite"></span>
      </div>
      <div class="viewport checker" data-testid="pixel-viewport">
        <div class="empty muted">Load an example, or drop a source image here.</div>
      </div>
      <dl class="stats" data-testid="pixel-stats"></dl>
    </div>
    <aside class="card pixel-side">
      <h3>Inputs</h3>
      <div class="inputs">
        <label>Source <input type="file" accept="image/*" data-input="source" data-field="source"></label>
        <label>Mask <input type="file" accept="image/*" data-input="mask" data-field="mask"></label>
        <label>Element sheet (3×3) <input type="file" accept="image/*" data-input="sheet" data-field="sheet"></label>
        <label>…or one sprite <input type="file" accept="image/*" data-input="sprite" data-field="sprite"></label>
        <div class="elements"><canvas class="sheet-preview pixelated" aria-label="elements"></canvas><span class="muted" data-field="elements"></span></div>
      </div>
      <h3>Parameters</h3>
      <form class="params" data-testid="pixel-params"></form>
      <h3>Export</h3>
      <div class="exports">
        <label class="inline">PNG scale <select name="export-scale"><option>1</option><option>2</option><option selected>4</option><option>8</option></select></label>
        <button type="button" data-act="export-png">Export PNG</button>
      </div>
    </aside>
  </div>`;
