// A `tangle` answer that is a delta (src/tangle/api.rs: `base` set, the
// answer the request named as its `base`) applied to that base: the base's
// shapes without the removed keys, plus the added shapes, in key order;
// points laid out again; every shape's `born`/`died` read from the steps (a
// step's outputs were born at it, its inputs died at it). Nothing is
// compared: the core said which shapes went and came, by key, so the kept
// shapes are copied column by column and keep their Path2Ds (draw.js
// `prepareTangle(r, link)`). The result equals the full answer of the same
// request (tests/tangle.rs `apply_delta` does the same natively).
import { shapeColumns, withAccessors, stepsOf, pointsOf, column } from './draw.js';

/**
 * Delta answer `d` applied to the full answer `base` (as prepared:
 * columns as typed arrays): `{r, oldOf, added, removed}`. `r`: the full
 * answer (base null); `oldOf[i]`: the base's index of shape i or -1;
 * `added`: indices in `r` of the added shapes; `removed`: indices in
 * `base` of the removed ones. Neither `d` nor `base` is changed.
 */
export function applyDelta(base, d) {
  if (d.base !== base.answer) throw new Error(`a delta of answer ${d.base} applied to answer ${base.answer}`);
  const B = shapeColumns(base.shapes), A = shapeColumns(d.shapes);
  const bpts = pointsOf(base.points), apts = pointsOf(d.points);
  const gone = column(d.removed, Uint32Array); // ascending keys
  const n = B.count - gone.length + A.count;
  const S = {
    count: n,
    key: new Uint32Array(n), tag: new Uint32Array(n), group: new Uint32Array(n), id: new Uint32Array(n),
    first: new Uint32Array(n), born: new Int32Array(n).fill(-1), died: new Int32Array(n).fill(-1),
    fill: new Float32Array(n), flags: new Uint8Array(n), ringFirst: new Uint32Array(n + 1),
  };
  const nRings = B.rings.length + A.rings.length;
  const rings = new Uint32Array(nRings);
  const nPts = bpts.length + apts.length;
  const oldOf = new Int32Array(n).fill(-1);
  const added = new Int32Array(A.count);
  const removed = new Int32Array(gone.length);
  // The shapes in key order: the base's (bar the removed) and the added, merged.
  let at = 0, ring = 0, pt = 0, g = 0, a = 0;
  const pts = new Float32Array(nPts);
  // Points are copied a run at a time: consecutive shapes of one answer lie end to end.
  let run = null; // {src, a, b, at}: src[a, b) goes to pts[at]
  const flush = () => { if (run) pts.set(run.src.subarray(run.a, run.b), run.at); run = null; };
  const copy = (C, cp, j) => {
    S.key[at] = C.key[j]; S.tag[at] = C.tag[j]; S.group[at] = C.group[j]; S.id[at] = C.id[j];
    S.fill[at] = C.fill[j]; S.flags[at] = C.flags[j];
    S.ringFirst[at] = ring;
    let len = 0;
    for (let q = C.ringFirst[j]; q < C.ringFirst[j + 1]; q++) { rings[ring++] = C.rings[q]; len += C.rings[q]; }
    S.first[at] = pt / 2;
    const from = 2 * C.first[j];
    if (run && run.src === cp && run.b === from) run.b += 2 * len;
    else { flush(); run = { src: cp, a: from, b: from + 2 * len, at: pt }; }
    pt += 2 * len;
    at++;
  };
  for (let j = 0; j <= B.count; j++) {
    const key = j < B.count ? B.key[j] : Infinity;
    while (a < A.count && A.key[a] < key) { added[a] = at; copy(A, apts, a++); }
    if (j === B.count) break;
    if (g < gone.length && gone[g] === key) { removed[g++] = j; continue; }
    if (a < A.count && A.key[a] === key) throw new Error(`a delta adds key ${key}, which the base keeps`);
    oldOf[at] = j;
    copy(B, bpts, j);
  }
  flush();
  if (at !== n || g !== gone.length) throw new Error('a delta that does not fit its base');
  S.ringFirst[n] = ring;
  S.rings = ring === nRings ? rings : rings.subarray(0, ring);
  const steps = stepsOf(d.steps);
  steps.forEach((st, k) => {
    for (const o of st.outputs) S.born[o] = k;
    for (const i of st.inputs) S.died[i] = k;
  });
  const r = {
    ...d, base: null, removed: new Uint8Array(0), dirty: null,
    shapes: withAccessors(S), points: pt === pts.length ? pts : pts.subarray(0, pt), steps,
  };
  return { r, oldOf, added, removed };
}
