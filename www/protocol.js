// The worker protocol, documented once. Every message is a plain object.
//
// Page → worker
//   {type: 'run', id, kind, payload}   start a job; `kind` is a request kind the
//                                      core knows ('inspect', 'pixel', 'fit', ...);
//                                      byte inputs are Uint8Arrays whose buffers
//                                      are transferred, not copied.
//                                      Kinds and payloads: src/api/mod.rs (KINDS)
//                                      and each tool's src/<tool>/api.rs. Missing
//                                      payload fields take the defaults of the
//                                      request type; {kind: 'defaults',
//                                      payload: {tool}} answers {tool, request,
//                                      budgets?}: that kind's default request.
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
//   {type: 'error', id, error: {kind, message, line?, column?, field?}}
//                                      the job failed. The core's typed error,
//                                      passed on untouched:
//                                        kind    'invalid-input' | 'limit' |
//                                                'syntax' | 'cancelled'
//                                        message the whole text, for people
//                                        line, column  1-based place of a
//                                                syntax error (in `field`)
//                                        field   dotted path of the request
//                                                field at fault, e.g.
//                                                'program', 'tolerance',
//                                                'params.d_max', 'points.3'
//                                      The page adds 'crash' and 'protocol'.
//   {type: 'panic', id, message}       the core crashed: a wasm trap, or any
//                                      other exception thrown from the
//                                      instance that is not a typed error
//                                      (e.g. RangeError: Maximum call stack
//                                      size exceeded). The worker is unusable;
//                                      the pool terminates and replaces it. A
//                                      worker that dies without a word
//                                      ('error' event) is treated alike.
export const MSG = Object.freeze({
  RUN: 'run', CANCEL: 'cancel', INPUT: 'input',
  READY: 'ready', PROGRESS: 'progress', NEED: 'need', RESULT: 'result', ERROR: 'error', PANIC: 'panic',
});

// Wall-clock budget of one run of slices before the worker yields.
export const SLICE_MS = 15;

/** An error reported by a job; `kind` is 'invalid-input', 'limit', 'syntax', 'cancelled', 'crash' or 'protocol'.
 * `line`/`column` place a syntax error, `field` names the request field at fault (undefined when unknown). */
export class JobError extends Error {
  constructor(message, kind = 'invalid-input', { line, column, field } = {}) {
    super(message);
    this.name = 'JobError';
    this.kind = kind;
    this.line = line;
    this.column = column;
    this.field = field;
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
