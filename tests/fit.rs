//! Integration tests of the Fit tool (pattern programs → fields → loss →
//! optimiser), through the public API only. Small grids and budgets keep
//! them fast in debug builds.
use filigree::core::job::{run_quietly, run_to_end, Cancel, Job, Step};
use filigree::core::rng::Rng;
use filigree::pattern::field::{Evaluator, Scene};
use filigree::pattern::fit::{colour_indices, Budget, FitJob, FitOptions, TargetSource};
use filigree::pattern::generators::{generator, GENERATORS};
use filigree::pattern::loss::{LossKind, LossOptions, Objective};
use filigree::pattern::optim::{GaOptions, InitMethod};
use filigree::pattern::record::{Program, RecordLimits};
use filigree::pattern::render;
use filigree::pattern::target::Target;
use filigree::raster::{decode, encode_png, Limits};
use filigree::Error;

fn program(name: &str) -> Program {
    Program::parse(generator(name).expect("generator").source).expect("parses")
}

fn small_opts(seed: u64) -> FitOptions {
    let mut o = FitOptions::budget(Budget::Quick);
    o.loss.grid = 48;
    o.ga = GaOptions {
        population: 40,
        generations: 6,
        ..GaOptions::default()
    };
    o.candidates = 2;
    o.iterations = 80;
    o.seed = seed;
    o
}

fn float_index(p: &Program, name: &str) -> usize {
    p.params()
        .iter()
        .filter(|d| !d.integer)
        .position(|d| d.name == name)
        .expect("param")
}

/// The fit finds the known parameters of a synthetic circles-grid target.
#[test]
fn fit_recovers_known_parameters_of_circles_grid() {
    let p = program("circles-grid");
    let truth = [0.19, 0.15, 0.09, 0.14, 0.045]; // dx, dy, ox, oy, r
    let job = FitJob::new(
        &p,
        &p.defaults(),
        &TargetSource::Params(&truth),
        small_opts(3),
    )
    .unwrap();
    let r = run_quietly(job).unwrap();
    let decls: Vec<_> = p.params().iter().filter(|d| !d.integer).collect();
    for (k, d) in decls.iter().enumerate() {
        let err = (r.params[k] - truth[k]).abs() / (d.hi - d.lo);
        assert!(
            err < 0.04,
            "{}: fitted {} vs true {} (normalised error {err})",
            d.name,
            r.params[k],
            truth[k]
        );
    }
    assert!(
        r.loss <= r.init_loss,
        "Adam made things worse: {} > {}",
        r.loss,
        r.init_loss
    );
    assert!(
        r.history.windows(2).all(|w| w[1] <= w[0]),
        "best-so-far history must not increase"
    );
}

/// Polishing with the image-space loss keeps the fit and lowers the
/// parameter error on a stroked pattern (fills inset under strokes).
#[test]
fn polish_with_the_image_loss() {
    let p = program("shingles");
    let truth = [0.2, 0.21, 0.04, 0.06, 0.11, 0.012];
    let err = |x: &[f64]| -> f64 {
        let d: Vec<_> = p.params().iter().filter(|d| !d.integer).collect();
        x.iter()
            .zip(&truth)
            .zip(&d)
            .map(|((a, b), d)| ((a - b) / (d.hi - d.lo)).powi(2))
            .sum::<f64>()
            / x.len() as f64
    };
    let plain = run_quietly(
        FitJob::new(
            &p,
            &p.defaults(),
            &TargetSource::Params(&truth),
            small_opts(2),
        )
        .unwrap(),
    )
    .unwrap();
    let mut o = small_opts(2);
    o.polish = 80;
    let pol =
        run_quietly(FitJob::new(&p, &p.defaults(), &TargetSource::Params(&truth), o).unwrap())
            .unwrap();
    assert!(plain.polish_loss.is_none() && pol.polish_loss.is_some());
    assert_eq!(
        plain.start_points, pol.start_points,
        "the polish starts where the plain fit ended"
    );
    assert!(
        err(&pol.params) <= err(&plain.params),
        "{} > {}",
        err(&pol.params),
        err(&plain.params)
    );
    assert!(err(&pol.params) < 2e-3, "{}", err(&pol.params));
}

