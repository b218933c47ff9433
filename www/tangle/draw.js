// Drawing a `tangle` answer (src/tangle/api.rs TangleResponse) on a 2-D
// canvas, pen-and-ink: black strokes on paper white, grey fills for `fill`,
// black with white lines for `white_lines`, filled marks for `mark`.
//
//   const t = prepareTangle(response, link?)  per-shape bounding boxes, styles, lazily built Path2Ds
//                                       (the byte columns of shapes and steps viewed as typed arrays);
//                                       with `link` (delta.js applyDelta: the answer was a delta of
//                                       the prepared answer `link.T`), the shapes the delta kept
//                                       keep their Path2Ds
//   t.visible(i, k)                     shape i shown after k steps (k = steps.length: final)
//   t.batches(k) → {k, parts, count}    what step k shows: a few Path2D batches per ink style
//                                       (a segment tree over steps, nodes built lazily, kept;
//                                       a part's `span`: how many steps show it)
//   paintBatches(g, batches, lineWidth, layers?, key?)  draws them (g already transformed);
//                                       with createLayers(), heavy parts come from bitmaps
//   t.changes(k, from, kFrom)           shapes shown at step k of t and not at step kFrom of `from`
//                                       (t itself, or the base of t's delta: what the delta says)
//   t.regionParts(k, keep) → {parts}    batches(k) cut down to the shapes passing keep(i)
//   t.pick(x, y, k, g) → shape index    the smallest shape shown at step k containing (x, y)
//   t.subtree(s) → Set of shape indices made by step s or by steps that depend on it
//   drawThumbnail(canvas, response)     the final shapes fitted into a small canvas

/** Visible after k steps: made before step k (or a start shape) and not yet consumed by a step < k. */
export const shownAt = (born, died, k) => born < k && (died === -1 || died >= k);

/** Fill grey of a tone (0 = paper, 1 = black), as the core's export writes it. */
const greyOf = (tone) => Math.round(255 * (1 - Math.min(1, Math.max(0, tone))));

/** The answer's points (f32 little-endian bytes, src/tangle/api.rs) as a Float32Array. */
export function pointsOf(bytes) {
  if (bytes instanceof Float32Array) return bytes;
  const u8 = bytes.byteOffset % 4 === 0 ? bytes : bytes.slice();
  const view = new DataView(u8.buffer, u8.byteOffset, u8.byteLength);
  const n = u8.byteLength >> 2;
  // Little-endian on every platform a browser runs on; read it right anywhere else.
  if (new Uint8Array(new Uint16Array([1]).buffer)[0] === 1) return new Float32Array(u8.buffer, u8.byteOffset, n);
  const out = new Float32Array(n);
  for (let i = 0; i < n; i++) out[i] = view.getFloat32(4 * i, true);
  return out;
}

/** A column of little-endian bytes as a typed array of `Type`. */
export function column(bytes, Type) {
  if (bytes instanceof Type) return bytes;
  const u8 = bytes.byteOffset % Type.BYTES_PER_ELEMENT === 0 ? bytes : bytes.slice();
  const n = u8.byteLength / Type.BYTES_PER_ELEMENT;
  if (new Uint8Array(new Uint16Array([1]).buffer)[0] === 1) return new Type(u8.buffer, u8.byteOffset, n);
  const view = new DataView(u8.buffer, u8.byteOffset, u8.byteLength);
  const get = { 1: 'getUint8', 4: Type === Float32Array ? 'getFloat32' : Type === Int32Array ? 'getInt32' : 'getUint32' }[Type.BYTES_PER_ELEMENT];
  return Type.from({ length: n }, (_, i) => view[get](i * Type.BYTES_PER_ELEMENT, true));
}

/**
 * The answer's shapes (columns of bytes, src/tangle/api.rs `shape_columns`)
 * as typed arrays, plus `at(i)`: shape i as an object
 * {key, tag, group, id, born, died, first, rings, fill, white_lines, mark}.
 */
export function shapeColumns(c) {
  if (c.born instanceof Int32Array) return c;
  return withAccessors({
    count: c.count, key: column(c.key, Uint32Array),
    tag: column(c.tag, Uint32Array), group: column(c.group, Uint32Array), id: column(c.id, Uint32Array),
    first: column(c.first, Uint32Array), born: column(c.born, Int32Array), died: column(c.died, Int32Array),
    fill: column(c.fill, Float32Array), flags: column(c.flags, Uint8Array),
    ringFirst: column(c.ring_first, Uint32Array), rings: column(c.rings, Uint32Array),
  });
}

