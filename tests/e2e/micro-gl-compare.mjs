// Micro's WebGL2 sphere tracer against the CPU reference, in the page:
// every shipped scene rendered both ways from the same request (the
// comparison micro-gl.test.mjs asserts on, and the frames
// micro-gl.bench.mjs times).

/**
 * In the page: render every shipped scene (or those named in `only`) both
 * ways, return the comparison per scene and camera. The GPU draws each
 * picture once; with `timed` > 0 it then draws it `timed` more times and
 * `frameMs` is the quickest (the first draw compiles and warms up), and with
 * `bigSide` the first view once more at that size (`bigMs`, one frame).
 */
export async function compareAll(page, { side, steps, cameras, extra = {}, only = null, timed = 0, bigSide = 0 }) {
  return page.evaluate(async ({ side, steps, cameras, extra, only, timed, bigSide }) => {
    const { MicroGl } = await import('/www/micro/gl.js');
    const pool = window.filigree.pool;
    const examples = await pool.run('micro-examples', {});
    const gl = new MicroGl();
    const decode = async (png) => {
      const bmp = await createImageBitmap(new Blob([png], { type: 'image/png' }));
      const c = new OffscreenCanvas(bmp.width, bmp.height);
      const g = c.getContext('2d');
      g.drawImage(bmp, 0, 0);
      return g.getImageData(0, 0, bmp.width, bmp.height).data;
    };
    const out = [];
    for (const ex of examples.filter((e) => !only || only.includes(e.name))) {
      for (const camera of cameras) {
        const req = { scene: ex.scene, width: side, height: side, steps, camera, ...extra };
        const [shader, cpu] = await Promise.all([pool.run('micro-glsl', req), pool.run('micro-render', req)]);
        const t0 = performance.now();
        gl.use(shader);
        const compileMs = performance.now() - t0;
        const last = gl.draw(camera, side, side, { stats: true });
        const times = [];
        for (let i = 0; i < timed; i++) {
          const t = performance.now();
          gl.draw(camera, side, side, { stats: true });
          times.push(performance.now() - t);
        }
        // The first view once more at bigSide (one frame, no warm-up: the
        // shader is compiled), for the frame-time summary; only where the
        // small frame was quick (a 256² frame costs ~16× a 64² one: tens of
        // seconds in SwiftShader for the heavy scenes, too long for CI).
        let bigMs = null;
        if (bigSide && camera === cameras[0] && times.length && Math.min(...times) < 20) {
          const t = performance.now();
          gl.draw(camera, bigSide, bigSide);
          bigMs = performance.now() - t;
        }
        const a = await decode(cpu.png);
        const b = last.rgba;
        const bg = extra.background || [24, 26, 30];
        const isBg = (d, i) => d[i] === bg[0] && d[i + 1] === bg[1] && d[i + 2] === bg[2];
        let hitMiss = 0, sum = 0, cpuHits = 0;
        for (let i = 0; i < a.length; i += 4) {
          if (isBg(a, i) !== isBg(b, i)) hitMiss++;
          if (!isBg(a, i)) cpuHits++;
          sum += Math.abs(a[i] - b[i]) + Math.abs(a[i + 1] - b[i + 1]) + Math.abs(a[i + 2] - b[i + 2]);
        }
        const n = a.length / 4;
        out.push({
          name: ex.name, camera, functions: shader.functions, fragmentBytes: shader.fragment.length,
          hitMiss: hitMiss / n, mean: sum / (3 * n), cpuHitFraction: cpuHits / n,
          cpuStats: cpu.stats, glStats: last.stats,
          compileMs, frameMs: times.length ? Math.min(...times) : null, bigMs,
        });
      }
    }
    return out;
  }, { side, steps, cameras, extra, only, timed, bigSide });
}

export const VIEWS = [
  { yaw: 35, pitch: 28, distance: 3.6, target: [0, 0, 0], fov: 40 },
  { yaw: 200, pitch: -15, distance: 0.9, target: [0.1, 0.2, 0.3], fov: 40 },
];
