//! Fit's requests as typed data, shared by the CLI and the browser worker.
//!
//! Each request kind (`fit`, `fit-eval`, `render-pattern`, `pattern-info`,
//! `pattern-generators`, `pattern-snap`) has one serde struct whose defaults
//! are defined once, by its `Default` impl (`#[serde(default)]` makes a
//! missing field take it), and one `start_*` function that checks the
//! request and returns a stepped [`Job`]. The registry (`crate::api`)
//! deserialises payloads into these structs; `filigree fit`/`render` build
//! the same structs from their flags. Field names are the worker's JSON
//! names; every error names the field at fault ([`Error::at`]).
use super::field::Scene;
use super::fit::{Budget, FitJob, FitOptions, FitResult, Preparation, TargetData, TargetSource};
use super::global::GlobalOptions;
use super::loss::{LossKind, Objective, SdfUnits};
use super::optim::InitMethod;
use super::record::{Canvas, Program, RecordLimits};
use super::render;
use super::target::Target;
use crate::core::error::{Error, Result};
use crate::core::job::{Job, OneShot, Progress, Step};
use crate::core::request_limits as lim;
use crate::raster::RawImage;
use crate::raster::{decode_file, Limits, Rgba8Image};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Parse a program; errors are about the `program` field.
fn parse(src: &str) -> Result<Program> {
    if src.trim().is_empty() {
        return Err(
            Error::input("`program` is empty: give the pattern program's text").at("program"),
        );
    }
    Program::parse(src).map_err(|e| e.at("program"))
}

/// Values of all declared parameters from a name → value map; missing
/// names take their defaults, unknown names are an error about `field`.
pub fn named_values(program: &Program, named: &BTreeMap<String, f64>) -> Result<Vec<f64>> {
    named_values_at(program, named, "params")
}

fn named_values_at(
    program: &Program,
    named: &BTreeMap<String, f64>,
    field: &str,
) -> Result<Vec<f64>> {
    let mut vals = program.defaults();
    for (k, v) in named {
        let at = format!("{field}.{k}");
        let i = program
            .params()
            .iter()
            .position(|p| &p.name == k)
            .ok_or_else(|| {
                let names: Vec<&str> = program.params().iter().map(|p| p.name.as_str()).collect();
                Error::input(format!(
                    "the program has no parameter '{k}' (it has {})",
                    names.join(", ")
                ))
                .at(&at)
            })?;
        // A value outside the declared range was clamped without a word
        // (`angle` 100 drew angle 0.5): it is an error naming the range.
        let d = &program.params()[i];
        if !(v.is_finite() && (d.lo..=d.hi).contains(v)) {
            return Err(Error::input(format!(
                "`{at}` is {}; the program declares '{k}' in [{}, {}]",
                lim::short_number(*v),
                d.lo,
                d.hi
            ))
            .at(&at));
        }
        vals[i] = *v;
    }
    Ok(vals)
}

/// Float values (declaration order) out of all values.
fn float_values(program: &Program, all: &[f64]) -> Vec<f64> {
    program
        .params()
        .iter()
        .zip(all)
        .filter(|(p, _)| !p.integer)
        .map(|(_, v)| *v)
        .collect()
}

/// Record a program with named values on the square canvas: the scene
/// and its float values.
fn scene_of(src: &str, named: &BTreeMap<String, f64>) -> Result<(Program, Scene, Vec<f64>)> {
    scene_on(src, named, Canvas::SQUARE)
}

/// [`scene_of`] on `canvas`.
fn scene_on(
    src: &str,
    named: &BTreeMap<String, f64>,
    canvas: Canvas,
) -> Result<(Program, Scene, Vec<f64>)> {
    let p = parse(src)?;
    let vals = named_values(&p, named)?;
    let rec = p
        .record_on(&vals, &RecordLimits::default(), canvas)
        .map_err(|e| e.at("program"))?;
    let fl = rec.float_values();
    Ok((p, Scene::new(rec), fl))
}

// ---------------------------------------------------------------- pattern-info

/// `pattern-info`: what a program declares and draws.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PatternInfoRequest {
    /// Program text.
    pub program: String,
    /// Values by name; missing ones take their defaults.
    pub params: BTreeMap<String, f64>,
}

/// One declared parameter, for building sliders.
#[derive(Debug, Clone, Serialize)]
pub struct ParamInfo {
    pub name: String,
    pub lo: f64,
    pub hi: f64,
    pub default: f64,
    pub integer: bool,
}

/// What a program declares and draws with its defaults.
#[derive(Debug, Clone, Serialize)]
pub struct ProgramInfo {
    pub params: Vec<ParamInfo>,
    /// Palette as `#rrggbb`; index 0 is the background.
    pub colours: Vec<String>,
    /// Shapes drawn with the default (or given) values.
    pub shapes: usize,
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// Parse and record a program; report its parameters and palette.
pub fn program_info(req: &PatternInfoRequest) -> Result<ProgramInfo> {
    let (p, scene, _) = scene_of(&req.program, &req.params)?;
    Ok(ProgramInfo {
        params: p
            .params()
            .iter()
            .map(|d| ParamInfo {
                name: d.name.clone(),
                lo: d.lo,
                hi: d.hi,
                default: d.default,
                integer: d.integer,
            })
            .collect(),
        colours: scene.rec.colours.iter().map(|c| hex(*c)).collect(),
        shapes: scene.rec.shapes.len(),
    })
}

/// Start a `pattern-info` request (one short step).
pub fn start_info(req: PatternInfoRequest) -> Result<impl Job<Output = ProgramInfo>> {
    Ok(OneShot::new(move || program_info(&req)))
}

/// Start a `pattern-generators` request: the shipped generators.
pub fn start_generators() -> impl Job<Output = &'static [super::generators::Generator]> {
    OneShot::new(|| Ok(super::generators::GENERATORS))
}

// -------------------------------------------------------------- render-pattern

/// `render-pattern` / `filigree render`: draw a program.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RenderPatternRequest {
    /// Program text.
    pub program: String,
    /// Values by name; missing ones take their defaults.
    pub params: BTreeMap<String, f64>,
    /// Width in pixels, 1..=2048 (512).
    pub size: usize,
    /// Height in pixels, 1..=2048; without it, `size` (a square). The
    /// canvas takes the picture's aspect, its shorter side 1 program unit
    /// (`Canvas::of_pixels`), as a fit to a target of that size does.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub height: Option<usize>,
    /// Samples per pixel side, 1..=4 (1 = exact palette colours).
    pub supersample: usize,
}

impl Default for RenderPatternRequest {
    fn default() -> Self {
        RenderPatternRequest {
            program: String::new(),
            params: BTreeMap::new(),
            size: 512,
            height: None,
            supersample: 1,
        }
    }
}

/// A drawn pattern: `size × height` RGBA and the SVG of the same size.
#[derive(Debug, Clone, Serialize)]
pub struct RenderResponse {
    #[serde(flatten)]
    pub image: RawImage,
    pub svg: String,
}

enum RenderPhase {
    Record(RenderPatternRequest),
    Raster(Scene, Vec<f64>, (usize, usize), Box<render::Raster>),
    Svg(Scene, Vec<f64>, (usize, usize), Rgba8Image),
    Finished,
}

/// Work units (item evaluations, or samples × channels) of one raster step
/// of `render-pattern`: a few milliseconds (`filigree bench slices`).
pub const RENDER_WORK_PER_STEP: u64 = 300_000;

