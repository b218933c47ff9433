//! A WebGL2 (GLSL ES 3.00) fragment-shader sphere tracer generated from a
//! compiled scene: the `micro-glsl` request. The browser renders the
//! interactive view with it; the CPU path ([`super::render`]) stays the
//! reference and makes every export.
//!
//! Every node becomes one GLSL function with its checked parameters (and
//! what checking derived: gradient bounds, inverse matrices, normalised
//! weights) baked in as constants, so the shader evaluates the same
//! normalised field as [`super::scene::Scene::eval`]:
//!
//! - particles and lattices hash their cells exactly like the CPU: Eq. 1's
//!   wrapping 64-bit polynomial and the SplitMix64 draws of
//!   [`crate::core::rng::Rng`] are done in 64-bit arithmetic emulated with
//!   `uvec2` (high, low) words, so every cell keeps the same particle with
//!   the same shape and orientation; the uniform numbers keep the top 24 of
//!   the CPU's 53 bits;
//! - `D(q)`'s congruences are exact modular arithmetic in `uint`
//!   (products of residues below 2^16 directly, larger moduli by
//!   shift-and-add), so the same cells are selected;
//! - tracing (fixed, bisection, adaptive steps), the clipping box, the hit
//!   threshold, normals and shading follow `render::trace` and
//!   `render::shade` line by line.
//!
//! Precision: the shader computes in 32-bit floats, the CPU in 64-bit. A
//! ray that grazes a surface, a hash draw that lands within 2^-24 of a
//! threshold (the keep probability, a mixture weight) or a zoom so deep
//! that a pixel's footprint nears float resolution can come out
//! differently. The browser test (`tests/e2e/micro-gl.test.mjs`) holds
//! every shipped scene to: at most 2% of pixels disagree on hit or miss,
//! and the mean absolute difference over all channels is at most 4 levels
//! of 255. The panel uses the CPU path when a pixel's footprint at the
//! target falls below 1e-6 of the scene's size (`www/micro/gl.js`).
use super::cells::{Combine, Field, Lattice, Particles, Pile, Poly, Select, Shape, Size};
use super::periodic::{Periodic, Surface, Tpms, Wave};
use super::render::{Shade, Shading, StepMode, Trace, AMBIENT, LIGHT};
use super::scene::{Op, Scene};
use crate::core::error::{Error, Result};
use std::fmt::Write;

/// The fixed settings baked into a shader (everything but the camera and
/// the image size, which are uniforms).
#[derive(Debug, Clone, Copy)]
pub struct Settings {
    pub trace: Trace,
    /// Hit threshold as a fraction of a pixel's footprint.
    pub pixel_fraction: f64,
    pub shade: Shade,
}

/// A generated shader pair.
#[derive(Debug, Clone, PartialEq)]
pub struct Program {
    pub vertex: String,
    pub fragment: String,
    /// GLSL functions generated for scene nodes.
    pub functions: usize,
}

/// The vertex shader: one triangle covering the viewport.
pub const VERTEX: &str = "#version 300 es
void main() {
  vec2 v = vec2(float((gl_VertexID << 1) & 2), float(gl_VertexID & 2));
  gl_Position = vec4(v * 2.0 - 1.0, 0.0, 1.0);
}
";

/// A float constant as GLSL text, or an error when it does not fit 32 bits.
fn lit(x: f64) -> Result<String> {
    let f = x as f32;
    if !f.is_finite() || (x != 0.0 && f.abs() < f32::MIN_POSITIVE) {
        return Err(Error::Unsupported(format!(
            "the scene has the number {x}, outside the GPU's 32-bit float range; \
             the CPU renderer can still draw it"
        ))
        .at("scene"));
    }
    let s = format!("{f:?}");
    Ok(if f < 0.0 { format!("({s})") } else { s })
}

fn v3(v: [f64; 3]) -> Result<String> {
    Ok(format!(
        "vec3({}, {}, {})",
        lit(v[0])?,
        lit(v[1])?,
        lit(v[2])?
    ))
}

fn field(f: &Field, p: &str) -> Result<String> {
    if f.gradient == [0.0; 3] {
        lit(f.value)
    } else {
        Ok(format!(
            "({} + dot({}, {p}))",
            lit(f.value)?,
            v3(f.gradient)?
        ))
    }
}

/// A [`Poly`] of the vector `p`: the linear part, then each term as a
/// product of its coordinates.
fn poly(f: &Poly, p: &str) -> Result<String> {
    let lin = Field {
        value: f.value,
        gradient: f.gradient,
    };
    let mut out = field(&lin, p)?;
    if f.terms.is_empty() {
        return Ok(out);
    }
    out = format!("({out}");
    for t in &f.terms {
        out.push_str(&format!(" + {}", lit(t.c)?));
        for (axis, n) in [("x", t.x), ("y", t.y), ("z", t.z)] {
            for _ in 0..n {
                out.push_str(&format!(" * {p}.{axis}"));
            }
        }
    }
    out.push(')');
    Ok(out)
}

/// The 64-bit constant `v` as `uvec2(high, low)`.
fn u64c(v: u64) -> String {
    format!("uvec2({}u, {}u)", (v >> 32) as u32, v as u32)
}

const GOLDEN: u64 = 0x9E37_79B9_7F4A_7C15;

