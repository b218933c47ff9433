// Autosave of the documents, for the document controller (document.js): each
// tool's document is written to IndexedDB (app/autosave.js) after
// every change, with the newest of its undo history (keptHistory), and read
// back at the tool's first sight (checked by the core; its undo history
// restored under it). Where storage is blocked the panel says so (the
// storage note); when another tab saves a document this tab holds, the tabs
// bar offers its version (Reload) or keeps this tab's (Keep mine).
//
//   const storage = new DocStorage(controller); storage.listen();
//   storage.autosaveFor(tool)            → an Autosave of tool's document
//   storage.save(tool, d)                write d's present (debounced)
//   await storage.firstDocument(tool, ctx) → the autosave if valid, else the defaults
//   storage.restoreHistory(tool, d, saved) its kept undo history back under it
//   storage.takeOtherTab() / keepMine()  the tabs bar's two answers
//   storage.showNote() / showTabs()      the storage note and the tabs bar of the shown panel
import { Autosave, onOtherTab } from './autosave.js';
import { keptHistory, shareBytes } from './history.js';
import { plainError } from './errors.js';
import { checkState } from './core-state.js';

export const STORAGE_BLOCKED_NOTE = 'This page cannot save your work here (storage is blocked) — use Save project.';
const AUTOSAVE_FORMAT = 'filigree-autosave';

export class DocStorage {
  constructor(ctl) {
    this.ctl = ctl;
    this.blocked = false; // an autosave's last storage call failed: the page says it cannot save here
  }

  /** Flush on pagehide; hear other tabs' saves; ask before closing a tab whose change is held. */
  listen() {
    const ctl = this.ctl;
    addEventListener('pagehide', () => { for (const d of ctl.docs.values()) d.autosave?.flush(); });
    // Another tab saved a document this tab holds: offer its version (tabs bar).
    if (ctl.persist) {
      onOtherTab(({ key, rev }) => ctl.docs.get(key)?.autosave?.noteOther(rev));
      // A change held back by another tab's save is lost if the tab closes: the browser asks first.
      addEventListener('beforeunload', (e) => {
        if (![...ctl.docs.values()].some((d) => d.autosave?.held)) return;
        e.preventDefault();
        e.returnValue = '';
      });
    }
  }

  autosaveFor(tool) {
    return new Autosave(tool.id, {
      onBlocked: () => this.onBlocked(),
      onUnblocked: () => this.onBlocked(),
      onConflict: () => this.showTabs(),
    });
  }

  /** Write `tool`'s document `d` (debounced: what is written is made then). */
  save(tool, d) {
    d.autosave.save(this.autosaved(tool, d));
  }

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
    const ctl = this.ctl;
    const h = d.history;
    const base = h.present;
    // The states as checked (and converted: Pixel's images as PNG), not as stored.
    const valid = async (list) => {
      if (!Array.isArray(list)) return [];
      const kept = [];
      for (let i = list.length; i > 0; i--) {
        try {
          kept.unshift(await checkState(ctl.pool, tool, list[i - 1], tool.state.version));
        } catch {
          break;
        }
        if (d.history !== h) return [];
      }
      return kept;
    };
    const past = await valid(saved?.past);
    const future = await valid(saved?.future);
    if (d.history !== h || (!past.length && !future.length)) return;
    shareBytes([...past, ...future], base);
    // Redo only while the document is still the one loaded (any change since ends that branch).
    if (!h.past.length && !h.future.length && h.present === base) h.future = future;
    h.past.unshift(...past);
    if (h.past.length > h.limit) h.past.splice(0, h.past.length - h.limit);
    if (ctl.current?.tool === tool) ctl.refresh();
  }

  /** The document of `tool` at first sight: its autosave if valid, else its defaults. */
  async firstDocument(tool, ctx) {
    const d = this.ctl.docOf(tool);
    const saved = await d.autosave?.load();
    if (saved) {
      try {
        const legacy = saved.format !== AUTOSAVE_FORMAT; // before the controller: the bare state, version 1
        const state = await checkState(this.ctl.pool, tool, legacy ? saved : saved.state, legacy ? 1 : saved.version);
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

  /** An autosave found storage refused, or working again: the note says so while any is refused. */
  onBlocked() {
    this.blocked = [...this.ctl.docs.values()].some((d) => d.autosave?.blocked);
    this.showNote();
  }

  /** The storage note of the shown panel: there while storage is blocked (never in a page that does not save). */
  showNote() {
    const ctl = this.ctl;
    const note = ctl.current?.el.querySelector('.doc-note');
    if (!note) return;
    note.hidden = !this.blocked || !ctl.persist;
    note.textContent = STORAGE_BLOCKED_NOTE;
  }

  /** The tabs bar: shown while another tab's newer save of this document is neither taken nor overruled. */
  showTabs() {
    const cur = this.ctl.current;
    const bar = cur?.el.querySelector('.doc-tabs');
    if (!bar) return;
    const a = this.ctl.docs.get(cur.tool.id)?.autosave;
    bar.hidden = !a?.conflict;
    if (!a?.conflict) return;
    bar.querySelector('span').textContent = `This ${cur.tool.title} document was changed in another tab.${a.held ? ' Your changes here are not saved until you choose.' : ''}`;
  }

  /** Reload: the other tab's save becomes this tab's document (an undoable step: Undo brings this tab's back). */
  async takeOtherTab() {
    const ctl = this.ctl;
    const cur = ctl.current;
    const d = cur && ctl.docs.get(cur.tool.id);
    if (!d?.autosave || !d.history) return;
    const saved = await d.autosave.load();
    let state;
    try {
      if (!saved) throw new Error('the other tab\'s save is gone');
      state = await checkState(ctl.pool, cur.tool, saved.state, saved.version);
    } catch (err) {
      cur.ctx.error(new Error(`The other tab's version could not be read (${plainError(err) ?? 'cancelled'}); yours is kept.`));
      return;
    }
    if (ctl.current !== cur) return;
    d.autosave.adopt(d.autosave.rev);
    d.history.push(state);
    d.history.seal();
    ctl.refresh(); // not saved again: it is what is stored
    this.showTabs();
  }

  /** Keep mine: this tab's document is saved over the other tab's. */
  keepMine() {
    const cur = this.ctl.current;
    const d = cur && this.ctl.docs.get(cur.tool.id);
    if (!d?.autosave || !d.history) return;
    const over = d.autosave.conflict;
    this.save(cur.tool, d);
    d.autosave.flush({ over }).then(() => this.showTabs());
  }
}
