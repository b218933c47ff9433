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
    let mut out = vec![0.0f32; n * n];
    let mut amp = 1.0f32;
    let mut period = base.max(1);
    for o in 0..octaves.max(1) {
        let s = seed.wrapping_add(0x51_7cc1_b727_220a_u64.wrapping_mul(o as u64 + 1));
        let scale = period as f32 / n as f32;
        for y in 0..n {
            let fy = (y as f32 + 0.5) * scale;
            for x in 0..n {
                let v = gradient_noise((x as f32 + 0.5) * scale, fy, period, s);
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
/// Returns (F1, F2) in cell units.
pub fn worley(n: usize, cells: u32, jitter: f32, seed: u64) -> (Vec<f32>, Vec<f32>) {
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
    let scale = c as f32 / n as f32;
    for y in 0..n {
        let py = (y as f32 + 0.5) * scale;
        let cy = py.floor() as i64;
        for x in 0..n {
            let px = (x as f32 + 0.5) * scale;
            let cx = px.floor() as i64;
            let (mut d1, mut d2) = (f32::MAX, f32::MAX);
            for dy in -1..=1 {
                for dx in -1..=1 {
                    let (gx, gy) = (cx + dx, cy + dy);
                    let (ox, oy) = pts[(gy.rem_euclid(c) * c + gx.rem_euclid(c)) as usize];
                    let ex = gx as f32 + ox - px;
                    let ey = gy as f32 + oy - py;
                    let d = (ex * ex + ey * ey).sqrt();
                    if d < d1 {
                        d2 = d1;
                        d1 = d;
                    } else if d < d2 {
                        d2 = d;
                    }
                }
            }
            f1[y * n + x] = d1;
            f2[y * n + x] = d2;
        }
    }
    (f1, f2)
}

/// The number of texton shapes [`texton`] knows.
pub const SHAPES: usize = 5;

/// A texton's height at local coordinates (u, v) (the texton fills the unit
/// disk / square): 0 bump, 1 pyramid, 2 cross, 3 ring, 4 bar.
#[inline]
pub fn texton(shape: usize, u: f32, v: f32) -> f32 {
    let (au, av) = (u.abs(), v.abs());
    if au >= 1.0 || av >= 1.0 {
        return 0.0;
    }
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
