//! Texture: perceptual procedural-texture retrieval, after Liu, Gan, Dong,
//! Dong & Dong, "Perception-driven procedural texture generation from
//! examples" (PCN). MISSION X1–X7.
//!
//! - [`image`]: the grey image every stage passes along ([`Gray`]).
//!
//! Planned (issue 11): procedural models and their height-map shading
//! (`models`), the dataset (`dataset`), perceptual scale estimators
//! (`scales`), the PCN-2 feature extractor (`pcn`), the learners (`learn`)
//! and the static index asset the browser loads.
pub mod dataset;
pub mod image;
pub mod models;
pub mod scales;

pub use image::Gray;
