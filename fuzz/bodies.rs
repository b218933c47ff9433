//! The bodies of the fuzz targets, shared by `fuzz/fuzz_targets/*.rs`
//! (cargo-fuzz on nightly) and `tests/fuzz_corpus.rs` (which replays every
//! corpus file through the same code on stable, so `cargo test` keeps the
//! corpora as regression tests without fuzzing).
//!
//! Each body takes raw bytes and runs them through the code a user's input
//! reaches. Errors are fine; a panic, a hang, a stack overflow or a result
//! that silently misleads (non-finite numbers in a drawing or a loss) is a
//! finding. Work is bounded the way the product bounds it: default limits
//! everywhere, and a stepped job is stepped at most [`MAX_STEPS`] times
//! (each step is meant to be a bounded slice; the rest is more of the same).
#![allow(dead_code)]

use filigree::api::Response;
use filigree::core::job::{run_quietly, Job, Step};
use filigree::pattern::api::{
    self as pattern_api, EvalPoints, FitEvalRequest, PatternInfoRequest, RenderPatternRequest,
};
use filigree::raster::{decode, Limits, Rgba8Image};
use serde::Deserialize;
use std::collections::BTreeMap;

/// Steps a fuzzed stepped job may take before it is dropped.
pub const MAX_STEPS: usize = 16;

/// A fuzz target's body.
pub type Body = fn(&[u8]);

/// Every target: name (= `fuzz/corpus/<name>/`) and body.
pub const TARGETS: &[(&str, Body)] = &[
    ("lang", lang),
    ("image", image),
    ("strokes", strokes),
    ("requests", requests),
    ("project", project),
    ("tangle_grammar", tangle_grammar),
    ("tangle_start", tangle_start),
    ("inset", inset),
    ("micro_scene", micro_scene),
    ("texture_ratings", texture_ratings),
    ("texture_index", texture_index),
];

fn finite_svg(svg: &str, what: &str) {
    assert!(
        !svg.contains("NaN") && !svg.contains("inf"),
        "{what}: the SVG has non-finite numbers: {svg}"
    );
}

/// The pattern language: parse and record under the default limits (via
/// `pattern-info`), draw at a tiny size (raster with supersampling, and the
/// SVG), and evaluate the loss against the program's own drawing at its
/// defaults and at a moved point (via `fit-eval` on an 8² grid).
pub fn lang(data: &[u8]) {
    let Ok(src) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(info) = pattern_api::program_info(&PatternInfoRequest {
        program: src.into(),
        params: BTreeMap::new(),
    }) else {
        return;
    };
    let render = RenderPatternRequest {
        program: src.into(),
        size: 12,
        supersample: 2,
        ..Default::default()
    };
    if let Ok(r) = pattern_api::start_render(render).and_then(run_quietly) {
        assert_eq!((r.image.width, r.image.height), (12, 12));
        assert_eq!(r.image.rgba.len(), 12 * 12 * 4);
        finite_svg(&r.svg, "render-pattern");
    }
    // The same program on a canvas that is not square ([0, 1.33] × [0, 1]).
    let wide = RenderPatternRequest {
        program: src.into(),
        size: 12,
        height: Some(9),
        ..Default::default()
    };
    if let Ok(r) = pattern_api::start_render(wide).and_then(run_quietly) {
        assert_eq!((r.image.width, r.image.height), (12, 9));
        assert_eq!(r.image.rgba.len(), 12 * 9 * 4);
        finite_svg(&r.svg, "render-pattern (12 × 9)");
    }
    let floats: Vec<_> = info.params.iter().filter(|p| !p.integer).collect();
    if floats.is_empty() || info.shapes == 0 {
        return;
    }
    let defaults: Vec<f64> = floats.iter().map(|p| p.default).collect();
    let moved: Vec<f64> = floats.iter().map(|p| p.lo + 0.37 * (p.hi - p.lo)).collect();
    let eval = FitEvalRequest {
        program: src.into(),
        target_params: Some(BTreeMap::new()),
        grid: Some(8),
        extra: EvalPoints {
            points: vec![defaults, moved],
        },
        ..Default::default()
    };
    if let Ok(r) = pattern_api::start_eval(eval).and_then(run_quietly) {
        let losses = r.losses;
        assert!(
            losses.iter().all(|l| l.is_finite() && *l >= 0.0),
            "losses {losses:?} are not finite and non-negative"
        );
    }
}

/// Image decoding under the default limits, then what the app does with a
/// decoded image: `inspect` (palette, clusters, thumbnail), reading it as a
/// Pixel mask, and as an element sheet or sprite.
pub fn image(data: &[u8]) {
    let Ok(img) = decode(data, Limits::default()) else {
        return;
    };
    let lim = Limits::default();
    assert!(img.width >= 1 && img.height >= 1);
    assert!(img.width <= lim.max_side && img.height <= lim.max_side);
    assert_eq!(img.data.len(), img.width as usize * img.height as usize * 4);
    let opts = filigree::inspect::InspectOptions::default();
    let info = filigree::inspect::inspect(data, &opts).expect("decoded once, so it inspects");
    assert_eq!((info.width, info.height), (img.width, img.height));
    // Colours of pixels with alpha > 0: none in a fully transparent image.
    assert!(info.colour_count <= (img.width * img.height) as usize);
    let t = &info.thumbnail;
    assert_eq!(t.data.len(), t.width as usize * t.height as usize * 4);
    let mask = filigree::pixel::inputs::mask_from_image(&img);
    assert_eq!(mask.len(), (img.width * img.height) as usize);
    let _ = filigree::pixel::ElementSheet::from_sheet(&img);
    let _ = filigree::pixel::ElementSheet::from_sprite(&img, filigree::pixel::Direction8::Up);
}

