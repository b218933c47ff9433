//! `micro-fit`: reconstruction of scene parameters from a target (paper
//! §6, Table 3) through the same request the browser sends.
use filigree::core::job::{run_quietly, Cancel};
use filigree::core::parallel::run_sharded;
use filigree::micro::fit_api::{
    start_fit, FitParam, FitTarget, MicroFitRequest, MicroFitResponse, Optimizer,
};
use serde_json::json;

/// Gyroid 1D (Eq. 40): `Σᵢ sin(η xᵢ)`, normalised by its gradient bound.
fn gyroid_1d(eta: f64) -> String {
    let t = |axis: &str| json!([{"wave": "sin", "axis": axis, "freq": eta}]);
    json!({"type": "periodic", "terms": [t("x"), t("y"), t("z")]}).to_string()
}

fn eta_param() -> Vec<FitParam> {
    vec![FitParam {
        pointer: "/terms/0/0/freq".into(),
        lo: 10.0,
        hi: 400.0,
        also: vec!["/terms/1/0/freq".into(), "/terms/2/0/freq".into()],
    }]
}

/// The paper's set-up: η = 100 from η = 300 over a box of side 0.25 (four
/// periods), on a 16³ grid here to keep the test quick (the bench uses 32³).
fn gyroid_request(optimizer: Optimizer, budget: u32) -> MicroFitRequest {
    MicroFitRequest {
        scene: gyroid_1d(300.0),
        params: eta_param(),
        target: FitTarget::Scene {
            scene: gyroid_1d(100.0),
        },
        grid: 16,
        center: [0.125; 3],
        half: 0.125,
        optimizer,
        budget,
        population: 40,
        sigma: 0.6,
        seed: 1,
        ..Default::default()
    }
}

fn fit(req: MicroFitRequest) -> MicroFitResponse {
    run_quietly(start_fit(req).expect("a valid request")).expect("a fit")
}

#[test]
fn each_optimizer_recovers_the_gyroid_1d_frequency() {
    let runs: Vec<_> = [Optimizer::Cmaes, Optimizer::NelderMead, Optimizer::Powell]
        .into_iter()
        .map(|opt| (opt, fit(gyroid_request(opt, 800))))
        .collect();
    for (opt, r) in &runs {
        eprintln!(
            "{opt:?}: η = {}, loss {} from {}, {} evaluations, validation {:?}",
            r.values[0], r.loss, r.initial_loss, r.evaluations, r.validation
        );
    }
    for (opt, r) in runs {
        let eta = r.values[0];
        // CMA-ES closes in on the narrow well more slowly than the local
        // methods polish it (the paper's fit.rs unit test allows ±2 too).
        let (tol, val) = match opt {
            Optimizer::Cmaes => (2.0, 0.1),
            _ => (0.01, 1e-6),
        };
        assert!(
            (eta - 100.0).abs() < tol,
            "{opt:?}: η = {eta} after {} evaluations (loss {} from {})",
            r.evaluations,
            r.loss,
            r.initial_loss
        );
        assert!(r.loss < r.initial_loss - 3.0, "{opt:?}");
        assert!(r.evaluations <= 800);
        // The history is the running best, ending at the answer.
        assert!(r.history.windows(2).all(|w| w[1] <= w[0]));
        assert_eq!(r.history.last(), Some(&r.loss));
        assert_eq!(r.history.len(), r.history_evaluations.len());
        assert!(r.validation.unwrap() < val, "{opt:?}: {:?}", r.validation);
        // The fitted scene carries the value at every tied pointer (JSON
        // text: serde_json reads floats back within an ulp).
        let s: serde_json::Value = serde_json::from_str(&r.scene).unwrap();
        for k in 0..3 {
            let v = s["terms"][k][0]["freq"].as_f64().unwrap();
            assert!((v - eta).abs() < 1e-12 * eta, "{v} ≠ {eta}");
        }
    }
}

