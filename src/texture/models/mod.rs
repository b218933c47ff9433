//! Procedural texture models (paper §4, footnote 1; MISSION X1): each is a
//! function (parameters, seed, size) → height map, shaded under a light by
//! [`shade`] (the one place for shading).
//!
//! The footnote lists 22 names for "the 23 methods"; we add **Fractal
//! (midpoint displacement)**, the classic diamond–square fBm, as the 23rd:
//! the text's "Fractal" family has two named members while "Folding of
//! Fractal" and the Fractal discussion (§5.4) imply fractal surfaces in
//! general, and midpoint displacement is the third standard way to make
//! them (besides 1/f^β octave sums and Fourier spectral synthesis).
//!
//! Files: [`common`] (noise, Worley, textons, folding, FFT), [`automata`]
//! (the three cellular automata), [`cellular`], [`fractal`] (1/f^β,
//! Fourier spectral synthesis, midpoint displacement), [`perlin`],
//! [`texton`] (addition, probability map, random grid, random walk,
//! regular), [`composite`] (the four foldings and three fusions),
//! [`islamic`], [`matrix`], [`reaction`] (reaction–diffusion).
//!
//! Conventions: coordinates are image units on the unit torus, so a model
//! looks the same at any size and tiles (all 23 tile, except that Fourier
//! and midpoint synthesis at a size that is not a power of two are
//! resampled from the next power of two, which still tiles). Simulations
//! (automata, reaction–diffusion) run on their own grid whose size is a
//! parameter, then are resampled, so their cost is bounded whatever the
//! output size. Heights are in [0, 1].
//!
//! Parameters: a NaN or infinite value is an error naming
//! `params.<name>`; a finite value outside its range is clamped to it and
//! an integer parameter is rounded (sliders and grids can then never fail).
use crate::core::error::{Error, Result};
use crate::texture::image::Gray;

pub mod automata;
pub mod cellular;
pub mod common;
pub mod composite;
pub mod fractal;
pub mod islamic;
pub mod look;
pub mod matrix;
pub mod perlin;
pub mod reaction;
pub mod texton;

/// The smallest and largest rendered side in pixels.
pub const MIN_SIZE: usize = 8;
pub const MAX_SIZE: usize = 2048;

/// One parameter of a model: its range, default, whether it is an
/// integer, and the part of the range the dataset samples.
///
/// `lo..=hi` is what a user may set (sliders, CLI, documents) and what
/// [`Model::check`] clamps to. `dataset_lo..=dataset_hi` (inside it) is
/// where the dataset's linear grid takes its values
/// ([`crate::texture::dataset`]): the paper kept only samples "with
/// obviously different appearances" (§4.3), so where a model draws
/// another model's picture at the end of a parameter (a random grid with
/// no jitter is a regular grid, a folding at one fold is its input, a
/// fusion at one end of its weight is mostly one ingredient), the dataset
/// range stops short of that end. Declared with [`ParamSpec::dataset`]
/// next to the parameter, with the reason; by default it is the whole
/// range.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ParamSpec {
    pub name: &'static str,
    pub lo: f64,
    pub hi: f64,
    pub default: f64,
    pub integer: bool,
    pub dataset_lo: f64,
    pub dataset_hi: f64,
}

impl ParamSpec {
    /// The same parameter with the dataset sampling only `lo..=hi` (which
    /// must lie inside the user range; a test checks every model).
    pub const fn dataset(self, lo: f64, hi: f64) -> ParamSpec {
        ParamSpec {
            dataset_lo: lo,
            dataset_hi: hi,
            ..self
        }
    }
}

const fn real(name: &'static str, lo: f64, hi: f64, default: f64) -> ParamSpec {
    ParamSpec {
        name,
        lo,
        hi,
        default,
        integer: false,
        dataset_lo: lo,
        dataset_hi: hi,
    }
}

const fn int(name: &'static str, lo: f64, hi: f64, default: f64) -> ParamSpec {
    ParamSpec {
        name,
        lo,
        hi,
        default,
        integer: true,
        dataset_lo: lo,
        dataset_hi: hi,
    }
}

/// The model families of the paper's footnote.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Family {
    CellularAutomaton,
    Cellular,
    Folding,
    Fractal,
    Fusion,
    Islamic,
    MatrixTransformation,
    Perlin,
    ReactionDiffusion,
    Texton,
}

