// Files in (issue 35 item 10): a file dropped anywhere in the window goes
// to the tool that takes one (not only onto the marked zone); your own
// Pixel source starts clean (no example strokes, "Fish example" no longer
// pressed); Texture says plainly when a dropped file is empty or damaged,
// and stops saying it is reading it.
import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { launch, dropFile, fixture, rgbPng } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
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
