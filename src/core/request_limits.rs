//! Limits of request fields, in one place, and the checks that apply them
//! where a request enters the core (the browser's payloads and the CLI's
//! flags become the same request structs, so both are checked here).
//!
//! Image, buffer and program limits are the other half of the list, in
//! [`crate::core::limits`]; these are the limits of the numbers a person
//! types or a panel sends.
//! Every message names the field (its dotted request path) and the range.
use crate::core::error::{Error, Result};

/// RGB distance (tolerance) range: 0 (exact) to the largest distance
/// between two RGB colours, √3·255 ≈ 441.7.
pub const TOLERANCE: (f64, f64) = (0.0, super::limits::MAX_TOLERANCE);
/// Side of a rendered pattern (`render-pattern`, `filigree render`).
pub const RENDER_SIZE: (usize, usize) = (1, 2048);
/// Samples per pixel side of a rendered pattern.
pub const SUPERSAMPLE: (usize, usize) = (1, 4);
/// Side of a snapped target (`pattern-snap`).
pub const SNAP_SIZE: (usize, usize) = (8, 2048);
/// Loss grid side of a `fit-eval` (it splits one loss over several steps).
pub const GRID: (usize, usize) = (8, 1024);
/// Loss grid side of a `fit`. A fit evaluates one loss or one gradient per
/// step at least; at 256 a gradient is under ~20 ms, at 1024 it was 300 ms.
/// An image target's fields are sampled from up to 512 px, so a 256 grid
/// loses little.
pub const FIT_GRID: (usize, usize) = (8, 256);
/// GA population and generations of a fit.
pub const POPULATION: (usize, usize) = (2, 10_000);
pub const GENERATIONS: (usize, usize) = (0, 10_000);
/// Candidates refined with Adam, and Adam (and polish) iterations each.
pub const CANDIDATES: (usize, usize) = (1, 100);
pub const ITERATIONS: (usize, usize) = (0, 100_000);
/// A fit's time bound (`max_seconds`), seconds.
pub const FIT_SECONDS: (f64, f64) = (0.1, 3600.0);
/// Shards one fit may be split into (one per worker of a pool).
pub const SHARDS: usize = 64;
/// Parameter vectors in one `fit-eval` request.
pub const EVAL_POINTS: usize = 10_000;
/// Largest magnitude of a named parameter value.
pub const PARAM_MAGNITUDE: f64 = 1e9;
/// Native threads of a CLI fit: one shard each, so at most [`SHARDS`].
pub const THREADS: (usize, usize) = (1, SHARDS);
/// Pixel: annotation scale K, density ρ, margins (pixels, either sign),
/// HSV shift, CIELAB distance d_max, most excluded colours.
pub const ANNOTATION_SCALE: (u32, u32) = (1, super::limits::MAX_ANNOTATION_SCALE);
pub const DENSITY: (f64, f64) = (0.0, 1.0);
pub const MARGIN: i32 = super::limits::MAX_MARGIN;
pub const HUE_SHIFT: f64 = 360.0;
pub const SV_SHIFT: f64 = 100.0;
pub const D_MAX: (f64, f64) = (0.0, 1000.0);
pub const EXCLUDED: usize = 256;

/// `v` must be finite and within `lo..=hi`.
pub fn finite_in(field: &str, v: f64, (lo, hi): (f64, f64)) -> Result<f64> {
    if v.is_finite() && (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(Error::input(format!(
            "`{field}` must be a finite number in {lo}..={hi} (got {})",
            short_number(v)
        ))
        .at(field))
    }
}

/// A number for a message: as written when that is at most 12 characters,
/// else in scientific notation (a 309-digit value is not echoed in full).
pub fn short_number(v: f64) -> String {
    let t = format!("{v}");
    if t.len() <= 12 {
        t
    } else {
        format!("{v:.4e}")
    }
}

/// `v` must be within `lo..=hi`.
pub fn int_in<T: PartialOrd + std::fmt::Display + Copy>(
    field: &str,
    v: T,
    (lo, hi): (T, T),
) -> Result<T> {
    if lo <= v && v <= hi {
        Ok(v)
    } else {
        Err(Error::input(format!("`{field}` must be in {lo}..={hi} (got {v})")).at(field))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 34: a 309-digit value was echoed in full in the refusal.
    #[test]
    fn huge_numbers_are_shortened_in_messages() {
        let e = finite_in("tolerance", 1e308, (0.0, 442.0))
            .unwrap_err()
            .to_string();
        assert!(e.contains("1.0000e308") && e.len() < 120, "{e}");
        assert_eq!(short_number(0.25), "0.25");
    }

    #[test]
    fn checks_name_the_field_and_reject_non_finite() {
        let e = finite_in("tolerance", f64::NAN, TOLERANCE).unwrap_err();
        assert_eq!(e.field(), Some("tolerance"));
        assert!(e.to_string().contains("`tolerance`"), "{e}");
        assert!(finite_in("tolerance", -5.0, TOLERANCE).is_err());
        assert!(finite_in("tolerance", f64::INFINITY, TOLERANCE).is_err());
        assert_eq!(finite_in("tolerance", 60.0, TOLERANCE), Ok(60.0));
        let e = int_in("supersample", usize::MAX, SUPERSAMPLE).unwrap_err();
        assert!(e.to_string().contains("1..=4"), "{e}");
    }
}
