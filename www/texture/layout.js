// The Texture panel's markup: the example (drop zone, model to render, the
// prediction), the retrieved texture (view, chart of the scales, export)
// and the controls (the twelve scale sliders, the retrieved parameters).

export const html = `
  <div class="texture-layout">
    <section class="card texture-example" aria-label="Example">
      <h3>Example</h3>
      <div class="texture-drop drop-zone-lite" data-testid="texture-drop">
        <canvas data-testid="texture-example" role="img" aria-label="the example texture" width="256" height="256"></canvas>
        <p class="muted">Drop or paste an image here, or</p>
      </div>
      <div class="texture-pick-model">
        <label class="inline">Model <select name="example-model" data-testid="texture-model-select"></select></label>
        <button type="button" data-act="render-example">Render as example</button>
      </div>
      <p class="texture-predicted" data-testid="texture-predicted" aria-live="polite"></p>
      <ol class="texture-top" data-testid="texture-top" aria-label="Likeliest models"></ol>
    </section>
    <section class="card texture-result" aria-label="Retrieved texture">
      <div class="toolbar" role="toolbar" aria-label="Texture">
        <label class="inline"><input type="checkbox" name="tile" data-testid="texture-tile"> Tile 2×2</label>
        <button type="button" data-act="export-png">Export PNG</button>
        <button type="button" data-act="export-json">Export JSON</button>
      </div>
      <div class="texture-view"><canvas data-testid="texture-canvas" role="img" aria-label="the retrieved texture"></canvas></div>
      <p class="texture-retrieved muted" data-testid="texture-retrieved" aria-live="polite"></p>
      <canvas class="texture-chart" data-testid="texture-chart" role="img" aria-label="requested and retrieved scales"></canvas>
      <p class="muted texture-legend"><span class="key req"></span> requested <span class="key got"></span> retrieved <span data-testid="texture-cosine"></span></p>
    </section>
    <section class="card texture-controls" aria-label="Perceptual scales">
      <h3>Perceptual scales</h3>
      <p class="muted texture-note" data-testid="texture-estimates-note">These are computational estimates from image measures, not human ratings (a ratings file replaces them when the index is built).</p>
      <div class="sliders texture-sliders" data-testid="texture-sliders"></div>
      <label class="inline texture-same"><input type="checkbox" name="same-model" data-field="sameModel" data-testid="texture-same-model"> Stay within the predicted model</label>
      <details class="texture-params" data-testid="texture-params" open>
        <summary>Parameters</summary>
        <div class="texture-param-list"></div>
      </details>
      <div class="status muted" data-testid="texture-status" aria-live="polite"></div>
    </section>
  </div>`;
