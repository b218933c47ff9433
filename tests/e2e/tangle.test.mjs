// The Tangle panel (issue 10 item 10): the paper's Fig. 9 leaf grammar grown
// in a worker, the step slider through its history, selecting a step by
// clicking a shape (and walking back), re-expanding it, editing one step's
// outline distance with only that part of the picture redone, and the SVG
// export (parsed, one <path> per final shape, the same bytes as the native
// CLI: tests/golden/tangle-leaf-seed1.svg.sha256 holds the SHA-256 and byte
// length of `filigree tangle --grammar assets/tangle/leaf.tangle --seed 1 --out x.svg`).
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import { launch, tangleRuns as runs, waitForTangle as waitForResult } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const count = (page) => page.$eval('[data-testid=tangle-count]', (el) => Number(el.dataset.count));

/**
 * In the page: the shown answer at the shown step and view, drawn as a full repaint draws
 * it (www/tangle/draw.js batches) on a canvas of its own, every part directly: no highlight
 * (an overlay, not the drawing) and no bitmaps. (On the GPU canvas a heavy part copied
 * from a bitmap differs from one drawn directly by a few levels at its edges, and an edit
 * that moves steps moves shapes between parts, so the panel's own repaint may differ by
 * that much where nothing changed.)
 */
const PAINTED = `window.tanglePainted = async () => {
  const { prepareTangle, paintBatches } = await import('/www/tangle/draw.js');
  const t = window.filigree.testHooks.tangle;
  const T = prepareTangle(t.result());
  const c = document.querySelector('[data-testid=tangle-canvas]');
  const o = document.createElement('canvas');
  o.width = c.width;
  o.height = c.height;
  const g = o.getContext('2d');
  g.fillStyle = '#fff';
  g.fillRect(0, 0, o.width, o.height);
  const v = t.view();
  g.setTransform(v.dpr * v.s, 0, 0, v.dpr * v.s, v.dpr * v.tx, v.dpr * v.ty);
  const sw = t.state().stroke_width;
  paintBatches(g, T.batches(t.step()), sw > 0 ? Math.max(sw, 0.5 / v.s) : 0);
  return g.getImageData(0, 0, o.width, o.height).data;
};`;

/**
 * Keep the canvas's pixels and the selected step's input mask (in the page: a picture is
 * millions of numbers), to compare with the picture after the next change.
 */
const snapshot = (page) => page.evaluate(async () => {
  const t = window.filigree.testHooks.tangle;
  const c = document.querySelector('[data-testid=tangle-canvas]');
  window.tangleBefore = { data: await window.tanglePainted(), mask: t.selectedMask() };
  return { width: c.width, height: c.height, covered: window.tangleBefore.mask.reduce((a, b) => a + b, 0) };
});

/** Pixels that changed since the snapshot inside the snapshot's mask and outside it. */
const changes = (page) => page.evaluate(async () => {
  const a = window.tangleBefore.data, m = window.tangleBefore.mask;
  const b = await window.tanglePainted();
  let inside = 0, outside = 0;
  for (let p = 0; p < m.length; p++) {
    const o = 4 * p;
    if (a[o] === b[o] && a[o + 1] === b[o + 1] && a[o + 2] === b[o + 2]) continue;
    if (m[p]) inside++;
    else outside++;
  }
  return { inside, outside };
});

const frames = (page) => page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
const selected = (page) => page.evaluate(() => window.filigree.testHooks.tangle.state().selected);
const operator = (page) => page.$eval('[data-testid=tangle-selected]', (e) => e.dataset.operator);

/** A final shape (not a mark) for which `which(shape, step, answer)` holds, with a point where a click picks it. */
async function shapeOf(page, which) {
  return page.evaluate((src) => {
    const pred = eval(`(${src})`);
    const t = window.filigree.testHooks.tangle;
    const r = t.result();
    const cands = Array.from({ length: r.shapes.count }, (_, i) => [r.shapes.at(i), i])
      .filter(([s]) => s.died === -1 && s.born >= 0 && !s.mark && pred(s, r.steps[s.born], r))
      .map(([, i]) => i);
    for (const i of cands.slice(0, 60)) {
      const p = t.pointIn(i);
      if (p) return { i, born: r.shapes.born[i], point: p };
    }
    return null;
  }, which.toString());
}

async function clickCanvas(page, [x, y]) {
  const box = await page.locator('[data-testid=tangle-canvas]').boundingBox();
  await page.mouse.click(box.x + x, box.y + y);
}