/** Typed shape columns `S` with `ringsOf(i)` and `at(i)` added. */
export function withAccessors(S) {
  S.ringsOf = (i) => S.rings.subarray(S.ringFirst[i], S.ringFirst[i + 1]);
  S.at = (i) => ({
    key: S.key[i], tag: S.tag[i], group: S.group[i], id: S.id[i], born: S.born[i], died: S.died[i], first: S.first[i],
    rings: [...S.ringsOf(i)], fill: S.fill[i], white_lines: (S.flags[i] & 1) !== 0, mark: (S.flags[i] & 2) !== 0,
  });
  return S;
}

/** The answer's steps, each step's `inputs` and `outputs` (u32 little-endian bytes, src/tangle/api.rs `StepOut`) viewed as Uint32Arrays, in place. */
export function stepsOf(steps) {
  for (const st of steps) {
    st.inputs = column(st.inputs, Uint32Array);
    st.outputs = column(st.outputs, Uint32Array);
  }
  return steps;
}

export function prepareTangle(r, link = null) {
  const S = r.shapes = shapeColumns(r.shapes);
  stepsOf(r.steps);
  const n = S.count;
  const pts = pointsOf(r.points);
  const { born, died, first } = S;
  const box = new Float32Array(4 * n);
  const paths = new Array(n);
  // After an edit most shapes are the base's (the delta kept them): they keep their Path2Ds.
  if (link) for (let i = 0; i < n; i++) if (link.oldOf[i] >= 0) paths[i] = link.T.paths[link.oldOf[i]];
  for (let i = 0; i < n; i++) {
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    const outer = S.rings[S.ringFirst[i]] || 0; // the outer ring bounds the shape
    for (let p = first[i] * 2, e = (first[i] + outer) * 2; p < e; p += 2) {
      const x = pts[p], y = pts[p + 1];
      if (x < x0) x0 = x;
      if (x > x1) x1 = x;
      if (y < y0) y0 = y;
      if (y > y1) y1 = y;
    }
    box[4 * i] = x0; box[4 * i + 1] = y0; box[4 * i + 2] = x1; box[4 * i + 3] = y1;
  }

  /** Append shape i's rings to path p. */
  function trace(p, i) {
    let o = first[i] * 2;
    for (const len of S.ringsOf(i)) {
      if (!len) continue;
      p.moveTo(pts[o], pts[o + 1]);
      for (let j = 1; j < len; j++) p.lineTo(pts[o + 2 * j], pts[o + 2 * j + 1]);
      p.closePath();
      o += 2 * len;
    }
  }
  const pathOf = (i) => {
    if (!paths[i]) { paths[i] = new Path2D(); trace(paths[i], i); }
    return paths[i];
  };

  // Shape i is shown for k in [born + 1, died] (died -1: to the end). For the
  // step slider, the shapes sit in a segment tree over k: each interval is
  // split over O(log steps) nodes, and the shapes shown at k are exactly those
  // of the nodes on the root-to-k path, each in one of them. A node's Path2Ds
  // are built the first time a step below it is shown, so a slider move
  // paints ~log2(steps) batches per ink style and builds only what it has not
  // seen before: the upper nodes (most of the picture) are shared by all steps.
  const nSteps = r.steps.length;
  const members = new Map(); // node (heap numbering, root 1) → shape indices
  const built = new Map(); // node → its batches
  function insert(node, lo, hi, a, b, i) {
    if (b < lo || a > hi) return;
    if (a <= lo && hi <= b) {
      if (!members.has(node)) members.set(node, []);
      members.get(node).push(i);
      return;
    }
    const mid = (lo + hi) >> 1;
    insert(2 * node, lo, mid, a, b, i);
    insert(2 * node + 1, mid + 1, hi, a, b, i);
  }
  for (let i = 0; i < n; i++) insert(1, 0, nSteps, born[i] + 1, died[i] === -1 ? nSteps : died[i], i);

  /** Shapes `list` (those passing `keep`) as one batch: one Path2D per ink style (fills by grey). */
  function batchOfList(list, keep = null) {
    const b = { fills: new Map(), black: null, white: null, marks: null, count: 0, vertices: 0 };
    const add = (key, i) => {
      // Each shape's own Path2D is built once per answer; a batch copies it
      // natively (addPath), far cheaper than tracing every vertex again.
      if (!b[key]) b[key] = new Path2D();
      b[key].addPath(pathOf(i));
    };
    for (const i of list) {
      if (keep && !keep(i)) continue;
      b.count++;
      for (const len of S.ringsOf(i)) b.vertices += len;
      if (S.flags[i] & 2) { add('marks', i); continue; }
      if (S.fill[i] > 0) {
        const g = greyOf(S.fill[i]);
        if (!b.fills.has(g)) b.fills.set(g, new Path2D());
        b.fills.get(g).addPath(pathOf(i));
      }
      add(S.flags[i] & 1 ? 'white' : 'black', i);
    }
    return b;
  }
  /** How many steps show the shapes of a node (the length of its interval). */
  function spanOf(node) {
    let lo = 0, hi = nSteps;
    for (let bit = 30 - Math.clz32(node); bit >= 0; bit--) {
      const mid = (lo + hi) >> 1;
      if ((node >> bit) & 1) lo = mid + 1; else hi = mid;
    }
    return hi - lo + 1;
  }
  /** The batches of a node, built once; `span`: how many steps show them. */
  function batchOf(node) {
    let b = built.get(node);
    if (!b) {
      built.set(node, b = batchOfList(members.get(node) || []));
      b.span = spanOf(node);
    }
    return b;
  }
  /** Nodes on the root-to-k path of the step tree that hold shapes. */
  function nodesOf(k) {
    const out = [];
    for (let node = 1, lo = 0, hi = nSteps; ;) {
      if (members.has(node)) out.push(node);
      if (lo === hi) break;
      const mid = (lo + hi) >> 1;
      if (k <= mid) { node = 2 * node; hi = mid; } else { node = 2 * node + 1; lo = mid + 1; }
    }
    return out;
  }

  let cached = null;
  let heavy = null;
  const t = {
    r, n, pts, born, died, box, paths,
    /** The base of the delta this answer was made from (until the panel drops it, once painted). */
    from: link ? link.T : null,
    /** Whether this answer was made from a delta. */
    delta: !!link,
    steps: nSteps,
    visible: (i, k) => shownAt(born[i], died[i], k),
    count(k) {
      let c = 0;
      for (let i = 0; i < n; i++) if (shownAt(born[i], died[i], k)) c++;
      return c;
    },
    path: pathOf,
    /** Vertices of shape i (all its rings). */
    vertices(i) {
      let v = 0;
      for (let q = S.ringFirst[i], e = S.ringFirst[i + 1]; q < e; q++) v += S.rings[q];
      return v;
    },
    /** What step k shows, as `{k, parts, count}`: the batches of the nodes on its path. */
    batches(k) {
      if (cached?.k === k) return cached;
      const parts = [];
      let count = 0;
      for (const node of nodesOf(k)) {
        const b = batchOf(node);
        parts.push(b);
        count += b.count;
      }
      cached = { k, parts, count };
      return cached;
    },
    /**
     * What `batches(k)` paints, cut down to the shapes passing `keep(i)`,
     * part by part in the same order (not kept): repainting a clipped
     * region draws only the shapes that reach into it.
     */
    regionParts(k, keep) {
      const parts = [], nodes = [];
      nodesOf(k).forEach((node, at) => {
        const b = batchOfList(members.get(node), keep);
        if (b.count) { parts.push(b); nodes.push(at); }
      });
      return { k, parts, nodes }; // nodes[p]: the index in batches(k).parts that part p is cut from
    },
    /**
     * What differs between step `k` of this answer and step `kFrom` of
     * `from`: `from` is this answer (a slider move) or the base of the
     * delta it was made from (an edit; then only between the final steps,
     * where the delta says it: its added and removed shapes, as shown
     * there). `{added, removed}`: shapes of this answer shown now and not
     * then, and shapes of `from` shown then and not now; false when not known.
     */
    changes(k, from, kFrom) {
      const added = [], removed = [];
      if (from === t) {
        for (let i = 0; i < n; i++) {
          const now = shownAt(born[i], died[i], k), then = shownAt(born[i], died[i], kFrom);
          if (now && !then) added.push(i); else if (then && !now) removed.push(i);
        }
      } else if (link && from === t.from && k === nSteps && kFrom === from.steps) {
        // A kept shape is consumed in both answers or in neither (src/tangle/api.rs
        // `same_shape`), so at the final steps it is shown in both or in neither.
        for (const i of link.added) if (shownAt(born[i], died[i], k)) added.push(i);
        for (const j of link.removed) if (from.visible(j, kFrom)) removed.push(j);
      } else return false;
      return { added, removed };
    },
    /**
     * The parts (step-tree nodes) with at least `min` vertices, heaviest
     * first, as `{vertices, part()}` (part() builds the node's batches): what
     * may be prepared as bitmaps before a slider move needs them.
     */
    heavyParts(min = LAYER_VERTICES) {
      if (heavy?.min === min) return heavy.out;
      const out = [];
      for (const [node, list] of members) {
        let v = 0;
        for (const i of list) v += t.vertices(i);
        if (v >= min) out.push({ vertices: v, part: () => batchOf(node) });
      }
      heavy = { min, out: out.sort((a, b) => b.vertices - a.vertices) };
      return heavy.out;
    },
    /** Shapes kept from the delta's base (`prepareTangle(r, link)`), for tests. */
    get reused() { return link ? link.oldOf.reduce((a, j) => a + (j >= 0), 0) : 0; },
    /** The smallest shape shown at step k whose outline contains (x, y), or -1. */
    pick(x, y, k, g) {
      let best = -1, bestArea = Infinity;
      for (let i = 0; i < n; i++) {
        const b = 4 * i;
        if (x < box[b] || x > box[b + 2] || y < box[b + 1] || y > box[b + 3]) continue;
        if (!shownAt(born[i], died[i], k)) continue;
        const area = (box[b + 2] - box[b]) * (box[b + 3] - box[b + 1]);
        if (area >= bestArea) continue;
        g.save();
        g.setTransform(1, 0, 0, 1, 0, 0);
        const inside = g.isPointInPath(pathOf(i), x, y, 'evenodd');
        g.restore();
        if (inside) { best = i; bestArea = area; }
      }
      return best;
    },
    /** Shapes made by step s or by a later step whose inputs are among them (the step's subtree). */
    subtree(s) {
      const made = new Set(r.steps[s]?.outputs || []);
      for (let k = s + 1; k < r.steps.length; k++) {
        const st = r.steps[k];
        if (st.inputs.some((i) => made.has(i))) for (const o of st.outputs) made.add(o);
      }
      return made;
    },
    /** Positions of the steps that depend on step s (itself included), as the core's `dependents`. */
    dependents(s) {
      const made = new Set();
      const out = [];
      for (let k = s; k < r.steps.length; k++) {
        const st = r.steps[k];
        if (k === s || st.inputs.some((i) => made.has(i))) {
          out.push(k);
          for (const o of st.outputs) made.add(o);
        }
      }
      return out;
    },
    /** [x0, y0, x1, y1] of shapes `list`. */
    bounds(list) {
      let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
      for (const i of list) {
        const b = 4 * i;
        x0 = Math.min(x0, box[b]); y0 = Math.min(y0, box[b + 1]);
        x1 = Math.max(x1, box[b + 2]); y1 = Math.max(y1, box[b + 3]);
      }
      return Number.isFinite(x0) ? [x0, y0, x1, y1] : null;
    },
  };
  return t;
}

