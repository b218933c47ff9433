// The document controller (www/app/document.js) and share links (www/app/share.js):
// links round-trip a Pixel and a Fit state into a fresh browser with the
// same result pixels; bad project files and links are refused without
// touching the user's work; leaving a tool or changing the generator during
// a fit stops it cleanly; examples are undoable; blocked storage is said
// plainly and the app still works; test hooks exist only in a test page.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import zlib from 'node:zlib';
import { launch, pickGenerator, ready, ROOT, HOOK_SCRIPTS } from './harness.mjs';
import { bundledOnly } from '../../scripts/bundle.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const ERROR = '[data-testid=doc-error]';

function watchErrors(page) {
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  return errors;
}

// ---- Pixel helpers -------------------------------------------------------------------

async function waitForPixel(page, previous = null) {
  await page.waitForFunction((prev) => {
    const el = document.querySelector('[data-testid=pixel-status]');
    const runs = Number(el?.dataset.runs || 0);
    return el.textContent.startsWith('done') && runs > 0 && (prev === null || runs > prev)
      && !window.filigree.testHooks.pixel.pending();
  }, previous, { timeout: 30000 });
  return page.$eval('[data-testid=pixel-status]', (el) => Number(el.dataset.runs));
}

async function dragStroke(page, points, size = 128) {
  const box = await page.locator('[data-testid=pixel-canvas]').boundingBox();
  const z = box.width / size;
  const at = ([x, y]) => [box.x + x * z, box.y + y * z];
  await page.mouse.move(...at(points[0]));
  await page.mouse.down();
  for (const p of points.slice(1)) await page.mouse.move(...at(p), { steps: 6 });
  await page.mouse.up();
}

// FNV-1a of a result's pixels, computed in the page.
const PIXEL_HASH = `(rgba) => { let h = 2166136261; for (let i = 0; i < rgba.length; i++) { h ^= rgba[i]; h = Math.imul(h, 16777619) >>> 0; } return h; }`;
const pixelResultHash = (page) => page.evaluate(`(${PIXEL_HASH})(window.filigree.testHooks.pixel.result().rgba)`);

async function pixelReady(page) {
  await page.waitForFunction(() => window.filigree?.testHooks?.pixel?.state()?.example === 'fish');
  return waitForPixel(page);
}

// ---- Fit helpers ----------------------------------------------------------------------


async function runFit(page) {
  await page.click('button[data-act=fit]');
  await page.waitForFunction(() => /^fitted/.test(document.querySelector('[data-testid=fit-status]').textContent)
    || !document.querySelector('[data-testid=doc-error]').hidden, null, { timeout: 120000 });
  assert.equal(await page.isHidden(ERROR), true, await page.textContent(ERROR));
}

/** Hash of the program rendered at 256² with the document's values. */
const fitRenderHash = (page) => page.evaluate(async (hashSrc) => {
  const hash = eval(hashSrc); // eslint-disable-line no-eval
  const d = window.filigree.testHooks.fit.state();
  const info = window.filigree.testHooks.fit.info();
  const params = Object.fromEntries(info.params.map((p, i) => [p.name, d.values[i]]));
  const r = await window.filigree.pool.run('render-pattern', { program: d.program, params, size: 256 });
  return { render: hash(r.rgba), target: hash(d.target.rgba) };
}, PIXEL_HASH);

async function startPaperFit(page) {
  await pickGenerator(page, 'stripes');
  await page.click('button[data-act=make-target]');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state().truth !== null);
  await page.selectOption('select[name=budget]', 'paper');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state().settings.budget === 'paper');
  await page.click('button[data-act=fit]');
  await page.waitForFunction(() => /loss/.test(document.querySelector('[data-testid=fit-status]').textContent)
    && !document.querySelector('button[data-act=cancel]').disabled);
}

// ---- share links ----------------------------------------------------------------------------

