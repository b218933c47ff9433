// Tangle edits on the fast path (issue 10 item 9, issue 33 item 4): while an
// edit's answer is due the canvas is left as it is; the worker answers with
// a delta against the answer shown (www/tangle/delta.js applies it; the kept
// shapes keep their Path2Ds, draw.js `prepareTangle(r, link)`) and the panel
// repaints only the tiles where the picture changed.
// Both must give exactly what a fresh answer painted in full gives:
// - the shapes the panel holds equal a fresh, full expansion's (not kept
//   by the worker, nothing reused), column by column and point by point;
// - the canvas after the partial repaint equals the panel's full repaint,
//   and that equals a fresh answer's shapes painted in full on a canvas of
//   its own (so a wrongly reused Path2D, or a tile left stale outside the
//   repainted region, fails).
// The software 2-D canvas: in headless Chromium the GPU canvas runs on
// SwiftShader, whose pictures are not even stable between two identical
// full repaints (30k pixels differ), so pixel equality means nothing there.
// "Equals" allows anti-aliasing to differ a little: heavy parts of the
// picture are drawn through bitmaps and the rest directly, and the two
// composite edge pixels up to 9 levels in 255 apart. A line drawn where
// there is none, or missing, differs by far more at its core: pixels off by
// more than 100 levels must be none, and those off by more than 2 a few.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch, tangleRuns as runs, waitForTangle as waitForResult } from './harness.mjs';

