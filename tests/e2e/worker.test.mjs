import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { MODULE_KINDS } from '../../www/app/protocol.js';
import { launch, dropFile, fixture, ROOT } from './harness.mjs';

// The deliberate-crash request ('debug-abort', feature test-hooks of
// src/wasm) is in no shipped module (pkg/). `FILIGREE_TEST_HOOKS=1 bash
// scripts/build.sh` also builds an Inspect module with it into pkg-test/;
// these tests serve it in place of pkg/'s (service worker blocked, so the
// page fetches it). 'debug-abort' is no tool's kind, so it runs in the
// Inspect module.
const TEST_PKG = path.join(ROOT, 'pkg-test');

async function testCorePage(env) {
  for (const f of ['filigree_inspect_bg.wasm', 'filigree_inspect.js']) {
    if (!fs.existsSync(path.join(TEST_PKG, f))) {
      throw new Error(`pkg-test/${f} is missing: run FILIGREE_TEST_HOOKS=1 bash scripts/build.sh`);
    }
  }
  const page = await env.newPage({ path: null, serviceWorkers: 'block' });
  await page.context().route(/\/pkg\/filigree_inspect(_bg\.wasm|\.js)$/, (route) => {
    const name = new URL(route.request().url()).pathname.split('/').pop();
    route.fulfill({ path: path.join(TEST_PKG, name) });
  });
  await page.goto(env.url + '#tool=inspect');
  await page.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
  return page;
}

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

test('a worker that crashes mid-job is reported and replaced; the next job succeeds', async () => {
  const page = await testCorePage(env);
  const outcome = await page.evaluate(async () => {
    const progress = [];
    try {
      // The worker reports progress once a slice has run 15 ms: 40 steps
      // once crashed before the first report (a fresh-clone CI run on a
      // quiet machine); 400 steps are ten times the work.
      await window.filigree.pool.run('debug-abort', { steps: 400 }, { onProgress: (p) => progress.push(p.fraction) });
      return { ok: true };
    } catch (e) {
      return { ok: false, kind: e.kind, message: e.message, progress };
    }
  });
  assert.equal(outcome.ok, false);
  assert.equal(outcome.kind, 'crash');
  assert.match(outcome.message, /deliberate crash/);
  assert.ok(outcome.progress.length > 0, 'the job reported progress before it crashed');
  // The UI says what happened.
  await page.waitForSelector('.toast-error');
  assert.match(await page.textContent('.toast-error'), /crashed and its worker was restarted/);
  // And the app keeps working.
  await dropFile(page, '[data-testid=drop-zone]', fixture('fish.png'));
  await page.waitForSelector('[data-testid=palette] li');
  assert.equal(await page.textContent('[data-field=size]'), '128 × 128 px');
});

test('a RangeError (stack overflow) from the core is fatal: the worker is replaced, not reused', async () => {
  const page = await testCorePage(env);
  const r = await page.evaluate(async () => {
    const pool = window.filigree.pool;
    const out = {};
    try {
      await pool.run('debug-abort', { steps: 1, overflow: true });
      out.ok = true;
    } catch (e) {
      out.kind = e.kind;
      out.message = e.message;
    }
    // Every worker of the pool still answers (none kept a corrupted instance).
    const n = pool.slots.length;
    const infos = await Promise.all(Array.from({ length: 2 * n }, () =>
      pool.run('pattern-info', { program: 'circle(0.5, 0.5, 0.25);' }).then((i) => i.shapes, (e) => `${e.kind}: ${e.message}`)));
    out.infos = infos;
    return out;
  });
  assert.equal(r.ok, undefined, 'the overflow did not return');
  assert.equal(r.kind, 'crash', r.message);
  assert.match(r.message, /Maximum call stack size exceeded|RangeError|crashed/);
  assert.ok(r.infos.every((s) => s === 1), JSON.stringify(r.infos));
});

test('cancelling a running job stops it quickly without killing the worker', async () => {
  const page = await testCorePage(env);
  const r = await page.evaluate(async () => {
    const ctrl = new AbortController();
    let t0 = 0;
    const job = window.filigree.pool.run('debug-abort', { steps: 100000 }, {
      signal: ctrl.signal,
      onProgress: () => { if (!t0) { t0 = performance.now(); ctrl.abort(); } },
    });
    try { await job; return { ok: true }; } catch (e) {
      return { kind: e.kind, message: e.message, ms: performance.now() - t0 };
    }
  });
  assert.equal(r.kind, 'cancelled');
  assert.equal(r.message, 'cancelled', 'stopped at a slice boundary, not by terminating the worker');
  assert.ok(r.ms < 500, `cancel took ${r.ms} ms`);
  const again = await page.evaluate(() => window.filigree.pool.run('debug-abort', { steps: 1 }).catch((e) => e.kind));
  assert.equal(again, 'crash', 'the same pool still runs jobs after a cancel');
});

test('the shipped core has no test hooks', async () => {
  const page = await env.newPage({ path: '#tool=inspect' });
  const e = await page.evaluate(() => window.filigree.pool.run('debug-abort', { steps: 1 })
    .then(() => null, (e) => ({ kind: e.kind, message: e.message })));
  assert.equal(e?.kind, 'invalid-input');
  assert.match(e.message, /unknown request kind 'debug-abort'/);
  for (const m of Object.keys(MODULE_KINDS)) {
    const wasm = fs.readFileSync(path.join(ROOT, `pkg/filigree_${m}_bg.wasm`));
    assert.equal(wasm.includes('deliberate crash'), false, `pkg/filigree_${m}_bg.wasm carries the debug-abort job`);
  }
});

