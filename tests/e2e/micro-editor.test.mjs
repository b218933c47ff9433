// Micro's scene editor and smaller things (issue 35 items 7 and 10): the
// scene JSON is pretty-printed in an editor as wide as the view; a JSON
// error is printed under its line and the picture keeps its last good frame;
// Roughness and Specular show only for GGX; the Reconstruct plot's axis
// reads the numbers the status gives.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

/** The picture's pixels: a grey level per pixel. */
const picture = (page) => page.$eval('[data-testid=micro-canvas]', (c) => {
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  const g = new Array(d.length / 4);
  for (let i = 0; i < g.length; i++) g[i] = d[4 * i] + d[4 * i + 1] + d[4 * i + 2];
  return g;
});
const spread = (g) => { const m = g.reduce((a, b) => a + b, 0) / g.length; return Math.sqrt(g.reduce((a, b) => a + (b - m) ** 2, 0) / g.length); };

test('micro: the scene JSON is pretty-printed and full width; an error shows under its line and the picture stays', async () => {
  const wide = await env.newPage({ path: '#tool=micro' });
  // The editor is there before the document is; wait for its scene.
  await wide.waitForFunction(() => [...document.querySelectorAll('.micro-editor .cm-line')].some((l) => l.textContent.trim()));
  // One field a line, not one long line.
  const lines = await wide.$$eval('.micro-editor .cm-line', (ls) => ls.map((l) => l.textContent));
  assert.ok(lines.length >= 5, `the gyroid's JSON on ${lines.length} lines: ${lines.join(' | ')}`);
  assert.ok(lines.some((l) => /^\s+"surface": "gyroid",$/.test(l)), 'a key a line, indented');
  // As wide as the view (it was a 292 px side column at 1280).
  const widths = await wide.evaluate(() => ({ editor: document.querySelector('.micro-editor .cm-editor').getBoundingClientRect().width, view: document.querySelector('.micro-layout').getBoundingClientRect().width }));
  assert.ok(widths.editor > 0.9 * widths.view, `the editor is ${Math.round(widths.editor)} px of ${Math.round(widths.view)}`);
  await wide.context().close();

  // A small window: the (software) GPU draws a small picture sooner.
  const page = await env.newPage({ path: '#tool=micro', viewport: { width: 600, height: 400 } });
  await page.waitForFunction(() => Number(document.querySelector('[data-testid=micro-status]')?.dataset.runs) > 0
    && !window.filigree.testHooks.micro.pending() && document.querySelector('.micro-editor .cm-content'), null, { timeout: 60000 });

  const before = await picture(page);
  assert.ok(spread(before) > 20, 'a picture is shown');
  // A JSON error: the message is printed right under line 3, and the picture is not blanked.
  const bad = '{"type": "tpms",\n "surface": "gyroid",\n "period": 0.5,,\n "thickness": 0.35}';
  await page.fill('[data-testid=micro-scene]', bad);
  await page.waitForSelector('[data-testid=doc-error]:not([hidden])', { timeout: 30000 });
  await page.waitForSelector('.micro-editor .cm-inline-error');
  const under = await page.evaluate(() => {
    const msg = document.querySelector('.micro-editor .cm-inline-error');
    const lines = [...document.querySelectorAll('.micro-editor .cm-line')];
    const third = lines[2].getBoundingClientRect();
    const m = msg.getBoundingClientRect();
    return { text: msg.textContent, gap: m.top - third.bottom, visible: m.height > 0 && m.width > 100 };
  });
  assert.match(under.text, /line 3, column \d+/);
  assert.ok(under.visible && Math.abs(under.gap) < 4, `the message sits under line 3 (gap ${under.gap} px)`);
  await page.waitForFunction(() => !window.filigree.testHooks.micro.pending(), null, { timeout: 30000 });
  await page.waitForTimeout(300);
  const after = await picture(page);
  const changed = after.filter((v, i) => Math.abs(v - before[i]) > 30).length / after.length;
  assert.ok(changed < 0.05, `the last good frame stays (${(changed * 100).toFixed(1)}% of pixels changed)`);
  // The window changes size (a phone turned) while the scene is wrong: the picture is redrawn
  // at the new size from the last good frame, not blanked.
  await page.setViewportSize({ width: 600, height: 360 });
  await page.waitForTimeout(500);
  const resized = await picture(page);
  assert.ok(resized.length < before.length, 'the picture was resized');
  const mean = (g) => g.reduce((a, b) => a + b, 0) / g.length;
  assert.ok(spread(resized) > 20 && Math.abs(mean(resized) - mean(before)) < 0.2 * mean(before),
    `the picture is not blanked (mean ${Math.round(mean(resized))} vs ${Math.round(mean(before))}, spread ${Math.round(spread(resized))})`);
  // Fixed: the message goes.
  await page.fill('[data-testid=micro-scene]', '{"type": "tpms", "surface": "gyroid", "period": 0.5, "thickness": 0.3}');
  await page.waitForSelector('.micro-editor .cm-inline-error', { state: 'detached', timeout: 30000 });

  // Roughness and Specular are GGX's: hidden under Lambert (CSS display must not beat `hidden`).
  assert.equal(await page.$eval('[data-testid=micro-shading]', (s) => s.value), 'lambert');
  assert.equal(await page.isVisible('[data-testid=micro-roughness]'), false, 'Roughness hidden under Lambert');
  assert.equal(await page.isVisible('[data-testid=micro-specular]'), false, 'Specular hidden under Lambert');
  await page.selectOption('[data-testid=micro-shading]', 'ggx');
  await page.waitForSelector('[data-testid=micro-roughness]', { state: 'visible' });
  assert.equal(await page.isVisible('[data-testid=micro-specular]'), true);
  await page.selectOption('[data-testid=micro-shading]', 'lambert');
  await page.waitForSelector('[data-testid=micro-roughness]', { state: 'hidden' });
});

test('micro reconstruct: the loss plot\'s axis reads the numbers of the status', async () => {
  const page = await env.newPage({ path: '#tool=micro' });
  await page.waitForSelector('[data-testid=micro-examples] [data-example=gyroid]', { timeout: 30000 });
  await page.click('[data-testid=micro-fit] > summary');
  const row = '[data-testid=micro-fit-params] [data-pointer="/thickness"]';
  await page.waitForSelector(row);
  await page.check(`${row} [name=fit-on]`);
  await page.fill(`${row} [name=fit-truth]`, '0.2');
  await page.selectOption('[data-testid=micro-fit-optimizer]', 'powell');
  await page.fill('[data-testid=micro-fit-budget]', '24');
  await page.click('[data-testid=micro-fit-run]');
  await page.waitForFunction(() => Number(document.querySelector('[data-testid=micro-fit-status]').dataset.fits || 0) >= 1, null, { timeout: 120000 });
  const text = await page.textContent('[data-testid=micro-fit-status]');
  const [, first, last] = /loss (-?[\d.]+) → (-?[\d.]+)/.exec(text);
  const axis = await page.$eval('[data-testid=micro-fit-plot]', (c) => ({ top: c.dataset.top, bottom: c.dataset.bottom }));
  assert.deepEqual(axis, { top: first, bottom: last }, `the status says ${first} → ${last}`);
});
