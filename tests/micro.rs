//! Micro end to end: every node's field is 1-Lipschitz after
//! normalisation, sphere tracing agrees with dense ray marching, requests
//! are deterministic, and errors name their field.
use filigree::api::run_json;
use filigree::core::rng::Rng;
use filigree::micro::render::{self, Stats, StepMode, Trace};
use filigree::micro::{parse, Scene};
use glam::DVec3;
use serde_json::json;

/// One scene per node type and option (each node kind at least once).
fn scenes() -> Vec<(&'static str, serde_json::Value)> {
    let sphere = json!({"type": "sphere", "radius": 0.4});
    vec![
        ("sphere", sphere.clone()),
        (
            "box",
            json!({"type": "box", "center": [0.1, 0, 0], "half": [0.3, 0.5, 0.2], "round": 0.05}),
        ),
        (
            "plane",
            json!({"type": "plane", "normal": [1, 2, 3], "offset": 0.2}),
        ),
        (
            "particles-spheres",
            json!({"type": "particles", "cell": 0.2, "seed": 5, "size": {"dist": "uniform", "min": 0.1, "max": 0.45}}),
        ),
        (
            "particles-mixture",
            json!({"type": "particles", "cell": 0.15, "seed": 2, "jitter": 0.7,
            "size": {"dist": "normal", "mean": 0.3, "std": 0.1, "max": 0.5},
            "shapes": [{"shape": "ellipsoid", "axes": [1, 0.4, 0.3], "weight": 2}, {"shape": "torus", "ratio": 0.4},
                       {"shape": "cylinder", "aspect": 0.5}, {"shape": "hex_prism", "aspect": 2}, {"shape": "red_blood_cell"}]}),
        ),
        (
            "particles-varying",
            json!({"type": "particles", "cell": 0.1, "seed": 9,
            "size": {"dist": "fixed", "radius": 0.4},
            "size_scale": {"value": 0.5, "gradient": [0, 0, 0.5]},
            "keep": {"value": 0.5, "gradient": [0.3, 0, 0]},
            "offset": {"value": 0.0, "gradient": [0.01, 0.02, 0.0]},
            "warp": {"amplitude": 0.05, "frequency": 8},
            "random_orientation": false}),
        ),
        (
            "lattice",
            json!({"type": "lattice", "cell": 0.1, "radius": 0.9}),
        ),
        (
            "lattice-agglomerate",
            json!({"type": "lattice", "cell": 0.1, "radius": 0.7, "smooth": 0.3, "jitter": 0.3,
            "select": {"combine": "any", "terms": [
                {"poly": [{"c": 1, "x": 1}, {"c": 1, "y": 1}], "modulus": 3, "classes": [{"residue": 0}]},
                {"poly": [{"c": 1, "z": 2}], "modulus": 5, "classes": [{"residue": 1, "include": false}], "combine": "all"}]}}),
        ),
        (
            "pile",
            json!({"type": "pile", "cell": 0.2, "radius": 0.5, "axis": [0, 1, 1],
            "angle": {"value": 0.2, "gradient": [0.5, 0.2, 0]}, "deform": {"value": 0.01, "gradient": [0.02, 0.02, 0.02]},
            "noise_frequency": 7, "extent": 1.2}),
        ),
        (
            "gyroid-solid",
            json!({"type": "tpms", "surface": "gyroid", "period": 0.4, "level": 0.3}),
        ),
        (
            "diamond-sheet",
            json!({"type": "tpms", "surface": "diamond", "period": 0.5, "thickness": 0.2}),
        ),
        (
            "primitive",
            json!({"type": "tpms", "surface": "primitive", "period": 0.7, "level": -0.5}),
        ),
        (
            "periodic",
            json!({"type": "periodic", "constant": 0.3, "thickness": 0.0, "terms": [
            [{"wave": "sin", "axis": "x", "freq": 9, "amp": 1.2}, {"wave": "cos", "axis": "y", "freq": 5, "phase": 0.3, "power": 2}],
            [{"wave": "sin", "axis": "z", "freq": 13}],
            [{"wave": "cos", "axis": "x", "freq": 3}, {"wave": "cos", "axis": "y", "freq": 3}, {"wave": "sin", "axis": "z", "freq": 4, "power": 3}]]}),
        ),
        (
            "union-smooth",
            json!({"type": "union", "smooth": 0.2, "children": [sphere.clone(), {"type": "box", "center": [0.4, 0, 0], "half": [0.2, 0.2, 0.2]}]}),
        ),
        (
            "intersection-smooth",
            json!({"type": "intersection", "smooth": 0.1, "children": [
            {"type": "tpms", "surface": "gyroid", "period": 0.3, "thickness": 0.3}, sphere.clone()]}),
        ),
        (
            "difference",
            json!({"type": "difference", "smooth": 0.05, "base": {"type": "box", "half": [0.5, 0.5, 0.5]},
            "minus": [{"type": "particles", "cell": 0.25, "seed": 1, "size": {"dist": "fixed", "radius": 0.4}}]}),
        ),
        (
            "transform-shear",
            json!({"type": "transform", "matrix": [[1, 0.8, 0], [0, 1, 0], [0.3, 0, 2]],
            "rotate": {"axis": [1, 1, 0], "angle": 0.7}, "scale": 0.5, "translate": [0.1, 0.2, 0],
            "child": {"type": "tpms", "surface": "gyroid", "period": 0.5}}),
        ),
        (
            "offset",
            json!({"type": "offset", "amount": 0.05, "child": {"type": "lattice", "cell": 0.2, "radius": 0.5}}),
        ),
        (
            "shell",
            json!({"type": "shell", "thickness": 0.02, "child": sphere.clone()}),
        ),
        (
            "repeat",
            json!({"type": "repeat", "cell": [0.3, 0.3, 0.5], "child": {"type": "sphere", "radius": 0.1}}),
        ),
    ]
}

