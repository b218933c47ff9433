// What Texture's panel says about its document in words: the predicted
// model (or that none is close), the likeliest models with their
// probabilities, and the retrieved texture with its cosine similarity.

/** The readout of a mounted panel (`live.list`: state.js, for the models' names): {show(doc)}. */
export function createReadout({ q, live }) {
  const predictedEl = q('[data-testid=texture-predicted]');
  const topEl = q('[data-testid=texture-top]');
  const retrievedEl = q('[data-testid=texture-retrieved]');
  const cosineEl = q('[data-testid=texture-cosine]');
  const nameOf = (id) => live.list.find((x) => x.id === id)?.name ?? id;

  function show(s) {
    const p = s.predicted;
    if (p) {
      const close = p.close !== false;
      predictedEl.textContent = close
        ? `Predicted model: ${nameOf(p.model)}`
        : 'No close model: the example is far from every model in the index. The nearest are below.';
      predictedEl.dataset.model = p.model;
      predictedEl.dataset.close = String(close);
    } else {
      predictedEl.textContent = 'No prediction yet: give an example.';
      delete predictedEl.dataset.model;
      delete predictedEl.dataset.close;
    }
    topEl.replaceChildren(...(p?.top || []).map((c) => {
      const li = document.createElement('li');
      li.dataset.model = c.model;
      li.textContent = `${nameOf(c.model)} — ${(100 * c.probability).toFixed(c.probability < 0.1 ? 1 : 0)}%`;
      return li;
    }));
    topEl.hidden = !p?.top?.length;
    const r = s.retrieved;
    if (r) {
      retrievedEl.textContent = `${nameOf(r.model)}, seed ${r.seed}${r.sample === null ? '' : ` (sample ${r.sample})`}${r.edited ? ' — parameters edited' : ''}`;
      retrievedEl.dataset.model = r.model;
      cosineEl.textContent = r.cosine === null ? '' : `· cosine similarity ${r.cosine.toFixed(3)}${r.edited ? ' (before your edits)' : ''}`;
    } else {
      retrievedEl.textContent = 'Nothing retrieved yet.';
      delete retrievedEl.dataset.model;
      cosineEl.textContent = '';
    }
  }

  return { show };
}
