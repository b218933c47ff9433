// "Fit": find the parameters of a pattern program that best match a target
// (MISSION F10). Pick or edit a program, draw the target with a brush in the
// program's colours, upload an image, or make a target from chosen values;
// the fit runs in workers with a live loss plot and the best pattern so far
// drawn over the target.
import { putRgba, hex, wirePickers } from './file-input.js';
import { radioGroup } from './radio-group.js';
import { Autosave, History, projectText, parseProject, download } from './project.js';
import { LossPlot } from './loss-plot.js';
import { createCodeEditor } from './code-editor.js';

const TARGET_SIZE = 256;
const rgbOf = (h) => [1, 3, 5].map((i) => parseInt(h.slice(i, i + 2), 16));
const PREVIEW_EVERY_MS = 250;

const html = `
  <div class="fit-layout">
    <section class="card fit-program" aria-label="Pattern program">
      <label class="inline">Generator <select name="generator" data-testid="fit-generator"></select></label>
      <details class="program">
        <summary>Program</summary>
        <div class="program-editor"></div>
        <div class="row-buttons"><button type="button" data-act="apply-program">Apply program</button></div>
      </details>
      <div class="error program-error" role="alert" data-testid="fit-program-error" hidden></div>
      <div class="muted program-facts" data-testid="fit-facts"></div>
      <h3>Parameters</h3>
      <form class="sliders" data-testid="fit-sliders"></form>
      <div class="row-buttons">
        <button type="button" data-act="make-target">Make target from these values</button>
      </div>
    </section>
    <section class="card fit-target" aria-label="Target">
      <div class="toolbar">
        <span class="swatches-inline" role="radiogroup" aria-label="Brush colour" data-testid="fit-brush-colours"></span>
        <label class="inline">size <input type="number" name="brush" min="1" max="64" value="12"></label>
        <button type="button" data-act="undo" title="Undo (Ctrl+Z)" aria-label="Undo">↶</button>
        <button type="button" data-act="redo" title="Redo (Ctrl+Shift+Z)" aria-label="Redo">↷</button>
        <button type="button" data-act="clear-target">Clear</button>
        <button type="button" data-pick="target">Upload target…</button><input type="file" accept="image/*" data-input="target" hidden>
      </div>
      <div class="stack checker">
        <canvas class="target" width="${TARGET_SIZE}" height="${TARGET_SIZE}" data-testid="fit-target" aria-label="target: draw here"></canvas>
        <canvas class="overlay" width="${TARGET_SIZE}" height="${TARGET_SIZE}" data-testid="fit-overlay" aria-hidden="true"></canvas>
      </div>
      <label class="inline">overlay <input type="range" name="overlay" min="0" max="1" step="0.05" value="0.6"></label>
      <div class="error target-error" role="alert" hidden></div>
    </section>
    <section class="card fit-run" aria-label="Fitting">
      <div class="fit-settings">
        <label class="inline">Budget <select name="budget"><option value="quick">quick</option><option value="paper">paper</option></select></label>
        <label class="inline">Loss <select name="loss">
          <option value="sdf">SDF (paper)</option><option value="l1">L1</option>
          <option value="pyramid">Gaussian pyramid</option><option value="image">image L2</option></select></label>
        <label class="inline">Seed <input type="number" name="seed" min="0" value="1"></label>
      </div>
      <div class="row-buttons">
        <button type="button" class="primary" data-act="fit">Run fit</button>
        <button type="button" data-act="cancel" disabled>Cancel</button>
      </div>
      <progress max="1" value="0"></progress>
      <div class="status muted" data-testid="fit-status" aria-live="polite"></div>
      <div class="error fit-error" role="alert" hidden></div>
      <canvas class="plot" data-testid="fit-plot" aria-label="loss plot"></canvas>
      <table class="results" data-testid="fit-results"><thead><tr><th>parameter</th><th>fitted</th><th>truth</th></tr></thead><tbody></tbody></table>
      <div class="row-buttons">
        <button type="button" data-act="export-svg">Export SVG</button>
        <button type="button" data-act="export-json">Export JSON</button>
        <button type="button" data-act="save-project">Save project</button>
        <button type="button" data-pick="project">Open project…</button><input type="file" accept=".json,application/json" data-input="project" hidden>
      </div>
    </section>
  </div>`;

