// "Start from": where the tangle starts. The grammar's own start, a
// rectangle, a typed word (applied once the typing pauses), an SVG file, or
// a polygon drawn on the canvas (polygon-draw.js).

const WORD_DELAY_MS = 400; // a typed start word applies once the typing pauses this long
const START_KINDS = [
  ['grammar', "the grammar's start"],
  ['rect', 'a rectangle'],
  ['text', 'a typed word'],
  ['svg', 'an SVG file'],
  ['polygon', 'a polygon drawn here'],
];

const startKind = (s) => s?.start?.kind ?? 'grammar';

/**
 * The start form of a mounted panel (`q` finds its elements);
 * `drawPolygon()` starts drawing a start polygon on the canvas.
 */
export function createStartForm(ctx, { q, live, drawPolygon }) {
  const state = () => ctx.state();
  const kindSel = q('[name=start-kind]');
  for (const [v, label] of START_KINDS) kindSel.append(new Option(label, v));
  function showStartRows(kind) {
    for (const [v] of START_KINDS) {
      const row = q(`.tangle-start-${v}`);
      if (row) row.hidden = v !== kind;
    }
  }
  function setStart(start) {
    const doc = state();
    if (!doc) return;
    live.refit = true;
    live.lastPick = -1;
    ctx.commit({ ...doc, start, edits: [], selected: null });
  }
  const num = (name, lo, hi, d) => {
    const v = Number(q(`[name=${name}]`).value);
    return Number.isFinite(v) ? Math.max(lo, Math.min(hi, v)) : d;
  };
  const rectStart = () => ({ kind: 'rect', width: num('start-width', 1, 1e6, 800), height: num('start-height', 1, 1e6, 600) });
  const textStart = () => ({ kind: 'text', text: q('[name=start-text]').value.trim() || 'Tangle', height: num('start-text-height', 1, 1e6, 300) });
  kindSel.onchange = () => {
    const kind = kindSel.value;
    showStartRows(kind);
    if (kind === 'grammar') setStart(null);
    else if (kind === 'rect') setStart(rectStart());
    else if (kind === 'text') setStart(textStart());
    else if (kind === 'svg') q('[name=start-svg]').click();
    else if (kind === 'polygon') drawPolygon();
  };
  for (const n of ['start-width', 'start-height']) q(`[name=${n}]`).onchange = () => setStart(rectStart());
  // A typed word applies as you type, once the typing pauses (and at once on Enter or leaving the field).
  let wordTimer = null;
  const applyWord = () => {
    ctx.clearTimeout(wordTimer);
    wordTimer = null;
    const next = textStart();
    const cur = state()?.start;
    if (cur?.kind === 'text' && cur.text === next.text && cur.height === next.height) return;
    setStart(next);
  };
  for (const n of ['start-text', 'start-text-height']) {
    const input = q(`[name=${n}]`);
    input.onchange = applyWord;
    input.oninput = () => {
      ctx.clearTimeout(wordTimer);
      wordTimer = ctx.setTimeout(applyWord, WORD_DELAY_MS);
    };
  }
  q('[name=start-svg]').onchange = async (e) => {
    const file = e.target.files[0];
    e.target.value = '';
    if (!file) return;
    const svg = await file.text();
    setStart({ kind: 'svg', svg });
  };

  /** Show document `s`'s start (the kind too, unless a polygon is being drawn). */
  function render(s, drawing) {
    if (!drawing) showKind(s);
    if (s.start?.kind === 'rect') { q('[name=start-width]').value = String(s.start.width); q('[name=start-height]').value = String(s.start.height); }
    if (s.start?.kind === 'text' && wordTimer === null) {
      // Not under the user's fingers: the field keeps what is typed (a trailing space, say).
      const word = q('[name=start-text]');
      if (document.activeElement !== word || word.value.trim() !== s.start.text) word.value = s.start.text;
      q('[name=start-text-height]').value = String(s.start.height);
    }
  }
  function showKind(s) {
    kindSel.value = startKind(s);
    showStartRows(kindSel.value);
  }

  return {
    setStart, render,
    /** Show the document's start kind again (a drawing was cancelled). */
    reset: () => showKind(state()),
    /** Whether a typed word is waiting to apply. */
    typing: () => wordTimer !== null,
  };
}
