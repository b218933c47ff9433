// Jobs belong to the document, not the panel (issue 35 item 4): a fit keeps
// running when the user opens another tool, the tool bar shows its
// progress, and it is there when they come back; Stop keeps the best
// values so far for "Apply fitted values"; a fit ended by a change says
// it was cancelled and why.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch, pickGenerator } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const STATUS = '[data-testid=fit-status]';
const BADGE = '[data-testid=tool-job-fit]';
const fitState = (page) => page.evaluate(() => window.filigree.testHooks.fit.state());

/** Fit with a target made from `generator`'s values moved off it, budget `budget`, Run fit pressed. */
async function startFit(page, budget, generator = 'stripes') {
  await pickGenerator(page, generator);
  await page.click('button[data-act=make-target]');
  await page.waitForFunction(() => window.filigree.testHooks.fit.state().truth !== null);
  await page.focus('[data-testid=fit-sliders] input');
  for (let i = 0; i < 60; i++) await page.keyboard.press('ArrowRight');
  await page.selectOption('select[name=budget]', budget);
  await page.waitForFunction((b) => window.filigree.testHooks.fit.state().settings.budget === b, budget);
  await page.click('button[data-act=fit]');
  await page.waitForFunction(() => window.filigree.testHooks.fit.running());
}

// The tool bar's buttons are clicked without waiting for the page to paint
// two frames in a row (Playwright's "stable" check): with every core busy
// with a fit, headless Chromium's software compositor may paint none for
// seconds, while the page itself answers at once.
async function openTool(page, id) {
  await page.click(`#tools button[data-tool=${id}]`, { force: true });
  await page.waitForFunction((t) => document.documentElement.dataset.view === t && window.filigree.testHooks[t], id, { polling: 50 });
}

test('a fit runs on in another tool, with its progress in the tool bar; back in Fit, Stop keeps the best so far and Apply puts it in', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  // Spades at the paper budget: about 18 s here, its Adam stage (with a best so far) from about 8 s.
  await startFit(page, 'paper', 'spades');
  const before = (await fitState(page)).values;

  // Off to Tangle: the fit goes on; the Fit button in the tool bar says how far.
  await openTool(page, 'tangle');
  await page.waitForSelector(BADGE);
  const pct = async () => Number(/(\d+)%/.exec(await page.textContent(BADGE))?.[1] ?? NaN);
  const first = await pct();
  assert.ok(Number.isFinite(first), await page.textContent(BADGE));
  await page.waitForFunction(([sel, p]) => {
    const m = /(\d+)%/.exec(document.querySelector(sel)?.textContent ?? '');
    return m && Number(m[1]) > p;
  }, [BADGE, first], { timeout: 30000, polling: 100 });
  assert.match(await page.getAttribute(BADGE, 'title'), /^Fit: .*\d+%$/);

  // Back in Fit: the same fit, still running, its status there.
  await openTool(page, 'fit');
  assert.equal(await page.evaluate(() => window.filigree.testHooks.fit.running()), true, 'the fit is still running');
  await page.waitForFunction((s) => / \d+% — loss /.test(document.querySelector(s).textContent), STATUS, { polling: 100 });
  assert.ok(await page.$eval('.fit-run progress', (p) => p.value) > 0);
  assert.equal(await page.isEnabled('button[data-act=cancel]'), true);

  // Stop, pressed the moment there is a best candidate (from inside the page: a busy
  // machine may finish the fit while a driven click waits): the values stay, the best
  // so far waits for Apply.
  await page.evaluate(async () => {
    for (let i = 0; i < 600 && !window.filigree.testHooks.fit.job()?.best; i++) await new Promise((r) => setTimeout(r, 50));
    document.querySelector('button[data-act=cancel]').click();
  });
  await page.waitForFunction((s) => /^stopped at \d+% — .*Apply fitted values puts in the best so far \(loss [\d.e+-]+\)/.test(document.querySelector(s).textContent), STATUS);
  assert.ok(await page.evaluate(() => window.filigree.testHooks.fit.plot.points.length) >= 1, 'the loss plot');
  assert.deepEqual((await fitState(page)).values, before, 'Stop changed nothing yet');
  assert.equal(await page.isEnabled('[data-testid=fit-apply]'), true, 'Apply fitted values is enabled after Stop');
  const best = await page.evaluate(() => window.filigree.testHooks.fit.job().best);
  await page.click('[data-testid=fit-apply]');
  await page.waitForFunction((v) => JSON.stringify(window.filigree.testHooks.fit.state().values) === JSON.stringify(v), best.values);
  const s = await fitState(page);
  assert.equal(s.result.loss, best.loss);
  assert.match(await page.textContent(STATUS), /^applied/);
  assert.equal(await page.isDisabled('[data-testid=fit-apply]'), true, 'applied once');
  assert.equal(await page.isVisible(BADGE), false, 'the tool bar has nothing more to say');
  // One undo puts the values from before back.
  await page.click('button[data-act=undo]');
  assert.deepEqual((await fitState(page)).values, before);
  await page.close();
});

