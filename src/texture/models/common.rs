//! Building blocks the models share: tileable gradient and value noise,
//! Worley distances, texton stamping, triangle-wave folding, wrapped blurs
//! and resampling, and the inverse 2-D FFT of spectral synthesis.
//!
//! Every coordinate is in image units (the image is the unit torus
//! `[0, 1)²`), so a model looks the same at 128² and 256²; everything that
//! can wrap does, so the textures tile. Transcendental functions come from
//! `libm` so native and wasm give the same bits.
use crate::core::rng::Rng;

/// A 64-bit mix of two lattice coordinates and a seed.
#[inline]
pub fn hash(x: u32, y: u32, seed: u64) -> u64 {
    let mut h = seed ^ 0x243f_6a88_85a3_08d3;
    h ^= (x as u64).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    h = h.rotate_left(31).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    h ^= (y as u64).wrapping_mul(0xc2b2_ae3d_27d4_eb4f);
    h = h.rotate_left(29).wrapping_mul(0x94d0_49bb_1331_11eb);
    h ^ (h >> 32)
}

/// A uniform number in [0, 1) from a hash.
#[inline]
pub fn unit(h: u64) -> f32 {
    (h >> 40) as f32 * (1.0 / (1u64 << 24) as f32)
}

const R: f32 = std::f32::consts::FRAC_1_SQRT_2;
const GRAD: [(f32, f32); 8] = [
    (1.0, 0.0),
    (-1.0, 0.0),
    (0.0, 1.0),
    (0.0, -1.0),
    (R, R),
    (-R, R),
    (R, -R),
    (-R, -R),
];

#[inline]
fn fade(t: f32) -> f32 {
    t * t * t * (t * (t * 6.0 - 15.0) + 10.0)
}

#[inline]
fn lattice(v: f32, period: u32) -> (u32, u32, f32) {
    let f = v.floor();
    let p = period.max(1) as i64;
    let i = (f as i64).rem_euclid(p) as u32;
    (i, ((i as i64 + 1) % p) as u32, v - f)
}

/// Gradient noise in about [-1, 1] at lattice coordinates (x, y), periodic
/// with `period` lattice cells in both directions.
pub fn gradient_noise(x: f32, y: f32, period: u32, seed: u64) -> f32 {
    let (x0, x1, fx) = lattice(x, period);
    let (y0, y1, fy) = lattice(y, period);
    let g = |ix: u32, iy: u32, ox: f32, oy: f32| {
        let (gx, gy) = GRAD[(hash(ix, iy, seed) >> 61) as usize];
        gx * ox + gy * oy
    };
    let (u, v) = (fade(fx), fade(fy));
    let a = g(x0, y0, fx, fy);
    let b = g(x1, y0, fx - 1.0, fy);
    let c = g(x0, y1, fx, fy - 1.0);
    let d = g(x1, y1, fx - 1.0, fy - 1.0);
    let ab = a + u * (b - a);
    let cd = c + u * (d - c);
    (ab + v * (cd - ab)) * std::f32::consts::SQRT_2
}

/// Value noise in [0, 1] (smoothly interpolated random lattice values),
/// periodic with `period` cells.
pub fn value_noise(x: f32, y: f32, period: u32, seed: u64) -> f32 {
    let (x0, x1, fx) = lattice(x, period);
    let (y0, y1, fy) = lattice(y, period);
    let v = |ix, iy| unit(hash(ix, iy, seed));
    let (u, w) = (fade(fx), fade(fy));
    let ab = v(x0, y0) + u * (v(x1, y0) - v(x0, y0));
    let cd = v(x0, y1) + u * (v(x1, y1) - v(x0, y1));
    ab + w * (cd - ab)
}

/// Octaves of tileable gradient noise on an `n`×`n` image: `base` cells per
/// image side at the first octave, doubling each octave, amplitude times
/// `gain` per octave; `turbulence` in [0, 1] blends toward |noise|.
pub fn fbm(n: usize, base: u32, octaves: u32, gain: f32, turbulence: f32, seed: u64) -> Vec<f32> {
    fbm_with(n, base, octaves, gain, turbulence, Basis::Gradient, seed)
}