/// Helpers every shader has: 64-bit words, the cell hash, SplitMix64,
/// primitives, smooth minimum, rotations.
const PRELUDE: &str = r#"#version 300 es
precision highp float;
precision highp int;
uniform vec3 u_origin;
uniform vec3 u_forward;
uniform vec3 u_right;
uniform vec3 u_up;
uniform float u_tan_half;
uniform vec2 u_res;
layout(location = 0) out vec4 o_color;
// Work counters: steps, field evaluations, hit | exhausted << 1 | undone << 2, gradient checks.
layout(location = 1) out uvec4 o_stats;
int g_steps = 0, g_evals = 0, g_checks = 0, g_undone = 0;
const float BIG = 1e30;

// ---- 64-bit words as uvec2(high, low) ----
uvec2 add64(uvec2 a, uvec2 b) {
  uint lo = a.y + b.y;
  return uvec2(a.x + b.x + (lo < a.y ? 1u : 0u), lo);
}
uvec2 mul32w(uint a, uint b) {
  uint a0 = a & 0xFFFFu, a1 = a >> 16, b0 = b & 0xFFFFu, b1 = b >> 16;
  uint p00 = a0 * b0, p01 = a0 * b1, p10 = a1 * b0, p11 = a1 * b1;
  uint mid = (p00 >> 16) + (p01 & 0xFFFFu) + (p10 & 0xFFFFu);
  return uvec2(p11 + (p01 >> 16) + (p10 >> 16) + (mid >> 16), (p00 & 0xFFFFu) | (mid << 16));
}
uvec2 mul64(uvec2 a, uvec2 b) {
  uvec2 r = mul32w(a.y, b.y);
  r.x += a.y * b.x + a.x * b.y;
  return r;
}
uvec2 shr64(uvec2 a, int n) {
  return uvec2(a.x >> uint(n), (a.y >> uint(n)) | (a.x << uint(32 - n)));
}
uvec2 sx64(int v) { return uvec2(v < 0 ? 0xFFFFFFFFu : 0u, uint(v)); }
// Eq. 1-2 before the node's seed: N * sum a_ijk qx^i qy^j qz^k (wrapping),
// in Horner form (the same value mod 2^64 with fewer products).
uvec2 cell_hash(ivec3 q) {
  uvec2 x = sx64(q.x), y = sx64(q.y), z = sx64(q.z);
  uvec2 c0 = add64(uvec2(0u, 1000003u), mul64(uvec2(0u, 73856093u), x));
  uvec2 c1 = add64(uvec2(0u, 19349663u), mul64(uvec2(0u, 83492791u), x));
  uvec2 c2 = add64(uvec2(0u, 2654435761u), mul64(uvec2(0u, 805459861u), x));
  uvec2 c3 = add64(uvec2(0u, 3674653429u), mul64(uvec2(0u, 2097152011u), x));
  uvec2 t = add64(add64(c0, mul64(y, c1)), mul64(z, add64(c2, mul64(y, c3))));
  return mul64(t, uvec2(0u, 10u));
}
// SplitMix64's output for state s, as a uniform number in [0, 1) (top 24 bits).
float splitmix01(uvec2 s) {
  uvec2 z = s;
  z = mul64(z ^ shr64(z, 30), uvec2(0xBF58476Du, 0x1CE4E5B9u));
  z = mul64(z ^ shr64(z, 27), uvec2(0x94D049BBu, 0x133111EBu));
  z = z ^ shr64(z, 31);
  return float(z.x >> 8) * (1.0 / 16777216.0);
}
// Draw k (0-based) of a generator whose state after seeding is s0.
float draw(uvec2 s0, uvec2 k_golden) { return splitmix01(add64(s0, k_golden)); }

// ---- exact modular arithmetic for D(q) ----
uint rem_q(int v, uint m) {
  uint a = uint(abs(v)) % m;
  return (v < 0 && a != 0u) ? m - a : a;
}
uint mulmod(uint a, uint b, uint m) {
  if (m <= 65536u) return (a * b) % m;
  uint r = 0u;
  for (int i = 31; i >= 0; i--) {
    r = (r << 1) % m;
    if (((b >> uint(i)) & 1u) != 0u) { r += a; if (r >= m) r -= m; }
  }
  return r;
}
uint powmod(uint x, int e, uint m) {
  uint r = 1u % m;
  for (int i = 0; i < e; i++) r = mulmod(r, x, m);
  return r;
}

