// Screenshots of the home view and every panel at 1280×800 (desktop) and
// 390×844 (touch phone) in headless Chromium, for looking at layouts and for
// docs/. Also prints each view's horizontal overflow (scrollWidth vs width).
//   node scripts/screenshots.mjs [out-dir]   (default tests/e2e/artifacts/screens)
import fs from 'node:fs';
import path from 'node:path';
import { launch, ROOT } from '../tests/e2e/harness.mjs';

const out = path.resolve(process.argv[2] || path.join(ROOT, 'tests/e2e/artifacts/screens'));
fs.mkdirSync(out, { recursive: true });
const SIZES = {
  desktop: { viewport: { width: 1280, height: 800 } },
  phone: { viewport: { width: 390, height: 844 }, isMobile: true, hasTouch: true, deviceScaleFactor: 2 },
};
const VIEWS = ['', '#tool=pixel', '#tool=fit', '#tool=inspect', '#tool=tangle', '#tool=micro', '#tool=texture'];
// What "ready" means per view: the example's result is on screen.
const READY = {
  '': () => document.querySelectorAll('.home-preview[data-ready]').length === 6,
  '#tool=pixel': () => document.querySelector('[data-testid=pixel-status]')?.dataset.runs,
  '#tool=fit': () => document.querySelector('[data-testid=fit-sliders] input'),
  '#tool=inspect': () => document.querySelector('[data-testid=drop-zone]'),
  '#tool=tangle': () => Number(document.querySelector('[data-testid=tangle-status]')?.dataset.runs) > 0,
  '#tool=micro': () => Number(document.querySelector('[data-testid=micro-status]')?.dataset.runs) > 0,
  '#tool=texture': () => !!document.querySelector('[data-testid=texture-retrieved][data-model]') && !window.filigree?.testHooks?.texture?.pending(),
};

const env = await launch();
try {
  for (const [size, opts] of Object.entries(SIZES)) {
    for (const view of VIEWS) {
      const page = await env.newPage({ path: view, ...opts });
      await page.waitForFunction(READY[view], null, { timeout: 90000 }).catch(() => console.warn(`${size} ${view}: not ready`));
      await page.waitForTimeout(600);
      const name = `${size}-${view.replace('#tool=', '') || 'home'}.png`;
      await page.screenshot({ path: path.join(out, name) });
      const o = await page.evaluate(() => ({ scroll: document.documentElement.scrollWidth, width: innerWidth, height: document.documentElement.scrollHeight }));
      console.log(`${name}: scrollWidth ${o.scroll} / ${o.width}, page height ${o.height}`);
      await page.context().close();
    }
  }
} finally {
  await env.close();
}
