//! Replays every file of every fuzz corpus (`fuzz/corpus/<target>/`)
//! through the body its fuzz target runs (`fuzz/bodies.rs`), on stable: the
//! corpora, including the minimised inputs of past crashes, are regression
//! tests without a fuzz run. Fuzzing itself is `cargo +nightly fuzz run
//! <target>` (see `fuzz/README.md`).
use crate::support::app_projects;
#[path = "../fuzz/bodies.rs"]
mod bodies;

use std::path::{Path, PathBuf};

fn corpus(target: &str) -> Vec<PathBuf> {
    files_in(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("fuzz/corpus")
            .join(target),
    )
}

fn files_in(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_file())
        .collect();
    files.sort();
    files
}

fn body(target: &str) -> bodies::Body {
    bodies::TARGETS
        .iter()
        .find(|(n, _)| *n == target)
        .unwrap_or_else(|| panic!("no fuzz body '{target}'"))
        .1
}

/// Run `body` on `file` on a thread with the stack a fuzzer's main thread
/// has (8 MiB); whether it returned without panicking.
fn passes(body: bodies::Body, file: &Path) -> bool {
    let data = std::fs::read(file).unwrap();
    std::thread::Builder::new()
        .stack_size(8 << 20)
        .spawn(move || body(&data))
        .unwrap()
        .join()
        .is_ok()
}

/// Run every corpus file of `target` through its body, naming the file that fails.
fn replay(target: &str) {
    let body = body(target);
    let files = corpus(target);
    assert!(
        files.len() >= 5,
        "fuzz/corpus/{target} has only {} files",
        files.len()
    );
    for f in files {
        assert!(
            passes(body, &f),
            "{} fails the '{target}' fuzz body",
            f.display()
        );
    }
}

/// Inputs of fuzz findings whose fix has not landed yet
/// (`fuzz/pending/<target>/`, listed in the findings report). Run with
/// `--ignored`: each one that passes now belongs in `fuzz/corpus/<target>/`.
#[test]
#[ignore]
fn pending_findings_now_pass() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/pending");
    let mut failing = vec![];
    for (target, body) in bodies::TARGETS {
        let dir = root.join(target);
        if !dir.is_dir() {
            continue;
        }
        for f in files_in(&dir) {
            if !passes(*body, &f) {
                failing.push(f.display().to_string());
            }
        }
    }
    assert!(failing.is_empty(), "still failing: {failing:#?}");
}

#[test]
fn inset_corpus_replays() {
    replay("inset");
}

#[test]
fn lang_corpus_replays() {
    replay("lang");
}

#[test]
fn image_corpus_replays() {
    replay("image");
}

#[test]
fn strokes_corpus_replays() {
    replay("strokes");
}

#[test]
fn requests_corpus_replays() {
    replay("requests");
}

#[test]
fn project_corpus_replays() {
    replay("project");
}

#[test]
fn tangle_grammar_corpus_replays() {
    replay("tangle_grammar");
}

#[test]
fn tangle_start_corpus_replays() {
    replay("tangle_start");
}

#[test]
fn micro_scene_corpus_replays() {
    replay("micro_scene");
}

#[test]
fn texture_ratings_corpus_replays() {
    replay("texture_ratings");
}

#[test]
fn texture_index_corpus_replays() {
    replay("texture_index");
}

/// Every request kind has at least one seed in the `requests` corpus.
#[test]
fn requests_corpus_covers_every_kind() {
    let mut seen = vec![false; bodies::REQUEST_KINDS.len()];
    for f in corpus("requests") {
        if let Some(&k) = std::fs::read(&f).unwrap().first() {
            seen[k as usize % bodies::REQUEST_KINDS.len()] = true;
        }
    }
    let missing: Vec<_> = bodies::REQUEST_KINDS
        .iter()
        .zip(&seen)
        .filter(|(_, s)| !**s)
        .map(|(k, _)| *k)
        .collect();
    assert!(missing.is_empty(), "no seed for {missing:?}");
}

