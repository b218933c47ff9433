// Tangle's document and what the page derives from it. The document IS the
// request: grammar, start, seed, ink settings and the user's edits in order
// ({step, params}); the core replays the edits, so the page keeps no tangle
// state of its own and undo is just the previous document. History,
// autosave, project files and links come from the document controller
// (app/document.js); the schema (every field, its rules and messages) is
// src/tangle/state.rs, applied by the controller (`check-state`).
import { shippedExamples, shareByExample } from '../ui/examples.js';

// Shipped grammars: fetched once per page.
export const examples = shippedExamples('tangle-examples');

// The panel's own requests ask the worker to keep the expansion (`keep`) and
// go to the worker that kept it, so an edit regrows only its step's subtree
// there instead of the whole tangle (src/tangle/api.rs, app/client.js).
export const KEEP_AFFINITY = 'tangle';

/** The `tangle` request of document `s` (the core's defaults for the rest). */
export const requestOf = (s) => ({
  grammar: s.grammar, start: s.start, seed: s.seed, wobble: s.wobble, stroke_width: s.stroke_width, edits: s.edits,
});

/** Whether documents `a` and `b` grow the same tangle (the pen width only draws it). */
export const sameRequest = (a, b) => a.grammar === b.grammar && a.start === b.start && a.seed === b.seed
  && a.wobble === b.wobble && a.edits === b.edits;

export const tangleState = {
  version: 1,
  async defaults(ctx) {
    const [list, d] = await Promise.all([examples(ctx.run), ctx.coreDefaults()]);
    const ex = list.find((e) => e.name === 'leaf') || list[0];
    return {
      example: ex.name, grammar: ex.grammar, seed: d.seed, start: null,
      wobble: d.wobble, stroke_width: d.stroke_width, edits: [], selected: null,
    };
  },
  migrate: (raw) => raw,
  fileName: (s) => s.example || 'tangle',
  // A shipped grammar travels by name.
  ...shareByExample(examples, 'grammar', { tool: 'Tangle', what: 'grammar' }),
};

/**
 * What a mounted panel derives from the document (not saved), shared by its
 * parts: the last answer, the step shown, and what the next answer does.
 */
export function createLive(state) {
  const live = {
    T: null, // prepareTangle(answer) of the current (or last good) document (draw.js)
    shownFor: null, // the document T answers
    k: 0, // shown step
    refit: true, // the next answer fits the view to the drawing
    lastPick: -1, // the shape the last click on the canvas picked (a second click walks back)
    /** The selected step, while the shown answer answers the document; else null. */
    selected() {
      const s = state()?.selected;
      return live.T && s != null && s < live.T.steps && live.shownFor && sameRequest(live.shownFor, state()) ? s : null;
    },
  };
  return live;
}
