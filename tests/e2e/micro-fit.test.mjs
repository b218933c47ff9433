// The Micro tool's "Reconstruct" section (issue 12 items 3, 7, 8): tick a
// number of the shipped gyroid (its sheet thickness), give it another
// target value, run a short
// reconstruction in the worker pool (`micro-fit`, sharded) and see the
// loss fall on the plot; apply the fitted value to the scene as one
// undoable change. And fit wasm = native: the shared fit requests give, in
// the worker, the native core's results to the bit.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { launch, ROOT } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const state = (page) => page.evaluate(() => window.filigree.testHooks.micro.state());

test('micro reconstruct: the loss falls, the fitted value is applied and undone', async () => {
  const page = await env.newPage({ path: '#tool=micro' });
  await page.waitForSelector('[data-testid=micro-examples] [data-example=gyroid]', { timeout: 30000 });
  await page.click('[data-example=gyroid]');
  await page.waitForFunction(() => window.filigree.testHooks.micro.state()?.example === 'gyroid');
  const scene0 = (await state(page)).scene;
  const thickness0 = JSON.parse(scene0).thickness;

  await page.click('[data-testid=micro-fit] > summary');
  // The rows list the scene's numbers by JSON pointer.
  await page.waitForSelector('[data-testid=micro-fit-params] [data-pointer="/period"]');
  const rows = await page.evaluate(() => window.filigree.testHooks['micro-fit'].rows());
  assert.deepEqual(rows.map((r) => r.pointer), ['/period', '/thickness']);
  // Fit the sheet's thickness to a target scene whose thickness is 0.2.
  const row = '[data-testid=micro-fit-params] [data-pointer="/thickness"]';
  await page.check(`${row} [name=fit-on]`);
  await page.fill(`${row} [name=fit-truth]`, '0.2');
  await page.fill(`${row} [name=fit-lo]`, '0.05');
  await page.fill(`${row} [name=fit-hi]`, '0.8');
  await page.selectOption('[data-testid=micro-fit-optimizer]', 'powell');
  await page.fill('[data-testid=micro-fit-budget]', '60');
  await page.click('[data-testid=micro-fit-run]');
  await page.waitForFunction(() => Number(document.querySelector('[data-testid=micro-fit-status]').dataset.fits || 0) >= 1,
    null, { timeout: 120000 });
  const st = await page.$eval('[data-testid=micro-fit-status]', (el) => ({ ...el.dataset, text: el.textContent }));
  assert.ok(Number(st.loss) < Number(st.initial) - 1, `the loss fell: ${st.initial} → ${st.loss} (${st.text})`);
  assert.match(st.text, /fitted in .* \/thickness = 0\.2/);
  assert.ok(await page.evaluate(() => window.filigree.testHooks['micro-fit'].plotted()) >= 2, 'the loss curve is drawn');
  const fitted = await page.evaluate(() => window.filigree.testHooks['micro-fit'].result());
  assert.ok(Math.abs(fitted.values[0] - 0.2) < 0.01, `thickness ${fitted.values[0]}`);
  assert.equal((await state(page)).scene, scene0, 'nothing changes before Apply');

  // Apply: one undoable change of the document.
  await page.click('[data-testid=micro-fit-apply]');
  await page.waitForFunction((s0) => window.filigree.testHooks.micro.state().scene !== s0, scene0);
  const applied = await state(page);
  assert.ok(Math.abs(JSON.parse(applied.scene).thickness - fitted.values[0]) < 1e-12);
  assert.equal(JSON.parse(applied.scene).period, JSON.parse(scene0).period);
  assert.equal(applied.example, null);
  await page.click('button[data-act=undo]');
  await page.waitForFunction((s0) => window.filigree.testHooks.micro.state().scene === s0, scene0);
  assert.equal(JSON.parse((await state(page)).scene).thickness, thickness0);

  // A bad range is the core's typed error, shown in the panel's error area.
  await page.check(`${row} [name=fit-on]`);
  await page.fill(`${row} [name=fit-lo]`, '0.9');
  await page.fill(`${row} [name=fit-hi]`, '0.1');
  await page.click('[data-testid=micro-fit-run]');
  await page.waitForSelector('[data-testid=doc-error]:not([hidden])', { timeout: 30000 });
  assert.match(await page.textContent('[data-testid=doc-error]'), /range .* is empty/);
  await page.context().close();
});

