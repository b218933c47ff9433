// Tangle by keyboard and smaller things (issue 35 items 8 and 10): a step
// list chosen with the keyboard and in sync with the drawing's selection;
// a typed start word applies as you type; no Canvas2D read-back warning
// while the drawing is zoomed and its layers are drawn ahead.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const selected = (page) => page.evaluate(() => window.filigree.testHooks.tangle.state().selected);
const listSelection = (page) => page.$eval('[data-testid=tangle-step-list]', (l) => ({
  selected: [...l.querySelectorAll('[aria-selected=true]')].map((o) => Number(o.dataset.step)),
  active: l.getAttribute('aria-activedescendant'),
}));

test('tangle: the step list is chosen by keyboard and follows a click on the drawing; no read-back warning', async () => {
  const page = await env.newPage({ path: null, viewport: { width: 1000, height: 640 } });
  const warnings = [];
  page.on('console', (m) => { if (/willReadFrequently|readback/i.test(m.text())) warnings.push(m.text()); });
  await page.goto(`${env.url}#tool=tangle`);
  await page.waitForFunction(() => Number(document.querySelector('[data-testid=tangle-status]')?.dataset.runs) > 0
    && document.querySelector('[data-testid=tangle-step-list] [role=option]'), null, { timeout: 60000, polling: 100 });
  const steps = Number(await page.getAttribute('[data-testid=tangle-step]', 'max'));
  const options = await page.$$eval('[data-testid=tangle-step-list] [role=option]', (os) => os.map((o) => o.textContent));
  assert.equal(options.length, steps, 'one row per step');
  assert.match(options[0], /^1\. \w+/);

  // Keyboard: Tab reaches the list; Home, arrows and End choose steps; the drawing highlights each.
  await page.focus('[data-testid=tangle-step-list]');
  await page.keyboard.press('Home');
  await page.waitForFunction(() => window.filigree.testHooks.tangle.state().selected === 0);
  assert.deepEqual(await listSelection(page), { selected: [0], active: 'tangle-step-0' });
  assert.match(await page.textContent('[data-testid=tangle-selected]'), /^Step 1 of/);
  assert.ok(await page.evaluate(() => window.filigree.testHooks.tangle.selectedBox()), 'the drawing highlights step 1');
  await page.keyboard.press('ArrowDown');
  await page.keyboard.press('ArrowDown');
  await page.waitForFunction(() => window.filigree.testHooks.tangle.state().selected === 2);
  assert.deepEqual((await listSelection(page)).selected, [2]);
  await page.keyboard.press('End');
  await page.waitForFunction((n) => window.filigree.testHooks.tangle.state().selected === n - 1, steps);
  assert.equal(await page.evaluate(() => document.activeElement.dataset.testid), 'tangle-step-list', 'the focus stays in the list');
  // The last row is scrolled into the list's view.
  assert.ok(await page.$eval('[data-testid=tangle-step-list]', (l) => {
    const o = l.querySelector('[aria-selected=true]').getBoundingClientRect();
    const r = l.getBoundingClientRect();
    return o.top >= r.top - 1 && o.bottom <= r.bottom + 1;
  }), 'the chosen row is in view');
  await page.keyboard.press('Escape');
  await page.waitForFunction(() => window.filigree.testHooks.tangle.state().selected === null);
  assert.deepEqual((await listSelection(page)).selected, []);

  // A click on a shape of the drawing selects its step in the list too.
  const box = await page.locator('[data-testid=tangle-canvas]').boundingBox();
  await page.mouse.click(box.x + box.width * 0.5, box.y + box.height * 0.5);
  await page.waitForFunction(() => window.filigree.testHooks.tangle.state().selected !== null);
  const sel = await selected(page);
  assert.deepEqual(await listSelection(page), { selected: [sel], active: `tangle-step-${sel}` });

  // Zoom in and out: the heavy parts' layers are drawn ahead each time, with no read-back warning.
  for (const zoom of ['zoom-in', 'zoom-out']) {
    await page.click(`[data-act=${zoom}]`);
    await page.waitForTimeout(300);
    // Drawn ahead (the idle work is done, or has had a few seconds).
    await page.waitForFunction(() => window.filigree.testHooks.tangle.prebuilt(), null, { timeout: 4000, polling: 100 }).catch(() => {});
  }
  assert.deepEqual(warnings, [], 'no Canvas2D read-back warning');
});

test('tangle: a typed start word applies as you type, without Enter or leaving the field', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => Number(document.querySelector('[data-testid=tangle-status]')?.dataset.runs) > 0, null, { timeout: 60000 });
  await page.selectOption('[name=start-kind]', 'text');
  await page.waitForFunction(() => window.filigree.testHooks.tangle.state().start?.kind === 'text', null, { polling: 100 });
  const word = page.locator('[name=start-text]');
  await word.click();
  await word.press('Control+A');
  await page.keyboard.type('Ink ', { delay: 40 });
  // No Enter, no blur: the pause after typing applies it.
  await page.waitForFunction(() => window.filigree.testHooks.tangle.state().start?.text === 'Ink', null, { timeout: 15000, polling: 100 });
  assert.equal(await page.evaluate(() => document.activeElement.name), 'start-text', 'the field keeps the focus');
  assert.equal(await word.inputValue(), 'Ink ', 'what is typed stays in the field (its trailing space too)');
  await page.keyboard.type('well', { delay: 40 });
  await page.waitForFunction(() => window.filigree.testHooks.tangle.state().start?.text === 'Ink well', null, { timeout: 15000, polling: 100 });
  // One undo step per pause, and undo brings the earlier word back.
  await page.click('button[data-act=undo]');
  await page.waitForFunction(() => window.filigree.testHooks.tangle.state().start?.text === 'Ink');
  assert.equal(await word.inputValue(), 'Ink');
});
