// Source of www/vendor/code-editor.bundle.js (built by scripts/bundle.mjs
// with esbuild; the bundle is generated, not committed). It turns CodeMirror 6
// into the small API www/ui/code-editor.js documents; nothing else imports it.
import { EditorState, Compartment, StateField, StateEffect } from '@codemirror/state';
import {
  EditorView, keymap, lineNumbers, highlightActiveLine, highlightActiveLineGutter, drawSelection,
  highlightSpecialChars, Decoration, WidgetType,
} from '@codemirror/view';
import { defaultKeymap, history, historyKeymap } from '@codemirror/commands';
import {
  StreamLanguage, HighlightStyle, syntaxHighlighting, bracketMatching, indentOnInput, indentUnit,
} from '@codemirror/language';
import { setDiagnostics, lintGutter } from '@codemirror/lint';
import { tags as t } from '@lezer/highlight';

// ---- languages ----------------------------------------------------------------

// Fit's pattern language (src/pattern/lang.rs): statements, shapes, builtins.
const FIT_KEYWORDS = new Set(['param', 'int', 'in', 'fn', 'for', 'if', 'else', 'return', 'let', 'background']);
const FIT_BUILTINS = new Set([
  'circle', 'rect', 'line', 'point', 'path', 'move', 'quad', 'cubic', 'close', 'union', 'intersect', 'difference',
  'translate', 'rotate', 'scale', 'sin', 'cos', 'tan', 'atan', 'sqrt', 'abs', 'exp', 'ln', 'floor', 'ceil', 'round',
  'pow', 'mod', 'min', 'max', 'hypot', 'clamp', 'lerp', 'select', 'rgb',
]);
const FIT_ATOMS = new Set(['PI', 'TAU', 'true', 'false']);

