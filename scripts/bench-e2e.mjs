// Browser figures for the notes, run by hand (not part of the pass/fail
// suite): cold load of the page, `inspect` of the 1024² PNG in the worker
// (compare `filigree bench inspect`), the fish case of `filigree bench pixel`
// in the worker, and a paper-budget Fit of circles-mix through the panel.
// Prints one JSON object; exits non-zero if a run fails.
//
//   bash scripts/build.sh && node scripts/bench-e2e.mjs
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { launch, fixture } from '../tests/e2e/harness.mjs';

const env = await launch();
try {
  console.log(JSON.stringify(await bench(env)));
} finally {
  await env.close();
}

async function bench(env) {
  const page = await env.newPage({ path: null });
  const t0 = Date.now();
  await page.goto(env.url);
  await page.waitForFunction(() => document.documentElement.dataset.coreReady === '1');
  const readyMs = Date.now() - t0;
  const paintMs = await page.evaluate(() => new Promise((resolve) => {
    new PerformanceObserver((list) => resolve(list.getEntries()[0].startTime))
      .observe({ type: 'paint', buffered: true });
    setTimeout(() => resolve(-1), 2000);
  }));
  const b64 = fs.readFileSync(fixture('gradient-1024.png')).toString('base64');
  const r = await page.evaluate(async (b64) => {
    const bin = atob(b64);
    const bytes = new Uint8Array(bin.length);
    for (let i = 0; i < bin.length; i++) bytes[i] = bin.charCodeAt(i);
    const times = [];
    let last;
    for (let i = 0; i < 7; i++) {
      const t = performance.now();
      last = await window.filigree.pool.run('inspect', { bytes: bytes.slice() });
      times.push(performance.now() - t);
    }
    times.sort((a, b) => a - b);
    return { width: last.width, colours: last.colour_count, min: times[0], median: times[3] };
  }, b64);
  assert.equal(r.width, 1024);
  assert.equal(r.colours, 65536);
  // The fish case of `filigree bench pixel`, end to end in the worker
  // (same files, strokes and parameters as assets/pixel/cases.json).
  const fish = await page.evaluate(async () => {
    const base = new URL('assets/pixel/', location.href);
    const get = async (f) => new Uint8Array(await (await fetch(new URL(f, base))).arrayBuffer());
    const cases = await (await fetch(new URL('cases.json', base))).json();
    const c = cases.fish;
    const [source, maskPng, sheet] = await Promise.all([c.source, c.mask, c.sheet].map(get));
    const strokes = (await (await fetch(new URL(c.strokes, base))).json()).strokes;
    const pool = window.filigree.pool;
    const mask = await pool.run('pixel-mask', { bytes: maskPng });
    const times = [];
    let placed = 0;
    for (let i = 0; i < 15; i++) {
      const t = performance.now();
      const r = await pool.run('pixel', { source: source.slice(), sheet: sheet.slice(), mask: { ...mask, bits: mask.bits.slice() }, strokes, params: c.params });
      times.push(performance.now() - t);
      placed = r.placed;
    }
    times.sort((a, b) => a - b);
    return { placed, min: times[0], median: times[7] };
  });
  assert.ok(fish.placed > 0, 'the fish case placed no element');
  // One wasm module per tool: the Pixel one is what these timings load.
  const wasm = fs.statSync(new URL('../pkg/filigree_pixel_bg.wasm', import.meta.url)).size;
  return {
    bench: 'browser', pixel_wasm_bytes: wasm, first_contentful_paint_ms: Math.round(paintMs), core_ready_ms: readyMs,
    inspect_1024_worker_ms: { min: +r.min.toFixed(1), median: +r.median.toFixed(1) },
    pixel_fish_worker_ms: { placed: fish.placed, min: +fish.min.toFixed(1), median: +fish.median.toFixed(1) },
    fit_paper_circles_mix_14_params: await paperFit(env),
  };
}

// A paper-budget fit of the 14-parameter circles-mix generator through the
// Fit panel, as a person runs it: target made from the defaults, Fit clicked.
async function paperFit(env) {
  const page = await env.newPage({ path: '#tool=fit' });
  await page.waitForSelector('[data-testid=fit-sliders] .row');
  await page.selectOption('[data-testid=fit-generator]', 'circles-mix');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state()?.generator === 'circles-mix');
  await page.selectOption('select[name=budget]', 'paper');
  await page.click('button[data-act=make-target]');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state().truth !== null);
  const t0 = Date.now();
  await page.click('button[data-act=fit]');
  await page.waitForFunction(() => /^fitted/.test(document.querySelector('[data-testid=fit-status]').textContent)
    || !document.querySelector('.fit-error').hidden, null, { timeout: 180000 });
  const seconds = (Date.now() - t0) / 1000;
  const r = await page.evaluate(() => {
    const { values, truth } = window.filigree.testHooks.fit.state();
    const params = window.filigree.testHooks.fit.info().params;
    let mse = 0;
    params.forEach((p, i) => { mse += ((values[i] - truth[i]) / (p.hi - p.lo)) ** 2 / params.length; });
    return { mse, status: document.querySelector('[data-testid=fit-status]').textContent };
  });
  assert.match(r.status, /^fitted/);
  return { seconds: +seconds.toFixed(2), workers: await page.evaluate(() => window.filigree.pool.slots.length), param_mse: +r.mse.toExponential(2) };
}
