// The markup of Micro's "Reconstruct" section (fit.js).

export const html = `
  <summary>Reconstruct</summary>
  <p class="muted small">Fit numbers of the scene to a target with the Fourier loss (amplitude and phase spectra of the sampled field).</p>
  <div class="micro-fit-params" style="max-height:16rem;overflow:auto" data-testid="micro-fit-params" role="group" aria-label="Numbers to fit"></div>
  <div class="micro-fit-target">
    <label class="inline"><input type="radio" name="fit-target" value="scene" checked data-testid="micro-fit-target-scene"> This scene with the target values</label>
    <label class="inline"><input type="radio" name="fit-target" value="slice" data-testid="micro-fit-target-slice"> A slice image</label>
    <input type="file" accept="image/*" name="fit-slice" data-testid="micro-fit-slice" hidden>
  </div>
  <div class="micro-fit-settings">
    <label class="inline">Optimizer <select name="fit-optimizer" data-testid="micro-fit-optimizer"></select></label>
    <label class="inline">Evaluations <input type="number" name="fit-budget" min="2" max="100000" step="1" data-testid="micro-fit-budget"></label>
    <label class="inline">Grid <select name="fit-grid"><option>8</option><option>16</option><option>32</option><option>64</option></select></label>
    <label class="inline" title="Blurred power profiles first, then amplitudes, then the paper's loss: finds several frequencies at once (gyroid 3D/5D) where the paper's loss alone has needle-thin basins. The loss shown is always the paper's."><input type="checkbox" name="fit-c2f" data-testid="micro-fit-c2f"> Coarse to fine</label>
  </div>
  <div class="micro-fit-actions">
    <button type="button" data-act="fit-run" data-testid="micro-fit-run">Reconstruct</button>
    <button type="button" data-act="fit-stop" data-testid="micro-fit-stop" disabled>Stop</button>
    <button type="button" data-act="fit-apply" data-testid="micro-fit-apply" disabled>Apply fitted values</button>
  </div>
  <canvas class="loss-plot" style="display:block;width:100%;height:140px" data-testid="micro-fit-plot" aria-label="loss while fitting"></canvas>
  <div class="status muted" data-testid="micro-fit-status" aria-live="polite"></div>`;
