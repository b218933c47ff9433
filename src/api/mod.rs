//! The request registry: request kind → typed request → stepped job →
//! serialisable response. The one entry point of every tool's requests.
//!
//! [`start`] deserialises a payload with ANY serde `Deserializer` (the wasm
//! boundary uses `serde_wasm_bindgen`, native tests and fuzzers use
//! `serde_json`, see [`run_json`]) into the kind's request struct, whose
//! defaults are defined once in its tool's `api` module
//! ([`crate::pattern::api`], [`crate::pixel::api`], [`inspect`]), checks it
//! and returns a boxed [`Job`] whose output is a [`Response`]. The CLI
//! builds the same request structs from its flags and calls the same
//! `start_*` functions.
//!
//! Adding a tool: its `src/<tool>/api.rs` (request/response structs with
//! `Default`, `start_*` functions), one arm per kind in [`start`], one
//! variant in [`Response`] and in [`DefaultRequest`].
//!
//! Errors: a payload that does not deserialise becomes an
//! [`Error::BadRequest`] (kind `bad-request`) naming the kind and the field, e.g.
//! "pattern-info: `program` must be text (got null)", with
//! [`Error::field`] = `program`.
pub mod inspect;
pub mod project;

use crate::core::check;
use crate::core::error::{Error, Result};
use crate::core::job::{Job, Step};
use crate::micro::api as micro;
use crate::micro::fit_api as micro_fit;
use crate::pattern::api as pattern;
use crate::pixel::api as pixel;
use crate::tangle::api as tangle;
use crate::texture::api as texture;
use serde::{Deserialize, Deserializer, Serialize};

pub use crate::raster::RawImage;

/// Every request kind the registry serves.
pub const KINDS: &[&str] = &[
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
    "defaults",
    "check-state",
    "open-project",
    "tangle",
    "tangle-examples",
    "micro-render",
    "micro-slice",
    "micro-examples",
    "texture-models",
    "texture-render",
    "texture-index",
    "texture-analyse",
    "texture-retrieve",
    "micro-fit",
    "micro-glsl",
    // Last, so the fuzz corpora's kind bytes (an index into this list) keep
    // their meaning.
    "tangle-png",
];

