// Start-up benchmark (not a test): what a first visit costs, per view, in
// headless Chromium, each run from a fresh browser context (empty HTTP
// cache) with the service worker blocked (its precache would download
// everything). Prints one JSON object.
//
//   node scripts/bench-startup.mjs [runs=3] [root=this checkout]
//
// `root` is a directory served as the app, e.g. a copy of an older build to
// compare with.
//
// Cases: each tool (`#tool=<id>`), the home view (no tool) and an embed
// (`?embed=1#tool=pixel`, Pixel's default example without the chrome). For
// each: the bytes over the network (encoded bodies: gzipped where the
// server gzips, 0 for a 304) until the core is ready (a worker reported its
// wasm loaded: html[data-core-ready=1]) and once the network has been quiet
// for QUIET_MS, the wasm bytes among them and which pkg/*.wasm were fetched
// (with how many requests, and how many of them downloaded it: more than
// one download is a file sent twice), and the time from navigation to core
// ready (the bytes "at ready" are those of the requests finished when the
// benchmark sees it, a few milliseconds later). The home view loads no core: bytes
// only, and it is a failure if it fetched any wasm. Also each module's raw
// and gzipped size (gzip -9); a module not built yet is null.
//
// Exits non-zero, after printing, when a case failed (not ready in time,
// page errors, wasm on the home view); the other cases are still measured.
import fs from 'node:fs';
import path from 'node:path';
import zlib from 'node:zlib';
import { launch, ROOT } from '../tests/e2e/harness.mjs';

const runs = Number(process.argv[2] || 3);
const root = path.resolve(process.argv[3] || ROOT);
const TOOLS = ['pixel', 'fit', 'inspect', 'tangle', 'micro', 'texture'];
const MODULES = ['inspect', 'pixel', 'fit', 'tangle', 'tangle-png', 'micro', 'texture'];
const CASES = [
  ...TOOLS.map((id) => ({ name: id, path: `#tool=${id}`, core: true })),
  { name: 'home', path: '', core: false },
  { name: 'embed', path: '?embed=1#tool=pixel', core: true },
];
const READY_TIMEOUT_MS = 60000;
const QUIET_MS = 1000; // no request in flight for this long: the page has settled
const SETTLE_TIMEOUT_MS = 30000;

/** Raw and gzip -9 sizes of a file of the served root, or null when it does not exist. */
function sizes(rel) {
  const file = path.join(root, rel);
  if (!fs.existsSync(file)) return null;
  const bytes = fs.readFileSync(file);
  return { raw: bytes.length, gzip: zlib.gzipSync(bytes, { level: 9 }).length };
}

/**
 * Every request of `context` (pages and their workers): a log of finished
 * ones ({path, bytes}, bytes = encoded body received, 0 when failed), and
 * the number in flight.
 */
function watchNetwork(context) {
  const log = [];
  const pending = new Set();
  let inFlight = 0;
  let lastChange = Date.now();
  const done = (req, failed) => {
    inFlight--;
    lastChange = Date.now();
    const rel = new URL(req.url()).pathname;
    const p = (failed ? Promise.reject(new Error('failed')) : req.sizes()).then(
      (s) => log.push({ path: rel, bytes: Math.max(0, s.responseBodySize) }),
      () => log.push({ path: rel, bytes: 0 }));
    pending.add(p);
    p.finally(() => pending.delete(p));
  };
  context.on('request', () => { inFlight++; lastChange = Date.now(); });
  context.on('requestfinished', (req) => done(req, false));
  context.on('requestfailed', (req) => done(req, true));
  return {
    /** The finished requests so far (waits for their sizes). */
    async snapshot() {
      await Promise.all([...pending]);
      return [...log];
    },
    /** Resolves once nothing has been in flight for QUIET_MS (or after SETTLE_TIMEOUT_MS). */
    async quiet() {
      const t0 = Date.now();
      while (Date.now() - t0 < SETTLE_TIMEOUT_MS) {
        if (inFlight <= 0 && Date.now() - lastChange >= QUIET_MS) return true;
        await new Promise((r) => setTimeout(r, 100));
      }
      return false;
    },
  };
}

/**
 * Totals of a request log: bytes, wasm bytes, and per wasm file its fetches,
 * how many of them downloaded it (a body came over the network: not a
 * revalidation answered 304, which Chromium reports as a 200 from its
 * cache), and its bytes.
 */
function totals(log) {
  const wasm = {};
  let bytes = 0;
  let wasmBytes = 0;
  for (const { path: p, bytes: b } of log) {
    bytes += b;
    if (!p.endsWith('.wasm')) continue;
    wasmBytes += b;
    const name = p.slice(p.lastIndexOf('/pkg/') + 1);
    wasm[name] ??= { fetches: 0, downloads: 0, bytes: 0 };
    wasm[name].fetches++;
    if (b > 0) wasm[name].downloads++;
    wasm[name].bytes += b;
  }
  return { requests: log.length, bytes, wasmBytes, wasm };
}

