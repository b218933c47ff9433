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

/**
 * A user's image file as PNG bytes: a PNG as it is, any other image the
 * browser reads (JPEG, WebP, GIF, BMP, ...) decoded by the browser and
 * encoded as PNG at its own size. The Fit, Micro and Texture modules read
 * PNG only (src/raster/image_buf.rs `decode_sent`), so their panels send this.
 */
export async function asPng(file) {
  const bytes = new Uint8Array(await file.arrayBuffer());
  if (!bytes.length) throw new Error(`${file.name || 'the file'} is empty (0 bytes): there is no picture in it`);
  if (PNG_MAGIC.every((b, i) => bytes[i] === b)) return bytes;
  let bmp;
  try {
    bmp = await createImageBitmap(new Blob([bytes]), { premultiplyAlpha: 'none', colorSpaceConversion: 'none' });
  } catch {
    throw new Error(`${file.name || 'the file'} is not an image this browser can read (PNG, JPEG, WebP, GIF, BMP): it may be damaged`);
  }
  try {
    const c = new OffscreenCanvas(bmp.width, bmp.height);
    c.getContext('2d').drawImage(bmp, 0, 0);
    return new Uint8Array(await (await c.convertToBlob({ type: 'image/png' })).arrayBuffer());
  } finally {
    bmp.close?.();
  }
}