test('a Pixel share link opens the same state and the same result pixels in a fresh browser', async () => {
  const a = await env.newPage({ path: '#tool=pixel' });
  let runs = await pixelReady(a);
  await dragStroke(a, [[20, 70], [45, 62], [70, 66], [95, 80]]);
  runs = await waitForPixel(a, runs);
  await a.$eval('[data-key=density] input', (el) => { el.value = '0.6'; el.dispatchEvent(new Event('input', { bubbles: true })); el.dispatchEvent(new Event('change', { bubbles: true })); });
  runs = await waitForPixel(a, runs);
  const want = await a.evaluate(() => {
    const s = window.filigree.testHooks.pixel.state();
    return { strokes: s.strokes, params: s.params, maskOn: s.mask.bits.reduce((x, y) => x + y, 0) };
  });
  const wantHash = await pixelResultHash(a);

  // The Copy link button makes the link (the clipboard may be refused headless; the link is shown then).
  await a.click('button[data-act=copy-link]');
  await a.waitForSelector('.toast[data-link]');
  const link = await a.$eval('.toast[data-link]', (t) => t.dataset.link);
  assert.match(link, /#tool=pixel&share=[A-Za-z0-9_-]+$/);
  assert.ok(link.length < 8192 + 200, `the link is ${link.length} characters`);

  const b = await env.newPage({ path: link.slice(link.indexOf('#')) });
  await b.waitForFunction((n) => window.filigree?.testHooks?.pixel?.state()?.strokes.length === n, want.strokes.length);
  await waitForPixel(b);
  const got = await b.evaluate(() => {
    const s = window.filigree.testHooks.pixel.state();
    return { strokes: s.strokes, params: s.params, maskOn: s.mask.bits.reduce((x, y) => x + y, 0) };
  });
  assert.deepEqual(got, want);
  assert.equal(await pixelResultHash(b), wantHash, 'same result pixels');
  assert.equal(new URL(b.url()).hash, '#tool=pixel', 'the link is consumed (a reload does not reapply it)');
  // The link came in as an undoable step over the fresh document.
  assert.equal(await b.isEnabled('button[data-act=undo]'), true);
});

test('a Fit share link restores program, target and values; the same seed fits to the same result', async () => {
  const a = await env.newPage({ path: '#tool=fit' });
  await pickGenerator(a, 'stripes');
  await a.click('button[data-act=make-target]');
  await a.waitForFunction(() => window.filigree.testHooks.fit.state().truth !== null);
  await runFit(a);
  const want = await a.evaluate(() => {
    const s = window.filigree.testHooks.fit.state();
    return { generator: s.generator, values: s.values, truth: s.truth, settings: s.settings, loss: s.result.loss };
  });
  const wantHash = await fitRenderHash(a);
  const { fragment } = await a.evaluate(() => window.filigree.currentShare());

  const b = await env.newPage({ path: `#${fragment}` });
  await b.waitForFunction(() => window.filigree?.testHooks?.fit?.state()?.generator === 'stripes'
    && window.filigree.testHooks.fit.info()?.params.length === window.filigree.testHooks.fit.state().values.length);
  const got = await b.evaluate(() => {
    const s = window.filigree.testHooks.fit.state();
    return { generator: s.generator, values: s.values, truth: s.truth, settings: s.settings, loss: s.result.loss };
  });
  assert.deepEqual(got, want);
  assert.deepEqual(await fitRenderHash(b), wantHash, 'same target pixels and same pattern pixels');
  // Fitting again with the same seed gives exactly the same values.
  await runFit(b);
  assert.deepEqual(await b.evaluate(() => window.filigree.testHooks.fit.state().values), want.values);
  assert.deepEqual(await fitRenderHash(b), wantHash);
});

test('a corrupt or hostile link says so plainly and leaves the autosaved work alone', async () => {
  const page = await env.newPage({ path: '#tool=pixel' });
  await pixelReady(page);
  await dragStroke(page, [[20, 70], [60, 64], [95, 80]]);
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state().strokes.length === 4);
  await page.waitForTimeout(700); // the autosave is debounced
  const strokes = () => page.evaluate(() => window.filigree.testHooks.pixel.state().strokes.length);

  const cases = [
    ['tool=pixel&share=%%%not-base64', /This link is damaged or not a Filigree link/],
    ['tool=pixel&share=AAAAAAAA', /This link is damaged or not a Filigree link/],
    // A zip bomb: 8 MB of zeros deflate to a few KB.
    [`tool=pixel&share=${zlib.deflateRawSync(Buffer.alloc(8 << 20)).toString('base64url')}`, /unpacks to more than 1 MB/],
  ];
  // A well-formed link whose state is wrong: the mask does not match its size.
  const bad = await page.evaluate(async () => {
    const { encodeShare } = await import('./www/app/share.js');
    return encodeShare('pixel', { example: 'fish', sheet: null, sprite: null, mask: { width: 128, height: 128, packed: new Uint8Array(3) }, strokes: [], params: {}, names: {} });
  });
  cases.push([bad, /could not be opened: mask is cut short/]);
  for (const [fragment, message] of cases) {
    await page.evaluate((f) => { location.hash = f; }, fragment);
    await page.waitForFunction((re) => new RegExp(re).test(document.querySelector('[data-testid=doc-error]').textContent), message.source);
    const text = await page.textContent(ERROR);
    assert.match(text, /Your own work is unchanged\.$/);
    assert.ok(!/TypeError|undefined|at \w+ \(/.test(text), `plain words: ${text}`);
    assert.equal(await strokes(), 4, 'the document is untouched');
  }
  await page.reload();
  await page.waitForFunction(() => window.filigree?.testHooks?.pixel?.state()?.strokes.length === 4);
  await waitForPixel(page);
  assert.equal(await strokes(), 4, 'the autosave is untouched');
});

// ---- project files ------------------------------------------------------------------------------

// Issue 34: a Tangle link whose start is an SVG of 3,000 nested groups (it
// crashed the worker: "memory access out of bounds") and one whose start
// rectangle is a million units a side (one step asked for four million
// pieces) are refused in plain words; the Tangle document stays.
test('a Tangle link with a too-deep SVG or a huge start is refused; the work stays', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => window.filigree.testHooks?.tangle?.state()?.grammar);
  const before = await page.evaluate(() => JSON.stringify(window.filigree.testHooks.tangle.state()));
  const link = (start) => page.evaluate(async (start) => {
    const { encodeShare } = await import('./www/app/share.js');
    return encodeShare('tangle', {
      example: null, grammar: 'outline(4) : a -> [b, c]\n', seed: 1, start,
      wobble: 0, stroke_width: 1, edits: [], selected: null,
    });
  }, start);
  const deep = `<svg xmlns="http://www.w3.org/2000/svg">${'<g>'.repeat(3000)}<rect width="9" height="9"/>${'</g>'.repeat(3000)}</svg>`;
  for (const [start, message] of [
    [{ kind: 'svg', svg: deep }, /could not be opened: start\.svg.*more than 256 deep/],
    [{ kind: 'rect', width: 1e6, height: 1e6 }, /could not be opened: start\.width.*at most 20000/],
  ]) {
    const fragment = await link(start);
    await page.evaluate((f) => { location.hash = f; }, fragment);
    await page.waitForFunction((re) => new RegExp(re).test(document.querySelector('[data-testid=doc-error]')?.textContent ?? ''), message.source);
    assert.match(await page.textContent(ERROR), /Your own work is unchanged\.$/);
    assert.equal(await page.evaluate(() => JSON.stringify(window.filigree.testHooks.tangle.state())), before, 'the document is untouched');
  }
});

