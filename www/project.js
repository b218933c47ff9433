// Projects (MISSION S8): every tool's state can be autosaved to IndexedDB,
// saved to / loaded from a project file, and undone/redone.
//
// State is plain data; byte inputs (images) are Uint8Arrays. IndexedDB stores
// them as they are; project files encode them as {"$bytes": base64}.

const DB_NAME = 'filigree';
const STORE = 'autosave';
export const PROJECT_FORMAT = 'filigree-project';
export const PROJECT_VERSION = 1;

function openDb() {
  return new Promise((resolve, reject) => {
    const req = indexedDB.open(DB_NAME, 1);
    req.onupgradeneeded = () => req.result.createObjectStore(STORE);
    req.onsuccess = () => resolve(req.result);
    req.onerror = () => reject(req.error);
  });
}

async function withStore(mode, fn) {
  const db = await openDb();
  try {
    return await new Promise((resolve, reject) => {
      const tx = db.transaction(STORE, mode);
      const req = fn(tx.objectStore(STORE));
      tx.oncomplete = () => resolve(req?.result);
      tx.onerror = () => reject(tx.error);
      tx.onabort = () => reject(tx.error);
    });
  } finally {
    db.close();
  }
}

let persistAsked = false;

/** Autosave of one tool's state: `load()` once on mount, `save(state)` on every change. */
export class Autosave {
  constructor(tool, { delayMs = 400 } = {}) {
    this.key = tool;
    this.delayMs = delayMs;
    this.timer = null;
    this.pending = null;
    this.lastSaved = Promise.resolve();
  }

  async load() {
    try {
      return (await withStore('readonly', (s) => s.get(this.key))) ?? null;
    } catch (err) {
      console.warn('autosave unavailable:', err);
      return null;
    }
  }

  /** Debounced write; `flush()` forces it (e.g. on pagehide). */
  save(state) {
    this.pending = state;
    clearTimeout(this.timer);
    this.timer = setTimeout(() => this.flush(), this.delayMs);
    if (!persistAsked && navigator.storage?.persist) {
      persistAsked = true;
      navigator.storage.persist().catch(() => {});
    }
  }

  flush() {
    clearTimeout(this.timer);
    if (this.pending === null) return this.lastSaved;
    const state = this.pending;
    this.pending = null;
    this.lastSaved = withStore('readwrite', (s) => s.put(state, this.key)).catch((err) => {
      console.warn('autosave failed:', err);
    });
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

function toBase64(bytes) {
  let s = '';
  for (let i = 0; i < bytes.length; i += 0x8000) s += String.fromCharCode(...bytes.subarray(i, i + 0x8000));
  return btoa(s);
}

function fromBase64(b64) {
  const bin = atob(b64);
  const out = new Uint8Array(bin.length);
  for (let i = 0; i < bin.length; i++) out[i] = bin.charCodeAt(i);
  return out;
}

function encode(v) {
  if (v instanceof Uint8Array) return { $bytes: toBase64(v) };
  if (Array.isArray(v)) return v.map(encode);
  if (v && typeof v === 'object') return Object.fromEntries(Object.entries(v).map(([k, x]) => [k, encode(x)]));
  return v;
}

function decode(v) {
  if (Array.isArray(v)) return v.map(decode);
  if (v && typeof v === 'object') {
    if (typeof v.$bytes === 'string') return fromBase64(v.$bytes);
    return Object.fromEntries(Object.entries(v).map(([k, x]) => [k, decode(x)]));
  }
  return v;
}

/** The text of a project file for `tool` with `state`. */
export function projectText(tool, state) {
  return JSON.stringify({ format: PROJECT_FORMAT, version: PROJECT_VERSION, tool, state: encode(state) });
}

/** Parse a project file's text; throws an Error saying what is wrong. */
export function parseProject(text, expectedTool) {
  let doc;
  try {
    doc = JSON.parse(text);
  } catch (err) {
    throw new Error(`not a Filigree project: the file is not valid JSON (${err.message})`);
  }
  if (doc?.format !== PROJECT_FORMAT) throw new Error('not a Filigree project: "format" is missing or different');
  if (doc.version > PROJECT_VERSION) throw new Error(`this project was saved by a newer Filigree (format ${doc.version})`);
  if (expectedTool && doc.tool !== expectedTool) throw new Error(`this is a ${doc.tool} project; open it in the ${doc.tool} tool`);
  return decode(doc.state);
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
