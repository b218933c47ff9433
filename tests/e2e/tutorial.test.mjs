// A tutorial page on another origin with embeds of every tool (issue 35
// item 1; tests/e2e/pages/tutorial.html): each embed opens on its picture,
// in view without scrolling inside it; read-only is not inert (sliders,
// steps, orbit; Reset brings the author's state back) and nothing persists;
// the wheel scrolls the tutorial until the reader clicks into an embed;
// heights follow the content or the author's `height`.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import path from 'node:path';
import { launch, ROOT } from './harness.mjs';
import { start } from '../../scripts/serve.mjs';

let env;
let host;
let page; // the tutorial
let app; // the user's own app, first-party, in the same browser
let userAutosave;
const errors = [];

/** Every IndexedDB record of a page or frame, as text ({} where the browser gives the frame no storage). */
const dumpStorage = (target) => target.evaluate(async () => {
  const out = {};
  let names;
  try { names = await indexedDB.databases(); } catch { return out; }
  for (const { name } of names) {
    const db = await new Promise((res, rej) => { const r = indexedDB.open(name); r.onsuccess = () => res(r.result); r.onerror = () => rej(r.error); });
    for (const store of db.objectStoreNames) {
      const all = await new Promise((res) => { const r = db.transaction(store).objectStore(store).getAll(); r.onsuccess = () => res(r.result); });
      out[`${name}/${store}`] = JSON.stringify(all, (k, v) => (ArrayBuffer.isView(v) ? `bytes:${v.length}` : v));
    }
    db.close();
  }
  return out;
});