// Issue 34: the same bad Tangle states as a project file (Open project…):
// a too-deep SVG start, a million-unit start and a runaway grammar are
// refused in plain words before anything is autosaved; the work stays.
test('a Tangle project file with a too-deep SVG or a huge start is refused; the autosave stays', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => window.filigree.testHooks?.tangle?.state()?.grammar);
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('button[data-act=save-project]')]);
  const good = JSON.parse(fs.readFileSync(await download.path(), 'utf8'));
  assert.equal(good.tool, 'tangle');
  const before = await page.evaluate(() => JSON.stringify(window.filigree.testHooks.tangle.state()));
  const saved = () => page.evaluate(() => new Promise((resolve) => {
    const open = indexedDB.open('filigree');
    open.onsuccess = () => {
      const db = open.result;
      const names = [...db.objectStoreNames];
      if (!names.length) { resolve(null); return; }
      const tx = db.transaction(names, 'readonly');
      const all = names.map((n) => new Promise((r) => { const q = tx.objectStore(n).getAll(); q.onsuccess = () => r(q.result); }));
      Promise.all(all).then((v) => resolve(JSON.stringify(v)));
    };
    open.onerror = () => resolve(null);
  }));
  const autosaveBefore = await saved();
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'filigree-tangle-'));
  const deep = `<svg xmlns="http://www.w3.org/2000/svg">${'<g>'.repeat(3000)}<rect width="9" height="9"/>${'</g>'.repeat(3000)}</svg>`;
  for (const [name, start, message] of [
    ['deep.filigree.json', { kind: 'svg', svg: deep }, /deep\.filigree\.json was not opened — .*more than 256 deep/],
    ['huge.filigree.json', { kind: 'rect', width: 1e6, height: 1e6 }, /huge\.filigree\.json was not opened — .*at most 20000/],
  ]) {
    const file = path.join(dir, name);
    fs.writeFileSync(file, JSON.stringify({ ...good, state: { ...good.state, start } }));
    await page.setInputFiles('input[data-input=project]', file);
    await page.waitForFunction((re) => new RegExp(re).test(document.querySelector('[data-testid=doc-error]')?.textContent ?? ''), message.source, { timeout: 20000 });
    assert.match(await page.textContent(ERROR), /Your work is unchanged\.$/);
    assert.equal(await page.evaluate(() => JSON.stringify(window.filigree.testHooks.tangle.state())), before, 'the document is untouched');
  }
  assert.equal(await saved(), autosaveBefore, 'the autosave is untouched');
});

