//! The fractal models: 1/f^β noise (octave sums of value noise), Fourier
//! spectral synthesis (a random-phase spectrum shaped by 1/f^β and a
//! direction, inverse FFT) and midpoint displacement (diamond–square; the
//! 23rd model, see the module docs of `models`).
use super::common::{hash, ifft2, normalise, resample, standardise, unit, value_noise};
use super::{int, real, Family, Model, ParamSpec};

const ONE_OVER_F_PARAMS: &[ParamSpec] = &[
    real("beta", 0.5, 3.5, 2.0),
    int("frequency", 2.0, 16.0, 4.0),
    int("octaves", 2.0, 7.0, 5.0),
];

/// Octaves of value noise from `frequency` cells per side, the octave at
/// frequency f weighted by f^(−β/2) (a power spectrum falling as 1/f^β):
/// small β is rough, large β smooth.
pub const ONE_OVER_F: Model = Model {
    id: "fractal-one-over-f",
    name: "Fractal (one-over-f-beta noise)",
    family: Family::Fractal,
    params: ONE_OVER_F_PARAMS,
    generate: one_over_f,
};

fn one_over_f(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    one_over_f_raw(n, p[0] as f32, p[1] as u32, p[2] as u32, seed)
}

/// Normalised 1/f^β noise (shared by folding).
pub(crate) fn one_over_f_raw(n: usize, beta: f32, freq: u32, octaves: u32, seed: u64) -> Vec<f32> {
    let mut h = vec![0.0f32; n * n];
    let gain = libm::powf(2.0, -beta / 2.0);
    let mut amp = 1.0;
    let mut period = freq.max(1);
    for o in 0..octaves {
        let s = seed ^ (0xa076_1d64_78bd_642f_u64.wrapping_mul(o as u64 + 1));
        let k = period as f32 / n as f32;
        for y in 0..n {
            for x in 0..n {
                h[y * n + x] +=
                    amp * value_noise((x as f32 + 0.5) * k, (y as f32 + 0.5) * k, period, s);
            }
        }
        amp *= gain;
        period *= 2;
    }
    normalise(&mut h);
    h
}

const SPECTRAL_PARAMS: &[ParamSpec] = &[
    real("beta", 1.5, 4.0, 2.8),
    real("direction", 0.0, 180.0, 45.0),
    real("spread", 5.0, 180.0, 180.0),
    real("rms", 0.05, 0.3, 0.18),
];

/// Fourier spectral synthesis (the paper's §5.4 example, parameters RMS,
/// DDir and the angular variance): amplitudes f^(−β/2) times a Gaussian
/// in the angle between a frequency and `direction` (σ = `spread`
/// degrees; 180 is nearly isotropic), random phases, inverse FFT, then
/// heights of standard deviation `rms` around 0.5.
pub const SPECTRAL: Model = Model {
    id: "fractal-fourier",
    name: "Fractal (Fourier spectral synthesis)",
    family: Family::Fractal,
    params: SPECTRAL_PARAMS,
    generate: spectral,
};

fn spectral(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let m = n.next_power_of_two().max(8);
    let beta = p[0] as f32;
    let dir = (p[1] as f32).to_radians();
    let sigma = (p[2] as f32).to_radians();
    let mut re = vec![0.0f32; m * m];
    let mut im = vec![0.0f32; m * m];
    let signed = |i: usize| {
        if i < m / 2 {
            i as i64
        } else {
            i as i64 - m as i64
        }
    };
    for y in 0..m {
        let ky = signed(y);
        for x in 0..m {
            let kx = signed(x);
            if kx == 0 && ky == 0 {
                continue;
            }
            let f = ((kx * kx + ky * ky) as f32).sqrt();
            // Angle of the wave vector relative to the direction, folded to
            // [−π/2, π/2] (a wave and its opposite are the same stripes).
            let mut d = libm::atan2f(ky as f32, kx as f32) - dir;
            d = d - std::f32::consts::PI * libm::roundf(d / std::f32::consts::PI);
            let w = libm::expf(-d * d / (2.0 * sigma * sigma));
            let a = libm::powf(f, -beta / 2.0) * w;
            // Phases keyed by the signed frequency, so sizes agree.
            let ph = std::f32::consts::TAU * unit(hash(kx as u32, ky as u32, seed));
            re[y * m + x] = a * libm::cosf(ph);
            im[y * m + x] = a * libm::sinf(ph);
        }
    }
    ifft2(&mut re, &mut im, m);
    let mut h = resample(&re, m, n);
    standardise(&mut h, p[3] as f32);
    h
}

const MIDPOINT_PARAMS: &[ParamSpec] = &[
    real("roughness", 0.1, 0.95, 0.6),
    int("start", 0.0, 4.0, 2.0),
    real("ridged", 0.0, 1.0, 0.0),
];

/// Midpoint displacement (diamond–square) on a torus: 2^`start` random
/// points per side, then each halving of the spacing adds midpoints
/// displaced by a random amount shrinking by 2^−H, H = 1 − `roughness`;
/// `ridged` blends toward 1 − |2h − 1| (ridges).
pub const MIDPOINT: Model = Model {
    id: "fractal-midpoint",
    name: "Fractal (midpoint displacement)",
    family: Family::Fractal,
    params: MIDPOINT_PARAMS,
    generate: midpoint,
};

fn midpoint(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let m = n.next_power_of_two().max(16);
    let hurst = 1.0 - p[0] as f32;
    let start = 1usize << (p[1] as usize);
    let ridged = p[2] as f32;
    // Random values keyed by the point's position on a fixed 4096 lattice,
    // so renders at different sizes share their coarse structure.
    let key = 4096 / m.min(4096);
    let rnd = |x: usize, y: usize| unit(hash((x * key) as u32, (y * key) as u32, seed)) * 2.0 - 1.0;
    let mut h = vec![0.0f32; m * m];
    let mut step = m / start.min(m);
    for y in (0..m).step_by(step) {
        for x in (0..m).step_by(step) {
            h[y * m + x] = rnd(x, y);
        }
    }
    let mut scale = 1.0f32;
    let at = |h: &[f32], x: isize, y: isize| {
        h[(y.rem_euclid(m as isize) as usize) * m + x.rem_euclid(m as isize) as usize]
    };
    while step > 1 {
        let half = step / 2;
        scale *= libm::powf(2.0, -hurst);
        for y in (0..m).step_by(step) {
            for x in (0..m).step_by(step) {
                let (xi, yi, s) = (x as isize, y as isize, step as isize);
                let avg = (at(&h, xi, yi)
                    + at(&h, xi + s, yi)
                    + at(&h, xi, yi + s)
                    + at(&h, xi + s, yi + s))
                    * 0.25;
                h[(y + half) * m + x + half] = avg + scale * rnd(x + half, y + half);
            }
        }
        for y in (0..m).step_by(half) {
            let odd_row = (y / half) % 2 == 1;
            let x0 = if odd_row { 0 } else { half };
            for x in (x0..m).step_by(step) {
                let (xi, yi, hh) = (x as isize, y as isize, half as isize);
                let avg = (at(&h, xi - hh, yi)
                    + at(&h, xi + hh, yi)
                    + at(&h, xi, yi - hh)
                    + at(&h, xi, yi + hh))
                    * 0.25;
                h[y * m + x] = avg + scale * rnd(x, y);
            }
        }
        step = half;
    }
    normalise(&mut h);
    for v in &mut h {
        *v += ridged * ((1.0 - (2.0 * *v - 1.0).abs()) - *v);
    }
    let mut out = resample(&h, m, n);
    normalise(&mut out);
    out
}
