// <filigree-embed>: put one Filigree tool on any page (MISSION S7).
//
//   <script src="https://HOST/PATH/www/embed.js" defer></script>
//   <filigree-embed tool="fit" state="…share fragment…" title="Fit a honeycomb"
//                   mode="interactive" preview="honeycomb.png"></filigree-embed>
//
// A static facade first (title, a preview image or a styled placeholder, a
// play button); the iframe is inserted lazily when the element scrolls into
// view or when the button is clicked (as lite-youtube-embed does), so a page
// with ten embeds does not start ten wasm cores. No dependencies, no special
// headers on the host page (the app uses no SharedArrayBuffer, so no
// COOP/COEP), works from any origin.
//
// Attributes (README.md, "Embedding Filigree in your page")
//   state     the share-link fragment ("Copy link" in the app, without '#')
//   tool      the tool id, for the facade's words when `title` is absent (else
//             the tool named in `state`)
//   mode      "readonly" (default: the reader explores, nothing is kept, Reset
//             brings the author's state back) or "interactive" ("Open in
//             Filigree" carries the reader's state)
//   controls  "open": the tool's controls start open (default: the picture
//             alone, with a Controls button)
//   src       the app's index.html (default: ../index.html next to this script)
//   title     the facade's heading and the iframe's accessible title
//   preview   an image URL shown on the facade
//   load      "visible" (default: load when scrolled into view) or "click"
//   height    CSS height of the embed (a number is pixels); without it the
//             height follows the content: the app in the frame posts its
//             height ({type: 'filigree-embed:height'}) and the element takes it
(() => {
  if (typeof customElements === 'undefined' || customElements.get('filigree-embed')) return;

  // Where this script came from, to find the app next to it. currentScript is
  // null in a module script; then look for our own <script> element.
  const here = document.currentScript?.src
    || [...document.querySelectorAll('script[src]')].map((s) => s.src).find((s) => /\/embed\.js(\?|#|$)/.test(s))
    || location.href;
  const DEFAULT_SRC = new URL('../index.html', here).href;

  const TOOL_NAMES = { pixel: 'Pixel', fit: 'Fit', inspect: 'Inspect image', tangle: 'Tangle', micro: 'Micro', texture: 'Texture' };
  // Before the app says its height, an estimate: the picture's height per
  // width (www/app/embed-mode.js, STAGES) and what is around it.
  const RATIOS = { pixel: 0.5, fit: 0.6, tangle: 0.55, micro: 0.6, texture: 0.5 };
  const AROUND_PX = 170; // the embed's bar, the card, its toolbar and status

  const CSS = `
    :host { display: block; position: relative; width: 100%; max-width: 100%;
      height: var(--filigree-embed-height, clamp(360px, 70vh, 640px));
      border-radius: 10px; overflow: hidden; background: #16141d; color: #ebe7f3;
      font: 15px/1.45 system-ui, -apple-system, "Segoe UI", sans-serif; contain: content; }
    :host([hidden]) { display: none; }
    .facade { position: absolute; inset: 0; display: grid; place-items: center; cursor: pointer;
      background: radial-gradient(circle at 30% 20%, #2c2540, #16141d 70%); }
    .facade img { position: absolute; inset: 0; width: 100%; height: 100%; object-fit: cover; opacity: .85; }
    .facade .pattern { position: absolute; inset: 0; opacity: .18;
      background: radial-gradient(circle, #c9a2ff 0 2px, transparent 3px) 0 0 / 22px 22px; }
    .bar { position: absolute; left: 0; right: 0; top: 0; padding: .7rem 1rem; display: flex; gap: .6rem;
      align-items: center; background: linear-gradient(#000a, #0000); pointer-events: none; }
    .bar svg { flex: none; color: #c9a2ff; }
    .title { font-weight: 600; overflow: hidden; text-overflow: ellipsis; white-space: nowrap; }
    button { position: relative; display: inline-flex; align-items: center; gap: .6rem; font: inherit; font-weight: 600;
      color: #1b1526; background: #c9a2ff; border: 0; border-radius: 999px; padding: .7rem 1.3rem;
      box-shadow: 0 6px 24px #0008; cursor: pointer; }
    button:hover { background: #d9bcff; }
    button:focus-visible { outline: 3px solid #7fd1c7; outline-offset: 3px; }
    iframe { position: absolute; inset: 0; width: 100%; height: 100%; border: 0; display: block; background: #16141d; }
    .loading { position: absolute; right: .8rem; bottom: .6rem; font-size: .8rem; color: #a49cb8; pointer-events: none; }
  `;

  const LOGO = '<svg viewBox="0 0 32 32" width="22" height="22" aria-hidden="true"><g fill="none" stroke="currentColor" stroke-width="2.2" stroke-linecap="round"><path d="M16 3c6 5 6 21 0 26M16 3c-6 5-6 21 0 26M3 16c5-6 21-6 26 0M3 16c5 6 21 6 26 0"/><circle cx="16" cy="16" r="3"/></g></svg>';

  class FiligreeEmbed extends HTMLElement {
    static get observedAttributes() { return ['state', 'mode', 'src', 'title', 'preview', 'height', 'tool', 'controls']; }

    constructor() {
      super();
      this.attachShadow({ mode: 'open' });
      this.iframe = null;
      this.observer = null;
      this.contentHeight = 0; // what the app in the frame said its height is
      // The app in our frame says its height (size=content): take it unless the author set one.
      this.onMessage = (e) => {
        if (!this.iframe || e.source !== this.iframe.contentWindow) return;
        const h = e.data?.type === 'filigree-embed:height' ? Number(e.data.height) : NaN;
        if (!Number.isFinite(h) || h <= 0) return;
        this.contentHeight = Math.min(4000, Math.max(120, Math.ceil(h)));
        this.applyHeight();
      };
    }

    connectedCallback() {
      // (Re)connected: start from the facade (a moved iframe reloads anyway).
      this.iframe = null;
      this.contentHeight = 0;
      window.addEventListener('message', this.onMessage);
      this.render();
      if (this.getAttribute('load') === 'click') return;
      if (!('IntersectionObserver' in window)) {
        this.activate();
        return;
      }
      this.observer = new IntersectionObserver((entries) => {
        if (entries.some((e) => e.isIntersecting)) this.activate();
      }, { rootMargin: '200px 0px' });
      this.observer.observe(this);
    }

    disconnectedCallback() {
      window.removeEventListener('message', this.onMessage);
      this.observer?.disconnect();
      this.observer = null;
    }

    attributeChangedCallback(name) {
      if (!this.shadowRoot.firstChild) return;
      if (this.iframe && name !== 'preview') {
        this.iframe.title = this.label;
        const url = this.appUrl;
        if (this.iframe.src !== url) this.iframe.src = url;
        this.applyHeight();
      } else if (!this.iframe) {
        this.render();
      }
    }

    /** The tool's id: the `tool` attribute, else the one the state names. */
    get toolId() {
      return this.getAttribute('tool') || new URLSearchParams((this.getAttribute('state') || '').replace(/^#/, '')).get('tool') || '';
    }

    /** The facade's heading and the iframe's title. */
    get label() {
      const id = this.toolId;
      const tool = TOOL_NAMES[id] || (id && id[0].toUpperCase() + id.slice(1));
      return this.getAttribute('title') || (tool ? `Filigree ${tool}` : 'Filigree');
    }

    /** The URL the iframe loads: the app in embed mode with the state in its fragment. */
    get appUrl() {
      const url = new URL(this.getAttribute('src') || DEFAULT_SRC, document.baseURI);
      url.searchParams.set('embed', '1');
      if (this.getAttribute('mode') === 'interactive') url.searchParams.set('mode', 'interactive');
      else url.searchParams.delete('mode');
      if (this.getAttribute('controls') === 'open') url.searchParams.set('controls', 'open');
      else url.searchParams.delete('controls');
      // No height from the author: the app sizes its picture by the width and says its height.
      if (this.getAttribute('height')) url.searchParams.delete('size');
      else url.searchParams.set('size', 'content');
      const state = (this.getAttribute('state') || '').replace(/^#/, '');
      url.hash = state;
      return url.href;
    }

    /** The author's height; else the content's, once the app said it; else an estimate from the width. */
    applyHeight() {
      const h = this.getAttribute('height');
      if (h) {
        this.style.setProperty('--filigree-embed-height', /^\d+(\.\d+)?$/.test(h) ? `${h}px` : h);
        return;
      }
      const width = this.getBoundingClientRect().width;
      const ratio = RATIOS[this.toolId];
      const estimate = width > 0 && ratio ? AROUND_PX + Math.min(480, Math.max(200, width * ratio)) : 0;
      const px = this.contentHeight || estimate;
      if (px) this.style.setProperty('--filigree-embed-height', `${px}px`);
      else this.style.removeProperty('--filigree-embed-height');
    }

    render() {
      this.applyHeight();
      const root = this.shadowRoot;
      root.innerHTML = `<style>${CSS}</style>`;
      const facade = document.createElement('div');
      facade.className = 'facade';
      facade.part = 'facade';
      const preview = this.getAttribute('preview');
      if (preview) {
        const img = document.createElement('img');
        img.alt = '';
        img.loading = 'lazy';
        img.decoding = 'async';
        img.src = new URL(preview, document.baseURI).href;
        facade.append(img);
      } else {
        const pattern = document.createElement('div');
        pattern.className = 'pattern';
        facade.append(pattern);
      }
      const bar = document.createElement('div');
      bar.className = 'bar';
      bar.innerHTML = LOGO;
      const title = document.createElement('span');
      title.className = 'title';
      title.textContent = this.label;
      bar.append(title);
      const button = document.createElement('button');
      button.type = 'button';
      button.part = 'button';
      button.setAttribute('aria-label', `Open the embedded Filigree: ${this.label}`);
      button.innerHTML = '<svg viewBox="0 0 24 24" width="18" height="18" aria-hidden="true"><path d="M7 4l13 8-13 8z" fill="currentColor"/></svg><span>Open here</span>';
      facade.append(bar, button);
      // The whole facade is clickable; the button is what keyboards and screen readers reach.
      facade.addEventListener('click', () => this.activate({ focus: true }));
      root.append(facade);
    }

    /** Replace the facade with the iframe (once). */
    activate({ focus = false } = {}) {
      this.observer?.disconnect();
      this.observer = null;
      if (this.iframe) return;
      const iframe = document.createElement('iframe');
      iframe.title = this.label;
      iframe.setAttribute('allow', 'clipboard-write');
      iframe.loading = 'lazy';
      iframe.referrerPolicy = 'strict-origin-when-cross-origin';
      iframe.src = this.appUrl;
      const loading = document.createElement('div');
      loading.className = 'loading';
      loading.textContent = 'Loading Filigree…';
      iframe.addEventListener('load', () => loading.remove(), { once: true });
      this.iframe = iframe;
      const root = this.shadowRoot;
      root.querySelector('.facade')?.remove();
      root.append(iframe, loading);
      if (focus) iframe.focus();
      this.dispatchEvent(new CustomEvent('filigree-embed-load', { bubbles: true }));
    }
  }

  customElements.define('filigree-embed', FiligreeEmbed);
})();
