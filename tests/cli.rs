//! The `filigree` binary end to end: arguments in, files and JSON out.
use std::process::Command;

fn filigree(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_filigree"))
        .args(args)
        .output()
        .expect("run filigree")
}

#[test]
fn version_and_help() {
    let out = filigree(&["--version"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains(env!("CARGO_PKG_VERSION")));
    let help = String::from_utf8_lossy(&filigree(&["--help"]).stdout).to_string();
    assert!(help.contains("inspect"), "{help}");
}

#[test]
fn a_reader_that_stops_early_ends_the_output_quietly() {
    // `filigree render --print-request … | head -c 0`: the reader is gone
    // before the first line is written. A Unix tool then stops as if killed
    // by SIGPIPE; it used to panic with "failed printing to stdout".
    let mut child = Command::new(env!("CARGO_BIN_EXE_filigree"))
        .args([
            "render",
            "--program",
            "circles-grid",
            "--out",
            "x.png",
            "--print-request",
        ])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run filigree");
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(
        matches!(out.status.code(), Some(0) | Some(141)),
        "{:?} {stderr}",
        out.status
    );
}

#[test]
fn inspect_json_reports_size_and_palette() {
    let out = filigree(&["inspect", "tests/fixtures/fish.png", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["width"], 128);
    assert_eq!(v["height"], 128);
    assert_eq!(v["colour_count"], 3);
    assert_eq!(
        v["palette"][0]["rgba"],
        serde_json::json!([82, 99, 202, 255])
    );
}

#[test]
fn inspect_errors_name_the_file_and_the_problem() {
    let dir = std::env::temp_dir().join(format!("filigree-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.png");
    std::fs::write(&bad, b"not a png at all").unwrap();
    let out = filigree(&["inspect", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.png") && err.contains("not an image"),
        "{err}"
    );
    let out = filigree(&["inspect", "does/not/exist.png"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("does/not/exist.png"));
}

// ------------------------------------------------------------------
// One request layer: the CLI builds the browser's request structs.

fn print_request(args: &[&str]) -> serde_json::Value {
    let mut a = args.to_vec();
    a.push("--print-request");
    let out = filigree(&a);
    assert!(
        out.status.success(),
        "{:?}: {}",
        args,
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

/// The request a browser gets from `payload` (deserialised like the worker does).
fn browser<T: serde::de::DeserializeOwned>(kind: &str, payload: serde_json::Value) -> T {
    filigree::api::request(kind, payload).unwrap()
}

fn cli<T: serde::de::DeserializeOwned>(kind: &str, args: &[&str]) -> T {
    filigree::api::request(kind, print_request(args)).unwrap()
}

fn bytes(path: &str) -> serde_json::Value {
    serde_json::to_value(std::fs::read(path).unwrap()).unwrap()
}

/// For every tool the CLI serves, the request it builds from minimal
/// arguments equals the request a browser gets from a minimal payload: the
/// defaults are the same (they are defined once, in the request types).
#[test]
fn cli_and_browser_default_requests_are_identical() {
    use filigree::api::inspect::InspectRequest;
    use filigree::pattern::api::{FitRequest, RenderPatternRequest};
    use filigree::pixel::api::{mask_bits, PixelMaskRequest, PixelRequest};
    use serde_json::json;

    let fish = "tests/fixtures/fish.png";
    let a: InspectRequest = cli("inspect", &["inspect", fish]);
    let b: InspectRequest = browser("inspect", json!({ "bytes": bytes(fish) }));
    assert_eq!(a, b);
    assert_eq!(a.tolerance, 24.0);

    let src = filigree::pattern::generators::generator("circles-grid")
        .unwrap()
        .source;
    let a: FitRequest = cli(
        "fit",
        &["fit", "--program", "circles-grid", "--target", fish],
    );
    let b: FitRequest = browser("fit", json!({ "program": src, "target_png": bytes(fish) }));
    assert_eq!(a, b);
    assert_eq!(a.budget, filigree::pattern::fit::Budget::Quick);

    let a: RenderPatternRequest = cli(
        "render-pattern",
        &["render", "--program", "circles-grid", "--out", "x.png"],
    );
    let b: RenderPatternRequest = browser("render-pattern", json!({ "program": src }));
    assert_eq!(a, b);
    assert_eq!((a.size, a.supersample), (512, 1));

    let dir = "assets/pixel";
    let p = |f: &str| format!("{dir}/{f}");
    let (source, mask, sheet, strokes) = (
        p("fish.png"),
        p("fish_body_boundary.png"),
        p("fish_scale.png"),
        p("fish_strokes.json"),
    );
    let a: PixelRequest = cli(
        "pixel",
        &[
            "pixel",
            "--source",
            &source,
            "--mask",
            &mask,
            "--sheet",
            &sheet,
            "--strokes",
            &strokes,
            "--out",
            "x.png",
        ],
    );
    // The browser turns a mask file into bits with `pixel-mask` first.
    let bits = mask_bits(&PixelMaskRequest {
        bytes: std::fs::read(&mask).unwrap(),
    })
    .unwrap();
    let strokes: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&strokes).unwrap()).unwrap();
    let b: PixelRequest = browser(
        "pixel",
        json!({
            "source": bytes(&source),
            "mask": bits,
            "sheet": bytes(&sheet),
            "strokes": strokes["strokes"],
        }),
    );
    assert_eq!(a, b);
    assert_eq!(a.params, filigree::pixel::PixelParams::default());
}

/// Flags go through the same request fields: aliases, units and values.
#[test]
fn cli_flags_map_onto_request_fields() {
    let v = print_request(&[
        "fit",
        "--program",
        "circles-grid",
        "--target-params",
        "{}",
        "--init",
        "nm",
        "--units",
        "canvas",
        "--budget",
        "paper",
        "--tolerance",
        "12",
    ]);
    assert_eq!(v["init"], "nelder-mead");
    assert_eq!(v["units"], "canvas");
    assert_eq!(v["budget"], "paper");
    assert_eq!(v["tolerance"], 12.0);
    let v = print_request(&[
        "pixel",
        "--source",
        "assets/pixel/fish.png",
        "--mask",
        "assets/pixel/fish_body_boundary.png",
        "--sheet",
        "assets/pixel/fish_scale.png",
        "--strokes",
        "assets/pixel/fish_strokes.json",
        "--out",
        "x.png",
        "--dmax",
        "7",
        "--margins",
        "-1,-1",
        "--density",
        "80%",
        "--exclude",
        "none",
    ]);
    assert_eq!(v["params"]["d_max"], 7.0);
    assert_eq!(v["params"]["margins"], serde_json::json!([-1, -1]));
    assert_eq!(v["params"]["density"], 0.8);
    assert_eq!(v["params"]["exclude"], serde_json::json!([]));
}

/// Every numeric flag is checked where it enters, and the message names it.
#[test]
fn bad_numbers_are_rejected_with_the_flag_named() {
    let fish = "tests/fixtures/fish.png";
    for (args, want) in [
        (
            vec![
                "fit",
                "--program",
                "circles-grid",
                "--target",
                fish,
                "--tolerance",
                "NaN",
            ],
            "--tolerance",
        ),
        (
            vec![
                "fit",
                "--program",
                "circles-grid",
                "--target",
                fish,
                "--tolerance",
                "-5",
            ],
            "`tolerance` must be a finite number in 0..=442 (got -5)",
        ),
        (
            vec![
                "fit",
                "--program",
                "circles-grid",
                "--target",
                fish,
                "--threads",
                "20000",
            ],
            "--threads: `threads` must be in 1..=64 (got 20000)",
        ),
        (
            vec![
                "fit",
                "--program",
                "circles-grid",
                "--target",
                fish,
                "--grid",
                "2",
            ],
            "--grid: `grid` must be in 8..=256 (got 2)",
        ),
        // A fit's loss grid stops at 256: one gradient per step stays short
        // (at 1024 one took 300 ms in the worker).
        (
            vec![
                "fit",
                "--program",
                "circles-grid",
                "--target",
                fish,
                "--grid",
                "1024",
            ],
            "--grid: `grid` must be in 8..=256 (got 1024)",
        ),
        (
            vec![
                "fit",
                "--program",
                "circles-grid",
                "--target",
                fish,
                "--init",
                "annealing",
            ],
            "--init: `init` is 'annealing'; expected one of",
        ),
        (
            vec![
                "render",
                "--program",
                "circles-grid",
                "--out",
                "/tmp/x.png",
                "--size",
                "2",
                "--supersample",
                "9223372036854775808",
            ],
            "--supersample: `supersample` must be in 1..=4 (got 9223372036854775808)",
        ),
        (
            vec!["inspect", fish, "--tolerance", "inf"],
            "--tolerance: must be a finite number",
        ),
        (
            vec![
                "pixel",
                "--source",
                "assets/pixel/fish.png",
                "--mask",
                "assets/pixel/fish_body_boundary.png",
                "--sheet",
                "assets/pixel/fish_scale.png",
                "--strokes",
                "assets/pixel/fish_strokes.json",
                "--out",
                "/tmp/x.png",
                "--margins",
                "2147483647,0",
            ],
            "--margins: `params.margins.0` must be in -4096..=4096 (got 2147483647)",
        ),
        (
            vec![
                "pixel",
                "--source",
                "assets/pixel/fish.png",
                "--mask",
                "assets/pixel/fish_body_boundary.png",
                "--sheet",
                "assets/pixel/fish_scale.png",
                "--strokes",
                "assets/pixel/fish_strokes.json",
                "--out",
                "/tmp/x.png",
                "--dmax",
                "-3",
            ],
            "--dmax: `params.d_max` must be a finite number in 0..=1000 (got -3)",
        ),
    ] {
        let out = filigree(&args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(err.contains(want), "{args:?}: {err}");
    }
}

/// `filigree fit --out fitted.png` writes the fitted pattern as a PNG the
/// size of the target image (a non-square target too), in the pattern's
/// colours, and `--svg` / `--out x.svg` write SVGs of that size.
#[test]
fn fit_writes_the_fitted_render_sized_like_the_target() {
    use filigree::raster::{decode, encode_png, Limits, Rgba8Image};
    let dir = std::env::temp_dir().join(format!("filigree-fit-out-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let p = |name: &str| dir.join(name).to_str().unwrap().to_string();
    // A 96 × 80 target: white with dark-blue dots roughly on circles-grid's lattice.
    let (w, h) = (96u32, 80u32);
    let mut img = Rgba8Image::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let (u, v) = ((x as f64 + 0.5) / w as f64, (y as f64 + 0.5) / h as f64);
            let (fu, fv) = ((u - 0.1) / 0.2, (v - 0.1) / 0.2);
            let d = ((fu - fu.round()) * 0.2).hypot((fv - fv.round()) * 0.2);
            let c = if d < 0.05 {
                [0x1f, 0x4e, 0x79, 255]
            } else {
                [255, 255, 255, 255]
            };
            img.put(x, y, c);
        }
    }
    std::fs::write(p("target.png"), encode_png(&img).unwrap()).unwrap();
    let out = filigree(&[
        "fit",
        "--program",
        "circles-grid",
        "--target",
        &p("target.png"),
        "--grid",
        "32",
        "--seed",
        "2",
        "--threads",
        "1",
        "--json",
        "--out",
        &p("fitted.png"),
        "--svg",
        &p("fitted.svg"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let fitted = decode(&std::fs::read(p("fitted.png")).unwrap(), Limits::default()).unwrap();
    assert_eq!((fitted.width, fitted.height), (w, h));
    let (mut bg, mut fg) = (0, 0);
    for px in fitted.data.chunks(4) {
        match px {
            [255, 255, 255, 255] => bg += 1,
            [0x1f, 0x4e, 0x79, 255] => fg += 1,
            other => panic!("colour {other:?} is not in the circles-grid palette"),
        }
    }
    assert!(bg > fg && fg > 100, "{bg} background and {fg} dot pixels");
    let svg = std::fs::read_to_string(p("fitted.svg")).unwrap();
    assert!(
        svg.starts_with("<svg") && svg.contains("width=\"96\" height=\"80\""),
        "{}",
        &svg[..200.min(svg.len())]
    );
    assert!(svg.contains("<circle"));
    // Without a target image (drawn from parameters): 512 px.
    let out = filigree(&[
        "fit",
        "--program",
        "circles-grid",
        "--target-params",
        r#"{"r": 0.05}"#,
        "--grid",
        "16",
        "--threads",
        "1",
        "--json",
        "--out",
        &p("params.svg"),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let svg = std::fs::read_to_string(p("params.svg")).unwrap();
    assert!(
        svg.contains("width=\"512\" height=\"512\""),
        "{}",
        &svg[..200.min(svg.len())]
    );
    // A wrong extension is refused before the fit runs.
    let out = filigree(&[
        "fit",
        "--program",
        "circles-grid",
        "--target",
        &p("target.png"),
        "--out",
        &p("fitted.jpg"),
    ]);
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("name the file with .png or .svg"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `filigree fit --help` documents the defaults that make a fit work
/// without flags, and the time bound and polish flags reach the request.
#[test]
fn fit_help_documents_the_defaults_and_the_flags_reach_the_request() {
    let help = String::from_utf8_lossy(&filigree(&["fit", "--help"]).stdout).to_string();
    for want in [
        "--max-seconds",
        "--polish 100",
        "longer side, 32..=128",
        "--out",
    ] {
        assert!(help.contains(want), "{want} missing from:\n{help}");
    }
    let v = print_request(&[
        "fit",
        "--program",
        "circles-grid",
        "--target-params",
        "{}",
        "--max-seconds",
        "5",
        "--polish",
        "0",
    ]);
    assert_eq!(v["max_seconds"], 5.0);
    assert_eq!(v["polish"], 0);
    // Without the flags: the request's own defaults (none sent, as the browser does).
    let v = print_request(&["fit", "--program", "circles-grid", "--target-params", "{}"]);
    assert_eq!(v["max_seconds"], 30.0);
    assert!(v["polish"].is_null() && v["grid"].is_null(), "{v}");
}

/// Issue 34 (hostile and careless inputs through the CLI): each is refused
/// with a message naming what to change, before any work, and never by a
/// crash (each of these aborted, ran for minutes or wrote nothing before).
#[test]
fn outputs_and_sizes_are_checked_before_the_work_starts() {
    let dir = std::env::temp_dir().join(format!("filigree-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let target = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/fixtures/fish.png");
    // Each message is the up-front check's own, so the refusal came before
    // any work (not after a fit or a 40 GB allocation).
    let refused = |args: &[&str], why: &str| {
        let out = filigree(args);
        let err = String::from_utf8_lossy(&out.stderr).to_string();
        assert!(!out.status.success(), "{args:?} succeeded");
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(why), "{args:?}: {err}");
    };
    // A sheet of 20,000 px cells allocated 40 GB before its range check.
    refused(
        &["texture", "sheet", "--size", "20000", "--out", "/tmp/s.png"],
        "--size: a sheet cell is 8..=512 pixels (got 20000)",
    );
    // A fit whose output folder does not exist failed only after the fit.
    refused(
        &[
            "fit",
            "--program",
            "stripes",
            "--target",
            target,
            "--out",
            "/nonexistent/x.png",
            "--json",
        ],
        "the folder /nonexistent does not exist",
    );
    refused(
        &[
            "fit",
            "--program",
            "stripes",
            "--target",
            target,
            "--svg",
            "/nonexistent/x.svg",
        ],
        "the folder /nonexistent does not exist",
    );
    // PNG bytes were written to a .jpg.
    let jpg = dir.join("x.jpg");
    refused(
        &[
            "micro",
            "render",
            "--scene",
            concat!(env!("CARGO_MANIFEST_DIR"), "/assets/micro/gyroid.json"),
            "--out",
            jpg.to_str().unwrap(),
        ],
        "name the file with .png",
    );
    refused(
        &[
            "texture",
            "render",
            "--model",
            "perlin",
            "--out",
            jpg.to_str().unwrap(),
        ],
        "name the file with .png",
    );
    // `--size 0` with `--out` exited 0 and wrote nothing.
    let png = dir.join("retrieved.png");
    refused(
        &[
            "texture",
            "--index",
            concat!(env!("CARGO_MANIFEST_DIR"), "/assets/texture-index.bin"),
            "--image",
            target,
            "--out",
            png.to_str().unwrap(),
            "--size",
            "0",
        ],
        "--size: the retrieved texture",
    );
    assert!(!png.exists());
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 34 item 1: 12,000 nested groups overflowed the CLI's stack in the
/// SVG reader (exit 134); now a clear refusal.
#[test]
fn a_deeply_nested_svg_start_is_refused_not_a_crash() {
    let dir = std::env::temp_dir().join(format!("filigree-deep-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let svg = dir.join("deep.svg");
    std::fs::write(
        &svg,
        format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\">{}<rect width=\"10\" height=\"10\"/>{}</svg>",
            "<g transform=\"scale(1)\">".repeat(12_000),
            "</g>".repeat(12_000)
        ),
    )
    .unwrap();
    let out = filigree(&[
        "tangle",
        "--grammar",
        concat!(env!("CARGO_MANIFEST_DIR"), "/assets/tangle/leaf.tangle"),
        "--start",
        svg.to_str().unwrap(),
        "--out",
        dir.join("x.svg").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("nests elements more than 256 deep"), "{err}");
    std::fs::remove_dir_all(&dir).ok();
}

/// Issue 34 item 4: values outside their range were clamped without a
/// word (`angle` 100 drew angle 0.5; `frequency=1e308` drew 24); now each
/// is an error naming the field, the range and the value (short).
#[test]
fn out_of_range_values_are_errors_naming_the_range() {
    let err = |args: &[&str]| {
        let out = filigree(args);
        assert_eq!(out.status.code(), Some(1), "{args:?}");
        String::from_utf8_lossy(&out.stderr).to_string()
    };
    let e = err(&[
        "render",
        "--program",
        "stripes",
        "--params",
        r#"{"angle":100}"#,
        "--out",
        "/tmp/x.png",
    ]);
    assert!(
        e.contains("`params.angle` is 100; the program declares 'angle' in [-0.5, 0.5]"),
        "{e}"
    );
    let e = err(&[
        "fit",
        "--program",
        "stripes",
        "--target-params",
        r#"{"angle":99}"#,
    ]);
    assert!(e.contains("`target_params.angle` is 99"), "{e}");
    let e = err(&[
        "texture",
        "render",
        "--model",
        "perlin",
        "--param",
        "frequency=1e308",
        "--out",
        "/tmp/x.png",
    ]);
    assert!(
        e.contains("--param frequency: ") && e.contains("outside the model's range"),
        "{e}"
    );
    assert!(
        e.len() < 200,
        "a 309-digit number is not echoed in full: {e}"
    );
    // Not JSON and not a file: said so, not "No such file or directory".
    for bad in ["[1,2]", "garbage{", "null"] {
        let e = err(&[
            "render",
            "--program",
            "stripes",
            "--params",
            bad,
            "--out",
            "/tmp/x.png",
        ]);
        assert!(
            e.contains("--params:") && !e.contains("No such file"),
            "{bad}: {e}"
        );
    }
}
