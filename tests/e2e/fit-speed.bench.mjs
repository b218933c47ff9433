// Fit in the browser with the default settings (issue 9 item 2: "the
// browser's Fit button should give the best result a user can get, in
// seconds"). Not a pass/fail test: prints JSON, headless Chromium at 1280×800.
//
//   node tests/e2e/fit-speed.bench.mjs [root] [generator,...]
//
// For every generator in the picker (or the ones named): the target is the
// program drawn from known values (its defaults moved by a seeded ±15% of
// each range, so the truth is no special point), then "Run fit" is clicked
// with the panel's default settings, as a person would. Per generator:
// seconds from the click to "fitted" (the panel's own figure), evaluations,
// the normalised parameter MSE against the truth (errors relative to each
// range, as `bench fit` and the paper measure), and the mean per-colour IoU
// of the fitted values' drawing against the truth's (the figure the issue's
// designers' test used: 0.95 counts as landed). The fit is sharded over the worker pool
// (all workers but one); `workers` says how many.
import { launch, pickGenerator } from './harness.mjs';

const root = process.argv[2] && process.argv[2] !== '-' ? process.argv[2] : undefined;
const only = process.argv[3] ? process.argv[3].split(',') : null;
const env = await launch(root ? { root } : {});
const page = await env.newPage({ path: '#tool=fit' });
await page.waitForSelector('[data-testid=fit-sliders] .row');
const names = only ?? (await page.$$eval('[data-testid=fit-generator] option', (os) => os.map((o) => o.value))).filter(Boolean);
const round = (x, d = 3) => Number(x.toPrecision(d));

const rows = [];
for (const [g, name] of names.entries()) {
  await pickGenerator(page, name);
  // The truth: defaults moved by a seeded fraction of each float range.
  const truth = await page.evaluate((seed) => {
    let s = (seed * 2654435761) >>> 0 || 1;
    const rand = () => { s ^= s << 13; s >>>= 0; s ^= s >>> 17; s ^= s << 5; s >>>= 0; return s / 4294967296; };
    const st = window.filigree.testHooks.fit.state();
    const values = window.filigree.testHooks.fit.info().params.map((p, i) => (p.integer ? st.values[i]
      : Math.min(p.hi, Math.max(p.lo, st.values[i] + (rand() - 0.5) * 0.3 * (p.hi - p.lo)))));
    window.filigree.doc.current.ctx.commit({ ...st, values });
    return values;
  }, g + 1);
  await page.waitForFunction((v) => JSON.stringify(window.filigree.testHooks.fit.state().values) === JSON.stringify(v), truth);
  await page.click('button[data-act=make-target]');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state().truth !== null);
  const t0 = Date.now();
  await page.click('button[data-act=fit]');
  await page.waitForFunction(() => /^fitted/.test(document.querySelector('[data-testid=fit-status]').textContent)
    || !document.querySelector('[data-testid=doc-error]').hidden, null, { timeout: 600000 });
  const wall = (Date.now() - t0) / 1000;
  const out = await page.evaluate(async () => {
    const f = window.filigree.testHooks.fit;
    const st = f.state(), info = f.info();
    const ctx = window.filigree.doc.current.ctx;
    const status = document.querySelector('[data-testid=fit-status]').textContent;
    let mse = 0, n = 0;
    info.params.forEach((p, i) => {
      if (p.integer) return;
      const e = (st.values[i] - st.truth[i]) / (p.hi - p.lo);
      mse += e * e;
      n++;
    });
    // Mean per-colour IoU: the truth and the fitted values drawn without
    // anti-aliasing (one sample a pixel, so every pixel is one of the program's
    // colours), at the target's size; per colour of the truth's drawing, the
    // pixels it covers in both over those it covers in either.
    const draw = async (values) => (await ctx.run('render-pattern', {
      program: st.program, params: Object.fromEntries(info.params.map((p, i) => [p.name, values[i]])),
      size: st.target.width, supersample: 1,
    })).rgba;
    const a = await draw(st.truth), b = await draw(st.values), px = a.length / 4;
    const key = (d, i) => (d[4 * i] << 16) | (d[4 * i + 1] << 8) | d[4 * i + 2];
    const inter = new Map(), uni = new Map();
    const add = (m, k) => m.set(k, (m.get(k) || 0) + 1);
    for (let i = 0; i < px; i++) {
      const p = key(a, i), q = key(b, i);
      add(uni, p);
      if (p === q) add(inter, p); else add(uni, q);
    }
    const truthColours = new Set();
    for (let i = 0; i < px; i++) truthColours.add(key(a, i));
    const palette = [...truthColours];
    const ious = palette.map((k) => (inter.get(k) || 0) / uni.get(k));
    const seconds = Number(/fitted in ([\d.]+) s/.exec(status)?.[1]);
    const evaluations = Number(/after (\d+) evaluations/.exec(status)?.[1]);
    return {
      status, seconds, evaluations, param_mse: n ? mse / n : 0,
      mean_iou: ious.reduce((x, y) => x + y, 0) / ious.length, colours: palette.length,
      workers: Math.max(1, ctx.pool.slots.length - 1), settings: st.settings,
    };
  });
  if (!/^fitted/.test(out.status)) throw new Error(`${name}: ${await page.textContent('[data-testid=doc-error]')}`);
  rows.push({
    generator: name, seconds: out.seconds, wall_seconds: round(wall), evaluations: out.evaluations,
    param_mse: round(out.param_mse), mean_iou: round(out.mean_iou, 4), colours: out.colours,
    workers: out.workers, settings: out.settings,
  });
  console.error(`${name}: ${out.seconds} s, IoU ${round(out.mean_iou, 4)}, MSE ${round(out.param_mse)}`);
}
const secs = rows.map((r) => r.seconds).sort((a, b) => a - b);
console.log(JSON.stringify({
  bench: 'fit-browser',
  load: (await import('node:os')).loadavg().map((x) => round(x, 2)),
  rows,
  seconds_median: secs[Math.floor(secs.length / 2)], seconds_max: secs.at(-1),
  landed_iou_0_95: rows.filter((r) => r.mean_iou >= 0.95).length, of: rows.length,
}, null, 1));
await env.close();
