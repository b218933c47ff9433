// App shell: header, tool switcher, worker pool, service worker, toasts.
// Each tool is a module exporting {id, title, mount(el, app), unmount?()};
// the switcher lists only the tools registered in TOOLS.
import { WorkerPool } from './client.js';
import inspectTool from './inspect-panel.js';
import pixelTool from './pixel-panel.js';
import fitTool from './fit-panel.js';
import { mountHome } from './home.js';

const TOOLS = [pixelTool, fitTool, inspectTool];

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

const app = { pool, toast };
// Tests and the console reach the pool through this handle.
window.filigree = app;
let current = null;

// No tool (or an unknown one) in the hash: the home view with one card per tool.
const HOME = { id: 'home', title: 'Home', mount(el) { this.view = mountHome(el, app, TOOLS); }, unmount() { this.view?.unmount(); } };

function selectTool(id) {
  const tool = TOOLS.find((t) => t.id === id) || HOME;
  if (current?.tool === tool) return;
  current?.tool.unmount?.();
  const panel = $('#panel');
  panel.replaceChildren();
  const el = document.createElement('section');
  el.className = `tool tool-${tool.id}`;
  el.setAttribute('aria-label', tool.title);
  panel.append(el);
  tool.mount(el, app);
  current = { tool, el };
  document.documentElement.dataset.view = tool.id;
  for (const b of document.querySelectorAll('#tools button')) b.setAttribute('aria-current', String(b.dataset.tool === tool.id));
  const params = new URLSearchParams(location.hash.slice(1));
  if (tool === HOME ? params.has('tool') : params.get('tool') !== tool.id) {
    if (tool === HOME) params.delete('tool'); else params.set('tool', tool.id);
    history.replaceState(null, '', params.size ? `#${params}` : location.pathname + location.search);
  }
}

for (const tool of TOOLS) {
  const b = document.createElement('button');
  b.type = 'button';
  b.dataset.tool = tool.id;
  b.textContent = tool.title;
  b.onclick = () => selectTool(tool.id);
  $('#tools').append(b);
}
selectTool(new URLSearchParams(location.hash.slice(1)).get('tool'));
addEventListener('hashchange', () => selectTool(new URLSearchParams(location.hash.slice(1)).get('tool')));

// Service worker: offline after the first visit; updates are offered, never forced.
if ('serviceWorker' in navigator) {
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
  navigator.serviceWorker.register(new URL('../sw.js', import.meta.url)).then((reg) => {
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
