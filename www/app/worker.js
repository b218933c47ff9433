// The one module worker: serves the protocol in protocol.js, loading each
// tool's wasm module the first time a job needs it (the page compiles it
// once and sends the WebAssembly.Module with the job). One job at a time per
// worker; the pool runs several workers.
import { MSG, SLICE_MS, moduleUrl, transferables } from './protocol.js';

// console_error_panic_hook writes the panic message with console.error just
// before the trap; keep it so the 'panic' reply can say what happened.
let lastConsoleError = '';
const consoleError = console.error.bind(console);
console.error = (...args) => {
  lastConsoleError = args.map(String).join(' ');
  consoleError(...args);
};

// name → Promise of the module's glue ({start_job, version}), instantiated once.
const cores = new Map();
const broken = new Set(); // modules whose instance threw something untyped

function core(name, wasm) {
  if (!cores.has(name)) {
    cores.set(name, (async () => {
      const glue = await import(moduleUrl(name, '.js'));
      await glue.default({ module_or_path: wasm ?? moduleUrl(name) });
      self.postMessage({ type: MSG.READY, version: glue.version(), module: name });
      return glue;
    })());
  }
  return cores.get(name);
}

const cancelled = new Set();
const waiting = new Map(); // id → resolve of a job paused on its `need`

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

async function run({ id, kind, payload, module, wasm }) {
  let glue;
  try {
    glue = await core(module, wasm);
  } catch (err) {
    cores.delete(module);
    self.postMessage({ type: MSG.PANIC, id, message: `the core could not load: ${err?.message ?? err}` });
    return;
  }
  if (broken.has(module)) {
    self.postMessage({ type: MSG.PANIC, id, message: 'the core crashed earlier in this worker' });
    return;
  }
  let job = null;
  try {
    job = glue.start_job(kind, payload);
    let sliceStart = performance.now();
    for (;;) {
      if (cancelled.delete(id)) {
        self.postMessage({ type: MSG.ERROR, id, error: { kind: 'cancelled', message: 'cancelled' } });
        return;
      }
      const r = job.step();
      if (r.need) {
        self.postMessage({ type: MSG.PROGRESS, id, progress: r.progress }, transferables(r.progress));
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
      // A progress with a picture is posted whatever the time (the job
      // bounds how often it draws one); any other at the slice's end.
      const sliceEnd = performance.now() - sliceStart >= SLICE_MS;
      if (sliceEnd || r.progress.picture) {
        self.postMessage({ type: MSG.PROGRESS, id, progress: r.progress }, transferables(r.progress));
      }
      if (sliceEnd) {
        await yieldToEventLoop();
        sliceStart = performance.now();
      }
    }
  } catch (err) {
    if (isCoreError(err)) {
      self.postMessage({ type: MSG.ERROR, id, error: err });
      return;
    }
    broken.add(module);
    // A panic writes its message to the console just before the trap.
    const why = (err instanceof WebAssembly.RuntimeError && lastConsoleError) || String(err);
    self.postMessage({ type: MSG.PANIC, id, message: `the core crashed: ${why}` });
  } finally {
    cancelled.delete(id);
    waiting.delete(id);
    if (job && !broken.has(module)) job.free();
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
