//! Cellular (Worley) texture: distances to jittered feature points, one per
//! cell of a `cells`×`cells` torus grid.
use super::common::{normalise, worley};
use super::{int, real, Family, Model, ParamSpec};

const PARAMS: &[ParamSpec] = &[
    // Dataset from 6: with 3 cells per side a training window (a quarter
    // of the texture) shows one or two cells, a few flat facets rather
    // than a field of cells (rendered side by side, 2026-12-03).
    int("cells", 3.0, 24.0, 8.0).dataset(6.0, 24.0),
    // Dataset from 0.5: with little jitter the cells are a square lattice
    // of domes or pyramids, `texton-regular`'s picture (at 0.25 still
    // visibly a lattice); from 0.5 they are irregular Voronoi cells
    // (rendered side by side, 2026-12-02).
    real("jitter", 0.0, 1.0, 0.8).dataset(0.5, 1.0),
    real("crack", 0.0, 1.0, 0.3),
    real("power", 0.5, 2.0, 1.0),
];

/// Height `(1 − crack)·F1 + crack·(F2 − F1)` raised to `power`: crack 0
/// gives domes (F1), crack 1 gives cell walls (F2 − F1); jitter 0 is a
/// regular grid of cells, 1 fully random.
pub const CELLULAR: Model = Model {
    id: "cellular",
    name: "Cellular",
    family: Family::Cellular,
    params: PARAMS,
    generate: cellular,
};

pub(crate) fn cellular(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let mut h = cellular_raw(n, p[0] as u32, p[1] as f32, p[2] as f32, seed);
    let pw = p[3] as f32;
    for v in &mut h {
        *v = libm::powf(v.max(0.0), pw);
    }
    normalise(&mut h);
    h
}

/// The unpowered cellular height in [0, 1] (shared by folding and fusion).
pub(crate) fn cellular_raw(n: usize, cells: u32, jitter: f32, crack: f32, seed: u64) -> Vec<f32> {
    let (f1, f2) = worley(n, cells, jitter, seed);
    let mut h: Vec<f32> = f1
        .iter()
        .zip(&f2)
        .map(|(&a, &b)| {
            // Domes: high at the feature point, low at the walls.
            let dome = 1.0 - a.min(1.0);
            let wall = (b - a).min(1.0);
            (1.0 - crack) * dome + crack * wall
        })
        .collect();
    normalise(&mut h);
    h
}
