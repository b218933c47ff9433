//! One tool's wasm module. Exactly one tool feature is on per build
//! (`scripts/build.sh`); `start_job` serves that tool's request kinds and the
//! shared ones ([`filigree::api::SHARED_KINDS`]), and its documents only.
//! Everything else (the job handle, errors, the panic hook) is the library's
//! `web` module.
#![forbid(unsafe_code)]
use filigree::web::{start_job_with, Start, WebJob};
use wasm_bindgen::prelude::*;

#[cfg(feature = "inspect")]
const MODULE: (&str, Start) = ("inspect", filigree::api::start_inspect);
#[cfg(feature = "pixel")]
const MODULE: (&str, Start) = ("pixel", filigree::api::start_pixel);
#[cfg(feature = "fit")]
const MODULE: (&str, Start) = ("fit", filigree::api::start_fit);
#[cfg(feature = "tangle")]
const MODULE: (&str, Start) = ("tangle", filigree::api::start_tangle);
#[cfg(feature = "tangle-png")]
const MODULE: (&str, Start) = ("tangle-png", filigree::api::start_tangle_png);
#[cfg(feature = "micro")]
const MODULE: (&str, Start) = ("micro", filigree::api::start_micro);
#[cfg(feature = "texture")]
const MODULE: (&str, Start) = ("texture", filigree::api::start_texture);
// A build for clippy or `cargo check` with no tool: the shared kinds only.
#[cfg(not(any(
    feature = "inspect",
    feature = "pixel",
    feature = "fit",
    feature = "tangle",
    feature = "tangle-png",
    feature = "micro",
    feature = "texture"
)))]
const MODULE: (&str, Start) = ("inspect", filigree::api::start_inspect);

#[wasm_bindgen(start)]
pub fn start() {
    filigree::web::init();
}

/// Which tool's module this is (`pkg/filigree_<module>.js`).
#[wasm_bindgen]
pub fn module() -> String {
    MODULE.0.to_string()
}

/// Start a job of `kind` with `payload`; throws a typed error object.
#[wasm_bindgen]
pub fn start_job(kind: &str, payload: JsValue) -> Result<WebJob, JsValue> {
    #[cfg(feature = "test-hooks")]
    if kind == "debug-abort" {
        return hooks::start(payload);
    }
    start_job_with(MODULE.1, kind, payload)
}

#[cfg(feature = "test-hooks")]
mod hooks {
    //! `debug-abort`: runs a few busy slices and then panics, as a wasm trap
    //! would, so the e2e tests can check that the worker reports it and the
    //! pool replaces it. Never in the shipped modules.
    use filigree::api::{boxed, Response};
    use filigree::core::job::{Job, Progress, Step};
    use filigree::web::{web_job, WebJob};
    use serde::Deserialize;
    use wasm_bindgen::JsValue;

    #[derive(Debug, Clone, Default, Deserialize)]
    #[serde(default)]
    struct DebugAbort {
        /// Steps to run before aborting, so the page sees a job "mid-way".
        steps: u32,
        /// Abort by unbounded recursion instead of a panic: in wasm the
        /// engine throws `RangeError: Maximum call stack size exceeded`.
        overflow: bool,
        #[serde(skip)]
        left: u32,
    }

    pub fn start(payload: JsValue) -> Result<WebJob, JsValue> {
        let req: DebugAbort =
            filigree::api::request("debug-abort", filigree::web::deserializer(payload))
                .map_err(|e| JsValue::from_str(&e.to_string()))?;
        let job = DebugAbort {
            steps: req.steps.max(1),
            left: req.steps,
            overflow: req.overflow,
        };
        Ok(web_job(boxed(job, |()| Response::Nothing)))
    }

    impl Job for DebugAbort {
        type Output = ();
        fn step(&mut self) -> filigree::Result<Step<()>> {
            if self.left == 0 {
                if self.overflow {
                    std::hint::black_box(recurse(std::hint::black_box(u64::MAX)));
                }
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
                1.0 - self.left as f64 / self.steps as f64,
                "about to crash",
            )))
        }
    }

    /// Recursion that never ends in practice.
    #[allow(unconditional_recursion)]
    fn recurse(n: u64) -> u64 {
        if n == 0 {
            return 0;
        }
        std::hint::black_box(recurse(std::hint::black_box(n - 1))).wrapping_add(1)
    }
}
