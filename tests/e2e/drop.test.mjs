// Files in (issue 35 item 10): a file dropped anywhere in the window goes
// to the tool that takes one (not only onto the marked zone); your own
// Pixel source starts clean (no example strokes, "Fish example" no longer
// pressed); Texture says plainly when a dropped file is empty or damaged,
// and stops saying it is reading it. Tangle and Micro take what they open
// (an SVG start or a grammar; a scene JSON) dropped anywhere, and a project
// file opens from any tool, wherever it lands; a bad file is refused in
// plain words and the document stays.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { launch, dropFile, fixture, rgbPng } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

test('drop anywhere: Pixel, Fit, Inspect and Texture take a file dropped outside their zone', async () => {
  const page = await env.newPage({ path: '#tool=inspect' });
  // Inspect: onto the page's header.
  await dropFile(page, '.app-header', fixture('fish.png'));
  await page.waitForSelector('[data-testid=palette] li', { timeout: 15000 });
  assert.equal(await page.textContent('[data-field=name]'), 'fish.png');

  // Fit: onto the run card, far from the target.
  await page.click('#tools button[data-tool=fit]');
  await page.waitForSelector('[data-testid=fit-sliders] input');
  await dropFile(page, '.fit-run', fixture('fish.png'));
  await page.waitForFunction(() => /fish\.png: snapped/.test(document.querySelector('[data-testid=fit-status]').textContent), null, { timeout: 15000 });

  // Texture: onto the scales.
  await page.click('#tools button[data-tool=texture]');
  await page.waitForFunction(() => !!document.querySelector('[data-testid=texture-retrieved][data-model]') && !window.filigree.testHooks.texture.pending(), null, { timeout: 60000 });
  await dropFile(page, '.texture-controls', fixture('trunk.png'));
  await page.waitForFunction(() => window.filigree.testHooks.texture.state().source?.name === 'trunk.png', null, { timeout: 30000 });
});

test('pixel: your own source (dropped on the header) drops the example\'s strokes and un-presses "Fish example"', async () => {
  const page = await env.newPage({ path: '#tool=pixel' });
  await page.waitForFunction(() => window.filigree?.testHooks?.pixel?.state()?.example === 'fish');
  assert.equal(await page.getAttribute('button[data-example=fish]', 'aria-pressed'), 'true');
  assert.ok(await page.evaluate(() => window.filigree.testHooks.pixel.state().strokes.length) > 0, 'the example has strokes');
  const own = await rgbPng(40, 24, (x, y) => (x > 8 && x < 32 && y > 6 && y < 18 ? [200, 60, 40] : [30, 90, 160]));
  await dropFile(page, '.app-header', { name: 'mine.png', bytes: own, type: 'image/png' });
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state().example === null, null, { timeout: 15000 });
  const s = await page.evaluate(() => { const d = window.filigree.testHooks.pixel.state(); return { strokes: d.strokes.length, w: d.mask.width, on: d.mask.bits.reduce((a, b) => a + b, 0), name: d.names.source }; });
  assert.deepEqual(s, { strokes: 0, w: 40, on: 40 * 24, name: 'mine.png' }, 'a clean start: no strokes, a full mask');
  assert.equal(await page.getAttribute('button[data-example=fish]', 'aria-pressed'), 'false', '"Fish example" no longer pressed');
  // Back to the example: pressed again (one undo).
  await page.click('button[data-act=undo]');
  await page.waitForFunction(() => window.filigree.testHooks.pixel.state().example === 'fish');
  assert.equal(await page.getAttribute('button[data-example=fish]', 'aria-pressed'), 'true');
});

