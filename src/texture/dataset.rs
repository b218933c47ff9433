//! The dataset (paper §4 and §5.1; MISSION X2): every model's parameters
//! sampled on a linear grid ("we discretize and sample the parameter space
//! on the linear scale for each parameter"), each grid point rendered once
//! as a height map and shaded under the fixed light, then optionally
//! augmented as in §5.1: re-shaded under other light directions (same
//! elevation, other azimuths) and cut into 4 non-overlapping crops.
//!
//! Grid: with n = [`DatasetConfig::per_model`] points per model, every
//! parameter's values are a linear grid of n levels over its dataset
//! range, and the points combine them as a Latin hypercube (each level of
//! each parameter used once, the orders shuffled per parameter with the
//! dataset's seed) rather than the full product of a few levels each. At
//! two dozen points per model, the product gave a model of 3–5
//! parameters 2–3 levels of each, and the classifier trained on it took
//! textures between the levels for other models: two thirds of textures
//! with parameters drawn at random in the dataset ranges were recognised,
//! against 89% of held-out grid points, which share the training levels
//! (`src/bench/examples/texture_compare.rs`,
//! `docs/bench/texture-retrieval-2026-12-03d.md`). Each model's defaults,
//! the picture the app shows first, are one more point unless they are
//! one already (every default lies in its dataset range; a test checks).
//!
//! The levels span each parameter's *dataset range*
//! ([`crate::texture::models::ParamSpec::dataset`]), not always its whole
//! range: as the paper kept only samples "with obviously different
//! appearances" (§4.3), a model is sampled only where its picture is its
//! own, not where it draws another model's (a random grid without jitter
//! is a regular grid, a folding at one fold is its input, a fusion near
//! one end of its weight is one ingredient, an automaton that has not
//! organised is blurred random cells). Each range is declared, with its
//! reason, next to the parameter; `models/tests.rs` checks the
//! coincidences and that no grid point comes near them.
//!
//! With crops on, the height map is rendered at twice the size and shaded,
//! and its four quadrants are the samples (the paper cut its 512² textures
//! into four 256² ones), so every image has side `size`.
//!
//! Every sample keeps its model, parameters, seed, light and crop; the
//! same config gives the same samples and bytes, natively and in wasm.
//! Rendering is independent per base sample: [`DatasetJob`] steps one base
//! at a time (browser, progress) and natively [`build_threads`] spreads
//! bases over scoped threads. (`core::parallel`'s sharded jobs exchange
//! `f64` vectors through an all-gather; images would be copied to every
//! shard, so the dataset does not use it.)
use crate::core::error::{Error, Result};
use crate::core::job::{Job, Progress, Step};
use crate::core::rng::Rng;
use crate::texture::image::Gray;
use crate::texture::models::look::Look;
use crate::texture::models::{render_height, shade, Light, Model, MODELS};

/// What to build.
#[derive(Clone, Debug, PartialEq)]
pub struct DatasetConfig {
    /// Most base samples (grid points) per model.
    pub per_model: usize,
    /// Side of every image in pixels.
    pub size: usize,
    /// Lights to shade every height map under (the first is the main one).
    pub lights: Vec<Light>,
    /// Cut each texture into 4 quadrant crops (rendered at 2 × `size`).
    pub crops: bool,
    /// Seed of the whole dataset; each base sample derives its own.
    pub seed: u64,
    /// Further images per base under random [`Look`]s (issue 36: other
    /// programs' lights, reliefs, tones, blur, noise, scales and
    /// rotations), each a `size`² window of the rendered height map. They
    /// train the classifiers and never enter the space.
    pub looks: usize,
}

impl Default for DatasetConfig {
    /// 40 per model (943 bases with the defaults), 256², the fixed light
    /// only, no crops.
    fn default() -> Self {
        DatasetConfig {
            per_model: 40,
            size: 256,
            lights: vec![Light::DEFAULT],
            crops: false,
            seed: 1,
            looks: 0,
        }
    }
}

/// The paper's second light for augmentation: same elevation, from the
/// lower right.
pub const AUGMENT_LIGHT: Light = Light {
    azimuth: 315.0,
    elevation: 45.0,
};

impl DatasetConfig {
    /// The paper's augmentation (§5.1): two lights × four crops per base.
    pub fn augmented(mut self) -> Self {
        self.lights = vec![Light::DEFAULT, AUGMENT_LIGHT];
        self.crops = true;
        self
    }

