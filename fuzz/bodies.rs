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

use filigree::core::job::{Job, Step};
use filigree::pattern::api::{self as pattern_api, FitSettings, TargetSpec};
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
    let none = BTreeMap::new();
    let Ok(info) = pattern_api::program_info(src, &none) else {
        return;
    };
    if let Ok(r) = pattern_api::render_program(src, &none, 12, 2) {
        assert_eq!((r.image.width, r.image.height), (12, 12));
        assert_eq!(r.image.data.len(), 12 * 12 * 4);
        finite_svg(&r.svg, "render_program");
    }
    let floats: Vec<_> = info.params.iter().filter(|p| !p.integer).collect();
    if floats.is_empty() || info.shapes == 0 {
        return;
    }
    let defaults: Vec<f64> = floats.iter().map(|p| p.default).collect();
    let moved: Vec<f64> = floats.iter().map(|p| p.lo + 0.37 * (p.hi - p.lo)).collect();
    let target = TargetSpec {
        params: Some(BTreeMap::new()),
        ..Default::default()
    };
    let settings = FitSettings {
        grid: Some(8),
        ..Default::default()
    };
    if let Ok(losses) = pattern_api::eval_batch(src, &none, &target, &settings, &[defaults, moved])
    {
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

/// Request kinds in the order the first byte of a `requests` input picks them.
pub const REQUEST_KINDS: &[&str] = &[
    "inspect",
    "decode-image",
    "pixel",
    "pixel-mask",
    "fit",
    "fit-eval",
    "render-pattern",
    "pattern-info",
    "pattern-generators",
    "pattern-snap",
];

// Payloads as the worker receives them (mirrors of `src/web/jobs.rs`, whose
// structs are private and tied to wasm-bindgen; byte fields are JSON arrays
// of numbers here, `Uint8Array`s there).

#[derive(Deserialize)]
struct BytesRequest {
    bytes: Vec<u8>,
    tolerance: Option<f64>,
}

#[derive(Deserialize)]
struct MaskBits {
    width: u32,
    height: u32,
    bits: Vec<u8>,
}

#[derive(Deserialize)]
struct PixelRequest {
    source: Vec<u8>,
    mask: MaskBits,
    #[serde(default)]
    sheet: Option<Vec<u8>>,
    #[serde(default)]
    sprite: Option<Vec<u8>>,
    #[serde(default)]
    strokes: Vec<filigree::pixel::Stroke>,
    #[serde(default)]
    params: filigree::pixel::PixelParams,
}

#[derive(Deserialize)]
struct RawRgba {
    width: u32,
    height: u32,
    rgba: Vec<u8>,
}

#[derive(Deserialize)]
struct FitCommon {
    program: String,
    #[serde(default)]
    params: BTreeMap<String, f64>,
    #[serde(default)]
    target_png: Option<Vec<u8>>,
    #[serde(default)]
    target_rgba: Option<RawRgba>,
    #[serde(default)]
    target_params: Option<BTreeMap<String, f64>>,
    tolerance: Option<f64>,
    #[serde(flatten)]
    settings: FitSettings,
}

impl FitCommon {
    fn target(&mut self) -> TargetSpec {
        TargetSpec {
            image: self.target_png.take(),
            rgba: self.target_rgba.take().map(|r| (r.width, r.height, r.rgba)),
            params: self.target_params.take(),
            tolerance: self.tolerance,
        }
    }
}

#[derive(Deserialize)]
struct FitEvalRequest {
    #[serde(flatten)]
    common: FitCommon,
    points: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct RenderPatternRequest {
    program: String,
    #[serde(default)]
    params: BTreeMap<String, f64>,
    size: Option<usize>,
    supersample: Option<usize>,
}

#[derive(Deserialize)]
struct PatternInfoRequest {
    program: String,
    #[serde(default)]
    params: BTreeMap<String, f64>,
}

#[derive(Deserialize)]
struct PatternSnapRequest {
    program: String,
    #[serde(default)]
    params: BTreeMap<String, f64>,
    bytes: Vec<u8>,
    size: Option<usize>,
    tolerance: Option<f64>,
}

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

fn decode_default(bytes: &[u8]) -> Option<Rgba8Image> {
    decode(bytes, Limits::default()).ok()
}

fn mask_image(m: &MaskBits) -> Option<Rgba8Image> {
    if m.bits.len() as u64 != m.width as u64 * m.height as u64 {
        return None;
    }
    let data = m
        .bits
        .iter()
        .flat_map(|&b| if b != 0 { [255; 4] } else { [0; 4] })
        .collect();
    Rgba8Image::from_raw(m.width, m.height, data).ok()
}

/// One request as the worker receives it: the first byte picks the kind
/// ([`REQUEST_KINDS`], modulo their count), the rest is the JSON payload.
pub fn requests(data: &[u8]) {
    let Some((&k, json)) = data.split_first() else {
        return;
    };
    run_request(REQUEST_KINDS[k as usize % REQUEST_KINDS.len()], json);
}

/// Run one request of `kind` with a JSON `payload` the way `src/web/jobs.rs` does.
pub fn run_request(kind: &str, payload: &[u8]) {
    fn parse<T: for<'de> Deserialize<'de>>(p: &[u8]) -> Option<T> {
        serde_json::from_slice(p).ok()
    }
    match kind {
        "inspect" => {
            let Some(req) = parse::<BytesRequest>(payload) else {
                return;
            };
            let mut opts = filigree::inspect::InspectOptions::default();
            if let Some(t) = req.tolerance {
                opts.tolerance = t;
            }
            let _ = filigree::inspect::inspect(&req.bytes, &opts);
        }
        "decode-image" => {
            let Some(req) = parse::<BytesRequest>(payload) else {
                return;
            };
            let _ = decode_default(&req.bytes);
        }
        "pixel-mask" => {
            let Some(req) = parse::<BytesRequest>(payload) else {
                return;
            };
            if let Some(img) = decode_default(&req.bytes) {
                let m = filigree::pixel::inputs::mask_from_image(&img);
                assert_eq!(m.len(), (img.width * img.height) as usize);
            }
        }
        "pixel" => {
            let Some(req) = parse::<PixelRequest>(payload) else {
                return;
            };
            use filigree::pixel::{Elements, PixelInputs, PixelJob};
            let elements = match (&req.sheet, &req.sprite) {
                (Some(b), None) => match decode_default(b) {
                    Some(i) => Elements::Sheet(i),
                    None => return,
                },
                (None, Some(b)) => match decode_default(b) {
                    Some(i) => Elements::Sprite(i),
                    None => return,
                },
                _ => return,
            };
            let (Some(source), Some(mask)) = (decode_default(&req.source), mask_image(&req.mask))
            else {
                return;
            };
            let inputs = PixelInputs {
                source,
                mask,
                elements,
                strokes: req.strokes,
            };
            if let Ok(job) = PixelJob::new(inputs, req.params) {
                step_some(job);
            }
        }
        "fit" => {
            let Some(mut req) = parse::<FitCommon>(payload) else {
                return;
            };
            let target = req.target();
            if let Ok((job, scene)) =
                pattern_api::start_fit(&req.program, &req.params, &target, &req.settings)
            {
                if let Some(r) = step_some(job) {
                    assert!(r.loss.is_finite(), "fit loss {}", r.loss);
                    if let Ok(out) = pattern_api::fit_output(&scene, r) {
                        finite_svg(&out.svg, "fit");
                    }
                }
            }
        }
        "fit-eval" => {
            let Some(mut req) = parse::<FitEvalRequest>(payload) else {
                return;
            };
            let target = req.common.target();
            let c = &req.common;
            if let Ok(l) =
                pattern_api::eval_batch(&c.program, &c.params, &target, &c.settings, &req.points)
            {
                assert_eq!(l.len(), req.points.len());
            }
        }
        "render-pattern" => {
            let Some(req) = parse::<RenderPatternRequest>(payload) else {
                return;
            };
            let size = req.size.unwrap_or(512);
            if let Ok(r) = pattern_api::render_program(
                &req.program,
                &req.params,
                size,
                req.supersample.unwrap_or(1),
            ) {
                assert_eq!(r.image.data.len(), size * size * 4);
                finite_svg(&r.svg, "render-pattern");
            }
        }
        "pattern-info" => {
            let Some(req) = parse::<PatternInfoRequest>(payload) else {
                return;
            };
            let _ = pattern_api::program_info(&req.program, &req.params);
        }
        "pattern-generators" => {
            assert!(!filigree::pattern::generators::GENERATORS.is_empty());
        }
        "pattern-snap" => {
            let Some(req) = parse::<PatternSnapRequest>(payload) else {
                return;
            };
            if let Ok(s) = pattern_api::snap_target(
                &req.program,
                &req.params,
                &req.bytes,
                req.size.unwrap_or(256),
                req.tolerance.unwrap_or(60.0),
            ) {
                assert!((0.0..=1.0).contains(&s.unmatched), "{}", s.unmatched);
            }
        }
        other => panic!("no request kind '{other}' in the fuzz bodies"),
    }
}
