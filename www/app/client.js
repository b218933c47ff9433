// Main-thread side of the worker protocol: a pool of module workers, each
// with its own single-threaded wasm instances (no SharedArrayBuffer, so the
// app embeds anywhere). Workers start lazily and are replaced when they crash.
// The core is one wasm module per tool (protocol.js MODULE_KINDS): the pool
// fetches and compiles a module the first time a job needs it, once per
// page, and hands the compiled WebAssembly.Module to each worker with the
// job, so a page downloads only the tools it uses, each once (several embeds
// on a page share the download through the HTTP cache).
//
//   const result = await pool.run('inspect', {bytes}, {onProgress, signal, module});
import { MSG, JobError, moduleFor, moduleUrl, transferables } from './protocol.js';

const WORKER_URL = new URL('./worker.js', import.meta.url);
// After a cancel, a job has this long to stop at a slice boundary before
// its worker is terminated (the hard stop).
const HARD_STOP_MS = 1000;

// The core is built with WebAssembly SIMD; this smallest SIMD function
// (i8x16.splat, i8x16.popcnt) validates only where SIMD is supported.
const SIMD_PROBE = new Uint8Array([0, 97, 115, 109, 1, 0, 0, 0, 1, 5, 1, 96, 0, 1, 123, 3, 2, 1, 0, 10, 10, 1, 8, 0, 65, 0, 253, 15, 253, 98, 11]);

/** Fetch and compile a tool's wasm module (streaming where the server allows). */
async function compileModule(name) {
  if (!WebAssembly.validate(SIMD_PROBE)) {
    throw new Error('this browser cannot run the core: it needs WebAssembly SIMD (Chrome 91+, Firefox 89+, Safari 16.4+)');
  }
  const res = await fetch(moduleUrl(name));
  if (!res.ok) throw new Error(`${name} module: the server answered ${res.status}`);
  if (WebAssembly.compileStreaming && res.headers.get('content-type')?.startsWith('application/wasm')) {
    return WebAssembly.compileStreaming(res);
  }
  return WebAssembly.compile(await res.arrayBuffer());
}

/** A JobError from the worker's `{kind, message, line?, column?, field?}`. */
function jobError(e) {
  return new JobError(String(e?.message ?? 'the job failed'), e?.kind || 'invalid-input', e ?? {});
}

class Slot {
  constructor(pool, index) {
    this.pool = pool;
    this.index = index;
    this.worker = null;
    this.job = null; // {id, resolve, reject, onProgress, hardStop}
    this.version = null;
    this.affinity = null; // the `affinity` of the last job started here (see WorkerPool.run)
  }

  ensureWorker() {
    if (this.worker) return;
    const w = new Worker(WORKER_URL, { type: 'module', name: `filigree-${this.index}` });
    w.onmessage = (e) => this.onMessage(e.data);
    w.onerror = (e) => {
      e.preventDefault?.();
      this.crash(`the worker stopped: ${e.message || 'failed to load'}`);
    };
    w.onmessageerror = () => this.crash('a message from the worker could not be read');
    this.worker = w;
  }

  onMessage(msg) {
    if (msg.type === MSG.READY) {
      this.version = msg.version;
      this.pool.onReady?.(msg.version);
      return;
    }
    const job = this.job;
    if (!job || msg.id !== job.id) return;
    if (msg.type === MSG.PROGRESS) job.onProgress?.(msg.progress);
    else if (msg.type === MSG.NEED) this.answer(job, msg.need);
    else if (msg.type === MSG.RESULT) this.finish(() => job.resolve(msg.result));
    else if (msg.type === MSG.ERROR) this.finish(() => job.reject(jobError(msg.error)));
    else if (msg.type === MSG.PANIC) this.crash(msg.message);
  }

  finish(settle) {
    clearTimeout(this.job?.hardStop);
    this.job?.cleanup?.();
    this.job = null;
    settle();
    this.pool.dispatch();
  }