/** One part's ink: fills, black lines, white lines, marks. */
function paintPart(g, b, lineWidth) {
  for (const [grey, p] of b.fills) {
    g.fillStyle = `rgb(${grey},${grey},${grey})`;
    g.fill(p, 'evenodd');
  }
  if (lineWidth > 0) {
    g.lineJoin = 'round';
    g.lineWidth = lineWidth;
    g.strokeStyle = '#000';
    if (b.black) g.stroke(b.black);
    g.strokeStyle = '#fff';
    if (b.white) g.stroke(b.white);
  }
  g.fillStyle = '#000';
  if (b.marks) g.fill(b.marks, 'evenodd');
}

/** Parts with at least this many vertices are drawn from a bitmap when `layers` are given. */
export const LAYER_VERTICES = 20000;

/** Canvases of dropped bitmaps kept for new ones (a canvas's memory is not made anew). */
const SPARE_CANVASES = 4;

/**
 * Bitmaps of heavy parts for one view, least recently used dropped beyond a
 * memory budget. Rasterising lines is most of a repaint (900k vertices: ~200 ms
 * in software); the big parts of a step's picture (the upper nodes of the
 * step tree) are shared by neighbouring steps, so a slider move redraws only
 * the small parts and copies the rest.
 */
export function createLayers(budgetBytes = 96e6) {
  const cache = new Map(); // part → {key, canvas}
  const spare = []; // canvases of dropped bitmaps, for the next ones
  return {
    /** `part`'s bitmap for view `key` on a w×h canvas; `render(g)` draws it when missing. */
    get(part, key, w, h, render) {
      let e = cache.get(part);
      cache.delete(part);
      if (!e || e.key !== key || e.canvas.width !== w || e.canvas.height !== h) {
        const canvas = e?.canvas || spare.pop() || document.createElement('canvas');
        canvas.width = w; // clears it
        canvas.height = h;
        render(canvas.getContext('2d'));
        e = { key, canvas };
      }
      cache.set(part, e);
      const keep = Math.max(2, Math.floor(budgetBytes / (4 * w * h)));
      for (const [old, o] of cache) {
        if (cache.size <= keep) break;
        cache.delete(old);
        if (spare.length < SPARE_CANVASES) spare.push(o.canvas);
      }
      return e.canvas;
    },
    /** Whether `part`'s bitmap for view `key` on a w×h canvas is kept. */
    has(part, key, w, h) {
      const e = cache.get(part);
      return !!e && e.key === key && e.canvas.width === w && e.canvas.height === h;
    },
    /** How many w×h bitmaps the budget keeps. */
    capacity: (w, h) => Math.max(2, Math.floor(budgetBytes / (4 * w * h))),
    clear: () => cache.clear(),
    get size() { return cache.size; },
  };
}

