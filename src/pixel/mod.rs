//! Pixel-art texturing ("Pixel"), after Cunha 2025, *Procedural texturing for
//! pixel art* (`papers/pixel-art-texturing.txt`). Files follow Section 3:
//!
//! - [`inputs`]      — §3 intro: source, mask, 3×3 element sheet or one sprite turned eight ways
//! - [`position`]    — §3.1 positions: random / packed, margins, density, partial
//! - [`colour`]      — §3.2 colour maps: HSV shift, colour difference, shared border, auto (d_max)
//! - [`orientation`] — §3.3 strokes → annotated vectors on a K× upscaled grid, averaged down
//! - [`laplace`]     — §3.3 ΔI = 0 with annotations fixed (Neumann border, multigrid-preconditioned CG)
//! - [`placement`]   — §3.4 nearest of eight orientations, per-pixel or region colouring, mask clipping
//!
//! The entry point is [`PixelJob`] (a [`Job`] whose steps are the paper's
//! stages) or [`texture`] to run it at once. Everything random draws from one
//! seeded [`crate::core::rng::Rng`], so the same inputs and seed give the same
//! bytes natively and in wasm.
pub mod api;
pub mod colour;
pub mod inputs;
pub mod laplace;
pub mod orientation;
pub mod placement;
pub mod position;
pub mod state;

pub use colour::{ColourMapKind, ColourStrategy};
pub use inputs::{Direction8, ElementSheet};
pub use laplace::SolveStats;
pub use orientation::Stroke;
pub use placement::ElementColour;
pub use position::PositionStrategy;

use crate::core::error::{Error, Result};
use crate::core::job::{run_quietly, Job, Progress, Step};
use crate::raster::{ColourCounter, Rgba8Image};
use serde::de::{self, IgnoredAny, MapAccess, SeqAccess, Unexpected, Visitor};
use serde::{Deserialize, Deserializer, Serialize};

pub use crate::core::limits::MAX_PALETTE;

/// Every setting of the method, as plain data. Missing fields take the
/// defaults, which follow the thesis (appendix A's most common values and the
/// reference tool's defaults); unknown fields are an error so a typo is seen.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PixelParams {
    /// Upscale factor K of the annotation grid, `1..=32` (reference tool: 4).
    pub annotation_scale: u32,
    /// Position strategy (random).
    pub positions: PositionStrategy,
    /// Density ρ in `0..=1` (1 = 100%).
    pub density: f64,
    /// Margins `[mx, my]` in pixels, may be negative ([0, 0]).
    #[serde(deserialize_with = "crate::core::check::exactly")]
    pub margins: [i32; 2],
    /// Allow elements only partly inside the mask (false).
    pub partial: bool,
    /// Colour strategy (auto).
    pub colour: ColourStrategy,
    /// HSV displacement: hue in degrees, saturation and value in percentage
    /// points ([0, 0, -30], the thesis' Fig. 5b).
    #[serde(deserialize_with = "crate::core::check::exactly")]
    pub hsv: [f64; 3],
    /// RGB colours never used for elements ([[0, 0, 0]]: black outlines).
    #[serde(deserialize_with = "colours")]
    pub exclude: Vec<[u8; 3]>,
    /// Maximum CIELAB distance for the automatic choice (50).
    pub d_max: f64,
    /// Per-pixel or region colouring (region).
    pub element_colour: ElementColour,
    /// Orientation of every element when there are no strokes, and where the
    /// field averages to zero (down, as in the thesis' Fig. 8c).
    pub default_direction: Direction8,
    /// Which way a single sprite (not a sheet) points as drawn (up).
    pub sprite_direction: Direction8,
    /// Seed of every random choice.
    pub seed: u64,
}