/// `render-pattern` as a job: record; rasterise in bounded steps
/// ([`render::Raster`], [`RENDER_WORK_PER_STEP`]); write SVG.
pub struct RenderJob(RenderPhase);

impl Job for RenderJob {
    type Output = RenderResponse;
    fn step(&mut self) -> Result<Step<RenderResponse>> {
        match std::mem::replace(&mut self.0, RenderPhase::Finished) {
            RenderPhase::Record(req) => {
                let size = (req.size, req.height.unwrap_or(req.size));
                let canvas = Canvas::of_pixels(size.0, size.1);
                let (_, scene, fl) = scene_on(&req.program, &req.params, canvas)?;
                let raster = render::Raster::with_size(&scene, &fl, size, req.supersample)?;
                let stage = raster.stage();
                self.0 = RenderPhase::Raster(scene, fl, size, Box::new(raster));
                Ok(Step::Running(Progress::new(0.05, stage)))
            }
            RenderPhase::Raster(scene, fl, size, mut raster) => {
                if raster.run(&scene, RENDER_WORK_PER_STEP) {
                    self.0 = RenderPhase::Svg(scene, fl, size, raster.into_image());
                    return Ok(Step::Running(Progress::new(0.95, "writing SVG")));
                }
                let p = Progress::new(0.05 + 0.9 * raster.fraction(), raster.stage());
                self.0 = RenderPhase::Raster(scene, fl, size, raster);
                Ok(Step::Running(p))
            }
            RenderPhase::Svg(scene, fl, size, img) => Ok(Step::Done(RenderResponse {
                svg: render::svg_sized(&scene, &fl, size.0 as f64, size.1 as f64)?,
                image: RawImage::from(img),
            })),
            RenderPhase::Finished => Err(Error::input("this job has already finished")),
        }
    }
}

/// Check a `render-pattern` request and start it.
pub fn start_render(req: RenderPatternRequest) -> Result<RenderJob> {
    lim::int_in("size", req.size, lim::RENDER_SIZE)?;
    if let Some(h) = req.height {
        lim::int_in("height", h, lim::RENDER_SIZE)?;
    }
    lim::int_in("supersample", req.supersample, lim::SUPERSAMPLE)?;
    for (k, v) in &req.params {
        lim::finite_in(
            &format!("params.{k}"),
            *v,
            (-lim::PARAM_MAGNITUDE, lim::PARAM_MAGNITUDE),
        )?;
    }
    Ok(RenderJob(RenderPhase::Record(req)))
}

// ---------------------------------------------------------------- pattern-snap

/// `pattern-snap`: an uploaded target snapped to a program's palette.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct PatternSnapRequest {
    /// Program text.
    pub program: String,
    pub params: BTreeMap<String, f64>,
    /// The uploaded image: its pixels (`rgba`, what the page sends: the
    /// browser decodes the user's file), or natively its file (`bytes`, any
    /// format). Exactly one of the two.
    #[serde(with = "serde_bytes")]
    pub bytes: Vec<u8>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rgba: Option<RawRgba>,
    /// Longer side of the snapped picture, 8..=2048 (256); the shorter
    /// side keeps the upload's aspect (`Canvas::grid`), so a fit to it
    /// sees the design unstretched.
    pub size: usize,
    /// RGB distance counted as "far", 0..=442 (60).
    pub tolerance: f64,
}

impl Default for PatternSnapRequest {
    fn default() -> Self {
        PatternSnapRequest {
            program: String::new(),
            params: BTreeMap::new(),
            bytes: vec![],
            rgba: None,
            size: 256,
            tolerance: 60.0,
        }
    }
}

/// A target image snapped to a program's palette.
#[derive(Debug, Clone, Serialize)]
pub struct SnapResponse {
    /// `size` along the longer side, the upload's aspect: every pixel one
    /// of the program's colours, or, where
    /// the upload blends two of them (an anti-aliased edge), that blend of
    /// the two, so the fit still reads its outlines to a fraction of a
    /// pixel (see `geom::aa_distance`).
    #[serde(flatten)]
    pub image: RawImage,
    /// Fraction of pixels farther than the tolerance from every colour.
    pub unmatched: f64,
}

/// Decode an uploaded target, resample it to `size` pixels along its
/// longer side (nearest; the aspect kept) and
/// snap every pixel to the nearest colour the program draws with (or its
/// background), or to the blend of two of them that explains it better (an
/// anti-aliased edge), so the user sees exactly what the fit will compare
/// against and the fit keeps the edges' sub-pixel positions.
pub fn snap_target(req: &PatternSnapRequest) -> Result<SnapResponse> {
    let size = lim::int_in("size", req.size, lim::SNAP_SIZE)?;
    let tolerance = lim::finite_in("tolerance", req.tolerance, lim::TOLERANCE)?;
    let img = match (&req.rgba, req.bytes.is_empty()) {
        (Some(r), true) => {
            Rgba8Image::from_raw(r.width, r.height, r.rgba.clone()).map_err(|e| e.at("rgba"))?
        }
        (None, false) => decode_file(&req.bytes, Limits::default()).map_err(|e| e.at("bytes"))?,
        (Some(_), false) => {
            return Err(Error::input(
                "give the image once: its pixels (`rgba`) or its file (`bytes`), not both",
            )
            .at("rgba"))
        }
        (None, true) => {
            return Err(Error::input(
                "there is no image: give its pixels (`rgba`) or its file (`bytes`)",
            )
            .at("rgba"))
        }
    };
    let (_, scene, _) = scene_of(&req.program, &req.params)?;
    let colours = &scene.rec.colours;
    let (w, h) = super::fit::image_canvas(&img).grid(size);
    let (idx, mix, unmatched) = super::target::snap_to_palette_wh(&img, colours, w, h, tolerance);
    let mut image = Rgba8Image::new(w as u32, h as u32);
    for (i, (&k, &(other, t))) in idx.iter().zip(&mix).enumerate() {
        let (a, b) = (colours[k as usize], colours[other as usize]);
        let c = |j: usize| (t * a[j] as f64 + (1.0 - t) * b[j] as f64).round() as u8;
        image.data[4 * i..4 * i + 4].copy_from_slice(&[c(0), c(1), c(2), 255]);
    }
    Ok(SnapResponse {
        image: RawImage::from(image),
        unmatched,
    })
}

/// Start a `pattern-snap` request (one step: a decode and a resample).
pub fn start_snap(req: PatternSnapRequest) -> Result<impl Job<Output = SnapResponse>> {
    Ok(OneShot::new(move || snap_target(&req)))
}

// ------------------------------------------------------------------------ fit

/// How a fit picks its starting points (`periodic`, the default;
/// `genetic`, also `ga`, the paper's; `random`; `nelder-mead`, also `nm`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Init {
    /// The global stage for repeating designs ([`super::global`]):
    /// spectra over the whole box, then a sweep of the phase.
    #[default]
    Periodic,
    #[serde(alias = "ga")]
    Genetic,
    Random,
    #[serde(alias = "nm")]
    NelderMead,
}

impl Init {
    /// The shared initialiser it names; `None` for [`Init::Periodic`],
    /// which is Fit's own ([`FitOptions::global`]).
    pub fn method(self) -> Option<InitMethod> {
        match self {
            Init::Periodic => None,
            Init::Genetic => Some(InitMethod::Genetic),
            Init::Random => Some(InitMethod::Random),
            Init::NelderMead => Some(InitMethod::NelderMead),
        }
    }
}

