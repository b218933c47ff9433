// The grammar text editor (ui/code-editor.js): typing commits the text once
// it pauses (a new grammar drops the edits and the selection), Ctrl+Enter
// generates, and a syntax error marks its line and column.
import { createCodeEditor } from '../ui/code-editor.js';

const TYPING_DELAY_MS = 600;

/**
 * The editor in `parent` for a mounted panel, inside the `details` that
 * holds it: `live` (state.js), `generate()` (Ctrl+Enter).
 */
export function createGrammarEditor(ctx, parent, { details, live, generate }) {
  const state = () => ctx.state();
  let editor = null;
  let typingTimer = null;
  const ready = createCodeEditor(parent, {
    language: 'tangle', label: 'tangle grammar',
    attributes: { 'data-testid': 'tangle-grammar', 'data-field': 'grammar' },
    onChange: () => {
      ctx.clearTimeout(typingTimer);
      typingTimer = ctx.setTimeout(apply, TYPING_DELAY_MS);
    },
  }).then((ed) => {
    editor = ed;
    if (state()) ed.setValue(state().grammar);
    ed.getValue && parent.addEventListener('keydown', (e) => {
      if (e.key === 'Enter' && (e.ctrlKey || e.metaKey)) { e.preventDefault(); generate(); }
    });
    return ed;
  });

  /** Commit the editor's text when it differs from the document's grammar. */
  function apply() {
    ctx.clearTimeout(typingTimer);
    typingTimer = null;
    const doc = state();
    if (!editor || !doc) return false;
    const text = editor.getValue();
    if (text === doc.grammar) return false;
    live.refit = true;
    ctx.commit({ ...doc, grammar: text, example: null, edits: [], selected: null }, { coalesce: 'grammar-typing' });
    return true;
  }

  return {
    apply,
    /** The grammar as typed (the document's until the editor is ready). */
    text: (doc) => (editor ? editor.getValue() : doc.grammar),
    /** Whether typed text is waiting to be committed. */
    typing: () => typingTimer !== null,
    /** Drop the typed text's pending commit. */
    dropTyping() {
      ctx.clearTimeout(typingTimer);
      typingTimer = null;
    },
    /** Show document `s`'s grammar (not over typed text) and clear a mark of an older grammar. */
    render(s, prev) {
      if (editor && editor.getValue() !== s.grammar && typingTimer === null) editor.setValue(s.grammar);
      if (editor && (!prev || prev.grammar !== s.grammar)) editor.clearError();
    },
    /** Show error `err` at its line and column when it is the grammar's (opening `details`). */
    markError(err) {
      if (err.field !== 'grammar' && err.kind !== 'syntax') return;
      details.open = true;
      const at = Number.isInteger(err.line) && [err.line, err.column ?? 1];
      if (at) ready.then((ed) => ctx.alive() && ed.markError(at[0], at[1], err.message));
    },
  };
}