before(async () => {
  env = await launch();
  host = await start(0, path.join(ROOT, 'tests/e2e/pages'));
  // The user's own work in the full app, autosaved; and the tutorial's states, made in the app.
  app = await env.newPage({ path: '#tool=fit', keep: true }); // shared by every test
  await app.waitForSelector('[data-testid=fit-sliders] .row');
  // A target made from the values, then the values moved off it: the author's Fit problem.
  await app.click('button[data-act=make-target]');
  await app.waitForFunction(() => window.filigree.testHooks.fit.state().truth);
  await app.focus('[data-testid=fit-sliders] input');
  for (let i = 0; i < 8; i++) await app.keyboard.press('ArrowRight');
  const states = {};
  for (const tool of ['fit', 'pixel', 'tangle', 'micro', 'texture']) {
    await app.evaluate((t) => window.filigree.selectTool(t), tool);
    states[tool] = (await app.evaluate(async () => {
      for (let i = 0; i < 100; i++) {
        try { return await window.filigree.currentShare(); } catch { await new Promise((r) => setTimeout(r, 100)); }
      }
      return null;
    })).fragment;
  }
  // Back on Fit: the user's document, autosaved.
  await app.evaluate(() => window.filigree.selectTool('fit'));
  for (let i = 0; i < 100; i++) {
    userAutosave = await dumpStorage(app);
    if (/"values"/.test(userAutosave['filigree/autosave'] ?? '') && !/"values":\[0\.17,/.test(userAutosave['filigree/autosave'])) break;
    await app.waitForTimeout(100);
  }
  page = await app.context().newPage();
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  page.on('pageerror', (e) => errors.push(e.message));
  const q = new URLSearchParams({ app: env.url });
  await page.goto(`http://127.0.0.1:${host.address().port}/tutorial.html?${q}#${encodeURIComponent(JSON.stringify(states))}`);
  await page.waitForFunction(() => customElements.get('filigree-embed'));
});
afterEach(() => env?.closeTestPages());
after(async () => {
  await env?.close();
  await new Promise((r) => (host ? host.close(r) : r()));
});

const SLOT = (slot, n = 0) => `:nth-match([data-slot=${slot}], ${n + 1})`;

/** Scroll embed `sel` into the tutorial's view, wait for its app; {frame, box}. */
async function show(sel) {
  const el = page.locator(sel);
  await el.scrollIntoViewIfNeeded();
  const handle = await page.waitForSelector(sel.startsWith('iframe') ? sel : `${sel} >> css=iframe`, { timeout: 15000 });
  const frame = await handle.contentFrame();
  await frame.waitForFunction(() => document.documentElement.dataset.coreReady === '1' && document.documentElement.dataset.embedReady === '1', null, { timeout: 30000 });
  await el.scrollIntoViewIfNeeded();
  return { frame, el };
}

/**
 * Wait until embed `el` keeps its height (it follows its page's, which
 * grows as the result and its status arrive), then scroll it into view as
 * the reader would; a machine under load may still be laying it out when
 * `show` scrolled.
 */
async function settle(el) {
  let last = -1;
  for (let same = 0, i = 0; same < 3 && i < 50; i++) {
    const h = (await el.boundingBox())?.height ?? -1;
    same = h === last ? same + 1 : 0;
    last = h;
    await page.waitForTimeout(100);
  }
  await el.scrollIntoViewIfNeeded();
}

/** The picture is in view: the embed inside the tutorial's window, the picture inside the embed's, nothing scrolled. */
async function inView(frame, el) {
  await settle(el);
  const box = await el.boundingBox();
  const vh = await page.evaluate(() => innerHeight);
  assert.ok(box.y >= 0 && box.y + box.height <= vh + 1, `the embed spans ${box.y}..${box.y + box.height} in a ${vh} px window`);
  const f = await frame.evaluate(() => {
    const pic = document.querySelector('.embed-picture').getBoundingClientRect();
    return { top: pic.top, bottom: pic.bottom, w: pic.width, h: pic.height, vh: innerHeight, scroll: document.scrollingElement.scrollTop, sh: document.scrollingElement.scrollHeight };
  });
  assert.equal(f.scroll, 0);
  assert.ok(f.sh <= f.vh + 1, `the embed's page is ${f.sh} px in a ${f.vh} px frame (it would scroll)`);
  assert.ok(f.top >= 0 && f.bottom <= f.vh, `the picture spans ${f.top}..${f.bottom} of ${f.vh}`);
  assert.ok(f.w >= 200 && f.h >= 200, `the picture is ${f.w}×${f.h}`);
  return { box, frame: f };
}

/** A canvas's pixels, hashed; and how many are not the background's. */
const canvasFacts = (frame, sel) => frame.$eval(sel, (c) => {
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  let h = 2166136261, ink = 0;
  for (let i = 0; i < d.length; i++) h = Math.imul(h ^ d[i], 16777619);
  for (let i = 0; i < d.length; i += 4) if (d[i + 3] && (d[i] !== d[0] || d[i + 1] !== d[1] || d[i + 2] !== d[2])) ink++;
  return { hash: h >>> 0, ink };
});

const present = (frame) => frame.evaluate(() => JSON.stringify(window.filigree.doc.present(), (k, v) => (ArrayBuffer.isView(v) ? `bytes:${v.length}` : v)));

async function resetBack(frame, origin) {
  await frame.click('.embed-bar [data-act=embed-reset]');
  await frame.waitForFunction((o) => JSON.stringify(window.filigree.doc.present(), (k, v) => (ArrayBuffer.isView(v) ? `bytes:${v.length}` : v)) === o, origin);
  assert.equal(await frame.isHidden('.embed-bar [data-act=embed-reset]'), true, 'Reset hides once back');
}

/** The frame's page height, and the element's, which follows it. */
async function followsContent(frame, el) {
  await page.waitForFunction(async () => true);
  const h = await frame.evaluate(() => Math.ceil(document.body.getBoundingClientRect().height));
  const box = await el.boundingBox();
  assert.ok(Math.abs(box.height - h) <= 2, `the element is ${box.height} px, its content ${h} px`);
}

test('facades: labels name the tool in capitals; below the fold nothing loads', async () => {
  const labels = await page.$$eval('filigree-embed', (els) => els.map((e) => e.shadowRoot.querySelector('.title')?.textContent ?? e.shadowRoot.querySelector('iframe')?.title));
  assert.deepEqual(labels, ['Texturing the fish', 'A leaf tangle', 'A gyroid', 'Perceptual texture sliders', 'Your own tangle', 'Filigree Fit']);
  assert.equal(await page.locator('filigree-embed').last().evaluate((e) => e.shadowRoot.querySelector('iframe')), null, 'far below, still a facade');
});

test('Pixel: the fish first, controls in the drawer; the density moves and Reset brings it back', async () => {
  const { frame, el } = await show(SLOT('pixel'));
  await frame.waitForFunction(() => window.filigree.testHooks.pixel?.result() && !window.filigree.testHooks.pixel.pending(), null, { timeout: 30000 });
  await inView(frame, el);
  await followsContent(frame, el);
  assert.equal(await frame.isHidden('#embed-drawer'), true, 'the controls start in the drawer');
  const origin = await present(frame);
  await frame.click('.embed-bar [data-act=embed-controls]');
  await frame.waitForSelector('#embed-drawer', { state: 'visible' });
  await followsContent(frame, el);
  const before = await frame.evaluate(() => window.filigree.testHooks.pixel.result());
  await frame.focus('[data-testid=pixel-params] input[type=range]');
  for (let i = 0; i < 10; i++) await frame.press('[data-testid=pixel-params] input[type=range]', 'ArrowLeft');
  await frame.waitForFunction((b) => { const h = window.filigree.testHooks.pixel; return !h.pending() && h.result() && h.result() !== b; }, before, { timeout: 30000 }).catch(() => {});
  assert.notEqual(await present(frame), origin, 'the reader changed the density');
  await resetBack(frame, origin);
});

test('Fit in a plain 760×480 iframe: target and result without scrolling; a slider moves the outline; Reset', async () => {
  const { frame, el } = await show('iframe.plain');
  await frame.waitForFunction(() => window.filigree.testHooks.fit?.info(), null, { timeout: 30000 });
  await frame.waitForFunction(() => {
    const c = document.querySelector('[data-testid=fit-overlay]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    for (let i = 3; i < d.length; i += 4) if (d[i]) return true;
    return false;
  }, null, { timeout: 20000 });
  const { frame: f } = await inView(frame, el);
  assert.ok(f.h >= 300, `the target is ${f.h} px tall in a 480 px frame`);
  const target = await canvasFacts(frame, '[data-testid=fit-target]');
  assert.ok(target.ink > 1000, 'the target is drawn');
  const origin = await present(frame);
  const overlay = await canvasFacts(frame, '[data-testid=fit-overlay]');
  await frame.click('.embed-bar [data-act=embed-controls]');
  const slider = '[data-testid=fit-sliders] input[type=range]';
  await frame.focus(slider);
  for (let i = 0; i < 40; i++) await frame.press(slider, 'ArrowRight');
  await frame.waitForFunction((h) => {
    const c = document.querySelector('[data-testid=fit-overlay]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let x = 2166136261;
    for (let i = 0; i < d.length; i++) x = Math.imul(x ^ d[i], 16777619);
    return (x >>> 0) !== h;
  }, overlay.hash, { timeout: 20000 });
  assert.notEqual(await present(frame), origin);
  // Beside the picture in a wide frame: the picture is still whole.
  const pic = await frame.evaluate(() => document.querySelector('.embed-picture').getBoundingClientRect().bottom <= innerHeight);
  assert.equal(pic, true);
  await resetBack(frame, origin);
});

test('Tangle at the author\'s 560 px: the drawing and its step slider in view; steps scrub; the wheel scrolls the tutorial until the reader clicks in', async () => {
  const { frame, el } = await show(SLOT('tangle'));
  await frame.waitForFunction(() => window.filigree.testHooks.tangle?.result() && !window.filigree.testHooks.tangle.pending(), null, { timeout: 30000 });
  assert.equal(Math.round((await el.boundingBox()).height), 560, 'the author\'s height');
  await inView(frame, el);
  const step = await frame.evaluate(() => {
    const r = document.querySelector('[data-testid=tangle-step]').getBoundingClientRect();
    return { top: r.top, bottom: r.bottom, vh: innerHeight };
  });
  assert.ok(step.bottom <= step.vh && step.top >= 0, `the step slider at ${step.top}..${step.bottom} of ${step.vh}`);
  const full = await canvasFacts(frame, '[data-testid=tangle-canvas]');

  // The wheel over the drawing scrolls the tutorial and leaves the drawing alone.
  const box = await el.boundingBox();
  await page.mouse.move(box.x + box.width / 2, box.y + box.height / 2);
  const y0 = await page.evaluate(() => scrollY);
  await page.mouse.wheel(0, 240);
  await page.waitForFunction((y) => scrollY > y + 100, y0, { timeout: 5000 });
  assert.equal((await canvasFacts(frame, '[data-testid=tangle-canvas]')).hash, full.hash, 'no zoom before a click');
  await page.evaluate((y) => scrollTo(0, y), y0);

  // Steps scrub by the keyboard; the count follows.
  await frame.click('[data-testid=tangle-step]');
  await frame.press('[data-testid=tangle-step]', 'Home');
  await frame.waitForFunction(() => /^step 0 \//.test(document.querySelector('[data-testid=tangle-count]').textContent));
  await frame.waitForFunction((h) => {
    const c = document.querySelector('[data-testid=tangle-canvas]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let x = 2166136261;
    for (let i = 0; i < d.length; i++) x = Math.imul(x ^ d[i], 16777619);
    return (x >>> 0) !== h;
  }, full.hash);
  await frame.press('[data-testid=tangle-step]', 'End');

  // Clicked into: now the wheel zooms the drawing and the tutorial stays.
  const painted = await canvasFacts(frame, '[data-testid=tangle-canvas]');
  const y1 = await page.evaluate(() => scrollY);
  const c = await frame.$('[data-testid=tangle-canvas]');
  const cb = await c.boundingBox();
  await page.mouse.move(cb.x + cb.width / 2, cb.y + cb.height / 2);
  await page.mouse.wheel(0, -240);
  await frame.waitForFunction((h) => {
    const cv = document.querySelector('[data-testid=tangle-canvas]');
    const d = cv.getContext('2d').getImageData(0, 0, cv.width, cv.height).data;
    let x = 2166136261;
    for (let i = 0; i < d.length; i++) x = Math.imul(x ^ d[i], 16777619);
    return (x >>> 0) !== h;
  }, painted.hash, { timeout: 5000 });
  assert.equal(await page.evaluate(() => scrollY), y1, 'the tutorial did not scroll');
  // Back to the tutorial: a click on it gives the wheel back to the page.
  await page.mouse.click(5, 5);
  await frame.waitForFunction(() => document.documentElement.dataset.embedEngaged === '0');
});

test('Micro: the structure first; dragging orbits it (read-only, not inert); Reset', async () => {
  const { frame, el } = await show(SLOT('micro'));
  await frame.waitForFunction(() => window.filigree.testHooks.micro?.last(), null, { timeout: 45000 });
  await inView(frame, el);
  await followsContent(frame, el);
  const origin = await present(frame);
  const yaw = await frame.evaluate(() => window.filigree.testHooks.micro.state().camera.yaw);
  const cb = await (await frame.$('[data-testid=micro-canvas]')).boundingBox();
  await page.mouse.move(cb.x + cb.width / 2, cb.y + cb.height / 2);
  await page.mouse.down();
  await page.mouse.move(cb.x + cb.width / 2 + 60, cb.y + cb.height / 2 + 10, { steps: 6 });
  await page.mouse.up();
  await frame.waitForFunction((y) => window.filigree.testHooks.micro.state().camera.yaw !== y, yaw);
  await resetBack(frame, origin);
});

test('Texture: the retrieved texture first; a perceptual slider retrieves another; no "Drop … or" with nothing after; Reset', async () => {
  const { frame, el } = await show(SLOT('texture'));
  const settled = () => !window.filigree.testHooks.texture?.pending() && !!document.querySelector('[data-testid=texture-retrieved][data-model]');
  await frame.waitForFunction(settled, null, { timeout: 45000 });
  await inView(frame, el);
  await followsContent(frame, el);
  const origin = await present(frame);
  await frame.click('.embed-bar [data-act=embed-controls]');
  const words = await frame.textContent('[data-testid=texture-drop]');
  assert.doesNotMatch(words, /Drop or paste an image here, or\s*$/);
  assert.match(words, /author's example/);
  const slider = '[data-testid=texture-sliders] input[type=range]';
  assert.equal(await frame.isEnabled(slider), true, 'the sliders move in a read-only embed');
  await frame.focus(slider);
  for (let i = 0; i < 4; i++) await frame.press(slider, 'ArrowRight');
  await frame.waitForFunction((o) => JSON.stringify(window.filigree.doc.present(), (k, v) => (ArrayBuffer.isView(v) ? `bytes:${v.length}` : v)) !== o, origin);
  await frame.waitForFunction(settled, null, { timeout: 30000 });
  await resetBack(frame, origin);
});

test('an interactive embed with its controls open; the click-to-load Fit; nothing any embed did was saved', async () => {
  const { frame, el } = await show(SLOT('tangle', 1));
  assert.equal(await frame.isVisible('#embed-drawer'), true, 'controls="open"');
  assert.match(await frame.textContent('.embed-bar'), /interactive/);
  await frame.waitForFunction(() => window.filigree.testHooks.tangle?.result(), null, { timeout: 30000 });
  await inView(frame, el);

  const last = page.locator('filigree-embed').last();
  await last.scrollIntoViewIfNeeded();
  await page.waitForTimeout(300);
  assert.equal(await last.evaluate((e) => e.shadowRoot.querySelector('iframe')), null, 'load="click" waits for the click');
  await last.getByRole('button', { name: /Open the embedded Filigree: Filigree Fit/ }).click();
  const f2 = await (await page.waitForSelector('filigree-embed:last-of-type >> css=iframe')).contentFrame();
  await f2.waitForFunction(() => document.documentElement.dataset.embedReady === '1', null, { timeout: 30000 });

  // Nothing persisted: the frames (third-party, partitioned) hold no storage, and the user's own autosave is as it was.
  for (const fr of page.frames().filter((x) => x !== page.mainFrame())) {
    assert.deepEqual(await dumpStorage(fr), {}, `${fr.url()} stored something`);
  }
  assert.deepEqual(await dumpStorage(app), userAutosave, 'the user\'s autosave is untouched');
  assert.deepEqual(errors, []);
});
