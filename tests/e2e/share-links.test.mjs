// Links carry everything or say what they leave out (issue 35 item 6): a
// Texture example (256² grey noise, ~100 KB of PNG) travels in the link (its grey pixels,
// deflated, within the 96 KB a link holds) and a fresh browser opening the
// link has the same pixels; an
// example too big for a link is named before anything is copied, and the
// link copied on the user's word leaves it out and says so.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { launch, dropFile, rgbPng } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const state = (page) => page.evaluate(() => window.filigree.testHooks.texture.state());
const settled = () => !!window.filigree?.testHooks?.texture && !window.filigree.testHooks.texture.pending()
  && !!document.querySelector('[data-testid=texture-retrieved][data-model]');

/** Seeded noise, so the example is the same bytes on every run. */
function noise(seed) {
  let s = seed >>> 0;
  return () => { s = (Math.imul(s, 1664525) + 1013904223) >>> 0; return s / 2 ** 32; };
}

async function copyLink(page) {
  await page.click('button[data-act=copy-link]');
  return page.waitForSelector('.toast[data-link], .toast[data-omits]');
}

test('a Texture link carries a full-size grey example: a fresh browser opening it has the same example', async () => {
  const page = await env.newPage({ path: '#tool=texture' });
  await page.waitForFunction(settled, null, { timeout: 45000 });
  // Grey noise of all 256 levels, the worst case of a kept example: a grey
  // PNG of ~100 KB from the browser's encoder (the example was 52 KB).
  const rnd = noise(7);
  const png = await rgbPng(256, 256, () => { const v = Math.floor(rnd() * 256); return [v, v, v]; });
  await dropFile(page, '[data-testid=texture-drop]', { name: 'grain.png', bytes: png, type: 'image/png' });
  await page.waitForFunction(() => window.filigree.testHooks.texture.state()?.source?.name === 'grain.png', null, { timeout: 30000 });
  await page.waitForFunction(settled, null, { timeout: 30000 });
  const mine = await state(page);
  const size = mine.source.png.length;
  // As PNG bytes it could not fit: base64 makes 72 KB into 96.
  assert.ok(size > 72 * 1024, `the kept example is ${size} bytes`);

  const toast = await copyLink(page);
  assert.equal(await toast.getAttribute('data-omits'), null, await toast.textContent());
  console.log(`example: ${size} bytes of PNG; link: ${(await toast.getAttribute('data-link')).length} characters`);
  const link = await toast.getAttribute('data-link');
  assert.doesNotMatch(await toast.textContent(), /leaves out/);
  assert.ok(link.length < 96 * 1024 + 200, `the link is ${link.length} characters`);

  // A fresh browser (its own storage) opens the link: the example is there, pixel for pixel.
  const other = await env.newPage({ path: null });
  await other.goto(link);
  await other.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
  await other.waitForFunction(settled, null, { timeout: 45000 });
  const theirs = await state(other);
  assert.equal(theirs.source?.kind, 'image', 'the example came with the link');
  assert.equal(theirs.source.name, 'grain.png');
  assert.deepEqual(theirs.scales, mine.scales);
  assert.deepEqual(theirs.predicted, mine.predicted);
  const pixels = (p) => p.evaluate(async () => {
    const { png } = window.filigree.testHooks.texture.state().source;
    const bmp = await createImageBitmap(new Blob([png], { type: 'image/png' }));
    const c = new OffscreenCanvas(bmp.width, bmp.height);
    c.getContext('2d').drawImage(bmp, 0, 0);
    const d = c.getContext('2d').getImageData(0, 0, bmp.width, bmp.height).data;
    let h = 2166136261;
    for (const b of d) h = Math.imul(h ^ b, 16777619);
    return { w: bmp.width, h: bmp.height, hash: h >>> 0 };
  });
  assert.deepEqual(await pixels(other), await pixels(page), 'the same pixels');
  // And it is drawn: the example canvas is not blank.
  await other.waitForFunction(() => {
    const c = document.querySelector('[data-testid=texture-example]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let lo = 255, hi = 0;
    for (let i = 0; i < d.length; i += 4) { lo = Math.min(lo, d[i]); hi = Math.max(hi, d[i]); }
    return hi - lo > 100;
  }, null, { timeout: 15000 });
  await other.close();
  await page.close();
});

test('an example too big for a link is named before copying; the link copied on the user\'s word leaves it out and says so', async () => {
  const page = await env.newPage({ path: '#tool=texture' });
  await page.waitForFunction(settled, null, { timeout: 45000 });
  // The user's project file holds a 150 KB colour example (a project keeps up to 256 KB).
  const doc = await state(page);
  const rnd = noise(11);
  const big = await rgbPng(224, 224, () => [rnd() * 256, rnd() * 256, rnd() * 256].map(Math.floor));
  assert.ok(big.length > 140 * 1024 && big.length < 256 * 1024, `${big.length} bytes`);
  const encode = (v) => (v && typeof v === 'object' && !Array.isArray(v)
    ? Object.fromEntries(Object.entries(v).map(([k, x]) => [k, encode(x)])) : Array.isArray(v) ? v.map(encode) : v);
  const project = {
    format: 'filigree-project', version: 2, tool: 'texture', stateVersion: 1,
    state: { ...encode(doc), source: { kind: 'image', name: 'big.png', png: { $bytes: big.toString('base64') } } },
  };
  const file = path.join(fs.mkdtempSync(path.join(os.tmpdir(), 'filigree-')), 'big.filigree.json');
  fs.writeFileSync(file, JSON.stringify(project));
  await page.setInputFiles('input[data-input=project]', file);
  await page.waitForFunction(() => window.filigree.testHooks.texture.state()?.source?.name === 'big.png', null, { timeout: 30000 });

  const toast = await copyLink(page);
  assert.equal(await toast.getAttribute('data-omits'), 'the example');
  assert.equal(await toast.getAttribute('data-link'), null, 'nothing is copied before the user agrees');
  const words = await toast.textContent();
  const m = /leaves out the example \((\d+) KB > the 96 KB a link holds\)/.exec(words);
  assert.ok(m, words);
  assert.ok(Number(m[1]) > 96, `${m[1]} KB`);

  await page.click('.toast[data-omits] button:text("Copy link without it")');
  const copied = await page.waitForSelector('.toast[data-link]');
  assert.match(await copied.textContent(), /It leaves out the example/);
  const link = await copied.getAttribute('data-link');
  const other = await env.newPage({ path: null });
  await other.goto(link);
  await other.waitForFunction(() => window.filigree?.testHooks?.texture?.state(), null, { timeout: 45000 });
  const theirs = await state(other);
  assert.equal(theirs.source, null, 'the example was left out, as the page said');
  assert.deepEqual(theirs.scales, doc.scales, 'everything else came');
  await other.close();
  await page.close();
});
