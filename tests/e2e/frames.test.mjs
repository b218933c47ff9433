// The full app framed where storage and service workers may be refused: a
// cross-origin iframe, an iframe in an about:blank page, and the app served
// under a sub-path. It must work, say plainly when it cannot save, and keep
// the console free of error storms.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { launch, ROOT, dropFile, fixture } from './harness.mjs';
import { start } from '../../scripts/serve.mjs';

let env;
let host;
let hostUrl;
before(async () => {
  env = await launch();
  host = await start(0, path.join(ROOT, 'tests/e2e/pages'));
  hostUrl = `http://127.0.0.1:${host.address().port}/`;
});
afterEach(() => env?.closeTestPages());
after(async () => {
  await env?.close();
  await new Promise((r) => (host ? host.close(r) : r()));
});

/** Console errors of a page and its frames, plus uncaught errors inside every frame (read with frameErrors). */
async function watchErrors(page) {
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(e.message));
  await page.context().addInitScript(() => {
    window.__uncaught = [];
    addEventListener('error', (e) => window.__uncaught.push(String(e.message)));
    addEventListener('unhandledrejection', (e) => window.__uncaught.push(String(e.reason?.message ?? e.reason)));
  });
  return errors;
}
const frameErrors = (frame) => frame.evaluate(() => window.__uncaught);

const NOTE = /cannot save your work here/i;

