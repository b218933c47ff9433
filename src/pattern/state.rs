//! The Fit tool's document (what the page keeps, autosaves, saves in a
//! project file and shares), its schema version and its checks, field by
//! field (see [`crate::core::value`]). Field names are the page's:
//!
//! ```text
//! { generator: name | null, program: text, values: [number],
//!   target: {width, height, rgba: bytes} | null, truth: [number] | null,
//!   result: {params: [number], loss, names?: [text], evaluations} | null,
//!   settings: {budget: "quick" | "paper", loss: "sdf" | ..., seed} }
//! ```
//!
//! The program's size is the core's program limit
//! ([`crate::core::limits::MAX_PROGRAM_BYTES`]); budgets and losses are the
//! core's `fit` request names. A target is 256 px along its longer side
//! ([`TARGET_SIDE`]): square when drawn or made from values, the upload's
//! aspect when uploaded (the fit's canvas follows it); files from before
//! uploads kept their aspect hold 256 × 256 targets, which still check.
use super::fit::Budget;
use super::loss::LossKind;
use crate::core::error::Result;
use crate::core::limits::MAX_PROGRAM_BYTES;
use crate::core::value::{invalid, js_len, js_text, Value, MAX_SAFE_INTEGER};
use serde::de::value::{Error as DeError, StrDeserializer};
use serde::{Deserialize, Serialize};

/// Schema version of the Fit state (the page's `state.version`).
pub const STATE_VERSION: u32 = 1;
/// Longer side of the target the page keeps, in pixels (the side of a
/// drawn one).
pub const TARGET_SIDE: u32 = 256;
/// Most numbers in `values`, `truth` and `result.params` (and names).
pub const MAX_VALUES: usize = 1000;
/// Longest generator name, in characters.
pub const MAX_GENERATOR_NAME: usize = 100;
/// The budgets and losses, as the `fit` request names them.
pub const BUDGETS: &[&str] = &["quick", "paper"];
pub const LOSSES: &[&str] = &["sdf", "l1", "pyramid", "image"];

/// A checked Fit document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitState {
    pub generator: Option<String>,
    pub program: String,
    pub values: Vec<f64>,
    pub target: Option<Target>,
    pub truth: Option<Vec<f64>>,
    pub result: Option<FitResultState>,
    pub settings: Settings,
}

/// The drawn (or rendered) target: straight RGBA.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Target {
    pub width: u32,
    pub height: u32,
    #[serde(with = "serde_bytes")]
    pub rgba: Vec<u8>,
}

/// The last fit's answer, as the page shows it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct FitResultState {
    pub params: Vec<f64>,
    pub loss: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub names: Option<Vec<String>>,
    pub evaluations: u64,
}

/// The fit settings the panel offers.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Settings {
    pub budget: Budget,
    pub loss: LossKind,
    pub seed: u64,
}

fn finite_list(v: Option<&Value>, field: &str) -> Result<Vec<f64>> {
    v.and_then(Value::as_list)
        .filter(|l| l.len() <= MAX_VALUES)
        .and_then(|l| l.iter().map(Value::finite).collect())
        .ok_or_else(|| {
            invalid(
                field,
                format!("must be a list of at most {MAX_VALUES} finite numbers"),
            )
        })
}

fn choice<'a, T: Deserialize<'a>>(v: Option<&'a Value>, field: &str, names: &[&str]) -> Result<T> {
    v.and_then(Value::as_text)
        .filter(|s| names.contains(s))
        .and_then(|s| T::deserialize(StrDeserializer::<DeError>::new(s)).ok())
        .ok_or_else(|| invalid(field, format!("must be one of {}", names.join(", "))))
}

fn seed(v: Option<&Value>, field: &str) -> Result<u64> {
    v.and_then(Value::whole)
        .filter(|x| (0.0..=MAX_SAFE_INTEGER).contains(x))
        .map(|x| x as u64)
        .ok_or_else(|| invalid(field, "must be a whole number ≥ 0"))
}