/// The lattice noise an octave sum is made of: Perlin's gradient noise
/// (smooth, no lattice-aligned plateaus) or value noise (random heights at
/// the lattice points, interpolated: blockier, with visible lattice
/// alignment at few octaves).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Basis {
    Gradient,
    Value,
}

/// [`fbm`] over either [`Basis`]. Value noise is centred to about [-1, 1]
/// and its octaves are seeded as `fractal-one-over-f`'s are, so that its
/// octave sum at persistence 0.5 is that model's at β = 2 (up to an
/// affine map, which normalising removes).
pub fn fbm_with(
    n: usize,
    base: u32,
    octaves: u32,
    gain: f32,
    turbulence: f32,
    basis: Basis,
    seed: u64,
) -> Vec<f32> {
    let mut out = vec![0.0f32; n * n];
    let mut amp = 1.0f32;
    let mut period = base.max(1);
    for o in 0..octaves.max(1) {
        let s = match basis {
            Basis::Gradient => {
                seed.wrapping_add(0x51_7cc1_b727_220a_u64.wrapping_mul(o as u64 + 1))
            }
            Basis::Value => seed ^ 0xa076_1d64_78bd_642f_u64.wrapping_mul(o as u64 + 1),
        };
        let scale = period as f32 / n as f32;
        for y in 0..n {
            let fy = (y as f32 + 0.5) * scale;
            for x in 0..n {
                let fx = (x as f32 + 0.5) * scale;
                let v = match basis {
                    Basis::Gradient => gradient_noise(fx, fy, period, s),
                    Basis::Value => value_noise(fx, fy, period, s) * 2.0 - 1.0,
                };
                let v = v + turbulence * (v.abs() * 2.0 - 0.6 - v);
                out[y * n + x] += amp * v;
            }
        }
        amp *= gain;
        period = period.saturating_mul(2).min(1 << 16);
    }
    out
}

/// Worley (cellular) distances on an `n`×`n` torus: `cells` feature points
/// per side, one per cell, displaced by `jitter` in [0, 1] of a cell.
/// Returns (F1, F2) in cell units (Euclidean).
pub fn worley(n: usize, cells: u32, jitter: f32, seed: u64) -> (Vec<f32>, Vec<f32>) {
    let w = worley_with(n, cells, jitter, Metric::Euclidean, seed);
    (w.f1, w.f2)
}

/// The distance [`worley_with`] measures: Euclidean (round cells),
/// Manhattan (|dx| + |dy|: diamond-like cells with straight, diagonal
/// walls) or Chebyshev (max(|dx|, |dy|): square-cornered cells).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    Euclidean,
    Manhattan,
    Chebyshev,
}

impl Metric {
    /// 0 Euclidean, 1 Manhattan, anything else Chebyshev.
    pub fn from_index(i: usize) -> Metric {
        match i {
            0 => Metric::Euclidean,
            1 => Metric::Manhattan,
            _ => Metric::Chebyshev,
        }
    }
}

/// Worley distances per pixel: the nearest and second-nearest feature
/// point's distances (cell units) and the nearest one's cell (`y·cells +
/// x`, for per-cell values).
pub struct Worley {
    pub f1: Vec<f32>,
    pub f2: Vec<f32>,
    pub id: Vec<u32>,
}

