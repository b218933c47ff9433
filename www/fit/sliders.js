// The program's parameters: what it declares and draws (facts), a slider a
// parameter. A float previews as it moves (one undo step a drag); an
// integer shapes the program (how many shapes), so it commits on release.

const fmt = (v) => (Math.abs(v) >= 100 ? v.toFixed(1) : v.toFixed(3));

/** The sliders of the panel (`live`: state.js). */
export function createSliders(ctx, { q, live }) {
  const doc = () => ctx.state();
  const form = q('form.sliders');

  const currentValues = () => {
    const d = doc();
    return live.info && d.values.length === live.info.params.length ? d.values : live.info.params.map((p) => p.default);
  };

  /** Facts and one slider a parameter of `live.info`, at document `d`'s values. */
  function build(d) {
    const { info } = live;
    q('[data-testid=fit-facts]').textContent =
      `${info.params.filter((p) => !p.integer).length} parameters to fit, ${info.shapes} shapes, ${info.colours.length - 1} colour${info.colours.length === 2 ? '' : 's'} on ${info.colours[0]}`;
    const values = d.values.length === info.params.length ? d.values : info.params.map((p) => p.default);
    form.replaceChildren(...info.params.map((p, i) => {
      const row = document.createElement('div');
      row.className = 'row';
      row.dataset.param = p.name;
      const label = document.createElement('label');
      label.textContent = p.integer ? `${p.name} (int)` : p.name;
      const input = document.createElement('input');
      Object.assign(input, { type: 'range', min: p.lo, max: p.hi, step: p.integer ? 1 : (p.hi - p.lo) / 1000 });
      input.value = values[i];
      input.setAttribute('aria-label', p.name);
      input.dataset.field = `params.${p.name}`;
      const out = document.createElement('output');
      out.textContent = fmt(values[i]);
      const set = (opts) => {
        const vals = [...currentValues()];
        vals[i] = Number(input.value);
        ctx.commit({ ...doc(), values: vals }, opts);
      };
      input.oninput = () => {
        out.textContent = fmt(Number(input.value));
        if (!p.integer) set({ coalesce: `param-${p.name}` });
      };
      input.onchange = () => {
        if (p.integer) set();
        ctx.seal();
      };
      row.append(label, input, out);
      return row;
    }));
  }

  /** The sliders follow document `d`'s values. */
  function sync(d) {
    for (const [i, p] of live.info.params.entries()) {
      const row = q(`form.sliders [data-param="${CSS.escape(p.name)}"]`);
      if (!row || d.values[i] === undefined) continue;
      const input = row.querySelector('input');
      if (Number(input.value) !== d.values[i]) input.value = d.values[i];
      row.querySelector('output').textContent = fmt(d.values[i]);
    }
  }

  return { build, sync };
}