impl Family {
    pub fn name(self) -> &'static str {
        match self {
            Family::CellularAutomaton => "cellular automaton",
            Family::Cellular => "cellular",
            Family::Folding => "folding",
            Family::Fractal => "fractal",
            Family::Fusion => "fusion",
            Family::Islamic => "islamic",
            Family::MatrixTransformation => "matrix transformation",
            Family::Perlin => "perlin",
            Family::ReactionDiffusion => "reaction-diffusion",
            Family::Texton => "texton",
        }
    }
}

/// A generator: checked parameters (spec order), seed, side → `n²` heights.
pub type Generate = fn(&[f64], u64, usize) -> Vec<f32>;

/// A procedural texture model.
#[derive(Clone, Copy)]
pub struct Model {
    /// Stable kebab-case id (file formats and the CLI use it).
    pub id: &'static str,
    /// The paper's name.
    pub name: &'static str,
    pub family: Family,
    pub params: &'static [ParamSpec],
    pub(crate) generate: Generate,
}

impl std::fmt::Debug for Model {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Model").field("id", &self.id).finish()
    }
}

impl Model {
    /// The default parameter values, in spec order.
    pub fn defaults(&self) -> Vec<f64> {
        self.params.iter().map(|p| p.default).collect()
    }

    /// The index of parameter `name`.
    pub fn param_index(&self, name: &str) -> Option<usize> {
        self.params.iter().position(|p| p.name == name)
    }

    /// Check `values` (one per parameter): NaN/∞ is an error at
    /// `params.<name>`; out of range is clamped; integers are rounded.
    pub fn check(&self, values: &[f64]) -> Result<Vec<f64>> {
        if values.len() != self.params.len() {
            return Err(Error::input(format!(
                "model '{}' takes {} parameters ({}), got {}",
                self.id,
                self.params.len(),
                self.params
                    .iter()
                    .map(|p| p.name)
                    .collect::<Vec<_>>()
                    .join(", "),
                values.len()
            ))
            .at("params"));
        }
        self.params
            .iter()
            .zip(values)
            .map(|(p, &v)| {
                if !v.is_finite() {
                    return Err(Error::input(format!(
                        "parameter '{}' of model '{}' must be a finite number (range {}..{})",
                        p.name, self.id, p.lo, p.hi
                    ))
                    .at(format!("params.{}", p.name)));
                }
                let v = v.clamp(p.lo, p.hi);
                Ok(if p.integer { v.round() } else { v })
            })
            .collect()
    }

    /// Defaults overridden by `(name, value)` pairs; an unknown name is an error.
    pub fn with(&self, pairs: &[(&str, f64)]) -> Result<Vec<f64>> {
        let mut v = self.defaults();
        for (name, value) in pairs {
            let i = self.param_index(name).ok_or_else(|| {
                Error::input(format!(
                    "model '{}' has no parameter '{name}' (it has: {})",
                    self.id,
                    self.params
                        .iter()
                        .map(|p| p.name)
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
                .at(format!("params.{name}"))
            })?;
            v[i] = *value;
        }
        Ok(v)
    }
}

/// Every model, in the footnote's order (the 23rd, midpoint displacement,
/// after the other fractals). A model's index here is its class label.
pub static MODELS: [Model; 23] = [
    automata::FOREST_FIRE,
    automata::SURFACE_TENSION,
    automata::EXCITABLE,
    cellular::CELLULAR,
    composite::FOLD_TEXTON,
    composite::FOLD_CELLULAR,
    composite::FOLD_FRACTAL,
    composite::FOLD_PERLIN,
    fractal::ONE_OVER_F,
    fractal::SPECTRAL,
    fractal::MIDPOINT,
    composite::FUSE_CELLULAR_TEXTON,
    composite::FUSE_PERLIN_CELLULAR,
    composite::FUSE_PERLIN_TEXTON,
    islamic::ISLAMIC,
    matrix::MATRIX,
    perlin::PERLIN,
    reaction::REACTION_DIFFUSION,
    texton::ADDITION,
    texton::PROBABILITY_MAP,
    texton::RANDOM_GRID,
    texton::RANDOM_WALK,
    texton::REGULAR,
];

/// The model with this id (or, case-insensitively, this paper name).
pub fn find(name: &str) -> Option<&'static Model> {
    MODELS
        .iter()
        .find(|m| m.id == name || m.name.eq_ignore_ascii_case(name))
}

/// The model with this id, or an error listing the ids.
pub fn lookup(name: &str) -> Result<&'static Model> {
    find(name).ok_or_else(|| {
        Error::input(format!(
            "unknown texture model '{name}'; models: {}",
            MODELS.iter().map(|m| m.id).collect::<Vec<_>>().join(", ")
        ))
        .at("model")
    })
}

