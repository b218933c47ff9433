//! Perlin noise: octaves of tileable gradient noise (Perlin 1985/2002),
//! with optional turbulence (|noise|).
use super::common::{fbm, normalise};
use super::{int, real, Family, Model, ParamSpec};

const PARAMS: &[ParamSpec] = &[
    int("frequency", 2.0, 24.0, 6.0),
    int("octaves", 1.0, 6.0, 4.0),
    real("persistence", 0.3, 0.8, 0.5),
    real("turbulence", 0.0, 1.0, 0.0),
];

/// `frequency` lattice cells per side at the first octave, each octave
/// doubling it with amplitude × `persistence`; `turbulence` blends toward
/// |noise| (billows and creases).
pub const PERLIN: Model = Model {
    id: "perlin",
    name: "Perlin noise",
    family: Family::Perlin,
    params: PARAMS,
    generate: perlin,
};

fn perlin(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    perlin_raw(n, p[0] as u32, p[1] as u32, p[2] as f32, p[3] as f32, seed)
}

/// Normalised Perlin fBm (shared by folding and fusion).
pub(crate) fn perlin_raw(
    n: usize,
    freq: u32,
    oct: u32,
    gain: f32,
    turb: f32,
    seed: u64,
) -> Vec<f32> {
    let mut h = fbm(n, freq, oct, gain, turb, seed);
    normalise(&mut h);
    h
}
