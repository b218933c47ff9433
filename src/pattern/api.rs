//! Plain-data entry points used by the wasm boundary and the CLI: programs
//! as text, parameters by name, images as encoded bytes.
use super::field::Scene;
use super::fit::{Budget, FitJob, FitOptions, FitResult, TargetSource};
use super::loss::{LossKind, LossOptions, Objective};
use super::optim::InitMethod;
use super::record::{Program, RecordLimits};
use super::render;
use super::target::Target;
use crate::core::error::{Error, Result};
use crate::raster::{decode, Limits, Rgba8Image};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Values of all declared parameters from a name → value map; missing
/// names take their defaults, unknown names are an error.
pub fn named_values(program: &Program, named: &BTreeMap<String, f64>) -> Result<Vec<f64>> {
    let mut vals = program.defaults();
    for (k, v) in named {
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
            })?;
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
pub fn program_info(src: &str, named: &BTreeMap<String, f64>) -> Result<ProgramInfo> {
    let p = Program::parse(src)?;
    let vals = named_values(&p, named)?;
    let rec = p.record(&vals, &RecordLimits::default())?;
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
        colours: rec.colours.iter().map(|c| hex(*c)).collect(),
        shapes: rec.shapes.len(),
    })
}

/// A drawn pattern.
#[derive(Debug, Clone)]
pub struct Rendered {
    pub image: Rgba8Image,
    pub svg: String,
}

/// Draw a program with named values at `size × size` (1..=2048) with
/// `supersample²` samples per pixel, plus its SVG.
pub fn render_program(
    src: &str,
    named: &BTreeMap<String, f64>,
    size: usize,
    supersample: usize,
) -> Result<Rendered> {
    if !(1..=2048).contains(&size) {
        return Err(Error::limit(format!(
            "size {size} is outside 1..=2048 pixels"
        )));
    }
    let p = Program::parse(src)?;
    let vals = named_values(&p, named)?;
    let rec = p.record(&vals, &RecordLimits::default())?;
    let fl = rec.float_values();
    let scene = Scene::new(rec);
    Ok(Rendered {
        image: render::render(&scene, &fl, size, supersample.clamp(1, 4))?,
        svg: render::svg(&scene, &fl, size as f64)?,
    })
}

/// Where a fit's target comes from, as plain data.
#[derive(Debug, Clone, Default)]
pub struct TargetSpec {
    /// An encoded image (PNG, JPEG, ...).
    pub image: Option<Vec<u8>>,
    /// Or raw RGBA: (width, height, bytes).
    pub rgba: Option<(u32, u32, Vec<u8>)>,
    /// Or the program drawn with these values ("make target").
    pub params: Option<BTreeMap<String, f64>>,
    /// RGB distance within which a pixel matches a palette colour (default 60).
    pub tolerance: Option<f64>,
}

/// Settings of a fit request; every field is optional.
#[derive(Debug, Clone, Default, Deserialize)]
#[serde(default)]
pub struct FitSettings {
    /// `quick` (default) or `paper`.
    pub budget: Option<String>,
    /// `sdf` (default), `l1`, `pyramid`, `image`.
    pub loss: Option<String>,
    /// `genetic` (default), `random`, `nelder-mead`.
    pub init: Option<String>,
    pub seed: Option<u64>,
    /// Loss grid side (8..=1024).
    pub grid: Option<usize>,
    /// Overrides of the budget: population, generations, candidates, iterations.
    pub population: Option<usize>,
    pub generations: Option<usize>,
    pub candidates: Option<usize>,
    pub iterations: Option<usize>,
    /// Adam iterations on the image-space loss after the fit (default 0 = off).
    pub polish: Option<usize>,
    /// `[k, n]`: this job is shard k of n of one fit (see `FitOptions::shards`).
    pub shards: Option<(usize, usize)>,
}

