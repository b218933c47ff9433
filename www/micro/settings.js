// Micro's render settings: the step mode, slice view and its z, and the
// shading (surface, roughness, specular, absorption, path tracing and its
// depth); each change commits the document (a slider's drag one coalesced
// step), and `render(doc)` shows a document's values.
import { clamp } from './state.js';

const SPP_CHOICES = [0, 4, 16, 64, 256, 1024];
const STEP_MODES = [
  ['fixed', 'Fixed steps'],
  ['bisection', 'Bisection'],
  ['adaptive', 'Adaptive'],
];

/** The settings of a mounted panel (`root`: the panel's element). */
export function createSettings(ctx, { root, q }) {
  const state = () => ctx.state();
  const stepsSel = q('[name=steps]');
  for (const [v, label] of STEP_MODES) {
    const o = document.createElement('option');
    o.value = v;
    o.textContent = label;
    stepsSel.append(o);
  }
  stepsSel.onchange = () => { const doc = state(); if (doc) ctx.commit({ ...doc, steps: stepsSel.value }); };
  const sliceBox = q('[name=slice]');
  sliceBox.onchange = () => { const doc = state(); if (doc) ctx.commit({ ...doc, view: sliceBox.checked ? 'slice' : 'render' }); };
  const zInput = q('[name=z]');
  zInput.oninput = () => { const doc = state(); if (doc) ctx.commit({ ...doc, z: Number(zInput.value) }, { coalesce: 'micro-z' }); };
  zInput.onchange = () => ctx.seal();

  const shadingSel = q('[name=shading]');
  const sppSel = q('[name=spp]');
  const depthInput = q('[name=max_depth]');
  const sliders = ['roughness', 'specular', 'absorption'].map((k) => q(`[name=${k}]`));
  const sppLabel = (n) => (n ? `${n} samples per pixel` : 'off (direct shading)');
  const sppOptions = (cur) => {
    const want = [...new Set([...SPP_CHOICES, cur])].sort((a, b) => a - b);
    if (sppSel.options.length === want.length && [...sppSel.options].every((o, i) => Number(o.value) === want[i])) return;
    sppSel.replaceChildren(...want.map((n) => { const o = document.createElement('option'); o.value = String(n); o.textContent = sppLabel(n); return o; }));
  };
  sppOptions(0);
  const commitField = (k, v, coalesce) => { const doc = state(); if (doc && doc[k] !== v) ctx.commit({ ...doc, [k]: v }, coalesce ? { coalesce } : undefined); };
  shadingSel.onchange = () => commitField('shading', shadingSel.value);
  sppSel.onchange = () => commitField('spp', Number(sppSel.value));
  depthInput.onchange = () => {
    const v = Math.round(Number(depthInput.value));
    if (Number.isFinite(v)) commitField('max_depth', clamp(v, 1, 64));
    else depthInput.value = String(state()?.max_depth ?? 4);
  };
  for (const el of sliders) {
    el.oninput = () => commitField(el.name, Number(el.value), `micro-${el.name}`);
    el.onchange = () => ctx.seal();
  }

  return {
    render(s) {
      stepsSel.value = s.steps;
      sliceBox.checked = s.view === 'slice';
      zInput.disabled = s.view !== 'slice';
      if (Number(zInput.value) !== s.z) zInput.value = String(s.z);
      zInput.nextElementSibling.textContent = s.z.toFixed(2);
      shadingSel.value = s.shading;
      for (const el of sliders) {
        if (Number(el.value) !== s[el.name]) el.value = String(s[el.name]);
        el.nextElementSibling.textContent = String(s[el.name]);
      }
      for (const l of root.querySelectorAll('[data-ggx]')) l.hidden = s.shading !== 'ggx';
      sppOptions(s.spp);
      sppSel.value = String(s.spp);
      depthInput.value = String(s.max_depth);
      depthInput.disabled = !(s.spp > 0);
    },
  };
}
