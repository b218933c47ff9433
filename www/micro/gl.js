// Micro's interactive view on the GPU (issue 12, MISSION M7): the core
// generates a WebGL2 fragment-shader sphere tracer from the same compiled
// scene it traces on the CPU (`micro-glsl`, src/micro/glsl.rs); this module
// compiles it and draws it. The CPU path (`micro-render`) stays the
// reference and makes every export.
//
// Every draw goes into an offscreen framebuffer with two targets: the
// picture (RGBA8) and per-pixel work counters (RGBA32UI: steps along the
// ray, field evaluations, hit | out-of-steps << 1, gradient checks). The
// panel reads the pixels back and paints them on its own 2-D canvas, so the
// GPU and CPU pictures reach the page the same way.
//
// Precision: the shader computes in 32-bit floats. `usable(camera)` says
// whether a view is within what 32 bits resolve: a pixel's footprint at the
// target must stay above 1e-6 of the scene's size (|target| + bounds);
// deeper zooms go to the CPU.

export const MIN_FOOTPRINT = 1e-6;

const rad = (d) => (d * Math.PI) / 180;
const sub = (a, b) => [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
const cross = (a, b) => [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]];
const norm = (a) => Math.hypot(a[0], a[1], a[2]);
const unit = (a) => { const l = norm(a); return [a[0] / l, a[1] / l, a[2] / l]; };

/** The orbit camera's rays, as src/micro/render.rs `Rays::new` builds them. */
export function cameraBasis(c) {
  const yaw = rad(c.yaw), pitch = rad(c.pitch);
  const fov = c.fov ?? 40;
  const dir = [Math.cos(pitch) * Math.cos(yaw), Math.cos(pitch) * Math.sin(yaw), Math.sin(pitch)];
  const target = c.target || [0, 0, 0];
  const origin = [target[0] + dir[0] * c.distance, target[1] + dir[1] * c.distance, target[2] + dir[2] * c.distance];
  const forward = [-dir[0], -dir[1], -dir[2]];
  let right = cross(forward, [0, 0, 1]);
  if (norm(right) < 1e-9) right = [1, 0, 0];
  right = unit(right);
  const up = cross(right, forward);
  return { origin, forward, right, up, tanHalf: Math.tan(rad(fov) * 0.5) };
}

/** Whether 32-bit floats resolve this view (else use the CPU). */
export function usable(camera, height, bounds = 1) {
  const { tanHalf } = cameraBasis(camera);
  const footprint = camera.distance * (2 * tanHalf / height);
  const size = norm(camera.target || [0, 0, 0]) + bounds;
  return footprint >= MIN_FOOTPRINT * size;
}

/** Why WebGL2 cannot be used here, or null. */
export function unavailable() {
  try {
    const c = document.createElement('canvas');
    const gl = c.getContext('webgl2');
    if (!gl) return 'this browser has no WebGL2';
    gl.getExtension('WEBGL_lose_context')?.loseContext();
    return null;
  } catch (e) {
    return `WebGL2 failed to start (${e.message})`;
  }
}

function compile(gl, type, source) {
  const s = gl.createShader(type);
  gl.shaderSource(s, source);
  gl.compileShader(s);
  if (!gl.getShaderParameter(s, gl.COMPILE_STATUS)) {
    const log = gl.getShaderInfoLog(s) || 'no log';
    gl.deleteShader(s);
    throw new Error(`the GPU could not compile the scene's shader: ${log.trim().split('\n').slice(0, 4).join(' ')}`);
  }
  return s;
}

/** A WebGL2 renderer of one generated shader at a time. */
export class MicroGl {
  /** A renderer, or throws with a message a person can read. */
  constructor() {
    this.canvas = document.createElement('canvas');
    this.canvas.width = 1;
    this.canvas.height = 1;
    const gl = this.canvas.getContext('webgl2', { antialias: false, depth: false, stencil: false, alpha: false, preserveDrawingBuffer: false });
    if (!gl) throw new Error('this browser has no WebGL2');
    this.gl = gl;
    this.program = null;
    this.source = null;
    this.vao = gl.createVertexArray();
    this.targets = new Map(); // "w×h" → {fb, color, stats}
    this.lost = false;
    this.canvas.addEventListener('webglcontextlost', (e) => { e.preventDefault(); this.lost = true; });
  }

  /** Compile and link a `micro-glsl` response (cached by its text). Throws on failure. */
  use({ vertex, fragment }) {
    if (this.lost) throw new Error('the GPU context was lost');
    if (this.source === fragment && this.program) return;
    const gl = this.gl;
    const vs = compile(gl, gl.VERTEX_SHADER, vertex);
    const fs = compile(gl, gl.FRAGMENT_SHADER, fragment);
    const p = gl.createProgram();
    gl.attachShader(p, vs);
    gl.attachShader(p, fs);
    gl.linkProgram(p);
    gl.deleteShader(vs);
    gl.deleteShader(fs);
    if (!gl.getProgramParameter(p, gl.LINK_STATUS)) {
      const log = gl.getProgramInfoLog(p) || 'no log';
      gl.deleteProgram(p);
      throw new Error(`the GPU could not link the scene's shader: ${log.trim().slice(0, 300)}`);
    }
    if (this.program) gl.deleteProgram(this.program);
    this.program = p;
    this.source = fragment;
    this.loc = Object.fromEntries(['u_origin', 'u_forward', 'u_right', 'u_up', 'u_tan_half', 'u_res']
      .map((n) => [n, gl.getUniformLocation(p, n)]));
  }