/// A number, or what else a list item is (read whole, so an item of the
/// wrong kind is refused by the list's own rule, naming the list).
pub(crate) struct AnyNumber(pub std::result::Result<f64, &'static str>);

impl<'de> Deserialize<'de> for AnyNumber {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        type R<E> = std::result::Result<AnyNumber, E>;
        impl<'de> Visitor<'de> for V {
            type Value = AnyNumber;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("any value")
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> R<E> {
                Ok(AnyNumber(Ok(v)))
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> R<E> {
                Ok(AnyNumber(Ok(v as f64)))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> R<E> {
                Ok(AnyNumber(Ok(v as f64)))
            }
            fn visit_bool<E: de::Error>(self, _: bool) -> R<E> {
                Ok(AnyNumber(Err("true or false")))
            }
            fn visit_str<E: de::Error>(self, _: &str) -> R<E> {
                Ok(AnyNumber(Err("text")))
            }
            fn visit_bytes<E: de::Error>(self, _: &[u8]) -> R<E> {
                Ok(AnyNumber(Err("bytes")))
            }
            fn visit_unit<E: de::Error>(self) -> R<E> {
                Ok(AnyNumber(Err("null")))
            }
            fn visit_none<E: de::Error>(self) -> R<E> {
                self.visit_unit()
            }
            fn visit_some<D: Deserializer<'de>>(self, d: D) -> R<D::Error> {
                AnyNumber::deserialize(d)
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut a: A) -> R<A::Error> {
                while a.next_element::<IgnoredAny>()?.is_some() {}
                Ok(AnyNumber(Err("a list")))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut a: A) -> R<A::Error> {
                while a.next_entry::<IgnoredAny, IgnoredAny>()?.is_some() {}
                Ok(AnyNumber(Err("an object")))
            }
        }
        d.deserialize_any(V)
    }
}

/// A list of `N` numbers, each `ok`; anything else is refused as a whole,
/// in the words of `what` ("must be `what` (got [3, text])").
pub(crate) fn numbers<'de, D, const N: usize>(
    d: D,
    what: &'static str,
    ok: fn(f64) -> bool,
) -> std::result::Result<[f64; N], D::Error>
where
    D: Deserializer<'de>,
{
    struct V<const N: usize>(&'static str, fn(f64) -> bool);
    impl<'de, const N: usize> Visitor<'de> for V<N> {
        type Value = [f64; N];
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str(self.0)
        }
        fn visit_seq<A: SeqAccess<'de>>(self, mut a: A) -> std::result::Result<[f64; N], A::Error> {
            let mut items = Vec::with_capacity(N);
            while let Some(AnyNumber(x)) = a.next_element()? {
                items.push(x);
            }
            let fine = items.len() == N && items.iter().all(|x| x.is_ok_and(self.1));
            if fine {
                let xs: Vec<f64> = items.into_iter().map(|x| x.unwrap_or(0.0)).collect();
                return Ok(xs.try_into().unwrap_or([0.0; N]));
            }
            if items.len() != N {
                let n = items.len();
                return Err(de::Error::invalid_value(
                    Unexpected::Other(&format!("a list of {n} items")),
                    &self,
                ));
            }
            let words: Vec<String> = items
                .iter()
                .map(|x| match x {
                    Ok(v) => crate::core::value::js_number(*v),
                    Err(what) => what.to_string(),
                })
                .collect();
            Err(de::Error::invalid_value(
                Unexpected::Other(&format!("[{}]", words.join(", "))),
                &self,
            ))
        }
    }
    d.deserialize_seq(V::<N>(what, ok))
}

/// `exclude`: each colour a list `[r, g, b]` of whole numbers 0–255.
fn colours<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Vec<[u8; 3]>, D::Error> {
    struct Rgb([u8; 3]);
    impl<'de> Deserialize<'de> for Rgb {
        fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
            let c = numbers::<D, 3>(
                d,
                "an [r, g, b] colour (whole numbers from 0 to 255)",
                |v| v.fract() == 0.0 && (0.0..=255.0).contains(&v),
            )?;
            Ok(Rgb(c.map(|v| v as u8)))
        }
    }
    Ok(Vec::<Rgb>::deserialize(d)?
        .into_iter()
        .map(|c| c.0)
        .collect())
}

impl Default for PixelParams {
    fn default() -> Self {
        PixelParams {
            annotation_scale: 4,
            positions: PositionStrategy::Random,
            density: 1.0,
            margins: [0, 0],
            partial: false,
            colour: ColourStrategy::Auto,
            hsv: [0.0, 0.0, -30.0],
            exclude: vec![[0, 0, 0]],
            d_max: 50.0,
            element_colour: ElementColour::Region,
            default_direction: Direction8::Down,
            sprite_direction: Direction8::Up,
            seed: 0,
        }
    }
}

/// The element as given by the user.
#[derive(Debug, Clone)]
pub enum Elements {
    /// A 3×3 sheet (see [`ElementSheet::from_sheet`]).
    Sheet(Rgba8Image),
    /// One sprite, turned into eight orientations (see [`ElementSheet::from_sprite`]).
    Sprite(Rgba8Image),
}

/// The images and strokes of one run.
#[derive(Debug, Clone)]
pub struct PixelInputs {
    /// The pixel art to texture.
    pub source: Rgba8Image,
    /// Same size as `source`; see [`inputs::mask_from_image`].
    pub mask: Rgba8Image,
    pub elements: Elements,
    /// Brush strokes in source-pixel coordinates; may be empty.
    pub strokes: Vec<Stroke>,
}

