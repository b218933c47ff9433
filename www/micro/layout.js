// The Micro panel's markup: the view (toolbar, shading, the canvas and its
// notes), the side (shipped scenes, parameters, reconstruction) and the
// scene JSON editor.

export const html = `
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
          <button type="button" data-act="export-json" data-testid="micro-export-json">Export scene JSON</button>
        </span>
      </div>
      <div class="toolbar micro-shading" role="group" aria-label="Shading">
        <span class="group">
          <label class="inline">Surface <select name="shading" data-field="shading" data-testid="micro-shading">
            <option value="lambert">Lambert</option><option value="ggx">GGX</option></select></label>
          <label class="inline" data-ggx>Roughness <input type="range" name="roughness" min="0.02" max="1" step="0.01" data-field="roughness" data-testid="micro-roughness"><output></output></label>
          <label class="inline" data-ggx>Specular <input type="range" name="specular" min="0" max="1" step="0.01" data-field="specular" data-testid="micro-specular"><output></output></label>
        </span>
        <span class="group">
          <label class="inline">Absorption <input type="range" name="absorption" min="0" max="5" step="0.05" data-field="absorption" data-testid="micro-absorption"><output></output></label>
        </span>
        <span class="group">
          <label class="inline">Path tracing <select name="spp" data-field="spp" data-testid="micro-spp"></select></label>
          <label class="inline">Max depth <input type="number" name="max_depth" min="1" max="64" step="1" data-field="max_depth" data-testid="micro-max-depth"></label>
        </span>
      </div>
      <div class="micro-viewport" data-testid="micro-viewport">
        <canvas data-testid="micro-canvas" tabindex="0" role="img" aria-label="microstructure: drag or arrow keys to orbit, shift-drag or shift-arrow keys to pan, wheel or + and − to zoom"></canvas>
      </div>
      <div class="status muted" data-testid="micro-status" aria-live="polite"></div>
      <div class="status muted" data-testid="micro-gpu-note" hidden></div>
      <div class="status muted" data-testid="micro-cpu-note" hidden></div>
      <div class="status micro-renderer" data-testid="micro-renderer" role="status" hidden>
        <span></span>
        <button type="button" data-act="use-cpu" hidden>Draw on the CPU</button>
        <button type="button" data-act="keep-gpu" hidden>Keep the GPU</button>
        <button type="button" data-act="use-gpu" hidden>Use the GPU again</button>
      </div>
    </section>
    <aside class="card micro-side">
      <h3>Scene</h3>
      <ul class="micro-examples" data-testid="micro-examples" aria-label="Shipped scenes"></ul>
      <details class="micro-params" data-testid="micro-params">
        <summary>Parameters</summary>
        <div class="micro-param-list"></div>
      </details>
      <details class="micro-fit" data-testid="micro-fit"></details>
    </aside>
    <section class="card micro-editor-card" aria-label="Scene JSON">
      <details class="micro-program" open>
        <summary>Scene JSON</summary>
        <div class="micro-editor"></div>
      </details>
    </section>
  </div>`;
