// Embed mode (MISSION S7): `index.html?embed=1#<share fragment>` shows ONE
// tool without the app chrome, for tutorial pages (see www/embed.js, the
// <filigree-embed> element that frames it).
//
//   ?embed=1                     read-only: the result is shown, controls are inert
//   ?embed=1&mode=interactive    controls live
//
// Either way an embedded instance never touches the user's storage: main.js
// makes the document controller with `persist: false` (no autosave is read
// or written, no `navigator.storage.persist()`), and the service worker is
// not registered (from a third-party frame it would control the user's
// full-app scope). "Open in Filigree" opens the full app with the same state
// (the current one, when interactive).
//
// main.js calls embedOptions() once, enterEmbed() instead of its routing,
// and serviceWorkerAllowed() before registering the worker.

import { decodeShare, hasShare } from './share.js';

/** The embed settings in `loc`'s query, or null when the page is the full app. */
export function embedOptions(loc = location) {
  const query = new URLSearchParams(loc.search);
  if (query.get('embed') !== '1') return null;
  const mode = query.get('mode') === 'interactive' ? 'interactive' : 'readonly';
  return { mode, readOnly: mode === 'readonly', fragment: loc.hash.replace(/^#/, '') };
}

/**
 * Whether to register the service worker. Not when embedded, not in a frame
 * of another origin (the browser refuses or partitions it there, and it
 * would claim the full app's scope from a third-party context), and not
 * where merely reading `navigator.serviceWorker` throws or gives nothing
 * (sandboxed and storage-blocked documents). Skipping is silent: the app
 * works the same, only without offline.
 */
export function serviceWorkerAllowed(embed) {
  if (embed || inCrossOriginFrame()) return false;
  try {
    return Boolean(navigator.serviceWorker);
  } catch {
    return false;
  }
}

/** True inside a frame whose top page is another origin (or an opaque one). */
export function inCrossOriginFrame() {
  if (window.top === window.self) return false;
  try {
    return window.top.location.origin !== location.origin;
  } catch {
    return true;
  }
}

/** The full app's URL (no embed parameters) carrying `fragment`. */
export function fullAppUrl(fragment, loc = location) {
  const url = new URL(loc.href);
  url.searchParams.delete('embed');
  url.searchParams.delete('mode');
  url.hash = fragment || '';
  return url.href;
}

const LOGO = '<svg viewBox="0 0 32 32" width="20" height="20" aria-hidden="true"><g fill="none" stroke="currentColor" stroke-width="2.2" stroke-linecap="round"><path d="M16 3c6 5 6 21 0 26M16 3c-6 5-6 21 0 26M3 16c5-6 21-6 26 0M3 16c5 6 21 6 26 0"/><circle cx="16" cy="16" r="3"/></g></svg>';

// Embed-only styles live here, not in styles.css: they apply only under
// html[data-embed] and ship with the code that sets it.
const EMBED_CSS = `
html[data-embed] .app-header, html[data-embed] #tools { display: none !important; }
html[data-embed] main { max-width: none; padding: .6rem; }
html[data-embed] [data-act=save-project], html[data-embed] [data-act=open-project],
html[data-embed] label:has(> [data-input=project]), html[data-embed] [data-act=copy-link],
html[data-embed] [data-role=storage-note] { display: none !important; }
.embed-bar { display: flex; align-items: center; gap: .6rem; padding: .4rem .8rem; min-height: 2.6rem;
  background: var(--panel, #1f1c29); border-bottom: 1px solid var(--line, #363047); position: sticky; top: 0; z-index: 5; }
.embed-bar .logo { color: var(--accent, #c9a2ff); display: inline-flex; }
.embed-bar .name { font-weight: 600; }
.embed-bar .mode { font-size: .78rem; color: var(--muted, #a49cb8); border: 1px solid var(--line, #363047);
  border-radius: 99px; padding: .05rem .55rem; }
.embed-bar .open { margin-left: auto; color: var(--accent, #c9a2ff); font-weight: 600; text-decoration: none;
  border: 1px solid var(--accent, #c9a2ff); border-radius: 7px; padding: .25rem .7rem; white-space: nowrap; }
.embed-bar .open:hover, .embed-bar .open:focus-visible { background: var(--accent, #c9a2ff); color: #1b1526; }
.embed-note { margin: .6rem; }
html[data-embed=readonly] #panel :is(.doc-bar, [role=toolbar], button) { display: none !important; }
html[data-embed=readonly] #panel :is(input, select, textarea, button, .button-like) { opacity: .55; }
html[data-embed=readonly] #panel canvas { cursor: default !important; }
`;

/**
 * Turn the page into an embed: chrome, then the link's state through
 * `app.openState` (read-only or not). The document controller was made with
 * `persist: false`, so nothing here is ever autosaved.
 */
export async function enterEmbed(app, embed) {
  app.embed = embed;
  const root = document.documentElement;
  root.dataset.embed = embed.mode;
  const style = document.createElement('style');
  style.textContent = EMBED_CSS;
  document.head.append(style);

  const params = new URLSearchParams(embed.fragment);
  const bar = document.createElement('div');
  bar.className = 'embed-bar';
  bar.setAttribute('role', 'banner');
  const open = document.createElement('a');
  open.className = 'open';
  open.target = '_blank';
  open.rel = 'noopener';
  open.textContent = 'Open in Filigree ↗';
  open.href = fullAppUrl(embed.fragment);
  bar.innerHTML = `<span class="logo">${LOGO}</span><span class="name"></span><span class="mode"></span>`;
  bar.querySelector('.mode').textContent = embed.readOnly ? 'view only' : 'interactive — not saved';
  bar.querySelector('.mode').title = embed.readOnly
    ? 'This embed shows a result; open it in Filigree to change it.'
    : 'Changes here are not saved; open in Filigree to keep working.';
  bar.append(open);
  document.body.prepend(bar);
  const panel = document.querySelector('#panel');
  // Read-only: everything in the tool is shown but cannot be focused or changed.
  if (embed.readOnly && panel) panel.inert = true;

  // Interactive: the link carries what the reader made. The href is kept
  // fresh as the pointer or focus reaches it (for middle-click and "open in
  // new tab"); a plain click waits for the current state, then opens it.
  if (!embed.readOnly) {
    const refresh = async () => {
      try {
        const share = await app.currentShare?.();
        if (share?.fragment) open.href = fullAppUrl(share.fragment);
      } catch { /* too big for a link or not ready: keep the embed's own state */ }
      return open.href;
    };
    for (const type of ['pointerenter', 'focus']) open.addEventListener(type, refresh);
    open.addEventListener('click', async (e) => {
      if (e.ctrlKey || e.metaKey || e.shiftKey || e.button !== 0) return;
      e.preventDefault();
      window.open(await refresh(), '_blank', 'noopener');
    });
  }

  const label = (tool) => document.querySelector(`#tools [data-tool="${CSS.escape(tool || '')}"]`)?.textContent || tool;
  let tool = params.get('tool');
  try {
    if (!hasShare(embed.fragment)) {
      await app.selectTool(tool);
    } else {
      const shared = await decodeShare(embed.fragment);
      tool = shared.tool;
      await app.openState(shared.tool, shared.state, { readOnly: embed.readOnly, source: 'embed', version: shared.version });
    }
  } catch (err) {
    await app.selectTool(tool);
    const note = document.createElement('div');
    note.className = 'error embed-note';
    note.setAttribute('role', 'alert');
    note.textContent = `${err.message} The tool opens with its defaults.`;
    panel?.before(note);
  }
  // The shell rewrites the fragment to #tool=…; keep the state so a reload shows it again.
  history.replaceState(null, '', `#${embed.fragment}`);
  bar.querySelector('.name').textContent = label(tool) || 'Filigree';
  root.dataset.embedReady = '1';
}