/// The strokes file the `pixel` CLI reads (`{"strokes": [[[x, y], ...], ...]}`,
/// the same JSON the page keeps in a project and sends in a `pixel` request).
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StrokesFile {
    strokes: Vec<filigree::pixel::Stroke>,
}

/// A small synthetic pixel-art scene: two colours with a black outline, a
/// full mask and a 3-pixel arrow sprite.
fn tiny_scene(side: u32) -> (Rgba8Image, Rgba8Image, Rgba8Image) {
    let mut source = Rgba8Image::new(side, side);
    let mut mask = Rgba8Image::new(side, side);
    for y in 0..side {
        for x in 0..side {
            let edge = x == 0 || y == 0 || x == side - 1 || y == side - 1;
            let c = if edge {
                [0, 0, 0, 255]
            } else if (x / 4 + y / 4) % 2 == 0 {
                [200, 80, 40, 255]
            } else {
                [60, 140, 200, 255]
            };
            source.put(x, y, c);
            mask.put(x, y, [255, 255, 255, 255]);
        }
    }
    let mut sprite = Rgba8Image::new(3, 3);
    for (x, y) in [(1, 0), (0, 1), (1, 1), (2, 1), (1, 2)] {
        sprite.put(x, y, [255, 255, 255, 255]);
    }
    (source, mask, sprite)
}

/// Stroke JSON as the Pixel tool reads it: parsed like the CLI's strokes
/// file, checked and rasterised to annotations on a 128² image (K = 4), and,
/// when the strokes lie on a 32² image, a whole Pixel run with them.
pub fn strokes(data: &[u8]) {
    let Ok(f) = serde_json::from_slice::<StrokesFile>(data) else {
        return;
    };
    use filigree::pixel::orientation::{annotate, check_strokes};
    if let Ok(a) = annotate(128, 128, &f.strokes, 4) {
        assert_eq!(a.fixed.len(), 128 * 128);
        assert!(a
            .values
            .iter()
            .all(|v| v[0].is_finite() && v[1].is_finite()));
    }
    if check_strokes(32, 32, &f.strokes).is_err() {
        return;
    }
    let (source, mask, sprite) = tiny_scene(32);
    let inputs = filigree::pixel::PixelInputs {
        source,
        mask,
        elements: filigree::pixel::Elements::Sprite(sprite),
        strokes: f.strokes,
    };
    let params = filigree::pixel::PixelParams::default();
    let out = filigree::pixel::texture(inputs, params).expect("valid strokes on a valid scene");
    assert_eq!((out.image.width, out.image.height), (32, 32));
    assert!(out
        .field
        .iter()
        .all(|v| v[0].is_finite() && v[1].is_finite()));
}

/// Request kinds in the order the first byte of a `requests` input picks
/// them: the registry's own list. (Until the registry listed `defaults`,
/// `check-state` and `open-project`, this was a copy of its first ten
/// kinds; the corpus files were remapped then so each keeps its kind.)
pub const REQUEST_KINDS: &[&str] = filigree::api::KINDS;

/// Step a job at most [`MAX_STEPS`] times; `Some(output)` if it finished.
fn step_some<J: Job>(mut job: J) -> Option<J::Output> {
    for _ in 0..MAX_STEPS {
        match job.step() {
            Ok(Step::Done(out)) => return Some(out),
            Ok(Step::Running(p)) => {
                assert!(
                    p.fraction.is_finite() && (0.0..=1.0).contains(&p.fraction),
                    "progress {}",
                    p.fraction
                );
            }
            Err(_) => return None,
        }
    }
    None
}

/// One request as the worker receives it: the first byte picks the kind
/// ([`REQUEST_KINDS`], modulo their count), the rest is the JSON payload.
pub fn requests(data: &[u8]) {
    let Some((&k, json)) = data.split_first() else {
        return;
    };
    run_request(REQUEST_KINDS[k as usize % REQUEST_KINDS.len()], json);
}

/// Run one request of `kind` with a JSON `payload` through the registry the
/// worker uses (`filigree::api`), and check what it answers.
pub fn run_request(kind: &str, payload: &[u8]) {
    let mut de = serde_json::Deserializer::from_slice(payload);
    let Ok(job) = filigree::api::start(kind, &mut de) else {
        return;
    };
    let Some(out) = step_some(job) else {
        return;
    };
    match out {
        Response::Fit(r) => {
            assert!(r.result.loss.is_finite(), "fit loss {}", r.result.loss);
            finite_svg(&r.svg, "fit");
        }
        Response::Render(r) => {
            let (w, h) = (r.image.width as usize, r.image.height as usize);
            assert_eq!(r.image.rgba.len(), w * h * 4);
            finite_svg(&r.svg, "render-pattern");
        }
        Response::Snap(s) => {
            assert!((0.0..=1.0).contains(&s.unmatched), "{}", s.unmatched);
        }
        Response::Mask(m) => {
            assert_eq!(m.bits.len() as u64, m.width as u64 * m.height as u64);
        }
        Response::Generators(g) => assert!(!g.is_empty()),
        Response::TanglePng(r) => assert!(r.png.starts_with(b"\x89PNG\r\n\x1a\n")),
        _ => {}
    }
}

