// The first screen: what Filigree is in two lines, and one card per tool with
// a live example computed by the core in the worker pool (the same jobs the
// panels run). A card is a link to `#tool=<id>`: one click opens the tool.
//   const home = mountHome(el, app, tools);  …  home.unmount();
// Previews are cancelled on unmount; a failed preview leaves its card usable.

import { drawThumbnail } from './tangle-draw.js';

const ASSETS = new URL('../assets/', import.meta.url);

const CARDS = {
  pixel: {
    blurb: 'Texture pixel art: paint a mask, draw strokes, and oriented scales, bricks or leaves fill the region.',
    alt: 'The fish example textured with scales by the core',
    preview: previewPixel,
  },
  fit: {
    blurb: 'Fit a pattern program to a drawing: the optimiser finds the parameters that match your target.',
    alt: 'The honeycomb pattern program rendered by the core',
    preview: previewFit,
  },
  inspect: {
    blurb: 'Inspect an image: its size and palette, the colours Fit and Pixel work with.',
    alt: 'The fish sprite and its palette as read by the core',
    preview: previewInspect,
  },
  tangle: {
    blurb: 'Grow pen-and-ink tangles from a grammar, step by step; select any step and redo or retune it.',
    alt: "The paper's leaf grammar grown by the core",
    preview: previewTangle,
  },
  micro: {
    blurb: 'Render multiscale microstructures from implicit functions; orbit and zoom from the sample down to its grains.',
    alt: 'The gyroid scene sphere-traced by the core',
    preview: previewMicro,
  },
  texture: {
    blurb: 'Find a procedural texture from an example and steer it with twelve perceptual sliders (estimated, not human-rated).',
    alt: 'A regular texton texture rendered by the core, tiled 2×2',
    preview: previewTexture,
  },
};

async function bytesOf(rel, signal) {
  const res = await fetch(new URL(rel, ASSETS), { signal });
  if (!res.ok) throw new Error(`${rel}: ${res.status}`);
  return new Uint8Array(await res.arrayBuffer());
}

function draw(canvas, { width, height, rgba }) {
  canvas.width = width;
  canvas.height = height;
  canvas.getContext('2d').putImageData(new ImageData(new Uint8ClampedArray(rgba.buffer, rgba.byteOffset, rgba.byteLength), width, height), 0, 0);
}

// The fish example of the Pixel panel (assets/pixel/cases.json), textured.
async function previewPixel(pool, box, signal) {
  const cases = await (await fetch(new URL('pixel/cases.json', ASSETS), { signal })).json();
  const c = cases.fish;
  const [source, maskPng, sheet, strokes] = await Promise.all(
    [c.source, c.mask, c.sheet, c.strokes].map((f) => bytesOf(`pixel/${f}`, signal)),
  );
  const mask = await pool.run('pixel-mask', { bytes: maskPng }, { signal });
  const r = await pool.run('pixel', {
    source, sheet, mask, strokes: JSON.parse(new TextDecoder().decode(strokes)).strokes, params: c.params,
  }, { signal });
  const canvas = document.createElement('canvas');
  canvas.className = 'pixelated';
  draw(canvas, r);
  box.replaceChildren(canvas);
}

// A generator from the Fit panel's list, at its default values.
async function previewFit(pool, box, signal) {
  const program = new TextDecoder().decode(await bytesOf('patterns/honeycomb.flg', signal));
  const r = await pool.run('render-pattern', { program, size: 240, supersample: 2 }, { signal });
  const canvas = document.createElement('canvas');
  draw(canvas, r);
  box.replaceChildren(canvas);
}

// The inspect job on a sample image: thumbnail and the first swatches.
async function previewInspect(pool, box, signal) {
  const r = await pool.run('inspect', { bytes: await bytesOf('pixel/fish.png', signal) }, { signal });
  const canvas = document.createElement('canvas');
  canvas.className = 'pixelated';
  draw(canvas, r.thumbnail);
  const ul = document.createElement('ul');
  ul.className = 'home-swatches';
  ul.setAttribute('aria-label', `${r.colour_count} colours`);
  for (const cl of r.clusters.slice(0, 8)) {
    const li = document.createElement('li');
    const [R, G, B] = cl.rgba;
    li.style.background = `rgb(${R} ${G} ${B})`;
    ul.append(li);
  }
  const facts = document.createElement('span');
  facts.className = 'home-facts';
  facts.textContent = `${r.width}×${r.height} px · ${r.colour_count} colours`;
  box.replaceChildren(canvas, ul, facts);
}

