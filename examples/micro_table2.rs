//! Table 2 probe: the multiscale scene with each step strategy, modes
//! alternating per repeat so load changes weigh on all alike.
//! `cargo run --release --example micro_table2 -- [size] [repeats] [scene.json]`
use filigree::core::job::run_quietly;
use filigree::micro::api::{start_render, MicroRenderRequest};
use filigree::micro::render::StepMode;
use std::time::Instant;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let size: u32 = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(256);
    let repeats: usize = a.get(2).and_then(|s| s.parse().ok()).unwrap_or(3);
    let path = a
        .get(3)
        .cloned()
        .unwrap_or("assets/micro/multiscale.json".into());
    let scene = std::fs::read_to_string(&path).expect("scene");
    let variants: [(&str, StepMode, u32, f64); 7] = [
        ("fixed", StepMode::Fixed, 10, 0.0),
        ("bisection", StepMode::Bisection, 10, 0.0),
        ("fully adaptive", StepMode::Adaptive, 1, 0.0),
        ("adaptive N 10", StepMode::Adaptive, 10, 0.0),
        ("adaptive N 100", StepMode::Adaptive, 100, 0.0),
        ("adaptive N 500", StepMode::Adaptive, 500, 0.0),
        ("adaptive D(p) = 1", StepMode::Adaptive, 10, 0.05),
    ];
    let mut ms = vec![vec![]; variants.len()];
    let mut stats = vec![None; variants.len()];
    for _ in 0..repeats {
        for (k, (_, mode, n, cell)) in variants.iter().enumerate() {
            let req = MicroRenderRequest {
                scene: scene.clone(),
                width: size,
                height: size,
                steps: *mode,
                check_every: *n,
                check_cell: *cell,
                ..Default::default()
            };
            let t = Instant::now();
            let out = run_quietly(start_render(req).unwrap()).unwrap();
            ms[k].push(t.elapsed().as_secs_f64() * 1e3);
            stats[k] = Some(out.stats);
        }
    }
    let med = |v: &mut Vec<f64>| {
        v.sort_by(|a, b| a.total_cmp(b));
        v[v.len() / 2]
    };
    let f = med(&mut ms[0].clone());
    println!("{path} {size}² repeats {repeats}");
    for (k, (name, ..)) in variants.iter().enumerate() {
        let m = med(&mut ms[k]);
        let s = stats[k].unwrap();
        let r = s.rays as f64;
        println!(
            "{name:20} {m:8.1} ms ratio {:.3}  steps/ray {:.2} evals/ray {:.2} checks/ray {:.3} undone/ray {:.3} hits {} exhausted {}",
            m / f,
            s.steps as f64 / r,
            s.sdf_evals as f64 / r,
            s.gradient_checks as f64 / r,
            s.undone_steps as f64 / r,
            s.hits,
            s.exhausted
        );
    }
}
