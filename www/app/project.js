// Projects (MISSION S8): storage, project files and undo history used by
// the document controller (document.js, its storage.js and open.js): every
// tool's state is autosaved to IndexedDB, saved to / loaded from a project
// file, and undone/redone.
//
// State is plain data; byte inputs (images) are Uint8Arrays. IndexedDB stores
// them as they are; project files encode them as {"$bytes": base64}.
// Reading a project file (envelope, bytes, the tool's state) is the core's
// `open-project` (src/api/project.rs), which knows the same format.

const DB_NAME = 'filigree';
const STORE = 'autosave';
export const PROJECT_FORMAT = 'filigree-project';
// File format 2 adds `stateVersion` (the tool's state schema version);
// format-1 files carry tool states of version 1.
export const PROJECT_VERSION = 2;
/** A storage call that has not answered by then is taken as refused (an
 * `about:blank` host or a third-party frame may hang IndexedDB for ever). */
export const STORAGE_TIMEOUT_MS = 1500;

/** `promise`, or a rejection once `ms` have passed. */
export function withTimeout(promise, ms, what) {
  let timer;
  return Promise.race([
    promise,
    new Promise((_, reject) => { timer = setTimeout(() => reject(new Error(`${what} did not answer within ${ms} ms`)), ms); }),
  ]).finally(() => clearTimeout(timer));
}

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

