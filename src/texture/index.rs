//! The Texture index: everything the browser needs to go from an example
//! image to a procedural model and its parameters (MISSION X5, X6).
//!
//! - a trained [`Pcn`] (both filter banks);
//! - linear one-vs-rest SVMs from PCN features to the generating model
//!   (on the features' explicit χ² map, [`chi2_map`]: a χ²-kernel machine
//!   kept linear, beside the image's standardised global values,
//!   [`super::globals`]) and to each of the twelve perceptual scales
//!   (1–9), as in Section 4.1;
//! - queries read two windows of a large image and sum the machines'
//!   scores ([`PcnConfig::views`], test-time augmentation);
//! - the perceptual texture space: a 3-D Isomap of the samples'
//!   dissimilarities, with, per axis, the subset of scales that correlate
//!   with it and a Gaussian SVR from that subset to the coordinate (4.2);
//! - every base sample's model, parameters, seed, scales and coordinates,
//!   for retrieval (4.3).
//!
//! **Dissimilarity.** The paper's similarity matrix comes from people
//! sorting textures into groups. We have no such data, so two samples'
//! dissimilarity is the Euclidean distance between their (estimated or
//! user-supplied) scale vectors: the space is built from the same
//! perceptual description the paper's subjects were asked to rate.
//!
//! **File.** [`Index::to_bytes`] writes one little-endian binary: a magic
//! string, a format version, the sections in a fixed order, and an FNV-1a
//! checksum of everything before it. [`Index::from_bytes`] checks all of
//! them and every length against the bytes left, so a truncated, corrupt
//! or other-version file is a clear error, never a panic or a huge
//! allocation.
use super::globals::{self, GLOBALS};
use super::learn::isomap::{isomap, pearson};
use super::learn::svm::{chi2_map, Linear, OneVsRest, Svr, CHI2_MAP_DIMS};
use super::pcn::{Pcn, PcnConfig};
use super::scales::{ScaleQuantiles, SCALE_RANGE};
use super::Gray;
use crate::core::error::{Error, Result};
use crate::core::parallel::par_map;
use serde::{Deserialize, Serialize};

pub use super::scales::SCALE_NAMES as SCALES;

/// Magic bytes at the start of every index file.
pub const MAGIC: &[u8; 16] = b"FILIGREE-TEXIDX\0";
/// How many base samples nearest the requested point in the perceptual
/// space [`Index::retrieve`] re-ranks by their scales.
pub const SHORTLIST: usize = 8;

/// The index format's version: bump it whenever the layout changes.
///
/// 3: the model classifier also reads 28 global values
/// ([`super::globals`]), standardised by a [`GlobalScaler`] stored after it.
/// 4: the scale classifiers read the global values too
/// ([`GlobalScaler::scale_row`]); the scales' cut points follow them when
/// the labels are the estimators' ([`Index::measured`]).
/// 5: the model classifier's [`Confidence`] (temperature and closeness
/// threshold) after the global scaler.
pub const VERSION: u32 = 5;

/// One training texture: its grey image, where it came from, and its
/// scales (1–9). Augmented copies have `base: false`: they train the
/// classifiers but do not enter the space.
#[derive(Clone, Debug)]
pub struct Training {
    pub image: Gray,
    pub model: u16,
    pub params: Vec<f32>,
    pub seed: u64,
    pub scales: [u8; 12],
    pub base: bool,
}

/// A base sample as the index keeps it.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    pub model: u16,
    pub params: Vec<f32>,
    pub seed: u64,
    pub scales: [u8; 12],
    pub coords: [f32; 3],
}

/// One axis of the perceptual space: the scales it is regressed from and
/// the regression (inputs are (scale − 1) / 8; the output is the
/// coordinate divided by `spread`).
#[derive(Clone, Debug, PartialEq)]
pub struct Axis {
    pub scales: Vec<u8>,
    pub spread: f32,
    pub svr: Svr,
}

/// How to build an index.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct IndexConfig {
    pub pcn: PcnConfig,
    /// SVM penalty of the model classifier. 10, chosen on a validation
    /// split of the training bases (a third of each model's, never the
    /// held-out test bases; `src/bench/examples/texture_validation.rs`): 1 → 10
    /// raised it by 0.7 and 2 points at 12 and 24 training bases per
    /// model, 30 gave no more (`docs/bench/texture-accuracy-2026-12-02.md`).
    pub c_model: f64,
    /// SVM penalty of the twelve scale classifiers.
    pub c_class: f64,
    /// Weight of the standardised global values ([`super::globals`]) beside
    /// the χ² map in the model classifier's rows. 1, chosen on the
    /// validation split (0.3 / 0.6 / 1 / 1.7 / 3: 78.4 / 79.9 / 80.5 /
    /// 78.8 / 78.4% of validation images, 73.2% without them;
    /// `docs/bench/texture-accuracy-2026-12-03.md`).
    pub global_weight: f64,
    /// Neighbours in Isomap's graph.
    pub isomap_k: usize,
    /// At most this many images (spread evenly) learn the PCA filters.
    pub filter_images: usize,
    /// A scale joins an axis's regression if |r| with the axis is at least
    /// this (the best three always do). 0.1, chosen on a validation split
    /// of the bases (`src/bench/examples/texture_space.rs`; the Latin-hypercube
    /// dataset, 2026-12-03d): R² of the three axes 0.993 / 0.915 / 0.879
    /// at 0.3, 0.993 / 0.915 / 0.944 at 0.2, 0.993 / 0.967 / 0.956 at 0.1.
    /// Lower thresholds blend more scales into every axis, so one slider
    /// moves the requested point less; [`Index::retrieve`]'s shortlist
    /// makes up for it: the sliders' response (`src/bench/examples/texture_rerank.rs`)
    /// was the same at 0.2 and 0.1.
    pub min_correlation: f64,
    /// How the model classifier's scores become probabilities and when an
    /// image is "no close model" ([`Confidence`]).
    pub confidence: Confidence,
}

/// How sure the model classifier is (issue 36). Its one-vs-rest scores,
/// averaged over an image's views, become probabilities by a softmax at
/// `temperature`. An image is "no close model" when it is far from every
/// model's training images: its [`Index::closeness`] (distance to the
/// nearest model's centre over that model's [`Region::radius`]) is above
/// `close`. (The classifier's own best score cannot say it: linear scores
/// grow without bound away from the data, and a flat grey picture or a
/// ramp scored higher than most textures.)
///
/// Both are chosen on the validation part of the cross-implementation set
/// (`bench/texture-xset/`), never on its test part: the temperature that
/// minimises the negative log-likelihood of the right models, and the
/// threshold below which few validation textures fall while flat, ramp,
/// text and photo-like pictures do (`filigree bench texture --xset`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Confidence {
    pub temperature: f32,
    pub close: f32,
}

