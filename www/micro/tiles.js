// The full CPU picture in tiles: TILE_GRID² `micro-render` jobs over the
// worker pool (a tile's pixels are bit for bit those of the one-job
// render), and path tracing in progressive passes of 1, 1, 2, 4, … samples
// per pixel (`sample_start`), each pass's summed radiance added in and the
// average shown. The jobs themselves run in schedule.js.

const TILE_GRID = 4; // the full CPU picture: TILE_GRID² tiles
const PASS_MAX = 256; // most samples per pixel in one progressive pass

/** TILE_GRID × TILE_GRID tiles covering a side × side image (fewer when it is tiny). */
export function tilesOf(side, grid = TILE_GRID) {
  const n = Math.max(1, Math.min(grid, side));
  const cut = (i) => Math.floor((side * i) / n);
  const out = [];
  for (let j = 0; j < n; j++) for (let i = 0; i < n; i++) out.push({ x: cut(i), y: cut(j), w: cut(i + 1) - cut(i), h: cut(j + 1) - cut(j) });
  return out;
}

/** Progressive passes for `spp` samples: [first sample, samples] of 1, 1, 2, 4, … (at most PASS_MAX). */
export function passesOf(spp) {
  const out = [];
  let start = 0;
  while (start < spp) {
    const n = Math.min(spp - start, Math.max(1, Math.min(start, PASS_MAX)));
    out.push([start, n]);
    start += n;
  }
  return out;
}

/** Render counters `b` added into `a` (a copy of `b` when `a` is null); returns the sum. */
export function addStats(a, b) {
  if (!a) return { ...b };
  for (const k of Object.keys(b)) a[k] += b[k];
  return a;
}

/** A reader of tile PNGs: `(bytes, w, h)` → their pixels (RGBA, row order). */
export function createTileReader() {
  const tileCanvas = document.createElement('canvas');
  const tileG = tileCanvas.getContext('2d', { willReadFrequently: true });
  return async (bytes, w, h) => {
    const bmp = await createImageBitmap(new Blob([bytes], { type: 'image/png' }), { premultiplyAlpha: 'none', colorSpaceConversion: 'none' });
    tileCanvas.width = w;
    tileCanvas.height = h;
    tileG.clearRect(0, 0, w, h);
    tileG.drawImage(bmp, 0, 0);
    bmp.close?.();
    return tileG.getImageData(0, 0, w, h).data;
  };
}

/**
 * Tile `t`'s summed radiance `rad` (f32 RGB, little-endian) added into `acc`
 * (the side × side picture's sums), its average over `total` samples shown in `frame`.
 */
export function addRadiance(frame, acc, t, rad, side, total) {
  const dv = new DataView(rad.buffer, rad.byteOffset, rad.byteLength);
  const k = 255 / total;
  for (let y = 0; y < t.h; y++) {
    for (let x = 0; x < t.w; x++) {
      const px = (t.y + y) * side + t.x + x;
      const src = ((y * t.w + x) * 3) * 4;
      for (let c = 0; c < 3; c++) {
        const v = (acc[px * 3 + c] += dv.getFloat32(src + c * 4, true));
        frame.data[px * 4 + c] = Math.min(255, Math.max(0, Math.round(v * k)));
      }
      frame.data[px * 4 + 3] = 255;
    }
  }
}

/** Tile `t`'s pixels `px` (RGBA) put into `frame` (side pixels wide). */
export function putTile(frame, t, px, side) {
  for (let y = 0; y < t.h; y++) frame.data.set(px.subarray(y * t.w * 4, (y + 1) * t.w * 4), ((t.y + y) * side + t.x) * 4);
}