function streamFor({ keywords, builtins = new Set(), atoms = new Set(), lineComment = '//', hashComment = false }) {
  return {
    name: 'filigree',
    startState: () => ({}),
    token(stream) {
      if (stream.eatSpace()) return null;
      if (stream.match(lineComment) || (hashComment && stream.match('#'))) { stream.skipToEnd(); return 'comment'; }
      if (stream.match(/^"(?:[^"\\]|\\.)*"?/)) return 'string';
      if (stream.match(/^(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?/)) return 'number';
      if (stream.match(/^[A-Za-z_][A-Za-z0-9_]*/)) {
        const w = stream.current();
        if (keywords.has(w)) return 'keyword';
        if (atoms.has(w)) return 'atom';
        if (builtins.has(w)) return 'builtin';
        // A name followed by ':' is a named argument (fill:, width:, radius:).
        if (stream.match(/^\s*:(?!:)/, false)) return 'propertyName';
        return 'variableName';
      }
      if (stream.match(/^(?:\.\.|==|!=|<=|>=|&&|\|\||->|[-+*/%^<>!=|])/)) return 'operator';
      if (stream.match(/^[()[\]{}]/)) return 'bracket';
      stream.next();
      return 'punctuation';
    },
    languageData: { commentTokens: { line: lineComment } },
  };
}

const LANGUAGES = {
  filigree: () => StreamLanguage.define(streamFor({ keywords: FIT_KEYWORDS, builtins: FIT_BUILTINS, atoms: FIT_ATOMS })),
  // Grammars for the tangle tool: rules `name -> body;`, comments with // or #.
  tangle: () => StreamLanguage.define(streamFor({
    keywords: new Set(['rule', 'start', 'param', 'int', 'in', 'let', 'if', 'else', 'for', 'fn', 'return']),
    atoms: new Set(['PI', 'TAU', 'true', 'false']), hashComment: true,
  })),
  json: () => StreamLanguage.define({
    name: 'json',
    token(stream) {
      if (stream.eatSpace()) return null;
      if (stream.match(/^"(?:[^"\\]|\\.)*"?(?=\s*:)/)) return 'propertyName';
      if (stream.match(/^"(?:[^"\\]|\\.)*"?/)) return 'string';
      if (stream.match(/^-?\d+\.?\d*(?:[eE][+-]?\d+)?/)) return 'number';
      if (stream.match(/^(?:true|false|null)\b/)) return 'atom';
      stream.next();
      return 'punctuation';
    },
  }),
};

// ---- the error under its line -------------------------------------------------
// The lint diagnostic underlines the token and marks the gutter; its message
// would show only on hover. This block widget prints it right under the
// line, where the eyes already are.

const setInlineError = StateEffect.define();

class ErrorWidget extends WidgetType {
  constructor(message) { super(); this.message = message; }
  eq(other) { return other.message === this.message; }
  toDOM() {
    const d = document.createElement('div');
    d.className = 'cm-inline-error';
    d.textContent = this.message;
    return d;
  }
  ignoreEvent() { return false; }
}

const inlineError = StateField.define({
  create: () => Decoration.none,
  update(deco, tr) {
    let next = deco.map(tr.changes);
    for (const e of tr.effects) {
      if (!e.is(setInlineError)) continue;
      next = e.value
        ? Decoration.set([Decoration.widget({ widget: new ErrorWidget(e.value.message), block: true, side: 1 }).range(e.value.pos)])
        : Decoration.none;
    }
    return next;
  },
  provide: (f) => EditorView.decorations.from(f),
});

// ---- look ---------------------------------------------------------------------

const highlight = HighlightStyle.define([
  { tag: t.keyword, color: '#c9a2ff', fontWeight: '600' },
  { tag: [t.atom, t.bool, t.null], color: '#ffb86b' },
  { tag: t.number, color: '#ffd166' },
  { tag: t.string, color: '#7fd1c7' },
  { tag: t.comment, color: '#8a829e', fontStyle: 'italic' },
  { tag: [t.standard(t.variableName), t.special(t.variableName)], color: '#8cb8ff' },
  { tag: t.propertyName, color: '#f3a6c8' },
  { tag: t.operator, color: '#d9d3e6' },
  { tag: t.variableName, color: '#ebe7f3' },
]);

const theme = EditorView.theme({
  '&': { backgroundColor: '#15131b', color: '#ebe7f3', fontSize: '12.5px', borderRadius: '6px', border: '1px solid #363047' },
  '&.cm-focused': { outline: '2px solid #c9a2ff', outlineOffset: '1px' },
  '.cm-scroller': { fontFamily: 'ui-monospace, "SF Mono", Menlo, Consolas, monospace', lineHeight: '1.45' },
  '.cm-content': { caretColor: '#ffffff' },
  '.cm-cursor': { borderLeftColor: '#ffffff' },
  '.cm-gutters': { backgroundColor: '#1b1824', color: '#8a829e', border: 'none', borderRight: '1px solid #363047' },
  '.cm-activeLine': { backgroundColor: '#ffffff0a' },
  '.cm-activeLineGutter': { backgroundColor: '#ffffff12', color: '#ebe7f3' },
  '&.cm-focused .cm-selectionBackground, .cm-selectionBackground, ::selection': { backgroundColor: '#4b3d6e !important' },
  '.cm-matchingBracket': { backgroundColor: '#ffffff22', outline: '1px solid #8a829e' },
  '.cm-lintRange-error': { backgroundImage: 'none', textDecoration: 'underline wavy #ff7b8a', textUnderlineOffset: '3px' },
  '.cm-tooltip': { backgroundColor: '#282436', border: '1px solid #363047', color: '#ebe7f3' },
  '.cm-diagnostic-error': { borderLeftColor: '#ff7b8a' },
  '.cm-inline-error': {
    color: '#ffd0d6', backgroundColor: '#3a1f29', borderLeft: '3px solid #ff7b8a', padding: '2px 8px', margin: '1px 0 3px',
    fontFamily: 'system-ui, sans-serif', fontSize: '12px', whiteSpace: 'pre-wrap',
  },
}, { dark: true });

// ---- the API ------------------------------------------------------------------

/** See www/ui/code-editor.js for the contract. */
export function createEditor(parent, { value = '', language = 'filigree', onChange, label = 'code', attributes = {} } = {}) {
  const lang = (LANGUAGES[language] || LANGUAGES.filigree)();
  const ariaLabel = new Compartment();
  let quiet = false;
  const view = new EditorView({
    parent,
    state: EditorState.create({
      doc: value,
      extensions: [
        lineNumbers(), highlightActiveLineGutter(), highlightSpecialChars(), history(), drawSelection(),
        indentOnInput(), bracketMatching(), highlightActiveLine(), lintGutter(),
        indentUnit.of('  '), lang, syntaxHighlighting(highlight), theme, inlineError,
        // Tab is not bound: it moves focus out of the editor, as everywhere on
        // the page (indent with Ctrl+] / Ctrl+[ instead).
        keymap.of([...defaultKeymap, ...historyKeymap]),
        // tabindex: the editable content is a named Tab stop, so the scrolling box around it is
        // reachable by keyboard (axe: scrollable-region-focusable).
        ariaLabel.of(EditorView.contentAttributes.of({ ...attributes, 'aria-label': label, 'aria-multiline': 'true', tabindex: '0' })),
        EditorView.updateListener.of((u) => {
          if (u.docChanged && !quiet) onChange?.(u.state.doc.toString());
        }),
      ],
    }),
  });

  const clampPos = (line, column) => {
    const doc = view.state.doc;
    const l = doc.line(Math.max(1, Math.min(doc.lines, Math.round(line) || 1)));
    const from = Math.min(l.to, l.from + Math.max(0, (Math.round(column) || 1) - 1));
    return { l, from };
  };

  return {
    view,
    kind: 'codemirror',
    getValue: () => view.state.doc.toString(),
    setValue(text) {
      if (text === view.state.doc.toString()) return;
      quiet = true;
      try {
        view.dispatch({ changes: { from: 0, to: view.state.doc.length, insert: text } });
      } finally {
        quiet = false;
      }
    },
    markError(line, column, message) {
      const { l, from } = clampPos(line, column);
      // Underline the token at the error (to the end of the word), at least one character.
      const rest = view.state.doc.sliceString(from, l.to);
      const word = /^[A-Za-z0-9_.]+/.exec(rest);
      const to = Math.min(l.to, from + Math.max(1, word ? word[0].length : 1));
      const diag = { from, to: to > from ? to : from, severity: 'error', message: message || 'error' };
      view.dispatch(setDiagnostics(view.state, [diag]));
      view.dispatch({ effects: setInlineError.of({ pos: l.to, message: diag.message }) });
      view.dispatch({ selection: { anchor: from }, effects: EditorView.scrollIntoView(from, { y: 'center' }) });
    },
    clearError() {
      view.dispatch(setDiagnostics(view.state, []));
      view.dispatch({ effects: setInlineError.of(null) });
    },
    focus: () => view.focus(),
    destroy: () => view.destroy(),
  };
}
