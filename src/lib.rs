//! Filigree: a procedural-pattern studio.
//!
//! The crate is the whole product's computational core. It builds natively
//! (library + the `filigree` CLI, feature `cli`) and for `wasm32-unknown-unknown`
//! (feature `web`, the only code that touches wasm-bindgen; see `src/web/`).
//!
//! Layers (see ARCHITECTURE.md):
//! - [`core`]: errors, limits, the step-driven [`core::job::Job`] interface with
//!   progress and cancellation, seeded randomness.
//! - [`raster`]: image decoding with explicit limits, palettes, thumbnails, PNG encoding.
//! - [`inspect`]: the shared "what is in this image" service (size, palette, thumbnail).
//! - shared building blocks, public so every tool (and its benches) can use
//!   them: [`geom`] (2-D primitives, their distance functions, the distance
//!   transform) and [`optim`] (ask/tell optimisers, Adam).
//! - one folder per tool (`pixel`, `pattern`), plain Rust with no browser types;
//!   each has an `api` module: its typed requests with their defaults.
//! - [`api`]: the request registry (kind → request → job → response) that the
//!   wasm boundary, the CLI, tests and fuzzers share.
#![forbid(unsafe_code)]

pub mod api;
pub mod core;
pub mod geom;
pub mod inspect;
pub mod micro;
pub mod optim;
pub mod pattern;
pub mod pixel;
pub mod raster;
pub mod tangle;
pub mod texture;

#[cfg(feature = "web")]
pub mod web;

pub use crate::core::error::{Error, Result};