/** Each grammar card: its name, its `data-thumb` mark, and the dark pixels of its preview. */
const cardThumbs = (page) => page.$$eval('[data-testid=tangle-examples] [data-example]', (bs) => bs.map((b) => {
  const c = b.querySelector('canvas');
  const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
  let ink = 0;
  for (let i = 0; i < d.length; i += 4) if (d[i + 3] > 0 && d[i] < 128) ink++;
  return { name: b.dataset.example, thumb: b.dataset.thumb ?? null, ink };
}));

test('tangle: grow the leaf, walk its history, select, re-expand and edit a step, export the same SVG as the CLI', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.addScriptTag({ content: PAINTED });
  await page.waitForFunction(() => window.filigree?.testHooks?.tangle && Number(document.querySelector('[data-testid=tangle-status]').dataset.runs || 0) > 0, null, { timeout: 60000 });
  // The picker lists the shipped grammars, the paper's leaf first.
  const names = await page.$$eval('[data-testid=tangle-examples] [data-example]', (bs) => bs.map((b) => b.dataset.example));
  assert.equal(names[0], 'leaf');
  assert.ok(names.includes('village'), names.join());
  // A card whose preview is still growing is marked pending (and dimmed), not left blank.
  for (const c of await cardThumbs(page)) assert.ok(c.ink > 100 || c.thumb === 'pending', `${c.name}: blank and not pending`);

  let n = await runs(page);
  await page.click('[data-example=leaf]');
  n = await waitForResult(page, n);
  await page.click('[data-act=generate]');
  n = await waitForResult(page, n);
  const doc = await page.evaluate(() => window.filigree.testHooks.tangle.state());
  assert.equal(doc.example, 'leaf');
  assert.deepEqual(doc.edits, []);
  const r = await page.evaluate(() => ({ steps: window.filigree.testHooks.tangle.result().steps.length, stats: window.filigree.testHooks.tangle.result().stats }));
  assert.ok(r.steps > 10, `${r.steps} steps`);
  const final = await count(page);
  assert.equal(final, r.stats.shapes, 'the count shown at the last step is the final shape count');

  // Drag the step slider back and forth: the shown count follows.
  const s = await page.locator('[data-testid=tangle-step]').boundingBox();
  const y = s.y + s.height / 2;
  await page.mouse.move(s.x + s.width - 2, y);
  await page.mouse.down();
  await page.mouse.move(s.x + s.width * 0.05, y, { steps: 8 });
  const early = await count(page);
  const earlyStep = await page.$eval('[data-testid=tangle-count]', (el) => Number(el.dataset.step));
  await page.mouse.move(s.x + s.width * 0.5, y, { steps: 4 });
  const mid = await count(page);
  await page.mouse.move(s.x + s.width + 20, y, { steps: 8 });
  await page.mouse.up();
  assert.ok(earlyStep < r.steps / 4, `early step ${earlyStep}`);
  assert.ok(early < final && early !== mid, `counts ${early}, ${mid}, ${final}`);
  assert.equal(await count(page), final, 'back at the end: the final count again');
  assert.match(await page.textContent('[data-testid=tangle-count]'), new RegExp(`${final.toLocaleString('en')} shapes`));

  // Click a stippled square: its step (stippling) is selected; a second click on the
  // same shape walks back to the step that made its input (an outline).
  const stippled = await shapeOf(page, (s, st) => st.operator === 'stippling');
  assert.ok(stippled, 'a stippled shape can be clicked');
  await clickCanvas(page, stippled.point);
  await page.waitForFunction((b) => window.filigree.testHooks.tangle.state().selected === b, stippled.born);
  assert.equal(await operator(page), 'stippling');
  assert.ok(await page.$('[data-testid=tangle-param-spacing]'), 'the step\'s parameters have sliders');
  await clickCanvas(page, stippled.point);
  const parent = await page.evaluate((s) => {
    const r = window.filigree.testHooks.tangle.result();
    return r.shapes.born[r.steps[s].inputs[0]];
  }, stippled.born);
  assert.ok(parent >= 0 && parent < stippled.born);
  await page.waitForFunction((p) => window.filigree.testHooks.tangle.state().selected === p, parent);
  assert.equal(await operator(page), 'outline');
  await frames(page);

  // Edit that outline's distance: only its shapes are redone.
  const snap2 = await snapshot(page);
  const old = Number(await page.$eval('[data-testid=tangle-param-distance]', (i) => i.value));
  const next = old + 4;
  await page.$eval('[data-testid=tangle-param-distance]', (i, v) => {
    i.value = String(v);
    i.dispatchEvent(new Event('input', { bubbles: true }));
    i.dispatchEvent(new Event('change', { bubbles: true }));
  }, next);
  n = await waitForResult(page, n);
  const ed2 = await page.evaluate(() => window.filigree.testHooks.tangle.state());
  assert.equal(ed2.edits.length, 1);
  assert.equal(ed2.edits[0].step, parent);
  assert.ok(Math.abs(ed2.edits[0].params.distance - next) < 0.5, JSON.stringify(ed2.edits[0]));
  const newStep = await page.evaluate((sel) => window.filigree.testHooks.tangle.result().steps[sel], ed2.selected);
  assert.equal(newStep.operator, 'outline', 'the regrown step stays selected');
  assert.ok(Math.abs(newStep.params[0].value - ed2.edits[0].params.distance) < 1e-9, 'the regrown step has the new distance');
  const d2 = await changes(page);
  assert.ok(d2.inside > 50, `the outline changed (${d2.inside} pixels)`);
  assert.equal(d2.outside, 0, 'nothing changed outside the edited step\'s shapes');
  assert.ok(snap2.covered < snap2.width * snap2.height * 0.8, 'the step covers only part of the picture');

  // Re-expand the step that made a ring (ung_quads: two rules match it, outline or split):
  // each re-expansion is a new random draw of that step only; the picture changes only
  // inside the step's input shapes, and within a few draws it changes.
  await page.click('[data-act=select-none]');
  const ring = await shapeOf(page, (s, st, r) => r.tags[s.tag] === 'out_2');
  assert.ok(ring, 'a ring can be clicked');
  await clickCanvas(page, ring.point);
  await page.waitForFunction((b) => window.filigree.testHooks.tangle.state().selected === b, ring.born);
  let changed = 0;
  for (let tries = 1; tries <= 6 && !changed; tries++) {
    await frames(page);
    await snapshot(page);
    await page.click('[data-act=reexpand]');
    n = await waitForResult(page, n);
    const st = await page.evaluate(() => window.filigree.testHooks.tangle.state());
    assert.equal(st.edits.length, 1 + tries);
    assert.deepEqual(st.edits.at(-1).params, {});
    const d = await changes(page);
    assert.equal(d.outside, 0, `re-expansion ${tries} changed nothing outside the step's shapes`);
    if (d.inside > 50) changed = tries;
  }
  assert.ok(changed, 'a re-expansion drew a different picture there');

  // Undo goes back one edit.
  const edits = (await page.evaluate(() => window.filigree.testHooks.tangle.state())).edits.length;
  await page.click('[data-act=undo]');
  n = await waitForResult(page, n);
  assert.equal((await page.evaluate(() => window.filigree.testHooks.tangle.state())).edits.length, edits - 1);

  // Export: the SVG parses, one <path> per final shape the page shows.
  const shown = await count(page);
  const svg = await page.evaluate(() => window.filigree.testHooks.tangle.exportSvg());
  const parsed = await page.evaluate((text) => {
    const d = new DOMParser().parseFromString(text, 'image/svg+xml');
    return { error: !!d.querySelector('parsererror'), paths: d.querySelectorAll('path').length, root: d.documentElement.nodeName };
  }, svg);
  assert.deepEqual(parsed, { error: false, paths: shown, root: 'svg' });

  // The button downloads it.
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('[data-act=export-svg]')]);
  assert.match(download.suggestedFilename(), /^leaf-seed1\.svg$/);

  // A fresh leaf at seed 1: the same bytes as the native CLI.
  await page.click('[data-example=leaf]');
  n = await waitForResult(page, n);
  const fresh = await page.evaluate(async () => {
    const svg = await window.filigree.testHooks.tangle.exportSvg();
    const bytes = new TextEncoder().encode(svg);
    const hash = [...new Uint8Array(await crypto.subtle.digest('SHA-256', bytes))].map((b) => b.toString(16).padStart(2, '0')).join('');
    return { hash, length: bytes.length };
  });
  // The native SVG (3 MB) is kept as its SHA-256 and byte length.
  const [hash, length] = fs.readFileSync(new URL('../golden/tangle-leaf-seed1.svg.sha256', import.meta.url), 'utf8').trim().split(/\s+/);
  assert.equal(fresh.length, Number(length), 'SVG length equals the native golden');
  assert.equal(fresh.hash, hash, 'the browser\'s SVG is byte for byte the native CLI\'s');

  // Every grammar card got its preview (a blank card is dimmed until then, marked pending).
  await page.waitForSelector('[data-testid=tangle-examples][data-thumbnails=ready]', { timeout: 120000 });
  for (const c of await cardThumbs(page)) {
    assert.equal(c.thumb, null, `${c.name}: no longer pending`);
    assert.ok(c.ink > 100, `${c.name}: its preview has ink (${c.ink} dark pixels)`);
  }
});