/// Every target in `fuzz/Cargo.toml` has a body here and a corpus.
#[test]
fn every_fuzz_target_is_replayed() {
    let manifest =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/Cargo.toml"))
            .unwrap();
    for line in manifest.lines() {
        if let Some(name) = line
            .strip_prefix("name = \"")
            .and_then(|l| l.strip_suffix('"'))
        {
            if name == "filigree-fuzz" {
                continue;
            }
            assert!(
                bodies::TARGETS.iter().any(|(n, _)| *n == name),
                "fuzz target '{name}' has no body in fuzz/bodies.rs"
            );
            assert!(!corpus(name).is_empty());
        }
    }
}

/// Small programs that reach what the shipped generators do not:
/// booleans, cubics, open paths, points, functions with `return`,
/// branches, every built-in function, transforms nested in functions.
const SEED_PROGRAMS: &[&str] = &[
    "param r in [0.05, 0.2] = 0.1;\nunion(fill: \"#123\") { circle(0.4, 0.5, r); circle(0.6, 0.5, r); }\n",
    "param r in [0.05, 0.3] = 0.2;\ndifference(fill: \"#a00\", stroke: \"#000\", width: 0.01) {\n  rect(0.5, 0.5, 0.6, 0.6, radius: 0.05);\n  circle(0.5, 0.5, r);\n}\nintersect(fill: \"blue\") { circle(0.3, 0.3, 0.2); rect(0.3, 0.3, 0.2, 0.5, rotation: 0.3); }\n",
    "param a in [0, 1] = 0.5;\npath(stroke: \"#0a0\", width: 0.02) { move(0.1, 0.1); cubic(0.2, a, 0.8, 1 - a, 0.9, 0.9); quad(0.5, 0.5, 0.1, 0.9); }\npath(fill: \"#00f\") { move(0.2, 0.2); line(0.8, 0.2); line(0.5, 0.8); close(); }\n",
    "param x in [0, 1] = 0.5;\nint param n in [1, 4] = 3;\nfn f(k) { if k % 2 == 0 { return k * 0.1; } else { return 0.05; } }\nfor i in 0..n { point(x, f(i), stroke: \"red\", width: 0.02); line(0, i / n, 1, x, stroke: \"green\"); }\n",
    "param t in [-1, 1] = 0.2;\nlet s = sin(t) + cos(t) + tan(t / 4) + atan(t) + atan2(t, 1) + sqrt(abs(t)) + exp(t) + ln(2 + t);\nlet u = floor(s) + ceil(s) + round(s) + pow(2, t) + mod(5, 3) + hypot(t, 1) + min(t, 0.5, s) + max(t, -0.5);\ncircle(clamp(t, 0.2, 0.8), lerp(0.2, 0.8, 0.5), 0.05 + 0.01 * select(t, u, s) / (1 + abs(u)), fill: rgb(10, 20, 30));\n",
    "background \"#eee\";\nparam a in [0, 6.3] = 1;\nfn flower(n) { for k in 0..n { rotate(k * 2 * PI / n + a) { translate(0.1, 0) { scale(0.5) { circle(0, 0, 0.05, fill: \"#f0f\"); } } } } }\ntranslate(0.5, 0.5) { flower(6); }\n",
    "param a in [0, 1] = 0.5;\nint param d in [0, 3] = 2;\nfn rec(k) { if k > 0 { translate(0.1, 0.1) { rec(k - 1); } } else { circle(a, a, 0.1, fill: \"#000\"); } }\nrec(d);\nif d < 2 && !(d == 7) || d >= 1 { rect(0.5, 0.5, 0.1, 0.1, fill: \"#fff\", stroke: \"#000\"); }\n",
    "param a in [0, 1] = 0.5;\nlet k = 0;\nfor i in 0..10 { k = k + i ^ 2; }\nsegment(0, 0, a, k / 300, stroke: \"#abc\", width: 0.03);\n",
];

