// Micro's shipped scenes: a button each (the core's list, pretty-printed);
// one click replaces the scene as one undoable step.
import { examples } from './state.js';

/** The scene picker of a mounted panel: {mark(doc)} presses the document's scene. */
export function createScenePicker(ctx, { q, editor }) {
  const state = () => ctx.state();
  const list = q('[data-testid=micro-examples]');
  examples(ctx.run).then((exs) => {
    if (!ctx.alive()) return;
    list.replaceChildren(...exs.map((ex) => {
      const li = document.createElement('li');
      const b = document.createElement('button');
      b.type = 'button';
      b.className = 'micro-example';
      b.dataset.example = ex.name;
      b.title = ex.about;
      b.textContent = ex.name;
      b.onclick = () => loadExample(ex);
      li.append(b);
      return li;
    }));
    markExample(state());
  }).catch((err) => ctx.error(err, { prefix: 'The shipped scenes' }));

  function markExample(s) {
    for (const b of list.querySelectorAll('[data-example]')) b.setAttribute('aria-pressed', String(b.dataset.example === s?.example));
  }

  function loadExample(ex) {
    const doc = state();
    if (!doc) return;
    editor.stopTyping();
    ctx.commit({ ...doc, example: ex.name, scene: ex.scene });
  }

  return { mark: markExample };
}