test('tangle: a grammar error is marked in the editor at its line; a typed word is a start', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => window.filigree?.testHooks?.tangle && Number(document.querySelector('[data-testid=tangle-status]').dataset.runs || 0) > 0, null, { timeout: 60000 });
  let n = await runs(page);
  const text = await page.evaluate(() => window.filigree.testHooks.tangle.state().grammar);
  const bad = text.replace('outline(25) : big_poly -> [in, out]', 'outline(25 : big_poly -> [in, out]');
  assert.notEqual(bad, text);
  await page.fill('[data-testid=tangle-grammar]', bad);
  await page.click('[data-act=generate]');
  await page.waitForSelector('[data-testid=doc-error]:not([hidden])', { timeout: 30000 });
  const err = await page.textContent('[data-testid=doc-error]');
  assert.match(err, /line 10/, err);
  // Back to the shipped grammar, started from a typed word.
  await page.click('[data-example=leaf]');
  n = await waitForResult(page, n);
  await page.selectOption('[name=start-kind]', 'text');
  n = await waitForResult(page, n);
  const st = await page.evaluate(() => window.filigree.testHooks.tangle.state().start);
  assert.deepEqual(st, { kind: 'text', text: 'Tangle', height: 300 });
  assert.ok(await count(page) > 50);
});

