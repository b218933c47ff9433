//! Sphere tracing of a Micro scene (paper §4–5) with fixed, bisection and
//! adaptive step lengths, normals by central differences, Lambert or GGX
//! (Cook–Torrance) shading with Beer–Lambert volume absorption, an orbit
//! camera, and z-slices of the field.
//!
//! Shading (the same formulas in the GPU shader, [`super::glsl`]): the
//! sample box is filled with a host medium that absorbs light along the ray
//! from where the ray enters the box to the surface it hits,
//! `T = exp(−absorption · length)` (Beer–Lambert, [`beer_lambert`]); the
//! surface gets an ambient term, a Lambert term, and with `ggx` a
//! microfacet specular term ([`ggx_specular`]: Trowbridge–Reitz normal
//! distribution, height-uncorrelated Smith masking, Schlick's Fresnel) that
//! takes its share `F` from the diffuse term.
//!
//! The scene is clipped to the box `[−bounds, bounds]³` (a sample of the
//! material). The hit threshold grows with the distance along the ray (a
//! fraction of the pixel's footprint), so the camera can zoom from the
//! whole sample to single particles without any precomputation.
//!
//! Step strategies (the scene's field is 1-Lipschitz, see [`super::scene`]):
//! - `fixed`: classic sphere tracing, step = distance.
//! - `bisection`: steps of `bisection_factor` × distance; when the field
//!   turns negative, bisect back to the surface (may skip features thinner
//!   than the overshoot).
//! - `adaptive`: over-relaxed sphere tracing (Keinert et al. 2014):
//!   steps of `max_relax` (default 1.5) × distance. A step whose
//!   unbounding spheres do not overlap is undone and retaken plainly, and
//!   the next step is plain too; if the retaken step's sphere reaches the
//!   undone point's, the ray goes on from there (its distance is known),
//!   so an undone step costs one evaluation. So it never passes a surface
//!   (the field is 1-Lipschitz). Gradient checks every `check_every` steps
//!   from step N on (every step for N = 1), or by cell (`check_cell`, our
//!   form of the paper's D(p)), skipped where the ray is within twice the
//!   hit threshold, set the relaxation from the slope along the ray
//!   ([`relax_for_slope`]): the gradient's component along the ray, by a
//!   forward difference from the distance already known (1 evaluation; a
//!   full central-difference gradient, 6, until issue 12's session 18).
//!   Measured (issue 12, `docs/bench/micro-table2-2026-12-03.md` and
//!   `micro-dp-2026-12-03.md`): on the multiscale scene the rays are short
//!   (10–17 steps) and run within a few hit thresholds of fine particles;
//!   on it and on four other presets no selection of checks (every N,
//!   D(p) cells of 0.04–0.25), no kind of check (6, 2 or 1 evaluations)
//!   and no cap on the relaxation a check may set (1.5–3) took fewer
//!   evaluations than no checks, so checks are pure cost there.
use super::scene::Scene;
use crate::micro::sdf3;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// An orbit camera around `target` (z up). Angles in degrees.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Camera {
    pub target: [f64; 3],
    /// Distance from the target (zoom).
    pub distance: f64,
    /// Azimuth around z and elevation above the xy plane.
    pub yaw: f64,
    pub pitch: f64,
    /// Vertical field of view.
    pub fov: f64,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            target: [0.0; 3],
            distance: 3.6,
            yaw: 35.0,
            pitch: 28.0,
            fov: 40.0,
        }
    }
}

/// How a ray advances.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StepMode {
    #[default]
    Fixed,
    Bisection,
    Adaptive,
}

/// Everything a trace needs besides the scene and the ray.
#[derive(Debug, Clone, Copy)]
pub struct Trace {
    pub mode: StepMode,
    pub check_every: u32,
    /// When > 0, gradient checks are selected by position instead (the
    /// paper's D(p) checks): when the ray enters a new cell of this size
    /// whose index q has `qx + 2 qy + 3 qz ≡ 0 (mod check_modulus)`.
    pub check_cell: f64,
    pub check_modulus: u32,
    pub max_relax: f64,
    pub bisection_factor: f64,
    pub max_steps: u32,
    /// Hit when the distance < `precision` × t.
    pub precision: f64,
    /// Half size of the clipping box.
    pub bounds: f64,
}

