// Micro's scene JSON editor: typing commits the text once it pauses (one
// coalesced history step), a document's scene is shown unless the user is
// typing, and the core's complaint about the scene is marked at its line.
import { createCodeEditor } from '../ui/code-editor.js';

const TYPING_DELAY_MS = 600;

/** The scene editor of a mounted panel. */
export function createSceneEditor(ctx, { q }) {
  const state = () => ctx.state();
  let typingTimer = null;

  let editor = null;
  const editorReady = createCodeEditor(q('.micro-editor'), {
    language: 'json', label: 'scene JSON',
    attributes: { 'data-testid': 'micro-scene', 'data-field': 'scene' },
    onChange: () => {
      ctx.clearTimeout(typingTimer);
      typingTimer = ctx.setTimeout(applyEditor, TYPING_DELAY_MS);
    },
  }).then((ed) => {
    editor = ed;
    if (state()) ed.setValue(state().scene);
    return ed;
  });

  function applyEditor() {
    ctx.clearTimeout(typingTimer);
    typingTimer = null;
    const doc = state();
    if (!editor || !doc) return false;
    const text = editor.getValue();
    if (text === doc.scene) return false;
    ctx.commit({ ...doc, scene: text, example: null }, { coalesce: 'scene-typing' });
    return true;
  }

  function markSceneError(err) {
    if (err?.field !== 'scene' && err?.kind !== 'syntax') return false;
    const at = Number.isInteger(err.line) && [err.line, err.column ?? 1];
    q('details.micro-program').open = true;
    editorReady.then((ed) => ctx.alive() && ed.markError(at ? at[0] : 1, at ? at[1] : 1, err.message));
    return true;
  }

  return {
    /** Whether typed text waits to be committed. */
    typing: () => typingTimer !== null,
    /** Forget the typed text's pending commit (the document's scene replaces it). */
    stopTyping() {
      ctx.clearTimeout(typingTimer);
      typingTimer = null;
    },
    clearError: () => editor?.clearError(),
    markError: markSceneError,
    render(s, prev) {
      if (editor && editor.getValue() !== s.scene && typingTimer === null) editor.setValue(s.scene);
      if (editor && prev && prev.scene !== s.scene) editor.clearError();
    },
  };
}