test('a corrupt project file is refused before anything is autosaved; the work stays', async () => {
  const page = await env.newPage({ path: '#tool=pixel' });
  await pixelReady(page);
  await dragStroke(page, [[20, 70], [60, 64], [95, 80]]);
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state().strokes.length === 4);
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('button[data-act=save-project]')]);
  const good = JSON.parse(fs.readFileSync(await download.path(), 'utf8'));
  assert.equal(good.tool, 'pixel');
  assert.equal(good.stateVersion, 1);

  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'filigree-doc-'));
  const write = (name, text) => { const f = path.join(dir, name); fs.writeFileSync(f, text); return f; };
  const broken = structuredClone(good);
  broken.state.mask.bits = { $bytes: Buffer.from([1, 0, 1]).toString('base64') };
  const files = [
    [write('notes.filigree.json', 'hello'), /notes\.filigree\.json was not opened — not a Filigree project: the file is not valid JSON/],
    [write('mask.filigree.json', JSON.stringify(broken)), /mask\.filigree\.json was not opened — mask\.bits must hold 16384 values \(128×128\), found 3/],
    [write('future.filigree.json', JSON.stringify({ ...good, version: 99 })), /saved by a newer Filigree/],
    [write('strokes.filigree.json', JSON.stringify({ ...good, state: { ...good.state, strokes: [[[1, 2], [3, 'x']]] } })), /strokes\.0\.1 must be a point/],
    // The core checks the state with its own request limits (src/pixel/state.rs).
    [write('dmax.filigree.json', JSON.stringify({ ...good, state: { ...good.state, params: { ...good.state.params, d_max: 2000 } } })), /dmax\.filigree\.json was not opened — params\.d_max must be a number from 0 to 1000\. Your work is unchanged\.$/],
  ];
  let runs = await waitForPixel(page);
  for (const [file, message] of files) {
    await page.setInputFiles('input[data-input=project]', file);
    await page.waitForFunction((re) => new RegExp(re).test(document.querySelector('[data-testid=doc-error]').textContent), message.source);
    assert.match(await page.textContent(ERROR), /Your work is unchanged\.$/);
    assert.equal(await page.evaluate(() => window.filigree.testHooks.pixel.state().strokes.length), 4);
  }
  // A texturing run that finishes after the refusal does not wipe it: the
  // message stays until the user acts (it once vanished with the next result).
  const shown = await page.textContent(ERROR);
  await dragStroke(page, [[30, 40], [70, 44]]);
  runs = await waitForPixel(page, runs);
  assert.equal(await page.isHidden(ERROR), false);
  assert.equal(await page.textContent(ERROR), shown);
  assert.equal(await page.evaluate(() => window.filigree.testHooks.pixel.state().strokes.length), 5);
  await page.click('button[data-act=undo]');
  // A format-1 project (before stateVersion) still opens: older files migrate.
  const v1 = { format: 'filigree-project', version: 1, tool: 'pixel', state: { ...good.state, strokes: [] } };
  await page.setInputFiles('input[data-input=project]', write('old.filigree.json', JSON.stringify(v1)));
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state().strokes.length === 0);
  assert.equal(await page.isHidden(ERROR), true);
  // Undo brings the whole previous document back.
  await page.click('button[data-act=undo]');
  assert.equal(await page.evaluate(() => window.filigree.testHooks.pixel.state().strokes.length), 4);
  await page.waitForTimeout(700);
  await page.reload();
  await page.waitForFunction(() => window.filigree?.testHooks?.pixel?.state()?.strokes.length === 4);
  fs.rmSync(dir, { recursive: true, force: true });
});

test('a Fit project saved by the app opens again through the core; a bad setting is named', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await pickGenerator(page, 'stripes');
  await page.click('button[data-act=make-target]');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state().truth !== null);
  const want = await page.evaluate(() => window.filigree.testHooks.fit.state());
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('button[data-act=save-project]')]);
  const saved = JSON.parse(fs.readFileSync(await download.path(), 'utf8'));
  const dir = fs.mkdtempSync(path.join(os.tmpdir(), 'filigree-fit-'));
  const bad = path.join(dir, 'budget.filigree.json');
  fs.writeFileSync(bad, JSON.stringify({ ...saved, state: { ...saved.state, settings: { ...saved.state.settings, budget: 'slow' } } }));
  await page.setInputFiles('input[data-input=project]', bad);
  await page.waitForFunction(() => /settings\.budget must be one of quick, paper/.test(document.querySelector('[data-testid=doc-error]').textContent));
  // Another generator, then the saved file: the same document comes back.
  await pickGenerator(page, 'circles-grid');
  const good = path.join(dir, 'stripes.filigree.json');
  fs.copyFileSync(await download.path(), good);
  await page.setInputFiles('input[data-input=project]', good);
  await page.waitForFunction(() => window.filigree.testHooks.fit.state()?.generator === 'stripes');
  const got = await page.evaluate(() => window.filigree.testHooks.fit.state());
  assert.deepEqual({ ...got, target: null }, { ...want, target: null });
  assert.deepEqual(got.target.rgba, want.target.rgba);
  assert.equal(got.result, null, 'a missing result is null, as the panel keeps it');
  assert.equal(await page.isHidden(ERROR), true);
  fs.rmSync(dir, { recursive: true, force: true });
});

