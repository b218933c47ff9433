// Micro's canvas: sized to the view in device pixels (at most FULL_SIDE a
// side), it shows the CPU picture (`live.bitmap`, scaled) or the rows the
// GPU view paints straight on it.
import { clamp } from './state.js';

export const FULL_SIDE = 384; // full render, pixels a side (at most)
export const PREVIEW_DIV = 4; // while dragging: 1/4 of the full side (the GPU's first coarse frames too)

/**
 * The canvas of a mounted panel (`live`: state.js). On a resize it repaints
 * the CPU picture, or calls `onResize()` when there is none (the GPU's).
 */
export function createPicture({ q, live, onResize }) {
  const canvas = q('[data-testid=micro-canvas]');
  const g = canvas.getContext('2d');
  const viewport = q('.micro-viewport');

  /** Pixels a side of the full image (the canvas's size on screen, capped). */
  function fullSide() {
    const dpr = window.devicePixelRatio || 1;
    const w = viewport.clientWidth || FULL_SIDE;
    return clamp(Math.round(w * dpr), 16, FULL_SIDE);
  }

  function paint() {
    const side = fullSide();
    if (canvas.width !== side || canvas.height !== side) { canvas.width = side; canvas.height = side; }
    g.fillStyle = '#181a1e';
    g.fillRect(0, 0, side, side);
    if (!live.bitmap) return;
    g.imageSmoothingEnabled = true;
    g.drawImage(live.bitmap, 0, 0, side, side);
  }

  /** Rows y0.. of the full picture (RGBA, `w` wide), straight on the canvas. */
  function paintRows(rgba, w, y0, rows) {
    const side = fullSide();
    if (canvas.width !== side || canvas.height !== side) { canvas.width = side; canvas.height = side; }
    g.putImageData(new ImageData(rgba, w, rows), 0, y0);
  }

  const ro = new ResizeObserver(() => {
    if (live.bitmap) paint();
    else onResize();
  });
  ro.observe(viewport);

  return { canvas, g, fullSide, paint, paintRows, detach: () => ro.disconnect() };
}