impl Default for Confidence {
    fn default() -> Self {
        // Chosen on the validation part of the cross-implementation set
        // (issue 36; `src/bench/examples/texture_xset.rs`): the temperature that
        // minimises the right models' negative log-likelihood (1.18: 2.511
        // nats, 2.520 at 1); the closeness of its textures is at most 0.77
        // at the 99th percentile, while a flat grey picture has 1.40, a
        // ramp 1.46 and a drawing of three large shapes 1.05. (A page of
        // text, 0.53, and screenshots of this app, 0.45–0.53, read as
        // texton arrangements and are not caught.)
        Confidence {
            temperature: 1.18,
            close: 0.95,
        }
    }
}

/// The model classifier's reading of an image ([`Index::read_models`]).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Reading {
    /// Every model with its probability, most likely first.
    pub ranked: Vec<(u16, f64)>,
    /// The image's [`Index::closeness`]: 1 is as far from the nearest
    /// model as the model's own typical training image.
    pub distance: f64,
    /// Whether `distance` is at most [`Confidence::close`].
    pub close: bool,
}

/// Where one model's training images lie, in the scale classifiers' rows
/// ([`GlobalScaler::scale_row`]: the square-rooted histograms and the
/// standardised global values): their mean and standard deviation per
/// value, and the 90th percentile of their own standardised distances to
/// the mean ([`Region::distance`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Region {
    pub centre: Vec<f32>,
    pub spread: Vec<f32>,
    pub radius: f32,
}

/// Added (in quadrature) to every value's deviation in a [`Region`], so a
/// bin a model never fills does not make the smallest difference there
/// infinite.
const SPREAD_FLOOR: f64 = 0.02;

impl Region {
    /// The root-mean-square of `row`'s differences from the centre, each
    /// over its value's spread (a diagonal Mahalanobis distance).
    pub fn distance(&self, row: &[f32]) -> f64 {
        let sum: f64 = row
            .iter()
            .zip(&self.centre)
            .zip(&self.spread)
            .map(|((x, m), s)| ((*x as f64 - *m as f64) / *s as f64).powi(2))
            .sum();
        (sum / self.centre.len().max(1) as f64).sqrt()
    }
}

/// The 90th percentile of a model's images' distances to their centre is
/// its [`Region::radius`].
const REGION_QUANTILE: f64 = 0.9;

impl Default for IndexConfig {
    fn default() -> Self {
        IndexConfig {
            pcn: PcnConfig::default(),
            c_model: 10.0,
            c_class: 1.0,
            global_weight: 1.0,
            isomap_k: 10,
            filter_images: 240,
            min_correlation: 0.1,
            confidence: Confidence::default(),
        }
    }
}

/// The trained index.
#[derive(Clone, Debug, PartialEq)]
pub struct Index {
    /// The model names, by model id (checked against the app's models).
    pub model_names: Vec<String>,
    pub pcn: Pcn,
    /// Reads [`GlobalScaler::model_row`]s ([`Index::model_scores`]).
    pub model_classifier: OneVsRest,
    /// Standardises the global values for the classifiers.
    pub globals: GlobalScaler,
    /// The model classifier's probabilities and closeness.
    pub confidence: Confidence,
    /// Each model's region, in the model classifier's class order.
    pub regions: Vec<Region>,
    /// Read [`GlobalScaler::scale_row`]s.
    pub scale_classifiers: Vec<OneVsRest>,
    /// The cut points that made the samples' scales, when every label is
    /// the estimators' ([`super::scales`]; no human rating replaced any).
    /// Then an image's scales are its own measures at those cut points
    /// ([`Index::analyse`]): a scale *is* its estimator, and computing it
    /// beats a classifier's guess of it (validation, first images: 72.9%
    /// exact and 96.3% within one, against 48.1% and 84.1% for the
    /// classifiers; `src/bench/examples/texture_scales.rs`). With ratings the
    /// classifiers predict them, as in the paper.
    pub measured: Option<ScaleQuantiles>,
    pub axes: Vec<Axis>,
    pub samples: Vec<Sample>,
}

/// The training images' mean and standard deviation of every global value
/// ([`super::globals`]), and the weight of the standardised values beside
/// the χ² map in the model classifier's rows.
#[derive(Clone, Debug, PartialEq)]
pub struct GlobalScaler {
    pub mean: Vec<f32>,
    pub sd: Vec<f32>,
    pub weight: f32,
}

/// Standardised global values are clamped to this many standard
/// deviations, so one odd measure of a user's image cannot outvote the
/// histograms.
const GLOBAL_CLAMP: f64 = 5.0;

impl GlobalScaler {
    /// Fits the standardisation to feature rows (PCN features of length
    /// `dim`, then the global values).
    pub fn fit(rows: &[Vec<f32>], dim: usize, weight: f64) -> GlobalScaler {
        let n = rows.len().max(1) as f64;
        let k = rows.first().map_or(0, |r| r.len().saturating_sub(dim));
        let mut mean = vec![0f64; k];
        for r in rows {
            for (m, v) in mean.iter_mut().zip(&r[dim..]) {
                *m += *v as f64 / n;
            }
        }
        let mut var = vec![0f64; k];
        for r in rows {
            for ((s, v), m) in var.iter_mut().zip(&r[dim..]).zip(&mean) {
                *s += (*v as f64 - m).powi(2) / n;
            }
        }
        GlobalScaler {
            mean: mean.iter().map(|&m| m as f32).collect(),
            // A constant value is centred and left at its scale.
            sd: var
                .iter()
                .map(|&v| if v > 1e-12 { v.sqrt() as f32 } else { 1.0 })
                .collect(),
            weight: weight as f32,
        }
    }

    /// The model classifier's row for a feature row (PCN features of
    /// length `dim`, then the global values): the χ² map of the
    /// histograms, then the standardised global values times the weight.
    pub fn model_row(&self, f: &[f32], dim: usize) -> Vec<f32> {
        let mut out = chi2_map(&f[..dim]);
        self.push_standardised(&f[dim..], &mut out);
        out
    }

    /// The scale classifiers' row: the PCN features as they are, then the
    /// standardised global values times the weight. (The global values
    /// raised the scales' validation accuracy from 41.9 to 48.1% exact and
    /// from 79.7 to 84.1% within one; the χ² map gave no more and costs
    /// three times the weights: `src/bench/examples/texture_scales.rs`.)
    pub fn scale_row(&self, f: &[f32], dim: usize) -> Vec<f32> {
        let mut out = f[..dim].to_vec();
        self.push_standardised(&f[dim..], &mut out);
        out
    }

    fn push_standardised(&self, globals: &[f32], out: &mut Vec<f32>) {
        for ((v, m), s) in globals.iter().zip(&self.mean).zip(&self.sd) {
            let z = ((*v as f64 - *m as f64) / *s as f64).clamp(-GLOBAL_CLAMP, GLOBAL_CLAMP);
            // NaN (an image the measures cannot read) counts as the mean.
            out.push(if z.is_nan() {
                0.0
            } else {
                (self.weight as f64 * z) as f32
            });
        }
    }
}

