// The example in a link. A kept example is a grey PNG from the browser's
// encoder, which writes grey as colour (a 256² example of fine grain is up
// to ~100 KB). A link carries its grey pixels instead, Paeth-filtered as
// PNG does and deflated with the rest of the link (share.js): at most 64 KB
// before deflating, so every example the page keeps fits the 96 KB a link
// holds. The recipient's page encodes the same pixels as its PNG. A colour
// PNG (from a project file) travels as its bytes.
import { pngOf } from './pictures.js';

const paeth = (a, b, c) => {
  const p = a + b - c;
  const pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
  return pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
};

/** Grey pixels (width·height bytes) Paeth-filtered (`undo` = false) or restored (`undo` = true), in place of a copy. */
export function paethFilter(px, width, height, undo) {
  const out = new Uint8Array(px.length);
  const src = undo ? out : px; // the neighbours are always original pixels
  for (let y = 0; y < height; y++) {
    for (let x = 0; x < width; x++) {
      const i = y * width + x;
      const a = x ? src[i - 1] : 0, b = y ? src[i - width] : 0, c = x && y ? src[i - width - 1] : 0;
      out[i] = (px[i] + (undo ? 1 : -1) * paeth(a, b, c)) & 255;
    }
  }
  return out;
}

/** A PNG's pixels as grey bytes, or null when it has colour or transparency (or does not decode). */
export async function greyPixels(png) {
  let bmp;
  try {
    bmp = await createImageBitmap(new Blob([png], { type: 'image/png' }), { colorSpaceConversion: 'none', premultiplyAlpha: 'none' });
  } catch {
    return null;
  }
  const { width, height } = bmp;
  const c = new OffscreenCanvas(width, height);
  const g = c.getContext('2d');
  g.drawImage(bmp, 0, 0);
  bmp.close?.();
  const d = g.getImageData(0, 0, width, height).data;
  const grey = new Uint8Array(width * height);
  for (let i = 0; i < grey.length; i++) {
    const [r, gg, b, a] = [d[4 * i], d[4 * i + 1], d[4 * i + 2], d[4 * i + 3]];
    if (r !== gg || r !== b || a !== 255) return null;
    grey[i] = r;
  }
  return { width, height, grey };
}

/** The example of a link (`{grey: {width, height, filtered}}`) as the document's PNG. */
export async function greyFromLink(x) {
  const { width, height, filtered } = x ?? {};
  if (!Number.isInteger(width) || !Number.isInteger(height) || width < 1 || height < 1 || width > 4096 || height > 4096
    || !(filtered instanceof Uint8Array) || filtered.length !== width * height) {
    throw Object.assign(new Error('source is damaged'), { field: 'source' });
  }
  const grey = paethFilter(filtered, width, height, true);
  const rgba = new Uint8ClampedArray(width * height * 4);
  for (let i = 0; i < grey.length; i++) {
    rgba[4 * i] = grey[i]; rgba[4 * i + 1] = grey[i]; rgba[4 * i + 2] = grey[i]; rgba[4 * i + 3] = 255;
  }
  const c = document.createElement('canvas');
  c.width = width;
  c.height = height;
  c.getContext('2d').putImageData(new ImageData(rgba, width, height), 0, 0);
  return pngOf(c);
}