/// Raw RGBA pixels of a target (`target_rgba`).
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct RawRgba {
    pub width: u32,
    pub height: u32,
    #[serde(with = "serde_bytes")]
    pub rgba: Vec<u8>,
}

/// Nothing more: the `fit` request itself.
#[derive(Debug, Clone, Copy, Default, PartialEq, Serialize, Deserialize)]
pub struct NoExtra {}

/// What `fit-eval` adds to a fit request.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct EvalPoints {
    /// Float parameter vectors (declaration order, raw units), at most 10,000.
    pub points: Vec<Vec<f64>>,
}

/// A fit: program, target and settings (`fit`; with `points`, `fit-eval`).
/// Give one of `target_png` (encoded image bytes), `target_rgba` (raw
/// pixels) or `target_params` (the program drawn with these values).
///
/// The default budget is `quick`, for both the browser and `filigree fit`:
/// it is what the interactive panel runs (seconds, not minutes), and one
/// default for both keeps a fit made in one place reproducible in the
/// other. The paper's settings are `budget: "paper"` / `--budget paper`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, bound(deserialize = "X: Deserialize<'de> + Default"))]
pub struct FitRequestOf<X> {
    /// Program text.
    pub program: String,
    /// Values by name for integer (structural) parameters; others default.
    pub params: BTreeMap<String, f64>,
    /// The target image (or `target_rgba`, its pixels). The fit's canvas
    /// takes its aspect, shorter side 1 (`Canvas::of_pixels`; a square image
    /// gives `[0, 1]²`), so the CLI and the browser, sending the same image,
    /// fit on the same canvas; `target_params` draws on the square canvas.
    #[serde(with = "serde_bytes", skip_serializing_if = "Option::is_none")]
    pub target_png: Option<Vec<u8>>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_rgba: Option<RawRgba>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub target_params: Option<BTreeMap<String, f64>>,
    /// RGB distance within which a target pixel matches a palette colour, 0..=442 (60).
    pub tolerance: f64,
    /// `quick` (default) or `paper`.
    pub budget: Budget,
    /// `sdf` (default), `l1`, `pyramid`, `image`.
    pub loss: LossKind,
    /// `periodic` (default), `genetic` (`ga`, the paper's), `random`,
    /// `nelder-mead` (`nm`).
    pub init: Init,
    /// Field units in the loss: `pixels` (default) or `canvas`.
    pub units: SdfUnits,
    /// Seed of every random choice (1).
    pub seed: u64,
    /// Loss grid side: `fit` 8..=256, `fit-eval` 8..=1024. Without it, an
    /// image target's grid follows the image: its longer side, from
    /// [`AUTO_GRID`]`.0` up to [`AUTO_GRID`]`.1` (a bigger image's fields are
    /// computed at its own resolution and sampled onto the grid); a target
    /// drawn from parameters takes the budget's (64 quick, 128 paper).
    pub grid: Option<usize>,
    /// Overrides of the budget.
    pub population: Option<usize>,
    pub generations: Option<usize>,
    pub candidates: Option<usize>,
    pub iterations: Option<usize>,
    /// Adam iterations on the image-space loss after the fit (0 = off, the
    /// paper's method). Without it: [`AUTO_POLISH`] after an SDF, L1 or
    /// pyramid fit (`filigree bench fit` shows the polish lowering the
    /// parameter error on most generators), none after an image-loss fit
    /// (it would only continue the same loss).
    pub polish: Option<usize>,
    /// `[k, n]`: this job is shard k of n of one fit (see `FitOptions::shards`).
    pub shards: Option<(usize, usize)>,
    /// Time bound in seconds, 0.1..=3600 (30): the GA generations, Adam
    /// iterations and polish are scaled down, all by one factor, until the
    /// fit's estimated time fits. The estimate counts the work of one field
    /// evaluation at the program's defaults on the loss grid (item
    /// evaluations, [`NS_PER_WORK`] each, a loss+gradient twice a loss) and
    /// not the clock, so a fit stays the same on every machine and in every
    /// shard; a slower machine (or the browser) takes longer than the bound.
    pub max_seconds: f64,
    /// `fit` only: draw the best values so far as the fit goes
    /// (`progress.picture`, at most every [`PREVIEW_EVERY_STEPS`] steps and
    /// only when the best changed) and the fitted values in the answer
    /// (`picture`), each exactly the `render-pattern` of those values at the
    /// answer's `width × height` (the target's size) with `supersample` 1,
    /// so the page needs no second job to show them (false). Of a sharded
    /// fit, every shard draws its own best so far; only shard 0's answer
    /// has the picture.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub preview: bool,
    #[serde(flatten)]
    pub extra: X,
}

/// `fit`.
pub type FitRequest = FitRequestOf<NoExtra>;
/// `fit-eval`: a fit request plus `points`.
pub type FitEvalRequest = FitRequestOf<EvalPoints>;

impl<X: Default> Default for FitRequestOf<X> {
    fn default() -> Self {
        FitRequestOf {
            program: String::new(),
            params: BTreeMap::new(),
            target_png: None,
            target_rgba: None,
            target_params: None,
            tolerance: 60.0,
            budget: Budget::Quick,
            loss: LossKind::Sdf,
            init: Init::Periodic,
            units: SdfUnits::Pixels,
            seed: 1,
            grid: None,
            population: None,
            generations: None,
            candidates: None,
            iterations: None,
            polish: None,
            shards: None,
            max_seconds: 30.0,
            preview: false,
            extra: X::default(),
        }
    }
}

/// The loss grid of an image target without a `grid`: the image's longer
/// side, at least `.0`, at most `.1` pixels.
pub const AUTO_GRID: (usize, usize) = (32, 128);

/// Image-space polish iterations without a `polish` (see `polish`).
pub const AUTO_POLISH: usize = 100;

/// Estimated native time of one weighted item evaluation
/// ([`super::field::Evaluator::work`]) or field value of a loss, in
/// nanoseconds, for `max_seconds`: 10–24 ns measured over the shipped
/// generators at 64² and 128² (a loss with its gradient took 0.8–2.5 times
/// a loss; counted as 2).
pub const NS_PER_WORK: f64 = 20.0;

/// Scale `o`'s GA generations (or global stage), Adam iterations and
/// polish down (by one factor, each kept at least 1) so that the fit's
/// estimated time is at most `max_seconds`, one loss evaluation costing
/// `work` weighted item evaluations plus one per field value, on a grid of
/// `grid_values` pixels, for `dim` float parameters. A spectral comparison
/// of the global stage draws on its smaller grid (work scaled by the ratio
/// of pixels) and transforms each of `field_values / grid_values` colours.
/// Returns the factor (1 = unchanged).
pub fn fit_time_bound(
    o: &mut FitOptions,
    (work, field_values, grid_values): (u64, usize, usize),
    dim: usize,
    max_seconds: f64,
) -> f64 {
    let loss_ns = (work as f64 + field_values as f64) * NS_PER_WORK;
    let init = match o.global {
        Some(g) => {
            let (spectra, losses) = g.evaluations(dim);
            let px = (g.grid * g.grid) as f64;
            let colours = (field_values / grid_values.max(1)) as f64;
            let ratio = (px / grid_values.max(1) as f64).min(1.0);
            // A transform: about 20 operations per value (log2 of 64² ≈ 12
            // butterflies, the window, the blur).
            let spectrum_ns = work as f64 * ratio * NS_PER_WORK + colours * px * 20.0 * NS_PER_WORK;
            (spectra as f64 * spectrum_ns + losses as f64 * loss_ns) / loss_ns
        }
        None => o.ga.population as f64 * (o.ga.generations + 1) as f64,
    };
    let adam = (o.candidates * o.iterations + o.polish) as f64;
    let planned = (init + 2.0 * adam) * loss_ns * 1e-9;
    if planned <= max_seconds {
        return 1.0;
    }
    let f = max_seconds / planned;
    let scale = |v: usize| {
        if v == 0 {
            0
        } else {
            ((v as f64 * f).floor() as usize).max(1)
        }
    };
    o.ga.generations = scale(o.ga.generations);
    if let Some(g) = &mut o.global {
        g.samples = scale(g.samples);
        g.sweep = scale(g.sweep);
    }
    o.iterations = scale(o.iterations);
    o.patience = o.patience.min(o.iterations);
    if o.polish > 0 {
        o.polish = scale(o.polish);
    }
    f
}

