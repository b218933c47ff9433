//! Texture: perceptual procedural-texture retrieval, after Liu, Gan, Dong,
//! Dong & Dong, "Perception-driven procedural texture generation from
//! examples" (PCN). MISSION X1–X7.
//!
//! - [`api`]: the `texture-*` requests (CLI and browser).
//! - [`image`]: the grey image every stage passes along ([`Gray`]).
//! - [`models`]: the procedural models (height maps) and the one shading.
//! - [`dataset`]: models' parameters on a linear grid, rendered, augmented.
//! - [`pcn`]: the PCN-2 feature extractor.
//! - [`lbp`]: rotation-invariant local binary patterns beside PCN-2 (issue 36).
//! - [`learn`]: support vector machines and Isomap.
//! - [`scales`]: estimators of the twelve perceptual scales, 1–9.
//! - [`globals`]: global values (scale measures, radial spectrum, grey
//!   moments) the model classifier reads beside PCN-2 (our addition).
//! - [`index`]: the trained index the browser loads, and retrieval.
//! - [`state`]: the Texture document (the page's state) and its checks.
pub mod api;
pub mod build;
pub mod dataset;
pub mod globals;
pub mod image;
pub mod index;
pub mod lbp;
pub mod learn;
pub mod models;
pub mod pcn;
pub mod scales;
pub mod state;

pub use image::Gray;
