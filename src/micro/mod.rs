//! Micro: multiscale microstructures as implicit functions, after Venu,
//! Bosak & Padrón-Griffe, "Procedural Multiscale Geometry Modeling using
//! Implicit Functions" (2025).
//!
//! - [`scene`]: a scene is a tree of JSON nodes (primitives, booleans and
//!   blends, transforms, and the structures below), checked and compiled
//!   into a field normalised by each node's gradient bound.
//! - [`cells`]: suspended particles (hashed grid seeds, Eq. 1–3; the dual
//!   grid's 8 cells, Eq. 4–6; shapes, size distributions, offset, warp,
//!   rejection, mixtures), agglomerates (27-neighbourhood, `D(q)` from
//!   integer polynomial congruences, Eq. 8–9, smooth-min) and piles (Eq. 10).
//! - [`periodic`]: gyroid, diamond, primitive and Eq. 11's sums of
//!   products of sines and cosines.
//! - [`render`]: sphere tracing with fixed, bisection and adaptive steps,
//!   normals, shading, the orbit camera and slices.
//! - [`glsl`]: the same scene as a WebGL2 fragment-shader sphere tracer
//!   (`micro-glsl`), the browser's interactive view.
//! - [`api`]: the `micro-render`, `micro-glsl` and `micro-slice` requests.
//! - [`fit`]: the Fourier loss (§6.1, Eq. 36, 39); [`fit_api`]: the
//!   `micro-fit` request and its job (reconstruction, Table 3).
//! - [`examples`]: the shipped scenes (`micro-examples`); [`state`]: the
//!   browser tool's document.
pub mod api;
pub mod cells;
mod checks;
pub mod examples;
pub mod fit;
pub mod fit_api;
pub mod glsl;
pub mod periodic;
pub mod render;
pub mod scene;
pub mod sdf3;
pub mod state;

pub use scene::{parse, Node, Scene};
