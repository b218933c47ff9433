// Texture's grey pictures: the core's grey bytes as ImageData and PNG, and a
// user's image file shrunk to a grey example PNG the document can keep.

const EXAMPLE_SIDE = 256; // a dropped example is shrunk to at most this
const MAX_SOURCE_PNG = 256 * 1024; // src/texture/state.rs

/** Grey bytes (side²) → RGBA ImageData. */
export function grayImage(gray, side) {
  const g = gray instanceof Uint8Array ? gray : new Uint8Array(gray);
  const rgba = new Uint8ClampedArray(side * side * 4);
  for (let i = 0; i < side * side; i++) {
    const v = g[i];
    rgba[4 * i] = v; rgba[4 * i + 1] = v; rgba[4 * i + 2] = v; rgba[4 * i + 3] = 255;
  }
  return new ImageData(rgba, side, side);
}

export async function pngOf(canvas) {
  const blob = await new Promise((resolve, reject) => canvas.toBlob((b) => (b ? resolve(b) : reject(new Error('the image could not be encoded as PNG'))), 'image/png'));
  return new Uint8Array(await blob.arrayBuffer());
}

/** A grey picture as PNG bytes. */
export async function grayPng(gray, side) {
  const c = document.createElement('canvas');
  c.width = side;
  c.height = side;
  c.getContext('2d').putImageData(grayImage(gray, side), 0, 0);
  return pngOf(c);
}

/** A user's image file → a grey PNG at most `EXAMPLE_SIDE` a side (and at most MAX_SOURCE_PNG bytes). */
export async function shrinkExample(file) {
  let bmp;
  if (!file.size) throw new Error(`${file.name || 'the file'} is empty (0 bytes): there is no picture in it`);
  try {
    bmp = await createImageBitmap(file);
  } catch {
    throw new Error(`${file.name || 'the file'} is not an image this browser can read (PNG, JPEG, WebP, GIF): it may be damaged`);
  }
  try {
    for (let side = EXAMPLE_SIDE; side >= 32; side = Math.round(side / 2)) {
      const s = Math.min(1, side / Math.max(bmp.width, bmp.height));
      const w = Math.max(1, Math.round(bmp.width * s)), h = Math.max(1, Math.round(bmp.height * s));
      const c = document.createElement('canvas');
      c.width = w;
      c.height = h;
      const g = c.getContext('2d');
      g.fillStyle = '#fff'; // transparent parts read as white, as the core does
      g.fillRect(0, 0, w, h);
      g.imageSmoothingQuality = 'high';
      g.drawImage(bmp, 0, 0, w, h);
      const d = g.getImageData(0, 0, w, h);
      for (let i = 0; i < d.data.length; i += 4) {
        const y = Math.round(0.2126 * d.data[i] + 0.7152 * d.data[i + 1] + 0.0722 * d.data[i + 2]);
        d.data[i] = y; d.data[i + 1] = y; d.data[i + 2] = y;
      }
      g.putImageData(d, 0, 0);
      const png = await pngOf(c);
      if (png.length <= MAX_SOURCE_PNG) return png;
    }
  } finally {
    bmp.close?.();
  }
  throw new Error('the example could not be kept small enough');
}