/**
 * Draw what `batches(k)` returned, part by part (a part's lines cover its
 * own fills; parts do not overlap, and a shared edge is drawn by both
 * sides). `g` maps drawing units to the canvas. With `layers`
 * (createLayers), heavy parts are copied from bitmaps of view `key`; with
 * `keep(part)` too, a heavy part without a bitmap gets one only when keep
 * says so (else it is drawn directly: a bitmap costs a second pass).
 */
export function paintBatches(g, { parts }, lineWidth, layers = null, key = '', keep = null) {
  for (const b of parts) {
    if (!layers || b.vertices < LAYER_VERTICES
      || (keep && !keep(b) && !layers.has(b, key, g.canvas.width, g.canvas.height))) {
      paintPart(g, b, lineWidth);
      continue;
    }
    const m = g.getTransform();
    const bitmap = layers.get(b, key, g.canvas.width, g.canvas.height, (lg) => {
      lg.setTransform(m);
      paintPart(lg, b, lineWidth);
    });
    g.save();
    g.setTransform(1, 0, 0, 1, 0, 0);
    g.drawImage(bitmap, 0, 0);
    g.restore();
  }
}

// A 1×1 canvas that layer bitmaps are drawn into to make the browser rasterise them.
let touch = null;

/**
 * Draw `part`'s bitmap for view `key` into `layers` ahead of need (idle
 * time), with transform `m` (a DOMMatrix) and pen `lineWidth`, and have the
 * browser rasterise it now rather than when a slider move first shows it.
 * (Drawing one pixel of it elsewhere takes a snapshot, which rasterises it;
 * reading a pixel back did too, but repeated read-backs of a canvas made
 * Chromium warn and move it off the GPU: willReadFrequently.)
 */
