// The Micro panel (issue 12, MISSION M7, S8–S10): a shipped scene rendered
// by the core in a worker (`micro-render`), orbiting by dragging (small
// previews while dragging, the full image once the gesture ends), zooming
// by the camera distance, JSON errors marked in the scene editor at the
// core's line, the slice view (`micro-slice`), and the document kept by the
// autosave across a reload. WebGL2 is hidden here so the worker path is
// what runs; the GPU view has its own tests (micro-gl.test.mjs).
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { launch, ROOT } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const runs = (page) => page.$eval('[data-testid=micro-status]', (el) => Number(el.dataset.runs || 0));

/** Wait until the panel has shown one more full image than `previous` and nothing is due. */
async function waitForRender(page, previous, timeout = 90000) {
  await page.waitForFunction((prev) => {
    const el = document.querySelector('[data-testid=micro-status]');
    return Number(el.dataset.runs || 0) > prev && !window.filigree.testHooks.micro.pending();
  }, previous, { timeout });
  return runs(page);
}

/** The canvas's pixels, summarised: how many differ from the background, their brightness spread. */
const pixels = (page) => page.evaluate(() => {
  const c = document.querySelector('[data-testid=micro-canvas]');
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  const bg = [d[0], d[1], d[2]];
  let fg = 0, lo = 255, hi = 0, sum = 0;
  for (let i = 0; i < d.length; i += 4) {
    if (Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]) <= 6) continue;
    fg++;
    const y = 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2];
    sum += y;
    lo = Math.min(lo, y);
    hi = Math.max(hi, y);
  }
  window.microBefore = d;
  return { width: c.width, height: c.height, fg, spread: hi - lo, mean: fg ? sum / fg : 0, total: d.length / 4 };
});

/** Fraction of pixels that differ from the last `pixels` call's picture. */
const changed = (page) => page.evaluate(() => {
  const c = document.querySelector('[data-testid=micro-canvas]');
  const a = window.microBefore;
  const b = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  if (a.length !== b.length) return 1;
  let n = 0;
  for (let i = 0; i < a.length; i += 4) if (a[i] !== b[i] || a[i + 1] !== b[i + 1] || a[i + 2] !== b[i + 2]) n++;
  return n / (a.length / 4);
});

const state = (page) => page.evaluate(() => window.filigree.testHooks.micro.state());

/** The panel with WebGL2 hidden: the worker (CPU) path this file is about.
 * The GPU view has its own tests (micro-gl.test.mjs). */
async function cpuPage(path) {
  // A quarter of the device pixels a side (the panel's picture is its
  // width in device pixels, at most 384): about 1/6 of the pixels to trace,
  // the same checks.
  const page = await env.newPage({ path: null, deviceScaleFactor: 0.25 });
  await page.addInitScript(() => {
    const get = HTMLCanvasElement.prototype.getContext;
    HTMLCanvasElement.prototype.getContext = function (type, ...rest) {
      return type === 'webgl2' ? null : get.call(this, type, ...rest);
    };
  });
  await page.goto(`${env.url}${path}`);
  await page.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
  return page;
}

