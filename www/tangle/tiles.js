// Tile painting: a repaint of part of the canvas works on tiles of TILE
// device pixels. A small mask canvas (one pixel a tile) gets the changed
// shapes drawn on it, grown by the pen and a margin; the tiles it touches
// are cleared and redrawn, clipped, from the shapes that reach into them
// (canvas.js `changedRegion`, `paintRegion`).
//
// A view `m` is [scale, x, y]: drawing units to device pixels (the canvas's
// transform times its pixel ratio).

export const TILE = 8;

/**
 * The tiles of a `width`×`height` canvas that `changed` (a Path2D) and the
 * highlights `hls` ({path, box?}) cover in view `m` with pen `lineWidth`,
 * drawn on `mask`: `{tiles, cols, rows, count, sum}` (tiles: 1 where covered;
 * sum: its summed-area table), null when none, or false when most of the
 * canvas (a full repaint is cheaper).
 */
export function changedTiles(mask, width, height, [ds, dx, dy], lineWidth, changed, hls) {
  const cols = Math.ceil(width / TILE), rows = Math.ceil(height / TILE);
  if (mask.width !== cols || mask.height !== rows) { mask.width = cols; mask.height = rows; }
  const mg = mask.getContext('2d', { willReadFrequently: true });
  mg.setTransform(1, 0, 0, 1, 0, 0);
  mg.clearRect(0, 0, cols, rows);
  const s = ds / TILE;
  mg.setTransform(s, 0, 0, s, dx / TILE, dy / TILE);
  // A pen's half width past the outline, and anti-aliasing: grown by a tile below.
  mg.lineWidth = lineWidth + 4 / ds;
  mg.lineJoin = 'round';
  mg.fillStyle = mg.strokeStyle = '#000';
  mg.fill(changed, 'nonzero');
  mg.stroke(changed);
  for (const x of hls) {
    mg.fill(x.path, 'nonzero');
    if (x.box) mg.strokeRect(x.box[0], x.box[1], x.box[2] - x.box[0], x.box[3] - x.box[1]);
  }
  const a = mg.getImageData(0, 0, cols, rows).data;
  // Marked tiles, grown by one (the mask's own anti-aliasing may miss an edge).
  const tiles = new Uint8Array(cols * rows);
  let count = 0;
  for (let y = 0; y < rows; y++) {
    for (let x = 0; x < cols; x++) {
      if (!a[4 * (y * cols + x) + 3]) continue;
      for (let v = Math.max(0, y - 1); v <= Math.min(rows - 1, y + 1); v++) {
        for (let u = Math.max(0, x - 1); u <= Math.min(cols - 1, x + 1); u++) {
          if (!tiles[v * cols + u]) { tiles[v * cols + u] = 1; count++; }
        }
      }
    }
  }
  if (!count) return null;
  if (count > 0.9 * cols * rows) return false;
  // Summed-area table: any marked tile within a box in O(1).
  const sum = new Int32Array((cols + 1) * (rows + 1));
  for (let y = 0; y < rows; y++) {
    let run = 0;
    for (let x = 0; x < cols; x++) {
      run += tiles[y * cols + x];
      sum[(y + 1) * (cols + 1) + x + 1] = sum[y * (cols + 1) + x + 1] + run;
    }
  }
  return { tiles, cols, rows, count, sum };
}

/**
 * The clip of `region`'s tiles (one rectangle a run of a row) and the box
 * around them, cut to a `width`×`height` canvas: `{clip, bx, by, bw, bh}`.
 */
export function tileClip({ tiles, cols, rows }, width, height) {
  const clip = new Path2D();
  let x0 = cols, y0 = rows, x1 = 0, y1 = 0;
  for (let y = 0; y < rows; y++) {
    for (let x = 0; x < cols; x++) {
      if (!tiles[y * cols + x]) continue;
      let e = x;
      while (e + 1 < cols && tiles[y * cols + e + 1]) e++;
      clip.rect(x * TILE, y * TILE, (e - x + 1) * TILE, TILE);
      x0 = Math.min(x0, x); x1 = Math.max(x1, e + 1); y0 = Math.min(y0, y); y1 = Math.max(y1, y + 1);
      x = e;
    }
  }
  const bx = x0 * TILE, by = y0 * TILE, bw = Math.min(width, x1 * TILE) - bx, bh = Math.min(height, y1 * TILE) - by;
  return { clip, bx, by, bw, bh };
}

/**
 * `(i) → bool`: whether shape i's box (`box`, four numbers a shape), grown
 * by `margin` drawing units, touches a tile of `region` in view `m`.
 */
export function touchesTiles({ cols, rows, sum }, box, [ds, dx, dy], margin) {
  const s = ds / TILE, ox = dx / TILE, oy = dy / TILE;
  const m = margin;
  return (i) => {
    const u0 = Math.max(0, Math.floor(s * (box[4 * i] - m) + ox)), v0 = Math.max(0, Math.floor(s * (box[4 * i + 1] - m) + oy));
    const u1 = Math.min(cols, Math.floor(s * (box[4 * i + 2] + m) + ox) + 1), v1 = Math.min(rows, Math.floor(s * (box[4 * i + 3] + m) + oy) + 1);
    if (u1 <= u0 || v1 <= v0) return false;
    const w = cols + 1;
    return sum[v1 * w + u1] - sum[v0 * w + u1] - sum[v1 * w + u0] + sum[v0 * w + u0] > 0;
  };
}
