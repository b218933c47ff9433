// The one module worker: loads the wasm core and serves the protocol in
// protocol.js. One job at a time per worker; the pool runs several workers.
import init, { start_job, version } from '../pkg/filigree.js';
import { MSG, SLICE_MS, transferables } from './protocol.js';

// console_error_panic_hook writes the panic message with console.error just
// before the trap; keep it so the 'panic' reply can say what happened.
let lastConsoleError = '';
const consoleError = console.error.bind(console);
console.error = (...args) => {
  lastConsoleError = args.map(String).join(' ');
  consoleError(...args);
};

// The core is built with WebAssembly SIMD; this smallest SIMD function
// (i8x16.splat, i8x16.popcnt) validates only where SIMD is supported.
const SIMD_PROBE = new Uint8Array([0, 97, 115, 109, 1, 0, 0, 0, 1, 5, 1, 96, 0, 1, 123, 3, 2, 1, 0, 10, 10, 1, 8, 0, 65, 0, 253, 15, 253, 98, 11]);
const ready = init({ module_or_path: new URL('../pkg/filigree_bg.wasm', import.meta.url) }).then(() => {
  self.postMessage({ type: MSG.READY, version: version() });
}, (err) => {
  throw WebAssembly.validate(SIMD_PROBE) ? err
    : new Error('this browser cannot run the core: it needs WebAssembly SIMD (Chrome 91+, Firefox 89+, Safari 16.4+)');
});

const cancelled = new Set();
const waiting = new Map(); // id → resolve of a job paused on its `need`
let broken = false;

// A macrotask yield that is not clamped like nested setTimeout(0).
function yieldToEventLoop() {
  return new Promise((resolve) => {
    const ch = new MessageChannel();
    ch.port1.onmessage = () => resolve();
    ch.port2.postMessage(null);
  });
}

// The core throws its errors as plain objects {kind, message, line?, column?,
// field?} (protocol.js); they are passed on untouched. Anything else thrown
// while the instance runs (a WebAssembly.RuntimeError trap, a RangeError
// "Maximum call stack size exceeded", a TypeError in the glue) may have left
// the instance half-way through a call: it is never used again.
function isCoreError(err) {
  return err !== null && typeof err === 'object' && !(err instanceof Error)
    && typeof err.kind === 'string' && typeof err.message === 'string';
}

async function run({ id, kind, payload }) {
  try {
    await ready;
  } catch (err) {
    self.postMessage({ type: MSG.PANIC, id, message: `the core could not load: ${err?.message ?? err}` });
    return;
  }
  if (broken) {
    self.postMessage({ type: MSG.PANIC, id, message: 'the core crashed earlier in this worker' });
    return;
  }
  let job = null;
  try {
    job = start_job(kind, payload);
    let sliceStart = performance.now();
    for (;;) {
      if (cancelled.delete(id)) {
        self.postMessage({ type: MSG.ERROR, id, error: { kind: 'cancelled', message: 'cancelled' } });
        return;
      }
      const r = job.step();
      if (r.need) {
        self.postMessage({ type: MSG.PROGRESS, id, progress: r.progress });
        self.postMessage({ type: MSG.NEED, id, need: r.need });
        const data = await new Promise((resolve) => waiting.set(id, resolve));
        // A cancel wakes the job with no data (read at the top of the loop);
        // anything else must be every shard's part, or provide() says why.
        if (!cancelled.has(id)) job.provide(data ?? []);
        sliceStart = performance.now();
        continue;
      }
      if (r.done) {
        self.postMessage({ type: MSG.RESULT, id, result: r.result }, transferables(r.result));
        return;
      }
      if (performance.now() - sliceStart >= SLICE_MS) {
        self.postMessage({ type: MSG.PROGRESS, id, progress: r.progress });
        await yieldToEventLoop();
        sliceStart = performance.now();
      }
    }
  } catch (err) {
    if (isCoreError(err)) {
      self.postMessage({ type: MSG.ERROR, id, error: err });
      return;
    }
    broken = true;
    // A panic writes its message to the console just before the trap.
    const why = (err instanceof WebAssembly.RuntimeError && lastConsoleError) || String(err);
    self.postMessage({ type: MSG.PANIC, id, message: `the core crashed: ${why}` });
  } finally {
    cancelled.delete(id);
    waiting.delete(id);
    if (job && !broken) job.free();
  }
}

self.onmessage = (e) => {
  const msg = e.data;
  if (msg.type === MSG.CANCEL) {
    cancelled.add(msg.id);
    waiting.get(msg.id)?.(null); // a paused job wakes up to see the cancel
  } else if (msg.type === MSG.INPUT) {
    waiting.get(msg.id)?.(msg.data);
    waiting.delete(msg.id);
  } else if (msg.type === MSG.RUN) run(msg);
};
