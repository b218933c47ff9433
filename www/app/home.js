// The first screen: what Filigree is in two lines, and one card per tool with
// a picture of its example. The pictures (assets/home/<tool>.png) are made
// ahead of time by the same core, natively (scripts/home-cards.sh), so the
// home view loads no wasm: a tool's module is fetched when the tool opens.
// A card is a link to `#tool=<id>`: one click opens the tool.
//   const home = mountHome(el, app, tools);  …  home.unmount();
// A picture that fails to load leaves its card usable (a short note instead).

const PICTURES = new URL('../../assets/home/', import.meta.url);

// width × height: each picture's own size (scripts/home-cards.sh).
const CARDS = {
  pixel: {
    blurb: 'Texture pixel art: paint a mask, draw strokes, and oriented scales, bricks or leaves fill the region.',
    alt: 'The fish example textured with scales by the core',
    size: [128, 128],
    pixelated: true,
  },
  fit: {
    blurb: 'Fit a pattern program to a drawing: the optimiser finds the parameters that match your target.',
    alt: 'The honeycomb pattern program rendered by the core',
    size: [240, 240],
  },
  inspect: {
    blurb: 'Inspect an image: its size and palette, the colours Fit and Pixel work with.',
    alt: 'The fish sprite and its palette as read by the core',
    size: [128, 128],
    pixelated: true,
    // What `filigree inspect --json assets/pixel/fish.png` reads (its first
    // clusters); scripts/home-cards.sh checks they are still these.
    swatches: ['#5263ca', '#7a8bf1', '#000000'],
    facts: '128×128 px · 3 colours',
  },
  tangle: {
    blurb: 'Grow pen-and-ink tangles from a grammar, step by step; select any step and redo or retune it.',
    alt: "The paper's leaf grammar grown by the core",
    size: [320, 240],
  },
  micro: {
    blurb: 'Render multiscale microstructures from implicit functions; orbit and zoom from the sample down to its grains.',
    alt: 'The gyroid scene sphere-traced by the core',
    size: [160, 120],
  },
  texture: {
    blurb: 'Find a procedural texture from an example and steer it with twelve perceptual sliders (estimated, not human-rated).',
    alt: 'A regular texton texture rendered by the core, tiled 2×2',
    size: [256, 256],
  },
};

/** The card's picture (and the Inspect card's palette and facts) in `box`; `data-ready` once it has loaded. */
function showPicture(box, id, card) {
  const img = document.createElement('img');
  img.src = new URL(`${id}.png`, PICTURES).href;
  img.alt = card.alt;
  [img.width, img.height] = card.size;
  img.decoding = 'async';
  if (card.pixelated) img.className = 'pixelated';
  img.addEventListener('load', () => { box.dataset.ready = '1'; }, { once: true });
  img.addEventListener('error', () => {
    const s = document.createElement('span');
    s.className = 'muted';
    s.textContent = 'no preview';
    img.replaceWith(s);
  }, { once: true });
  box.append(img);
  if (card.swatches) {
    const ul = document.createElement('ul');
    ul.className = 'home-swatches';
    ul.setAttribute('aria-label', card.facts);
    for (const colour of card.swatches) {
      const li = document.createElement('li');
      li.style.background = colour;
      ul.append(li);
    }
    const facts = document.createElement('span');
    facts.className = 'home-facts';
    facts.textContent = card.facts;
    box.append(ul, facts);
  }
}

export function mountHome(el, _app, tools) {
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
    if (card.size) showPicture(box, tool.id, card);
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
  }
  // Nothing runs in the background: the pictures are plain images.
  return { unmount() {} };
}