/// A fit from an image file (PNG round trip, palette snapping) lands where
/// a fit from the parameters does.
#[test]
fn fit_from_a_png_target() {
    let p = program("circles-grid");
    let truth = [0.16, 0.2, 0.12, 0.08, 0.05];
    let rec = p.record(&p.defaults(), &RecordLimits::default()).unwrap();
    let scene = Scene::new(rec);
    let img = render::render(&scene, &truth, 96, 2).unwrap(); // anti-aliased edges
    let png = encode_png(&img).unwrap();
    let img = decode(&png, Limits::default()).unwrap();
    let r = run_quietly(
        FitJob::new(
            &p,
            &p.defaults(),
            &TargetSource::Image(&img, 60.0),
            small_opts(5),
        )
        .unwrap(),
    )
    .unwrap();
    let k = float_index(&p, "r");
    assert!((r.params[k] - 0.05).abs() < 0.004, "radius {}", r.params[k]);
    let k = float_index(&p, "dx");
    assert!((r.params[k] - 0.16).abs() < 0.006, "dx {}", r.params[k]);
}

#[test]
fn a_target_in_foreign_colours_is_rejected_with_the_palette_named() {
    let p = program("circles-grid");
    let mut img = filigree::raster::Rgba8Image::new(32, 32);
    for y in 0..32 {
        for x in 0..32 {
            img.put(x, y, [0, 200, 0, 255]);
        }
    }
    let e = FitJob::new(
        &p,
        &p.defaults(),
        &TargetSource::Image(&img, 30.0),
        small_opts(1),
    )
    .err()
    .expect("must fail");
    let m = e.to_string();
    assert!(
        m.contains("#1f4e79") && m.contains("#ffffff") && m.contains("tolerance"),
        "{m}"
    );
}

/// Same seed, same result; another seed, another path.
#[test]
fn fits_are_deterministic_by_seed() {
    let p = program("stripes-dots");
    let truth: Vec<f64> = p
        .params()
        .iter()
        .map(|d| d.lo + 0.4 * (d.hi - d.lo))
        .collect();
    let mut o = small_opts(7);
    o.iterations = 20;
    o.ga.generations = 2;
    let run = |o: FitOptions| {
        run_quietly(FitJob::new(&p, &p.defaults(), &TargetSource::Params(&truth), o).unwrap())
            .unwrap()
    };
    let a = run(o);
    let b = run(o);
    assert_eq!(a, b);
    let mut o2 = o;
    o2.seed = 8;
    let c = run(o2);
    assert_ne!(a.history, c.history);
    // Shards on threads change nothing but speed.
    let mut o3 = o;
    let jobs: Vec<_> = (0..3)
        .map(|k| {
            o3.shards = (k, 3);
            FitJob::new(&p, &p.defaults(), &TargetSource::Params(&truth), o3).unwrap()
        })
        .collect();
    let sharded =
        filigree::core::parallel::run_sharded_threads(jobs, &Cancel::new(), |_, _| {}).unwrap();
    assert_eq!(sharded, a);
}

#[test]
fn every_initialiser_runs_and_the_job_can_be_cancelled() {
    let p = program("circles-grid");
    let truth = [0.19, 0.15, 0.09, 0.14, 0.045];
    for init in [
        InitMethod::Genetic,
        InitMethod::Random,
        InitMethod::NelderMead,
    ] {
        let mut o = small_opts(2);
        o.init = init;
        o.iterations = 10;
        let r =
            run_quietly(FitJob::new(&p, &p.defaults(), &TargetSource::Params(&truth), o).unwrap())
                .unwrap();
        assert!(
            r.loss.is_finite() && r.loss < r.history[0] + 1e-12,
            "{init:?}"
        );
    }
    let cancel = Cancel::new();
    let mut steps = 0;
    let job = FitJob::new(
        &p,
        &p.defaults(),
        &TargetSource::Params(&truth),
        small_opts(2),
    )
    .unwrap();
    let res = run_to_end(job, &cancel, |prog| {
        steps += 1;
        assert!(prog.fraction <= 1.0 && prog.figure.is_some());
        if steps == 3 {
            cancel.cancel();
        }
    });
    assert_eq!(res, Err(Error::Cancelled));
    // Progress is monotone and steps are bounded.
    let mut job = FitJob::new(
        &p,
        &p.defaults(),
        &TargetSource::Params(&truth),
        small_opts(2),
    )
    .unwrap();
    let mut last = 0.0;
    while let Step::Running(pr) = job.step().unwrap() {
        assert!(pr.fraction >= last, "{} < {last}", pr.fraction);
        last = pr.fraction;
    }
}