export function prebuildLayer(layers, part, key, w, h, m, lineWidth) {
  const c = layers.get(part, key, w, h, (lg) => {
    lg.setTransform(m);
    paintPart(lg, part, lineWidth);
  });
  touch ??= document.createElement('canvas').getContext('2d');
  touch.canvas.width = 1;
  touch.canvas.height = 1;
  touch.drawImage(c, 0, 0, 1, 1, 0, 0, 1, 1);
}

/** The final shapes of `r` fitted into `canvas` (white paper, thin black lines). */
export function drawThumbnail(canvas, r) {
  const t = prepareTangle(r);
  const g = canvas.getContext('2d');
  const [x0, y0, x1, y1] = r.bounds;
  const w = canvas.width, h = canvas.height;
  g.fillStyle = '#fff';
  g.fillRect(0, 0, w, h);
  const s = Math.min((w - 8) / Math.max(1e-9, x1 - x0), (h - 8) / Math.max(1e-9, y1 - y0));
  if (!Number.isFinite(s) || s <= 0) return;
  g.setTransform(s, 0, 0, s, (w - s * (x1 - x0)) / 2 - s * x0, (h - s * (y1 - y0)) / 2 - s * y0);
  paintBatches(g, t.batches(t.steps), 0.8 / s);
  g.setTransform(1, 0, 0, 1, 0, 0);
}