/// What the index says about an image.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Analysis {
    pub model: u16,
    pub scales: [u8; 12],
    /// The model classifier's reading: `model` is its first.
    pub reading: Reading,
}

/// A retrieved sample and how well it matches the request.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Retrieval {
    pub sample: usize,
    pub point: [f32; 3],
    /// Cosine similarity of the requested and the retrieved scales.
    pub cosine: f64,
}

fn to_unit(s: &[u8; 12], subset: &[u8]) -> Vec<f32> {
    subset
        .iter()
        .map(|&k| (s[k as usize] as f32 - 1.0) / 8.0)
        .collect()
}

fn to_unit_f(s: &[f32; 12], subset: &[u8]) -> Vec<f32> {
    subset
        .iter()
        .map(|&k| (s[k as usize] - 1.0) / 8.0)
        .collect()
}

/// Each scale's level at the cut points `q` of the estimators' raw
/// measures of an image's windows ([`PcnConfig::quadrant_views`]) summed in
/// order and averaged, as the dataset's bases were labelled; None for a
/// measure the windows cannot give.
fn measure_scales(q: &ScaleQuantiles, windows: &[super::scales::Scales]) -> [Option<u8>; 12] {
    let mut raw = [0f64; 12];
    for w in windows {
        for (r, v) in raw.iter_mut().zip(w) {
            *r += v;
        }
    }
    for r in &mut raw {
        *r /= windows.len().max(1) as f64;
    }
    let levels = q.to_likert(&raw);
    std::array::from_fn(|k| (!windows.is_empty() && raw[k].is_finite()).then_some(levels[k]))
}

/// The first index of the largest value (0 when empty), as
/// [`OneVsRest::predict`] breaks ties.
fn argmax(s: &[f64]) -> usize {
    (0..s.len()).fold(0, |b, i| if s[i] > s[b] { i } else { b })
}

fn add(sum: &mut [f64], s: &[f64]) {
    for (a, b) in sum.iter_mut().zip(s) {
        *a += b;
    }
}

/// Cosine similarity of two scale vectors.
pub fn cosine(a: &[f32], b: &[f32]) -> f64 {
    let ab: f64 = a.iter().zip(b).map(|(x, y)| *x as f64 * *y as f64).sum();
    let aa: f64 = a.iter().map(|x| (*x as f64).powi(2)).sum();
    let bb: f64 = b.iter().map(|x| (*x as f64).powi(2)).sum();
    if aa <= 0.0 || bb <= 0.0 {
        0.0
    } else {
        ab / (aa * bb).sqrt()
    }
}

impl Index {
    /// Trains everything from `training` (see [`Training`]): the filters
    /// ([`Index::train_pcn`]), every image's features, then the rest
    /// ([`Index::fit`]).
    /// `measured`: the cut points that made the scales, when they are
    /// the estimators' (see [`Index::measured`]).
    pub fn build(
        model_names: Vec<String>,
        training: &[Training],
        measured: Option<ScaleQuantiles>,
        config: &IndexConfig,
    ) -> Result<Index> {
        Self::check(&model_names, training)?;
        let pcn = Self::train_pcn(training, config)?;
        let features = Self::features(&pcn, training)?;
        Self::fit(model_names, training, pcn, &features, measured, config)
    }

    fn check(model_names: &[String], training: &[Training]) -> Result<()> {
        if training.iter().filter(|t| t.base).count() < 4 {
            return Err(Error::input("an index needs at least four base samples"));
        }
        if let Some(t) = training.iter().find(|t| {
            t.model as usize >= model_names.len() || t.scales.iter().any(|s| !(1..=9).contains(s))
        }) {
            return Err(Error::input(format!(
                "sample of model {} has a model id or a scale out of range",
                t.model
            )));
        }
        Ok(())
    }

    /// The PCA filters, learnt from an even spread of at most
    /// `filter_images` of the training images.
    pub fn train_pcn(training: &[Training], config: &IndexConfig) -> Result<Pcn> {
        config.pcn.validate()?;
        let stride = training.len().div_ceil(config.filter_images.max(1)).max(1);
        let filter_set: Vec<Gray> = training
            .iter()
            .step_by(stride)
            .map(|t| t.image.clone())
            .collect();
        Pcn::train(&filter_set, config.pcn.clone())
    }

    /// Every training image's feature row ([`Index::image_features`]), on
    /// all cores natively.
    pub fn features(pcn: &Pcn, training: &[Training]) -> Result<Vec<Vec<f32>>> {
        par_map(training, |t| Self::image_features(pcn, &t.image))
            .into_iter()
            .collect()
    }

    /// An image's feature row: the PCN features of its
    /// [`PcnConfig::view`] (`pcn.config.feature_len()` values), then that
    /// view's [`globals::GLOBALS`] global values.
    pub fn image_features(pcn: &Pcn, img: &Gray) -> Result<Vec<f32>> {
        let view = pcn.config.view(img)?;
        let mut f = pcn.features(&view)?;
        f.extend(globals::measure(&view)?);
        Ok(f)
    }

    /// Everything after the features: the classifiers on `features` (one
    /// row per `training` record), the space and the samples.
    pub fn fit(
        model_names: Vec<String>,
        training: &[Training],
        pcn: Pcn,
        features: &[Vec<f32>],
        measured: Option<ScaleQuantiles>,
        config: &IndexConfig,
    ) -> Result<Index> {
        Self::check(&model_names, training)?;
        if features.len() != training.len() {
            return Err(Error::input("one feature row per training image is needed"));
        }
        let base: Vec<&Training> = training.iter().filter(|t| t.base).collect();
        let models: Vec<u16> = training.iter().map(|t| t.model).collect();
        let dim = pcn.config.feature_len();
        if features.iter().any(|f| f.len() != dim + GLOBALS) {
            return Err(Error::input(
                "feature rows are PCN features then the global values (Index::features)",
            ));
        }
        let globals = GlobalScaler::fit(features, dim, config.global_weight);
        let mapped: Vec<Vec<f32>> = features.iter().map(|f| globals.model_row(f, dim)).collect();
        let model_classifier = OneVsRest::train(&mapped, &models, config.c_model);
        drop(mapped);
        let scale_rows: Vec<Vec<f32>> =
            features.iter().map(|f| globals.scale_row(f, dim)).collect();
        let regions = Self::regions(&scale_rows, &models, &model_classifier.classes);
        let scale_ids: Vec<usize> = (0..12).collect();
        let scale_classifiers = par_map(&scale_ids, |&k| {
            let labels: Vec<u16> = training.iter().map(|t| t.scales[k] as u16).collect();
            OneVsRest::train(&scale_rows, &labels, config.c_class)
        });
        let (axes, coords) = Self::space(&base, config)?;
        let samples = base
            .iter()
            .zip(&coords)
            .map(|(t, c)| Sample {
                model: t.model,
                params: t.params.clone(),
                seed: t.seed,
                scales: t.scales,
                coords: *c,
            })
            .collect();
        Ok(Index {
            model_names,
            pcn,
            model_classifier,
            globals,
            confidence: config.confidence,
            regions,
            scale_classifiers,
            measured,
            axes,
            samples,
        })
    }