/// Writes the seed inputs of every corpus (`fuzz/corpus/<target>/seed-*`)
/// from the shipped programs, fixture images and strokes. Run by hand
/// (`cargo test --test integration -- --ignored fuzz_corpus::write_seeds`) before
/// fuzzing afresh; `cargo fuzz cmin` then keeps what adds coverage.
#[test]
#[ignore]
fn write_seeds() {
    use filigree::pattern::generators::{generator, GENERATORS};
    use serde_json::json;
    use std::io::Cursor;
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let put = |target: &str, name: &str, bytes: &[u8]| {
        let dir = root.join("fuzz/corpus").join(target);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join(format!("seed-{name}")), bytes).unwrap();
    };
    let file = |p: &str| std::fs::read(root.join(p)).unwrap();

    // lang: every shipped program and the feature tour above.
    for g in GENERATORS {
        put("lang", &format!("{}.flg", g.name), g.source.as_bytes());
    }
    for (i, p) in SEED_PROGRAMS.iter().enumerate() {
        put("lang", &format!("tour-{i}.flg"), p.as_bytes());
    }

    // image: fixtures as they are, and re-encoded in every decoded format.
    let rgba = |p: &str| image::load_from_memory(&file(p)).unwrap().to_rgba8();
    let encode = |img: image::DynamicImage, f: image::ImageFormat| {
        let mut out = Cursor::new(vec![]);
        img.write_to(&mut out, f).unwrap();
        out.into_inner()
    };
    for p in [
        "assets/pixel/fish_scale.png",
        "assets/pixel/bark_scale.png",
        "assets/pixel/fish.png",
        "assets/pixel/trunk_boundary.png",
    ] {
        let name = Path::new(p).file_name().unwrap().to_str().unwrap();
        put("image", name, &file(p));
    }
    let scale = rgba("assets/pixel/fish_scale.png");
    let dynimg = image::DynamicImage::ImageRgba8(scale.clone());
    put(
        "image",
        "fish_scale.jpg",
        &encode(
            image::DynamicImage::ImageRgb8(dynimg.to_rgb8()),
            image::ImageFormat::Jpeg,
        ),
    );
    for (ext, f) in [
        ("gif", image::ImageFormat::Gif),
        ("bmp", image::ImageFormat::Bmp),
        ("webp", image::ImageFormat::WebP),
    ] {
        put(
            "image",
            &format!("fish_scale.{ext}"),
            &encode(dynimg.clone(), f),
        );
    }
    let gradient = image::RgbaImage::from_fn(64, 48, |x, y| {
        image::Rgba([(x * 4) as u8, (y * 5) as u8, 128, (255 - x) as u8])
    });
    put(
        "image",
        "gradient-translucent.png",
        &encode(
            image::DynamicImage::ImageRgba8(gradient),
            image::ImageFormat::Png,
        ),
    );
    let one = image::RgbaImage::from_pixel(1, 1, image::Rgba([1, 2, 3, 255]));
    put(
        "image",
        "one-pixel.png",
        &encode(
            image::DynamicImage::ImageRgba8(one),
            image::ImageFormat::Png,
        ),
    );

    // strokes: the shipped strokes files and small edge cases on a 32² image.
    put(
        "strokes",
        "fish.json",
        &file("assets/pixel/fish_strokes.json"),
    );
    put(
        "strokes",
        "trunk.json",
        &file("assets/pixel/trunk_strokes.json"),
    );
    for (name, s) in [
        ("empty.json", r#"{"strokes": []}"#),
        ("dot.json", r#"{"strokes": [[[5, 5]], [[6, 6], [6, 6]]]}"#),
        (
            "small.json",
            r#"{"strokes": [[[2, 2], [30, 30], [2.5, 29.5]], [[16, 0], [16, 32]]]}"#,
        ),
        ("edge.json", r#"{"strokes": [[[-1, -1], [33, 33]]]}"#),
        ("huge.json", r#"{"strokes": [[[1e39, 0], [0, 0]]]}"#),
    ] {
        put("strokes", name, s.as_bytes());
    }

    // requests: one minimal payload per kind (first byte = kind index).
    let kind = |k: &str| bodies::REQUEST_KINDS.iter().position(|n| *n == k).unwrap() as u8;
    let req = |name: &str, k: &str, payload: serde_json::Value| {
        let mut b = vec![kind(k)];
        b.extend(serde_json::to_vec(&payload).unwrap());
        put("requests", name, &b);
    };
    let bark = file("assets/pixel/bark_scale.png");
    let png = |img: image::RgbaImage| {
        encode(
            image::DynamicImage::ImageRgba8(img),
            image::ImageFormat::Png,
        )
    };
    let tiny_source = png(image::RgbaImage::from_fn(8, 8, |x, y| {
        if x == 0 || y == 7 {
            image::Rgba([0, 0, 0, 255])
        } else {
            image::Rgba([180, (x * 20) as u8, 40, 255])
        }
    }));
    let tiny_sprite = png(image::RgbaImage::from_fn(3, 3, |x, y| {
        image::Rgba([255, 255, 255, if x == 1 || y == 1 { 255 } else { 0 }])
    }));
    req(
        "inspect.json",
        "inspect",
        json!({"bytes": bark, "tolerance": 30}),
    );
    req(
        "decode-image.json",
        "decode-image",
        json!({"bytes": tiny_source}),
    );
    req(
        "pixel-mask.json",
        "pixel-mask",
        json!({"bytes": tiny_sprite}),
    );
    let mask = json!({"width": 8, "height": 8, "bits": vec![1u8; 64]});
    req(
        "pixel-sprite.json",
        "pixel",
        json!({"source": tiny_source, "mask": mask, "sprite": tiny_sprite,
               "strokes": [[[1, 1], [7, 6]]], "params": {"positions": "packed", "seed": 3}}),
    );
    req(
        "pixel-sheet.json",
        "pixel",
        json!({"source": tiny_source, "mask": mask, "sheet": file("assets/pixel/fish_scale.png"),
               "params": {"partial": true, "margins": [-1, -1], "colour": "hsv"}}),
    );
    let grid = generator("circles-grid").unwrap().source;
    let small =
        json!({"grid": 16, "population": 6, "generations": 1, "candidates": 1, "iterations": 3});
    let mut fit = json!({"program": grid, "target_params": {"r": 0.05}});
    fit.as_object_mut()
        .unwrap()
        .extend(small.as_object().unwrap().clone());
    req("fit-params.json", "fit", fit.clone());
    let rendered =
        filigree::pattern::api::start_render(filigree::pattern::api::RenderPatternRequest {
            program: grid.into(),
            params: [("r".to_string(), 0.06)].into(),
            size: 16,
            height: None,
            supersample: 1,
        })
        .and_then(filigree::core::job::run_quietly)
        .unwrap();
    let rendered_image =
        filigree::raster::Rgba8Image::from_raw(16, 16, rendered.image.rgba.clone()).unwrap();
    let mut fit_png = fit.clone();
    fit_png["target_params"] = serde_json::Value::Null;
    fit_png["target_png"] = json!(filigree::raster::encode_png(&rendered_image).unwrap());
    fit_png["loss"] = json!("l1");
    fit_png["init"] = json!("nelder-mead");
    req("fit-png.json", "fit", fit_png);
    let mut fit_rgba = fit.clone();
    fit_rgba["target_params"] = serde_json::Value::Null;
    fit_rgba["target_rgba"] =
        json!({"width": 16, "height": 16, "rgba": rendered.image.rgba.clone()});
    fit_rgba["shards"] = json!([1, 2]);
    fit_rgba["polish"] = json!(2);
    req("fit-rgba.json", "fit", fit_rgba);
    let mut eval = fit.clone();
    eval["points"] = json!([
        [0.2, 0.17, 0.12, 0.12, 0.05],
        [0.13, 0.13, 0.06, 0.06, 0.03]
    ]);
    req("fit-eval.json", "fit-eval", eval);
    req(
        "render-pattern.json",
        "render-pattern",
        json!({"program": generator("honeycomb").unwrap().source, "size": 24, "supersample": 2}),
    );
    req(
        "pattern-info.json",
        "pattern-info",
        json!({"program": generator("spades").unwrap().source, "params": {"angle": 0.2}}),
    );
    req("pattern-generators.json", "pattern-generators", json!({}));
    req(
        "pattern-snap.json",
        "pattern-snap",
        json!({"program": grid, "bytes": filigree::raster::encode_png(&rendered_image).unwrap(),
               "size": 8, "tolerance": 40}),
    );
    req("defaults.json", "defaults", json!({"tool": "fit"}));
    let inspect_state = json!({"name": "fish.png", "bytes": file("assets/pixel/fish.png")});
    req(
        "check-state.json",
        "check-state",
        json!({"tool": "inspect", "version": 1, "state": inspect_state}),
    );
    let mut fit_state = app_projects::fit_doc("circles-grid", false);
    fit_state["result"] = json!({"params": [0.1], "loss": 0.5, "names": ["r"]});
    req(
        "check-state-fit.json",
        "check-state",
        json!({"tool": "fit", "version": 1, "state": fit_state}),
    );
    req(
        "open-project.json",
        "open-project",
        json!({"text": app_projects::project_text("inspect", 1, app_projects::inspect_doc())}),
    );

    // project: files as the app saves them (the fish and trunk examples,
    // Fit before and after a fit, Inspect), one saved from the running app,
    // a format-1 file, and two small broken ones.
    let text = |name: &str, t: String| put("project", name, t.as_bytes());
    for ex in ["fish", "trunk"] {
        text(
            &format!("pixel-{ex}.filigree.json"),
            app_projects::project_text("pixel", 1, app_projects::pixel_example(ex)),
        );
    }
    text(
        "fit-stripes.filigree.json",
        app_projects::project_text("fit", 1, app_projects::fit_doc("stripes", false)),
    );
    let mut fitted = app_projects::fit_doc("honeycomb", false);
    let values = fitted["values"].clone();
    fitted["truth"] = values.clone();
    fitted["result"] = json!({"params": values, "loss": 0.02, "names": ["a"], "evaluations": 9});
    text(
        "fit-fitted-no-target.filigree.json",
        app_projects::project_text("fit", 1, fitted),
    );
    text(
        "inspect.filigree.json",
        app_projects::project_text("inspect", 1, app_projects::inspect_doc()),
    );
    put(
        "project",
        "saved-by-app-fish.filigree.json",
        &file("tests/fixtures/fish.filigree.json"),
    );
    for (name, image) in [("texture-model", false), ("texture-image", true)] {
        text(
            &format!("{name}.filigree.json"),
            app_projects::project_text("texture", 1, app_projects::texture_doc(image)),
        );
    }
    let v1 = json!({"format": "filigree-project", "version": 1, "tool": "inspect",
                    "state": {"name": null, "bytes": null}});
    text("format-1.filigree.json", v1.to_string());
    text("not-json.filigree.json", "hello".into());
    let mut small = app_projects::pixel_example("fish");
    small["mask"] = json!({"width": 2, "height": 1, "bits": {"$bytes": "AQA="}});
    small["strokes"] = json!([[[0, 0], [2, 1]]]);
    text(
        "pixel-small.filigree.json",
        app_projects::project_text("pixel", 1, small),
    );

    // micro_scene: the shipped scenes and a few edges; requests: one
    // render and one slice.
    for name in [
        "gyroid",
        "spheres",
        "fibres",
        "agglomerate",
        "piled",
        "multiscale",
    ] {
        let scene = file(&format!("assets/micro/{name}.json"));
        put("micro_scene", &format!("{name}.json"), &scene);
    }
    for (name, s) in [
        (
            "transform-matrix.json",
            r#"{"type": "transform", "matrix": [[1, 0.5, 0], [0, 1, 0], [0, 0, 3]], "child": {"type": "periodic", "terms": [[{"wave": "sin", "axis": "x", "freq": 1e5, "power": 8}]]}}"#,
        ),
        (
            "huge-values.json",
            r#"{"type": "difference", "base": {"type": "box", "half": [1e6, 1e6, 1e6]}, "minus": [{"type": "lattice", "cell": 1e-6, "radius": 1, "jitter": 0.5, "select": {"terms": [{"poly": [{"c": 9223372036854775807, "x": 8, "y": 8, "z": 8}], "modulus": 2147483648, "classes": [{"residue": -1}]}]}}]}"#,
        ),
        (
            "deep.json",
            &format!(
                "{}{{\"type\": \"sphere\", \"radius\": 1}}{}",
                "{\"type\": \"shell\", \"thickness\": 0.01, \"child\": ".repeat(30),
                "}".repeat(30)
            ),
        ),
        (
            "pile-steep.json",
            r#"{"type": "pile", "angle": {"gradient": [1e6, 0, 0]}, "extent": 1e6}"#,
        ),
        (
            "particles-everything.json",
            r#"{"type": "particles", "cell": 0.01, "size": {"dist": "normal", "mean": 0.2, "std": 1, "max": 0.45}, "warp": {"amplitude": 1, "frequency": 1000}, "shapes": [{"shape": "red_blood_cell", "weight": 0}, {"shape": "torus", "ratio": 1}]}"#,
        ),
    ] {
        put("micro_scene", name, s.as_bytes());
    }
    let scene = String::from_utf8(file("assets/micro/spheres.json")).unwrap();
    req(
        "micro-render.json",
        "micro-render",
        json!({"scene": scene, "width": 8, "height": 6, "steps": "adaptive"}),
    );
    req(
        "micro-slice.json",
        "micro-slice",
        json!({"scene": scene, "width": 8, "height": 6, "z": 0.3}),
    );
    req("micro-examples.json", "micro-examples", json!({}));
    req(
        "micro-glsl.json",
        "micro-glsl",
        json!({"scene": scene, "width": 8, "height": 6, "steps": "bisection"}),
    );
    req("texture-models.json", "texture-models", json!({}));
    req(
        "texture-render.json",
        "texture-render",
        json!({"model": "perlin", "size": 16, "seed": 3}),
    );
    req(
        "texture-index.json",
        "texture-index",
        json!({"bytes": b"FILIGREE-TEXIDX\0\x01\0\0\0".to_vec()}),
    );
    req(
        "texture-analyse.json",
        "texture-analyse",
        json!({"index": "0000000000000000", "bytes": [137, 80, 78, 71]}),
    );
    req(
        "texture-retrieve.json",
        "texture-retrieve",
        json!({"index": "0", "scales": [5, 5, 5, 5, 5, 5, 5, 5, 5, 5, 5, 9], "size": 0}),
    );
    let g = r#"{"type": "tpms", "surface": "gyroid", "period": 0.5, "thickness": 0.35}"#;
    let t = r#"{"type": "tpms", "surface": "gyroid", "period": 0.4, "thickness": 0.35}"#;
    req(
        "micro-fit.json",
        "micro-fit",
        json!({"scene": g, "params": [{"pointer": "/period", "lo": 0.2, "hi": 0.8}],
               "target": {"kind": "scene", "scene": t}, "grid": 4, "budget": 6, "population": 3}),
    );
    req(
        "micro-fit-powell-tied.json",
        "micro-fit",
        json!({"scene": g, "params": [{"pointer": "/period", "lo": 0.2, "hi": 0.8, "also": ["/thickness"]}],
               "target": {"kind": "volume", "values": vec![0.1; 64]}, "grid": 4, "budget": 5,
               "optimizer": "powell", "shards": [1, 2]}),
    );
    req(
        "micro-fit-image.json",
        "micro-fit",
        json!({"scene": g, "params": [{"pointer": "/thickness", "lo": 0, "hi": 3}],
               "target": {"kind": "image", "scene": t}, "budget": 3, "optimizer": "nelder-mead",
               "render": {"width": 4, "height": 4}}),
    );
    req(
        "micro-fit-bad.json",
        "micro-fit",
        json!({"scene": g, "params": [{"pointer": "/surface", "lo": 1, "hi": 0}],
               "target": {"kind": "slices", "pngs": [[1, 2, 3]], "range": -1}, "grid": 3}),
    );
}