// ---- primitives (src/geom/sdf3.rs) ----
float sd_cuboid(vec3 p, vec3 h) {
  vec3 q = abs(p) - h;
  return length(max(q, 0.0)) + min(max(q.x, max(q.y, q.z)), 0.0);
}
float sd_ellipsoid(vec3 p, vec3 r) { return (length(p / r) - 1.0) * min(r.x, min(r.y, r.z)); }
float sd_torus(vec3 p, float major, float minor) {
  return length(vec2(length(p.xy) - major, p.z)) - minor;
}
float sd_cylinder(vec3 p, float r, float h) {
  vec2 d = vec2(length(p.xy) - r, abs(p.z) - h);
  return min(max(d.x, d.y), 0.0) + length(max(d, 0.0));
}
float sd_hex_prism(vec3 p, float r, float h) {
  const vec3 K = vec3(-0.8660254037844386, 0.5, 0.5773502691896258);
  vec2 a = abs(p.xy);
  a -= 2.0 * min(dot(K.xy, a), 0.0) * K.xy;
  float s = (a.y - r) < 0.0 ? -1.0 : 1.0;
  vec2 d = vec2(length(a - vec2(clamp(a.x, -K.z * r, K.z * r), r)) * s, abs(p.z) - h);
  return min(max(d.x, d.y), 0.0) + length(max(d, 0.0));
}
float smin(float a, float b, float k) {
  if (k <= 0.0) return min(a, b);
  float h = max(k - abs(a - b), 0.0) / k;
  return min(a, b) - h * h * k * 0.25;
}
float smax(float a, float b, float k) { return -smin(-a, -b, k); }
// Shoemake's uniform rotation from three uniform numbers (sdf3::random_rotation).
mat3 random_rotation(float u1, float u2, float u3) {
  const float TAU = 6.283185307179586;
  float a = sqrt(1.0 - u1), b = sqrt(u1);
  vec4 q = vec4(a * sin(TAU * u2), a * cos(TAU * u2), b * sin(TAU * u3), b * cos(TAU * u3));
  q = normalize(q);
  float x2 = q.x + q.x, y2 = q.y + q.y, z2 = q.z + q.z;
  float xx = q.x * x2, xy = q.x * y2, xz = q.x * z2;
  float yy = q.y * y2, yz = q.y * z2, zz = q.z * z2;
  float wx = q.w * x2, wy = q.w * y2, wz = q.w * z2;
  return mat3(1.0 - (yy + zz), xy + wz, xz - wy,
              xy - wz, 1.0 - (xx + zz), yz + wx,
              xz + wy, yz - wx, 1.0 - (xx + yy));
}
mat3 axis_rotation(vec3 a, float angle) {
  float s = sin(angle), c = cos(angle), t = 1.0 - c;
  return mat3(t * a.x * a.x + c, t * a.x * a.y + s * a.z, t * a.x * a.z - s * a.y,
              t * a.x * a.y - s * a.z, t * a.y * a.y + c, t * a.y * a.z + s * a.x,
              t * a.x * a.z + s * a.y, t * a.y * a.z - s * a.x, t * a.z * a.z + c);
}
ivec3 floor_i(vec3 v) { return ivec3(clamp(floor(v), -1e9, 1e9)); }
// Rust's f64::round: halves away from zero.
vec3 round_away(vec3 v) { return sign(v) * floor(abs(v) + 0.5); }
float powu(float x, int n) { float r = 1.0; for (int i = 0; i < n; i++) r *= x; return r; }
float min3(vec3 v) { return min(v.x, min(v.y, v.z)); }
"#;

struct Gen {
    out: String,
    n: usize,
}

impl Gen {
    fn name(&mut self) -> String {
        self.n += 1;
        format!("n{}", self.n)
    }

    /// Emit node `op` (children first); return its function's name.
    fn node(&mut self, op: &Op) -> Result<String> {
        let body = match op {
            Op::Sphere(c, r) => format!("return length(p - {}) - {};", v3(c.to_array())?, lit(*r)?),
            Op::Box(c, h, r) => format!(
                "return sd_cuboid(p - {}, max({} - {}, 0.0)) - {};",
                v3(c.to_array())?,
                v3(h.to_array())?,
                lit(*r)?,
                lit(*r)?
            ),
            Op::Plane(n, o) => format!("return dot({}, p) - {};", v3(n.to_array())?, lit(*o)?),
            Op::Particles(c) => self.particles(c)?,
            Op::Lattice(c) => self.lattice(c)?,
            Op::Pile(c) => pile(c)?,
            Op::Tpms(t) => tpms(t)?,
            Op::Periodic(t) => periodic(t)?,
            Op::Union(cs, k) | Op::Intersection(cs, k) => {
                let f = if matches!(op, Op::Union(..)) {
                    "smin"
                } else {
                    "smax"
                };
                let names = cs
                    .iter()
                    .map(|c| self.node(c))
                    .collect::<Result<Vec<_>>>()?;
                let mut b = format!("float v = {}(p);", names[0]);
                for n in &names[1..] {
                    let _ = write!(b, "\n  v = {f}(v, {n}(p), {});", lit(*k)?);
                }
                b + "\n  return v;"
            }
            Op::Difference(base, cs, k) => {
                let bn = self.node(base)?;
                let names = cs
                    .iter()
                    .map(|c| self.node(c))
                    .collect::<Result<Vec<_>>>()?;
                let mut b = format!("float v = {bn}(p);");
                for n in &names {
                    let _ = write!(b, "\n  v = smax(v, -{n}(p), {});", lit(*k)?);
                }
                b + "\n  return v;"
            }
            Op::Transform(c, inv, t, s) => {
                let cn = self.node(c)?;
                let a = inv.to_cols_array();
                let m = a.iter().map(|x| lit(*x)).collect::<Result<Vec<_>>>()?;
                format!(
                    "return {cn}(mat3({}) * (p - {})) * {};",
                    m.join(", "),
                    v3(t.to_array())?,
                    lit(*s)?
                )
            }
            Op::Offset(c, a) => format!("return {}(p) - {};", self.node(c)?, lit(*a)?),
            Op::Shell(c, t) => format!("return abs({}(p)) - {};", self.node(c)?, lit(*t)?),
            Op::Repeat(c, cell) => {
                let cn = self.node(c)?;
                let cl = v3(cell.to_array())?;
                format!("return {cn}(p - {cl} * round_away(p / {cl}));")
            }
        };
        let name = self.name();
        let _ = write!(self.out, "float {name}(vec3 p) {{\n  {body}\n}}\n");
        Ok(name)
    }