    /// Each class's [`Region`] over its rows.
    pub fn regions(rows: &[Vec<f32>], labels: &[u16], classes: &[u16]) -> Vec<Region> {
        classes
            .iter()
            .map(|&c| {
                let mine: Vec<&Vec<f32>> = rows
                    .iter()
                    .zip(labels)
                    .filter(|(_, &l)| l == c)
                    .map(|(r, _)| r)
                    .collect();
                let dim = rows.first().map_or(0, |r| r.len());
                let mut centre = vec![0f64; dim];
                for r in &mine {
                    for (m, v) in centre.iter_mut().zip(r.iter()) {
                        *m += *v as f64;
                    }
                }
                let n = mine.len().max(1) as f64;
                let centre: Vec<f32> = centre.iter().map(|m| (m / n) as f32).collect();
                let mut var = vec![0f64; dim];
                for r in &mine {
                    for ((v, x), m) in var.iter_mut().zip(r.iter()).zip(&centre) {
                        *v += (*x as f64 - *m as f64).powi(2) / n;
                    }
                }
                let spread: Vec<f32> = var
                    .iter()
                    .map(|v| (v + SPREAD_FLOOR * SPREAD_FLOOR).sqrt() as f32)
                    .collect();
                let mut region = Region {
                    centre,
                    spread,
                    radius: 1.0,
                };
                let mut d: Vec<f64> = mine.iter().map(|r| region.distance(r)).collect();
                d.sort_by(f64::total_cmp);
                region.radius = d
                    .get(((d.len().max(1) - 1) as f64 * REGION_QUANTILE) as usize)
                    .copied()
                    .unwrap_or(1.0)
                    .max(1e-6) as f32;
                region
            })
            .collect()
    }

    /// How far the feature rows of an image's views are from the nearest
    /// model: the [`Region::distance`] of their mean scale row
    /// ([`GlobalScaler::scale_row`]) from each model's region over its
    /// radius, the smallest of those.
    pub fn closeness(&self, views: &[Vec<f32>]) -> f64 {
        let dim = self.pcn.config.feature_len();
        let mut mean: Vec<f32> = Vec::new();
        for f in views {
            let row = self.globals.scale_row(f, dim);
            if mean.is_empty() {
                mean = vec![0.0; row.len()];
            }
            for (m, v) in mean.iter_mut().zip(&row) {
                *m += v / views.len() as f32;
            }
        }
        self.regions
            .iter()
            .map(|r| r.distance(&mean) / r.radius as f64)
            .fold(f64::INFINITY, f64::min)
    }

