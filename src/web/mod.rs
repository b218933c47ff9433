//! The wasm boundary (feature `web`): the only module that touches
//! wasm-bindgen. JsValue → [`crate::api`] registry → JsValue; no logic.
//! Each tool's wasm module (the `filigree-wasm` crate in `src/wasm/`, built
//! once per tool) exports a `start_job` that calls [`start_job_with`] with
//! its tool's registry ([`crate::api::start_pixel`], ...), so a module
//! links only its own tool's code.
//!
//! The worker (`www/app/worker.js`) calls `start_job` with a request kind and
//! its payload (a plain JS object; byte fields are `Uint8Array`s), then calls
//! [`WebJob::step`] in a loop, yielding to its event loop every ~15 ms so a
//! cancel message can be read. Errors are thrown as plain objects
//! `{kind, message, line?, column?, field?}` ([`crate::core::error::ErrorInfo`]);
//! anything else thrown (a trap, a `RangeError`) means the instance is broken.
use crate::api::{RequestJob, Response};
use crate::core::error::Error;
use crate::core::job::{Progress, Step};
use serde::Serialize;
use wasm_bindgen::prelude::*;

/// Install the panic hook once; a panic then reaches the console with its
/// message before the trap, and the worker reports it as a `panic` message.
/// (Each module's start function calls it.)
pub fn init() {
    console_error_panic_hook::set_once();
}

/// The crate version, so the page can show which core it runs.
#[wasm_bindgen]
pub fn version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}

/// One running job, stepped by the worker. An opaque handle for JS.
#[wasm_bindgen]
pub struct WebJob {
    inner: Box<RequestJob>,
}

/// Serialise to plain JS objects: structs and maps become objects,
/// `serde_bytes` fields become `Uint8Array`s (transferred, not copied, to the page).
fn to_js<T: Serialize + ?Sized>(v: &T) -> Result<JsValue, JsValue> {
    v.serialize(&serde_wasm_bindgen::Serializer::new().serialize_maps_as_objects(true))
        .map_err(|e| error(Error::input(format!("the result could not be sent: {e}"))))
}

/// A core error as the plain object the worker passes on untouched.
fn error(e: Error) -> JsValue {
    let info = e.info();
    info.serialize(&serde_wasm_bindgen::Serializer::new().serialize_maps_as_objects(true))
        .unwrap_or_else(|_| JsValue::from_str(&info.message))
}

/// A module's registry: one of [`crate::api::start_pixel`], ... for the
/// browser's deserializer.
pub type Start = fn(&str, serde_wasm_bindgen::Deserializer) -> crate::Result<Box<RequestJob>>;

/// Start a job of `kind` with `payload` from the registry `start`; throws
/// a typed error object.
pub fn start_job_with(start: Start, kind: &str, payload: JsValue) -> Result<WebJob, JsValue> {
    // A request is always an object; anything else would reach serde as a
    // JS TypeError ("Reflect.get called on non-object").
    if !payload.is_object() || js_sys::Array::is_array(&payload) {
        let got = if payload.is_null() {
            "null".to_string()
        } else if payload.is_undefined() {
            "nothing".to_string()
        } else if js_sys::Array::is_array(&payload) {
            "a list".to_string()
        } else {
            payload.js_typeof().as_string().unwrap_or_default()
        };
        return Err(error(Error::BadRequest(format!(
            "{kind}: the request must be an object (got {got})"
        ))));
    }
    let inner = start(kind, serde_wasm_bindgen::Deserializer::from(payload)).map_err(error)?;
    Ok(WebJob { inner })
}

/// A job made outside the registry (a test hook), as a [`WebJob`].
pub fn web_job(inner: Box<RequestJob>) -> WebJob {
    WebJob { inner }
}

#[derive(Serialize)]
struct Running<'a> {
    done: bool,
    progress: &'a Progress,
    /// Data to exchange with sibling jobs before the next step (see `Job::outbox`).
    #[serde(skip_serializing_if = "Option::is_none")]
    need: Option<Vec<f64>>,
}

#[derive(Serialize)]
struct Done<'a> {
    done: bool,
    result: &'a Response,
}

#[wasm_bindgen]
impl WebJob {
    /// Do one bounded slice of work. Returns `{done: false, progress: {fraction, stage, figure},
    /// need?: number[]}` or `{done: true, result: ...}`; throws a typed error object. With
    /// `need`, call [`WebJob::provide`] before stepping again.
    pub fn step(&mut self) -> Result<JsValue, JsValue> {
        match self.inner.step().map_err(error)? {
            Step::Running(p) => to_js(&Running {
                done: false,
                progress: &p,
                need: self.inner.outbox(),
            }),
            Step::Done(r) => to_js(&Done {
                done: true,
                result: &r,
            }),
        }
    }

    /// Answer the `need` of the last step: every sibling shard's `need`,
    /// in shard order (an array of number arrays; the page only relays).
    pub fn provide(&mut self, parts: JsValue) -> Result<(), JsValue> {
        let parts: Vec<Vec<f64>> =
            crate::api::request("exchange", serde_wasm_bindgen::Deserializer::from(parts))
                .map_err(error)?;
        self.inner.inbox(parts).map_err(error)
    }
}

/// The browser's deserializer over a JS value (for a test hook's request).
pub fn deserializer(payload: JsValue) -> serde_wasm_bindgen::Deserializer {
    serde_wasm_bindgen::Deserializer::from(payload)
}
