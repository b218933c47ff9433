// Issue 37: a real repeating design (bench/designs/diagonal-stripes: drawn
// outside the team, its program written as a user would, the initial angle
// and spacing off the truth) fitted in the browser with the defaults, as a
// designer would: paste the program, drop the picture, press Run fit. The
// paper's GA ended at the angle's bound (stripes at ~28° instead of 45°,
// IoU 0.24); the default global stage (spectra, then a phase sweep) finds
// the right basin, and the status names the stage while it runs.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import fs from 'node:fs';
import path from 'node:path';
import { launch, ROOT } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

const design = (file) => fs.readFileSync(path.join(ROOT, 'bench/designs', file));

test('a real diagonal-stripes design fits with the defaults: the global stage finds the 45° basin', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await page.click('details.program summary');
  await page.fill('[data-testid=fit-program]', design('diagonal-stripes.flg').toString('utf8'));
  await page.click('button[data-act=apply-program]');
  await page.waitForFunction(() => window.filigree.testHooks.fit.info()?.params?.some((p) => p.name === 'spacing'));
  const [chooser] = await Promise.all([page.waitForEvent('filechooser'), page.click('.fit-target button.pick')]);
  await chooser.setFiles({ name: 'diagonal-stripes.png', mimeType: 'image/png', buffer: design('diagonal-stripes.png') });
  await page.waitForFunction(() => /snapped/.test(document.querySelector('[data-testid=fit-status]').textContent)
    || !document.querySelector('[data-testid=doc-error]').hidden);
  assert.equal(await page.isHidden('[data-testid=doc-error]'), true, await page.textContent('[data-testid=doc-error]'));
  // Every status the fit shows, to see the global stage named while it runs.
  await page.evaluate(() => {
    window.__statuses = [];
    const el = document.querySelector('[data-testid=fit-status]');
    new MutationObserver(() => window.__statuses.push(el.textContent)).observe(el, { childList: true, characterData: true, subtree: true });
  });
  await page.click('button[data-act=fit]');
  await page.waitForFunction(() => /^fitted/.test(document.querySelector('[data-testid=fit-status]').textContent)
    || !document.querySelector('[data-testid=doc-error]').hidden, null, { timeout: 120000 });
  assert.equal(await page.isHidden('[data-testid=doc-error]'), true, await page.textContent('[data-testid=doc-error]'));
  const statuses = await page.evaluate(() => window.__statuses);
  assert.ok(statuses.some((s) => /global search/.test(s)), `the status named the global stage: ${statuses.slice(0, 5)}`);
  // The loss plot shades the share of the fit the global stage took (it
  // has no loss of its own to plot), then plots the loss.
  const stage = await page.getAttribute('[data-testid=fit-plot]', 'data-stage');
  assert.match(stage ?? '', /^global search 0\.\d+$/, `the plot's stage: ${stage}`);
  const points = await page.evaluate(() => window.filigree.testHooks.fit.plot.points.length);
  assert.ok(points >= 5, `${points} loss points after the global stage`);
  const { values, params } = await page.evaluate(() => ({
    values: window.filigree.testHooks.fit.state().values,
    params: window.filigree.testHooks.fit.info().params,
  }));
  const fitted = Object.fromEntries(params.map((p, i) => [p.name, values[i]]));
  const truth = JSON.parse(design('diagonal-stripes.truth.json'));
  // What a failure needs to be read on another machine: the pool's size
  // (the fit is sharded over it) and the stages the fit went through.
  const seen = `(cores ${await page.evaluate(() => navigator.hardwareConcurrency)}; stages ${[...new Set(statuses.map((s) => s.replace(/ \d+%.*$/, '')))].join(' | ')})`;
  assert.ok(Math.abs(fitted.angle - truth.angle) < 0.02, `angle ${fitted.angle}, truth ${truth.angle} ${seen}`);
  assert.ok(Math.abs(fitted.spacing - truth.spacing) < 0.003, `spacing ${fitted.spacing}, truth ${truth.spacing} ${seen}`);
  assert.ok(Math.abs(fitted.width - truth.width) < 0.004, `width ${fitted.width}, truth ${truth.width} ${seen}`);
});
