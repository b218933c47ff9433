// One way in for images, shared by every tool: drag-and-drop onto a zone,
// a file picker, and paste anywhere on the page while the zone is mounted.

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
  return () => document.removeEventListener('paste', paste);
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
