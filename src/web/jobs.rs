//! Request kind → core job. Each arm deserialises the payload, builds a core
//! [`Job`](crate::core::job::Job) and wraps it so the worker can step it.
use crate::core::error::Error;
use crate::core::job::{Job, OneShot, Progress, Step};
use crate::inspect::{inspect, InspectOptions};
use crate::pattern::api::{self as pattern_api, FitSettings, TargetSpec};
use crate::raster::{decode, Limits};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use wasm_bindgen::JsValue;

/// A job with its output already turned into a JS value.
pub trait DynJob {
    fn step(&mut self) -> Result<JsValue, String>;
    /// Deliver every shard's part of the job's last `need`, in shard order.
    fn provide(&mut self, parts: Vec<Vec<f64>>) -> Result<(), String>;
}

#[derive(Serialize)]
struct Running<'a> {
    done: bool,
    progress: &'a Progress,
    /// Data to exchange with sibling jobs before the next step (see `Job::outbox`).
    #[serde(skip_serializing_if = "Option::is_none")]
    need: Option<Vec<f64>>,
}

struct Wrapped<J, F> {
    job: J,
    to_js: F,
}

impl<J, F> DynJob for Wrapped<J, F>
where
    J: Job,
    F: FnMut(J::Output) -> Result<JsValue, String>,
{
    fn provide(&mut self, parts: Vec<Vec<f64>>) -> Result<(), String> {
        self.job.inbox(parts).map_err(|e| e.to_string())
    }

    fn step(&mut self) -> Result<JsValue, String> {
        match self.job.step().map_err(|e| e.to_string())? {
            Step::Running(p) => to_js(&Running {
                done: false,
                progress: &p,
                need: self.job.outbox(),
            }),
            Step::Done(out) => {
                let result = (self.to_js)(out)?;
                let obj = js_sys::Object::new();
                js_sys::Reflect::set(&obj, &"done".into(), &JsValue::TRUE).map_err(js_err)?;
                js_sys::Reflect::set(&obj, &"result".into(), &result).map_err(js_err)?;
                Ok(obj.into())
            }
        }
    }
}

fn wrap<J, F>(job: J, to_js: F) -> Box<dyn DynJob>
where
    J: Job + 'static,
    F: FnMut(J::Output) -> Result<JsValue, String> + 'static,
{
    Box::new(Wrapped { job, to_js })
}

fn js_err(v: JsValue) -> String {
    v.as_string().unwrap_or_else(|| format!("{v:?}"))
}

/// Serialise to plain JS objects: structs and maps become objects,
/// `serde_bytes` fields become `Uint8Array`s (transferred, not copied, to the page).
pub fn to_js<T: Serialize + ?Sized>(v: &T) -> Result<JsValue, String> {
    v.serialize(&serde_wasm_bindgen::Serializer::new().serialize_maps_as_objects(true))
        .map_err(|e| e.to_string())
}

fn from_js<T: for<'de> Deserialize<'de>>(kind: &str, v: JsValue) -> Result<T, String> {
    serde_wasm_bindgen::from_value(v).map_err(|e| format!("bad {kind} request: {e}"))
}

#[derive(Deserialize)]
struct InspectRequest {
    #[serde(with = "serde_bytes")]
    bytes: Vec<u8>,
    tolerance: Option<f64>,
}

/// An image as it crosses the boundary undecoded: straight RGBA bytes.
#[derive(Serialize)]
pub struct RawImage<'a> {
    pub width: u32,
    pub height: u32,
    #[serde(with = "serde_bytes")]
    pub rgba: &'a [u8],
}

impl<'a> RawImage<'a> {
    pub fn of(img: &'a crate::raster::Rgba8Image) -> Self {
        RawImage {
            width: img.width,
            height: img.height,
            rgba: &img.data,
        }
    }
}

/// A mask as the browser edits it: one byte per pixel, non-zero = textured.
#[derive(Deserialize, Serialize)]
struct MaskBits {
    width: u32,
    height: u32,
    #[serde(with = "serde_bytes")]
    bits: Vec<u8>,
}

