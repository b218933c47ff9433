//! Checks shared by every scene node's reader ([`super::scene`],
//! [`super::cells`], [`super::periodic`]): errors that name the node path,
//! and finite numbers within their range.
use crate::core::error::{Error, Result};
use glam::DVec3;

/// Build error about `scene` at node path `path`.
pub(crate) fn bad(path: &str, msg: impl std::fmt::Display) -> Error {
    let at = if path.is_empty() {
        "the scene".to_string()
    } else {
        format!("scene node `{path}`")
    };
    Error::input(format!("{at}: {msg}")).at("scene")
}

pub(crate) fn join(path: &str, seg: impl std::fmt::Display) -> String {
    if path.is_empty() {
        seg.to_string()
    } else {
        format!("{path}.{seg}")
    }
}

/// `v` finite and within `lo..=hi`, else an error naming `path.name`.
pub(crate) fn num(path: &str, name: &str, v: f64, lo: f64, hi: f64) -> Result<f64> {
    if v.is_finite() && v >= lo && v <= hi {
        Ok(v)
    } else {
        Err(bad(
            &join(path, name),
            format!("must be a finite number in {lo}..={hi} (got {v})"),
        ))
    }
}

pub(crate) fn vec3(path: &str, name: &str, v: [f64; 3], lo: f64, hi: f64) -> Result<DVec3> {
    for (i, x) in v.iter().enumerate() {
        num(path, &format!("{name}.{i}"), *x, lo, hi)?;
    }
    Ok(DVec3::from_array(v))
}

/// Coordinates and lengths of a scene live in ±1e6 world units.
pub(crate) const WORLD: f64 = 1e6;
