// The shell: home view, layouts that fit a 1280×800 desktop and a 390×844
// touch phone, the code editor (CodeMirror bundle and its textarea fallback).
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { launch, ready, ROOT } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const PHONE = { viewport: { width: 390, height: 844 }, isMobile: true, hasTouch: true, deviceScaleFactor: 2 };
const VIEWS = {
  home: { path: '', ready: () => document.querySelectorAll('.home-preview[data-ready]').length === 6 },
  pixel: { path: '#tool=pixel', ready: () => Number(document.querySelector('[data-testid=pixel-status]')?.dataset.runs) > 0 },
  fit: { path: '#tool=fit', ready: () => !!document.querySelector('[data-testid=fit-sliders] input') },
  inspect: { path: '#tool=inspect', ready: () => !!document.querySelector('[data-testid=drop-zone] button') },
  texture: { path: '#tool=texture', ready: () => !!document.querySelector('[data-testid=texture-retrieved][data-model]') && !window.filigree?.testHooks?.texture?.pending() },
};

const TOOL_IDS = ['pixel', 'fit', 'inspect', 'tangle', 'micro', 'texture'];
// The wasm files a page asks for (paths), recorded from before it loads.
const recordWasm = (page) => {
  const wasm = [];
  page.on('request', (r) => {
    const p = new URL(r.url()).pathname;
    if (p.endsWith('.wasm')) wasm.push(p);
  });
  return wasm;
};

