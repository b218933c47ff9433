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

const ready = init({ module_or_path: new URL('../pkg/filigree_bg.wasm', import.meta.url) }).then(() => {
  self.postMessage({ type: MSG.READY, version: version() });
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

function errorKind(message) {
  if (/exceeds|limit/i.test(message)) return 'limit';
  if (/line \d+, column \d+/.test(message)) return 'syntax';
  return 'invalid-input';
}

function isTrap(err) {
  return err instanceof WebAssembly.RuntimeError;
}

async function run({ id, kind, payload }) {
  await ready;
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
    if (isTrap(err)) {
      broken = true;
      const why = lastConsoleError || String(err);
      self.postMessage({ type: MSG.PANIC, id, message: `the core crashed: ${why}` });
      return;
    }
    const message = err && err.message ? err.message : String(err);
    self.postMessage({ type: MSG.ERROR, id, error: { kind: errorKind(message), message } });
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
