// The selected step and its edits. Clicking a shape selects the step that
// made it (clicking again walks further back); the side column shows the
// step and a slider for each of its parameters. Moving one appends an edit
// {step, params} to the document (a drag replaces its own edit), and
// Re-expand appends an empty one: the step is grown again with a new random
// draw. The regrown step lands at a new position; the next answer selects
// it there (`resolveSelection`).
import { createStepList } from './step-list.js';

/**
 * The selection of a mounted panel (`q` finds its elements): `live`
 * (state.js), `painter` (canvas.js: picking on its canvas), `runner`
 * (schedule.js: a released slider runs at once).
 */
export function createSelection(ctx, { q, live, painter, runner, status }) {
  const state = () => ctx.state();
  let drag = null; // a parameter drag: {key, base, step, predicted, group}
  let pendingGroup = null; // after an edit: re-find the selected step by its group
  let pendingKey = null;

  function select(next, opts = { coalesce: 'tangle-select' }) {
    const doc = state();
    if (!doc || doc.selected === next) return;
    ctx.commit({ ...doc, selected: next }, opts);
  }
  /** Select step `i` (null: none) from a list or a button, not from the canvas. */
  const choose = (i) => { live.lastPick = -1; select(i); };

  /** The step before `s`: the one that made its shapes (null: they are start shapes). */
  function parentStep(s) {
    const first = live.T.r.steps[s]?.inputs[0];
    if (first === undefined) return null;
    const b = live.T.born[first];
    return b >= 0 ? b : null;
  }

  /** A click on the canvas at (cx, cy) CSS px. */
  function pickAt(cx, cy) {
    const { T } = live;
    if (!T) return;
    const [x, y] = painter.toWorld(cx, cy);
    const i = T.pick(x, y, live.k, painter.g);
    const sel = live.selected();
    if (i < 0) { live.lastPick = -1; return; }
    let next;
    if (i === live.lastPick && sel !== null) {
      next = parentStep(sel);
      if (next === null) { status('this is the first step that made these shapes'); next = sel; }
    } else {
      next = T.born[i] >= 0 ? T.born[i] : null;
      if (next === null) status('a start shape: no step made it');
    }
    live.lastPick = i;
    select(next);
  }

  /** Append edit {step: sel, params} (a drag replaces its own edit) and re-run. */
  function edit(sel, params, key) {
    const doc = state();
    const { T } = live;
    if (!doc || !T) return;
    if (!drag || drag.key !== key) {
      drag = {
        key, base: doc.edits, step: sel, group: T.r.steps[sel].group,
        // The regrown step lands after the steps it does not touch.
        predicted: T.steps - T.dependents(sel).length,
      };
    }
    const edits = [...drag.base, { step: drag.step, params }];
    pendingGroup = drag.group;
    pendingKey = key;
    ctx.commit({ ...doc, edits, selected: drag.predicted }, { coalesce: key });
  }

  let editNo = 0;
  function reexpand() {
    const sel = live.selected();
    if (sel === null) return;
    drag = null;
    edit(sel, {}, `tangle-reexpand-${++editNo}`);
    drag = null;
  }

  /** After an edit, the edited step was regrown at a new position: select it there. */
  function resolveSelection() {
    if (pendingGroup === null || !live.T) return;
    const group = pendingGroup, key = pendingKey;
    pendingGroup = pendingKey = null;
    const pos = live.T.r.steps.findIndex((s) => s.group === group);
    const doc = state();
    if (pos >= 0 && doc && doc.selected !== pos) ctx.commit({ ...doc, selected: pos }, { coalesce: key });
  }

  // ---- the side column: the step, its list and its parameters ----------------------------

  const stepList = createStepList(q('[data-testid=tangle-step-list]'), { live, choose });

  function showSelected() {
    stepList.sync();
    const { T } = live;
    const sel = live.selected();
    const box = q('[data-testid=tangle-selected]');
    const form = q('[data-testid=tangle-params]');
    for (const a of ['reexpand', 'select-back', 'select-none']) q(`[data-act=${a}]`).disabled = sel === null;
    if (sel === null) {
      box.textContent = 'Click a shape to select the step that made it; click it again to go further back.';
      box.classList.add('muted');
      delete box.dataset.step;
      form.replaceChildren();
      return;
    }
    const st = T.r.steps[sel];
    box.classList.remove('muted');
    box.dataset.step = String(sel);
    box.dataset.operator = st.operator;
    const tag = T.r.tags[st.tag] ?? st.tag;
    box.innerHTML = '';
    const b = document.createElement('b');
    b.textContent = `Step ${sel + 1} of ${T.steps}: ${st.operator}`;
    const facts = document.createElement('span');
    facts.className = 'muted';
    facts.textContent = ` — rule on line ${st.line}, tag ${tag}, group ${st.group}, ${st.inputs.length} in → ${st.outputs.length} out`;
    box.append(b, facts);
    if (drag) return; // keep the slider being dragged
    form.dataset.step = String(sel);
    form.replaceChildren(...st.params.map((p) => paramRow(sel, p)));
    if (!st.params.length) {
      const none = document.createElement('p');
      none.className = 'muted';
      none.textContent = `${st.operator} has no parameters; Re-expand draws its rule again.`;
      form.append(none);
    }
  }

  let dragNo = 0;
  function paramRow(sel, p) {
    const row = document.createElement('label');
    row.className = 'tangle-param';
    row.dataset.param = p.name;
    const name = document.createElement('span');
    name.textContent = p.name;
    const input = document.createElement('input');
    input.type = 'range';
    input.min = String(p.min);
    input.max = String(Math.max(p.max, p.value));
    input.step = p.integer ? '1' : String((p.max - p.min) / 400);
    input.value = String(p.value);
    input.dataset.testid = `tangle-param-${p.name}`;
    input.setAttribute('aria-label', `${p.name} of step ${sel + 1}`);
    const out = document.createElement('output');
    const show = (v) => { out.textContent = p.integer ? String(v) : v.toFixed(2).replace(/\.?0+$/, ''); };
    show(p.value);
    let key = null;
    input.oninput = () => {
      const v = p.integer ? Math.round(Number(input.value)) : Number(input.value);
      show(v);
      key ??= `tangle-param-${sel}-${p.name}-${++dragNo}`;
      edit(sel, { [p.name]: v }, key);
    };
    input.onchange = () => {
      ctx.seal();
      key = null;
      drag = null;
      if (runner.due()) runner.run(); // released: no need to wait for more moves
      else if (live.shownFor === state()) showSelected();
    };
    row.append(name, input, out);
    return row;
  }

  q('[data-act=reexpand]').onclick = reexpand;
  q('[data-act=select-back]').onclick = () => {
    const sel = live.selected();
    if (sel === null) return;
    const p = parentStep(sel);
    if (p === null) status('this is the first step that made these shapes');
    else select(p);
  };
  q('[data-act=select-none]').onclick = () => choose(null);

  return { pickAt, reexpand, resolveSelection, showSelected };
}
