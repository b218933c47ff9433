// The Micro panel (issue 12, MISSION M7, S8–S10): a shipped scene rendered
// by the core in a worker (`micro-render`), orbiting by dragging (small
// previews while dragging, the full image once the gesture ends), zooming
// by the camera distance, JSON errors marked in the scene editor at the
// core's line, the slice view (`micro-slice`), and the document kept by the
// autosave across a reload. WebGL2 is hidden here so the worker path is
// what runs; the GPU view has its own tests (micro-gl.test.mjs).
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { launch } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
after(async () => { await env?.close(); });

const runs = (page) => page.$eval('[data-testid=micro-status]', (el) => Number(el.dataset.runs || 0));

/** Wait until the panel has shown one more full image than `previous` and nothing is due. */
async function waitForRender(page, previous, timeout = 90000) {
  await page.waitForFunction((prev) => {
    const el = document.querySelector('[data-testid=micro-status]');
    return Number(el.dataset.runs || 0) > prev && !window.filigreeMicro.pending();
  }, previous, { timeout });
  return runs(page);
}

/** The canvas's pixels, summarised: how many differ from the background, their brightness spread. */
const pixels = (page) => page.evaluate(() => {
  const c = document.querySelector('[data-testid=micro-canvas]');
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  const bg = [d[0], d[1], d[2]];
  let fg = 0, lo = 255, hi = 0;
  for (let i = 0; i < d.length; i += 4) {
    if (Math.abs(d[i] - bg[0]) + Math.abs(d[i + 1] - bg[1]) + Math.abs(d[i + 2] - bg[2]) <= 6) continue;
    fg++;
    const y = 0.299 * d[i] + 0.587 * d[i + 1] + 0.114 * d[i + 2];
    lo = Math.min(lo, y);
    hi = Math.max(hi, y);
  }
  window.microBefore = d;
  return { width: c.width, height: c.height, fg, spread: hi - lo, total: d.length / 4 };
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

const state = (page) => page.evaluate(() => window.filigreeMicro.state());

/** The panel with WebGL2 hidden: the worker (CPU) path this file is about.
 * The GPU view has its own tests (micro-gl.test.mjs). */
async function cpuPage(path) {
  const page = await env.newPage({ path: null });
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
  assert.equal((await page.evaluate(() => window.filigreeMicro.last())).preview, false, 'the full image after the drag');
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
  assert.equal((await page.evaluate(() => window.filigreeMicro.last())).kind, 'micro-slice');
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
  await page.waitForFunction(() => window.filigreeMicro?.state(), null, { timeout: 30000 });
  await waitForRender(page, 0);
  const back = await state(page);
  assert.equal(back.example, 'gyroid');
  assert.deepEqual(back.camera, saved.camera);
  assert.equal(back.view, 'slice');
  assert.equal(back.z, saved.z);
  await page.context().close();
});

test('micro: a share link carries the scene by name and the camera; undo steps back through zooms', async () => {
  const a = await cpuPage('#tool=micro');
  await a.waitForSelector('[data-testid=micro-examples] [data-example=piled]', { timeout: 30000 });
  let n = await waitForRender(a, await runs(a));
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
  await b.waitForFunction(() => window.filigreeMicro?.state()?.example === 'piled', null, { timeout: 30000 });
  await waitForRender(b, 0);
  assert.deepEqual(await state(b), want);
  await a.context().close();
  await b.context().close();
});