let env;
before(async () => { env = await launch({ args: ['--disable-accelerated-2d-canvas'] }); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

/** Select a step with a `distance` (outline, place) whose subtree has `lo`–`hi` shapes; set its distance to `v`. */
async function editDistance(page, lo, hi, v) {
  const target = await page.evaluate(([lo, hi]) => {
    const r = window.filigree.testHooks.tangle.result();
    const subtree = (k) => {
      const made = new Set(r.steps[k].outputs);
      for (let j = k + 1; j < r.steps.length; j++) if (r.steps[j].inputs.some((i) => made.has(i))) for (const o of r.steps[j].outputs) made.add(o);
      return made.size;
    };
    const c = r.steps.map((s, k) => [k, s.params.some((p) => p.name === 'distance') ? subtree(k) : -1]).filter(([, n]) => n >= lo && n <= hi)
      .sort((a, b) => a[1] - b[1]);
    return c.length ? c[0] : null;
  }, [lo, hi]);
  assert.ok(target, `a step with a distance and a subtree of ${lo}–${hi} shapes`);
  await page.evaluate((sel) => window.filigree.doc.current.ctx.commit({ ...window.filigree.testHooks.tangle.state(), selected: sel }), target[0]);
  await page.waitForSelector(`[data-testid=tangle-params][data-step="${target[0]}"] [data-testid=tangle-param-distance]`);
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  if (v === null) return target;
  const n = await runs(page);
  await page.$eval('[data-testid=tangle-param-distance]', (i, v) => {
    i.value = String(v);
    i.dispatchEvent(new Event('input', { bubbles: true }));
    i.dispatchEvent(new Event('change', { bubbles: true }));
  }, v);
  await waitForResult(page, n);
  return target;
}

/**
 * In the page: the canvas now (as the panel left it), the panel's full repaint, and a fresh
 * full answer of the same document painted in full on its own canvas; pixel differences
 * (any channel off by more than 2) between them, and whether the shapes equal the fresh ones.
 */
const compare = (page) => page.evaluate(async () => {
  const t = window.filigree.testHooks.tangle;
  const { prepareTangle, paintBatches } = await import('/www/tangle/draw.js');
  const { requestOf } = await import('/www/tangle/panel.js');
  const c = document.querySelector('[data-testid=tangle-canvas]');
  const g = c.getContext('2d');
  const timing = t.timing();
  const patched = g.getImageData(0, 0, c.width, c.height).data;
  t.paintNow();
  const full = g.getImageData(0, 0, c.width, c.height).data;
  // The same without the selected step's highlight, to compare with a fresh answer's picture.
  t.options.highlight = false;
  t.paintNow();
  const plain = g.getImageData(0, 0, c.width, c.height).data;
  t.options.highlight = true;
  t.paintNow();
  // A fresh answer: not kept by a worker, every shape traced anew.
  const doc = t.state();
  const fresh = await window.filigree.doc.current.ctx.run('tangle', requestOf(doc));
  const F = prepareTangle(fresh);
  const mine = t.result();
  const cols = ['key', 'tag', 'group', 'id', 'first', 'born', 'died', 'fill', 'flags', 'ringFirst', 'rings'];
  const sameShapes = mine.shapes.count === F.r.shapes.count
    && cols.every((k) => mine.shapes[k].length === F.r.shapes[k].length && mine.shapes[k].every((x, i) => Object.is(x, F.r.shapes[k][i])))
    && F.pts.length === window.filigree.testHooks.tangle.points().length && F.pts.every((x, i) => Object.is(x, window.filigree.testHooks.tangle.points()[i]))
    && JSON.stringify(mine.steps) === JSON.stringify(F.r.steps);
  const o = document.createElement('canvas');
  o.width = c.width;
  o.height = c.height;
  const og = o.getContext('2d');
  og.fillStyle = '#fff';
  og.fillRect(0, 0, o.width, o.height);
  const v = t.view();
  og.setTransform(v.dpr * v.s, 0, 0, v.dpr * v.s, v.dpr * v.tx, v.dpr * v.ty);
  const sw = doc.stroke_width;
  paintBatches(og, F.batches(t.step()), sw > 0 ? Math.max(sw, 0.5 / v.s) : 0);
  const freshPixels = og.getImageData(0, 0, o.width, o.height).data;
  const diff = (a, b, over) => {
    let n = 0;
    for (let p = 0; p < a.length; p += 4) {
      if (Math.abs(a[p] - b[p]) > over || Math.abs(a[p + 1] - b[p + 1]) > over || Math.abs(a[p + 2] - b[p + 2]) > over) n++;
    }
    return n;
  };
  return {
    answer: timing.answer, region: timing.region, reused: t.reused(), shapes: mine.shapes.count, sameShapes,
    patchedVsFull: diff(patched, full, 100), fullVsFresh: diff(plain, freshPixels, 100),
    antialiasing: [diff(patched, full, 2), diff(plain, freshPixels, 2)],
    pixels: c.width * c.height,
  };
});

test('tangle: an edit keeps the unchanged shapes and repaints only where it changed, exactly as a fresh answer painted in full', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => window.filigree?.testHooks?.tangle && Number(document.querySelector('[data-testid=tangle-status]').dataset.runs || 0) > 0, null, { timeout: 60000 });
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));

  // A drag: the same edit with another value replaces it (the worker replays the edits
  // on its unedited copy, so the regrown shapes get the same groups and ids as the
  // shown ones, with other points: none of them may keep its Path2D).
  await editDistance(page, 4, 120, null);
  let n = await runs(page);
  const before = await page.evaluate(() => window.filigree.testHooks.tangle.state().edits.length);
  // Until its answer arrives, an edit leaves the canvas as it is (the last picture and its
  // highlight): no repaint competes with the worker for the CPU. Every frame until the
  // answer is looked at, and the panel's paints are timed: none may fall between the input
  // and the answer (however fast the worker answers on this machine).
  const held = await page.$eval('[data-testid=tangle-param-distance]', async (i) => {
    const t = window.filigree.testHooks.tangle;
    const status = document.querySelector('[data-testid=tangle-status]');
    const runs = () => Number(status.dataset.runs);
    const n0 = runs();
    const t0 = performance.now();
    i.value = String(Number(i.value) * 0.5);
    i.dispatchEvent(new Event('input', { bubbles: true }));
    let frames = 0;
    while (runs() === n0 && performance.now() - t0 < 60000) {
      await new Promise((r) => requestAnimationFrame(r));
      frames++;
    }
    const tm = t.timing();
    return { answered: runs() > n0, frames, whileDue: tm.paints.filter((p) => p > t0 && p < tm.answeredAt).length };
  });
  assert.ok(held.answered, 'the edit was answered');
  assert.equal(held.whileDue, 0, `nothing was repainted while the answer was due (${held.frames} frames)`);
  n = await waitForResult(page, n);
  const first = await page.evaluate(() => window.filigree.testHooks.tangle.state().edits.at(-1).params.distance);
  await page.$eval('[data-testid=tangle-param-distance]', (i) => {
    i.value = String(Number(i.value) * 1.5);
    i.dispatchEvent(new Event('input', { bubbles: true }));
    i.dispatchEvent(new Event('change', { bubbles: true }));
  });
  await waitForResult(page, n);
  const st = await page.evaluate(() => window.filigree.testHooks.tangle.state());
  assert.equal(st.edits.length, before + 1, 'a drag is one edit');
  assert.notEqual(st.edits.at(-1).params.distance, first, 'the drag changed the value');
  let c = await compare(page);
  assert.ok(c.answer.delta, 'a drag is answered with a delta');
  assert.ok(c.reused < c.shapes, 'the regrown shapes did not keep their Path2Ds');
  console.log(`drag: repainted ${Math.round(c.region * 100)}% of the canvas, ${c.reused}/${c.shapes} shapes kept; anti-aliasing differences ${c.antialiasing}`);
  assert.ok(c.sameShapes, 'after a drag: the shapes equal a fresh full expansion\'s');
  assert.equal(c.patchedVsFull, 0, 'after a drag: what the panel painted equals a full repaint');
  assert.equal(c.fullVsFresh, 0, 'after a drag: the full repaint equals a fresh answer painted in full');

  // A small subtree: the repaint covers part of the canvas only.
  const [, size] = await editDistance(page, 4, 120, 11);
  c = await compare(page);
  console.log(`edit 1: subtree ${size} shapes, repainted ${Math.round(c.region * 100)}% of the canvas, ${c.reused}/${c.shapes} shapes kept; anti-aliasing differences ${c.antialiasing}`);
  assert.ok(c.sameShapes, 'the shapes equal a fresh full expansion\'s, column by column and point by point');
  assert.ok(c.reused > c.shapes / 2, `most shapes kept their Path2Ds (${c.reused} of ${c.shapes})`);
  assert.ok(c.region > 0 && c.region < 0.5, `the edit repainted part of the canvas only (${c.region}; subtree ${size} shapes)`);
  assert.equal(c.patchedVsFull, 0, 'the partial repaint equals a full repaint pixel for pixel');
  assert.ok(c.antialiasing[0] < 0.01 * c.pixels, `and differs from it at a few edge pixels only (${c.antialiasing[0]})`);
  assert.equal(c.fullVsFresh, 0, 'the full repaint equals a fresh answer painted in full ');

  // A second edit of a bigger subtree, and an undo (the worker replays from its unedited copy).
  await editDistance(page, 121, 2000, 7);
  c = await compare(page);
  console.log(`edit 2: repainted ${Math.round(c.region * 100)}% of the canvas, ${c.reused}/${c.shapes} shapes kept; anti-aliasing differences ${c.antialiasing}`);
  assert.ok(c.sameShapes, 'after a second edit: the shapes equal a fresh full expansion\'s');
  assert.equal(c.patchedVsFull, 0, 'after a second edit: what the panel painted equals a full repaint');
  assert.equal(c.fullVsFresh, 0, 'after a second edit: the full repaint equals a fresh answer painted in full');
  n = await runs(page);
  await page.click('[data-act=undo]');
  await waitForResult(page, n);
  c = await compare(page);
  assert.ok(c.answer.delta, 'an undo is answered with a delta');
  assert.ok(c.sameShapes, 'after an undo: the shapes equal a fresh full expansion\'s');
  assert.equal(c.patchedVsFull, 0, 'after an undo: what the panel painted equals a full repaint');
  assert.equal(c.fullVsFresh, 0, 'after an undo: the full repaint equals a fresh answer painted in full');
});