/// The answer of any request (serialised as the inner value alone).
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum Response {
    Inspect(Box<inspect::InspectResponse>),
    Image(RawImage),
    Pixel(Box<pixel::PixelResponse>),
    Mask(pixel::MaskBits),
    Fit(Box<pattern::FitOutput>),
    Eval(pattern::EvalResponse),
    Render(pattern::RenderResponse),
    Info(pattern::ProgramInfo),
    Generators(&'static [crate::pattern::generators::Generator]),
    Snap(pattern::SnapResponse),
    Defaults(Box<Defaults>),
    State(Box<project::ToolState>),
    Project(Box<project::OpenedProject>),
    Tangle(Box<tangle::TangleResponse>),
    TanglePng(tangle::TanglePngResponse),
    TangleExamples(&'static [crate::tangle::examples::Example]),
    MicroRender(Box<micro::MicroRenderResponse>),
    MicroGlsl(Box<micro::MicroGlslResponse>),
    MicroSlice(Box<micro::MicroSliceResponse>),
    MicroExamples(&'static [crate::micro::examples::Example]),
    TextureModels(Vec<texture::ModelInfo>),
    TextureImage(Box<texture::TextureImage>),
    TextureIndex(Box<texture::TextureIndexResponse>),
    TextureAnalysis(Box<texture::TextureAnalysis>),
    TextureRetrieval(Box<texture::TextureRetrieval>),
    MicroFit(Box<micro_fit::MicroFitResponse>),
    /// `null`.
    Nothing,
}

/// A running request, as the worker and native drivers step it.
pub type RequestJob = dyn Job<Output = Response>;

/// A job whose output is turned into a [`Response`]; exchanges pass through.
struct Mapped<J, F> {
    job: J,
    into: F,
}

impl<J: Job, F: FnMut(J::Output) -> Response> Job for Mapped<J, F> {
    type Output = Response;
    fn step(&mut self) -> Result<Step<Response>> {
        Ok(match self.job.step()? {
            Step::Running(p) => Step::Running(p),
            Step::Done(out) => Step::Done((self.into)(out)),
        })
    }
    fn outbox(&mut self) -> Option<Vec<f64>> {
        self.job.outbox()
    }
    fn inbox(&mut self, parts: Vec<Vec<f64>>) -> Result<()> {
        self.job.inbox(parts)
    }
}

/// A job whose output becomes a [`Response`], boxed for the registry.
pub fn boxed<J, F>(job: J, into: F) -> Box<RequestJob>
where
    J: Job + 'static,
    F: FnMut(J::Output) -> Response + 'static,
{
    Box::new(Mapped { job, into })
}

/// `defaults`: which tool's default request to describe.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct DefaultsRequest {
    /// A request kind (`pixel`, `fit`, `inspect`, `render-pattern`, ...).
    pub tool: String,
}

/// A default request, serialised from the request struct's `Default`.
#[derive(Debug, Clone, Serialize)]
#[serde(untagged)]
pub enum DefaultRequest {
    Inspect(inspect::InspectRequest),
    DecodeImage(inspect::DecodeImageRequest),
    Pixel(pixel::PixelRequest),
    PixelMask(pixel::PixelMaskRequest),
    Fit(pattern::FitRequest),
    FitEval(pattern::FitEvalRequest),
    Render(pattern::RenderPatternRequest),
    Info(pattern::PatternInfoRequest),
    Snap(pattern::PatternSnapRequest),
    Defaults(DefaultsRequest),
    CheckState(project::CheckStateRequest),
    OpenProject(project::OpenProjectRequest),
    Tangle(Box<tangle::TangleRequest>),
    TanglePng(Box<tangle::TanglePngRequest>),
    MicroRender(Box<micro::MicroRenderRequest>),
    MicroSlice(Box<micro::MicroSliceRequest>),
    TextureRender(texture::TextureRenderRequest),
    TextureIndex(texture::TextureIndexRequest),
    TextureAnalyse(texture::TextureAnalyseRequest),
    TextureRetrieve(texture::TextureRetrieveRequest),
    MicroFit(Box<micro_fit::MicroFitRequest>),
    Nothing,
}

/// The answer of `defaults`: the tool's default request (every field at its
/// default; required inputs such as `program` or `bytes` empty) and, for
/// the fit kinds, what each budget preset amounts to.
#[derive(Debug, Clone, Serialize)]
pub struct Defaults {
    pub tool: String,
    pub request: DefaultRequest,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub budgets: Option<std::collections::BTreeMap<&'static str, pattern::BudgetInfo>>,
}

/// The default request of `tool`.
pub fn defaults(tool: &str) -> Result<Defaults> {
    use DefaultRequest as D;
    let request = match tool {
        "inspect" => D::Inspect(Default::default()),
        "decode-image" => D::DecodeImage(Default::default()),
        "pixel" => D::Pixel(Default::default()),
        "pixel-mask" => D::PixelMask(Default::default()),
        "fit" => D::Fit(Default::default()),
        "fit-eval" => D::FitEval(Default::default()),
        "render-pattern" => D::Render(Default::default()),
        "pattern-info" => D::Info(Default::default()),
        "pattern-snap" => D::Snap(Default::default()),
        "defaults" => D::Defaults(Default::default()),
        "check-state" => D::CheckState(Default::default()),
        "open-project" => D::OpenProject(Default::default()),
        "pattern-generators" | "tangle-examples" | "micro-examples" | "texture-models" => {
            D::Nothing
        }
        "texture-render" => D::TextureRender(Default::default()),
        "texture-index" => D::TextureIndex(Default::default()),
        "texture-analyse" => D::TextureAnalyse(Default::default()),
        "texture-retrieve" => D::TextureRetrieve(Default::default()),
        "tangle" => D::Tangle(Default::default()),
        "tangle-png" => D::TanglePng(Default::default()),
        "micro-render" | "micro-glsl" => D::MicroRender(Default::default()),
        "micro-slice" => D::MicroSlice(Default::default()),
        "micro-fit" => D::MicroFit(Default::default()),
        other => return Err(unknown_kind(other).at("tool")),
    };
    let budgets = matches!(tool, "fit" | "fit-eval").then(pattern::budgets);
    Ok(Defaults {
        tool: tool.to_string(),
        request,
        budgets,
    })
}

fn unknown_kind(kind: &str) -> Error {
    Error::input(format!(
        "unknown request kind '{kind}' (known: {})",
        KINDS.join(", ")
    ))
}

/// The wasm modules the app is split into: one per tool, each serving its
/// tool's request kinds and the [`SHARED_KINDS`]. The page loads a tool's
/// module when the tool is first used (`www/app/protocol.js` holds the same
/// table, checked by `tests/modules.rs`); natively [`start`] serves every kind.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Module {
    Inspect,
    Pixel,
    Fit,
    Tangle,
    /// Tangle's PNG export, loaded on the first export: the rasteriser and
    /// the PNG encoder stay out of the Tangle module.
    TanglePng,
    Micro,
    Texture,
}

impl Module {
    pub const ALL: [Module; 7] = [
        Module::Inspect,
        Module::Pixel,
        Module::Fit,
        Module::Tangle,
        Module::TanglePng,
        Module::Micro,
        Module::Texture,
    ];

    /// Its name: `pkg/filigree_<name>.js`, and the tool whose documents it checks.
    pub fn name(self) -> &'static str {
        match self {
            Module::Inspect => "inspect",
            Module::Pixel => "pixel",
            Module::Fit => "fit",
            Module::Tangle => "tangle",
            Module::TanglePng => "tangle-png",
            Module::Micro => "micro",
            Module::Texture => "texture",
        }
    }

    /// The request kinds only this module serves.
    pub fn kinds(self) -> &'static [&'static str] {
        match self {
            Module::Inspect => IMAGE_KINDS,
            Module::Pixel => &["pixel", "pixel-mask"],
            Module::Fit => &[
                "fit",
                "fit-eval",
                "render-pattern",
                "pattern-info",
                "pattern-generators",
                "pattern-snap",
            ],
            Module::Tangle => &["tangle", "tangle-examples"],
            Module::TanglePng => &["tangle-png"],
            Module::Micro => &[
                "micro-render",
                "micro-slice",
                "micro-examples",
                "micro-fit",
                "micro-glsl",
            ],
            Module::Texture => &[
                "texture-models",
                "texture-render",
                "texture-index",
                "texture-analyse",
                "texture-retrieve",
            ],
        }
    }

    /// Whether it also serves [`IMAGE_KINDS`]: Inspect, and Pixel, whose
    /// panel draws its source and element sheet with `decode-image` (in its
    /// own module, so the Pixel page loads no other one). Tangle reads no
    /// images; Fit, Micro and Texture send the PNGs their pages make and
    /// decode them inside their own requests.
    pub const fn images(self) -> bool {
        self.image_decoder().is_some()
    }

    /// The decoder of its [`IMAGE_KINDS`], if it serves them. The Inspect
    /// module reads the user's file as it is: every format. Every other
    /// module reads what its page sends: PNG only in wasm (the page turns
    /// any other format into PNG; [`crate::raster::decode_sent`]), so it
    /// links no JPEG, WebP, GIF or BMP decoder; natively every format.
    pub const fn image_decoder(self) -> Option<crate::raster::Decoder> {
        match self {
            Module::Inspect => Some(crate::raster::decode),
            Module::Pixel => Some(crate::raster::decode_sent),
            _ => None,
        }
    }
}

