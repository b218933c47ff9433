// A limit a program meets at a statement (too many shapes, a loop that never
// ends) is marked under that statement's line, from the error's `line` and
// `column` fields: the page reads no place out of the message text.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

test('fit: a shape limit met at line 3 is marked under line 3, from the error\'s place', async () => {
  const page = await env.newPage({ path: '#tool=fit' });
  await page.waitForFunction(() => !!document.querySelector('[data-testid=fit-sliders] input'));
  await page.click('button[data-act=show-program]');
  await page.waitForSelector('.fit-editor .code-editor .cm-content');
  await page.fill('[data-testid=fit-program]',
    'param a in [0.1, 0.2] = 0.15;\n// two\nfor k in 0..100000 { circle(0.5, 0.5, a, fill: "#000000"); }\n// four\n');
  await page.click('button[data-act=apply-program]');
  await page.waitForSelector('.fit-editor .cm-inline-error', { timeout: 30000 });
  const at = await page.evaluate(() => {
    const msg = document.querySelector('.fit-editor .cm-inline-error');
    const third = [...document.querySelectorAll('.fit-editor .cm-line')][2].getBoundingClientRect();
    return { text: msg.textContent, gap: msg.getBoundingClientRect().top - third.bottom };
  });
  assert.match(at.text, /line 3, column \d+: more than \d+ shapes/);
  assert.ok(Math.abs(at.gap) < 4, `under line 3 (gap ${at.gap} px)`);
});
