//! Reaction–diffusion: the Gray–Scott model (Pearson 1993) on a torus of
//! `grid` cells, from a random start, for a bounded number of steps; the
//! height is the concentration of V, resampled to the output size.
//!
//! (F, k) pairs come from Pearson's chart (in the usual scaling
//! D_u = 0.2097, D_v = 0.105 a cell², Δt = 1) along a path through his
//! patterned regimes (`pattern` 0 → 1: labyrinth, holes, holes mixed with
//! stripes, coral labyrinth, stripes, mitosis (spots and stripes
//! dividing), spots), so every parameter value forms a pattern rather
//! than dying out (each waypoint and the midpoints between them simulated
//! at 72² for 1200 steps, 2026-12-04).
use super::common::{normalise, resample};
use super::{int, real, Family, Model, ParamSpec};
use crate::core::rng::Rng;

const PARAMS: &[ParamSpec] = &[
    real("pattern", 0.0, 1.0, 0.5),
    int("grid", 48.0, 96.0, 72.0),
    int("steps", 400.0, 1600.0, 1200.0),
];

/// Pearson-chart waypoints `(pattern, F, k)` the `pattern` parameter runs
/// through (piecewise linear). Holes and coral stay at 0.375 and 0.625, so
/// the default 0.5 is their midpoint as before (the same bits).
const PATH: [(f32, f32, f32); 7] = [
    (0.0, 0.030, 0.0565),   // labyrinth
    (0.1875, 0.037, 0.060), // labyrinth, finer
    (0.375, 0.039, 0.058),  // holes
    (0.625, 0.0545, 0.062), // coral (labyrinth with loops)
    (0.75, 0.042, 0.063),   // stripes (worms)
    (0.875, 0.045, 0.0635), // mitosis: spots and worms dividing
    (1.0, 0.038, 0.064),    // spots
];

/// (F, k) at `pattern` in [0, 1].
fn feed_kill(pattern: f32) -> (f32, f32) {
    let i = PATH[..PATH.len() - 1]
        .iter()
        .rposition(|w| w.0 <= pattern)
        .unwrap_or(0);
    let (a, b) = (PATH[i], PATH[i + 1]);
    let f = ((pattern - a.0) / (b.0 - a.0)).clamp(0.0, 1.0);
    (a.1 + f * (b.1 - a.1), a.2 + f * (b.2 - a.2))
}

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
    let (feed, kill) = feed_kill(p[0] as f32);
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
    let coef = Coef { du, dv, feed, kill };
    for _ in 0..steps {
        for y in 0..g {
            let (yu, yd) = ((y + g - 1) % g * g, (y + 1) % g * g);
            let row = y * g;
            let rows = Rows {
                ur: &u[row..row + g],
                uu: &u[yu..yu + g],
                ud: &u[yd..yd + g],
                vr: &v[row..row + g],
                vu: &v[yu..yu + g],
                vd: &v[yd..yd + g],
            };
            let (nur, nvr) = (&mut nu[row..row + g], &mut nv[row..row + g]);
            rows.cell(&coef, 0, g - 1, 1, nur, nvr);
            for x in 1..g - 1 {
                rows.cell(&coef, x, x - 1, x + 1, nur, nvr);
            }
            rows.cell(&coef, g - 1, g - 2, 0, nur, nvr);
        }
        std::mem::swap(&mut u, &mut nu);
        std::mem::swap(&mut v, &mut nv);
    }
    let mut out = resample(&v, g, n);
    normalise(&mut out);
    out
}

struct Coef {
    du: f32,
    dv: f32,
    feed: f32,
    kill: f32,
}

/// One row of U and V with the rows above and below (wrapped).
struct Rows<'a> {
    ur: &'a [f32],
    uu: &'a [f32],
    ud: &'a [f32],
    vr: &'a [f32],
    vu: &'a [f32],
    vd: &'a [f32],
}

impl Rows<'_> {
    /// One explicit Euler step of cell `x` (neighbours `l`, `r` in the row).
    #[inline(always)]
    fn cell(&self, c: &Coef, x: usize, l: usize, r: usize, nu: &mut [f32], nv: &mut [f32]) {
        let (ui, vi) = (self.ur[x], self.vr[x]);
        let lu = self.ur[l] + self.ur[r] + self.uu[x] + self.ud[x] - 4.0 * ui;
        let lv = self.vr[l] + self.vr[r] + self.vu[x] + self.vd[x] - 4.0 * vi;
        let uvv = ui * vi * vi;
        nu[x] = ui + c.du * lu - uvv + c.feed * (1.0 - ui);
        nv[x] = vi + c.dv * lv + uvv - (c.feed + c.kill) * vi;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_pattern_is_the_old_paths_midpoint_and_the_waypoints_are_reached() {
        // Before 2026-12-04 the path was mazes, holes, coral, spots at
        // equal steps; the default 0.5 was halfway from holes to coral.
        let (f, k) = feed_kill(0.5);
        assert_eq!(f, 0.039f32 + 0.5 * (0.0545f32 - 0.039));
        assert_eq!(k, 0.058f32 + 0.5 * (0.062f32 - 0.058));
        for w in PATH {
            let (f, k) = feed_kill(w.0);
            assert!((f - w.1).abs() < 1e-7 && (k - w.2).abs() < 1e-7, "{w:?}");
        }
    }
}