/// Kinds every module serves (a document's defaults and checks).
pub const SHARED_KINDS: &[&str] = &["defaults", "check-state", "open-project"];

/// The Inspect module's kinds, also served by every module that reads
/// images ([`Module::images`]), so its panel need not load another module.
pub const IMAGE_KINDS: &[&str] = &["inspect", "decode-image"];

/// The module that serves `kind`; `None` for a shared or unknown kind.
pub fn module_of(kind: &str) -> Option<Module> {
    Module::ALL.into_iter().find(|m| m.kinds().contains(&kind))
}

/// Start a request of `kind` whose payload `payload` deserialises into the
/// kind's request struct. Errors are typed ([`Error::kind`]) and name the
/// request field at fault ([`Error::field`]). Serves every kind (the CLI,
/// tests, fuzzers); a wasm module serves its own ([`start_pixel`], ...).
pub fn start<'de, D: Deserializer<'de>>(kind: &str, payload: D) -> Result<Box<RequestJob>> {
    match module_of(kind) {
        Some(Module::Pixel) => start_pixel(kind, payload),
        Some(Module::Fit) => start_fit(kind, payload),
        Some(Module::Tangle) => start_tangle(kind, payload),
        Some(Module::TanglePng) => start_tangle_png(kind, payload),
        Some(Module::Micro) => start_micro(kind, payload),
        Some(Module::Texture) => start_texture(kind, payload),
        Some(Module::Inspect) | None => start_shared(
            kind,
            payload,
            project::check_any,
            Some(crate::raster::decode),
        ),
    }
}

