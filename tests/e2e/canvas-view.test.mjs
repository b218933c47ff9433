// www/pixel/canvas-view.js: a brush drag on a big image repaints one small
// rectangle per frame (one putImageData), does no layout work on pointermove,
// maps pointers to image pixels at any zoom, and paints within a frame.
// Prints the input-to-paint latency medians for 1024² and 4096² images.
import { test, before, after, afterEach } from 'node:test';
import assert from 'node:assert/strict';
import { launch } from './harness.mjs';

let env;
before(async () => { env = await launch(); });
afterEach(() => env?.closeTestPages());
after(async () => { await env?.close(); });

async function brushDrag(page, size) {
  await page.evaluate(async (size) => {
    const { CanvasView } = await import('./www/pixel/canvas-view.js');
    document.getElementById('cv-test')?.remove();
    const box = document.createElement('div');
    box.id = 'cv-test';
    box.style.cssText = 'position:fixed;left:0;top:0;width:800px;height:600px;z-index:99;background:#000';
    document.body.append(box);
    const img = new ImageData(size, size);
    for (let i = 0; i < img.data.length; i += 4) { img.data[i] = (i >> 2) % 251; img.data[i + 1] = (i >> 10) % 241; img.data[i + 2] = 90; img.data[i + 3] = 255; }
    const bitmap = await createImageBitmap(img);
    const mask = { width: size, height: size, bits: new Uint8Array(size * size) };
    const stats = { frames: [], lat: [], layoutReads: 0, moving: false };
    const view = new CanvasView(box, { reserve: 0, onPaint: () => {} });
    view.showMask = true;
    view.setImage(bitmap, size, size);
    view.setMask(mask);
    await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
    // Spies: overlay uploads per frame, layout reads during pointermove.
    const put = view.overlayCtx.putImageData.bind(view.overlayCtx);
    let frame = null;
    view.overlayCtx.putImageData = (...a) => { frame?.push([a[0].width, a[0].height]); put(...a); };
    const paint = view.paint.bind(view);
    view.paint = () => { frame = []; paint(); stats.frames.push(frame); frame = null; };
    const gbcr = Element.prototype.getBoundingClientRect;
    Element.prototype.getBoundingClientRect = function (...a) { if (stats.moving) stats.layoutReads++; return gbcr.apply(this, a); };
    // Let the set-up's own full repaint (first resize observation) pass before the drag.
    await new Promise((r) => setTimeout(r, 100));
    await new Promise((r) => requestAnimationFrame(() => requestAnimationFrame(r)));
    stats.frames.length = 0;
    const R = 6;
    const dab = (e) => {
      const [x, y] = view.toImage(e);
      for (let j = Math.floor(y - R); j <= y + R; j++) {
        for (let i = Math.floor(x - R); i <= x + R; i++) if (i >= 0 && j >= 0 && i < size && j < size && Math.hypot(i - x, j - y) <= R) mask.bits[j * size + i] = 1;
      }
      view.maskChanged({ x: x - R - 1, y: y - R - 1, w: 2 * R + 2, h: 2 * R + 2 });
      // Input → paint: the frame that paints this change is done when the
      // next animation frame callback after it has run and yielded.
      const t0 = e.timeStamp;
      requestAnimationFrame(() => setTimeout(() => stats.lat.push(performance.now() - t0), 0));
    };
    let down = false;
    view.element.addEventListener('pointerdown', (e) => { down = true; dab(e); });
    view.element.addEventListener('pointermove', (e) => {
      if (!down) return;
      stats.moving = true;
      dab(e);
      stats.moving = false;
    });
    view.element.addEventListener('pointerup', () => { down = false; });
    const rl = view.relayout.bind(view);
    view.relayout = () => { stats.relayouts = (stats.relayouts || 0) + 1; rl(); };
    window.cvTest = { view, stats, mask };
  }, size);
  const box = await page.locator('#cv-test .canvas-view').boundingBox();
  await page.mouse.move(box.x + box.width * 0.2, box.y + box.height * 0.3);
  await page.mouse.down();
  for (let i = 1; i <= 60; i++) {
    await page.mouse.move(box.x + box.width * (0.2 + i * 0.01), box.y + box.height * (0.3 + 0.3 * Math.sin(i / 10)));
    await page.waitForTimeout(8);
  }
  await page.mouse.up();
  await page.waitForTimeout(200);
  return page.evaluate(() => {
    const { view, stats, mask } = window.cvTest;
    const lat = [...stats.lat].sort((a, b) => a - b);
    // The overlay really shows the painted mask: as many screen pixels as the mask covers, zoomed.
    const o = view.overlayCtx.getImageData(0, 0, view.overlay.width, view.overlay.height).data;
    let shown = 0;
    for (let i = 3; i < o.length; i += 4) if (o[i]) shown++;
    const painted = mask.bits.reduce((a, b) => a + b, 0);
    return {
      zoom: view.zoom,
      frames: stats.frames.length,
      maxPutsPerFrame: Math.max(...stats.frames.map((f) => f.length)),
      maxRect: Math.max(...stats.frames.flat().map(([w, h]) => w * h)),
      overlayPixels: view.overlay.width * view.overlay.height, relayouts: stats.relayouts, sizes: stats.frames.map((f) => f.map(([w, h]) => w * h)).flat().slice(0, 12),
      layoutReads: stats.layoutReads,
      median: lat[lat.length >> 1], p90: lat[Math.floor(lat.length * 0.9)], samples: lat.length,
      shown, expected: painted * view.zoom * view.zoom,
    };
  });
}

