//! Reaction–diffusion: the Gray–Scott model (Pearson 1993) on a torus of
//! `grid` cells, from a random start, for a bounded number of steps; the
//! height is the concentration of V, resampled to the output size.
//!
//! (F, k) pairs come from Pearson's chart along a path of patterned
//! regimes (`pattern` 0 → 1: mazes, holes, coral, spots), so every
//! parameter value forms a pattern rather than dying out.
use super::common::{normalise, resample};
use super::{int, real, Family, Model, ParamSpec};
use crate::core::rng::Rng;

const PARAMS: &[ParamSpec] = &[
    real("pattern", 0.0, 1.0, 0.5),
    int("grid", 48.0, 112.0, 80.0),
    int("steps", 400.0, 2000.0, 1500.0),
];

/// Pearson-chart waypoints (F, k) the `pattern` parameter runs through.
const PATH: [(f32, f32); 4] = [
    (0.029, 0.057),
    (0.039, 0.058),
    (0.0545, 0.062),
    (0.035, 0.065),
];

/// `pattern` picks the regime; `grid` the cells per side (fewer → larger
/// features); `steps` how far the pattern has developed.
pub const REACTION_DIFFUSION: Model = Model {
    id: "reaction-diffusion",
    name: "Reaction Diffusion",
    family: Family::ReactionDiffusion,
    params: PARAMS,
    generate: reaction,
};

fn reaction(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let t = p[0] as f32 * (PATH.len() - 1) as f32;
    let i = (t.floor() as usize).min(PATH.len() - 2);
    let f = t - i as f32;
    let feed = PATH[i].0 + f * (PATH[i + 1].0 - PATH[i].0);
    let kill = PATH[i].1 + f * (PATH[i + 1].1 - PATH[i].1);
    let g = p[1] as usize;
    let steps = p[2] as usize;
    let mut rng = Rng::new(seed);
    let mut u = vec![1.0f32; g * g];
    let mut v = vec![0.0f32; g * g];
    // Random seeding: scattered squares of V.
    for _ in 0..(g * g / 60).max(4) {
        let (cx, cy) = (rng.below(g), rng.below(g));
        for dy in 0..3 {
            for dx in 0..3 {
                let j = ((cy + dy) % g) * g + (cx + dx) % g;
                u[j] = 0.5;
                v[j] = 0.25 + 0.1 * rng.f64() as f32;
            }
        }
    }
    let (du, dv) = (0.2097f32, 0.105f32);
    let (mut nu, mut nv) = (u.clone(), v.clone());
    let left: Vec<usize> = (0..g).map(|x| (x + g - 1) % g).collect();
    let right: Vec<usize> = (0..g).map(|x| (x + 1) % g).collect();
    for _ in 0..steps {
        for y in 0..g {
            let (yu, yd, row) = (left[y] * g, right[y] * g, y * g);
            for x in 0..g {
                let i = row + x;
                let (a, b) = (row + left[x], row + right[x]);
                let (c, d) = (yu + x, yd + x);
                let (ui, vi) = (u[i], v[i]);
                let lu = u[a] + u[b] + u[c] + u[d] - 4.0 * ui;
                let lv = v[a] + v[b] + v[c] + v[d] - 4.0 * vi;
                let uvv = ui * vi * vi;
                nu[i] = ui + du * lu - uvv + feed * (1.0 - ui);
                nv[i] = vi + dv * lv + uvv - (feed + kill) * vi;
            }
        }
        std::mem::swap(&mut u, &mut nu);
        std::mem::swap(&mut v, &mut nv);
    }
    let mut out = resample(&v, g, n);
    normalise(&mut out);
    out
}
