//! Periodic implicit functions (paper §3.4): triply periodic minimal
//! surfaces and the general sum of products of sines and cosines (Eq. 11),
//! each divided by a bound of its gradient's magnitude so that it is
//! 1-Lipschitz. No grid, no neighbour cells: one evaluation per point.
//! Trigonometry is `libm`'s, so native and wasm agree bit for bit.
use super::checks::{bad, join, num, WORLD};
use crate::core::error::Result;
use crate::core::limits::MAX_MICRO_TERMS;
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// Which minimal surface.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Surface {
    Gyroid,
    Diamond,
    Primitive,
}

/// A TPMS: `g(k p) − level` (solid) or `|g(k p)| − thickness` (sheet)
/// with `k = 2π / period`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tpms {
    pub surface: Surface,
    /// Cell size (world units).
    pub period: f64,
    /// Solid: the level set `g = level` bounds the solid `g < level`.
    #[serde(default)]
    pub level: f64,
    /// Sheet: when > 0, the shell `|g| < thickness` (in units of g).
    #[serde(default)]
    pub thickness: f64,
    #[serde(skip)]
    pub(crate) k: f64,
    #[serde(skip)]
    pub(crate) inv_bound: f64,
}

impl Tpms {
    pub(crate) fn checked(&self, path: &str) -> Result<Tpms> {
        let mut t = self.clone();
        num(path, "period", t.period, 1e-6, WORLD)?;
        num(path, "level", t.level, -3.0, 3.0)?;
        num(path, "thickness", t.thickness, 0.0, 3.0)?;
        t.k = std::f64::consts::TAU / t.period;
        // |∇g| ≤ √3 k for the gyroid and primitive (Cauchy–Schwarz per
        // axis), ≤ √6 k for the diamond (each partial ≤ 2 k).
        let c = match t.surface {
            Surface::Gyroid | Surface::Primitive => 3f64.sqrt(),
            Surface::Diamond => 6f64.sqrt(),
        };
        t.inv_bound = 1.0 / (c * t.k);
        Ok(t)
    }

    /// The raw function value `g(k p)`.
    pub fn raw(surface: Surface, q: DVec3) -> f64 {
        let (sx, cx) = (libm::sin(q.x), libm::cos(q.x));
        let (sy, cy) = (libm::sin(q.y), libm::cos(q.y));
        let (sz, cz) = (libm::sin(q.z), libm::cos(q.z));
        match surface {
            Surface::Gyroid => sx * cy + sy * cz + sz * cx,
            Surface::Diamond => sx * sy * sz + sx * cy * cz + cx * sy * cz + cx * cy * sz,
            Surface::Primitive => cx + cy + cz,
        }
    }

    pub(crate) fn eval(&self, p: DVec3) -> f64 {
        let g = Self::raw(self.surface, p * self.k);
        let v = if self.thickness > 0.0 {
            g.abs() - self.thickness
        } else {
            g - self.level
        };
        v * self.inv_bound
    }
}

/// Sine or cosine.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Wave {
    Sin,
    Cos,
}

/// A coordinate axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Axis {
    X,
    Y,
    Z,
}

/// One factor `amp · wave(freq · p_axis + phase) ^ power`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Factor {
    pub wave: Wave,
    pub axis: Axis,
    #[serde(default = "one")]
    pub amp: f64,
    #[serde(default = "one")]
    pub freq: f64,
    #[serde(default)]
    pub phase: f64,
    #[serde(default = "one_u")]
    pub power: u32,
}

fn one() -> f64 {
    1.0
}
fn one_u() -> u32 {
    1
}

/// Eq. 11: `SC(p) = Σᵢ Πⱼ Tᵢⱼ(p)^kᵢⱼ + constant`, the solid `SC < 0`
/// (or the sheet `|SC| < thickness`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Periodic {
    /// Each term is a product of factors.
    pub terms: Vec<Vec<Factor>>,
    #[serde(default)]
    pub constant: f64,
    #[serde(default)]
    pub thickness: f64,
    #[serde(skip)]
    pub(crate) inv_bound: f64,
}

const MAX_POWER: u32 = 8;

fn powu(x: f64, n: u32) -> f64 {
    let mut r = 1.0;
    for _ in 0..n {
        r *= x;
    }
    r
}

impl Periodic {
    pub(crate) fn checked(&self, path: &str) -> Result<Periodic> {
        let mut t = self.clone();
        let factors: usize = t.terms.iter().map(Vec::len).sum();
        if t.terms.is_empty() || factors > MAX_MICRO_TERMS {
            return Err(bad(
                &join(path, "terms"),
                format!("needs 1 to {MAX_MICRO_TERMS} factors in all (got {factors})"),
            ));
        }
        num(path, "constant", t.constant, -WORLD, WORLD)?;
        num(path, "thickness", t.thickness, 0.0, WORLD)?;
        // Gradient bound per axis: for a product Π aⱼ wⱼ^kⱼ the partial
        // along an axis is bounded by Σ over the factors on that axis of
        // kⱼ |ωⱼ| Π |aₗ|^kₗ (|w| ≤ 1, |w'| ≤ 1).
        let mut g = [0.0f64; 3];
        for (i, term) in t.terms.iter().enumerate() {
            let mut mag = 1.0;
            for (j, f) in term.iter().enumerate() {
                let fp = join(path, format!("terms.{i}.{j}"));
                num(&fp, "amp", f.amp, -1e6, 1e6)?;
                num(&fp, "freq", f.freq, -1e6, 1e6)?;
                num(&fp, "phase", f.phase, -1e6, 1e6)?;
                if f.power > MAX_POWER {
                    return Err(bad(
                        &join(&fp, "power"),
                        format!("must be at most {MAX_POWER}"),
                    ));
                }
                mag *= powu(f.amp.abs(), f.power);
            }
            for f in term {
                if f.power > 0 {
                    g[f.axis as usize] += f.power as f64 * f.freq.abs() * mag;
                }
            }
        }
        let bound = (g[0] * g[0] + g[1] * g[1] + g[2] * g[2]).sqrt();
        if !(bound.is_finite() && bound > 0.0) {
            return Err(bad(
                &join(path, "terms"),
                "the function is constant (every factor has frequency, amplitude or power 0)",
            ));
        }
        t.inv_bound = 1.0 / bound;
        Ok(t)
    }

    /// The raw `SC(p)`.
    pub fn raw(&self, p: DVec3) -> f64 {
        let c = p.to_array();
        let mut sum = self.constant;
        for term in &self.terms {
            let mut prod = 1.0;
            for f in term {
                let x = f.freq * c[f.axis as usize] + f.phase;
                let w = match f.wave {
                    Wave::Sin => libm::sin(x),
                    Wave::Cos => libm::cos(x),
                };
                prod *= powu(f.amp * w, f.power);
            }
            sum += prod;
        }
        sum
    }

    pub(crate) fn eval(&self, p: DVec3) -> f64 {
        let v = self.raw(p);
        let v = if self.thickness > 0.0 {
            v.abs() - self.thickness
        } else {
            v
        };
        v * self.inv_bound
    }
}
