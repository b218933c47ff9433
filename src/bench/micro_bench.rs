//! `filigree bench micro`: the paper's Table 2, Table 1 and Table 3 analogues.
//!
//! (a) Table 2: one multiscale scene (`assets/micro/multiscale.json`)
//! rendered with each step strategy; milliseconds (median of `repeats`,
//! the strategies alternating in each repeat), wall clock and this
//! thread's CPU time, ratios to fixed steps measured in the same run, and
//! the work counters.
//! (b) Table 1: a fibrous volume made three ways (periodic function,
//! direct primitive repeated on a grid, agglomeration of a congruence-
//! selected lattice) at four noise scales η (fibre frequency per world unit).
//! (c) Table 3: reconstruction (`micro-fit`) of gyroid 1D, fibres 2D,
//! spheres 2D, gyroid 3D and 5D with each optimiser over seeds: validation
//! error, evaluations, seconds and milliseconds per loss evaluation, plus
//! what one loss evaluation at 32³ costs (FFT + loss, and sampling).
//! `--quick`: gyroid 1D and spheres 2D, one seed, a short budget.
//! The paper's figures (OptiX on an RTX 4090, path traced at their own
//! resolution; SciPy/pycma for Table 3) are printed beside ours for their
//! trends, not their values.
use filigree::core::job::{run_quietly, Cancel};
use filigree::core::parallel::run_sharded_threads;
use filigree::micro::api::{start_render, MicroRenderRequest, MicroRenderResponse};
use filigree::micro::fit_api::{start_fit, FitParam, FitTarget, MicroFitRequest, Optimizer};
use filigree::micro::render::StepMode;
use serde_json::{json, Value};
use std::f64::consts::PI;
use std::time::Instant;

const MULTISCALE: &str = include_str!("../../assets/micro/multiscale.json");
const PILED: &str = include_str!("../../assets/micro/piled.json");

/// Table 2 of the paper: step length, RT (ms), FPS.
const TABLE2: [(&str, f64, f64); 8] = [
    ("fixed", 9.3, 105.7),
    ("bisection", 9.0, 108.5),
    ("fully adaptive", 44.1, 22.6),
    ("adaptive N 10", 11.5, 85.8),
    ("adaptive N 100", 8.1, 121.1),
    ("adaptive N 500", 8.1, 121.5),
    ("bisection + adaptive N 500", 8.0, 122.0),
    ("adaptive D(p) = 1", 7.8, 124.5),
];

/// Table 1 of the paper: grid noise scale, then RT (ms) of periodic
/// functions, direct primitive, particle agglomeration.
const TABLE1: [(f64, f64, f64, f64); 4] = [
    (10.0, 2.6, 4.1, 51.7),
    (50.0, 2.6, 5.9, 94.9),
    (100.0, 2.6, 6.5, 137.2),
    (200.0, 2.6, 7.1, 157.9),
];

fn render(req: &MicroRenderRequest, repeats: usize) -> Result<(f64, MicroRenderResponse), String> {
    let mut secs = vec![];
    let mut last = None;
    for _ in 0..repeats.max(1) {
        let t = Instant::now();
        let job = start_render(req.clone()).map_err(|e| e.to_string())?;
        let out = run_quietly(job).map_err(|e| e.to_string())?;
        secs.push(t.elapsed().as_secs_f64());
        last = Some(out);
    }
    let (_, median) = super::min_median(secs);
    Ok((median * 1e3, last.expect("one repeat")))
}

/// M5's tiles: the multiscale scene at 512² in 16 bands on 1 and on 2
/// scoped threads (`render_threads`, the CLI's `--threads`); the bytes are
/// the same, the ratio is the speed-up (2 cores here).
fn tile_scaling(repeats: usize) -> Result<Value, String> {
    let req = MicroRenderRequest {
        scene: MULTISCALE.to_string(),
        width: 512,
        height: 512,
        ..Default::default()
    };
    // 1 and 2 threads alternate, so a change of the machine's load in the
    // meantime weighs on both alike; the load average is printed beside.
    let load_before = loadavg();
    let mut secs = [vec![], vec![]];
    let mut png = None;
    for _ in 0..repeats.max(1) {
        for (i, threads) in [1usize, 2].into_iter().enumerate() {
            let t = Instant::now();
            let out = filigree::micro::api::render_threads(&req, threads, 16, &Cancel::new())
                .map_err(|e| e.to_string())?;
            secs[i].push(t.elapsed().as_secs_f64());
            if *png.get_or_insert_with(|| out.png.clone()) != out.png {
                return Err("bench micro: the tiled render's bytes depend on the threads".into());
            }
        }
    }
    let [a, b] = secs.map(|s| super::min_median(s).1 * 1e3);
    Ok(json!({
        "scene": "assets/micro/multiscale.json", "image": "512x512", "tiles": 16,
        "threads_1_ms": a, "threads_2_ms": b, "speedup_2_threads": a / b,
        "repeats_alternating": repeats.max(1),
        "cores": std::thread::available_parallelism().map(|n| n.get()).unwrap_or(1),
        "loadavg_1m_before": load_before, "loadavg_1m_after": loadavg(),
        "note": "same 16 tiles, same bytes; other processes on the machine (loadavg, runnable \
            tasks averaged over a minute) take cores from the 2-thread run first",
    }))
}

