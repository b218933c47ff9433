// "Pixel": texture pixel art with oriented elements (MISSION P1–P6).
// The user loads a source, a mask and an element sheet (or one click on an
// example), paints the mask, draws orientation strokes on a zoomable pixel
// grid, and moves parameters; the core re-runs in a worker after each change
// (debounced, the previous run cancelled). State is autosaved and undoable.
import { acceptFiles, putRgba, hex, wirePickers } from './file-input.js';
import { radioGroup } from './radio-group.js';
import { Autosave, History, projectText, parseProject, download } from './project.js';

const ASSETS = new URL('../assets/pixel/', import.meta.url);
const DIRECTIONS = ['up', 'up-right', 'right', 'down-right', 'down', 'down-left', 'left', 'up-left'];
const RUN_DELAY_MS = 120;

/** Parameter controls, generated into the side panel. Keys are the core's PixelParams fields. */
const CONTROLS = [
  { key: 'positions', label: 'Positions', type: 'select', options: ['random', 'packed'] },
  { key: 'density', label: 'Density ρ', type: 'range', min: 0, max: 1, step: 0.01, show: (v) => `${Math.round(v * 100)}%` },
  { key: 'margins', label: 'Margins mx, my', type: 'ints', n: 2, min: -8, max: 16 },
  { key: 'partial', label: 'Partial elements at the mask edge', type: 'checkbox' },
  { key: 'colour', label: 'Colour map', type: 'select', options: ['auto', 'border', 'difference', 'hsv'] },
  { key: 'd_max', label: 'd_max (auto)', type: 'range', min: 0, max: 150, step: 1, show: (v) => String(v) },
  { key: 'hsv', label: 'HSV shift h°, s, v', type: 'ints', n: 3, min: -180, max: 180 },
  { key: 'exclude', label: 'Excluded colours', type: 'colours' },
  { key: 'element_colour', label: 'Element colour', type: 'select', options: ['region', 'pixel'] },
  { key: 'annotation_scale', label: 'Annotation scale K', type: 'range', min: 1, max: 16, step: 1, show: (v) => `×${v}` },
  { key: 'default_direction', label: 'Direction without strokes', type: 'select', options: DIRECTIONS },
  { key: 'seed', label: 'Seed', type: 'seed' },
];

const DEFAULT_PARAMS = {
  annotation_scale: 4, positions: 'random', density: 1, margins: [0, 0], partial: false,
  colour: 'auto', hsv: [0, 0, -30], exclude: [[0, 0, 0]], d_max: 50, element_colour: 'region',
  default_direction: 'down', sprite_direction: 'up', seed: 1,
};