/// [`worley`] under `metric`, with the nearest point's cell.
pub fn worley_with(n: usize, cells: u32, jitter: f32, metric: Metric, seed: u64) -> Worley {
    let c = cells.max(1) as i64;
    let pts: Vec<(f32, f32)> = (0..c * c)
        .map(|i| {
            let (cx, cy) = ((i % c) as u32, (i / c) as u32);
            let h = hash(cx, cy, seed);
            let jx = unit(h) - 0.5;
            let jy = unit(h.rotate_left(24)) - 0.5;
            (0.5 + jitter * jx, 0.5 + jitter * jy)
        })
        .collect();
    let mut f1 = vec![0.0f32; n * n];
    let mut f2 = vec![0.0f32; n * n];
    let mut id = vec![0u32; n * n];
    let scale = c as f32 / n as f32;
    for y in 0..n {
        let py = (y as f32 + 0.5) * scale;
        let cy = py.floor() as i64;
        for x in 0..n {
            let px = (x as f32 + 0.5) * scale;
            let cx = px.floor() as i64;
            let (mut d1, mut d2, mut i1) = (f32::MAX, f32::MAX, 0u32);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (gx, gy) = (cx + dx, cy + dy);
                    let cell = gy.rem_euclid(c) * c + gx.rem_euclid(c);
                    let (ox, oy) = pts[cell as usize];
                    let ex = gx as f32 + ox - px;
                    let ey = gy as f32 + oy - py;
                    let d = match metric {
                        Metric::Euclidean => (ex * ex + ey * ey).sqrt(),
                        Metric::Manhattan => ex.abs() + ey.abs(),
                        Metric::Chebyshev => ex.abs().max(ey.abs()),
                    };
                    if d < d1 {
                        d2 = d1;
                        d1 = d;
                        i1 = cell as u32;
                    } else if d < d2 {
                        d2 = d;
                    }
                }
            }
            f1[y * n + x] = d1;
            f2[y * n + x] = d2;
            id[y * n + x] = i1;
        }
    }
    Worley { f1, f2, id }
}

/// The number of texton shapes [`texton`] knows.
pub const SHAPES: usize = 19;

/// Every shape's name, by index (what the `shape` parameters select).
pub const SHAPE_NAMES: [&str; SHAPES] = [
    "bump",
    "pyramid",
    "cross",
    "ring",
    "bar",
    "flat disc",
    "cone",
    "flat square",
    "domed square",
    "flat triangle",
    "triangular pyramid",
    "flat hexagon",
    "domed hexagon",
    "flat five-point star",
    "conical five-point star",
    "conical four-point star",
    "domed six-point star",
    "flat cross",
    "flat ring",
];

/// The shapes with a flat top (where many overlap, one plateau).
pub const FLAT_TOPPED: [usize; 7] = [5, 7, 9, 11, 13, 17, 18];

/// How a texton rises inside its outline.
#[derive(Clone, Copy)]
enum Profile {
    /// A flat top with a steep rim (the outer 15% of the radius).
    Flat,
    /// A half-ellipsoid: round, steepest at the outline.
    Domed,
    /// Straight sides up to a point (a cone or a pyramid).
    Conical,
}

/// The height of a profile at gauge `g` (0 at the centre, 1 on the
/// outline, more outside).
#[inline]
fn profile(p: Profile, g: f32) -> f32 {
    if g >= 1.0 {
        return 0.0;
    }
    match p {
        Profile::Flat => {
            let t = ((1.0 - g) / 0.15).min(1.0);
            t * t * (3.0 - 2.0 * t)
        }
        Profile::Domed => (1.0 - g * g).sqrt(),
        Profile::Conical => 1.0 - g,
    }
}

const SIN_60: f32 = 0.866_025_4;

/// The gauge of an equilateral triangle of circumradius 1 with a vertex on
/// +x (centred on its centroid): the largest of its sides' normal
/// coordinates over the inradius ½.
#[inline]
fn triangle_gauge(u: f32, v: f32) -> f32 {
    let a = 0.5 * u + SIN_60 * v;
    let b = 0.5 * u - SIN_60 * v;
    a.max(b).max(-u) * 2.0
}

/// The gauge of a regular hexagon of circumradius 1 with a vertex on +x.
#[inline]
fn hexagon_gauge(u: f32, v: f32) -> f32 {
    let a = (SIN_60 * u + 0.5 * v).abs();
    let b = (SIN_60 * u - 0.5 * v).abs();
    a.max(b).max(v.abs()) / SIN_60
}

