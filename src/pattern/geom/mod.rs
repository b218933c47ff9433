//! Fit's 2-D geometry: exact distances to primitives with their derivatives
//! ([`primitives`]), quadratic and cubic Bézier helpers ([`bezier`]),
//! winding numbers ([`winding`]), the exact Euclidean distance transform of
//! a raster mask ([`distance_transform`]) and the sub-pixel one of an
//! anti-aliased coverage raster ([`aa_distance`]). (Only Fit uses them, so
//! they live in its folder; `crate::geom` holds what two tools share.)
//!
//! The Fit kernels use plain `[f64; 2]` points ([`Vec2`]): small scalar
//! kernels that callers (Fit's field evaluator) inline into lane loops, and
//! keeping their arithmetic exactly as written keeps results bit-identical
//! natively and in wasm. Coordinates are whatever the caller uses (Fit: the
//! `[0, 1]²` canvas, y down); nothing here knows about patterns or images.
//!
//! Distances of closed primitives (circles, rounded rectangles) are signed,
//! negative inside; points, segments and curve pieces are unsigned (a closed
//! path gets its sign from the winding number of its pieces). Derivatives
//! follow from the envelope theorem: for `d = |p − q(θ)|` with `q` the
//! closest point, `∂d/∂θ = −n·∂q/∂θ` at the fixed closest parameter,
//! `n = (p − q)/d`.
pub mod aa_distance;
pub mod bezier;
pub mod distance_transform;
pub mod primitives;
pub mod winding;

/// A point or vector.
pub type Vec2 = [f64; 2];

/// Euclidean length of `(x, y)`.
#[inline(always)]
pub fn len(x: f64, y: f64) -> f64 {
    (x * x + y * y).sqrt()
}
