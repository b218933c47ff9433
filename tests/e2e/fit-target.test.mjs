// Fit's target and overlay (issue 35 items 3 and 10): Run fit never runs
// on an empty target (it waits, saying how to make one); the target and the
// pattern drawn over it look different; after Cancel the overlay shows the
// values that were kept, not the abandoned candidate.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const ready = (page) => page.waitForFunction(() => !!document.querySelector('[data-testid=fit-sliders] input'));
/** FNV hash of a canvas's pixels. */
const canvasHash = (page, sel) => page.$eval(sel, (c) => {
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  let h = 2166136261;
  for (let i = 0; i < d.length; i++) { h ^= d[i]; h = Math.imul(h, 16777619) >>> 0; }
  return h;
});
/** Pixels of a PNG screenshot that are the overlay's pink ([r, g, b] near 255, 43, 214). */
async function pinkIn(page, sel) {
  const png = await page.locator(sel).screenshot();
  return page.evaluate(async (b64) => {
    const bmp = await createImageBitmap(new Blob([Uint8Array.from(atob(b64), (c) => c.charCodeAt(0))], { type: 'image/png' }));
    const c = new OffscreenCanvas(bmp.width, bmp.height);
    const g = c.getContext('2d');
    g.drawImage(bmp, 0, 0);
    const d = g.getImageData(0, 0, bmp.width, bmp.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) if (d[i] > 200 && d[i + 1] < 140 && d[i + 2] > 150) n++;
    return n;
  }, png.toString('base64'));
}

test('fit: Run fit waits for a target and says why; drawing one enables it; target and overlay look different', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await ready(page);
  // The default target is blank: the button is disabled and a visible reason says what to do.
  await page.waitForSelector('[data-testid=fit-why]:not([hidden])');
  assert.equal(await page.isDisabled('button[data-act=fit]'), true, 'Run fit disabled on a blank target');
  assert.match(await page.textContent('[data-testid=fit-why]'), /target is empty.*draw.*upload.*Make target from these values/s);
  assert.equal(await page.getAttribute('button[data-act=fit]', 'aria-describedby'), 'fit-why');
  assert.equal(await page.textContent('[data-testid=fit-status]'), '', 'nothing ran');

  // Draw a stroke on the target: the button is enabled and the reason goes.
  const box = await page.locator('[data-testid=fit-target]').boundingBox();
  await page.mouse.move(box.x + box.width * 0.3, box.y + box.height * 0.3);
  await page.mouse.down();
  for (let i = 1; i <= 8; i++) await page.mouse.move(box.x + box.width * (0.3 + i * 0.04), box.y + box.height * 0.35);
  await page.mouse.up();
  await page.waitForFunction(() => !document.querySelector('button[data-act=fit]').disabled);
  assert.equal(await page.isHidden('[data-testid=fit-why]'), true);
  // Clear: blank again, disabled again.
  await page.click('button[data-act=clear-target]');
  await page.waitForFunction(() => document.querySelector('button[data-act=fit]').disabled);
  assert.equal(await page.isVisible('[data-testid=fit-why]'), true);

  // A target made from the values: the very same shapes as the overlay, yet they look different.
  await page.click('button[data-act=make-target]');
  await page.waitForFunction(() => !document.querySelector('button[data-act=fit]').disabled);
  const targetPink = await page.$eval('[data-testid=fit-target]', (c) => {
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let n = 0;
    for (let i = 0; i < d.length; i += 4) if (d[i] > 200 && d[i + 1] < 140 && d[i + 2] > 150) n++;
    return n;
  });
  assert.equal(targetPink, 0, 'the target alone has no pink');
  assert.ok(await pinkIn(page, '.fit-target .stack') > 200, 'the pattern over it is outlined in pink');
  assert.match(await page.textContent('.fit-legend'), /Solid: the target.*Pink outlines/);
});

test('fit: after Cancel the overlay shows the kept values, not the abandoned candidate', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await ready(page);
  await page.click('button[data-act=make-target]');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state().truth);
  // Move r to its end: the values differ from the target's, so the fit's candidates differ from them.
  await page.focus('[data-testid=fit-sliders] input[aria-label=r]');
  await page.keyboard.press('End');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state().values.at(-1) > 0.059);
  const kept = await page.evaluate(() => window.filigree.testHooks.fit.state().values);
  // The overlay of the kept values (once the preview has settled).
  let h0 = -1;
  for (let i = 0; i < 40; i++) {
    await page.waitForTimeout(150);
    const h = await canvasHash(page, '[data-testid=fit-overlay]');
    if (h === h0) break;
    h0 = h;
  }
  await page.selectOption('select[name=budget]', 'paper');
  // Every job the page posts from here on, by kind.
  await page.evaluate(() => {
    const pool = window.filigree.pool;
    const run = pool.run.bind(pool);
    window.jobKinds = [];
    pool.run = (kind, ...rest) => { window.jobKinds.push(kind); return run(kind, ...rest); };
  });
  await page.click('button[data-act=fit]');
  // A candidate is drawn over the target while the fit runs (the first
  // ones come after the global stage, late in the fit), and Stop is
  // clicked in the same poll that sees it: a round trip from the test
  // lost the race to the fit's end on a loaded machine.
  const when = await page.waitForFunction((h) => {
    const c = document.querySelector('[data-testid=fit-overlay]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let x = 2166136261;
    for (let i = 0; i < d.length; i++) { x ^= d[i]; x = Math.imul(x, 16777619) >>> 0; }
    if (x === h) return false;
    const stop = document.querySelector('button[data-act=cancel]');
    if (stop.disabled) return 'ended';
    stop.click();
    return 'stopped';
  }, h0, { timeout: 90000, polling: 50 });
  assert.equal(await when.jsonValue(), 'stopped', 'the fit was still running when its candidate was drawn');
  await page.waitForFunction(() => /^stopped/.test(document.querySelector('[data-testid=fit-status]').textContent));
  assert.deepEqual(await page.evaluate(() => window.filigree.testHooks.fit.state().values), kept, 'the values are kept');
  // ...and after Cancel the overlay is the kept values' pattern again.
  await page.waitForFunction((h) => {
    const c = document.querySelector('[data-testid=fit-overlay]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let x = 2166136261;
    for (let i = 0; i < d.length; i++) { x ^= d[i]; x = Math.imul(x, 16777619) >>> 0; }
    return x === h;
  }, h0, { timeout: 5000, polling: 100 }).catch(() => assert.fail('the overlay still shows the abandoned candidate'));
  // The candidates were the fit's own pictures, and the kept values' one
  // was kept: no `render-pattern` during the fit or after its Stop.
  await page.waitForTimeout(500);
  assert.deepEqual(await page.evaluate(() => window.jobKinds.filter((k) => k !== 'fit')), [], 'only the fit ran');
});