/// Work counters.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    pub rays: u64,
    pub hits: u64,
    /// Scene evaluations (every call, including gradients and normals).
    pub sdf_evals: u64,
    /// Steps along rays.
    pub steps: u64,
    /// Adaptive gradient checks and undone over-relaxed steps.
    pub gradient_checks: u64,
    pub undone_steps: u64,
    /// Rays that ran out of steps.
    pub exhausted: u64,
}

impl Stats {
    pub fn add(&mut self, o: &Stats) {
        self.rays += o.rays;
        self.hits += o.hits;
        self.sdf_evals += o.sdf_evals;
        self.steps += o.steps;
        self.gradient_checks += o.gradient_checks;
        self.undone_steps += o.undone_steps;
        self.exhausted += o.exhausted;
    }
}

/// The clipped field: the scene intersected with the bounds box.
pub fn field(scene: &Scene, bounds: f64, p: DVec3) -> f64 {
    scene.eval(p).max(sdf3::cuboid(p, DVec3::splat(bounds)))
}

/// Entry and exit of a ray with the box `[−b, b]³`.
pub fn clip(o: DVec3, d: DVec3, b: f64) -> Option<(f64, f64)> {
    let inv = DVec3::ONE / d;
    let t1 = (DVec3::splat(-b) - o) * inv;
    let t2 = (DVec3::splat(b) - o) * inv;
    let near = t1.min(t2).max_element().max(0.0);
    let far = t1.max(t2).min_element();
    (near <= far && far.is_finite()).then_some((near, far))
}

/// Adaptive steps: the relaxation `ω` for a ray along which the distance
/// falls at `slope` per unit length (−∇f·d at a gradient check). With the
/// field locally linear, a step of `ω d` leaves a distance `d (1 − ω s)`,
/// and the two unbounding spheres still overlap while `ω ≤ 2 / (1 + s)`;
/// 0.9 of that, between 1 and `max_relax`.
pub fn relax_for_slope(slope: f64, max_relax: f64) -> f64 {
    let s = if slope.is_nan() {
        1.0
    } else {
        slope.clamp(-1.0, 1.0)
    };
    (1.8 / (1.0 + s)).clamp(1.0, max_relax.max(1.0))
}

/// Where a ray hits: distance along it, or `None`.
pub fn trace(scene: &Scene, o: DVec3, d: DVec3, s: &Trace, st: &mut Stats) -> Option<f64> {
    st.rays += 1;
    let (t0, t1) = clip(o, d, s.bounds * (1.0 + 1e-9) + 1e-12)?;
    let f = |t: f64, st: &mut Stats| {
        st.sdf_evals += 1;
        field(scene, s.bounds, o + d * t)
    };
    let tiny = 1e-12 * (1.0 + t1);
    let mut t = t0;
    let mut dist = f(t, st);
    let mut relax = s.max_relax.max(1.0);
    let mut cooldown = false;
    let mut last_cell = DVec3::NAN;
    for i in 0..s.max_steps {
        let eps = s.precision * t.max(tiny);
        if dist < eps {
            return Some(t);
        }
        if t > t1 {
            return None;
        }
        st.steps += 1;
        match s.mode {
            StepMode::Fixed => {
                t += dist;
                dist = f(t, st);
            }
            StepMode::Bisection => {
                let (tp, dp) = (t, dist);
                t += dist * s.bisection_factor;
                dist = f(t, st);
                if dist < 0.0 {
                    // Bisect [tp, t] to the sign change.
                    let (mut lo, mut hi) = (tp, t);
                    for _ in 0..60 {
                        if hi - lo < s.precision * lo.max(tiny) {
                            break;
                        }
                        let mid = 0.5 * (lo + hi);
                        if f(mid, st) < 0.0 {
                            hi = mid;
                        } else {
                            lo = mid;
                        }
                    }
                    let _ = dp;
                    return Some(lo);
                }
            }
            StepMode::Adaptive => {
                let check = if s.check_cell > 0.0 {
                    let q = ((o + d * t) / s.check_cell).floor();
                    let fresh = q != last_cell;
                    last_cell = q;
                    let m = s.check_modulus.max(1) as f64;
                    fresh && i > 0 && (q.x + 2.0 * q.y + 3.0 * q.z).rem_euclid(m) == 0.0
                } else {
                    i % s.check_every.max(1) == 0 && (i > 0 || s.check_every <= 1)
                };
                // No check where the ray is about to hit (its next plain
                // step would likely end within the threshold).
                if check && dist >= 2.0 * eps {
                    // The gradient's component along the ray is all the
                    // relaxation uses: a forward difference from the known
                    // distance, one evaluation (a full central-difference
                    // gradient cost 6 for the same slope; issue 12).
                    st.gradient_checks += 1;
                    let h = (s.precision * t).max(1e-9);
                    let ahead = f(t + h, st);
                    relax = relax_for_slope(-(ahead - dist) / h, s.max_relax);
                }
                let step = if cooldown { 1.0 } else { relax };
                cooldown = false;
                let (tp, dp) = (t, dist);
                t += dist * step;
                dist = f(t, st);
                if step > 1.0 && (dist < 0.0 || dp + dist < (t - tp) * (1.0 - 1e-12)) {
                    // The spheres at tp and t do not cover the segment:
                    // retake the step plainly, and the next one too.
                    st.undone_steps += 1;
                    cooldown = true;
                    let (tr, dr) = (t, dist);
                    t = tp + dp;
                    dist = f(t, st);
                    // Rescue: if the plain step's sphere reaches the
                    // relaxed point's, the segment up to it is covered
                    // after all; go on from there (its distance is known).
                    if dr >= 0.0 && dist + dr >= (tr - t) * (1.0 + 1e-12) {
                        t = tr;
                        dist = dr;
                    }
                }
            }
        }
    }
    st.exhausted += 1;
    None
}