fn scene(v: &serde_json::Value) -> Scene {
    parse(&v.to_string()).unwrap_or_else(|e| panic!("{v}: {e}"))
}

fn rnd(r: &mut Rng, lo: f64, hi: f64) -> DVec3 {
    DVec3::new(
        r.range_f64(lo, hi),
        r.range_f64(lo, hi),
        r.range_f64(lo, hi),
    )
}

/// |f(p) − f(q)| ≤ |p − q| (1 + ε) for every node type, at separations
/// from 1e-4 to 0.5 (the normalisation by each node's gradient bound is
/// what sphere tracing relies on).
#[test]
fn every_node_is_one_lipschitz_after_normalisation() {
    for (name, v) in scenes() {
        let s = scene(&v);
        let mut r = Rng::new(17);
        let mut steepest = 0.0f64;
        for i in 0..6000 {
            let p = rnd(&mut r, -1.2, 1.2);
            let len = [1e-4, 1e-3, 1e-2, 0.1, 0.5][i % 5];
            let q = p + rnd(&mut r, -1.0, 1.0).normalize() * len * r.f64();
            let (a, b) = (s.eval(p), s.eval(q));
            let gap = p.distance(q);
            assert!(
                (a - b).abs() <= gap * (1.0 + 1e-6) + 1e-12,
                "{name}: |f({p}) − f({q})| = {} > {gap}",
                (a - b).abs()
            );
            if gap > 0.0 {
                steepest = steepest.max((a - b).abs() / gap);
            }
        }
        // The bound is not absurdly loose: somewhere the field is at least
        // a tenth as steep as allowed (else tracing would crawl).
        assert!(steepest > 0.1, "{name}: steepest slope {steepest}");
    }
}

/// First sign change along a ray in `[from, to]` by marching with step
/// `h`, refined by bisection.
fn dense_hit(s: &Scene, o: DVec3, d: DVec3, from: f64, to: f64, h: f64) -> Option<f64> {
    let f = |t: f64| render::field(s, 1.0, o + d * t);
    let mut t = from;
    if f(t) <= 0.0 {
        return Some(t);
    }
    while t < to {
        let n = t + h;
        if f(n) <= 0.0 {
            let (mut lo, mut hi) = (t, n);
            for _ in 0..50 {
                let m = 0.5 * (lo + hi);
                if f(m) <= 0.0 {
                    hi = m
                } else {
                    lo = m
                }
            }
            return Some(hi);
        }
        t = n;
    }
    None
}