test('a fit that ends while the user is in another tool is in the document when they come back', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await startFit(page, 'quick');
  const before = (await fitState(page)).values;
  await openTool(page, 'micro');
  await page.waitForFunction((sel) => document.querySelector(sel)?.textContent === 'done', BADGE, { timeout: 60000, polling: 100 });
  await openTool(page, 'fit');
  const s = await fitState(page);
  assert.ok(s.result && Number.isFinite(s.result.loss), 'the fit\'s result is in the document');
  assert.notDeepEqual(s.values, before, 'its values too');
  assert.match(await page.textContent(STATUS), /^fitted in [\d.]+ s — loss/);
  assert.ok(await page.evaluate(() => window.filigree.testHooks.fit.plot.points.length) > 1);
  assert.equal(await page.isVisible(BADGE), false, 'seen: the tool bar is quiet again');
  // It is one undoable step, and autosaved like any change.
  await page.click('button[data-act=undo]');
  assert.deepEqual((await fitState(page)).values, before);
  await page.close();
});

test('a fit cut short by a change of generator says it was cancelled, and why', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await startFit(page, 'paper');
  await page.selectOption('[data-testid=fit-generator]', 'honeycomb');
  await page.waitForFunction((s) => /^cancelled at \d+% \(the generator changed\) — the values from before the fit are kept/.test(document.querySelector(s).textContent), STATUS);
  assert.equal(await page.evaluate(() => window.filigree.testHooks.fit.running()), false);
  await page.close();
});

test('Micro: a reconstruction runs on in another tool and comes back with its form as left; Stop keeps the best for Apply', async () => {
  const page = await env.newPage({ path: '#tool=micro' });
  await page.waitForSelector('[data-testid=micro-examples] [data-example=gyroid]', { timeout: 30000 });
  await page.click('[data-example=gyroid]');
  await page.waitForFunction(() => window.filigree.testHooks.micro.state()?.example === 'gyroid');
  const scene0 = await page.evaluate(() => window.filigree.testHooks.micro.state().scene);
  await page.click('[data-testid=micro-fit] > summary');
  const row = '[data-testid=micro-fit-params] [data-pointer="/thickness"]';
  await page.waitForSelector(row);
  await page.check(`${row} [name=fit-on]`);
  await page.fill(`${row} [name=fit-truth]`, '0.2');
  await page.fill(`${row} [name=fit-lo]`, '0.05');
  await page.fill(`${row} [name=fit-hi]`, '0.8');
  await page.selectOption('[data-testid=micro-fit-optimizer]', 'powell');
  await page.fill('[data-testid=micro-fit-budget]', '5000'); // long: it is stopped below
  await page.click('[data-testid=micro-fit-run]');
  await page.waitForFunction(() => /loss -?\d/.test(document.querySelector('[data-testid=micro-fit-status]').textContent), null, { timeout: 60000 });

  // In Fit, the Micro button shows the reconstruction's progress.
  await openTool(page, 'fit');
  const badge = '[data-testid=tool-job-micro]';
  await page.waitForSelector(badge);
  assert.match(await page.textContent(badge), /^\d+%$/);
  assert.match(await page.getAttribute(badge, 'title'), /^Reconstruct: /);

  // Back in Micro: open, ticked, the same target and ranges, still running.
  await openTool(page, 'micro');
  await page.waitForSelector(`${row} [name=fit-on]:checked`);
  assert.equal(await page.$eval('[data-testid=micro-fit]', (d) => d.open), true, 'Reconstruct is open as it was left');
  assert.equal(await page.inputValue(`${row} [name=fit-truth]`), '0.2');
  assert.equal(await page.inputValue(`${row} [name=fit-hi]`), '0.8');
  assert.equal(await page.inputValue('[data-testid=micro-fit-budget]'), '5000');
  assert.equal(await page.evaluate(() => window.filigree.testHooks['micro-fit'].running()), true);
  await page.waitForFunction(() => window.filigree.testHooks['micro-fit'].job()?.best);
  assert.ok(await page.evaluate(() => window.filigree.testHooks['micro-fit'].plotted()) >= 1, 'the loss plot came back');

  await page.click('[data-testid=micro-fit-stop]', { force: true }); // (see openTool)
  await page.waitForFunction(() => /^stopped at \d+% — Apply fitted values puts in the best so far: \/thickness = /.test(document.querySelector('[data-testid=micro-fit-status]').textContent));
  assert.equal(await page.isEnabled('[data-testid=micro-fit-apply]'), true, 'Apply fitted values is enabled after Stop');
  const best = await page.evaluate(() => window.filigree.testHooks['micro-fit'].job().best);
  await page.click('[data-testid=micro-fit-apply]');
  await page.waitForFunction((s0) => window.filigree.testHooks.micro.state().scene !== s0, scene0);
  const applied = JSON.parse(await page.evaluate(() => window.filigree.testHooks.micro.state().scene));
  assert.equal(applied.thickness, best.values[0]);
  assert.equal(applied.period, JSON.parse(scene0).period);
  await page.close();
});