/// Figures of a finished run.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PixelStats {
    /// Elements that drew at least one pixel.
    pub placed: usize,
    /// Positions chosen (after density).
    pub positions: usize,
    /// Distinct colours (alpha > 0) in the source and in the result.
    pub colours_before: usize,
    pub colours_after: usize,
    /// The colour map used (what `auto` resolved to).
    pub colour_map_used: ColourMapKind,
    /// Source pixels carrying a stroke vector.
    pub annotated_pixels: usize,
    /// The Laplace solve, when there were strokes.
    pub solve: Option<SolveStats>,
}

/// Everything a run produces.
#[derive(Debug, Clone)]
pub struct PixelOutput {
    /// The textured image, same size as the source.
    pub image: Rgba8Image,
    /// The colour map elements were coloured from.
    pub colour_map: Rgba8Image,
    /// The diffused orientation field, one `[x, y]` per pixel, row-major
    /// (y down). Not normalised; without strokes every entry is the default
    /// direction's unit vector.
    pub field: Vec<[f32; 2]>,
    /// Top-left corners of the placed cells, in placement order.
    pub positions: Vec<(i32, i32)>,
    pub stats: PixelStats,
}

/// The stage a [`PixelJob`] will work on at its next step.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stage {
    Positions,
    ColourMap,
    Orientation,
    Placement,
    Done,
}

impl Stage {
    /// Name used in progress messages and benchmarks.
    pub fn name(self) -> &'static str {
        match self {
            Stage::Positions => "positions",
            Stage::ColourMap => "colour map",
            Stage::Orientation => "orientation solve",
            Stage::Placement => "placement",
            Stage::Done => "done",
        }
    }
}

/// Work per step: pixel tests of the positions search, pixel visits of the
/// solver and of the placement, pixels of the colour map and the colour
/// count. At 4096² with a full mask a step of any stage stays around
/// 5–15 ms (`filigree bench slices`); the output never depends on it.
pub const STEP_BUDGET: usize = 200_000;

/// The whole method as a resumable [`Job`]: positions (several steps on big
/// masks), colour map (one step), orientation (annotation, then solver
/// iterations over several steps), placement (one step).
pub struct PixelJob {
    params: PixelParams,
    source: Rgba8Image,
    mask: Vec<bool>,
    sheet: ElementSheet,
    strokes: Vec<Stroke>,
    stage: Stage,
    /// Checks of every pixel still to do before the positions (see
    /// [`PixelJob::start`]).
    checks: Option<Checks>,
    sampler: Option<position::PositionSampler>,
    positions: Vec<(i32, i32)>,
    colour_map: Option<colour::ColourMap>,
    mapper: Option<colour::ColourMapper>,
    annotated: usize,
    solver: Option<laplace::FieldSolver>,
    field: Vec<[f32; 2]>,
    solve: Option<SolveStats>,
    placer: Option<placement::Placer>,
    /// The placer's copy of the source is complete.
    copied: bool,
    /// The placed image and element count once placement is done, while
    /// its colours (and, with HSV, the source's) are counted.
    placed: Option<(Rgba8Image, usize)>,
    counter: Option<ColourCounter>,
    colours_before: Option<usize>,
    colours_after: Option<usize>,
    /// Work per step ([`STEP_BUDGET`]).
    budget: usize,
}

/// Where [`PixelJob::run_checks`] is: the next pixel to look at, whether
/// an opaque source pixel and a marked mask pixel were found, and the
/// source's colour count (palette colour maps only).
struct Checks {
    next: usize,
    opaque: bool,
    marked: bool,
    counter: Option<ColourCounter>,
}

impl PixelJob {
    /// Check every input and parameter; errors say what to change.
    pub fn new(inputs: PixelInputs, params: PixelParams) -> Result<PixelJob> {
        let PixelInputs {
            source,
            mask,
            elements,
            strokes,
        } = inputs;
        let mask = inputs::check_source_and_mask(&source, &mask)?;
        let mut job = PixelJob::start(source, mask, elements, strokes, params)?;
        // The source has an opaque pixel and the mask a marked one (checked
        // above): only the colour count is left of the checks.
        if let Some(c) = &mut job.checks {
            c.opaque = true;
            c.marked = true;
        }
        while job.checks.is_some() {
            job.run_checks(usize::MAX)?;
        }
        Ok(job)
    }

