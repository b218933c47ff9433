// What the e2e tests and the latency bench read and switch: the figures of
// the last paint and answer (`timing`), the highlight switch (`options`),
// and the hooks the panel hands to `ctx.expose` (published only in a page a
// test opened, app/document.js).

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

/**
 * The hooks of a mounted panel: `live` (state.js), `painter` (canvas.js),
 * `pending()` (a run or a typed change is due or under way), `exportAs`
 * (export.js).
 */
export function tangleHooks(ctx, { live, painter, timing, options, pending, exportAs }) {
  const state = () => ctx.state();
  const { canvas, viewport, g, view } = painter;
  return {
    state,
    result: () => live.T?.r ?? null,
    /** The shown answer's points (a Float32Array). */
    points: () => live.T?.pts ?? null,
    pending,
    timing: () => ({ ...timing }),
    /** `{highlight}`: false leaves the selected step's highlight out. */
    options,
    /** Shapes the shown answer kept from its delta's base (their Path2Ds). */
    reused: () => live.T?.reused ?? 0,
    /** Forget every kept bitmap (the latency bench starts each pass from none). */
    clearLayers: () => painter.layers.clear(),
    /** Whether idle-time layer building is done (or off) for the current view. */
    prebuilt: () => painter.prebuilt(),
    /** Vertices per part of what step `at` shows (draw.js batches). */
    parts: (at) => (live.T ? live.T.batches(at).parts.map((b) => b.vertices) : []),
    step: () => live.k,
    view: () => ({ ...view, dpr: painter.dpr }),
    /** The selected step's input shapes' bounds in canvas pixels, or null. */
    selectedBox() {
      const { T } = live;
      const sel = live.selected();
      const b = sel !== null && T.bounds(T.r.steps[sel].inputs);
      if (!b) return null;
      const [x0, y0] = painter.toCss(b[0], b[1]), [x1, y1] = painter.toCss(b[2], b[3]);
      const dpr = painter.dpr;
      return [x0 * dpr, y0 * dpr, x1 * dpr, y1 * dpr];
    },
    /**
     * Where the selected step's input shapes cover the canvas (grown by `grow` CSS px),
     * one byte a canvas pixel (1: covered), or null: the only part an edit of it may redraw.
     */
    selectedMask(grow = 3) {
      const { T } = live;
      const sel = live.selected();
      if (sel === null) return null;
      const dpr = painter.dpr;
      const m = document.createElement('canvas');
      m.width = canvas.width;
      m.height = canvas.height;
      const mg = m.getContext('2d');
      mg.setTransform(dpr * view.s, 0, 0, dpr * view.s, dpr * view.tx, dpr * view.ty);
      mg.fillStyle = mg.strokeStyle = '#000';
      mg.lineWidth = (2 * grow) / view.s + (state().stroke_width || 0);
      mg.lineJoin = 'round';
      for (const i of T.r.steps[sel].inputs) {
        mg.fill(T.path(i), 'nonzero');
        mg.stroke(T.path(i));
      }
      const d = mg.getImageData(0, 0, m.width, m.height).data;
      const out = new Uint8Array(m.width * m.height);
      for (let i = 0; i < out.length; i++) out[i] = d[4 * i + 3] > 0 ? 1 : 0;
      return out;
    },
    /** A point (CSS px from the canvas's corner) where a click picks shape i at the shown step, or null. */
    pointIn(i) {
      const { T, k } = live;
      const b = 4 * i;
      for (let n = 2; n <= 32; n *= 2) {
        for (let a = 1; a < n; a++) {
          for (let c = 1; c < n; c++) {
            const x = T.box[b] + ((T.box[b + 2] - T.box[b]) * a) / n, y = T.box[b + 1] + ((T.box[b + 3] - T.box[b + 1]) * c) / n;
            const [cx, cy] = painter.toCss(x, y);
            if (cx < 2 || cy < 2 || cx > viewport.clientWidth - 2 || cy > viewport.clientHeight - 2) continue;
            const [wx, wy] = painter.toWorld(cx, cy);
            if (T.pick(wx, wy, k, g) === i) return [cx, cy];
          }
        }
      }
      return null;
    },
    exportSvg: async () => (await exportAs('svg'))?.svg ?? null,
    paintNow: painter.paintNow,
  };
}