/// Whether two values are the same, numbers bit for bit (`-0` is not `0`).
fn same_value(a: &filigree::api::project::Value, b: &filigree::api::project::Value) -> bool {
    use filigree::api::project::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => x.to_bits() == y.to_bits(),
        (Value::List(x), Value::List(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(a, b)| same_value(a, b))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .zip(y)
                    .all(|((ka, a), (kb, b))| ka == kb && same_value(a, b))
        }
        _ => a == b,
    }
}

/// How reading a project text failed: a limit (its message), bad base64,
/// or a syntax error.
fn read_failure(e: &filigree::Error) -> String {
    use filigree::api::project::json::NOT_BASE64;
    match e.kind() {
        "limit" => e.to_string(),
        _ if e.to_string() == NOT_BASE64 => "base64".into(),
        _ => "syntax".into(),
    }
}

/// A project file as the page hands it to the core: the bytes read as text
/// the way the page's `file.text()` does (invalid UTF-8 replaced), sent as
/// an `open-project` request through the registry. What opens must be a
/// checked state that the core's own requests accept, and opening it again
/// after saving it (as the page saves) must give the very same state.
///
/// First, the stepped JSON reader `open-project` uses, with a tiny fuel a
/// step (1 to 8, from the input's length: it stops in the middle of every
/// token), must read the text exactly as serde_json reads it in one go: the
/// same value, numbers bit for bit, or the same failure.
pub fn project(data: &[u8]) {
    use filigree::api::project::json::{read_at_once, read_stepped};
    use filigree::api::project::{open_project, project_text, ProjectState, ToolState};
    let text = String::from_utf8_lossy(data);
    let fuel = 1 + data.len() % 8;
    match (read_at_once(&text), read_stepped(&text, fuel)) {
        (Ok(a), Ok(b)) => assert!(
            same_value(&a, &b),
            "the stepped reader (fuel {fuel}) read another value: {b:?}, serde_json: {a:?}"
        ),
        (Err(a), Err(b)) => assert_eq!(
            read_failure(&a),
            read_failure(&b),
            "the readers fail differently: serde_json {a}; stepped (fuel {fuel}) {b}"
        ),
        (a, b) => panic!("the readers disagree: serde_json {a:?}; stepped (fuel {fuel}) {b:?}"),
    }
    let payload = serde_json::to_vec(&serde_json::json!({ "text": text })).unwrap();
    let mut de = serde_json::Deserializer::from_slice(&payload);
    let Ok(job) = filigree::api::start("open-project", &mut de) else {
        panic!("open-project refused a well-formed payload");
    };
    let Some(Response::Project(opened)) = step_some(job) else {
        return;
    };
    let ProjectState::Checked(state) = &opened.state else {
        // Every tool is at its first state version: an older one cannot exist.
        panic!(
            "a project of state version {} came back unchecked",
            opened.state_version
        );
    };
    match state {
        ToolState::Pixel(s) => {
            let m = &s.mask;
            assert_eq!(m.bits.len() as u64, m.width as u64 * m.height as u64);
            assert!(m.bits.iter().all(|&b| b <= 1));
            for p in s.strokes.iter().flatten() {
                assert!(p[0].is_finite() && p[1].is_finite());
            }
            filigree::pixel::api::check_params(&s.params).expect("a checked state runs");
        }
        ToolState::Fit(s) => {
            assert!(s.values.iter().all(|v| v.is_finite()));
            if let Some(t) = &s.truth {
                assert_eq!(t.len(), s.values.len());
            }
        }
        ToolState::Tangle(s) => {
            assert!(s.grammar.len() <= filigree::tangle::state::MAX_GRAMMAR_BYTES);
            assert!(s.edits.len() <= filigree::tangle::api::MAX_EDITS);
            assert!(s.wobble.is_finite() && s.stroke_width.is_finite());
        }
        ToolState::Micro(s) => {
            use filigree::micro::api::{DISTANCE, PITCH};
            assert!(s.scene.len() <= filigree::core::limits::MAX_MICRO_SCENE_BYTES);
            let c = &s.camera;
            assert!(c.yaw.is_finite() && (PITCH.0..=PITCH.1).contains(&c.pitch));
            assert!((DISTANCE.0..=DISTANCE.1).contains(&c.distance));
            assert!(c.target.iter().all(|v| v.is_finite()) && s.z.is_finite());
        }
        ToolState::Texture(s) => {
            use filigree::texture::state::{Source, MAX_SOURCE_PNG};
            assert!(s.scales.iter().all(|v| (1.0..=9.0).contains(v)));
            if let Some(Source::Image { png, .. }) = &s.source {
                assert!(png.len() <= MAX_SOURCE_PNG);
            }
            // The parameters kept are ones the render request takes.
            if let Some(r) = &s.retrieved {
                let m = filigree::texture::models::lookup(&r.model).expect("a checked model");
                assert_eq!(m.check(&r.params).expect("checked params"), r.params);
                assert!(r.seed < (1 << 53));
            }
        }
        ToolState::Inspect(_) => {}
    }
    let again = project_text(&opened.tool, opened.state_version, state).expect("saves");
    let reopened = open_project(&again).expect("a saved checked state opens again");
    assert_eq!(
        reopened.state, opened.state,
        "open → save → open changed the state"
    );
}