test('undo after opening a project restores size, sheet and strokes together', async () => {
  const page = await env.newPage({ path: '#tool=pixel' });
  await pixelReady(page);
  // Save the trunk as a project, go back to the fish, open the trunk project, undo.
  await page.click('button[data-example=trunk]');
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state()?.example === 'trunk');
  let runs = await waitForPixel(page);
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('button[data-act=save-project]')]);
  const file = path.join(os.tmpdir(), `trunk-${process.pid}.filigree.json`);
  fs.copyFileSync(await download.path(), file);
  await page.click('button[data-example=fish]');
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state()?.example === 'fish');
  runs = await waitForPixel(page, runs);
  const fish = await page.evaluate(() => {
    const s = window.filigree.testHooks.pixel.state();
    return { w: s.mask.width, strokes: s.strokes.length, sheet: s.sheet.length };
  });
  await page.setInputFiles('input[data-input=project]', file);
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state()?.example === 'trunk');
  runs = await waitForPixel(page, runs);
  await page.keyboard.press('Control+z');
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state()?.example === 'fish');
  await waitForPixel(page, runs);
  const after = await page.evaluate(() => {
    const s = window.filigree.testHooks.pixel.state();
    const r = window.filigree.testHooks.pixel.result();
    const layers = document.querySelector('.viewport .layers');
    const zoom = Number(document.querySelector('[data-testid=zoom]').textContent.slice(1));
    return {
      doc: { w: s.mask.width, strokes: s.strokes.length, sheet: s.sheet.length },
      resultWidth: r.width, layerWidth: parseFloat(layers.style.width) / zoom,
    };
  });
  assert.deepEqual(after.doc, fish);
  assert.equal(after.resultWidth, 128, 'the result is the fish again');
  assert.equal(after.layerWidth, 128, 'the canvas is sized for the fish again');
  fs.rmSync(file, { force: true });
});

// ---- examples ----------------------------------------------------------------------------------

test('an example click after edits is one undoable step', async () => {
  const page = await env.newPage({ path: '#tool=pixel' });
  await pixelReady(page);
  await page.click('button[data-act=clear-strokes]');
  await dragStroke(page, [[20, 70], [60, 64], [95, 80]]);
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state().strokes.length === 1);
  await page.click('button[data-example=trunk]');
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state()?.example === 'trunk');
  await page.locator('body').focus();
  await page.keyboard.press('Control+z');
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state()?.example === 'fish');
  assert.equal(await page.evaluate(() => window.filigree.testHooks.pixel.state().strokes.length), 1, 'the drawing is back');
  await page.keyboard.press('Control+y');
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state()?.example === 'trunk');
  await page.keyboard.press('Control+Shift+z'); // nothing left to redo
  assert.equal(await page.evaluate(() => window.filigree.testHooks.pixel.state().example), 'trunk');
});

// ---- lifecycle during a fit -----------------------------------------------------------------

test('switching tools during a fit lets it run on (issue 35 item 4); Stop idles the workers within 1 s, no error, the Fit state kept', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  const errors = watchErrors(page);
  await startPaperFit(page);
  const before = await page.evaluate(() => window.filigree.testHooks.fit.state());
  await page.click('#tools button[data-tool=inspect]');
  await page.waitForTimeout(500);
  assert.ok(await page.evaluate(() => window.filigree.pool.pending) > 0, 'the fit runs on in another tool');
  assert.equal(await page.$$eval('.toast-error', (t) => t.length), 0, 'no error toast');

  await page.click('#tools button[data-tool=fit]');
  await page.waitForFunction(() => window.filigree?.testHooks?.fit?.info()?.params.length === window.filigree.testHooks.fit.state().values.length
    && document.querySelectorAll('[data-testid=fit-sliders] .row').length > 0);
  assert.equal(await page.isEnabled('button[data-act=cancel]'), true, 'Stop enabled: the fit is still running');
  await page.click('button[data-act=cancel]');
  const t0 = Date.now();
  await page.waitForFunction(() => window.filigree.pool.pending === 0, null, { timeout: 1000, polling: 20 });
  const idleMs = Date.now() - t0;
  assert.ok(idleMs <= 1000, `idle after ${idleMs} ms`);
  assert.equal(await page.isEnabled('button[data-act=fit]'), true, 'Fit enabled');
  assert.equal(await page.isDisabled('button[data-act=cancel]'), true, 'Stop disabled');
  const back = await page.evaluate(() => window.filigree.testHooks.fit.state());
  assert.deepEqual({ ...back, target: null }, { ...before, target: null });
  assert.equal(await page.isHidden(ERROR), true);
  assert.deepEqual(errors, []);
});

test('changing the generator during a fit stops the old fit; the new sliders stay intact', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  const errors = watchErrors(page);
  await startPaperFit(page);
  await page.selectOption('[data-testid=fit-generator]', 'circles-grid');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state()?.generator === 'circles-grid'
    && window.filigree.testHooks.fit.info()?.params.length === window.filigree.testHooks.fit.state().values.length);
  await page.waitForFunction(() => window.filigree.pool.pending === 0, null, { timeout: 2000 });
  await page.waitForTimeout(500);
  const s = await page.evaluate(() => ({
    running: window.filigree.testHooks.fit.running(), result: window.filigree.testHooks.fit.state().result,
    sliders: document.querySelectorAll('[data-testid=fit-sliders] .row').length,
    params: window.filigree.testHooks.fit.info().params.length,
  }));
  assert.equal(s.running, false);
  assert.equal(s.result, null, 'the old fit did not finish into the new generator');
  assert.equal(s.sliders, s.params);
  assert.equal(await page.isHidden(ERROR), true, await page.textContent(ERROR));
  // The new generator starts with an empty target: Run fit waits for one and says so (issue 35).
  assert.equal(await page.isDisabled('button[data-act=fit]'), true);
  assert.match(await page.textContent('[data-testid=fit-why]'), /target is empty/);
  assert.deepEqual(errors, []);
  // One undo brings the stripes back, with their values.
  await page.click('button[data-act=undo]');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state()?.generator === 'stripes');
});

