// Drawing a `tangle` answer (src/tangle/api.rs TangleResponse) on a 2-D
// canvas, pen-and-ink: black strokes on paper white, grey fills for `fill`,
// black with white lines for `white_lines`, filled marks for `mark`.
//
//   const t = prepareTangle(response)   per-shape bounding boxes, styles, lazily built Path2Ds
//   t.visible(i, k)                     shape i shown after k steps (k = steps.length: final)
//   t.batches(k) → {k, parts, count}    what step k shows: a few Path2D batches per ink style
//                                       (a segment tree over steps, nodes built lazily, kept)
//   paintBatches(g, batches, lineWidth, layers?, key?)  draws them (g already transformed);
//                                       with createLayers(), heavy parts come from bitmaps
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

export function prepareTangle(r) {
  const n = r.shapes.length;
  const pts = pointsOf(r.points);
  const born = new Int32Array(n);
  const died = new Int32Array(n);
  const box = new Float32Array(4 * n);
  const paths = new Array(n);
  for (let i = 0; i < n; i++) {
    const s = r.shapes[i];
    born[i] = s.born;
    died[i] = s.died;
    let x0 = Infinity, y0 = Infinity, x1 = -Infinity, y1 = -Infinity;
    const outer = s.rings[0] || 0; // the outer ring bounds the shape
    for (let p = s.first * 2, e = (s.first + outer) * 2; p < e; p += 2) {
      const x = pts[p], y = pts[p + 1];
      if (x < x0) x0 = x;
      if (x > x1) x1 = x;
      if (y < y0) y0 = y;
      if (y > y1) y1 = y;
    }
    box.set([x0, y0, x1, y1], 4 * i);
  }

  /** Append shape i's rings to path p. */
  function trace(p, i) {
    const s = r.shapes[i];
    let o = s.first * 2;
    for (const len of s.rings) {
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
  const S = r.steps.length;
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
  for (let i = 0; i < n; i++) insert(1, 0, S, born[i] + 1, died[i] === -1 ? S : died[i], i);

  /** The batches of a node: one Path2D per ink style (fills by grey). */
  function batchOf(node) {
    let b = built.get(node);
    if (b) return b;
    b = { fills: new Map(), black: null, white: null, marks: null, count: 0, vertices: 0 };
    const add = (key, i) => {
      // Each shape's own Path2D is built once per answer; a batch copies it
      // natively (addPath), far cheaper than tracing every vertex again.
      if (!b[key]) b[key] = new Path2D();
      b[key].addPath(pathOf(i));
    };
    for (const i of members.get(node) || []) {
      b.count++;
      const s = r.shapes[i];
      for (const len of s.rings) b.vertices += len;
      if (s.mark) { add('marks', i); continue; }
      if (s.fill > 0) {
        const g = greyOf(s.fill);
        if (!b.fills.has(g)) b.fills.set(g, new Path2D());
        b.fills.get(g).addPath(pathOf(i));
      }
      add(s.white_lines ? 'white' : 'black', i);
    }
    built.set(node, b);
    return b;
  }

  let cached = null;
  const t = {
    r, n, pts, born, died, box,
    steps: S,
    visible: (i, k) => shownAt(born[i], died[i], k),
    count(k) {
      let c = 0;
      for (let i = 0; i < n; i++) if (shownAt(born[i], died[i], k)) c++;
      return c;
    },
    path: pathOf,
    /** What step k shows, as `{k, parts, count}`: the batches of the nodes on its path. */
    batches(k) {
      if (cached?.k === k) return cached;
      const parts = [];
      let count = 0;
      for (let node = 1, lo = 0, hi = S; ;) {
        if (members.has(node)) {
          const b = batchOf(node);
          parts.push(b);
          count += b.count;
        }
        if (lo === hi) break;
        const mid = (lo + hi) >> 1;
        if (k <= mid) { node = 2 * node; hi = mid; } else { node = 2 * node + 1; lo = mid + 1; }
      }
      cached = { k, parts, count };
      return cached;
    },
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

/**
 * Bitmaps of heavy parts for one view, least recently used dropped beyond a
 * memory budget. Rasterising lines is most of a repaint (900k vertices: ~200 ms
 * in software); the big parts of a step's picture (the upper nodes of the
 * step tree) are shared by neighbouring steps, so a slider move redraws only
 * the small parts and copies the rest.
 */
export function createLayers(budgetBytes = 96e6) {
  const cache = new Map(); // part → {key, canvas}
  return {
    /** `part`'s bitmap for view `key` on a w×h canvas; `render(g)` draws it when missing. */
    get(part, key, w, h, render) {
      let e = cache.get(part);
      cache.delete(part);
      if (!e || e.key !== key || e.canvas.width !== w || e.canvas.height !== h) {
        const canvas = e?.canvas || document.createElement('canvas');
        canvas.width = w;
        canvas.height = h;
        const g = canvas.getContext('2d');
        g.clearRect(0, 0, w, h);
        render(g);
        e = { key, canvas };
      }
      cache.set(part, e);
      const keep = Math.max(2, Math.floor(budgetBytes / (4 * w * h)));
      for (const old of cache.keys()) {
        if (cache.size <= keep) break;
        cache.delete(old);
      }
      return e.canvas;
    },
    clear: () => cache.clear(),
    get size() { return cache.size; },
  };
}

/**
 * Draw what `batches(k)` returned, part by part (a part's lines cover its
 * own fills; parts do not overlap, and a shared edge is drawn by both
 * sides). `g` maps drawing units to the canvas. With `layers`
 * (createLayers), heavy parts are copied from bitmaps of view `key`.
 */
export function paintBatches(g, { parts }, lineWidth, layers = null, key = '') {
  for (const b of parts) {
    if (!layers || b.vertices < LAYER_VERTICES) {
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
