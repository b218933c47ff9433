// Embedding (MISSION S7): <filigree-embed> on a third-party page served from
// a second origin (127.0.0.1 vs the app's localhost: another site, so the
// frame is a real third-party context), embed mode read-only and
// interactive, "Open in Filigree", and the user's autosave left alone.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { launch, pickGenerator, ROOT } from './harness.mjs';
import { start } from '../../scripts/serve.mjs';

let env;
let host; // the second origin's server
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

/** Console errors and uncaught exceptions of a page and all its frames. */
function watchErrors(page) {
  const errors = [];
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(e.message));
  return errors;
}

/** The share fragment of a Fit state made in the full app: generator `name`, defaults. */
async function fitShare(name = 'stripes') {
  const page = await env.newPage({ path: '#tool=fit' });
  await pickGenerator(page, name);
  const { fragment, tool } = await page.evaluate(() => window.filigree.currentShare());
  assert.equal(tool, 'fit');
  await page.close();
  return fragment;
}

/** The host page URL showing one <filigree-embed> with these attributes. */
function hostPage(attrs) {
  const q = new URLSearchParams({ app: env.url, ...attrs });
  return `${hostUrl}host.html?${q}`;
}

/** The embed's iframe as a Frame, once the app in it is ready. */
async function embedFrame(page) {
  const handle = await page.waitForSelector('filigree-embed iframe', { timeout: 15000 });
  const frame = await handle.contentFrame();
  await frame.waitForFunction(() => document.documentElement.dataset.coreReady === '1'
    && document.documentElement.dataset.embedReady === '1', null, { timeout: 30000 });
  return { frame, handle };
}

/** The decoded state the app in `target` (page or frame) holds now, as JSON. */
function currentState(target) {
  return target.evaluate(async () => {
    const { fragment } = await window.filigree.currentShare();
    const { decodeShare } = await import(new URL('www/app/share.js', document.baseURI).href);
    const shared = await decodeShare(fragment);
    return JSON.stringify(shared, (k, v) => (v instanceof Uint8Array ? [...v] : v));
  });
}

