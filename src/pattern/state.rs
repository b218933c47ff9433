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
use crate::core::check::{null_as_default, read_document, Check, Path};
use crate::core::error::Result;
use crate::core::limits::MAX_PROGRAM_BYTES;
use crate::core::value::{js_text, Value, MAX_SAFE_INTEGER};
use serde::{Deserialize, Deserializer, Serialize};

/// Schema version of the Fit state (the page's `state.version`).
pub const STATE_VERSION: u32 = 1;
/// Longer side of the target the page keeps, in pixels (the side of a
/// drawn one).
pub const TARGET_SIDE: u32 = 256;
/// Most numbers in `values`, `truth` and `result.params` (and names).
pub const MAX_VALUES: usize = 1000;
/// Longest generator name, in characters.
pub const MAX_GENERATOR_NAME: usize = 100;

/// A Fit document (unknown fields are dropped, as they always were).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitState {
    #[serde(default)]
    pub generator: Option<String>,
    pub program: String,
    pub values: Vec<f64>,
    #[serde(default)]
    pub target: Option<Target>,
    #[serde(default)]
    pub truth: Option<Vec<f64>>,
    #[serde(default)]
    pub result: Option<FitResultState>,
    pub settings: Settings,
}

/// The drawn (or rendered) target: straight RGBA.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Target {
    pub width: u32,
    pub height: u32,
    #[serde(with = "serde_bytes")]
    pub rgba: Vec<u8>,
}

/// The last fit's answer, as the page shows it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitResultState {
    pub params: Vec<f64>,
    pub loss: f64,
    /// Each name as the page's `String(name)` writes it.
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "js_texts"
    )]
    pub names: Option<Vec<String>>,
    /// Missing or `null` in older documents: 0.
    #[serde(default, deserialize_with = "null_as_default")]
    pub evaluations: u64,
}

/// The fit settings the panel offers: the `fit` request's own fields and
/// names ([`super::api::FitRequest`]'s `budget`, `loss`, `seed`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Settings {
    pub budget: Budget,
    pub loss: LossKind,
    pub seed: u64,
}

/// A list of anything, each item as text (`String(x)`); `null` is `None`.
fn js_texts<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Option<Vec<String>>, D::Error> {
    let list: Option<Vec<Value>> = Option::deserialize(d)?;
    Ok(list.map(|l| l.iter().map(|x| js_text(Some(x))).collect()))
}

/// At most [`MAX_VALUES`] finite numbers.
fn finite_list(at: &Path, list: &[f64]) -> Result<()> {
    if list.len() <= MAX_VALUES && list.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(at.invalid(format!(
            "must be a list of at most {MAX_VALUES} finite numbers"
        )))
    }
}

fn safe_whole(at: &Path, v: u64) -> Result<()> {
    at.whole_in(v, (0, MAX_SAFE_INTEGER as u64))
}

impl Check for FitState {
    fn check(&self, at: &Path) -> Result<()> {
        if let Some(g) = &self.generator {
            at.key("generator").js_len_at_most(
                g,
                MAX_GENERATOR_NAME,
                format!("must be a generator name (at most {MAX_GENERATOR_NAME} characters)"),
            )?;
        }
        if self.program.trim().is_empty() || self.program.len() > MAX_PROGRAM_BYTES {
            return Err(at.key("program").invalid(format!(
                "must be the text of a program (at most {MAX_PROGRAM_BYTES} bytes)"
            )));
        }
        finite_list(&at.key("values"), &self.values)?;
        self.target.check(&at.key("target"))?;
        if let Some(t) = &self.truth {
            finite_list(&at.key("truth"), t)?;
            if t.len() != self.values.len() {
                return Err(at.key("truth").invalid(format!(
                    "must have one value per parameter ({})",
                    self.values.len()
                )));
            }
        }
        self.result.check(&at.key("result"))?;
        safe_whole(&at.key("settings").key("seed"), self.settings.seed)
    }
}

impl Check for Target {
    fn check(&self, at: &Path) -> Result<()> {
        let (w, h) = (self.width, self.height);
        if w.min(h) < 1 || w.max(h) != TARGET_SIDE {
            return Err(at.invalid(format!(
                "must be {TARGET_SIDE} pixels along its longer side \
                 (and at least 1 along the other)"
            )));
        }
        let n = w as usize * h as usize * 4;
        if self.rgba.len() != n {
            return Err(at.key("rgba").invalid(format!("must hold {n} bytes")));
        }
        Ok(())
    }
}

impl Check for FitResultState {
    fn check(&self, at: &Path) -> Result<()> {
        finite_list(&at.key("params"), &self.params)?;
        if !(self.loss.is_finite() && self.loss >= 0.0) {
            return Err(at.key("loss").invalid("must be a finite number ≥ 0"));
        }
        safe_whole(&at.key("evaluations"), self.evaluations)?;
        if self.names.as_ref().is_some_and(|n| n.len() > MAX_VALUES) {
            return Err(at.key("names").invalid(format!(
                "must be a list of at most {MAX_VALUES} parameter names"
            )));
        }
        Ok(())
    }
}

/// Read and check a Fit document; the error names the field at fault.
pub fn check(raw: &Value) -> Result<FitState> {
    read_document(raw, "Fit")
}

#[cfg(test)]
mod tests {
    //! The document and the `fit` request agree: each range just inside is
    //! accepted, just outside refused naming the field.
    use super::*;
    use crate::core::error::Error;
    use serde_json::{json, Value as Json};

    fn doc() -> Json {
        json!({
            "generator": "stripes", "program": "param r in [0, 1] = 0.5;\ncircle(0.5, 0.5, r);\n",
            "values": [0.5], "target": null, "truth": [0.25],
            "result": {"params": [0.3], "loss": 0.0, "names": ["r"], "evaluations": 0},
            "settings": {"budget": "quick", "loss": "sdf", "seed": 0}
        })
    }