// ---- storage ------------------------------------------------------------------------------------

/** The Fit autosave's undo history as stored: {past, future} lengths and values. */
const storedHistory = (page) => page.evaluate(() => new Promise((resolve, reject) => {
  const r = indexedDB.open('filigree');
  r.onerror = () => reject(r.error);
  r.onsuccess = () => {
    const db = r.result;
    const get = db.transaction('autosave', 'readonly').objectStore('autosave').get('fit');
    get.onsuccess = () => {
      db.close();
      const h = get.result?.history;
      resolve(h ? { past: h.past.map((s) => s.values), future: h.future.map((s) => s.values), present: get.result.state.values } : null);
    };
    get.onerror = () => reject(get.error);
  };
}));

test('undo history survives a reload: Undo and Redo go where they went before, within the stored bound', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  const errors = watchErrors(page);
  await page.waitForSelector('[data-testid=fit-sliders] .row[data-param=dx]');
  const values = () => page.evaluate(() => window.filigree.testHooks.fit.state().values);
  const press = async (name) => {
    await page.focus(`[data-testid=fit-sliders] .row[data-param=${name}] input`);
    await page.keyboard.press('ArrowRight');
  };
  const v0 = await values();
  await press('dx');
  const v1 = await values();
  await press('dy');
  const v2 = await values();
  assert.notDeepEqual(v1, v0);
  assert.notDeepEqual(v2, v1);
  // Saved with its history (the autosave's debounce), then reloaded.
  for (let i = 0; i < 50 && JSON.stringify((await storedHistory(page))?.present) !== JSON.stringify(v2); i++) await page.waitForTimeout(100);
  await page.reload();
  await ready(page, '#tool=fit');
  await page.waitForSelector('[data-testid=fit-sliders] .row[data-param=dx]');
  assert.deepEqual(await values(), v2);
  await page.waitForSelector('button[data-act=undo]:not([disabled])', { timeout: 10000 });
  await page.click('button[data-act=undo]');
  assert.deepEqual(await values(), v1, 'Undo after the reload goes back to the state before');
  await page.click('button[data-act=undo]');
  assert.deepEqual(await values(), v0);
  // Redo comes back after a reload too.
  for (let i = 0; i < 50 && JSON.stringify((await storedHistory(page))?.present) !== JSON.stringify(v0); i++) await page.waitForTimeout(100);
  await page.reload();
  await ready(page, '#tool=fit');
  await page.waitForSelector('button[data-act=redo]:not([disabled])', { timeout: 10000 });
  await page.click('button[data-act=redo]');
  assert.deepEqual(await values(), v1, 'Redo after the reload');

  // The bound: the newest HISTORY_STATES each way, and HISTORY_BYTES in all (bytes shared by states counted once).
  const bound = await page.evaluate(async () => {
    const { keptHistory, History, HISTORY_STATES, HISTORY_BYTES } = await import('/www/app/history.js');
    const run = (make, n) => {
      const h = new History(make(0));
      for (let i = 1; i <= n; i++) h.push(make(i));
      for (let i = 0; i < 3; i++) h.undo();
      const k = keptHistory(h);
      return { past: k.past.map((s) => s.i), future: k.future.map((s) => s.i) };
    };
    const shared = new Uint8Array(200 * 1024);
    return {
      states: HISTORY_STATES,
      bytes: HISTORY_BYTES,
      small: run((i) => ({ i, text: 'x'.repeat(100) }), 80),
      big: run((i) => ({ i, text: String(i).repeat(100 * 1024) }), 80),
      sharedBytes: run((i) => ({ i, image: shared }), 80),
    };
  });
  assert.equal(bound.states, 50);
  const range = (a, b) => Array.from({ length: b - a + 1 }, (_, i) => a + i);
  assert.deepEqual(bound.small, { past: range(27, 76), future: [78, 79, 80].reverse() }, 'the newest 50 states back, the oldest dropped');
  assert.ok(bound.big.past.length < 10 && bound.big.past.length > 0, `100 KB states: ${bound.big.past.length} kept within ${bound.bytes} bytes`);
  assert.deepEqual(bound.big.past, range(77 - bound.big.past.length, 76), 'the newest kept');
  assert.equal(bound.sharedBytes.past.length, 50, 'an image shared by every state counts once');
  assert.deepEqual(errors, []);
});