test('micro reconstruct: coarse to fine goes into the request and its fit lowers the paper loss', async () => {
  const page = await env.newPage({ path: '#tool=micro' });
  await page.waitForSelector('[data-testid=micro-examples] [data-example=gyroid]', { timeout: 30000 });
  await page.click('[data-example=gyroid]');
  await page.waitForFunction(() => window.filigree.testHooks.micro.state()?.example === 'gyroid');
  await page.click('[data-testid=micro-fit] > summary');
  await page.waitForSelector('[data-testid=micro-fit-params] [data-pointer="/period"]');
  // Off by default (the core's default), on when ticked.
  assert.equal(await page.isChecked('[data-testid=micro-fit-c2f]'), false);
  const row = '[data-testid=micro-fit-params] [data-pointer="/period"]';
  const period0 = JSON.parse((await state(page)).scene).period;
  await page.check(`${row} [name=fit-on]`);
  await page.fill(`${row} [name=fit-truth]`, String(period0 * 1.3));
  await page.fill(`${row} [name=fit-lo]`, String(period0 * 0.5));
  await page.fill(`${row} [name=fit-hi]`, String(period0 * 2));
  await page.check('[data-testid=micro-fit-c2f]');
  await page.fill('[data-testid=micro-fit-budget]', '90');
  const req = await page.evaluate(() => window.filigree.testHooks['micro-fit'].request());
  assert.equal(req.coarse_to_fine, true);
  await page.click('[data-testid=micro-fit-run]');
  await page.waitForFunction(() => Number(document.querySelector('[data-testid=micro-fit-status]').dataset.fits || 0) >= 1,
    null, { timeout: 120000 });
  const st = await page.$eval('[data-testid=micro-fit-status]', (el) => ({ ...el.dataset, text: el.textContent }));
  assert.ok(Number(st.loss) < Number(st.initial), `the paper loss fell: ${st.initial} → ${st.loss} (${st.text})`);
  await page.context().close();
});

/** JSON text with object keys sorted and `undefined` as null: equal text, equal numbers (bit for bit). */
const canon = (v) => JSON.stringify(v, (k, x) => {
  if (x === undefined) return null;
  if (ArrayBuffer.isView(x)) return Array.from(x);
  if (x && typeof x === 'object' && !Array.isArray(x)) return Object.fromEntries(Object.entries(x).sort(([a], [b]) => (a < b ? -1 : 1)));
  return x;
});

test('micro-fit: the wasm worker gives the native results bit for bit (fitted values, loss trace, validation)', async () => {
  const page = await env.newPage({ path: '#tool=micro' });
  await page.waitForFunction(() => window.filigree?.pool, null, { timeout: 30000 });
  const dir = path.join(ROOT, 'tests/fixtures/micro-native');
  const { fits } = JSON.parse(fs.readFileSync(path.join(dir, 'fits.json'), 'utf8'));
  assert.deepEqual([...new Set(fits.map((f) => f.request.optimizer))].sort(), ['cmaes', 'nelder-mead', 'powell']);
  for (const f of fits) {
    // The same canonical text in the page (the worker's numbers as they came).
    const got = await page.evaluate(async (req) => {
      const r = await window.filigree.pool.run('micro-fit', req);
      return JSON.stringify(r, (k, x) => {
        if (x === undefined) return null;
        if (ArrayBuffer.isView(x)) return Array.from(x);
        if (x && typeof x === 'object' && !Array.isArray(x)) return Object.fromEntries(Object.entries(x).sort(([a], [b]) => (a < b ? -1 : 1)));
        return x;
      });
    }, f.request);
    const want = JSON.parse(fs.readFileSync(path.join(dir, `${f.name}.json`), 'utf8'));
    assert.ok(want.history.length >= 2 && want.loss < want.initial_loss, `${f.name}: the fixture is a real fit`);
    assert.equal(got, canon(want), `${f.name}: wasm result equals the native core's`);
  }
  await page.context().close();
});
