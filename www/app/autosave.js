// Autosave (MISSION S8): every tool's document is written to IndexedDB
// after each change and read back at its first sight (the document
// controller's storage.js drives it). State is plain data; byte inputs
// (images) are Uint8Arrays, stored as they are. Two tabs share one autosave
// per tool and never overwrite each other's newer save silently.

import { withTimeout } from '../ui/timeout.js';

const DB_NAME = 'filigree';
const STORE = 'autosave';
/** A storage call that has not answered by then is taken as refused (an
 * `about:blank` host or a third-party frame may hang IndexedDB for ever). */
export const STORAGE_TIMEOUT_MS = 1500;

function openDb() {
  return new Promise((resolve, reject) => {
    const req = indexedDB.open(DB_NAME, 1); // throws in an opaque origin
    req.onupgradeneeded = () => req.result.createObjectStore(STORE);
    req.onsuccess = () => resolve(req.result);
    req.onerror = () => reject(req.error);
    req.onblocked = () => reject(new Error('the database is blocked by another tab'));
  });
}

let dbPromise = null;
function db() {
  if (!dbPromise) {
    dbPromise = withTimeout(new Promise((resolve, reject) => {
      try { openDb().then(resolve, reject); } catch (err) { reject(err); }
    }), STORAGE_TIMEOUT_MS, 'storage');
    dbPromise.catch(() => { dbPromise = null; });
  }
  return dbPromise;
}

/** The transaction of `fn(store)` in `mode`: resolves with its request's result once committed, however long that takes. */
async function transact(mode, fn) {
  const database = await db();
  return new Promise((resolve, reject) => {
    const tx = database.transaction(STORE, mode);
    const req = fn(tx.objectStore(STORE));
    tx.oncomplete = () => resolve(req?.result);
    tx.onerror = () => reject(tx.error);
    tx.onabort = () => reject(tx.error);
  });
}

/** `transaction`, or a rejection once STORAGE_TIMEOUT_MS have passed (it may still commit later). */
const timed = (transaction) => withTimeout(transaction, STORAGE_TIMEOUT_MS, 'storage');

let persistAsked = false;

// ---- tabs ---------------------------------------------------------------------------------
//
// Two tabs of the app share one autosave per tool. Every autosave carries a
// revision (`rev`, counting up from 1) and the id of the tab that wrote it;
// a tab writes only over the revision it last read or wrote, in the same
// transaction as it checks, so a newer save of another tab is never
// overwritten silently (`onConflict` hears about it instead). After a
// write the tab says so on a BroadcastChannel, so the others learn at once
// (`onOtherTab`), not only when they next save.

/** This tab's id, in every autosave it writes. */
export const TAB_ID = Math.random().toString(36).slice(2, 10);
const CHANNEL_NAME = 'filigree-autosave';
let channel = null;
const tabListeners = new Set();

function tabChannel() {
  if (!channel && typeof BroadcastChannel === 'function') {
    try {
      channel = new BroadcastChannel(CHANNEL_NAME);
      channel.onmessage = (e) => {
        const m = e.data;
        if (!m || typeof m.key !== 'string' || !Number.isInteger(m.rev) || m.tab === TAB_ID) return;
        for (const fn of tabListeners) fn(m);
      };
    } catch { /* an opaque origin: no channel; the revision check still holds */ }
  }
  return channel;
}

/** `fn({key, rev, tab})` whenever another tab of this origin saved the autosave `key`. Returns an unsubscribe function. */
export function onOtherTab(fn) {
  tabChannel();
  tabListeners.add(fn);
  return () => tabListeners.delete(fn);
}

/** The revision of a stored autosave (0 for none, and for one saved before revisions). */
const revOf = (v) => (Number.isInteger(v?.rev) && v.rev > 0 ? v.rev : 0);

/**
 * Autosave of one key: `load()` once, `save(value)` on every change
 * (debounced), `flush()` on pagehide or when leaving. Every call fails fast
 * (STORAGE_TIMEOUT_MS); `onBlocked(err)` hears about the first failure so the
 * page can say plainly that it cannot save here, and `onUnblocked()` when a
 * write commits after all (a slow disk, not a refusal): each change is
 * tried again, none is dropped for good. A write finds a newer
 * revision than this tab's (another tab saved) and does not happen:
 * `onConflict(rev)` hears it and the value stays pending until
 * `flush({over: rev})` (the user keeps theirs) or `adopt(rev)` (they took
 * the other tab's).
 */