test('errors arrive typed: a syntax error has kind, line, column and field; a bad field is named', async () => {
  const page = await env.newPage({ path: '#tool=inspect' });
  const r = await page.evaluate(async () => {
    const pool = window.filigree.pool;
    const grab = (p) => p.then(() => null, (e) => ({
      name: e.name, kind: e.kind, message: e.message, line: e.line, column: e.column, field: e.field,
    }));
    return {
      syntax: await grab(pool.run('pattern-info', { program: 'param a in [0, 1] = 0.5;\ncircle(a, a a);\n' })),
      nullProgram: await grab(pool.run('pattern-info', { program: null })),
      tolerance: await grab(pool.run('inspect', { bytes: new Uint8Array(8), tolerance: -5 })),
      supersample: await grab(pool.run('render-pattern', { program: 'circle(0.5, 0.5, 0.2);', supersample: 1e12 })),
      unknownParam: await grab(pool.run('render-pattern', { program: 'param r in [0, 1] = 0.2;\ncircle(0.5, 0.5, r);', params: { radius: 1 } })),
      // Issue 34: a null payload said "Reflect.get called on non-object".
      nullPayload: await grab(pool.run('inspect', null)),
    };
  });
  assert.deepEqual(r.syntax, {
    name: 'JobError', kind: 'syntax', message: r.syntax.message, line: 2, column: 13, field: 'program',
  });
  assert.match(r.syntax.message, /line 2, column 13/);
  assert.equal(r.nullProgram.kind, 'bad-request');
  assert.equal(r.nullProgram.field, 'program');
  assert.equal(r.nullProgram.message, 'pattern-info: `program` must be text (got null)');
  assert.equal(r.nullProgram.line, undefined);
  assert.equal(r.tolerance.field, 'tolerance');
  assert.match(r.tolerance.message, /`tolerance` must be a finite number in 0\.\.=442/);
  assert.equal(r.supersample.field, 'supersample');
  assert.equal(r.unknownParam.field, 'params.radius');
  assert.match(r.unknownParam.message, /no parameter 'radius'/);
  assert.equal(r.nullPayload.kind, 'bad-request');
  assert.equal(r.nullPayload.message, 'inspect: the request must be an object (got null)');
});

test('jobs with an affinity run on the worker that ran the last one (waiting for it), others flow around it', async () => {
  const page = await env.newPage({ path: '#tool=inspect' });
  const r = await page.evaluate(async () => {
    const pool = window.filigree.pool;
    const homes = () => pool.slots.filter((s) => s.affinity === 'tangle').map((s) => s.index);
    const grammar = 'start rect(300, 200) : a\nregularSplit(line, 20, 0) : a -> [b]\noutline(4) : b -> [c, d]\n';
    const tangle = (extra, opts = {}) => pool.run('tangle', { grammar, wobble: 0, keep: true, ...extra }, { affinity: 'tangle', ...opts });
    const out = {};
    await tangle({});
    out.first = homes();
    // Busy workers elsewhere do not move it.
    const others = [pool.run('tangle', { grammar, seed: 7 }), pool.run('tangle', { grammar, seed: 8 })];
    await tangle({ edits: [{ step: 1, params: { distance: 6 } }] });
    await Promise.all(others);
    out.second = homes();
    // While its worker runs an affinity job, the next one waits for that
    // worker even though others are free.
    const ctrl = new AbortController();
    const slow = tangle({ grammar: 'start rect(2000, 2000) : a\nregularSplit(line, 20, 1) : a -> [b]\noutline(2) : b -> [c, d]\n', wobble: 1 }, { signal: ctrl.signal })
      .catch((e) => e.kind);
    await new Promise((res) => setTimeout(res, 50));
    const next = tangle({ edits: [{ step: 1, params: { distance: 5 } }], export: 'svg' });
    await new Promise((res) => setTimeout(res, 50));
    out.queued = pool.queue.length;
    out.freeWhileQueued = pool.slots.filter((s) => !s.job).length;
    ctrl.abort();
    out.slow = await slow;
    const kept = await next;
    out.third = homes();
    // The kept expansion's answer is a fresh one's.
    const fresh = await pool.run('tangle', { grammar, wobble: 0, edits: [{ step: 1, params: { distance: 5 } }], export: 'svg' });
    out.same = kept.svg === fresh.svg && kept.svg.length > 1000;
    return out;
  });
  assert.equal(r.first.length, 1);
  assert.deepEqual(r.second, r.first);
  assert.equal(r.queued, 1, 'the affinity job waited for its worker');
  assert.ok(r.freeWhileQueued >= 1, 'while another worker was free');
  assert.equal(r.slow, 'cancelled');
  assert.deepEqual(r.third, r.first);
  assert.ok(r.same, 'a kept expansion answers as a fresh one does');
});

// A core that cannot be compiled (a browser without WebAssembly SIMD, or a
// damaged download) must be said plainly when a job runs, not leave the job
// waiting for ever.
test('a core that fails to load fails each job with a plain message instead of hanging', { timeout: 60000 }, async () => {
  const page = await env.newPage({ path: null });
  await page.route('**/pkg/filigree_*_bg.wasm', (route) => route.fulfill({ status: 200, contentType: 'application/wasm', body: Buffer.from('not a wasm module') }));
  await page.goto(`${env.url}#tool=inspect`);
  const outcome = await page.evaluate(async () => {
    try {
      await window.filigree.pool.run('texture-models', {});
      return { ok: true };
    } catch (e) {
      return { ok: false, kind: e.kind, message: e.message };
    }
  });
  assert.equal(outcome.ok, false);
  assert.equal(outcome.kind, 'crash');
  assert.match(outcome.message, /the core could not load/);
  await page.waitForSelector('.toast-error');
  assert.match(await page.textContent('.toast-error'), /the core could not load/);
});
