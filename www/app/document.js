// The document controller: ONE place for what every tool needs around its
// state — undo/redo (drags coalesced), autosave to IndexedDB, project files
// (validated, versioned, migrated), share links, keyboard shortcuts, error
// display, and the lifecycle of a mounted panel. A tool adds no glue: it
// declares its state and its view.
//
// The state's schema lives in the core (src/api/project.rs and each tool's
// src/<tool>/state.rs): every document that comes from outside the page's
// own edits (an autosave, a project file, a link) is checked there, field by
// field, with the core's own limits (`check-state`, `open-project`). An
// older state version is migrated here first (the panel's `migrate`), then
// checked by the core; the core refuses any version but the current one.
//
//   export default {
//     id: 'pixel', title: 'Pixel',
//     state: {
//       version: 1,                         // schema version of the state
//       async defaults(ctx) → state,        // a fresh document (ctx.coreDefaults() for the core's defaults)
//       migrate(raw, fromVersion) → raw,    // an older schema → the current one (before the core's check)
//       async? toShare(state) → shareState, // what a link carries (throw Error to refuse)
//       shareLean?(state) → {state, omits} | null,  // when the link would pass share.js's
//                                           // MAX_FRAGMENT: the state without its big inputs,
//                                           // `omits` saying what ('the example'); said before copying
//       async fromShare?(shareState, ctx) → raw state (then checked by the core),
//     },
//     mount(el, ctx) → view,                // build the DOM once; view = {render, markError?, keys?, unmount?}
//   }
//   view.render(state, previous)            // after every change (commit, undo, redo, load); diff by identity
//   view.markError?(err)                    // e.g. put the editor cursor at err.line/err.column
//   view.keys?                              // {s: () => …}: single-key shortcuts (no modifier held)
//   async view.drop?(file)                  // a file dropped anywhere in the window that is not a
//                                           // project (those the controller opens in any tool):
//                                           // check it, then commit it; throw an Error in plain words
//                                           // to refuse it (the document stays). A panel that takes
//                                           // images through ui/file-input.js (acceptFiles) needs none.
//
// ctx (one per mount; dead once the panel is left):
//   ctx.state()                  the current document
//   ctx.commit(next, {coalesce}) a new undoable document; same `coalesce` key in a row = one step
//   ctx.seal()                   end a coalesced drag
//   ctx.run(kind, payload, opts) pool.run tied to the panel: leaving aborts it; a result
//                                arriving after leaving rejects as 'cancelled'
//   ctx.startJob(name, {label, quietMs}, body) a long job of the DOCUMENT (a fit, a reconstruction, a
//                                tangle's growth): body(job) runs on when the panel is left, the
//                                tool bar shows its progress, and it is there when the panel comes
//                                back; see DocJob below. Starting one stops the last of that name.
//   ctx.job(name)                that job (running or finished), or null
//   ctx.follow(job, fn)          fn(job) on each of its changes while the panel is mounted
//   ctx.memory                   an object of the tool's that outlives its panel (not saved):
//                                what the user left in a form that is not the document
//   ctx.signal                   aborts when the panel is left
//   ctx.setTimeout/clearTimeout  timers cleared when the panel is left
//   ctx.bitmap(imageData)        createImageBitmap, closed when the panel is left (ctx.release(b) earlier)
//   ctx.error(err, {prefix, source})  the panel's ONE error area (replaced, not appended), plain words
//   ctx.clearError(source?)      hide it; with `source`, only an error raised with that source
//   ctx.coreDefaults()           the tool's default request(s) from the core
//   ctx.expose(parts, name = id) the panel's raw parts for tests, only in a page opened
//                                by a test (globalThis.__filigreeTestHooks === true): the
//                                test layer's hooks of `name` (tests/e2e/hooks/<tool>.js,
//                                not shipped: globalThis.__filigreeHookBuilders[name](parts);
//                                none without a builder), set as controller.testHooks[name],
//                                removed when the panel is left
//   ctx.readOnly                 a read-only embed: the reader explores (commits, undo and
//                                Reset work, nothing persists); the panel locks the author's
//                                inputs (drawing on them, replacing their files)
//   ctx.alive()
import { Autosave, History, keptHistory, shareBytes, projectText, download, withTimeout, onOtherTab } from './project.js';
import { encodeShare, decodeShare, ShareTooBig, kb, LINK_LIMIT_TEXT } from './share.js';

export const STORAGE_BLOCKED_NOTE = 'This page cannot save your work here (storage is blocked) — use Save project.';
const AUTOSAVE_FORMAT = 'filigree-autosave';

// ---- plain words for errors ---------------------------------------------------

/** A sentence a person can act on for any error; null for a cancellation. */
export function plainError(err) {
  if (!err) return null;
  if (err.name === 'JobError' || typeof err.kind === 'string') {
    switch (err.kind) {
      case 'cancelled': return null;
      case 'crash': return 'The computation crashed and its worker was restarted; your work is kept. Try again.';
      case 'protocol': return 'The page and its computation worker disagree (an internal error); your work is kept. Reload the page.';
      default: break;
    }
    const m = String(err.message || '');
    // A request the core could not even read is the page's fault, not the user's.
    if (err.kind === 'bad-request') {
      console.warn('request refused by the core:', m);
      return 'Filigree sent its computation a request it could not read (an internal error); your work is kept. Reload the page.';
    }
    return m;
  }
  if (err instanceof TypeError || err instanceof RangeError || err instanceof ReferenceError || err instanceof SyntaxError) {
    console.error(err);
    return 'Something went wrong inside Filigree (an internal error); your work is kept. Details are in the browser console.';
  }
  return String(err.message || err);
}