/// The gauge of a star of `k` points (outer radius 1, inner radius
/// `inner`): the radius over the outline's radius at that angle, the
/// outline running straight in angle between tips and notches.
#[inline]
fn star_gauge(k: u32, inner: f32, u: f32, v: f32) -> f32 {
    let rho = (u * u + v * v).sqrt();
    if rho < 1e-6 {
        return 0.0;
    }
    if rho >= 1.0 {
        // Outside every tip (and most of a stamp's square): no angle needed.
        return rho;
    }
    let step = 2.0 * std::f32::consts::PI / k as f32;
    let a = libm::atan2f(v, u).rem_euclid(step) / step; // 0 and 1 at tips
    let tip = (2.0 * a - 1.0).abs(); // 1 at a tip, 0 at a notch
    rho / (inner + (1.0 - inner) * tip)
}

/// A texton's height at local coordinates (u, v) (the texton fills the unit
/// disk / square), by shape index ([`SHAPE_NAMES`]): 0 bump, 1 pyramid,
/// 2 cross, 3 ring, 4 bar, then outlines (disc, square, triangle,
/// hexagon, stars of 4, 5 and 6 points, plus sign, annulus) under flat,
/// domed and conical profiles.
#[inline]
pub fn texton(shape: usize, u: f32, v: f32) -> f32 {
    let (au, av) = (u.abs(), v.abs());
    if au >= 1.0 || av >= 1.0 {
        return 0.0;
    }
    let disc = || (u * u + v * v).sqrt();
    match shape {
        0 => {
            let d2 = u * u + v * v;
            if d2 < 1.0 {
                (1.0 - d2) * (1.0 - d2)
            } else {
                0.0
            }
        }
        1 => 1.0 - au.max(av),
        2 => {
            let arm = |a: f32, b: f32| {
                if b < 0.3 {
                    (1.0 - (b / 0.3) * (b / 0.3)) * (1.0 - a * a * a * a)
                } else {
                    0.0
                }
            };
            arm(au, av).max(arm(av, au))
        }
        3 => {
            let d = (u * u + v * v).sqrt();
            let t = (d - 0.7) / 0.25;
            (1.0 - t * t).max(0.0)
        }
        5 => profile(Profile::Flat, disc()),
        6 => profile(Profile::Conical, disc()),
        // Squares of side 1.6 (inside the unit square, with room to turn
        // a little before the corners clip).
        7 => profile(Profile::Flat, au.max(av) / 0.8),
        8 => profile(Profile::Domed, au.max(av) / 0.8),
        9 => profile(Profile::Flat, triangle_gauge(u, v)),
        10 => profile(Profile::Conical, triangle_gauge(u, v)),
        11 => profile(Profile::Flat, hexagon_gauge(u, v)),
        12 => profile(Profile::Domed, hexagon_gauge(u, v)),
        13 => profile(Profile::Flat, star_gauge(5, 0.45, u, v)),
        14 => profile(Profile::Conical, star_gauge(5, 0.45, u, v)),
        15 => profile(Profile::Conical, star_gauge(4, 0.35, u, v)),
        16 => profile(Profile::Domed, star_gauge(6, 0.55, u, v)),
        // A plus sign of arms 0.6 wide, flat-topped.
        17 => profile(
            Profile::Flat,
            (au.max(av / 0.3)).min(av.max(au / 0.3)) / 0.95,
        ),
        // An annulus of radii 0.45 and 0.95, flat-topped.
        18 => profile(Profile::Flat, (disc() - 0.7).abs() / 0.25),
        // 4, the bar (and any larger index).
        _ => {
            if av < 0.3 {
                (1.0 - (av / 0.3) * (av / 0.3)) * (1.0 - au * au * au * au)
            } else {
                0.0
            }
        }
    }
}