/// Gyroid [2D]: a sheet gyroid's period and thickness.
#[test]
fn cmaes_fits_two_parameters_of_a_sheet_gyroid() {
    let scene = |period: f64, thickness: f64| {
        json!({"type": "tpms", "surface": "gyroid", "period": period, "thickness": thickness})
            .to_string()
    };
    let r = fit(MicroFitRequest {
        scene: scene(0.7, 0.6),
        params: vec![
            FitParam {
                pointer: "/period".into(),
                lo: 0.35,
                hi: 1.0,
                also: vec![],
            },
            FitParam {
                pointer: "/thickness".into(),
                lo: 0.05,
                hi: 1.0,
                also: vec![],
            },
        ],
        target: FitTarget::Scene {
            scene: scene(0.5, 0.3),
        },
        grid: 32,
        half: 0.5,
        budget: 800,
        ..Default::default()
    });
    let (p, t) = (r.values[0], r.values[1]);
    assert!(
        (p - 0.5).abs() < 0.01 && (t - 0.3).abs() < 0.02,
        "period {p}, thickness {t} (loss {} from {})",
        r.loss,
        r.initial_loss
    );
    assert!(r.validation.unwrap() < 0.01, "{:?}", r.validation);
}

/// `bench micro`'s Gyroid [3D] (Table 3): a sheet gyroid's frequency η
/// (tied along x, y and z), amplitude and thickness, from η = 300, a = 6,
/// t = 0 to η = 100, a = 7, t = 1.2 on the 32³ grid. The paper's loss is
/// a needle in η (its phases match only within about 1 % of the truth):
/// CMA-ES on it alone ends on the plateau for two of these three seeds
/// (validation error about 3; the third finds η and stops at 1.2e-3).
/// Coarse to fine (`coarse_to_fine`: blurred power profiles on the
/// frequency planes, then amplitudes, then the paper's loss) brings every
/// seed below 1e-3 with the same budget (measured: 3.5e-5, 2.2e-5,
/// 2.3e-9), and its reported loss is the paper's loss of its answer.
/// Every seed of both is `filigree bench micro` (Table 3); here, the fast
/// check: seed 2, where the paper's loss alone ends on the plateau
/// (validation 3.04, η 377).
#[test]
fn coarse_to_fine_recovers_gyroid_3d_where_the_paper_loss_alone_does_not() {
    let gyroid = |eta: f64, a: f64, t: f64| {
        let f =
            |w: &str, ax: &str, amp: f64| json!({"wave": w, "axis": ax, "freq": eta, "amp": amp});
        json!({"type": "periodic", "thickness": t, "terms": [
            [f("sin", "x", a), f("cos", "y", 1.0)],
            [f("sin", "y", a), f("cos", "z", 1.0)],
            [f("sin", "z", a), f("cos", "x", 1.0)]]})
        .to_string()
    };
    let p = |pointer: &str, lo: f64, hi: f64, also: &[&str]| FitParam {
        pointer: pointer.into(),
        lo,
        hi,
        also: also.iter().map(|s| s.to_string()).collect(),
    };
    let freqs = ["/terms/0/1/freq", "/terms/1/0/freq", "/terms/1/1/freq"];
    let rest = ["/terms/2/0/freq", "/terms/2/1/freq"];
    let req = |seed: u64, coarse_to_fine: bool| MicroFitRequest {
        scene: gyroid(300.0, 6.0, 0.0),
        params: vec![
            p(
                "/terms/0/0/freq",
                10.0,
                400.0,
                &[&freqs[..], &rest[..]].concat(),
            ),
            p(
                "/terms/0/0/amp",
                1.0,
                20.0,
                &["/terms/1/0/amp", "/terms/2/0/amp"],
            ),
            p("/thickness", 0.0, 3.0, &[]),
        ],
        target: FitTarget::Scene {
            scene: gyroid(100.0, 7.0, 1.2),
        },
        grid: 32,
        center: [0.125; 3],
        half: 0.125,
        budget: C2F_TEST_BUDGET,
        population: 20,
        sigma: 0.3,
        seed,
        coarse_to_fine,
        ..Default::default()
    };
    let seed = 2;
    let exact = fit(req(seed, false));
    let c2f = fit(req(seed, true));
    eprintln!(
        "seed {seed}: paper loss alone {:?} (validation {:?}); coarse to fine {:?} \
         (validation {:?}, loss {})",
        exact.values, exact.validation, c2f.values, c2f.validation, c2f.loss
    );
    assert!(
        exact.validation.unwrap() > 0.1,
        "the paper's loss alone found it: {:?} (validation {:?})",
        exact.values,
        exact.validation
    );
    assert!(
        c2f.validation.unwrap() < 1e-3,
        "seed {seed}: {:?}",
        c2f.validation
    );
    assert!(
        (c2f.values[0] - 100.0).abs() < 0.1,
        "seed {seed}: {:?}",
        c2f.values
    );
    assert!(c2f.evaluations <= C2F_TEST_BUDGET as u64);
    // Honest: the reported loss is the paper's loss of the answer.
    let again = fit(MicroFitRequest {
        scene: c2f.scene.clone(),
        budget: 1,
        ..req(seed, false)
    });
    // Only deep in the needle, not equal: the start's values pass
    // through the normalised coordinates and back, which may move
    // them an ulp, and that near the minimum moves bins of rounding
    // noise across the phase floor (seen: −13.4 → −6.0).
    let l = again.initial_loss;
    assert!(
        l < -5.0 && c2f.loss < -5.0,
        "seed {seed}: {l}, {}",
        c2f.loss
    );
    assert_eq!(c2f.history.last(), Some(&c2f.loss));
    // Stages and all, shards give the unsharded run bit for bit (they
    // exchange both losses of each point).
    let short = MicroFitRequest {
        budget: 400,
        ..req(1, true)
    };
    let one = fit(short.clone());
    let jobs = (0..2)
        .map(|k| {
            start_fit(MicroFitRequest {
                shards: Some((k, 2)),
                ..short.clone()
            })
            .unwrap()
        })
        .collect();
    assert_eq!(run_sharded(jobs, &Cancel::new(), |_, _| {}).unwrap(), one);
}

