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

/// The dataset's least `folds` for every folding. One fold is the
/// identity ([`fold`] of a normalised map at 1 is the map itself), so a
/// folding there is its input model's picture, and up to 2 it is that
/// picture with one crease line (at mid-height). Above 2 there are
/// creases at two heights or more (at 2.5: 0.4 and 0.8), drawing the
/// nested contour ridges and terraces that only a folding makes (rendered
/// side by side, 2026-12-02). 2.5 is also the smallest default folds.
const FOLDS_FLOOR: f64 = 2.5;

fn folded(mut h: Vec<f32>, folds: f64) -> Vec<f32> {
    fold(&mut h, folds as f32);
    h
}

const FOLD_TEXTON_PARAMS: &[ParamSpec] = &[
    real("folds", 1.0, 5.0, 2.5).dataset(FOLDS_FLOOR, 5.0),
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
    real("folds", 1.0, 5.0, 2.5).dataset(FOLDS_FLOOR, 5.0),
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
    real("folds", 1.0, 6.0, 3.0).dataset(FOLDS_FLOOR, 6.0),
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
    real("folds", 1.0, 6.0, 3.0).dataset(FOLDS_FLOOR, 6.0),
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

/// The dataset's fusion weights, the same for the three fusions: near
/// either end of 0.2..0.8 one ingredient dominates the picture (at 0.2 a
/// fusion with textons is a texton grid with a faint background, and the
/// cellular-texton and Perlin-texton fusions draw the same picture; at 0.8
/// the textons fade and it is its cellular or Perlin ingredient's), so the
/// dataset keeps 0.4..0.6, where both ingredients show.
const WEIGHT_LO: f64 = 0.4;
const WEIGHT_HI: f64 = 0.6;

/// The dataset's least Perlin frequency or cell count of a fusion's
/// smooth ingredient (Perlin noise, cellular): with 2–4 features per side
/// its slopes are too gentle to show beside the other ingredient's steep
/// ones (textons, cell walls), so the fusion is then that other
/// ingredient's picture alone (at weight 0.5 and 16 textons per side, the
/// cellular-texton and Perlin-texton fusions are the same texton grid),
/// whatever the weight. (`fusion-perlin-texton`'s default frequency, 4,
/// is below it: the sliders' default picture was left as it was.)
const BACKGROUND_FLOOR: f64 = 6.0;

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
    real("weight", 0.2, 0.8, 0.5).dataset(WEIGHT_LO, WEIGHT_HI),
    // Dataset from 6 (see `BACKGROUND_FLOOR`).
    int("cells", 3.0, 16.0, 6.0).dataset(BACKGROUND_FLOOR, 16.0),
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
        let (a, b) = cellular_texton(p, seed, n);
        fuse(a, b, p[0])
    },
};

const FUSE_PC_PARAMS: &[ParamSpec] = &[
    real("weight", 0.2, 0.8, 0.5).dataset(WEIGHT_LO, WEIGHT_HI),
    // Dataset from 6 (see `BACKGROUND_FLOOR`).
    int("frequency", 2.0, 16.0, 6.0).dataset(BACKGROUND_FLOOR, 16.0),
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
        let (a, b) = perlin_cellular(p, seed, n);
        fuse(a, b, p[0])
    },
};

const FUSE_PT_PARAMS: &[ParamSpec] = &[
    real("weight", 0.2, 0.8, 0.5).dataset(WEIGHT_LO, WEIGHT_HI),
    // Dataset from 6 (see `BACKGROUND_FLOOR`).
    int("frequency", 2.0, 16.0, 4.0).dataset(BACKGROUND_FLOOR, 16.0),
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
        let (a, b) = perlin_texton(p, seed, n);
        fuse(a, b, p[0])
    },
};

fn cellular_texton(p: &[f64], seed: u64, n: usize) -> (Vec<f32>, Vec<f32>) {
    let a = cellular_raw(n, p[1] as u32, 0.8, 0.7, seed);
    let b = random_grid_raw(n, p[2] as usize, 0.25, 0.4, p[3] as usize, 0.5, seed2(seed));
    (a, b)
}

fn perlin_cellular(p: &[f64], seed: u64, n: usize) -> (Vec<f32>, Vec<f32>) {
    let a = perlin_raw(n, p[1] as u32, 4, 0.5, 0.0, seed);
    let b = cellular_raw(n, p[2] as u32, 0.8, p[3] as f32, seed2(seed));
    (a, b)
}

fn perlin_texton(p: &[f64], seed: u64, n: usize) -> (Vec<f32>, Vec<f32>) {
    let a = perlin_raw(n, p[1] as u32, 4, 0.5, 0.0, seed);
    let b = random_grid_raw(n, p[2] as usize, 0.2, 0.4, p[3] as usize, 0.5, seed2(seed));
    (a, b)
}

/// A fusion's two normalised ingredients (the first weighted by the
/// `weight` parameter, the second by 1 − `weight`), or `None` for a model
/// that is not a fusion. The generators above blend exactly these (the
/// dataset-range tests measure each one's share of the relief).
#[cfg(test)]
pub(crate) fn fusion_ingredients(
    model: &Model,
    p: &[f64],
    seed: u64,
    n: usize,
) -> Option<(Vec<f32>, Vec<f32>)> {
    let parts = match model.id {
        "fusion-cellular-texton" => cellular_texton,
        "fusion-perlin-cellular" => perlin_cellular,
        "fusion-perlin-texton" => perlin_texton,
        _ => return None,
    };
    Some(parts(p, seed, n))
}
