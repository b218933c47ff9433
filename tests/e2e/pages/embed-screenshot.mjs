import { chromium } from 'playwright-core';
// The README's docs/embed.png: a Pixel embed (the fish, read-only) on the
// third-party test page. Run: node tests/e2e/pages/embed-screenshot.mjs
import path from 'node:path';
import { fileURLToPath } from 'node:url';
import { start } from '../../../scripts/serve.mjs';
const HERE = path.dirname(fileURLToPath(import.meta.url));
const app = await start(0); const host = await start(0, HERE);
const url = `http://localhost:${app.address().port}/`;
const b = await chromium.launch({ executablePath: '/usr/bin/chromium', args: ['--headless=new','--no-sandbox','--enable-unsafe-swiftshader','--use-angle=swiftshader'] });
const ctx = await b.newContext({ viewport: { width: 1100, height: 1000 } });
const p = await ctx.newPage();
p.on('console', m => m.type() === 'error' && console.log('[console]', m.text()));
const tool = 'pixel';
await p.goto(url + '#tool=' + tool);
await p.waitForFunction(() => document.documentElement.dataset.coreReady === '1');
await p.waitForTimeout(4000);
const { fragment } = await p.evaluate(() => window.filigree.currentShare());
console.log('fragment length', fragment.length);
const page = await ctx.newPage();
const q = new URLSearchParams({ app: url, state: fragment, title: 'Texturing the fish', height: '700', heading: 'Texturing pixel art with oriented scales', intro: 'Strokes drawn along the body orient the scales; the palette is the drawing\'s own. Move the density or the seed in Filigree to see other textures.' });
await page.goto(`http://127.0.0.1:${host.address().port}/host.html?${q}`);
const f = await (await page.waitForSelector('filigree-embed iframe')).contentFrame();
await f.waitForFunction(() => document.documentElement.dataset.embedReady === '1', null, { timeout: 30000 });
await page.waitForTimeout(5000);
await page.screenshot({ path: path.join(HERE, '../../../docs/embed.png'), clip: { x: 0, y: 0, width: 1100, height: 910 } });
await b.close(); app.close(); host.close();
