// A new build is offered, not forced: the waiting service worker takes over
// only when the person clicks the offer, and then the new files are served.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import os from 'node:os';
import path from 'node:path';
import { execFileSync } from 'node:child_process';
import { launch, ROOT } from './harness.mjs';

let env;
let root;
before(async () => {
  // Serve a copy of the built app so the test can "deploy" a new version.
  root = fs.mkdtempSync(path.join(os.tmpdir(), 'filigree-update-'));
  for (const name of ['index.html', 'sw.js', 'www', 'pkg', 'assets', 'scripts']) {
    fs.cpSync(path.join(ROOT, name), path.join(root, name), { recursive: true });
  }
  env = await launch({ root });
});
afterEach(() => env?.closeTestPages());
after(async () => {
  await env?.close();
  fs.rmSync(root, { recursive: true, force: true });
});

test('a new version is offered and applied only when accepted', async () => {
  const page = await env.newPage({ path: '#tool=inspect', serviceWorkers: 'allow' });
  await page.evaluate(async () => {
    await navigator.serviceWorker.ready;
    if (!navigator.serviceWorker.controller) {
      await new Promise((r) => navigator.serviceWorker.addEventListener('controllerchange', r, { once: true }));
    }
  });
  const oldCache = await page.evaluate(async () => (await caches.keys()).find((k) => k.startsWith('filigree-')));

  // Deploy: change a shipped file and regenerate the precache manifest.
  fs.appendFileSync(path.join(root, 'www/styles.css'), '\n/* new build */ .brand { letter-spacing: .03em; }\n');
  execFileSync('node', [path.join(root, 'scripts/precache.mjs')]);

  await page.evaluate(async () => (await navigator.serviceWorker.getRegistration()).update());
  await page.waitForSelector('.toast button:text("Reload to update")', { timeout: 30000 });
  // Not forced: the old worker still controls the page until the offer is taken.
  const stillOld = await page.evaluate(() => fetch('www/styles.css').then((r) => r.text()));
  assert.ok(!stillOld.includes('new build'), 'the page keeps its version until the user accepts');

  await Promise.all([page.waitForEvent('load'), page.click('.toast button:text("Reload to update")')]);
  await page.waitForFunction(() => document.documentElement.dataset.coreReady === '1');
  const css = await page.evaluate(() => fetch('www/styles.css').then((r) => r.text()));
  assert.ok(css.includes('new build'), 'after the update the new files are served');
  const caches2 = await page.evaluate(async () => (await caches.keys()).filter((k) => k.startsWith('filigree-')));
  assert.equal(caches2.length, 1, 'the old cache was removed');
  assert.notEqual(caches2[0], oldCache);
});