/** A hash of the Fit preview (the pattern drawn over the target) and how many pixels it paints. */
function overlayFacts(frame) {
  return frame.evaluate(() => {
    const c = document.querySelector('[data-testid=fit-overlay]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let h = 2166136261, painted = 0;
    for (let i = 0; i < d.length; i++) h = Math.imul(h ^ d[i], 16777619);
    for (let i = 3; i < d.length; i += 4) if (d[i]) painted++;
    return { hash: h >>> 0, painted };
  });
}

async function waitForPreview(frame, previous) {
  await frame.waitForFunction((prev) => {
    const c = document.querySelector('[data-testid=fit-overlay]');
    if (!c) return false;
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let h = 2166136261, painted = 0;
    for (let i = 0; i < d.length; i++) h = Math.imul(h ^ d[i], 16777619);
    for (let i = 3; i < d.length; i += 4) if (d[i]) painted++;
    return painted > 0 && (h >>> 0) !== prev;
  }, previous ?? null, { timeout: 20000 });
  return overlayFacts(frame);
}

test('an embed on a third-party page waits below the fold, then shows the read-only result', async () => {
  const state = await fitShare('stripes');
  const page = await env.newPage({ path: null });
  const errors = watchErrors(page);
  await page.goto(hostPage({ state, title: 'Stripes, fitted', below: '1' }));
  // The facade: a title and a button with an accessible name, no iframe yet.
  const button = page.getByRole('button', { name: /Open the embedded Filigree: Stripes, fitted/ });
  await button.waitFor();
  await page.waitForTimeout(500);
  assert.equal(await page.locator('filigree-embed iframe').count(), 0, 'no iframe before the embed is near the viewport');
  assert.equal(page.frames().length, 1);

  await page.locator('filigree-embed').scrollIntoViewIfNeeded();
  const { frame, handle } = await embedFrame(page);
  // The iframe is what the brief asks for.
  const attrs = await handle.evaluate((f) => ({
    allow: f.getAttribute('allow'), loading: f.getAttribute('loading'), title: f.title,
    width: f.getBoundingClientRect().width, hostWidth: f.getRootNode().host.getBoundingClientRect().width,
  }));
  assert.equal(attrs.allow, 'clipboard-write');
  assert.equal(attrs.loading, 'lazy');
  assert.equal(attrs.title, 'Stripes, fitted');
  assert.equal(attrs.width, attrs.hostWidth, 'the iframe fills the element');
  const url = new URL(frame.url());
  assert.equal(url.origin, new URL(env.url).origin, 'the frame is the app origin');
  assert.notEqual(new URL(page.url()).origin, url.origin, 'the host is another origin');
  assert.equal(url.searchParams.get('embed'), '1');

  // No special headers needed: the host and the frame are not cross-origin isolated.
  assert.equal(await page.evaluate(() => window.crossOriginIsolated), false);
  assert.equal(await frame.evaluate(() => window.crossOriginIsolated), false);

  // One tool, no app chrome, read-only, the result drawn.
  const chrome = await frame.evaluate(() => ({
    header: getComputedStyle(document.querySelector('.app-header')).display,
    bar: document.querySelector('.embed-bar')?.textContent,
    inert: document.querySelector('#panel').inert,
    save: [...document.querySelectorAll('button')].filter((b) => /save project/i.test(b.textContent) && b.offsetParent).length,
  }));
  assert.equal(chrome.header, 'none');
  assert.match(chrome.bar, /Fit.*read-only.*Open in Filigree/s);
  assert.equal(chrome.inert, false, 'read-only is not inert (issue 35): the reader explores');
  assert.equal(chrome.save, 0, 'no visible Save project button');
  const preview = await waitForPreview(frame);
  assert.ok(preview.painted > 1000, `the pattern is drawn (${preview.painted} pixels)`);
  // The state is the one in the link.
  assert.equal(await currentState(frame), await currentState(await (async () => {
    const p = await env.newPage({ path: `#${state}` });
    await p.waitForSelector('[data-testid=fit-sliders] .row');
    return p;
  })()));
  // Read-only does not change the author's state: the reader moves a slider
  // (in the drawer), the preview follows, "Open in Filigree" still carries
  // the author's state, and Reset brings it back.
  const open = await frame.getAttribute('.embed-bar .open', 'href');
  await frame.click('.embed-bar [data-act=embed-controls]');
  const slider = '[data-testid=fit-sliders] input[type=range]';
  await frame.focus(slider);
  for (let i = 0; i < 30; i++) await frame.press(slider, 'ArrowRight');
  const moved = await waitForPreview(frame, preview.hash);
  assert.notEqual(moved.hash, preview.hash, 'the reader\'s slider moved the pattern');
  assert.equal(await frame.getAttribute('.embed-bar .open', 'href'), open, 'Open in Filigree carries the author\'s state');
  await frame.click('.embed-bar [data-act=embed-reset]');
  // The first new picture may still be one of the slider's previews in
  // flight (30 key presses): wait for the picture to settle on the
  // author's, which a stale preview left on screen would never do.
  const back = await frame.waitForFunction((want) => {
    const c = document.querySelector('[data-testid=fit-overlay]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let h = 2166136261;
    for (let i = 0; i < d.length; i++) h = Math.imul(h ^ d[i], 16777619);
    return (h >>> 0) === want;
  }, preview.hash, { timeout: 20000, polling: 100 }).then(() => true, () => false);
  assert.ok(back, 'Reset: the author\'s picture again');
  assert.deepEqual(errors, []);
});

test('load="click": nothing loads until the facade button is pressed (keyboard works)', async () => {
  const state = await fitShare('stripes');
  const page = await env.newPage({ path: null });
  // No src: the element finds the app next to embed.js.
  await page.goto(hostPage({ state, tool: 'fit', load: 'click', nosrc: '1', preview: `${env.url}www/icons/icon-512.png` }));
  const button = page.getByRole('button', { name: /Open the embedded Filigree: Filigree Fit/ });
  await button.waitFor();
  await page.waitForTimeout(800);
  assert.equal(await page.locator('filigree-embed iframe').count(), 0, 'a click-to-load embed stays a facade when visible');
  // The preview image is shown, decorative (the title says what it is).
  const img = await page.locator('filigree-embed img').evaluate((i) => ({ alt: i.alt, w: i.naturalWidth, shown: i.getBoundingClientRect().width }));
  assert.deepEqual({ alt: img.alt, w: img.w }, { alt: '', w: 512 });
  assert.ok(img.shown > 300, `the preview fills the facade (${img.shown} px wide)`);
  await button.focus();
  await page.keyboard.press('Enter');
  const { frame } = await embedFrame(page);
  assert.equal(new URL(frame.url()).pathname, '/index.html');
  assert.ok((await waitForPreview(frame)).painted > 0);
});

test('interactive embed: an edit changes the result and "Open in Filigree" carries it to the full app', async () => {
  const state = await fitShare('stripes');
  const page = await env.newPage({ path: null });
  const errors = watchErrors(page);
  await page.goto(hostPage({ state, mode: 'interactive', title: 'Try the stripes' }));
  const { frame } = await embedFrame(page);
  assert.match(await frame.textContent('.embed-bar'), /interactive/);
  const first = await waitForPreview(frame);
  const before = await currentState(frame);

  // Move the first slider: the preview redraws and the state changes.
  await frame.$eval('[data-testid=fit-sliders] input[type=range]', (el) => {
    el.value = String(Number(el.min) + 0.8 * (Number(el.max) - Number(el.min)));
    el.dispatchEvent(new Event('input', { bubbles: true }));
    el.dispatchEvent(new Event('change', { bubbles: true }));
  });
  const second = await waitForPreview(frame, first.hash);
  assert.notEqual(second.hash, first.hash);
  const edited = await currentState(frame);
  assert.notEqual(edited, before, 'the edit is in the state');

  // The embed never saves: Ctrl+S and Ctrl+O are not taken over (no project download, no picker).
  const downloads = [];
  page.on('download', (d) => downloads.push(d));
  await frame.click('.embed-bar .name');
  await page.keyboard.press('Control+s');
  await page.waitForTimeout(800);
  assert.equal(downloads.length, 0, 'Ctrl+S downloaded a project inside an embed');

  // "Open in Filigree" opens the full app in a new tab with the edited state.
  const link = frame.getByRole('link', { name: /Open in Filigree/ });
  assert.equal(await link.getAttribute('target'), '_blank');
  // A plain click (no hover first) carries the state as it is now.
  const [popup] = await Promise.all([page.context().waitForEvent('page'), link.click()]);
  await popup.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
  await popup.waitForSelector('[data-testid=fit-sliders] .row');
  const url = new URL(popup.url());
  assert.equal(url.searchParams.get('embed'), null, 'the full app, not an embed');
  assert.equal(await popup.evaluate(() => getComputedStyle(document.querySelector('.app-header')).display === 'none'), false);
  assert.equal(await currentState(popup), edited, 'the full app has the edited state');
  assert.deepEqual(errors, []);
});

test('read-only "Open in Filigree" arrives with the same state', async () => {
  const state = await fitShare('honeycomb');
  const page = await env.newPage({ path: null });
  await page.goto(hostPage({ state }));
  const { frame } = await embedFrame(page);
  const inEmbed = await currentState(frame);
  const link = frame.getByRole('link', { name: /Open in Filigree/ });
  const href = new URL(await link.getAttribute('href'));
  assert.equal(href.hash.slice(1), state, 'the link carries the embed\'s fragment');
  const [popup] = await Promise.all([page.context().waitForEvent('page'), link.click()]);
  await popup.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
  await popup.waitForSelector('[data-testid=fit-sliders] .row');
  assert.equal(await popup.$eval('[data-testid=fit-generator]', (s) => s.value), 'honeycomb');
  assert.equal(await currentState(popup), inEmbed);
});

test('an interactive embed on the app\'s own origin never writes the user\'s autosave nor registers a service worker', async () => {
  // The user's own work: the full app with honeycomb, autosaved.
  const page = await env.newPage({ path: '#tool=fit', serviceWorkers: 'allow' });
  await pickGenerator(page, 'honeycomb');
  const dump = () => page.evaluate(async () => {
    const names = (await indexedDB.databases()).map((d) => d.name).filter(Boolean).sort();
    const out = {};
    for (const name of names) {
      const db = await new Promise((res, rej) => { const r = indexedDB.open(name); r.onsuccess = () => res(r.result); r.onerror = () => rej(r.error); });
      for (const store of db.objectStoreNames) {
        const all = await new Promise((res, rej) => {
          const tx = db.transaction(store, 'readonly');
          const r = tx.objectStore(store).getAll();
          r.onsuccess = () => res(r.result); r.onerror = () => rej(r.error);
        });
        out[`${name}/${store}`] = JSON.stringify(all, (k, v) => (ArrayBuffer.isView(v) ? `bytes:${v.length}:${Array.prototype.reduce.call(v, (a, b) => (a * 31 + b) >>> 0, 7)}` : v));
      }
      db.close();
    }
    return out;
  });
  // Wait for the autosave to land (debounced), then record it. Up to 30 s:
  // on a loaded machine (a CI run on 2026-12-03) 10 s was not enough.
  let saved = {};
  for (let i = 0; i < 150 && !/honeycomb/.test(Object.values(saved).join()); i++) {
    await page.waitForTimeout(200);
    saved = await dump();
  }
  assert.match(Object.values(saved).join(), /honeycomb/, 'the user\'s autosave holds their honeycomb');

  // A same-origin page embeds a stripes state, interactively, and the reader edits it.
  const state = await fitShare('stripes');
  await page.waitForTimeout(1500);
  const before = await dump();
  const errors = watchErrors(page);
  await page.evaluate((src) => {
    const f = document.createElement('iframe');
    f.src = src;
    f.style.cssText = 'width:900px;height:700px';
    document.body.append(f);
  }, `${env.url}index.html?embed=1&mode=interactive#${state}`);
  const frame = await (await page.waitForSelector('iframe')).contentFrame();
  await frame.waitForFunction(() => document.documentElement.dataset.embedReady === '1', null, { timeout: 30000 });
  const first = await waitForPreview(frame);
  for (const f of [0.2, 0.7, 0.4]) {
    await frame.$eval('[data-testid=fit-sliders] input[type=range]', (el, f) => {
      el.value = String(Number(el.min) + f * (Number(el.max) - Number(el.min)));
      el.dispatchEvent(new Event('input', { bubbles: true }));
      el.dispatchEvent(new Event('change', { bubbles: true }));
    }, f);
    await page.waitForTimeout(300);
  }
  await waitForPreview(frame, first.hash);
  // Leaving the embed is when an autosave would flush.
  await page.evaluate(() => document.querySelector('iframe').remove());
  await page.waitForTimeout(1500);
  assert.deepEqual(await dump(), before, 'the autosave is byte-for-byte what it was');
  assert.deepEqual(await dump(), saved, 'and still the user\'s own');
  const regs = await page.evaluate(async () => (await navigator.serviceWorker.getRegistrations()).map((r) => r.scope));
  // The full app registered its worker; the embed added none (same scope would be reused, so check the count).
  assert.ok(regs.length <= 1, `registrations: ${regs}`);
  assert.deepEqual(errors, []);
});

test('an embedded instance registers no service worker; the full app in the same place does', async () => {
  // Top-level, first-party: the one place a registration would succeed.
  const state = await fitShare('stripes');
  const registrations = async (path) => {
    const context = await env.browser.newContext();
    try {
      const page = await context.newPage();
      await page.goto(env.url + path);
      await page.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
      await page.waitForTimeout(1500);
      return await page.evaluate(async () => (await navigator.serviceWorker.getRegistrations()).length);
    } finally {
      await context.close();
    }
  };
  assert.equal(await registrations(`#tool=fit`), 1, 'the full app registers its worker (the control)');
  assert.equal(await registrations(`index.html?embed=1#${state}`), 0, 'read-only embed: none');
  assert.equal(await registrations(`index.html?embed=1&mode=interactive#${state}`), 0, 'interactive embed: none');
});

test('on a 390 px phone the embed fits the page width (no sideways scrolling of the host or the tool)', async () => {
  const state = await fitShare('stripes');
  const page = await env.newPage({ path: null, viewport: { width: 390, height: 844 }, isMobile: true, hasTouch: true });
  await page.goto(hostPage({ state, title: 'Stripes on a phone', mode: 'interactive' }));
  // In view at once, so it loads without a tap.
  const { frame, handle } = await embedFrame(page);
  const box = await handle.boundingBox();
  const host = await page.evaluate(() => ({ scroll: document.documentElement.scrollWidth, client: document.documentElement.clientWidth }));
  assert.ok(host.scroll <= host.client, `host page ${host.scroll} px wide in a ${host.client} px viewport`);
  assert.ok(box.x >= 0 && box.x + box.width <= 390, `the iframe spans ${box.x}..${box.x + box.width}`);
  const inner = await frame.evaluate(() => ({ scroll: document.documentElement.scrollWidth, client: document.documentElement.clientWidth }));
  console.log(`phone embed: frame content ${inner.scroll} px in ${inner.client} px`);
  assert.ok(inner.scroll <= inner.client, `the embedded tool is ${inner.scroll} px wide in a ${inner.client} px frame`);
  assert.ok((await waitForPreview(frame)).painted > 0);
});

test('a damaged embed link says so plainly and the tool still opens', async () => {
  const page = await env.newPage({ path: null });
  await page.goto(hostPage({ state: 'tool=fit&share=AAAAbroken-data' }));
  const { frame } = await embedFrame(page);
  await frame.waitForSelector('.embed-note');
  assert.match(await frame.textContent('.embed-note'), /This link is damaged or not a Filigree link/);
  await frame.waitForSelector('[data-testid=fit-sliders] .row', { state: 'attached' });
  await frame.waitForSelector('[data-testid=embed-stage] [data-testid=fit-target]');
});
