//! Table 2 probe (issue 12): the multiscale scene traced with each step
//! strategy, plus the adaptive strategy as it was before issue 12
//! ("old", a copy below), variants alternating per repeat so load changes
//! weigh on all alike. Each pixel: trace, and for a hit the central-
//! difference normal (6 evaluations), as `micro-render` does.
//! `cargo run --release --example micro_table2 -- [size] [repeats] [scene.json]`
#![allow(clippy::disallowed_methods)] // timing: native only
use filigree::geom::sdf3;
use filigree::micro::render::{self, Camera, Rays, Stats, StepMode, Trace};
use filigree::micro::Scene;
use glam::DVec3;
use std::time::Instant;

/// `render::trace`'s adaptive branch before issue 12: a 6-evaluation
/// gradient check every N steps (from step 0), relax `0.9 / g` (≤ 4) where
/// g < 0.7, an undone step retaken plainly.
fn old_adaptive(scene: &Scene, o: DVec3, d: DVec3, s: &Trace, st: &mut Stats) -> Option<f64> {
    st.rays += 1;
    let (t0, t1) = render::clip(o, d, s.bounds * (1.0 + 1e-9) + 1e-12)?;
    let f = |t: f64, st: &mut Stats| {
        st.sdf_evals += 1;
        render::field(scene, s.bounds, o + d * t)
    };
    let tiny = 1e-12 * (1.0 + t1);
    let (mut t, mut relax, mut last_cell) = (t0, 1.0f64, DVec3::NAN);
    let mut dist = f(t, st);
    for i in 0..s.max_steps {
        if dist < s.precision * t.max(tiny) {
            return Some(t);
        }
        if t > t1 {
            return None;
        }
        st.steps += 1;
        let check = if s.check_cell > 0.0 {
            let q = ((o + d * t) / s.check_cell).floor();
            let fresh = q != last_cell;
            last_cell = q;
            let m = s.check_modulus.max(1) as f64;
            i == 0 || (fresh && (q.x + 2.0 * q.y + 3.0 * q.z).rem_euclid(m) == 0.0)
        } else {
            i % s.check_every.max(1) == 0
        };
        if check {
            st.gradient_checks += 1;
            let h = (s.precision * t).max(1e-9);
            let mut e = |q| {
                st.sdf_evals += 1;
                render::field(scene, s.bounds, q)
            };
            let g = sdf3::gradient(&mut e, o + d * t, h).length();
            relax = if g < 0.7 {
                (0.9 / g.max(1e-9)).clamp(1.0, 4.0)
            } else {
                1.0
            };
        }
        let (tp, dp) = (t, dist);
        t += dist * relax;
        dist = f(t, st);
        if relax > 1.0 && (dist < 0.0 || dp + dist < (t - tp) * (1.0 - 1e-12)) {
            st.undone_steps += 1;
            relax = 1.0;
            t = tp + dp;
            dist = f(t, st);
        }
    }
    st.exhausted += 1;
    None
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let size: u32 = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(160);
    let repeats: usize = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(5);
    let path = a
        .get(3)
        .cloned()
        .unwrap_or("assets/micro/multiscale.json".into());
    let scene =
        filigree::micro::parse(&std::fs::read_to_string(&path).expect("scene")).expect("parse");
    let rays = Rays::new(&Camera::default(), size, size);
    let base = Trace {
        mode: StepMode::Fixed,
        check_every: 10,
        check_cell: 0.0,
        check_modulus: 3,
        max_relax: 1.5,
        bisection_factor: 1.5,
        max_steps: 512,
        precision: rays.pixel_angle() * 0.5,
        bounds: 1.0,
    };
    let v = |name: &'static str, old: bool, mode, n, cell| {
        (
            name,
            old,
            Trace {
                mode,
                check_every: n,
                check_cell: cell,
                ..base
            },
        )
    };
    let variants = [
        v("fixed", false, StepMode::Fixed, 10, 0.0),
        v("bisection", false, StepMode::Bisection, 10, 0.0),
        v("old fully adaptive", true, StepMode::Adaptive, 1, 0.0),
        v("old adaptive N 10", true, StepMode::Adaptive, 10, 0.0),
        v("old adaptive N 100", true, StepMode::Adaptive, 100, 0.0),
        v("old adaptive N 500", true, StepMode::Adaptive, 500, 0.0),
        v("old adaptive D(p) = 1", true, StepMode::Adaptive, 10, 0.05),
        v("fully adaptive", false, StepMode::Adaptive, 1, 0.0),
        v("adaptive N 10", false, StepMode::Adaptive, 10, 0.0),
        v("adaptive N 100", false, StepMode::Adaptive, 100, 0.0),
        v("adaptive N 500", false, StepMode::Adaptive, 500, 0.0),
        v("adaptive D(p) = 1", false, StepMode::Adaptive, 10, 0.05),
        v(
            "adaptive D(p) = 1, cell 0.1",
            false,
            StepMode::Adaptive,
            10,
            0.1,
        ),
        v(
            "adaptive D(p) = 1, cell 0.25",
            false,
            StepMode::Adaptive,
            10,
            0.25,
        ),
    ];
    let mut ms = vec![vec![]; variants.len()];
    let mut stats = vec![Stats::default(); variants.len()];
    for _ in 0..repeats {
        for (k, (_, old, tr)) in variants.iter().enumerate() {
            let mut st = Stats::default();
            let t = Instant::now();
            let mut sum = 0.0;
            for y in 0..size {
                for x in 0..size {
                    let d = rays.dir(x, y);
                    let hit = if *old {
                        old_adaptive(&scene, rays.origin, d, tr, &mut st)
                    } else {
                        render::trace(&scene, rays.origin, d, tr, &mut st)
                    };
                    if let Some(th) = hit {
                        st.hits += 1;
                        let mut e = |q| {
                            st.sdf_evals += 1;
                            render::field(&scene, 1.0, q)
                        };
                        let h = (tr.precision * th * 0.5).max(1e-9);
                        sum += sdf3::gradient(&mut e, rays.origin + d * th, h).x;
                    }
                }
            }
            std::hint::black_box(sum);
            ms[k].push(t.elapsed().as_secs_f64() * 1e3);
            stats[k] = st;
        }
    }
    let med = |v: &[f64]| {
        let mut v = v.to_vec();
        v.sort_by(f64::total_cmp);
        v[v.len() / 2]
    };
    let f = med(&ms[0]);
    let fe = stats[0].sdf_evals as f64;
    println!("{path} {size}² repeats {repeats} (alternating); ratios to fixed in this run");
    for (k, (name, ..)) in variants.iter().enumerate() {
        let m = med(&ms[k]);
        let s = stats[k];
        let r = s.rays as f64;
        println!(
            "| {name} | {m:.0} | {:.3} | {:.2} | {:.2} | {:.3} | {:.2} | {:.3} | {} |",
            m / f,
            s.steps as f64 / r,
            s.sdf_evals as f64 / r,
            s.sdf_evals as f64 / fe,
            s.gradient_checks as f64 / r,
            s.undone_steps as f64 / r,
            s.hits
        );
    }
}
