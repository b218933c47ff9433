// Micro's slow-GPU guard (issue 35 item 9): a picture whose GPU work takes
// too long (2 s; a software GPU takes 20–110 s) is said to be slow in plain
// words, with an offer of the CPU renderer. Taking it draws on the CPU (the
// tiled `micro-render` path), and the choice holds for the tab's session,
// a reload included, until "Use the GPU again". The threshold is lowered by
// a test hook, so no slow GPU is needed.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch, ready } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const NOTE = '[data-testid=micro-renderer]';
const runs = (page) => page.$eval('[data-testid=micro-status]', (el) => Number(el.dataset.runs || 0));
async function waitForRender(page, previous, timeout = 60000) {
  await page.waitForFunction((prev) => Number(document.querySelector('[data-testid=micro-status]').dataset.runs || 0) > prev
    && !window.filigree.testHooks.micro.pending(), previous, { timeout });
  return runs(page);
}
const last = (page) => page.evaluate(() => window.filigree.testHooks.micro.last());

/** The share of the canvas's pixels that are not the background (the structure drawn). */
const drawn = (page) => page.evaluate(() => {
  const c = document.querySelector('[data-testid=micro-canvas]');
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  let k = 0;
  for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - 24) + Math.abs(d[i + 1] - 26) + Math.abs(d[i + 2] - 30) > 6) k++;
  return k / (d.length / 4);
});

test('micro: a slow GPU is said plainly and the CPU offered; the choice draws on the CPU, survives a reload and is undone', async () => {
  // A quarter of the device pixels: SwiftShader takes seconds for a full-size GPU picture.
  const page = await env.newPage({ path: '#tool=micro', deviceScaleFactor: 0.25 });
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  page.on('console', (m) => { if (m.type() === 'error') errors.push(m.text()); });
  // The first GPU frame is there (its refinement may still run).
  await page.waitForFunction(() => window.filigree.testHooks.micro?.last()?.gpu, null, { timeout: 60000 });

  // Any GPU picture is "slow" past a 1 ms threshold: the next one says so and offers the CPU.
  await page.evaluate(() => window.filigree.testHooks.micro.slowGpuMs(1));
  await page.click('[data-act=zoom-in]');
  await page.waitForSelector(`${NOTE}:not([hidden])`, { timeout: 30000 });
  assert.match(await page.textContent(NOTE), /The GPU is slow here: this picture took \d+\.\d s of GPU work.*CPU renderer/);
  assert.equal(await page.isVisible(`${NOTE} [data-act=use-cpu]`), true, 'the offer: Draw on the CPU');

  // Take it: the picture is drawn again, in tiles on the CPU.
  await page.click(`${NOTE} [data-act=use-cpu]`);
  await page.waitForFunction(() => { const h = window.filigree.testHooks.micro; return h.last()?.gpu === false && !h.pending(); }, null, { timeout: 30000 });
  let n = await runs(page);
  const l = await last(page);
  assert.deepEqual({ gpu: l.gpu, preview: l.preview, tiles: l.tiles }, { gpu: false, preview: false, tiles: 16 });
  assert.match(await page.textContent('[data-testid=micro-status]'), /on the CPU in 16 tiles/);
  assert.ok(await drawn(page) > 0.2, 'the CPU drew the gyroid');
  assert.match(await page.textContent(NOTE), /Drawn on the CPU, as you chose/);
  assert.equal(await page.isVisible(`${NOTE} [data-act=use-gpu]`), true);

  // It sticks: an orbit is drawn on the CPU, and so is the picture after a reload.
  await page.focus('[data-testid=micro-canvas]');
  await page.keyboard.press('ArrowLeft');
  n = await waitForRender(page, n);
  assert.equal((await last(page)).gpu, false, 'an orbit stays on the CPU');
  await page.reload();
  await ready(page, '#tool=micro');
  await waitForRender(page, 0);
  assert.equal((await last(page)).gpu, false, 'after a reload, still the CPU');
  assert.match(await page.textContent(NOTE), /Drawn on the CPU, as you chose/);

  // And it is undone: back on the GPU, no offer after it.
  await page.click(`${NOTE} [data-act=use-gpu]`);
  await page.waitForFunction(() => window.filigree.testHooks.micro.last()?.gpu === true, null, { timeout: 30000 });
  assert.equal(await page.isHidden(NOTE), true);
  assert.deepEqual(errors, []);
  await page.context().close();
});