    /// The perceptual space of the base samples and its axis regressions.
    fn space(base: &[&Training], config: &IndexConfig) -> Result<(Vec<Axis>, Vec<[f32; 3]>)> {
        let n = base.len();
        let mut d = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                d[i * n + j] = base[i]
                    .scales
                    .iter()
                    .zip(&base[j].scales)
                    .map(|(a, b)| (*a as f64 - *b as f64).powi(2))
                    .sum::<f64>()
                    .sqrt();
            }
        }
        let y = isomap(&d, n, config.isomap_k, 3)?;
        let coords: Vec<[f32; 3]> = (0..n)
            .map(|i| [y[i * 3] as f32, y[i * 3 + 1] as f32, y[i * 3 + 2] as f32])
            .collect();
        let mut axes = Vec::with_capacity(3);
        for a in 0..3 {
            let target: Vec<f64> = (0..n).map(|i| y[i * 3 + a]).collect();
            let mut ranked: Vec<(usize, f64)> = (0..12)
                .map(|k| {
                    (
                        k,
                        pearson(
                            &base.iter().map(|t| t.scales[k] as f64).collect::<Vec<_>>(),
                            &target,
                        )
                        .abs(),
                    )
                })
                .collect();
            ranked.sort_by(|p, q| q.1.total_cmp(&p.1).then(p.0.cmp(&q.0)));
            let subset: Vec<u8> = ranked
                .iter()
                .enumerate()
                .filter(|(r, (_, c))| *r < 3 || *c >= config.min_correlation)
                .map(|(_, (k, _))| *k as u8)
                .collect();
            let mean = target.iter().sum::<f64>() / n as f64;
            let spread = (target.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / n as f64)
                .sqrt()
                .max(1e-9);
            let rows: Vec<Vec<f32>> = base.iter().map(|t| to_unit(&t.scales, &subset)).collect();
            let z: Vec<f64> = target.iter().map(|v| v / spread).collect();
            let svr = Svr::train(&rows, &z, 10.0, 0.05, 1.0 / subset.len() as f64 * 8.0);
            axes.push(Axis {
                scales: subset,
                spread: spread as f32,
                svr,
            });
        }
        Ok((axes, coords))
    }

    /// The smallest short side, in pixels, of an image [`Index::analyse`]
    /// accepts: half the network's window (`side`, 128 for the shipped
    /// index). A smaller picture would be enlarged more than twice to fill
    /// the window, and what the network reads of it is the enlargement's
    /// blur, not the texture: its model and scales would be made up.
    pub fn min_side(&self) -> usize {
        self.pcn.config.side.div_ceil(2).max(1)
    }

    /// The predicted model and scales of an image (at least
    /// [`Index::min_side`] pixels on its short side).
    pub fn analyse(&self, img: &Gray) -> Result<Analysis> {
        let min = self.min_side();
        if img.width.min(img.height) < min {
            return Err(Error::input(format!(
                "the example is {}×{} pixels; the texture analysis needs at least {min} on \
                 its short side (it reads a {}-pixel window, and a smaller picture would be \
                 enlarged into a blur). Use a larger picture of the texture, or repeat a small \
                 seamless tile to fill {}×{}",
                img.width,
                img.height,
                self.pcn.config.side,
                self.pcn.config.side,
                self.pcn.config.side
            ))
            .at("bytes"));
        }
        // Test-time augmentation: every classifier's scores summed over
        // the image's windows (one for an image the size of the view).
        let views = self.view_features(img)?;
        let reading = self.read_views(&views);
        let scales = match &self.measured {
            None => self.classify_scales(&views),
            Some(q) => {
                let raw = self
                    .pcn
                    .config
                    .quadrant_views(img)?
                    .iter()
                    .map(super::scales::measure)
                    .collect::<Result<Vec<_>>>()?;
                let measured = measure_scales(q, &raw);
                // A measure the image cannot give takes the classifier's.
                let classified = if measured.contains(&None) {
                    self.classify_scales(&views)
                } else {
                    [5; 12]
                };
                std::array::from_fn(|k| measured[k].unwrap_or(classified[k]))
            }
        };
        Ok(Analysis {
            model: reading.ranked.first().map_or(0, |r| r.0),
            scales,
            reading,
        })
    }

    /// The model classifier's reading of `img` ([`Index::read_views`]).
    pub fn read_models(&self, img: &Gray) -> Result<Reading> {
        Ok(self.read_views(&self.view_features(img)?))
    }

    /// Every model with its probability, from the feature rows of an
    /// image's views: the one-vs-rest scores averaged over the views, a
    /// softmax at [`Confidence::temperature`], and whether the best score
    /// reaches [`Confidence::close`].
    pub fn read_views(&self, views: &[Vec<f32>]) -> Reading {
        let mut sum = vec![0f64; self.model_classifier.classes.len()];
        for f in views {
            add(&mut sum, &self.model_scores(f));
        }
        let n = views.len().max(1) as f64;
        let mean: Vec<f64> = sum.iter().map(|s| s / n).collect();
        let best = mean.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let t = (self.confidence.temperature as f64).max(1e-6);
        let e: Vec<f64> = mean.iter().map(|s| libm::exp((s - best) / t)).collect();
        let z: f64 = e.iter().sum::<f64>().max(f64::MIN_POSITIVE);
        let mut ranked: Vec<(u16, f64)> = self
            .model_classifier
            .classes
            .iter()
            .zip(&e)
            .map(|(&c, &p)| (c, p / z))
            .collect();
        // Ties keep the classifier's order, as argmax did.
        ranked.sort_by(|a, b| b.1.total_cmp(&a.1));
        let distance = self.closeness(views);
        Reading {
            ranked,
            distance,
            close: distance <= self.confidence.close as f64,
        }
    }

    /// The feature rows ([`Index::image_features`]) of the windows
    /// [`Index::analyse`] reads of an image ([`PcnConfig::views`]).
    pub fn view_features(&self, img: &Gray) -> Result<Vec<Vec<f32>>> {
        self.pcn
            .config
            .views(img)?
            .iter()
            .map(|view| Self::image_features(&self.pcn, view))
            .collect()
    }

    /// The scale classifiers' answer for the feature rows of an image's
    /// views ([`Index::image_features`]), their scores summed.
    pub fn classify_scales(&self, views: &[Vec<f32>]) -> [u8; 12] {
        let dim = self.pcn.config.feature_len();
        let mut scales = [5u8; 12];
        for (s, c) in scales.iter_mut().zip(&self.scale_classifiers) {
            let mut sum = vec![0f64; c.classes.len()];
            for f in views {
                add(&mut sum, &c.scores(&self.globals.scale_row(f, dim)));
            }
            *s = c.classes.get(argmax(&sum)).copied().unwrap_or(5) as u8;
        }
        scales
    }

    /// The model classifier's scores (in its `classes` order) for a feature
    /// row ([`Index::image_features`]).
    pub fn model_scores(&self, f: &[f32]) -> Vec<f64> {
        let dim = self.pcn.config.feature_len();
        self.model_classifier
            .scores(&self.globals.model_row(f, dim))
    }

    /// The model of a feature row ([`Index::image_features`]) of one view.
    pub fn predict_model(&self, f: &[f32]) -> u16 {
        let s = self.model_scores(f);
        self.model_classifier
            .classes
            .get(argmax(&s))
            .copied()
            .unwrap_or(0)
    }

    /// The point of requested scales (1–9, fractional allowed) in the space.
    pub fn locate(&self, scales: &[f32; 12]) -> [f32; 3] {
        let mut p = [0f32; 3];
        for (o, axis) in p.iter_mut().zip(&self.axes) {
            *o = (axis.svr.predict(&to_unit_f(scales, &axis.scales)) * axis.spread as f64) as f32;
        }
        p
    }

    /// The texture for requested scales: [`Index::retrieve_among`] with
    /// the shipped shortlist, [`SHORTLIST`].
    pub fn retrieve(&self, scales: &[f32; 12], model: Option<u16>) -> Result<Retrieval> {
        self.retrieve_among(scales, model, SHORTLIST)
    }

    /// The paper's retrieval, then a re-ranking: the `shortlist` base
    /// samples nearest the requested point in the space (optionally of one
    /// model only), and of those the one whose scales are nearest the
    /// requested scales (Euclidean; ties to the nearer in the space).
    /// `shortlist` 1 is the paper's nearest neighbour.
    pub fn retrieve_among(
        &self,
        scales: &[f32; 12],
        model: Option<u16>,
        shortlist: usize,
    ) -> Result<Retrieval> {
        check_requested(scales)?;
        let point = self.locate(scales);
        let d2 = |c: &[f32; 3]| {
            (0..3)
                .map(|i| (c[i] as f64 - point[i] as f64).powi(2))
                .sum::<f64>()
        };
        let mut near: Vec<(f64, usize)> = self
            .samples
            .iter()
            .enumerate()
            .filter(|(_, s)| model.is_none_or(|m| s.model == m))
            .map(|(i, s)| (d2(&s.coords), i))
            .collect();
        if near.is_empty() {
            return Err(Error::input("no sample of that model is in the index").at("model"));
        }
        near.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
        near.truncate(shortlist.max(1));
        let off = |i: usize| {
            self.samples[i]
                .scales
                .iter()
                .zip(scales)
                .map(|(&s, &r)| (s as f64 - r as f64).powi(2))
                .sum::<f64>()
        };
        // `near` is in space order, so `min_by` keeps the nearer of equals.
        let best = near
            .iter()
            .map(|&(_, i)| i)
            .min_by(|&i, &j| off(i).total_cmp(&off(j)))
            .expect("the shortlist is not empty");
        let got: Vec<f32> = self.samples[best]
            .scales
            .iter()
            .map(|&s| s as f32)
            .collect();
        Ok(Retrieval {
            sample: best,
            point,
            cosine: cosine(scales, &got),
        })
    }
}

fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| {
        (h ^ b as u64).wrapping_mul(0x0100_0000_01b3)
    })
}

struct Writer(Vec<u8>);

