//! Texton models: small shapes ("textons": bump, pyramid, cross, ring, bar,
//! and discs, squares, triangles, hexagons, stars, plus signs and rings
//! under flat, domed and conical profiles; see [`super::common::texton`]
//! and [`SHAPE_NAMES`](super::common::SHAPE_NAMES)) placed on the torus by
//! five rules —
//! addition (random positions, heights added), probability map (positions
//! drawn from a noise map), random grid (a jittered lattice), random walk
//! (chains) and regular (a lattice with a row offset).
use super::common::{fbm, normalise, scatter, stamp, Combine, Stamp, FLAT_TOPPED, SHAPES};
use super::{int, real, Family, Model, ParamSpec};
use crate::core::rng::Rng;
use std::f32::consts::PI;

fn finish(mut h: Vec<f32>) -> Vec<f32> {
    normalise(&mut h);
    h
}

fn shape_of(v: f64) -> usize {
    (v as usize).min(SHAPES - 1)
}

/// The largest `shape` index (every texton shape, for every model that
/// draws textons).
pub(crate) const SHAPE_HI: f64 = (SHAPES - 1) as f64;

const ADDITION_PARAMS: &[ParamSpec] = &[
    int("count", 20.0, 400.0, 150.0),
    real("size", 0.02, 0.12, 0.05),
    int("shape", 0.0, SHAPE_HI, 0.0),
    real("size_variation", 0.0, 1.0, 0.5),
];

/// `count` textons at uniform random positions and angles, radius `size`
/// (image units) varied by ± `size_variation`, heights added (overlaps
/// pile up).
pub const ADDITION: Model = Model {
    id: "texton-addition",
    name: "Texton Addition",
    family: Family::Texton,
    params: ADDITION_PARAMS,
    generate: addition,
};

fn addition(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let mut rng = Rng::new(seed);
    let mut h = vec![0.0f32; n * n];
    let (size, shape, var) = (p[1] as f32, shape_of(p[2]), p[3] as f32);
    for (x, y) in scatter(p[0] as usize, &mut rng) {
        let r = size * (1.0 + var * (rng.f64() as f32 * 2.0 - 1.0) * 0.8);
        let angle = rng.f64() as f32 * PI;
        stamp(
            &mut h,
            n,
            &Stamp {
                x,
                y,
                r,
                angle,
                shape,
                amp: 1.0,
            },
            Combine::Add,
        );
    }
    finish(h)
}

const PROB_PARAMS: &[ParamSpec] = &[
    int("count", 50.0, 500.0, 220.0),
    real("size", 0.015, 0.06, 0.03),
    int("map_frequency", 2.0, 8.0, 3.0),
    real("clustering", 0.5, 6.0, 3.0),
    int("shape", 0.0, SHAPE_HI, 0.0),
];

/// Textons placed by rejection sampling from a probability map (Perlin
/// noise at `map_frequency`, raised to `clustering`): they gather in
/// patches. Overlaps keep the higher texton.
pub const PROBABILITY_MAP: Model = Model {
    id: "texton-probability-map",
    name: "Texton probability map",
    family: Family::Texton,
    params: PROB_PARAMS,
    generate: probability_map,
};

fn probability_map(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let mut rng = Rng::new(seed);
    // The map on a coarse 64² grid is plenty for placement decisions.
    let g = 64;
    let mut map = fbm(g, p[2] as u32, 2, 0.5, 0.0, seed ^ 0x5eed);
    normalise(&mut map);
    let k = p[3] as f32;
    let count = p[0] as usize;
    let (size, shape) = (p[1] as f32, shape_of(p[4]));
    let mut h = vec![0.0f32; n * n];
    let mut placed = 0;
    let mut tries = 0;
    while placed < count && tries < count * 40 {
        tries += 1;
        let (x, y) = (rng.f64() as f32, rng.f64() as f32);
        let m =
            map[((y * g as f32) as usize).min(g - 1) * g + ((x * g as f32) as usize).min(g - 1)];
        if (rng.f64() as f32) < libm::powf(m, k) {
            let angle = rng.f64() as f32 * PI;
            stamp(
                &mut h,
                n,
                &Stamp {
                    x,
                    y,
                    r: size,
                    angle,
                    shape,
                    amp: 1.0,
                },
                Combine::Max,
            );
            placed += 1;
        }
    }
    finish(h)
}

const GRID_PARAMS: &[ParamSpec] = &[
    int("grid", 4.0, 20.0, 10.0),
    // Dataset from 0.2: with no jitter this is `texton-regular`'s picture
    // (same lattice and textons), and up to ~0.1 of a cell it still reads
    // as a slightly wobbly regular grid; from 0.2 the lattice is visibly
    // broken (rendered side by side, 2026-12-02).
    real("jitter", 0.0, 0.5, 0.25).dataset(0.2, 0.5),
    real("size", 0.2, 0.6, 0.4),
    int("shape", 0.0, SHAPE_HI, 1.0),
    real("rotation", 0.0, 1.0, 0.5),
];

