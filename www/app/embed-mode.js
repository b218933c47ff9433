// Embed mode (MISSION S7, issue 35 item 1): `index.html?embed=1#<share
// fragment>` shows ONE tool without the app chrome, for tutorial pages (see
// www/embed.js, the <filigree-embed> element that frames it). It opens on
// the result: the tool's picture first, at the frame's size, its controls
// in a drawer ("Controls" in the bar: beside the picture in a wide frame,
// below it in a narrow one).
//
//   ?embed=1                     read-only: the reader explores (sliders, orbit,
//                                steps, undo, Reset) and nothing is kept; the
//                                author's inputs (drawing on them, their files) are
//                                locked; "Open in Filigree" opens the author's state
//   ?embed=1&mode=interactive    everything live; "Open in Filigree" carries the
//                                reader's state
//   &controls=open               the drawer starts open
//   &size=content                the page's height follows its content and is
//                                posted to the parent ({type: 'filigree-embed:height',
//                                height}); <filigree-embed> asks for this unless the
//                                author gave a height. Otherwise the picture fills
//                                the frame's height.
//
// The mouse wheel scrolls the host page until the reader clicks (or tabs)
// into the embed: before that the embed does not scroll and no tool sees
// the wheel (Tangle's and Micro's wheel zoom), and a touch drag on a
// picture pans the page.
//
// Either way an embedded instance never touches the user's storage: main.js
// makes the document controller with `persist: false` (no autosave is read
// or written, no `navigator.storage.persist()`), and the service worker is
// not registered (from a third-party frame it would control the user's
// full-app scope).
//
// main.js calls embedOptions() once, enterEmbed() instead of its routing,
// and serviceWorkerAllowed() before registering the worker.

import { decodeShare, hasShare } from './share.js';

