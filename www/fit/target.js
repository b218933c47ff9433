// The target: drawn with a brush in the program's colours (the last one,
// the background, erases), uploaded (or dropped, or pasted) and snapped to
// the program's palette, made from the current values, or cleared.
import { acceptFiles, hex, pixelsOf } from '../ui/file-input.js';
import { radioGroup } from '../ui/radio-group.js';
import { named, rgbOf } from './program.js';
import { backgroundTarget, targetRequest, TARGET_SIZE } from './state.js';

/** The target part of the panel (`live`: state.js). */
export function createTarget(ctx, { q, live, status }) {
  const doc = () => ctx.state();
  const targetCanvas = q('canvas.target');
  const overlay = q('canvas.overlay');
  const stack = q('.stack');
  const tctx = targetCanvas.getContext('2d', { willReadFrequently: true });
  let brush = 0; // index into the brush colours (last = background)

  // Brush colours: the program's colours, then the background (an eraser).
  const colours = () => {
    const palette = live.info.colours.map(rgbOf);
    return [...palette.slice(1), palette[0]];
  };

  function showColours() {
    const sw = q('[data-testid=fit-brush-colours]');
    const list = colours();
    brush = Math.min(brush, list.length - 1);
    sw.replaceChildren(...list.map((c, i) => {
      const b = document.createElement('button');
      b.type = 'button';
      b.className = 'swatch-button';
      b.style.background = hex([...c, 255]);
      b.title = i === list.length - 1 ? `background ${hex([...c, 255])} (erase)` : hex([...c, 255]);
      b.setAttribute('aria-label', b.title);
      b.setAttribute('role', 'radio');
      b.setAttribute('aria-checked', String(i === brush));
      b.onclick = () => { brush = i; sw.querySelectorAll('button').forEach((x, j) => x.setAttribute('aria-checked', String(j === i))); };
      return b;
    }));
  }

  function store(extra = {}) {
    const { width, height } = targetCanvas;
    const rgba = new Uint8Array(tctx.getImageData(0, 0, width, height).data.buffer);
    ctx.commit({ ...doc(), ...extra, target: { width, height, rgba } });
  }

  // The target at its own size and aspect; the overlay takes the same.
  function draw(t) {
    if (!t) return;
    if (targetCanvas.width !== t.width || targetCanvas.height !== t.height) {
      targetCanvas.width = overlay.width = t.width;
      targetCanvas.height = overlay.height = t.height;
    }
    stack.style.aspectRatio = `${t.width} / ${t.height}`;
    tctx.putImageData(new ImageData(new Uint8ClampedArray(t.rgba), t.width, t.height), 0, 0);
  }

  // Paint exact palette colours (no anti-aliasing): a disc of `size` pixels.
  function dab(x, y) {
    const [r, g, b] = colours()[brush];
    const size = Number(q('[name=brush]').value) || 8;
    const rad = size / 2;
    const x0 = Math.max(0, Math.floor(x - rad)), y0 = Math.max(0, Math.floor(y - rad));
    const x1 = Math.min(targetCanvas.width, Math.ceil(x + rad)), y1 = Math.min(targetCanvas.height, Math.ceil(y + rad));
    if (x1 <= x0 || y1 <= y0) return;
    const img = tctx.getImageData(x0, y0, x1 - x0, y1 - y0);
    for (let j = 0; j < y1 - y0; j++) {
      for (let i = 0; i < x1 - x0; i++) {
        if (Math.hypot(x0 + i + 0.5 - x, y0 + j + 0.5 - y) > rad) continue;
        const k = 4 * (j * (x1 - x0) + i);
        img.data[k] = r; img.data[k + 1] = g; img.data[k + 2] = b; img.data[k + 3] = 255;
      }
    }
    tctx.putImageData(img, x0, y0);
  }

  let painting = null;
  let box = null;
  const toTarget = (e) => [(e.clientX - box.left) / box.width * targetCanvas.width, (e.clientY - box.top) / box.height * targetCanvas.height];
  stack.addEventListener('pointerdown', (e) => {
    if (!live.info || e.button > 0 || ctx.readOnly) return;
    stack.setPointerCapture(e.pointerId);
    box = targetCanvas.getBoundingClientRect();
    painting = toTarget(e);
    dab(...painting);
  });
  stack.addEventListener('pointermove', (e) => {
    if (!painting) return;
    const p = toTarget(e);
    const steps = Math.ceil(Math.hypot(p[0] - painting[0], p[1] - painting[1]) / 2);
    for (let s = 1; s <= steps; s++) dab(painting[0] + (p[0] - painting[0]) * s / steps, painting[1] + (p[1] - painting[1]) * s / steps);
    painting = p;
  });
  const endPaint = () => {
    if (!painting) return;
    painting = null;
    store({ truth: null });
  };
  stack.addEventListener('pointerup', endPaint);
  stack.addEventListener('pointercancel', endPaint);

  async function makeFromValues() {
    const d = doc();
    try {
      const r = await ctx.run('render-pattern', targetRequest(d.program, named(live.info, d.values)));
      ctx.commit({ ...doc(), target: { width: r.width, height: r.height, rgba: r.rgba }, truth: [...d.values] });
    } catch (err) {
      ctx.error(err);
    }
  }

  async function upload(file) {
    ctx.clearError();
    try {
      // Its pixels: the browser reads the file (the Fit module reads no image file).
      const rgba = await pixelsOf(file);
      const r = await ctx.run('pattern-snap', { program: doc().program, params: named(live.info, doc().values), rgba, size: TARGET_SIZE });
      ctx.commit({ ...doc(), target: { width: r.width, height: r.height, rgba: r.rgba }, truth: null });
      status(`${file.name}: snapped to the program's colours (${Math.round(r.unmatched * 100)}% of pixels were far from all of them)`);
    } catch (err) {
      ctx.error(err, { prefix: file.name });
    }
  }

  q('[data-act=make-target]').onclick = () => makeFromValues();
  q('[data-act=clear-target]').onclick = () => live.info && ctx.commit({ ...doc(), target: backgroundTarget(live.info), truth: null });
  // The target takes a dropped, pasted or picked image like Pixel's source does.
  const detachFiles = acceptFiles(q('.fit-target'), upload, { pickerLabel: 'Upload target…' });
  const detachRadios = radioGroup(q('[data-testid=fit-brush-colours]'));
  q('.fit-target input[type=file]').dataset.input = 'target';

  return {
    draw,
    showColours,
    detach() {
      detachFiles();
      detachRadios();
    },
  };
}