impl MaskBits {
    /// The mask as an image that `pixel::inputs::mask_from_image` reads back
    /// exactly: opaque white inside, transparent outside.
    fn to_image(&self) -> Result<crate::raster::Rgba8Image, String> {
        if self.bits.len() != self.width as usize * self.height as usize {
            return Err(format!(
                "the mask has {} values but is declared {}×{}",
                self.bits.len(),
                self.width,
                self.height
            ));
        }
        let data = self
            .bits
            .iter()
            .flat_map(|&b| if b != 0 { [255; 4] } else { [0; 4] })
            .collect();
        crate::raster::Rgba8Image::from_raw(self.width, self.height, data)
            .map_err(|e| e.to_string())
    }
}

/// Target and settings shared by `"fit"` and `"fit-eval"` requests. Give
/// one of `target_png` (encoded image bytes), `target_rgba` (raw pixels) or
/// `target_params` (the program drawn with these values).
#[derive(Deserialize)]
struct FitCommon {
    /// Program text.
    program: String,
    /// Values by name for integer (structural) parameters; others default.
    #[serde(default)]
    params: BTreeMap<String, f64>,
    #[serde(default, with = "serde_bytes")]
    target_png: Option<Vec<u8>>,
    #[serde(default)]
    target_rgba: Option<MasklessRgba>,
    #[serde(default)]
    target_params: Option<BTreeMap<String, f64>>,
    /// RGB distance for snapping target colours to the palette (default 60).
    tolerance: Option<f64>,
    /// "quick" (default) | "paper"
    budget: Option<String>,
    /// "sdf" (default) | "l1" | "pyramid" | "image"
    loss: Option<String>,
    /// "genetic" (default) | "random" | "nelder-mead"
    init: Option<String>,
    seed: Option<u64>,
    grid: Option<usize>,
    population: Option<usize>,
    generations: Option<usize>,
    candidates: Option<usize>,
    iterations: Option<usize>,
    /// Adam iterations on the image-space loss after the fit (0 = off).
    polish: Option<usize>,
    /// `[k, n]`: shard k of n of one fit across a worker pool.
    shards: Option<(usize, usize)>,
}

#[derive(Deserialize)]
struct MasklessRgba {
    width: u32,
    height: u32,
    #[serde(with = "serde_bytes")]
    rgba: Vec<u8>,
}

impl FitCommon {
    fn split(self) -> (String, BTreeMap<String, f64>, TargetSpec, FitSettings) {
        let target = TargetSpec {
            image: self.target_png,
            rgba: self.target_rgba.map(|r| (r.width, r.height, r.rgba)),
            params: self.target_params,
            tolerance: self.tolerance,
        };
        let settings = FitSettings {
            budget: self.budget,
            loss: self.loss,
            init: self.init,
            seed: self.seed,
            grid: self.grid,
            population: self.population,
            generations: self.generations,
            candidates: self.candidates,
            iterations: self.iterations,
            polish: self.polish,
            shards: self.shards,
        };
        (self.program, self.params, target, settings)
    }
}

#[derive(Deserialize)]
struct FitEvalRequest {
    #[serde(flatten)]
    common: FitCommon,
    /// Float parameter vectors (declaration order, raw units).
    points: Vec<Vec<f64>>,
}

#[derive(Deserialize)]
struct RenderPatternRequest {
    program: String,
    #[serde(default)]
    params: BTreeMap<String, f64>,
    /// Side in pixels (default 512).
    size: Option<usize>,
    /// Samples per pixel side (default 1 = exact palette colours).
    supersample: Option<usize>,
}

#[derive(Deserialize)]
struct PatternSnapRequest {
    program: String,
    #[serde(default)]
    params: BTreeMap<String, f64>,
    /// The uploaded image file.
    #[serde(with = "serde_bytes")]
    bytes: Vec<u8>,
    /// Side of the snapped square (default 256).
    size: Option<usize>,
    /// RGB distance counted as "far" (default 60).
    tolerance: Option<f64>,
}

#[derive(Deserialize)]
struct PatternInfoRequest {
    program: String,
    #[serde(default)]
    params: BTreeMap<String, f64>,
}

