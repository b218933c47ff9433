//! The three cellular-automaton models: forest fire (Drossel–Schwabl),
//! surface tension (Vichniac's annealing vote) and excitable media
//! (Griffeath's cyclic cellular automaton, which forms spiral waves).
//!
//! Each runs on a torus of `grid` cells for a bounded number of steps
//! (grid² × steps ≤ 160² × 150 cell updates), then the state is turned into
//! heights, lightly blurred and resampled to the output size.
use super::common::{box_blur, normalise, resample};
use super::{int, real, Family, Model, ParamSpec};
use crate::core::rng::Rng;

/// Wrapped Moore neighbours: the index rows above/below and columns left/right.
fn neighbours(g: usize, i: usize) -> [usize; 8] {
    let (x, y) = (i % g, i / g);
    let (xl, xr) = ((x + g - 1) % g, (x + 1) % g);
    let (yu, yd) = ((y + g - 1) % g, (y + 1) % g);
    [
        yu * g + xl,
        yu * g + x,
        yu * g + xr,
        y * g + xl,
        y * g + xr,
        yd * g + xl,
        yd * g + x,
        yd * g + xr,
    ]
}

fn finish(mut h: Vec<f32>, g: usize, blur: usize, n: usize) -> Vec<f32> {
    box_blur(&mut h, g, blur);
    let mut out = resample(&h, g, n);
    normalise(&mut out);
    out
}

const FOREST_PARAMS: &[ParamSpec] = &[
    int("grid", 64.0, 160.0, 96.0),
    // Dataset: growth 0.015..0.04 and lightning 8e-5..2e-4, where fires
    // leave burn scars (square fronts, regrowth of another age). With more
    // lightning (up to 1e-3) fires start everywhere, and with too little
    // (2e-5) none has started in the first steps; slow growth (0.005)
    // leaves the initial random trees; all three draw the blurred speckle
    // of random cells that `ca-excitable-media` draws where it does not
    // organise (rendered side by side, 2026-12-02).
    real("growth", 0.005, 0.08, 0.03).dataset(0.015, 0.04),
    real("lightning", 0.00002, 0.001, 0.0002).dataset(0.00008, 0.0002),
    int("steps", 20.0, 150.0, 80.0),
];

/// Trees grow on empty cells with probability `growth`, lightning sets a
/// tree alight with probability `lightning`, fire spreads to neighbouring
/// trees and burns out. Height: a tree's age (capped), so burnt scars and
/// regrowth read as relief.
pub const FOREST_FIRE: Model = Model {
    id: "ca-forest-fire",
    name: "CA (Forest fire model)",
    family: Family::CellularAutomaton,
    params: FOREST_PARAMS,
    generate: forest_fire,
};

fn forest_fire(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let g = p[0] as usize;
    let (grow, light) = (p[1], p[2]);
    let steps = p[3] as usize;
    let mut rng = Rng::new(seed);
    // 0 empty, 1 tree, 2 fire.
    let mut state: Vec<u8> = (0..g * g).map(|_| u8::from(rng.f64() < 0.55)).collect();
    let mut age: Vec<u16> = (0..g * g).map(|_| rng.below(40) as u16).collect();
    let mut next = state.clone();
    for _ in 0..steps {
        for i in 0..g * g {
            next[i] = match state[i] {
                2 => {
                    age[i] = 0;
                    0
                }
                1 => {
                    let burning = neighbours(g, i).iter().any(|&j| state[j] == 2);
                    if burning || rng.f64() < light {
                        2
                    } else {
                        age[i] = age[i].saturating_add(1);
                        1
                    }
                }
                _ => u8::from(rng.f64() < grow),
            };
        }
        std::mem::swap(&mut state, &mut next);
    }
    let cap = 40.0f32;
    let h: Vec<f32> = state
        .iter()
        .zip(&age)
        .map(|(&s, &a)| {
            if s == 1 {
                0.25 + (a as f32).min(cap) / cap
            } else {
                0.0
            }
        })
        .collect();
    finish(h, g, 1, n)
}