/// Check a Fit document field by field; the error names the field at fault.
pub fn check(raw: &Value) -> Result<FitState> {
    if !raw.is_plain_object() {
        return Err(invalid("state", "is not a Fit document"));
    }
    let generator = match raw.get("generator") {
        None | Some(Value::Null) => None,
        Some(Value::Text(g)) if js_len(g) <= MAX_GENERATOR_NAME => Some(g.clone()),
        Some(_) => return Err(invalid("generator", "must be a generator name")),
    };
    let program = raw
        .get("program")
        .and_then(Value::as_text)
        .filter(|p| !p.trim().is_empty() && p.len() <= MAX_PROGRAM_BYTES)
        .ok_or_else(|| {
            invalid(
                "program",
                format!("must be the text of a program (at most {MAX_PROGRAM_BYTES} bytes)"),
            )
        })?
        .to_string();
    let values = finite_list(raw.get("values"), "values")?;

    let target = match raw.get("target") {
        None | Some(Value::Null) => None,
        Some(t) => {
            let side = |k: &str| {
                t.get(k)
                    .and_then(Value::as_f64)
                    .filter(|v| v.fract() == 0.0 && (1.0..=TARGET_SIDE as f64).contains(v))
                    .map(|v| v as u32)
            };
            let (width, height) = match (side("width"), side("height")) {
                (Some(w), Some(h)) if w.max(h) == TARGET_SIDE => (w, h),
                _ => {
                    return Err(invalid(
                        "target",
                        format!(
                            "must be {TARGET_SIDE} pixels along its longer side \
                             (and at least 1 along the other)"
                        ),
                    ))
                }
            };
            let n = width as usize * height as usize * 4;
            match t.get("rgba") {
                Some(Value::Bytes(b)) if b.len() == n => Some(Target {
                    width,
                    height,
                    rgba: b.clone(),
                }),
                _ => return Err(invalid("target.rgba", format!("must hold {n} bytes"))),
            }
        }
    };

    let truth = match raw.get("truth") {
        None | Some(Value::Null) => None,
        t => Some(finite_list(t, "truth")?),
    };
    if let Some(t) = &truth {
        if t.len() != values.len() {
            return Err(invalid(
                "truth",
                format!("must have one value per parameter ({})", values.len()),
            ));
        }
    }

    let result = match raw.get("result") {
        None | Some(Value::Null) => None,
        Some(r) if !r.is_object_like() => return Err(invalid("result", "is not a fit result")),
        Some(r) => {
            let params = finite_list(r.get("params"), "result.params")?;
            let loss = r
                .get("loss")
                .and_then(Value::finite)
                .filter(|l| *l >= 0.0)
                .ok_or_else(|| invalid("result.loss", "must be a finite number ≥ 0"))?;
            let evaluations = match r.get("evaluations") {
                None | Some(Value::Null) => 0,
                e => seed(e, "result.evaluations")?,
            };
            let names = match r.get("names") {
                None | Some(Value::Null) => None,
                Some(n) => Some(
                    n.as_list()
                        .filter(|l| l.len() <= MAX_VALUES)
                        .ok_or_else(|| {
                            invalid(
                                "result.names",
                                format!("must be a list of at most {MAX_VALUES} parameter names"),
                            )
                        })?
                        .iter()
                        .map(|x| js_text(Some(x)))
                        .collect(),
                ),
            };
            Some(FitResultState {
                params,
                loss,
                names,
                evaluations,
            })
        }
    };

    let s = raw
        .get("settings")
        .filter(|s| s.is_object_like())
        .ok_or_else(|| invalid("settings", "are missing"))?;
    let settings = Settings {
        budget: choice(s.get("budget"), "settings.budget", BUDGETS)?,
        loss: choice(s.get("loss"), "settings.loss", LOSSES)?,
        seed: seed(s.get("seed"), "settings.seed")?,
    };
    Ok(FitState {
        generator,
        program,
        values,
        target,
        truth,
        result,
        settings,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn budgets_and_losses_are_the_core_names() {
        for b in BUDGETS {
            let v: Budget = Budget::deserialize(StrDeserializer::<DeError>::new(b)).unwrap();
            assert_eq!(serde_json::to_value(v).unwrap(), *b);
        }
        for l in LOSSES {
            let v = LossKind::deserialize(StrDeserializer::<DeError>::new(l)).unwrap();
            assert_eq!(serde_json::to_value(v).unwrap(), *l);
        }
    }
}