test('undo history: a link opened at load starts from the autosave alone, as before', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await page.waitForSelector('[data-testid=fit-sliders] .row[data-param=dx]');
  const values = () => page.evaluate(() => window.filigree.testHooks.fit.state().values);
  for (const name of ['dx', 'dy']) {
    await page.focus(`[data-testid=fit-sliders] .row[data-param=${name}] input`);
    await page.keyboard.press('ArrowRight');
  }
  const mine = await values();
  for (let i = 0; i < 50 && JSON.stringify((await storedHistory(page))?.present) !== JSON.stringify(mine); i++) await page.waitForTimeout(100);
  assert.equal((await storedHistory(page)).past.length, 2);
  // A link to the defaults, opened in this browser: one Undo back to the autosaved work, no further.
  await page.click('button[data-act=undo]');
  await page.click('button[data-act=undo]');
  const link = `${env.url}#${(await page.evaluate(() => window.filigree.currentShare())).fragment}`;
  await page.click('button[data-act=redo]');
  await page.click('button[data-act=redo]');
  for (let i = 0; i < 50 && JSON.stringify((await storedHistory(page))?.present) !== JSON.stringify(mine); i++) await page.waitForTimeout(100);
  await page.goto('about:blank');
  await page.goto(link);
  await ready(page, '#tool=fit');
  await page.waitForFunction((m) => { const v = window.filigree.testHooks.fit?.state()?.values; return v && JSON.stringify(v) !== JSON.stringify(m); }, mine);
  await page.click('button[data-act=undo]');
  assert.deepEqual(await values(), mine, 'Undo goes back to the autosaved work');
  await page.waitForTimeout(500);
  assert.equal(await page.isDisabled('button[data-act=undo]'), true, 'and no further: the autosave\'s history is not restored under a link');
});


test('when storage hangs the panels still work and say plainly that they cannot save', async () => {
  const page = await env.newPage({ path: null });
  // IndexedDB that never answers (as in some sandboxed or about:blank hosts).
  await page.addInitScript(() => {
    Object.defineProperty(window, 'indexedDB', { value: { open: () => ({}) }, configurable: true });
  });
  const t0 = Date.now();
  await page.goto(`${env.url}#tool=fit`);
  await page.waitForSelector('[data-testid=fit-sliders] .row', { timeout: 15000 });
  await page.waitForSelector('[data-testid=doc-note]:not([hidden])');
  assert.equal(await page.textContent('[data-testid=doc-note]'),
    'This page cannot save your work here (storage is blocked) — use Save project.');
  assert.ok(Date.now() - t0 < 15000);
  // Still usable: a target from values, and Save project offers the file.
  await page.click('button[data-act=make-target]');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state().truth !== null);
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('button[data-act=save-project]')]);
  assert.equal(JSON.parse(fs.readFileSync(await download.path(), 'utf8')).tool, 'fit');
});

test('test hooks are published only in a page a test opened, and leave with their panel', async () => {
  // A page without the harness's init script: nothing for tests, not even an empty registry.
  const context = await env.browser.newContext({ viewport: { width: 1280, height: 800 } });
  try {
    const plain = await context.newPage();
    await plain.goto(`${env.url}#tool=micro`);
    await ready(plain, '#tool=micro');
    await plain.waitForSelector('[data-testid=micro-fit]');
    assert.deepEqual(await plain.evaluate(() => ({
      registry: 'testHooks' in window.filigree,
      globals: Object.keys(window).filter((k) => /^(__)?filigree./i.test(k)),
    })), { registry: false, globals: [] });
  } finally {
    await context.close();
  }
  // A test page: the shown panel's hooks (Micro's and its reconstruction's), gone once it is left.
  const page = await env.newPage({ path: '#tool=micro' });
  await page.waitForFunction(() => window.filigree.testHooks.micro?.state());
  const names = () => page.evaluate(() => Object.keys(window.filigree.testHooks).sort());
  assert.deepEqual(await names(), ['micro', 'micro-fit']);
  await page.click('#tools button[data-tool=inspect]');
  await page.waitForFunction(() => document.documentElement.dataset.view === 'inspect');
  assert.deepEqual(await names(), [], 'Inspect exposes nothing and Micro\'s hooks left with it');
  await page.click('#tools button[data-tool=fit]');
  await page.waitForFunction(() => window.filigree.testHooks.fit);
  assert.deepEqual(await names(), ['fit']);
});