async function runCase(env, c) {
  const page = await env.newPage({ path: null, serviceWorkers: 'block' });
  const context = page.context();
  const net = watchNetwork(context);
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  try {
    // Note the moment the shell marks the core ready, without polling.
    await page.addInitScript(() => {
      new MutationObserver((_, obs) => {
        if (document.documentElement.dataset.coreReady === '1') {
          window.__coreReadyAt = performance.now();
          obs.disconnect();
        }
      }).observe(document, { subtree: true, attributes: true, attributeFilter: ['data-core-ready'] });
    });
    await page.goto(env.url + c.path);
    const sample = {};
    if (c.core) {
      await page.waitForFunction(() => window.__coreReadyAt !== undefined, null, { timeout: READY_TIMEOUT_MS });
      sample.readyMs = await page.evaluate(() => window.__coreReadyAt);
      sample.atReady = totals(await net.snapshot());
    } else {
      await page.waitForFunction(() => document.documentElement.dataset.view === 'home', null, { timeout: READY_TIMEOUT_MS });
    }
    sample.settledInTime = await net.quiet();
    sample.settled = totals(await net.snapshot());
    sample.firstPaintMs = await page.evaluate(() => performance.getEntriesByName('first-paint')[0]?.startTime ?? null);
    if (errors.length) sample.pageErrors = errors;
    return sample;
  } catch (err) {
    return { error: String(err.message || err).split('\n')[0], pageErrors: errors, settled: totals(await net.snapshot()) };
  } finally {
    await context.close();
  }
}

const median = (xs) => {
  const s = xs.filter((x) => typeof x === 'number').sort((a, b) => a - b);
  return s.length ? s[Math.floor(s.length / 2)] : null;
};

/** Medians of a case's samples, the wasm files any run fetched, and its failures. */
function summarise(c, samples) {
  const ok = samples.filter((s) => !s.error);
  const wasmFiles = {};
  for (const s of ok) {
    for (const [name, w] of Object.entries(s.settled.wasm)) {
      const most = wasmFiles[name] ?? { fetches: 0, downloads: 0 };
      wasmFiles[name] = { fetches: Math.max(most.fetches, w.fetches), downloads: Math.max(most.downloads, w.downloads) };
    }
  }
  const failures = samples.filter((s) => s.error).map((s) => s.error);
  for (const s of ok) failures.push(...(s.pageErrors ?? []).map((e) => `page error: ${e}`));
  if (!c.core && Object.keys(wasmFiles).length) failures.push(`the home view fetched wasm: ${Object.keys(wasmFiles).join(', ')}`);
  const out = {
    path: c.path,
    ...(c.core ? {
      readyMsMedian: median(ok.map((s) => s.readyMs)),
      bytesAtReadyMedian: median(ok.map((s) => s.atReady.bytes)),
      wasmBytesAtReadyMedian: median(ok.map((s) => s.atReady.wasmBytes)),
    } : {}),
    bytesSettledMedian: median(ok.map((s) => s.settled.bytes)),
    wasmBytesSettledMedian: median(ok.map((s) => s.settled.wasmBytes)),
    requestsSettledMedian: median(ok.map((s) => s.settled.requests)),
    firstPaintMsMedian: median(ok.map((s) => s.firstPaintMs)),
    // pkg/*.wasm fetched → the most requests for it in one run, and the most
    // of them that downloaded it.
    wasmFiles,
    failures,
    samples,
  };
  return out;
}

const modules = Object.fromEntries(MODULES.map((m) => [m, sizes(`pkg/filigree_${m}_bg.wasm`)]));
const single = sizes('pkg/filigree_bg.wasm'); // the one core before the per-tool split

const env = await launch({ root });
const cases = {};
try {
  const samples = Object.fromEntries(CASES.map((c) => [c.name, []]));
  // Runs interleave the cases, so a slow moment of the machine is spread over all of them.
  for (let i = 0; i < runs; i++) {
    for (const c of CASES) samples[c.name].push(await runCase(env, c));
  }
  for (const c of CASES) cases[c.name] = summarise(c, samples[c.name]);
} finally {
  await env.close();
}

const failed = Object.entries(cases).filter(([, c]) => c.failures.length).map(([name]) => name);
console.log(JSON.stringify({
  bench: 'startup',
  runs,
  root,
  wasm: { modules, single },
  cases,
  failed,
}));
if (failed.length) process.exitCode = 1;