const C2F_TEST_BUDGET: u32 = 3000;

#[test]
fn a_seed_fixes_the_run_and_shards_give_the_unsharded_result() {
    let req = MicroFitRequest {
        budget: 200,
        population: 10,
        ..gyroid_request(Optimizer::Cmaes, 200)
    };
    let a = fit(req.clone());
    let b = fit(req.clone());
    assert_eq!(a, b);
    let c = fit(MicroFitRequest {
        seed: 2,
        ..req.clone()
    });
    assert_ne!(a.history, c.history, "another seed, another run");
    for n in [2, 3] {
        let jobs = (0..n)
            .map(|k| {
                start_fit(MicroFitRequest {
                    shards: Some((k, n)),
                    ..req.clone()
                })
                .unwrap()
            })
            .collect();
        let s = run_sharded(jobs, &Cancel::new(), |_, _| {}).unwrap();
        assert_eq!(s, a, "{n} shards");
    }
}

/// Analysis by synthesis (§12.2): the target is a picture; each candidate
/// is rendered with the same camera and compared by Eq. 39.
#[test]
fn analysis_by_synthesis_lowers_the_image_loss() {
    let scene = |period: f64| {
        json!({"type": "tpms", "surface": "gyroid", "period": period, "thickness": 0.3}).to_string()
    };
    let mut req = MicroFitRequest {
        scene: scene(0.8),
        params: vec![FitParam {
            pointer: "/period".into(),
            lo: 0.3,
            hi: 1.0,
            also: vec![],
        }],
        target: FitTarget::Image {
            png: None,
            scene: Some(scene(0.5)),
        },
        optimizer: Optimizer::Powell,
        budget: 40,
        ..Default::default()
    };
    req.render.width = 32;
    req.render.height = 32;
    // Coarse to fine compares volume spectra: refused here, naming itself.
    let refused = start_fit(MicroFitRequest {
        coarse_to_fine: true,
        ..req.clone()
    })
    .err()
    .expect("an image target refuses coarse_to_fine");
    assert!(format!("{:?}", refused.field()).contains("coarse_to_fine"));
    let r = fit(req);
    assert!(
        r.loss < r.initial_loss - 0.5,
        "{} from {}",
        r.loss,
        r.initial_loss
    );
    assert!((r.values[0] - 0.5).abs() < 0.1, "period {}", r.values[0]);
}

