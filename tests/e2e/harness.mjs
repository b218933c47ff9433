// Shared set-up for the browser end-to-end tests: our static server on a
// free port, Debian's Chromium driven by playwright-core, and helpers that
// act like a person (drop a file on a zone, pick one, wait for text).
import { chromium } from 'playwright-core';
import fs from 'node:fs';
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { start } from '../../scripts/serve.mjs';

export const ROOT = path.resolve(path.dirname(fileURLToPath(import.meta.url)), '../..');
export const fixture = (name) => path.join(ROOT, 'tests/fixtures', name);

const CHROMIUM = process.env.CHROMIUM_PATH || '/usr/bin/chromium';
// The GPU is SwiftShader (software Vulkan/GL): WebGL and the GPU 2-D canvas
// run on it as on a real GPU, but compositing every frame of every page
// through it is what cost most CPU in the whole suite (the jobs file: 107 →
// 52 CPU-seconds with `--disable-gpu-compositing`; CPU of the whole browser, wall
// halved). So the compositor draws in software; canvases and WebGL stay
// "hardware accelerated" (chrome://gpu), the paths a user's GPU takes.
//
// Every context is a browser window, and each window preloads the address
// bar's two WebUI popups (a renderer each, about 1 CPU-second per context:
// the a11y file, 30 contexts, 95 → 62 CPU-seconds without them). A test
// browser has no address bar to type in, so they are turned off. Playwright
// passes its own `--disable-features=<list>` and Chromium keeps only the last
// such switch, so ours repeats Playwright's list, read from playwright-core
// (pinned in package.json); a launch with its own `--disable-features` in
// `args` (frames.test.mjs) keeps overriding both, as before.
const NO_FEATURES = ['WebUIOmniboxPopup', 'WebUIOmniboxAimPopup'];
function playwrightDisabledFeatures() {
  const bundle = fs.readFileSync(path.join(ROOT, 'node_modules/playwright-core/lib/coreBundle.js'), 'utf8');
  const list = bundle.match(/\bdisabledFeatures = \[([^\]]*)\]/)?.[1].match(/"[^"]+"/g)?.map((q) => q.slice(1, -1));
  if (!list?.length) throw new Error("tests/e2e/harness.mjs: Playwright's --disable-features list not found in playwright-core; update playwrightDisabledFeatures()");
  return list;
}
const ARGS = [
  '--headless=new', '--no-sandbox', '--disable-background-networking', '--disable-component-update',
  '--disable-sync', '--no-first-run', '--disable-quic',
  '--enable-unsafe-swiftshader', '--use-angle=swiftshader', '--disable-gpu-compositing',
  `--disable-features=${[...playwrightDisabledFeatures(), ...NO_FEATURES].join(',')}`,
];

