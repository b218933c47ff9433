// The pattern language's one nesting budget (lang::MAX_DEPTH) must fit the
// stack of the release wasm in the worker: the deepest program of every
// kind of nesting runs, one level more is a located limit error, and
// nothing ever traps (a trap would surface as kind 'crash').
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch } from './harness.mjs';
import { FAMILIES, runIn } from './pattern-depth-families.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const located = (r) => Number.isInteger(r.line) || /line \d+, column \d+/.test(r.message);

test('the deepest programs the nesting budget allows run in the wasm worker; deeper is a located limit error, never a trap', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  const deepest = {};
  for (const [name, make] of Object.entries(FAMILIES)) {
    // Bisection for the deepest k that runs; every failure on the way must
    // be the budget's error, not a crash.
    let lo = 0;
    let hi = 1024;
    let over = await runIn(page, make(hi));
    assert.equal(over.ok, false, `${name}: ${hi} levels were accepted`);
    while (hi - lo > 1) {
      const mid = (lo + hi) >> 1;
      const r = await runIn(page, make(mid));
      if (r.ok) lo = mid;
      else { hi = mid; over = r; }
      if (!r.ok) assert.notEqual(r.kind, 'crash', `${name} at ${mid}: ${r.message}`);
    }
    assert.ok(lo >= 12, `${name}: only ${lo} levels run`);
    assert.equal((await runIn(page, make(lo))).ok, true, `${name} at ${lo}`);
    assert.ok(over.kind === 'limit' || over.kind === 'syntax', `${name} at ${hi}: ${over.kind} ${over.message}`);
    assert.match(over.message, /nested/, name);
    assert.ok(located(over), `${name}: ${JSON.stringify(over)}`);
    deepest[name] = lo;
  }
  console.log('deepest programs in wasm:', JSON.stringify(deepest));
  // Far beyond the budget: still an error, quickly.
  for (const make of [FAMILIES.parentheses, FAMILIES.recursion, FAMILIES['recursion through blocks']]) {
    const r = await runIn(page, make(100000));
    assert.ok(r.kind === 'limit' || r.kind === 'syntax', `${r.kind} ${r.message}`);
  }
  // The worker was never replaced.
  assert.equal(await page.$('.toast-error'), null);
  assert.equal((await runIn(page, FAMILIES.blocks(3))).ok, true);
});