/// A ray generator for an orbit camera and an image size.
#[derive(Debug, Clone, Copy)]
pub struct Rays {
    pub origin: DVec3,
    forward: DVec3,
    right: DVec3,
    up: DVec3,
    tan_half: f64,
    width: u32,
    height: u32,
}

impl Rays {
    pub fn new(c: &Camera, width: u32, height: u32) -> Rays {
        let (yaw, pitch) = (c.yaw.to_radians(), c.pitch.to_radians());
        let dir = DVec3::new(
            libm::cos(pitch) * libm::cos(yaw),
            libm::cos(pitch) * libm::sin(yaw),
            libm::sin(pitch),
        );
        let target = DVec3::from_array(c.target);
        let origin = target + dir * c.distance;
        let forward = -dir;
        let mut right = forward.cross(DVec3::Z);
        if right.length() < 1e-9 {
            right = DVec3::X;
        }
        let right = right.normalize();
        let up = right.cross(forward);
        Rays {
            origin,
            forward,
            right,
            up,
            tan_half: libm::tan(c.fov.to_radians() * 0.5),
            width,
            height,
        }
    }

    /// The unit direction through the centre of pixel (x, y) (y down).
    pub fn dir(&self, x: u32, y: u32) -> DVec3 {
        let h = self.height as f64;
        let sx = (2.0 * (x as f64 + 0.5) - self.width as f64) / h;
        let sy = (h - 2.0 * (y as f64 + 0.5)) / h;
        (self.forward + self.right * (sx * self.tan_half) + self.up * (sy * self.tan_half))
            .normalize()
    }

    /// Angular size of a pixel (radians, approximately).
    pub fn pixel_angle(&self) -> f64 {
        2.0 * self.tan_half / self.height as f64
    }
}

/// The surface model.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Shading {
    /// Ambient + Lambert.
    #[default]
    Lambert,
    /// Ambient + Lambert + a GGX microfacet specular lobe.
    Ggx,
}

/// Shading settings.
#[derive(Debug, Clone, Copy)]
pub struct Shade {
    pub color: [u8; 3],
    pub background: [u8; 3],
    pub light: DVec3,
    /// Absorption per world unit travelled inside the sample before the hit.
    pub absorption: f64,
    pub shading: Shading,
    /// GGX: perceptual roughness (α = roughness²).
    pub roughness: f64,
    /// GGX: reflectance at normal incidence (0.04 for most dielectrics).
    pub specular: f64,
}

