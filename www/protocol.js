// The worker protocol, documented once. Every message is a plain object.
//
// Page → worker
//   {type: 'run', id, kind, payload}   start a job; `kind` is a request kind the
//                                      core knows ('inspect', 'pixel', 'fit', ...);
//                                      byte inputs are Uint8Arrays whose buffers
//                                      are transferred, not copied.
//   {type: 'cancel', id}               stop job `id` at its next slice boundary
//                                      (read within ~15 ms of wall time).
//   {type: 'input', id, data}          the answer to the job's `need` (below):
//                                      every sibling shard's `need`, in shard
//                                      order (WorkerPool.runSharded relays them;
//                                      the core merges, the page never does).
//
// Worker → page
//   {type: 'ready', version}           the wasm core is loaded.
//   {type: 'progress', id, progress: {fraction, stage, figure}}
//                                      at most every ~15 ms while a job runs.
//   {type: 'need', id, need}           the job must exchange data with sibling
//                                      jobs (e.g. one fit sharded over the pool)
//                                      and pauses until an 'input' arrives.
//   {type: 'result', id, result}       the job finished; typed arrays in
//                                      `result` arrive as transferred buffers.
//   {type: 'error', id, error: {kind, message}}
//                                      the job failed: bad input, a limit, a
//                                      syntax error, or kind 'cancelled'.
//   {type: 'panic', id, message}       the core crashed (wasm trap). The worker
//                                      is unusable; the pool terminates and
//                                      replaces it. A worker that dies without
//                                      a word ('error' event) is treated alike.
export const MSG = Object.freeze({
  RUN: 'run', CANCEL: 'cancel', INPUT: 'input',
  READY: 'ready', PROGRESS: 'progress', NEED: 'need', RESULT: 'result', ERROR: 'error', PANIC: 'panic',
});

// Wall-clock budget of one run of slices before the worker yields.
export const SLICE_MS = 15;

/** An error reported by a job; `kind` is 'invalid-input', 'limit', 'syntax', 'cancelled', 'crash' or 'protocol'. */
export class JobError extends Error {
  constructor(message, kind = 'invalid-input') {
    super(message);
    this.name = 'JobError';
    this.kind = kind;
  }
}

/** Every ArrayBuffer reachable in `value` (for postMessage transfer lists). */
export function transferables(value, out = new Set()) {
  if (value instanceof ArrayBuffer) out.add(value);
  else if (ArrayBuffer.isView(value)) out.add(value.buffer);
  else if (Array.isArray(value)) value.forEach((v) => transferables(v, out));
  else if (value && typeof value === 'object') Object.values(value).forEach((v) => transferables(v, out));
  return [...out];
}
