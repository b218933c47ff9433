// Drawing a polyline on the canvas: a start polygon, or a curve or shape
// that is added to the grammar text as a `curve`/`shape` polyline
// definition for split and place rules. Clicks add points (the gestures,
// gestures.js, tell a click from a pan); a double-click or the bar's button
// finishes, Cancel drops it. While drawing, the canvas paints the polyline
// over the tangle (canvas.js `overlay`).
import { HIGHLIGHT_LINE } from './canvas.js';

// What a polyline drawn on the canvas becomes.
const DRAW_PURPOSES = {
  start: { what: 'a start polygon', finish: 'Use this polygon', min: 3 },
  curve: { what: 'a curve', finish: 'Add this curve', min: 2 },
  shape: { what: 'a shape', finish: 'Add this shape', min: 3 },
};

/**
 * The polyline drawing of a mounted panel (`q` finds its elements):
 * `painter` (canvas.js), `grammarText(doc)` (the
 * editor's text), `setStart(start)`, `stopPlay()`, `onCancel()` (the start
 * form shows the document's start again).
 */
export function createPolygonDraw(ctx, { q, live, painter, status, grammarText, setStart, stopPlay, onCancel }) {
  const state = () => ctx.state();
  let drawing = null; // the polyline being drawn: [[x, y], ...]
  let drawingFor = 'start'; // what it becomes: DRAW_PURPOSES

  /** Start drawing a polyline on the canvas for `purpose` (DRAW_PURPOSES). */
  function begin(purpose = 'start') {
    drawing = [];
    drawingFor = purpose;
    stopPlay();
    const p = DRAW_PURPOSES[purpose];
    q('.tangle-draw-bar').hidden = false;
    q('[data-act=draw-finish]').textContent = p.finish;
    q('[data-testid=tangle-draw-count]').textContent = '0';
    status(`drawing ${p.what}: click to add points, double-click or "${p.finish}" to finish`);
    // The drawing area comes into view: the button may sit far down the side column.
    q('[data-testid=tangle-canvas]').scrollIntoView({ block: 'nearest' });
    painter.paint();
  }
  function addPoint(cx, cy) {
    const [x, y] = painter.toWorld(cx, cy);
    drawing.push([Math.round(x * 100) / 100, Math.round(y * 100) / 100]);
    q('[data-testid=tangle-draw-count]').textContent = String(drawing.length);
    painter.paint();
  }
  function finish() {
    const pts = drawing;
    end();
    // A double-click adds its point twice.
    const clean = pts.filter((p, i) => i === 0 || p[0] !== pts[i - 1][0] || p[1] !== pts[i - 1][1]);
    const p = DRAW_PURPOSES[drawingFor];
    if (clean.length < p.min) { status(`${p.what} needs at least ${p.min} points`); return; }
    if (drawingFor === 'start') setStart({ kind: 'polygon', points: clean });
    else addDefinition(drawingFor, clean);
  }

  /**
   * Add the drawn polyline to the grammar as `curve drawnN = polyline(...)` (or
   * `shape`), first in the text so every rule can name it. The core scales it
   * to what it cuts or fills, so only its form matters.
   */
  function addDefinition(kind, pts) {
    const doc = state();
    if (!doc) return;
    const text = grammarText(doc);
    let k = 1;
    while (new RegExp(`\\bdrawn${k}\\b`).test(text)) k++;
    const name = `drawn${k}`;
    const x0 = Math.min(...pts.map((p) => p[0])), y0 = Math.min(...pts.map((p) => p[1]));
    const num = (v) => String(Math.round(v * 10) / 10);
    const line = `${kind} ${name} = polyline(${pts.map(([x, y]) => `${num(x - x0)} ${num(y - y0)}`).join(', ')})`;
    const use = kind === 'curve' ? `regularSplit(${name}, 40, 0) : tag -> [a]` : `place(20, 4, ${name}) : tag -> [a, b]`;
    live.refit = false;
    ctx.commit({ ...doc, grammar: `${line}\n${text}`, example: null, edits: [], selected: null });
    status(`added "${kind} ${name}" to the grammar; use it in a rule, e.g. ${use}`);
  }
  function end() {
    drawing = null;
    q('.tangle-draw-bar').hidden = true;
    painter.paint();
  }

  /** The polyline over the tangle, in CSS px (g: the canvas's context). */
  function paintOn(g) {
    if (!drawing) return;
    const { dpr, toCss } = painter;
    g.setTransform(dpr, 0, 0, dpr, 0, 0);
    g.strokeStyle = HIGHLIGHT_LINE;
    g.fillStyle = HIGHLIGHT_LINE;
    g.lineWidth = 2;
    g.beginPath();
    drawing.forEach(([x, y], i) => {
      const [cx, cy] = toCss(x, y);
      if (i) g.lineTo(cx, cy); else g.moveTo(cx, cy);
    });
    if (drawing.length > 2 && drawingFor !== 'curve') g.closePath();
    g.stroke();
    for (const [x, y] of drawing) {
      const [cx, cy] = toCss(x, y);
      g.fillRect(cx - 3, cy - 3, 6, 6);
    }
  }

  q('[data-act=draw-finish]').onclick = finish;
  q('[data-act=draw-cancel]').onclick = () => { end(); onCancel(); status(''); };
  q('[data-act=draw-start]').onclick = () => begin();
  q('[data-act=draw-curve]').onclick = () => begin('curve');
  q('[data-act=draw-shape]').onclick = () => begin('shape');
  q('[data-testid=tangle-canvas]').addEventListener('dblclick', (e) => { if (drawing) { e.preventDefault(); finish(); } });

  return {
    begin, addPoint,
    /** Whether a polyline is being drawn. */
    active: () => !!drawing,
    paintOn,
  };
}