export default {
  id: 'fit',
  title: 'Fit',
  mount(el, { pool }) {
    el.innerHTML = html;
    const q = (s) => el.querySelector(s);
    const targetCanvas = q('canvas.target');
    const tctx = targetCanvas.getContext('2d', { willReadFrequently: true });
    const overlay = q('canvas.overlay');
    const plot = new LossPlot(q('canvas.plot'));
    const autosave = new Autosave('fit');
    // The program editor (CodeMirror, lazily loaded; a textarea without the bundle).
    let editor = null;
    createCodeEditor(q('.program-editor'), { language: 'filigree', label: 'pattern program', attributes: { 'data-testid': 'fit-program' } })
      .then((ed) => { editor = ed; if (doc()) ed.setValue(doc().program); });

    // The document (saved, undoable): program, values, target pixels, settings, result.
    let history = new History(null);
    let info = null; // pattern-info of the current program
    let generators = [];
    let brush = 0; // index into info.colours (last = background)
    let running = null;
    let previewBusy = false;
    let previewWanted = null;
    let lastPreviewAt = 0;

    const doc = () => history.present;
    // Requests name their parameters; the document keeps values in declaration order.
    const named = (values, { integersOnly = false } = {}) => Object.fromEntries(
      info.params.map((p, i) => [p.name, values[i]]).filter(([, ], i) => !integersOnly || info.params[i].integer),
    );
    // Palette of the program: index 0 is the background.
    const palette = () => info.colours.map(rgbOf);
    const showError = (sel, message) => { q(sel).hidden = !message; q(sel).textContent = message || ''; };
    const status = (t) => { q('[data-testid=fit-status]').textContent = t; };

    function commit(next, opts) {
      history.push(next, opts);
      autosave.save(doc());
      q('[data-act=undo]').disabled = !history.canUndo;
      q('[data-act=redo]').disabled = !history.canRedo;
    }

    // ---- program ----------------------------------------------------------------

    async function setProgram(program, { values = null, fresh = false, generator = null } = {}) {
      let next;
      try {
        // Integer parameters shape the program (how many shapes it draws):
        // record it with the user's integers when they belong to this program.
        const sameProgram = info && values && doc()?.program === program;
        next = await pool.run('pattern-info', { program, params: sameProgram ? named(values, { integersOnly: true }) : {} });
      } catch (err) {
        // Keep the last good program running; say where this one is wrong.
        showError('.program-error', err.message);
        // Typed errors carry line and column; older workers only say them in the message.
        const at = err.line ? [err.line, err.column] : /line (\d+), column (\d+)/.exec(err.message)?.slice(1).map(Number);
        if (at) editor?.markError(at[0], at[1] ?? 1, err.message);
        return false;
      }
      showError('.program-error', '');
      editor?.clearError();
      info = next;
      const vals = values && values.length === info.params.length ? values : info.params.map((p) => p.default);
      const base = doc() || { target: null, truth: null, result: null, settings: { budget: 'quick', loss: 'sdf', seed: 1 } };
      const d = { ...base, generator: generator ?? base.generator ?? null, program, values: vals, result: null };
      if (fresh) history = new History(d); else commit(d);
      autosave.save(doc());
      renderProgramUi();
      schedulePreview(vals);
      return true;
    }

    function renderProgramUi() {
      const d = doc();
      editor?.setValue(d.program);
      q('[name=generator]').value = d.generator ?? '';
      q('[data-testid=fit-facts]').textContent =
        `${info.params.filter((p) => !p.integer).length} parameters to fit, ${info.shapes} shapes, ${info.colours.length - 1} colour${info.colours.length === 2 ? '' : 's'} on ${info.colours[0]}`;
      // Sliders, one per declared parameter.
      const form = q('form.sliders');
      form.replaceChildren(...info.params.map((p, i) => {
        const row = document.createElement('div');
        row.className = 'row';
        row.dataset.param = p.name;
        const label = document.createElement('label');
        label.textContent = p.integer ? `${p.name} (int)` : p.name;
        const input = document.createElement('input');
        Object.assign(input, { type: 'range', min: p.lo, max: p.hi, step: p.integer ? 1 : (p.hi - p.lo) / 1000 });
        input.value = d.values[i];
        input.setAttribute('aria-label', p.name);
        const out = document.createElement('output');
        out.textContent = fmt(d.values[i]);
        input.oninput = () => {
          const values = [...doc().values];
          values[i] = Number(input.value);
          out.textContent = fmt(values[i]);
          commit({ ...doc(), values }, { coalesce: `param-${p.name}` });
          schedulePreview(values);
        };
        input.onchange = async () => {
          history.seal();
          // An integer parameter changes the program's structure: re-read it.
          if (p.integer) await setProgram(doc().program, { values: doc().values, generator: doc().generator });
        };
        row.append(label, input, out);
        return row;
      }));
      // Brush colours: the program's colours, then the background (an eraser).
      const sw = q('[data-testid=fit-brush-colours]');
      const colours = [...palette().slice(1), palette()[0]];
      brush = Math.min(brush, colours.length - 1);
      sw.replaceChildren(...colours.map((c, i) => {
        const b = document.createElement('button');
        b.type = 'button';
        b.className = 'swatch-button';
        b.style.background = hex([...c, 255]);
        b.title = i === colours.length - 1 ? `background ${hex([...c, 255])} (erase)` : hex([...c, 255]);
        b.setAttribute('aria-label', b.title);
        b.setAttribute('role', 'radio');
        b.setAttribute('aria-checked', String(i === brush));
        b.onclick = () => { brush = i; sw.querySelectorAll('button').forEach((x, j) => x.setAttribute('aria-checked', String(j === i))); };
        return b;
      }));
      if (!doc().target) fillTarget(palette()[0]);
      else drawTarget();
      renderResults();
    }

    const fmt = (v) => (Math.abs(v) >= 100 ? v.toFixed(1) : v.toFixed(3));

    // ---- preview: the pattern for the current values, over the target ----------

    function schedulePreview(values) {
      previewWanted = values;
      if (previewBusy) return;
      const wait = Math.max(0, PREVIEW_EVERY_MS - (performance.now() - lastPreviewAt));
      previewBusy = true;
      setTimeout(async () => {
        const values = previewWanted;
        previewWanted = null;
        lastPreviewAt = performance.now();
        try {
          const r = await pool.run('render-pattern', { program: doc().program, params: named(values), size: TARGET_SIZE });
          // Only the shapes: background pixels become transparent, so the
          // target shows through wherever the pattern has nothing.
          const [br, bg, bb] = palette()[0];
          for (let i = 0; i < r.rgba.length; i += 4) {
            if (r.rgba[i] === br && r.rgba[i + 1] === bg && r.rgba[i + 2] === bb) r.rgba[i + 3] = 0;
          }
          putRgba(overlay, r.width, r.height, r.rgba);
        } catch (err) {
          showError('.program-error', err.message);
        } finally {
          previewBusy = false;
          if (previewWanted) schedulePreview(previewWanted);
        }
      }, wait);
    }

    // ---- target: drawing, upload, make from values ------------------------------

    function fillTarget([r, g, b]) {
      tctx.fillStyle = `rgb(${r},${g},${b})`;
      tctx.fillRect(0, 0, TARGET_SIZE, TARGET_SIZE);
      storeTarget({ truth: null });
    }

    function storeTarget(extra = {}, opts) {
      const rgba = new Uint8Array(tctx.getImageData(0, 0, TARGET_SIZE, TARGET_SIZE).data.buffer);
      commit({ ...doc(), ...extra, target: { width: TARGET_SIZE, height: TARGET_SIZE, rgba } }, opts);
    }

    function drawTarget() {
      const t = doc().target;
      if (t) tctx.putImageData(new ImageData(new Uint8ClampedArray(t.rgba), t.width, t.height), 0, 0);
    }

    // Paint exact palette colours (no anti-aliasing): a disc of `size` pixels.
    function dab(x, y) {
      const colours = [...palette().slice(1), palette()[0]];
      const [r, g, b] = colours[brush];
      const size = Number(q('[name=brush]').value) || 8;
      const rad = size / 2;
      const x0 = Math.max(0, Math.floor(x - rad)), y0 = Math.max(0, Math.floor(y - rad));
      const x1 = Math.min(TARGET_SIZE, Math.ceil(x + rad)), y1 = Math.min(TARGET_SIZE, Math.ceil(y + rad));
      if (x1 <= x0 || y1 <= y0) return;
      const img = tctx.getImageData(x0, y0, x1 - x0, y1 - y0);
      for (let j = 0; j < y1 - y0; j++) {
        for (let i = 0; i < x1 - x0; i++) {
          if (Math.hypot(x0 + i + 0.5 - x, y0 + j + 0.5 - y) > rad) continue;
          const k = 4 * (j * (x1 - x0) + i);
          img.data[k] = r; img.data[k + 1] = g; img.data[k + 2] = b; img.data[k + 3] = 255;
        }
      }
      tctx.putImageData(img, x0, y0);
    }

    let painting = null;
    const toTarget = (e) => {
      const r = targetCanvas.getBoundingClientRect();
      return [(e.clientX - r.left) / r.width * TARGET_SIZE, (e.clientY - r.top) / r.height * TARGET_SIZE];
    };
    const stack = q('.stack');
    stack.addEventListener('pointerdown', (e) => {
      if (!info || e.button > 0) return;
      stack.setPointerCapture(e.pointerId);
      painting = toTarget(e);
      dab(...painting);
    });
    stack.addEventListener('pointermove', (e) => {
      if (!painting) return;
      const p = toTarget(e);
      const steps = Math.ceil(Math.hypot(p[0] - painting[0], p[1] - painting[1]) / 2);
      for (let s = 1; s <= steps; s++) dab(painting[0] + (p[0] - painting[0]) * s / steps, painting[1] + (p[1] - painting[1]) * s / steps);
      painting = p;
    });
    const endPaint = () => {
      if (!painting) return;
      painting = null;
      storeTarget({ truth: null });
    };
    stack.addEventListener('pointerup', endPaint);
    stack.addEventListener('pointercancel', endPaint);

    async function makeTarget() {
      const d = doc();
      const r = await pool.run('render-pattern', { program: d.program, params: named(d.values), size: TARGET_SIZE });
      tctx.putImageData(new ImageData(new Uint8ClampedArray(r.rgba), r.width, r.height), 0, 0);
      storeTarget({ truth: [...d.values] });
      renderResults();
    }

    async function uploadTarget(file) {
      showError('.target-error', '');
      try {
        const bytes = new Uint8Array(await file.arrayBuffer());
        const r = await pool.run('pattern-snap', { program: doc().program, params: named(doc().values), bytes, size: TARGET_SIZE });
        tctx.putImageData(new ImageData(new Uint8ClampedArray(r.rgba), r.width, r.height), 0, 0);
        storeTarget({ truth: null });
        status(`${file.name}: snapped to the program's colours (${Math.round(r.unmatched * 100)}% of pixels were far from all of them)`);
      } catch (err) {
        showError('.target-error', `${file.name}: ${err.message}`);
      }
    }

    // ---- fitting ----------------------------------------------------------------

    async function fit() {
      const d = doc();
      if (!d?.target) return;
      running?.abort();
      const ctrl = new AbortController();
      running = ctrl;
      showError('.fit-error', '');
      plot.clear();
      q('[data-act=cancel]').disabled = false;
      q('[data-act=fit]').disabled = true;
      const t0 = performance.now();
      const floatIdx = info.params.map((p, i) => (p.integer ? -1 : i)).filter((i) => i >= 0);
      // A fresh payload per request: its pixel buffer is transferred to a worker.
      const common = () => ({
        program: d.program, params: named(d.values, { integersOnly: true }),
        target_rgba: { ...d.target, rgba: d.target.rgba.slice() },
        budget: d.settings.budget, loss: d.settings.loss, seed: d.settings.seed,
      });
      let shownLoss = Infinity;
      const show = (fraction, stage, loss, best) => {
        q('progress').value = fraction;
        status(`${stage} — loss ${Number.isFinite(loss) ? loss.toPrecision(4) : '…'}`);
        if (Number.isFinite(loss)) plot.push(fraction, loss);
        if (best && loss <= shownLoss) {
          shownLoss = loss;
          const values = [...doc().values];
          floatIdx.forEach((k, j) => { values[k] = best[j]; });
          schedulePreview(values);
        }
      };
      try {
        const r = await parallelFit(common, ctrl.signal, show);
        const values = [...doc().values];
        floatIdx.forEach((k, j) => { values[k] = r.params[j]; });
        commit({ ...doc(), values, result: { params: r.params, loss: r.loss, names: r.names, evaluations: r.evaluations } });
        plot.push(1, r.loss);
        q('progress').value = 1;
        status(`fitted in ${((performance.now() - t0) / 1000).toFixed(1)} s — loss ${r.loss.toPrecision(4)} after ${r.evaluations} evaluations`);
        renderProgramUi();
        schedulePreview(values);
      } catch (err) {
        if (err.kind === 'cancelled') status('cancelled — the values from before the fit are kept');
        else showError('.fit-error', err.message);
      } finally {
        if (running === ctrl) running = null;
        q('[data-act=cancel]').disabled = true;
        q('[data-act=fit]').disabled = false;
      }
    }

    // One fit sharded across the worker pool (all workers but one, which
    // stays free for previews). The pool relays the shards' exchanges and
    // the core merges them, so the result is exactly that of one fit
    // (tests/fit.rs checks this with the native driver).
    async function parallelFit(common, signal, show) {
      const n = Math.max(1, pool.slots.length - 1);
      const fractions = Array(n).fill(0);
      const losses = Array(n).fill(Infinity);
      return pool.runSharded('fit', common(), {
        shards: n,
        signal,
        onProgress: (p, k) => {
          fractions[k] = p.fraction;
          if (p.figure != null) losses[k] = p.figure;
          const best = Math.min(...losses);
          const stage = n > 1 ? `${p.stage} (${n} workers)` : p.stage;
          show(fractions.reduce((a, b) => a + b, 0) / n, stage, best, losses[k] === best ? p.values : null);
        },
      });
    }

    function renderResults() {
      const d = doc();
      const tbody = q('.results tbody');
      if (!info) return;
      tbody.replaceChildren(...info.params.filter((p) => !p.integer).map((p) => {
        const i = info.params.indexOf(p);
        const tr = document.createElement('tr');
        tr.dataset.param = p.name;
        const fitted = d.result ? fmt(d.values[i]) : '—';
        const truth = d.truth ? fmt(d.truth[i]) : '—';
        tr.innerHTML = `<td>${p.name}</td><td data-col="fitted">${fitted}</td><td data-col="truth">${truth}</td>`;
        return tr;
      }));
    }

    // ---- controls -----------------------------------------------------------------

    q('[name=generator]').onchange = (e) => {
      const g = generators.find((x) => x.name === e.target.value);
      if (g) setProgram(g.source, { generator: g.name }).then((ok) => ok && fillTarget(palette()[0]));
    };
    q('[data-act=apply-program]').onclick = () => setProgram(editor.getValue(), { values: doc()?.values, generator: null });
    q('[data-act=make-target]').onclick = () => makeTarget().catch((err) => showError('.target-error', err.message));
    q('[data-act=clear-target]').onclick = () => info && fillTarget(palette()[0]);
    q('[data-act=fit]').onclick = fit;
    q('[data-act=cancel]').onclick = () => running?.abort();
    q('[name=overlay]').oninput = (e) => { overlay.style.opacity = e.target.value; };
    overlay.style.opacity = q('[name=overlay]').value;
    for (const name of ['budget', 'loss', 'seed']) {
      q(`[name=${name}]`).onchange = (e) => {
        const v = name === 'seed' ? Math.max(0, Math.round(Number(e.target.value) || 0)) : e.target.value;
        commit({ ...doc(), settings: { ...doc().settings, [name]: v } });
      };
    }
    const undo = () => { history.undo(); restore(); };
    const redo = () => { history.redo(); restore(); };
    q('[data-act=undo]').onclick = undo;
    q('[data-act=redo]').onclick = redo;
    this.onKey = (e) => {
      if (e.target.closest?.('input, select, textarea, [contenteditable]')) return;
      if ((e.ctrlKey || e.metaKey) && e.key.toLowerCase() === 'z') {
        e.preventDefault();
        if (e.shiftKey) redo(); else undo();
      }
    };
    document.addEventListener('keydown', this.onKey);

    radioGroup(q('[data-testid=fit-brush-colours]'));
    wirePickers(el);
    el.querySelectorAll('input[data-input]').forEach((input) => {
      input.onchange = async () => {
        const file = input.files[0];
        input.value = '';
        if (!file) return;
        if (input.dataset.input === 'target') return uploadTarget(file);
        try {
          const loaded = parseProject(await file.text(), 'fit');
          if (await setProgram(loaded.program, { values: loaded.values, generator: loaded.generator })) {
            commit(loaded);
            restore();
          }
        } catch (err) {
          showError('.fit-error', `${file.name}: ${err.message}`);
        }
      };
    });

    const baseName = () => doc()?.generator || 'pattern';
    q('[data-act=export-svg]').onclick = async () => {
      const r = await pool.run('render-pattern', { program: doc().program, params: named(doc().values), size: 512 });
      download(`${baseName()}.svg`, r.svg, 'image/svg+xml');
    };
    q('[data-act=export-json]').onclick = () => {
      const d = doc();
      const params = Object.fromEntries(info.params.map((p, i) => [p.name, d.values[i]]));
      download(`${baseName()}-params.json`, JSON.stringify({ generator: d.generator, params, loss: d.result?.loss ?? null }, null, 2), 'application/json');
    };
    q('[data-act=save-project]').onclick = () => download(`${baseName()}.filigree.json`, projectText('fit', doc()), 'application/json');

    // Bring the view in line with the document after undo/redo or a load.
    async function restore() {
      const d = doc();
      for (const name of ['budget', 'loss', 'seed']) q(`[name=${name}]`).value = d.settings[name];
      drawTarget();
      renderProgramUi();
      schedulePreview(d.values);
      autosave.save(d);
    }

    this.onHide = () => autosave.flush();
    addEventListener('pagehide', this.onHide);

    (async () => {
      generators = await pool.run('pattern-generators', {});
      q('[name=generator]').replaceChildren(
        new Option('(custom program)', ''),
        ...generators.map((g) => new Option(g.paper ? `${g.name} — ${g.paper}` : g.name, g.name)),
      );
      const saved = await autosave.load();
      if (saved?.program && await setProgram(saved.program, { values: saved.values, fresh: true, generator: saved.generator })) {
        history = new History(saved);
        await restore();
        return;
      }
      const first = generators.find((g) => g.name === 'circles-grid') || generators[0];
      await setProgram(first.source, { fresh: true, generator: first.name });
      await restore();
    })().catch((err) => showError('.fit-error', err.message));

    window.filigreeFit = { state: doc, info: () => info, plot };
  },
  unmount() {
    document.removeEventListener('keydown', this.onKey);
    removeEventListener('pagehide', this.onHide);
    this.onHide?.();
  },
};
