// SwiftShader frame times of Micro's WebGL2 sphere tracer (issue 12, the
// bench notes). Not a pass/fail test (micro-gl.test.mjs checks the pictures
// against the CPU): prints one JSON line, headless Chromium.
//
//   node tests/e2e/micro-gl.bench.mjs [root]
//
// Every shipped scene, fixed steps, the first of the test's views: the
// quickest of three 64² frames after the first (which compiles and warms
// up), the shader's compile time, the average steps per ray, and one 256²
// frame where the 64² frame took under 20 ms (a 256² frame costs ~16× a 64²
// one: tens of seconds in SwiftShader for the heavy scenes).
import { launch } from './harness.mjs';
import { compareAll, VIEWS } from './micro-gl-compare.mjs';

const SIDE = 64;
const root = process.argv[2] && process.argv[2] !== '-' ? process.argv[2] : undefined;
const env = await launch(root ? { root } : {});
try {
  const page = await env.newPage({ path: '#tool=micro' });
  const rows = await compareAll(page, { side: SIDE, steps: 'fixed', cameras: [VIEWS[0]], timed: 3, bigSide: 256 });
  const round = (x) => (x === null ? null : +x.toFixed(1));
  console.log(JSON.stringify({
    bench: 'micro-gl', renderer: 'SwiftShader (software WebGL2)', steps: 'fixed', view: VIEWS[0],
    note: `${SIDE}: best of 3 frames after the first; 256: one frame, timed only where the ${SIDE}² frame took under 20 ms (null: skipped)`,
    frame_ms: Object.fromEntries(rows.map((r) => [r.name, {
      [SIDE]: round(r.frameMs), 256: round(r.bigMs), compile: round(r.compileMs),
      steps_per_ray: +(r.glStats.steps / r.glStats.rays).toFixed(1),
    }])),
  }));
} finally {
  await env.close();
}