/// A tangle grammar text (`filigree::tangle::grammar::parse`), read as the
/// editor hands it over (invalid UTF-8 replaced). An error must point
/// inside the text; a grammar must hold only what the parser promises
/// (rules within `MAX_RULES` with valid output counts, known curve and
/// shape names, finite parameters that `Op::with_param` keeps as they are),
/// and what `to_text` writes must read back to the same grammar.
pub fn tangle_grammar(data: &[u8]) {
    use filigree::tangle::ast::{CurveDef, DefKind, Grammar, Op};
    use filigree::tangle::grammar::{parse, to_text, MAX_RULES};
    let text = String::from_utf8_lossy(data);
    let g = match parse(&text) {
        Ok(g) => g,
        Err(e) => {
            if let Some((line, column)) = e.position() {
                let chars = text.split('\n').nth(line - 1).map(|l| l.chars().count());
                assert!(
                    chars.is_some_and(|n| column >= 1 && column <= n + 1),
                    "{e}: the position is outside the text"
                );
            }
            return;
        }
    };
    assert!(!g.rules.is_empty() && g.rules.len() <= MAX_RULES);
    let defined =
        |name: &str, kind: DefKind| g.defs.iter().any(|d| d.name == name && d.kind == kind);
    for d in &g.defs {
        match &d.curve {
            CurveDef::Polyline(p) => assert!(p.iter().all(|p| p.is_finite())),
            CurveDef::Zigzag { amplitude, period } | CurveDef::Wave { amplitude, period } => {
                assert!(amplitude.is_finite() && period.is_finite())
            }
            CurveDef::Arc { bulge } => assert!(bulge.is_finite()),
            _ => {}
        }
    }
    for r in &g.rules {
        let outputs = match r.op {
            Op::Outline { .. }
            | Op::Place { .. }
            | Op::Fill { .. }
            | Op::Stipple { .. }
            | Op::Invert => 2,
            _ => 1,
        };
        assert!((1..=outputs).contains(&r.outputs.len()), "{r:?}");
        match &r.op {
            Op::Split { curve, offsets, .. } => {
                assert!(curve == "line" || defined(curve, DefKind::Curve), "{r:?}");
                assert!(!offsets.is_empty());
            }
            Op::Place { shape, .. } => {
                assert!(shape == "circle" || defined(shape, DefKind::Shape), "{r:?}")
            }
            _ => {}
        }
        for p in r.op.params() {
            assert!(p.value.is_finite(), "{r:?}");
            assert_eq!(
                r.op.with_param(p.name, p.value).as_ref(),
                Some(&r.op),
                "{}",
                p.name
            );
        }
    }
    let strip = |mut g: Grammar| {
        g.defs.iter_mut().for_each(|d| d.line = 0);
        g.start.iter_mut().for_each(|s| s.line = 0);
        g.rules.iter_mut().for_each(|r| (r.line, r.column) = (0, 0));
        g
    };
    let written = to_text(&g);
    let again = parse(&written)
        .unwrap_or_else(|e| panic!("to_text wrote what parse refuses: {e}\n{written}"));
    assert_eq!(
        strip(again),
        strip(g.clone()),
        "to_text → parse changed the grammar"
    );
    // Cost oracle: the grammar grown from its own start shapes must be
    // refused or stay within the tangle's budgets (see `grow_checked`).
    let req = tangle_fuzz_request(text.into_owned());
    let gate = filigree::tangle::api::start_tangle(req.clone());
    let setup = tangle_setup(g);
    assert_eq!(
        gate.is_ok(),
        setup.is_ok(),
        "the fuzz body's start shapes differ from start_tangle's: {:?} vs {:?}",
        gate.err(),
        setup.err()
    );
    if let Ok((g, start, motifs)) = setup {
        grow_checked(g, start, motifs, &req);
    }
}

/// Steps and live shapes a fuzzed tangle may grow (a request's defaults
/// are 5,000 and 50,000; up to 100,000 and 250,000 may be asked). The
/// budgets that bound any request whatever it asks (`MAX_WORK`,
/// `MAX_POINTS`, `MAX_HISTORY`) are the product's, and the per-step
/// time-per-work oracle holds at any step count.
pub const TANGLE_FUZZ_STEPS: usize = 200;
pub const TANGLE_FUZZ_SHAPES: usize = 5_000;

/// CPU seconds one fuzz input may take (with [`CPU_ORACLES`] on, as the
/// fuzz targets set it; the replay in `cargo test` runs unoptimised):
/// issue 34's ~5 s natively, times ~4 for the fuzz build's coverage
/// instrumentation (measured 3.4×: a placement recursing into its
/// remainder takes 3.0 s in the release CLI and 10.3 s under the fuzzer).
/// libFuzzer's own `-timeout` is wall-clock time, which a shared machine
/// stretches.
pub const MAX_INPUT_CPU_SECONDS: f64 = 20.0;

/// Time-per-work oracle of a tangle step (with [`CPU_ORACLES`] on): a step's
/// CPU time is at most `STEP_CPU_SLACK + work × STEP_CPU_PER_WORK` seconds.
/// `MAX_WORK` (100M) is meant to be seconds natively (~20 ns a unit); the
/// bound is ~25× that, so only a cost the work measure misses by far (a
/// step whose time its estimate and count do not see) trips it.
pub const STEP_CPU_SLACK: f64 = 0.25;
pub const STEP_CPU_PER_WORK: f64 = 500e-9;