test('canvas view: a brush drag repaints one small rectangle per frame, no layout on pointermove (1024² and 4096²)', async () => {
  const page = await env.newPage({ path: '#tool=inspect' });
  const results = {};
  await brushDrag(page, 256); // warm-up: compile the code paths, create the GPU layers
  for (const size of [1024, 4096]) {
    const r = await brushDrag(page, size);
    results[size] = r;
    assert.ok(r.frames >= 5, `${size}: painted in ${r.frames} frames`);
    assert.equal(r.maxPutsPerFrame, 1, `${size}: one putImageData per frame`);
    // Frames coalesce a few moves; far below the full layer.
    assert.ok(r.maxRect < r.overlayPixels / 50, `${size}: dirty rectangle ${r.maxRect} of ${r.overlayPixels} px ${JSON.stringify([r.relayouts, r.sizes])}`);
    assert.equal(r.layoutReads, 0, `${size}: no layout reads on pointermove`);
    assert.ok(Math.abs(r.shown - r.expected) < 0.1 * r.expected, `${size}: painted mask visible in the overlay (${r.shown} px shown, ${Math.round(r.expected)} expected)`);
    assert.ok(r.zoom < 1, `${size}: fit zoom shows the whole image (${r.zoom})`);
  }
  console.log(JSON.stringify({
    bench: 'canvas-view brush drag', input_to_paint_ms: Object.fromEntries(Object.entries(results).map(([k, r]) => [k, { median: +r.median.toFixed(1), p90: +r.p90.toFixed(1), samples: r.samples }])),
  }));
});

test('canvas view: pointer mapping and integer zoom', async () => {
  const page = await env.newPage({ path: '#tool=inspect' });
  const r = await page.evaluate(async () => {
    const { CanvasView } = await import('./www/pixel/canvas-view.js');
    const box = document.createElement('div');
    box.style.cssText = 'position:fixed;left:10px;top:20px;width:700px;height:500px;z-index:99';
    document.body.append(box);
    const view = new CanvasView(box, { integer: true, reserve: 0 });
    view.setImage(new ImageData(128, 64), 128, 64);
    const fit = view.zoom; // floor(min(700/128, (innerHeight-20)/64)) = 5
    const rect = view.element.getBoundingClientRect();
    const p = view.toImage({ clientX: rect.left + 5 * 10.5, clientY: rect.top + 5 * 3.25 });
    view.setZoom(8);
    const z8 = [view.zoom, view.element.getBoundingClientRect().width];
    view.setZoom('fit');
    return { fit, p, z8, back: view.zoom, rendering: getComputedStyle(view.base).imageRendering };
  });
  assert.equal(r.fit, 5);
  assert.deepEqual(r.p.map((v) => +v.toFixed(3)), [10.5, 3.25]);
  assert.deepEqual(r.z8, [8, 1024]);
  assert.equal(r.back, 5);
  assert.equal(r.rendering, 'pixelated');
});
