// Files in: a scene JSON file dropped anywhere in the window.
import { requestOf, prettyScene } from './state.js';

const MAX_SCENE_BYTES = 256 * 1024; // the core's MAX_MICRO_SCENE_BYTES (src/core/limits.rs)

/**
 * A scene JSON file dropped anywhere in the window (document.js: view.drop):
 * read and traced once by the core (a 2×2 picture) before it replaces the
 * scene; a file the core refuses leaves the document as it is. Returns
 * the panel's `drop(file)`.
 */
export function createDrop(ctx, { editor, status }) {
  const state = () => ctx.state();
  return async function dropScene(file) {
    if (!/\.json$/i.test(file.name) && !/\bjson\b/i.test(file.type)) {
      throw new Error('Micro opens scene JSON files (like Export scene JSON writes) and Filigree projects');
    }
    if (file.size > MAX_SCENE_BYTES) throw new Error(`it is ${Math.ceil(file.size / 1024)} KB, more than a scene may be (${MAX_SCENE_BYTES / 1024} KB)`);
    const text = await file.text();
    try { JSON.parse(text); } catch (err) { throw new Error(`it is not JSON (${err.message})`); }
    const doc = state();
    if (!doc) throw new Error('the panel is still loading');
    const [kind, payload] = requestOf({ ...doc, scene: text, view: 'render', spp: 0 }, 2);
    await ctx.run(kind, payload);
    const now = state();
    if (!now || !ctx.alive()) return;
    editor.stopTyping();
    ctx.commit({ ...now, scene: prettyScene(text), example: null });
    status(`opened the scene ${file.name}`);
  };
}