/// One texton per cell of a `grid`×`grid` lattice, displaced by up to
/// `jitter` of a cell and turned by up to `rotation`·180°; radius `size`
/// of a cell.
pub const RANDOM_GRID: Model = Model {
    id: "texton-random-grid",
    name: "Texton random grid",
    family: Family::Texton,
    params: GRID_PARAMS,
    generate: random_grid,
};

fn random_grid(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    random_grid_raw(
        n,
        p[0] as usize,
        p[1] as f32,
        p[2] as f32,
        shape_of(p[3]),
        p[4] as f32,
        seed,
    )
}

/// A normalised random-grid texton map (shared by folding and fusion).
pub(crate) fn random_grid_raw(
    n: usize,
    grid: usize,
    jitter: f32,
    size: f32,
    shape: usize,
    rotation: f32,
    seed: u64,
) -> Vec<f32> {
    let mut rng = Rng::new(seed);
    let mut h = vec![0.0f32; n * n];
    let cell = 1.0 / grid.max(1) as f32;
    for gy in 0..grid {
        for gx in 0..grid {
            let jx = (rng.f64() as f32 * 2.0 - 1.0) * jitter;
            let jy = (rng.f64() as f32 * 2.0 - 1.0) * jitter;
            let angle = rng.f64() as f32 * PI * rotation;
            let s = Stamp {
                x: (gx as f32 + 0.5 + jx) * cell,
                y: (gy as f32 + 0.5 + jy) * cell,
                r: size * cell,
                angle,
                shape,
                amp: 1.0,
            };
            stamp(&mut h, n, &s, Combine::Max);
        }
    }
    finish(h)
}

const WALK_PARAMS: &[ParamSpec] = &[
    int("walks", 1.0, 16.0, 6.0),
    int("steps", 20.0, 200.0, 80.0),
    real("stride", 0.5, 2.0, 1.0),
    real("size", 0.01, 0.04, 0.02),
    real("turn", 0.1, 1.5, 0.5),
    int("shape", 0.0, SHAPE_HI, 0.0),
];

/// `walks` random walks of `steps` textons each: every step moves
/// `stride` radii in a heading that turns by a random angle of up to
/// ± `turn` radians, so textons form worm-like chains.
pub const RANDOM_WALK: Model = Model {
    id: "texton-random-walk",
    name: "Texton random walk",
    family: Family::Texton,
    params: WALK_PARAMS,
    generate: random_walk,
};

fn random_walk(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let mut rng = Rng::new(seed);
    let mut h = vec![0.0f32; n * n];
    let (stride, size, turn) = (p[2] as f32, p[3] as f32, p[4] as f32);
    let shape = shape_of(p[5]);
    for _ in 0..p[0] as usize {
        let (mut x, mut y) = (rng.f64() as f32, rng.f64() as f32);
        let mut heading = rng.f64() as f32 * 2.0 * PI;
        // Flat-topped textons of one height merge into one plateau where
        // chains cross (at the most walks and steps, everywhere): each
        // chain of them stands at its own height. (The older shapes keep
        // one height, and their random numbers.)
        let amp = if FLAT_TOPPED.contains(&shape) {
            0.6 + 0.4 * rng.f64() as f32
        } else {
            1.0
        };
        for _ in 0..p[1] as usize {
            let s = Stamp {
                x,
                y,
                r: size,
                angle: heading,
                shape,
                amp,
            };
            stamp(&mut h, n, &s, Combine::Max);
            heading += (rng.f64() as f32 * 2.0 - 1.0) * turn;
            x = (x + stride * size * libm::cosf(heading)).rem_euclid(1.0);
            y = (y + stride * size * libm::sinf(heading)).rem_euclid(1.0);
        }
    }
    finish(h)
}

const REGULAR_PARAMS: &[ParamSpec] = &[
    int("grid", 4.0, 20.0, 8.0),
    real("size", 0.2, 0.6, 0.4),
    int("shape", 0.0, SHAPE_HI, 2.0),
    real("angle", 0.0, 90.0, 0.0),
    real("row_offset", 0.0, 0.5, 0.0),
];

/// Identical textons on a `grid`×`grid` lattice, every other row shifted
/// by `row_offset` of a cell, all turned by `angle` degrees.
pub const REGULAR: Model = Model {
    id: "texton-regular",
    name: "Texton regular",
    family: Family::Texton,
    params: REGULAR_PARAMS,
    generate: regular,
};

fn regular(p: &[f64], _seed: u64, n: usize) -> Vec<f32> {
    let grid = p[0] as usize;
    let cell = 1.0 / grid as f32;
    let (size, shape) = (p[1] as f32, shape_of(p[2]));
    let angle = (p[3] as f32).to_radians();
    let off = p[4] as f32;
    let mut h = vec![0.0f32; n * n];
    for gy in 0..grid {
        let shift = if gy % 2 == 1 { off } else { 0.0 };
        for gx in 0..grid {
            let s = Stamp {
                x: (gx as f32 + 0.5 + shift) * cell,
                y: (gy as f32 + 0.5) * cell,
                r: size * cell,
                angle,
                shape,
                amp: 1.0,
            };
            stamp(&mut h, n, &s, Combine::Max);
        }
    }
    finish(h)
}