test('micro: gyroid renders, orbit and zoom re-render, JSON errors are marked, slice view, autosave', async () => {
  const page = await cpuPage('#tool=micro');
  await page.waitForSelector('[data-testid=micro-examples] [data-example=gyroid]', { timeout: 30000 });
  let n = await runs(page);
  // Pick another scene first so that picking the gyroid is a real change.
  await page.click('[data-example=spheres]');
  n = await waitForRender(page, n);
  await page.click('[data-example=gyroid]');
  n = await waitForRender(page, n);
  assert.equal((await state(page)).example, 'gyroid');
  assert.equal(await page.getAttribute('[data-example=gyroid]', 'aria-pressed'), 'true');
  const first = await pixels(page);
  assert.ok(first.fg > first.total * 0.2, `the gyroid covers the picture (${first.fg} of ${first.total} pixels)`);
  assert.ok(first.spread > 40, `shaded, not flat (brightness spread ${first.spread})`);
  assert.match(await page.textContent('[data-testid=micro-status]'), /rays hit.*field evaluations/);

  // Orbit: drag across the canvas; previews while dragging, then the full image.
  const camera0 = (await state(page)).camera;
  const box = await page.locator('[data-testid=micro-canvas]').boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  for (let i = 1; i <= 10; i++) {
    await page.mouse.move(cx + i * 8, cy + i * 3);
    await page.waitForTimeout(30);
  }
  await page.mouse.up();
  n = await waitForRender(page, n);
  const camera1 = (await state(page)).camera;
  assert.notEqual(camera1.yaw, camera0.yaw, 'the drag turned the camera');
  assert.notEqual(camera1.pitch, camera0.pitch);
  assert.ok(Number(await page.$eval('[data-testid=micro-status]', (el) => el.dataset.previews || 0)) >= 1, 'small previews while dragging');
  assert.equal((await page.evaluate(() => window.filigree.testHooks.micro.last())).preview, false, 'the full image after the drag');
  assert.ok(await changed(page) > 0.05, 'the orbit changed the picture');

  // Zoom in three times: the distance multiplies and the picture is rendered again.
  await pixels(page);
  for (let i = 0; i < 3; i++) await page.click('button[data-act=zoom-in]');
  n = await waitForRender(page, n);
  const camera2 = (await state(page)).camera;
  assert.ok(Math.abs(camera2.distance - camera1.distance / 1.5 ** 3) < 1e-9, `distance ${camera1.distance} → ${camera2.distance}`);
  assert.ok(await changed(page) > 0.05, 'the zoom changed the picture');
  assert.match(await page.textContent('[data-testid=micro-status]'), /zoom ×3\.38/);

  // A JSON error is marked at the core's line.
  const bad = '{"type": "tpms",\n "surface": "gyroid",\n "period": 0.5,,\n "thickness": 0.35}';
  await page.fill('[data-testid=micro-scene]', bad);
  await page.waitForSelector('[data-testid=doc-error]:not([hidden])', { timeout: 30000 });
  const msg = await page.textContent('[data-testid=doc-error]');
  assert.match(msg, /line 3, column \d+/);
  const line = await page.waitForFunction(() => {
    const cm = document.querySelector('.micro-editor .cm-lintRange-error');
    if (cm) {
      const lines = [...document.querySelectorAll('.micro-editor .cm-line')];
      return lines.indexOf(cm.closest('.cm-line')) + 1;
    }
    const note = [...document.querySelectorAll('.micro-editor .code-editor *')].find((e) => !e.hidden && /^line \d+/.test(e.textContent));
    return note ? Number(/^line (\d+)/.exec(note.textContent)[1]) : 0;
  }, null, { timeout: 15000 });
  assert.equal(await line.jsonValue(), 3, 'the error is marked on line 3');
  assert.equal((await state(page)).example, null, 'an edited scene is no longer the example');

  // Back to the gyroid; the slice view shows another picture.
  await page.click('[data-example=gyroid]');
  n = await waitForRender(page, n);
  await page.waitForSelector('[data-testid=doc-error]', { state: 'hidden' });
  await pixels(page);
  await page.check('[data-testid=micro-slice-toggle]');
  n = await waitForRender(page, n);
  assert.equal((await state(page)).view, 'slice');
  assert.equal((await page.evaluate(() => window.filigree.testHooks.micro.last())).kind, 'micro-slice');
  assert.ok(await changed(page) > 0.2, 'the slice is a different picture');
  assert.match(await page.textContent('[data-testid=micro-status]'), /slice z = 0.*inside/);
  // Moving the slice plane changes the slice.
  await pixels(page);
  await page.$eval('[data-testid=micro-z]', (el) => { el.value = '0.3'; el.dispatchEvent(new Event('input', { bubbles: true })); });
  n = await waitForRender(page, n);
  assert.ok(await changed(page) > 0.05, 'another z, another slice');

  // Reload: the autosave brings the document back (example, camera, view).
  const saved = await state(page);
  await page.waitForTimeout(1500);
  await page.reload();
  await page.waitForFunction(() => window.filigree?.testHooks?.micro?.state(), null, { timeout: 30000 });
  await waitForRender(page, 0);
  const back = await state(page);
  assert.equal(back.example, 'gyroid');
  assert.deepEqual(back.camera, saved.camera);
  assert.equal(back.view, 'slice');
  assert.equal(back.z, saved.z);
  await page.context().close();
});