test('tangle: an example picked right after typing replaces the typed grammar, in the document and the editor', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => window.filigree?.testHooks?.tangle && Number(document.querySelector('[data-testid=tangle-status]').dataset.runs || 0) > 0, null, { timeout: 60000 });
  let n = await runs(page);
  const before = await page.evaluate(() => window.filigree.testHooks.tangle.state());
  const other = before.example === 'checkerboard' ? 'pebbles' : 'checkerboard';
  const want = fs.readFileSync(new URL(`../../assets/tangle/${other}.tangle`, import.meta.url), 'utf8');
  // Typed text waits 0.6 s before it is committed; the example is picked within that pause.
  await page.fill('[data-testid=tangle-grammar]', `${before.grammar}\n// typed, then an example picked`);
  assert.equal(await page.evaluate(() => window.filigree.testHooks.tangle.pending()), true, 'the typed text waits for its pause');
  await page.click(`[data-example=${other}]`);
  n = await waitForResult(page, n);
  // Longer than the typing pause: nothing typed is committed afterwards.
  await page.waitForTimeout(1200);
  const after = await page.evaluate(() => window.filigree.testHooks.tangle.state());
  assert.equal(after.example, other);
  assert.equal(after.grammar, want);
  const shown = await page.$eval('[data-testid=tangle-grammar]', (el) => el.value ?? el.innerText);
  assert.equal(shown.replace(/\s+/g, ' ').trim(), want.replace(/\s+/g, ' ').trim());
  assert.equal(await page.evaluate(() => window.filigree.testHooks.tangle.pending()), false);
});

test('tangle: an uploaded SVG icon starts the tangle as it looks, fitted to the grammar\'s frame', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => window.filigree?.testHooks?.tangle && Number(document.querySelector('[data-testid=tangle-status]').dataset.runs || 0) > 0, null, { timeout: 60000 });
  let n = await runs(page);
  await page.click('[data-example=leaf]'); // start rect(800, 600)
  n = await waitForResult(page, n);
  // Choosing "an SVG file" opens the file picker; the person picks the icon.
  const [chooser] = await Promise.all([page.waitForEvent('filechooser'), page.selectOption('[name=start-kind]', 'svg')]);
  await chooser.setFiles(new URL('../fixtures/badge.svg', import.meta.url).pathname);
  n = await waitForResult(page, n);
  const start = await page.evaluate(() => {
    const t = window.filigree.testHooks.tangle;
    const r = t.result(), pts = t.points();
    const out = [];
    for (let i = 0; i < r.shapes.count; i++) {
      const s = r.shapes.at(i);
      if (s.born !== -1) continue;
      const m = s.rings.reduce((a, b) => a + b, 0);
      let lo = [Infinity, Infinity], hi = [-Infinity, -Infinity];
      for (let k = s.first; k < s.first + m; k++) {
        const [x, y] = [pts[2 * k], pts[2 * k + 1]];
        lo = [Math.min(lo[0], x), Math.min(lo[1], y)];
        hi = [Math.max(hi[0], x), Math.max(hi[1], y)];
      }
      out.push({ rings: s.rings.length, lo, hi });
    }
    return { kind: t.state().start.kind, shapes: out, grown: r.stats.shapes };
  });
  assert.equal(start.kind, 'svg');
  // The disc (with the dot over its rim, and the white bar as a hole) and the <use>d dot;
  // the white background is paper.
  assert.equal(start.shapes.length, 2, JSON.stringify(start.shapes));
  const disc = start.shapes.find((s) => s.rings === 2);
  assert.ok(disc, JSON.stringify(start.shapes));
  // The 24-unit drawing (ink y 2..23) scaled into the leaf's 800×600 frame: full height.
  const lo = Math.min(...start.shapes.map((s) => s.lo[1])), hi = Math.max(...start.shapes.map((s) => s.hi[1]));
  assert.ok(Math.abs(lo) < 0.5 && Math.abs(hi - 600) < 0.5, `${lo}..${hi}`);
  assert.ok(start.grown > 100, `the leaf grammar grew on it: ${start.grown} shapes`);
});

