//! The wasm boundary (feature `web`): the only module that touches
//! wasm-bindgen. It turns typed requests into core calls and nothing else.
//!
//! The worker (`www/worker.js`) calls [`start_job`] with a request kind and
//! its payload (a plain JS object; byte fields are `Uint8Array`s), then calls
//! [`WebJob::step`] in a loop, yielding to its event loop every ~15 ms so a
//! cancel message can be read. Adding a tool = one arm in `jobs::start`.
use wasm_bindgen::prelude::*;

mod jobs;

/// Install the panic hook once; a panic then reaches the console with its
/// message before the trap, and the worker reports it as a `panic` message.
#[wasm_bindgen(start)]
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
    inner: Box<dyn jobs::DynJob>,
}

/// Start a job of `kind` with `payload`. Errors (unknown kind, bad payload,
/// bad input) come back as a JS `Error` whose message is shown to the user.
#[wasm_bindgen]
pub fn start_job(kind: &str, payload: JsValue) -> Result<WebJob, JsError> {
    let inner = jobs::start(kind, payload).map_err(|e| JsError::new(&e))?;
    Ok(WebJob { inner })
}

#[wasm_bindgen]
impl WebJob {
    /// Do one bounded slice of work. Returns `{done: false, progress: {fraction, stage, figure},
    /// need?: number[]}` or `{done: true, result: ...}`; throws on error. With
    /// `need`, call [`WebJob::provide`] before stepping again.
    pub fn step(&mut self) -> Result<JsValue, JsError> {
        self.inner.step().map_err(|e| JsError::new(&e))
    }

    /// Answer the `need` of the last step: every sibling shard's `need`,
    /// in shard order (an array of number arrays; the page only relays).
    pub fn provide(&mut self, parts: JsValue) -> Result<(), JsError> {
        let parts: Vec<Vec<f64>> = serde_wasm_bindgen::from_value(parts)
            .map_err(|e| JsError::new(&format!("bad exchange data: {e}")))?;
        self.inner.provide(parts).map_err(|e| JsError::new(&e))
    }
}