impl Writer {
    fn u32(&mut self, v: u32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f32(&mut self, v: f32) {
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn len(&mut self, n: usize) {
        self.u32(n as u32);
    }
    fn f32s(&mut self, v: &[f32]) {
        self.len(v.len());
        for x in v {
            self.f32(*x);
        }
    }
    fn bytes(&mut self, v: &[u8]) {
        self.len(v.len());
        self.0.extend_from_slice(v);
    }
    fn ovr(&mut self, c: &OneVsRest) {
        self.len(c.classes.len());
        for (k, m) in c.classes.iter().zip(&c.machines) {
            self.u32(*k as u32);
            self.f32(m.rho);
            self.f32s(&m.w);
        }
    }
}

struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

fn corrupt(what: &str) -> Error {
    Error::input(format!(
        "the texture index is corrupt ({what}); rebuild it with `filigree build-index`"
    ))
}

impl<'a> Reader<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8]> {
        if self.b.len() - self.at < n {
            return Err(corrupt(&format!("{what} runs past the end")));
        }
        self.at += n;
        Ok(&self.b[self.at - n..self.at])
    }
    fn u32(&mut self, what: &str) -> Result<u32> {
        Ok(u32::from_le_bytes(
            self.take(4, what)?.try_into().expect("4 bytes"),
        ))
    }
    fn u64(&mut self, what: &str) -> Result<u64> {
        Ok(u64::from_le_bytes(
            self.take(8, what)?.try_into().expect("8 bytes"),
        ))
    }
    fn f32(&mut self, what: &str) -> Result<f32> {
        let v = f32::from_le_bytes(self.take(4, what)?.try_into().expect("4 bytes"));
        if v.is_finite() {
            Ok(v)
        } else {
            Err(corrupt(&format!("{what} is not a finite number")))
        }
    }
    /// A count of items of at least `item` bytes each, checked against
    /// what is left so a bad count cannot allocate more than the file.
    fn len(&mut self, item: usize, what: &str) -> Result<usize> {
        let n = self.u32(what)? as usize;
        if n.saturating_mul(item.max(1)) > self.b.len() - self.at {
            return Err(corrupt(&format!("{what} claims {n} items")));
        }
        Ok(n)
    }
    fn f32s(&mut self, what: &str) -> Result<Vec<f32>> {
        let n = self.len(4, what)?;
        (0..n).map(|_| self.f32(what)).collect()
    }
    fn bytes(&mut self, what: &str) -> Result<&'a [u8]> {
        let n = self.len(1, what)?;
        self.take(n, what)
    }
    fn ovr(&mut self, dim: usize, what: &str) -> Result<OneVsRest> {
        let n = self.len(12, what)?;
        let mut classes = Vec::with_capacity(n);
        let mut machines = Vec::with_capacity(n);
        for _ in 0..n {
            classes.push(self.u32(what)?.min(u16::MAX as u32) as u16);
            let rho = self.f32(what)?;
            let w = self.f32s(what)?;
            if w.len() != dim {
                return Err(corrupt(&format!("{what} has weights of the wrong length")));
            }
            machines.push(Linear { w, rho });
        }
        if n == 0 {
            return Err(corrupt(&format!("{what} has no classes")));
        }
        Ok(OneVsRest { classes, machines })
    }
}

impl Index {
    /// The index as one versioned binary (see the module docs).
    pub fn to_bytes(&self) -> Vec<u8> {
        let mut w = Writer(MAGIC.to_vec());
        w.u32(VERSION);
        w.bytes(
            serde_json::to_string(&self.pcn.config)
                .expect("the settings serialise")
                .as_bytes(),
        );
        w.len(self.model_names.len());
        for n in &self.model_names {
            w.bytes(n.as_bytes());
        }
        for f in &self.pcn.stage1 {
            w.f32s(f);
        }
        for bank in &self.pcn.stage2 {
            for f in bank {
                w.f32s(f);
            }
        }
        w.ovr(&self.model_classifier);
        w.f32s(&self.globals.mean);
        w.f32s(&self.globals.sd);
        w.f32(self.globals.weight);
        w.f32(self.confidence.temperature);
        w.f32(self.confidence.close);
        w.len(self.regions.len());
        for r in &self.regions {
            w.f32s(&r.centre);
            w.f32s(&r.spread);
            w.f32(r.radius);
        }
        for c in &self.scale_classifiers {
            w.ovr(c);
        }
        match &self.measured {
            None => w.u32(0),
            Some(q) => {
                w.u32(1);
                for e in q.edges.iter().flatten() {
                    w.u64(e.to_bits());
                }
            }
        }
        for a in &self.axes {
            w.bytes(&a.scales);
            w.f32(a.spread);
            w.f32(a.svr.gamma);
            w.f32(a.svr.rho);
            w.f32s(&a.svr.coef);
            for s in &a.svr.support {
                w.f32s(s);
            }
        }
        w.len(self.samples.len());
        for s in &self.samples {
            w.u32(s.model as u32);
            w.u64(s.seed);
            w.0.extend_from_slice(&s.scales);
            for c in s.coords {
                w.f32(c);
            }
            w.f32s(&s.params);
        }
        let sum = fnv1a(&w.0);
        w.u64(sum);
        w.0
    }