test('fit: the program editor is as wide as the view; a broken program\'s error is printed under its line', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await ready(page);
  await page.click('button[data-act=show-program]');
  await page.waitForSelector('.fit-editor .code-editor .cm-content');
  const w = await page.evaluate(() => ({ editor: document.querySelector('.fit-editor .cm-editor').getBoundingClientRect().width, view: document.querySelector('.fit-layout').getBoundingClientRect().width }));
  assert.ok(w.editor > 0.9 * w.view, `the editor is ${Math.round(w.editor)} px of ${Math.round(w.view)} (it was a 260 px column)`);
  await page.fill('[data-testid=fit-program]', 'param a in [0, 1] = 0.5;\n// two\ncircle(0.5, 0.5, a +, fill: "#000000");\n// four\n');
  await page.click('button[data-act=apply-program]');
  await page.waitForSelector('.fit-editor .cm-inline-error');
  const at = await page.evaluate(() => {
    const msg = document.querySelector('.fit-editor .cm-inline-error');
    const third = [...document.querySelectorAll('.fit-editor .cm-line')][2].getBoundingClientRect();
    const r = msg.getBoundingClientRect();
    return { text: msg.textContent, gap: r.top - third.bottom, inView: r.top >= 0 && r.bottom <= innerHeight };
  });
  assert.match(at.text, /line 3, column \d+/);
  assert.ok(Math.abs(at.gap) < 4, `under line 3 (gap ${at.gap} px)`);
  assert.ok(at.inView, 'scrolled into view');
  // Fixed and applied: the message goes.
  await page.fill('[data-testid=fit-program]', 'param a in [0.1, 0.4] = 0.2;\ncircle(0.5, 0.5, a, fill: "#000000");\n');
  await page.click('button[data-act=apply-program]');
  await page.waitForSelector('.fit-editor .cm-inline-error', { state: 'detached' });
});

// The program's text in the editor, as the user sees it (CodeMirror draws
// one element per line).
const programText = (page) => page.evaluate(() => [...document.querySelectorAll('.fit-editor .cm-line')]
  .map((l) => l.textContent).join('\n'));

test('fit: program text typed while the core loads, or typed and not yet applied, is never replaced behind the user\'s back', async () => {
  // Seen on a loaded machine: a program pasted into the editor before the
  // first document's facts arrived was replaced by the document's program
  // when they did, and Apply then applied the old one.
  const page = await env.newPage({ path: null });
  let release;
  const gate = new Promise((resolve) => { release = resolve; });
  await page.route('**/filigree_fit_bg.wasm', async (route) => { await gate; await route.continue(); });
  await page.goto(`${env.url}#tool=fit`);
  await page.click('button[data-act=show-program]');
  await page.waitForSelector('.fit-editor .code-editor .cm-content');
  const early = 'int param n in [1, 4] = 2;\nparam a in [0.05, 0.1] = 0.08;\nfor i in 0..n { circle(0.2 + i * 0.25, 0.5, a, fill: "#000000"); }\n';
  await page.fill('[data-testid=fit-program]', early);
  release();
  await ready(page); // the first document's facts have arrived: its sliders are drawn
  assert.equal(await programText(page), early, 'the text typed while the core loaded is still there');
  await page.click('button[data-act=apply-program]');
  await page.waitForFunction(() => /2 shapes/.test(document.querySelector('[data-testid=fit-facts]').textContent));
  // Typed, not applied; then an int parameter moves, which re-reads the
  // program's facts (it shapes what the program draws).
  const draft = `${early}// not applied yet\n`;
  await page.fill('[data-testid=fit-program]', draft);
  await page.$eval('[data-testid=fit-sliders] .row[data-param=n] input', (el) => {
    el.value = '3';
    el.dispatchEvent(new Event('change'));
  });
  await page.waitForFunction(() => /3 shapes/.test(document.querySelector('[data-testid=fit-facts]').textContent));
  assert.equal(await programText(page), draft, 'the edit not yet applied is still there');
});