async function withStore(mode, fn) {
  const database = await db();
  return withTimeout(new Promise((resolve, reject) => {
    const tx = database.transaction(STORE, mode);
    const req = fn(tx.objectStore(STORE));
    tx.oncomplete = () => resolve(req?.result);
    tx.onerror = () => reject(tx.error);
    tx.onabort = () => reject(tx.error);
  }), STORAGE_TIMEOUT_MS, 'storage');
}

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
 * page can say plainly that it cannot save here. A write finds a newer
 * revision than this tab's (another tab saved) and does not happen:
 * `onConflict(rev)` hears it and the value stays pending until
 * `flush({over: rev})` (the user keeps theirs) or `adopt(rev)` (they took
 * the other tab's).
 */
export class Autosave {
  constructor(key, { delayMs = 400, onBlocked, onConflict } = {}) {
    this.key = key;
    this.delayMs = delayMs;
    this.timer = null;
    this.pending = null;
    this.lastSaved = Promise.resolve();
    this.onBlocked = onBlocked;
    this.onConflict = onConflict;
    this.blocked = false;
    this.rev = 0; // the revision this tab last read or wrote
    this.conflict = 0; // a newer revision of another tab, not taken nor overruled yet
  }

  fail(err) {
    console.warn('autosave unavailable:', err?.message || err);
    if (!this.blocked) { this.blocked = true; this.onBlocked?.(err); }
  }

  async load() {
    try {
      const v = (await withStore('readonly', (s) => s.get(this.key))) ?? null;
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
    if (this.blocked) { this.pending = null; return this.lastSaved; }
    if (this.conflict && over < this.conflict) return this.lastSaved; // held until the user decides
    const value = typeof this.pending === 'function' ? this.pending() : this.pending;
    this.pending = null;
    const base = Math.max(this.rev, over);
    let wrote = 0;
    let found = 0;
    this.lastSaved = withStore('readwrite', (s) => {
      const get = s.get(this.key);
      get.onsuccess = () => {
        found = revOf(get.result);
        if (found > base) return; // another tab saved after this one last read: do not overwrite it
        wrote = found + 1;
        s.put({ ...value, rev: wrote, tab: TAB_ID }, this.key);
      };
      return get;
    }).then(() => {
      if (wrote) {
        this.rev = wrote;
        if (this.conflict <= over) this.conflict = 0;
        tabChannel()?.postMessage({ key: this.key, rev: wrote, tab: TAB_ID });
      } else {
        if (this.pending === null) this.pending = value; // kept for Keep mine
        this.noteOther(found);
      }
    }, (err) => this.fail(err));
    return this.lastSaved;
  }
}

/**
 * Undo/redo over immutable snapshots. Consecutive pushes with the same
 * `coalesce` key (e.g. one slider being dragged) replace each other, so a
 * whole drag is one undo step.
 */
export class History {
  constructor(initial, { limit = 200 } = {}) {
    this.past = [];
    this.present = initial;
    this.future = [];
    this.limit = limit;
    this.lastKey = null;
  }

  push(state, { coalesce = null } = {}) {
    if (coalesce === null || coalesce !== this.lastKey) {
      this.past.push(this.present);
      if (this.past.length > this.limit) this.past.shift();
    }
    this.lastKey = coalesce;
    this.present = state;
    this.future = [];
  }

  /** End a coalescing run (call on pointerup/change) so the next drag is a new step. */
  seal() {
    this.lastKey = null;
  }

  get canUndo() { return this.past.length > 0; }
  get canRedo() { return this.future.length > 0; }

  undo() {
    if (!this.canUndo) return this.present;
    this.future.push(this.present);
    this.present = this.past.pop();
    this.lastKey = null;
    return this.present;
  }

  redo() {
    if (!this.canRedo) return this.present;
    this.past.push(this.present);
    this.present = this.future.pop();
    this.lastKey = null;
    return this.present;
  }
}

// ---- undo history kept with the autosave -------------------------------------------
//
// The autosave carries the newest states of the undo history (`past`, `future`,
// oldest first as History holds them): at most HISTORY_STATES each way and
// HISTORY_BYTES in all with the present, the states nearest the present kept
// first (past before future). Bytes are counted as IndexedDB stores a value:
// one byte array shared by many states (an image no edit touched) once, a
// string every time.

export const HISTORY_STATES = 50;
export const HISTORY_BYTES = 1 << 20;

/** About how many bytes `v` adds to a stored value; objects already in `seen` count nothing more. */
function storedSize(v, seen) {
  if (typeof v === 'string') return 8 + v.length;
  if (v === null || typeof v !== 'object') return 8;
  if (seen.has(v)) return 4;
  seen.add(v);
  if (ArrayBuffer.isView(v)) return 16 + (seen.has(v.buffer) ? 0 : (seen.add(v.buffer), v.byteLength));
  if (v instanceof ArrayBuffer) return v.byteLength;
  let n = 16;
  if (Array.isArray(v)) for (const x of v) n += storedSize(x, seen);
  else for (const k of Object.keys(v)) n += 8 + k.length + storedSize(v[k], seen);
  return n;
}

/**
 * What of history `h` the autosave keeps: {past, future} (each oldest first,
 * as History holds them), bounded by `states` each way and `bytes` in all.
 */
export function keptHistory(h, { states = HISTORY_STATES, bytes = HISTORY_BYTES } = {}) {
  const seen = new WeakSet();
  let total = storedSize(h.present, seen);
  // Both stacks end at the present (the next undo is past's last, the next redo future's last).
  const newest = (stack) => {
    const out = [];
    for (let i = stack.length - 1; i >= 0 && out.length < states; i--) {
      const size = storedSize(stack[i], seen);
      if (total + size > bytes) break;
      total += size;
      out.push(stack[i]);
    }
    return out.reverse();
  };
  const past = newest(h.past);
  const future = newest(h.future);
  return { past, future };
}

/**
 * Make the byte arrays of `states` that hold the same bytes as one of
 * `present`'s that very array (in place), so they are stored once again: the
 * core's check of a restored document hands back copies of its bytes, which
 * its restored history would otherwise keep a second time.
 */
export function shareBytes(states, present) {
  const mine = new Map(); // byteLength → arrays of present
  const visit = (v, fn, seen = new Set()) => {
    if (!v || typeof v !== 'object' || seen.has(v)) return v;
    seen.add(v);
    if (ArrayBuffer.isView(v)) return fn(v);
    for (const k of Object.keys(v)) {
      const x = visit(v[k], fn, seen);
      if (x !== v[k]) v[k] = x;
    }
    return v;
  };
  visit(present, (a) => {
    if (a instanceof Uint8Array) mine.set(a.byteLength, [...(mine.get(a.byteLength) || []), a]);
    return a;
  });
  if (!mine.size) return;
  const same = new Map(); // an array of the states → its twin in present
  const twin = (a) => {
    if (!(a instanceof Uint8Array)) return a;
    if (!same.has(a)) same.set(a, (mine.get(a.byteLength) || []).find((b) => b.every((x, i) => x === a[i])) || a);
    return same.get(a);
  };
  for (const s of states) visit(s, twin);
}

function toBase64(bytes) {
  let s = '';
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return btoa(s);
}

function encode(v) {
  if (v instanceof Uint8Array) return { $bytes: toBase64(v) };
  if (Array.isArray(v)) return v.map(encode);
  if (v && typeof v === 'object') return Object.fromEntries(Object.entries(v).map(([k, x]) => [k, encode(x)]));
  return v;
}

/** The text of a project file for `tool` whose state (schema `stateVersion`) is `state`. */
export function projectText(tool, stateVersion, state) {
  return JSON.stringify({ format: PROJECT_FORMAT, version: PROJECT_VERSION, tool, stateVersion, state: encode(state) });
}

/** Offer `data` (string, bytes or Blob) as a download named `name`. */
export function download(name, data, type = 'application/octet-stream') {
  const blob = data instanceof Blob ? data : new Blob([data], { type });
  const a = document.createElement('a');
  a.href = URL.createObjectURL(blob);
  a.download = name;
  document.body.append(a);
  a.click();
  a.remove();
  setTimeout(() => URL.revokeObjectURL(a.href), 10000);
}