/// The Inspect module's kinds: the shared ones, checking Inspect documents.
pub fn start_inspect<'de, D: Deserializer<'de>>(kind: &str, payload: D) -> Result<Box<RequestJob>> {
    start_shared(
        kind,
        payload,
        project::check_inspect,
        const { Module::Inspect.image_decoder() },
    )
}

/// The Pixel module's kinds.
pub fn start_pixel<'de, D: Deserializer<'de>>(kind: &str, payload: D) -> Result<Box<RequestJob>> {
    Ok(match kind {
        "pixel" => boxed(pixel::start_pixel(request(kind, payload)?)?, |r| {
            Response::Pixel(Box::new(r.into()))
        }),
        "pixel-mask" => boxed(pixel::start_mask(request(kind, payload)?), Response::Mask),
        _ => {
            return start_shared(
                kind,
                payload,
                project::check_pixel,
                const { Module::Pixel.image_decoder() },
            )
        }
    })
}

/// The Fit module's kinds.
pub fn start_fit<'de, D: Deserializer<'de>>(kind: &str, payload: D) -> Result<Box<RequestJob>> {
    Ok(match kind {
        "fit" => boxed(pattern::start_fit(&request(kind, payload)?)?, |r| {
            Response::Fit(Box::new(r))
        }),
        "fit-eval" => boxed(
            pattern::start_eval(request(kind, payload)?)?,
            Response::Eval,
        ),
        "render-pattern" => boxed(
            pattern::start_render(request(kind, payload)?)?,
            Response::Render,
        ),
        "pattern-info" => boxed(
            pattern::start_info(request(kind, payload)?)?,
            Response::Info,
        ),
        "pattern-generators" => {
            serde::de::IgnoredAny::deserialize(payload).map_err(|e| serde_error(kind, e))?;
            boxed(pattern::start_generators(), Response::Generators)
        }
        "pattern-snap" => boxed(
            pattern::start_snap(request(kind, payload)?)?,
            Response::Snap,
        ),
        _ => {
            return start_shared(
                kind,
                payload,
                project::check_fit,
                const { Module::Fit.image_decoder() },
            )
        }
    })
}

/// The Tangle module's kinds.
pub fn start_tangle<'de, D: Deserializer<'de>>(kind: &str, payload: D) -> Result<Box<RequestJob>> {
    Ok(match kind {
        "tangle" => boxed(tangle::start_tangle(request(kind, payload)?)?, |r| {
            Response::Tangle(Box::new(r))
        }),
        "tangle-examples" => listing(kind, payload, || {
            Response::TangleExamples(crate::tangle::examples::EXAMPLES)
        })?,
        _ => {
            return start_shared(
                kind,
                payload,
                project::check_tangle,
                const { Module::Tangle.image_decoder() },
            )
        }
    })
}

/// The `tangle-png` module's kinds: Tangle's PNG export. It holds no
/// documents, so it checks none.
pub fn start_tangle_png<'de, D: Deserializer<'de>>(
    kind: &str,
    payload: D,
) -> Result<Box<RequestJob>> {
    Ok(match kind {
        "tangle-png" => boxed(
            tangle::start_png(request(kind, payload)?)?,
            Response::TanglePng,
        ),
        _ => {
            return start_shared(
                kind,
                payload,
                project::check_none,
                const { Module::TanglePng.image_decoder() },
            )
        }
    })
}

