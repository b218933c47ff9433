// The document controller: ONE place for what every tool needs around its
// state — undo/redo (drags coalesced), autosave to IndexedDB, project files
// (validated, versioned, migrated), share links, keyboard shortcuts, error
// display, and the lifecycle of a mounted panel. A tool adds no glue: it
// declares its state and its view.
//
// The controller holds the documents (one undo history per tool), the shown
// panel and the test hooks, and wires its parts, one concern a file:
//   storage.js     autosave: when it writes, what it restores, blocked storage, two tabs
//   open.js        project files and share links, saved and opened
//   drops.js       files dropped anywhere in the window
//   jobs.js        a document's long jobs (DocJob), running on when its panel is left
//   context.js     a mounted panel's ctx and its life
//   chrome.js      the document bar, notes and error area around every panel
//   keys.js        keyboard shortcuts
//   core-state.js  the core's defaults and checks of a document
//   errors.js      errors in plain words
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
// ctx: see context.js. Test hooks (ctx.expose), only in a page opened by a
// test (globalThis.__filigreeTestHooks === true): the test layer's hooks of
// `name` (tests/e2e/hooks/<tool>.js, not shipped:
// globalThis.__filigreeHookBuilders[name](parts)) or, for a tool without
// them, none; set as controller.testHooks[name].
import { History } from './history.js';
import { DocJobs } from './jobs.js';
import { DocStorage } from './storage.js';
import { openState, openFragment, currentShare } from './open.js';
import { listenForDrops } from './drops.js';
import { panelLife, endLife, panelContext } from './context.js';
import { chromeFor, wireChrome } from './chrome.js';
import { onKey } from './keys.js';

export class DocumentController {
  /**
   * `tools`: the declared tools; `host`: the element panels mount into;
   * `persist`: false for an embedded instance (never writes autosave).
   */
  constructor({ pool, toast, tools, host, persist = true, onShow, onJob }) {
    this.onShow = onShow;
    this.jobs = new DocJobs(this, onJob); // onJob(job): a document's job started, moved on or ended (the tool bar shows it)
    this.memories = new Map(); // tool id → ctx.memory
    this.pool = pool;
    this.toast = toast;
    this.tools = tools;
    this.host = host;
    this.persist = persist;
    this.docs = new Map(); // tool id → {history, version, autosave}
    this.current = null; // {tool, el, ctx, view, rendered, life}
    this.storage = new DocStorage(this);
    // Panels' test hooks (ctx.expose), by tool id or name; null unless a test opened the page.
    this.testHooks = globalThis.__filigreeTestHooks === true ? {} : null;
    this.changeListeners = new Set(); // onChange

    this.keydown = (e) => onKey(this, e);
    document.addEventListener('keydown', this.keydown);
    listenForDrops(this);
    this.storage.listen();
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
    return this.jobs.of(id);
  }

  /** The test layer's hooks `name` built from a panel's raw `parts`; null without a builder (none are published). */
  testHooksOf(parts, name) {
    const build = globalThis.__filigreeHookBuilders?.[name];
    return typeof build === 'function' ? build(parts) : null;
  }

  // ---- project files and links (open.js) ---------------------------------------------------

  /** Open a shared state in tool `toolId` as an undoable step; rejects with a plain Error (work untouched). */
  openState(toolId, state, opts) {
    return openState(this, toolId, state, opts);
  }

  /** Open the state a fragment carries (a share link); shows a plain error on failure. */
  openFragment(fragment, fallbackTool) {
    return openFragment(this, fragment, fallbackTool);
  }

  /** {tool, fragment, omitted?} of the current document (ShareTooBig when it does not fit a link). */
  currentShare() {
    return currentShare(this);
  }

  // ---- changes ---------------------------------------------------------------------------

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
    else if (d.autosave && this.persist) this.storage.save(tool, d);
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

  /** After a new present: autosave, buttons, render. */
  changed() {
    const cur = this.current;
    if (!cur) return;
    const d = this.docs.get(cur.tool.id);
    if (d.autosave && this.persist && !cur.readOnly) {
      this.storage.save(cur.tool, d);
      if (d.autosave.conflict) this.storage.showTabs(); // held: say that this change is not saved yet
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

  // ---- per-tool documents -------------------------------------------------------------

  docOf(tool) {
    let d = this.docs.get(tool.id);
    if (!d) {
      d = {
        history: null,
        loading: null,
        autosave: this.persist && tool.state ? this.storage.autosaveFor(tool) : null,
      };
      this.docs.set(tool.id, d);
    }
    return d;
  }

  // ---- mounting -------------------------------------------------------------------------

  /** Leave the current panel: abort its requests (not its document's jobs), clear its timers, close its bitmaps, flush its autosave. */
  leave() {
    const cur = this.current;
    if (!cur) return;
    this.current = null;
    endLife(this, cur.life);
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
        const p = this.storage.firstDocument(tool, cur.ctx).then((s) => { d.history = new History(s); });
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
      if (!incoming) this.storage.restoreHistory(tool, d, saved).catch((err) => console.warn('undo history not restored:', err));
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
    const el = chromeFor(tool, readOnly);
    this.host.replaceChildren(el);
    const cur = { tool, el, life: panelLife(), view: null, rendered: null, readOnly };
    this.current = cur;
    cur.ctx = panelContext(this, cur);
    wireChrome(this, cur);
    el.querySelector('.doc-busy').textContent = tool.state ? 'loading…' : '';
    cur.view = tool.mount(el.querySelector('.doc-body'), cur.ctx) || {};
    this.storage.showNote();
    this.storage.showTabs();
    this.onShow?.(tool.id);
    // Its jobs' outcomes are shown from here on.
    this.jobs.shown(tool.id);
  }
}
