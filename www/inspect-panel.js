// "Inspect image": size, palette and thumbnail of a dropped, pasted or picked
// image, computed by the core in a worker (the same `inspect` the CLI runs).
import { acceptFiles, putRgba, hex } from './file-input.js';

const html = `
  <div class="card drop-zone" data-testid="drop-zone">
    <h2>Inspect an image</h2>
    <p class="muted">Drop an image here, paste one, or choose a file. Filigree reads its size and palette — the colours Fit and Pixel work with.</p>
  </div>
  <div class="card result" data-testid="inspect-result" hidden>
    <div class="error" role="alert" hidden></div>
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
  </div>`;

export default {
  id: 'inspect',
  title: 'Inspect image',
  mount(el, { pool }) {
    el.innerHTML = html;
    const q = (s) => el.querySelector(s);
    const result = q('.result');
    let controller = null;

    const show = (sel, on) => { q(sel).hidden = !on; };

    async function onFile(file) {
      controller?.abort();
      controller = new AbortController();
      result.hidden = false;
      show('.error', false);
      show('.busy', true);
      try {
        const bytes = new Uint8Array(await file.arrayBuffer());
        const r = await pool.run('inspect', { bytes }, { signal: controller.signal });
        render(file.name, r);
      } catch (err) {
        if (err.kind === 'cancelled') return;
        // Keep the last good result on screen; say what is wrong with this file.
        q('.error').textContent = `${file.name}: ${err.message}`;
        show('.error', true);
      } finally {
        show('.busy', false);
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
        li.innerHTML = `<span class="sw" style="background:${code}"></span><code>${code}</code><span class="muted">${c.count} px</span>`;
        li.title = `${code}: ${c.count} pixels, ${c.members} exact colour(s)`;
        return li;
      }));
      show('.summary', true);
      show('.palette-block', true);
    }

    this.detach = acceptFiles(q('.drop-zone'), onFile);
  },
  unmount() {
    this.detach?.();
  },
};