/// Ambient light and the light's strength (a white Lambert surface facing
/// the light gets `AMBIENT + LIGHT`).
pub const AMBIENT: f64 = 0.18;
pub const LIGHT: f64 = 0.82;

/// Beer–Lambert transmittance through `length` of a medium absorbing
/// `sigma` per unit length.
pub fn beer_lambert(sigma: f64, length: f64) -> f64 {
    libm::exp(-sigma * length.max(0.0))
}

/// Schlick's Fresnel reflectance for reflectance `f0` at normal incidence.
pub fn fresnel_schlick(f0: f64, cos: f64) -> f64 {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (1.0 - f0) * m
}

/// Trowbridge–Reitz (GGX) normal distribution `D(h)` for `α`.
pub fn ggx_d(n_h: f64, alpha: f64) -> f64 {
    let a2 = alpha * alpha;
    let c = n_h.max(0.0);
    let d = c * c * (a2 - 1.0) + 1.0;
    a2 / (std::f64::consts::PI * d * d)
}

/// Smith's masking for one direction (GGX): `G1(v) = 2 (n·v) / (n·v + √(α² + (1 − α²)(n·v)²))`.
pub fn smith_g1(n_v: f64, alpha: f64) -> f64 {
    let c = n_v.max(0.0);
    let a2 = alpha * alpha;
    2.0 * c / (c + (a2 + (1.0 - a2) * c * c).sqrt()).max(1e-300)
}

/// The GGX specular BRDF `D G F / (4 (n·l)(n·v))` for unit `n`, `v` (to
/// the viewer) and `l` (to the light); 0 below either horizon.
pub fn ggx_specular(n: DVec3, v: DVec3, l: DVec3, alpha: f64, f0: f64) -> f64 {
    let (n_l, n_v) = (n.dot(l), n.dot(v));
    if n_l <= 0.0 || n_v <= 0.0 {
        return 0.0;
    }
    let h = (v + l).normalize_or(n);
    let d = ggx_d(n.dot(h), alpha);
    let g = smith_g1(n_l, alpha) * smith_g1(n_v, alpha);
    let f = fresnel_schlick(f0, v.dot(h));
    d * g * f / (4.0 * n_l * n_v)
}

/// The brightness factors of a surface point with unit normal `n` seen
/// along `d`: (multiplier of the surface colour, white specular added).
pub fn surface(sh: &Shade, n: DVec3, d: DVec3) -> (f64, f64) {
    let l = sh.light;
    let n_l = n.dot(l).max(0.0);
    match sh.shading {
        Shading::Lambert => (AMBIENT + LIGHT * n_l, 0.0),
        Shading::Ggx => {
            let v = -d;
            let alpha = sh.roughness * sh.roughness;
            let h = (v + l).normalize_or(n);
            let f = fresnel_schlick(sh.specular, v.dot(h).max(0.0));
            let spec =
                ggx_specular(n, v, l, alpha, sh.specular) * n_l * LIGHT * std::f64::consts::PI;
            ((AMBIENT + LIGHT * n_l) * (1.0 - f), spec)
        }
    }
}

/// Shade a hit at distance `t` along `d` from `o`.
pub fn shade(
    scene: &Scene,
    o: DVec3,
    d: DVec3,
    t: Option<f64>,
    s: &Trace,
    sh: &Shade,
    st: &mut Stats,
) -> [u8; 4] {
    let Some(t) = t else {
        let [r, g, b] = sh.background;
        return [r, g, b, 255];
    };
    st.hits += 1;
    let p = o + d * t;
    let h = (s.precision * t * 0.5).max(1e-9);
    let n = sdf3::gradient(
        &mut |q| {
            st.sdf_evals += 1;
            field(scene, s.bounds, q)
        },
        p,
        h,
    )
    .normalize_or(-d);
    let (k, spec) = surface(sh, n, d);
    let t0 = clip(o, d, s.bounds * (1.0 + 1e-9) + 1e-12).map_or(t, |c| c.0);
    let absorb = beer_lambert(sh.absorption, t - t0);
    let c = |v: u8| {
        ((v as f64 * k + 255.0 * spec) * absorb)
            .round()
            .clamp(0.0, 255.0) as u8
    };
    [c(sh.color[0]), c(sh.color[1]), c(sh.color[2]), 255]
}

