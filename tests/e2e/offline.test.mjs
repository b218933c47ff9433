import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch, dropFile, fixture } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

test('after one visit the app loads and inspects offline', async () => {
  const page = await env.newPage({ path: '#tool=inspect', serviceWorkers: 'allow' });
  // Wait until the service worker controls the page (first install claims clients).
  await page.evaluate(async () => {
    await navigator.serviceWorker.ready;
    if (!navigator.serviceWorker.controller) {
      await new Promise((r) => navigator.serviceWorker.addEventListener('controllerchange', r, { once: true }));
    }
  });
  // Really offline: the server is gone and the browser is told so.
  await new Promise((r) => env.server.close(r));
  env.server.closeAllConnections?.();
  await page.context().setOffline(true);
  await page.reload();
  await page.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
  await dropFile(page, '[data-testid=drop-zone]', fixture('fish.png'));
  await page.waitForSelector('[data-testid=palette] li');
  assert.equal(await page.textContent('[data-field=size]'), '128 × 128 px');
  env.server.listen(0); // let after() close it cleanly
});
