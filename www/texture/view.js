// Texture's retrieved texture: rendered live from its model and parameters
// (`texture-render`, unless a retrieval brought its picture), tiled 2×2 on
// request.
import { grayImage } from './pictures.js';
import { SIDE, keyOf } from './state.js';

/** Draw `image` (ImageData) `tile` × `tile` times on canvas `c`, sized to fit. */
export function drawTiled(c, image, tile) {
  const s = image.width;
  c.width = s * tile;
  c.height = s * tile;
  const g = c.getContext('2d');
  for (let y = 0; y < tile; y++) for (let x = 0; x < tile; x++) g.putImageData(image, x * s, y * s);
}

/**
 * The view of a mounted panel (`live.shown`: state.js; `counters`: the status
 * element's dataset, counting renders): {drawView(), renderRetrieved(r), rendering()}.
 */
export function createView(ctx, { q, live, counters }) {
  const view = q('[data-testid=texture-canvas]');
  const tileBox = q('[name=tile]');
  let rendering = null; // AbortController of the render in flight

  function drawView() {
    const tile = tileBox.checked ? 2 : 1;
    if (!live.shown) {
      view.width = SIDE;
      view.height = SIDE;
      view.getContext('2d').clearRect(0, 0, SIDE, SIDE);
      return;
    }
    drawTiled(view, live.shown.image, tile);
  }

  /** Render the retrieved model + parameters unless that picture is already shown. */
  async function renderRetrieved(r) {
    const key = keyOf(r);
    if (live.shown?.key === key) { drawView(); return; }
    rendering?.abort();
    if (!r) { live.shown = null; drawView(); return; }
    const ctrl = new AbortController();
    rendering = ctrl;
    try {
      const img = await ctx.run('texture-render', { model: r.model, params: r.params, seed: r.seed, size: SIDE }, { signal: ctrl.signal });
      if (rendering !== ctrl || !ctx.alive()) return;
      live.shown = { key, image: grayImage(img.gray, img.size) };
      counters.renders = String(Number(counters.renders) + 1);
      drawView();
      ctx.clearError('render');
    } catch (err) {
      if (rendering === ctrl && err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Render', source: 'render' });
    } finally {
      if (rendering === ctrl) rendering = null;
    }
  }

  tileBox.onchange = () => drawView();

  return {
    drawView,
    renderRetrieved,
    /** How many times the picture tiles (1 or 2). */
    tile: () => (tileBox.checked ? 2 : 1),
    /** Whether a render is under way. */
    rendering: () => rendering !== null,
    abort: () => rendering?.abort(),
  };
}
