// Files dropped anywhere in the window, for the document controller
// (document.js). A project file opens in any tool, whatever it is dropped
// on. Any other file goes to the panel's `view.drop` when it has one
// (Tangle, Micro), wherever it lands (the editors included: they would paste
// the file's bytes as text); else to the panel's own drop zone
// (ui/file-input.js: images, anywhere too). A refused file leaves the
// document as it was and says why.
//
//   listenForDrops(ctl)          the window's drag and drop, seen first (capture)
//   await openDropped(ctl, file) → whether it opened
import { plainError } from './errors.js';
import { openProjectFile } from './open.js';

const hasFiles = (e) => [...(e.dataTransfer?.types || [])].includes('Files');
const isJson = (file) => /\.json$/i.test(file.name) || /\bjson\b/i.test(file.type);

/** Whether `file` is a Filigree project: named so, or JSON whose envelope says so (its first bytes). */
async function isProjectFile(file) {
  if (/\.filigree\.json$/i.test(file.name)) return true;
  if (!isJson(file)) return false;
  try {
    return /^\s*\{[^]*"format"\s*:\s*"filigree-project"/.test(await file.slice(0, 4096).text());
  } catch {
    return false;
  }
}

/** A file dropped anywhere in the window: the controller sees it first (capture). */
export function listenForDrops(ctl) {
  addEventListener('dragover', (e) => onDragOver(ctl, e), true);
  addEventListener('dragleave', (e) => { if (!e.relatedTarget) dragHint(ctl, false); }, true);
  addEventListener('drop', (e) => onDrop(ctl, e), true);
}

/** Whether the current panel takes dropped files here (not a read-only embed, not the home view). */
function dropTarget(ctl) {
  const cur = ctl.current;
  return cur && !cur.life.dead && !cur.readOnly && cur.tool.state ? cur : null;
}

function onDragOver(ctl, e) {
  if (!hasFiles(e)) return;
  const cur = dropTarget(ctl);
  if (!cur?.view?.drop) return;
  // The panel's: not an editor's either (it would paste the file as text).
  e.preventDefault();
  e.stopPropagation();
  e.dataTransfer.dropEffect = 'copy';
  dragHint(ctl, true);
}

/** The tool lit while a file is over the window (and every zone dark again after). */
function dragHint(ctl, on) {
  const el = ctl.current?.el;
  el?.classList.toggle('drop-over', on);
  if (!on) for (const z of document.querySelectorAll('.dragging')) z.classList.remove('dragging');
}

function onDrop(ctl, e) {
  const file = hasFiles(e) && e.dataTransfer.files[0];
  const cur = file && dropTarget(ctl);
  if (!cur) { dragHint(ctl, false); return; }
  // Images for a panel without view.drop: its zone's (acceptFiles) to take.
  if (!cur.view?.drop && !isJson(file)) { ctl.current?.el.classList.remove('drop-over'); return; }
  e.preventDefault();
  e.stopPropagation();
  dragHint(ctl, false);
  openDropped(ctl, file);
}

/** Open a dropped file: a project as a project, else the panel's (view.drop); says plainly when refused. */
export async function openDropped(ctl, file) {
  const cur = ctl.current;
  if (await isProjectFile(file)) return openProjectFile(ctl, file);
  if (ctl.current !== cur) return false;
  try {
    if (!cur.view?.drop) throw new Error(`it is not a Filigree project, and ${cur.tool.title} opens images and projects`);
    await cur.view.drop(file);
  } catch (err) {
    if (ctl.current !== cur || err?.kind === 'cancelled') return false;
    // A core error with a place says it in its message ("line L, column C: ...").
    const why = `${plainError(err) ?? 'it was cancelled'}`.replace(/\.$/, '');
    cur.ctx.error(new Error(`${file.name} was not opened — ${why}. Your work is unchanged.`), { source: 'drop' });
    return false;
  }
  if (ctl.current === cur) cur.ctx.clearError('drop');
  return true;
}