const hasFiles = (e) => [...(e.dataTransfer?.types || [])].includes('Files');
const isJson = (file) => /\.json$/i.test(file.name) || /\bjson\b/i.test(file.type);

/** Whether `file` is a Filigree project: named so, or JSON whose envelope says so (its first bytes). */
async function isProjectFile(file) {
  if (/\.filigree\.json$/i.test(file.name)) return true;
  if (!isJson(file)) return false;
  try {
    return /^\s*\{[^]*"format"\s*:\s*"filigree-project"/.test(await file.slice(0, 4096).text());
  } catch {
    return false;
  }
}

function cancelled() {
  const e = new Error('cancelled');
  e.name = 'JobError';
  e.kind = 'cancelled';
  return e;
}

/**
 * Plain data from the core with every `undefined` made `null` (the core's
 * "none" arrives as `undefined`; documents use `null`). In place.
 */
export function nulls(v) {
  if (Array.isArray(v)) {
    for (let i = 0; i < v.length; i++) if (v[i] === undefined || (v[i] && typeof v[i] === 'object')) v[i] = nulls(v[i]);
    return v;
  }
  if (v && typeof v === 'object' && !ArrayBuffer.isView(v)) {
    for (const k of Object.keys(v)) v[k] = nulls(v[k]);
    return v;
  }
  return v === undefined ? null : v;
}

// ---- core defaults ----------------------------------------------------------------

const defaultsCache = new Map();
/** The tool's default request(s), from the core (`defaults` request kind). */
export function coreDefaults(pool, tool) {
  if (!defaultsCache.has(tool)) {
    // The core answers {tool, request, budgets?}: the tool's default request.
    // The core's `Default` impls are the only copy of the defaults.
    const p = pool.run('defaults', { tool }).then((d) => d?.request ?? d).catch((err) => {
      defaultsCache.delete(tool);
      throw err;
    });
    defaultsCache.set(tool, p);
  }
  return defaultsCache.get(tool).then((d) => structuredClone(d));
}

// ---- jobs of a document ------------------------------------------------------------------

/**
 * A long job that belongs to a tool's document, not to its panel: leaving
 * the panel does not stop it; the tool bar shows its progress; the panel
 * finds it again when it comes back (`ctx.job(name)`) and shows where it is.
 * Its body reports (`report`), keeps the best answer so far (`best`), and
 * puts its outcome in the document with `commit`, whether the panel is
 * mounted or not.
 *
 *   status   'running' | 'done' | 'stopped' (the user's Stop: `best` is kept
 *            for the panel to offer) | 'cancelled' (`reason` says why) | 'failed' (`error`)
 *   progress {fraction, stage, figure}; points: [fraction, figure] for a plot
 *   data     the panel's own facts about the job (what it started from)
 */
export class DocJob {
  constructor(ctl, tool, name, { label = name, quietMs = 0 } = {}) {
    this.ctl = ctl;
    this.tool = tool;
    this.name = name;
    this.label = label;
    this.ctrl = new AbortController();
    this.signal = this.ctrl.signal;
    this.status = 'running';
    this.progress = { fraction: 0, stage: 'starting', figure: null };
    this.points = [];
    this.best = null;
    this.result = null;
    this.error = null;
    this.reason = '';
    this.data = {};
    this.seen = false; // its outcome was shown in its panel
    this.listeners = new Set();
    this.startedAt = performance.now();
    this.endedAt = null;
    // A job that may well end at once (a tangle's growth after an edit) reaches the tool
    // bar only once it has run `quietMs`; one that ends before stays quiet.
    this.quietUntil = this.startedAt + quietMs;
    this.announced = quietMs <= 0;
    if (!this.announced) setTimeout(() => { if (this.running) ctl.jobChanged(this); }, quietMs);
  }

  get running() { return this.status === 'running'; }

  /** pool.run for this job: its module, its signal (Stop and cancel abort it). */
  run(kind, payload, opts = {}) {
    const signal = opts.signal ? AbortSignal.any([this.signal, opts.signal]) : this.signal;
    return this.ctl.pool.run(kind, payload, { module: this.tool.id, ...opts, signal });
  }

  /** pool.runSharded for this job. */
  runSharded(kind, payload, opts = {}) {
    return this.ctl.pool.runSharded(kind, payload, { ...opts, signal: this.signal });
  }

  /** Where the job is: `progress` (merged), a plot `point`, a new `best`. */
  report(progress, { point, best } = {}) {
    if (!this.running) return;
    this.progress = { ...this.progress, ...progress };
    if (point && point.every(Number.isFinite)) this.points.push(point);
    if (best !== undefined) this.best = best;
    this.changed();
  }

  /** Stop with `status` 'stopped' (the user's Stop, the best kept) or 'cancelled' with a reason. */
  stop(reason = '') {
    if (!this.running) return;
    this.stopAs = reason ? 'cancelled' : 'stopped';
    this.reason = reason;
    this.ctrl.abort();
  }

  /** The tool's document becomes `fn(present)` (null: unchanged), as one undoable step, mounted or not. */
  commit(fn) {
    return this.ctl.commitTo(this.tool.id, fn);
  }

  subscribe(fn) {
    this.listeners.add(fn);
    return () => this.listeners.delete(fn);
  }

  changed() {
    for (const fn of this.listeners) {
      try { fn(this); } catch (err) { console.error(err); }
    }
    this.ctl.jobChanged(this);
  }

  /** Run `body(job)` to its end; the job's status says how it ended. */
  async start(body) {
    try {
      this.result = await body(this);
      this.status = this.signal.aborted ? this.stopAs || 'cancelled' : 'done';
    } catch (err) {
      if (this.signal.aborted || err?.kind === 'cancelled') {
        this.status = this.stopAs || 'cancelled';
        if (!this.reason && !this.stopAs) this.reason = 'its work was stopped';
      } else {
        this.status = 'failed';
        this.error = err;
      }
    }
    this.endedAt = performance.now();
    this.changed();
    return this;
  }
}

// ---- the controller -------------------------------------------------------------------

const CHROME = `
  <div class="doc-bar" role="toolbar" aria-label="Document">
    <button type="button" data-act="undo" aria-label="Undo" title="Undo (Ctrl+Z)" disabled>↶ Undo</button>
    <button type="button" data-act="redo" aria-label="Redo" title="Redo (Ctrl+Shift+Z or Ctrl+Y)" disabled>↷ Redo</button>
    <button type="button" data-act="save-project" title="Save project (Ctrl+S)">Save project</button>
    <button type="button" data-act="open-project" title="Open project (Ctrl+O)">Open project…</button>
    <input type="file" accept=".json,application/json" data-input="project" hidden tabindex="-1" aria-hidden="true">
    <button type="button" data-act="copy-link" title="Copy a link to this state">Copy link</button>
    <span class="doc-busy muted" aria-live="polite"></span>
  </div>
  <div class="doc-note" role="status" data-testid="doc-note" hidden></div>
  <div class="doc-note doc-tabs" role="alert" data-testid="doc-tabs" hidden>
    <span></span>
    <button type="button" data-act="tab-reload" title="Show the other tab's version here (Undo brings yours back)">Reload</button>
    <button type="button" data-act="tab-keep" title="Save this tab's version over the other tab's">Keep mine</button>
  </div>
  <div class="error doc-error" role="alert" data-testid="doc-error" hidden></div>
  <div class="doc-body"></div>`;

export class DocumentController {
  /**
   * `tools`: the declared tools; `host`: the element panels mount into;
   * `persist`: false for an embedded instance (never writes autosave).
   */
  constructor({ pool, toast, tools, host, persist = true, onShow, onJob }) {
    this.onShow = onShow;
    this.onJob = onJob; // onJob(job): a document's job started, moved on or ended (the tool bar shows it)
    this.jobs = new Map(); // tool id → Map(name → DocJob), the last of each name
    this.memories = new Map(); // tool id → ctx.memory
    this.pool = pool;
    this.toast = toast;
    this.tools = tools;
    this.host = host;
    this.persist = persist;
    this.docs = new Map(); // tool id → {history, version, autosave}
    this.current = null; // {tool, el, ctx, view, rendered, life}
    this.storageBlocked = false;
    // Panels' test hooks (ctx.expose), by tool id or name; null unless a test opened the page.
    this.testHooks = globalThis.__filigreeTestHooks === true ? {} : null;
    this.changeListeners = new Set(); // onChange

    this.keydown = (e) => this.onKey(e);
    document.addEventListener('keydown', this.keydown);
    // A file dropped anywhere in the window: the controller sees it first (capture).
    addEventListener('dragover', (e) => this.onDragOver(e), true);
    addEventListener('dragleave', (e) => { if (!e.relatedTarget) this.dragHint(false); }, true);
    addEventListener('drop', (e) => this.onDrop(e), true);
    addEventListener('pagehide', () => { for (const d of this.docs.values()) d.autosave?.flush(); });
    // Another tab saved a document this tab holds: offer its version (tabs bar).
    if (this.persist) {
      onOtherTab(({ key, rev }) => this.docs.get(key)?.autosave?.noteOther(rev));
      // A change held back by another tab's save is lost if the tab closes: the browser asks first.
      addEventListener('beforeunload', (e) => {
        if (![...this.docs.values()].some((d) => d.autosave?.held)) return;
        e.preventDefault();
        e.returnValue = '';
      });
    }
  }

  tool(id) {
    return this.tools.find((t) => t.id === id);
  }

  /** `fn(present, toolId)` after every new present shown (a change, undo, redo, load). Returns an unsubscribe function. */
  onChange(fn) {
    this.changeListeners.add(fn);
    return () => this.changeListeners.delete(fn);
  }

  /** The jobs of tool `id`'s document (name → DocJob). */
  jobsOf(id) {
    if (!this.jobs.has(id)) this.jobs.set(id, new Map());
    return this.jobs.get(id);
  }

  /** A job moved on: the tool bar hears it; an outcome shown in its mounted panel is seen. */
  jobChanged(job) {
    if (!job.running && this.current?.tool === job.tool) job.seen = true;
    if (!job.announced) {
      if (!job.running || performance.now() < job.quietUntil) return;
      job.announced = true;
    }
    this.onJob?.(job);
  }

  /**
   * Tool `id`'s document becomes `fn(present)` (null or the same: no
   * change) as one undoable step: rendered when its panel is mounted,
   * autosaved either way.
   */
  commitTo(id, fn) {
    const tool = this.tool(id);
    const d = this.docs.get(id);
    if (!tool || !d?.history) return false;
    const next = fn(d.history.present);
    if (!next || next === d.history.present) return false;
    d.history.push(next);
    d.history.seal();
    if (this.current?.tool === tool) this.changed();
    else if (d.autosave && this.persist) d.autosave.save(this.autosaved(tool, d));
    return true;
  }

  /** The current tool's document, or null. */
  present() {
    return (this.current && this.docs.get(this.current.tool.id)?.history?.present) ?? null;
  }

  /** Make `state` the current tool's document again, as one undoable step (an embed's Reset). */
  resetTo(state) {
    const d = this.current && this.docs.get(this.current.tool.id);
    if (!d?.history || d.history.present === state) return;
    d.history.push(state);
    d.history.seal();
    this.changed();
  }

  // ---- per-tool documents -------------------------------------------------------------

  /**
   * What the autosave of `tool`'s document `d` writes, made when it is
   * written (the debounce's last): the present and the newest of its undo
   * history (keptHistory: bounded in states and bytes), so Undo after a
   * reload goes back where it went before.
   */
  autosaved(tool, d) {
    return () => ({ format: AUTOSAVE_FORMAT, version: tool.state.version, state: d.history.present, history: keptHistory(d.history) });
  }

  /**
   * Put the undo history an autosave kept (`saved` = {past, future}) back
   * under the document just loaded from it. Each state is checked by the
   * core as the present was (nearest the present first; a refused one ends
   * its side there); meanwhile the document works as it is and nothing is
   * saved, and what the user did meanwhile stays on top.
   */
  async restoreHistory(tool, d, saved) {
    const h = d.history;
    const base = h.present;
    const valid = async (list) => {
      if (!Array.isArray(list)) return [];
      let i = list.length;
      for (; i > 0; i--) {
        try {
          await this.check(tool, list[i - 1], tool.state.version);
        } catch {
          break;
        }
        if (d.history !== h) return [];
      }
      return list.slice(i);
    };
    const past = await valid(saved?.past);
    const future = await valid(saved?.future);
    if (d.history !== h || (!past.length && !future.length)) return;
    shareBytes([...past, ...future], base);
    // Redo only while the document is still the one loaded (any change since ends that branch).
    if (!h.past.length && !h.future.length && h.present === base) h.future = future;
    h.past.unshift(...past);
    if (h.past.length > h.limit) h.past.splice(0, h.past.length - h.limit);
    if (this.current?.tool === tool) this.refresh();
  }

  docOf(tool) {
    let d = this.docs.get(tool.id);
    if (!d) {
      d = {
        history: null,
        loading: null,
        autosave: this.persist && tool.state
          ? new Autosave(tool.id, { onBlocked: () => this.blocked(), onConflict: () => this.showTabs() })
          : null,
      };
      this.docs.set(tool.id, d);
    }
    return d;
  }

  blocked() {
    this.storageBlocked = true;
    this.showNote();
  }

  /** The tabs bar: shown while another tab's newer save of this document is neither taken nor overruled. */
  showTabs() {
    const cur = this.current;
    const bar = cur?.el.querySelector('.doc-tabs');
    if (!bar) return;
    const a = this.docs.get(cur.tool.id)?.autosave;
    bar.hidden = !a?.conflict;
    if (!a?.conflict) return;
    bar.querySelector('span').textContent = `This ${cur.tool.title} document was changed in another tab.${a.held ? ' Your changes here are not saved until you choose.' : ''}`;
  }

  /** Reload: the other tab's save becomes this tab's document (an undoable step: Undo brings this tab's back). */
  async takeOtherTab() {
    const cur = this.current;
    const d = cur && this.docs.get(cur.tool.id);
    if (!d?.autosave || !d.history) return;
    const saved = await d.autosave.load();
    let state;
    try {
      if (!saved) throw new Error('the other tab\'s save is gone');
      state = await this.check(cur.tool, saved.state, saved.version);
    } catch (err) {
      cur.ctx.error(new Error(`The other tab's version could not be read (${plainError(err) ?? 'cancelled'}); yours is kept.`));
      return;
    }
    if (this.current !== cur) return;
    d.autosave.adopt(d.autosave.rev);
    d.history.push(state);
    d.history.seal();
    this.refresh(); // not saved again: it is what is stored
    this.showTabs();
  }

  /** Keep mine: this tab's document is saved over the other tab's. */
  keepMine() {
    const cur = this.current;
    const d = cur && this.docs.get(cur.tool.id);
    if (!d?.autosave || !d.history) return;
    const over = d.autosave.conflict;
    d.autosave.save(this.autosaved(cur.tool, d));
    d.autosave.flush({ over }).then(() => this.showTabs());
  }

  showNote() {
    const note = this.current?.el.querySelector('.doc-note');
    if (!note) return;
    note.hidden = !this.storageBlocked || !this.persist;
    note.textContent = STORAGE_BLOCKED_NOTE;
  }

  /**
   * Migrate `raw` (schema `version`) for `tool` here, then have the core
   * check it (`check-state`): resolves with the normalised state, rejects
   * with an Error (a JobError naming the field at fault) in plain words.
   */
  async check(tool, raw, version) {
    const spec = tool.state;
    if (!Number.isInteger(version) || version < 1) throw new Error('the state has no schema version');
    let s = raw;
    if (version < spec.version) {
      if (!spec.migrate) throw new Error(`${tool.title} state version ${version} can no longer be read`);
      s = spec.migrate(s, version);
      version = spec.version;
    }
    // Copied, not transferred: `raw` may be a live document.
    return nulls(await this.pool.run('check-state', { tool: tool.id, version, state: s }, { transfer: [] }));
  }

  /** The document of `tool` at first sight: its autosave if valid, else its defaults. */
  async firstDocument(tool, ctx) {
    const d = this.docOf(tool);
    const saved = await d.autosave?.load();
    if (saved) {
      try {
        const legacy = saved.format !== AUTOSAVE_FORMAT; // before the controller: the bare state, version 1
        const state = await this.check(tool, legacy ? saved : saved.state, legacy ? 1 : saved.version);
        // Its undo history, when saved with this schema version (an older one starts afresh).
        d.savedHistory = !legacy && saved.version === tool.state.version ? saved.history ?? null : null;
        return state;
      } catch (err) {
        // A crashed or cancelled check says nothing about the autosave: keep it.
        if (err?.name === 'JobError' && !['invalid-input', 'bad-request', 'limit'].includes(err.kind)) throw err;
        ctx.error(new Error(`Your autosaved ${tool.title} work could not be restored (${err.message}); a fresh document was started.`));
      }
    }
    return tool.state.defaults(ctx);
  }

  // ---- mounting -------------------------------------------------------------------------

  /** Leave the current panel: abort its requests (not its document's jobs), clear its timers, close its bitmaps, flush its autosave. */
  leave() {
    const cur = this.current;
    if (!cur) return;
    this.current = null;
    cur.life.dead = true;
    cur.life.ctrl.abort();
    for (const t of cur.life.timers) clearTimeout(t);
    cur.life.timers.clear();
    for (const b of cur.life.bitmaps) b.close?.();
    cur.life.bitmaps.clear();
    for (const [name, hooks] of cur.life.hooks) if (this.testHooks?.[name] === hooks) delete this.testHooks[name];
    cur.life.hooks.clear();
    for (const off of cur.life.follows) off(); // its jobs run on (ctx.startJob), unwatched
    cur.life.follows.clear();
    try { cur.view?.unmount?.(); } catch (err) { console.error(err); }
    this.docs.get(cur.tool.id)?.autosave?.flush();
  }

  /**
   * Show tool `id` (its kept document when it was open before). `incoming`
   * = {state, source} is a validated document to load as an undoable step.
   */
  async show(id, incoming = null, { readOnly = false } = {}) {
    const tool = this.tool(id) || this.tools[0];
    if (this.current?.tool === tool && !incoming) return this.current;
    // The tool's wasm module downloads and starts while its panel builds.
    this.pool.preload?.(tool.id);
    if (this.current?.tool !== tool) this.mount(tool, readOnly);
    const cur = this.current;
    const d = this.docOf(tool);
    while (tool.state && !d.history) {
      if (!d.loading) {
        const p = this.firstDocument(tool, cur.ctx).then((s) => { d.history = new History(s); });
        d.loading = p;
        p.catch(() => { if (d.loading === p) d.loading = null; });
      }
      try {
        await d.loading;
      } catch (err) {
        if (cur.life.dead) return cur;
        // An earlier visit's load was cut short by leaving: load again for this one.
        if (err.kind === 'cancelled') { await null; continue; }
        cur.ctx.error(err);
        if (!incoming) break;
        d.history = new History(incoming.state);
        incoming = null;
        this.changed();
      }
    }
    cur.el.querySelector('.doc-busy').textContent = '';
    // The autosave's undo history comes back under its document; a link or a
    // project opened at first sight starts from the autosave alone, as before.
    if (d.savedHistory && d.history) {
      const saved = d.savedHistory;
      d.savedHistory = null;
      if (!incoming) this.restoreHistory(tool, d, saved).catch((err) => console.warn('undo history not restored:', err));
    }
    if (cur.life.dead) return cur;
    if (incoming) {
      d.history.push(incoming.state);
      d.history.seal();
      this.changed();
    } else this.refresh();
    return cur;
  }

  mount(tool, readOnly) {
    this.leave();
    const el = document.createElement('section');
    el.className = `tool tool-${tool.id}`;
    el.setAttribute('aria-label', tool.title);
    el.innerHTML = CHROME;
    if (!tool.state) el.querySelector('.doc-bar').hidden = true;
    if (readOnly) el.dataset.readonly = '1';
    this.host.replaceChildren(el);
    const life = { ctrl: new AbortController(), timers: new Set(), bitmaps: new Set(), hooks: new Map(), follows: new Set(), dead: false };
    const cur = { tool, el, life, view: null, rendered: null, readOnly };
    this.current = cur;
    cur.ctx = this.context(cur);
    this.wireChrome(cur);
    el.querySelector('.doc-busy').textContent = tool.state ? 'loading…' : '';
    cur.view = tool.mount(el.querySelector('.doc-body'), cur.ctx) || {};
    this.showNote();
    this.showTabs();
    this.onShow?.(tool.id);
    // Its jobs' outcomes are shown from here on.
    for (const job of this.jobsOf(tool.id).values()) if (!job.running && !job.seen) { job.seen = true; if (job.announced) this.onJob?.(job); }
  }

  context(cur) {
    const ctl = this;
    const { life, tool } = cur;
    const doc = () => this.docs.get(tool.id);
    const errorEl = cur.el.querySelector('.doc-error');
    const ctx = {
      pool: this.pool,
      toast: this.toast,
      signal: life.ctrl.signal,
      readOnly: cur.readOnly,
      alive: () => !life.dead,
      state: () => doc()?.history?.present ?? null,
      commit(next, opts) {
        if (life.dead || !doc()?.history) return false;
        doc().history.push(next, opts);
        ctl.changed();
        return true;
      },
      seal() { doc()?.history?.seal(); },
      run(kind, payload, opts = {}) {
        if (life.dead) return Promise.reject(cancelled());
        const inner = new AbortController();
        const abort = () => inner.abort();
        life.ctrl.signal.addEventListener('abort', abort, { once: true });
        opts.signal?.addEventListener('abort', abort, { once: true });
        if (opts.signal?.aborted) inner.abort();
        return ctl.pool.run(kind, payload, { module: tool.id, ...opts, signal: inner.signal }).then((r) => {
          if (life.dead) throw cancelled();
          return r;
        }).finally(() => {
          life.ctrl.signal.removeEventListener('abort', abort);
          opts.signal?.removeEventListener('abort', abort);
        });
      },
      setTimeout(fn, ms) {
        if (life.dead) return 0;
        const t = setTimeout(() => { life.timers.delete(t); if (!life.dead) fn(); }, ms);
        life.timers.add(t);
        return t;
      },
      clearTimeout(t) { clearTimeout(t); life.timers.delete(t); },
      async bitmap(source) {
        const b = await createImageBitmap(source);
        if (life.dead) { b.close(); throw cancelled(); }
        life.bitmaps.add(b);
        return b;
      },
      release(b) { if (b) { life.bitmaps.delete(b); b.close(); } },
      error(err, { prefix = '', source = '' } = {}) {
        if (life.dead) return;
        const message = plainError(err);
        if (message === null) return;
        ctx.clearError();
        errorEl.textContent = prefix ? `${prefix}: ${message}` : message;
        errorEl.dataset.source = source;
        errorEl.hidden = false;
        if (err?.field) {
          const control = cur.el.querySelector(`[data-field="${CSS.escape(err.field)}"]`)
            || cur.el.querySelector(`[data-field="${CSS.escape(err.field.split('.')[0])}"]`);
          if (control) {
            control.setAttribute('aria-invalid', 'true');
            control.setAttribute('aria-errormessage', errorEl.id || (errorEl.id = `doc-error-${tool.id}`));
          }
        }
        try { cur.view?.markError?.(err); } catch (e) { console.error(e); }
      },
      clearError(source) {
        // A background job that succeeds clears only the error it raised itself
        // (not, say, a refused project file shown meanwhile).
        if (source !== undefined && !errorEl.hidden && errorEl.dataset.source !== source) return;
        errorEl.hidden = true;
        errorEl.textContent = '';
        for (const c of cur.el.querySelectorAll('[aria-invalid=true]')) {
          c.removeAttribute('aria-invalid');
          c.removeAttribute('aria-errormessage');
        }
      },
      coreDefaults: () => coreDefaults(ctl.pool, tool.id),
      startJob(name, opts, body) {
        const jobs = ctl.jobsOf(tool.id);
        jobs.get(name)?.stop('a new one started');
        const job = new DocJob(ctl, tool, name, opts);
        jobs.set(name, job);
        job.promise = job.start(body);
        ctl.jobChanged(job);
        return job;
      },
      job: (name) => ctl.jobsOf(tool.id).get(name) ?? null,
      get memory() {
        if (!ctl.memories.has(tool.id)) ctl.memories.set(tool.id, {});
        return ctl.memories.get(tool.id);
      },
      follow(job, fn) {
        if (life.dead) return () => {};
        const off = job.subscribe(fn);
        life.follows.add(off);
        return () => { off(); life.follows.delete(off); };
      },
      expose(parts, name = tool.id) {
        if (!ctl.testHooks || life.dead) return;
        // The hooks are the test layer's (a panel without a builder has none).
        const build = globalThis.__filigreeHookBuilders?.[name];
        if (typeof build !== 'function') return;
        const hooks = build(parts);
        ctl.testHooks[name] = hooks;
        life.hooks.set(name, hooks);
      },
      undo: () => ctl.undo(),
      redo: () => ctl.redo(),
    };
    return ctx;
  }

  wireChrome(cur) {
    const q = (s) => cur.el.querySelector(s);
    q('[data-act=undo]').onclick = () => this.undo();
    q('[data-act=redo]').onclick = () => this.redo();
    q('[data-act=save-project]').onclick = () => this.saveProject();
    const input = q('input[data-input=project]');
    q('[data-act=open-project]').onclick = () => input.click();
    input.onchange = () => {
      const file = input.files[0];
      input.value = '';
      if (file) this.openProjectFile(file);
    };
    q('[data-act=copy-link]').onclick = () => this.copyLink();
    q('[data-act=tab-reload]').onclick = () => this.takeOtherTab();
    q('[data-act=tab-keep]').onclick = () => this.keepMine();
    if (cur.readOnly) for (const a of ['undo', 'redo', 'open-project']) q(`[data-act=${a}]`).hidden = true;
  }

  // ---- changes ---------------------------------------------------------------------------

  /** After a new present: autosave, buttons, render. */
  changed() {
    const cur = this.current;
    if (!cur) return;
    const d = this.docs.get(cur.tool.id);
    if (d.autosave && this.persist && !cur.readOnly) {
      d.autosave.save(this.autosaved(cur.tool, d));
      if (d.autosave.conflict) this.showTabs(); // held: say that this change is not saved yet
    }
    this.refresh();
  }

  refresh() {
    const cur = this.current;
    if (!cur) return;
    const d = this.docs.get(cur.tool.id);
    const h = d?.history;
    cur.el.querySelector('[data-act=undo]').disabled = !h?.canUndo;
    cur.el.querySelector('[data-act=redo]').disabled = !h?.canRedo;
    if (!h || h.present === cur.rendered) return;
    for (const fn of this.changeListeners) fn(h.present, cur.tool.id);
    const prev = cur.rendered;
    cur.rendered = h.present;
    try {
      cur.view.render?.(h.present, prev);
    } catch (err) {
      cur.ctx.error(err);
    }
  }

  undo() {
    const h = this.current && this.docs.get(this.current.tool.id)?.history;
    if (!h?.canUndo) return;
    h.undo();
    this.changed();
  }

  redo() {
    const h = this.current && this.docs.get(this.current.tool.id)?.history;
    if (!h?.canRedo) return;
    h.redo();
    this.changed();
  }

  // ---- project files and links -----------------------------------------------------------

  saveProject() {
    const cur = this.current;
    const state = cur && this.docs.get(cur.tool.id)?.history?.present;
    if (!state) return;
    const base = String(cur.tool.state.fileName?.(state) || cur.tool.id).replace(/\.[^.]+$/, '').replace(/[^\w.-]+/g, '-');
    download(`${base}.filigree.json`, projectText(cur.tool.id, cur.tool.state.version, state), 'application/json');
  }

  /**
   * Open a project file: read and checked in full by the core
   * (`open-project`: envelope, bytes, the tool's state) before anything
   * changes; the current work stays on failure.
   */
  async openProjectFile(file) {
    const ctx = this.current?.ctx;
    let tool, state;
    try {
      const text = await file.text();
      // Read in the current tool's module (no other module loads for it); a
      // project of another tool comes back unchecked and is checked in its own.
      const opened = nulls(await this.pool.run('open-project', { text }, { module: this.current?.tool.id }));
      tool = this.tool(opened.tool);
      if (!tool?.state) throw new Error(`it is a project of a tool this Filigree does not have ('${opened.tool}')`);
      // An older state version comes back unchecked: migrate it, then check it.
      state = opened.checked ? opened.state : await this.check(tool, opened.state, opened.stateVersion);
    } catch (err) {
      const why = String(plainError(err) ?? 'it was cancelled').replace(/\.$/, '');
      ctx?.error(new Error(`${file.name} was not opened — ${why}. Your work is unchanged.`));
      return false;
    }
    const cur = await this.show(tool.id, { state, source: 'project' });
    cur.ctx.clearError();
    return true;
  }

  /**
   * Open a shared state (what a link carries) in tool `toolId`: converted
   * (`fromShare`), migrated and validated BEFORE anything changes, then
   * loaded as an undoable step (autosaved unless `readOnly` or persist is off).
   * Rejects with an Error with a plain message; the user's work is untouched then.
   */
  async openState(toolId, state, { version, readOnly = false, source = 'link' } = {}) {
    const tool = this.tool(toolId);
    if (!tool?.state) throw new Error(`Filigree has no tool '${toolId}'.`);
    let full;
    try {
      const raw = tool.state.fromShare ? await tool.state.fromShare(state, this.helperCtx(tool)) : state;
      full = await this.check(tool, raw, version ?? tool.state.version);
    } catch (err) {
      const why = String(plainError(err) ?? 'it was cancelled').replace(/([^.])$/, '$1.');
      throw new Error(`This ${source} could not be opened: ${why} Your own work is unchanged.`);
    }
    if (readOnly) this.persist = false;
    await this.show(tool.id, { state: full, source }, { readOnly });
    return true;
  }

  /** A context for conversions outside a mounted panel (opening a link). */
  helperCtx(tool) {
    return { pool: this.pool, run: (k, p, o) => this.pool.run(k, p, { module: tool.id, ...o }), coreDefaults: () => coreDefaults(this.pool, tool.id) };
  }

  /**
   * {tool, fragment, omitted?} of the current document; throws ShareTooBig
   * or an Error saying why it cannot be shared. A state whose link would be
   * too big is shared without its big inputs when the tool says how
   * (`state.shareLean(state) → {state, omits}`, `omits` in words: 'the
   * example'); `omitted` = {what, size} then says what the link leaves out.
   */
  async currentShare() {
    const cur = this.current;
    const state = cur && this.docs.get(cur.tool.id)?.history?.present;
    if (!state) throw new Error('There is nothing to share yet.');
    const spec = cur.tool.state;
    const s = spec.toShare ? await spec.toShare(state) : state;
    try {
      return { tool: cur.tool.id, fragment: await encodeShare(cur.tool.id, s, { version: spec.version }) };
    } catch (err) {
      const lean = err instanceof ShareTooBig && spec.shareLean?.(state);
      if (!lean) throw err;
      const fragment = await encodeShare(cur.tool.id, spec.toShare ? await spec.toShare(lean.state) : lean.state, { version: spec.version });
      return { tool: cur.tool.id, fragment, omitted: { what: lean.omits, size: err.size } };
    }
  }

  async copyLink() {
    let share;
    try {
      share = await this.currentShare();
    } catch (err) {
      if (err instanceof ShareTooBig) {
        this.toast(err.message, { timeout: 15000, action: { label: 'Save project', run: () => this.saveProject() } });
      } else this.current?.ctx.error(err);
      return null;
    }
    // A link that leaves something out says so before it is copied.
    if (share.omitted) {
      const { what, size } = share.omitted;
      return new Promise((resolve) => {
        const t = this.toast(`This link leaves out ${what} (${kb(size)} > the ${LINK_LIMIT_TEXT} a link holds): whoever opens it gets everything else. Save project keeps it all.`, {
          timeout: 0, action: { label: 'Copy link without it', run: () => resolve(this.copyFragment(share.fragment, ` It leaves out ${what}.`)) },
        });
        t.dataset.omits = what;
        const save = document.createElement('button');
        save.type = 'button';
        save.textContent = 'Save project';
        save.onclick = () => { t.remove(); this.saveProject(); resolve(null); };
        t.querySelector('button').after(save);
      });
    }
    return this.copyFragment(share.fragment);
  }

  /** Copy the app's URL with `fragment` (shown in a toast when the clipboard refuses). */
  async copyFragment(fragment, note = '') {
    const url = new URL(location.href);
    url.searchParams.delete('embed');
    url.searchParams.delete('mode');
    url.hash = fragment;
    const link = url.href;
    this.lastLink = link;
    let copied = false;
    try {
      await withTimeout(navigator.clipboard.writeText(link), 1000, 'clipboard');
      copied = true;
    } catch { /* no clipboard permission: show the link instead */ }
    const t = this.toast(copied ? `Link copied. Anyone who opens it sees this state.${note}` : `Copy this link (the clipboard is not available here):${note}`, { timeout: 12000 });
    t.dataset.link = link;
    if (!copied) {
      const field = document.createElement('input');
      field.readOnly = true;
      field.value = link;
      field.setAttribute('aria-label', 'link to this state');
      t.querySelector('span').after(field);
      field.select();
    }
    return link;
  }

  /** Open the state a fragment carries (a share link); shows a plain error on failure. */
  async openFragment(fragment, fallbackTool) {
    let decoded;
    try {
      decoded = await decodeShare(fragment);
      await this.openState(decoded.tool, decoded.state, { version: decoded.version, source: 'link' });
      return true;
    } catch (err) {
      const cur = await this.show(decoded?.tool || fallbackTool);
      const msg = /Your own work is unchanged/.test(err.message) ? err.message : `${err.message} Your own work is unchanged.`;
      cur.ctx.error(new Error(msg));
      return false;
    }
  }

  // ---- files dropped anywhere ---------------------------------------------------------------
  //
  // A project file opens in any tool, whatever it is dropped on. Any other file
  // goes to the panel's `view.drop` when it has one (Tangle, Micro), wherever it
  // lands (the editors included: they would paste the file's bytes as text);
  // else to the panel's own drop zone (ui/file-input.js: images, anywhere too).
  // A refused file leaves the document as it was and says why.

  /** Whether the current panel takes dropped files here (not a read-only embed, not the home view). */
  dropTarget() {
    const cur = this.current;
    return cur && !cur.life.dead && !cur.readOnly && cur.tool.state ? cur : null;
  }

  onDragOver(e) {
    if (!hasFiles(e)) return;
    const cur = this.dropTarget();
    if (!cur?.view?.drop) return;
    // The panel's: not an editor's either (it would paste the file as text).
    e.preventDefault();
    e.stopPropagation();
    e.dataTransfer.dropEffect = 'copy';
    this.dragHint(true);
  }

  /** The tool lit while a file is over the window (and every zone dark again after). */
  dragHint(on) {
    const el = this.current?.el;
    el?.classList.toggle('drop-over', on);
    if (!on) for (const z of document.querySelectorAll('.dragging')) z.classList.remove('dragging');
  }

  onDrop(e) {
    const file = hasFiles(e) && e.dataTransfer.files[0];
    const cur = file && this.dropTarget();
    if (!cur) { this.dragHint(false); return; }
    // Images for a panel without view.drop: its zone's (acceptFiles) to take.
    if (!cur.view?.drop && !isJson(file)) { this.current?.el.classList.remove('drop-over'); return; }
    e.preventDefault();
    e.stopPropagation();
    this.dragHint(false);
    this.openDropped(file);
  }

  /** Open a dropped file: a project as a project, else the panel's (view.drop); says plainly when refused. */
  async openDropped(file) {
    const cur = this.current;
    if (await isProjectFile(file)) return this.openProjectFile(file);
    if (this.current !== cur) return false;
    try {
      if (!cur.view?.drop) throw new Error(`it is not a Filigree project, and ${cur.tool.title} opens images and projects`);
      await cur.view.drop(file);
    } catch (err) {
      if (this.current !== cur || err?.kind === 'cancelled') return false;
      const line = Number.isInteger(err?.line) && !/\bline \d/.test(err.message || '') ? `line ${err.line}: ` : '';
      const why = `${line}${plainError(err) ?? 'it was cancelled'}`.replace(/\.$/, '');
      cur.ctx.error(new Error(`${file.name} was not opened — ${why}. Your work is unchanged.`), { source: 'drop' });
      return false;
    }
    if (this.current === cur) cur.ctx.clearError('drop');
    return true;
  }

  // ---- keys ---------------------------------------------------------------------------------

  onKey(e) {
    const cur = this.current;
    if (!cur || e.defaultPrevented) return;
    const t = e.target;
    if (t?.closest?.('input, select, textarea, [contenteditable=""], [contenteditable=true], .cm-editor')) return;
    const mod = e.ctrlKey || e.metaKey;
    const key = e.key.length === 1 ? e.key.toLowerCase() : e.key;
    if (mod && !e.altKey) {
      if (key === 'z') { e.preventDefault(); if (e.shiftKey) this.redo(); else this.undo(); } else if (key === 'y' && !e.shiftKey) { e.preventDefault(); this.redo(); } else if (key === 's' && !e.shiftKey && cur.tool.state && this.persist) { e.preventDefault(); this.saveProject(); } else if (key === 'o' && !e.shiftKey && cur.tool.state && !cur.readOnly && this.persist) {
        e.preventDefault();
        cur.el.querySelector('input[data-input=project]').click();
      }
      return;
    }
    if (e.altKey || e.shiftKey || mod) return;
    const fn = cur.view?.keys?.[key];
    if (fn) { e.preventDefault(); fn(); }
  }
}