    /// Reads an index written by [`Index::to_bytes`]; any damage is an error.
    pub fn from_bytes(bytes: &[u8]) -> Result<Index> {
        if bytes.len() < MAGIC.len() + 12 || &bytes[..MAGIC.len()] != MAGIC {
            return Err(Error::input("this is not a Filigree texture index"));
        }
        let body = &bytes[..bytes.len() - 8];
        let sum = u64::from_le_bytes(bytes[bytes.len() - 8..].try_into().expect("8 bytes"));
        let mut r = Reader {
            b: body,
            at: MAGIC.len(),
        };
        let version = r.u32("version")?;
        if version != VERSION {
            return Err(Error::input(format!(
                "the texture index is format version {version}, this app reads version {VERSION}; rebuild it with `filigree build-index`"
            )));
        }
        if fnv1a(body) != sum {
            return Err(corrupt("checksum mismatch"));
        }
        let config: PcnConfig = serde_json::from_slice(r.bytes("settings")?)
            .map_err(|e| corrupt(&format!("settings: {e}")))?;
        config
            .validate()
            .map_err(|e| corrupt(&format!("settings: {e}")))?;
        let names = r.len(4, "model names")?;
        let model_names = (0..names)
            .map(|_| {
                String::from_utf8(r.bytes("model name")?.to_vec())
                    .map_err(|_| corrupt("a model name is not UTF-8"))
            })
            .collect::<Result<Vec<_>>>()?;
        let taps = config.k1 * config.k2;
        let filter = |r: &mut Reader| -> Result<Vec<f32>> {
            let f = r.f32s("filter")?;
            if f.len() != taps {
                return Err(corrupt("a filter has the wrong size"));
            }
            Ok(f)
        };
        let stage1 = (0..config.l1)
            .map(|_| filter(&mut r))
            .collect::<Result<Vec<_>>>()?;
        let stage2 = (0..config.subsets().len())
            .map(|_| {
                (0..config.l2)
                    .map(|_| filter(&mut r))
                    .collect::<Result<Vec<_>>>()
            })
            .collect::<Result<Vec<_>>>()?;
        let dim = config.feature_len();
        let model_classifier = r.ovr(dim * CHI2_MAP_DIMS + GLOBALS, "model classifier")?;
        if model_classifier
            .classes
            .iter()
            .any(|&c| c as usize >= model_names.len())
        {
            return Err(corrupt("the model classifier names an unknown model"));
        }
        let mean = r.f32s("global means")?;
        let sd = r.f32s("global deviations")?;
        let weight = r.f32("global weight")?;
        if mean.len() != GLOBALS || sd.len() != GLOBALS {
            return Err(corrupt("the global values' scaler has the wrong length"));
        }
        if sd.iter().any(|&v| v <= 0.0) {
            return Err(corrupt("a global value's deviation is not positive"));
        }
        let globals = GlobalScaler { mean, sd, weight };
        let confidence = Confidence {
            temperature: r.f32("temperature")?,
            close: r.f32("closeness threshold")?,
        };
        if !(confidence.temperature > 0.0
            && confidence.temperature.is_finite()
            && confidence.close.is_finite())
        {
            return Err(corrupt("the confidence settings are not usable numbers"));
        }
        let region_count = r.len(4, "regions")?;
        if region_count != model_classifier.classes.len() {
            return Err(corrupt("one region per model class is needed"));
        }
        let regions = (0..region_count)
            .map(|_| {
                let centre = r.f32s("region centre")?;
                let spread = r.f32s("region spread")?;
                let radius = r.f32("region radius")?;
                if centre.len() != dim + GLOBALS
                    || spread.len() != centre.len()
                    || spread.iter().any(|s| !(*s > 0.0 && s.is_finite()))
                    || !(radius > 0.0 && radius.is_finite())
                {
                    return Err(corrupt("a model's region has the wrong size or spread"));
                }
                Ok(Region {
                    centre,
                    spread,
                    radius,
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let scale_classifiers = (0..12)
            .map(|_| r.ovr(dim + GLOBALS, "scale classifier"))
            .collect::<Result<Vec<_>>>()?;
        let measured = match r.u32("measured scales flag")? {
            0 => None,
            1 => {
                let mut edges = vec![[0f64; 8]; 12];
                for e in edges.iter_mut().flatten() {
                    *e = f64::from_bits(r.u64("scale cut point")?);
                }
                if edges
                    .iter()
                    .any(|e| e.iter().any(|v| !v.is_finite()) || e.windows(2).any(|p| p[0] > p[1]))
                {
                    return Err(corrupt("the scales' cut points are not finite and ordered"));
                }
                Some(ScaleQuantiles { edges })
            }
            _ => return Err(corrupt("the measured scales flag is not 0 or 1")),
        };
        let mut axes = Vec::with_capacity(3);
        for _ in 0..3 {
            let scales = r.bytes("axis scales")?.to_vec();
            if scales.is_empty() || scales.iter().any(|&k| k >= 12) {
                return Err(corrupt("an axis names an unknown scale"));
            }
            let spread = r.f32("axis spread")?;
            let gamma = r.f32("axis gamma")?;
            let rho = r.f32("axis rho")?;
            let coef = r.f32s("axis coefficients")?;
            let support = (0..coef.len())
                .map(|_| {
                    let s = r.f32s("support vector")?;
                    if s.len() != scales.len() {
                        return Err(corrupt("a support vector has the wrong length"));
                    }
                    Ok(s)
                })
                .collect::<Result<Vec<_>>>()?;
            axes.push(Axis {
                scales,
                spread,
                svr: Svr {
                    gamma,
                    rho,
                    support,
                    coef,
                },
            });
        }
        let n = r.len(40, "samples")?;
        let mut samples = Vec::with_capacity(n);
        for _ in 0..n {
            let model = r.u32("sample model")?;
            if model as usize >= model_names.len() {
                return Err(corrupt("a sample names an unknown model"));
            }
            let seed = r.u64("sample seed")?;
            let scales: [u8; 12] = r.take(12, "sample scales")?.try_into().expect("12 bytes");
            if scales.iter().any(|s| !(1..=9).contains(s)) {
                return Err(corrupt("a sample's scale is outside 1–9"));
            }
            let coords = [r.f32("coords")?, r.f32("coords")?, r.f32("coords")?];
            let params = r.f32s("sample parameters")?;
            samples.push(Sample {
                model: model as u16,
                params,
                seed,
                scales,
                coords,
            });
        }
        if r.at != body.len() {
            return Err(corrupt("bytes are left over"));
        }
        if samples.is_empty() {
            return Err(corrupt("no samples"));
        }
        Ok(Index {
            model_names,
            pcn: Pcn {
                config,
                stage1,
                stage2,
            },
            model_classifier,
            globals,
            confidence,
            regions,
            scale_classifiers,
            measured,
            axes,
            samples,
        })
    }
}

/// The requested scales of a `texture-retrieve` (and of a Texture
/// document): each finite and within [`SCALE_RANGE`].
pub fn check_requested(scales: &[f32; 12]) -> Result<()> {
    let (lo, hi) = SCALE_RANGE;
    if scales
        .iter()
        .any(|&s| !s.is_finite() || !(lo..=hi).contains(&(s as f64)))
    {
        return Err(Error::input(format!("scales run from {lo} to {hi}")).at("scales"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;

    /// A toy dataset: three "models" (stripes along x, along y, noise) at
    /// several periods and seeds, with scales made up to follow them.
    pub(crate) fn toy() -> (Vec<String>, Vec<Training>) {
        let side = 40;
        let mut out = Vec::new();
        for seed in 0..8u64 {
            let mut r = Rng::new(seed);
            for model in 0..3u16 {
                let period = 4.0 + seed as f32;
                let mut g = Gray::new(side, side);
                for y in 0..side {
                    for x in 0..side {
                        g.data[y * side + x] = match model {
                            0 => 0.5 + 0.5 * (x as f32 * std::f32::consts::TAU / period).sin(),
                            1 => 0.5 + 0.5 * (y as f32 * std::f32::consts::TAU / period).sin(),
                            _ => r.f64() as f32,
                        };
                    }
                }
                let coarse = (1 + seed) as u8;
                let mut scales = [5u8; 12];
                scales[8] = coarse; // coarseness follows the period
                scales[6] = if model == 2 { 1 } else { 9 }; // directionality
                scales[3] = if model == 2 { 9 } else { 2 }; // randomness
                scales[0] = 1 + (seed % 9) as u8;
                out.push(Training {
                    image: g,
                    model,
                    params: vec![period],
                    seed,
                    scales,
                    base: true,
                });
            }
        }
        (
            vec!["stripes x".into(), "stripes y".into(), "noise".into()],
            out,
        )
    }

    fn config() -> IndexConfig {
        IndexConfig {
            pcn: PcnConfig {
                k1: 5,
                k2: 5,
                l1: 4,
                l2: 6,
                patch_step: 2,
                side: 32,
                intensity_bins: 4,
                ..PcnConfig::default()
            },
            isomap_k: 5,
            ..IndexConfig::default()
        }
    }

    #[test]
    fn an_index_round_trips_through_its_bytes_and_rejects_damage() {
        let (names, data) = toy();
        let idx = Index::build(names, &data, None, &config()).unwrap();
        let bytes = idx.to_bytes();
        let back = Index::from_bytes(&bytes).unwrap();
        assert_eq!(back, idx);
        assert_eq!(back.to_bytes(), bytes);
        // Every truncation and a flipped byte anywhere are errors.
        for cut in (0..bytes.len()).step_by(97) {
            assert!(Index::from_bytes(&bytes[..cut]).is_err(), "cut at {cut}");
        }
        let mut flipped = bytes.clone();
        flipped[bytes.len() / 2] ^= 0x10;
        let e = Index::from_bytes(&flipped).unwrap_err().to_string();
        assert!(e.contains("corrupt"), "{e}");
        let mut other = bytes.clone();
        other[16] = 9;
        let e = Index::from_bytes(&other).unwrap_err().to_string();
        assert!(e.contains("version 9"), "{e}");
        assert!(Index::from_bytes(b"PNG....").is_err());
    }

    /// With the estimators' labels, an image's scales are its own measures
    /// at the index's cut points; without them (ratings), the classifiers'
    /// answer. Both indexes round-trip through their bytes.
    #[test]
    fn with_estimated_labels_an_images_scales_are_its_measures_at_the_cut_points() {
        use crate::texture::scales::{measure, Scales};
        let (names, data) = toy();
        let raw: Vec<Scales> = data.iter().map(|t| measure(&t.image).unwrap()).collect();
        let q = ScaleQuantiles::fit(&raw).unwrap();
        let measured = Index::build(names.clone(), &data, Some(q.clone()), &config()).unwrap();
        let rated = Index::build(names, &data, None, &config()).unwrap();
        assert_eq!(measured.scale_classifiers, rated.scale_classifiers);
        for idx in [&measured, &rated] {
            assert_eq!(&Index::from_bytes(&idx.to_bytes()).unwrap(), idx);
        }
        let mut differ = 0;
        for t in &data {
            let windows = measured.pcn.config.quadrant_views(&t.image).unwrap();
            let sum = windows.iter().fold([0.0; 12], |mut s, w| {
                for (a, v) in s.iter_mut().zip(measure(w).unwrap()) {
                    *a += v;
                }
                s
            });
            let want = q.to_likert(&sum.map(|v| v / windows.len() as f64));
            assert_eq!(measured.analyse(&t.image).unwrap().scales, want);
            let views = rated.view_features(&t.image).unwrap();
            let svm = rated.classify_scales(&views);
            assert_eq!(rated.analyse(&t.image).unwrap().scales, svm);
            differ += (svm != want) as usize;
        }
        // The toy's made-up labels are not its measures: the two sources
        // give different answers, so the test sees which one analyse used.
        assert!(differ > data.len() / 2, "{differ} of {}", data.len());
    }

    /// The windows' measures are averaged before they meet the cut
    /// points; a measure no window gives leaves the scale to the classifier.
    #[test]
    fn measured_scales_average_the_windows_and_skip_what_is_not_finite() {
        let q = ScaleQuantiles {
            edges: vec![[1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0]; 12],
        };
        let mut a = [0.5; 12];
        let mut b = [8.5; 12];
        a[3] = f64::NAN;
        b[5] = 4.0;
        let got = measure_scales(&q, &[a, b]);
        assert_eq!(got[0], Some(5)); // mean 4.5: four cut points below
        assert_eq!(got[5], Some(3)); // mean 2.25
        assert_eq!(got[3], None);
        assert_eq!(measure_scales(&q, &[]), [None; 12]);
    }

    #[test]
    fn the_model_classifier_recognises_the_models_of_the_toy_set() {
        let (names, data) = toy();
        let idx = Index::build(names, &data, None, &config()).unwrap();
        let right = data
            .iter()
            .filter(|t| idx.analyse(&t.image).unwrap().model == t.model)
            .count();
        assert!(right * 10 >= data.len() * 9, "{right}/{} right", data.len());
    }

    /// Retrieval's answer has scales closer to the request than a random
    /// sample's, on average over requests taken from the samples.
    #[test]
    fn retrieval_beats_a_random_sample() {
        let (names, data) = toy();
        let idx = Index::build(names, &data, None, &config()).unwrap();
        let mut r = Rng::new(3);
        let dist = |a: &[u8; 12], b: &[f32; 12]| {
            a.iter()
                .zip(b)
                .map(|(x, y)| (*x as f32 - y).powi(2))
                .sum::<f32>()
        };
        let (mut got, mut random) = (0.0, 0.0);
        for s in &idx.samples {
            let want: [f32; 12] = s.scales.map(|v| v as f32);
            let hit = idx.retrieve(&want, None).unwrap();
            got += dist(&idx.samples[hit.sample].scales, &want);
            random += dist(&idx.samples[r.below(idx.samples.len())].scales, &want);
        }
        assert!(got < random * 0.5, "retrieved {got} vs random {random}");
        let only = idx.retrieve(&[5.0; 12], Some(2)).unwrap();
        assert_eq!(idx.samples[only.sample].model, 2);
        assert!(idx.retrieve(&[0.0; 12], None).is_err());
    }

    /// A shortlist of 1 is the paper's nearest neighbour in the space; a
    /// longer one returns, from the nearest few, a sample whose scales are
    /// at least as near the request, and a shortlist of every sample is
    /// the nearest in scales outright.
    #[test]
    fn the_shortlist_re_ranks_the_nearest_in_the_space_by_scales() {
        let (names, data) = toy();
        let idx = Index::build(names, &data, None, &config()).unwrap();
        let off = |i: usize, want: &[f32; 12]| {
            idx.samples[i]
                .scales
                .iter()
                .zip(want)
                .map(|(&s, &r)| (s as f32 - r).powi(2))
                .sum::<f32>()
        };
        let mut r = Rng::new(5);
        for _ in 0..40 {
            let want: [f32; 12] = std::array::from_fn(|_| 1.0 + 8.0 * r.f64() as f32);
            let p = idx.locate(&want);
            let d = |i: usize| {
                let c = idx.samples[i].coords;
                (0..3).map(|a| (c[a] - p[a]).powi(2)).sum::<f32>()
            };
            let nn = idx.retrieve_among(&want, None, 1).unwrap().sample;
            assert!((0..idx.samples.len()).all(|i| d(nn) <= d(i)));
            let mut last = off(nn, &want);
            for k in [2, 4, 8] {
                let got = idx.retrieve_among(&want, None, k).unwrap().sample;
                assert!(off(got, &want) <= last, "shortlist {k}");
                last = off(got, &want);
            }
            let all = idx.retrieve_among(&want, None, usize::MAX).unwrap().sample;
            assert!((0..idx.samples.len()).all(|i| off(all, &want) <= off(i, &want)));
        }
    }
}