/// The loss grid a request without `grid` gets for `target` (see `grid`).
pub fn auto_grid(target: &TargetData, budget_grid: usize) -> usize {
    match target {
        TargetData::Image(img, _) => {
            (img.width.max(img.height) as usize).clamp(AUTO_GRID.0, AUTO_GRID.1)
        }
        TargetData::Params(_) => budget_grid,
    }
}

/// What a budget preset amounts to (for showing defaults next to overrides).
#[derive(Debug, Clone, Serialize)]
pub struct BudgetInfo {
    pub population: usize,
    pub generations: usize,
    pub candidates: usize,
    pub iterations: usize,
    pub grid: usize,
}

/// The presets by name.
pub fn budgets() -> BTreeMap<&'static str, BudgetInfo> {
    [("quick", Budget::Quick), ("paper", Budget::Paper)]
        .into_iter()
        .map(|(n, b)| {
            let o = FitOptions::budget(b);
            let info = BudgetInfo {
                population: o.ga.population,
                generations: o.ga.generations,
                candidates: o.candidates,
                iterations: o.iterations,
                grid: o.loss.grid,
            };
            (n, info)
        })
        .collect()
}

impl<X> FitRequestOf<X> {
    /// Options from the settings; errors name the field.
    pub fn options(&self) -> Result<FitOptions> {
        let mut o = FitOptions::budget(self.budget);
        o.loss.kind = self.loss;
        o.loss.units = self.units;
        match self.init.method() {
            Some(m) => o.init = m,
            None => {
                o.global = Some(match self.budget {
                    Budget::Quick => GlobalOptions::default(),
                    Budget::Paper => GlobalOptions::thorough(),
                })
            }
        }
        o.seed = self.seed;
        if let Some(v) = self.grid {
            o.loss.grid = lim::int_in("grid", v, lim::GRID)?;
        }
        if let Some(v) = self.population {
            o.ga.population = lim::int_in("population", v, lim::POPULATION)?;
        }
        if let Some(v) = self.generations {
            o.ga.generations = lim::int_in("generations", v, lim::GENERATIONS)?;
        }
        if let Some(v) = self.candidates {
            o.candidates = lim::int_in("candidates", v, lim::CANDIDATES)?;
        }
        if let Some(v) = self.iterations {
            o.iterations = lim::int_in("iterations", v, lim::ITERATIONS)?;
        }
        o.polish = match self.polish {
            Some(v) => lim::int_in("polish", v, lim::ITERATIONS)?,
            None if self.loss == LossKind::Image => 0,
            None => AUTO_POLISH,
        };
        if let Some((k, n)) = self.shards {
            if n == 0 || n > lim::SHARDS || k >= n {
                return Err(Error::input(format!(
                    "`shards` [{k}, {n}]: need 1..={} shards and an index below their count",
                    lim::SHARDS
                ))
                .at("shards"));
            }
            o.shards = (k, n);
        }
        Ok(o)
    }

    /// The target, owned, for a job that builds its fields in its steps.
    fn target_data(&self, p: &Program) -> Result<TargetData> {
        let (mut img, mut fl) = (None, vec![]);
        let tol = match self.target(p, &mut img, &mut fl)? {
            TargetSource::Image(_, tol) => tol,
            TargetSource::Params(_) => return Ok(TargetData::Params(fl)),
        };
        Ok(TargetData::Image(img.expect("an image target"), tol))
    }

    /// The target as the fit sees it; `img`/`fl` hold what it borrows.
    fn target<'a>(
        &self,
        p: &Program,
        img: &'a mut Option<Rgba8Image>,
        fl: &'a mut Vec<f64>,
    ) -> Result<TargetSource<'a>> {
        let tol = lim::finite_in("tolerance", self.tolerance, lim::TOLERANCE)?;
        if let Some(bytes) = &self.target_png {
            *img = Some(decode_file(bytes, Limits::default()).map_err(|e| e.at("target_png"))?);
        } else if let Some(r) = &self.target_rgba {
            *img = Some(
                Rgba8Image::from_raw(r.width, r.height, r.rgba.clone())
                    .map_err(|e| e.at("target_rgba"))?,
            );
        } else if let Some(named) = &self.target_params {
            *fl = float_values(p, &named_values_at(p, named, "target_params")?);
            return Ok(TargetSource::Params(fl));
        } else {
            return Err(Error::input(
                "the fit needs a target: `target_png` (an image), `target_rgba` (pixels) or `target_params`",
            ));
        }
        Ok(TargetSource::Image(img.as_ref().expect("just set"), tol))
    }
}

/// A finished fit as plain data.
#[derive(Debug, Clone, Serialize)]
pub struct FitOutput {
    #[serde(flatten)]
    pub result: FitResult,
    /// The best parameters by name (float ones).
    pub named: BTreeMap<String, f64>,
    /// The loss that `loss`, `init_loss` and `history` are values of
    /// (`polish_loss`, when there is one, is the image-space loss).
    pub loss_name: LossKind,
    /// Width and height in pixels of the fitted pattern's pictures: the
    /// target image's (its longer side at most [`FIT_OUTPUT_MAX_SIDE`]), or
    /// 512 × 512 for a target drawn from parameters.
    pub width: u32,
    pub height: u32,
    /// The fitted pattern as SVG, `width × height` px.
    pub svg: String,
    /// With `preview`: the fitted pattern's pixels, `width × height`, as
    /// `render-pattern` draws the fitted values at that size.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub picture: Option<RawImage>,
}

/// Longest side of a fit's output pictures (the `render-pattern` limit).
pub const FIT_OUTPUT_MAX_SIDE: u32 = 2048;

/// The size of a fit's output pictures for a target: the image's own, scaled
/// down to [`FIT_OUTPUT_MAX_SIDE`] if bigger; 512 × 512 without an image.
pub fn output_size(target: &TargetData) -> (u32, u32) {
    match target {
        TargetData::Image(img, _) => {
            let (w, h) = (img.width.max(1), img.height.max(1));
            let m = w.max(h);
            if m <= FIT_OUTPUT_MAX_SIDE {
                (w, h)
            } else {
                let k = |v: u32| {
                    ((v as u64 * FIT_OUTPUT_MAX_SIDE as u64 + m as u64 / 2) / m as u64).max(1)
                        as u32
                };
                (k(w), k(h))
            }
        }
        TargetData::Params(_) => (512, 512),
    }
}

