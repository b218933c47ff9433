// Every view fits a phone (issue 35 item 2): at 390×844 nothing is wider
// than the window, both when a view is opened at that width and after the
// window narrows from a desktop's 1280×800 (a phone turned, a window
// resized). The program editors stay inside their cards: long lines scroll
// inside the editor, never the page.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const PHONE = { width: 390, height: 844 };
const DESKTOP = { width: 1280, height: 800 };
// What "shown" means per view: its example's picture (or its controls) is there.
const READY = {
  home: () => document.querySelectorAll('.home-preview[data-ready]').length === 6,
  pixel: () => Number(document.querySelector('[data-testid=pixel-status]')?.dataset.runs) > 0,
  fit: () => !!document.querySelector('[data-testid=fit-sliders] input'),
  inspect: () => !!document.querySelector('[data-testid=drop-zone] button'),
  tangle: () => Number(document.querySelector('[data-testid=tangle-status]')?.dataset.runs) > 0 && !!document.querySelector('.tangle-editor .cm-content'),
  // (Micro's picture sits in a box of fixed aspect: its layout is there before the first, slow, picture.)
  micro: () => !!document.querySelector('[data-testid=micro-examples] button') && !!document.querySelector('.micro-editor .cm-content'),
  texture: () => !!document.querySelector('[data-testid=texture-retrieved][data-model]') && !window.filigree?.testHooks?.texture?.pending(),
};
const VIEWS = Object.keys(READY);

/** What sticks out of the window: the page's scroll width, and visible elements past the right edge
 * that no box within the window scrolls or clips; each editor that is wider than its card. */
const overflow = () => {
  const w = innerWidth;
  const past = [];
  for (const e of document.querySelectorAll('body *')) {
    if (!e.getClientRects().length) continue;
    const r = e.getBoundingClientRect();
    if (!r.width || r.right <= w + 1) continue;
    let held = false;
    for (let a = e.parentElement; a && a !== document.body; a = a.parentElement) {
      if (getComputedStyle(a).overflowX !== 'visible' && a.getBoundingClientRect().right <= w + 1) { held = true; break; }
    }
    if (!held) past.push(`${e.tagName.toLowerCase()}${e.className && typeof e.className === 'string' ? `.${e.className.trim().split(/\s+/).join('.')}` : ''} → ${Math.round(r.right)} px`);
  }
  const editors = [...document.querySelectorAll('.code-editor')].filter((c) => c.getClientRects().length).map((c) => {
    const card = c.closest('.card').getBoundingClientRect();
    const ed = (c.querySelector('.cm-editor') || c.firstElementChild).getBoundingClientRect();
    return { inCard: ed.left >= card.left - 0.5 && ed.right <= card.right + 0.5, wrapperScrolls: c.scrollWidth > c.clientWidth + 1 };
  });
  return { scrollWidth: document.documentElement.scrollWidth, bodyWidth: document.body.scrollWidth, width: w, past: past.slice(0, 6), editors };
};

function check(o, what) {
  // A phone's browser widens its layout viewport to content that is too wide (and zooms out):
  // the window must still be the phone's 390 px.
  assert.equal(o.width, PHONE.width, `${what}: the layout viewport grew to ${o.width} px (content too wide)`);
  assert.ok(o.scrollWidth <= o.width && o.bodyWidth <= o.width, `${what}: the page is ${o.scrollWidth} px wide in a ${o.width} px window (${o.past.join('; ')})`);
  assert.deepEqual(o.past, [], `${what}: elements past the right edge`);
  for (const [i, e] of o.editors.entries()) {
    assert.ok(e.inCard, `${what}: editor ${i} inside its card`);
    assert.equal(e.wrapperScrolls, false, `${what}: editor ${i} scrolls inside itself, not in a wider box`);
  }
}

/** Open `view` in `page` as a person does: a tab of the header (the brand for home). */
async function show(page, view) {
  if (view === 'home') await page.click('a.brand');
  else await page.click(`#tools button[data-tool=${view}]`);
  await page.waitForFunction(READY[view], null, { timeout: 60000 });
}

/** Fit's program editor open, as a person opens it. */
async function openFitProgram(page) {
  await page.click('[data-act=show-program]');
  await page.waitForSelector('.fit-editor .code-editor .cm-content');
  await page.waitForTimeout(100);
}

// One page for both ways, so the second showing of a tool finds its module compiled and its
// examples fetched: each view is opened at 1280×800 and the window narrowed, then it is left
// and opened again at 390.
test('phone 390×844: every view fits, narrowed from 1280×800 and opened at 390 (Fit with its program editor open)', async () => {
  const page = await env.newPage({ path: null, viewport: DESKTOP });
  await page.goto(env.url);
  for (const view of VIEWS) {
    await page.setViewportSize(DESKTOP);
    await show(page, view);
    if (view === 'fit') await openFitProgram(page);
    await page.setViewportSize(PHONE);
    // Two frames: the layout and any ResizeObserver have run.
    await page.evaluate(() => new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r))));
    check(await page.evaluate(overflow), `${view} narrowed to 390`);
    // Leave it and open it again at 390.
    await show(page, view === 'home' ? 'inspect' : 'home');
    await show(page, view);
    check(await page.evaluate(overflow), `${view} opened at 390`);
    if (view === 'fit') {
      await openFitProgram(page);
      check(await page.evaluate(overflow), 'fit opened at 390 with the program open');
    }
  }
});
