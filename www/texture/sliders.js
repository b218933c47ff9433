// Texture's twelve perceptual scales as sliders, and "Stay within the
// predicted model": a move commits the document (a drag one coalesced step)
// and asks the runner (schedule.js) for the nearest texture.
import { SCALES, label } from './state.js';

/** The sliders of a mounted panel: {sync(doc)} shows a document's scales (and its example's estimates). */
export function createSliders(ctx, { q, sameBox, runner }) {
  const state = () => ctx.state();
  const sliders = SCALES.map((name, i) => {
    const row = document.createElement('div');
    row.className = 'row';
    const id = `texture-scale-${name}`;
    row.innerHTML = `<label for="${id}" title="${label(name)} (estimate)">${label(name)}</label>
      <input type="range" id="${id}" min="1" max="9" step="0.5" data-field="scales.${i}" data-testid="${id}" data-scale="${name}">
      <output for="${id}"></output>`;
    const input = row.querySelector('input');
    input.oninput = () => {
      const doc = state();
      if (!doc) return;
      const scales = [...doc.scales];
      scales[i] = Number(input.value);
      ctx.commit({ ...doc, scales }, { coalesce: 'texture-scales' });
      runner.schedule();
    };
    input.onchange = () => runner.seal();
    input.addEventListener('pointerdown', () => runner.hold(true));
    input.addEventListener('pointerup', () => runner.hold(false));
    q('.texture-sliders').append(row);
    return { input, out: row.querySelector('output'), row };
  });

  sameBox.onchange = () => {
    const doc = state();
    if (!doc) return;
    ctx.commit({ ...doc, sameModel: sameBox.checked }, { coalesce: 'texture-scales' });
    runner.sealAfterAnswer();
    runner.schedule();
  };

  function sync(s) {
    s.scales.forEach((v, i) => {
      const { input, out } = sliders[i];
      if (Number(input.value) !== v) input.value = String(v);
      const est = s.predicted ? s.predicted.scales[i] : null;
      out.textContent = String(v);
      out.title = est === null ? '' : `estimate of the example: ${est}`;
      input.setAttribute('aria-valuetext', `${v}${est === null ? '' : ` (the example's estimate: ${est})`}`);
    });
    sameBox.checked = !!s.sameModel;
    sameBox.disabled = !s.predicted;
  }

  return { sync };
}

