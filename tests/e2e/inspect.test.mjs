import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { launch, dropFile, fixture, bigPng } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const resultText = (page, field) => page.textContent(`[data-testid=inspect-result] [data-field=${field}]`);

test('dropping a PNG shows its size, palette and thumbnail', async () => {
  const page = await env.newPage({ path: '#tool=inspect' });
  await dropFile(page, '[data-testid=drop-zone]', fixture('fish.png'));
  await page.waitForSelector('[data-testid=palette] li');
  assert.equal(await resultText(page, 'size'), '128 × 128 px');
  assert.equal(await resultText(page, 'colours'), '3');
  const swatches = await page.$$eval('[data-testid=palette] code', (els) => els.map((e) => e.textContent));
  assert.deepEqual(swatches, ['#5263ca', '#7a8bf1', '#000000']);
  // The thumbnail canvas really holds the fish: its most common opaque colour is the body blue.
  const px = await page.$eval('[data-testid=inspect-result] canvas', (c) => {
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    const counts = {};
    for (let i = 0; i < d.length; i += 4) if (d[i + 3] === 255) counts[`${d[i]},${d[i + 1]},${d[i + 2]}`] = (counts[`${d[i]},${d[i + 1]},${d[i + 2]}`] || 0) + 1;
    return Object.entries(counts).sort((a, b) => b[1] - a[1])[0][0];
  });
  assert.equal(px, '82,99,202');
});

test('bad files get a clear error and the next good file still works', async () => {
  const page = await env.newPage({ path: '#tool=inspect' });
  const zone = '[data-testid=drop-zone]';
  const error = '[data-testid=doc-error]';
  await dropFile(page, zone, fixture('fish.png'));
  await page.waitForSelector('[data-testid=palette] li');

  const png = fs.readFileSync(fixture('trunk.png'));
  await dropFile(page, zone, { name: 'broken.png', bytes: png.subarray(0, 200), type: 'image/png' });
  await page.waitForSelector(`${error}:not([hidden])`);
  assert.match(await page.textContent(error), /broken\.png: .*(damaged or truncated)/);
  // The last good result is still on screen.
  assert.equal(await resultText(page, 'name'), 'fish.png');

  await dropFile(page, zone, { name: 'notes.txt', bytes: Buffer.from('just some text'), type: 'text/plain' });
  await page.waitForFunction((sel) => document.querySelector(sel).textContent.startsWith('notes.txt'), error);
  assert.match(await page.textContent(error), /not an image/);

  await dropFile(page, zone, { name: 'huge.png', bytes: await bigPng(8000, 8000), type: 'image/png' });
  await page.waitForFunction((sel) => document.querySelector(sel).textContent.startsWith('huge.png'), error);
  assert.equal(await page.textContent(error), 'huge.png: 8000×8000 exceeds the 4096×4096 limit');

  await page.setInputFiles('[data-testid=drop-zone] input[type=file]', fixture('trunk.png'));
  await page.waitForFunction(() => document.querySelector('[data-field=name]').textContent === 'trunk.png');
  assert.equal(await page.isHidden(error), true);
  assert.match(await resultText(page, 'size'), /^\d+ × \d+ px$/);
});
