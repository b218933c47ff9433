// Start-up benchmark (not a test): wasm bytes, first paint and "core ready"
// (the first worker's wasm instantiated) in headless Chromium, each from a
// fresh browser context (empty cache), as JSON.
//   node scripts/bench-startup.mjs [runs=7]
import fs from 'node:fs';
import path from 'node:path';
import { launch, ROOT } from '../tests/e2e/harness.mjs';

const runs = Number(process.argv[2] || 7);
const env = await launch();
const samples = [];
try {
  for (let i = 0; i < runs; i++) {
    const page = await env.newPage({ path: null, serviceWorkers: 'block' });
    // Note the moment the shell marks the core ready, without polling.
    await page.addInitScript(() => {
      new MutationObserver((_, obs) => {
        if (document.documentElement.dataset.coreReady === '1') {
          window.__coreReadyAt = performance.now();
          obs.disconnect();
        }
      }).observe(document, { subtree: true, attributes: true, attributeFilter: ['data-core-ready'] });
    });
    await page.goto(env.url);
    await page.waitForFunction(() => window.__coreReadyAt !== undefined, null, { timeout: 30000 });
    samples.push(await page.evaluate(() => ({
      firstPaintMs: performance.getEntriesByName('first-paint')[0]?.startTime ?? null,
      coreReadyMs: window.__coreReadyAt,
    })));
    await page.context().close();
  }
} finally {
  await env.close();
}
const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };
console.log(JSON.stringify({
  bench: 'startup',
  wasmBytes: fs.statSync(path.join(ROOT, 'pkg/filigree_bg.wasm')).size,
  runs,
  firstPaintMsMedian: median(samples.map((s) => s.firstPaintMs)),
  coreReadyMsMedian: median(samples.map((s) => s.coreReadyMs)),
  samples,
}));