/** Whether `path` (what follows the server's URL) opens a tool rather than the home view. */
export const opensTool = (path) => /[#&]tool=|[?&]embed/.test(path);

/**
 * Wait until the view `path` opened is usable: a tool's core module has
 * loaded (`coreReady`); the home view loads no core, so there its cards.
 */
export async function ready(page, path) {
  if (opensTool(path)) {
    await page.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
  } else {
    await page.waitForSelector('.home-cards', { timeout: 30000 });
  }
}

/**
 * The test layer's hooks (tests/e2e/hooks/*.js): classic scripts that each
 * add `globalThis.__filigreeHookBuilders[<tool id or name>] = (parts) => hooks`,
 * where `parts` are the raw references a panel hands to `ctx.expose`
 * (www/app/document.js). They run as init scripts of every test page and
 * frame, before the app; the app does not ship them (scripts/precache.mjs
 * lists what ships: index.html, www, pkg, assets).
 */
export const HOOK_SCRIPTS = fs.readdirSync(path.join(ROOT, 'tests/e2e/hooks'))
  .filter((n) => n.endsWith('.js')).sort().map((n) => path.join(ROOT, 'tests/e2e/hooks', n));

/** Start server (serving `root`, the repository by default) + browser (extra Chromium `args`).
 * Returns {url, browser, server, newPage({path, keep, ...context options}), closeTestPages(), close()};
 * newPage opens a page in a new browser context, goes to `path` (the home view by
 * default; null: nowhere) and waits until it is ready (see `ready`). Its pages
 * (and their frames) are test pages: the panels' test hooks are in
 * `window.filigree.testHooks[<tool id or name>]` (`ctx.expose`,
 * www/app/document.js, built by HOOK_SCRIPTS).
 *
 * Cost: every app page runs its tool's Web Workers, and a page left open keeps
 * computing (a fit, a tangle, a texture) and takes CPU from the tests after it.
 * So a test file calls `afterEach(() => env?.closeTestPages())`: each test's
 * contexts close when it ends, except those opened with `keep: true` (a page a
 * file shares across tests, made in `before`), which close with `close()`.
 * And a context blocks the app's service worker unless the test asks for it
 * (`serviceWorkers: 'allow'`, in the tests about offline use, updates, the
 * precache and where the worker may or may not be registered): installing it
 * precaches every tool module and the editor bundle, and the app works without
 * it (as it does in an embed, where it never registers one). */
export async function launch({ root = ROOT, args = [] } = {}) {
  const server = await start(0, root);
  const url = `http://localhost:${server.address().port}/`;
  const browser = await chromium.launch({ executablePath: CHROMIUM, args: [...ARGS, ...args], headless: true });
  const kept = [];
  let perTest = [];
  const env = {
    url, browser, server,
    async newPage({ path: p = '', keep = false, ...opts } = {}) {
      const context = await browser.newContext({
        viewport: { width: 1280, height: 800 }, acceptDownloads: true, serviceWorkers: 'block', ...opts,
      });
      (keep ? kept : perTest).push(context);
      await context.addInitScript(() => { globalThis.__filigreeTestHooks = true; });
      for (const file of HOOK_SCRIPTS) await context.addInitScript({ path: file });
      const page = await context.newPage();
      page.on('pageerror', (e) => console.error('[page error]', e.message));
      if (p !== null) {
        await page.goto(url + p);
        await ready(page, p);
      }
      return page;
    },
    /** Close the contexts newPage opened without `keep` (a test's own pages). */
    async closeTestPages() {
      const open = perTest;
      perTest = [];
      await Promise.all(open.map((c) => c.close().catch(() => {})));
    },
    async close() {
      await env.closeTestPages();
      for (const c of kept) await c.close().catch(() => {});
      await browser.close();
      await new Promise((r) => server.close(r));
    },
  };
  return env;
}

/**
 * Choose Fit generator `name` as a user would (the select), then wait until
 * the document holds it and its sliders are drawn. The select shows the new
 * name at once, but the document changes only when the generator's program
 * has been read, so waiting on the select alone races the commit.
 */
export async function pickGenerator(page, name) {
  await page.waitForSelector('[data-testid=fit-sliders] .row');
  await page.selectOption('[data-testid=fit-generator]', name);
  await page.waitForFunction((n) => window.filigree.testHooks.fit.state()?.generator === n
    && window.filigree.testHooks.fit.info()?.params.length === window.filigree.testHooks.fit.state().values.length
    && document.querySelector(`[data-testid=fit-sliders] .row[data-param="${window.filigree.testHooks.fit.info().params[0].name}"]`), name);
}

/** The Tangle panel's count of shown answers. */
export const tangleRuns = (page) => page.$eval('[data-testid=tangle-status]', (el) => Number(el.dataset.runs || 0));

/**
 * Wait until the Tangle panel has shown one more answer than `previous` and
 * nothing is due, then two frames (so the answer is painted); returns the count.
 */
export async function waitForTangle(page, previous, timeout = 60000) {
  await page.waitForFunction((prev) => {
    const el = document.querySelector('[data-testid=tangle-status]');
    return Number(el.dataset.runs || 0) > prev && !window.filigree.testHooks.tangle.pending();
  }, previous, { timeout });
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  return tangleRuns(page);
}

/** Drop a file (path or {name, bytes, type}) onto `selector` with real drag events. */
export async function dropFile(page, selector, file) {
  const { name, bytes, type } = typeof file === 'string'
    ? { name: path.basename(file), bytes: fs.readFileSync(file), type: 'image/png' }
    : file;
  const dt = await page.evaluateHandle(({ name, b64, type }) => {
    const bin = atob(b64);
    const arr = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) arr[i] = bin.charCodeAt(i);
    const data = new DataTransfer();
    data.items.add(new File([arr], name, { type }));
    return data;
  }, { name, b64: Buffer.from(bytes).toString('base64'), type });
  await page.dispatchEvent(selector, 'dragenter', { dataTransfer: dt });
  await page.dispatchEvent(selector, 'dragover', { dataTransfer: dt });
  await page.dispatchEvent(selector, 'drop', { dataTransfer: dt });
}

/** A PNG file of `ihdr` (its 13 bytes) and the raw, filtered scanlines `raw`. */
async function png(ihdr, raw) {
  const zlib = await import('node:zlib');
  const crcTable = Array.from({ length: 256 }, (_, n) => {
    let c = n;
    for (let k = 0; k < 8; k++) c = c & 1 ? 0xedb88320 ^ (c >>> 1) : c >>> 1;
    return c >>> 0;
  });
  const crc = (buf) => {
    let c = 0xffffffff;
    for (const b of buf) c = crcTable[(c ^ b) & 0xff] ^ (c >>> 8);
    return (c ^ 0xffffffff) >>> 0;
  };
  const chunk = (type, data) => {
    const len = Buffer.alloc(4); len.writeUInt32BE(data.length);
    const td = Buffer.concat([Buffer.from(type), data]);
    const c = Buffer.alloc(4); c.writeUInt32BE(crc(td));
    return Buffer.concat([len, td, c]);
  };
  return Buffer.concat([
    Buffer.from([0x89, 0x50, 0x4e, 0x47, 0x0d, 0x0a, 0x1a, 0x0a]),
    chunk('IHDR', ihdr), chunk('IDAT', zlib.deflateSync(raw)), chunk('IEND', Buffer.alloc(0)),
  ]);
}

/** A real, valid 1-bit greyscale PNG of the given size (tiny on disk, huge when decoded). */
export async function bigPng(width, height) {
  const rowBytes = 1 + Math.ceil(width / 8);
  const raw = Buffer.alloc(rowBytes * height);
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(width, 0); ihdr.writeUInt32BE(height, 4);
  ihdr[8] = 1; ihdr[9] = 0;
  return png(ihdr, raw);
}

/** An RGB PNG of `width × height` whose pixel (x, y) is `colour(x, y)` ([r, g, b]). */
export async function rgbPng(width, height, colour) {
  const raw = Buffer.alloc((1 + 3 * width) * height);
  for (let y = 0; y < height; y++) {
    for (let x = 0; x < width; x++) raw.set(colour(x, y), y * (1 + 3 * width) + 1 + 3 * x);
  }
  const ihdr = Buffer.alloc(13);
  ihdr.writeUInt32BE(width, 0); ihdr.writeUInt32BE(height, 4);
  ihdr[8] = 8; ihdr[9] = 2;
  return png(ihdr, raw);
}
