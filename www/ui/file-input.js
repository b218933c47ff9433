// One way in for images, shared by every tool: drag-and-drop onto the zone
// or anywhere else in the window, a file picker, and paste anywhere on the
// page while the zone is mounted.

/**
 * Make `zone` accept image files. `onFile(file)` gets each file the user gives.
 * Returns a function that removes the listeners (call it on unmount).
 */
export function acceptFiles(zone, onFile, { accept = 'image/*', pickerLabel = 'Choose a file…' } = {}) {
  const input = document.createElement('input');
  input.type = 'file';
  input.accept = accept;
  input.hidden = true;
  input.onchange = () => {
    if (input.files[0]) onFile(input.files[0]);
    input.value = '';
  };
  const pick = document.createElement('button');
  pick.type = 'button';
  pick.className = 'pick';
  pick.textContent = pickerLabel;
  pick.onclick = () => input.click();
  zone.append(input, pick);

  const over = (e) => {
    e.preventDefault();
    zone.classList.add('dragging');
  };
  const leave = () => zone.classList.remove('dragging');
  const drop = (e) => {
    e.preventDefault();
    leave();
    const file = e.dataTransfer?.files?.[0];
    if (file) onFile(file);
  };
  const paste = (e) => {
    const file = [...(e.clipboardData?.files || [])][0];
    if (file) {
      e.preventDefault();
      onFile(file);
    }
  };
  zone.addEventListener('dragover', over);
  zone.addEventListener('dragleave', leave);
  zone.addEventListener('drop', drop);
  document.addEventListener('paste', paste);
  // A file dropped anywhere in the window is the zone's (a panel has one way in for
  // a file): the zone lights up while a file is over the window. What handles a drop
  // itself (the zone, an editor) has called preventDefault by the time it gets here.
  const hasFiles = (e) => [...(e.dataTransfer?.types || [])].includes('Files');
  const winOver = (e) => {
    if (!hasFiles(e) || e.defaultPrevented) return;
    e.preventDefault();
    zone.classList.add('dragging');
  };
  const winLeave = (e) => { if (!e.relatedTarget) leave(); };
  const winDrop = (e) => {
    if (!hasFiles(e)) return leave();
    if (!e.defaultPrevented) drop(e);
  };
  addEventListener('dragover', winOver);
  addEventListener('dragleave', winLeave);
  addEventListener('drop', winDrop);
  return () => {
    document.removeEventListener('paste', paste);
    removeEventListener('dragover', winOver);
    removeEventListener('dragleave', winLeave);
    removeEventListener('drop', winDrop);
  };
}

/**
 * File pickers that are real buttons: each `button[data-pick=NAME]` in `root`
 * opens the file dialog of the hidden `input[type=file][data-input=NAME]` next
 * to it (keyboard reachable and in the accessibility tree, unlike a label
 * around a hidden input). The input's own change handler does the loading.
 */
export function wirePickers(root) {
  for (const b of root.querySelectorAll('button[data-pick]')) {
    const input = root.querySelector(`input[type=file][data-input="${b.dataset.pick}"]`);
    if (input) b.addEventListener('click', () => input.click());
  }
}

/** Draw RGBA bytes into a canvas at native size (CSS scales it crisply). */
export function putRgba(canvas, width, height, rgba) {
  canvas.width = width;
  canvas.height = height;
  const ctx = canvas.getContext('2d');
  ctx.putImageData(new ImageData(new Uint8ClampedArray(rgba.buffer, rgba.byteOffset, rgba.byteLength), width, height), 0, 0);
}

/** '#rrggbb' (or '#rrggbbaa' when not opaque) for an [r, g, b, a] array. */
export function hex([r, g, b, a]) {
  const h = (v) => v.toString(16).padStart(2, '0');
  return `#${h(r)}${h(g)}${h(b)}${a === 255 ? '' : h(a)}`;
}

const PNG_MAGIC = [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a];

/** Whether `bytes` start like a PNG file. */
export const isPng = (bytes) => bytes.length >= 8 && PNG_MAGIC.every((b, i) => bytes[i] === b);

/**
 * A user's image file as PNG bytes ({@link pngOf} of its bytes). The Pixel,
 * Micro and Texture modules read PNG only (src/raster/image_buf.rs
 * `decode_sent`), so their panels send this.
 */
export async function asPng(file) {
  return pngOf(new Uint8Array(await file.arrayBuffer()), file.name);
}

/**
 * Image bytes as PNG: a PNG as it is (the same bytes, so the core reads the
 * same pixels as natively); any other image the browser reads (JPEG, WebP,
 * GIF, BMP, ...) decoded by the browser with no colour-space conversion and
 * no premultiplied alpha, and encoded as an 8-bit RGBA PNG at its own size.
 * `name` names the file in errors.
 */
export async function pngOf(bytes, name = 'the file') {
  if (isPng(bytes)) return bytes;
  const { width, height, rgba } = await pixelsOfBytes(bytes, name);
  return encodePng(width, height, rgba);
}

/**
 * A user's image file as its pixels, {width, height, rgba}: decoded by the
 * browser (any format it reads) with no colour-space conversion and no
 * premultiplied alpha, 8 bits a channel. The Fit module reads no image
 * file (src/raster/image_buf.rs `decode_file`), so its target upload sends
 * this. An image larger than the core takes (IMAGE_LIMITS) is refused
 * before its pixels are read back.
 */
export async function pixelsOf(file) {
  return pixelsOfBytes(new Uint8Array(await file.arrayBuffer()), file.name);
}

