// The code editor for programs (Fit) and grammars (Tangle).
//
//   const ed = await createCodeEditor(parent, { value, language, onChange, label });
//   ed.getValue() → string          ed.setValue(text)   (does not call onChange)
//   ed.markError(line, column, message)   1-based; underlines the token there,
//                                   puts a marker in the gutter, moves the cursor
//                                   there and scrolls it into view
//   ed.clearError()                 ed.focus()          ed.kind: 'codemirror' | 'textarea'
//
// attributes: extra attributes for the editable element (e.g. {'data-testid': …}).
// language: 'filigree' (Fit's pattern language), 'tangle' or 'json'.
// CodeMirror 6 is bundled at build time (scripts/bundle-editor.mjs) into
// www/vendor/code-editor.bundle.js, served from our own origin and precached
// by the service worker; it is imported lazily, so first paint never waits for
// it. Without the bundle (npm not run) the editor is a plain textarea with the
// same API: the error line is selected and named below it.
// Keyboard: Tab leaves the editor (it does not indent; Ctrl+] / Ctrl+[ indent).

let bundle = null;
function loadBundle() {
  bundle ??= import('../vendor/code-editor.bundle.js').catch((err) => {
    console.warn('code editor bundle missing, using a plain textarea:', err?.message || err);
    return null;
  });
  return bundle;
}

/** Start fetching the editor early (e.g. when a panel that needs it mounts). */
export function preloadCodeEditor() {
  loadBundle();
}

export async function createCodeEditor(parent, { value = '', language = 'filigree', onChange, label = 'code', attributes = {}, fallback = false } = {}) {
  const wrap = document.createElement('div');
  wrap.className = 'code-editor';
  wrap.dataset.language = language;
  parent.append(wrap);
  const mod = fallback ? null : await loadBundle();
  if (mod) {
    const ed = mod.createEditor(wrap, { value, language, onChange, label, attributes });
    wrap.dataset.editor = 'codemirror';
    return ed;
  }
  return textareaEditor(wrap, { value, onChange, label, attributes });
}

function textareaEditor(wrap, { value, onChange, label, attributes }) {
  wrap.dataset.editor = 'textarea';
  const ta = document.createElement('textarea');
  ta.spellcheck = false;
  ta.wrap = 'off';
  ta.rows = 16;
  ta.value = value;
  for (const [k, v] of Object.entries(attributes)) ta.setAttribute(k, v);
  ta.setAttribute('aria-label', label);
  const note = document.createElement('div');
  note.className = 'code-editor-error';
  note.hidden = true;
  ta.addEventListener('input', () => onChange?.(ta.value));
  wrap.append(ta, note);
  return {
    kind: 'textarea',
    getValue: () => ta.value,
    setValue(text) { ta.value = text; },
    markError(line, column, message) {
      const lines = ta.value.split('\n');
      const l = Math.max(1, Math.min(lines.length, Math.round(line) || 1));
      let from = 0;
      for (let i = 0; i < l - 1; i++) from += lines[i].length + 1;
      from += Math.max(0, Math.min(lines[l - 1].length, (Math.round(column) || 1) - 1));
      note.textContent = `line ${l}, column ${column}: ${message}`;
      note.hidden = false;
      ta.setAttribute('aria-invalid', 'true');
      ta.focus();
      ta.setSelectionRange(from, Math.min(ta.value.length, from + 1));
      // Scroll the line into view: rows are one line-height each.
      const lh = parseFloat(getComputedStyle(ta).lineHeight) || 16;
      ta.scrollTop = Math.max(0, (l - 3) * lh);
    },
    clearError() {
      note.hidden = true;
      ta.removeAttribute('aria-invalid');
    },
    focus: () => ta.focus(),
    destroy: () => wrap.remove(),
  };
}