const TENSION_PARAMS: &[ParamSpec] = &[
    int("grid", 48.0, 160.0, 96.0),
    real("density", 0.4, 0.6, 0.5),
    int("iterations", 2.0, 40.0, 20.0),
    int("smoothing", 0.0, 3.0, 1.0),
];

/// Random binary cells; each step a cell takes the majority of its 3×3
/// block except that 4 and 5 of 9 are swapped (the annealing rule), which
/// lets boundaries straighten like surface tension: blobs coarsen with
/// `iterations`, their share is `density`.
pub const SURFACE_TENSION: Model = Model {
    id: "ca-surface-tension",
    name: "CA (Surface tension model)",
    family: Family::CellularAutomaton,
    params: TENSION_PARAMS,
    generate: surface_tension,
};

fn surface_tension(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let g = p[0] as usize;
    let density = p[1];
    let iters = p[2] as usize;
    let mut rng = Rng::new(seed);
    let mut s: Vec<u8> = (0..g * g).map(|_| u8::from(rng.f64() < density)).collect();
    let mut next = s.clone();
    for _ in 0..iters {
        for i in 0..g * g {
            let c = s[i] + neighbours(g, i).iter().map(|&j| s[j]).sum::<u8>();
            next[i] = u8::from(matches!(c, 4 | 6..=9));
        }
        std::mem::swap(&mut s, &mut next);
    }
    let h: Vec<f32> = s.iter().map(|&v| v as f32).collect();
    finish(h, g, p[3] as usize, n)
}

const EXCITABLE_PARAMS: &[ParamSpec] = &[
    int("grid", 64.0, 160.0, 112.0),
    // Dataset: states 4–5, threshold 2–3, steps 60–120, where the automaton
    // organises into waves and spirals. Elsewhere it stays the blurred
    // speckle of random states: with threshold 1 every cell advances at
    // once, with many states and threshold 3 none does, and after 10–50
    // steps a fine grid has not organised yet; that speckle is also the
    // forest fire's picture without fires (see `FOREST_PARAMS`).
    int("states", 3.0, 12.0, 5.0).dataset(4.0, 5.0),
    int("threshold", 1.0, 3.0, 2.0).dataset(2.0, 3.0),
    int("steps", 10.0, 120.0, 80.0).dataset(60.0, 120.0),
];

/// Griffeath's cyclic automaton: a cell in state s moves to s+1 (mod
/// `states`) when at least `threshold` neighbours are already there. From
/// random states it organises into travelling waves and spirals; height is
/// the phase (a cosine of the state, so the cycle has no seam).
pub const EXCITABLE: Model = Model {
    id: "ca-excitable-media",
    name: "CA (Excitable media model)",
    family: Family::CellularAutomaton,
    params: EXCITABLE_PARAMS,
    generate: excitable,
};

fn excitable(p: &[f64], seed: u64, n: usize) -> Vec<f32> {
    let g = p[0] as usize;
    let k = p[1] as u8;
    let th = p[2] as usize;
    let steps = p[3] as usize;
    let mut rng = Rng::new(seed);
    let mut s: Vec<u8> = (0..g * g).map(|_| rng.below(k as usize) as u8).collect();
    let mut next = s.clone();
    for _ in 0..steps {
        for i in 0..g * g {
            let up = (s[i] + 1) % k;
            let c = neighbours(g, i).iter().filter(|&&j| s[j] == up).count();
            next[i] = if c >= th { up } else { s[i] };
        }
        std::mem::swap(&mut s, &mut next);
    }
    let h: Vec<f32> = s
        .iter()
        .map(|&v| 0.5 - 0.5 * libm::cosf(std::f32::consts::TAU * v as f32 / k as f32))
        .collect();
    finish(h, g, 1, n)
}