const html = `
  <div class="pixel-layout">
    <div class="card pixel-stage">
      <div class="toolbar" role="toolbar" aria-label="Pixel tools">
        <span class="group">
          <button type="button" data-example="fish" class="primary">Fish example</button>
          <button type="button" data-example="trunk">Trunk example</button>
        </span>
        <span class="group" role="radiogroup" aria-label="Brush">
          <button type="button" data-mode="stroke" role="radio" aria-checked="true" title="Draw orientation strokes (S)">✎ Strokes</button>
          <button type="button" data-mode="paint" role="radio" aria-checked="false" title="Paint the mask (M)">▣ Paint mask</button>
          <button type="button" data-mode="erase" role="radio" aria-checked="false" title="Erase the mask (E)">▢ Erase mask</button>
        </span>
        <label class="inline">size <input type="number" name="brush" min="1" max="32" value="3"></label>
        <span class="group">
          <button type="button" data-act="zoom-out" aria-label="Zoom out">−</button>
          <span class="zoom" data-testid="zoom">×4</span>
          <button type="button" data-act="zoom-in" aria-label="Zoom in">+</button>
        </span>
        <span class="group">
          <button type="button" data-act="undo" title="Undo (Ctrl+Z)" aria-label="Undo">↶</button>
          <button type="button" data-act="redo" title="Redo (Ctrl+Shift+Z)" aria-label="Redo">↷</button>
          <button type="button" data-act="clear-strokes">Clear strokes</button>
        </span>
      </div>
      <div class="toggles">
        <label><input type="checkbox" name="show-result" checked> result</label>
        <label><input type="checkbox" name="show-mask"> mask</label>
        <label><input type="checkbox" name="show-strokes" checked> strokes</label>
        <label><input type="checkbox" name="show-arrows"> vector field</label>
        <span class="status muted" data-testid="pixel-status" aria-live="polite"></span>
      </div>
      <div class="error" role="alert" hidden></div>
      <div class="viewport checker" data-testid="pixel-viewport">
        <canvas class="view" data-testid="pixel-canvas" aria-label="pixel art: draw strokes or paint the mask here"></canvas>
        <div class="empty muted">Load an example, or drop a source image here.</div>
      </div>
      <dl class="stats" data-testid="pixel-stats"></dl>
    </div>
    <aside class="card pixel-side">
      <h3>Inputs</h3>
      <div class="inputs">
        <label>Source <input type="file" accept="image/*" data-input="source"></label>
        <label>Mask <input type="file" accept="image/*" data-input="mask"></label>
        <label>Element sheet (3×3) <input type="file" accept="image/*" data-input="sheet"></label>
        <label>…or one sprite <input type="file" accept="image/*" data-input="sprite"></label>
        <div class="elements"><canvas class="sheet-preview pixelated" aria-label="elements"></canvas><span class="muted" data-field="elements"></span></div>
      </div>
      <h3>Parameters</h3>
      <form class="params" data-testid="pixel-params"></form>
      <h3>Export</h3>
      <div class="exports">
        <label class="inline">PNG scale <select name="export-scale"><option>1</option><option>2</option><option selected>4</option><option>8</option></select></label>
        <button type="button" data-act="export-png">Export PNG</button>
        <button type="button" data-act="save-project">Save project</button>
        <button type="button" data-pick="project">Open project…</button><input type="file" accept=".json,application/json" data-input="project" hidden>
      </div>
    </aside>
  </div>`;

/** Decode an image file in the worker: {width, height, rgba}. */
function decodeImage(pool, bytes) {
  return pool.run('decode-image', { bytes: bytes.slice() });
}

async function fetchBytes(url) {
  const res = await fetch(url);
  if (!res.ok) throw new Error(`${url.pathname}: ${res.status}`);
  return new Uint8Array(await res.arrayBuffer());
}

