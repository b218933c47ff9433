// Responsiveness of the Tangle panel (issue 10 item 9). Not a pass/fail test:
// prints JSON with medians (and p90) in ms, headless Chromium at 1280×800.
//
//   node tests/e2e/tangle-latency.bench.mjs [root]
//
// - village: the time to grow it (request → answer shown), then step-slider
//   moves: from the input event to the end of the next animation frame (the
//   panel's repaint: Path2D batches for the step + fills and strokes), and the
//   panel's own paint work (`paint`, of which `batches` builds Path2Ds).
//   Drags move the slider a few steps at a time, as a hand does (the heavy
//   parts of the picture are shared with the previous step and copied from
//   bitmaps); jumps alternate between far steps (most parts new).
//   A pan frame (the last picture moved as a bitmap) is measured the same way.
// - leaf: a parameter edit on a step (an outline distance, on the outline
//   step with the largest subtree of ≤ 2,000 shapes): from the slider's
//   change to the regrown tangle painted (round trip; a released slider runs
//   at once, no debounce), and the worker's part (`run`: the kept expansion
//   regrows the subtree, then the delta against the answer shown is sent).
//   Each edit's `full` twin, measured in the same run right after it: the
//   full answer of the same document from the same worker (what the page
//   gets from a worker that does not hold its answer, and must handle
//   anyway): its worker round trip, its bytes and the page's preparation of it.
// - baseline: bench/tangle-baseline.tangle (the grid + outlines `filigree
//   bench tangle` runs beside shapely/GEOS) grown in the worker, min/median.
// The floor line is an empty animation frame measured in the same run.
// Round trips are timed in the
// page (the input event to the end of the frame that paints the answer), not
// through the test driver. `pan_work_ms` is our JS per pan frame (the
// handler's bitmap copy), `pan_frame_ms` the frame interval around it.
// "to frame" figures end with a one-pixel read of the canvas in the frame
// callback after the panel's paint, so the browser's rasterisation of what
// the panel drew is inside them.
import { launch } from './harness.mjs';

const root = process.argv[2];
// Software 2-D canvas: in headless Chromium the GPU canvas runs on
// SwiftShader, which rasterises big paths at ~30 s a frame (an artefact of
// the emulated GPU, not what a user's GPU or Chromium's software raster does).
// The page is still composited on SwiftShader (~30 ms of CPU a frame in the
// GPU process, beside the page's threads on a 2-core machine);
// TANGLE_BENCH_COMPOSITING=software composites in software instead, to see
// how much of a figure that is (not the default: the figures of earlier
// sessions were measured with it).
const args = ['--disable-accelerated-2d-canvas',
  ...(process.env.TANGLE_BENCH_COMPOSITING === 'software' ? ['--disable-gpu-compositing'] : [])];
const env = await launch(root ? { root, args } : { args });
const median = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length / 2)]; };
const p90 = (xs) => { const s = [...xs].sort((a, b) => a - b); return s[Math.floor(s.length * 0.9)]; };
const round = (x) => Math.round(x * 10) / 10;
const summary = (xs) => ({ median: round(median(xs)), p90: round(p90(xs)), n: xs.length });

const page = await env.newPage({ path: '#tool=tangle' });
// CPU time, which the machine's load does not inflate: the renderer process's (its main
// thread, the worker's thread and the raster threads: `ProcessTime`) and its main
// thread's (`ThreadTime`), read over the DevTools protocol around an interaction, in ms.
const cdp = await page.context().newCDPSession(page);
await cdp.send('Performance.enable', { timeDomain: 'threadTicks' });
async function cpuNow() {
  const { metrics } = await cdp.send('Performance.getMetrics');
  const get = (name) => 1000 * (metrics.find((m) => m.name === name)?.value ?? NaN);
  return { process: get('ProcessTime'), main: get('ThreadTime') };
}
async function cpuOf(fn) {
  const a = await cpuNow();
  const out = await fn();
  const b = await cpuNow();
  return { out, cpu: { process: b.process - a.process, main: b.main - a.main } };
}
const runs = () => page.$eval('[data-testid=tangle-status]', (el) => Number(el.dataset.runs || 0));
async function waitForResult(prev) {
  await page.waitForFunction((p) => Number(document.querySelector('[data-testid=tangle-status]').dataset.runs || 0) > p
    && !window.filigree.testHooks.tangle.pending(), prev, { timeout: 300000 });
}
await page.waitForFunction(() => window.filigree?.testHooks?.tangle && Number(document.querySelector('[data-testid=tangle-status]').dataset.runs || 0) > 0, null, { timeout: 60000 });