/// The 1-minute load average from `/proc/loadavg` (None elsewhere).
fn loadavg() -> Option<f64> {
    std::fs::read_to_string("/proc/loadavg")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

fn stats(out: &MicroRenderResponse) -> Value {
    serde_json::to_value(out.stats).unwrap_or(Value::Null)
}

/// The three fibrous scenes at noise scale `eta`: fibres along x on a
/// square grid of spacing 2π/η in y and z, radius ≈ 1.26/η.
fn fibres(eta: f64) -> [(&'static str, String); 3] {
    let spacing = 2.0 * PI / eta;
    let r = 1.26 / eta;
    let periodic = json!({"type": "periodic", "constant": 1.2, "terms": [
        [{"wave": "cos", "axis": "y", "freq": eta, "amp": -1}],
        [{"wave": "cos", "axis": "z", "freq": eta, "amp": -1}]]});
    let direct = json!({"type": "repeat", "cell": [1, spacing, spacing],
        "child": {"type": "box", "half": [10, r, r], "round": r}});
    let w = spacing / 2.0;
    let agglomerate = json!({"type": "lattice", "cell": w, "radius": r / w, "smooth": 0.25,
        "select": {"combine": "all", "terms": [
            {"poly": [{"c": 1, "y": 1}], "modulus": 2, "classes": [{"residue": 0}]},
            {"poly": [{"c": 1, "z": 1}], "modulus": 2, "classes": [{"residue": 0}]}]}});
    [
        ("periodic", periodic.to_string()),
        ("direct", direct.to_string()),
        ("agglomeration", agglomerate.to_string()),
    ]
}

/// Which parts of `bench micro` to run.
pub struct Parts {
    pub render: bool,
    pub fit: bool,
    /// `--only loss`: one loss evaluation's cost and its split.
    pub loss: bool,
    pub quick: bool,
    pub seeds: u64,
    pub threads: usize,
}

pub fn run(repeats: usize, size: u32, parts: Parts) -> Result<(), String> {
    if parts.loss {
        println!("{}", json!({"bench": "micro", "loss_eval": loss_eval()?}));
        return Ok(());
    }
    let table3 = if parts.fit {
        Some(table3(parts.quick, parts.seeds, parts.threads)?)
    } else {
        None
    };
    if !parts.render {
        println!(
            "{}",
            json!({"bench": "micro", "table3_reconstruction": table3})
        );
        return Ok(());
    }
    let base = MicroRenderRequest {
        scene: MULTISCALE.to_string(),
        width: size,
        height: size,
        ..Default::default()
    };
    // (a) step strategies.
    let variants: [(&str, StepMode, u32, f64); 7] = [
        ("fixed", StepMode::Fixed, 10, 0.0),
        ("bisection", StepMode::Bisection, 10, 0.0),
        ("fully adaptive", StepMode::Adaptive, 1, 0.0),
        ("adaptive N 10", StepMode::Adaptive, 10, 0.0),
        ("adaptive N 100", StepMode::Adaptive, 100, 0.0),
        ("adaptive N 500", StepMode::Adaptive, 500, 0.0),
        // D(p): checks where a ray enters a 0.25-unit cell of the
        // congruence class (0.05 until issue 12: 0.9 checks per ray here).
        ("adaptive D(p) = 1", StepMode::Adaptive, 10, 0.25),
    ];
    let mut table2 = vec![];
    for (scene_name, scene) in [("multiscale", MULTISCALE), ("piled", PILED)] {
        let reqs: Vec<MicroRenderRequest> = variants
            .iter()
            .map(|&(_, mode, n, cell)| MicroRenderRequest {
                scene: scene.to_string(),
                steps: mode,
                check_every: n,
                check_cell: cell,
                ..base.clone()
            })
            .collect();
        // The variants alternate within each repeat (as in `tile_scaling`
        // and `src/bench/examples/micro_table2.rs`), so a change of the machine's
        // load weighs on all alike; beside the wall clock, this thread's
        // time on a core (the render runs on it), which load does not
        // inflate.
        let (mut wall, mut cpu) = (vec![vec![]; reqs.len()], vec![vec![]; reqs.len()]);
        let mut outs: Vec<Option<MicroRenderResponse>> = reqs.iter().map(|_| None).collect();
        for _ in 0..repeats.max(1) {
            for (k, req) in reqs.iter().enumerate() {
                let (t, c) = (Instant::now(), thread_cpu_ns());
                let job = start_render(req.clone()).map_err(|e| e.to_string())?;
                let out = run_quietly(job).map_err(|e| e.to_string())?;
                wall[k].push(t.elapsed().as_secs_f64() * 1e3);
                let c = thread_cpu_ns()
                    .zip(c)
                    .map_or(f64::NAN, |(b, a)| (b - a) as f64 * 1e-6);
                cpu[k].push(c);
                outs[k] = Some(out);
            }
        }
        let med = |v: &[f64]| super::min_median(v.to_vec()).1;
        let (f, fc) = (med(&wall[0]), med(&cpu[0]));
        let fe = outs[0].as_ref().map_or(1.0, |o| o.stats.sdf_evals as f64);
        let mut rows = vec![];
        for (k, (name, ..)) in variants.iter().enumerate() {
            let out = outs[k].as_ref().ok_or("bench micro: no render")?;
            let (ms, cpu_ms) = (med(&wall[k]), med(&cpu[k]));
            let paper = TABLE2.iter().find(|r| r.0 == *name);
            rows.push(json!({
                "strategy": name, "ms": ms, "ratio_to_fixed": ms / f,
                "cpu_ms": cpu_ms, "cpu_ratio_to_fixed": cpu_ms / fc,
                "evals_ratio_to_fixed": out.stats.sdf_evals as f64 / fe, "stats": stats(out),
                "paper_ms": paper.map(|r| r.1), "paper_ratio_to_fixed": paper.map(|r| r.1 / TABLE2[0].1),
            }));
        }
        table2.push(
            json!({"scene": format!("assets/micro/{scene_name}.json"), "rows": rows,
            "repeats_alternating": repeats.max(1), "loadavg_1m": loadavg()}),
        );
    }
    // (b) fibrous volume three ways.
    let mut fib = vec![];
    for (eta, p_per, p_dir, p_agg) in TABLE1 {
        let mut row = json!({"noise_scale": eta, "paper_ms": {"periodic": p_per, "direct": p_dir, "agglomeration": p_agg}});
        for (name, scene) in fibres(eta) {
            let req = MicroRenderRequest {
                scene,
                ..base.clone()
            };
            let (ms, out) = render(&req, repeats)?;
            row[name] = json!({"ms": ms, "fps": 1e3 / ms, "sdf_evals": out.stats.sdf_evals, "hits": out.stats.hits});
        }
        fib.push(row);
    }
    let tiles = tile_scaling(repeats)?;
    let out = json!({
        "bench": "micro",
        "image": format!("{size}x{size}"),
        "tile_scaling": tiles,
        "repeats": repeats.max(1),
        "table2_step_strategies": table2,
        "paper_note": "paper: OptiX on an RTX 4090, 1500 steps, Lambertian particles; \
            bisection + adaptive (paper 8.0 ms) is not a separate strategy here; adaptive = \
            over-relaxed steps (max_relax 1.5) with gradient checks every N steps from step N \
            (D(p): by 0.25-unit cell) setting the relaxation from the slope along the ray, a \
            1-evaluation forward difference (issue 12, docs/bench/micro-table2-2026-12-03.md, \
            micro-dp-2026-12-03.md); cpu_ms: this thread's time on a core",
        "table1_fibres": fib,
        "table3_reconstruction": table3,
    });
    println!("{out}");
    Ok(())
}

/// Table 3 of the paper: validation error and time per microstructure and
/// optimiser (SHGO-SDF, BH-SDF, CMA-ES-SDF, CMA-ES-S, Powell-S; "-S" fits
/// rendered images). `None`: not applicable.
type PaperCell = Option<(f64, &'static str)>;
const TABLE3: [(&str, [PaperCell; 5]); 5] = [
    (
        "gyroid-1d",
        [
            Some((0.0, "2.85s")),
            Some((0.0, "16.67s")),
            Some((0.0, "2.23s")),
            Some((1e-4, "20m")),
            Some((1e-6, "7m")),
        ],
    ),
    (
        "fibres-2d",
        [
            Some((0.34, "13m")),
            Some((1e-3, "20m")),
            Some((0.65, "6m")),
            Some((1.0, "20m")),
            Some((1.0, "5m")),
        ],
    ),
    (
        "gyroid-3d",
        [
            Some((1e-3, "22.7s")),
            Some((6e-3, "20m")),
            Some((1.02, "7m")),
            Some((0.15, "14m")),
            Some((2e-3, "20m")),
        ],
    ),
    (
        "spheres-2d",
        [
            None,
            None,
            Some((1e-5, "4m")),
            Some((1.01, "20m")),
            Some((1.01, "5m")),
        ],
    ),
    (
        "gyroid-5d",
        [
            Some((0.66, "2m")),
            Some((0.65, "15m")),
            Some((3e-4, "11m")),
            Some((0.03, "20m")),
            Some((0.44, "15m")),
        ],
    ),
];
const PAPER_COLUMNS: [&str; 5] = ["SHGO-SDF", "BH-SDF", "CMA-ES-SDF", "CMA-ES-S", "Powell-S"];

fn p(pointer: &str, lo: f64, hi: f64, also: &[&str]) -> FitParam {
    FitParam {
        pointer: pointer.into(),
        lo,
        hi,
        also: also.iter().map(|s| s.to_string()).collect(),
    }
}

/// A gyroid as Eq. 11 terms: `a sin(ηx x) cos(ηy y) + ...` with a sheet
/// thickness `t` (the paper's Gyroid [1D]/[3D]/[5D] family).
fn gyroid_terms(ex: f64, ey: f64, ez: f64, a: f64, t: f64) -> String {
    let f = |w: &str, ax: &str, freq: f64, amp: f64| json!({"wave": w, "axis": ax, "freq": freq, "amp": amp});
    json!({"type": "periodic", "thickness": t, "terms": [
        [f("sin", "x", ex, a), f("cos", "y", ey, 1.0)],
        [f("sin", "y", ey, a), f("cos", "z", ez, 1.0)],
        [f("sin", "z", ez, a), f("cos", "x", ex, 1.0)]]})
    .to_string()
}

const EX: [&str; 2] = ["/terms/0/0/freq", "/terms/2/1/freq"];
const EY: [&str; 2] = ["/terms/0/1/freq", "/terms/1/0/freq"];
const EZ: [&str; 2] = ["/terms/1/1/freq", "/terms/2/0/freq"];
const AMP: [&str; 3] = ["/terms/0/0/amp", "/terms/1/0/amp", "/terms/2/0/amp"];

/// Fibres along x on a grid of frequency η, turned by θ about z.
fn fibres_scene(eta: f64, theta: f64) -> String {
    json!({"type": "transform", "rotate": {"axis": [0, 0, 1], "angle": theta},
        "child": {"type": "periodic", "constant": 1.2, "terms": [
            [{"wave": "cos", "axis": "y", "freq": eta, "amp": -1}],
            [{"wave": "cos", "axis": "z", "freq": eta, "amp": -1}]]}})
    .to_string()
}

fn spheres_scene(cell: f64, radius: f64) -> String {
    json!({"type": "particles", "cell": cell, "seed": 5, "jitter": 0.5,
        "size": {"dist": "fixed", "radius": radius}})
    .to_string()
}

/// The five problems: (name, start scene, target scene, parameters, truth,
/// box centre and half size).
#[allow(clippy::type_complexity)]
fn problems() -> Vec<(
    &'static str,
    String,
    String,
    Vec<FitParam>,
    Vec<f64>,
    f64,
    f64,
)> {
    let all = |a: &[&str], b: &[&str]| -> Vec<String> {
        a.iter().chain(b).map(|s| s.to_string()).collect()
    };
    let eta_all = all(
        &all(&EX, &EY).iter().map(String::as_str).collect::<Vec<_>>(),
        &EZ,
    );
    let eta = |lo, hi| {
        let rest: Vec<&str> = eta_all[1..].iter().map(String::as_str).collect();
        p(&eta_all[0], lo, hi, &rest)
    };
    vec![
        (
            "gyroid-1d",
            gyroid_terms(300.0, 300.0, 300.0, 1.0, 0.0),
            gyroid_terms(100.0, 100.0, 100.0, 1.0, 0.0),
            vec![eta(10.0, 400.0)],
            vec![100.0],
            0.125,
            0.125,
        ),
        (
            "fibres-2d",
            fibres_scene(200.0, PI),
            fibres_scene(100.0, PI / 4.0),
            vec![
                p(
                    "/child/terms/0/0/freq",
                    10.0,
                    400.0,
                    &["/child/terms/1/0/freq"],
                ),
                p("/rotate/angle", 0.0, PI, &[]),
            ],
            vec![100.0, PI / 4.0],
            0.125,
            0.125,
        ),
        (
            "gyroid-3d",
            gyroid_terms(300.0, 300.0, 300.0, 6.0, 0.0),
            gyroid_terms(100.0, 100.0, 100.0, 7.0, 1.2),
            vec![
                eta(10.0, 400.0),
                p(AMP[0], 1.0, 20.0, &AMP[1..]),
                p("/thickness", 0.0, 3.0, &[]),
            ],
            vec![100.0, 7.0, 1.2],
            0.125,
            0.125,
        ),
        (
            "spheres-2d",
            spheres_scene(0.08, 0.2),
            spheres_scene(0.05, 0.3),
            vec![
                p("/cell", 0.02, 0.12, &[]),
                p("/size/radius", 0.05, 0.45, &[]),
            ],
            vec![0.05, 0.3],
            0.0,
            0.25,
        ),
        (
            "gyroid-5d",
            gyroid_terms(200.0, 200.0, 200.0, 6.0, 0.0),
            gyroid_terms(100.0, 120.0, 80.0, 7.0, 1.2),
            vec![
                p(EX[0], 10.0, 400.0, &EX[1..]),
                p(EY[0], 10.0, 400.0, &EY[1..]),
                p(EZ[0], 10.0, 400.0, &EZ[1..]),
                p(AMP[0], 1.0, 20.0, &AMP[1..]),
                p("/thickness", 0.0, 3.0, &[]),
            ],
            vec![100.0, 120.0, 80.0, 7.0, 1.2],
            0.125,
            0.125,
        ),
    ]
}

/// `bench micro`'s budget for a coarse-to-fine fit of a problem: gyroid 3D
/// and 5D get twice the paper-loss rows' (their first stage finds the
/// frequencies; the last two need the rest to pin the thickness).
fn c2f_budget(name: &str) -> u32 {
    match name {
        "gyroid-3d" | "gyroid-5d" => 3000,
        _ => 1500,
    }
}

/// The figures: a pycma + NumPy FFT version on a 32³ grid (ms per
/// loss evaluation; seconds to recover gyroid 1D) and the goal here.
const PYCMA_MS_PER_EVAL: f64 = 0.9;
const PYCMA_GYROID_1D_SECONDS: f64 = 0.8;
const GOAL_MS_PER_EVAL: f64 = 0.2;

/// `--only loss`: what one `micro-fit` loss evaluation costs on a 32³ grid
/// for gyroid 1D (the yardstick), whole and split into its parts:
/// the scene at the candidate (JSON edit + compile), sampling (the lattice
/// path, and point by point as before it, same values), FFT + loss
/// (half spectrum against the target's, computed once). Single-threaded.
fn loss_eval() -> Result<Value, String> {
    use filigree::core::job::Job;
    let (_, start, target, params, _, c, half) =
        problems().into_iter().next().ok_or("no problems")?;
    let mut job = start_fit(MicroFitRequest {
        scene: start,
        params,
        target: FitTarget::Scene {
            scene: target.clone(),
        },
        grid: 32,
        center: [c; 3],
        half,
        budget: 10,
        ..Default::default()
    })
    .map_err(|e| e.to_string())?;
    job.step().map_err(|e| e.to_string())?; // samples the target
                                            // A candidate near the truth (η ≈ 101 of 10..400).
    let u = [(101.0 - 10.0) / 390.0];
    let scene = job.scene_for(&u).ok_or("invalid candidate")?;
    let values = job.sample(&scene, false).map_err(|e| e.to_string())?;
    let target_scene = filigree::micro::parse(&target).map_err(|e| e.to_string())?;
    let target_values = job
        .sample(&target_scene, false)
        .map_err(|e| e.to_string())?;
    let mut old = legacy::OldLoss::new(32, &target_values)?;
    let n = 200;
    let compile = timed(n, || {
        std::hint::black_box(job.scene_for(&u));
    });
    let sample = timed(n, || {
        std::hint::black_box(job.sample(&scene, false).expect("sample"));
    });
    let pointwise = timed(n / 10, || {
        std::hint::black_box(job.sample(&scene, true).expect("sample"));
    });
    let fft = timed(n, || {
        std::hint::black_box(job.loss_of_samples(&values).expect("loss"));
    });
    let old_fft = timed(n, || {
        std::hint::black_box(old.loss(&values).expect("loss"));
    });
    let whole = timed(n, || {
        std::hint::black_box(job.evaluate(&u).expect("loss"));
    });
    let new_loss = job.loss_of_samples(&values).map_err(|e| e.to_string())?;
    let old_loss = old.loss(&values)?;
    let pick = |t: (f64, f64), i: usize| if i == 0 { t.0 } else { t.1 };
    let split = |i: usize| {
        json!({"scene_compile": pick(compile, i), "sampling": pick(sample, i),
            "fft_and_loss": pick(fft, i), "fft_and_loss_before": pick(old_fft, i)})
    };
    Ok(json!({
        "grid": "32^3", "problem": "gyroid-1d", "threads": 1,
        "ms_per_eval": whole.0, "cpu_ms_per_eval": whole.1,
        "split_ms": split(0), "split_cpu_ms": split(1),
        "fft_and_loss_before_over_now_cpu": old_fft.1 / fft.1,
        "fft_and_loss_before_over_now_wall": old_fft.0 / fft.0,
        "loss_now": new_loss, "loss_before": old_loss,
        "sampling_pointwise_ms": pointwise.0,
        "sampling_lattice_over_pointwise": sample.0 / pointwise.0,
        "goal_ms_per_eval": GOAL_MS_PER_EVAL,
        "pycma_numpy_ms_per_eval": PYCMA_MS_PER_EVAL,
        "ratio_to_pycma_numpy": whole.0 / PYCMA_MS_PER_EVAL,
        "loadavg_1m": loadavg(),
        "note": "ms: wall clock, median of 5 batches; cpu_ms: this thread's time on a core \
            (/proc/thread-self/schedstat), which a loaded machine does not inflate. \
            ms_per_eval: the job's own evaluation (scene, lattice samples into the reused \
            buffer, FFT, loss); the split times each part alone (sampling into a fresh buffer). \
            fft_and_loss_before: the previous FFT (realfft/rustfft, four-step) and per-bin loop \
            (libm atan2) on the same samples, kept in this bench for the comparison",
    }))
}

/// This thread's time on a core so far, in ns (Linux; None elsewhere).
fn thread_cpu_ns() -> Option<u64> {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()?
        .split_whitespace()
        .next()?
        .parse()
        .ok()
}

/// Milliseconds per call of `f`: wall clock and this thread's CPU time
/// (medians of 5 batches of `n`).
fn timed(n: usize, mut f: impl FnMut()) -> (f64, f64) {
    let (mut wall, mut cpu) = (vec![], vec![]);
    for _ in 0..5 {
        let (t, c) = (Instant::now(), thread_cpu_ns());
        for _ in 0..n {
            f();
        }
        wall.push(t.elapsed().as_secs_f64() * 1e3 / n as f64);
        let c = thread_cpu_ns()
            .zip(c)
            .map_or(f64::NAN, |(b, a)| (b - a) as f64 * 1e-6);
        cpu.push(c / n as f64);
    }
    (super::min_median(wall).1, super::min_median(cpu).1)
}

/// Milliseconds per call of `f` (median of 5 batches of `n`).
fn ms_per(n: usize, f: impl FnMut()) -> f64 {
    timed(n, f).0
}

/// (c) Table 3: reconstruction per problem × optimiser × seed; `quick`:
/// gyroid 1D and spheres 2D, one seed, budget 300.
pub fn table3(quick: bool, seeds: u64, threads: usize) -> Result<Value, String> {
    if quick {
        table3_of(&["gyroid-1d", "spheres-2d"], 300, false, 1, threads)
    } else {
        table3_of(&[], 1500, true, seeds.max(1), threads)
    }
}

/// [`table3`] for the problems named in `only` (all when empty), each fit
/// within `budget` evaluations (coarse to fine with its own larger budget
/// when `c2f_budgets`), over seeds `1..=seeds`.
fn table3_of(
    only: &[&str],
    budget: u32,
    c2f_budgets: bool,
    seeds: u64,
    threads: usize,
) -> Result<Value, String> {
    use filigree::micro::fit::{fourier_loss, Fourier};
    // What one loss evaluation costs at 32³, split in its two parts.
    let n = 32;
    let vals: Vec<f64> = (0..n * n * n).map(|i| libm::sin(i as f64 * 0.37)).collect();
    let mut fourier = Fourier::new([n, n, n]).map_err(|e| e.to_string())?;
    let target = fourier.spectrum(&vals).map_err(|e| e.to_string())?;
    let whole_ms = ms_per(50, || {
        let s = fourier.spectrum(&vals).expect("spectrum");
        std::hint::black_box(fourier_loss(&s, &target));
    });
    let half_target = fourier.half_spectrum(&vals).map_err(|e| e.to_string())?;
    let fft_ms = ms_per(50, || {
        let s = fourier.half_spectrum(&vals).expect("spectrum");
        std::hint::black_box(fourier_loss(&s, &half_target));
    });
    let gyroid = filigree::micro::parse(&gyroid_terms(100.0, 100.0, 100.0, 1.0, 0.0))
        .map_err(|e| e.to_string())?;
    let sample_ms = ms_per(20, || {
        let mut s = 0.0;
        for i in 0..n * n * n {
            let p = [(i % n) as f64, ((i / n) % n) as f64, (i / n / n) as f64];
            s += gyroid.eval_array([p[0] * 0.008, p[1] * 0.008, p[2] * 0.008]);
        }
        std::hint::black_box(s);
    });
    let mut rows = vec![];
    for (name, start, target, params, truth, c, half) in problems() {
        if !only.is_empty() && !only.contains(&name) {
            continue;
        }
        let paper = TABLE3.iter().find(|r| r.0 == name).map(|r| r.1);
        let paper: Value = PAPER_COLUMNS
            .iter()
            .zip(paper.unwrap_or([None; 5]))
            .map(|(k, cell)| {
                (
                    k.to_string(),
                    cell.map_or(json!("N/A"), |(e, t)| json!({"val_error": e, "time": t})),
                )
            })
            .collect::<serde_json::Map<_, _>>()
            .into();
        let mut by_opt = vec![];
        // Each optimiser on the paper's loss alone, then (but for spheres,
        // whose fits take a minute each) coarse to fine, with a larger
        // budget for gyroid 3D and 5D.
        let c2f: &[bool] = if name == "spheres-2d" {
            &[false]
        } else {
            &[false, true]
        };
        let combos = c2f.iter().flat_map(|&c| {
            [Optimizer::Cmaes, Optimizer::NelderMead, Optimizer::Powell].map(|o| (o, c))
        });
        for (opt, coarse_to_fine) in combos {
            let budget = if coarse_to_fine && c2f_budgets {
                c2f_budget(name)
            } else {
                budget
            };
            let mut runs = vec![];
            for seed in 1..=seeds {
                let req = MicroFitRequest {
                    scene: start.clone(),
                    params: params.clone(),
                    target: FitTarget::Scene {
                        scene: target.clone(),
                    },
                    grid: 32,
                    center: [c; 3],
                    half,
                    optimizer: opt,
                    budget,
                    population: 20,
                    sigma: 0.3,
                    seed,
                    coarse_to_fine,
                    ..Default::default()
                };
                let t = Instant::now();
                let jobs = (0..threads)
                    .map(|k| {
                        start_fit(MicroFitRequest {
                            shards: Some((k, threads)),
                            ..req.clone()
                        })
                        .map_err(|e| format!("{name}: {e}"))
                    })
                    .collect::<Result<Vec<_>, _>>()?;
                let out = run_sharded_threads(jobs, &Cancel::new(), |_, _| {})
                    .map_err(|e| format!("{name}: {e}"))?;
                let secs = t.elapsed().as_secs_f64();
                let rel: Vec<f64> = out
                    .values
                    .iter()
                    .zip(&truth)
                    .map(|(v, t)| ((v - t) / t).abs())
                    .collect();
                runs.push(json!({
                    "seed": seed, "validation": out.validation, "loss": out.loss,
                    "initial_loss": out.initial_loss, "evaluations": out.evaluations,
                    "seconds": secs, "ms_per_eval": secs * 1e3 / out.evaluations.max(1) as f64,
                    "values": out.values, "relative_error": rel,
                }));
            }
            let med = |key: &str| {
                let v: Vec<f64> = runs.iter().filter_map(|r| r[key].as_f64()).collect();
                (!v.is_empty()).then(|| super::min_median(v).1)
            };
            // Per run, the largest relative error of a parameter; median.
            let worst: Vec<f64> = runs
                .iter()
                .filter_map(|r| {
                    let a = r["relative_error"].as_array()?;
                    Some(a.iter().filter_map(Value::as_f64).fold(0.0, f64::max))
                })
                .collect();
            let worst_rel = (!worst.is_empty()).then(|| super::min_median(worst).1);
            by_opt.push(json!({
                "optimizer": opt, "coarse_to_fine": coarse_to_fine, "budget": budget,
                "median_validation": med("validation"),
                "median_seconds": med("seconds"), "median_ms_per_eval": med("ms_per_eval"),
                "median_evaluations": med("evaluations"),
                "median_relative_error_max": worst_rel,
                "runs": runs,
            }));
        }
        let reference = (name == "gyroid-1d").then(|| {
            json!({"what": "pycma + NumPy FFT, 32^3 (issue 12)", "ms_per_eval": PYCMA_MS_PER_EVAL,
                "seconds": PYCMA_GYROID_1D_SECONDS, "val_error": 0.0})
        });
        rows.push(json!({
            "problem": name, "truth": truth, "reference": reference,
            "start": params.iter().map(|p| p.pointer.clone()).collect::<Vec<_>>(),
            "ours": by_opt, "paper": paper,
        }));
    }
    Ok(json!({
        "grid": "32^3", "budget": budget, "seeds": seeds, "threads": threads,
        "loss_eval_ms_32": {"fft_and_loss": fft_ms, "fft_and_loss_whole_spectrum": whole_ms,
            "whole_over_half": whole_ms / fft_ms, "sampling_gyroid": sample_ms,
            "goal_per_eval": GOAL_MS_PER_EVAL, "pycma_numpy_reference": PYCMA_MS_PER_EVAL},
        "validation_note": "MSE of the fitted field against the target on a grid shifted by \
            half a cell, over the target's variance (paper: 'Val. Error'); paper columns are \
            SciPy/pycma on their machine with a ~20 min limit; -S columns fit rendered images",
        "rows": rows,
    }))
}

/// The loss of one evaluation as it was before the lane FFT (session 8):
/// the 3-D real FFT over realfft/rustfft (kernels ≤ 32, four-step split)
/// and the per-bin loop with libm's atan2, kept here only so `bench micro
/// --only loss` can time old and new in the same run. Same results up to
/// rounding (`old_over_new_loss_difference`).
mod legacy {
    #![allow(dead_code)]
    use realfft::num_complex::Complex;
    use realfft::{RealFftPlanner, RealToComplex};
    use rustfft::{Fft, FftPlanner};
    use std::sync::Arc;
    type C64 = Complex<f64>;
    type Result<T> = std::result::Result<T, String>;
    const LEAF: usize = 32;
    const MAX_FFT_SIDE: usize = 4096;

    /// A complex FFT of one power-of-two length and direction.
    enum Plan {
        /// rustfft's butterfly (length ≤ [`LEAF`]).
        Leaf(Arc<dyn Fft<f64>>),
        /// Four-step: `n = n1 · n2` with `n1 = LEAF`: `n2` transforms of
        /// length `n1` on the transposed input, twiddles `W_n^(j2·k1)`, then
        /// `n1` transforms of length `n2`, then a transpose.
        Split {
            n1: usize,
            n2: usize,
            first: Arc<dyn Fft<f64>>,
            second: Box<Plan>,
            twiddles: Vec<C64>,
        },
    }

    impl Plan {
        fn new(n: usize, inverse: bool, planner: &mut FftPlanner<f64>) -> Plan {
            let leaf = |len: usize, planner: &mut FftPlanner<f64>| {
                if inverse {
                    planner.plan_fft_inverse(len)
                } else {
                    planner.plan_fft_forward(len)
                }
            };
            if n <= LEAF {
                return Plan::Leaf(leaf(n, planner));
            }
            let (n1, n2) = (LEAF, n / LEAF);
            let sign = if inverse { 1.0 } else { -1.0 };
            let mut twiddles = Vec::with_capacity(n);
            for j2 in 0..n2 {
                for k1 in 0..n1 {
                    let a = sign * std::f64::consts::TAU * ((j2 * k1) % n) as f64 / n as f64;
                    twiddles.push(C64::new(libm::cos(a), libm::sin(a)));
                }
            }
            Plan::Split {
                n1,
                n2,
                first: leaf(n1, planner),
                second: Box::new(Plan::new(n2, inverse, planner)),
                twiddles,
            }
        }

        /// Transform `buf` in place: consecutive transforms of this length.
        /// `tmp` is resized as needed.
        fn process(&self, buf: &mut [C64], tmp: &mut Vec<C64>) {
            match self {
                Plan::Leaf(f) => {
                    let need = f.get_inplace_scratch_len();
                    if tmp.len() < need {
                        tmp.resize(need, C64::default());
                    }
                    f.process_with_scratch(buf, &mut tmp[..need]);
                }
                Plan::Split {
                    n1,
                    n2,
                    first,
                    second,
                    twiddles,
                } => {
                    let (n1, n2) = (*n1, *n2);
                    let n = n1 * n2;
                    let mut t = vec![C64::default(); n];
                    for x in buf.chunks_exact_mut(n) {
                        // t[j2·n1 + j1] = x[j1·n2 + j2]
                        for j1 in 0..n1 {
                            for j2 in 0..n2 {
                                t[j2 * n1 + j1] = x[j1 * n2 + j2];
                            }
                        }
                        first.process(&mut t);
                        for (v, w) in t.iter_mut().zip(twiddles) {
                            *v *= w;
                        }
                        // x[k1·n2 + j2] = t[j2·n1 + k1]
                        for j2 in 0..n2 {
                            for k1 in 0..n1 {
                                x[k1 * n2 + j2] = t[j2 * n1 + k1];
                            }
                        }
                        second.process(x, tmp);
                        // X[k1 + n1·k2] = x[k1·n2 + k2]
                        t.copy_from_slice(x);
                        for k1 in 0..n1 {
                            for k2 in 0..n2 {
                                x[k1 + n1 * k2] = t[k1 * n2 + k2];
                            }
                        }
                    }
                }
            }
        }
    }

    /// A forward 3-D FFT of real `nx × ny × nz` volumes (x fastest) giving the
    /// coefficients with `kx ≤ nx/2` (the others are their complex conjugates:
    /// `X[kx, ky, kz] = conj X[nx − kx, −ky, −kz]`). Plans, scratch and the
    /// output are kept between calls: a fit's thousands of transforms
    /// allocate nothing.
    struct RealFft3 {
        dims: [usize; 3],
        half: usize,
        r2c: Option<Arc<dyn RealToComplex<f64>>>,
        /// x when longer than [`LEAF`]: a complex transform of the real row.
        fx: Option<Plan>,
        fy: Option<Plan>,
        fz: Option<Plan>,
        row: Vec<f64>,
        crow: Vec<C64>,
        scratch: Vec<C64>,
        lines: Vec<C64>,
        out: Vec<C64>,
    }

    impl RealFft3 {
        /// A transform of `dims` volumes: each side a power of two up to
        /// [`MAX_FFT_SIDE`] (1 allowed), at least two values in all.
        fn new(dims: [usize; 3]) -> Result<RealFft3> {
            if dims.iter().product::<usize>() < 2 {
                return Err(std::convert::identity(format!(
                    "an FFT needs sides that are powers of two up to {MAX_FFT_SIDE} \
                 (got {}×{}×{})",
                    dims[0], dims[1], dims[2]
                )));
            }
            let [nx, ny, nz] = dims;
            let half = if nx > 1 { nx / 2 + 1 } else { 1 };
            let r2c =
                (nx > 1 && nx <= LEAF).then(|| RealFftPlanner::<f64>::new().plan_fft_forward(nx));
            let mut planner = FftPlanner::<f64>::new();
            let fx = (nx > LEAF).then(|| Plan::new(nx, false, &mut planner));
            let fy = (ny > 1).then(|| Plan::new(ny, false, &mut planner));
            let fz = (nz > 1).then(|| Plan::new(nz, false, &mut planner));
            let scratch_len = r2c.as_ref().map_or(0, |p| p.get_scratch_len());
            Ok(RealFft3 {
                dims,
                half,
                r2c,
                fx,
                fy,
                fz,
                row: vec![0.0; nx],
                crow: vec![C64::default(); nx],
                scratch: vec![C64::default(); scratch_len],
                lines: vec![C64::default(); half * ny.max(nz)],
                out: vec![C64::default(); half * ny * nz],
            })
        }

        /// The shape this transform takes.
        fn dims(&self) -> [usize; 3] {
            self.dims
        }

        /// Coefficients kept along x: `nx/2 + 1` (1 for a flat x).
        fn half(&self) -> usize {
            self.half
        }

        /// The half spectrum of `values` (`nx·ny·nz` of them, x fastest), laid
        /// out as `kx + half·(ky + ny·kz)`.
        fn forward(&mut self, values: &[f64]) -> Result<&[C64]> {
            let [nx, ny, nz] = self.dims;
            if values.len() != nx * ny * nz {
                return Err(std::convert::identity(format!(
                    "a {nx}×{ny}×{nz} transform needs {} values (got {})",
                    nx * ny * nz,
                    values.len()
                )));
            }
            let h = self.half;
            // x: one real-to-complex transform per row.
            match &self.r2c {
                Some(r2c) => {
                    for (src, dst) in values.chunks_exact(nx).zip(self.out.chunks_exact_mut(h)) {
                        self.row.copy_from_slice(src);
                        let need = r2c.get_scratch_len();
                        if self.scratch.len() < need {
                            self.scratch.resize(need, C64::default());
                        }
                        r2c.process_with_scratch(&mut self.row, dst, &mut self.scratch[..need])
                            .map_err(|e| std::convert::identity(format!("FFT: {e}")))?;
                    }
                }
                None => match &self.fx {
                    Some(fx) => {
                        for (src, dst) in values.chunks_exact(nx).zip(self.out.chunks_exact_mut(h))
                        {
                            for (c, &v) in self.crow.iter_mut().zip(src) {
                                *c = C64::new(v, 0.0);
                            }
                            fx.process(&mut self.crow, &mut self.scratch);
                            dst.copy_from_slice(&self.crow[..h]);
                        }
                    }
                    None => {
                        for (d, &v) in self.out.iter_mut().zip(values) {
                            *d = C64::new(v, 0.0);
                        }
                    }
                },
            }
            // y: per z plane, gather the h lines (kx fixed) contiguously.
            if let Some(fy) = &self.fy {
                let lines = &mut self.lines[..h * ny];
                for plane in self.out.chunks_exact_mut(h * ny) {
                    for y in 0..ny {
                        for kx in 0..h {
                            lines[kx * ny + y] = plane[kx + h * y];
                        }
                    }
                    fy.process(lines, &mut self.scratch);
                    for y in 0..ny {
                        for kx in 0..h {
                            plane[kx + h * y] = lines[kx * ny + y];
                        }
                    }
                }
            }
            // z: per y row, gather the h lines along z.
            if let Some(fz) = &self.fz {
                let lines = &mut self.lines[..h * nz];
                let plane = h * ny;
                for y in 0..ny {
                    for z in 0..nz {
                        let base = z * plane + y * h;
                        for kx in 0..h {
                            lines[kx * nz + z] = self.out[base + kx];
                        }
                    }
                    fz.process(lines, &mut self.scratch);
                    for z in 0..nz {
                        let base = z * plane + y * h;
                        for kx in 0..h {
                            self.out[base + kx] = lines[kx * nz + z];
                        }
                    }
                }
            }
            Ok(&self.out)
        }
    }

    /// The old `Fourier::half_loss` (libm atan2, a modulo per bin).
    pub struct OldLoss {
        fft: RealFft3,
        amp: Vec<f64>,
        target_amp: Vec<f64>,
        target_phase: Vec<f64>,
    }

    fn phase_of(c: C64, a: f64, floor: f64) -> f64 {
        if a > floor {
            libm::atan2(c.im, c.re)
        } else {
            0.0
        }
    }

    fn weight_of(kx: usize, nx: usize) -> f64 {
        if kx == 0 || 2 * kx == nx {
            1.0
        } else {
            2.0
        }
    }

    impl OldLoss {
        pub fn new(n: usize, target: &[f64]) -> Result<OldLoss> {
            let mut fft = RealFft3::new([n, n, n])?;
            let data = fft.forward(target)?.to_vec();
            let amp: Vec<f64> = data.iter().map(|c| c.norm_sqr().sqrt()).collect();
            let floor = amp.iter().copied().fold(0.0, f64::max) * 1e-9;
            let phase = data
                .iter()
                .zip(&amp)
                .map(|(c, &a)| phase_of(*c, a, floor))
                .collect();
            Ok(OldLoss {
                fft,
                amp: vec![0.0; amp.len()],
                target_amp: amp,
                target_phase: phase,
            })
        }

        pub fn loss(&mut self, values: &[f64]) -> Result<f64> {
            let nx = self.fft.dims[0];
            let h = self.fft.half;
            let data = self.fft.forward(values)?;
            let mut max = 0.0f64;
            for (a, c) in self.amp.iter_mut().zip(data) {
                *a = c.norm_sqr().sqrt();
                max = max.max(*a);
            }
            let floor = max * 1e-9;
            let (mut s, mut count) = (0.0, 0.0);
            for (i, (c, &a)) in data.iter().zip(&self.amp).enumerate() {
                let da = a - self.target_amp[i];
                let dp = phase_of(*c, a, floor) - self.target_phase[i];
                let w = weight_of(i % h, nx);
                s += w * (da * da + dp * dp);
                count += w;
            }
            Ok(libm::log(s / (2.0 * f64::max(count, 1.0)) + 1e-12))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast check of `bench micro`'s Table 3 (the table itself, a
    /// minute even with `--quick`, is the benchmark's): for one problem on a
    /// tiny budget, a row per optimiser with and without coarse to fine,
    /// each within its budget, beside the paper's cells.
    #[test]
    fn table_3_has_a_row_per_optimiser_within_its_budget() {
        let t = table3_of(&["gyroid-1d"], 30, false, 1, 1).unwrap();
        assert_eq!(t["grid"], "32^3");
        let rows = t["rows"].as_array().unwrap();
        assert_eq!(rows.len(), 1);
        assert_eq!(rows[0]["problem"], "gyroid-1d");
        assert!(rows[0]["paper"]["CMA-ES-SDF"].is_object());
        let ours = rows[0]["ours"].as_array().unwrap();
        let kinds: Vec<(String, bool)> = ours
            .iter()
            .map(|o| {
                (
                    o["optimizer"].as_str().unwrap().to_string(),
                    o["coarse_to_fine"].as_bool().unwrap(),
                )
            })
            .collect();
        assert_eq!(kinds.len(), 6, "{kinds:?}");
        for c2f in [false, true] {
            for opt in ["cmaes", "nelder-mead", "powell"] {
                assert!(
                    kinds.contains(&(opt.to_string(), c2f)),
                    "{opt} {c2f}: {kinds:?}"
                );
            }
        }
        for o in ours {
            assert_eq!(o["budget"], 30);
            let evals = o["median_evaluations"].as_f64().unwrap();
            assert!(evals > 0.0 && evals <= 30.0, "{o}");
            assert!(o["median_validation"].as_f64().unwrap().is_finite());
            assert_eq!(o["runs"].as_array().unwrap().len(), 1);
        }
    }
}