test('micro: pan moves the target, a particle size in the parameters changes the render, the scene JSON and a PNG export', async () => {
  const page = await cpuPage('#tool=micro');
  await page.waitForSelector('[data-testid=micro-examples] [data-example=spheres]', { timeout: 30000 });
  let n = await waitForRender(page, 0);
  await page.click('[data-example=spheres]');
  n = await waitForRender(page, n);

  // Shift-drag pans: the target moves in the view plane, yaw and pitch stay.
  const c0 = (await state(page)).camera;
  const box = await page.locator('[data-testid=micro-canvas]').boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  await pixels(page);
  await page.keyboard.down('Shift');
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  for (let i = 1; i <= 6; i++) { await page.mouse.move(cx + i * 6, cy); await page.waitForTimeout(30); }
  await page.mouse.up();
  await page.keyboard.up('Shift');
  n = await waitForRender(page, n);
  const c1 = (await state(page)).camera;
  assert.equal(c1.yaw, c0.yaw, 'a pan does not orbit');
  assert.equal(c1.pitch, c0.pitch);
  assert.equal(c1.distance, c0.distance);
  const moved = Math.hypot(...c1.target.map((v, i) => v - c0.target[i]));
  assert.ok(moved > 0.05, `the target moved (${moved})`);
  // Dragging right moves the target to the left of the view: against the camera's right vector.
  const yaw = c0.yaw * Math.PI / 180;
  const right = [-Math.sin(yaw), Math.cos(yaw)]; // forward × z, forward = −(cos yaw, sin yaw) in the plane
  assert.ok((c1.target[0] - c0.target[0]) * right[0] + (c1.target[1] - c0.target[1]) * right[1] < 0, 'against the right vector');
  assert.ok(await changed(page) > 0.05, 'the pan changed the picture');
  // Undo brings the target back.
  await page.click('button[data-act=undo]');
  n = await waitForRender(page, n);
  assert.deepEqual((await state(page)).camera, c0);

  // The parameters: one fieldset per node, a field per number; the largest
  // particle size changes the scene JSON and the picture.
  await page.click('[data-testid=micro-params] summary');
  const field = page.locator('[data-testid=micro-params] input[data-pointer="/size/max"]');
  assert.equal(Number(await field.inputValue()), JSON.parse((await state(page)).scene).size.max);
  assert.equal(await page.locator('[data-testid=micro-params] fieldset[data-node="/"] legend').textContent(), 'particles');
  await pixels(page);
  await field.fill('0.2');
  await field.press('Enter');
  n = await waitForRender(page, n);
  const doc = await state(page);
  assert.equal(JSON.parse(doc.scene).size.max, 0.2);
  assert.equal(doc.example, null, 'an edited scene is no longer the example');
  assert.ok(await changed(page) > 0.05, 'smaller particles, another picture');
  // The editor shows the new JSON.
  await page.waitForFunction(() => /"max": 0.2/.test(document.querySelector('.micro-editor').textContent), null, { timeout: 15000 });
  // Nested nodes get their own fieldsets (a union of two clouds).
  await page.click('[data-example=multiscale]');
  n = await waitForRender(page, n);
  const nodes = await page.$$eval('[data-testid=micro-params] fieldset', (fs) => fs.map((f) => f.dataset.node));
  assert.deepEqual(nodes.slice(0, 3), ['/', '/children/0', '/children/1']);
  assert.ok(await page.locator('[data-testid=micro-params] input[data-pointer="/children/2/size/radius"]').count() === 1);

  // Export the scene JSON: the document's scene, as a file.
  const [dl] = await Promise.all([page.waitForEvent('download'), page.click('[data-testid=micro-export-json]')]);
  assert.equal(dl.suggestedFilename(), 'multiscale.json');
  const text = fs.readFileSync(await dl.path(), 'utf8');
  assert.equal(text, (await state(page)).scene);

  // Export PNG of the slice view: a full-size PNG of the document's view.
  await page.check('[data-testid=micro-slice-toggle]');
  n = await waitForRender(page, n);
  const [png] = await Promise.all([page.waitForEvent('download'), page.click('button[data-act=export-png]')]);
  assert.equal(png.suggestedFilename(), 'multiscale-slice.png');
  const bytes = fs.readFileSync(await png.path());
  assert.equal(bytes.subarray(1, 4).toString('latin1'), 'PNG');
  assert.deepEqual([bytes.readUInt32BE(16), bytes.readUInt32BE(20)], [768, 768], 'twice the panel\'s largest side');
  await page.context().close();
});

