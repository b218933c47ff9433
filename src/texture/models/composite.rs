//! Folding and fusion: models built from others. Folding passes a base
//! height map through a triangle wave ([`super::common::fold`]), turning
//! slopes into ridges and terraces; fusion blends two normalised base maps.
use super::cellular::cellular_raw;
use super::common::{fold, normalise};
use super::fractal::one_over_f_raw;
use super::perlin::perlin_raw;
use super::texton::random_grid_raw;
use super::{int, real, Family, Model, ParamSpec};

fn seed2(seed: u64) -> u64 {
    seed ^ 0xd6e8_feb8_6659_fd93
}

fn folded(mut h: Vec<f32>, folds: f64) -> Vec<f32> {
    fold(&mut h, folds as f32);
    h
}

const FOLD_TEXTON_PARAMS: &[ParamSpec] = &[
    real("folds", 1.0, 5.0, 2.5),
    int("grid", 3.0, 12.0, 6.0),
    real("size", 0.3, 0.9, 0.7),
    real("jitter", 0.0, 0.5, 0.3),
];

/// A jittered grid of large bumps, folded `folds` times.
pub const FOLD_TEXTON: Model = Model {
    id: "folding-texton",
    name: "Folding of Texton Placement",
    family: Family::Folding,
    params: FOLD_TEXTON_PARAMS,
    generate: |p, seed, n| {
        let h = random_grid_raw(n, p[1] as usize, p[3] as f32, p[2] as f32, 0, 0.0, seed);
        folded(h, p[0])
    },
};

const FOLD_CELLULAR_PARAMS: &[ParamSpec] = &[
    real("folds", 1.0, 5.0, 2.5),
    int("cells", 3.0, 16.0, 6.0),
    real("jitter", 0.0, 1.0, 0.8),
];

/// Worley domes (F1), folded `folds` times: concentric terraces per cell.
pub const FOLD_CELLULAR: Model = Model {
    id: "folding-cellular",
    name: "Folding of Cellular",
    family: Family::Folding,
    params: FOLD_CELLULAR_PARAMS,
    generate: |p, seed, n| folded(cellular_raw(n, p[1] as u32, p[2] as f32, 0.0, seed), p[0]),
};

const FOLD_FRACTAL_PARAMS: &[ParamSpec] = &[
    real("folds", 1.0, 6.0, 3.0),
    real("beta", 1.0, 3.5, 2.5),
    int("frequency", 2.0, 8.0, 3.0),
];

/// 1/f^β noise, folded `folds` times: contour-like ridges.
pub const FOLD_FRACTAL: Model = Model {
    id: "folding-fractal",
    name: "Folding of Fractal",
    family: Family::Folding,
    params: FOLD_FRACTAL_PARAMS,
    generate: |p, seed, n| folded(one_over_f_raw(n, p[1] as f32, p[2] as u32, 5, seed), p[0]),
};

const FOLD_PERLIN_PARAMS: &[ParamSpec] = &[
    real("folds", 1.0, 6.0, 3.0),
    int("frequency", 2.0, 12.0, 4.0),
    int("octaves", 1.0, 5.0, 3.0),
];

/// Perlin noise, folded `folds` times: marble-like bands.
pub const FOLD_PERLIN: Model = Model {
    id: "folding-perlin",
    name: "Folding of Perlin noise",
    family: Family::Folding,
    params: FOLD_PERLIN_PARAMS,
    generate: |p, seed, n| {
        folded(
            perlin_raw(n, p[1] as u32, p[2] as u32, 0.5, 0.0, seed),
            p[0],
        )
    },
};

fn fuse(a: Vec<f32>, b: Vec<f32>, w: f64) -> Vec<f32> {
    let w = w as f32;
    let mut h: Vec<f32> = a
        .iter()
        .zip(&b)
        .map(|(x, y)| w * x + (1.0 - w) * y)
        .collect();
    normalise(&mut h);
    h
}

const FUSE_CT_PARAMS: &[ParamSpec] = &[
    real("weight", 0.2, 0.8, 0.5),
    int("cells", 3.0, 16.0, 6.0),
    int("grid", 4.0, 16.0, 10.0),
    int("shape", 0.0, 4.0, 0.0),
];

/// `weight` × cellular walls + (1 − `weight`) × a random texton grid.
pub const FUSE_CELLULAR_TEXTON: Model = Model {
    id: "fusion-cellular-texton",
    name: "Fusion of Cellular and Texton",
    family: Family::Fusion,
    params: FUSE_CT_PARAMS,
    generate: |p, seed, n| {
        let a = cellular_raw(n, p[1] as u32, 0.8, 0.7, seed);
        let b = random_grid_raw(n, p[2] as usize, 0.25, 0.4, p[3] as usize, 0.5, seed2(seed));
        fuse(a, b, p[0])
    },
};

const FUSE_PC_PARAMS: &[ParamSpec] = &[
    real("weight", 0.2, 0.8, 0.5),
    int("frequency", 2.0, 16.0, 6.0),
    int("cells", 3.0, 16.0, 6.0),
    real("crack", 0.0, 1.0, 0.5),
];

/// `weight` × Perlin noise + (1 − `weight`) × cellular (F1/F2 − F1 by `crack`).
pub const FUSE_PERLIN_CELLULAR: Model = Model {
    id: "fusion-perlin-cellular",
    name: "Fusion of Perlin and Cellular",
    family: Family::Fusion,
    params: FUSE_PC_PARAMS,
    generate: |p, seed, n| {
        let a = perlin_raw(n, p[1] as u32, 4, 0.5, 0.0, seed);
        let b = cellular_raw(n, p[2] as u32, 0.8, p[3] as f32, seed2(seed));
        fuse(a, b, p[0])
    },
};

const FUSE_PT_PARAMS: &[ParamSpec] = &[
    real("weight", 0.2, 0.8, 0.5),
    int("frequency", 2.0, 16.0, 4.0),
    int("grid", 4.0, 16.0, 8.0),
    int("shape", 0.0, 4.0, 3.0),
];

/// `weight` × Perlin noise + (1 − `weight`) × a random texton grid.
pub const FUSE_PERLIN_TEXTON: Model = Model {
    id: "fusion-perlin-texton",
    name: "Fusion of Perlin and Texton",
    family: Family::Fusion,
    params: FUSE_PT_PARAMS,
    generate: |p, seed, n| {
        let a = perlin_raw(n, p[1] as u32, 4, 0.5, 0.0, seed);
        let b = random_grid_raw(n, p[2] as usize, 0.2, 0.4, p[3] as usize, 0.5, seed2(seed));
        fuse(a, b, p[0])
    },
};