/** The core's image limits (src/core/limits.rs MAX_IMAGE_SIDE, MAX_IMAGE_PIXELS); the core checks them again. */
export const IMAGE_LIMITS = { side: 4096, pixels: 16 * 1024 * 1024 };

function tooLarge(width, height, name) {
  if (Math.max(width, height) > IMAGE_LIMITS.side || width * height > IMAGE_LIMITS.pixels) {
    throw new Error(`${name} is ${width}×${height} pixels: images up to ${IMAGE_LIMITS.side} pixels a side and 16 megapixels are read`);
  }
}

async function pixelsOfBytes(bytes, name) {
  if (!bytes.length) throw new Error(`${name} is empty (0 bytes): there is no picture in it`);
  // A PNG's size is in its header: a huge one is refused before the browser decodes it.
  if (isPng(bytes) && bytes.length >= 24) {
    const header = new DataView(bytes.buffer, bytes.byteOffset + 16, 8);
    tooLarge(header.getUint32(0), header.getUint32(4), name);
  }
  let bmp;
  try {
    bmp = await createImageBitmap(new Blob([bytes]), { premultiplyAlpha: 'none', colorSpaceConversion: 'none' });
  } catch {
    throw new Error(`${name} is not an image this browser can read (PNG, JPEG, WebP, GIF, BMP): it may be damaged`);
  }
  try {
    const { width, height } = bmp;
    tooLarge(width, height, name);
    return { width, height, rgba: straightRgba(bmp) };
  } finally {
    bmp.close?.();
  }
}

/**
 * The pixels of an ImageBitmap (made with premultiplyAlpha 'none') as they
 * are: uploaded to a WebGL texture with no premultiplication and no colour
 * conversion and read back, since a 2D canvas keeps premultiplied pixels (a
 * transparent pixel would lose its colour, a translucent one be rounded).
 * Without WebGL, or for a bitmap larger than its textures, a 2D canvas:
 * exact for opaque pixels.
 */
function straightRgba(bmp) {
  const { width: w, height: h } = bmp;
  const c = new OffscreenCanvas(w, h);
  const gl = c.getContext('webgl', { premultipliedAlpha: false, antialias: false });
  if (gl && Math.max(w, h) <= gl.getParameter(gl.MAX_TEXTURE_SIZE)) {
    try {
      const tex = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, tex);
      gl.pixelStorei(gl.UNPACK_PREMULTIPLY_ALPHA_WEBGL, false);
      gl.pixelStorei(gl.UNPACK_COLORSPACE_CONVERSION_WEBGL, gl.NONE);
      gl.pixelStorei(gl.UNPACK_FLIP_Y_WEBGL, false);
      gl.texImage2D(gl.TEXTURE_2D, 0, gl.RGBA, gl.RGBA, gl.UNSIGNED_BYTE, bmp);
      const fb = gl.createFramebuffer();
      gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
      gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, tex, 0);
      if (gl.checkFramebufferStatus(gl.FRAMEBUFFER) === gl.FRAMEBUFFER_COMPLETE) {
        const out = new Uint8Array(w * h * 4);
        // A texture's first row is the bitmap's top row, and readPixels reads it first.
        gl.readPixels(0, 0, w, h, gl.RGBA, gl.UNSIGNED_BYTE, out);
        if (gl.getError() === gl.NO_ERROR) return out;
      }
    } finally {
      gl.getExtension('WEBGL_lose_context')?.loseContext();
    }
  }
  const g = new OffscreenCanvas(w, h).getContext('2d');
  g.drawImage(bmp, 0, 0);
  return new Uint8Array(g.getImageData(0, 0, w, h, { colorSpace: 'srgb' }).data.buffer);
}

let crcTable = null;
function crc32(bytes, crc = 0xffffffff) {
  crcTable ??= Uint32Array.from({ length: 256 }, (_, n) => {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    return c;
  });
  for (const b of bytes) crc = crcTable[(crc ^ b) & 0xff] ^ (crc >>> 8);
  return crc;
}

/** An 8-bit RGBA PNG of `rgba` (rows unfiltered, zlib by the browser's CompressionStream). */
async function encodePng(w, h, rgba) {
  const raw = new Uint8Array(h * (1 + 4 * w));
  for (let y = 0; y < h; y++) raw.set(rgba.subarray(4 * w * y, 4 * w * (y + 1)), y * (1 + 4 * w) + 1);
  const zlib = new Uint8Array(await new Response(new Blob([raw]).stream().pipeThrough(new CompressionStream('deflate'))).arrayBuffer());
  const chunk = (type, data) => {
    const out = new Uint8Array(12 + data.length);
    const v = new DataView(out.buffer);
    v.setUint32(0, data.length);
    for (let i = 0; i < 4; i++) out[4 + i] = type.charCodeAt(i);
    out.set(data, 8);
    v.setUint32(8 + data.length, (crc32(out.subarray(4, 8 + data.length)) ^ 0xffffffff) >>> 0);
    return out;
  };
  const ihdr = new Uint8Array(13);
  const v = new DataView(ihdr.buffer);
  v.setUint32(0, w);
  v.setUint32(4, h);
  ihdr.set([8, 6, 0, 0, 0], 8); // 8 bits, RGBA, deflate, no filter method, not interlaced
  const parts = [Uint8Array.from(PNG_MAGIC), chunk('IHDR', ihdr), chunk('IDAT', zlib), chunk('IEND', new Uint8Array(0))];
  return new Uint8Array(await new Blob(parts).arrayBuffer());
}