/// Sphere tracing (fixed and adaptive steps) never passes a surface that
/// dense marching finds, and its hits lie where dense marching finds the
/// surface (or on a sliver thinner than the march's step, which a march
/// 100 times denser around the hit confirms); bisection agrees on nearly
/// every ray.
#[test]
fn sphere_traced_hits_agree_with_dense_marching() {
    let picks = [
        "particles-spheres",
        "particles-mixture",
        "particles-varying",
        "lattice-agglomerate",
        "pile",
        "diamond-sheet",
        "periodic",
        "transform-shear",
    ];
    let all = scenes();
    for name in picks {
        let v = &all.iter().find(|(n, _)| *n == name).unwrap().1;
        let s = scene(v);
        let o = DVec3::new(2.6, -1.9, 1.7);
        let mut r = Rng::new(5);
        let n = 120;
        let rays: Vec<(DVec3, Option<f64>)> = (0..n)
            .map(|_| {
                let d = (rnd(&mut r, -0.6, 0.6) - o).normalize();
                let dense = render::clip(o, d, 1.0)
                    .and_then(|(t0, t1)| dense_hit(&s, o, d, t0 + 1e-9, t1, 1e-3));
                (d, dense)
            })
            .collect();
        for (mode, check_cell) in [
            (StepMode::Fixed, 0.0),
            (StepMode::Adaptive, 0.0),
            (StepMode::Adaptive, 0.05),
            (StepMode::Bisection, 0.0),
        ] {
            let tr = Trace {
                mode,
                check_every: 3,
                check_cell,
                check_modulus: 3,
                max_relax: 4.0,
                bisection_factor: 1.5,
                max_steps: 5000,
                precision: 1e-5,
                bounds: 1.0,
            };
            let (mut agree, mut hits) = (0, 0);
            for &(d, dense) in &rays {
                let mut st = Stats::default();
                let traced = render::trace(&s, o, d, &tr, &mut st);
                match (traced, dense) {
                    (Some(t), Some(td)) => {
                        hits += 1;
                        if mode != StepMode::Bisection {
                            // Never past a surface dense marching saw.
                            assert!(
                                t <= td + 1e-4,
                                "{name} {mode:?}: traced {t} beyond dense {td}"
                            );
                        }
                        let sliver = || dense_hit(&s, o, d, t - 1e-3, t + 2e-3, 1e-5).is_some();
                        agree += ((t - td).abs() < 1e-3 || (t < td && sliver())) as usize;
                    }
                    (None, None) => agree += 1,
                    (Some(t), None) => {
                        agree += dense_hit(&s, o, d, t - 1e-3, t + 2e-3, 1e-5).is_some() as usize
                    }
                    (None, Some(td)) => assert!(
                        mode == StepMode::Bisection,
                        "{name} {mode:?}: missed the surface at {td}"
                    ),
                }
            }
            let need = if mode == StepMode::Bisection {
                0.9
            } else {
                0.97
            };
            assert!(
                agree as f64 >= need * n as f64,
                "{name} {mode:?}: {agree}/{n} rays agree"
            );
            assert!(hits > 10, "{name}: only {hits} hits");
        }
    }
}

