// The shipped grammars as cards with a small picture each. The pictures are
// grown one at a time after the main drawing, each at low settings, and
// kept for the page's life; a grammar that cannot grow at those settings
// says so on its card.
import { drawThumbnail } from './draw.js';
import { examples } from './state.js';

const THUMB = { width: 96, height: 72 };
// A thumbnail grows only this far (its grammar runs once, cached for the page's life).
const THUMB_REQUEST = { max_steps: 400, max_shapes: 2500, resolution: 4 };

const thumbnails = new Map(); // name → canvas

/**
 * The cards in list `list` of a mounted panel; `pick(example)` loads a
 * shipped grammar.
 */
export function createExamplePicker(ctx, list, { pick }) {
  examples(ctx.run).then((exs) => {
    if (!ctx.alive()) return;
    list.replaceChildren(...exs.map((ex) => {
      const li = document.createElement('li');
      const b = document.createElement('button');
      b.type = 'button';
      b.className = 'tangle-example';
      b.dataset.example = ex.name;
      b.title = ex.about;
      const c = document.createElement('canvas');
      c.width = THUMB.width;
      c.height = THUMB.height;
      c.setAttribute('aria-hidden', 'true');
      const name = document.createElement('span');
      name.textContent = ex.name;
      b.append(c, name);
      b.onclick = () => pick(ex);
      li.append(b);
      const cached = thumbnails.get(ex.name);
      if (cached) c.getContext('2d').drawImage(cached, 0, 0);
      else b.dataset.thumb = 'pending'; // its preview is still growing (styles.css dims the card)
      return li;
    }));
    mark(ctx.state());
  }).catch((err) => ctx.error(err, { prefix: 'The shipped grammars' }));

  /** Press the card of document `s`'s example. */
  function mark(s) {
    for (const b of list.querySelectorAll('[data-example]')) b.setAttribute('aria-pressed', String(b.dataset.example === s?.example));
  }

  // One at a time, after the main drawing, each at low settings; kept for the page's life.
  let thumbsBusy = false;
  async function loadThumbnails() {
    if (thumbsBusy) return;
    thumbsBusy = true;
    try {
      for (const ex of await examples(ctx.run)) {
        if (thumbnails.has(ex.name) || !ctx.alive()) continue;
        let r;
        try {
          r = await ctx.run('tangle', { grammar: ex.grammar, seed: 1, ...THUMB_REQUEST });
        } catch (err) {
          if (err?.kind === 'cancelled') throw err;
          // This grammar cannot grow here (its card says so); the others still get theirs.
          const b = list.querySelector(`[data-example="${CSS.escape(ex.name)}"]`);
          if (b) { b.title = `${ex.about} (no preview: ${err?.message || err})`; b.dataset.thumb = 'none'; }
          continue;
        }
        const c = document.createElement('canvas');
        c.width = THUMB.width;
        c.height = THUMB.height;
        drawThumbnail(c, r);
        thumbnails.set(ex.name, c);
        const card = list.querySelector(`[data-example="${CSS.escape(ex.name)}"]`);
        card?.querySelector('canvas').getContext('2d').drawImage(c, 0, 0);
        if (card) delete card.dataset.thumb;
      }
      list.dataset.thumbnails = 'ready';
    } catch (err) {
      if (err?.kind !== 'cancelled') console.warn('tangle thumbnails:', err?.message || err);
    } finally {
      thumbsBusy = false;
    }
  }

  return { mark, loadThumbnails };
}