/// Exact gradients of the full pipeline (program → tape → fields → loss)
/// against central differences, for shipped generators with strokes, fills,
/// rectangles, Bézier paths and the on-top operator.
#[test]
fn pipeline_gradients_match_central_differences() {
    for name in [
        "stripes-dots",
        "shingles",
        "spades",
        "rectangles",
        "circles-mix",
    ] {
        let p = program(name);
        let rec = p.record(&p.defaults(), &RecordLimits::default()).unwrap();
        let scene = Scene::new(rec);
        let decls: Vec<_> = scene.rec.float_decls().into_iter().cloned().collect();
        let truth: Vec<f64> = decls.iter().map(|d| d.lo + 0.6 * (d.hi - d.lo)).collect();
        // An irregular point: round fractions can put pixel centres exactly
        // between two shapes, a kink where one-sided derivatives differ.
        let x: Vec<f64> = decls
            .iter()
            .map(|d| d.lo + 0.4371 * (d.hi - d.lo))
            .collect();
        let opts = LossOptions {
            grid: 40,
            ..LossOptions::default()
        };
        let idx = colour_indices(&scene, &truth, opts.grid).unwrap();
        let t = Target::from_indices(&scene, &idx, opts.grid, opts.scale());
        let mut obj = Objective::new(scene, t, opts);
        let mut g = vec![0.0; x.len()];
        obj.loss_grad(&x, &mut g);
        for k in 0..x.len() {
            let h = 1e-7 * (decls[k].hi - decls[k].lo);
            let (mut a, mut b) = (x.clone(), x.clone());
            a[k] += h;
            b[k] -= h;
            let fd = (obj.loss(&a) - obj.loss(&b)) / (2.0 * h);
            let tol = 2e-3 * (1.0 + fd.abs().max(g[k].abs()));
            assert!(
                (fd - g[k]).abs() < tol,
                "{name} / {}: fd {fd} vs analytic {}",
                decls[k].name,
                g[k]
            );
        }
    }
}

/// The pattern fields of every shipped generator agree in sign with a
/// brute-force painter's-algorithm raster (point-in-shape by drawing order)
/// and the loss at the truth is far below the loss elsewhere.
#[test]
fn generators_render_and_the_truth_is_a_minimum() {
    let mut rng = Rng::new(4);
    for g in GENERATORS {
        let p = Program::parse(g.source).unwrap();
        let rec = p.record(&p.defaults(), &RecordLimits::default()).unwrap();
        let scene = Scene::new(rec);
        let decls = scene.rec.float_decls();
        let truth: Vec<f64> = decls
            .iter()
            .map(|d| d.lo + (d.hi - d.lo) * rng.range_f64(0.2, 0.8))
            .collect();
        let other: Vec<f64> = decls
            .iter()
            .map(|d| d.lo + (d.hi - d.lo) * rng.range_f64(0.2, 0.8))
            .collect();
        let opts = LossOptions {
            grid: 48,
            kind: LossKind::Sdf,
            ..LossOptions::default()
        };
        let idx = colour_indices(&scene, &truth, 48).unwrap();
        let t = Target::from_indices(&scene, &idx, 48, opts.scale());
        let mut obj = Objective::new(scene.clone(), t, opts);
        let at = obj.loss(&truth);
        let off = obj.loss(&other);
        assert!(
            at * 3.0 < off,
            "{}: loss at truth {at} vs elsewhere {off}",
            g.name
        );
        let svg = render::svg(&scene, &truth, 256.0).unwrap();
        assert!(
            svg.starts_with("<svg") && svg.trim_end().ends_with("</svg>"),
            "{}",
            g.name
        );
        let mut ev = Evaluator::new(16, 1.0);
        let mut nodes = vec![];
        scene.rec.tape.forward(&truth, &mut nodes);
        ev.eval(&scene, &nodes, false);
        assert_eq!(ev.s.len(), scene.channels.len() * 256);
    }
}