    fn read(j: &Json) -> Result<FitState> {
        check(&Value::read(j, false).unwrap())
    }

    fn with(edit: impl Fn(&mut Json)) -> Json {
        let mut d = doc();
        edit(&mut d);
        d
    }

    #[track_caller]
    fn refused(d: &Json, field: &str) -> Error {
        let e = read(d).unwrap_err();
        assert_eq!(e.field(), Some(field), "{e}");
        assert!(e.to_string().starts_with(field), "{e} names {field}");
        e
    }

    #[test]
    fn every_range_is_inside_or_out_by_one() {
        let n = |k: usize| json!(vec![0.5; k]);
        // (inside, outside, field)
        let cases: Vec<(Json, Json, &str)> = vec![
            (
                with(|d| d["generator"] = json!("g".repeat(MAX_GENERATOR_NAME))),
                with(|d| d["generator"] = json!("g".repeat(MAX_GENERATOR_NAME + 1))),
                "generator",
            ),
            (
                with(|d| d["program"] = json!("c".repeat(MAX_PROGRAM_BYTES))),
                with(|d| d["program"] = json!("c".repeat(MAX_PROGRAM_BYTES + 1))),
                "program",
            ),
            (
                with(|d| {
                    d["values"] = n(MAX_VALUES);
                    d["truth"] = n(MAX_VALUES);
                }),
                with(|d| {
                    d["values"] = n(MAX_VALUES + 1);
                    d["truth"] = Json::Null;
                }),
                "values",
            ),
            (
                with(|d| d["result"]["params"] = n(MAX_VALUES)),
                with(|d| d["result"]["params"] = n(MAX_VALUES + 1)),
                "result.params",
            ),
            (
                with(|d| d["result"]["names"] = json!(vec!["r"; MAX_VALUES])),
                with(|d| d["result"]["names"] = json!(vec!["r"; MAX_VALUES + 1])),
                "result.names",
            ),
            (
                with(|d| d["truth"] = n(1)),
                with(|d| d["truth"] = n(2)),
                "truth",
            ),
            (
                with(|d| d["result"]["loss"] = json!(0.0)),
                with(|d| d["result"]["loss"] = json!(-1e-9)),
                "result.loss",
            ),
            (
                with(|d| d["settings"]["seed"] = json!(MAX_SAFE_INTEGER)),
                with(|d| d["settings"]["seed"] = json!(-1)),
                "settings.seed",
            ),
            (
                with(|d| {
                    d["target"] = json!({"width": TARGET_SIDE, "height": 1,
                        "rgba": vec![0u8; TARGET_SIDE as usize * 4]})
                }),
                with(|d| {
                    d["target"] = json!({"width": TARGET_SIDE + 1, "height": 1,
                        "rgba": vec![0u8; (TARGET_SIDE as usize + 1) * 4]})
                }),
                "target",
            ),
        ];
        for (inside, outside, field) in cases {
            // serde_json has no bytes: a target's rgba goes in as bytes.
            let bytes = |j: &Json| {
                let mut v = Value::read(j, false).unwrap();
                if let Value::Object(kv) = &mut v {
                    for (k, t) in kv.iter_mut() {
                        if let (true, Value::Object(t)) = (k == "target", t) {
                            for (k, r) in t.iter_mut() {
                                if let (true, Value::List(l)) = (k == "rgba", &*r) {
                                    let b = l.iter().map(|x| x.as_f64().unwrap() as u8).collect();
                                    *r = Value::Bytes(b);
                                }
                            }
                        }
                    }
                }
                v
            };
            check(&bytes(&inside)).unwrap_or_else(|e| panic!("{field} inside: {e}"));
            let e = check(&bytes(&outside)).unwrap_err();
            assert_eq!(e.field(), Some(field), "{e}");
            assert!(e.to_string().starts_with(field), "{e}");
        }
        // NaN, which a page's number can be, is not a value.
        let mut v = Value::read(doc(), false).unwrap();
        if let Value::Object(kv) = &mut v {
            for (_, v) in kv.iter_mut().filter(|(k, _)| k == "values") {
                *v = Value::List(vec![Value::Number(f64::NAN)]);
            }
        }
        assert_eq!(check(&v).unwrap_err().field(), Some("values"));
    }

    #[test]
    fn the_settings_are_the_fit_requests() {
        // Every budget and loss the `fit` request reads is a document's,
        // and no other name.
        let req = crate::pattern::api::FitRequest::default();
        let d = with(|d| {
            d["settings"]["budget"] = serde_json::to_value(req.budget).unwrap();
            d["settings"]["loss"] = serde_json::to_value(req.loss).unwrap();
            d["settings"]["seed"] = json!(req.seed);
        });
        let s = read(&d).unwrap().settings;
        assert_eq!((s.budget, s.loss, s.seed), (req.budget, req.loss, req.seed));
        for name in ["paper", "quick"] {
            read(&with(|d| d["settings"]["budget"] = json!(name))).unwrap();
        }
        for name in ["sdf", "l1", "pyramid", "image"] {
            read(&with(|d| d["settings"]["loss"] = json!(name))).unwrap();
        }
        let e = refused(
            &with(|d| d["settings"]["budget"] = json!("slow")),
            "settings.budget",
        );
        assert_eq!(e.to_string(), "settings.budget must be one of quick, paper");
        refused(&with(|d| d["settings"]["loss"] = json!(3)), "settings.loss");
        // Unknown fields are dropped, as they always were.
        let s = read(&with(|d| d["extra"] = json!(1))).unwrap();
        assert_eq!(s, read(&doc()).unwrap());
    }
}
