//! Cellular (Worley) texture: distances to jittered feature points, one per
//! cell of a `cells`×`cells` torus grid (Worley 1996), under a distance
//! metric, drawing one of the distance features (F1, F2, F2 − F1 or the
//! dome/crack blend) through a height profile (linear facets, domes, flat
//! plateaus, a mosaic of flat cells).
use super::common::{hash, normalise, unit, worley_with, Metric};
use super::{int, real, Family, Model, ParamSpec};

const PARAMS: &[ParamSpec] = &[
    // 3..24 cells per side: cells of 85 to 11 px on a 256² render.
    // Dataset from 5 (51 px cells): with 3 cells per side a training
    // window (a quarter of the texture) shows one or two cells, a few
    // flat facets rather than a field of cells (rendered side by side,
    // 2026-12-03); at 5 a window still holds six or more.
    int("cells", 3.0, 24.0, 8.0).dataset(5.0, 24.0),
    // Dataset from 0.5: with little jitter the cells are a square lattice
    // of domes or pyramids, `texton-regular`'s picture (at 0.25 still
    // visibly a lattice); from 0.5 they are irregular Voronoi cells
    // (rendered side by side, 2026-12-02).
    real("jitter", 0.0, 1.0, 0.8).dataset(0.5, 1.0),
    real("crack", 0.0, 1.0, 0.3),
    real("power", 0.5, 2.0, 1.0),
    // 0 Euclidean, 1 Manhattan, 2 Chebyshev ([`Metric`]).
    int("metric", 0.0, 2.0, 0.0),
    // 0 the dome/crack blend (by `crack`), 1 F1, 2 F2, 3 F2 − F1.
    int("feature", 0.0, 3.0, 0.0),
    // 0 the feature as it is (facets and cones), 1 domed cells, 2 flat
    // cells with sharp walls, 3 with rounded walls, 4 mosaic (one random
    // height a cell).
    int("profile", 0.0, 4.0, 0.0),
];

/// The feature drawn, as a height map before the profile: `feature` 0 is
/// `(1 − crack)·(1 − F1) + crack·(F2 − F1)` (crack 0 domes high at the
/// feature points, crack 1 cell walls as grooves), 1 is F1 (a pit at
/// each point, ridges on the walls), 2 is F2 (Worley's second-nearest
/// distance: creased hummocks), 3 is F2 − F1 (grooves on the walls).
/// `profile` 0 draws it as it is (with the Euclidean metric the F1 domes
/// are cones, the walls' sides planes: faceted cells); the others draw
/// the cells themselves, whatever the feature: 1 a round dome a cell
/// (cobbles), 2 and 3 flat cells standing between walls (sharp or
/// rounded), 4 one random height a cell (a flat mosaic). The result is raised to `power`. Jitter 0 is a regular grid
/// of cells, 1 fully random.
pub const CELLULAR: Model = Model {
    id: "cellular",
    name: "Cellular",
    family: Family::Cellular,
    params: PARAMS,
    generate: cellular,
};

/// The cellular model's options beyond the lattice (see [`CELLULAR`]).
#[derive(Clone, Copy)]
pub(crate) struct Style {
    pub metric: Metric,
    pub feature: usize,
    pub crack: f32,
    pub profile: usize,
}

pub(crate) fn cellular(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let style = Style {
        metric: Metric::from_index(p[4] as usize),
        feature: p[5] as usize,
        crack: p[2] as f32,
        profile: p[6] as usize,
    };
    let mut h = cellular_styled(n, p[0] as u32, p[1] as f32, style, seed);
    let pw = p[3] as f32;
    for v in &mut h {
        *v = libm::powf(v.max(0.0), pw);
    }
    normalise(&mut h);
    h
}

/// The unpowered cellular height in [0, 1]: the dome/crack blend,
/// Euclidean, linear profile (shared by folding and fusion).
pub(crate) fn cellular_raw(n: usize, cells: u32, jitter: f32, crack: f32, seed: u64) -> Vec<f32> {
    let style = Style {
        metric: Metric::Euclidean,
        feature: 0,
        crack,
        profile: 0,
    };
    cellular_styled(n, cells, jitter, style, seed)
}

/// The unpowered cellular height in [0, 1] in any [`Style`].
pub(crate) fn cellular_styled(n: usize, cells: u32, jitter: f32, s: Style, seed: u64) -> Vec<f32> {
    let w = worley_with(n, cells, jitter, s.metric, seed);
    let mut h: Vec<f32> = match s.profile {
        // A round dome a cell: a spherical cap over its feature point
        // reaching 0 at the cell's farthest pixel (its radius), so the
        // cell has no creases inside and domes meet in creases.
        1 => {
            let mut radius = vec![0.0f32; (cells.max(1) * cells.max(1)) as usize];
            for (&i, &a) in w.id.iter().zip(&w.f1) {
                let r = &mut radius[i as usize];
                *r = r.max(a);
            }
            w.f1.iter()
                .zip(&w.id)
                .map(|(&a, &i)| {
                    let t = a / radius[i as usize].max(1e-6);
                    (1.0 - t * t).max(0.0).sqrt()
                })
                .collect()
        }
        // Flat cells between walls: the wall distance F2 − F1 (0 on a
        // wall, about twice the distance to it nearby) through a ramp of
        // 0.1 cell (sharp) or 0.4 cell with a quarter-circle shoulder.
        2 => {
            w.f1.iter()
                .zip(&w.f2)
                .map(|(&a, &b)| ((b - a) / 0.1).min(1.0))
                .collect()
        }
        3 => {
            w.f1.iter()
                .zip(&w.f2)
                .map(|(&a, &b)| {
                    let t = 1.0 - ((b - a) / 0.4).min(1.0);
                    (1.0 - t * t).sqrt()
                })
                .collect()
        }
        // One random height a cell, from its feature point's cell.
        4 => {
            w.id.iter()
                .map(|&i| unit(hash(i, 0x6d6f_7361, seed)))
                .collect()
        }
        _ => {
            w.f1.iter()
                .zip(&w.f2)
                .map(|(&a, &b)| match s.feature {
                    // Domes: high at the feature point, low at the walls.
                    0 => {
                        let dome = 1.0 - a.min(1.0);
                        let wall = (b - a).min(1.0);
                        (1.0 - s.crack) * dome + s.crack * wall
                    }
                    1 => a.min(1.5),
                    2 => b.min(2.0),
                    _ => (b - a).min(1.0),
                })
                .collect()
        }
    };
    normalise(&mut h);
    h
}
