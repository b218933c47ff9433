// Project files and share links, for the document controller (document.js):
// the shown document saved as a project file or copied as a link, and a
// project file or a link's state opened as a new undoable document state.
// Whatever comes in is read and checked in full by the core (`open-project`,
// `check-state`, after the panel's `migrate` and `toCore`) before anything changes; on
// failure the user's work stays and the panel's error area says why.
//
//   saveProject(ctl)                      download <name>.filigree.json
//   await openProjectFile(ctl, file)      → whether it opened (in its own tool)
//   await openState(ctl, toolId, state, {version, readOnly, source}) → true, or a plain Error
//   await currentShare(ctl)               → {tool, fragment, omitted?} of the shown document
//   await copyLink(ctl)                   → the link copied (or shown), or null
//   await openFragment(ctl, fragment, fallbackTool) → whether the link opened
import { projectText } from './project-file.js';
import { download } from '../ui/download.js';
import { withTimeout } from '../ui/timeout.js';
import { encodeShare, decodeShare, ShareTooBig, kb, LINK_LIMIT_TEXT } from './share.js';
import { plainError } from './errors.js';
import { nulls, coreDefaults, checkState } from './core-state.js';

export function saveProject(ctl) {
  const cur = ctl.current;
  const state = cur && ctl.docs.get(cur.tool.id)?.history?.present;
  if (!state) return;
  const base = String(cur.tool.state.fileName?.(state) || cur.tool.id).replace(/\.[^.]+$/, '').replace(/[^\w.-]+/g, '-');
  download(`${base}.filigree.json`, projectText(cur.tool.id, cur.tool.state.version, state), 'application/json');
}

/**
 * Open a project file: read by the core (`open-project`: envelope, bytes),
 * its state converted and checked in full (`checkState`) before anything
 * changes; the current work stays on failure.
 */
export async function openProjectFile(ctl, file) {
  const ctx = ctl.current?.ctx;
  let tool, state;
  try {
    const text = await file.text();
    // Read in the current tool's module (no other module loads for it), and
    // left unchecked: its state is checked as every document from outside is
    // (checkState: migrated, converted by the tool's `toCore`, then checked
    // in the tool's own module).
    const opened = nulls(await ctl.pool.run('open-project', { text, unchecked: true }, { module: ctl.current?.tool.id }));
    tool = ctl.tool(opened.tool);
    if (!tool?.state) throw new Error(`it is a project of a tool this Filigree does not have ('${opened.tool}')`);
    state = await checkState(ctl.pool, tool, opened.state, opened.stateVersion);
  } catch (err) {
    const why = String(plainError(err) ?? 'it was cancelled').replace(/\.$/, '');
    ctx?.error(new Error(`${file.name} was not opened — ${why}. Your work is unchanged.`));
    return false;
  }
  const cur = await ctl.show(tool.id, { state, source: 'project' });
  cur.ctx.clearError();
  return true;
}

/**
 * Open a shared state (what a link carries) in tool `toolId`: converted
 * (`fromShare`), migrated and validated BEFORE anything changes, then
 * loaded as an undoable step (autosaved unless `readOnly` or persist is off).
 * Rejects with an Error with a plain message; the user's work is untouched then.
 */
export async function openState(ctl, toolId, state, { version, readOnly = false, source = 'link' } = {}) {
  const tool = ctl.tool(toolId);
  if (!tool?.state) throw new Error(`Filigree has no tool '${toolId}'.`);
  let full;
  try {
    const raw = tool.state.fromShare ? await tool.state.fromShare(state, helperCtx(ctl, tool)) : state;
    full = await checkState(ctl.pool, tool, raw, version ?? tool.state.version);
  } catch (err) {
    const why = String(plainError(err) ?? 'it was cancelled').replace(/([^.])$/, '$1.');
    throw Object.assign(new Error(`This ${source} could not be opened: ${why} Your own work is unchanged.`), { workUnchanged: true });
  }
  if (readOnly) ctl.persist = false;
  await ctl.show(tool.id, { state: full, source }, { readOnly });
  return true;
}