/// Package a fit result with its SVG, `size` (width, height) pixels.
pub fn fit_output(
    scene: &Scene,
    r: FitResult,
    loss: LossKind,
    size: (u32, u32),
) -> Result<FitOutput> {
    let svg = render::svg_sized(scene, &r.params, size.0 as f64, size.1 as f64)?;
    let named = r
        .names
        .iter()
        .cloned()
        .zip(r.params.iter().copied())
        .collect();
    Ok(FitOutput {
        result: r,
        named,
        loss_name: loss,
        width: size.0,
        height: size.1,
        svg,
        picture: None,
    })
}

/// Steps of a fit (each about [`super::fit::FitOptions::work_per_step`]
/// work units, a few milliseconds) from one `preview` picture to the next
/// at least: a 256² picture costs about as much as one to four steps, so
/// previews add at most a few percent to a fit's work.
pub const PREVIEW_EVERY_STEPS: u32 = 40;

/// `scene` drawn with float values `params` at `size` (width, height)
/// pixels, supersample 1: what `render-pattern` gives for the same values
/// at that size when `scene` was recorded on that size's canvas
/// ([`Canvas::of_pixels`]).
pub fn picture(scene: &Scene, params: &[f64], size: (u32, u32)) -> Result<RawImage> {
    let mut raster =
        render::Raster::with_size(scene, params, (size.0 as usize, size.1 as usize), 1)?;
    while !raster.run(scene, RENDER_WORK_PER_STEP) {}
    Ok(RawImage::from(raster.into_image()))
}

/// What a `fit` with `preview` has drawn: the values of its last picture
/// and the steps since. The shards of a sharded fit share their bests at
/// each exchange, after which every shard holds the same best: only shard 0
/// (`first`) draws those (`merged`), and only it draws the answer (the
/// pool answers shard 0's). A best a shard found on its own between
/// exchanges (its refinement candidates) is drawn by that shard. So the
/// page gets one picture of each best, where n shards each drawing their
/// best sent it n copies of the shared ones.
struct Previews {
    last: Option<Vec<f64>>,
    steps: u32,
    first: bool,
    merged: Option<Vec<f64>>,
}

/// A running `fit`: the core [`FitJob`] whose result comes with its SVG.
pub struct FitRequestJob {
    job: FitJob,
    scene: Scene,
    /// The output pictures' size ([`output_size`]).
    size: (u32, u32),
    loss: LossKind,
    /// With `preview`: what has been drawn so far.
    previews: Option<Previews>,
}

impl FitRequestJob {
    /// The fit itself (e.g. to read its objective).
    pub fn fit(&self) -> &FitJob {
        &self.job
    }
    /// The core fit job alone (its output without the SVG).
    pub fn into_fit(self) -> FitJob {
        self.job
    }
}

impl FitRequestJob {
    /// `p` with a picture of its best values when previews are on, the
    /// best changed since the last picture, and [`PREVIEW_EVERY_STEPS`]
    /// steps have passed since it (the first picture as soon as there is
    /// a best).
    fn with_preview(&mut self, p: Progress) -> Result<Progress> {
        let Some(pv) = self.previews.as_mut() else {
            return Ok(p);
        };
        pv.steps = pv.steps.saturating_add(1);
        let due = pv.last.is_none() || pv.steps >= PREVIEW_EVERY_STEPS;
        match &p.values {
            Some(v) if !pv.first && pv.merged.as_ref() == Some(v) => Ok(p),
            Some(v) if due && pv.last.as_ref() != Some(v) => {
                let pic = picture(&self.scene, v, self.size)?;
                pv.last = Some(v.clone());
                pv.steps = 0;
                Ok(p.with_picture(pic))
            }
            _ => Ok(p),
        }
    }
}

impl Job for FitRequestJob {
    type Output = FitOutput;
    fn step(&mut self) -> Result<Step<FitOutput>> {
        Ok(match self.job.step()? {
            Step::Running(p) => Step::Running(self.with_preview(p)?),
            Step::Done(r) => {
                let picture = match &self.previews {
                    Some(pv) if pv.first => Some(picture(&self.scene, &r.params, self.size)?),
                    _ => None,
                };
                let mut out = fit_output(&self.scene, r, self.loss, self.size)?;
                out.picture = picture;
                Step::Done(out)
            }
        })
    }
    fn outbox(&mut self) -> Option<Vec<f64>> {
        self.job.outbox()
    }
    fn inbox(&mut self, parts: Vec<Vec<f64>>) -> Result<()> {
        self.job.inbox(parts)?;
        if let Some(pv) = self.previews.as_mut() {
            pv.merged = Some(self.job.best().0);
        }
        Ok(())
    }
}

/// Check a `fit` request and start it.
pub fn start_fit(req: &FitRequest) -> Result<FitRequestJob> {
    let p = parse(&req.program)?;
    let vals = named_values(&p, &req.params)?;
    if let Some(g) = req.grid {
        lim::int_in("grid", g, lim::FIT_GRID)?;
    }
    let mut opts = req.options()?;
    let t = req.target_data(&p)?;
    if req.grid.is_none() {
        opts.loss.grid = auto_grid(&t, opts.loss.grid);
    }
    let size = output_size(&t);
    let max_seconds = lim::finite_in("max_seconds", req.max_seconds, lim::FIT_SECONDS)?;
    {
        // One field evaluation at the defaults: the work a loss costs.
        let canvas = t.canvas();
        let rec = p
            .record_on(&vals, &RecordLimits::default(), canvas)
            .map_err(|e| e.at("program"))?;
        let scene = Scene::new(rec);
        let grid = super::field::Grid::on(canvas, opts.loss.grid);
        let mut ev = super::field::Evaluator::on(grid, opts.loss.scale_on(canvas));
        let mut nodes = vec![];
        scene
            .rec
            .tape
            .forward(&scene.rec.float_values(), &mut nodes);
        ev.eval(&scene, &nodes, false);
        let fields = grid.len() * scene.channels.len();
        let dim = scene.rec.float_params.len();
        fit_time_bound(&mut opts, (ev.work, fields, grid.len()), dim, max_seconds);
    }
    let job = FitJob::start(&p, &vals, t, opts).map_err(|e| e.at("program"))?;
    let scene = job.objective().scene.clone();
    Ok(FitRequestJob {
        job,
        scene,
        size,
        loss: opts.loss.kind,
        previews: req.preview.then_some(Previews {
            last: None,
            steps: 0,
            first: req.shards.is_none_or(|(k, _)| k == 0),
            merged: None,
        }),
    })
}

/// Losses of a `fit-eval` request, in the order of its points.
#[derive(Debug, Clone, Serialize)]
pub struct EvalResponse {
    pub losses: Vec<f64>,
}

/// Work units of one `fit-eval` step: item evaluations of the fields, and
/// field values of the loss pass ([`crate::pattern::loss::LossPass`]),
/// chosen for steps of a few milliseconds (`filigree bench slices`).
pub const EVAL_WORK_PER_STEP: u64 = 600_000;

/// `fit-eval` as a job: each step spends about [`EVAL_WORK_PER_STEP`]: many
/// points at a small grid, part of one point's fields at a big one (the
/// fields of one loss are evaluated a few tiles at a time, see
/// [`Objective::begin_loss`]), so no step is unbounded.
pub struct EvalJob {
    obj: Objective,
    /// The target in the making: built in the first steps.
    prep: Option<Preparation>,
    points: Vec<Vec<f64>>,
    losses: Vec<f64>,
    /// The current point's loss is under way ...
    busy: bool,
    /// ... and its fields are complete (the loss pass is under way).
    fields_done: bool,
    /// Work units per step ([`EVAL_WORK_PER_STEP`]).
    budget: u64,
}

