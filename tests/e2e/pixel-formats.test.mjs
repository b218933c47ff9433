// The Pixel module reads PNG only (src/raster/image_buf.rs `decode_sent`,
// `sent_header_size`): the page turns every image into PNG before the core
// sees it. A JPEG, GIF or WebP the user gives as the source or the element
// sheet is textured; an old document (a project file, an autosave) holding
// a JPEG or GIF image opens and renders; and nothing but the Pixel module
// is fetched for any of it.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { launch, fixture, ready } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const PNG_MAGIC = [0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a];
const ASSET = (name) => new URL(`../../assets/pixel/${name}`, import.meta.url).pathname;

/** A Pixel page that records which wasm modules it fetches. */
async function pixelPage() {
  const page = await env.newPage({ path: null });
  const modules = new Set();
  page.on('request', (r) => { const m = /filigree_(\w+)_bg\.wasm/.exec(r.url()); if (m) modules.add(m[1]); });
  await page.goto(`${env.url}#tool=pixel`);
  await ready(page, '#tool=pixel');
  await page.waitForFunction(() => window.filigree?.testHooks?.pixel?.state()?.example === 'fish');
  await settled(page);
  return { page, modules };
}

/** Wait until the panel has a result for its current document (or shows an error), and say which. */
async function settled(page) {
  await page.waitForFunction(() => {
    const h = window.filigree?.testHooks?.pixel;
    const err = document.querySelector('[data-testid=doc-error]');
    if (err && !err.hidden) return true;
    const el = document.querySelector('[data-testid=pixel-status]');
    return h && el?.textContent.startsWith('done') && !h.pending() && h.result();
  }, null, { timeout: 60000 });
  assert.equal(await page.isHidden('[data-testid=doc-error]'), true, await page.textContent('[data-testid=doc-error]'));
}

/** `bytes` (an array of numbers) as `type`, encoded by the browser: decoded, drawn, `convertToBlob`. */
const reencoded = (page, bytes, type) => page.evaluate(async ({ bytes, type }) => {
  const bmp = await createImageBitmap(new Blob([new Uint8Array(bytes)]));
  const c = new OffscreenCanvas(bmp.width, bmp.height);
  c.getContext('2d').drawImage(bmp, 0, 0);
  const blob = await c.convertToBlob({ type, quality: 0.95 });
  return { type: blob.type, bytes: [...new Uint8Array(await blob.arrayBuffer())] };
}, { bytes, type });

/** The RGBA pixels of image bytes, as the core decodes them. */
const pixels = (page, bytes) => page.evaluate(async (bytes) => {
  const img = await window.filigree.pool.run('decode-image', { bytes: new Uint8Array(bytes) }, { module: 'pixel' });
  return { width: img.width, height: img.height, rgba: [...img.rgba] };
}, bytes);

/**
 * A GIF89a of RGBA pixels (at most 255 opaque colours; alpha 0 is the
 * transparent index, drawn black): the browser encodes no GIF. Its LZW
 * data is literal 9-bit codes with a clear code every 250, which every
 * decoder reads.
 */
function gif({ width, height, rgba }) {
  const index = new Map();
  const palette = [[0, 0, 0]]; // 0: transparent
  const idx = new Uint8Array(width * height);
  for (let p = 0; p < width * height; p++) {
    const a = rgba[4 * p + 3];
    if (a === 0) continue;
    assert.equal(a, 255, 'a GIF pixel is opaque or transparent');
    const key = rgba.slice(4 * p, 4 * p + 3).join();
    if (!index.has(key)) { index.set(key, palette.length); palette.push(rgba.slice(4 * p, 4 * p + 3)); }
    idx[p] = index.get(key);
  }
  assert.ok(palette.length <= 256, `${palette.length} colours fit a GIF`);
  const codes = [];
  for (let p = 0; p < idx.length; p++) {
    if (p % 250 === 0) codes.push(256);
    codes.push(idx[p]);
  }
  codes.push(257);
  const lzw = [];
  let acc = 0, n = 0;
  for (const c of codes) {
    acc |= c << n; n += 9;
    while (n >= 8) { lzw.push(acc & 0xff); acc >>>= 8; n -= 8; }
  }
  if (n) lzw.push(acc & 0xff);
  const out = [...Buffer.from('GIF89a')];
  const u16 = (v) => [v & 0xff, v >> 8];
  out.push(...u16(width), ...u16(height), 0xf7, 0, 0);
  for (let i = 0; i < 256; i++) out.push(...(palette[i] ?? [0, 0, 0]));
  out.push(0x21, 0xf9, 4, 1, 0, 0, 0, 0); // transparent index 0
  out.push(0x2c, 0, 0, 0, 0, ...u16(width), ...u16(height), 0, 8);
  for (let i = 0; i < lzw.length; i += 255) {
    const block = lzw.slice(i, i + 255);
    out.push(block.length, ...block);
  }
  out.push(0, 0x3b);
  return out;
}