/** The embed settings in `loc`'s query, or null when the page is the full app. */
export function embedOptions(loc = location) {
  const query = new URLSearchParams(loc.search);
  if (query.get('embed') !== '1') return null;
  const mode = query.get('mode') === 'interactive' ? 'interactive' : 'readonly';
  return {
    mode,
    readOnly: mode === 'readonly',
    size: query.get('size') === 'content' ? 'content' : 'frame',
    controls: query.get('controls') === 'open',
    fragment: loc.hash.replace(/^#/, ''),
  };
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

// Each tool's stage: its result card (moved out of the panel's layout, above
// it), the picture in it that takes the stage's free height (`square`: kept
// square, or at the aspect its panel sets), the picture's height per width
// when the page follows its content (`ratio`), and the parts of the card
// that go to the drawer. A tool without a stage (Inspect) shows whole.
// www/embed.js estimates an embed's height from the same ratios.
const STAGES = {
  pixel: { result: '.pixel-stage', picture: '.viewport', ratio: 0.5 },
  fit: { result: '.fit-target', picture: '.stack', square: true, ratio: 0.6 },
  tangle: { result: '.tangle-stage', picture: '.tangle-viewport', ratio: 0.55 },
  micro: { result: '.micro-stage', picture: '.micro-viewport', square: true, ratio: 0.6, drawer: ['.micro-shading'] },
  texture: { result: '.texture-result', picture: '.texture-view', square: true, ratio: 0.5 },
};
/** A frame at least this wide shows the open drawer beside the picture. */
const SIDE_DRAWER_PX = 720;

// Embed-only styles live here, not in styles.css: they apply only under
// html[data-embed] and ship with the code that sets it.
const EMBED_CSS = `
html[data-embed] .app-header, html[data-embed] #tools { display: none !important; }
html[data-embed] body { overflow-x: hidden; }
html[data-embed] main { max-width: none; padding: .5rem .6rem; }
html[data-embed] #panel .doc-bar, html[data-embed] [data-role=storage-note] { display: none !important; }
.embed-bar { display: flex; align-items: center; gap: .5rem; padding: .35rem .7rem; min-height: 2.6rem; flex-wrap: wrap;
  background: var(--panel, #1f1c29); border-bottom: 1px solid var(--line, #363047); position: sticky; top: 0; z-index: 5; }
.embed-bar .logo { color: var(--accent, #c9a2ff); display: inline-flex; }
.embed-bar .name { font-weight: 600; font-size: 1rem; margin: 0; }
.embed-bar .mode { font-size: .78rem; color: var(--muted, #a49cb8); border: 1px solid var(--line, #363047);
  border-radius: 99px; padding: .05rem .55rem; }
.embed-bar button { padding: .2rem .65rem; }
.embed-bar .open { margin-left: auto; color: var(--accent, #c9a2ff); font-weight: 600; text-decoration: none;
  border: 1px solid var(--accent, #c9a2ff); border-radius: 7px; padding: .25rem .7rem; white-space: nowrap; }
.embed-bar .open:hover, .embed-bar .open:focus-visible { background: var(--accent, #c9a2ff); color: #1b1526; }
@media (max-width: 460px) {
  .embed-bar { gap: .35rem; padding: .3rem .5rem; }
  .embed-bar .logo, .embed-bar .mode { display: none; }
  .embed-bar button, .embed-bar .open { font-size: .88rem; padding: .2rem .5rem; }
}
.embed-note { margin: .6rem; }

/* The stage: the result card, its picture taking the height left. */
/* A frame of the author's size: the stage fills it. Sized by its content:
   the picture's height follows the width, the page's the picture. */
html[data-embed-size=frame] .embed-stage { height: calc(100vh - var(--embed-bar-h, 2.8rem) - 1rem); min-height: 12rem; }
html[data-embed-size=content] { overflow: hidden; }
html[data-embed-size=content] .embed-picture { flex: none !important; height: clamp(12.5rem, calc(100vw * var(--embed-ratio, .55)), 30rem) !important; }
.embed-stage ~ .embed-drawer { margin-top: .6rem; }
.embed-stage > .card { height: 100%; margin: 0; display: flex; flex-direction: column; gap: .45rem; min-height: 0; padding: .6rem .7rem; }
.embed-stage > .card > * { flex: none; margin: 0; min-width: 0; }
.embed-stage > .card > .toolbar { gap: .3rem .6rem; }
.embed-stage .embed-picture { flex: 1 1 0 !important; min-height: 5rem !important; height: auto !important; max-height: none !important; }
.embed-stage .embed-picture.square { width: auto !important; max-width: 100%; align-self: center; aspect-ratio: 1; }
.embed-stage .embed-picture.square canvas { object-fit: contain; }
.embed-stage .embed-picture.fill { width: 100%; }
.embed-stage .pixel-stage .viewport { overflow: auto; }
.embed-stage .texture-chart { height: 4.5rem; }
.embed-stage .stats { margin: 0; }

/* The drawer: the rest of the panel, one column. */
html[data-embed] .embed-drawer { display: none; grid-template-columns: minmax(0, 1fr) !important; }
html[data-embed-drawer=open] .embed-drawer { display: grid; }
html[data-embed] .embed-drawer > * { grid-row: auto !important; grid-column: auto !important; }
html[data-embed] .embed-drawer > .toolbar { background: var(--panel, #1f1c29); border: 1px solid var(--line, #363047);
  border-radius: var(--radius, 10px); padding: .6rem .7rem; margin: 0; }
@media (min-width: ${SIDE_DRAWER_PX}px) {
  html[data-embed-drawer=open] #panel .doc-body:has(> .embed-stage) { display: grid; grid-template-columns: minmax(0, 1fr) minmax(17rem, 40%); gap: 0 .6rem; align-items: start; }
  html[data-embed-drawer=open] .embed-stage ~ .embed-drawer { margin-top: 0; max-height: var(--embed-drawer-h, 30rem); overflow: auto; overscroll-behavior: contain; }
}

/* Read-only: the author's inputs are locked (drawing on them, their files). */
html[data-embed=readonly] #panel :is(.pick, [data-pick], label:has(> input[type=file]), [data-act=open-project],
  .fit-target > .toolbar, .pixel-stage [data-example], .pixel-stage [data-mode], .pixel-stage label:has(> [name=brush]),
  .pixel-stage [data-act=clear-strokes]) { display: none !important; }
html[data-embed=readonly] #panel :is(canvas, .stack) { cursor: default !important; }
html[data-embed] .tool[data-readonly] :is(input, select) { pointer-events: auto; }

/* Until the reader clicks into the embed, the page it sits in scrolls. */
html[data-embed-size=frame][data-embed-engaged="0"] { overflow: hidden; }
html[data-embed-engaged="0"] #panel :is(canvas, .stack, .canvas-view, .tangle-viewport, .micro-viewport) { touch-action: pan-y !important; }
`;

const TOOL_NAMES = { pixel: 'Pixel', fit: 'Fit', inspect: 'Inspect image', tangle: 'Tangle', micro: 'Micro', texture: 'Texture' };

/**
 * Move the mounted tool's result card into a stage at the top of its panel,
 * and make the rest of the panel (its layout) the drawer. Both stay inside
 * the panel's element, where the panel finds its parts. Runs whenever the
 * panel mounts.
 */
function arrange(panel) {
  const el = panel.querySelector(':scope > section.tool');
  if (!el || el.dataset.embedArranged) return null;
  el.dataset.embedArranged = '1';
  const tool = [...el.classList].find((c) => c.startsWith('tool-'))?.slice(5);
  const body = el.querySelector(':scope > .doc-body');
  const spec = STAGES[tool];
  const result = spec && body?.querySelector(spec.result);
  const drawer = result?.parentElement;
  if (!result || drawer === body) return { tool, stage: null };
  drawer.id = 'embed-drawer';
  drawer.classList.add('embed-drawer');
  const stage = document.createElement('div');
  stage.className = 'embed-stage';
  stage.dataset.testid = 'embed-stage';
  stage.style.setProperty('--embed-ratio', String(spec.ratio));
  body.prepend(stage);
  stage.append(result);
  result.querySelector(spec.picture)?.classList.add('embed-picture', spec.square ? 'square' : 'fill');
  for (const sel of spec.drawer ?? []) {
    const part = result.querySelector(sel);
    if (part) drawer.prepend(part);
  }
  return { tool, stage };
}

/**
 * Turn the page into an embed: chrome, then the link's state through
 * `app.openState` (read-only or not). The document controller was made with
 * `persist: false`, so nothing here is ever autosaved.
 */
export async function enterEmbed(app, embed) {
  app.embed = embed;
  const root = document.documentElement;
  root.dataset.embed = embed.mode;
  root.dataset.embedSize = embed.size;
  root.dataset.embedDrawer = embed.controls ? 'open' : 'closed';
  root.dataset.embedEngaged = '0';
  const style = document.createElement('style');
  style.textContent = EMBED_CSS;
  document.head.append(style);

  const params = new URLSearchParams(embed.fragment);
  const bar = document.createElement('div');
  bar.className = 'embed-bar';
  bar.setAttribute('role', 'banner');
  bar.innerHTML = `<span class="logo">${LOGO}</span><span class="name"></span><span class="mode"></span>
    <button type="button" data-act="embed-controls" aria-controls="embed-drawer" aria-expanded="false" hidden>Controls ▾</button>
    <button type="button" data-act="embed-reset" title="Back to the author's version" hidden>Reset</button>`;
  const open = document.createElement('a');
  open.className = 'open';
  open.target = '_blank';
  open.rel = 'noopener';
  open.textContent = 'Open in Filigree ↗';
  open.href = fullAppUrl(embed.fragment);
  bar.append(open);
  bar.querySelector('.mode').textContent = embed.readOnly ? 'read-only' : 'interactive · not saved';
  bar.querySelector('.mode').title = embed.readOnly
    ? 'Try it: nothing you change here is kept or changes the author\u2019s version; Reset brings it back.'
    : 'Changes here are not saved; Open in Filigree to keep working on them.';
  document.body.prepend(bar);
  const panel = document.querySelector('#panel');
  new ResizeObserver(() => root.style.setProperty('--embed-bar-h', `${bar.offsetHeight}px`)).observe(bar);

  // The drawer.
  const controls = bar.querySelector('[data-act=embed-controls]');
  const setDrawer = (open) => {
    root.dataset.embedDrawer = open ? 'open' : 'closed';
    controls.setAttribute('aria-expanded', String(open));
    controls.textContent = open ? 'Controls ▴' : 'Controls ▾';
  };
  controls.onclick = () => {
    const opening = root.dataset.embedDrawer !== 'open';
    setDrawer(opening);
    // Below the picture (a narrow frame): bring the controls into view.
    if (opening && innerWidth < SIDE_DRAWER_PX) document.getElementById('embed-drawer')?.scrollIntoView({ block: 'start' });
  };
  setDrawer(embed.controls);
  const place = () => {
    const arranged = arrange(panel);
    if (!arranged) return;
    controls.hidden = !arranged.stage;
    if (!arranged.stage) setDrawer(true);
    // Beside the picture, the drawer is as tall as the stage (and scrolls).
    else new ResizeObserver(() => root.style.setProperty('--embed-drawer-h', `${arranged.stage.offsetHeight}px`)).observe(arranged.stage);
  };
  if (panel) {
    new MutationObserver(place).observe(panel, { childList: true });
    place();
  }

  // The wheel and touch belong to the host page until the reader clicks,
  // taps or tabs into the embed; leaving it (the window loses focus) gives
  // them back.
  const engage = (on) => { root.dataset.embedEngaged = on ? '1' : '0'; };
  addEventListener('pointerdown', () => engage(true), true);
  addEventListener('focusin', () => { if (document.hasFocus()) engage(true); });
  addEventListener('blur', () => engage(false));
  addEventListener('wheel', (e) => { if (root.dataset.embedEngaged !== '1') e.stopPropagation(); }, { capture: true, passive: true });

  // Content-sized: the parent (<filigree-embed>) hears the height to give the frame.
  if (embed.size === 'content' && window.parent !== window) {
    let last = 0;
    const post = () => {
      const height = Math.ceil(document.body.getBoundingClientRect().height);
      if (height === last) return;
      last = height;
      window.parent.postMessage({ type: 'filigree-embed:height', height }, '*');
    };
    new ResizeObserver(post).observe(document.body);
  }

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

  const label = (tool) => TOOL_NAMES[tool] || tool;
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
  bar.querySelector('.name').textContent = label(app.doc?.current?.tool.id ?? tool) || 'Filigree';

  // Reset: back to the document the embed opened with (one undoable step).
  const origin = app.doc?.present();
  const reset = bar.querySelector('[data-act=embed-reset]');
  if (origin && app.doc) {
    app.doc.onChange((present) => { reset.hidden = present === origin; });
    reset.onclick = () => app.doc.resetTo(origin);
  }
  root.dataset.embedReady = '1';
}