    /// Suspended particles: a per-cell function (Eq. 3 + rejection) and the
    /// dual grid's 8 cells (Eq. 4–6).
    fn particles(&mut self, c: &Particles) -> Result<String> {
        let pn = self.name();
        let d = &c.c;
        let seed_key = c.seed.wrapping_mul(GOLDEN) ^ GOLDEN;
        let draw = |k: u64| format!("draw(s0, {})", u64c(GOLDEN.wrapping_mul(k + 1)));
        let mut b = format!("uvec2 s0 = cell_hash(q) ^ {};\n", u64c(seed_key));
        if c.jitter > 0.0 {
            let _ = writeln!(
                b,
                "  vec3 c = vec3(q) + 0.5 + (vec3({}, {}, {}) - 0.5) * {};",
                draw(0),
                draw(1),
                draw(2),
                lit(c.jitter)?
            );
        } else {
            b.push_str("  vec3 c = vec3(q) + 0.5;\n");
        }
        let _ = writeln!(b, "  vec3 world = c * {};", lit(c.cell)?);
        let keeps_all = c.keep.gradient == [0.0; 3] && c.keep.value >= 1.0;
        if !keeps_all {
            let _ = writeln!(
                b,
                "  if ({} >= {}) return BIG;",
                draw(3),
                field(&c.keep, "world")?
            );
        }
        let size = match c.size {
            Size::Fixed { radius } => lit(radius)?,
            Size::Uniform { min, max } => format!(
                "({} + {} * {})",
                lit(min)?,
                lit(max - min)?,
                draw(4)
            ),
            Size::Normal { mean, std, max } => format!(
                "clamp({} + {} * (sqrt(-2.0 * log(1.0 - {})) * cos(6.283185307179586 * {})), 0.0, {})",
                lit(mean)?,
                lit(std)?,
                draw(4),
                draw(5),
                lit(max)?
            ),
        };
        let scale = if c.size_scale.gradient == [0.0; 3] && c.size_scale.value >= 1.0 {
            "1.0".to_string()
        } else {
            format!("clamp({}, 0.0, 1.0)", field(&c.size_scale, "world")?)
        };
        let _ = writeln!(
            b,
            "  float r = clamp({size} * {scale}, 0.0, {});",
            lit(d.r_max)?
        );
        b.push_str(
            "  if (r <= 0.0) return BIG;\n  vec3 d = pw - c;\n  float bounding = length(d) - r;\n  if (bounding >= cut) return bounding;\n",
        );
        let shapes: Vec<&Shape> = c.shapes.iter().map(|s| &s.shape).collect();
        if shapes.iter().all(|s| **s == Shape::Sphere) {
            b.push_str("  return bounding;\n");
        } else {
            b.push_str("  int sh = 0;\n");
            if shapes.len() > 1 {
                let x6 = draw(6);
                let _ = writeln!(b, "  float x6 = {x6};\n  sh = {};", shapes.len() - 1);
                for (i, w) in d.weights.iter().enumerate().take(shapes.len() - 1).rev() {
                    let _ = writeln!(b, "  if (x6 < {}) sh = {i};", lit(*w)?);
                }
            }
            let spheres: Vec<String> = shapes
                .iter()
                .enumerate()
                .filter(|(_, s)| ***s == Shape::Sphere)
                .map(|(i, _)| format!("sh == {i}"))
                .collect();
            if !spheres.is_empty() {
                let _ = writeln!(b, "  if ({}) return bounding;", spheres.join(" || "));
            }
            if c.random_orientation {
                let _ = writeln!(
                    b,
                    "  d = transpose(random_rotation({}, {}, {})) * d;",
                    draw(7),
                    draw(8),
                    draw(9)
                );
            }
            b.push_str("  vec3 u = d / r;\n  float s = BIG;\n");
            for (i, s) in shapes.iter().enumerate() {
                if **s == Shape::Sphere {
                    continue;
                }
                let _ = writeln!(b, "  if (sh == {i}) s = {};", shape_sdf(s, "u")?);
            }
            b.push_str("  return max(s * r, bounding);\n");
        }
        let _ = write!(
            self.out,
            "float {pn}(ivec3 q, vec3 pw, float cut) {{\n  {b}}}\n"
        );
        let warp = match &c.warp {
            Some(w) => format!(
                "p + {} * sin({} * p.yzx + vec3(1.7, 0.4, 2.9))",
                lit(w.amplitude)?,
                lit(w.frequency)?
            ),
            None => "p".into(),
        };
        Ok(format!(
            "vec3 pw = ({warp}) / {cell};
  ivec3 b = floor_i(pw - 0.5);
  float d = BIG;
  for (int i = 0; i < 8; i++) {{
    d = min(d, {pn}(b + ivec3(i & 1, (i >> 1) & 1, (i >> 2) & 1), pw, d));
  }}
  vec3 lo = pw - vec3(b);
  d = min(d, min3(min(lo, 2.0 - lo)) + {margin} - {rmax});
  return ({off} + {cell} * d) * {inv};",
            cell = lit(c.cell)?,
            margin = lit(d.margin)?,
            rmax = lit(d.r_max)?,
            off = field(&c.offset, "p")?,
            inv = lit(d.inv_lip)?,
        ))
    }

