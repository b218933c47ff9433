// A file dropped anywhere in the window (app/document.js: view.drop): an
// SVG becomes the start shape, a grammar (.tangle, plain text) the grammar
// text, once the core has read it with the rest of the document (one step
// grown); a file it refuses leaves the document as it is.
import { requestOf } from './state.js';

// The core's limits on what a dropped file may hold (src/tangle/state.rs).
const MAX_GRAMMAR_BYTES = 256 * 1024;
const MAX_SVG_BYTES = 1024 * 1024;

/** `view.drop` of a mounted panel: `editor` (grammar-editor.js), `live` (state.js). */
export function createDrop(ctx, { live, editor, status }) {
  const state = () => ctx.state();
  return async function dropFile(file) {
    const name = file.name.toLowerCase();
    const svg = /\.svg$/.test(name) || file.type === 'image/svg+xml';
    const grammar = !svg && /\.(tangle|txt)$/.test(name);
    if (!svg && !grammar) throw new Error('Tangle opens SVG files (a start shape), grammars (.tangle) and Filigree projects');
    const limit = svg ? MAX_SVG_BYTES : MAX_GRAMMAR_BYTES;
    if (file.size > limit) throw new Error(`it is ${Math.ceil(file.size / 1024)} KB, more than ${svg ? 'an SVG start' : 'a grammar'} may be (${limit / 1024} KB)`);
    const text = await file.text();
    const doc = state();
    if (!doc) throw new Error('the panel is still loading');
    const change = svg ? { start: { kind: 'svg', svg: text } } : { grammar: text, example: null };
    await ctx.run('tangle', { ...requestOf({ ...doc, ...change, edits: [] }), max_steps: 1 });
    const now = state();
    if (!now || !ctx.alive()) return;
    if (!svg) editor.dropTyping();
    live.refit = true;
    live.lastPick = -1;
    ctx.commit({ ...now, ...change, edits: [], selected: null });
    status(`opened ${svg ? 'the start shape' : 'the grammar'} ${file.name}`);
  };
}
