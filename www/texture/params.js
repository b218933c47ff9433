// The retrieved texture's parameters and seed as number fields: an edit
// re-renders it (view.js) and marks the document's retrieval as edited;
// typing in one field is one history step, sealed after a pause.
const EDIT_DELAY_MS = 250;

/** The parameter fields of a mounted panel (`live.list`: state.js): {buildParams(retrieved)}. */
export function createParams(ctx, { q, live }) {
  const state = () => ctx.state();
  const paramList = q('.texture-param-list');
  let editTimer = null;

  let paramsFor = ''; // model id the inputs are built for
  function buildParams(r) {
    const m = r && live.list.find((x) => x.id === r.model);
    if (!m) { paramList.replaceChildren(); paramsFor = ''; return; }
    if (paramsFor !== m.id) {
      paramsFor = m.id;
      paramList.replaceChildren(...m.params.map((p, i) => {
        const row = document.createElement('label');
        row.className = 'texture-param';
        const span = document.createElement('span');
        span.textContent = p.name.replace(/_/g, ' ');
        const input = document.createElement('input');
        input.type = 'number';
        input.min = String(p.lo);
        input.max = String(p.hi);
        input.step = p.integer ? '1' : 'any';
        input.dataset.field = `retrieved.params.${i}`;
        input.dataset.param = p.name;
        input.title = `${p.lo} to ${p.hi}${p.integer ? ', whole numbers' : ''}`;
        input.oninput = () => editParam(i, input);
        row.append(span, input);
        return row;
      }), (() => {
        const row = document.createElement('label');
        row.className = 'texture-param texture-seed';
        const span = document.createElement('span');
        span.textContent = 'seed';
        const input = document.createElement('input');
        input.type = 'number';
        input.min = '0';
        input.step = '1';
        input.dataset.field = 'retrieved.seed';
        input.dataset.param = 'seed';
        input.oninput = () => editParam(-1, input);
        row.append(span, input);
        return row;
      })());
    }
    const inputs = paramList.querySelectorAll('input');
    inputs.forEach((input, i) => {
      const v = i < r.params.length ? r.params[i] : r.seed;
      // Parameters at six significant digits; the seed exactly (an integer ≤ 2⁵³).
      const shown = i < r.params.length ? String(+v.toPrecision(6)) : String(v);
      // A new input's value is '' (which Number reads as 0): a parameter at
      // 0 must still be written.
      if (document.activeElement !== input && (input.value === '' || Number(input.value) !== v)) input.value = shown;
    });
  }

  function editParam(i, input) {
    const doc = state();
    const r = doc?.retrieved;
    const m = r && live.list.find((x) => x.id === r.model);
    if (!m || input.value === '') return;
    let v = Number(input.value);
    if (!Number.isFinite(v)) return;
    const next = { ...r, params: [...r.params], edited: true };
    if (i < 0) {
      if (!Number.isSafeInteger(v) || v < 0) return;
      next.seed = v;
    } else {
      const p = m.params[i];
      v = Math.min(p.hi, Math.max(p.lo, p.integer ? Math.round(v) : v));
      next.params[i] = v;
    }
    ctx.clearTimeout(editTimer);
    editTimer = ctx.setTimeout(() => { editTimer = null; ctx.seal(); }, EDIT_DELAY_MS);
    ctx.commit({ ...doc, retrieved: next }, { coalesce: `texture-param-${i}` });
  }

  return { buildParams };
}
