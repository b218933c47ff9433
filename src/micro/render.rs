//! Sphere tracing of a Micro scene (paper §4–5) with fixed, bisection and
//! adaptive step lengths, normals by central differences, Lambert shading
//! with simple absorption, an orbit camera, and z-slices of the field.
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
//! - `adaptive`: every `check_every` steps, estimate the local gradient
//!   magnitude g (6 evaluations); where the normalised field is clearly
//!   flatter than its bound (g < 0.7) step `0.9 distance / g` (at most
//!   `max_relax` × distance). A step whose unbounding spheres do not
//!   overlap is undone and retaken plainly (over-relaxed sphere tracing,
//!   Keinert et al. 2014), so it misses nothing fixed steps would find.
use super::scene::Scene;
use crate::geom::sdf3;
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
    let mut relax = 1.0f64;
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
                    i == 0 || (fresh && (q.x + 2.0 * q.y + 3.0 * q.z).rem_euclid(m) == 0.0)
                } else {
                    i % s.check_every.max(1) == 0
                };
                if check {
                    st.gradient_checks += 1;
                    let h = (s.precision * t).max(1e-9);
                    let p = o + d * t;
                    let g = sdf3::gradient(
                        &mut |q| {
                            st.sdf_evals += 1;
                            field(scene, s.bounds, q)
                        },
                        p,
                        h,
                    )
                    .length();
                    // Over-relax only where the bound is clearly loose
                    // (g < 0.7), with a 10% margin.
                    relax = if g < 0.7 {
                        (0.9 / g.max(1e-9)).clamp(1.0, s.max_relax)
                    } else {
                        1.0
                    };
                }
                let (tp, dp) = (t, dist);
                t += dist * relax;
                dist = f(t, st);
                if relax > 1.0 && (dist < 0.0 || dp + dist < (t - tp) * (1.0 - 1e-12)) {
                    // The spheres at tp and t do not cover the segment: undo.
                    st.undone_steps += 1;
                    relax = 1.0;
                    t = tp + dp;
                    dist = f(t, st);
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

/// Shading settings.
#[derive(Debug, Clone, Copy)]
pub struct Shade {
    pub color: [u8; 3],
    pub background: [u8; 3],
    pub light: DVec3,
    /// Absorption per world unit travelled inside the sample before the hit.
    pub absorption: f64,
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
    let lambert = n.dot(sh.light).max(0.0);
    let t0 = clip(o, d, s.bounds * (1.0 + 1e-9) + 1e-12).map_or(t, |c| c.0);
    let absorb = libm::exp(-sh.absorption * (t - t0).max(0.0));
    let k = (0.18 + 0.82 * lambert) * absorb;
    let c = |v: u8| (v as f64 * k).round().clamp(0.0, 255.0) as u8;
    [c(sh.color[0]), c(sh.color[1]), c(sh.color[2]), 255]
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
