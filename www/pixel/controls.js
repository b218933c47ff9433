// Pixel's parameter form: one row per field of the core's PixelParams
// (CONTROLS), each change one commit of the document (a slider's drag one
// coalesced step), and `sync(params)` to show a document's values.
import { hex } from '../ui/file-input.js';

const DIRECTIONS = ['up', 'up-right', 'right', 'down-right', 'down', 'down-left', 'left', 'up-left'];

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
  { key: 'annotation_scale', label: 'Annotation scale K', type: 'range', min: 1, max: 32, step: 1, show: (v) => `×${v}` },
  { key: 'default_direction', label: 'Direction without strokes', type: 'select', options: DIRECTIONS },
  { key: 'seed', label: 'Seed', type: 'seed' },
];

/** The rows of CONTROLS in `form`; returns {sync(params)}. */
export function createControls(ctx, form) {
  const state = () => ctx.state();
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
      ctx.commit({ ...doc, params: { ...doc.params, [c.key]: value } }, opts);
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
      input.onchange = () => ctx.seal();
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
          const v = [...input.querySelectorAll('input')].map((x) => Math.max(c.min, Math.min(c.max, Math.round(Number(x.value) || 0))));
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
        if (parsed.error) { ctx.error(Object.assign(new Error(`Excluded colours: ${parsed.error}`), { field: 'params.exclude' })); return; }
        ctx.clearError();
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
    input.dataset.field = `params.${c.key}`;
    row.insertBefore(input, row.children[1] || null);
    return row;
  }

  function syncControls(p) {
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
    form.querySelector('[data-key=hsv]').classList.toggle('dim', p.colour !== 'hsv' && p.colour !== 'auto');
    form.querySelector('[data-key=d_max]').classList.toggle('dim', p.colour !== 'auto');
  }

  return { sync: syncControls };
}

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
