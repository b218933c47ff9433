// The document's chrome around every tool's panel, for the document
// controller (document.js): the document bar (Undo, Redo, Save project,
// Open project, Copy link, a busy note), the storage note and the tabs bar
// (their words: storage.js), the panel's one error area, and the body the
// panel mounts into.
//
//   const el = chromeFor(tool, readOnly)  a tool's section: the chrome and an empty .doc-body
//   wireChrome(ctl, cur)                  its buttons to the controller's parts
import { saveProject, openProjectFile, copyLink } from './open.js';

const CHROME = `
  <div class="doc-bar" role="toolbar" aria-label="Document">
    <button type="button" data-act="undo" aria-label="Undo" title="Undo (Ctrl+Z)" disabled>↶ Undo</button>
    <button type="button" data-act="redo" aria-label="Redo" title="Redo (Ctrl+Shift+Z or Ctrl+Y)" disabled>↷ Redo</button>
    <button type="button" data-act="save-project" title="Save project (Ctrl+S)">Save project</button>
    <button type="button" data-act="open-project" title="Open project (Ctrl+O)">Open project…</button>
    <input type="file" accept=".json,application/json" data-input="project" hidden tabindex="-1" aria-hidden="true">
    <button type="button" data-act="copy-link" title="Copy a link to this state">Copy link</button>
    <span class="doc-busy muted" aria-live="polite"></span>
  </div>
  <div class="doc-note" role="status" data-testid="doc-note" hidden></div>
  <div class="doc-note doc-tabs" role="alert" data-testid="doc-tabs" hidden>
    <span></span>
    <button type="button" data-act="tab-reload" title="Show the other tab's version here (Undo brings yours back)">Reload</button>
    <button type="button" data-act="tab-keep" title="Save this tab's version over the other tab's">Keep mine</button>
  </div>
  <div class="error doc-error" role="alert" data-testid="doc-error" hidden></div>
  <div class="doc-body"></div>`;

/** The section of `tool`: its chrome (no document bar for a tool without a document) and an empty body. */
export function chromeFor(tool, readOnly) {
  const el = document.createElement('section');
  el.className = `tool tool-${tool.id}`;
  el.setAttribute('aria-label', tool.title);
  el.innerHTML = CHROME;
  if (!tool.state) el.querySelector('.doc-bar').hidden = true;
  if (readOnly) el.dataset.readonly = '1';
  return el;
}

/** The chrome's buttons of the mounted `cur` (a read-only embed has no Undo, Redo or Open). */
export function wireChrome(ctl, cur) {
  const q = (s) => cur.el.querySelector(s);
  q('[data-act=undo]').onclick = () => ctl.undo();
  q('[data-act=redo]').onclick = () => ctl.redo();
  q('[data-act=save-project]').onclick = () => saveProject(ctl);
  const input = q('input[data-input=project]');
  q('[data-act=open-project]').onclick = () => input.click();
  input.onchange = () => {
    const file = input.files[0];
    input.value = '';
    if (file) openProjectFile(ctl, file);
  };
  q('[data-act=copy-link]').onclick = () => copyLink(ctl);
  q('[data-act=tab-reload]').onclick = () => ctl.storage.takeOtherTab();
  q('[data-act=tab-keep]').onclick = () => ctl.storage.keepMine();
  if (cur.readOnly) for (const a of ['undo', 'redo', 'open-project']) q(`[data-act=${a}]`).hidden = true;
}
