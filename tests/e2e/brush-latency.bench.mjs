// Input-to-paint latency of a brush drag in the Pixel panel (issue 8 item 4),
// on a 1024² and a 4096² source, strokes and mask painting. Not a pass/fail
// test: prints the medians (and p90) in ms.
//
//   node tests/e2e/brush-latency.bench.mjs [root]      (root: an app checkout, default this one)
//
// Latency of one pointermove = from the event's timestamp to a task queued
// from the first animation frame after the panel handled it (that frame's
// paint has been produced by then). Chromium headless, 1280×800.
import { launch, bigPng } from './harness.mjs';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';

const root = process.argv[2];
const env = await launch(root ? { root } : {});
const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };
const p90 = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length * 0.9)]; };

try {
  for (const side of [1024, 4096]) {
    const file = path.join(os.tmpdir(), `latency-${side}.png`);
    fs.writeFileSync(file, await bigPng(side, side));
    const page = await env.newPage({ path: '#tool=pixel' });
    await page.waitForFunction(() => window.filigreePixel?.state()?.example === 'fish', null, { timeout: 30000 });
    await page.setInputFiles('input[data-input=source]', file);
    await page.waitForFunction((n) => window.filigreePixel.state()?.mask.width === n
      && document.querySelector('[data-testid=pixel-canvas]').getBoundingClientRect().width >= n, side, { timeout: 60000 });
    await page.waitForTimeout(500);
    for (const mode of ['stroke', 'paint']) {
      await page.click(`button[data-mode=${mode}]`);
      await page.evaluate(() => {
        window.latencies = [];
        const c = document.querySelector('[data-testid=pixel-canvas]');
        c.addEventListener('pointermove', (e) => {
          if (!e.buttons) return;
          const t0 = e.timeStamp;
          requestAnimationFrame(() => setTimeout(() => window.latencies.push(performance.now() - t0), 0));
        });
      });
      const box = await page.locator('.viewport').boundingBox();
      await page.mouse.move(box.x + 40, box.y + 40);
      await page.mouse.down();
      for (let i = 0; i < 4; i++) {
        await page.mouse.move(box.x + 40 + 400, box.y + 40 + 60 * i + 30, { steps: 40 });
        await page.mouse.move(box.x + 40, box.y + 40 + 60 * i + 60, { steps: 40 });
      }
      await page.mouse.up();
      await page.waitForTimeout(300);
      const lat = await page.evaluate(() => window.latencies);
      console.log(`${side}² ${mode.padEnd(6)}: median ${median(lat).toFixed(1)} ms, p90 ${p90(lat).toFixed(1)} ms over ${lat.length} moves`);
      await page.evaluate(() => window.filigree.doc?.undo?.());
    }
    await page.context().close();
  }
} finally {
  await env.close();
}
