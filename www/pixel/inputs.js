// Files in: a shipped example (one undoable step), the source, mask and
// element sheet or sprite the user gives (the file inputs, or a source
// dropped on the picture; each turned into PNG in the page, the only format
// the Pixel module reads, and checked by the core before it is committed),
// and the preview of the elements.
import { acceptFiles, asPng, putRgba } from '../ui/file-input.js';
import { exampleDoc } from './state.js';

/** The inputs of a mounted panel: {loadExample(name), showElements(doc), detach()}. */
export function createInputs(ctx, { el, q, status }) {
  const state = () => ctx.state();

  async function loadExample(name) {
    ctx.clearError();
    status(`loading the ${name} example…`);
    try {
      const doc = await exampleDoc(name, ctx);
      // Examples replace the work as an undoable step.
      ctx.commit(doc);
    } catch (err) {
      status('');
      ctx.error(err, { prefix: `The ${name} example` });
    }
  }

  async function loadInput(which, file) {
    ctx.clearError();
    const doc = state();
    try {
      // PNG: the Pixel module reads no other format (the browser decodes a JPEG, GIF, WebP or BMP).
      const bytes = await asPng(file);
      if (which === 'source') {
        const img = await ctx.run('decode-image', { bytes: bytes.slice() });
        // An example's mask and strokes were drawn for the example's picture: your own
        // source starts with a full mask and no strokes. Over your own source, a new one
        // keeps the mask when the sizes agree (else a full one), and the strokes rescaled
        // to the new size so they stay on the same part of the picture.
        const own = doc && doc.example == null;
        const keepMask = own && doc.mask && doc.mask.width === img.width && doc.mask.height === img.height;
        const mask = keepMask ? doc.mask : { width: img.width, height: img.height, bits: new Uint8Array(img.width * img.height).fill(1) };
        const sx = own ? img.width / doc.mask.width : 1, sy = own ? img.height / doc.mask.height : 1;
        const strokes = (own ? doc.strokes : []).map((s) => s.map(([x, y]) => [Math.round(x * sx * 100) / 100, Math.round(y * sy * 100) / 100]));
        ctx.commit({
          ...doc, example: null, source: bytes, mask, strokes, names: { ...(doc?.names || {}), source: file.name },
        });
        return;
      }
      if (!doc) throw new Error('load a source image first');
      if (which === 'mask') {
        const mask = await ctx.run('pixel-mask', { bytes });
        if (mask.width !== doc.mask.width || mask.height !== doc.mask.height) {
          throw new Error(`the mask is ${mask.width}×${mask.height} pixels but the source image is ${doc.mask.width}×${doc.mask.height}; they must be the same size`);
        }
        ctx.commit({ ...doc, mask });
      } else {
        await ctx.run('decode-image', { bytes: bytes.slice() });
        ctx.commit({ ...doc, sheet: which === 'sheet' ? bytes : null, sprite: which === 'sprite' ? bytes : null, names: { ...doc.names, sheet: file.name } });
      }
    } catch (err) {
      if (!err.field) err.field = which;
      ctx.error(err, { prefix: file.name });
    }
  }

  async function showElements(doc) {
    const bytes = doc.sheet || doc.sprite;
    const c = q('.sheet-preview');
    if (!bytes) { c.width = c.height = 0; q('[data-field=elements]').textContent = 'no elements yet'; return; }
    try {
      const img = await ctx.run('decode-image', { bytes: bytes.slice() });
      putRgba(c, img.width, img.height, img.rgba);
      q('[data-field=elements]').textContent = `${doc.sheet ? 'sheet' : 'sprite'} ${img.width}×${img.height}`;
    } catch (err) {
      ctx.error(err, { prefix: 'Element sheet' });
    }
  }

  el.querySelectorAll('input[data-input]').forEach((input) => {
    input.onchange = () => {
      if (input.files[0]) loadInput(input.dataset.input, input.files[0]);
      input.value = '';
    };
  });
  const detach = acceptFiles(q('.viewport'), (file) => loadInput('source', file), { pickerLabel: 'Choose a source image…' });
  q('.viewport .pick').classList.add('overlay-pick');

  return { loadExample, showElements, detach };
}
