// Tangle's test hooks (a test page's init script, harness.mjs; never
// shipped). From the panel's raw parts (www/tangle/panel.js: ctx.expose):
// the document getter `state`, `live` (state.js), `painter` (canvas.js),
// `timing` and `options` (timing.js), `runner` (schedule.js), `editor`
// (grammar-editor.js), `startForm` (start.js), `exportAs` (export.js).
(globalThis.__filigreeHookBuilders ??= {}).tangle = ({ state, live, painter, timing, options, runner, editor, startForm, exportAs }) => {
  const { canvas, viewport, g, view } = painter;
  return {
    state,
    result: () => live.T?.r ?? null,
    /** The shown answer's points (a Float32Array). */
    points: () => live.T?.pts ?? null,
    /** A run or a typed change is due or under way. */
    pending: () => runner.busy() || editor.typing() || startForm.typing(),
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
};
