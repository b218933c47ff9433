//! Perlin noise: octaves of tileable gradient noise (Perlin 1985/2002) or,
//! as many programs draw it under the same name, value noise, with
//! optional turbulence (|noise|).
use super::common::{fbm_with, normalise, Basis};
use super::{int, real, Family, Model, ParamSpec};

const PARAMS: &[ParamSpec] = &[
    int("frequency", 2.0, 24.0, 6.0),
    // 1 (smooth blobs) to 8 octaves (detail down to the pixel at 256²
    // from frequency 2).
    int("octaves", 1.0, 8.0, 4.0),
    real("persistence", 0.3, 0.8, 0.5),
    real("turbulence", 0.0, 1.0, 0.0),
    // 0 gradient noise, 1 value noise. Dataset gradient only: value-noise
    // octaves are `fractal-one-over-f`'s picture (the same sum, persistence
    // p being β = −2·log2 p; a test pins it), so the dataset leaves them to
    // that model.
    int("basis", 0.0, 1.0, 0.0).dataset(0.0, 0.0),
];

/// `frequency` lattice cells per side at the first octave, each octave
/// doubling it with amplitude × `persistence`; `turbulence` blends toward
/// |noise| (billows and creases); `basis` 0 is gradient noise, 1 value
/// noise.
pub const PERLIN: Model = Model {
    id: "perlin",
    name: "Perlin noise",
    family: Family::Perlin,
    params: PARAMS,
    generate: perlin,
};

fn perlin(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let basis = if p[4] >= 0.5 {
        Basis::Value
    } else {
        Basis::Gradient
    };
    let mut h = fbm_with(
        n,
        p[0] as u32,
        p[1] as u32,
        p[2] as f32,
        p[3] as f32,
        basis,
        seed,
    );
    normalise(&mut h);
    h
}

/// Normalised Perlin fBm of gradient noise (shared by folding and fusion).
pub(crate) fn perlin_raw(
    n: usize,
    freq: u32,
    oct: u32,
    gain: f32,
    turb: f32,
    seed: u64,
) -> Vec<f32> {
    let mut h = fbm_with(n, freq, oct, gain, turb, Basis::Gradient, seed);
    normalise(&mut h);
    h
}
