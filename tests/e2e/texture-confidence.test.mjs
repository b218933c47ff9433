// Issue 36: the Texture panel says how sure it is. A texture of one of
// the models shows the three likeliest models with probabilities, most
// likely first and the predicted one on top; a picture that is no
// procedural texture (a smooth grey ramp) says "No close
// model" and still lists the nearest three. Both are kept in the document, so a reload shows them.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch, dropFile } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const state = (page) => page.evaluate(() => window.filigree.testHooks.texture.state());
const settled = () => !!window.filigree?.testHooks?.texture && !window.filigree.testHooks.texture.pending()
  && !!document.querySelector('[data-testid=texture-retrieved][data-model]');

/** A 256² PNG drawn by the page: `kind` 'ramp' (black to white, left to right) or a model's render. */
async function picture(page, kind) {
  const b64 = await page.evaluate(async (kind) => {
    const c = document.createElement('canvas');
    c.width = 256;
    c.height = 256;
    const g = c.getContext('2d');
    if (kind === 'ramp') {
      // Columns of grey stepping from black to white (a canvas gradient
      // would be dithered: noise, which reads as a fine texture).
      for (let x = 0; x < 256; x++) {
        g.fillStyle = `rgb(${x},${x},${x})`;
        g.fillRect(x, 0, 1, 256);
      }
    } else {
      const r = await window.filigree.pool.run('texture-render', { model: kind, seed: 31, size: 256 });
      const rgba = new Uint8ClampedArray(r.size * r.size * 4);
      r.gray.forEach((v, i) => { rgba[4 * i] = v; rgba[4 * i + 1] = v; rgba[4 * i + 2] = v; rgba[4 * i + 3] = 255; });
      g.putImageData(new ImageData(rgba, r.size, r.size), 0, 0);
    }
    const blob = await new Promise((res) => c.toBlob(res, 'image/png'));
    const bytes = new Uint8Array(await blob.arrayBuffer());
    let s = '';
    for (const b of bytes) s += String.fromCharCode(b);
    return btoa(s);
  }, kind);
  return Buffer.from(b64, 'base64');
}

async function drop(page, name, png) {
  const before = (await state(page))?.source?.name;
  await dropFile(page, '[data-testid=texture-drop]', { name, bytes: png, type: 'image/png' });
  await page.waitForFunction((n) => window.filigree.testHooks.texture.state()?.source?.name === n, name, { timeout: 30000 });
  assert.notEqual(before, name);
  await page.waitForFunction(settled, null, { timeout: 30000 });
}

/** The listed models as [id, percent] pairs. */
const listed = (page) => page.$$eval('[data-testid=texture-top] li', (xs) => xs.map((x) => [x.dataset.model, Number(x.textContent.match(/([\d.]+)%/)[1])]));

test('a texture lists its three likeliest models; a grey ramp says no close model', async () => {
  const page = await env.newPage({ path: '#tool=texture' });
  await page.waitForFunction(settled, null, { timeout: 45000 });

  await drop(page, 'cells.png', await picture(page, 'cellular'));
  let s = await state(page);
  assert.equal(s.predicted.top.length, 3);
  assert.equal(s.predicted.top[0].model, s.predicted.model, 'the prediction is the likeliest model');
  const p = s.predicted.top.map((c) => c.probability);
  assert.ok(p[0] >= p[1] && p[1] >= p[2] && p[2] > 0, `descending probabilities ${p}`);
  assert.ok(p[0] + p[1] + p[2] <= 1 + 1e-9, `a distribution's top three ${p}`);
  assert.notEqual(s.predicted.close, false, 'a model\'s own texture is close to the index (close: true is left out)');
  let shown = await listed(page);
  assert.deepEqual(shown.map((x) => x[0]), s.predicted.top.map((c) => c.model));
  assert.ok(Math.abs(shown[0][1] - 100 * p[0]) < 1, `the panel shows ${shown[0][1]}% for ${p[0]}`);
  assert.match(await page.textContent('[data-testid=texture-predicted]'), /^Predicted model: /);
  assert.equal(await page.getAttribute('[data-testid=texture-predicted]', 'data-close'), 'true');

  await drop(page, 'ramp.png', await picture(page, 'ramp'));
  s = await state(page);
  assert.equal(s.predicted.close, false, `a ramp is no texture (nearest ${s.predicted.model})`);
  assert.match(await page.textContent('[data-testid=texture-predicted]'), /No close model/);
  assert.equal(await page.getAttribute('[data-testid=texture-predicted]', 'data-close'), 'false');
  assert.equal((await listed(page)).length, 3, 'the nearest three are still listed');
  assert.match(await page.textContent('[data-testid=texture-status]'), /no close model/);

  // The answer is part of the document: a reload shows it again.
  await page.waitForTimeout(700); // the autosave is debounced
  await page.reload();
  await page.waitForFunction(settled, null, { timeout: 45000 });
  s = await state(page);
  assert.equal(s.source.name, 'ramp.png');
  assert.equal(s.predicted.close, false);
  assert.match(await page.textContent('[data-testid=texture-predicted]'), /No close model/);
  assert.equal((await listed(page)).length, 3);
});