/// Whether the CPU-time oracles are on: the fuzz targets turn them on
/// (instrumented optimised builds); the replay in `cargo test` leaves them
/// off (unoptimised, and a test's time is not a finding).
pub static CPU_ORACLES: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

fn cpu_oracles() -> bool {
    CPU_ORACLES.load(std::sync::atomic::Ordering::Relaxed)
}

/// CPU time of this thread, seconds (Linux `schedstat`, nanoseconds);
/// `None` where it cannot be read.
pub fn thread_cpu() -> Option<f64> {
    let s = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: u64 = s.split_whitespace().next()?.parse().ok()?;
    Some(ns as f64 * 1e-9)
}

/// CPU seconds since `since` (a [`thread_cpu`] reading); 0 without one.
fn cpu_since(since: Option<f64>) -> f64 {
    match (since, thread_cpu()) {
        (Some(a), Some(b)) => b - a,
        _ => 0.0,
    }
}

/// The per-input CPU cap ([`MAX_INPUT_CPU_SECONDS`]) in fuzz builds.
fn cpu_cap(since: Option<f64>, what: &str) {
    if cpu_oracles() {
        let t = cpu_since(since);
        assert!(
            t <= MAX_INPUT_CPU_SECONDS,
            "cost oracle: {what} took {t:.1} s of CPU (cap {MAX_INPUT_CPU_SECONDS} s)"
        );
    }
}

/// The request a fuzzed grammar runs under: the defaults, with the fuzz
/// step and shape budgets.
pub fn tangle_fuzz_request(grammar: String) -> filigree::tangle::api::TangleRequest {
    filigree::tangle::api::TangleRequest {
        grammar,
        max_steps: TANGLE_FUZZ_STEPS,
        max_shapes: TANGLE_FUZZ_SHAPES,
        ..Default::default()
    }
}

type TangleStart = (
    filigree::tangle::ast::Grammar,
    Vec<(filigree::tangle::geom::polygon::Polygon, String)>,
    std::collections::HashMap<String, filigree::tangle::geom::polygon::Polygon>,
);

/// What `tangle::api::start_tangle` sets up for a request without a
/// `start` (its private `flatten_svg_defs`, `grammar_starts` and `motifs`,
/// from the public pieces they use, with the same checks): SVG curves as
/// polylines, the grammar's start shapes (an 800×600 rectangle when it has
/// none), the motifs `place` can use. The body checks it agrees with
/// `start_tangle` on what is refused.
pub fn tangle_setup(mut g: filigree::tangle::ast::Grammar) -> Result<TangleStart, String> {
    use filigree::tangle::api::{LETTER_HEIGHT, MAX_START_POINTS};
    use filigree::tangle::ast::{CurveDef, DefKind, StartShape};
    use filigree::tangle::geom::polygon::Polygon;
    use filigree::tangle::geom::svg::path_rings;
    use filigree::tangle::MAX_START_SIDE;
    use glam::DVec2;
    const TOL: f64 = 0.05;
    for d in &mut g.defs {
        if let CurveDef::Svg(path) = &d.curve {
            let rings = path_rings(path, TOL).map_err(|e| e.to_string())?;
            let first = rings.into_iter().next().ok_or("no points")?;
            d.curve = CurveDef::Polyline(first);
        }
    }
    let polys = |rings: Vec<Vec<DVec2>>| -> Result<Vec<Polygon>, String> {
        let n: usize = rings.iter().map(Vec::len).sum();
        if n > MAX_START_POINTS {
            return Err(format!("{n} start points"));
        }
        let v = Polygon::new(rings).ok_or("not finite")?;
        if v.is_empty() {
            return Err("no area".into());
        }
        let (lo, hi) = Polygon::bbox_all(&v);
        if (hi - lo).max_element() > MAX_START_SIDE {
            return Err("too large".into());
        }
        Ok(v)
    };
    let rect = |w: f64, h: f64| -> Result<Polygon, String> {
        if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0 && w.max(h) <= MAX_START_SIDE) {
            return Err("bad rect".into());
        }
        Ok(Polygon::rect(DVec2::ZERO, DVec2::new(w, h)))
    };
    let mut start = vec![];
    for s in &g.start {
        let made = match &s.shape {
            StartShape::Rect { width, height } => vec![rect(*width, *height)?],
            StartShape::Circle { radius } => {
                if !(*radius > 0.0 && 2.0 * radius <= MAX_START_SIDE) {
                    return Err("bad circle".into());
                }
                let n = (std::f64::consts::TAU * radius / 2.0).clamp(16.0, 4096.0);
                vec![Polygon::circle(DVec2::splat(*radius), *radius, n as usize)]
            }
            StartShape::Polygon(pts) => polys(vec![pts.clone()])?,
            StartShape::Svg(d) => polys(path_rings(d, TOL).map_err(|e| e.to_string())?)?,
            StartShape::Text(t) => polys(
                filigree::tangle::letters::text_rings(t, LETTER_HEIGHT)
                    .map_err(|e| e.to_string())?,
            )?,
        };
        start.extend(made.into_iter().map(|p| (p, s.tag.clone())));
    }
    if g.start.is_empty() {
        let tag = g.rules.first().map(|r| r.tag.clone()).unwrap_or_default();
        start.push((rect(800.0, 600.0)?, tag));
    }
    let mut motifs = std::collections::HashMap::new();
    motifs.insert("circle".to_string(), Polygon::circle(DVec2::ZERO, 1.0, 32));
    for d in &g.defs {
        if d.kind != DefKind::Shape {
            continue;
        }
        let poly = match &d.curve {
            CurveDef::Circle => Some(Polygon::circle(DVec2::ZERO, 1.0, 32)),
            CurveDef::Ngon(n) => Some(Polygon::circle(
                DVec2::ZERO,
                1.0,
                (*n as usize).clamp(3, 64),
            )),
            CurveDef::Polyline(pts) => Polygon::new(vec![pts.clone()])
                .and_then(|v| v.into_iter().next())
                .and_then(|p| filigree::tangle::place::normalise_motif(&p)),
            _ => None,
        };
        if let Some(p) = poly {
            motifs.insert(d.name.clone(), p);
        }
    }
    Ok((g, start, motifs))
}

