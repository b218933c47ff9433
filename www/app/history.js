// Undo history (MISSION S8): each tool's document is undone and redone
// over immutable snapshots, and the newest of them travel with the autosave
// (keptHistory, shareBytes).

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