    /// Agglomerates: `D(q)` and the 27-neighbourhood (Eq. 7–9).
    fn lattice(&mut self, c: &Lattice) -> Result<String> {
        let keep = match &c.select {
            Some(s) => {
                let sn = self.name();
                let body = select(s)?;
                let _ = write!(self.out, "bool {sn}(ivec3 q) {{\n{body}}}\n");
                format!("if (!{sn}(q)) continue;\n      ")
            }
            None => String::new(),
        };
        let centre = if c.jitter > 0.0 {
            let seed_key = c.seed.wrapping_mul(GOLDEN) ^ GOLDEN;
            let dr = |k: u64| format!("draw(s0, {})", u64c(GOLDEN.wrapping_mul(k + 1)));
            format!(
                "uvec2 s0 = cell_hash(q) ^ {};\n      vec3 c = vec3(q) + 0.5 + (vec3({}, {}, {}) - 0.5) * {};",
                u64c(seed_key),
                dr(0),
                dr(1),
                dr(2),
                lit(c.jitter)?
            )
        } else {
            "vec3 c = vec3(q) + 0.5;".into()
        };
        Ok(format!(
            "vec3 pw = p / {cell};
  ivec3 q0 = floor_i(pw);
  float d = BIG;
  for (int dz = -1; dz <= 1; dz++) for (int dy = -1; dy <= 1; dy++) for (int dx = -1; dx <= 1; dx++) {{
      ivec3 q = q0 + ivec3(dx, dy, dz);
      {keep}{centre}
      d = smin(d, distance(pw, c) - {r}, {k});
  }}
  vec3 lo = pw - vec3(q0) + 1.0;
  d = min(d, min3(min(lo, 3.0 - lo)) + {margin} - {r} - {k});
  return ({off} + {cell} * d) * {inv};",
            cell = lit(c.cell)?,
            r = lit(c.radius)?,
            k = lit(c.smooth)?,
            margin = lit(c.c.margin)?,
            off = field(&c.offset, "p")?,
            inv = lit(c.c.inv_lip)?,
        ))
    }
}

/// `D(q)` as a GLSL body (Eq. 9), exact modular arithmetic.
fn select(s: &Select) -> Result<String> {
    let mut b = String::new();
    let mut parts = vec![];
    for (i, t) in s.terms.iter().enumerate() {
        let m = t.modulus as u64;
        let _ = writeln!(
            b,
            "  uint m{i} = {m}u;\n  uint x{i} = rem_q(q.x, m{i}), y{i} = rem_q(q.y, m{i}), z{i} = rem_q(q.z, m{i});\n  uint r{i} = 0u;"
        );
        for mono in &t.poly {
            let c = mono.c.rem_euclid(t.modulus) as u64;
            let _ = writeln!(
                b,
                "  r{i} = (r{i} + mulmod(mulmod(mulmod({c}u, powmod(x{i}, {}, m{i}), m{i}), powmod(y{i}, {}, m{i}), m{i}), powmod(z{i}, {}, m{i}), m{i})) % m{i};",
                mono.x, mono.y, mono.z
            );
        }
        let tests: Vec<String> = t
            .classes
            .iter()
            .map(|c| {
                let r = c.residue.rem_euclid(t.modulus);
                format!("((r{i} == {r}u) == {})", c.include)
            })
            .collect();
        let join = match t.combine {
            Combine::Any => " || ",
            Combine::All => " && ",
        };
        parts.push(format!("({})", tests.join(join)));
    }
    let join = match s.combine {
        Combine::Any => " || ",
        Combine::All => " && ",
    };
    let _ = writeln!(b, "  return {};", parts.join(join));
    Ok(b)
}

/// A unit-bounded particle shape at `u` (cells::Shape::sdf).
fn shape_sdf(s: &Shape, u: &str) -> Result<String> {
    Ok(match s {
        Shape::Sphere => format!("(length({u}) - 1.0)"),
        Shape::Ellipsoid { axes } => format!("sd_ellipsoid({u}, {})", v3(*axes)?),
        Shape::Torus { ratio } => {
            let major = 1.0 / (1.0 + ratio);
            format!("sd_torus({u}, {}, {})", lit(major)?, lit(major * ratio)?)
        }
        Shape::Cylinder { aspect } => {
            let r = 1.0 / (1.0 + aspect * aspect).sqrt();
            format!("sd_cylinder({u}, {}, {})", lit(r)?, lit(r * aspect)?)
        }
        Shape::HexPrism { aspect } => {
            let c = 2.0 / 3f64.sqrt();
            let r = 1.0 / (c * c + aspect * aspect).sqrt();
            format!("sd_hex_prism({u}, {}, {})", lit(r)?, lit(r * aspect)?)
        }
        Shape::RedBloodCell => {
            format!("smin(sd_torus({u}, 0.72, 0.26), sd_cylinder({u}, 0.72, 0.1), 0.12)")
        }
    })
}

