//! Folding and fusion: models built from others. Folding passes a base
//! height map through a triangle wave ([`super::common::fold`]), turning
//! slopes into ridges and terraces; fusion blends two base maps scaled to
//! the same mean slope, so its weight is each one's share of the relief.
use super::cellular::cellular_raw;
use super::common::{fold, normalise};
use super::fractal::one_over_f_raw;
use super::perlin::perlin_raw;
use super::texton::{random_grid_raw, SHAPE_HI};
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

/// The dataset's largest texton `size` (radius, of a grid cell) of
/// `folding-texton`. The paper's folded textons are "randomly distributed
/// near-regular shape elements" (§5.5): separate targets standing on flat
/// ground. A round texton of radius `size` covers π·size² of its cell, so
/// up to 0.45 at least a third of the ground stays flat whatever the
/// jitter; from about 0.6 the bumps overlap into a field that tiles the
/// plane, and folded it is `folding-cellular`'s field of ring targets
/// (rendered side by side, 2026-12-03: at size 0.9 most of its held-out
/// images were taken for folded cellular).
pub(crate) const FOLD_TEXTON_SIZE_MAX: f64 = 0.45;

const FOLD_TEXTON_PARAMS: &[ParamSpec] = &[
    real("folds", 1.0, 5.0, 2.5).dataset(FOLDS_FLOOR, 5.0),
    int("grid", 3.0, 12.0, 6.0),
    // Dataset 0.3..0.45 (see `FOLD_TEXTON_SIZE_MAX`).
    real("size", 0.3, 0.9, 0.4).dataset(0.3, FOLD_TEXTON_SIZE_MAX),
    // Dataset from 0.2, as `texton-random-grid`'s jitter: the paper's
    // folded textons are randomly placed, and without jitter they are a
    // lattice of targets, which the classifier took for folded cells
    // (validation, 2026-12-03).
    real("jitter", 0.0, 0.5, 0.3).dataset(0.2, 0.5),
];

/// A jittered grid of bumps, folded `folds` times.
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
    // Dataset from 0.5, as `cellular`'s jitter: with little jitter the
    // cells are a square lattice, and folded they are a lattice of ring
    // targets, `texton-regular`'s picture with ring textons (rendered
    // side by side, 2026-12-03).
    real("jitter", 0.0, 1.0, 0.8).dataset(0.5, 1.0),
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
/// either end of 0.2..0.8 one ingredient makes most of the relief (at 0.2
/// a fusion with textons is a texton grid with a faint background, and
/// the cellular-texton and Perlin-texton fusions draw the same picture; at
/// 0.8 the textons fade and it is its cellular or Perlin ingredient's), so
/// the dataset keeps 0.4..0.6, where both ingredients show.
const WEIGHT_LO: f64 = 0.4;
const WEIGHT_HI: f64 = 0.6;

/// The dataset's least Perlin frequency or cell count of a fusion's
/// smooth ingredient (Perlin noise, cellular): with 2–4 features per side
/// a training window (a quarter of the texture) holds one or two of them,
/// a tilt rather than a texture beside the other ingredient's many small
/// ones.
const BACKGROUND_FLOOR: f64 = 6.0;

/// The mean slope of an `n`×`n` torus height map: the mean length of its
/// wrapped central-difference gradient (in height per pixel pair), summed
/// in a fixed order so native and wasm agree.
fn mean_slope(h: &[f32], n: usize) -> f64 {
    let mut e = 0.0f64;
    for y in 0..n {
        let (up, down) = (((y + n - 1) % n) * n, ((y + 1) % n) * n);
        for x in 0..n {
            let (l, r) = ((x + n - 1) % n, (x + 1) % n);
            let dx = (h[y * n + r] - h[y * n + l]) as f64;
            let dy = (h[down + x] - h[up + x]) as f64;
            e += (dx * dx + dy * dy).sqrt();
        }
    }
    e / (n * n) as f64
}

/// The two ingredients of a fusion scaled to the same mean slope (1 per
/// pixel pair), so that `weight` is the share of the relief, which is what
/// shading shows, that the first one makes. Blending the height-normalised
/// maps instead let the ingredient with the smaller features make most of
/// the slopes whatever the weight: at weight 0.4, Perlin noise of
/// frequency 6 made a fifth of the relief beside 16 cells, so the fusion
/// was the `cellular` model's picture (2026-12-03; the shares over the old
/// dataset grid ran from 0.15 to 0.83). A flat ingredient stays flat.
fn balanced(a: Vec<f32>, b: Vec<f32>, n: usize) -> (Vec<f32>, Vec<f32>) {
    let scale = |mut h: Vec<f32>| {
        let s = mean_slope(&h, n);
        let k = if s > 1e-9 { (1.0 / s) as f32 } else { 0.0 };
        for v in &mut h {
            *v *= k;
        }
        h
    };
    (scale(a), scale(b))
}

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
    int("shape", 0.0, SHAPE_HI, 0.0),
];

/// `weight` × cellular walls + (1 − `weight`) × a random texton grid,
/// each at the same mean slope (so `weight` is the cells' share of the
/// relief).
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
    // Dataset from 6 too: with 3 cells per side the walls are too far
    // apart to show in a training window, and the picture is Perlin
    // noise's (rendered side by side, 2026-12-03).
    int("cells", 3.0, 16.0, 6.0).dataset(BACKGROUND_FLOOR, 16.0),
    real("crack", 0.0, 1.0, 0.5),
];

/// `weight` × Perlin noise + (1 − `weight`) × cellular (F1/F2 − F1 by
/// `crack`), each at the same mean slope.
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
    int("frequency", 2.0, 16.0, 6.0).dataset(BACKGROUND_FLOOR, 16.0),
    int("grid", 4.0, 16.0, 8.0),
    int("shape", 0.0, SHAPE_HI, 3.0),
];

/// `weight` × Perlin noise + (1 − `weight`) × a random texton grid, each
/// at the same mean slope.
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
    balanced(a, b, n)
}

fn perlin_cellular(p: &[f64], seed: u64, n: usize) -> (Vec<f32>, Vec<f32>) {
    let a = perlin_raw(n, p[1] as u32, 4, 0.5, 0.0, seed);
    let b = cellular_raw(n, p[2] as u32, 0.8, p[3] as f32, seed2(seed));
    balanced(a, b, n)
}

fn perlin_texton(p: &[f64], seed: u64, n: usize) -> (Vec<f32>, Vec<f32>) {
    let a = perlin_raw(n, p[1] as u32, 4, 0.5, 0.0, seed);
    let b = random_grid_raw(n, p[2] as usize, 0.2, 0.4, p[3] as usize, 0.5, seed2(seed));
    balanced(a, b, n)
}

/// A fusion's two ingredients, scaled to the same mean slope (the first
/// weighted by the `weight` parameter, the second by 1 − `weight`), or `None` for a model
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