/// The Micro module's kinds.
pub fn start_micro<'de, D: Deserializer<'de>>(kind: &str, payload: D) -> Result<Box<RequestJob>> {
    Ok(match kind {
        "micro-render" => boxed(micro::start_render(request(kind, payload)?)?, |r| {
            Response::MicroRender(Box::new(r))
        }),
        "micro-glsl" => boxed(micro::start_glsl(request(kind, payload)?)?, |r| {
            Response::MicroGlsl(Box::new(r))
        }),
        "micro-slice" => boxed(micro::start_slice(request(kind, payload)?)?, |r| {
            Response::MicroSlice(Box::new(r))
        }),
        "micro-fit" => boxed(micro_fit::start_fit(request(kind, payload)?)?, |r| {
            Response::MicroFit(Box::new(r))
        }),
        "micro-examples" => listing(kind, payload, || {
            Response::MicroExamples(crate::micro::examples::EXAMPLES)
        })?,
        _ => {
            return start_shared(
                kind,
                payload,
                project::check_micro,
                const { Module::Micro.image_decoder() },
            )
        }
    })
}

/// The Texture module's kinds.
pub fn start_texture<'de, D: Deserializer<'de>>(kind: &str, payload: D) -> Result<Box<RequestJob>> {
    Ok(match kind {
        "texture-models" => listing(kind, payload, || {
            Response::TextureModels(texture::model_infos())
        })?,
        "texture-render" => boxed(texture::start_render(request(kind, payload)?)?, |r| {
            Response::TextureImage(Box::new(r))
        }),
        "texture-index" => boxed(texture::start_index(request(kind, payload)?), |r| {
            Response::TextureIndex(Box::new(r))
        }),
        "texture-analyse" => boxed(texture::start_analyse(request(kind, payload)?)?, |r| {
            Response::TextureAnalysis(Box::new(r))
        }),
        "texture-retrieve" => boxed(texture::start_retrieve(request(kind, payload)?)?, |r| {
            Response::TextureRetrieval(Box::new(r))
        }),
        _ => {
            return start_shared(
                kind,
                payload,
                project::check_texture,
                const { Module::Texture.image_decoder() },
            )
        }
    })
}

/// A kind that takes no request and lists what the tool ships (examples,
/// models): its payload is read and ignored, the answer made by `answer`.
fn listing<'de, D: Deserializer<'de>>(
    kind: &str,
    payload: D,
    answer: impl FnOnce() -> Response + 'static,
) -> Result<Box<RequestJob>> {
    serde::de::IgnoredAny::deserialize(payload).map_err(|e| serde_error(kind, e))?;
    Ok(boxed(
        crate::core::job::OneShot::new(move || Ok(answer())),
        |r| r,
    ))
}

/// The kinds every module serves; `checks`: the documents this module
/// checks; `images`: the decoder of [`IMAGE_KINDS`] if it serves them too
/// ([`Module::image_decoder`]).
fn start_shared<'de, D: Deserializer<'de>>(
    kind: &str,
    payload: D,
    checks: project::StateCheck,
    images: Option<crate::raster::Decoder>,
) -> Result<Box<RequestJob>> {
    Ok(match (kind, images) {
        ("inspect", Some(whole)) => boxed(
            inspect::start_inspect_with(request(kind, payload)?, whole)?,
            |r| Response::Inspect(Box::new(r)),
        ),
        ("decode-image", Some(whole)) => boxed(
            inspect::start_decode_with(request(kind, payload)?, whole),
            Response::Image,
        ),
        ("defaults", _) => {
            let req: DefaultsRequest = request(kind, payload)?;
            let d = defaults(&req.tool)?;
            boxed(crate::core::job::OneShot::new(move || Ok(d)), |d| {
                Response::Defaults(Box::new(d))
            })
        }
        ("check-state", _) => {
            let req: project::CheckStateRequest = request(kind, payload)?;
            boxed(
                crate::core::job::OneShot::new(move || project::run_check_state(&req, checks)),
                |s| Response::State(Box::new(s)),
            )
        }
        ("open-project", _) => {
            let req: project::OpenProjectRequest = request(kind, payload)?;
            boxed(project::start_open_project(req, checks), |p| {
                Response::Project(Box::new(p))
            })
        }
        (other, _) => match module_of(other) {
            Some(m) => {
                return Err(Error::input(format!(
                    "'{other}' requests are served by the {} module, not this one",
                    m.name()
                )))
            }
            None => return Err(unknown_kind(other)),
        },
    })
}