test('tangle: an edit is answered with a delta, which the page applies: its shapes and canvas equal a fresh full answer\'s', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => window.filigree?.testHooks?.tangle && Number(document.querySelector('[data-testid=tangle-status]').dataset.runs || 0) > 0, null, { timeout: 60000 });
  await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
  const first = await page.evaluate(() => window.filigree.testHooks.tangle.timing().answer);
  assert.equal(first.delta, false, 'the first answer is in full (nothing shown to apply a delta to)');
  const [, size] = await editDistance(page, 4, 120, 11);
  const c = await compare(page);
  console.log(`delta: ${c.answer.added} shapes added, ${c.answer.removed} removed of ${c.shapes}, ${c.answer.bytes} bytes (the full answer: ${first.bytes}); subtree ${size}`);
  assert.ok(c.answer.delta, 'the edit was answered with a delta');
  assert.ok(c.answer.added > 0 && c.answer.added < c.shapes / 4, `it adds few of the shapes (${c.answer.added} of ${c.shapes})`);
  assert.ok(c.answer.removed > 0, 'and removes the old subtree');
  assert.ok(c.answer.bytes < first.bytes / 2, `it is a small part of a full answer (${c.answer.bytes} of ${first.bytes} bytes)`);
  assert.ok(Array.isArray(c.answer.dirty) && c.answer.dirty.length === 4, 'it names its dirty box');
  assert.ok(c.sameShapes, 'the shapes after the delta equal a fresh full answer\'s, column by column and point by point');
  assert.equal(c.patchedVsFull, 0, 'the partial repaint equals a full repaint');
  assert.equal(c.fullVsFresh, 0, 'the canvas equals a fresh full answer painted in full');
});