// The Tangle panel's first grammar (the paper's leaf), grown a little.
async function previewTangle(pool, box, signal) {
  const [leaf] = await pool.run('tangle-examples', {}, { signal });
  const r = await pool.run('tangle', { grammar: leaf.grammar, max_steps: 400, max_shapes: 4000 }, { signal });
  const canvas = document.createElement('canvas');
  canvas.width = 320;
  canvas.height = 240;
  drawThumbnail(canvas, r);
  box.replaceChildren(canvas);
}

// The Micro panel's gyroid, sphere-traced small.
async function previewMicro(pool, box, signal) {
  const exs = await pool.run('micro-examples', {}, { signal });
  const ex = exs.find((e) => e.name === 'gyroid') || exs[0];
  const r = await pool.run('micro-render', { scene: ex.scene, width: 160, height: 120 }, { signal });
  const bmp = await createImageBitmap(new Blob([r.png], { type: 'image/png' }));
  const canvas = document.createElement('canvas');
  canvas.width = r.width;
  canvas.height = r.height;
  canvas.getContext('2d').drawImage(bmp, 0, 0);
  bmp.close();
  box.replaceChildren(canvas);
}

// A Texture model rendered small and tiled 2×2 (the models tile); the
// index the Texture panel uses is not fetched here.
async function previewTexture(pool, box, signal) {
  const side = 128;
  const r = await pool.run('texture-render', { model: 'texton-regular', seed: 1, size: side }, { signal });
  const canvas = document.createElement('canvas');
  canvas.width = side * 2;
  canvas.height = side * 2;
  const rgba = new Uint8ClampedArray(side * side * 4);
  r.gray.forEach((v, i) => { rgba[4 * i] = v; rgba[4 * i + 1] = v; rgba[4 * i + 2] = v; rgba[4 * i + 3] = 255; });
  const img = new ImageData(rgba, side, side);
  const g = canvas.getContext('2d');
  for (const [x, y] of [[0, 0], [side, 0], [0, side], [side, side]]) g.putImageData(img, x, y);
  box.replaceChildren(canvas);
}

export function mountHome(el, { pool }, tools) {
  const ctrl = new AbortController();
  el.innerHTML = `
    <div class="home-intro">
      <h1>Filigree</h1>
      <p>A studio for procedural patterns and pixel art that runs in your browser, also offline.</p>
      <p class="muted">Fit pattern programs to a drawing, texture pixel art with oriented elements, grow pen-and-ink tangles from a grammar, model microstructures as implicit surfaces, find a procedural texture like an example, read an image's palette — pick a tool to start.</p>
    </div>
    <ul class="home-cards" data-testid="home-cards"></ul>`;
  const list = el.querySelector('.home-cards');
  for (const tool of tools) {
    const card = CARDS[tool.id] || { blurb: '', alt: tool.title };
    const li = document.createElement('li');
    const a = document.createElement('a');
    a.className = 'home-card card';
    a.href = `#tool=${tool.id}`;
    a.dataset.tool = tool.id;
    const box = document.createElement('div');
    box.className = 'home-preview checker';
    box.setAttribute('role', 'img');
    box.setAttribute('aria-label', card.alt);
    box.innerHTML = '<span class="muted">computing the example…</span>';
    const h = document.createElement('h2');
    h.textContent = tool.title;
    const p = document.createElement('p');
    p.className = 'muted';
    p.textContent = card.blurb;
    const go = document.createElement('span');
    go.className = 'home-open';
    go.textContent = `Open ${tool.title} →`;
    a.append(box, h, p, go);
    li.append(a);
    list.append(li);
    card.preview?.(pool, box, ctrl.signal).then(() => { box.dataset.ready = '1'; }).catch((err) => {
      if (ctrl.signal.aborted || err?.kind === 'cancelled' || err?.name === 'AbortError') return;
      box.innerHTML = '';
      const s = document.createElement('span');
      s.className = 'muted';
      s.textContent = `no preview (${err?.message || err})`;
      box.append(s);
    });
  }
  return { unmount: () => ctrl.abort() };
}
