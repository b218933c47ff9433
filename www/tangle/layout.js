// The Tangle panel's markup: the stage (tool bar, canvas, drawing bar, step
// slider, status) and the side column (selected step, step list, grammar,
// start, ink, export). The panel's parts find their elements in it by
// data-act, data-testid and name.

export const html = `
  <div class="tangle-layout">
    <section class="card tangle-stage" aria-label="Tangle drawing">
      <div class="toolbar" role="toolbar" aria-label="Tangle">
        <span class="group">
          <button type="button" class="primary" data-act="generate" title="Grow the tangle from the grammar (Ctrl+Enter in the editor)">Generate</button>
          <button type="button" data-act="cancel" disabled>Cancel</button>
        </span>
        <span class="group">
          <label class="inline">Seed <input type="number" name="seed" min="0" step="1" data-field="seed" data-testid="tangle-seed"></label>
          <button type="button" data-act="new-seed" title="New seed" aria-label="New seed">⟳</button>
        </span>
        <span class="group">
          <button type="button" data-act="zoom-out" aria-label="Zoom out">−</button>
          <button type="button" data-act="zoom-fit" title="Fit the drawing">Fit</button>
          <button type="button" data-act="zoom-in" aria-label="Zoom in">+</button>
        </span>
      </div>
      <div class="tangle-viewport" data-testid="tangle-viewport">
        <canvas data-testid="tangle-canvas" role="img" aria-label="tangle drawing: click a shape to select the step that made it; drag to pan, wheel to zoom"></canvas>
        <div class="tangle-draw-bar" hidden>
          <span>Click to add points (<span data-testid="tangle-draw-count">0</span>)</span>
          <button type="button" class="primary" data-act="draw-finish">Use this polygon</button>
          <button type="button" data-act="draw-cancel">Cancel</button>
        </div>
      </div>
      <div class="tangle-steps">
        <button type="button" data-act="play" aria-label="Play the growth" title="Play / pause">▶</button>
        <input type="range" name="step" min="0" max="0" value="0" step="1" aria-label="Step in the history" data-testid="tangle-step">
        <output class="tangle-count" data-testid="tangle-count" aria-live="polite">—</output>
      </div>
      <div class="status muted" data-testid="tangle-status" aria-live="polite"></div>
    </section>
    <aside class="card tangle-side">
      <h3>Selected step</h3>
      <div class="tangle-selected muted" data-testid="tangle-selected">Click a shape to select the step that made it; click it again to go further back.</div>
      <form class="tangle-params" data-testid="tangle-params"></form>
      <h3 id="tangle-steps-title">Steps</h3>
      <ol class="tangle-step-list" role="listbox" tabindex="0" aria-labelledby="tangle-steps-title" data-testid="tangle-step-list"
        title="Arrow keys, Home and End choose a step; Escape deselects"></ol>
      <div class="row-buttons">
        <button type="button" data-act="reexpand" disabled title="Undo this step and everything grown from it, and expand it again with a new random draw">Re-expand</button>
        <button type="button" data-act="select-back" disabled title="The step that made this step's shapes">◂ Earlier step</button>
        <button type="button" data-act="select-none" disabled>Deselect</button>
      </div>
      <h3>Grammar</h3>
      <ul class="tangle-examples" data-testid="tangle-examples" aria-label="Shipped grammars"></ul>
      <details class="tangle-program" open>
        <summary>Grammar text</summary>
        <div class="tangle-editor"></div>
        <div class="row-buttons">
          <button type="button" data-act="draw-curve" title="Draw a polyline on the canvas; it is added to the grammar as a curve for regularSplit">Draw a curve</button>
          <button type="button" data-act="draw-shape" title="Draw a closed outline on the canvas; it is added to the grammar as a shape for place">Draw a shape</button>
        </div>
      </details>
      <h3>Start from</h3>
      <div class="tangle-start">
        <select name="start-kind" data-field="start" aria-label="Start from"></select>
        <span class="tangle-start-rect" hidden>
          <label class="inline">w <input type="number" name="start-width" min="1" max="1000000" value="800" data-field="start.width"></label>
          <label class="inline">h <input type="number" name="start-height" min="1" max="1000000" value="600" data-field="start.height"></label>
        </span>
        <span class="tangle-start-text" hidden>
          <input type="text" name="start-text" maxlength="200" value="Tangle" aria-label="Word" data-field="start.text">
          <label class="inline">height <input type="number" name="start-text-height" min="1" max="1000000" value="300"></label>
        </span>
        <span class="tangle-start-svg" hidden>
          <input type="file" accept=".svg,image/svg+xml" name="start-svg" aria-label="SVG file" data-field="start.svg"
            title="What the file draws: shapes inside shapes become holes, overlapping shapes one shape, white fills holes; scaled to the grammar's start size">
        </span>
        <span class="tangle-start-polygon" hidden>
          <button type="button" data-act="draw-start">Draw a polygon</button>
        </span>
      </div>
      <h3>Ink</h3>
      <div class="tangle-ink">
        <label>Wobble <input type="range" name="wobble" min="0" max="10" step="0.1" data-field="wobble"><output></output></label>
        <label>Pen width <input type="range" name="stroke_width" min="0" max="6" step="0.1" data-field="stroke_width"><output></output></label>
      </div>
      <h3>Export</h3>
      <div class="row-buttons">
        <button type="button" data-act="export-svg">Export SVG</button>
        <label class="inline">PNG <select name="png-width"><option>800</option><option selected>1600</option><option>3200</option></select> px</label>
        <button type="button" data-act="export-png">Export PNG</button>
      </div>
    </aside>
  </div>`;
