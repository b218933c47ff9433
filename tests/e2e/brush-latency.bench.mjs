// Input-to-paint latency of a brush drag in the Pixel panel (issue 8 item 4),
// on a 1024² and a 4096² source, strokes and mask painting. Not a pass/fail
// test: prints the medians (and p90) in ms.
//
//   node tests/e2e/brush-latency.bench.mjs [root]      (root: an app checkout, default this one)
//
// The first line is the floor: the same drag on a page that paints nothing,
// measured in the same run (on a busy machine it dominates; compare against it).
// Each line also gives the panel's own repaint work per frame (CanvasView.paint).
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
env.browser.on('disconnected', () => console.log('browser disconnected'));
const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };
const p90 = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length * 0.9)]; };

/** The same drag and measurement on a page that paints nothing: the floor this machine gives now. */
async function floor() {
  const page = await env.newPage({ path: null });
  await page.setContent('<div id="pad" style="width:600px;height:400px;touch-action:none"></div>');
  await page.evaluate(() => {
    window.latencies = [];
    document.querySelector('#pad').addEventListener('pointermove', (e) => {
      if (!e.buttons) return;
      const t0 = e.timeStamp;
      requestAnimationFrame(() => setTimeout(() => window.latencies.push(performance.now() - t0), 0));
    });
  });
  await page.mouse.move(40, 40);
  await page.mouse.down();
  for (let i = 0; i < 4; i++) {
    await page.mouse.move(440, 60 * i + 70, { steps: 40 });
    await page.mouse.move(40, 60 * i + 100, { steps: 40 });
  }
  await page.mouse.up();
  const lat = await page.evaluate(() => window.latencies);
  await page.context().close();
  return lat;
}

try {
  const base = await floor();
  console.log(`floor (a page that paints nothing): median ${median(base).toFixed(1)} ms, p90 ${p90(base).toFixed(1)} ms over ${base.length} moves`);
  for (const side of (process.env.SIDES || "1024,4096").split(",").map(Number)) {
    const file = path.join(os.tmpdir(), `latency-${side}.png`);
    fs.writeFileSync(file, await bigPng(side, side));
    const page = await env.newPage({ path: '#tool=pixel' });
    page.on('crash', () => console.log('page crashed', side));
    page.on('close', () => console.log('page closed', side));
    page.on('console', (m) => m.type() === 'error' && console.log('[console]', m.text()));
    await page.waitForFunction(() => window.filigree?.testHooks?.pixel?.state()?.example === 'fish', null, { timeout: 30000 });
    await page.setInputFiles('input[data-input=source]', file);
    // The source is decoded and laid out (the view may scale it down to fit the window).
    await page.waitForFunction((n) => window.filigree.testHooks.pixel.state()?.mask.width === n
      && document.querySelector('.tool-pixel canvas.base').width === n, side, { timeout: 60000 });
    await page.waitForTimeout(500);
    for (const mode of ['stroke', 'paint']) {
      await page.click(`button[data-mode=${mode}]`);
      await page.evaluate(async () => {
        window.latencies = [];
        window.paints = [];
        const c = document.querySelector('[data-testid=pixel-canvas]');
        c.addEventListener('pointermove', (e) => {
          if (!e.buttons) return;
          const t0 = e.timeStamp;
          requestAnimationFrame(() => setTimeout(() => window.latencies.push(performance.now() - t0), 0));
        });
        // Our own work per frame: the view's repaint of what the brush touched.
        if (!window.paintHooked) {
          window.paintHooked = true;
          const { CanvasView } = await import(new URL('www/pixel/canvas-view.js', document.baseURI).href);
          const paint = CanvasView.prototype.paint;
          CanvasView.prototype.paint = function timed() {
            const t = performance.now();
            paint.call(this);
            window.paints.push(performance.now() - t);
          };
        }
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
      const { lat, paints } = await page.evaluate(() => ({ lat: window.latencies, paints: window.paints }));
      console.log(`${side}² ${mode.padEnd(6)}: median ${median(lat).toFixed(1)} ms, p90 ${p90(lat).toFixed(1)} ms over ${lat.length} moves;`
        + ` repaint work per frame median ${median(paints).toFixed(2)} ms, max ${Math.max(...paints).toFixed(1)} ms over ${paints.length} frames`);
      await page.evaluate(() => window.filigree.doc?.undo?.());
    }
    await page.context().close();
  }
} finally {
  await env.close();
}
