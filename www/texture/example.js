// Texture's example: an image dropped, pasted or chosen (shrunk to a grey
// PNG, pictures.js), or one of the models rendered; the runner analyses it
// (schedule.js). The example canvas shows the document's example.
import { acceptFiles } from '../ui/file-input.js';
import { grayImage, grayPng, shrinkExample } from './pictures.js';
import { SIDE, sourceKey } from './state.js';

/** The example of a mounted panel: {drawExample(source), detach()}. */
export function createExample(ctx, { q, live, runner, status, modelSel }) {
  const state = () => ctx.state();
  const exampleCanvas = q('[data-testid=texture-example]');
  let exampleShown = '';

  async function onFile(file) {
    if (ctx.readOnly) return;
    try {
      status('reading the example…');
      const png = await shrinkExample(file);
      if (!ctx.alive()) return;
      const source = { kind: 'image', name: String(file.name || 'pasted image').slice(0, 200), png };
      await drawExample(source);
      // Refused (too small to read, say): the canvas shows the document's example again.
      if (!(await runner.useExample(source, png)) && ctx.alive()) await drawExample(state()?.source);
    } catch (err) {
      // Nothing is being read any more: say so, and show the document's example again.
      if (!ctx.alive()) return;
      status('the example was not read (see above); the one before is kept');
      ctx.error(err, { prefix: 'Example' });
      await drawExample(state()?.source).catch(() => {});
    }
  }
  const dropZone = q('[data-testid=texture-drop]');
  const removeFiles = acceptFiles(dropZone, onFile, { pickerLabel: 'Choose an image…' });
  // A read-only embed keeps the author's example: no drop, no picker, and words that say so.
  if (ctx.readOnly) {
    dropZone.querySelector('p').textContent = 'The author\'s example.';
    dropZone.querySelector('.pick').hidden = true;
  }

  q('[data-act=render-example]').onclick = async () => {
    const m = live.list.find((x) => x.id === modelSel.value);
    if (!m) return;
    try {
      const source = { kind: 'model', model: m.id, params: m.params.map((p) => p.default), seed: 1 };
      const img = await ctx.run('texture-render', { model: m.id, params: source.params, seed: 1, size: SIDE });
      if (!ctx.alive()) return;
      exampleCanvas.width = SIDE;
      exampleCanvas.height = SIDE;
      exampleCanvas.getContext('2d').putImageData(grayImage(img.gray, SIDE), 0, 0);
      exampleShown = sourceKey(source);
      await runner.useExample(source, await grayPng(img.gray, SIDE));
    } catch (err) {
      if (err?.kind !== 'cancelled') ctx.error(err, { prefix: 'Render example' });
    }
  };

  async function drawExample(source) {
    const key = sourceKey(source);
    if (key === exampleShown) return;
    exampleShown = key;
    const g = exampleCanvas.getContext('2d');
    if (!source) {
      g.clearRect(0, 0, exampleCanvas.width, exampleCanvas.height);
      return;
    }
    if (source.kind === 'model') {
      const img = await ctx.run('texture-render', { model: source.model, params: source.params, seed: source.seed, size: SIDE });
      if (exampleShown !== key) return;
      exampleCanvas.width = SIDE;
      exampleCanvas.height = SIDE;
      g.putImageData(grayImage(img.gray, SIDE), 0, 0);
    } else {
      const bmp = await createImageBitmap(new Blob([source.png], { type: 'image/png' }));
      if (exampleShown !== key) { bmp.close?.(); return; }
      exampleCanvas.width = bmp.width;
      exampleCanvas.height = bmp.height;
      g.drawImage(bmp, 0, 0);
      bmp.close?.();
    }
  }

  return { drawExample, detach: removeFiles };
}
