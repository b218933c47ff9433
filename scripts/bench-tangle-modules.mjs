// Two builds of the Tangle wasm module side by side, in Node's V8 (the
// engine of Chromium), without a browser: each shipped grammar below grown
// from seed 1 to its answer (`tangle` request, every step), the builds
// interleaved run by run (A B, then B A, ...) so a busy machine slows both
// alike. Prints JSON: per grammar and build, the minimum and median ms.
//
//   node scripts/bench-tangle-modules.mjs DIR_A DIR_B [RUNS]
//
// DIR_A, DIR_B hold filigree_tangle.js and filigree_tangle_bg.wasm (a pkg/
// of scripts/build.sh, or a module built with other settings). Used for
// size-against-speed choices of the Tangle build (docs/bench/).
import { readFileSync } from 'node:fs';
import path from 'node:path';
import { pathToFileURL } from 'node:url';

const [dirA, dirB, runs = '7'] = process.argv.slice(2);
if (!dirA || !dirB) {
  console.error('usage: node scripts/bench-tangle-modules.mjs DIR_A DIR_B [RUNS]');
  process.exit(2);
}
const root = path.join(path.dirname(new URL(import.meta.url).pathname), '..');
const grammars = Object.fromEntries(
  [['village', 'assets/tangle/village.tangle'], ['leaf', 'assets/tangle/leaf.tangle'],
    ['letters', 'assets/tangle/letters.tangle'], ['baseline', 'bench/tangle-baseline.tangle']]
    .map(([name, file]) => [name, readFileSync(path.join(root, file), 'utf8')]),
);

async function load(dir) {
  const abs = path.resolve(dir);
  const m = await import(`${pathToFileURL(path.join(abs, 'filigree_tangle.js')).href}?${encodeURIComponent(abs)}`);
  m.initSync({ module: readFileSync(path.join(abs, 'filigree_tangle_bg.wasm')) });
  return m;
}

function grow(m, grammar) {
  const t0 = performance.now();
  const job = m.start_job('tangle', { grammar, seed: 1 });
  for (let r = job.step(); !r.done; r = job.step());
  return performance.now() - t0;
}

const builds = { A: await load(dirA), B: await load(dirB) };
const times = {};
for (let i = 0; i < Number(runs); i++) {
  for (const [name, grammar] of Object.entries(grammars)) {
    for (const b of i % 2 ? ['B', 'A'] : ['A', 'B']) (times[name] ??= { A: [], B: [] })[b].push(grow(builds[b], grammar));
  }
}
const summary = (v) => {
  const s = [...v].sort((x, y) => x - y);
  return { min_ms: +s[0].toFixed(1), median_ms: +s[s.length >> 1].toFixed(1) };
};
const out = { A: path.resolve(dirA), B: path.resolve(dirB), runs: Number(runs), grammars: {} };
for (const [name, t] of Object.entries(times)) {
  out.grammars[name] = { A: summary(t.A), B: summary(t.B), B_over_A_min: +(Math.min(...t.B) / Math.min(...t.A)).toFixed(3) };
}
console.log(JSON.stringify(out, null, 1));