test('tangle: a curve drawn on the canvas joins the grammar and a split cuts along it; a drawn shape joins too', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => window.filigree?.testHooks?.tangle && Number(document.querySelector('[data-testid=tangle-status]').dataset.runs || 0) > 0, null, { timeout: 60000 });
  let n = await runs(page);
  const straight = 'start rect(600, 400) : a\nregularSplit(line, 100, 0) : a -> [b]\n';
  await page.fill('[data-testid=tangle-grammar]', straight);
  await page.click('[data-act=generate]');
  n = await waitForResult(page, n);
  const before = await page.evaluate(() => window.filigree.testHooks.tangle.result().stats);
  // A zigzag drawn with five clicks, finished with the bar's button.
  await page.click('[data-act=draw-curve]');
  assert.equal(await page.textContent('[data-act=draw-finish]'), 'Add this curve');
  // The drawing area is in view, though the button sits low in the side column.
  const box = await page.locator('[data-testid=tangle-canvas]').boundingBox();
  assert.ok(box.y + box.height * 0.2 >= 0 && box.y + box.height * 0.8 <= 800, `the canvas is in view: ${JSON.stringify(box)}`);
  for (const [fx, fy] of [[0.2, 0.5], [0.35, 0.3], [0.5, 0.5], [0.65, 0.3], [0.8, 0.5]]) {
    await page.mouse.click(box.x + fx * box.width, box.y + fy * box.height);
  }
  assert.equal(await page.textContent('[data-testid=tangle-draw-count]'), '5');
  await page.click('[data-act=draw-finish]');
  n = await waitForResult(page, n);
  const grammar = await page.evaluate(() => window.filigree.testHooks.tangle.state().grammar);
  const m = /^curve drawn1 = polyline\(([^)]*)\)\n/.exec(grammar);
  assert.ok(m, grammar);
  assert.equal(m[1].split(',').length, 5);
  assert.ok(grammar.endsWith(straight), 'the rest of the grammar is kept');
  // Used by the split: bands with zigzag edges (far more vertices per shape).
  await page.fill('[data-testid=tangle-grammar]', grammar.replace('regularSplit(line', 'regularSplit(drawn1'));
  await page.click('[data-act=generate]');
  n = await waitForResult(page, n);
  const after = await page.evaluate(() => window.filigree.testHooks.tangle.result().stats);
  assert.ok(after.shapes >= 2, JSON.stringify(after));
  assert.ok(after.vertices / after.shapes > before.vertices / before.shapes + 4, `${JSON.stringify(after)} vs ${JSON.stringify(before)}`);
  // A shape: three clicks and a double-click close it; it is added as `shape drawn2`.
  await page.click('[data-act=draw-shape]');
  for (const [fx, fy] of [[0.3, 0.3], [0.6, 0.35], [0.45, 0.7]]) {
    await page.mouse.click(box.x + fx * box.width, box.y + fy * box.height);
  }
  await page.mouse.dblclick(box.x + 0.3 * box.width, box.y + 0.6 * box.height);
  n = await waitForResult(page, n);
  const g2 = await page.evaluate(() => window.filigree.testHooks.tangle.state().grammar);
  assert.match(g2, /^shape drawn2 = polyline\(([^,)]*,){3}[^,)]*\)\ncurve drawn1 = /);
  // Undo takes the definition out again.
  await page.keyboard.press('Control+z');
  n = await waitForResult(page, n);
  assert.ok((await page.evaluate(() => window.filigree.testHooks.tangle.state().grammar)).startsWith('curve drawn1 ='));
});