/// Options from settings, with errors naming the bad value.
pub fn fit_options(s: &FitSettings) -> Result<FitOptions> {
    let b = s.budget.as_deref().unwrap_or("quick");
    let mut o = FitOptions::budget(
        Budget::parse(b)
            .ok_or_else(|| Error::input(format!("unknown budget '{b}' (quick, paper)")))?,
    );
    if let Some(l) = &s.loss {
        o.loss.kind = LossKind::parse(l)
            .ok_or_else(|| Error::input(format!("unknown loss '{l}' (sdf, l1, pyramid, image)")))?;
    }
    if let Some(i) = &s.init {
        o.init = match i.as_str() {
            "genetic" => InitMethod::Genetic,
            "random" => InitMethod::Random,
            "nelder-mead" => InitMethod::NelderMead,
            _ => {
                return Err(Error::input(format!(
                    "unknown init '{i}' (genetic, random, nelder-mead)"
                )))
            }
        };
    }
    if let Some(v) = s.seed {
        o.seed = v;
    }
    if let Some(v) = s.grid {
        o.loss.grid = v;
    }
    if let Some(v) = s.population {
        o.ga.population = v.clamp(2, 10_000);
    }
    if let Some(v) = s.generations {
        o.ga.generations = v.min(10_000);
    }
    if let Some(v) = s.candidates {
        o.candidates = v.clamp(1, 100);
    }
    if let Some(v) = s.iterations {
        o.iterations = v.min(100_000);
    }
    if let Some((k, n)) = s.shards {
        if n == 0 || n > 64 || k >= n {
            return Err(Error::input(format!(
                "shard {k} of {n}: need 1..=64 shards and an index below their count"
            )));
        }
        o.shards = (k, n);
    }
    if let Some(v) = s.polish {
        o.polish = v.min(100_000);
    }
    Ok(o)
}

fn target_source<'a>(
    p: &Program,
    t: &'a TargetSpec,
    img: &'a mut Option<Rgba8Image>,
    fl: &'a mut Vec<f64>,
) -> Result<TargetSource<'a>> {
    let tol = t.tolerance.unwrap_or(60.0);
    if let Some(bytes) = &t.image {
        *img = Some(decode(bytes, Limits::default())?);
    } else if let Some((w, h, data)) = &t.rgba {
        *img = Some(Rgba8Image::from_raw(*w, *h, data.clone())?);
    } else if let Some(named) = &t.params {
        *fl = float_values(p, &named_values(p, named)?);
        return Ok(TargetSource::Params(fl));
    } else {
        return Err(Error::input(
            "the fit needs a target: an image, RGBA pixels or target parameters",
        ));
    }
    Ok(TargetSource::Image(img.as_ref().expect("just set"), tol))
}

/// Start a fit; also returns the scene (for drawing results).
pub fn start_fit(
    src: &str,
    named: &BTreeMap<String, f64>,
    target: &TargetSpec,
    settings: &FitSettings,
) -> Result<(FitJob, Scene)> {
    let p = Program::parse(src)?;
    let vals = named_values(&p, named)?;
    let opts = fit_options(settings)?;
    let (mut img, mut fl) = (None, vec![]);
    let t = target_source(&p, target, &mut img, &mut fl)?;
    let job = FitJob::new(&p, &vals, &t, opts)?;
    let scene = job.objective().scene.clone();
    Ok((job, scene))
}

/// A finished fit as plain data.
#[derive(Debug, Clone, Serialize)]
pub struct FitOutput {
    #[serde(flatten)]
    pub result: FitResult,
    /// The best parameters by name (float ones).
    pub named: BTreeMap<String, f64>,
    /// The fitted pattern as SVG, 512 px wide.
    pub svg: String,
}

/// Package a fit result with its SVG.
pub fn fit_output(scene: &Scene, r: FitResult) -> Result<FitOutput> {
    let svg = render::svg(scene, &r.params, 512.0)?;
    let named = r
        .names
        .iter()
        .cloned()
        .zip(r.params.iter().copied())
        .collect();
    Ok(FitOutput {
        result: r,
        named,
        svg,
    })
}