/// Payload of a `"pixel"` request. Images are encoded files (PNG, ...); the
/// mask is bits (a mask file becomes bits through `"pixel-mask"`); exactly one
/// of `sheet` and `sprite` is given.
#[derive(Deserialize)]
struct PixelRequest {
    #[serde(with = "serde_bytes")]
    source: Vec<u8>,
    mask: MaskBits,
    #[serde(default, with = "serde_bytes")]
    sheet: Option<Vec<u8>>,
    #[serde(default, with = "serde_bytes")]
    sprite: Option<Vec<u8>>,
    #[serde(default)]
    strokes: Vec<crate::pixel::Stroke>,
    #[serde(default)]
    params: crate::pixel::PixelParams,
}

fn decode_named(what: &str, bytes: &[u8]) -> Result<crate::raster::Rgba8Image, String> {
    crate::raster::decode(bytes, crate::raster::Limits::default())
        .map_err(|e| format!("{what}: {e}"))
}

fn pixel_job(req: PixelRequest) -> Result<crate::pixel::PixelJob, String> {
    use crate::pixel::{Elements, PixelInputs, PixelJob};
    let elements = match (req.sheet, req.sprite) {
        (Some(b), None) => Elements::Sheet(decode_named("element sheet", &b)?),
        (None, Some(b)) => Elements::Sprite(decode_named("element sprite", &b)?),
        (Some(_), Some(_)) => {
            return Err("give either an element sheet or a single sprite, not both".into())
        }
        (None, None) => return Err("an element sheet (3×3) or a single sprite is needed".into()),
    };
    let inputs = PixelInputs {
        source: decode_named("source image", &req.source)?,
        mask: req.mask.to_image()?,
        elements,
        strokes: req.strokes,
    };
    PixelJob::new(inputs, req.params).map_err(|e| e.to_string())
}

#[derive(Deserialize)]
struct AbortRequest {
    /// Steps to run before aborting, so the page sees a job "mid-way".
    steps: u32,
}

/// A test-only job that runs a few slices and then traps, as a wasm panic
/// would: the worker must report it and the pool must replace the worker.
struct DebugAbort {
    left: u32,
    total: u32,
}

impl Job for DebugAbort {
    type Output = ();
    fn step(&mut self) -> crate::Result<Step<()>> {
        if self.left == 0 {
            panic!("debug-abort: deliberate crash requested by a test");
        }
        self.left -= 1;
        // Stay busy for a moment so the job is observably "running".
        let mut x = 0u64;
        for i in 0..2_000_000u64 {
            x = x.wrapping_mul(31).wrapping_add(i);
        }
        std::hint::black_box(x);
        Ok(Step::Running(Progress::new(
            1.0 - self.left as f64 / self.total as f64,
            "about to crash",
        )))
    }
}