/// Deserialise a request, turning serde's error into a typed one that
/// names the kind and the field.
pub fn request<'de, T: Deserialize<'de>, D: Deserializer<'de>>(
    kind: &str,
    payload: D,
) -> Result<T> {
    serde_path_to_error::deserialize(payload).map_err(|e| {
        let field = check::dotted(e.path());
        let mut err = humanise(kind, &field, &e.inner().to_string());
        if !field.is_empty() {
            err = err.at(field);
        }
        err
    })
}

fn serde_error(kind: &str, e: impl std::fmt::Display) -> Error {
    humanise(kind, "", &e.to_string())
}

/// Serde's message about `field` in words ([`check::describe`]), as a
/// `bad-request` naming the kind: "pattern-info: `program` must be text
/// (got null)".
fn humanise(kind: &str, field: &str, msg: &str) -> Error {
    Error::BadRequest(format!(
        "{kind}: {}",
        check::describe(check::Style::Request, field, msg)
    ))
}

/// Run a request natively from its JSON payload, as the worker would
/// receive it, and return the response as JSON (byte fields become arrays
/// of numbers). For tests and fuzzers.
#[cfg(feature = "json")]
pub fn run_json(kind: &str, payload: &str) -> Result<serde_json::Value> {
    let mut de = serde_json::Deserializer::from_str(payload);
    let job = start(kind, &mut de)?;
    de.end()
        .map_err(|e| Error::input(format!("{kind}: the payload has trailing text ({e})")))?;
    let out = crate::core::job::run_quietly(job)?;
    serde_json::to_value(&out).map_err(|e| Error::input(format!("{kind}: {e}")))
}