const frameFloor = await page.evaluate(async () => {
  const out = [];
  for (let i = 0; i < 20; i++) {
    const t0 = performance.now();
    await new Promise((r) => requestAnimationFrame(() => r()));
    out.push(performance.now() - t0);
  }
  return out;
});

// TANGLE_BENCH_ONLY=leaf, =village or =baseline runs one part.
const only = process.env.TANGLE_BENCH_ONLY || '';
let n = 0;
let villageOut = null;
async function villageBench() {
// ---- village: grow, then slider moves and pans
n = await runs();
const t0 = Date.now();
await page.click('[data-example=village]');
await waitForResult(n);
const growMs = Date.now() - t0;
async function sliderAndPan() {
  return page.evaluate(async () => {
  const t = window.filigree.testHooks.tangle;
  t.clearLayers(); // each pass starts with no bitmap kept
  const r = t.result();
  const slider = document.querySelector('[data-testid=tangle-step]');
  const steps = r.steps.length;
  const moves = [], paints = [], batches = [], drags = [], dragPaints = [], flushes = [], waits = [];
  const c = document.querySelector('[data-testid=tangle-canvas]');
  // A frame callback after the panel's paint, then one pixel read back: the browser
  // rasterises the canvas's drawing there and then, so the time includes it.
  let flushMs = 0;
  const flush = () => { const f0 = performance.now(); c.getContext('2d').getImageData(0, 0, 1, 1); flushMs = performance.now() - f0; };
  const frame = () => new Promise((res) => requestAnimationFrame(() => { flush(); res(); }));
  t.paintNow();
  await frame();
  for (const from of [0.95, 0.6, 0.3]) {
    for (let i = 0; i < 12; i++) {
      const k = Math.round(steps * from) - i * 2;
      const start = performance.now();
      slider.value = String(k);
      slider.dispatchEvent(new Event('input', { bubbles: true }));
      await frame();
      if (i > 0) { drags.push(performance.now() - start); dragPaints.push(t.timing().paint); }
    }
  }
  for (let i = 0; i < 24; i++) {
    const k = Math.round(steps * (i % 2 ? 0.5 + i / 60 : 1 - i / 60));
    const start = performance.now();
    slider.value = String(k);
    slider.dispatchEvent(new Event('input', { bubbles: true }));
    await frame();
    moves.push(performance.now() - start);
    paints.push(t.timing().paint);
    batches.push(t.timing().batches);
    flushes.push(flushMs);
    waits.push(t.timing().paintAt - start);
  }
  // The same kind of jumps as a person makes them: the panel has had idle time since the
  // last paint (up to 3 s, until its idle work is done) before each one. On a new view
  // (zoomed in a step), so no bitmap of the jumps above is of use.
  document.querySelector('[data-act=zoom-in]').click();
  t.clearLayers();
  await new Promise((r) => setTimeout(r, 400));
  const settledMoves = [];
  const settle = async () => {
    const until = performance.now() + 3000;
    await new Promise((r) => setTimeout(r, 100));
    while (!t.prebuilt() && performance.now() < until) await new Promise((r) => setTimeout(r, 50));
  };
  for (let i = 0; i < 12; i++) {
    const k = Math.round(steps * (i % 2 ? 0.5 + i / 30 : 1 - i / 30));
    await settle();
    const start = performance.now();
    slider.value = String(k);
    slider.dispatchEvent(new Event('input', { bubbles: true }));
    await frame();
    settledMoves.push(performance.now() - start);
  }
  // Back to the end: the final tangle, then pan frames (the bitmap of the last paint, moved).
  slider.value = String(steps);
  slider.dispatchEvent(new Event('input', { bubbles: true }));
  await frame();
  const b = c.getBoundingClientRect();
  const pans = [], panWork = [];
  await frame();
  c.dispatchEvent(new PointerEvent('pointerdown', { pointerId: 7, clientX: b.left + 100, clientY: b.top + 100, bubbles: true }));
  await frame();
  for (let i = 1; i <= 20; i++) {
    const start = performance.now();
    c.dispatchEvent(new PointerEvent('pointermove', { pointerId: 7, clientX: b.left + 100 + 5 * i, clientY: b.top + 100 + 3 * i, bubbles: true }));
    // The handler's own time plus the bitmap copy in its frame callback (ours), then the frame.
    const handler = performance.now() - start;
    await frame();
    pans.push(performance.now() - start);
    panWork.push(handler + t.timing().pan);
  }
  c.dispatchEvent(new PointerEvent('pointerup', { pointerId: 7, clientX: b.left + 200, clientY: b.top + 160, bubbles: true }));
  await new Promise((r) => setTimeout(r, 300));
  await frame();
  // Back to the fitted view for the next pass.
  document.querySelector('[data-act=zoom-fit]').click();
  await frame();
  return {
    steps, shapes: r.stats.shapes, vertices: r.stats.vertices, all_shapes: r.shapes.count,
    worker_ms: Math.round(t.timing().run), moves, settledMoves, flushes, waits, paints, batches, drags, dragPaints, pans, panWork, sharp_paint: t.timing().paint,
  };
  });
}
const village = await sliderAndPan();
// Back-to-back jumps again, alone between two CPU readings: CPU ms per jump.
async function jumpCpu() {
  const n = 24;
  const { cpu } = await cpuOf(() => page.evaluate(async ({ n }) => {
    const t = window.filigree.testHooks.tangle;
    const slider = document.querySelector('[data-testid=tangle-step]');
    const steps = t.result().steps.length;
    const c = document.querySelector('[data-testid=tangle-canvas]');
    const frame = () => new Promise((res) => requestAnimationFrame(() => { c.getContext('2d').getImageData(0, 0, 1, 1); res(); }));
    t.clearLayers(); // no bitmap kept from the passes above
    for (let i = 0; i < n; i++) {
      slider.value = String(Math.round(steps * (i % 2 ? 0.51 + i / 65 : 0.99 - i / 65)));
      slider.dispatchEvent(new Event('input', { bubbles: true }));
      await frame();
    }
  }, { n }));
  return { process: round(cpu.process / n), main: round(cpu.main / n) };
}
const jumpCpuAfter = await jumpCpu();

return {
    grow_ms: growMs, worker_ms: village.worker_ms, steps: village.steps, final_shapes: village.shapes, vertices: village.vertices,
    shapes_in_history: village.all_shapes,
    slider_drag_to_frame_ms: summary(village.drags), slider_drag_paint_ms: summary(village.dragPaints),
    slider_jump_to_frame_ms: summary(village.moves), slider_jump_paint_ms: summary(village.paints),
    slider_jump_batches_ms: summary(village.batches),
    // From the input event to the panel's paint (the frame's start), and the raster of what
    // it drew (the pixel read in the frame callback after it).
    slider_jump_input_to_paint_ms: summary(village.waits),
    slider_jump_raster_ms: summary(village.flushes),
    slider_jump_cpu_ms_per_jump: jumpCpuAfter,
    slider_jump_after_idle_to_frame_ms: summary(village.settledMoves),
    pan_work_ms: summary(village.panWork), pan_frame_ms: summary(village.pans),
    sharp_repaint_ms: round(village.sharp_paint),
  };
}
if (only === '' || only === 'village') villageOut = await villageBench();
let leafOut = null;
// ---- leaf: a parameter edit round trip. `op` 'outline': the outline step with the
// largest subtree of at most 2,000 shapes (its distance moved; `bench tangle` picks the
// same way natively); `op` null: the step of any operator with the largest such subtree
// (its first parameter moved by a few per cent), the bound.
async function leafBench(op) {
n = await runs();
await page.click('[data-example=leaf]');
await waitForResult(n);
const edits = [];
const subtreeSizes = [];
for (let i = 0; i < 12; i++) {
  const target = await page.evaluate((op) => {
    const r = window.filigree.testHooks.tangle.result();
    const subtree = (k) => {
      const made = new Set(r.steps[k].outputs);
      for (let j = k + 1; j < r.steps.length; j++) {
        if (r.steps[j].inputs.some((i) => made.has(i))) for (const o of r.steps[j].outputs) made.add(o);
      }
      return made.size;
    };
    const c = r.steps.map((s, k) => [k, (op ? s.operator === op : s.params.length > 0) ? subtree(k) : Infinity])
      .filter(([, n]) => n <= 2000).sort((a, b) => b[1] - a[1]);
    return c[0][0];
  }, op);
  subtreeSizes.push(await page.evaluate((k) => {
    const r = window.filigree.testHooks.tangle.result();
    const made = new Set(r.steps[k].outputs);
    for (let j = k + 1; j < r.steps.length; j++) if (r.steps[j].inputs.some((i) => made.has(i))) for (const o of r.steps[j].outputs) made.add(o);
    return made.size;
  }, target));
  await page.evaluate((sel) => window.filigree.doc.current.ctx.commit({ ...window.filigree.testHooks.tangle.state(), selected: sel }), target);
  const param = op === 'outline' ? 'distance' : await page.evaluate((k) => window.filigree.testHooks.tangle.result().steps[k].params[0].name, target);
  await page.waitForSelector(`[data-testid=tangle-param-${param}]`);
  // The value moved to: outline distances 3, 3, 4, 4, ... as before; otherwise a few per
  // cent up from the step's own value, within its range.
  const v = op === 'outline' ? 3 + (i >> 1) : await page.evaluate(({ k, i }) => {
    const p = window.filigree.testHooks.tangle.result().steps[k].params[0];
    const x = Math.min(p.max, p.value * (1 + 0.03 * (1 + (i >> 1))));
    return p.integer ? Math.max(p.min, Math.round(x) === p.value ? p.value + 1 : Math.round(x)) : x;
  }, { k: target, i });
  // Settle: the selection painted, nothing running.
  await page.waitForFunction(() => !window.filigree.testHooks.tangle.pending());
  const { out: r, cpu } = await cpuOf(() => page.evaluate(async ({ v, param }) => {
    const t = window.filigree.testHooks.tangle;
    await new Promise((res) => requestAnimationFrame(() => requestAnimationFrame(res)));
    const status = document.querySelector('[data-testid=tangle-status]');
    const n = Number(status.dataset.runs || 0);
    const i = document.querySelector(`[data-testid=tangle-param-${param}]`);
    // The answer is shown (runs counted) in the task that schedules its paint;
    // a frame callback asked for then runs right after that paint.
    const done = new Promise((res) => {
      const mo = new MutationObserver(() => {
        if (Number(status.dataset.runs || 0) > n) {
          mo.disconnect();
          requestAnimationFrame(() => {
            const before = performance.now();
            document.querySelector('[data-testid=tangle-canvas]').getContext('2d').getImageData(0, 0, 1, 1); // rasterised
            res([performance.now(), before]);
          });
        }
      });
      mo.observe(status, { attributes: true, attributeFilter: ['data-runs'] });
    });
    const start = performance.now();
    i.value = String(v);
    i.dispatchEvent(new Event('input', { bubbles: true }));
    i.dispatchEvent(new Event('change', { bubbles: true }));
    const [end, beforeFlush] = await done;
    const tm = t.timing();
    return {
      total: end - start, run: tm.run, prepare: tm.prepare, paint: tm.paint, region: tm.region, reused: t.reused(),
      toPaint: tm.paintAt - tm.answeredAt, raster: end - beforeFlush,
      toRun: tm.runAt - start, toFrame: beforeFlush - tm.paintEndAt,
      delta: tm.answer.delta, bytes: tm.answer.bytes, added: tm.answer.added, removed: tm.answer.removed,
    };
  }, { v, param }));
  r.cpuProcess = cpu.process;
  r.cpuMain = cpu.main;
  await page.waitForFunction(() => !window.filigree.testHooks.tangle.pending());
  // The full answer of the same document from the same worker (no base named), and the
  // page's preparation of it: what a worker that does not hold the answer shown sends.
  r.full = await page.evaluate(async () => {
    const { prepareTangle } = await import('/www/tangle/draw.js');
    const { answerBytes } = await import('/www/tangle/timing.js');
    const { requestOf, KEEP_AFFINITY } = await import('/www/tangle/state.js');
    const ctx = window.filigree.doc.current.ctx;
    const t0 = performance.now();
    const full = await ctx.run('tangle', { ...requestOf(window.filigree.testHooks.tangle.state()), keep: true }, { affinity: KEEP_AFFINITY });
    const t1 = performance.now();
    const bytes = answerBytes(full);
    prepareTangle(full);
    return { run: t1 - t0, prepare: performance.now() - t1, bytes, delta: full.base != null };
  });
  edits.push(r);
}
const leafShapes = await page.evaluate(() => window.filigree.testHooks.tangle.result().stats.shapes);
const editedStep = await page.evaluate(() => { const s = window.filigree.testHooks.tangle.state(); const st = window.filigree.testHooks.tangle.result().steps[s.selected]; return st ? `${st.operator}, line ${st.line}` : null; });

const editFigure = (key) => summary(edits.map((e) => e[key]));
const fullFigure = (key) => summary(edits.map((e) => e.full[key]));
return {
    final_shapes: leafShapes, edited_subtree_shapes: subtreeSizes, edited_step: editedStep,
    param_edit_round_trip_ms: editFigure('total'),
    param_edit_worker_ms: editFigure('run'), prepare_ms: editFigure('prepare'), repaint_ms: editFigure('paint'),
    answer_to_paint_ms: editFigure('toPaint'), raster_ms: editFigure('raster'),
    input_to_request_ms: editFigure('toRun'), painted_to_frame_ms: editFigure('toFrame'),
    round_trip_cpu_ms: { renderer_process: editFigure('cpuProcess'), main_thread: editFigure('cpuMain') },
    repainted_fraction: editFigure('region'), shapes_kept_from_last_answer: editFigure('reused'),
    answers_that_were_deltas: edits.filter((e) => e.delta).length, of_edits: edits.length,
    delta_answer_bytes: editFigure('bytes'), delta_added_shapes: editFigure('added'), delta_removed_shapes: editFigure('removed'),
    full_answer: { bytes: fullFigure('bytes'), worker_round_trip_ms: fullFigure('run'), prepare_ms: fullFigure('prepare'), deltas: edits.filter((e) => e.full.delta).length },
  };
}
let leafLargestOut = null;
if (only === '' || only === 'leaf') {
  leafOut = await leafBench('outline');
  leafLargestOut = await leafBench(null);
}
// ---- baseline: the grammar `filigree bench tangle` times natively beside shapely/GEOS
// (bench/tangle-baseline.tangle: 18,000 shapes, no wobble), grown in the browser's worker:
// the issue asks to match shapely's time there. A new seed each time, so no kept
// expansion is reused; `run` is the panel's request-to-answer time, `grow` to the frame.
let baselineOut = null;
async function baselineBench() {
  const grammar = (await import('node:fs')).readFileSync(new URL('../../bench/tangle-baseline.tangle', import.meta.url), 'utf8');
  const runsMs = [], growMs = [];
  let stats = null;
  for (let seed = 11; seed < 16; seed++) {
    const prev = await runs();
    const t0 = Date.now();
    await page.evaluate(({ grammar, seed }) => window.filigree.doc.current.ctx.commit({
      ...window.filigree.testHooks.tangle.state(), grammar, seed, wobble: 0, edits: [], selected: null,
    }), { grammar, seed });
    await waitForResult(prev);
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => r())));
    growMs.push(Date.now() - t0);
    runsMs.push(await page.evaluate(() => window.filigree.testHooks.tangle.timing().run));
    stats = await page.evaluate(() => window.filigree.testHooks.tangle.result().stats);
  }
  const min = (xs) => round(Math.min(...xs));
  return {
    final_shapes: stats.shapes, vertices: stats.vertices,
    worker_ms: { min: min(runsMs), ...summary(runsMs) }, grow_to_frame_ms: { min: min(growMs), ...summary(growMs) },
  };
}
if (only === '' || only === 'baseline') baselineOut = await baselineBench();
console.log(JSON.stringify({
  load: (await import('node:os')).loadavg().map((x) => round(x)),
  compositing: process.env.TANGLE_BENCH_COMPOSITING === 'software' ? 'software' : 'gpu (SwiftShader)',
  frame_floor_ms: summary(frameFloor),
  village: villageOut,
  leaf: leafOut,
  leaf_largest_subtree: leafLargestOut,
  baseline: baselineOut,
}, null, 1));
await env.close();