    fn check(&self) -> Result<()> {
        if self.per_model == 0 || self.per_model > 100_000 {
            return Err(Error::input("per_model must be in 1..=100000").at("per_model"));
        }
        if self.lights.is_empty() {
            return Err(Error::input("a dataset needs at least one light").at("lights"));
        }
        for (i, l) in self.lights.iter().enumerate() {
            if !l.azimuth.is_finite() || !(0.0..=90.0).contains(&l.elevation) {
                return Err(Error::input(
                    "a light needs a finite azimuth and an elevation in 0..=90 degrees",
                )
                .at(format!("lights.{i}")));
            }
        }
        let render = if self.crops { self.size * 2 } else { self.size };
        if !(crate::texture::models::MIN_SIZE..=crate::texture::models::MAX_SIZE).contains(&render)
        {
            return Err(Error::limit(format!(
                "dataset size {} (rendered at {render}) is outside {}..={} pixels",
                self.size,
                crate::texture::models::MIN_SIZE,
                crate::texture::models::MAX_SIZE
            ))
            .at("size"));
        }
        Ok(())
    }
}

/// One grid point: a model and parameters, before rendering.
#[derive(Clone, Debug, PartialEq)]
pub struct BaseSpec {
    /// Index among all base samples.
    pub base: usize,
    /// Index of the model in [`MODELS`] (the class label).
    pub model: usize,
    pub params: Vec<f64>,
    pub seed: u64,
}

/// One rendered image with everything needed to make it again.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    pub base: usize,
    pub model: usize,
    pub params: Vec<f64>,
    pub seed: u64,
    /// Index into the config's lights, and the light itself; a look's
    /// image has `lights.len() + j` for its `j`-th look.
    pub light_index: usize,
    pub light: Light,
    /// Quadrant 0..4 (row-major: top-left, top-right, bottom-left,
    /// bottom-right) or `None` for the whole texture.
    pub crop: Option<u8>,
    /// The look of a varied image ([`DatasetConfig::looks`]).
    pub look: Option<Look>,
    pub image: Gray,
}

impl Sample {
    /// The model that made it.
    pub fn model(&self) -> &'static Model {
        &MODELS[self.model]
    }
}

/// One model's design: `n` points; parameter `i` takes every level of a
/// linear grid of `n` levels over its dataset range once, in an order
/// shuffled per parameter by `rng` (a Latin hypercube; see the module
/// docs).
pub fn design(model: &Model, n: usize, rng: &mut Rng) -> Vec<Vec<f64>> {
    let mut points = vec![Vec::with_capacity(model.params.len()); n];
    for i in 0..model.params.len() {
        let mut order: Vec<usize> = (0..n).collect();
        rng.shuffle(&mut order);
        for (point, &j) in points.iter_mut().zip(&order) {
            point.push(level_value(model, i, j, n));
        }
    }
    points
}

/// A parameter point drawn uniformly inside `model`'s dataset ranges
/// (integers rounded): a texture of the model the dataset never held, for
/// measuring how the index reads what lies between its points.
pub fn random_point(model: &Model, rng: &mut Rng) -> Vec<f64> {
    model
        .params
        .iter()
        .map(|p| {
            let v = p.dataset_lo + (p.dataset_hi - p.dataset_lo) * rng.f64();
            if p.integer {
                v.round()
            } else {
                v
            }
        })
        .collect()
}

/// The value of level `j` of `levels` for parameter `i` of `model`: the
/// levels span the parameter's dataset range ([`ParamSpec::dataset`]); a
/// single level is the default, moved into that range.
///
/// [`ParamSpec::dataset`]: crate::texture::models::ParamSpec::dataset
fn level_value(model: &Model, i: usize, j: usize, levels: usize) -> f64 {
    let p = &model.params[i];
    let (lo, hi) = (p.dataset_lo, p.dataset_hi);
    let v = if levels <= 1 {
        p.default.clamp(lo, hi)
    } else {
        (lo + (hi - lo) * j as f64 / (levels - 1) as f64).clamp(lo, hi)
    };
    if p.integer {
        v.round()
    } else {
        v
    }
}

/// Every base sample of the dataset, in model order then design order,
/// each model's design ([`design`]) followed by its
/// defaults (unless they are a grid point): the app's first picture of
/// every model is in the dataset, at another seed.
pub fn plan(config: &DatasetConfig) -> Result<Vec<BaseSpec>> {
    config.check()?;
    let mut out = Vec::new();
    for (mi, m) in MODELS.iter().enumerate() {
        let mut rng = Rng::new(config.seed ^ ((mi as u64) << 40) ^ 0x00de_5197);
        let mut grid = design(m, config.per_model, &mut rng);
        let defaults: Vec<f64> = (0..m.params.len())
            .map(|i| level_value(m, i, 0, 1))
            .collect();
        if !grid.contains(&defaults) {
            grid.push(defaults);
        }
        for (g, params) in grid.into_iter().enumerate() {
            let mut rng =
                Rng::new(config.seed ^ ((mi as u64) << 40) ^ (g as u64).wrapping_mul(0x9e37_79b9));
            out.push(BaseSpec {
                base: out.len(),
                model: mi,
                params,
                // 53 bits: a page's number holds the seed exactly (the
                // browser gets it from `texture-retrieve` and keeps it in
                // the document; serde-wasm-bindgen refuses a larger u64).
                seed: rng.next_u64() >> 11,
            });
        }
    }
    Ok(out)
}

