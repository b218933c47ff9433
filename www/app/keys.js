// Keyboard shortcuts of the shown panel, for the document controller
// (document.js): Ctrl/Cmd+Z undo, Ctrl/Cmd+Shift+Z or Ctrl/Cmd+Y redo,
// Ctrl/Cmd+S save project, Ctrl/Cmd+O open project, and the panel's own
// single keys (`view.keys`, no modifier held). None while typing in a field
// or an editor.
//
//   document.addEventListener('keydown', (e) => onKey(ctl, e));
import { saveProject } from './open.js';

export function onKey(ctl, e) {
  const cur = ctl.current;
  if (!cur || e.defaultPrevented) return;
  const t = e.target;
  if (t?.closest?.('input, select, textarea, [contenteditable=""], [contenteditable=true], .cm-editor')) return;
  const mod = e.ctrlKey || e.metaKey;
  const key = e.key.length === 1 ? e.key.toLowerCase() : e.key;
  if (mod && !e.altKey) {
    if (key === 'z') { e.preventDefault(); if (e.shiftKey) ctl.redo(); else ctl.undo(); } else if (key === 'y' && !e.shiftKey) { e.preventDefault(); ctl.redo(); } else if (key === 's' && !e.shiftKey && cur.tool.state && ctl.persist) { e.preventDefault(); saveProject(ctl); } else if (key === 'o' && !e.shiftKey && cur.tool.state && !cur.readOnly && ctl.persist) {
      e.preventDefault();
      cur.el.querySelector('input[data-input=project]').click();
    }
    return;
  }
  if (e.altKey || e.shiftKey || mod) return;
  const fn = cur.view?.keys?.[key];
  if (fn) { e.preventDefault(); fn(); }
}
