// The figures of the last paint and answer (`timing`) and the highlight
// switch (`options`): kept by the panel, read and switched by the e2e tests
// and the latency bench through the panel's raw parts (`ctx.expose`;
// the hooks are the test layer's, tests/e2e/hooks/tangle.js).

/**
 * Figures of the last paint/answer for tests and the latency bench: ms,
 * `region` (the repainted fraction of the canvas), `why` (why the last
 * repaint could not be partial), `paints` (when the canvas was last drawn),
 * `answer` (the last answer as it came: `{delta, added, removed, dirty, bytes}`,
 * delta: whether it was a delta of the answer shown).
 */
export const createTiming = () => ({ paint: 0, batches: 0, run: 0, prepare: 0, pan: 0, region: 1, why: '', paints: [], answer: null });

/** Bytes of an answer's typed arrays as it came from the worker (columns, points, removed keys, step indices). */
export function answerBytes(r) {
  let n = (r.points?.byteLength ?? 0) + (r.removed?.byteLength ?? 0);
  for (const v of Object.values(r.shapes)) n += v?.byteLength ?? 0;
  for (const st of r.steps) n += (st.inputs?.byteLength ?? 0) + (st.outputs?.byteLength ?? 0);
  return n;
}

/** The canvas was drawn at `at` (a few times kept, for the tests). */
export function noteDrawn(timing, at) {
  timing.paints = [...timing.paints.slice(-15), at];
}

/**
 * `highlight: false` leaves the selected step's highlight out of a paint
 * (tests compare the picture with a fresh answer's).
 */
export const createOptions = () => ({ highlight: true });