impl Job for EvalJob {
    type Output = EvalResponse;
    fn step(&mut self) -> Result<Step<EvalResponse>> {
        let budget = self.budget;
        if let Some(prep) = &mut self.prep {
            if let Some((t, normals)) = prep.step(&self.obj.scene, budget)? {
                self.obj.set_target(t, normals);
                self.prep = None;
            }
            return Ok(Step::Running(Progress::new(0.0, "preparing the target")));
        }
        let dim = self.obj.scene.rec.float_params.len();
        let mut spent = 0u64;
        while self.losses.len() < self.points.len() && spent < budget {
            let i = self.losses.len();
            if !self.busy {
                let x = &self.points[i];
                if x.len() != dim {
                    return Err(Error::input(format!(
                        "point {i} has {} values; the program has {dim} float parameters",
                        x.len()
                    ))
                    .at(format!("points.{i}")));
                }
                if let Some(j) = x.iter().position(|v| !v.is_finite()) {
                    return Err(Error::input(format!(
                        "point {i}: value {j} is not a finite number"
                    ))
                    .at(format!("points.{i}")));
                }
                spent += 1;
                match self.obj.begin_loss(x) {
                    Some(l) => {
                        self.losses.push(l);
                        continue;
                    }
                    None => self.busy = true,
                }
            }
            if !self.fields_done {
                let (done, w) = self.obj.loss_tiles(budget - spent.min(budget));
                spent += w;
                if !done {
                    break;
                }
                self.fields_done = true;
                continue;
            }
            // The loss pass reads every field value, a bounded part a step.
            let left = budget - spent.min(budget);
            spent += left.min(self.obj.loss_size()).max(1);
            match self
                .obj
                .loss_pass(usize::try_from(left).unwrap_or(usize::MAX))
            {
                Some(l) => {
                    self.losses.push(l);
                    self.busy = false;
                    self.fields_done = false;
                }
                None => break,
            }
        }
        if self.losses.len() == self.points.len() {
            Ok(Step::Done(EvalResponse {
                losses: std::mem::take(&mut self.losses),
            }))
        } else {
            let part = if self.busy {
                0.9 * self.obj.tiles_fraction()
            } else {
                0.0
            };
            let f = (self.losses.len() as f64 + part) / self.points.len() as f64;
            let stage = if self.fields_done {
                "evaluating: loss"
            } else {
                "evaluating: fields"
            };
            Ok(Step::Running(Progress::new(f, stage)))
        }
    }
}

