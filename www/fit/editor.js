// The program: the generator picker (the shipped programs) and the program
// text in its editor (CodeMirror, lazily loaded; a textarea without the
// bundle), applied with "Apply program"; an error in it is marked at the
// line and column the core gives.
import { createCodeEditor } from '../ui/code-editor.js';
import { generatorDoc } from './state.js';
import { programInfo } from './program.js';

/** The program part of the panel (`live`: state.js; `stopFit(reason)`: run.js). */
export function createProgramEditor(ctx, { q, live, stopFit }) {
  const doc = () => ctx.state();
  let editor = null;
  // The program the editor was last given from the document (null: none
  // yet). The text is replaced only when the document's program changes
  // (undo, a file, a generator, Apply): a program being typed and not yet
  // applied survives everything else (an int slider, a target), and so
  // does text typed before the first document arrived.
  let shown = null;
  const show = (d) => {
    if (!editor || d.program === shown) return;
    const typedFirst = shown === null && editor.getValue() !== '';
    if (!typedFirst && editor.getValue() !== d.program) editor.setValue(d.program);
    shown = d.program;
  };
  const editorReady = createCodeEditor(q('.program-editor'), {
    language: 'filigree', label: 'pattern program', attributes: { 'data-testid': 'fit-program', 'data-field': 'program' },
  }).then((ed) => {
    editor = ed;
    if (doc()) show(doc());
    return ed;
  });
  const picker = q('[name=generator]');
  const showGenerator = (d) => {
    picker.value = live.generators.some((g) => g.name === d.generator) ? d.generator : '';
  };

  const generatorsReady = ctx.run('pattern-generators', {}).then((list) => {
    live.generators = list;
    picker.replaceChildren(
      new Option('(custom program)', ''),
      ...list.map((g) => new Option(g.paper ? `${g.name} — ${g.paper}` : g.name, g.name)),
    );
    if (doc()) showGenerator(doc());
  }).catch((err) => ctx.error(err));

  picker.onchange = async (e) => {
    const g = live.generators.find((x) => x.name === e.target.value);
    if (!g) return;
    // A new generator ends the fit of the old one: its values would not fit the new sliders.
    stopFit('the generator changed');
    try {
      ctx.commit(await generatorDoc(ctx.run, g, doc()));
    } catch (err) {
      ctx.error(err);
      picker.value = doc()?.generator ?? '';
    }
  };
  q('[data-act=apply-program]').onclick = async () => {
    const program = editor ? editor.getValue() : doc().program;
    const d = doc();
    const { info } = live;
    try {
      const next = await programInfo(ctx.run, program);
      ctx.clearError();
      editor?.clearError();
      const same = info && next.params.length === info.params.length && next.params.every((p, i) => p.name === info.params[i].name);
      if (program !== d.program) stopFit();
      ctx.commit({
        ...d, program, generator: null,
        values: same ? d.values : next.params.map((p) => p.default),
        truth: same ? d.truth : null, result: null,
      });
    } catch (err) {
      // Keep the last good program running; say where this one is wrong.
      ctx.error(err);
    }
  };
  q('[data-act=show-program]').onclick = () => {
    q('details.program').open = true;
    q('.fit-editor').scrollIntoView({ block: 'start', behavior: 'smooth' });
    editorReady.then((ed) => ctx.alive() && ed.focus());
  };

  return {
    generatorsReady,
    /** The editor and the picker follow document `d`. */
    sync(d) {
      show(d);
      showGenerator(d);
    },
    /** An error about the program: open its text and mark where the core says (`line`, `column`). */
    markError(err) {
      if (err.field !== 'program' && err.kind !== 'syntax') return;
      q('details.program').open = true;
      if (Number.isInteger(err.line)) editorReady.then((ed) => ctx.alive() && ed.markError(err.line, err.column ?? 1, err.message));
    },
  };
}
