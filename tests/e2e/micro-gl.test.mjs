// Micro's WebGL2 sphere tracer (issue 12 item 7, MISSION M7) against the
// CPU reference: every shipped scene is rendered both ways in Chromium's
// SwiftShader — `micro-glsl` compiled by www/micro/gl.js and `micro-render`
// in a worker — from the same request, and the pictures must agree: at most
// MAX_HIT_MISS of the pixels may disagree on hit or miss, the mean absolute
// difference over all channels is at most MAX_MEAN levels of 255, and the
// summed work counters (steps per ray) stay within 10% of the CPU's. The
// test prints the average steps per ray; SwiftShader's frame times are
// micro-gl.bench.mjs's.
//
// Then the panel: the interactive view runs on the GPU (coarse frames while
// the camera moves, refined to full size when idle), and without WebGL2 it
// says so in plain words and draws on the CPU.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch } from './harness.mjs';
import { compareAll, VIEWS } from './micro-gl-compare.mjs';

const MAX_HIT_MISS = 0.02;
const MAX_MEAN = 4;
const SIDE = 64;

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

test('micro-gl: every shipped scene on the GPU agrees with the CPU reference (fixed steps, two views)', async () => {
  const page = await env.newPage({ path: '#tool=micro' });
  const rows = await compareAll(page, { side: SIDE, steps: 'fixed', cameras: VIEWS });
  assert.ok(rows.length >= 2 * 6, `${rows.length} renders`);
  for (const r of rows) {
    const steps = { cpu: r.cpuStats.steps / r.cpuStats.rays, gl: r.glStats.steps / r.glStats.rays };
    console.log(`[micro-gl] ${r.name} d=${r.camera.distance}: hit/miss ${(r.hitMiss * 100).toFixed(2)}%, mean |Δ| ${r.mean.toFixed(2)}, `
      + `coverage ${(r.cpuHitFraction * 100).toFixed(1)}%, steps/ray cpu ${steps.cpu.toFixed(1)} gpu ${steps.gl.toFixed(1)}, `
      + `${r.functions} functions, ${r.fragmentBytes} bytes of GLSL`);
    assert.ok(r.hitMiss <= MAX_HIT_MISS, `${r.name}: ${(r.hitMiss * 100).toFixed(2)}% of pixels disagree on hit or miss`);
    assert.ok(r.mean <= MAX_MEAN, `${r.name}: mean absolute difference ${r.mean.toFixed(2)}`);
    assert.equal(r.glStats.rays, SIDE * SIDE);
    assert.ok(Math.abs(r.glStats.hits - r.cpuStats.hits) <= MAX_HIT_MISS * SIDE * SIDE, `${r.name}: hits ${r.glStats.hits} vs ${r.cpuStats.hits}`);
    assert.ok(Math.abs(steps.gl - steps.cpu) <= 0.1 * steps.cpu + 0.5, `${r.name}: steps per ray ${steps.gl} vs ${steps.cpu}`);
  }
  // The comparison is not vacuous: the scenes cover a good part of the pictures.
  assert.ok(rows.filter((r) => r.cpuHitFraction > 0.2).length >= rows.length / 2);
  await page.context().close();
});

// One scene per step mode and shading here (every scene with fixed steps
// above): the shader's step loops are the same code for every scene, and
// every scene's generated GLSL is checked natively (src/micro/glsl.rs tests).
// Adaptive on gyroid: its rays are long enough at 64² for gradient checks
// (from step N = 10 on; piled's rays end within a few steps).
test('micro-gl: adaptive and bisection steps, GGX shading and absorption agree with the CPU too', async () => {
  const page = await env.newPage({ path: '#tool=micro' });
  const ggx = { shading: 'ggx', roughness: 0.3, specular: 0.04, absorption: 0.8 };
  for (const [steps, extra, only] of [['adaptive', {}, ['gyroid']], ['bisection', {}, ['spheres']], ['fixed', ggx, ['gyroid']]]) {
    const rows = await compareAll(page, { side: 64, steps, cameras: [VIEWS[0]], extra, only });
    assert.equal(rows.length, 1, `${only}: one scene`);
    for (const r of rows) {
      console.log(`[micro-gl] ${steps}${extra.shading ? ' ggx' : ''} ${r.name}: hit/miss ${(r.hitMiss * 100).toFixed(2)}%, mean |Δ| ${r.mean.toFixed(2)}, `
        + `gradient checks cpu ${r.cpuStats.gradient_checks} gpu ${r.glStats.gradient_checks}`);
      assert.ok(r.hitMiss <= MAX_HIT_MISS, `${steps} ${r.name}: ${(r.hitMiss * 100).toFixed(2)}% hit/miss`);
      assert.ok(r.mean <= MAX_MEAN, `${steps} ${r.name}: mean ${r.mean.toFixed(2)}`);
      if (steps === 'adaptive') assert.ok(r.glStats.gradient_checks > 0);
    }
  }
  await page.context().close();
});

const runs = (page) => page.$eval('[data-testid=micro-status]', (el) => Number(el.dataset.runs || 0));
async function waitForRender(page, previous, timeout = 120000) {
  await page.waitForFunction((prev) => Number(document.querySelector('[data-testid=micro-status]').dataset.runs || 0) > prev
    && !window.filigree.testHooks.micro.pending(), previous, { timeout });
  return runs(page);
}