test('what the tests compute from a panel is test-only code: not precached, not in a shipped file', async () => {
  // What ships: the service worker's precache list (scripts/precache.mjs).
  const manifest = fs.readFileSync(path.join(ROOT, 'pkg/precache-manifest.js'), 'utf8');
  const urls = [...manifest.matchAll(/"url": "\.\/([^"]+)"/g)].map((m) => m[1]);
  assert.ok(urls.includes('www/app/main.bundle.js') && urls.includes('www/app/worker.js'), 'the list names what ships');
  assert.deepEqual(HOOK_SCRIPTS.map((f) => path.basename(f)), ['fit.js', 'micro.js', 'pixel.js', 'tangle.js', 'texture.js'],
    'the test layer has a hook file a tool');
  assert.deepEqual(urls.filter((u) => u.startsWith('tests/')), [], 'nothing of tests/ ships');
  // The page bundle ships the modules it holds (scripts/bundle.mjs: their
  // text concatenated), and the code editor's is CodeMirror: the sources are
  // what is read.
  const inBundle = [...await bundledOnly()];
  assert.ok(inBundle.includes('www/app/document.js') && inBundle.includes('www/micro/panel.js'), 'the bundle holds the panels');
  assert.deepEqual(urls.filter((u) => inBundle.includes(u)), [], 'no module inside the page bundle is precached on its own');
  const scripts = [...urls.filter((u) => !u.endsWith('.bundle.js')), ...inBundle]
    .filter((u) => /\.m?js$/.test(u) && fs.existsSync(path.join(ROOT, u)))
    .map((u) => [u, fs.readFileSync(path.join(ROOT, u), 'utf8')]);
  // Only the controller names the test layer's builders; no shipped script makes one.
  const naming = scripts.filter(([, text]) => text.includes('__filigreeHookBuilders')).map(([u]) => u);
  assert.deepEqual(naming, ['www/app/document.js']);
  // A panel hands over raw parts, never hooks it built: the argument of each
  // `ctx.expose` is an object of names (`live`, `plot: run.plot`) or getters
  // of one (`job: () => job`), no call and no code that computes.
  const exposing = [];
  for (const [u, text] of scripts) {
    for (const m of text.matchAll(/ctx\.expose\(/g)) {
      if (/\/\/|^\s*\*/.test(text.slice(text.lastIndexOf('\n', m.index) + 1, m.index))) continue; // a comment
      const rest = text.slice(m.index + m[0].length);
      const arg = /^\{([^{}()]*(?:\(\)[^{}()]*)*)\}\s*(?:,\s*'[\w-]+'\s*)?\)/.exec(rest);
      const entries = arg?.[1].split(',').map((e) => e.trim()).filter(Boolean) ?? [];
      const raw = arg && entries.every((e) => /^\w+(\s*:\s*(\(\)\s*=>\s*)?[\w.]+)?$/.test(e));
      assert.ok(raw, `${u}: ctx.expose(${rest.slice(0, 80)}…) hands over hooks it built, not raw parts`);
      exposing.push(u);
    }
  }
  for (const tool of ['fit', 'micro', 'pixel', 'tangle', 'texture']) {
    assert.ok(exposing.includes(`www/${tool}/panel.js`), `${tool}'s panel hands its parts to ctx.expose`);
  }
  // A test page's hooks are the test layer's, built from the panel's raw parts
  // (a panel without a builder publishes nothing: app/document.js).
  const page = await env.newPage({ path: '#tool=pixel' });
  await page.waitForFunction(() => window.filigree.testHooks.pixel?.state());
  assert.deepEqual(await page.evaluate(() => Object.keys(window.__filigreeHookBuilders).sort()),
    ['fit', 'micro', 'micro-fit', 'pixel', 'tangle', 'texture']);
  assert.deepEqual(await page.evaluate(() => Object.keys(window.filigree.testHooks.pixel).sort()), ['pending', 'result', 'state']);
  for (const [tool, keys] of [['fit', ['info', 'job', 'plot', 'running', 'state']], ['tangle', ['pending', 'result', 'selectedMask', 'state', 'timing']]]) {
    await page.click(`#tools button[data-tool=${tool}]`);
    await page.waitForFunction((t) => window.filigree.testHooks[t]?.state(), tool, { timeout: 30000 });
    const got = await page.evaluate((t) => Object.keys(window.filigree.testHooks[t]), tool);
    for (const k of keys) assert.ok(got.includes(k), `${tool}'s hooks (tests/e2e/hooks/${tool}.js) have ${k}: ${got}`);
  }
});

test('the app in an about:blank host loads and works', async () => {
  // An opaque about:blank page framing the app (Chromium's local-network
  // checks would refuse a localhost frame in it; a deployed app is not local).
  const blankEnv = await launch({ args: ['--disable-features=LocalNetworkAccessChecks'] });
  try {
    const page = await blankEnv.newPage({ path: null });
    await page.goto('about:blank');
    await page.setContent(`<iframe src="${blankEnv.url}#tool=fit" style="width:1260px;height:780px;border:0"></iframe>`);
    const frame = await (await page.waitForSelector('iframe')).contentFrame();
    await frame.waitForSelector('[data-testid=fit-sliders] .row', { timeout: 20000 });
    await frame.click('button[data-act=make-target]');
    await frame.waitForFunction(() => window.filigree.testHooks.fit.state().truth !== null);
    // Whether this host lets the frame store or not, the page says the truth.
    const canStore = await frame.evaluate(async () => {
      try {
        await new Promise((resolve, reject) => {
          const r = indexedDB.open('probe');
          r.onsuccess = resolve; r.onerror = reject;
          setTimeout(() => reject(new Error('timeout')), 1500);
        });
        return true;
      } catch { return false; }
    });
    await frame.waitForTimeout(2000);
    assert.equal(await frame.isHidden('[data-testid=doc-note]'), canStore, `storage ${canStore ? 'works' : 'is blocked'} here`);
  } finally {
    await blankEnv.close();
  }
});