/// How stamped textons combine with what is already there.
#[derive(Clone, Copy, PartialEq)]
pub enum Combine {
    Max,
    Add,
}

/// One texton placed on the torus.
#[derive(Clone, Copy)]
pub struct Stamp {
    /// Centre in image units.
    pub x: f32,
    pub y: f32,
    /// Radius in image units.
    pub r: f32,
    /// Rotation in radians.
    pub angle: f32,
    pub shape: usize,
    pub amp: f32,
}

/// Draw `s` into the `n`×`n` height map `h` (wrapping around the edges).
pub fn stamp(h: &mut [f32], n: usize, s: &Stamp, combine: Combine) {
    let r = s.r.clamp(0.5 / n as f32, 0.5);
    let (cs, sn) = (libm::cosf(s.angle), libm::sinf(s.angle));
    let reach = r * std::f32::consts::SQRT_2;
    let x0 = ((s.x - reach) * n as f32).floor() as i64;
    let x1 = ((s.x + reach) * n as f32).ceil() as i64;
    let y0 = ((s.y - reach) * n as f32).floor() as i64;
    let y1 = ((s.y + reach) * n as f32).ceil() as i64;
    let ni = n as i64;
    let inv = 1.0 / (r * n as f32);
    for py in y0..=y1 {
        let dy = (py as f32 + 0.5) - s.y * n as f32;
        let row = py.rem_euclid(ni) as usize * n;
        for px in x0..=x1 {
            let dx = (px as f32 + 0.5) - s.x * n as f32;
            let u = (dx * cs + dy * sn) * inv;
            let v = (-dx * sn + dy * cs) * inv;
            let t = texton(s.shape, u, v) * s.amp;
            if t <= 0.0 {
                continue;
            }
            let cell = &mut h[row + px.rem_euclid(ni) as usize];
            match combine {
                Combine::Max => *cell = cell.max(t),
                Combine::Add => *cell += t,
            }
        }
    }
}

/// Triangle-wave folding of a height map normalised to [0, 1]: `folds`
/// rises and falls across the range (1 keeps it a ramp).
pub fn fold(h: &mut [f32], folds: f32) {
    normalise(h);
    for v in h.iter_mut() {
        let t = *v * folds;
        *v = 1.0 - ((t % 2.0) - 1.0).abs();
    }
}

/// Stretch to [0, 1]; a constant becomes 0.5.
pub fn normalise(h: &mut [f32]) {
    let (lo, hi) = h
        .iter()
        .fold((f32::INFINITY, f32::NEG_INFINITY), |(l, u), &v| {
            (l.min(v), u.max(v))
        });
    let span = hi - lo;
    for v in h.iter_mut() {
        *v = if span > 1e-9 && span.is_finite() {
            (*v - lo) / span
        } else {
            0.5
        };
    }
}

/// Mean and standard deviation.
pub fn mean_std(h: &[f32]) -> (f32, f32) {
    let n = h.len().max(1) as f64;
    let m = h.iter().map(|&v| v as f64).sum::<f64>() / n;
    let var = h
        .iter()
        .map(|&v| (v as f64 - m) * (v as f64 - m))
        .sum::<f64>()
        / n;
    (m as f32, var.sqrt() as f32)
}

/// Standardise to mean 0.5 and standard deviation `sd` (then clamp to [0, 1]).
pub fn standardise(h: &mut [f32], sd: f32) {
    let (m, s) = mean_std(h);
    let k = if s > 1e-9 { sd / s } else { 0.0 };
    for v in h.iter_mut() {
        *v = (0.5 + (*v - m) * k).clamp(0.0, 1.0);
    }
}

