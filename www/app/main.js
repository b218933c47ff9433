// App shell: header, tool switcher, worker pool, service worker, toasts.
// Each tool is a module declaring {id, title, state, mount(el, ctx)} (see
// document.js); the switcher lists only the tools registered in TOOLS.
import { WorkerPool } from './client.js';
import { DocumentController } from './document.js';
import { hasShare } from './share.js';
import inspectTool from '../inspect/panel.js';
import pixelTool from '../pixel/panel.js';
import fitTool from '../fit/panel.js';
import tangleTool from '../tangle/panel.js';
import microTool from '../micro/panel.js';
import textureTool from '../texture/panel.js';
import { embedOptions, enterEmbed, serviceWorkerAllowed } from './embed-mode.js';
import { mountHome } from './home.js';
import { addToolHead } from './help.js';

const TOOLS = [pixelTool, fitTool, inspectTool, tangleTool, microTool, textureTool];

const $ = (sel) => document.querySelector(sel);

/** Show a transient notice; `action` is an optional {label, run}. Returns the element. */
export function toast(message, { kind = 'info', action, timeout = 8000 } = {}) {
  const el = document.createElement('div');
  el.className = `toast toast-${kind}`;
  el.setAttribute('role', kind === 'error' ? 'alert' : 'status');
  const text = document.createElement('span');
  text.textContent = message;
  el.append(text);
  if (action) {
    const b = document.createElement('button');
    b.textContent = action.label;
    b.onclick = () => { el.remove(); action.run(); };
    el.append(b);
  }
  const close = document.createElement('button');
  close.className = 'ghost';
  close.setAttribute('aria-label', 'Dismiss');
  close.textContent = '×';
  close.onclick = () => el.remove();
  el.append(close);
  $('#toasts').append(el);
  if (timeout) setTimeout(() => el.remove(), timeout);
  return el;
}

const status = $('#core-status');
const pool = new WorkerPool({
  onReady(version) {
    status.textContent = `core ${version}`;
    status.classList.add('ok');
    document.documentElement.dataset.coreReady = '1';
  },
  onCrash(message) {
    toast(`The computation crashed and its worker was restarted (${message}). Your work is untouched.`, { kind: 'error' });
  },
});
pool.warm();

const embed = embedOptions(); // ?embed=1: one tool, no chrome, never saves (embed-mode.js)

// One document controller for every tool: history, autosave, project files,
// share links, shortcuts and the panels' lifecycle (see document.js).
const doc = new DocumentController({
  pool, toast, tools: TOOLS, host: $('#panel'), persist: !embed, onJob: showJob,
  onShow(id) {
    leaveHome();
    // The view's one h1 (the tool's title) and its Help (help.js).
    if (doc.current?.tool.id === id) addToolHead(doc.current.el, doc.current.tool);
    document.documentElement.dataset.view = id;
    for (const b of document.querySelectorAll('#tools button')) b.setAttribute('aria-current', String(b.dataset.tool === id));
    const params = new URLSearchParams(location.hash.slice(1));
    if (params.get('tool') !== id || params.has('share')) history.replaceState(null, '', `#tool=${id}`);
  },
});

const app = {
  pool,
  toast,
  doc,
  /** Switch to `toolId` and load `state` (a shared state) through its validate(); rejects with a plain Error. */
  openState: (toolId, state, opts) => doc.openState(toolId, state, opts),
  /** {tool, fragment} of the current document (a ShareTooBig error when it does not fit a link). */
  currentShare: () => doc.currentShare(),
  selectTool: (id) => doc.show(id),
};
// Tests, embedding and the console reach the app through this handle. A page
// opened by a test (globalThis.__filigreeTestHooks === true) also has the
// panels' test hooks (ctx.expose, document.js) in app.testHooks[<tool id or name>].
if (doc.testHooks) app.testHooks = doc.testHooks;
window.filigree = app;

const toolParam = () => new URLSearchParams(location.hash.slice(1)).get('tool');