/** Wait until the Fit panel in `frame` is usable: sliders and the preview drawn. */
async function fitWorks(frame) {
  await frame.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
  // (In an embed the sliders are in the closed drawer: there, not shown.)
  await frame.waitForSelector('[data-testid=fit-sliders] .row', { timeout: 15000, state: 'attached' });
  await frame.waitForFunction(() => {
    const c = document.querySelector('[data-testid=fit-overlay]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    for (let i = 3; i < d.length; i += 4) if (d[i]) return true;
    return false;
  }, null, { timeout: 15000 });
}

/** Whether the app in `frame` can save: the storage note is shown, or an autosave round-trips. */
async function storageFacts(frame) {
  return frame.evaluate(async () => {
    const el = document.querySelector('[data-testid=doc-note]');
    const note = Boolean(el && !el.hidden && /cannot save your work here/i.test(el.textContent));
    const idb = await Promise.race([
      new Promise((resolve) => {
        try {
          const r = indexedDB.open('filigree-probe');
          r.onsuccess = () => { r.result.close(); resolve('works'); };
          r.onerror = () => resolve('refused');
        } catch { resolve('throws'); }
      }),
      new Promise((resolve) => setTimeout(() => resolve('hangs'), 3000)),
    ]);
    return { note, idb };
  });
}

test('the app in a cross-origin iframe works and its storage state is said plainly', async () => {
  const page = await env.newPage({ path: null, serviceWorkers: 'allow' });
  const errors = await watchErrors(page);
  const swNoise = [];
  page.on('console', (m) => { if (/service ?worker/i.test(m.text())) swNoise.push(`${m.type()}: ${m.text()}`); });
  await page.goto(`${hostUrl}host.html?frame=${encodeURIComponent(`${env.url}#tool=fit`)}`);
  const frame = await (await page.waitForSelector('iframe')).contentFrame();
  await fitWorks(frame);
  const facts = await storageFacts(frame);
  // Chromium partitions a third-party frame's storage: either it works (and
  // the note stays away) or it does not (and the note says so).
  if (facts.idb === 'works') assert.equal(facts.note, false, 'no storage note where storage works');
  else assert.equal(facts.note, true, `storage ${facts.idb}, and the app says it cannot save`);
  // No service worker from a third-party frame, and nothing noisy about it.
  assert.equal(await frame.evaluate(() => { try { return navigator.serviceWorker?.controller ?? null; } catch { return null; } }), null);
  assert.deepEqual(swNoise, [], 'a framed app does not try to register a service worker (no refusal to log)');
  await page.waitForTimeout(1000);
  assert.deepEqual(errors, [], 'no console errors in a cross-origin frame');
  assert.deepEqual(await frameErrors(frame), [], 'no uncaught errors in the frame');
  console.log(`cross-origin frame: IndexedDB ${facts.idb}, storage note ${facts.note ? 'shown' : 'hidden'}`);
});

test('the app in an about:blank host works, says it cannot save there, and stays quiet', async () => {
  // An opaque about:blank page framing the app. Chromium's local-network
  // checks refuse a localhost frame in a page that is not local itself; a
  // deployed app is not on localhost, so they are turned off for this test.
  const blankEnv = await launch({ args: ['--disable-features=LocalNetworkAccessChecks'] });
  try {
    const page = await blankEnv.newPage({ path: null, serviceWorkers: 'allow' });
    const errors = await watchErrors(page);
    await page.goto('about:blank');
    await page.evaluate((src) => {
      const f = document.createElement('iframe');
      f.src = src;
      f.style.cssText = 'width:1200px;height:760px;border:0';
      document.body.append(f);
    }, `${blankEnv.url}#tool=fit`);
    const frame = await (await page.waitForSelector('iframe')).contentFrame();
    const t0 = Date.now();
    await fitWorks(frame);
    const facts = await storageFacts(frame);
    assert.notEqual(facts.idb, 'works', 'this host really blocks storage (else the test proves nothing)');
    await frame.waitForSelector('[data-testid=doc-note]:not([hidden])', { timeout: 5000 });
    assert.match(await frame.textContent('[data-testid=doc-note]'), NOTE);
    assert.ok(Date.now() - t0 < 20000, 'the panel did not wait on storage');
    // Editing still works there.
    const before = await frame.evaluate(() => window.filigree.testHooks.fit.state().values.join());
    await frame.$eval('[data-testid=fit-sliders] input[type=range]', (el) => {
      el.value = el.max;
      el.dispatchEvent(new Event('input', { bubbles: true }));
      el.dispatchEvent(new Event('change', { bubbles: true }));
    });
    await frame.waitForFunction((b) => window.filigree.testHooks.fit.state().values.join() !== b, before);
    await page.waitForTimeout(1000);
    assert.deepEqual(errors.filter((e) => !/autosave/i.test(e)), [], 'no console errors in an about:blank host');
    assert.deepEqual(await frameErrors(frame), [], 'no uncaught errors in the frame');
    console.log(`about:blank host: IndexedDB ${facts.idb}`);
  } finally {
    await blankEnv.close();
  }
});

test('the app under a sub-path (/sub/filigree/) loads, runs jobs and scopes its service worker there', async () => {
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'filigree-subpath-'));
  fs.mkdirSync(path.join(dir, 'sub'));
  fs.symlinkSync(ROOT, path.join(dir, 'sub', 'filigree'), 'dir');
  const server = await start(0, dir);
  const requests = [];
  try {
    const base = `http://localhost:${server.address().port}/sub/filigree/`;
    const context = await env.browser.newContext({ viewport: { width: 1280, height: 800 } });
    const page = await context.newPage();
    const errors = await watchErrors(page);
    page.on('request', (r) => requests.push(new URL(r.url()).pathname));
    page.on('response', (r) => { if (r.status() >= 400) errors.push(`${r.status()} ${r.url()}`); });
    await page.goto(`${base}#tool=inspect`);
    await page.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
    await dropFile(page, '[data-testid=drop-zone]', fixture('fish.png'));
    await page.waitForSelector('[data-testid=palette] li');
    const scope = await page.evaluate(async () => (await navigator.serviceWorker.ready).scope);
    assert.equal(scope, base, 'the service worker covers the sub-path, not the host root');
    // An embed under the sub-path works too.
    await page.goto(`${base}index.html?embed=1#tool=fit`);
    await page.waitForFunction(() => document.documentElement.dataset.embedReady === '1', null, { timeout: 30000 });
    await fitWorks(page.mainFrame());
    const outside = requests.filter((p) => !p.startsWith('/sub/filigree/'));
    assert.deepEqual(outside, [], 'every request stays under the sub-path');
    assert.deepEqual(errors, []);
    await context.close();
  } finally {
    await new Promise((r) => server.close(r));
    fs.rmSync(dir, { recursive: true, force: true });
  }
});