    /// Check the inputs and parameters that are cheap to check and set the
    /// job up; the checks that read every pixel (a source that is not fully
    /// transparent, a mask that marks a pixel, the palette limit) run in the
    /// job's first steps, a bounded part a step, with the same errors as
    /// [`PixelJob::new`]. `mask` is the mask as booleans (see
    /// [`inputs::mask_from_image`]), row-major, the source's size.
    pub fn start(
        source: Rgba8Image,
        mask: Vec<bool>,
        elements: Elements,
        strokes: Vec<Stroke>,
        params: PixelParams,
    ) -> Result<PixelJob> {
        source.validate()?;
        if mask.len() != source.pixel_count() {
            return Err(Error::input(format!(
                "the mask has {} values but the source image is {}×{}; they must be the same size",
                mask.len(),
                source.width,
                source.height
            )));
        }
        let (Elements::Sheet(img) | Elements::Sprite(img)) = &elements;
        img.validate()?;
        let sheet = match &elements {
            Elements::Sheet(img) => ElementSheet::from_sheet(img)?,
            Elements::Sprite(img) => ElementSheet::from_sprite(img, params.sprite_direction)?,
        };
        if params.annotation_scale == 0
            || params.annotation_scale > orientation::MAX_ANNOTATION_SCALE
        {
            return Err(Error::limit(format!(
                "annotation scale {} is outside 1..={} (the annotation scale limit)",
                params.annotation_scale,
                orientation::MAX_ANNOTATION_SCALE
            )));
        }
        orientation::check_strokes(source.width, source.height, &strokes)?;
        if !params.hsv.iter().all(|v| v.is_finite()) {
            return Err(Error::input("the HSV shift must be three finite numbers"));
        }
        if !(params.d_max.is_finite() && params.d_max >= 0.0) {
            return Err(Error::input(format!(
                "d_max {} must be a number ≥ 0",
                params.d_max
            )));
        }
        let pp = position::PositionParams {
            strategy: params.positions,
            margins: params.margins,
            density: params.density,
            partial: params.partial,
        };
        let sampler = position::PositionSampler::new(
            source.width,
            source.height,
            &mask,
            sheet.side,
            pp,
            params.seed,
        )?;
        let checks = Checks {
            next: 0,
            opaque: false,
            marked: false,
            counter: (params.colour != ColourStrategy::Hsv).then(ColourCounter::new),
        };
        Ok(PixelJob {
            params,
            source,
            mask,
            sheet,
            strokes,
            stage: Stage::Positions,
            checks: Some(checks),
            sampler: Some(sampler),
            positions: vec![],
            colour_map: None,
            mapper: None,
            annotated: 0,
            solver: None,
            field: vec![],
            solve: None,
            placer: None,
            copied: false,
            placed: None,
            counter: None,
            colours_before: None,
            colours_after: None,
            budget: STEP_BUDGET,
        })
    }

    /// About `budget` pixels more of the checks [`PixelJob::start`] left
    /// for the steps; drops them once complete. Errors name the request
    /// field to change (`mask`, `params`).
    fn run_checks(&mut self, budget: usize) -> Result<()> {
        let c = self.checks.as_mut().expect("checks under way");
        let n = self.source.pixel_count();
        let budget = budget.max(1);
        if !(c.opaque && c.marked) {
            let end = n.min(c.next.saturating_add(budget));
            for i in c.next..end {
                c.opaque |= self.source.at(i)[3] != 0;
                c.marked |= self.mask[i];
            }
            c.next = end;
            if c.opaque && c.marked {
                return Ok(());
            }
            if end < n {
                return Ok(());
            }
            let (w, h) = (self.source.width, self.source.height);
            if !c.opaque {
                return Err(Error::input(format!(
                    "the {w}×{h} source image is fully transparent: there is nothing to texture"
                ))
                .at("mask"));
            }
            return Err(Error::input(format!(
                "the {w}×{h} mask is empty: no pixel is marked for texturing \
                 (inside = opaque pixels, or bright pixels when the mask has no transparency)"
            ))
            .at("mask"));
        }
        if let Some(counter) = &mut c.counter {
            if !counter.run(&self.source, 0, budget, MAX_PALETTE) {
                return Ok(());
            }
            if counter.count() > MAX_PALETTE {
                return Err(Error::limit(format!(
                    "the source has more than {MAX_PALETTE} colours; the palette limit of the \
                     palette-based colour maps is {MAX_PALETTE} \
                     (is it pixel art? the HSV shift has no such limit)"
                ))
                // The colour map is the setting to change (the CLI's
                // --colour; it named --params, which Pixel does not have).
                .at("params.colour"));
            }
            self.colours_before = Some(counter.count());
        }
        self.checks = None;
        Ok(())
    }

    /// The stage the next [`Job::step`] works on.
    /// The same job with `budget` units of work per step instead of
    /// [`STEP_BUDGET`] (for tests that check the steps do not matter).
    pub fn with_budget(mut self, budget: usize) -> Self {
        self.budget = budget.max(1);
        self
    }

    pub fn stage(&self) -> Stage {
        self.stage
    }

    /// The element sheet in use (eight sprites).
    pub fn sheet(&self) -> &ElementSheet {
        &self.sheet
    }