/// Path-tracing settings (`spp` > 0 in a render request).
#[derive(Debug, Clone, Copy)]
pub struct PathSettings {
    /// Most surface bounces of one path.
    pub max_depth: u32,
    /// Bounces before Russian roulette may end a path.
    pub roulette_after: u32,
}

/// A pixel direction through (x + u, y + v) (u, v ∈ [0, 1): a point in the pixel).
impl Rays {
    pub fn dir_at(&self, x: f64, y: f64) -> DVec3 {
        let h = self.height as f64;
        let sx = (2.0 * x - self.width as f64) / h;
        let sy = (h - 2.0 * y) / h;
        (self.forward + self.right * (sx * self.tan_half) + self.up * (sy * self.tan_half))
            .normalize()
    }
}

/// Unit normal of the clipped field at `p` (central differences, step `h`).
fn normal(scene: &Scene, s: &Trace, p: DVec3, h: f64, d: DVec3, st: &mut Stats) -> DVec3 {
    sdf3::gradient(
        &mut |q| {
            st.sdf_evals += 1;
            field(scene, s.bounds, q)
        },
        p,
        h,
    )
    .normalize_or(-d)
}

/// A cosine-weighted direction around the unit `n`.
fn cosine_dir(n: DVec3, u1: f64, u2: f64) -> DVec3 {
    let r = u1.sqrt();
    let phi = std::f64::consts::TAU * u2;
    let (a, b) = n.any_orthonormal_pair();
    (a * (r * libm::cos(phi)) + b * (r * libm::sin(phi)) + n * (1.0 - u1).max(0.0).sqrt())
        .normalize()
}

/// One path's radiance (linear RGB, 1 = the surface colour's full value)
/// for the camera ray `o + t d`: diffuse surfaces of the shade's colour lit
/// by the directional light (next-event estimation with a shadow ray) and
/// a uniform white sky of strength [`AMBIENT`]; the host medium absorbs
/// along every segment inside the box (Beer–Lambert); paths end when they
/// leave, after `max_depth` bounces, or by Russian roulette (survival =
/// the path's largest throughput, at most 0.95) after `roulette_after`.
/// Camera rays that miss see the background.
#[allow(clippy::too_many_arguments)]
pub fn path_radiance(
    scene: &Scene,
    o: DVec3,
    d: DVec3,
    s: &Trace,
    sh: &Shade,
    ps: &PathSettings,
    rng: &mut crate::core::rng::Rng,
    st: &mut Stats,
) -> DVec3 {
    let albedo = DVec3::new(sh.color[0] as f64, sh.color[1] as f64, sh.color[2] as f64) / 255.0;
    let bg = DVec3::new(
        sh.background[0] as f64,
        sh.background[1] as f64,
        sh.background[2] as f64,
    ) / 255.0;
    let b = s.bounds * (1.0 + 1e-9) + 1e-12;
    let (mut o, mut d) = (o, d);
    let mut beta = DVec3::ONE;
    let mut sum = DVec3::ZERO;
    let mut depth = 0;
    loop {
        let Some(t) = trace(scene, o, d, s, st) else {
            // Left the sample: the sky (through the medium up to the box's exit).
            let exit = clip(o, d, b).map_or(0.0, |c| c.1 - c.0);
            let sky = if depth == 0 {
                bg
            } else {
                DVec3::splat(AMBIENT)
            };
            let tr = if depth == 0 {
                1.0
            } else {
                beer_lambert(sh.absorption, exit)
            };
            sum += beta * sky * tr;
            break;
        };
        st.hits += (depth == 0) as u64;
        let t_in = clip(o, d, b).map_or(t, |c| c.0);
        beta *= beer_lambert(sh.absorption, t - t_in);
        let p = o + d * t;
        let h = (s.precision * t.max(1e-6) * 0.5).max(1e-9);
        let n = normal(scene, s, p, h, d, st);
        // Leave the surface by a few hit thresholds.
        let lift = (s.precision * t.max(1e-3) * 4.0).max(1e-7);
        let start = p + n * lift;
        // Next-event estimation: the directional light, if nothing is in the way.
        let n_l = n.dot(sh.light);
        if n_l > 0.0 && trace(scene, start, sh.light, s, st).is_none() {
            let exit = clip(start, sh.light, b).map_or(0.0, |c| c.1 - c.0);
            sum += beta * albedo * (LIGHT * n_l * beer_lambert(sh.absorption, exit));
        }
        depth += 1;
        if depth >= ps.max_depth {
            break;
        }
        beta *= albedo;
        if depth > ps.roulette_after {
            let q = beta.max_element().min(0.95);
            if q <= 0.0 || rng.f64() >= q {
                break;
            }
            beta /= q;
        }
        o = start;
        d = cosine_dir(n, rng.f64(), rng.f64());
    }
    sum
}

