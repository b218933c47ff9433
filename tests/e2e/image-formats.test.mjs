// Fit sends the core the pixels of the user's image (the browser decodes the
// PNG, JPEG, WebP or GIF; src/raster/image_buf.rs `decode_file`), so its wasm
// module carries no image decoder at all. A JPEG or WebP uploaded as a Fit
// target is still read, and nothing but the Fit module is fetched for it; a
// PNG file sent to the Fit module is refused as unsupported, and a PNG whose
// header declares a size over the core's limits is refused by the page
// before the browser decodes it.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch, pickGenerator } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

/** A 200 × 160 picture of red stripes on cream, encoded by the browser as `type`. */
const encoded = (page, type) => page.evaluate(async (type) => {
  const c = new OffscreenCanvas(200, 160);
  const g = c.getContext('2d');
  g.fillStyle = '#fdf2e9';
  g.fillRect(0, 0, 200, 160);
  g.fillStyle = '#c0392b';
  for (let x = 0; x < 200; x += 40) g.fillRect(x, 0, 16, 160);
  const blob = await c.convertToBlob({ type, quality: 0.95 });
  return { type: blob.type, bytes: [...new Uint8Array(await blob.arrayBuffer())] };
}, type);

for (const [type, name] of [['image/jpeg', 'stripes.jpg'], ['image/webp', 'stripes.webp']]) {
  test(`fit: a ${type.slice(6).toUpperCase()} target is read through the page, with the Fit module only`, async () => {
    const page = await env.newPage({ path: '#tool=fit' });
    const modules = new Set();
    page.on('request', (r) => { const m = /filigree_(\w+)_bg\.wasm/.exec(r.url()); if (m) modules.add(m[1]); });
    await pickGenerator(page, 'dots'); // its colours: #c0392b on #fdf2e9
    const file = await encoded(page, type);
    assert.equal(file.type, type, `this browser encodes ${type}`);
    const [chooser] = await Promise.all([page.waitForEvent('filechooser'), page.click('.fit-target button.pick')]);
    await chooser.setFiles({ name, mimeType: type, buffer: Buffer.from(file.bytes) });
    await page.waitForFunction(() => /snapped/.test(document.querySelector('[data-testid=fit-status]').textContent)
      || !document.querySelector('[data-testid=doc-error]').hidden, null, { timeout: 30000 });
    assert.equal(await page.isHidden('[data-testid=doc-error]'), true, await page.textContent('[data-testid=doc-error]'));
    // The target holds the stripes: both colours, in about their shares (16 of every 40 px red).
    const red = await page.$eval('[data-testid=fit-target]', (c) => {
      const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
      let n = 0;
      for (let i = 0; i < d.length; i += 4) if (d[i] > 150 && d[i + 1] < 110) n++;
      return n / (d.length / 4);
    });
    assert.ok(red > 0.3 && red < 0.5, `red covers ${(red * 100).toFixed(1)}% of the target`);
    // The Fit module was loaded with the page; reading the file loaded no other
    // (the Inspect or Pixel module, which have the other decoders).
    assert.deepEqual([...modules].filter((m) => m !== 'fit'), [], `modules fetched for the file: ${[...modules].join(', ')}`);
  });
}

test('fit: the module reads pixels, not files; a PNG over the size limit is refused before it is decoded', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await pickGenerator(page, 'dots');
  // A PNG file sent as such: the Fit module has no decoder, and says so.
  const refused = await page.evaluate(async () => {
    const c = new OffscreenCanvas(8, 8);
    c.getContext('2d').fillRect(0, 0, 8, 8);
    const bytes = new Uint8Array(await (await c.convertToBlob({ type: 'image/png' })).arrayBuffer());
    const { program } = window.filigree.testHooks.fit.state();
    try {
      await window.filigree.pool.run('pattern-snap', { program, params: {}, bytes, size: 64 });
      return null;
    } catch (err) {
      return { kind: err.kind, field: err.field, message: err.message };
    }
  });
  assert.equal(refused?.kind, 'unsupported', JSON.stringify(refused));
  assert.equal(refused.field, 'bytes');
  // A PNG whose header says 20000 × 20000 (the file itself is tiny and broken):
  // refused by its declared size, with the limits in words.
  const png = Buffer.alloc(40);
  Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a, 0, 0, 0, 13, 0x49, 0x48, 0x44, 0x52]).copy(png);
  png.writeUInt32BE(20000, 16);
  png.writeUInt32BE(20000, 20);
  const [chooser] = await Promise.all([page.waitForEvent('filechooser'), page.click('.fit-target button.pick')]);
  await chooser.setFiles({ name: 'huge.png', mimeType: 'image/png', buffer: png });
  await page.waitForSelector('[data-testid=doc-error]:not([hidden])');
  assert.match(await page.textContent('[data-testid=doc-error]'), /^huge\.png is 20000×20000 pixels: images up to 4096 pixels a side/);
});
