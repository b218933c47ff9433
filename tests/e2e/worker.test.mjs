import { test, before, after } from 'node:test';
import assert from 'node:assert/strict';
import { launch, dropFile, fixture } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
after(async () => { await env?.close(); });

test('a worker that crashes mid-job is reported and replaced; the next job succeeds', async () => {
  const page = await env.newPage({ path: '#tool=inspect' });
  const outcome = await page.evaluate(async () => {
    const progress = [];
    try {
      await window.filigree.pool.run('debug-abort', { steps: 40 }, { onProgress: (p) => progress.push(p.fraction) });
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

test('cancelling a running job stops it quickly without killing the worker', async () => {
  const page = await env.newPage({ path: '#tool=inspect' });
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