/// A slice stack of grey PNGs as the target.
#[test]
fn slices_of_a_target_give_back_its_parameter() {
    use filigree::raster::{encode_png, Rgba8Image};
    let target = filigree::micro::parse(&gyroid_1d(100.0)).unwrap();
    let (n, range) = (16usize, 0.004);
    // One slice per grid plane (fewer planes alias the z waves: with 4,
    // their spacing is about one period at η = 100).
    let pngs: Vec<serde_bytes::ByteBuf> = (0..n)
        .map(|k| {
            let z = (k as f64 + 0.5) * 0.25 / n as f64;
            let mut data = vec![];
            for y in (0..n).rev() {
                for x in 0..n {
                    let p = [
                        (x as f64 + 0.5) * 0.25 / n as f64,
                        (y as f64 + 0.5) * 0.25 / n as f64,
                        z,
                    ];
                    let v = target.eval_array(p).clamp(-range, range);
                    let g = ((0.5 + 0.5 * v / range) * 255.0).round() as u8;
                    data.extend([g, g, g, 255]);
                }
            }
            let img = Rgba8Image {
                width: n as u32,
                height: n as u32,
                data,
            };
            serde_bytes::ByteBuf::from(encode_png(&img).unwrap())
        })
        .collect();
    let r = fit(MicroFitRequest {
        target: FitTarget::Slices { pngs, range },
        grid: n as u32,
        ..gyroid_request(Optimizer::Powell, 800)
    });
    assert!((r.values[0] - 100.0).abs() < 2.0, "η = {}", r.values[0]);
    assert_eq!(r.validation, None, "no target scene to validate against");
}