test('Tangle: a long growth goes on in another tool, shown in the tool bar, and its drawing is there on coming back, grown once', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await page.waitForFunction(() => window.filigree?.testHooks?.tangle && Number(document.querySelector('[data-testid=tangle-status]').dataset.runs || 0) > 0, null, { timeout: 60000 });
  // 2,500 cells outlined and stippled, 44,000 shapes: about as long a growth as the shape budget allows.
  const grammar = 'start rect(2000, 2000) : board\nregularSplit(line, 40, 1) : board -> [cells]\noutline(4) : cells -> [inner, frame]\nstippling(dots, 8, 1.5) : inner -> [dotted, dot]\n';
  await page.evaluate((g) => {
    const pool = window.filigree.pool;
    const run = pool.run.bind(pool);
    window.grown = 0;
    pool.run = (kind, payload, opts) => { if (kind === 'tangle' && payload.grammar === g) window.grown++; return run(kind, payload, opts); };
  }, grammar);
  // The document arrives as a link would bring it; while it grows, the user opens Fit
  // (clicked from inside the page the moment the growth starts: once answered, the
  // drawing takes the main thread for a while).
  await page.evaluate(async (g) => {
    await window.filigree.openState('tangle', { ...window.filigree.testHooks.tangle.state(), grammar: g, example: null, edits: [], selected: null });
    const growing = () => window.filigree.doc.jobsOf('tangle').get('grow')?.data.doc?.grammar === g;
    for (let i = 0; i < 300 && !growing(); i++) await new Promise((r) => setTimeout(r, 10));
    document.querySelector('#tools button[data-tool=fit]').click();
  }, grammar);
  await page.waitForFunction(() => document.documentElement.dataset.view === 'fit' && window.filigree.testHooks.fit);
  assert.equal(await page.evaluate(() => window.filigree.doc.jobsOf('tangle').get('grow').running), true, 'still growing in Fit');
  const badge = '[data-testid=tool-job-tangle]';
  await page.waitForSelector(badge);
  assert.match(await page.getAttribute(badge, 'title'), /^Tangle: /);
  await page.waitForFunction((sel) => document.querySelector(sel)?.textContent === 'done', badge, { timeout: 60000, polling: 100 });

  await openTool(page, 'tangle');
  await page.waitForFunction(() => !window.filigree.testHooks.tangle.pending() && window.filigree.testHooks.tangle.result()?.stats.shapes > 40000, null, { timeout: 30000 });
  assert.match(await page.textContent('[data-testid=tangle-status]'), /[\d,]+ shapes/);
  assert.equal(await page.evaluate(() => window.grown), 1, 'grown once: coming back took the answer');
  assert.equal(await page.isVisible(badge), false);
  await page.close();
});