/// Piles (Eq. 10): the deformed, rotated domain over a full lattice. The
/// nearest of the 27 lattice centres is always the point's own cell's.
fn pile(c: &Pile) -> Result<String> {
    Ok(format!(
        "mat3 rot = axis_rotation({axis}, {angle});
  vec3 n = sin({f} * p.yzx + vec3(1.3, 2.1, 0.7));
  vec3 pw = (rot * p + n * {deform}) / {cell};
  ivec3 q0 = floor_i(pw);
  float d = distance(pw, vec3(q0) + 0.5) - {r};
  vec3 lo = pw - vec3(q0) + 1.0;
  return {cell} * min(d, min3(min(lo, 3.0 - lo)) + {margin} - {r}) * {inv};",
        axis = v3(c.axis_n.to_array())?,
        angle = poly(&c.angle, "p")?,
        f = lit(c.noise_frequency)?,
        deform = poly(&c.deform, "p")?,
        cell = lit(c.cell)?,
        r = lit(c.radius)?,
        margin = lit(c.c.margin)?,
        inv = lit(c.c.inv_lip)?,
    ))
}

fn tpms(t: &Tpms) -> Result<String> {
    let g = match t.surface {
        Surface::Gyroid => "s.x * c.y + s.y * c.z + s.z * c.x",
        Surface::Diamond => "s.x * s.y * s.z + s.x * c.y * c.z + c.x * s.y * c.z + c.x * c.y * s.z",
        Surface::Primitive => "c.x + c.y + c.z",
    };
    let v = if t.thickness > 0.0 {
        format!("abs(g) - {}", lit(t.thickness)?)
    } else {
        format!("g - {}", lit(t.level)?)
    };
    Ok(format!(
        "vec3 k = p * {};\n  vec3 s = sin(k), c = cos(k);\n  float g = {g};\n  return ({v}) * {};",
        lit(t.k)?,
        lit(t.inv_bound)?
    ))
}

fn periodic(t: &Periodic) -> Result<String> {
    let mut sum = lit(t.constant)?;
    for term in &t.terms {
        let mut prod = String::from("1.0");
        for f in term {
            let axis = ["p.x", "p.y", "p.z"][f.axis as usize];
            let wave = match f.wave {
                Wave::Sin => "sin",
                Wave::Cos => "cos",
            };
            let _ = write!(
                prod,
                " * powu({} * {wave}({} * {axis} + {}), {})",
                lit(f.amp)?,
                lit(f.freq)?,
                lit(f.phase)?,
                f.power
            );
        }
        let _ = write!(sum, " + ({prod})");
    }
    let v = if t.thickness > 0.0 {
        format!("abs(v) - {}", lit(t.thickness)?)
    } else {
        "v".into()
    };
    Ok(format!(
        "float v = {sum};\n  return ({v}) * {};",
        lit(t.inv_bound)?
    ))
}

