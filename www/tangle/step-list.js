// The step list: every step of the answer, a listbox in sync with the
// selection. Keyboard (WAI-ARIA listbox, selection follows focus): arrows,
// Home, End, Page keys; Escape deselects. A click on a shape of the drawing
// selects the step here too.

/**
 * The listbox `stepList` of a mounted panel, showing the steps of
 * `live.T` (state.js); `choose(i)` selects step i (null: none).
 */
export function createStepList(stepList, { live, choose }) {
  let listFor = null; // the answer the list shows

  function build() {
    const { T } = live;
    if (listFor === T) return;
    listFor = T;
    if (!T) { stepList.replaceChildren(); return; }
    stepList.replaceChildren(...T.r.steps.map((st, i) => {
      const li = document.createElement('li');
      li.id = `tangle-step-${i}`;
      li.setAttribute('role', 'option');
      li.setAttribute('aria-selected', 'false');
      li.dataset.step = String(i);
      li.textContent = `${i + 1}. ${st.operator} · ${T.r.tags[st.tag] ?? st.tag} · ${st.inputs.length} → ${st.outputs.length}`;
      return li;
    }));
  }

  /** Show the answer's steps and mark the selected one. */
  function sync() {
    build();
    const sel = live.selected();
    const was = stepList.querySelector('[aria-selected=true]');
    if (was && Number(was.dataset.step) !== sel) was.setAttribute('aria-selected', 'false');
    const opt = sel === null ? null : stepList.children[sel];
    if (!opt) { stepList.removeAttribute('aria-activedescendant'); return; }
    opt.setAttribute('aria-selected', 'true');
    stepList.setAttribute('aria-activedescendant', opt.id);
    // Into view inside the list only (the page does not jump).
    if (opt.offsetTop < stepList.scrollTop) stepList.scrollTop = opt.offsetTop;
    else if (opt.offsetTop + opt.offsetHeight > stepList.scrollTop + stepList.clientHeight) stepList.scrollTop = opt.offsetTop + opt.offsetHeight - stepList.clientHeight;
  }

  stepList.addEventListener('click', (e) => {
    const li = e.target.closest('[role=option]');
    if (!li) return;
    choose(Number(li.dataset.step));
  });
  stepList.addEventListener('keydown', (e) => {
    const { T } = live;
    if (!T || !T.steps || e.altKey || e.ctrlKey || e.metaKey) return;
    const sel = live.selected();
    const page = Math.max(1, Math.floor(stepList.clientHeight / (stepList.firstElementChild?.offsetHeight || 20)) - 1);
    const at = sel ?? -1;
    const next = {
      ArrowDown: at + 1, ArrowUp: sel === null ? T.steps - 1 : at - 1, Home: 0, End: T.steps - 1,
      PageDown: at + page, PageUp: Math.max(0, at - page),
    }[e.key];
    if (e.key === 'Escape' && sel !== null) { e.preventDefault(); e.stopPropagation(); choose(null); return; }
    if (next === undefined) return;
    e.preventDefault();
    choose(Math.max(0, Math.min(T.steps - 1, next)));
  });

  return { sync };
}