/// Cost oracles of a tangle: grow `start` under `g` with `req`'s settings
/// (`tangle::expand::Expansion`, as a `tangle` job does) and check, with
/// the measures the engine keeps:
/// - every step's recorded work counts at least the points it read and
///   wrote, and (fuzz builds) its CPU time is within
///   `STEP_CPU_SLACK + work × STEP_CPU_PER_WORK`;
/// - the work held is the steps' sum and within `MAX_WORK`;
/// - the history within `MAX_HISTORY` shapes, the points held (each
///   polygon once) within `MAX_POINTS`, the live shapes and the steps
///   within the request's budgets; the expansion ends;
/// - the answer (`respond`) has finite points, within the same budgets;
/// - (fuzz builds) the whole input within `MAX_INPUT_CPU_SECONDS`.
pub fn grow_checked(
    g: filigree::tangle::ast::Grammar,
    start: Vec<(filigree::tangle::geom::polygon::Polygon, String)>,
    motifs: std::collections::HashMap<String, filigree::tangle::geom::polygon::Polygon>,
    req: &filigree::tangle::api::TangleRequest,
) {
    use filigree::tangle::expand::{
        Expansion, Progress, Settings, MAX_HISTORY, MAX_POINTS, MAX_WORK,
    };
    let settings = Settings {
        seed: req.seed,
        max_steps: req.max_steps,
        max_shapes: req.max_shapes,
        resolution: req.resolution,
        wobble: req.wobble,
        wavelength: req.wavelength,
    };
    let begun = thread_cpu();
    let Ok(mut x) = Expansion::new(g, start, motifs, settings) else {
        return;
    };
    let mut step_began = thread_cpu();
    loop {
        match x.work() {
            Err(_) | Ok(Progress::Ended) => break,
            Ok(Progress::Working) => {}
            Ok(Progress::Stepped(k)) => {
                let s = &x.steps[k];
                let points = |ids: &[u32]| -> u64 {
                    ids.iter()
                        .map(|&i| x.records[i as usize].shape.poly.vertices() as u64)
                        .sum()
                };
                let (read, written) = (points(&s.inputs), points(&s.outputs));
                assert!(
                    s.work >= read + written,
                    "cost oracle: step {k} ({}) counts {} work for {read} points read and \
                     {written} written",
                    s.op.name(),
                    s.work
                );
                if cpu_oracles() {
                    let t = cpu_since(step_began);
                    let bound = STEP_CPU_SLACK + s.work as f64 * STEP_CPU_PER_WORK;
                    assert!(
                        t <= bound,
                        "cost oracle: step {k} ({:?}) took {t:.2} s of CPU for {} work \
                         (bound {bound:.2} s; {read} points in, {written} out)",
                        s.op,
                        s.work
                    );
                }
                step_began = thread_cpu();
            }
        }
        cpu_cap(begun, "growing the tangle");
    }
    let held: u64 = x.steps.iter().map(|s| s.work).sum();
    assert_eq!(held, x.work_held(), "the work held is not the steps' sum");
    assert!(held <= MAX_WORK, "cost oracle: {held} work > MAX_WORK");
    assert!(
        x.records.len() <= MAX_HISTORY,
        "cost oracle: {} shapes made > MAX_HISTORY",
        x.records.len()
    );
    let mut seen = std::collections::HashSet::new();
    let held_points: usize = x
        .records
        .iter()
        .filter(|r| seen.insert(std::sync::Arc::as_ptr(&r.shape.poly)))
        .map(|r| r.shape.poly.vertices())
        .sum();
    assert!(
        held_points <= MAX_POINTS,
        "cost oracle: {held_points} points held > MAX_POINTS"
    );
    assert!(x.live() <= req.max_shapes, "{} live shapes", x.live());
    assert!(x.steps.len() <= req.max_steps, "{} steps", x.steps.len());
    if let Ok(r) = filigree::tangle::api::respond(&x, req) {
        assert!(r.points.iter().all(|v| v.is_finite()), "non-finite point");
        // Every shape's points, shared polygons once per shape: what the
        // engine's point budget counts.
        assert!(
            r.points.len() / 2 <= MAX_POINTS,
            "cost oracle: the answer has {} points > MAX_POINTS",
            r.points.len() / 2
        );
        assert!(r.shapes.len() <= MAX_HISTORY);
        assert!(r.stats.shapes <= req.max_shapes);
        assert!(r.steps.len() <= req.max_steps);
    }
    cpu_cap(begun, "growing the tangle and its answer");
}