test('texture: an empty or a damaged file gets a plain error and the panel stops "reading the example…"', async () => {
  const page = await env.newPage({ path: '#tool=texture' });
  await page.waitForFunction(() => !!document.querySelector('[data-testid=texture-retrieved][data-model]') && !window.filigree.testHooks.texture.pending(), null, { timeout: 60000 });
  const before = await page.evaluate(() => window.filigree.testHooks.texture.state().source);
  for (const [file, why] of [
    [{ name: 'empty.png', bytes: Buffer.alloc(0), type: 'image/png' }, /empty\.png is empty \(0 bytes\)/],
    [{ name: 'broken.png', bytes: Buffer.from('\x89PNG\r\n\x1a\n this is not the rest of a PNG', 'binary'), type: 'image/png' }, /broken\.png is not an image .*damaged/],
  ]) {
    await dropFile(page, '[data-testid=texture-drop]', file);
    await page.waitForSelector('[data-testid=doc-error]:not([hidden])', { timeout: 15000 });
    assert.match(await page.textContent('[data-testid=doc-error]'), why);
    const status = await page.textContent('[data-testid=texture-status]');
    assert.doesNotMatch(status, /reading the example/, `status: ${status}`);
    assert.match(status, /not read/);
    assert.deepEqual(await page.evaluate(() => window.filigree.testHooks.texture.state().source), before, 'the example is kept');
  }
});

// ---- Tangle and Micro: a file dropped anywhere (document.js: view.drop) -----------------------

const ERROR = '[data-testid=doc-error]';
const text = (name, body, type = 'text/plain') => ({ name, bytes: Buffer.from(body), type });

/** Drop `file` on `selector`; resolves with the error shown (the last one cleared first). */
async function dropRefused(page, selector, file) {
  await page.evaluate(() => { const e = document.querySelector('[data-testid=doc-error]'); e.hidden = true; e.textContent = ''; });
  await dropFile(page, selector, file);
  await page.waitForSelector(`${ERROR}:not([hidden])`, { timeout: 15000 });
  return page.textContent(ERROR);
}

test('drop anywhere: Tangle takes an SVG start and a grammar dropped anywhere (the editor too); a bad file is refused and the document kept', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  await page.waitForFunction(() => window.filigree.testHooks.tangle?.state(), null, { timeout: 30000 });
  const tangle = () => page.evaluate(() => window.filigree.testHooks.tangle.state());

  // An SVG dropped on the page's header: the start shape.
  await dropFile(page, '.app-header', { name: 'badge.svg', bytes: fs.readFileSync(fixture('badge.svg')), type: 'image/svg+xml' });
  await page.waitForFunction(() => window.filigree.testHooks.tangle.state().start?.kind === 'svg', null, { timeout: 30000 });
  assert.equal(await page.$eval('[name=start-kind]', (s) => s.value), 'svg');
  assert.equal(await page.isHidden(ERROR), true);

  // A grammar dropped on the grammar editor replaces the grammar (not pasted into it as text).
  const grammar = 'start rect(400, 300) : field\nregularSplit(line, 50, 0) : field -> [strip]\n';
  await dropFile(page, '[data-testid=tangle-grammar]', text('strips.tangle', grammar));
  await page.waitForFunction((g) => window.filigree.testHooks.tangle.state().grammar === g, grammar, { timeout: 30000 });
  const doc = await tangle(page);
  assert.equal(doc.example, null);
  assert.equal(doc.start?.kind, 'svg', 'the start shape stays');

  // Refused: a grammar with an error (its line named), an image, an empty SVG. Nothing changes.
  assert.match(await dropRefused(page, '[data-testid=tangle-canvas]', text('broken.tangle', 'start rect(400, 300) : field\nnoSuchRule(3) : field -> [x]\n')),
    /^broken\.tangle was not opened — .*line 2.*Your work is unchanged\.$/);
  assert.match(await dropRefused(page, '.tangle-side', { name: 'photo.png', bytes: fs.readFileSync(fixture('fish.png')), type: 'image/png' }),
    /^photo\.png was not opened — Tangle opens SVG files \(a start shape\), grammars \(\.tangle\) and Filigree projects\. Your work is unchanged\.$/);
  assert.match(await dropRefused(page, '.app-header', text('empty.svg', '<svg xmlns="http://www.w3.org/2000/svg"/>', 'image/svg+xml')),
    /^empty\.svg was not opened — .+\. Your work is unchanged\.$/);
  assert.deepEqual(await tangle(page), doc, 'the document is as it was');
  assert.equal(await page.evaluate(() => document.querySelector('.tool').classList.contains('drop-over')), false, 'no drop outline left');
  assert.deepEqual(errors, []);  await page.context().close(); // its growth would take the CPU from the next test
});

