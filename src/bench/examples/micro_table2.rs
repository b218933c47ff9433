//! Table 2 probe (issue 12): the multiscale scene traced with each step
//! strategy, plus the adaptive strategy as it was in session 17 ("s17",
//! 6-evaluation gradient checks, a copy below), variants alternating per
//! repeat so load changes weigh on all alike. Each pixel: trace, and for a hit the central-
//! difference normal (6 evaluations), as `micro-render` does.
//! `cargo run --release --example micro_table2 -- [size] [repeats] [scene.json]`
#![allow(clippy::disallowed_methods)] // timing: native only
use filigree::micro::render::{self, Camera, Rays, Stats, StepMode, Trace};
use filigree::micro::sdf3;
use filigree::micro::Scene;
use glam::DVec3;
use std::time::Instant;

/// `render::trace`'s adaptive branch as of session 17 (issue 12): the same
/// loop, but each check a 6-evaluation central-difference gradient of which
/// only the slope along the ray was used (now: a 1-evaluation forward
/// difference along the ray).
fn s17_adaptive(scene: &Scene, o: DVec3, d: DVec3, s: &Trace, st: &mut Stats) -> Option<f64> {
    st.rays += 1;
    let (t0, t1) = render::clip(o, d, s.bounds * (1.0 + 1e-9) + 1e-12)?;
    let f = |t: f64, st: &mut Stats| {
        st.sdf_evals += 1;
        render::field(scene, s.bounds, o + d * t)
    };
    let tiny = 1e-12 * (1.0 + t1);
    let mut t = t0;
    let mut dist = f(t, st);
    let mut relax = s.max_relax.max(1.0);
    let mut cooldown = false;
    let mut last_cell = DVec3::NAN;
    for i in 0..s.max_steps {
        let eps = s.precision * t.max(tiny);
        if dist < eps {
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
            fresh && i > 0 && (q.x + 2.0 * q.y + 3.0 * q.z).rem_euclid(m) == 0.0
        } else {
            i % s.check_every.max(1) == 0 && (i > 0 || s.check_every <= 1)
        };
        if check && dist >= 2.0 * eps {
            st.gradient_checks += 1;
            let h = (s.precision * t).max(1e-9);
            let g = sdf3::gradient(
                &mut |q| {
                    st.sdf_evals += 1;
                    render::field(scene, s.bounds, q)
                },
                o + d * t,
                h,
            );
            relax = render::relax_for_slope(-g.dot(d), s.max_relax);
        }
        let step = if cooldown { 1.0 } else { relax };
        cooldown = false;
        let (tp, dp) = (t, dist);
        t += dist * step;
        dist = f(t, st);
        if step > 1.0 && (dist < 0.0 || dp + dist < (t - tp) * (1.0 - 1e-12)) {
            st.undone_steps += 1;
            cooldown = true;
            let (tr, dr) = (t, dist);
            t = tp + dp;
            dist = f(t, st);
            if dr >= 0.0 && dist + dr >= (tr - t) * (1.0 + 1e-12) {
                t = tr;
                dist = dr;
            }
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
        v(
            "s17 fully adaptive (6-eval checks)",
            true,
            StepMode::Adaptive,
            1,
            0.0,
        ),
        v("s17 adaptive N 10", true, StepMode::Adaptive, 10, 0.0),
        v(
            "s17 adaptive D(p), cell 0.25",
            true,
            StepMode::Adaptive,
            10,
            0.25,
        ),
        v(
            "fully adaptive (1-eval checks)",
            false,
            StepMode::Adaptive,
            1,
            0.0,
        ),
        v("adaptive N 10", false, StepMode::Adaptive, 10, 0.0),
        v("adaptive N 100", false, StepMode::Adaptive, 100, 0.0),
        v("adaptive N 500", false, StepMode::Adaptive, 500, 0.0),
        v(
            "adaptive D(p), cell 0.25",
            false,
            StepMode::Adaptive,
            10,
            0.25,
        ),
        v(
            "adaptive D(p), cell 0.1",
            false,
            StepMode::Adaptive,
            10,
            0.1,
        ),
        v(
            "adaptive D(p), cell 0.05",
            false,
            StepMode::Adaptive,
            10,
            0.05,
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
                        s17_adaptive(&scene, rays.origin, d, tr, &mut st)
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