/// Vector start shapes as the page and the CLI hand them to the core: the
/// bytes as text read as an SVG document (fitted into a frame: it stays
/// inside), as SVG path data and as a typed word; what parses must be
/// finite rings within the point limit, and a
/// tangle grown from it (small budgets) must keep its area.
pub fn tangle_start(data: &[u8]) {
    use filigree::tangle::geom::polygon::Polygon;
    use filigree::tangle::geom::svg::{document_polygons, path_rings, MAX_POINTS};
    let begun = thread_cpu();
    let text = String::from_utf8_lossy(data);
    let mut sources = vec![];
    // A document's shapes, fitted into a frame: inside it, finite.
    let frame = (glam::DVec2::ZERO, glam::DVec2::new(800.0, 600.0));
    if let Ok(polys) = document_polygons(&text, 0.05, Some(frame)) {
        let (lo, hi) = Polygon::bbox_all(&polys);
        assert!(
            lo.cmpge(frame.0 - 1e-6).all() && hi.cmple(frame.1 + 1e-6).all(),
            "{lo} {hi}"
        );
        sources.push(polys.into_iter().flat_map(|p| p.rings).collect());
    }
    if let Ok(r) = path_rings(&text, 0.05) {
        sources.push(r);
    }
    if let Ok(r) = filigree::tangle::letters::text_rings(&text, 50.0) {
        sources.push(r);
    }
    for rings in sources {
        let n: usize = rings.iter().map(Vec::len).sum();
        assert!(n <= MAX_POINTS, "{n} points");
        assert!(
            rings.iter().flatten().all(|p| p.is_finite()),
            "non-finite point"
        );
        let Some(polys) = Polygon::new(rings.clone()) else {
            continue;
        };
        let area: f64 = polys.iter().map(Polygon::area).sum();
        assert!(area.is_finite());
        let req = filigree::tangle::api::TangleRequest {
            grammar: START_GRAMMAR.into(),
            start: Some(filigree::tangle::api::StartRequest::Rings {
                rings: rings
                    .iter()
                    .map(|r| r.iter().map(|p| [p.x, p.y]).collect())
                    .collect(),
            }),
            max_steps: 20,
            max_shapes: 400,
            ..Default::default()
        };
        // What the product refuses is not grown; what it accepts grows
        // under the cost oracles of `grow_checked`.
        if filigree::tangle::api::start_tangle(req.clone()).is_err() {
            continue;
        }
        let g = filigree::tangle::grammar::parse(START_GRAMMAR).expect("parses");
        let start = polys.into_iter().map(|p| (p, "a".to_string())).collect();
        grow_checked(g, start, Default::default(), &req);
    }
    // The same text as the request's typed word (`StartRequest::Text`, as
    // the page sends it), 10 to 400 units tall (the size a grammar's
    // `start text(...)` has; larger words are the cost oracles' job in
    // `tangle_grammar`, whose start shapes go up to the product's limit).
    let word: String = text.chars().take(80).collect();
    let height = 10.0 + f64::from(data.first().copied().unwrap_or(0)) * (390.0 / 255.0);
    let req = filigree::tangle::api::TangleRequest {
        grammar: START_GRAMMAR.into(),
        start: Some(filigree::tangle::api::StartRequest::Text { text: word, height }),
        max_steps: 20,
        max_shapes: 400,
        ..Default::default()
    };
    if let Ok(job) = filigree::tangle::api::start_tangle(req) {
        if let Ok(r) = filigree::core::job::run_quietly(job) {
            assert!(r.points.iter().all(|v| v.is_finite()));
            assert!(r.stats.shapes <= 400 && r.steps.len() <= 20);
            assert!(r.points.len() / 2 <= filigree::tangle::expand::MAX_POINTS);
        }
    }
    cpu_cap(begun, "the start shapes and their tangles");
}

/// The grammar `tangle_start` grows its start shapes with: a split into
/// strips, each outlined.
const START_GRAMMAR: &str = "regularSplit(line, 20, 1) : a -> [b]\noutline(3) : b -> [c, d]\n";

/// Insets (`geom::offset`, cavalier_contours) of polygons read from raw
/// bytes: the first byte picks the distance, then each 5-byte record is a
/// point (two little-endian i16 coordinates on a 1/64 grid, so repeated,
/// collinear and nearly equal points are common) with a flag byte whose low
/// bit starts a new ring and whose next bit nudges the point by 1e-9 (the
/// near-coincident vertices real outlines have). What `Polygon::new` makes
/// of the rings is inset: no panic, and every piece is finite, inside its
/// polygon's box, no larger than it, outline counter-clockwise, holes
/// clockwise.
pub fn inset(data: &[u8]) {
    use filigree::tangle::geom::polygon::{ring_area2, Polygon};
    use glam::DVec2;
    let Some((&first, rest)) = data.split_first() else {
        return;
    };
    let d = 0.01 + f64::from(first) * 0.05;
    let mut rings: Vec<Vec<DVec2>> = vec![vec![]];
    for rec in rest.chunks_exact(5).take(4_000) {
        let x = f64::from(i16::from_le_bytes([rec[0], rec[1]])) / 64.0;
        let y = f64::from(i16::from_le_bytes([rec[2], rec[3]])) / 64.0;
        let nudge = if rec[4] & 2 != 0 { 1e-9 } else { 0.0 };
        if rec[4] & 1 != 0 && !rings.last().is_some_and(Vec::is_empty) {
            rings.push(vec![]);
        }
        rings
            .last_mut()
            .expect("one ring")
            .push(DVec2::new(x + nudge, y - nudge));
    }
    let Some(polys) = Polygon::new(rings) else {
        return;
    };
    for p in polys {
        let (lo, hi) = p.bbox();
        let pieces = p.inset(d);
        let area: f64 = pieces.iter().map(Polygon::area).sum();
        assert!(
            area <= p.area() * (1.0 + 1e-9) + 1e-6,
            "inset {area} > {}",
            p.area()
        );
        for q in &pieces {
            assert!(q.rings.iter().flatten().all(|v| v.is_finite()));
            let (a, b) = q.bbox();
            assert!(
                a.cmpge(lo - 1e-6).all() && b.cmple(hi + 1e-6).all(),
                "{a} {b} outside {lo} {hi}"
            );
            assert!(ring_area2(&q.rings[0]) > 0.0, "outline clockwise");
            assert!(
                q.rings[1..].iter().all(|h| ring_area2(h) < 0.0),
                "hole counter-clockwise"
            );
        }
    }
}