test('drop anywhere: Micro takes a scene JSON dropped anywhere; bad JSON and a scene the core refuses leave the document', async () => {
  // A quarter of the device pixels: its GPU pictures (SwiftShader) take little of the page's time.
  const page = await env.newPage({ path: '#tool=micro', deviceScaleFactor: 0.25 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  await page.waitForFunction(() => window.filigree.testHooks.micro?.state(), null, { timeout: 30000 });
  const micro = () => page.evaluate(() => window.filigree.testHooks.micro.state());
  const before = await micro();
  const scene = JSON.parse(before.scene);
  scene.thickness = 0.3;
  await dropFile(page, '.micro-side', text('thin.json', JSON.stringify(scene), 'application/json'));
  await page.waitForFunction((s) => window.filigree.testHooks.micro.state().scene === s, JSON.stringify(scene, null, 2), { timeout: 30000 });
  const doc = await micro();
  assert.equal(doc.example, null);
  assert.deepEqual(doc.camera, before.camera, 'only the scene changed');

  assert.match(await dropRefused(page, '[data-testid=micro-canvas]', text('notes.json', '{"type": ', 'application/json')),
    /^notes\.json was not opened — it is not JSON \(.+\)\. Your work is unchanged\.$/);
  assert.match(await dropRefused(page, '[data-testid=micro-scene]', text('blob.json', '{"type": "blob"}', 'application/json')),
    /^blob\.json was not opened — .*blob.*Your work is unchanged\.$/);
  assert.match(await dropRefused(page, '.app-header', { name: 'photo.png', bytes: fs.readFileSync(fixture('fish.png')), type: 'image/png' }),
    /^photo\.png was not opened — Micro opens scene JSON files .* and Filigree projects\. Your work is unchanged\.$/);
  assert.deepEqual(await micro(), doc, 'the document is as it was');
  assert.deepEqual(errors, []);  await page.context().close();
});

test('drop anywhere: a project file opens from any tool, even dropped on an image zone; a damaged one is refused', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => window.filigree.testHooks.tangle?.state(), null, { timeout: 30000 });
  // Pixel's project, dropped on Tangle's drawing: Pixel opens with the fish.
  await dropFile(page, '[data-testid=tangle-canvas]', { name: 'fish.filigree.json', bytes: fs.readFileSync(fixture('fish.filigree.json')), type: 'application/json' });
  await page.waitForFunction(() => window.filigree.testHooks.pixel?.state()?.example === 'fish', null, { timeout: 30000 });
  assert.equal(await page.isVisible('section.tool-pixel'), true);
  // Tangle's own project (saved by the app), dropped on Pixel's source zone: Tangle opens it.
  const project = await page.evaluate(async () => {
    const { projectText } = await import('/www/app/project-file.js');
    const state = { example: null, grammar: 'start rect(300, 200) : field\nregularSplit(line, 40, 1) : field -> [strip]\n', seed: 7, start: null, wobble: 0, stroke_width: 1, edits: [], selected: null };
    return projectText('tangle', 1, state);
  });
  // Named plainly .json: the envelope says it is a project.
  await dropFile(page, '.viewport', text('mine.json', project, 'application/json'));
  await page.waitForFunction(() => window.filigree.testHooks.tangle?.state()?.seed === 7, null, { timeout: 30000 });
  assert.match((await page.evaluate(() => window.filigree.testHooks.tangle.state())).grammar, /regularSplit\(line, 40, 1\)/);
  await page.evaluate(() => document.querySelectorAll('.dragging').length).then((k) => assert.equal(k, 0, 'no zone left lit'));
  // A damaged project: refused in plain words; Tangle's document stays.
  const doc = await page.evaluate(() => window.filigree.testHooks.tangle.state());
  assert.match(await dropRefused(page, '.tangle-side', text('broken.filigree.json', project.slice(0, 60), 'application/json')),
    /^broken\.filigree\.json was not opened — .+\. Your work is unchanged\.$/);
  assert.deepEqual(await page.evaluate(() => window.filigree.testHooks.tangle.state()), doc);  await page.context().close();
});