    fn progress(&self, fraction: f64) -> Step<PixelOutput> {
        Step::Running(Progress::new(fraction, self.stage.name()))
    }
}

impl Job for PixelJob {
    type Output = PixelOutput;

    fn step(&mut self) -> Result<Step<PixelOutput>> {
        if self.checks.is_some() {
            self.run_checks(self.budget)?;
            return Ok(Step::Running(Progress::new(0.0, "checking the inputs")));
        }
        match self.stage {
            Stage::Positions => {
                let s = self
                    .sampler
                    .as_mut()
                    .expect("sampler until positions are done");
                if s.run(&self.mask, self.budget) {
                    self.positions = self.sampler.take().expect("present").into_positions();
                    self.stage = Stage::ColourMap;
                    return Ok(self.progress(0.25));
                }
                let f = s.fraction();
                Ok(self.progress(0.25 * f))
            }
            Stage::ColourMap => {
                let mapper = self.mapper.get_or_insert_with(|| {
                    let p = colour::ColourParams {
                        strategy: self.params.colour,
                        hsv: self.params.hsv,
                        exclude: self.params.exclude.clone(),
                        d_max: self.params.d_max,
                    };
                    colour::ColourMapper::new(&self.source, &p)
                });
                if mapper.run(&self.source, &self.mask, self.budget) {
                    self.colour_map = self.mapper.take().map(colour::ColourMapper::finish);
                    self.stage = Stage::Orientation;
                    return Ok(self.progress(0.35));
                }
                let f = 0.25 + 0.1 * mapper.fraction();
                Ok(self.progress(f))
            }
            Stage::Orientation => {
                let (w, h) = (self.source.width, self.source.height);
                match self.solver.as_mut() {
                    None => {
                        let a = orientation::annotate_sparse(
                            w,
                            h,
                            &self.strokes,
                            self.params.annotation_scale,
                        )?;
                        self.annotated = a.len();
                        if self.annotated == 0 {
                            let u = self.params.default_direction.unit();
                            self.field = vec![[u[0] as f32, u[1] as f32]; (w * h) as usize];
                            self.stage = Stage::Placement;
                            return Ok(self.progress(0.9));
                        }
                        self.solver = Some(laplace::FieldSolver::new(w as usize, h as usize, a));
                        Ok(self.progress(0.36))
                    }
                    Some(solver) => {
                        if solver.run(self.budget) {
                            self.solve = Some(solver.stats());
                            self.field = self.solver.take().expect("running").into_field();
                            self.stage = Stage::Placement;
                            return Ok(self.progress(0.9));
                        }
                        let f = 0.36 + 0.54 * solver.fraction();
                        Ok(self.progress(f))
                    }
                }
            }
            Stage::Placement => {
                let cm = self
                    .colour_map
                    .as_ref()
                    .expect("colour map before placement");
                if self.placed.is_none() {
                    let placer = self
                        .placer
                        .get_or_insert_with(|| placement::Placer::new(&self.source));
                    if !self.copied {
                        // The output starts as the source: copied in parts
                        // (64 MB at 4096²), copying is cheap per pixel.
                        self.copied =
                            placer.copy_source(&self.source, self.budget.saturating_mul(16));
                        return Ok(self.progress(0.9));
                    }
                    let inputs = placement::PlaceInputs {
                        mask: &self.mask,
                        sheet: &self.sheet,
                        positions: &self.positions,
                        field: &self.field,
                        colour_map: &cm.map,
                        mode: self.params.element_colour,
                        default: self.params.default_direction,
                    };
                    if placer.run(&inputs, self.budget) {
                        self.placed = self.placer.take().map(placement::Placer::finish);
                    }
                    let f = self
                        .placer
                        .as_ref()
                        .map_or(1.0, |p| p.fraction(self.positions.len()));
                    return Ok(self.progress(0.9 + 0.08 * f));
                }
                // Count colours a slice at a time: the result's, then (with
                // the HSV map, which has no palette limit) the source's.
                let (image, _) = self.placed.as_ref().expect("placed");
                let counter = self.counter.get_or_insert_with(ColourCounter::new);
                if self.colours_after.is_none() {
                    if counter.run(image, 0, self.budget, usize::MAX) {
                        self.colours_after = Some(counter.count());
                        self.counter = None;
                    }
                    return Ok(self.progress(0.99));
                }
                if self.colours_before.is_none() {
                    if counter.run(&self.source, 0, self.budget, usize::MAX) {
                        self.colours_before = Some(counter.count());
                        self.counter = None;
                    }
                    return Ok(self.progress(0.995));
                }
                let cm = self.colour_map.take().expect("colour map before placement");
                let (image, placed) = self.placed.take().expect("placed");
                self.stage = Stage::Done;
                let stats = PixelStats {
                    placed,
                    positions: self.positions.len(),
                    colours_before: self.colours_before.unwrap_or(0),
                    colours_after: self.colours_after.unwrap_or(0),
                    colour_map_used: cm.kind,
                    annotated_pixels: self.annotated,
                    solve: self.solve,
                };
                Ok(Step::Done(PixelOutput {
                    image,
                    colour_map: cm.map,
                    field: std::mem::take(&mut self.field),
                    positions: std::mem::take(&mut self.positions),
                    stats,
                }))
            }
            Stage::Done => Err(Error::input("this pixel job has already finished")),
        }
    }
}