/// A Micro scene's JSON text (lossy UTF-8): parsed and checked under the
/// default limits; what compiles is evaluated at a few points (never NaN;
/// finite, or +∞ for an empty scene) and sphere-traced and sliced at 6×4.
pub fn micro_scene(data: &[u8]) {
    use filigree::core::limits::MAX_MICRO_NODES;
    use filigree::micro::api::{start_render, start_slice, MicroRenderRequest, MicroSliceRequest};
    let begun = thread_cpu();
    let text = String::from_utf8_lossy(data).into_owned();
    let Ok(scene) = filigree::micro::parse(&text) else {
        cpu_cap(begun, "refusing the scene");
        return;
    };
    assert!(
        scene.nodes >= 1 && scene.nodes <= MAX_MICRO_NODES,
        "{} nodes",
        scene.nodes
    );
    for p in [
        [0.0, 0.0, 0.0],
        [0.3, -0.7, 0.2],
        [1e3, -2e5, 7.0],
        [-0.5, 0.5, 1e-9],
    ] {
        let v = scene.eval_array(p);
        assert!(!v.is_nan(), "NaN at {p:?}");
    }
    let req = MicroRenderRequest {
        scene: text.clone(),
        width: 6,
        height: 4,
        max_steps: 64,
        ..Default::default()
    };
    let max_steps = u64::from(req.max_steps);
    if let Some(out) = step_some(start_render(req).expect("the scene parsed")) {
        let st = &out.stats;
        assert_eq!(st.rays, 24);
        assert!(!out.png.is_empty());
        // Cost oracle: the trace's counted work within what its step
        // limit allows (a ray: one evaluation, at most three per step
        // (a gradient check, the step, an undone step) or 60 bisections;
        // a hit: six more for its normal).
        assert!(st.hits <= st.rays && st.exhausted <= st.rays, "{st:?}");
        assert!(st.steps <= st.rays * max_steps, "cost oracle: {st:?}");
        assert!(
            st.sdf_evals <= st.rays * (1 + 3 * max_steps + 60) + 6 * st.hits,
            "cost oracle: {st:?}"
        );
    }
    cpu_cap(begun, "the scene's evaluation and render");
    let req = MicroSliceRequest {
        scene: text,
        width: 6,
        height: 4,
        ..Default::default()
    };
    if let Some(out) = step_some(start_slice(req).expect("the scene parsed")) {
        assert!(out.min.is_finite() && out.max.is_finite() && (0.0..=1.0).contains(&out.inside));
    }
    cpu_cap(begun, "the scene's evaluation, render and slice");
}

/// A human-ratings CSV for the Texture tool's perceptual scales
/// (`texture::scales::parse_ratings`): errors must point inside the text,
/// and what parses must be ids with 12 values in 1..=9, no id twice.
pub fn texture_ratings(data: &[u8]) {
    use filigree::texture::scales::{parse_ratings, N_SCALES};
    let text = String::from_utf8_lossy(data);
    match parse_ratings(&text) {
        Ok(rows) => {
            let mut ids = std::collections::HashSet::new();
            for r in &rows {
                assert!(
                    !r.id.is_empty() && ids.insert(r.id.clone()),
                    "id {:?}",
                    r.id
                );
                assert_eq!(r.scales.len(), N_SCALES);
                assert!(
                    r.scales.iter().all(|v| (1.0..=9.0).contains(v)),
                    "{:?}",
                    r.scales
                );
            }
        }
        Err(e) => {
            if let Some((line, column)) = e.position() {
                let lines = text.split('\n').count().max(1);
                assert!(
                    line >= 1 && line <= lines && column >= 1,
                    "{e} outside the text"
                );
            }
        }
    }
}

/// A texture index file (the app fetches it; `texture-index` parses it):
/// parsing must reject damage with an error, and a parsed index must
/// answer a retrieval.
pub fn texture_index(data: &[u8]) {
    use filigree::texture::api;
    if let Ok(index) = api::parse_index(data) {
        let req = api::TextureRetrieveRequest {
            size: 0,
            ..Default::default()
        };
        let r = api::retrieve(&index, &req).expect("a parsed index answers");
        assert!(r.cosine.is_finite());
    }
}
