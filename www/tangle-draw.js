// Drawing a `tangle` answer (src/tangle/api.rs TangleResponse) on a 2-D
// canvas, pen-and-ink: black strokes on paper white, grey fills for `fill`,
// black with white lines for `white_lines`, filled marks for `mark`.
//
//   const t = prepareTangle(response)   per-shape bounding boxes, styles, lazily built Path2Ds
//   t.visible(i, k)                     shape i shown after k steps (k = steps.length: final)
//   t.batches(k) → {fills, black, white, marks, count}   one Path2D per ink style for step k,
//                                       cached for the last step asked
//   paintBatches(g, batches, lineWidth) draws them (g already transformed)
//   t.pick(x, y, k, g) → shape index    the smallest shape shown at step k containing (x, y)
//   t.subtree(s) → Set of shape indices made by step s or by steps that depend on it
//   drawThumbnail(canvas, response)     the final shapes fitted into a small canvas

/** Visible after k steps: made before step k (or a start shape) and not yet consumed by a step < k. */
export const shownAt = (born, died, k) => born < k && (died === -1 || died >= k);

/** Fill grey of a tone (0 = paper, 1 = black), as the core's export writes it. */
const greyOf = (tone) => Math.round(255 * (1 - Math.min(1, Math.max(0, tone))));

export function prepareTangle(r) {
  const n = r.shapes.length;
  const pts = r.points instanceof Float32Array ? r.points : Float32Array.from(r.points);
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

  let cached = null;
  const t = {
    r, n, pts, born, died, box,
    steps: r.steps.length,
    visible: (i, k) => shownAt(born[i], died[i], k),
    count(k) {
      let c = 0;
      for (let i = 0; i < n; i++) if (shownAt(born[i], died[i], k)) c++;
      return c;
    },
    path: pathOf,
    batches(k) {
      if (cached?.k === k) return cached;
      const fills = new Map();
      const black = new Path2D(), white = new Path2D(), marks = new Path2D();
      let count = 0;
      for (let i = 0; i < n; i++) {
        if (!shownAt(born[i], died[i], k)) continue;
        count++;
        const s = r.shapes[i];
        // Each shape's own Path2D is built once per answer; a batch copies them
        // natively (addPath), far cheaper than tracing every vertex again.
        const p = pathOf(i);
        if (s.mark) { marks.addPath(p); continue; }
        if (s.fill > 0) {
          const g = greyOf(s.fill);
          if (!fills.has(g)) fills.set(g, new Path2D());
          fills.get(g).addPath(p);
        }
        (s.white_lines ? white : black).addPath(p);
      }
      cached = { k, fills, black, white, marks, count };
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

/** Draw batches: fills, black lines, white lines, marks. `g` maps drawing units to the canvas. */
export function paintBatches(g, b, lineWidth) {
  g.lineJoin = 'round';
  g.lineWidth = lineWidth;
  for (const [grey, p] of b.fills) {
    g.fillStyle = `rgb(${grey},${grey},${grey})`;
    g.fill(p, 'evenodd');
  }
  if (lineWidth > 0) {
    g.strokeStyle = '#000';
    g.stroke(b.black);
    g.strokeStyle = '#fff';
    g.stroke(b.white);
  }
  g.fillStyle = '#000';
  g.fill(b.marks, 'evenodd');
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