/// Render one base sample into its images (lights × crops).
pub fn render_base(config: &DatasetConfig, spec: &BaseSpec) -> Result<Vec<Sample>> {
    let model = &MODELS[spec.model];
    let n = if config.crops {
        config.size * 2
    } else {
        config.size
    };
    let height = render_height(model, &spec.params, spec.seed, n)?;
    let mut out = Vec::new();
    for (li, &light) in config.lights.iter().enumerate() {
        let lit = shade(&height, light);
        let pieces: Vec<(Option<u8>, Gray)> = if config.crops {
            (0..4u8)
                .map(|q| (Some(q), crop(&lit, q, config.size)))
                .collect()
        } else {
            vec![(None, lit)]
        };
        for (c, image) in pieces {
            out.push(Sample {
                base: spec.base,
                model: spec.model,
                params: spec.params.clone(),
                seed: spec.seed,
                light_index: li,
                light,
                crop: c,
                look: None,
                image,
            });
        }
    }
    let mut rng = Rng::new(spec.seed ^ 0x1005_cafe);
    for j in 0..config.looks {
        let look = Look::random(&mut rng);
        out.push(Sample {
            base: spec.base,
            model: spec.model,
            params: spec.params.clone(),
            seed: spec.seed,
            light_index: config.lights.len() + j,
            light: look.light.unwrap_or_default(),
            crop: None,
            look: Some(look),
            image: look.apply(&height, config.size),
        });
    }
    Ok(out)
}

/// Quadrant `q` (row-major) of side `s` of `g`.
fn crop(g: &Gray, q: u8, s: usize) -> Gray {
    let (ox, oy) = ((q as usize % 2) * s, (q as usize / 2) * s);
    let mut out = Gray::new(s, s);
    for y in 0..s {
        out.data[y * s..(y + 1) * s]
            .copy_from_slice(&g.data[(oy + y) * g.width + ox..(oy + y) * g.width + ox + s]);
    }
    out
}

/// Build the whole dataset on this thread.
pub fn build(config: &DatasetConfig) -> Result<Vec<Sample>> {
    let specs = plan(config)?;
    let mut out = Vec::new();
    for s in &specs {
        out.extend(render_base(config, s)?);
    }
    Ok(out)
}

/// Build the whole dataset on `threads` scoped threads (native only); the
/// same samples in the same order as [`build`].
#[cfg(not(target_arch = "wasm32"))]
pub fn build_threads(config: &DatasetConfig, threads: usize) -> Result<Vec<Sample>> {
    let specs = plan(config)?;
    let parts =
        crate::core::parallel::par_map_threads(&specs, threads, |spec| render_base(config, spec));
    let mut all = Vec::new();
    for p in parts {
        all.extend(p?);
    }
    Ok(all)
}

/// The dataset as a resumable job: one base sample per step.
pub struct DatasetJob {
    config: DatasetConfig,
    specs: Vec<BaseSpec>,
    next: usize,
    out: Vec<Sample>,
}

impl DatasetJob {
    pub fn new(config: DatasetConfig) -> Result<Self> {
        let specs = plan(&config)?;
        Ok(DatasetJob {
            config,
            specs,
            next: 0,
            out: Vec::new(),
        })
    }
}