/// The tracer and shader main, after `render::trace` / `render::shade`.
fn main_part(s: &Settings) -> Result<String> {
    let t = &s.trace;
    let sh = &s.shade;
    let col = |c: [u8; 3]| {
        format!(
            "vec3({:?}, {:?}, {:?})",
            c[0] as f32 / 255.0,
            c[1] as f32 / 255.0,
            c[2] as f32 / 255.0
        )
    };
    let step = match t.mode {
        StepMode::Fixed => "t += dist;\n      dist = field(o + d * t);".to_string(),
        StepMode::Bisection => format!(
            "float tp = t;
      t += dist * {bf};
      dist = field(o + d * t);
      if (dist < 0.0) {{
        float lo = tp, hi = t;
        for (int j = 0; j < 60; j++) {{
          if (hi - lo < prec * max(lo, tiny)) break;
          float mid = 0.5 * (lo + hi);
          if (field(o + d * mid) < 0.0) hi = mid; else lo = mid;
        }}
        hit = true;
        return lo;
      }}",
            bf = lit(t.bisection_factor)?
        ),
        StepMode::Adaptive => {
            let check = if t.check_cell > 0.0 {
                format!(
                    "vec3 qc = floor((o + d * t) / {cc});
      bool fresh = !have_cell || qc != last_cell;
      last_cell = qc; have_cell = true;
      bool check = fresh && i > 0 && mod(qc.x + 2.0 * qc.y + 3.0 * qc.z, {m}) == 0.0;",
                    cc = lit(t.check_cell)?,
                    m = lit(t.check_modulus.max(1) as f64)?
                )
            } else {
                let n = t.check_every.max(1);
                if n == 1 {
                    "bool check = true;".to_string()
                } else {
                    format!("bool check = i > 0 && i % {n} == 0;")
                }
            };
            format!(
                "{check}
      if (check && dist >= 2.0 * eps) {{
        g_checks++;
        float hc = max(prec * t, 1e-5 * (1.0 + length(o + d * t)));
        float ahead = field(o + d * (t + hc));
        relax = clamp(1.8 / (1.0 + clamp(-(ahead - dist) / hc, -1.0, 1.0)), 1.0, {mr});
      }}
      float w = cooldown ? 1.0 : relax;
      cooldown = false;
      float tp = t, dp = dist;
      t += dist * w;
      dist = field(o + d * t);
      if (w > 1.0 && (dist < 0.0 || dp + dist < (t - tp) * (1.0 - 1e-12))) {{
        g_undone++;
        cooldown = true;
        float tr = t, dr = dist;
        t = tp + dp;
        dist = field(o + d * t);
        if (dr >= 0.0 && dist + dr >= (tr - t) * (1.0 + 1e-12)) {{ t = tr; dist = dr; }}
      }}",
                mr = lit(t.max_relax.max(1.0))?
            )
        }
    };
    Ok(format!(
        r#"
float field(vec3 p) {{
  g_evals++;
  float v = scene(p);
  if (isnan(v)) v = BIG;
  return max(v, sd_cuboid(p, vec3({b})));
}}
vec3 grad(vec3 p, float h) {{
  vec3 dx = vec3(h, 0.0, 0.0), dy = vec3(0.0, h, 0.0), dz = vec3(0.0, 0.0, h);
  return vec3(field(p + dx) - field(p - dx), field(p + dy) - field(p - dy),
              field(p + dz) - field(p - dz)) / (2.0 * h);
}}
{surface}
bool clip_box(vec3 o, vec3 d, out float near, out float far) {{
  vec3 dd = vec3(abs(d.x) < 1e-30 ? 1e-30 : d.x, abs(d.y) < 1e-30 ? 1e-30 : d.y, abs(d.z) < 1e-30 ? 1e-30 : d.z);
  vec3 inv = 1.0 / dd;
  vec3 t1 = (vec3(-{b}) - o) * inv, t2 = (vec3({b}) - o) * inv;
  vec3 mn = min(t1, t2), mx = max(t1, t2);
  near = max(max(mn.x, max(mn.y, mn.z)), 0.0);
  far = min(mx.x, min(mx.y, mx.z));
  return near <= far;
}}
float trace(vec3 o, vec3 d, float prec, out bool hit, out bool exhausted) {{
  hit = false;
  exhausted = false;
  float t0, t1;
  if (!clip_box(o, d, t0, t1)) return 0.0;
  float tiny = 1e-12 * (1.0 + t1);
  float t = t0;
  float dist = field(o + d * t);
  float relax = {relax0};
  bool cooldown = false;
  vec3 last_cell = vec3(0.0);
  bool have_cell = false;
  for (int i = 0; i < {max_steps}; i++) {{
    float eps = prec * max(t, tiny);
    if (dist < eps) {{ hit = true; return t; }}
    if (t > t1) return t;
    g_steps++;
    {{
      {step}
    }}
  }}
  exhausted = true;
  return t;
}}
void main() {{
  vec2 s = (2.0 * gl_FragCoord.xy - u_res) / u_res.y;
  vec3 d = normalize(u_forward + u_right * (s.x * u_tan_half) + u_up * (s.y * u_tan_half));
  vec3 o = u_origin;
  float prec = 2.0 * u_tan_half / u_res.y * {pf};
  bool hit, exhausted;
  float t = trace(o, d, prec, hit, exhausted);
  if (!hit) {{
    o_color = vec4({bg}, 1.0);
    o_stats = uvec4(uint(g_steps), uint(g_evals), (exhausted ? 2u : 0u) | (uint(g_undone) << 2), uint(g_checks));
    return;
  }}
  vec3 p = o + d * t;
  // The CPU's step floor of 1e-9 is below 32-bit resolution: floor the
  // step at 1e-5 of the point's magnitude (a hit at the camera, t = 0).
  vec3 n = grad(p, max(prec * t * 0.5, 1e-5 * (1.0 + length(p))));
  float nl = length(n);
  n = nl > 0.0 && !isinf(nl) ? n / nl : -d;
  vec2 ks = surface(n, d);
  float t0, t1;
  if (!clip_box(o, d, t0, t1)) t0 = t;
  float absorb = exp(-{absorption} * max(t - t0, 0.0));
  o_color = vec4(clamp(({color} * ks.x + ks.y) * absorb, 0.0, 1.0), 1.0);
  o_stats = uvec4(uint(g_steps), uint(g_evals), 1u | (uint(g_undone) << 2), uint(g_checks));
}}
"#,
        b = lit(t.bounds)?,
        max_steps = t.max_steps,
        relax0 = lit(t.max_relax.max(1.0))?,
        pf = lit(s.pixel_fraction)?,
        bg = col(sh.background),
        color = col(sh.color),
        absorption = lit(sh.absorption)?,
        surface = surface(sh)?,
    ))
}