test('micro: a share link carries the scene by name and the camera; undo steps back through zooms', async () => {
  const a = await cpuPage('#tool=micro');
  await a.waitForSelector('[data-testid=micro-examples] [data-example=piled]', { timeout: 30000 });
  // The first picture (it may be done already: more than 0 runs, nothing due).
  let n = await waitForRender(a, 0);
  await a.click('[data-example=piled]');
  n = await waitForRender(a, n);
  await a.selectOption('[data-testid=micro-steps]', 'adaptive');
  n = await waitForRender(a, n);
  assert.match(await a.textContent('[data-testid=micro-status]'), /adaptive steps/);
  const before = (await state(a)).camera;
  await a.click('button[data-act=zoom-in]');
  n = await waitForRender(a, n);
  const zoomed = (await state(a)).camera;
  assert.ok(Math.abs(zoomed.distance - before.distance / 1.5) < 1e-9);
  // Undo: the camera comes back and the picture is rendered again.
  await a.click('button[data-act=undo]');
  n = await waitForRender(a, n);
  assert.deepEqual((await state(a)).camera, before);
  await a.click('button[data-act=redo]');
  n = await waitForRender(a, n);
  assert.deepEqual((await state(a)).camera, zoomed);
  const want = await state(a);

  await a.click('button[data-act=copy-link]');
  await a.waitForSelector('.toast[data-link]');
  const link = await a.$eval('.toast[data-link]', (t) => t.dataset.link);
  assert.match(link, /#tool=micro&share=[A-Za-z0-9_-]+$/);
  assert.ok(link.length < 400, `a shipped scene travels by name (${link.length} characters)`);
  const b = await cpuPage(link.slice(link.indexOf('#')));
  await b.waitForFunction(() => window.filigree?.testHooks?.micro?.state()?.example === 'piled', null, { timeout: 30000 });
  await waitForRender(b, 0);
  assert.deepEqual(await state(b), want);
  await a.context().close();
  await b.context().close();
});

/** Decode an 8-bit RGB or RGBA PNG (non-interlaced, as the core writes them) to RGBA. */
function decodePng(buf) {
  assert.equal(buf.toString('latin1', 1, 4), 'PNG');
  let off = 8, w = 0, h = 0, bpp = 0;
  const idat = [];
  while (off < buf.length) {
    const len = buf.readUInt32BE(off);
    const type = buf.toString('latin1', off + 4, off + 8);
    const data = buf.subarray(off + 8, off + 8 + len);
    if (type === 'IHDR') {
      w = data.readUInt32BE(0);
      h = data.readUInt32BE(4);
      assert.equal(data[8], 8, '8-bit');
      assert.equal(data[12], 0, 'not interlaced');
      bpp = { 2: 3, 6: 4 }[data[9]];
      assert.ok(bpp, `colour type ${data[9]}`);
    } else if (type === 'IDAT') idat.push(data);
    else if (type === 'IEND') break;
    off += 12 + len;
  }
  const raw = zlib.inflateSync(Buffer.concat(idat));
  const stride = w * bpp;
  const out = Buffer.alloc(w * h * 4);
  let prev = Buffer.alloc(stride);
  for (let y = 0; y < h; y++) {
    const f = raw[y * (stride + 1)];
    const line = raw.subarray(y * (stride + 1) + 1, (y + 1) * (stride + 1));
    const cur = Buffer.alloc(stride);
    for (let i = 0; i < stride; i++) {
      const a = i >= bpp ? cur[i - bpp] : 0, b = prev[i], c = i >= bpp ? prev[i - bpp] : 0;
      let pred = 0;
      if (f === 1) pred = a;
      else if (f === 2) pred = b;
      else if (f === 3) pred = (a + b) >> 1;
      else if (f === 4) {
        const p = a + b - c, pa = Math.abs(p - a), pb = Math.abs(p - b), pc = Math.abs(p - c);
        pred = pa <= pb && pa <= pc ? a : pb <= pc ? b : c;
      }
      cur[i] = (line[i] + pred) & 255;
    }
    for (let x = 0; x < w; x++) {
      for (let k = 0; k < 3; k++) out[(y * w + x) * 4 + k] = cur[x * bpp + k];
      out[(y * w + x) * 4 + 3] = bpp === 4 ? cur[x * bpp + 3] : 255;
    }
    prev = cur;
  }
  return { width: w, height: h, data: out };
}

/** Run one request in the page's worker pool (the wasm core); its PNG bytes. */
const workerPng = (page, kind, req) => page.evaluate(async ({ kind, req }) => {
  const r = await window.filigree.pool.run(kind, req);
  const png = r.png instanceof Uint8Array ? r.png : new Uint8Array(r.png);
  let bin = '';
  for (let i = 0; i < png.length; i += 0x8000) bin += String.fromCharCode.apply(null, png.subarray(i, i + 0x8000));
  return btoa(bin);
}, { kind, req }).then((b) => Buffer.from(b, 'base64'));

/** The panel's last tiled picture (RGBA). */
const frame = async (page) => Buffer.from(await page.evaluate(() => window.filigree.testHooks.micro.frame()), 'base64');

test('micro: the picture in tiles over the pool equals one job; shading controls; progressive path tracing; wasm = native bytes', async () => {
  const page = await cpuPage('#tool=micro');
  await page.waitForSelector('[data-testid=micro-examples] [data-example=piled]', { timeout: 30000 });
  let n = await waitForRender(page, 0);
  await page.click('[data-example=piled]');
  n = await waitForRender(page, n);
  // Tiles: every tile drawn as it came; together, pixel for pixel, the one-job PNG.
  let last = await page.evaluate(() => window.filigree.testHooks.micro.last());
  assert.equal(last.tiles, 16);
  assert.match(await page.textContent('[data-testid=micro-status]'), /on the CPU in 16 tiles/);
  let req = await page.evaluate(() => window.filigree.testHooks.micro.request());
  assert.equal(req.tile, undefined);
  let one = decodePng(await workerPng(page, 'micro-render', req));
  assert.equal(one.width, last.width);
  let tiled = await frame(page);
  assert.equal(tiled.length, one.data.length);
  assert.ok(tiled.equals(one.data), 'the tiled picture is the one-job picture, pixel for pixel');

  // Shading: GGX with its roughness and specular, then absorption; undo goes back.
  await pixels(page);
  await page.selectOption('[data-testid=micro-shading]', 'ggx');
  n = await waitForRender(page, n);
  assert.equal((await state(page)).shading, 'ggx');
  assert.equal(await page.isVisible('[data-testid=micro-roughness]'), true);
  assert.ok(await changed(page) > 0.05, 'GGX changed the picture');
  await page.$eval('[data-testid=micro-roughness]', (el) => { el.value = '0.15'; el.dispatchEvent(new Event('input', { bubbles: true })); el.dispatchEvent(new Event('change', { bubbles: true })); });
  n = await waitForRender(page, n);
  assert.equal((await state(page)).roughness, 0.15);
  const bright = await pixels(page);
  await page.$eval('[data-testid=micro-absorption]', (el) => { el.value = '2'; el.dispatchEvent(new Event('input', { bubbles: true })); el.dispatchEvent(new Event('change', { bubbles: true })); });
  n = await waitForRender(page, n);
  assert.equal((await state(page)).absorption, 2);
  assert.ok(await changed(page) > 0.05, 'absorption changed the picture');
  const dark = await pixels(page);
  assert.ok(dark.mean < bright.mean, `absorbed: darker (mean brightness ${dark.mean.toFixed(1)} < ${bright.mean.toFixed(1)})`);
  await page.click('button[data-act=undo]');
  n = await waitForRender(page, n);
  assert.equal((await state(page)).absorption, 0);
  assert.equal((await state(page)).roughness, 0.15);

  // Progressive path tracing: 4 samples in passes of 1, 1, 2, the pass count shown.
  await page.evaluate(() => {
    const el = document.querySelector('[data-testid=micro-status]');
    window.microPasses = [];
    new MutationObserver(() => window.microPasses.push(Number(el.dataset.passes || 0))).observe(el, { attributes: true, attributeFilter: ['data-passes'] });
  });
  await page.selectOption('[data-testid=micro-spp]', '4');
  n = await waitForRender(page, n);
  const doc = await state(page);
  assert.equal(doc.spp, 4);
  last = await page.evaluate(() => window.filigree.testHooks.micro.last());
  assert.equal(last.passes, 3);
  assert.deepEqual((await page.evaluate(() => window.microPasses)).filter((p) => p > 0), [1, 2, 3], 'one pass after another');
  assert.match(await page.textContent('[data-testid=micro-status]'), /path traced on the CPU, 4 samples per pixel in 3 passes/);
  assert.equal(await page.isEnabled('[data-testid=micro-max-depth]'), true);
  // The passes average to the one-job render with all the samples (float sums: within one level).
  req = await page.evaluate(() => window.filigree.testHooks.micro.request());
  one = decodePng(await workerPng(page, 'micro-render', req));
  tiled = await frame(page);
  let off = 0;
  for (let i = 0; i < tiled.length; i++) {
    const d = Math.abs(tiled[i] - one.data[i]);
    assert.ok(d <= 1, `byte ${i}: ${tiled[i]} vs ${one.data[i]}`);
    off += d > 0;
  }
  assert.ok(off < tiled.length / 100, `nearly all levels equal (${off} differ)`);
  // A share link carries the shading and the path tracing.
  await page.click('button[data-act=copy-link]');
  await page.waitForSelector('.toast[data-link]');
  const link = await page.$eval('.toast[data-link]', (t) => t.dataset.link);
  const b = await cpuPage(link.slice(link.indexOf('#')));
  await b.waitForFunction(() => window.filigree?.testHooks?.micro?.state()?.spp === 4, null, { timeout: 30000 });
  const bs = await state(b);
  assert.deepEqual(bs, doc);
  await b.context().close();

  // wasm = native: the worker's bytes for the shared requests are the native core's files.
  const dir = path.join(ROOT, 'tests/fixtures/micro-native');
  const list = JSON.parse(fs.readFileSync(path.join(dir, 'requests.json'), 'utf8')).requests;
  assert.ok(list.some((r) => r.kind === 'micro-slice') && list.some((r) => r.request.spp > 0));
  for (const steps of ['fixed', 'bisection', 'adaptive']) assert.ok(list.some((r) => r.request.steps === steps), steps);
  for (const r of list) {
    const scene = fs.readFileSync(path.join(ROOT, 'assets/micro', `${r.scene}.json`), 'utf8');
    const got = await workerPng(page, r.kind, { ...r.request, scene });
    const want = fs.readFileSync(path.join(dir, `${r.name}.png`));
    assert.ok(got.equals(want), `${r.name}: wasm bytes equal the native core's (${got.length} vs ${want.length} bytes)`);
  }
  await page.context().close();
});