  target(w, h) {
    const key = `${w}x${h}`;
    let t = this.targets.get(key);
    if (t) return t;
    const gl = this.gl;
    if (this.targets.size > 6) {
      for (const old of this.targets.values()) {
        gl.deleteFramebuffer(old.fb); gl.deleteTexture(old.color); gl.deleteTexture(old.stats);
      }
      this.targets.clear();
    }
    const tex = (internal, format, type) => {
      const x = gl.createTexture();
      gl.bindTexture(gl.TEXTURE_2D, x);
      gl.texImage2D(gl.TEXTURE_2D, 0, internal, w, h, 0, format, type, null);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MIN_FILTER, gl.NEAREST);
      gl.texParameteri(gl.TEXTURE_2D, gl.TEXTURE_MAG_FILTER, gl.NEAREST);
      return x;
    };
    const color = tex(gl.RGBA8, gl.RGBA, gl.UNSIGNED_BYTE);
    const stats = tex(gl.RGBA32UI, gl.RGBA_INTEGER, gl.UNSIGNED_INT);
    const fb = gl.createFramebuffer();
    gl.bindFramebuffer(gl.FRAMEBUFFER, fb);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT0, gl.TEXTURE_2D, color, 0);
    gl.framebufferTexture2D(gl.FRAMEBUFFER, gl.COLOR_ATTACHMENT1, gl.TEXTURE_2D, stats, 0);
    gl.drawBuffers([gl.COLOR_ATTACHMENT0, gl.COLOR_ATTACHMENT1]);
    const status = gl.checkFramebufferStatus(gl.FRAMEBUFFER);
    if (status !== gl.FRAMEBUFFER_COMPLETE) throw new Error(`the GPU cannot render to a ${w}×${h} target (status ${status})`);
    t = { fb, color, stats, w, h };
    this.targets.set(key, t);
    return t;
  }

  /**
   * Trace rows [y0, y1) (top-down) of a w×h picture of `camera`; returns
   * those rows' RGBA bytes, top-down. With `stats`, also their counters.
   */
  draw(camera, w, h, { y0 = 0, y1 = h, stats = false } = {}) {
    if (!this.program) throw new Error('no shader');
    const gl = this.gl;
    const t = this.target(w, h);
    const b = cameraBasis(camera);
    gl.bindFramebuffer(gl.FRAMEBUFFER, t.fb);
    gl.viewport(0, 0, w, h);
    // GL rows count from the bottom.
    const gy0 = h - y1, rows = y1 - y0;
    gl.enable(gl.SCISSOR_TEST);
    gl.scissor(0, gy0, w, rows);
    gl.useProgram(this.program);
    gl.uniform3fv(this.loc.u_origin, b.origin);
    gl.uniform3fv(this.loc.u_forward, b.forward);
    gl.uniform3fv(this.loc.u_right, b.right);
    gl.uniform3fv(this.loc.u_up, b.up);
    gl.uniform1f(this.loc.u_tan_half, b.tanHalf);
    gl.uniform2f(this.loc.u_res, w, h);
    gl.bindVertexArray(this.vao);
    gl.drawArrays(gl.TRIANGLES, 0, 3);
    gl.disable(gl.SCISSOR_TEST);
    gl.readBuffer(gl.COLOR_ATTACHMENT0);
    const raw = new Uint8Array(w * rows * 4);
    gl.readPixels(0, gy0, w, rows, gl.RGBA, gl.UNSIGNED_BYTE, raw);
    const rgba = flip(raw, w * 4, rows);
    let counters = null;
    if (stats) {
      gl.readBuffer(gl.COLOR_ATTACHMENT1);
      const s = new Uint32Array(w * rows * 4);
      gl.readPixels(0, gy0, w, rows, gl.RGBA_INTEGER, gl.UNSIGNED_INT, s);
      counters = sumStats(s);
    }
    gl.bindFramebuffer(gl.FRAMEBUFFER, null);
    const err = gl.getError();
    if (err !== gl.NO_ERROR) throw new Error(`WebGL error ${err} while drawing`);
    return { rgba, stats: counters };
  }
}

function flip(raw, stride, rows) {
  const out = new Uint8ClampedArray(raw.length);
  for (let y = 0; y < rows; y++) out.set(raw.subarray((rows - 1 - y) * stride, (rows - y) * stride), y * stride);
  return out;
}

/** Sum per-pixel counters into the CPU's `Stats` shape. */
export function sumStats(s) {
  const st = { rays: 0, hits: 0, sdf_evals: 0, steps: 0, gradient_checks: 0, undone_steps: 0, exhausted: 0 };
  for (let i = 0; i < s.length; i += 4) {
    st.rays++;
    st.steps += s[i];
    st.sdf_evals += s[i + 1];
    st.hits += s[i + 2] & 1;
    st.exhausted += (s[i + 2] >> 1) & 1;
    st.gradient_checks += s[i + 3];
  }
  return st;
}