  // Terminate and forget the worker; the next job on this slot starts a fresh one.
  crash(message) {
    this.worker?.terminate();
    this.worker = null;
    this.affinity = null;
    const job = this.job;
    if (job) this.finish(() => job.reject(new JobError(`${message}. The worker was restarted; try again.`, 'crash')));
    this.pool.onCrash?.(message);
  }

  // A job asked for data (see protocol.js 'need'): get it from the caller's onNeed.
  async answer(job, need) {
    try {
      if (!job.onNeed) throw new JobError('the job asked for data but the caller gave no onNeed', 'protocol');
      const data = await job.onNeed(need);
      if (this.job === job) this.worker.postMessage({ type: MSG.INPUT, id: job.id, data });
    } catch (err) {
      if (this.job !== job) return;
      this.worker.postMessage({ type: MSG.CANCEL, id: job.id });
      this.finish(() => job.reject(err));
    }
  }

  start(req) {
    this.ensureWorker();
    this.job = req;
    if (req.affinity) this.affinity = req.affinity;
    const { id, kind, payload, module, wasm } = req;
    this.worker.postMessage({ type: MSG.RUN, id, kind, payload, module, wasm }, req.transfer ?? transferables(payload));
  }

  cancel() {
    const job = this.job;
    if (!job) return;
    this.worker.postMessage({ type: MSG.CANCEL, id: job.id });
    job.hardStop = setTimeout(() => {
      if (this.job !== job) return;
      this.worker.terminate();
      this.worker = null;
      this.affinity = null;
      this.finish(() => job.reject(new JobError('cancelled (the worker was stopped)', 'cancelled')));
    }, HARD_STOP_MS);
  }
}

export class WorkerPool {
  /** `size` workers at most; `onCrash(message)` and `onReady(version)` are optional hooks. */
  constructor({ size = defaultSize(), onCrash, onReady } = {}) {
    this.slots = Array.from({ length: size }, (_, i) => new Slot(this, i));
    this.queue = [];
    this.nextId = 1;
    this.onCrash = onCrash;
    this.onReady = onReady;
    this.modules = new Map(); // name → Promise<WebAssembly.Module>
  }

  /** Start the first worker now (no wasm: a module loads with its first job). */
  warm() {
    this.slots[0].ensureWorker();
  }

  /**
   * Load module `name` into a worker now (a trivial job in it), so the tool
   * the user opened is ready before its first real job. Errors are left to
   * that job to report.
   */
  preload(name) {
    this.run('defaults', { tool: 'defaults' }, { module: name }).catch(() => {});
  }

  /** The compiled module `name` (fetched and compiled once; a failure is retried next time). */
  module(name) {
    if (!this.modules.has(name)) {
      const p = compileModule(name);
      p.catch(() => this.modules.delete(name));
      this.modules.set(name, p);
    }
    return this.modules.get(name);
  }

  /**
   * Run a job. Resolves with its result or rejects with a JobError
   * (kind 'cancelled' when `signal` aborts it).
   * @param {string} kind @param {object} payload
   * `onNeed(data)` answers a job that must exchange data mid-way (async is fine).
   * `affinity` (a string): run on the worker that last ran a job with the same
   * affinity, waiting for it if it is busy with one, so state the core keeps in
   * its instance (a `tangle` request's `keep`) is there for the next request.
   * Only a speed-up: any worker gives the same answer.
   * `module`: the tool module that runs a shared kind (protocol.js moduleFor;
   * a tool's own kinds always run in its module).
   * @param {{onProgress?: Function, onNeed?: Function, signal?: AbortSignal, transfer?: ArrayBuffer[], affinity?: string, module?: string}} [opts]
   */
  run(kind, payload, { onProgress, onNeed, signal, transfer, affinity, module } = {}) {
    return new Promise((resolve, reject) => {
      if (signal?.aborted) {
        reject(new JobError('cancelled', 'cancelled'));
        return;
      }
      const name = moduleFor(kind, payload, module);
      const req = { id: this.nextId++, kind, payload, module: name, transfer, affinity, onProgress, onNeed, resolve, reject };
      if (signal) {
        const onAbort = () => this.abort(req);
        signal.addEventListener('abort', onAbort, { once: true });
        req.cleanup = () => signal.removeEventListener('abort', onAbort);
      }
      this.module(name).then((wasm) => {
        if (req.aborted) return;
        req.wasm = wasm;
        this.queue.push(req);
        this.dispatch();
      }, (err) => {
        if (req.aborted) return;
        req.cleanup?.();
        const message = `the core could not load: ${err?.message ?? err}`;
        reject(new JobError(`${message}. Reload the page to try again.`, 'crash'));
        this.onCrash?.(message);
      });
    });
  }