#[test]
fn bad_requests_get_typed_errors_naming_the_field() {
    let ok = gyroid_request(Optimizer::Cmaes, 100);
    let cases: Vec<(MicroFitRequest, &str, &str)> = vec![
        (
            MicroFitRequest {
                params: vec![],
                ..ok.clone()
            },
            "invalid-input",
            "params",
        ),
        (
            MicroFitRequest {
                params: vec![FitParam {
                    pointer: "/terms/9/0/freq".into(),
                    lo: 1.0,
                    hi: 2.0,
                    also: vec![],
                }],
                ..ok.clone()
            },
            "invalid-input",
            "params.0.pointer",
        ),
        (
            MicroFitRequest {
                params: vec![FitParam {
                    pointer: "/terms/0/0/wave".into(),
                    lo: 1.0,
                    hi: 2.0,
                    also: vec![],
                }],
                ..ok.clone()
            },
            "invalid-input",
            "params.0.pointer",
        ),
        (
            MicroFitRequest {
                params: vec![FitParam {
                    pointer: "/terms/0/0/freq".into(),
                    lo: 2.0,
                    hi: 2.0,
                    also: vec!["/terms/0/0/freq".into()],
                }],
                ..ok.clone()
            },
            "invalid-input",
            "params.0.lo",
        ),
        (
            MicroFitRequest {
                params: vec![FitParam {
                    pointer: "/terms/0/0/freq".into(),
                    lo: 1.0,
                    hi: 2.0,
                    also: vec!["/terms/0/0/freq".into()],
                }],
                ..ok.clone()
            },
            "invalid-input",
            "params.0.also.0",
        ),
        (
            MicroFitRequest {
                grid: 24,
                ..ok.clone()
            },
            "invalid-input",
            "grid",
        ),
        (
            MicroFitRequest {
                grid: 128,
                ..ok.clone()
            },
            "invalid-input",
            "grid",
        ),
        (
            MicroFitRequest {
                budget: 0,
                ..ok.clone()
            },
            "invalid-input",
            "budget",
        ),
        // Issue 34: a budget below one generation returned the start
        // unchanged after one evaluation, without a word.
        (
            MicroFitRequest {
                budget: 20,
                population: 20,
                optimizer: Optimizer::Cmaes,
                ..ok.clone()
            },
            "invalid-input",
            "budget",
        ),
        (
            MicroFitRequest {
                scene: "{\"type\": \"sphere\"".into(),
                ..ok.clone()
            },
            "syntax",
            "scene",
        ),
        (
            MicroFitRequest {
                target: FitTarget::Scene {
                    scene: "{\"type\": \"cube\"}".into(),
                },
                ..ok.clone()
            },
            "syntax",
            "target.scene",
        ),
        (
            MicroFitRequest {
                target: FitTarget::Volume {
                    values: vec![0.0; 10],
                },
                ..ok.clone()
            },
            "invalid-input",
            "target.values",
        ),
        (
            MicroFitRequest {
                target: FitTarget::Slices {
                    pngs: vec![serde_bytes::ByteBuf::from(vec![1, 2, 3])],
                    range: 1.0,
                },
                ..ok.clone()
            },
            "invalid-input",
            "target.pngs.0",
        ),
        (
            MicroFitRequest {
                target: FitTarget::Image {
                    png: None,
                    scene: None,
                },
                ..ok.clone()
            },
            "invalid-input",
            "target",
        ),
        (
            MicroFitRequest {
                shards: Some((3, 3)),
                ..ok.clone()
            },
            "invalid-input",
            "shards",
        ),
    ];
    for (i, (req, kind, field)) in cases.into_iter().enumerate() {
        let e = start_fit(req)
            .err()
            .unwrap_or_else(|| panic!("case {i} passed"));
        assert_eq!((e.kind(), e.field()), (kind, Some(field)), "case {i}: {e}");
        assert!(!e.to_string().is_empty());
    }
    // Through the registry, as the browser sends it: serde's errors too,
    // as a request that could not be read (the sender's fault, `bad-request`).
    for (payload, field) in [
        (json!({"optimizer": "simulated-annealing"}), "optimizer"),
        (json!({"target": {"kind": "photo"}}), "target.kind"),
        (
            json!({"params": [{"pointer": 3, "lo": 0, "hi": 1}]}),
            "params.0.pointer",
        ),
        (json!({"grid": -1}), "grid"),
    ] {
        let e = filigree::api::run_json("micro-fit", &payload.to_string()).unwrap_err();
        assert_eq!(e.kind(), "bad-request", "{payload}: {e}");
        assert_eq!(e.field(), Some(field), "{payload}: {e}");
    }
}

#[test]
fn invalid_candidates_score_infinity_and_never_win() {
    // Radii above 0.45 of the cell are refused by the particles node: those
    // candidates cannot be built, and the fit goes on around them.
    let scene = |r: f64| {
        json!({"type": "particles", "cell": 0.25, "seed": 3, "jitter": 0.5,
               "size": {"dist": "fixed", "radius": r}})
        .to_string()
    };
    let r = fit(MicroFitRequest {
        scene: scene(0.2),
        params: vec![FitParam {
            pointer: "/size/radius".into(),
            lo: 0.05,
            hi: 5.0,
            also: vec![],
        }],
        target: FitTarget::Scene { scene: scene(0.3) },
        grid: 16,
        budget: 150,
        ..Default::default()
    });
    assert!(r.loss.is_finite());
    assert!((r.values[0] - 0.3).abs() < 0.02, "radius {}", r.values[0]);
}