fn check_size(size: usize) -> Result<()> {
    if !(MIN_SIZE..=MAX_SIZE).contains(&size) {
        return Err(Error::limit(format!(
            "texture size {size} is outside {MIN_SIZE}..={MAX_SIZE} pixels"
        ))
        .at("size"));
    }
    Ok(())
}

/// Render `model`'s height map (`size`×`size`, heights in [0, 1]) for
/// `params` (one per parameter, see [`Model::check`]) and `seed`. Same
/// inputs, same bits, natively and in wasm.
pub fn render_height(model: &Model, params: &[f64], seed: u64, size: usize) -> Result<Gray> {
    check_size(size)?;
    let p = model.check(params)?;
    let mut data = (model.generate)(&p, seed, size);
    debug_assert_eq!(data.len(), size * size);
    for v in &mut data {
        // Generators stay in range; this only guards the contract.
        *v = if v.is_finite() {
            v.clamp(0.0, 1.0)
        } else {
            0.0
        };
    }
    Ok(Gray {
        width: size,
        height: size,
        data,
    })
}

/// A distant light: azimuth (degrees, counter-clockwise from +x with y
/// pointing up the image) and elevation (degrees above the surface).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub azimuth: f64,
    pub elevation: f64,
}

impl Light {
    /// The fixed light every texture is shown under: from the upper left,
    /// 45° above the surface.
    pub const DEFAULT: Light = Light {
        azimuth: 135.0,
        elevation: 45.0,
    };

    fn vector(self) -> [f32; 3] {
        let (a, e) = (self.azimuth.to_radians(), self.elevation.to_radians());
        [
            (libm::cos(e) * libm::cos(a)) as f32,
            (libm::cos(e) * libm::sin(a)) as f32,
            libm::sin(e) as f32,
        ]
    }
}

impl Default for Light {
    fn default() -> Self {
        Light::DEFAULT
    }
}

/// How high a height of 1 stands, as a fraction of the image side (fixed,
/// so shading looks the same at every size).
pub const RELIEF: f32 = 0.04;

/// Shade a height map with a Lambertian surface under `light`: normals from
/// the wrapped central-difference gradient (height 1 = [`RELIEF`] of the
/// image side), brightness `max(0, n·l)`. The one place textures are lit.
pub fn shade(height: &Gray, light: Light) -> Gray {
    let k = RELIEF * height.width.max(height.height) as f32 * 0.5;
    shade_k(height, light, k, 0.0)
}

/// [`shade`] with the gradient's scale `k` (height units to pixels) and
/// an ambient light: brightness `ambient + (1 − ambient) · max(0, n·l)`
/// (the same bits as `shade` at its `k` and no ambient). [`look`] varies
/// them.
pub(crate) fn shade_k(height: &Gray, light: Light, k: f32, ambient: f32) -> Gray {
    let (w, h) = (height.width, height.height);
    let [lx, ly, lz] = light.vector();
    let mut out = Gray::new(w, h);
    for y in 0..h {
        for x in 0..w {
            let (xi, yi) = (x as isize, y as isize);
            let dx = (height.wrapped(xi + 1, yi) - height.wrapped(xi - 1, yi)) * k;
            // Image rows go down; the light's y goes up.
            let dy = (height.wrapped(xi, yi - 1) - height.wrapped(xi, yi + 1)) * k;
            let (nx, ny, nz) = (-dx, -dy, 1.0f32);
            let len = (nx * nx + ny * ny + nz * nz).sqrt();
            let lit = ((nx * lx + ny * ly + nz * lz) / len).clamp(0.0, 1.0);
            out.data[y * w + x] = ambient + (1.0 - ambient) * lit;
        }
    }
    out
}

/// Render and shade under [`Light::DEFAULT`].
pub fn render(model: &Model, params: &[f64], seed: u64, size: usize) -> Result<Gray> {
    Ok(shade(
        &render_height(model, params, seed, size)?,
        Light::DEFAULT,
    ))
}

#[cfg(test)]
mod tests;