#[test]
fn program_errors_are_clear_and_located() {
    let e = Program::parse("param a in [0, 1] = 0.5;\ncircle(0.5, 0.5 0.1);").unwrap_err();
    assert_eq!(
        e,
        Error::Syntax {
            line: 2,
            column: 17,
            message: "expected ',' but found number 0.1".into()
        }
    );
    let p = Program::parse("int param n in [1, 3] = 2;\nlet k = 0;\nfor i in 0..n {\n  for j in 0..1e15 { k = k + 1; }\n}").unwrap();
    let e = p
        .record(&p.defaults(), &RecordLimits::default())
        .unwrap_err();
    assert!(matches!(e, Error::Limit(_)), "{e:?}");
    assert!(e.to_string().starts_with("line 4, column"), "{e}");
    let p = Program::parse("param a in [0, 1] = 0.5;\nwhile_not_a_thing(a);").unwrap();
    let e = p
        .record(&p.defaults(), &RecordLimits::default())
        .unwrap_err();
    assert_eq!(
        e,
        Error::Syntax {
            line: 2,
            column: 1,
            message: "unknown function 'while_not_a_thing'".into()
        }
    );
    let e = Program::parse("fn circle(x) { }").unwrap_err();
    assert!(e.to_string().contains("built-in"), "{e}");
    let p =
        Program::parse("param a in [0, 1] = 0.5;\ncircle(0.5, 0.5, 0.1, fill: \"#000\");").unwrap();
    let e = p.record(&[0.5, 2.0], &RecordLimits::default()).unwrap_err();
    assert!(e.to_string().contains("declares 1 parameters but 2"), "{e}");
    let p = Program::parse("int param n in [1, 3] = 2;\ncircle(0.5, 0.5, 0.1);").unwrap();
    let e = FitJob::new(&p, &p.defaults(), &TargetSource::Params(&[]), small_opts(1))
        .err()
        .unwrap();
    assert!(e.to_string().contains("no float parameters"), "{e}");
    let tiny = RecordLimits {
        max_shapes: 3,
        ..RecordLimits::default()
    };
    let p = Program::parse("for i in 0..10 { circle(0.5, 0.5, 0.1); }").unwrap();
    let e = p.record(&[], &tiny).unwrap_err();
    assert!(e.to_string().contains("more than 3 shapes"), "{e}");
}

