//! Request kind → core job. Each arm deserialises the payload, builds a core
//! [`Job`](crate::core::job::Job) and wraps it so the worker can step it.
use crate::core::error::Error;
use crate::core::job::{Job, OneShot, Progress, Step};
use crate::inspect::{inspect, InspectOptions};
use crate::raster::{decode, Limits};
use serde::{Deserialize, Serialize};
use wasm_bindgen::JsValue;

/// A job with its output already turned into a JS value.
pub trait DynJob {
    fn step(&mut self) -> Result<JsValue, String>;
}

#[derive(Serialize)]
struct Running<'a> {
    done: bool,
    progress: &'a Progress,
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
    fn step(&mut self) -> Result<JsValue, String> {
        match self.job.step().map_err(|e| e.to_string())? {
            Step::Running(p) => to_js(&Running {
                done: false,
                progress: &p,
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