/// Colour of a slice value: inside warm, outside cool, darker bands
/// every `band`, the surface black.
pub fn slice_colour(v: f64, band: f64, grey: bool, range: f64) -> [u8; 4] {
    if grey {
        let g = (0.5 + 0.5 * (v / range)).clamp(0.0, 1.0);
        let g = (g * 255.0).round() as u8;
        return [g, g, g, 255];
    }
    let base: [f64; 3] = if v < 0.0 {
        [0.93, 0.55, 0.25]
    } else {
        [0.35, 0.55, 0.85]
    };
    let fade = 1.0 - 0.6 * (v.abs() / range).min(1.0);
    let frac = (v.abs() / band).fract();
    let stripe = if frac < 0.08 { 0.8 } else { 1.0 };
    let edge = (v.abs() / (band * 0.15)).min(1.0);
    let k = fade * stripe * edge;
    let c = |x: f64| (x * k * 255.0).round().clamp(0.0, 255.0) as u8;
    [c(base[0]), c(base[1]), c(base[2]), 255]
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// Directions on the upper hemisphere (z up) by a midpoint rule in
    /// (cos θ, φ): each with its solid angle.
    fn hemisphere(n: usize) -> Vec<(DVec3, f64)> {
        let mut out = vec![];
        let dw = (1.0 / n as f64) * (2.0 * PI / (4 * n) as f64);
        for i in 0..n {
            let c = (i as f64 + 0.5) / n as f64;
            let s = (1.0 - c * c).sqrt();
            for j in 0..4 * n {
                let phi = (j as f64 + 0.5) * 2.0 * PI / (4 * n) as f64;
                out.push((DVec3::new(s * libm::cos(phi), s * libm::sin(phi), c), dw));
            }
        }
        out
    }

    /// ∫ D(h) (n·h) dω = 1: the normal distribution is normalised.
    #[test]
    fn ggx_distribution_is_normalised() {
        for alpha in [0.2, 0.5, 1.0] {
            let total: f64 = hemisphere(800)
                .iter()
                .map(|(h, dw)| ggx_d(h.z, alpha) * h.z * dw)
                .sum();
            assert!((total - 1.0).abs() < 0.01, "α = {alpha}: {total}");
        }
    }

    /// f(v, l) = f(l, v), and the directional albedo ∫ f (n·l) dω stays
    /// below 1 (no energy is created) and grows with the Fresnel reflectance.
    #[test]
    fn ggx_is_reciprocal_and_conserves_energy() {
        let n = DVec3::Z;
        let dirs = hemisphere(120);
        for alpha in [0.1, 0.4, 0.9] {
            for cv in [0.1f64, 0.5, 0.95] {
                let v = DVec3::new((1.0 - cv * cv).sqrt(), 0.0, cv);
                let mut albedo = [0.0; 2];
                for (k, f0) in [0.04, 1.0].iter().enumerate() {
                    for (l, dw) in &dirs {
                        let f = ggx_specular(n, v, *l, alpha, *f0);
                        let g = ggx_specular(n, *l, v, alpha, *f0);
                        assert!((f - g).abs() <= 1e-9 * f.max(1.0), "{f} {g}");
                        albedo[k] += f * l.z * dw;
                    }
                }
                assert!(albedo[1] <= 1.0 + 1e-2, "α {alpha} cos {cv}: {}", albedo[1]);
                assert!(albedo[0] < albedo[1] && albedo[0] > 0.0);
            }
        }
        // Below the horizon: nothing.
        assert_eq!(ggx_specular(n, DVec3::Z, -DVec3::Z, 0.5, 0.04), 0.0);
    }

    /// Transmittance is 1 through nothing, falls strictly with thickness
    /// and with the absorption coefficient, and multiplies over segments.
    #[test]
    fn absorption_is_monotone_in_thickness() {
        assert_eq!(beer_lambert(3.0, 0.0), 1.0);
        let mut last = 1.0;
        for i in 1..50 {
            let t = beer_lambert(2.0, i as f64 * 0.05);
            assert!(t < last && t > 0.0);
            last = t;
        }
        assert!(beer_lambert(4.0, 0.3) < beer_lambert(2.0, 0.3));
        let split = beer_lambert(1.5, 0.2) * beer_lambert(1.5, 0.5);
        assert!((split - beer_lambert(1.5, 0.7)).abs() < 1e-15);
    }

    /// Path tracing is deterministic by seed, and deeper paths only add
    /// light (each bounce adds a non-negative term).
    #[test]
    fn path_tracing_is_deterministic_and_depth_adds_light() {
        use crate::core::rng::Rng;
        let scene = crate::micro::scene::parse(r#"{"type": "union", "children": [{"type": "sphere", "radius": 0.4}, {"type": "plane", "normal": [0, 0, 1], "offset": -0.4}]}"#).unwrap();
        let tr = Trace {
            mode: StepMode::Fixed,
            check_every: 10,
            check_cell: 0.0,
            check_modulus: 3,
            max_relax: 4.0,
            bisection_factor: 1.5,
            max_steps: 256,
            precision: 1e-3,
            bounds: 1.0,
        };
        let sh = Shade {
            color: [200, 180, 160],
            background: [10, 10, 10],
            light: DVec3::new(0.3, -0.2, 0.9).normalize(),
            absorption: 0.2,
            shading: Shading::Lambert,
            roughness: 0.3,
            specular: 0.04,
        };
        let o = DVec3::new(0.0, -2.5, 0.3);
        let d = (DVec3::new(0.05, 0.0, -0.45) - o).normalize();
        let run = |depth: u32, seed: u64| {
            let mut st = Stats::default();
            let mut acc = DVec3::ZERO;
            for k in 0..64 {
                let mut r = Rng::new(seed * 1000 + k);
                acc += path_radiance(
                    &scene,
                    o,
                    d,
                    &tr,
                    &sh,
                    &PathSettings {
                        max_depth: depth,
                        roulette_after: 100,
                    },
                    &mut r,
                    &mut st,
                );
            }
            acc / 64.0
        };
        assert_eq!(run(4, 1), run(4, 1));
        let (d1, d4) = (run(1, 3), run(4, 3));
        assert!(
            d4.x >= d1.x && d4.min_element() > d1.min_element() * 1.01,
            "{d1} {d4}"
        );
        assert!(d4.max_element() < 2.0);
    }

    /// GGX takes the Fresnel share from the diffuse term and adds a
    /// highlight where the half vector meets the normal.
    #[test]
    fn ggx_shading_adds_a_highlight_at_the_mirror_direction() {
        let l = DVec3::new(0.0, 0.6, 0.8);
        let mut sh = Shade {
            color: [200, 200, 200],
            background: [0; 3],
            light: l,
            absorption: 0.0,
            shading: Shading::Lambert,
            roughness: 0.3,
            specular: 0.04,
        };
        let n = DVec3::Z;
        let mirror = -DVec3::new(0.0, -0.6, 0.8); // the ray arrives along −(reflected l)
        let (k, s) = surface(&sh, n, mirror);
        assert_eq!(s, 0.0);
        assert!((k - (AMBIENT + LIGHT * 0.8)).abs() < 1e-12);
        sh.shading = Shading::Ggx;
        let (k2, s2) = surface(&sh, n, mirror);
        let (_, s3) = surface(&sh, n, -DVec3::new(0.6, 0.0, 0.8));
        assert!(k2 < k && s2 > 0.1 && s3 < s2 * 0.1, "{k2} {s2} {s3}");
    }
}