#[test]
fn the_registry_serves_micro_fit_with_its_defaults() {
    let d = filigree::api::run_json("defaults", r#"{"tool": "micro-fit"}"#).unwrap();
    assert_eq!(d["request"]["grid"], 32);
    assert_eq!(d["request"]["optimizer"], "cmaes");
    assert_eq!(d["request"]["target"]["kind"], "scene");
    let req = serde_json::to_string(&MicroFitRequest {
        budget: 30,
        ..gyroid_request(Optimizer::Powell, 30)
    })
    .unwrap();
    let out = filigree::api::run_json("micro-fit", &req).unwrap();
    assert_eq!(out["evaluations"], 30);
    assert!(out["loss"].as_f64().unwrap() <= out["initial_loss"].as_f64().unwrap());
}

/// `filigree micro fit`: files and flags → the same request → a JSON summary
/// and the fitted scene written out.
#[test]
fn the_cli_fits_a_scene_file_to_a_target_file() {
    let dir = std::env::temp_dir().join(format!("filigree-micro-fit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (scene, target, out) = (dir.join("s.json"), dir.join("t.json"), dir.join("fit.json"));
    std::fs::write(&scene, gyroid_1d(300.0)).unwrap();
    std::fs::write(&target, gyroid_1d(100.0)).unwrap();
    let run = |extra: &[&str]| {
        let mut args = vec![
            "micro",
            "fit",
            "--scene",
            scene.to_str().unwrap(),
            "--target",
            target.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--param",
            "/terms/0/0/freq,/terms/1/0/freq,/terms/2/0/freq=10:400",
            "--center",
            "0.125,0.125,0.125",
            "--half",
            "0.125",
        ];
        args.extend(extra);
        std::process::Command::new(env!("CARGO_BIN_EXE_filigree"))
            .args(&args)
            .output()
            .unwrap()
    };
    // The request it builds is the browser's, defaults included.
    let o = run(&["--print-request"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let req: MicroFitRequest = serde_json::from_slice(&o.stdout).unwrap();
    let mut want = gyroid_request(Optimizer::Cmaes, 1);
    want.grid = MicroFitRequest::default().grid;
    want.budget = MicroFitRequest::default().budget;
    want.population = MicroFitRequest::default().population;
    want.sigma = MicroFitRequest::default().sigma;
    assert_eq!(req, want);
    // A short Powell fit with two threads (two shards).
    let o = run(&[
        "--optimizer",
        "powell",
        "--budget",
        "400",
        "--threads",
        "2",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(summary["evaluations"], 400);
    assert!(summary["loss"].as_f64() < summary["initial_loss"].as_f64());
    assert!(summary["ms_per_eval"].as_f64().unwrap() > 0.0);
    let fitted: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap();
    let v = summary["params"][0]["value"].as_f64().unwrap();
    let got = fitted["terms"][2][0]["freq"].as_f64().unwrap();
    assert!((got - v).abs() < 1e-12 * v, "{got} ≠ {v}");
    // Errors name the flag.
    let o = run(&["--grid", "24"]);
    assert!(!o.status.success());
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        err.contains("--grid") && err.contains("power of two"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).ok();
}

/// The lattice path (a periodic root: each factor's values computed once
/// per axis) gives exactly the values of evaluating every point, for sines,
/// cosines, phases, powers, a constant and a sheet thickness, terms with
/// no, one and two factors along x and factors before and after them, for
/// a scene and a volume target; a scene it cannot take is sampled point by point.
#[test]
fn lattice_sampling_equals_pointwise_sampling_bit_for_bit() {
    use filigree::core::job::Job;
    let f = |w: &str, ax: &str, freq: f64, amp: f64, phase: f64, power: u32| json!({"wave": w, "axis": ax, "freq": freq, "amp": amp, "phase": phase, "power": power});
    let scenes = [
        gyroid_1d(100.0),
        json!({"type": "periodic", "thickness": 0.3, "constant": 0.2, "terms": [
            [f("sin", "x", 37.0, 1.5, 0.1, 1), f("cos", "y", 41.0, 0.7, 0.0, 2), f("sin", "z", 13.0, -1.0, 2.0, 3)],
            [f("cos", "z", 90.0, 1.0, 0.0, 1)],
            [f("sin", "y", 7.0, 2.0, 0.3, 1), f("sin", "y", 11.0, 1.0, 0.0, 1)],
            [f("cos", "z", 5.0, 0.9, 0.0, 1), f("cos", "x", 23.0, 1.1, 0.4, 1), f("sin", "x", 3.0, 1.0, 0.0, 2)],
            [f("sin", "x", 17.0, 0.8, 0.0, 1), f("cos", "z", 29.0, 1.0, 0.2, 1)]]})
        .to_string(),
        json!({"type": "sphere", "radius": 0.1}).to_string(),
    ];
    // Grids of 8 and, for the plane kernels' other shapes, 2 (planes of
    // 4) and 32 (the bench's).
    for (i, scene) in scenes.iter().enumerate() {
        for (volume, grid) in [(false, 8), (true, 8), (false, 2), (true, 32)] {
            let target = match volume {
                false => FitTarget::Scene {
                    scene: scene.clone(),
                },
                true => FitTarget::Volume {
                    values: vec![0.0; grid * grid * grid],
                },
            };
            let mut req = MicroFitRequest {
                scene: scene.clone(),
                params: vec![],
                target,
                grid: grid as u32,
                center: [0.1, -0.2, 0.3],
                half: 0.37,
                ..gyroid_request(Optimizer::Cmaes, 41)
            };
            req.params = match i {
                0 => eta_param(),
                1 => vec![FitParam {
                    pointer: "/constant".into(),
                    lo: -1.0,
                    hi: 1.0,
                    also: vec![],
                }],
                _ => vec![FitParam {
                    pointer: "/radius".into(),
                    lo: 0.01,
                    hi: 1.0,
                    also: vec![],
                }],
            };
            let mut job = start_fit(req).unwrap();
            job.step().unwrap();
            let s = job.scene_for(&[0.37]).expect("a valid scene");
            let lattice = job.sample(&s, false).unwrap();
            let points = job.sample(&s, true).unwrap();
            assert_eq!(lattice.len(), grid * grid * grid);
            assert!(
                lattice
                    .iter()
                    .zip(&points)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "scene {i}, grid {grid}"
            );
            assert!(job.loss_of_samples(&lattice).unwrap().is_finite());
        }
    }
}

/// The fits of `tests/fixtures/micro-native/fits.json` (one per optimiser,
/// lattice- and point-sampled scenes) give the responses stored beside it
/// (`<name>.json`), every number to the bit; the browser e2e
/// (`micro-fit.test.mjs`) runs the same requests in the wasm worker and
/// compares with the same files, so a fit gives the same bytes in wasm as
/// natively. `FILIGREE_BLESS=1` rewrites the files after an intended change.
#[test]
fn fits_give_the_stored_native_results() {
    let dir = format!("{}/tests/fixtures/micro-native", env!("CARGO_MANIFEST_DIR"));
    let list: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{dir}/fits.json")).unwrap())
            .unwrap();
    let bless = std::env::var("FILIGREE_BLESS").is_ok_and(|v| v == "1");
    let fits = list["fits"].as_array().unwrap();
    assert!(fits.len() >= 3);
    for f in fits {
        let name = f["name"].as_str().unwrap();
        let out = filigree::api::run_json("micro-fit", &f["request"].to_string()).unwrap();
        assert!(
            out["loss"].as_f64().unwrap() < out["initial_loss"].as_f64().unwrap(),
            "{name}"
        );
        let got = serde_json::to_string_pretty(&out).unwrap() + "\n";
        let path = format!("{dir}/{name}.json");
        if bless {
            std::fs::write(&path, &got).unwrap();
        }
        let want = std::fs::read_to_string(&path)
            .unwrap_or_else(|e| panic!("{path}: {e} (FILIGREE_BLESS=1 writes it)"));
        // serde_json prints each f64 as the shortest text that reads back
        // as it: equal text, equal bits.
        assert!(got == want, "{name}: the native result differs from {path}");
    }
}

/// `EVALS` (default 100) loss evaluations of the bench's problem (gyroid
/// 1D on a 32³ grid, a candidate near the truth): the scene, its lattice
/// samples, FFT and loss, the way the job does them. Ignored: a fixed
/// amount of work for `valgrind --tool=callgrind` (instructions per
/// evaluation: the difference of two counts over the difference of their
/// `EVALS`); times are `bench micro --only loss`'s.
#[test]
#[ignore]
fn a_fixed_number_of_loss_evaluations() {
    use filigree::core::job::Job;
    let evals: usize = std::env::var("EVALS").map_or(100, |v| v.parse().unwrap());
    let mut job = start_fit(MicroFitRequest {
        grid: 32,
        ..gyroid_request(Optimizer::Cmaes, 41)
    })
    .unwrap();
    job.step().unwrap();
    let u = [(101.0 - 10.0) / 390.0];
    for _ in 0..evals {
        assert!(job.evaluate(&u).unwrap().is_finite());
    }
}

/// Powell with coarse to fine on `bench micro`'s gyroid 5D (three tied
/// frequencies, the amplitude and the thickness; budget 3000): its first
/// stage's line searches polished the coarse profiles to 1e-7, about 250
/// evaluations per start, so the stage saw its start stuck in a local
/// minimum of the profiles and one restart, and every seed ended far off
/// (validation about 3.4, issue 12). Stopping those lines at
/// `COARSE_LINE_TOLERANCE` leaves budget for several restarts: every seed
/// finds the frequencies, and the fitted field matches (the amplitude and
/// thickness only matter through their ratio once the field is normalised).
/// One seed here; `filigree bench micro --only fit` fits gyroid 5D with
/// every optimiser over several seeds (the paper's Table 3).
#[test]
fn powell_coarse_to_fine_recovers_gyroid_5d() {
    let gyroid = |ex: f64, ey: f64, ez: f64, a: f64, t: f64| {
        let f = |w: &str, ax: &str, freq: f64, amp: f64| json!({"wave": w, "axis": ax, "freq": freq, "amp": amp});
        json!({"type": "periodic", "thickness": t, "terms": [
            [f("sin", "x", ex, a), f("cos", "y", ey, 1.0)],
            [f("sin", "y", ey, a), f("cos", "z", ez, 1.0)],
            [f("sin", "z", ez, a), f("cos", "x", ex, 1.0)]]})
        .to_string()
    };
    let p = |pointer: &str, lo: f64, hi: f64, also: &[&str]| FitParam {
        pointer: pointer.into(),
        lo,
        hi,
        also: also.iter().map(|s| s.to_string()).collect(),
    };
    for seed in 1..=1 {
        let out = fit(MicroFitRequest {
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
            optimizer: Optimizer::Powell,
            budget: 3000,
            seed,
            coarse_to_fine: true,
            ..Default::default()
        });
        let v = &out.values;
        eprintln!("seed {seed}: {v:?}, validation {:?}", out.validation);
        for (got, want) in v.iter().zip([100.0, 120.0, 80.0]) {
            assert!((got - want).abs() < 0.1, "seed {seed}: {v:?}");
        }
        let ratio = v[3] / v[4].max(1e-9);
        assert!(
            (ratio - 7.0 / 1.2).abs() < 0.1,
            "seed {seed}: amplitude / thickness {ratio}"
        );
        assert!(
            out.validation.unwrap() < 1e-6,
            "seed {seed}: {:?}",
            out.validation
        );
        assert!(out.evaluations <= 3000);
    }
}

/// A sampled volume target (`target.values`: what `micro fit --target
/// V.f32` reads, e.g. from a CT scan) gives back the gyroid's frequency: the
/// target scene sampled on the fit's own grid gives the scene target's fit,
/// value for value and loss for loss.
#[test]
fn a_sampled_volume_target_gives_the_scene_targets_fit() {
    let req = gyroid_request(Optimizer::Powell, 800);
    let job = start_fit(req.clone()).unwrap();
    let target = filigree::micro::parse(&gyroid_1d(100.0)).unwrap();
    let values = job.sample(&target, false).unwrap();
    assert_eq!(values.len(), 16 * 16 * 16);
    let by_scene = fit(req.clone());
    let by_volume = fit(MicroFitRequest {
        target: FitTarget::Volume { values },
        ..req
    });
    eprintln!(
        "volume: η = {}, loss {} (scene: η = {}, loss {})",
        by_volume.values[0], by_volume.loss, by_scene.values[0], by_scene.loss
    );
    assert!(
        (by_volume.values[0] - 100.0).abs() < 0.01,
        "{:?}",
        by_volume.values
    );
    assert!(by_volume.loss < by_volume.initial_loss - 3.0);
    assert_eq!(by_volume.values, by_scene.values);
    assert_eq!(by_volume.loss, by_scene.loss);
}