  /**
   * Run one job split into `shards` sibling jobs (shard k gets the payload
   * plus `shards: [k, n]`) and relay their exchanges: when every shard has
   * posted its `need`, each one gets the list of all parts in shard order
   * (an all-gather). The page never merges anything; the core does (see
   * src/core/parallel.rs, whose native driver relays the same way). Every
   * shard ends with the same merged result; resolves with shard 0's.
   * `onProgress(progress, k)` reports each shard.
   * @param {{shards?: number, onProgress?: Function, signal?: AbortSignal}} [opts]
   */
  async runSharded(kind, payload, { shards, onProgress, signal } = {}) {
    const n = Math.max(1, shards ?? this.slots.length - 1);
    const inner = new AbortController();
    const abort = () => inner.abort();
    if (signal?.aborted) abort();
    signal?.addEventListener('abort', abort, { once: true });
    let round = [];
    let handed = 0;
    const relay = (k, part) => new Promise((resolve) => {
      round[k] = { part, resolve };
      if (++handed < n) return;
      const waiting = round;
      round = [];
      handed = 0;
      const parts = waiting.map((r) => r.part);
      for (const r of waiting) r.resolve(parts);
    });
    try {
      const results = await Promise.all(Array.from({ length: n }, (_, k) => this.run(kind, { ...payload, shards: [k, n] }, {
        signal: inner.signal,
        // The shards share the payload's buffers: copy them, never transfer.
        transfer: [],
        onNeed: (need) => relay(k, need),
        onProgress: (p) => { if (!inner.signal.aborted) onProgress?.(p, k); },
      }).catch((err) => { inner.abort(); throw err; })));
      return results[0];
    } finally {
      signal?.removeEventListener('abort', abort);
    }
  }

  abort(req) {
    if (!req.wasm) {
      // Still waiting for its module: it never reaches a worker.
      req.aborted = true;
      req.cleanup?.();
      req.reject(new JobError('cancelled', 'cancelled'));
      return;
    }
    const queued = this.queue.indexOf(req);
    if (queued >= 0) {
      this.queue.splice(queued, 1);
      req.cleanup?.();
      req.reject(new JobError('cancelled', 'cancelled'));
      return;
    }
    this.slots.find((s) => s.job === req)?.cancel();
  }

  /** Start queued jobs on free workers, in order; see `run` for `affinity`. */
  dispatch() {
    for (let q = 0; q < this.queue.length;) {
      const req = this.queue[q];
      const free = this.slots.filter((s) => !s.job);
      if (!free.length) return;
      const home = req.affinity ? this.slots.find((s) => s.affinity === req.affinity) : null;
      let slot;
      if (home && !home.job) slot = home;
      else if (home && home.job.affinity === req.affinity) { q++; continue; } // wait for its worker
      // Otherwise a free worker, keeping those that hold another job's state free.
      else slot = free.find((s) => !s.affinity) ?? free[0];
      this.queue.splice(q, 1);
      slot.start(req);
    }
  }

  /** Jobs running or waiting. */
  get pending() {
    return this.queue.length + this.slots.filter((s) => s.job).length;
  }
}

function defaultSize() {
  // Each worker holds its own wasm instance: one per core for parallel work
  // (a sharded fit uses all but one), plus one so quick jobs (previews) never
  // wait behind a long one; four at most to bound memory.
  const cores = navigator.hardwareConcurrency || 2;
  return Math.max(2, Math.min(4, cores + 1));
}