export class Autosave {
  constructor(key, { delayMs = 400, onBlocked, onUnblocked, onConflict } = {}) {
    this.key = key;
    this.delayMs = delayMs;
    this.timer = null;
    this.pending = null;
    this.lastSaved = Promise.resolve();
    this.onBlocked = onBlocked;
    this.onUnblocked = onUnblocked;
    this.onConflict = onConflict;
    this.blocked = false;
    this.rev = 0; // the revision this tab last read or wrote
    this.conflict = 0; // a newer revision of another tab, not taken nor overruled yet
  }

  fail(err) {
    console.warn('autosave unavailable:', err?.message || err);
    if (!this.blocked) { this.blocked = true; this.onBlocked?.(err); }
  }

  /** A write committed: storage works (again), however slow it was. */
  worked() {
    if (this.blocked) { this.blocked = false; this.onUnblocked?.(); }
  }

  async load() {
    try {
      const v = (await timed(transact('readonly', (s) => s.get(this.key)))) ?? null;
      this.rev = revOf(v);
      if (this.conflict <= this.rev) this.conflict = 0;
      return v;
    } catch (err) {
      this.fail(err);
      return null;
    }
  }

  /** Debounced write of `value` (or of what the function `value()` answers when it is written); `flush()` forces it. */
  save(value) {
    this.pending = value;
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.flush(), this.delayMs);
    if (!persistAsked && navigator.storage?.persist) {
      persistAsked = true;
      withTimeout(Promise.resolve().then(() => navigator.storage.persist()), STORAGE_TIMEOUT_MS, 'storage.persist')
        .catch(() => {});
    }
  }

  /** Drop a pending write (e.g. the document was rejected). */
  cancel() {
    clearTimeout(this.timer);
    this.pending = null;
  }

  /** Another tab's revision `rev` is now this tab's document: later writes go over it. */
  adopt(rev) {
    this.rev = Math.max(this.rev, rev);
    if (this.conflict <= rev) this.conflict = 0;
    this.cancel();
  }

  /** Another tab said it saved revision `rev` (onOtherTab). */
  noteOther(rev) {
    if (rev > this.rev && rev > this.conflict) {
      this.conflict = rev;
      this.onConflict?.(rev);
    }
  }

  /** Whether this tab holds a change that is not saved because another tab saved meanwhile. */
  get held() {
    return this.pending !== null && this.conflict > 0;
  }

  /**
   * Write the pending value, unless a newer revision than this tab's is
   * stored; `over` = the revision the user chose to overrule (Keep mine).
   */
  flush({ over = 0 } = {}) {
    clearTimeout(this.timer);
    if (this.pending === null) return this.lastSaved;
    if (this.conflict && over < this.conflict) return this.lastSaved; // held until the user decides
    const value = typeof this.pending === 'function' ? this.pending() : this.pending;
    this.pending = null;
    let wrote = 0;
    let found = 0;
    const write = transact('readwrite', (s) => {
      const get = s.get(this.key);
      get.onsuccess = () => {
        // This tab's revision as of now: a write of this tab still out when
        // this one was started has committed (the store runs them in turn)
        // and is not taken for another tab's.
        const base = Math.max(this.rev, over);
        found = revOf(get.result);
        if (found > base) return; // another tab saved after this one last read: do not overwrite it
        wrote = found + 1;
        s.put({ ...value, rev: wrote, tab: TAB_ID }, this.key);
      };
      return get;
    });
    // What the write did is recorded when it commits, even after the timeout
    // has called storage blocked: a slow write that lands still moves this
    // tab's revision on and tells the other tabs, and a failed one is tried
    // again with the next change.
    write.then(() => {
      this.worked();
      if (wrote) {
        this.rev = Math.max(this.rev, wrote);
        if (this.conflict <= over) this.conflict = 0;
        tabChannel()?.postMessage({ key: this.key, rev: wrote, tab: TAB_ID });
      } else {
        if (this.pending === null) this.pending = value; // kept for Keep mine
        this.noteOther(found);
      }
    }, () => {
      if (this.pending === null) this.pending = value; // written with the next change, if storage comes back
    });
    this.lastSaved = timed(write).catch((err) => this.fail(err));
    return this.lastSaved;
  }
}