// No tool (or an unknown one) in the hash: the home view, one card per tool
// with a live example (home.js); a card links to #tool=<id>.
let home = null;
function leaveHome() {
  home?.unmount();
  home = null;
}
function showHome() {
  if (home) return;
  doc.leave();
  const el = document.createElement('section');
  el.className = 'tool tool-home';
  el.setAttribute('aria-label', 'Home');
  $('#panel').replaceChildren(el);
  home = mountHome(el, app, TOOLS);
  document.documentElement.dataset.view = 'home';
  for (const b of document.querySelectorAll('#tools button')) b.setAttribute('aria-current', 'false');
  if (location.hash) history.replaceState(null, '', location.pathname + location.search);
}

for (const tool of TOOLS) {
  const b = document.createElement('button');
  b.type = 'button';
  b.dataset.tool = tool.id;
  b.textContent = tool.title;
  b.onclick = () => doc.show(tool.id);
  $('#tools').append(b);
}

// A document's long job (a fit, a reconstruction, a tangle's growth) in the
// tool bar: its progress while it runs, wherever the user is; how it ended
// until its tool is shown again (jobs.js, DocJob).
const JOB_ENDS = { done: 'done', stopped: 'stopped', cancelled: 'cancelled', failed: 'failed' };
function showJob(job) {
  const b = document.querySelector(`#tools button[data-tool="${job.tool.id}"]`);
  if (!b) return;
  let badge = b.querySelector('.tool-job');
  const shown = job.running || !job.seen;
  if (!shown) { badge?.remove(); delete b.dataset.job; return; }
  if (!badge) {
    badge = document.createElement('span');
    badge.className = 'tool-job';
    badge.dataset.testid = `tool-job-${job.tool.id}`;
    b.append(badge);
  }
  b.dataset.job = job.status;
  const pct = Math.round(100 * (job.progress.fraction || 0));
  badge.textContent = job.running ? `${pct}%` : JOB_ENDS[job.status];
  badge.title = job.running ? `${job.label}: ${job.progress.stage} ${pct}%` : `${job.label}: ${JOB_ENDS[job.status]}`;
}

// A share link (#tool=…&share=…) opens as a new, undoable document state;
// a bad one says so and leaves the user's work alone.
async function route() {
  if (!hasShare(location.hash)) {
    if (!TOOLS.some((t) => t.id === toolParam())) return showHome();
    return doc.show(toolParam());
  }
  await doc.openFragment(location.hash, toolParam());
  // The link is consumed: a reload shows the (autosaved) document, not the link again.
  if (doc.current) history.replaceState(null, '', `#tool=${doc.current.tool.id}`);
}
if (embed) enterEmbed(app, embed);
else { route(); addEventListener('hashchange', route); }

// Service worker: offline after the first visit; updates are offered, never forced.
if (serviceWorkerAllowed(embed)) {
  const offerUpdate = (reg) => {
    if (!reg.waiting || !navigator.serviceWorker.controller) return;
    toast('A new version of Filigree is ready.', {
      timeout: 0,
      action: {
        label: 'Reload to update',
        run: () => {
          sessionStorage.setItem('filigree-updating', '1');
          reg.waiting?.postMessage({ type: 'SKIP_WAITING' });
        },
      },
    });
  };
  navigator.serviceWorker.register(new URL('../../sw.js', import.meta.url)).then((reg) => {
    offerUpdate(reg);
    reg.addEventListener('updatefound', () => {
      reg.installing?.addEventListener('statechange', () => offerUpdate(reg));
    });
  }).catch((err) => console.warn('service worker not registered:', err));
  let reloading = false;
  navigator.serviceWorker.addEventListener('controllerchange', () => {
    // Only reload when the user accepted an update (an old controller existed).
    if (reloading || !sessionStorage.getItem('filigree-updating')) return;
    reloading = true;
    sessionStorage.removeItem('filigree-updating');
    location.reload();
  });
}
