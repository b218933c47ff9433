// "Inspect image": size, palette and thumbnail of a dropped, pasted or picked
// image, computed by the core in a worker (the same `inspect` the CLI runs).
// The document is the image itself, so it is autosaved, undoable and
// shareable (when small) like every tool's (app/document.js).
import { acceptFiles, putRgba, hex } from '../ui/file-input.js';

const html = `
  <div class="inspect-layout">
    <div class="card drop-zone" data-testid="drop-zone">
      <h2>Inspect an image</h2>
      <p class="muted">Drop an image here, paste one, or choose a file. Filigree reads its size and palette — the colours Fit and Pixel work with.</p>
    </div>
    <div class="card result" data-testid="inspect-result" hidden>
      <div class="busy muted" hidden>Reading…</div>
      <div class="summary" hidden>
        <div class="thumb checker"><canvas aria-label="thumbnail"></canvas></div>
        <dl>
          <dt>File</dt><dd data-field="name"></dd>
          <dt>Size</dt><dd data-field="size"></dd>
          <dt>Colours</dt><dd data-field="colours"></dd>
          <dt>Translucent pixels</dt><dd data-field="translucent"></dd>
        </dl>
      </div>
      <div class="palette-block" hidden>
        <h3>Palette <span class="muted">(similar colours merged, most used first)</span></h3>
        <ul class="swatches" data-testid="palette"></ul>
      </div>
    </div>
  </div>`;

const inspectState = {
  version: 1,
  defaults: () => ({ name: null, bytes: null }),
  // The state's schema lives in the core (src/api/project.rs, `check-state`).
  migrate: (raw) => raw,
  fileName: (s) => s.name || 'inspect',
};

function mount(el, ctx) {
  el.innerHTML = html;
  const q = (s) => el.querySelector(s);
  const result = q('.result');
  let controller = null;
  let shown = null; // the bytes on screen
  let unsaved = null; // a file inspected before the document had loaded: committed once it has

  const show = (sel, on) => { q(sel).hidden = !on; };

  async function inspect(name, bytes, { commit }) {
    controller?.abort();
    const ctrl = new AbortController();
    controller = ctrl;
    result.hidden = false;
    ctx.clearError();
    show('.busy', true);
    try {
      const r = await ctx.run('inspect', { bytes: bytes.slice() }, { signal: ctrl.signal });
      render(name, r);
      shown = bytes;
      // Before the document has loaded (the first seconds), a commit is refused:
      // keep the file and commit it at the first render instead of losing it.
      if (commit && !ctx.commit({ name, bytes })) unsaved = { name, bytes };
    } catch (err) {
      if (err.kind === 'cancelled') return;
      // Keep the last good result on screen; say what is wrong with this file.
      ctx.error(err, { prefix: name });
    } finally {
      if (controller === ctrl) show('.busy', false);
    }
  }

  function render(name, r) {
    q('[data-field=name]').textContent = name;
    q('[data-field=size]').textContent = `${r.width} × ${r.height} px`;
    q('[data-field=colours]').textContent = String(r.colour_count);
    q('[data-field=translucent]').textContent = String(r.translucent_pixels);
    const canvas = q('canvas');
    putRgba(canvas, r.thumbnail.width, r.thumbnail.height, r.thumbnail.rgba);
    canvas.classList.toggle('pixelated', r.width <= 256 && r.height <= 256);
    const ul = q('.swatches');
    ul.replaceChildren(...r.clusters.slice(0, 64).map((c) => {
      const li = document.createElement('li');
      const code = hex(c.rgba);
      const sw = document.createElement('span');
      sw.className = 'sw';
      sw.style.background = code;
      const tag = document.createElement('code');
      tag.textContent = code;
      const count = document.createElement('span');
      count.className = 'muted';
      count.textContent = `${c.count} px`;
      li.append(sw, tag, count);
      li.title = `${code}: ${c.count} pixels, ${c.members} exact colour(s)`;
      return li;
    }));
    show('.summary', true);
    show('.palette-block', true);
  }

  const detach = acceptFiles(q('.drop-zone'), async (file) => {
    inspect(file.name, new Uint8Array(await file.arrayBuffer()), { commit: true });
  });

  return {
    render(s) {
      if (unsaved) {
        const u = unsaved;
        unsaved = null;
        if (u.bytes === shown && ctx.commit(u)) return;
      }
      if (!s?.bytes) {
        shown = null;
        result.hidden = true;
        return;
      }
      if (s.bytes !== shown) inspect(s.name, s.bytes, { commit: false });
    },
    unmount() {
      detach();
      controller?.abort();
    },
  };
}

export default { id: 'inspect', title: 'Inspect image', state: inspectState, mount };
