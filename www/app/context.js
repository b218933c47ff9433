// A mounted panel's `ctx` and its life, for the document controller
// (document.js): what a panel may do with its document, the computation and
// the page, everything tied to the panel's life — leaving the panel aborts
// its requests, clears its timers, closes its bitmaps and drops its test
// hooks; its document's jobs run on.
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
//                                back; see DocJob (jobs.js). Starting one stops the last of that name.
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
//                                by a test: the test layer's hooks of `name`, built by the
//                                controller (document.js, `expose`); set as
//                                controller.testHooks[name], removed when the panel is left
//   ctx.readOnly                 a read-only embed: the reader explores (commits, undo and
//                                Reset work, nothing persists); the panel locks the author's
//                                inputs (drawing on them, replacing their files)
//   ctx.alive()
//
//   const life = panelLife();  cur.ctx = panelContext(ctl, cur);  …  endLife(ctl, life);
import { plainError, cancelled } from './errors.js';
import { coreDefaults } from './core-state.js';

/** What a mounted panel holds that ends when it is left. */
export function panelLife() {
  return { ctrl: new AbortController(), timers: new Set(), bitmaps: new Set(), hooks: new Map(), follows: new Set(), dead: false };
}

/** The panel is left: abort its requests (not its document's jobs), clear its timers, close its bitmaps, drop its hooks. */
export function endLife(ctl, life) {
  life.dead = true;
  life.ctrl.abort();
  for (const t of life.timers) clearTimeout(t);
  life.timers.clear();
  for (const b of life.bitmaps) b.close?.();
  life.bitmaps.clear();
  for (const [name, hooks] of life.hooks) if (ctl.testHooks?.[name] === hooks) delete ctl.testHooks[name];
  life.hooks.clear();
  for (const off of life.follows) off(); // its jobs run on (ctx.startJob), unwatched
  life.follows.clear();
}

/** The ctx of the mounted `cur` = {tool, el, life, readOnly}. */
export function panelContext(ctl, cur) {
  const { life, tool } = cur;
  const doc = () => ctl.docs.get(tool.id);
  const errorEl = cur.el.querySelector('.doc-error');
  const ctx = {
    pool: ctl.pool,
    toast: ctl.toast,
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
      // A message that already starts with the prefix (a file's name) is not prefixed twice.
      errorEl.textContent = prefix && !message.startsWith(`${prefix} `) ? `${prefix}: ${message}` : message;
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
    startJob: (name, opts, body) => ctl.jobs.start(tool, name, opts, body),
    job: (name) => ctl.jobs.of(tool.id).get(name) ?? null,
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
      const hooks = ctl.testHooksOf(parts, name);
      if (!hooks) return;
      ctl.testHooks[name] = hooks;
      life.hooks.set(name, hooks);
    },
    undo: () => ctl.undo(),
    redo: () => ctl.redo(),
  };
  return ctx;
}