/// The CLI: render to PNG and SVG, fit a rendered target, report a bad program.
#[test]
fn cli_render_and_fit() {
    let exe = env!("CARGO_BIN_EXE_filigree");
    let dir = std::env::temp_dir().join(format!("filigree-fit-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let png = dir.join("t.png");
    let svg = dir.join("t.svg");
    let run = |args: &[&str]| std::process::Command::new(exe).args(args).output().unwrap();
    let params = r#"{"dx": 0.2, "r": 0.05}"#;
    let o = run(&[
        "render",
        "--program",
        "circles-grid",
        "--params",
        params,
        "--out",
        png.to_str().unwrap(),
        "--size",
        "64",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let o = run(&[
        "render",
        "--program",
        "circles-grid",
        "--params",
        params,
        "--out",
        svg.to_str().unwrap(),
    ]);
    assert!(o.status.success());
    assert!(std::fs::read_to_string(&svg).unwrap().contains("<circle"));
    let o = run(&[
        "fit",
        "--program",
        "circles-grid",
        "--target",
        png.to_str().unwrap(),
        "--budget",
        "quick",
        "--grid",
        "32",
        "--json",
        "--seed",
        "4",
        "--threads",
        "1",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let r = v["params"]["r"].as_f64().unwrap();
    assert!((r - 0.05).abs() < 0.008, "{v}");
    let bad = dir.join("bad.flg");
    std::fs::write(&bad, "param a in [0, 1] = 0.5;\ncircle(a, a a);\n").unwrap();
    let o = run(&[
        "fit",
        "--program",
        bad.to_str().unwrap(),
        "--target",
        png.to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("bad.flg: line 2, column 13: expected ','"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A fit sharded over several jobs, driven natively exactly as the browser's
/// worker pool drives it (the all-gather relay of `core::parallel`), gives
/// every shard the result of one unsharded fit, bit for bit: the shards
/// evaluate parts of every initialisation batch, exchange losses, stay
/// identical, refine contiguous shares of the candidates, share their bests
/// and polish the same point. Both native drivers (one thread, threads) agree.
#[test]
fn a_sharded_fit_equals_one_fit() {
    use filigree::core::parallel::{run_sharded, run_sharded_threads};
    use filigree::pattern::api::{start_fit, FitSettings, TargetSpec};
    use std::collections::BTreeMap;
    let src = generator("stripes-dots").unwrap().source;
    let named = BTreeMap::new();
    let mut truth = BTreeMap::new();
    truth.insert("spacing".to_string(), 0.15);
    let target = TargetSpec {
        params: Some(truth),
        ..Default::default()
    };
    let base = FitSettings {
        grid: Some(40),
        population: Some(25),
        generations: Some(3),
        candidates: Some(3),
        iterations: Some(30),
        polish: Some(5),
        seed: Some(9),
        ..Default::default()
    };
    let whole = run_quietly(start_fit(src, &named, &target, &base).unwrap().0).unwrap();
    let shards = |n: usize| -> Vec<_> {
        (0..n)
            .map(|k| {
                let s = FitSettings {
                    shards: Some((k, n)),
                    ..base.clone()
                };
                start_fit(src, &named, &target, &s).unwrap().0
            })
            .collect()
    };
    for n in [2, 3, 4] {
        let mut exchanges = vec![0; n];
        let mut seen = vec![0usize; n];
        let one = run_sharded(shards(n), &Cancel::new(), |k, _| seen[k] += 1).unwrap();
        assert_eq!(one, whole, "{n} shards, one thread");
        assert!(seen.iter().all(|&s| s > 0), "every shard reports progress");
        // Count the exchanges a shard takes part in by stepping it by hand.
        let mut jobs = shards(n);
        let mut done = vec![false; n];
        while !done.iter().all(|&d| d) {
            let mut parts = vec![];
            for (k, job) in jobs.iter_mut().enumerate() {
                loop {
                    match job.step().unwrap() {
                        Step::Done(r) => {
                            assert_eq!(r, whole);
                            done[k] = true;
                            break;
                        }
                        Step::Running(_) => {
                            if let Some(p) = job.outbox() {
                                parts.push(p);
                                exchanges[k] += 1;
                                break;
                            }
                        }
                    }
                }
            }
            if !parts.is_empty() {
                assert_eq!(parts.len(), n, "shards exchange in lockstep");
                for job in &mut jobs {
                    job.inbox(parts.clone()).unwrap();
                }
            }
        }
        // One exchange per initialisation batch (the first population and
        // each generation) and one for the bests.
        assert_eq!(exchanges, vec![3 + 1 + 1; n], "{n} shards");
        let threaded = run_sharded_threads(shards(n), &Cancel::new(), |_, _| {}).unwrap();
        assert_eq!(threaded, whole, "{n} shards, threads");
    }
    // The work is split, not repeated: each shard evaluates its share of a batch.
    let mut a = shards(2);
    let mut first = vec![];
    for job in &mut a {
        while first.len() < 2 {
            if let Step::Running(_) = job.step().unwrap() {
                if let Some(p) = job.outbox() {
                    first.push(p);
                    break;
                }
            }
        }
    }
    assert_eq!(
        first[0].len() + first[1].len(),
        25,
        "a population of 25, split"
    );
    // A job refuses input it did not ask for, and a shard cannot run alone.
    let mut lone = start_fit(src, &named, &target, &base).unwrap().0;
    assert!(lone.inbox(vec![vec![1.0]]).is_err());
    let e = run_quietly(shards(2).remove(0)).unwrap_err();
    assert!(e.to_string().contains("run_sharded"), "{e}");
}
