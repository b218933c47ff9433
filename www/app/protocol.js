// The worker protocol, documented once. Every message is a plain object.
//
// Page → worker
//   {type: 'run', id, kind, payload, module, wasm}
//                                      start a job in the wasm module `module`
//                                      (a tool's: MODULE_KINDS below), whose
//                                      compiled WebAssembly.Module the page
//                                      sends as `wasm` (compiled once per page,
//                                      shared by every worker); `kind` is a request kind the
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
//   {type: 'ready', version, module}   a tool's wasm module is loaded.
//   {type: 'progress', id, progress: {fraction, stage, figure, values?, picture?}}
//                                      at most every ~15 ms while a job runs, and
//                                      whenever it carries a `picture` (of `values`:
//                                      {width, height, rgba}, its buffer transferred;
//                                      a `fit` with `preview` draws one at most every
//                                      PREVIEW_EVERY_STEPS steps, src/pattern/api.rs).
//   {type: 'need', id, need}           the job must exchange data with sibling
//                                      jobs (e.g. one fit sharded over the pool)
//                                      and pauses until an 'input' arrives.
//   {type: 'result', id, result}       the job finished; typed arrays in
//                                      `result` arrive as transferred buffers.
//   {type: 'error', id, error: {kind, message, line?, column?, field?}}
//                                      the job failed. The core's typed error,
//                                      passed on untouched:
//                                        kind    'invalid-input' | 'bad-request' | 'limit' |
//                                                'unsupported' (valid, but not this
//                                                way: the GPU, where the CPU can) |
//                                                'syntax' | 'cancelled'
//                                        message the whole text, for people
//                                        line, column  1-based place in a text
//                                                (in `field`) of a syntax error, or
//                                                of a limit met there
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

// The wasm modules, one per tool: the kinds only that module serves
// (src/api/mod.rs `Module::kinds`; tests/modules.rs checks this table
// against it). Every module also serves SHARED_KINDS.
export const MODULE_KINDS = Object.freeze({
  inspect: ['inspect', 'decode-image'],
  pixel: ['pixel', 'pixel-mask'],
  fit: ['fit', 'fit-eval', 'render-pattern', 'pattern-info', 'pattern-generators', 'pattern-snap'],
  tangle: ['tangle', 'tangle-examples'],
  // Tangle's PNG export (www/tangle/export.js), loaded on the first export.
  'tangle-png': ['tangle-png'],
  micro: ['micro-render', 'micro-slice', 'micro-examples', 'micro-fit', 'micro-glsl'],
  texture: ['texture-models', 'texture-render', 'texture-index', 'texture-analyse', 'texture-retrieve'],
});
export const SHARED_KINDS = Object.freeze(['defaults', 'check-state', 'open-project']);
// The modules that also serve the Inspect module's kinds (they read the
// user's image files as they are; src/api/mod.rs `Module::images`). Fit,
// Micro and Texture send PNG the page made (the browser decodes the user's
// file), so their modules have the PNG decoder only.
export const IMAGE_MODULES = Object.freeze(['inspect', 'pixel']);

/** The module of a request kind; null for a shared (or unknown) kind. */
export function moduleOfKind(kind) {
  for (const [m, kinds] of Object.entries(MODULE_KINDS)) if (kinds.includes(kind)) return m;
  return null;
}

/**
 * The module that runs `kind` with `payload`: the kind's own; for `defaults
 * {tool}` the module of that kind; for `check-state {tool}` that tool's (a
 * module checks only its own tool's documents); else `fallback` (the caller's
 * tool, so a shared kind never loads another module), or 'inspect'. An image
 * kind ('inspect', 'decode-image') runs in the caller's module when it reads
 * images (IMAGE_MODULES).
 */
export function moduleFor(kind, payload, fallback) {
  const own = moduleOfKind(kind);
  if (own === 'inspect' && IMAGE_MODULES.includes(fallback)) return fallback;
  if (own) return own;
  if (kind === 'defaults') return moduleOfKind(payload?.tool) ?? fallback ?? 'inspect';
  if (kind === 'check-state' && Object.hasOwn(MODULE_KINDS, payload?.tool)) return payload.tool;
  return fallback ?? 'inspect';
}

/** The URL of a module's wasm (its JS glue is `filigree_<name>.js` beside it). */
export const moduleUrl = (name, ext = '_bg.wasm') => new URL(`../../pkg/filigree_${name}${ext}`, import.meta.url);

// Wall-clock budget of one run of slices before the worker yields.
export const SLICE_MS = 15;

/** An error reported by a job; `kind` is 'invalid-input', 'bad-request' (the request could not be read: the page's fault), 'limit', 'unsupported', 'syntax', 'cancelled', 'crash' or 'protocol'.
 * `line`/`column` place an error in a text (a syntax error, or a limit a program met at a statement), `field` names the request field at fault (undefined when unknown). */
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
