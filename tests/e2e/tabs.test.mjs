// Two tabs of the app on the same document (issue 35 item 5): a save in one
// tab is announced in the other (BroadcastChannel), which offers Reload or
// Keep mine; a tab never writes over the other's newer save without the
// user choosing so (each autosave carries a revision, checked in the same
// transaction as the write).
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch, ready } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const BAR = '[data-testid=doc-tabs]';
const values = (p) => p.evaluate(() => window.filigree.testHooks.fit.state().values);

/** What the tabs' shared autosave of Fit holds: {rev, values}. */
const stored = (p) => p.evaluate(() => new Promise((resolve, reject) => {
  const r = indexedDB.open('filigree');
  r.onerror = () => reject(r.error);
  r.onsuccess = () => {
    const db = r.result;
    const get = db.transaction('autosave', 'readonly').objectStore('autosave').get('fit');
    get.onsuccess = () => { db.close(); resolve(get.result ? { rev: get.result.rev, values: get.result.state.values } : null); };
    get.onerror = () => reject(get.error);
  };
}));

const same = (x, y) => JSON.stringify(x) === JSON.stringify(y);

/** The stored autosave once `ok(stored)` holds (10 s at most). */
async function until(page, ok) {
  let s = await stored(page);
  for (let i = 0; i < 100 && !ok(s); i++) { await page.waitForTimeout(100); s = await stored(page); }
  return s;
}

/** Move the slider of parameter `name` with the keyboard, as a person does. */
async function nudge(page, name, presses = 5) {
  await page.focus(`[data-testid=fit-sliders] .row[data-param=${name}] input`);
  for (let i = 0; i < presses; i++) await page.keyboard.press('ArrowRight');
}

async function fitTab(page) {
  await page.goto(`${env.url}#tool=fit`);
  await ready(page, '#tool=fit');
  await page.waitForSelector('[data-testid=fit-sliders] .row');
  return page;
}

test('two tabs: a save in one is offered to the other, which never overwrites it silently', async () => {
  const a = await fitTab(await env.newPage({ path: null }));
  const b = await fitTab(await a.context().newPage());
  const start = await values(a);
  assert.deepEqual(await values(b), start);

  // Tab A moves dx; its autosave lands and tab B hears of it at once.
  await nudge(a, 'dx');
  const mine = await values(a);
  assert.notDeepEqual(mine, start);
  const saved = await until(a, (s) => same(s?.values, mine));
  assert.deepEqual(saved?.values, mine, 'A\'s change was autosaved');
  await b.waitForSelector(`${BAR}:not([hidden])`, { timeout: 5000 });
  assert.match(await b.textContent(BAR), /Fit document was changed in another tab/);
  assert.equal(await a.isHidden(BAR), true, 'the tab that saved has no bar');

  // Tab B, not having chosen, moves dy: its change is held, not written over A's.
  await nudge(b, 'dy');
  const theirs = await values(b);
  assert.equal(theirs[1] !== start[1], true, 'dy moved in B');
  await b.waitForTimeout(1200); // past the autosave's debounce
  assert.deepEqual(await stored(a), saved, 'B did not overwrite A\'s newer save');
  assert.match(await b.textContent(BAR), /Your changes here are not saved until you choose/);

  // The case: reloading A shows A's change, not B's.
  await fitTab(a);
  assert.deepEqual(await values(a), mine, 'A\'s change survived its reload');

  // B keeps its own: now that is stored, and A is told.
  await b.click(`${BAR} button:text("Keep mine")`);
  await b.waitForSelector(`${BAR}[hidden]`, { state: 'attached' });
  const s = await until(a, (x) => same(x?.values, theirs));
  assert.deepEqual(s.values, theirs, 'Keep mine wrote B\'s version');
  assert.ok(s.rev > saved.rev, `revision ${saved.rev} → ${s.rev}`);
  await a.waitForSelector(`${BAR}:not([hidden])`, { timeout: 5000 });

  // A reloads B's version; the bar goes; Undo brings A's own back.
  await a.click(`${BAR} button:text("Reload")`);
  await a.waitForFunction((v) => JSON.stringify(window.filigree.testHooks.fit.state().values) === JSON.stringify(v), theirs);
  assert.equal(await a.isHidden(BAR), true);
  await a.waitForTimeout(800);
  assert.equal((await stored(a)).rev, s.rev, 'taking the other tab\'s version writes nothing');
  await a.click('button[data-act=undo]');
  assert.deepEqual(await values(a), mine, 'Undo brings A\'s version back');
  // …and that is an ordinary change of A, saved over what A last read; B hears of it.
  await b.waitForSelector(`${BAR}:not([hidden])`, { timeout: 5000 });
  await b.close();
  await a.close();
});

// A slow disk (a CI machine under load, a phone): a write that commits after
// the storage timeout is not a refusal. The page says it cannot save while
// the write is out, then takes that back; the other tab hears of the save.
// (Before, the late commit went unrecorded: no broadcast, and the tab stayed
// "blocked", dropping every later change.)
test('a save that commits after the storage timeout still counts: the other tab hears of it, and saving goes on', async () => {
  const a = await env.newPage({ path: null });
  // Each readwrite transaction of this tab commits `__slowWrites` ms late, as
  // on a slow disk: it is kept open by reads until then, so it also holds
  // back the next transaction on the store.
  await a.addInitScript(() => {
    const open = IDBDatabase.prototype.transaction;
    IDBDatabase.prototype.transaction = function (...args) {
      const tx = open.apply(this, args);
      const delay = window.__slowWrites;
      if (args[1] === 'readwrite' && delay) {
        const store = tx.objectStore(Array.isArray(args[0]) ? args[0][0] : args[0]);
        const end = Date.now() + delay;
        const hold = () => { if (Date.now() < end) store.count().onsuccess = hold; };
        hold();
      }
      return tx;
    };
  });
  await fitTab(a);
  const b = await fitTab(await a.context().newPage());
  const NOTE = '[data-testid=doc-note]';

  await a.evaluate(() => { window.__slowWrites = 2500; }); // past STORAGE_TIMEOUT_MS (1.5 s)
  await nudge(a, 'dx');
  await a.waitForSelector(`${NOTE}:not([hidden])`, { timeout: 5000 });
  assert.match(await a.textContent(NOTE), /cannot save your work here/);
  // A second change while the first write is still out: its write runs after
  // the first commits, and A does not take its own save for another tab's.
  await nudge(a, 'dy');
  const mine = await values(a);
  // The write lands: B is told, and A takes back what it said.
  await b.waitForSelector(`${BAR}:not([hidden])`, { timeout: 8000 });
  await a.waitForSelector(`${NOTE}[hidden]`, { state: 'attached', timeout: 5000 });
  const landed = await until(a, (x) => same(x?.values, mine));
  assert.deepEqual(landed?.values, mine, 'both changes were written, the later last');
  assert.equal(await a.isHidden(BAR), true, 'A was not told its own save came from another tab');

  // Saving goes on: A's next change (at normal speed) is written too.
  await a.evaluate(() => { window.__slowWrites = 0; });
  await nudge(a, 'dx');
  const next = await values(a);
  assert.notDeepEqual(next, mine);
  const s = await until(a, (x) => same(x?.values, next));
  assert.deepEqual(s?.values, next, 'the change after the slow one was autosaved');
  await b.close();
  await a.close();
});