/// Check a `fit-eval` request and start it: losses of many float-parameter
/// vectors against one target (for a worker pool evaluating a population).
pub fn start_eval(req: FitEvalRequest) -> Result<EvalJob> {
    let n = req.extra.points.len();
    if n > lim::EVAL_POINTS {
        return Err(Error::limit(format!(
            "{n} points in one batch; send at most {}",
            lim::EVAL_POINTS
        ))
        .at("points"));
    }
    let p = parse(&req.program)?;
    let vals = named_values(&p, &req.params)?;
    let mut opts = req.options()?;
    let t = req.target_data(&p)?;
    if req.grid.is_none() {
        opts.loss.grid = auto_grid(&t, opts.loss.grid);
    }
    let (scene, prep) =
        super::fit::begin_prepare(&p, &vals, t, &opts.loss).map_err(|e| e.at("program"))?;
    let canvas = scene.rec.canvas;
    let pending = Target::pending(
        super::field::Grid::on(canvas, opts.loss.grid),
        opts.loss.scale_on(canvas),
    );
    Ok(EvalJob {
        obj: Objective::new(scene, pending, opts.loss),
        prep: Some(prep),
        points: req.extra.points,
        losses: Vec::with_capacity(n),
        busy: false,
        fields_done: false,
        budget: EVAL_WORK_PER_STEP,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::job::{run_quietly, Cancel};
    use crate::pattern::generators::generator;

    fn named(pairs: &[(&str, f64)]) -> BTreeMap<String, f64> {
        pairs.iter().map(|(k, v)| (k.to_string(), *v)).collect()
    }

    /// Named values (every parameter) of a fit's float values: the
    /// program's integer values from `ints`, its floats from `floats`.
    fn all_named(src: &str, ints: &BTreeMap<String, f64>, floats: &[f64]) -> BTreeMap<String, f64> {
        let p = parse(src).unwrap();
        let all = named_values(&p, ints).unwrap();
        let mut fl = floats.iter();
        p.params()
            .iter()
            .zip(all)
            .map(|(d, v)| {
                (
                    d.name.clone(),
                    if d.integer { v } else { *fl.next().unwrap() },
                )
            })
            .collect()
    }

    /// A fit with `preview` draws its best values so far in its progress
    /// and its fitted values in its answer, each byte for byte what
    /// `render-pattern` gives for those values at the target's size (the
    /// panel's preview request: `size`, `height`, supersample 1), on a
    /// target that is not square; a picture only when the best changed and
    /// at most every PREVIEW_EVERY_STEPS steps. Without `preview`, none.
    #[test]
    fn a_fits_pictures_are_render_patterns_of_its_values() {
        let (w, h) = (90usize, 60usize);
        for name in ["circles-grid", "honeycomb", "waves", "crosses"] {
            let src = generator(name).unwrap().source;
            // The target: the program at its defaults, anti-aliased (Make target).
            let target = run_quietly(
                start_render(RenderPatternRequest {
                    program: src.into(),
                    size: w,
                    height: Some(h),
                    supersample: 4,
                    ..Default::default()
                })
                .unwrap(),
            )
            .unwrap()
            .image;
            let req = FitRequest {
                program: src.into(),
                target_rgba: Some(RawRgba {
                    width: target.width,
                    height: target.height,
                    rgba: target.rgba,
                }),
                // Small: a GA of 2 × 12 on a 24² grid, 2 × 30 Adam steps.
                init: Init::Genetic,
                grid: Some(24),
                population: Some(12),
                generations: Some(2),
                candidates: Some(2),
                iterations: Some(30),
                polish: Some(5),
                preview: true,
                ..Default::default()
            };
            let render = |floats: &[f64]| {
                run_quietly(
                    start_render(RenderPatternRequest {
                        program: src.into(),
                        params: all_named(src, &req.params, floats),
                        size: w,
                        height: Some(h),
                        ..Default::default()
                    })
                    .unwrap(),
                )
                .unwrap()
                .image
            };
            let mut job = start_fit(&req).unwrap();
            let (mut pictures, mut steps, mut last_at, mut last_values) = (0, 0u32, None, None);
            let out = loop {
                steps += 1;
                match job.step().unwrap() {
                    Step::Running(p) => {
                        if let Some(pic) = p.picture {
                            let v = p.values.clone().expect("a picture comes with its values");
                            assert_eq!(pic, render(&v), "{name}: the picture at step {steps}");
                            assert_ne!(
                                last_values.as_ref(),
                                Some(&v),
                                "{name}: a picture of the same best again"
                            );
                            if let Some(at) = last_at {
                                assert!(
                                    steps - at >= PREVIEW_EVERY_STEPS,
                                    "{name}: pictures {} steps apart",
                                    steps - at
                                );
                            }
                            (pictures, last_at, last_values) = (pictures + 1, Some(steps), Some(v));
                        }
                    }
                    Step::Done(out) => break out,
                }
            };
            assert!(
                pictures >= 1,
                "{name}: the fit drew its best values as it went"
            );
            assert_eq!((out.width, out.height), (w as u32, h as u32));
            assert_eq!(
                out.picture.as_ref(),
                Some(&render(&out.result.params)),
                "{name}: the answer's picture"
            );
            // Without `preview` (the CLI's and the default request): no pictures.
            let plain = FitRequest {
                preview: false,
                ..req.clone()
            };
            let mut job = start_fit(&plain).unwrap();
            let out = loop {
                match job.step().unwrap() {
                    Step::Running(p) => assert!(p.picture.is_none(), "{name}: a picture unasked"),
                    Step::Done(out) => break out,
                }
            };
            assert!(out.picture.is_none());
            assert!(!serde_json::to_string(&plain).unwrap().contains("preview"));
        }
    }

    /// A sharded fit with `preview` sends each best's picture once: after
    /// an exchange every shard holds the same best and only shard 0 draws
    /// it; what a shard found on its own (its refinement candidates), that
    /// shard draws. Every picture is of the best its shard reports, and only
    /// shard 0 answers with one.
    #[test]
    fn a_sharded_fit_draws_each_best_once() {
        use crate::core::parallel::run_sharded;
        let src = generator("circles-grid").unwrap().source;
        let target = run_quietly(
            start_render(RenderPatternRequest {
                program: src.into(),
                size: 48,
                height: Some(32),
                supersample: 2,
                ..Default::default()
            })
            .unwrap(),
        )
        .unwrap()
        .image;
        let req = FitRequest {
            program: src.into(),
            target_rgba: Some(RawRgba {
                width: target.width,
                height: target.height,
                rgba: target.rgba,
            }),
            init: Init::Genetic,
            grid: Some(16),
            population: Some(12),
            generations: Some(3),
            candidates: Some(3),
            iterations: Some(40),
            polish: Some(3),
            preview: true,
            ..Default::default()
        };
        let n = 3;
        let jobs = (0..n)
            .map(|k| {
                start_fit(&FitRequest {
                    shards: Some((k, n)),
                    ..req.clone()
                })
                .unwrap()
            })
            .collect();
        // (shard, values) of every picture, and every shard's bests.
        let mut drawn: Vec<(usize, Vec<f64>)> = vec![];
        let mut bests = vec![vec![]; n];
        let out = run_sharded(jobs, &Cancel::new(), |k, p| {
            if p.picture.is_some() {
                drawn.push((
                    k,
                    p.values.clone().expect("a picture comes with its values"),
                ));
            }
            if let Some(v) = &p.values {
                bests[k].push(v.clone());
            }
        })
        .unwrap();
        assert!(drawn.iter().any(|(k, _)| *k == 0), "shard 0 drew");
        // The shards do hold different bests at times (their own
        // candidates), so drawing by shard 0 alone would miss some.
        assert!(
            (1..n).any(|k| bests[k] != bests[0]),
            "the shards' bests differ somewhere"
        );
        for (i, (k, v)) in drawn.iter().enumerate() {
            assert!(
                !drawn[..i].iter().any(|(_, w)| w == v),
                "shard {k} drew values already drawn"
            );
        }
        assert!(out.picture.is_some(), "shard 0's answer has its picture");
    }

    /// A picture that is not square: `render-pattern` with `height` draws
    /// on the canvas of that aspect (round dots, an SVG of that size),
    /// `pattern-snap` keeps an upload's aspect, and a request written before
    /// `height` existed (no such field) is still the square it was.
    #[test]
    fn pictures_that_are_not_square_keep_their_aspect() {
        let src = "background \"#ffffff\";\ncircle(WIDTH / 2, HEIGHT / 2, 0.3, fill: \"#000000\");";
        let req = RenderPatternRequest {
            program: src.into(),
            size: 150,
            height: Some(100),
            ..Default::default()
        };
        let r = run_quietly(start_render(req).unwrap()).unwrap();
        assert_eq!((r.image.width, r.image.height), (150, 100));
        let dark = |x: u32, y: u32| r.image.rgba[4 * (y * 150 + x) as usize] < 128;
        // Radius 0.3 of the shorter side: 30 px both ways from (75, 50).
        assert!(dark(75, 50) && dark(75 + 29, 50) && dark(75, 50 + 29));
        assert!(!dark(75 + 31, 50) && !dark(75, 50 + 31));
        assert!(
            r.svg.starts_with(
                "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"150\" height=\"100\" viewBox=\"0 0 150 100\">"
            ),
            "{}",
            r.svg
        );
        assert!(
            r.svg.contains("<circle cx=\"75\" cy=\"50\" r=\"30\""),
            "{}",
            r.svg
        );
        let old: RenderPatternRequest =
            serde_json::from_str(&format!("{{\"program\": {src:?}, \"size\": 40}}")).unwrap();
        assert_eq!(old.height, None);
        let r = run_quietly(start_render(old).unwrap()).unwrap();
        assert_eq!((r.image.width, r.image.height), (40, 40));
        // An upload of 300 × 240 snapped to 128 along its longer side.
        let img = crate::raster::Rgba8Image::new(300, 240);
        let snapped = snap_target(&PatternSnapRequest {
            program: src.into(),
            bytes: crate::raster::encode_png(&img).unwrap(),
            size: 128,
            ..Default::default()
        })
        .unwrap();
        assert_eq!((snapped.image.width, snapped.image.height), (128, 102));
    }

    /// The page sends an upload's pixels (`rgba`; the browser decoded the
    /// user's file), the CLI its file (`bytes`): the same image snaps to the
    /// same picture either way, and a request with both or neither is
    /// refused naming `rgba`.
    #[test]
    fn a_snap_of_pixels_is_the_snap_of_their_png() {
        let src = generator("circles-grid").unwrap().source;
        let mut img = crate::raster::Rgba8Image::new(90, 70);
        let mut rng = crate::core::rng::Rng::new(7);
        for v in img.data.iter_mut() {
            *v = (rng.next_u64() >> 56) as u8;
        }
        let base = PatternSnapRequest {
            program: src.into(),
            size: 64,
            ..Default::default()
        };
        let raw = RawRgba {
            width: 90,
            height: 70,
            rgba: img.data.clone(),
        };
        let png = crate::raster::encode_png(&img).unwrap();
        let from_pixels = snap_target(&PatternSnapRequest {
            rgba: Some(raw.clone()),
            ..base.clone()
        })
        .unwrap();
        let from_file = snap_target(&PatternSnapRequest {
            bytes: png.clone(),
            ..base.clone()
        })
        .unwrap();
        assert_eq!(from_pixels.image, from_file.image);
        assert_eq!(from_pixels.unmatched, from_file.unmatched);
        for req in [
            PatternSnapRequest {
                rgba: Some(raw.clone()),
                bytes: png,
                ..base.clone()
            },
            base.clone(),
            PatternSnapRequest {
                rgba: Some(RawRgba {
                    rgba: vec![0; 10],
                    ..raw
                }),
                ..base
            },
        ] {
            let err = snap_target(&req).unwrap_err();
            assert_eq!(err.field(), Some("rgba"), "{err}");
        }
    }

    #[test]
    fn request_level_fit_render_and_batch() {
        let src = generator("circles-grid").unwrap().source;
        let info = program_info(&PatternInfoRequest {
            program: src.into(),
            ..Default::default()
        })
        .unwrap();
        assert_eq!(info.params.len(), 5);
        assert_eq!(info.colours, vec!["#ffffff", "#1f4e79"]);
        let truth = named(&[("dx", 0.2), ("r", 0.05)]);
        let render = RenderPatternRequest {
            program: src.into(),
            params: truth.clone(),
            size: 64,
            ..Default::default()
        };
        let mut job = start_render(render).unwrap();
        let mut steps = 0;
        let r = loop {
            steps += 1;
            match job.step().unwrap() {
                Step::Running(_) => continue,
                Step::Done(r) => break r,
            }
        };
        assert_eq!(steps, 3, "record, raster, SVG");
        assert_eq!((r.image.width, r.image.height), (64, 64));
        let img = Rgba8Image::from_raw(64, 64, r.image.rgba).unwrap();
        let png = crate::raster::encode_png(&img).unwrap();
        let fit = FitRequest {
            program: src.into(),
            target_png: Some(png),
            iterations: Some(30),
            generations: Some(3),
            population: Some(30),
            ..Default::default()
        };
        let out = run_quietly(start_fit(&fit).unwrap()).unwrap();
        assert!(out.svg.contains("<circle"));
        assert!((out.named["r"] - 0.05).abs() < 0.01, "{:?}", out.named);

        let good = vec![0.2, 0.17, 0.12, 0.12, 0.05];
        let bad = vec![0.13, 0.13, 0.06, 0.06, 0.03];
        let points: Vec<Vec<f64>> = (0..40)
            .map(|i| {
                if i % 2 == 0 {
                    good.clone()
                } else {
                    bad.clone()
                }
            })
            .collect();
        let eval = FitEvalRequest {
            program: fit.program.clone(),
            target_png: fit.target_png.clone(),
            extra: EvalPoints { points },
            ..Default::default()
        };
        let mut job = start_eval(eval.clone()).unwrap();
        let mut running = 0;
        let l = loop {
            match job.step().unwrap() {
                Step::Running(p) => {
                    running += 1;
                    assert!(p.fraction < 1.0);
                }
                Step::Done(r) => break r.losses,
            }
        };
        assert!(running >= 1, "40 points at grid 64 take more than one step");
        assert_eq!(l.len(), 40);
        assert!(l[0] < l[1]);
        assert!(
            l.iter().step_by(2).all(|v| *v == l[0]),
            "same point, same loss"
        );
        let short = FitEvalRequest {
            extra: EvalPoints {
                points: vec![vec![0.1]],
            },
            ..eval
        };
        let e = run_quietly(start_eval(short).unwrap()).unwrap_err();
        assert!(e.to_string().contains("point 0 has 1 values"), "{e}");
        assert_eq!(e.field(), Some("points.0"));
        let e = start_render(RenderPatternRequest {
            program: src.into(),
            params: named(&[("radius", 0.1)]),
            ..Default::default()
        })
        .and_then(run_quietly)
        .unwrap_err();
        assert!(e.to_string().contains("no parameter 'radius'"), "{e}");
        assert_eq!(e.field(), Some("params.radius"));
    }

    /// `fit-eval` spread over many small steps (part of one point's fields
    /// per step) gives the same losses, bit for bit, as evaluating each
    /// point in one go with the objective.
    #[test]
    fn fit_eval_stepped_gives_the_same_losses_as_one_go() {
        let src = generator("circles-mix").unwrap().source;
        let p = parse(src).unwrap();
        let x0 = float_values(&p, &p.defaults());
        let points: Vec<Vec<f64>> = (0..4)
            .map(|k| x0.iter().map(|v| v * (1.0 + 0.03 * k as f64)).collect())
            .collect();
        let req = FitEvalRequest {
            program: src.into(),
            target_params: Some(BTreeMap::new()),
            grid: Some(96),
            extra: EvalPoints {
                points: points.clone(),
            },
            ..Default::default()
        };
        // One go: the objective, one whole loss per point.
        let opts = req.options().unwrap();
        let (mut img, mut fl) = (None, vec![]);
        let t = req.target(&p, &mut img, &mut fl).unwrap();
        let vals = named_values(&p, &req.params).unwrap();
        let (scene, target) = crate::pattern::fit::prepare(&p, &vals, &t, &opts.loss).unwrap();
        let mut obj = Objective::new(scene, target, opts.loss);
        let want: Vec<u64> = points.iter().map(|x| obj.loss(x).to_bits()).collect();
        for budget in [1, 1000, u64::MAX] {
            let mut job = start_eval(req.clone()).unwrap();
            job.budget = budget;
            let mut steps = 0;
            let mut last = 0.0;
            let got = loop {
                steps += 1;
                match job.step().unwrap() {
                    Step::Running(p) => {
                        assert!(p.fraction >= last && p.fraction < 1.0);
                        last = p.fraction;
                    }
                    Step::Done(r) => break r.losses,
                }
            };
            let got: Vec<u64> = got.iter().map(|l| l.to_bits()).collect();
            assert_eq!(got, want, "budget {budget}");
            if budget == 1 {
                // One tile a step, then the loss pass a row or so a step.
                assert!(steps >= 4 * (36 + 96), "{steps} steps");
            }
        }
    }

    #[test]
    fn numeric_fields_are_checked_where_they_enter() {
        let src = generator("circles-grid").unwrap().source;
        let base = FitRequest {
            program: src.into(),
            target_params: Some(BTreeMap::new()),
            ..Default::default()
        };
        let field_of =
            |r: &FitRequest| start_fit(r).err().and_then(|e| e.field().map(String::from));
        for (req, field) in [
            (
                FitRequest {
                    tolerance: f64::NAN,
                    target_params: None,
                    target_png: Some(vec![1]),
                    ..base.clone()
                },
                "tolerance",
            ),
            (
                FitRequest {
                    tolerance: -5.0,
                    target_params: None,
                    target_png: Some(vec![1]),
                    ..base.clone()
                },
                "tolerance",
            ),
            (
                FitRequest {
                    grid: Some(4),
                    ..base.clone()
                },
                "grid",
            ),
            (
                FitRequest {
                    population: Some(1_000_000),
                    ..base.clone()
                },
                "population",
            ),
            (
                FitRequest {
                    shards: Some((2, 2)),
                    ..base.clone()
                },
                "shards",
            ),
            (
                FitRequest {
                    params: named(&[("dx", f64::INFINITY)]),
                    ..base.clone()
                },
                "params.dx",
            ),
            (
                FitRequest {
                    program: "circle(0.5 0.5, 0.1);".into(),
                    ..base.clone()
                },
                "program",
            ),
            (
                FitRequest {
                    program: " ".into(),
                    ..base.clone()
                },
                "program",
            ),
        ] {
            assert_eq!(field_of(&req).as_deref(), Some(field), "{req:?}");
        }
        let e = start_render(RenderPatternRequest {
            program: src.into(),
            supersample: usize::MAX,
            ..Default::default()
        })
        .err()
        .unwrap();
        assert_eq!(e.field(), Some("supersample"));
        let e = start_fit(&FitRequest {
            program: "param a in [0, 1] = 0.5;\ncircle(a, a a);\n".into(),
            ..base
        })
        .err()
        .unwrap();
        assert_eq!(
            (e.kind(), e.field(), e.position()),
            ("syntax", Some("program"), Some((2, 13)))
        );
    }
}