impl<J: Job + ?Sized> Job for Box<J> {
    type Output = J::Output;
    fn step(&mut self) -> Result<Step<J::Output>> {
        (**self).step()
    }
    fn outbox(&mut self) -> Option<Vec<f64>> {
        (**self).outbox()
    }
    fn inbox(&mut self, parts: Vec<Vec<f64>>) -> Result<()> {
        (**self).inbox(parts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::job::run_quietly;

    fn start_json(kind: &str, json: &str) -> Result<Box<RequestJob>> {
        start(kind, &mut serde_json::Deserializer::from_str(json))
    }

    fn err(kind: &str, json: &str) -> Error {
        match start_json(kind, json) {
            Err(e) => e,
            Ok(job) => match run_quietly(job) {
                Err(e) => e,
                Ok(_) => panic!("{kind} {json}: expected an error"),
            },
        }
    }

    #[test]
    fn serde_errors_become_typed_errors_naming_the_field() {
        let e = err("pattern-info", r#"{"program": null}"#);
        assert_eq!(e.kind(), "bad-request");
        assert_eq!(e.field(), Some("program"));
        assert_eq!(
            e.to_string(),
            "pattern-info: `program` must be text (got null)"
        );
        let e = err("fit", r#"{"program": "x", "loss": "l3"}"#);
        assert_eq!(e.field(), Some("loss"));
        assert!(
            e.to_string()
                .starts_with("fit: `loss` is 'l3'; expected one of 'sdf'"),
            "{e}"
        );
        let e = err("pixel", r#"{"params": {"d_max": "far"}}"#);
        assert_eq!(e.field(), Some("params.d_max"));
        assert!(e.to_string().contains("must be a number"), "{e}");
        let e = err("pixel", r#"{"params": {"dmax": 3}}"#);
        assert_eq!(e.field(), Some("params.dmax"));
        let e = err("fit-eval", r#"{"program": "x", "seed": -1}"#);
        assert_eq!(e.field(), Some("seed"));
        assert!(e.to_string().contains("whole number ≥ 0"), "{e}");
        let e = err("render-pattern", "42");
        assert_eq!(e.field(), None);
        assert!(
            e.to_string()
                .starts_with("render-pattern: the request must be an object"),
            "{e}"
        );
        let e = err("no-such-kind", "{}");
        assert!(
            e.to_string()
                .contains("unknown request kind 'no-such-kind'"),
            "{e}"
        );
        assert!(err("debug-abort", r#"{"steps": 1}"#)
            .to_string()
            .contains("unknown request kind"));
    }

    #[test]
    fn aliases_and_units_are_part_of_the_request() {
        let r: pattern::FitRequest = request(
            "fit",
            &mut serde_json::Deserializer::from_str(r#"{"init": "ga", "units": "canvas"}"#),
        )
        .unwrap();
        assert_eq!(
            (r.init, r.units),
            (
                pattern::Init::Genetic,
                crate::pattern::loss::SdfUnits::Canvas
            )
        );
        let r: pattern::FitRequest = request(
            "fit",
            &mut serde_json::Deserializer::from_str(r#"{"init": "nm", "budget": "paper"}"#),
        )
        .unwrap();
        assert_eq!(r.init, pattern::Init::NelderMead);
        assert_eq!(r.options().unwrap().ga.population, 250);
    }

    #[test]
    fn every_kind_has_defaults_and_the_defaults_are_the_request_defaults() {
        for kind in KINDS {
            let d = defaults(kind).unwrap();
            serde_json::to_value(&d).unwrap();
        }
        let v = serde_json::to_value(defaults("fit").unwrap()).unwrap();
        assert_eq!(v["request"]["budget"], "quick");
        assert_eq!(v["request"]["seed"], 1);
        assert_eq!(v["request"]["tolerance"], 60.0);
        assert_eq!(v["request"]["init"], "periodic");
        assert_eq!(v["budgets"]["paper"]["population"], 250);
        assert_eq!(v["budgets"]["quick"]["grid"], 64);
        let v = serde_json::to_value(defaults("pixel").unwrap()).unwrap();
        assert_eq!(
            v["request"]["params"],
            serde_json::to_value(crate::pixel::PixelParams::default()).unwrap()
        );
        assert_eq!(v["request"]["params"]["annotation_scale"], 4);
        assert_eq!(v["request"]["params"]["seed"], 0);
        let v = serde_json::to_value(defaults("inspect").unwrap()).unwrap();
        assert_eq!(v["request"]["tolerance"], 24.0);
        assert_eq!(err("defaults", r#"{"tool": "nope"}"#).field(), Some("tool"));
    }

    #[cfg(feature = "json")]
    #[test]
    fn run_json_serves_every_kind_natively() {
        let gens = run_json("pattern-generators", "null").unwrap();
        assert!(gens.as_array().unwrap().len() >= 3);
        let src = crate::pattern::generators::generator("circles-grid")
            .unwrap()
            .source;
        let program = serde_json::to_string(src).unwrap();
        let info = run_json("pattern-info", &format!(r#"{{"program": {program}}}"#)).unwrap();
        assert_eq!(info["params"].as_array().unwrap().len(), 5);
        let r = run_json(
            "render-pattern",
            &format!(r#"{{"program": {program}, "size": 16}}"#),
        )
        .unwrap();
        assert_eq!(r["width"], 16);
        assert_eq!(r["rgba"].as_array().unwrap().len(), 16 * 16 * 4);
        assert!(r["svg"].as_str().unwrap().contains("<svg"));
        let d = run_json("defaults", r#"{"tool": "render-pattern"}"#).unwrap();
        assert_eq!(d["request"]["size"], 512);
        let e = run_json("inspect", r#"{"bytes": [1, 2, 3]}"#).unwrap_err();
        assert_eq!(e.field(), Some("bytes"));
        let e = run_json("inspect", r#"{} x"#).unwrap_err();
        assert!(e.to_string().contains("trailing"), "{e}");
    }
}
