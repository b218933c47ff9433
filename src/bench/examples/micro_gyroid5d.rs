//! Issue 12 item 3: `bench micro`'s gyroid 5D fit with coarse to fine
//! (budget 3000, seeds 1–3) for each optimiser, one thread.
use filigree::core::job::run_quietly;
use filigree::micro::fit_api::{start_fit, FitParam, FitTarget, MicroFitRequest, Optimizer};
use serde_json::json;

fn gyroid(ex: f64, ey: f64, ez: f64, a: f64, t: f64) -> String {
    let f = |w: &str, ax: &str, freq: f64, amp: f64| json!({"wave": w, "axis": ax, "freq": freq, "amp": amp});
    json!({"type": "periodic", "thickness": t, "terms": [
        [f("sin", "x", ex, a), f("cos", "y", ey, 1.0)],
        [f("sin", "y", ey, a), f("cos", "z", ez, 1.0)],
        [f("sin", "z", ez, a), f("cos", "x", ex, 1.0)]]})
    .to_string()
}

fn p(pointer: &str, lo: f64, hi: f64, also: &[&str]) -> FitParam {
    FitParam {
        pointer: pointer.into(),
        lo,
        hi,
        also: also.iter().map(|s| s.to_string()).collect(),
    }
}

fn main() {
    let opts: Vec<Optimizer> = match std::env::args().nth(1).as_deref() {
        Some("powell") => vec![Optimizer::Powell],
        _ => vec![Optimizer::Cmaes, Optimizer::NelderMead, Optimizer::Powell],
    };
    for opt in opts {
        for seed in 1..=3 {
            let req = MicroFitRequest {
                scene: gyroid(200.0, 200.0, 200.0, 6.0, 0.0),
                params: vec![
                    p("/terms/0/0/freq", 10.0, 400.0, &["/terms/2/1/freq"]),
                    p("/terms/0/1/freq", 10.0, 400.0, &["/terms/1/0/freq"]),
                    p("/terms/1/1/freq", 10.0, 400.0, &["/terms/2/0/freq"]),
                    p(
                        "/terms/0/0/amp",
                        1.0,
                        20.0,
                        &["/terms/1/0/amp", "/terms/2/0/amp"],
                    ),
                    p("/thickness", 0.0, 3.0, &[]),
                ],
                target: FitTarget::Scene {
                    scene: gyroid(100.0, 120.0, 80.0, 7.0, 1.2),
                },
                grid: 32,
                center: [0.125; 3],
                half: 0.125,
                optimizer: opt,
                budget: 3000,
                population: 20,
                sigma: 0.3,
                seed,
                coarse_to_fine: true,
                ..Default::default()
            };
            let out = run_quietly(start_fit(req).expect("request")).expect("fit");
            println!(
                "{}",
                json!({"optimizer": opt, "seed": seed, "validation": out.validation, "loss": out.loss,
                    "values": out.values.iter().map(|v| (v * 1000.0).round() / 1000.0).collect::<Vec<_>>()})
            );
        }
    }
}