export default {
  id: 'pixel',
  title: 'Pixel',
  mount(el, { pool }) {
    el.innerHTML = html;
    const q = (s) => el.querySelector(s);
    const canvas = q('canvas.view');
    const ctx = canvas.getContext('2d');
    const autosave = new Autosave('pixel');

    // Document state (undoable, saved): inputs, mask, strokes, parameters.
    let history = new History(null);
    // Derived, not saved: decoded images, the last result, view settings.
    const view = { zoom: 4, mode: 'stroke', brush: 3, showResult: true, showMask: false, showStrokes: true, showArrows: false };
    let sourceImg = null; // {width, height, rgba}
    let sourceBitmap = null;
    let result = null; // the core's answer for the current state, or the last good one
    let resultBitmap = null;
    let running = null; // AbortController of the job in flight
    let runTimer = null;
    let drawing = null; // the stroke or mask edit in progress
    let generation = 0;

    const state = () => history.present;

    function setError(message) {
      q('.error').hidden = !message;
      q('.error').textContent = message || '';
    }
    const status = (text) => { q('[data-testid=pixel-status]').textContent = text; };

    // ---- state changes ------------------------------------------------------

    function commit(next, opts) {
      history.push(next, opts);
      changed();
    }

    function changed({ rerun = true } = {}) {
      autosave.save(state());
      syncControls();
      q('[data-act=undo]').disabled = !history.canUndo;
      q('[data-act=redo]').disabled = !history.canRedo;
      draw();
      if (rerun) scheduleRun();
    }

    async function loadDocument(doc, { fresh = true } = {}) {
      const gen = ++generation;
      const img = await decodeImage(pool, doc.source);
      if (gen !== generation) return;
      sourceImg = img;
      sourceBitmap = await rgbaBitmap(img);
      result = null;
      resultBitmap = null;
      if (fresh) history = new History(doc);
      else history.push(doc);
      fitZoom();
      await showElements(doc);
      q('.empty').hidden = true;
      changed();
    }

    async function loadExample(name) {
      setError('');
      status(`loading the ${name} example…`);
      // The same cases (files, parameters, strokes) the native benchmark runs.
      const cases = await (await fetch(new URL('cases.json', ASSETS))).json();
      const ex = cases[name];
      const [source, maskPng, sheet, strokesJson] = await Promise.all(
        [ex.source, ex.mask, ex.sheet, ex.strokes].map((f) => fetchBytes(new URL(f, ASSETS))),
      );
      const mask = await pool.run('pixel-mask', { bytes: maskPng });
      await loadDocument({
        example: name, source, sheet, sprite: null, mask,
        strokes: JSON.parse(new TextDecoder().decode(strokesJson)).strokes,
        params: { ...DEFAULT_PARAMS, ...ex.params },
        names: { source: ex.source, sheet: ex.sheet },
      });
    }

    async function loadInput(which, file) {
      setError('');
      const bytes = new Uint8Array(await file.arrayBuffer());
      const doc = state();
      try {
        if (which === 'project') {
          const loaded = parseProject(new TextDecoder().decode(bytes), 'pixel');
          await loadDocument(loaded, { fresh: false });
          return;
        }
        if (which === 'source') {
          const img = await decodeImage(pool, bytes);
          // A new source keeps the mask when the sizes agree, else starts with a full one.
          const keepMask = doc?.mask && doc.mask.width === img.width && doc.mask.height === img.height;
          const mask = keepMask ? doc.mask : { width: img.width, height: img.height, bits: new Uint8Array(img.width * img.height).fill(1) };
          await loadDocument({
            ...(doc || { sheet: null, sprite: null, strokes: [], params: { ...DEFAULT_PARAMS } }),
            example: null, source: bytes, mask, names: { ...(doc?.names || {}), source: file.name },
          }, { fresh: !doc });
          return;
        }
        if (!doc) throw new Error('load a source image first');
        if (which === 'mask') {
          const mask = await pool.run('pixel-mask', { bytes });
          if (mask.width !== sourceImg.width || mask.height !== sourceImg.height) {
            throw new Error(`the mask is ${mask.width}×${mask.height} pixels but the source image is ${sourceImg.width}×${sourceImg.height}; they must be the same size`);
          }
          commit({ ...doc, mask });
        } else {
          await decodeImage(pool, bytes);
          const next = { ...doc, sheet: which === 'sheet' ? bytes : null, sprite: which === 'sprite' ? bytes : null, names: { ...doc.names, sheet: file.name } };
          commit(next);
          await showElements(next);
        }
      } catch (err) {
        setError(`${file.name}: ${err.message}`);
      }
    }

    async function showElements(doc) {
      const bytes = doc.sheet || doc.sprite;
      const c = q('.sheet-preview');
      if (!bytes) { c.width = c.height = 0; q('[data-field=elements]').textContent = 'no elements yet'; return; }
      const img = await decodeImage(pool, bytes);
      putRgba(c, img.width, img.height, img.rgba);
      q('[data-field=elements]').textContent = `${doc.sheet ? 'sheet' : 'sprite'} ${img.width}×${img.height}`;
    }

    // ---- running the core ---------------------------------------------------

    function scheduleRun() {
      clearTimeout(runTimer);
      runTimer = setTimeout(() => { runTimer = null; run(); }, RUN_DELAY_MS);
    }

    async function run() {
      const doc = state();
      if (!doc || !(doc.sheet || doc.sprite)) return;
      running?.abort();
      const ctrl = new AbortController();
      running = ctrl;
      status('texturing…');
      const t0 = performance.now();
      try {
        const r = await pool.run('pixel', {
          source: doc.source.slice(), sheet: doc.sheet?.slice(), sprite: doc.sprite?.slice(),
          mask: { width: doc.mask.width, height: doc.mask.height, bits: doc.mask.bits.slice() },
          strokes: doc.strokes, params: doc.params,
        }, { signal: ctrl.signal, onProgress: (p) => status(`${p.stage}…`) });
        if (running !== ctrl) return;
        result = r;
        resultBitmap = await rgbaBitmap(r);
        setError('');
        status(`done in ${Math.round(performance.now() - t0)} ms`);
        showStats(r);
        draw();
        // Counts finished runs, so a test (or a person) can tell two results apart.
        const el2 = q('[data-testid=pixel-status]');
        el2.dataset.runs = String(Number(el2.dataset.runs || 0) + 1);
      } catch (err) {
        if (err.kind === 'cancelled') return;
        // Keep the last good result on screen; say what is wrong now.
        setError(err.message);
        status('');
      } finally {
        if (running === ctrl) running = null;
      }
    }

    function showStats(r) {
      const rows = [
        ['Elements placed', r.placed], ['Colours before', r.colours_before], ['Colours after', r.colours_after],
        ['Colour map', r.colour_map_used],
      ];
      q('.stats').replaceChildren(...rows.flatMap(([k, v]) => {
        const dt = document.createElement('dt'); dt.textContent = k;
        const dd = document.createElement('dd'); dd.textContent = String(v); dd.dataset.stat = k;
        return [dt, dd];
      }));
    }

    // ---- drawing ------------------------------------------------------------

    async function rgbaBitmap({ width, height, rgba }) {
      return createImageBitmap(new ImageData(new Uint8ClampedArray(rgba), width, height));
    }

    function fitZoom() {
      // The whole picture in the window: the viewport's width, and the height left below its top.
      const vp = q('.viewport');
      const availW = Math.max(200, vp.clientWidth - 4);
      const availH = Math.max(160, innerHeight - (vp.getBoundingClientRect().top + scrollY) - 24);
      view.zoom = Math.max(1, Math.min(16, Math.floor(Math.min(availW / sourceImg.width, availH / sourceImg.height))));
    }

    function draw() {
      const doc = state();
      if (!doc || !sourceImg) return;
      const z = view.zoom;
      const { width: w, height: h } = sourceImg;
      canvas.width = w * z;
      canvas.height = h * z;
      q('[data-testid=zoom]').textContent = `×${z}`;
      ctx.imageSmoothingEnabled = false;
      const base = view.showResult && resultBitmap ? resultBitmap : sourceBitmap;
      ctx.drawImage(base, 0, 0, w * z, h * z);
      if (z >= 8) drawGrid(w, h, z);
      if (view.showMask || view.mode !== 'stroke') drawMask(doc.mask, z);
      if (view.showArrows && result?.field) drawArrows(result.field, w, h, z);
      if (view.showStrokes) {
        for (const s of doc.strokes) drawStroke(s, z, '#ff5db1');
        if (drawing?.kind === 'stroke') drawStroke(drawing.points, z, '#ffd166');
      }
    }

    // The pixel grid, once cells are big enough to aim at.
    function drawGrid(w, h, z) {
      ctx.strokeStyle = 'rgba(0, 0, 0, 0.18)';
      ctx.lineWidth = 1;
      ctx.beginPath();
      for (let x = 0; x <= w; x++) { ctx.moveTo(x * z + 0.5, 0); ctx.lineTo(x * z + 0.5, h * z); }
      for (let y = 0; y <= h; y++) { ctx.moveTo(0, y * z + 0.5); ctx.lineTo(w * z, y * z + 0.5); }
      ctx.stroke();
    }

    function drawMask(mask, z) {
      ctx.fillStyle = 'rgba(127, 209, 199, 0.35)';
      for (let y = 0; y < mask.height; y++) {
        for (let x = 0; x < mask.width; x++) if (mask.bits[y * mask.width + x]) ctx.fillRect(x * z, y * z, z, z);
      }
    }

    function drawStroke(points, z, colour) {
      if (points.length < 2) return;
      ctx.strokeStyle = colour;
      ctx.lineWidth = Math.max(1.5, z / 3);
      ctx.lineCap = ctx.lineJoin = 'round';
      ctx.beginPath();
      points.forEach(([x, y], i) => (i ? ctx.lineTo(x * z, y * z) : ctx.moveTo(x * z, y * z)));
      ctx.stroke();
      const [x1, y1] = points[points.length - 1];
      const [x0, y0] = points[Math.max(0, points.length - 4)];
      arrowHead(x0 * z, y0 * z, x1 * z, y1 * z, Math.max(6, z * 1.5), colour);
    }

    function arrowHead(x0, y0, x1, y1, size, colour) {
      const a = Math.atan2(y1 - y0, x1 - x0);
      ctx.fillStyle = colour;
      ctx.beginPath();
      ctx.moveTo(x1, y1);
      ctx.lineTo(x1 - size * Math.cos(a - 0.45), y1 - size * Math.sin(a - 0.45));
      ctx.lineTo(x1 - size * Math.cos(a + 0.45), y1 - size * Math.sin(a + 0.45));
      ctx.fill();
    }

    // The diffused field as small arrows, one per cell of `step` pixels inside the mask.
    function drawArrows(field, w, h, z) {
      const step = Math.max(1, Math.ceil(12 / z));
      const mask = state().mask.bits;
      ctx.strokeStyle = 'rgba(255, 255, 255, 0.85)';
      ctx.lineWidth = 1;
      for (let y = Math.floor(step / 2); y < h; y += step) {
        for (let x = Math.floor(step / 2); x < w; x += step) {
          if (!mask[y * w + x]) continue;
          const vx = field[2 * (y * w + x)], vy = field[2 * (y * w + x) + 1];
          const len = Math.hypot(vx, vy);
          if (len < 1e-6) continue;
          const L = step * z * 0.42;
          const cx = (x + 0.5) * z, cy = (y + 0.5) * z;
          const dx = (vx / len) * L, dy = (vy / len) * L;
          ctx.beginPath();
          ctx.moveTo(cx - dx, cy - dy);
          ctx.lineTo(cx + dx, cy + dy);
          ctx.stroke();
          arrowHead(cx - dx, cy - dy, cx + dx, cy + dy, Math.max(3, L * 0.5), 'rgba(255, 255, 255, 0.85)');
        }
      }
    }

    // ---- pointer input: strokes and mask painting ----------------------------

    const toPixel = (e) => {
      const r = canvas.getBoundingClientRect();
      return [(e.clientX - r.left) / r.width * sourceImg.width, (e.clientY - r.top) / r.height * sourceImg.height];
    };

    function paintAt([fx, fy], on) {
      const m = drawing.mask;
      const r = view.brush / 2;
      for (let y = Math.floor(fy - r); y <= Math.floor(fy + r); y++) {
        for (let x = Math.floor(fx - r); x <= Math.floor(fx + r); x++) {
          if (x < 0 || y < 0 || x >= m.width || y >= m.height) continue;
          if (Math.hypot(x + 0.5 - fx, y + 0.5 - fy) <= Math.max(r, 0.5)) m.bits[y * m.width + x] = on ? 1 : 0;
        }
      }
    }

    canvas.addEventListener('pointerdown', (e) => {
      if (!state() || e.button > 0) return;
      canvas.setPointerCapture(e.pointerId);
      const p = toPixel(e);
      if (view.mode === 'stroke') {
        drawing = { kind: 'stroke', points: [p] };
      } else {
        const m = state().mask;
        drawing = { kind: 'mask', mask: { width: m.width, height: m.height, bits: m.bits.slice() } };
        paintAt(p, view.mode === 'paint');
        const doc = state();
        history.push({ ...doc, mask: drawing.mask }, { coalesce: 'mask-drag' });
      }
      draw();
    });

    canvas.addEventListener('pointermove', (e) => {
      if (!drawing) return;
      const p = toPixel(e);
      if (drawing.kind === 'stroke') {
        const last = drawing.points[drawing.points.length - 1];
        if (Math.hypot(p[0] - last[0], p[1] - last[1]) >= 0.25) drawing.points.push(p);
      } else {
        paintAt(p, view.mode === 'paint');
      }
      draw();
    });

    const endDrawing = () => {
      if (!drawing) return;
      const d = drawing;
      drawing = null;
      if (d.kind === 'stroke') {
        if (d.points.length >= 2) {
          const pts = d.points.map(([x, y]) => [Math.round(x * 100) / 100, Math.round(y * 100) / 100]);
          commit({ ...state(), strokes: [...state().strokes, pts] });
        } else draw();
      } else {
        history.seal();
        changed();
      }
    };
    canvas.addEventListener('pointerup', endDrawing);
    canvas.addEventListener('pointercancel', endDrawing);

    // ---- controls -------------------------------------------------------------

    const form = q('form.params');
    for (const c of CONTROLS) form.append(controlRow(c));

    function controlRow(c) {
      const row = document.createElement('div');
      row.className = 'row';
      row.dataset.key = c.key;
      const label = document.createElement('label');
      label.textContent = c.label;
      const id = `pixel-${c.key}`;
      label.htmlFor = id;
      row.append(label);
      const set = (value, opts) => {
        const doc = state();
        if (!doc) return;
        commit({ ...doc, params: { ...doc.params, [c.key]: value } }, opts);
      };
      let input;
      if (c.type === 'select') {
        input = document.createElement('select');
        for (const o of c.options) input.append(new Option(o, o));
        input.onchange = () => set(input.value);
      } else if (c.type === 'range') {
        input = document.createElement('input');
        Object.assign(input, { type: 'range', min: c.min, max: c.max, step: c.step });
        const out = document.createElement('output');
        row.append(out);
        input.oninput = () => set(Number(input.value), { coalesce: c.key });
        input.onchange = () => history.seal();
      } else if (c.type === 'checkbox') {
        input = document.createElement('input');
        input.type = 'checkbox';
        input.onchange = () => set(input.checked);
      } else if (c.type === 'ints') {
        input = document.createElement('span');
        input.className = 'ints';
        for (let i = 0; i < c.n; i++) {
          const n = document.createElement('input');
          Object.assign(n, { type: 'number', min: c.min, max: c.max, step: 1 });
          n.setAttribute('aria-label', `${c.label} ${i + 1}`);
          n.onchange = () => {
            const v = [...input.querySelectorAll('input')].map((x) => Math.round(Number(x.value) || 0));
            set(v);
          };
          input.append(n);
        }
      } else if (c.type === 'colours') {
        input = document.createElement('input');
        input.type = 'text';
        input.placeholder = '#000000, #ffffff';
        input.onchange = () => {
          const parsed = parseColours(input.value);
          if (parsed.error) { setError(`Excluded colours: ${parsed.error}`); return; }
          setError('');
          set(parsed.colours);
        };
      } else if (c.type === 'seed') {
        input = document.createElement('span');
        input.className = 'ints';
        const n = document.createElement('input');
        Object.assign(n, { type: 'number', min: 0, step: 1 });
        n.setAttribute('aria-label', 'seed');
        n.onchange = () => set(Math.max(0, Math.round(Number(n.value) || 0)));
        const b = document.createElement('button');
        b.type = 'button';
        b.textContent = '⟳';
        b.title = 'New seed';
        b.setAttribute('aria-label', 'New seed');
        b.onclick = () => set((state()?.params.seed ?? 0) + 1);
        input.append(n, b);
      }
      input.id = id;
      row.insertBefore(input, row.children[1] || null);
      return row;
    }

    function syncControls() {
      const p = state()?.params;
      if (!p) return;
      for (const c of CONTROLS) {
        const row = form.querySelector(`[data-key=${c.key}]`);
        const v = p[c.key];
        if (c.type === 'select') row.querySelector('select').value = v;
        else if (c.type === 'range') {
          row.querySelector('input').value = v;
          row.querySelector('output').textContent = c.show(v);
        } else if (c.type === 'checkbox') row.querySelector('input').checked = v;
        else if (c.type === 'ints') row.querySelectorAll('input').forEach((x, i) => { x.value = v[i]; });
        else if (c.type === 'colours') row.querySelector('input').value = v.map((rgb) => hex([...rgb, 255])).join(', ');
        else if (c.type === 'seed') row.querySelector('input').value = v;
      }
      const hsvRow = form.querySelector('[data-key=hsv]');
      hsvRow.classList.toggle('dim', p.colour !== 'hsv' && p.colour !== 'auto');
      form.querySelector('[data-key=d_max]').classList.toggle('dim', p.colour !== 'auto');
    }

    // ---- toolbar, toggles, keys ------------------------------------------------

    el.querySelectorAll('[data-example]').forEach((b) => {
      b.onclick = () => loadExample(b.dataset.example).catch((err) => setError(err.message));
    });
    el.querySelectorAll('[data-mode]').forEach((b) => {
      b.onclick = () => {
        view.mode = b.dataset.mode;
        el.querySelectorAll('[data-mode]').forEach((x) => x.setAttribute('aria-checked', String(x === b)));
        draw();
      };
    });
    q('[name=brush]').onchange = (e) => { view.brush = Math.max(1, Math.min(32, Number(e.target.value) || 1)); };
    const zoomBy = (d) => { view.zoom = Math.max(1, Math.min(32, view.zoom + d)); draw(); };
    q('[data-act=zoom-in]').onclick = () => zoomBy(view.zoom >= 8 ? 2 : 1);
    q('[data-act=zoom-out]').onclick = () => zoomBy(view.zoom > 8 ? -2 : -1);
    q('.viewport').addEventListener('wheel', (e) => {
      if (!e.ctrlKey || !sourceImg) return;
      e.preventDefault();
      zoomBy(e.deltaY < 0 ? 1 : -1);
    }, { passive: false });
    const undo = () => { history.undo(); changed(); };
    const redo = () => { history.redo(); changed(); };
    q('[data-act=undo]').onclick = undo;
    q('[data-act=redo]').onclick = redo;
    q('[data-act=clear-strokes]').onclick = () => state()?.strokes.length && commit({ ...state(), strokes: [] });
    for (const [name, key] of [['show-result', 'showResult'], ['show-mask', 'showMask'], ['show-strokes', 'showStrokes'], ['show-arrows', 'showArrows']]) {
      q(`[name=${name}]`).onchange = (e) => { view[key] = e.target.checked; draw(); };
    }
    this.onKey = (e) => {
      if (e.target.closest?.('input, select, textarea')) return;
      if ((e.ctrlKey || e.metaKey) && e.key.toLowerCase() === 'z') {
        e.preventDefault();
        if (e.shiftKey) redo(); else undo();
      } else if (e.key === 's' || e.key === 'm' || e.key === 'e') {
        el.querySelector(`[data-mode=${{ s: 'stroke', m: 'paint', e: 'erase' }[e.key]}]`).click();
      }
    };
    document.addEventListener('keydown', this.onKey);

    radioGroup(q('[role=radiogroup]'));
    wirePickers(el);
    el.querySelectorAll('input[data-input]').forEach((input) => {
      input.onchange = () => {
        if (input.files[0]) loadInput(input.dataset.input, input.files[0]);
        input.value = '';
      };
    });
    this.detach = acceptFiles(q('.viewport'), (file) => loadInput('source', file), { pickerLabel: 'Choose a source image…' });
    q('.viewport .pick').classList.add('overlay-pick');

    q('[data-act=export-png]').onclick = async () => {
      if (!result) { setError('nothing to export yet: load an example or a source and an element sheet'); return; }
      const s = Number(q('[name=export-scale]').value);
      const c = document.createElement('canvas');
      c.width = result.width * s;
      c.height = result.height * s;
      const x = c.getContext('2d');
      x.imageSmoothingEnabled = false;
      x.drawImage(resultBitmap, 0, 0, c.width, c.height);
      const blob = await new Promise((r) => c.toBlob(r, 'image/png'));
      const base = (state().names?.source || 'pixel').replace(/\.[^.]+$/, '');
      download(`${base}-textured${s > 1 ? `@${s}x` : ''}.png`, blob);
    };
    q('[data-act=save-project]').onclick = () => {
      if (!state()) return;
      const base = (state().names?.source || 'pixel').replace(/\.[^.]+$/, '');
      download(`${base}.filigree.json`, projectText('pixel', state()), 'application/json');
    };

    // Flush the autosave when the tab goes away (discard, close, crash-to-be).
    this.onHide = () => autosave.flush();
    addEventListener('pagehide', this.onHide);

    // Resume the autosaved document, or start from the fish.
    autosave.load().then((saved) => {
      if (saved?.source) return loadDocument(saved);
      return loadExample('fish');
    }).catch((err) => setError(err.message));

    // For tests and the console: the current document and result.
    // For tests and the console: the document, the last result, and whether a run is due or going.
    window.filigreePixel = { state, result: () => result, pending: () => runTimer !== null || running !== null };
  },
  unmount() {
    this.detach?.();
    document.removeEventListener('keydown', this.onKey);
    removeEventListener('pagehide', this.onHide);
    this.onHide?.();
  },
};

/** '#000000, #fff' → {colours: [[0,0,0],[255,255,255]]} or {error}. */
export function parseColours(text) {
  const colours = [];
  for (const part of text.split(/[\s,;]+/).filter(Boolean)) {
    const m = /^#?([0-9a-f]{3}|[0-9a-f]{6})$/i.exec(part);
    if (!m) return { error: `'${part}' is not a colour like #1a2b3c` };
    const h = m[1].length === 3 ? [...m[1]].map((c) => c + c).join('') : m[1];
    colours.push([0, 2, 4].map((i) => parseInt(h.slice(i, i + 2), 16)));
  }
  return { colours };
}