/** A context for conversions outside a mounted panel (opening a link). */
function helperCtx(ctl, tool) {
  return { pool: ctl.pool, run: (k, p, o) => ctl.pool.run(k, p, { module: tool.id, ...o }), coreDefaults: () => coreDefaults(ctl.pool, tool.id) };
}

/**
 * {tool, fragment, omitted?} of the current document; throws ShareTooBig
 * or an Error saying why it cannot be shared. A state whose link would be
 * too big is shared without its big inputs when the tool says how
 * (`state.shareLean(state) → {state, omits}`, `omits` in words: 'the
 * example'); `omitted` = {what, size} then says what the link leaves out.
 */
export async function currentShare(ctl) {
  const cur = ctl.current;
  const state = cur && ctl.docs.get(cur.tool.id)?.history?.present;
  if (!state) throw new Error('There is nothing to share yet.');
  const spec = cur.tool.state;
  const s = spec.toShare ? await spec.toShare(state) : state;
  try {
    return { tool: cur.tool.id, fragment: await encodeShare(cur.tool.id, s, { version: spec.version }) };
  } catch (err) {
    const lean = err instanceof ShareTooBig && spec.shareLean?.(state);
    if (!lean) throw err;
    const fragment = await encodeShare(cur.tool.id, spec.toShare ? await spec.toShare(lean.state) : lean.state, { version: spec.version });
    return { tool: cur.tool.id, fragment, omitted: { what: lean.omits, size: err.size } };
  }
}

export async function copyLink(ctl) {
  let share;
  try {
    share = await currentShare(ctl);
  } catch (err) {
    if (err instanceof ShareTooBig) {
      ctl.toast(err.message, { timeout: 15000, action: { label: 'Save project', run: () => saveProject(ctl) } });
    } else ctl.current?.ctx.error(err);
    return null;
  }
  // A link that leaves something out says so before it is copied.
  if (share.omitted) {
    const { what, size } = share.omitted;
    return new Promise((resolve) => {
      const t = ctl.toast(`This link leaves out ${what} (${kb(size)} > the ${LINK_LIMIT_TEXT} a link holds): whoever opens it gets everything else. Save project keeps it all.`, {
        timeout: 0, action: { label: 'Copy link without it', run: () => resolve(copyFragment(ctl, share.fragment, ` It leaves out ${what}.`)) },
      });
      t.dataset.omits = what;
      const save = document.createElement('button');
      save.type = 'button';
      save.textContent = 'Save project';
      save.onclick = () => { t.remove(); saveProject(ctl); resolve(null); };
      t.querySelector('button').after(save);
    });
  }
  return copyFragment(ctl, share.fragment);
}

/** Copy the app's URL with `fragment` (shown in a toast when the clipboard refuses). */
async function copyFragment(ctl, fragment, note = '') {
  const url = new URL(location.href);
  url.searchParams.delete('embed');
  url.searchParams.delete('mode');
  url.hash = fragment;
  const link = url.href;
  ctl.lastLink = link;
  let copied = false;
  try {
    await withTimeout(navigator.clipboard.writeText(link), 1000, 'clipboard');
    copied = true;
  } catch { /* no clipboard permission: show the link instead */ }
  const t = ctl.toast(copied ? `Link copied. Anyone who opens it sees this state.${note}` : `Copy this link (the clipboard is not available here):${note}`, { timeout: 12000 });
  t.dataset.link = link;
  if (!copied) {
    const field = document.createElement('input');
    field.readOnly = true;
    field.value = link;
    field.setAttribute('aria-label', 'link to this state');
    t.querySelector('span').after(field);
    field.select();
  }
  return link;
}

/** Open the state a fragment carries (a share link); shows a plain error on failure. */
export async function openFragment(ctl, fragment, fallbackTool) {
  let decoded;
  try {
    decoded = await decodeShare(fragment);
    await openState(ctl, decoded.tool, decoded.state, { version: decoded.version, source: 'link' });
    return true;
  } catch (err) {
    const cur = await ctl.show(decoded?.tool || fallbackTool);
    const msg = err.workUnchanged ? err.message : `${err.message} Your own work is unchanged.`;
    cur.ctx.error(new Error(msg));
    return false;
  }
}