const isPng = (bytes) => PNG_MAGIC.every((b, i) => bytes[i] === b);
const docBytes = (page, field) => page.evaluate((f) => [...(window.filigree.testHooks.pixel.state()[f] ?? [])], field);

/** Pixels that differ between two decoded images of one size (alpha everywhere, colour where opaque). */
function differing(a, b) {
  assert.deepEqual([a.width, a.height], [b.width, b.height]);
  let n = 0;
  for (let p = 0; p < a.width * a.height; p++) {
    const i = 4 * p;
    if (a.rgba[i + 3] !== b.rgba[i + 3] || (a.rgba[i + 3] && (a.rgba[i] !== b.rgba[i] || a.rgba[i + 1] !== b.rgba[i + 1] || a.rgba[i + 2] !== b.rgba[i + 2]))) n++;
  }
  return n;
}

test('pixel: a JPEG, a GIF and a WebP source are turned into PNG in the page and textured, with the Pixel module only', async () => {
  const { page, modules } = await pixelPage();
  const fishPng = [...fs.readFileSync(ASSET('fish.png'))];
  const fish = await pixels(page, fishPng);
  const files = [
    { name: 'fish.jpg', ...(await reencoded(page, fishPng, 'image/jpeg')), want: 'image/jpeg', exact: false },
    { name: 'fish.webp', ...(await reencoded(page, fishPng, 'image/webp')), want: 'image/webp', exact: false },
    { name: 'fish.gif', type: 'image/gif', bytes: gif(fish), exact: true },
  ];
  for (const f of files) {
    assert.ok(!isPng(f.bytes), `${f.name} is not a PNG`);
    if (f.want) assert.equal(f.type, f.want, `this browser encodes ${f.want}`);
    const before = await page.evaluate(() => window.filigree.testHooks.pixel.state().source);
    await page.setInputFiles('input[data-input=source]', { name: f.name, mimeType: f.type, buffer: Buffer.from(f.bytes) });
    await page.waitForFunction((b) => window.filigree.testHooks.pixel.state().source !== b
      || !document.querySelector('[data-testid=doc-error]').hidden, before, { timeout: 30000 });
    await settled(page);
    const source = await docBytes(page, 'source');
    assert.ok(isPng(source), `${f.name}: the document holds a PNG`);
    assert.equal(await page.evaluate(() => window.filigree.testHooks.pixel.state().names.source), f.name);
    const got = await pixels(page, source);
    // The GIF holds the fish's exact colours: the PNG the page made has them all.
    if (f.exact) assert.equal(differing(got, fish), 0, `${f.name}: the fish's pixels`);
    else assert.deepEqual([got.width, got.height], [fish.width, fish.height]);
    const placed = await page.evaluate(() => window.filigree.testHooks.pixel.result().placed);
    assert.ok(placed > 0, `${f.name}: ${placed} elements placed`);
  }
  assert.deepEqual([...modules], ['pixel'], `modules fetched: ${[...modules].join(', ')}`);
});

