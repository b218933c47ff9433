// Tangle's PNG export (issue 33, item 2): the rasteriser and the PNG encoder
// are a module of their own (`tangle-png`), fetched on the first PNG export,
// not when Tangle opens. The page sends it the final shapes of the answer it
// holds (www/tangle/export.js `drawingOf`), and the PNG it downloads is the
// native CLI's byte for byte (tests/golden/tangle-leaf-seed1-800.png.sha256:
// the SHA-256 and byte length of `filigree tangle --grammar
// assets/tangle/leaf.tangle --seed 1 --png-width 800 --out x.png`). The
// Tangle module itself refuses to draw a PNG.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import crypto from 'node:crypto';
import { launch, waitForTangle } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

test('tangle: the PNG export loads its own module on first use and gives the CLI\'s bytes', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  // The page fetches and compiles each module (www/app/client.js), so its
  // resource timings list every wasm fetched, in order.
  const modules = () => page.evaluate(() => performance.getEntriesByType('resource')
    .map((e) => /filigree_([\w-]+)_bg\.wasm/.exec(e.name)?.[1]).filter(Boolean));
  await waitForTangle(page, 0);
  assert.deepEqual(await modules(), ['tangle'], 'opening Tangle fetches the Tangle module only');
  const st = await page.evaluate(() => window.filigree.testHooks.tangle.state());
  assert.equal(st.example, 'leaf');
  assert.equal(st.seed, 1);

  await page.selectOption('[name=png-width]', '800');
  const [download] = await Promise.all([page.waitForEvent('download'), page.click('[data-act=export-png]')]);
  assert.match(download.suggestedFilename(), /^leaf-seed1\.png$/);
  const png = fs.readFileSync(await download.path());
  assert.deepEqual(await modules(), ['tangle', 'tangle-png'], 'the first PNG export fetches the tangle-png module');
  assert.equal(png.readUInt32BE(16), 800, 'the PNG is as wide as asked');
  const [hash, length] = fs.readFileSync(new URL('../golden/tangle-leaf-seed1-800.png.sha256', import.meta.url), 'utf8')
    .trim().split(/\s+/);
  assert.equal(png.length, Number(length), 'PNG length equals the native golden');
  assert.equal(crypto.createHash('sha256').update(png).digest('hex'), hash, 'the browser\'s PNG is byte for byte the native CLI\'s');

  // A second export reuses the module: no second download.
  const [again] = await Promise.all([page.waitForEvent('download'), page.click('[data-act=export-png]')]);
  assert.ok(fs.readFileSync(await again.path()).equals(png), 'the same document, the same PNG');
  assert.deepEqual(await modules(), ['tangle', 'tangle-png']);

  // The Tangle module draws no PNG: asked to, it says which module does.
  const refused = await page.evaluate(async () => {
    const { grammar } = window.filigree.testHooks.tangle.state();
    try {
      await window.filigree.pool.run('tangle', { grammar, seed: 1, export: 'png' });
      return null;
    } catch (err) {
      return { kind: err.kind, field: err.field, message: err.message };
    }
  });
  assert.equal(refused?.kind, 'unsupported', JSON.stringify(refused));
  assert.equal(refused.field, 'export');
  assert.match(refused.message, /tangle-png module/);
});

test('tangle: a broken drawing sent to the PNG module is refused, naming the field', async () => {
  const page = await env.newPage({ path: '#tool=tangle' });
  await waitForTangle(page, 0);
  const refused = await page.evaluate(async () => {
    // One square whose one ring claims five points.
    const f32 = (a) => new Uint8Array(new Float32Array(a).buffer);
    const u32 = (a) => new Uint8Array(new Uint32Array(a).buffer);
    try {
      await window.filigree.pool.run('tangle-png', {
        points: f32([0, 0, 10, 0, 10, 10, 0, 10]), rings: u32([5]), shapes: u32([1]), fill: f32([0]), flags: new Uint8Array([0]),
      });
      return null;
    } catch (err) {
      return { kind: err.kind, field: err.field };
    }
  });
  assert.deepEqual(refused, { kind: 'invalid-input', field: 'points' });
});