test('home: no hash shows what Filigree is and a card per tool with its picture, loading no wasm; one click opens the tool and loads its module only', async () => {
  const page = await env.newPage({ path: null });
  const wasm = recordWasm(page);
  await page.goto(env.url);
  await page.waitForSelector('.home-cards');
  assert.equal(await page.textContent('h1'), 'Filigree');
  assert.match(await page.textContent('.home-intro'), /browser/);
  const cards = await page.$$eval('.home-card', (as) => as.map((a) => [a.dataset.tool, a.getAttribute('href')]));
  assert.deepEqual(cards, TOOL_IDS.map((t) => [t, `#tool=${t}`]));
  await page.waitForFunction(VIEWS.home.ready, null, { timeout: 30000 });
  // Each card shows its picture (assets/home/<tool>.png, made ahead of time
  // by the core natively: scripts/home-cards.sh), decoded, with its text.
  const pictures = await page.$$eval('.home-card', (as) => as.map((a) => {
    const img = a.querySelector('.home-preview img');
    return [a.dataset.tool, img && new URL(img.src).pathname, img?.complete && img.naturalWidth > 0, !!img?.alt];
  }));
  assert.deepEqual(pictures, TOOL_IDS.map((t) => [t, `/assets/home/${t}.png`, true, true]));
  assert.match(await page.textContent('.home-card[data-tool=inspect] .home-facts'), /^128×128 px · \d+ colours$/);
  // Nothing was computed: the page fetched no core module and started none.
  // (The service worker's install precaches every module for offline use in
  // the background; those requests are its own, not the page's.)
  await page.waitForTimeout(500);
  assert.deepEqual(wasm, [], 'the home view fetches no wasm');
  assert.equal(await page.evaluate(() => document.documentElement.dataset.coreReady), undefined);

  // Opening a tool from its card loads that tool's module, and only it.
  await page.click('.home-card[data-tool=pixel]');
  await page.waitForSelector('[data-testid=pixel-canvas]');
  assert.match(page.url(), /#tool=pixel$/);
  await page.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
  await page.waitForFunction(VIEWS.pixel.ready, null, { timeout: 30000 });
  assert.deepEqual([...new Set(wasm)], ['/pkg/filigree_pixel_bg.wasm'], 'the Pixel panel fetches its own module only');
  // Back returns to the home view; the brand link does too.
  await page.goBack();
  await page.waitForSelector('.home-cards');
  await page.click('.home-card[data-tool=fit]');
  await page.waitForSelector('[data-testid=fit-target]');
  await page.click('a.brand');
  await page.waitForSelector('.home-cards');
  assert.equal(new URL(page.url()).searchParams.get('tool'), null);
});

test('home: a card whose picture fails to load still opens its tool', async () => {
  const page = await env.newPage({ path: null, serviceWorkers: 'block' });
  await page.route('**/assets/home/tangle.png', (r) => r.abort());
  await page.goto(env.url);
  await page.waitForFunction(() => document.querySelectorAll('.home-preview[data-ready]').length === 5, null, { timeout: 30000 });
  await page.waitForFunction(() => !document.querySelector('.home-card[data-tool=tangle] img'));
  assert.match(await page.textContent('.home-card[data-tool=tangle]'), /no preview.*Open Tangle/s);
  await page.click('.home-card[data-tool=tangle]');
  await page.waitForFunction(() => document.documentElement.dataset.view === 'tangle');
  assert.match(page.url(), /#tool=tangle$/);
});

test('desktop 1280×800: each panel shows its whole main canvas and its actions without scrolling', async () => {
  const inView = (page, sel) => page.$eval(sel, (e) => {
    const r = e.getBoundingClientRect();
    return { ok: r.width > 0 && r.top >= 0 && r.left >= 0 && r.bottom <= innerHeight + 0.5 && r.right <= innerWidth + 0.5, r: [r.left, r.top, r.right, r.bottom].map(Math.round) };
  });
  const page = await env.newPage({ path: VIEWS.pixel.path });
  await page.waitForFunction(VIEWS.pixel.ready, null, { timeout: 30000 });
  for (const sel of ['[data-testid=pixel-canvas]', 'button[data-act=export-png]', 'button[data-act=save-project]', 'button[data-act=open-project]', 'button[data-example=fish]']) {
    const v = await inView(page, sel);
    assert.ok(v.ok, `${sel} visible at 1280×800: ${v.r}`);
  }
  // The "Choose a source image…" button does not cover the drawing.
  const overlap = await page.evaluate(() => {
    const a = document.querySelector('[data-testid=pixel-canvas]').getBoundingClientRect();
    const b = document.querySelector('.viewport .pick').getBoundingClientRect();
    return Math.max(0, Math.min(a.right, b.right) - Math.max(a.left, b.left)) * Math.max(0, Math.min(a.bottom, b.bottom) - Math.max(a.top, b.top));
  });
  assert.equal(overlap, 0, 'the source picker does not cover the canvas');

  const fit = await env.newPage({ path: VIEWS.fit.path });
  await fit.waitForFunction(VIEWS.fit.ready, null, { timeout: 30000 });
  for (const sel of ['[data-testid=fit-target]', 'button[data-act=fit]', 'button[data-act=make-target]', '.fit-target button.pick', 'button[data-act=export-svg]', 'button[data-act=open-project]']) {
    const v = await inView(fit, sel);
    assert.ok(v.ok, `${sel} visible at 1280×800: ${v.r}`);
  }

  const tex = await env.newPage({ path: VIEWS.texture.path });
  await tex.waitForFunction(VIEWS.texture.ready, null, { timeout: 60000 });
  for (const sel of ['[data-testid=texture-canvas]', '[data-testid=texture-chart]', '[data-testid=texture-example]', '[data-testid=texture-scale-uniformity]',
    '[data-testid=texture-same-model]', 'button[data-act=export-png]', 'button[data-act=export-json]', '[data-testid=texture-drop] button.pick']) {
    const v = await inView(tex, sel);
    assert.ok(v.ok, `${sel} visible at 1280×800: ${v.r}`);
  }
  assert.deepEqual(await tex.evaluate(() => [document.documentElement.scrollHeight <= innerHeight, document.documentElement.scrollWidth <= innerWidth]), [true, true], 'the Texture panel does not scroll');
});

test('phone 390×844: no sideways overflow on the home view or any panel', async () => {
  for (const [name, v] of Object.entries(VIEWS)) {
    const page = await env.newPage({ path: v.path, ...PHONE });
    await page.waitForFunction(v.ready, null, { timeout: 30000 });
    await page.waitForTimeout(300);
    const w = await page.evaluate(() => [document.documentElement.scrollWidth, innerWidth]);
    assert.ok(w[0] <= 390, `${name}: scrollWidth ${w[0]} > 390`);
    // Nothing sticks out of the layout viewport on the right either (wide children of overflow:hidden boxes excluded).
    const wide = await page.evaluate(() => [...document.querySelectorAll('#panel *')]
      .filter((e) => e.getClientRects().length && e.getBoundingClientRect().right > innerWidth + 1 && !e.closest('.viewport, .cm-scroller'))
      .map((e) => e.tagName + (e.className ? `.${e.className}` : '')).slice(0, 5));
    assert.deepEqual(wide, [], `${name}: elements past the right edge`);
    await page.context().close();
  }
});

test('code editor: line numbers, Fit syntax colours, no wrapping, an error marked at its line and column, Tab moves on', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await page.waitForFunction(VIEWS.fit.ready, null, { timeout: 30000 });
  await page.click('details.program summary');
  await page.waitForSelector('.code-editor[data-editor=codemirror] .cm-content');
  assert.ok(await page.$('.code-editor .cm-lineNumbers .cm-gutterElement'), 'line numbers');
  assert.equal(await page.$('.code-editor .cm-lineWrapping'), null, 'no wrapping');
  await page.fill('[data-testid=fit-program]', 'param a in [0, 1] = 0.5;\n// two\ncircle(0.5, 0.5, a +, fill: "#000000");\n');
  await page.click('button[data-act=apply-program]');
  await page.waitForSelector('[data-testid=doc-error]:not([hidden])');
  const msg = await page.textContent('[data-testid=doc-error]');
  const [, line, column] = /line (\d+), column (\d+)/.exec(msg).map(Number);
  assert.equal(line, 3);
  await page.waitForSelector('.code-editor .cm-lintRange-error');
  const mark = await page.evaluate(() => {
    const range = document.querySelector('.code-editor .cm-lintRange-error');
    const lineEl = range.closest('.cm-line');
    const lines = [...document.querySelectorAll('.code-editor .cm-line')];
    const gutter = document.querySelectorAll('.code-editor .cm-lint-marker-error').length;
    // The cursor is at the error: the active line is the marked one.
    return { line: lines.indexOf(lineEl) + 1, gutter, active: lines.indexOf(document.querySelector('.code-editor .cm-activeLine')) + 1, before: (() => { const r = document.createRange(); r.setStart(lineEl, 0); r.setEndBefore(range); return r.toString(); })() };
  });
  assert.equal(mark.line, 3, 'underline on the error line');
  assert.equal(mark.active, 3, 'cursor moved to the error line');
  assert.ok(mark.gutter >= 1, 'gutter marker');
  assert.equal(mark.before.length + 1, column, 'underline starts at the error column');

  // A fixed program clears the mark.
  await page.fill('[data-testid=fit-program]', 'param a in [0.1, 0.4] = 0.2;\ncircle(0.5, 0.5, a, fill: "#000000");\n');
  await page.click('button[data-act=apply-program]');
  await page.waitForSelector('[data-testid=doc-error]', { state: 'hidden' });
  assert.equal(await page.$('.code-editor .cm-lintRange-error'), null);
  // Syntax colours: keyword, builtin shape, number, string and a plain name all differ from the name.
  const colours = await page.$$eval('.code-editor .cm-line span', (spans) => {
    const by = {};
    for (const s of spans) by[s.textContent] ??= getComputedStyle(s).color;
    return by;
  });
  const plain = await page.$eval('.code-editor .cm-content', (e) => getComputedStyle(e).color);
  for (const tok of ['param', 'circle', '0.5', '"#000000"']) {
    assert.ok(colours[tok] && colours[tok] !== plain, `${tok} highlighted: ${JSON.stringify(colours)}`);
  }
  assert.notEqual(colours.param, colours['0.5']);

  // Tab leaves the editor for the next control (it does not trap focus).
  await page.focus('[data-testid=fit-program]');
  await page.keyboard.press('Tab');
  assert.equal(await page.evaluate(() => document.activeElement.dataset.act), 'apply-program');
});

test('code editor without the bundle: a textarea with the same API marks the error line', async () => {
  const page = await env.newPage({ path: null });
  await page.route('**/code-editor.bundle.js', (r) => r.abort());
  await page.goto(env.url + '#tool=fit');
  await page.waitForFunction(VIEWS.fit.ready, null, { timeout: 30000 });
  await page.click('details.program summary');
  await page.waitForSelector('.code-editor[data-editor=textarea] textarea[data-testid=fit-program]');
  await page.fill('[data-testid=fit-program]', 'param a in [0, 1] = 0.5;\ncircle(0.5, 0.5, a +, fill: "#000000");\n');
  await page.click('button[data-act=apply-program]');
  await page.waitForSelector('.code-editor-error:not([hidden])');
  assert.match(await page.textContent('.code-editor-error'), /^line 2, column \d+/);
  const sel = await page.$eval('textarea[data-testid=fit-program]', (t) => t.value.slice(0, t.selectionStart).split('\n').length);
  assert.equal(sel, 2, 'the cursor is on the error line');
});

test('the editor bundle ships: served from our origin and listed in the service worker precache', async () => {
  const manifest = fs.readFileSync(`${ROOT}/pkg/precache-manifest.js`, 'utf8');
  assert.match(manifest, /"\.\/www\/vendor\/code-editor\.bundle\.js"/);
  const page = await env.newPage({ path: '#tool=fit' });
  const res = await page.evaluate(async () => {
    const r = await fetch('www/vendor/code-editor.bundle.js');
    return [r.status, r.headers.get('content-type')];
  });
  assert.equal(res[0], 200);
  assert.match(res[1], /javascript/);
});

test('offline after one visit, the program editor is still CodeMirror (the bundle is precached)', async () => {
  const own = await launch();
  try {
    const page = await own.newPage({ path: '#tool=fit', serviceWorkers: 'allow' });
    await page.evaluate(async () => {
      await navigator.serviceWorker.ready;
      if (!navigator.serviceWorker.controller) {
        await new Promise((r) => navigator.serviceWorker.addEventListener('controllerchange', r, { once: true }));
      }
    });
    await new Promise((r) => own.server.close(r));
    own.server.closeAllConnections?.();
    await page.context().setOffline(true);
    await page.reload();
    await page.waitForFunction(VIEWS.fit.ready, null, { timeout: 30000 });
    await page.click('details.program summary');
    await page.waitForSelector('.code-editor[data-editor=codemirror] .cm-content', { timeout: 10000 });
    own.server.listen(0);
  } finally {
    await own.close();
  }
});

test('a page loads its code as one script: the page bundle, then only the worker and the modules it imports', async () => {
  // scripts/bundle.mjs: www/app/main.js and what it imports in one file
  // (about 100 modules otherwise: ~110 requests and ~0.8 CPU-s a page load).
  for (const p of ['', '#tool=tangle']) {
    const page = await env.newPage({ path: null });
    const scripts = [];
    page.on('request', (r) => { const u = new URL(r.url()); if (u.pathname.endsWith('.js')) scripts.push(u.pathname); });
    await page.goto(env.url + p);
    await ready(page, p);
    const own = scripts.filter((s) => s.startsWith('/www/'));
    assert.equal(own[0], '/www/app/main.bundle.js', `${p || 'home'}: the page's first script`);
    // And the code editor's bundle, which Tangle's grammar editor imports.
    const allowed = ['/www/app/main.bundle.js', '/www/app/protocol.js', '/www/app/worker.js', '/www/vendor/code-editor.bundle.js'];
    assert.deepEqual(own.filter((s) => !allowed.includes(s)), [], `${p || 'home'}: no module of www/ but the bundle and the worker's`);
    await env.closeTestPages();
  }
});