fn asset(name: &str) -> String {
    std::fs::read_to_string(format!(
        "{}/assets/micro/{name}.json",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap()
}

/// The same request gives the same bytes; another seed other bytes.
#[test]
fn renders_are_deterministic_by_seed() {
    let req = |scene: &str| {
        json!({"scene": scene, "width": 40, "height": 32, "steps": "adaptive"}).to_string()
    };
    let a = run_json("micro-render", &req(&asset("spheres"))).unwrap();
    let b = run_json("micro-render", &req(&asset("spheres"))).unwrap();
    assert_eq!(a["png"], b["png"]);
    assert_eq!(a["stats"], b["stats"]);
    let other = asset("spheres").replace("\"seed\": 7", "\"seed\": 8");
    let c = run_json("micro-render", &req(&other)).unwrap();
    assert_ne!(a["png"], c["png"]);
    assert_eq!(a["stats"]["rays"], 40 * 32);
    assert!(a["stats"]["hits"].as_u64().unwrap() > 100);
}

/// Every shipped scene parses, renders and slices, and shows structure
/// (some rays hit, some miss; the slice is partly inside).
#[test]
fn shipped_scenes_render_and_slice() {
    for name in [
        "gyroid",
        "spheres",
        "fibres",
        "agglomerate",
        "piled",
        "multiscale",
    ] {
        let text = asset(name);
        let r = run_json(
            "micro-render",
            &json!({"scene": text, "width": 32, "height": 32}).to_string(),
        )
        .unwrap_or_else(|e| panic!("{name}: {e}"));
        let hits = r["stats"]["hits"].as_u64().unwrap();
        assert!(hits > 50 && hits < 1024, "{name}: {hits} hits");
        let png = r["png"].as_array().unwrap();
        assert_eq!(
            &png[1..4],
            &[json!(80), json!(78), json!(71)],
            "{name}: PNG signature"
        );
        let sl = run_json(
            "micro-slice",
            &json!({"scene": text, "width": 24, "height": 24, "z": 0.1}).to_string(),
        )
        .unwrap();
        let inside = sl["inside"].as_f64().unwrap();
        assert!(
            inside > 0.01 && inside < 0.99,
            "{name}: slice inside {inside}"
        );
        assert!(sl["min"].as_f64().unwrap() < 0.0 && sl["max"].as_f64().unwrap() > 0.0);
    }
}

#[test]
fn request_errors_name_their_field() {
    let e = run_json(
        "micro-render",
        r#"{"scene": "{\"type\": \"sphere\", \"radius\": 1}", "width": 0}"#,
    )
    .unwrap_err();
    assert_eq!(e.field(), Some("width"));
    let e = run_json("micro-render", r#"{"scene": "{\"type\": \"sphere\"}"}"#).unwrap_err();
    assert_eq!(e.field(), Some("scene"));
    assert_eq!(e.kind(), "syntax");
    assert!(e.to_string().contains("radius"), "{e}");
    let e = run_json(
        "micro-render",
        r#"{"scene": "{\"type\": \"sphere\", \"radius\": 1}", "camera": {"fov": 0}}"#,
    )
    .unwrap_err();
    assert_eq!(e.field(), Some("camera.fov"));
    let e = run_json(
        "micro-render",
        r#"{"scene": "{\"type\": \"sphere\", \"radius\": 1}", "steps": "magic"}"#,
    )
    .unwrap_err();
    assert_eq!(e.field(), Some("steps"));
    let e = run_json(
        "micro-slice",
        r#"{"scene": "{\"type\": \"sphere\", \"radius\": 1}", "width": 4096, "height": 4096}"#,
    )
    .unwrap_err();
    assert_eq!(e.kind(), "invalid-input");
    let d = run_json("defaults", r#"{"tool": "micro-render"}"#).unwrap();
    assert_eq!(d["request"]["width"], 256);
    assert_eq!(d["request"]["steps"], "fixed");
    let d = run_json("defaults", r#"{"tool": "micro-slice"}"#).unwrap();
    assert_eq!(d["request"]["half"], 1.0);
}

/// The camera zooms from the whole sample to single particles: at a
/// thousandth of the distance the render still finds surfaces, without
/// running out of steps.
#[test]
fn the_camera_zooms_to_microscale() {
    let text = asset("multiscale");
    for distance in [3.6, 0.05, 0.004] {
        let r = run_json(
            "micro-render",
            &json!({"scene": text, "width": 24, "height": 24, "steps": "adaptive",
                    "camera": {"target": [0.05, 0.02, 0.1], "distance": distance, "fov": 40}})
            .to_string(),
        )
        .unwrap();
        let st = &r["stats"];
        assert!(st["hits"].as_u64().unwrap() > 100, "{distance}: {st}");
        assert!(st["exhausted"].as_u64().unwrap() < 24, "{distance}: {st}");
    }
}