/// `render::surface`: (multiplier of the colour, white specular).
fn surface(sh: &Shade) -> Result<String> {
    let l = v3(sh.light.to_array())?;
    let body = match sh.shading {
        Shading::Lambert => format!(
            "return vec2({a} + {k} * max(dot(n, {l}), 0.0), 0.0);",
            a = lit(AMBIENT)?,
            k = lit(LIGHT)?
        ),
        Shading::Ggx => format!(
            "const float PI = 3.141592653589793;
  vec3 l = {l}, v = -d;
  float n_l = max(dot(n, l), 0.0), n_v = dot(n, v);
  float alpha = {alpha}, f0 = {f0};
  vec3 hv = v + l;
  vec3 h = length(hv) > 0.0 ? normalize(hv) : n;
  float f = f0 + (1.0 - f0) * pow(1.0 - clamp(max(dot(v, h), 0.0), 0.0, 1.0), 5.0);
  float spec = 0.0;
  if (dot(n, l) > 0.0 && n_v > 0.0) {{
    float a2 = alpha * alpha;
    float c = max(dot(n, h), 0.0);
    float dd = c * c * (a2 - 1.0) + 1.0;
    float D = a2 / (PI * dd * dd);
    float gl = 2.0 * n_l / max(n_l + sqrt(a2 + (1.0 - a2) * n_l * n_l), 1e-30);
    float gv = 2.0 * n_v / max(n_v + sqrt(a2 + (1.0 - a2) * n_v * n_v), 1e-30);
    float fs = f0 + (1.0 - f0) * pow(1.0 - clamp(dot(v, h), 0.0, 1.0), 5.0);
    spec = D * gl * gv * fs / (4.0 * n_l * n_v) * n_l * {k} * PI;
  }}
  return vec2(({a} + {k} * n_l) * (1.0 - f), spec);",
            alpha = lit(sh.roughness * sh.roughness)?,
            f0 = lit(sh.specular)?,
            a = lit(AMBIENT)?,
            k = lit(LIGHT)?
        ),
    };
    Ok(format!("vec2 surface(vec3 n, vec3 d) {{\n  {body}\n}}"))
}

/// Generate the shader pair for `scene` with `settings`.
pub fn program(scene: &Scene, settings: &Settings) -> Result<Program> {
    let mut g = Gen {
        out: String::from(PRELUDE),
        n: 0,
    };
    let root = g.node(&scene.root)?;
    let _ = writeln!(g.out, "float scene(vec3 p) {{ return {root}(p); }}");
    g.out.push_str(&main_part(settings)?);
    Ok(Program {
        vertex: VERTEX.to_string(),
        fragment: g.out,
        functions: g.n,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::micro::examples::EXAMPLES;

    fn settings() -> Settings {
        Settings {
            trace: Trace {
                mode: StepMode::Fixed,
                check_every: 10,
                check_cell: 0.0,
                check_modulus: 3,
                max_relax: 4.0,
                bisection_factor: 1.5,
                max_steps: 512,
                precision: 0.001,
                bounds: 1.0,
            },
            pixel_fraction: 0.5,
            shade: super::super::render::Shade {
                color: [200, 100, 50],
                background: [0, 0, 0],
                light: glam::DVec3::Z,
                absorption: 0.0,
                shading: super::super::render::Shading::Ggx,
                roughness: 0.35,
                specular: 0.04,
            },
        }
    }

    #[test]
    fn every_shipped_scene_generates_a_shader_with_one_function_per_node() {
        for e in EXAMPLES {
            let s = crate::micro::scene::parse(e.scene).unwrap();
            let p = program(&s, &settings()).unwrap();
            assert!(p.fragment.contains("float scene(vec3 p)"), "{}", e.name);
            // Particles emit a per-cell function too, selections one more.
            assert!(
                p.functions >= s.nodes,
                "{}: {} < {}",
                e.name,
                p.functions,
                s.nodes
            );
            for bad in ["NaN", "inf,", "inf)", "inf;"] {
                assert!(!p.fragment.contains(bad), "{}: {bad}", e.name);
            }
        }
    }

    #[test]
    fn numbers_outside_32_bit_floats_are_refused() {
        let s = crate::micro::scene::parse(
            r#"{"type": "periodic", "terms": [[{"wave": "sin", "axis": "x", "amp": 1e6, "power": 8}]]}"#,
        )
        .unwrap();
        let e = program(&s, &settings()).unwrap_err();
        assert_eq!(e.field(), Some("scene"));
        // The page tells "the GPU cannot, the CPU can" by this kind, not the text.
        assert_eq!(e.kind(), "unsupported");
        assert!(e.to_string().contains("32-bit"), "{e}");
        assert_eq!(lit(-2.5).unwrap(), "(-2.5)");
        assert_eq!(lit(1e-7).unwrap(), "1e-7");
    }

    /// The emulated 64-bit words and the hash are checked against the CPU
    /// in the browser (`tests/e2e/micro-gl.test.mjs`); here the constants
    /// the shader bakes are the CPU's.
    #[test]
    fn baked_hash_constants_are_the_cpus() {
        use crate::core::rng::Rng;
        let seed = 7u64;
        let q = glam::IVec3::new(-3, 5, 11);
        let s0 = super::super::cells::cell_seed(q, seed) ^ GOLDEN;
        // Rng::new xors GOLDEN; draw k is SplitMix64 at state + (k+1)·GOLDEN.
        let mut r = Rng::new(super::super::cells::cell_seed(q, seed));
        let mut st = s0;
        for _ in 0..3 {
            st = st.wrapping_add(GOLDEN);
            let mut z = st;
            z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
            z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
            z ^= z >> 31;
            assert_eq!(r.next_u64(), z);
        }
        assert_eq!(u64c(0x1_0000_0002), "uvec2(1u, 2u)");
    }
}