/// Bilinear resampling of a `g`×`g` torus to `n`×`n` (wrapping).
pub fn resample(src: &[f32], g: usize, n: usize) -> Vec<f32> {
    if g == n {
        return src.to_vec();
    }
    let k = g as f32 / n as f32;
    let gi = g as i64;
    let idx: Vec<(usize, usize, f32)> = (0..n)
        .map(|i| {
            let s = (i as f32 + 0.5) * k - 0.5;
            let f = s.floor();
            let a = (f as i64).rem_euclid(gi) as usize;
            (a, (a + 1) % g, s - f)
        })
        .collect();
    let mut out = vec![0.0f32; n * n];
    for (y, &(y0, y1, fy)) in idx.iter().enumerate() {
        for (x, &(x0, x1, fx)) in idx.iter().enumerate() {
            let a = src[y0 * g + x0] + fx * (src[y0 * g + x1] - src[y0 * g + x0]);
            let b = src[y1 * g + x0] + fx * (src[y1 * g + x1] - src[y1 * g + x0]);
            out[y * n + x] = a + fy * (b - a);
        }
    }
    out
}

/// Wrapped box blur of radius `r` (separable, one pass each way).
pub fn box_blur(h: &mut [f32], n: usize, r: usize) {
    if r == 0 || n == 0 {
        return;
    }
    let r = r.min(n / 2);
    let k = 1.0 / (2 * r + 1) as f32;
    let mut tmp = vec![0.0f32; n];
    for y in 0..n {
        let row = &mut h[y * n..(y + 1) * n];
        let mut acc: f32 = (0..=2 * r).map(|i| row[(i + n - r) % n]).sum();
        for x in 0..n {
            tmp[x] = acc * k;
            acc += row[(x + r + 1) % n] - row[(x + n - r) % n];
        }
        row.copy_from_slice(&tmp);
    }
    for x in 0..n {
        let mut acc: f32 = (0..=2 * r).map(|i| h[((i + n - r) % n) * n + x]).sum();
        for y in 0..n {
            tmp[y] = acc * k;
            acc += h[((y + r + 1) % n) * n + x] - h[((y + n - r) % n) * n + x];
        }
        for y in 0..n {
            h[y * n + x] = tmp[y];
        }
    }
}

/// Random placements: `count` uniform points on the torus.
pub fn scatter(count: usize, rng: &mut Rng) -> Vec<(f32, f32)> {
    (0..count)
        .map(|_| (rng.f64() as f32, rng.f64() as f32))
        .collect()
}

/// 2-D inverse FFT of an `m`×`m` spectrum (m a power of two), in place,
/// unscaled: the crate's one FFT ([`crate::geom::fft::fft2`]).
pub fn ifft2(re: &mut [f32], im: &mut [f32], m: usize) {
    crate::geom::fft::fft2(re, im, m, m, true)
        .expect("spectral synthesis works on power-of-two squares");
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gradient_noise_tiles_with_its_period() {
        for i in 0..50 {
            let (x, y) = (i as f32 * 0.37, i as f32 * 0.19);
            let a = gradient_noise(x, y, 4, 9);
            let b = gradient_noise(x + 4.0, y - 8.0, 4, 9);
            assert!((a - b).abs() < 1e-5, "{a} {b}");
            assert!(a.abs() <= 1.5);
        }
    }

    #[test]
    fn ifft2_of_a_single_coefficient_is_a_plane_wave() {
        let m = 8;
        let (mut re, mut im) = (vec![0.0f32; m * m], vec![0.0f32; m * m]);
        re[1] = 1.0; // kx = 1, ky = 0
        ifft2(&mut re, &mut im, m);
        for y in 0..m {
            for x in 0..m {
                let a = std::f64::consts::TAU * x as f64 / m as f64;
                assert!((re[y * m + x] as f64 - a.cos()).abs() < 1e-6);
                assert!((im[y * m + x] as f64 - a.sin()).abs() < 1e-6);
            }
        }
    }

    #[test]
    fn box_blur_keeps_the_mean() {
        let mut h: Vec<f32> = (0..64).map(|i| (i % 7) as f32).collect();
        let before: f32 = h.iter().sum();
        box_blur(&mut h, 8, 2);
        let after: f32 = h.iter().sum();
        assert!((before - after).abs() < 1e-3);
    }
}