test('pixel: a GIF element sheet with transparency keeps its pixels, and the fish is textured as with the PNG sheet', async () => {
  const { page, modules } = await pixelPage();
  const want = await page.evaluate(() => [...window.filigree.testHooks.pixel.result().rgba]);
  const sheetPng = [...fs.readFileSync(ASSET('fish_scale.png'))];
  const sheet = await pixels(page, sheetPng);
  assert.ok(sheet.rgba.some((v, i) => i % 4 === 3 && v === 0), 'the sheet has transparent pixels');
  await page.setInputFiles('input[data-input=sheet]', { name: 'scales.gif', mimeType: 'image/gif', buffer: Buffer.from(gif(sheet)) });
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state().names.sheet === 'scales.gif'
    || !document.querySelector('[data-testid=doc-error]').hidden, null, { timeout: 30000 });
  await settled(page);
  const stored = await docBytes(page, 'sheet');
  assert.ok(isPng(stored), 'the document holds a PNG sheet');
  assert.equal(differing(await pixels(page, stored), sheet), 0, 'the sheet\'s pixels, transparency included');
  const got = await page.evaluate(() => [...window.filigree.testHooks.pixel.result().rgba]);
  assert.equal(got.length, want.length);
  assert.equal(got.findIndex((v, i) => v !== want[i]), -1, 'the same result as with the PNG sheet');
  assert.deepEqual([...modules], ['pixel'], `modules fetched: ${[...modules].join(', ')}`);
});

test('pixel: an old project file with a JPEG source and an old autosave with a GIF source open and render, with the Pixel module only', async () => {
  const { page, modules } = await pixelPage();
  const fishPng = [...fs.readFileSync(ASSET('fish.png'))];
  const fish = await pixels(page, fishPng);
  const golden = await page.evaluate(() => [...window.filigree.testHooks.pixel.result().rgba]);

  // A project file saved when the source could be a JPEG: opened through the file input.
  const project = JSON.parse(fs.readFileSync(fixture('fish.filigree.json'), 'utf8'));
  assert.equal(project.tool, 'pixel');
  const jpeg = await reencoded(page, fishPng, 'image/jpeg');
  project.state.source = { $bytes: Buffer.from(jpeg.bytes).toString('base64') };
  project.state.strokes = [];
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'filigree-pixel-formats-'));
  const file = path.join(dir, 'old-jpeg.filigree.json');
  fs.writeFileSync(file, JSON.stringify(project));
  await page.setInputFiles('input[data-input=project]', file);
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state().strokes.length === 0
    || !document.querySelector('[data-testid=doc-error]').hidden, null, { timeout: 30000 });
  await settled(page);
  assert.ok(isPng(await docBytes(page, 'source')), 'the opened document holds a PNG source');
  assert.ok(await page.evaluate(() => window.filigree.testHooks.pixel.result().placed > 0), 'textured');

  // An autosave holding the fish as a GIF (what an older page stored), restored at load.
  await page.click('button[data-example=fish]');
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state().strokes.length > 0);
  await settled(page);
  await page.waitForTimeout(800); // the autosave is debounced
  const edited = await page.evaluate((bytes) => new Promise((resolve, reject) => {
    const open = indexedDB.open('filigree');
    open.onerror = () => reject(open.error);
    open.onsuccess = () => {
      const store = open.result.transaction('autosave', 'readwrite').objectStore('autosave');
      const get = store.get('pixel');
      get.onsuccess = () => {
        const v = get.result;
        if (!v?.state?.source) { reject(new Error('no Pixel autosave')); return; }
        v.state.source = new Uint8Array(bytes);
        for (const s of [...(v.history?.past ?? []), ...(v.history?.future ?? [])]) if (s?.source) s.source = new Uint8Array(bytes);
        const put = store.put(v, 'pixel');
        put.onsuccess = () => resolve(v.history?.past?.length ?? 0);
        put.onerror = () => reject(put.error);
      };
    };
  }), gif(fish));
  await page.reload();
  await page.waitForFunction(() => window.filigree?.testHooks?.pixel?.state()?.example === 'fish');
  await settled(page);
  const source = await docBytes(page, 'source');
  assert.ok(isPng(source), 'the restored document holds a PNG source');
  assert.equal(differing(await pixels(page, source), fish), 0, 'the fish\'s pixels');
  const got = await page.evaluate(() => [...window.filigree.testHooks.pixel.result().rgba]);
  assert.equal(got.findIndex((v, i) => v !== golden[i]), -1, 'the fish example\'s result');
  // Its undo history came back converted too: undo shows a PNG source (the project file's).
  if (edited > 0) {
    await page.waitForFunction(() => !document.querySelector('[data-act=undo]').disabled, null, { timeout: 30000 });
    await page.click('button[data-act=undo]');
    await settled(page);
    assert.ok(isPng(await docBytes(page, 'source')), 'the undone state holds a PNG source');
  }
  assert.deepEqual([...modules], ['pixel'], `modules fetched: ${[...modules].join(', ')}`);
});