pub fn start(kind: &str, payload: JsValue) -> Result<Box<dyn DynJob>, String> {
    match kind {
        "inspect" => {
            let req: InspectRequest = from_js(kind, payload)?;
            let mut opts = InspectOptions::default();
            if let Some(t) = req.tolerance {
                opts.tolerance = t;
            }
            Ok(wrap(
                OneShot::new(move || inspect(&req.bytes, &opts)),
                |r| {
                    #[derive(Serialize)]
                    struct Out<'a> {
                        #[serde(flatten)]
                        info: &'a crate::inspect::Inspection,
                        thumbnail: RawImage<'a>,
                    }
                    let out = Out {
                        info: &r,
                        thumbnail: RawImage::of(&r.thumbnail),
                    };
                    to_js(&out)
                },
            ))
        }
        "decode-image" => {
            let req: InspectRequest = from_js(kind, payload)?;
            Ok(wrap(
                OneShot::new(move || decode(&req.bytes, Limits::default())),
                |img| to_js(&RawImage::of(&img)),
            ))
        }
        "pixel" => {
            let req: PixelRequest = from_js(kind, payload)?;
            Ok(wrap(pixel_job(req)?, |out| {
                /// Result of a `"pixel"` job; `rgba` is a Uint8Array of
                /// `width*height*4` bytes, `field` an array of `2*width*height`
                /// numbers (x, y per pixel, row-major, y down).
                #[derive(Serialize)]
                struct Out<'a> {
                    width: u32,
                    height: u32,
                    #[serde(with = "serde_bytes")]
                    rgba: &'a [u8],
                    #[serde(with = "serde_bytes")]
                    colour_map: &'a [u8],
                    field: Vec<f32>,
                    positions: &'a [(i32, i32)],
                    placed: usize,
                    colours_before: usize,
                    colours_after: usize,
                    colour_map_used: &'static str,
                    stats: &'a crate::pixel::PixelStats,
                }
                let field: Vec<f32> = out.field.iter().flat_map(|v| [v[0], v[1]]).collect();
                let s = &out.stats;
                let o = Out {
                    width: out.image.width,
                    height: out.image.height,
                    rgba: &out.image.data,
                    colour_map: &out.colour_map.data,
                    field,
                    positions: &out.positions,
                    placed: s.placed,
                    colours_before: s.colours_before,
                    colours_after: s.colours_after,
                    colour_map_used: s.colour_map_used.name(),
                    stats: s,
                };
                to_js(&o)
            }))
        }
        "pixel-mask" => {
            let req: InspectRequest = from_js(kind, payload)?;
            Ok(wrap(
                OneShot::new(move || decode(&req.bytes, Limits::default())),
                |img| {
                    let inside = crate::pixel::inputs::mask_from_image(&img);
                    to_js(&MaskBits {
                        width: img.width,
                        height: img.height,
                        bits: inside.into_iter().map(u8::from).collect(),
                    })
                },
            ))
        }
        "fit" => {
            let (program, params, target, settings) = from_js::<FitCommon>(kind, payload)?.split();
            let (job, scene) = pattern_api::start_fit(&program, &params, &target, &settings)
                .map_err(|e| e.to_string())?;
            Ok(wrap(job, move |r| {
                let out = pattern_api::fit_output(&scene, r).map_err(|e| e.to_string())?;
                to_js(&out)
            }))
        }
        "fit-eval" => {
            let req: FitEvalRequest = from_js(kind, payload)?;
            let points = req.points;
            let (program, params, target, settings) = req.common.split();
            Ok(wrap(
                OneShot::new(move || {
                    pattern_api::eval_batch(&program, &params, &target, &settings, &points)
                }),
                |losses| {
                    #[derive(Serialize)]
                    struct Out {
                        losses: Vec<f64>,
                    }
                    to_js(&Out { losses })
                },
            ))
        }
        "render-pattern" => {
            let req: RenderPatternRequest = from_js(kind, payload)?;
            Ok(wrap(
                OneShot::new(move || {
                    pattern_api::render_program(
                        &req.program,
                        &req.params,
                        req.size.unwrap_or(512),
                        req.supersample.unwrap_or(1),
                    )
                }),
                |r| {
                    #[derive(Serialize)]
                    struct Out<'a> {
                        #[serde(flatten)]
                        image: RawImage<'a>,
                        svg: &'a str,
                    }
                    to_js(&Out {
                        image: RawImage::of(&r.image),
                        svg: &r.svg,
                    })
                },
            ))
        }
        "pattern-info" => {
            let req: PatternInfoRequest = from_js(kind, payload)?;
            Ok(wrap(
                OneShot::new(move || pattern_api::program_info(&req.program, &req.params)),
                |info| to_js(&info),
            ))
        }
        "pattern-generators" => Ok(wrap(
            OneShot::new(|| Ok(crate::pattern::generators::GENERATORS)),
            to_js,
        )),
        "pattern-snap" => {
            let req: PatternSnapRequest = from_js(kind, payload)?;
            Ok(wrap(
                OneShot::new(move || {
                    pattern_api::snap_target(
                        &req.program,
                        &req.params,
                        &req.bytes,
                        req.size.unwrap_or(256),
                        req.tolerance.unwrap_or(60.0),
                    )
                }),
                |s| {
                    #[derive(Serialize)]
                    struct Out<'a> {
                        #[serde(flatten)]
                        image: RawImage<'a>,
                        unmatched: f64,
                    }
                    to_js(&Out {
                        image: RawImage::of(&s.image),
                        unmatched: s.unmatched,
                    })
                },
            ))
        }
        "debug-abort" => {
            let req: AbortRequest = from_js(kind, payload)?;
            Ok(wrap(
                DebugAbort {
                    left: req.steps,
                    total: req.steps.max(1),
                },
                |()| Ok(JsValue::NULL),
            ))
        }
        other => Err(Error::input(format!("unknown request kind '{other}'")).to_string()),
    }
}
