//! Coarse to fine against the paper's loss alone on particle scenes
//! (issue 12): `bench micro`'s spheres 2D problem and an ellipsoid cloud
//! (cell and radius), each optimiser, seeds 1..=3, the same budget, one
//! thread. Prints one JSON line per fit.
//! `cargo run --release --example micro_c2f_particles -- [budget] [problem|all] [optimizer]`
#![allow(clippy::disallowed_methods)] // timing: native only
use filigree::core::job::run_quietly;
use filigree::micro::fit_api::{start_fit, FitParam, FitTarget, MicroFitRequest, Optimizer};
use serde_json::json;
use std::time::Instant;

fn cloud(cell: f64, radius: f64, shape: &str) -> String {
    let shapes = if shape == "ellipsoid" {
        json!([{"shape": "ellipsoid", "axes": [1, 0.6, 0.4]}])
    } else {
        json!([{"shape": "sphere"}])
    };
    json!({"type": "particles", "cell": cell, "seed": 5, "jitter": 0.5,
        "size": {"dist": "fixed", "radius": radius}, "shapes": shapes})
    .to_string()
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let budget: u32 = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(1500);
    let only = a.get(2).cloned().filter(|s| s != "all");
    let only_opt = a.get(3).cloned();
    let param = |p: &str, lo: f64, hi: f64| FitParam {
        pointer: p.into(),
        lo,
        hi,
        also: vec![],
    };
    let problems = [
        (
            "spheres-2d",
            cloud(0.08, 0.2, "sphere"),
            cloud(0.05, 0.3, "sphere"),
        ),
        (
            "ellipsoids-2d",
            cloud(0.09, 0.2, "ellipsoid"),
            cloud(0.06, 0.35, "ellipsoid"),
        ),
    ];
    let truth = [[0.05, 0.3], [0.06, 0.35]];
    for (k, (name, start, target)) in problems.iter().enumerate() {
        if only.as_deref().is_some_and(|o| o != *name) {
            continue;
        }
        for opt in [Optimizer::Cmaes, Optimizer::NelderMead, Optimizer::Powell] {
            if only_opt.as_deref().is_some_and(|o| json!(opt) != json!(o)) {
                continue;
            }
            for seed in 1..=3 {
                for c2f in [false, true] {
                    let req = MicroFitRequest {
                        scene: start.clone(),
                        params: vec![
                            param("/cell", 0.02, 0.12),
                            param("/size/radius", 0.05, 0.45),
                        ],
                        target: FitTarget::Scene {
                            scene: target.clone(),
                        },
                        grid: 32,
                        center: [0.0; 3],
                        half: 0.25,
                        optimizer: opt,
                        budget,
                        population: 20,
                        sigma: 0.3,
                        seed,
                        coarse_to_fine: c2f,
                        ..Default::default()
                    };
                    let t = Instant::now();
                    let out = run_quietly(start_fit(req).expect("request")).expect("fit");
                    let rel = out
                        .values
                        .iter()
                        .zip(truth[k])
                        .map(|(v, t)| ((v - t) / t).abs())
                        .fold(0.0, f64::max);
                    println!(
                        "{}",
                        json!({"problem": name, "optimizer": opt, "seed": seed, "coarse_to_fine": c2f,
                            "validation": out.validation, "loss": out.loss, "rel_err_max": rel,
                            "values": out.values, "evaluations": out.evaluations,
                            "seconds": t.elapsed().as_secs_f64()})
                    );
                }
            }
        }
    }
}