impl Job for DatasetJob {
    type Output = Vec<Sample>;
    fn step(&mut self) -> Result<Step<Vec<Sample>>> {
        if self.next >= self.specs.len() {
            return Ok(Step::Done(std::mem::take(&mut self.out)));
        }
        let s = &self.specs[self.next];
        self.out.extend(render_base(&self.config, s)?);
        self.next += 1;
        Ok(Step::Running(Progress::new(
            self.next as f64 / self.specs.len() as f64,
            format!("rendering {}", MODELS[s.model].id),
        )))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::job::{run_to_end, Cancel};

    #[test]
    fn the_default_grid_has_a_few_dozen_samples_per_model() {
        let specs = plan(&DatasetConfig::default()).unwrap();
        assert_eq!(specs.len(), 943);
        for (mi, m) in MODELS.iter().enumerate() {
            let of_model: Vec<_> = specs.iter().filter(|s| s.model == mi).collect();
            assert!(of_model.len() >= 16, "{}: {}", m.id, of_model.len());
            // Grid values are distinct and in range; the first parameter varies.
            let firsts: std::collections::BTreeSet<u64> =
                of_model.iter().map(|s| s.params[0].to_bits()).collect();
            assert!(firsts.len() >= 2, "{}", m.id);
            for s in &of_model {
                assert_eq!(m.check(&s.params).unwrap(), s.params, "{}", m.id);
            }
            assert!(
                of_model.iter().any(|s| s.params == m.defaults()),
                "{}: no base at the defaults",
                m.id
            );
        }
        let bigger = plan(&DatasetConfig {
            per_model: 80,
            ..DatasetConfig::default()
        })
        .unwrap();
        assert!(bigger.len() > specs.len());
    }

    #[test]
    fn augmentation_gives_lights_times_crops_images_that_keep_their_provenance() {
        let config = DatasetConfig {
            per_model: 2,
            size: 16,
            ..DatasetConfig::default()
        }
        .augmented();
        let specs = plan(&config).unwrap();
        let one = render_base(&config, &specs[5]).unwrap();
        assert_eq!(one.len(), 8);
        for (i, s) in one.iter().enumerate() {
            assert_eq!((s.image.width, s.image.height), (16, 16));
            assert_eq!(s.light_index, i / 4);
            assert_eq!(s.crop, Some((i % 4) as u8));
            assert_eq!(
                (s.model, &s.params, s.seed),
                (specs[5].model, &specs[5].params, specs[5].seed)
            );
        }
        // The crops are the quadrants of the one 32² texture.
        let whole = shade(
            &render_height(&MODELS[specs[5].model], &specs[5].params, specs[5].seed, 32).unwrap(),
            Light::DEFAULT,
        );
        assert_eq!(one[3].image.at(0, 0), whole.at(16, 16));
        assert_eq!(one[1].image.at(2, 5), whole.at(18, 5));
        // Another light gives other pixels.
        assert_ne!(one[0].image, one[4].image);
    }

    #[test]
    fn looks_add_their_own_windows_after_the_papers_images() {
        let config = DatasetConfig {
            per_model: 2,
            size: 16,
            looks: 3,
            ..DatasetConfig::default()
        }
        .augmented();
        let specs = plan(&config).unwrap();
        let one = render_base(&config, &specs[7]).unwrap();
        assert_eq!(one.len(), 8 + 3);
        assert!(one[..8].iter().all(|s| s.look.is_none()));
        for (j, s) in one[8..].iter().enumerate() {
            assert_eq!((s.image.width, s.image.height), (16, 16));
            assert_eq!(s.light_index, 2 + j, "after the two lights");
            assert!(s.look.is_some() && s.crop.is_none());
        }
        assert_ne!(one[8].image, one[9].image);
        // Without looks the paper's images are unchanged.
        let plain = render_base(&DatasetConfig { looks: 0, ..config }, &specs[7]).unwrap();
        assert_eq!(plain[..], one[..8]);
    }

    #[test]
    fn the_job_the_threads_and_the_plain_build_agree() {
        let config = DatasetConfig {
            per_model: 2,
            size: 16,
            ..DatasetConfig::default()
        };
        let a = build(&config).unwrap();
        let b = build_threads(&config, 3).unwrap();
        let c = run_to_end(
            DatasetJob::new(config.clone()).unwrap(),
            &Cancel::new(),
            |_| {},
        )
        .unwrap();
        assert_eq!(a, b);
        assert_eq!(a, c);
        assert_eq!(a.len(), plan(&config).unwrap().len());
        assert_eq!(build(&config).unwrap(), a);
    }

    #[test]
    fn bad_configs_are_typed_errors() {
        let e = plan(&DatasetConfig {
            lights: vec![],
            ..DatasetConfig::default()
        })
        .unwrap_err();
        assert_eq!(e.field(), Some("lights"));
        let e = plan(&DatasetConfig {
            size: 2000,
            crops: true,
            ..DatasetConfig::default()
        })
        .unwrap_err();
        assert_eq!((e.kind(), e.field()), ("limit", Some("size")));
        let e = plan(&DatasetConfig {
            lights: vec![Light {
                azimuth: f64::NAN,
                elevation: 45.0,
            }],
            ..DatasetConfig::default()
        })
        .unwrap_err();
        assert_eq!(e.field(), Some("lights.0"));
    }
}