/// Run the whole method at once (native callers and tests).
pub fn texture(inputs: PixelInputs, params: PixelParams) -> Result<PixelOutput> {
    run_quietly(PixelJob::new(inputs, params)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fish case scaled up `k` times (source, mask, sheet, strokes).
    fn fish(k: u32) -> PixelInputs {
        use crate::raster::{decode, Limits};
        let img = |b: &[u8]| decode(b, Limits::default()).unwrap();
        let up = |m: &Rgba8Image| {
            let mut out = Rgba8Image::new(m.width * k, m.height * k);
            for y in 0..out.height {
                for x in 0..out.width {
                    out.put(x, y, m.get(x / k, y / k));
                }
            }
            out
        };
        #[derive(serde::Deserialize)]
        struct Strokes {
            strokes: Vec<Stroke>,
        }
        let s: Strokes =
            serde_json::from_slice(include_bytes!("../../assets/pixel/fish_strokes.json")).unwrap();
        PixelInputs {
            source: up(&img(include_bytes!("../../assets/pixel/fish.png"))),
            mask: up(&img(include_bytes!(
                "../../assets/pixel/fish_body_boundary.png"
            ))),
            elements: Elements::Sheet(img(include_bytes!("../../assets/pixel/fish_scale.png"))),
            strokes: s
                .strokes
                .into_iter()
                .map(|st| {
                    st.into_iter()
                        .map(|p| [p[0] * k as f32, p[1] * k as f32])
                        .collect()
                })
                .collect(),
        }
    }

    /// The whole job with small steps (every stage spread over many) gives
    /// the same bytes as with the default budget and with one that does
    /// each stage in one go.
    #[test]
    fn stepping_the_whole_job_gives_the_same_bytes_whatever_the_budget() {
        for colour in [ColourStrategy::Auto, ColourStrategy::Hsv] {
            let params = PixelParams {
                positions: PositionStrategy::Packed,
                partial: true,
                colour,
                seed: 7,
                ..Default::default()
            };
            let mut outs = vec![];
            for budget in [2_000, STEP_BUDGET, usize::MAX] {
                let job = PixelJob::new(fish(3), params.clone())
                    .unwrap()
                    .with_budget(budget);
                let mut steps = 0;
                let mut job = job;
                let out = loop {
                    steps += 1;
                    if let Step::Done(out) = job.step().unwrap() {
                        break out;
                    }
                };
                outs.push((steps, out));
            }
            assert!(
                outs[0].0 > outs[2].0 + 100,
                "{} vs {} steps",
                outs[0].0,
                outs[2].0
            );
            for (_, o) in &outs[1..] {
                let a = &outs[0].1;
                assert!(o.image == a.image && o.colour_map == a.colour_map);
                assert_eq!(o.positions, a.positions);
                assert_eq!(o.stats, a.stats);
                assert!(o
                    .field
                    .iter()
                    .zip(&a.field)
                    .all(|(p, q)| p[0].to_bits() == q[0].to_bits()
                        && p[1].to_bits() == q[1].to_bits()));
            }
        }
    }

    /// The whole output as comparable text (floats as their bits).
    fn bits(o: &PixelOutput) -> String {
        let field: Vec<[u32; 2]> = o
            .field
            .iter()
            .map(|p| [p[0].to_bits(), p[1].to_bits()])
            .collect();
        format!(
            "{:?} {:?} {:?} {:?} {:?}",
            o.image.data, o.positions, o.stats, o.colour_map, field
        )
    }

    /// A job started with [`PixelJob::start`] (the checks of every pixel
    /// done in its first steps, a budget at a time) gives the bytes of
    /// [`PixelJob::new`] (checks at once), whatever the budget.
    #[test]
    fn checks_in_the_steps_give_the_same_bytes() {
        for colour in [ColourStrategy::Auto, ColourStrategy::Hsv] {
            let params = PixelParams {
                colour,
                seed: 3,
                ..Default::default()
            };
            let want = bits(&texture(fish(2), params.clone()).unwrap());
            for budget in [500, STEP_BUDGET] {
                let PixelInputs {
                    source,
                    mask,
                    elements,
                    strokes,
                } = fish(2);
                let mask = inputs::mask_from_image(&mask);
                let mut job = PixelJob::start(source, mask, elements, strokes, params.clone())
                    .unwrap()
                    .with_budget(budget);
                let mut checking = 0;
                let out = loop {
                    match job.step().unwrap() {
                        Step::Running(p) if p.stage == "checking the inputs" => checking += 1,
                        Step::Running(_) => {}
                        Step::Done(out) => break out,
                    }
                };
                assert_eq!(bits(&out), want, "{colour:?}, budget {budget}");
                if budget == 500 && colour != ColourStrategy::Hsv {
                    // The colour count reads every pixel, 500 a step.
                    assert!(checking >= job.source.pixel_count() / 500, "{checking}");
                }
            }
        }
    }

    /// The pixel checks left to the steps fail there with the errors (and
    /// request fields) [`PixelJob::new`] gives at once.
    #[test]
    fn checks_in_the_steps_fail_with_the_same_errors() {
        let run = |source: Rgba8Image, mask: Vec<bool>, colour| {
            let PixelInputs {
                elements, strokes, ..
            } = fish(1);
            let params = PixelParams {
                colour,
                ..Default::default()
            };
            let job = PixelJob::start(source, mask, elements, strokes, params).unwrap();
            run_quietly(job.with_budget(100)).unwrap_err()
        };
        let base = fish(1);
        let (w, h) = (base.source.width, base.source.height);
        let full = vec![true; (w * h) as usize];
        let e = run(Rgba8Image::new(w, h), full.clone(), ColourStrategy::Auto);
        assert!(e.to_string().contains("fully transparent"), "{e}");
        assert_eq!(e.field(), Some("mask"));
        let e = run(
            base.source.clone(),
            vec![false; (w * h) as usize],
            ColourStrategy::Auto,
        );
        assert!(e.to_string().contains("mask is empty"), "{e}");
        assert_eq!(e.field(), Some("mask"));
        let mut many = base.source.clone();
        for (i, px) in many.data.chunks_exact_mut(4).enumerate() {
            px.copy_from_slice(&[i as u8, (i >> 8) as u8, 7, 255]);
        }
        assert!(
            (w * h) as usize > MAX_PALETTE,
            "the fish has room for the palette limit"
        );
        let e = run(many, full, ColourStrategy::Auto);
        assert!(e.to_string().contains("palette limit"), "{e}");
        assert_eq!(e.field(), Some("params.colour"));
    }

    /// A `pixel` request from encoded files: `start_pixel` decodes
    /// nothing (a corrupt file is refused by the first step, naming its
    /// field), the images are read a bounded part a step, and the result is
    /// the bytes of [`PixelJob::new`] on the decoded images.
    #[test]
    fn a_request_decodes_its_images_in_steps() {
        use super::api::{start_pixel, MaskBits, PixelRequest};
        use crate::raster::{encode_png, DECODE_PIXELS_PER_STEP};
        let inputs = fish(8);
        let params = PixelParams {
            seed: 5,
            ..Default::default()
        };
        let want = bits(&texture(inputs.clone(), params.clone()).unwrap());
        let Elements::Sheet(sheet) = &inputs.elements else {
            unreachable!()
        };
        let req = PixelRequest {
            source: encode_png(&inputs.source).unwrap(),
            mask: MaskBits::of_image(&inputs.mask),
            sheet: Some(encode_png(sheet).unwrap()),
            sprite: None,
            strokes: inputs.strokes.clone(),
            params,
        };
        let mut job = start_pixel(req.clone()).unwrap();
        let mut reading = 0;
        let out = loop {
            match job.step().unwrap() {
                Step::Running(p) if p.stage == "reading pixels" => reading += 1,
                Step::Running(_) => {}
                Step::Done(out) => break out,
            }
        };
        assert_eq!(bits(&out), want);
        let rows = inputs.source.pixel_count() / DECODE_PIXELS_PER_STEP;
        assert!(rows >= 2 && reading >= rows, "{reading} reading steps");

        let fails = |req: PixelRequest, field: &str, says: &str| {
            let job = start_pixel(req).expect("nothing is decoded at the start");
            let e = run_quietly(job).unwrap_err();
            assert_eq!(e.field(), Some(field), "{e}");
            assert!(e.to_string().contains(says), "{e}");
        };
        let mut bad = req.clone();
        bad.source.truncate(bad.source.len() / 2);
        fails(bad, "source", "");
        let mut bad = req.clone();
        bad.sheet = Some(b"not an image".to_vec());
        fails(bad, "sheet", "");
        let mut bad = req.clone();
        bad.mask = MaskBits {
            width: 3,
            height: 2,
            bits: vec![1; 6],
        };
        fails(bad, "mask", "must be the same size");
        let mut bad = req;
        bad.sheet = None;
        bad.sprite = Some(encode_png(&Rgba8Image::new(5, 3)).unwrap());
        fails(bad, "sprite", "");
    }

    /// The Pixel module's readers in wasm (`pixel` and `pixel-mask` with
    /// [`decode_png`](crate::raster::decode_png), as
    /// [`decode_sent`](crate::raster::decode_sent) is there) give the bytes
    /// of every-format reading for PNG inputs (the mask's decoded in one go,
    /// the request's images in parts), and refuse a JPEG source,
    /// sheet or mask as `unsupported`, naming its field. This would catch a
    /// Pixel module that reads only PNG but a page or a path that still sends
    /// or reads another format.
    #[test]
    fn the_png_only_pixel_reads_pngs_as_every_format_does_and_refuses_a_jpeg() {
        use super::api::{
            mask_bits, mask_bits_with, start_pixel, start_pixel_with, MaskBits, PixelMaskRequest,
            PixelRequest,
        };
        use crate::raster::{decode, decode_png, encode_png, Decoder};
        use image::{ExtendedColorType, ImageEncoder};
        let inputs = fish(8);
        let params = PixelParams {
            seed: 3,
            ..Default::default()
        };
        let Elements::Sheet(sheet) = &inputs.elements else {
            unreachable!()
        };
        let req = PixelRequest {
            source: encode_png(&inputs.source).unwrap(),
            mask: MaskBits::of_image(&inputs.mask),
            sheet: Some(encode_png(sheet).unwrap()),
            sprite: None,
            strokes: inputs.strokes.clone(),
            params,
        };
        let run = |req: PixelRequest, whole: Decoder| {
            run_quietly(start_pixel_with(req, whole).expect("nothing is decoded at the start"))
        };
        let every = bits(&run_quietly(start_pixel(req.clone()).unwrap()).unwrap());
        assert_eq!(bits(&run(req.clone(), decode).unwrap()), every);
        assert_eq!(bits(&run(req.clone(), decode_png).unwrap()), every);

        let jpeg = |img: &Rgba8Image| {
            let rgb: Vec<u8> = img
                .data
                .chunks_exact(4)
                .flat_map(|p| [p[0], p[1], p[2]])
                .collect();
            let mut out = vec![];
            image::codecs::jpeg::JpegEncoder::new_with_quality(&mut out, 100)
                .write_image(&rgb, img.width, img.height, ExtendedColorType::Rgb8)
                .unwrap();
            out
        };
        let refused = |e: crate::core::error::Error, field: &str| {
            assert_eq!(e.kind(), "unsupported", "{e}");
            assert_eq!(e.field(), Some(field), "{e}");
            assert!(e.to_string().contains("JPEG"), "{e}");
        };
        let mut j = req.clone();
        j.source = jpeg(&inputs.source);
        assert!(
            run(j.clone(), decode).is_ok(),
            "natively a JPEG source is read"
        );
        refused(run(j, decode_png).unwrap_err(), "source");
        let mut j = req.clone();
        j.sheet = Some(jpeg(sheet));
        refused(run(j, decode_png).unwrap_err(), "sheet");

        let mask_png = PixelMaskRequest {
            bytes: encode_png(&inputs.mask).unwrap(),
        };
        assert_eq!(
            mask_bits_with(&mask_png, decode_png).unwrap(),
            mask_bits(&mask_png).unwrap()
        );
        let mask_jpeg = PixelMaskRequest {
            bytes: jpeg(&inputs.mask),
        };
        assert!(mask_bits_with(&mask_jpeg, decode).is_ok());
        refused(mask_bits_with(&mask_jpeg, decode_png).unwrap_err(), "bytes");
    }

    #[test]
    fn params_defaults_and_json_names() {
        let p: PixelParams = serde_json::from_str("{}").unwrap();
        assert_eq!(p, PixelParams::default());
        let p: PixelParams = serde_json::from_str(
            r#"{"positions":"packed","colour":"border","element_colour":"pixel","default_direction":"up-left","margins":[-1,2]}"#,
        )
        .unwrap();
        assert_eq!(p.positions, PositionStrategy::Packed);
        assert_eq!(p.colour, ColourStrategy::Border);
        assert_eq!(p.element_colour, ElementColour::Pixel);
        assert_eq!(p.default_direction, Direction8::UpLeft);
        assert_eq!(p.margins, [-1, 2]);
        let e = serde_json::from_str::<PixelParams>(r#"{"dmax": 3}"#)
            .unwrap_err()
            .to_string();
        assert!(e.contains("dmax"), "{e}");
    }
}