/// Loss of many float-parameter vectors against one target (for a worker
/// pool evaluating a GA population): `points[i]` has one value per float
/// parameter in declaration order, raw units. At most 10,000 points.
pub fn eval_batch(
    src: &str,
    named: &BTreeMap<String, f64>,
    target: &TargetSpec,
    settings: &FitSettings,
    points: &[Vec<f64>],
) -> Result<Vec<f64>> {
    if points.len() > 10_000 {
        return Err(Error::limit(format!(
            "{} points in one batch; send at most 10,000",
            points.len()
        )));
    }
    let p = Program::parse(src)?;
    let vals = named_values(&p, named)?;
    let opts = fit_options(settings)?;
    let (mut img, mut fl) = (None, vec![]);
    let t = target_source(&p, target, &mut img, &mut fl)?;
    let (scene, target): (Scene, Target) = super::fit::prepare(&p, &vals, &t, &opts.loss)?;
    let dim = scene.rec.float_params.len();
    let lo: LossOptions = opts.loss;
    let mut obj = Objective::new(scene, target, lo);
    points
        .iter()
        .enumerate()
        .map(|(i, x)| {
            if x.len() != dim {
                return Err(Error::input(format!(
                    "point {i} has {} values; the program has {dim} float parameters",
                    x.len()
                )));
            }
            Ok(obj.loss(x))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::job::run_quietly;
    use crate::pattern::generators::generator;

    #[test]
    fn request_level_fit_render_and_batch() {
        let src = generator("circles-grid").unwrap().source;
        let none = BTreeMap::new();
        let info = program_info(src, &none).unwrap();
        assert_eq!(info.params.len(), 5);
        assert_eq!(info.colours, vec!["#ffffff", "#1f4e79"]);
        let truth: BTreeMap<String, f64> =
            [("dx".to_string(), 0.2), ("r".to_string(), 0.05)].into();
        let r = render_program(src, &truth, 64, 1).unwrap();
        assert_eq!((r.image.width, r.image.height), (64, 64));
        let png = crate::raster::encode_png(&r.image).unwrap();
        let target = TargetSpec {
            image: Some(png),
            ..Default::default()
        };
        let settings = FitSettings {
            iterations: Some(30),
            generations: Some(3),
            population: Some(30),
            ..Default::default()
        };
        let (job, scene) = start_fit(src, &none, &target, &settings).unwrap();
        let out = fit_output(&scene, run_quietly(job).unwrap()).unwrap();
        assert!(out.svg.contains("<circle"));
        assert!((out.named["r"] - 0.05).abs() < 0.01, "{:?}", out.named);
        let pts = vec![
            vec![0.2, 0.17, 0.12, 0.12, 0.05],
            vec![0.13, 0.13, 0.06, 0.06, 0.03],
        ];
        let l = eval_batch(src, &none, &target, &settings, &pts).unwrap();
        assert!(l[0] < l[1]);
        let e = eval_batch(src, &none, &target, &settings, &[vec![0.1]]).unwrap_err();
        assert!(e.to_string().contains("point 0 has 1 values"), "{e}");
        let bad: BTreeMap<String, f64> = [("radius".to_string(), 0.1)].into();
        assert!(render_program(src, &bad, 64, 1)
            .unwrap_err()
            .to_string()
            .contains("no parameter 'radius'"));
    }
}

/// A target image snapped to a program's palette.
#[derive(Debug, Clone)]
pub struct Snapped {
    /// `size × size`, every pixel exactly one of the program's colours.
    pub image: Rgba8Image,
    /// Fraction of pixels farther than the tolerance from every colour.
    pub unmatched: f64,
}

/// Decode an uploaded target, resample it to `size × size` (nearest) and
/// snap every pixel to the nearest colour the program draws with (or its
/// background), so the user sees exactly what the fit will compare against.
pub fn snap_target(
    src: &str,
    named: &BTreeMap<String, f64>,
    bytes: &[u8],
    size: usize,
    tolerance: f64,
) -> Result<Snapped> {
    if !(8..=2048).contains(&size) {
        return Err(Error::limit(format!(
            "size {size} is outside 8..=2048 pixels"
        )));
    }
    let img = crate::raster::decode(bytes, crate::raster::Limits::default())?;
    let p = Program::parse(src)?;
    let rec = p.record(&named_values(&p, named)?, &RecordLimits::default())?;
    let (idx, unmatched) = super::target::snap_to_palette(&img, &rec.colours, size, tolerance);
    let mut image = Rgba8Image::new(size as u32, size as u32);
    for (i, &k) in idx.iter().enumerate() {
        let [r, g, b] = rec.colours[k as usize];
        image.data[4 * i..4 * i + 4].copy_from_slice(&[r, g, b, 255]);
    }
    Ok(Snapped { image, unmatched })
}