test('micro-gl: the panel orbits on the GPU, coarse first then refined; the slice stays on the CPU', async () => {
  // Half the device pixels: a quarter of the pixels to refine in SwiftShader.
  const page = await env.newPage({ path: '#tool=micro', deviceScaleFactor: 0.5 });
  await page.waitForSelector('[data-testid=micro-examples] [data-example=gyroid]', { timeout: 30000 });
  let n = await waitForRender(page, 0);
  assert.ok(await page.evaluate(() => window.filigree.testHooks.micro.gpu()), 'WebGL2 is used');
  assert.equal(await page.isHidden('[data-testid=micro-gpu-note]'), true);
  let last = await page.evaluate(() => window.filigree.testHooks.micro.last());
  assert.equal(last.gpu, true);
  assert.equal(last.preview, false);
  assert.match(await page.textContent('[data-testid=micro-status]'), /on the GPU.*rays hit.*per ray.*field evaluations/);
  // Drag: coarse frames while the camera moves, then the full picture.
  const previews0 = Number(await page.$eval('[data-testid=micro-status]', (el) => el.dataset.previews || 0));
  const box = await page.locator('[data-testid=micro-canvas]').boundingBox();
  const cx = box.x + box.width / 2, cy = box.y + box.height / 2;
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  for (let i = 1; i <= 6; i++) {
    await page.mouse.move(cx + i * 10, cy + i * 4);
    await page.waitForTimeout(40);
  }
  await page.mouse.up();
  n = await waitForRender(page, n);
  const previews = Number(await page.$eval('[data-testid=micro-status]', (el) => el.dataset.previews || 0));
  assert.ok(previews > previews0, 'coarse frames while dragging');
  last = await page.evaluate(() => window.filigree.testHooks.micro.last());
  assert.equal(last.gpu, true);
  assert.equal(last.preview, false, 'refined to full size once the camera rests');
  const fg = await page.evaluate(() => {
    const c = document.querySelector('[data-testid=micro-canvas]');
    const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;
    let k = 0;
    for (let i = 0; i < d.length; i += 4) if (Math.abs(d[i] - 24) + Math.abs(d[i + 1] - 26) + Math.abs(d[i + 2] - 30) > 6) k++;
    return k / (d.length / 4);
  });
  assert.ok(fg > 0.2, `the gyroid is drawn (${fg})`);
  assert.equal(await page.isHidden('[data-testid=micro-cpu-note]'), true);
  // A fast GPU draws its "coarse" frame at full size: that frame is the final
  // picture and must carry its counters (it once had none and threw).
  const errors = [];
  page.on('pageerror', (e) => errors.push(e.message));
  await page.evaluate(() => window.filigree.testHooks.micro.gpuPreviewDiv(1));
  await page.mouse.move(cx, cy);
  await page.mouse.wheel(0, -120);
  n = await waitForRender(page, n);
  last = await page.evaluate(() => window.filigree.testHooks.micro.last());
  assert.deepEqual(errors, []);
  assert.equal(last.gpu, true);
  assert.equal(last.preview, false);
  assert.equal(last.stats.rays, last.width * last.height, 'counters of the full-size frame');
  assert.match(await page.textContent('[data-testid=micro-status]'), /on the GPU.*rays hit/);
  // Path tracing is the CPU's: the panel says so; back to direct shading, the GPU again.
  await page.selectOption('[data-testid=micro-spp]', '4');
  n = await waitForRender(page, n);
  last = await page.evaluate(() => window.filigree.testHooks.micro.last());
  assert.equal(last.gpu, false);
  assert.equal(last.passes, 3);
  assert.match(await page.textContent('[data-testid=micro-cpu-note]'), /Drawn on the CPU.*path tracing runs on the CPU only/);
  await page.selectOption('[data-testid=micro-spp]', '0');
  n = await waitForRender(page, n);
  assert.equal((await page.evaluate(() => window.filigree.testHooks.micro.last())).gpu, true);
  // The slice view is the CPU's.
  await page.check('[data-testid=micro-slice-toggle]');
  n = await waitForRender(page, n);
  last = await page.evaluate(() => window.filigree.testHooks.micro.last());
  assert.equal(last.kind, 'micro-slice');
  assert.equal(last.gpu, false);
  await page.context().close();
});

test('micro-gl: without WebGL2 the panel says so and draws on the CPU', async () => {
  const page = await env.newPage({ path: null, deviceScaleFactor: 0.5 });
  await page.addInitScript(() => {
    const get = HTMLCanvasElement.prototype.getContext;
    HTMLCanvasElement.prototype.getContext = function (type, ...rest) {
      return type === 'webgl2' ? null : get.call(this, type, ...rest);
    };
  });
  await page.goto(`${env.url}#tool=micro`);
  await page.waitForFunction(() => document.documentElement.dataset.coreReady === '1', null, { timeout: 30000 });
  await page.waitForSelector('[data-testid=micro-examples] [data-example=gyroid]', { timeout: 30000 });
  await waitForRender(page, 0);
  assert.equal(await page.evaluate(() => window.filigree.testHooks.micro.gpu()), null);
  const note = await page.textContent('[data-testid=micro-gpu-note]');
  assert.match(note, /GPU view off: this browser has no WebGL2.*CPU/);
  assert.equal(await page.isVisible('[data-testid=micro-gpu-note]'), true);
  const last = await page.evaluate(() => window.filigree.testHooks.micro.last());
  assert.equal(last.gpu, false);
  assert.equal(last.kind, 'micro-render');
  assert.match(await page.textContent('[data-testid=micro-status]'), /rays hit.*field evaluations/);
  await page.context().close();
});
