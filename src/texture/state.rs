//! The Texture tool's document (what the page keeps, autosaves, saves in a
//! project file and shares), its schema version and its checks, field by
//! field (see [`crate::core::value`]). Field names are the page's:
//!
//! ```text
//! { source: null
//!         | {kind: "model", model: id, params: [number], seed}
//!         | {kind: "image", name: text, png: bytes},
//!   predicted: null | {model: id, scales: [12 × 1–9],
//!                      top: [≤ 3 × {model: id, probability: 0–1}],
//!                      close: bool},
//!   scales: [12 × number in 1–9],
//!   sameModel: bool,
//!   retrieved: null | {model: id, params: [number], seed, sample: int | null,
//!                      scales: [12 × 1–9] | null, cosine: number | null,
//!                      edited: bool} }
//! ```
//!
//! - `source` is the example: a model rendered from its parameters and seed
//!   (small: a link carries it), or an image the user dropped, kept as a
//!   grey PNG the page shrank to at most 256 pixels a side (at most
//!   [`MAX_SOURCE_PNG`] bytes).
//! - `predicted` is the core's analysis of the example (`texture-analyse`):
//!   the model and the twelve scale **estimates** (see
//!   [`super::scales`]: computational estimates, not human ratings), the
//!   most likely models with their probabilities (`top`, most likely
//!   first; missing in older documents) and whether any model is close
//!   (`close`, true when missing).
//! - `scales` are the twelve requested scales (the sliders), 1–9,
//!   fractions allowed, in [`super::index::SCALES`] order.
//! - `sameModel`: retrieve within the predicted model only.
//! - `retrieved` is the texture shown: the retrieved sample's model,
//!   parameters and seed (`texture-retrieve`), with the parameters as the
//!   user edited them (`edited`), the sample's scales and the cosine
//!   similarity to the request.
//!
//! Model ids and parameter counts are the models' own
//! ([`super::models::MODELS`]); parameters out of a model's range are
//! clamped and integers rounded, as `texture-render` does
//! ([`super::models::Model::check`]). Seeds are whole numbers up to
//! 2^53 − 1 (a page's number holds them exactly).
use super::index::SCALES;
use super::models::{self, Model};
use crate::core::error::Result;
use crate::core::value::{invalid, Value, MAX_SAFE_INTEGER};
use serde::Serialize;

/// Schema version of the Texture state (the page's `state.version`).
pub const STATE_VERSION: u32 = 1;
/// Largest dropped example kept in the document, bytes of PNG.
pub const MAX_SOURCE_PNG: usize = 256 * 1024;
/// Longest example file name, characters.
pub const MAX_NAME: usize = 200;
/// The range of a scale.
pub const SCALE_RANGE: (f64, f64) = (1.0, 9.0);

const PNG_MAGIC: &[u8] = b"\x89PNG\r\n\x1a\n";

/// The example the user gave.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Source {
    /// A model rendered from its parameters and seed.
    Model {
        model: String,
        params: Vec<f64>,
        seed: u64,
    },
    /// A dropped, pasted or chosen image, as a small grey PNG.
    Image {
        name: String,
        #[serde(with = "serde_bytes")]
        png: Vec<u8>,
    },
}

/// The core's analysis of the example.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Predicted {
    pub model: String,
    pub scales: [u8; 12],
    /// Left out when empty and `close` when true, so a document written
    /// before them opens and saves unchanged.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub top: Vec<Chance>,
    #[serde(skip_serializing_if = "is_true")]
    pub close: bool,
}

fn is_true(b: &bool) -> bool {
    *b
}

/// A model the analysis found likely, with its probability.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Chance {
    pub model: String,
    pub probability: f64,
}

/// The texture shown: a retrieved sample, its parameters perhaps edited.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Retrieved {
    pub model: String,
    pub params: Vec<f64>,
    pub seed: u64,
    pub sample: Option<u64>,
    pub scales: Option<[u8; 12]>,
    pub cosine: Option<f64>,
    pub edited: bool,
}

/// A checked Texture document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TextureState {
    pub source: Option<Source>,
    pub predicted: Option<Predicted>,
    pub scales: [f64; 12],
    #[serde(rename = "sameModel")]
    pub same_model: bool,
    pub retrieved: Option<Retrieved>,
}

fn object<'a>(v: &'a Value, field: &str, what: &str) -> Result<&'a Value> {
    if v.is_plain_object() {
        Ok(v)
    } else {
        Err(invalid(field, format!("must be {what}")))
    }
}

fn model_of(v: Option<&Value>, field: &str) -> Result<&'static Model> {
    let id = v
        .and_then(Value::as_text)
        .ok_or_else(|| invalid(field, "must be a texture model id"))?;
    models::MODELS.iter().find(|m| m.id == id).ok_or_else(|| {
        invalid(
            field,
            format!(
                "must be one of the texture models ({})",
                models::MODELS
                    .iter()
                    .map(|m| m.id)
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
        )
    })
}

/// A model's parameters: one finite number each, clamped to the ranges.
fn params_of(model: &Model, v: Option<&Value>, field: &str) -> Result<Vec<f64>> {
    let list = v.and_then(Value::as_list).ok_or_else(|| {
        invalid(
            field,
            format!(
                "must be the {} parameters of model '{}'",
                model.params.len(),
                model.id
            ),
        )
    })?;
    if list.len() != model.params.len() {
        return Err(invalid(
            field,
            format!(
                "must hold {} numbers ({}) for model '{}', not {}",
                model.params.len(),
                model
                    .params
                    .iter()
                    .map(|p| p.name)
                    .collect::<Vec<_>>()
                    .join(", "),
                model.id,
                list.len()
            ),
        ));
    }
    let mut values = Vec::with_capacity(list.len());
    for (i, (x, p)) in list.iter().zip(model.params).enumerate() {
        let x = x.finite().ok_or_else(|| {
            invalid(
                &format!("{field}.{i}"),
                format!("({}) must be a number from {} to {}", p.name, p.lo, p.hi),
            )
        })?;
        values.push(x);
    }
    // In range, integers whole: the render request's own rule.
    model.check(&values).map_err(|e| invalid(field, e.inner()))
}

fn seed_of(v: Option<&Value>, field: &str) -> Result<u64> {
    v.and_then(Value::whole)
        .filter(|s| (0.0..=MAX_SAFE_INTEGER).contains(s))
        .map(|s| s as u64)
        .ok_or_else(|| invalid(field, "must be a whole number from 0 to 2^53 − 1"))
}

fn likert(v: Option<&Value>, field: &str) -> Result<[u8; 12]> {
    let list = v
        .and_then(Value::as_list)
        .filter(|l| l.len() == 12)
        .ok_or_else(|| {
            invalid(
                field,
                "must be the 12 scales, each a whole number from 1 to 9",
            )
        })?;
    let mut out = [0u8; 12];
    for (i, (o, x)) in out.iter_mut().zip(list).enumerate() {
        *o = x
            .whole()
            .filter(|x| (1.0..=9.0).contains(x))
            .ok_or_else(|| {
                invalid(
                    &format!("{field}.{i}"),
                    format!("({}) must be a whole number from 1 to 9", SCALES[i]),
                )
            })? as u8;
    }
    Ok(out)
}

fn requested(v: Option<&Value>) -> Result<[f64; 12]> {
    let list = v
        .and_then(Value::as_list)
        .filter(|l| l.len() == 12)
        .ok_or_else(|| {
            invalid(
                "scales",
                "must be the 12 requested scales, numbers from 1 to 9",
            )
        })?;
    let mut out = [0.0; 12];
    for (i, (o, x)) in out.iter_mut().zip(list).enumerate() {
        *o = x
            .finite()
            .filter(|x| (SCALE_RANGE.0..=SCALE_RANGE.1).contains(x))
            .ok_or_else(|| {
                invalid(
                    &format!("scales.{i}"),
                    format!("({}) must be a number from 1 to 9", SCALES[i]),
                )
            })?;
    }
    Ok(out)
}

fn source(v: &Value) -> Result<Source> {
    let s = object(
        v,
        "source",
        "null or an example {kind: \"model\" | \"image\", ...}",
    )?;
    match s.get("kind").and_then(Value::as_text) {
        Some("model") => {
            let model = model_of(s.get("model"), "source.model")?;
            Ok(Source::Model {
                model: model.id.to_string(),
                params: params_of(model, s.get("params"), "source.params")?,
                seed: seed_of(s.get("seed"), "source.seed")?,
            })
        }
        Some("image") => {
            let name = s
                .get("name")
                .and_then(Value::as_text)
                .filter(|n| n.chars().count() <= MAX_NAME)
                .ok_or_else(|| {
                    invalid(
                        "source.name",
                        format!("must be a file name of at most {MAX_NAME} characters"),
                    )
                })?;
            let png = match s.get("png") {
                Some(Value::Bytes(b)) if b.len() > MAX_SOURCE_PNG => {
                    return Err(invalid(
                        "source.png",
                        format!(
                            "is {} bytes; a kept example is at most {MAX_SOURCE_PNG} bytes of PNG",
                            b.len()
                        ),
                    ))
                }
                Some(Value::Bytes(b)) if b.starts_with(PNG_MAGIC) => b.clone(),
                _ => return Err(invalid("source.png", "must be the bytes of a PNG image")),
            };
            Ok(Source::Image {
                name: name.to_string(),
                png,
            })
        }
        _ => Err(invalid("source.kind", "must be model or image")),
    }
}

fn predicted(v: &Value) -> Result<Predicted> {
    let p = object(v, "predicted", "null or {model, scales, top, close}")?;
    let top = match p.get("top") {
        None | Some(Value::Null) => Vec::new(),
        Some(t) => {
            let list = t
                .as_list()
                .filter(|l| l.len() <= crate::texture::api::TOP_MODELS)
                .ok_or_else(|| {
                    invalid(
                        "predicted.top",
                        format!(
                            "must be a list of at most {} models",
                            crate::texture::api::TOP_MODELS
                        ),
                    )
                })?;
            list.iter()
                .enumerate()
                .map(|(i, c)| {
                    let field = format!("predicted.top.{i}");
                    let c = object(c, &field, "{model, probability}")?;
                    Ok(Chance {
                        model: model_of(c.get("model"), &format!("{field}.model"))?
                            .id
                            .to_string(),
                        probability: c
                            .get("probability")
                            .and_then(Value::finite)
                            .filter(|p| (0.0..=1.0).contains(p))
                            .ok_or_else(|| {
                                invalid(
                                    &format!("{field}.probability"),
                                    "must be a number from 0 to 1",
                                )
                            })?,
                    })
                })
                .collect::<Result<Vec<_>>>()?
        }
    };
    let close = match p.get("close") {
        None | Some(Value::Null) => true,
        Some(Value::Bool(b)) => *b,
        Some(_) => return Err(invalid("predicted.close", "must be true or false")),
    };
    Ok(Predicted {
        model: model_of(p.get("model"), "predicted.model")?.id.to_string(),
        scales: likert(p.get("scales"), "predicted.scales")?,
        top,
        close,
    })
}

fn retrieved(v: &Value) -> Result<Retrieved> {
    let r = object(
        v,
        "retrieved",
        "null or {model, params, seed, sample, scales, cosine, edited}",
    )?;
    let model = model_of(r.get("model"), "retrieved.model")?;
    let sample = match r.get("sample") {
        None | Some(Value::Null) => None,
        s => Some(
            s.and_then(Value::whole)
                .filter(|s| (0.0..=MAX_SAFE_INTEGER).contains(s))
                .ok_or_else(|| invalid("retrieved.sample", "must be null or a sample number"))?
                as u64,
        ),
    };
    let scales = match r.get("scales") {
        None | Some(Value::Null) => None,
        s => Some(likert(s, "retrieved.scales")?),
    };
    let cosine = match r.get("cosine") {
        None | Some(Value::Null) => None,
        c => Some(
            c.and_then(Value::finite)
                .filter(|c| (-1.0..=1.0).contains(c))
                .ok_or_else(|| {
                    invalid("retrieved.cosine", "must be null or a number from -1 to 1")
                })?,
        ),
    };
    let edited = match r.get("edited") {
        None | Some(Value::Null) => false,
        Some(Value::Bool(b)) => *b,
        Some(_) => return Err(invalid("retrieved.edited", "must be true or false")),
    };
    Ok(Retrieved {
        model: model.id.to_string(),
        params: params_of(model, r.get("params"), "retrieved.params")?,
        seed: seed_of(r.get("seed"), "retrieved.seed")?,
        sample,
        scales,
        cosine,
        edited,
    })
}

fn optional<T>(v: Option<&Value>, f: impl FnOnce(&Value) -> Result<T>) -> Result<Option<T>> {
    match v {
        None | Some(Value::Null) => Ok(None),
        Some(v) => f(v).map(Some),
    }
}

/// Check a Texture document field by field; the error names the field at fault.
pub fn check(raw: &Value) -> Result<TextureState> {
    if !raw.is_plain_object() {
        return Err(invalid("state", "is not a Texture document"));
    }
    let same_model = match raw.get("sameModel") {
        None | Some(Value::Null) => false,
        Some(Value::Bool(b)) => *b,
        Some(_) => return Err(invalid("sameModel", "must be true or false")),
    };
    Ok(TextureState {
        source: optional(raw.get("source"), source)?,
        predicted: optional(raw.get("predicted"), predicted)?,
        scales: requested(raw.get("scales"))?,
        same_model,
        retrieved: optional(raw.get("retrieved"), retrieved)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::texture::api::{render, TextureRenderRequest, TextureRetrieveRequest};
    use serde_json::{json, Value as Json};

    fn value(j: &Json) -> Value {
        Value::read(j, false).unwrap()
    }

    fn png() -> Vec<u8> {
        let img = render(&TextureRenderRequest {
            model: "perlin".into(),
            size: 16,
            ..Default::default()
        })
        .unwrap();
        let rgba: Vec<u8> = img.gray.iter().flat_map(|&g| [g, g, g, 255]).collect();
        crate::raster::encode_png(&crate::raster::Rgba8Image {
            width: 16,
            height: 16,
            data: rgba,
        })
        .unwrap()
    }

    fn doc() -> Json {
        json!({
            "source": {"kind": "model", "model": "perlin", "params": models::find("perlin").unwrap().defaults(), "seed": 7},
            "predicted": {"model": "perlin", "scales": [5, 5, 4, 3, 6, 7, 2, 5, 5, 4, 6, 8],
                          "top": [{"model": "perlin", "probability": 0.6}, {"model": "folding-perlin", "probability": 0.25}],
                          "close": false},
            "scales": [5, 5, 4, 3, 6, 7, 2, 5, 5, 9, 6, 8.5],
            "sameModel": true,
            "retrieved": {"model": "cellular", "params": models::find("cellular").unwrap().defaults(),
                          "seed": 9_007_199_254_740_991u64, "sample": 12, "scales": [5, 5, 4, 3, 6, 7, 2, 5, 5, 8, 6, 8],
                          "cosine": 0.97, "edited": false},
        })
    }

    /// The error's field for `doc()` with `path` (slash separated) set to `v`.
    fn field_of(path: &str, v: Json) -> String {
        let mut d = doc();
        *d.pointer_mut(path).unwrap() = v;
        let e = check(&value(&d)).unwrap_err();
        assert!(
            e.to_string().starts_with(e.field().unwrap_or("?")),
            "{e} names its field first"
        );
        e.field().unwrap().to_string()
    }

    #[test]
    fn the_analysis_keeps_its_likely_models_and_closeness() {
        let p = check(&value(&doc())).unwrap().predicted.unwrap();
        assert_eq!(p.top.len(), 2);
        assert_eq!(
            (p.top[1].model.as_str(), p.top[1].probability),
            ("folding-perlin", 0.25)
        );
        assert!(!p.close);
        // Older documents have neither: no list, and close.
        let mut old = doc();
        old["predicted"] = json!({"model": "perlin", "scales": vec![5; 12]});
        let p = check(&value(&old)).unwrap().predicted.unwrap();
        assert!(p.top.is_empty() && p.close);
        assert_eq!(
            field_of("/predicted/top/1/probability", json!(1.5)),
            "predicted.top.1.probability"
        );
        assert_eq!(
            field_of("/predicted/top/0/model", json!("nope")),
            "predicted.top.0.model"
        );
        assert_eq!(field_of("/predicted/close", json!(1)), "predicted.close");
        let mut long = doc();
        long["predicted"]["top"] =
            Json::Array(vec![json!({"model": "perlin", "probability": 0.1}); 4]);
        assert_eq!(
            check(&value(&long)).unwrap_err().field(),
            Some("predicted.top")
        );
    }

    #[test]
    fn a_page_document_is_accepted_and_kept() {
        let s = check(&value(&doc())).unwrap();
        assert!(s.same_model);
        assert_eq!(s.scales[11], 8.5);
        assert_eq!(s.predicted.as_ref().unwrap().scales[11], 8);
        let r = s.retrieved.as_ref().unwrap();
        assert_eq!(
            (r.model.as_str(), r.seed, r.sample),
            ("cellular", 9_007_199_254_740_991, Some(12))
        );
        // Checking the normalised state again changes nothing.
        let again = check(&value(&serde_json::to_value(&s).unwrap())).unwrap();
        assert_eq!(again, s);
        // A fresh document: nothing but the scales.
        let s = check(&value(&json!({"scales": vec![5; 12]}))).unwrap();
        assert_eq!(
            (s.source, s.predicted, s.retrieved, s.same_model),
            (None, None, None, false)
        );
        // A dropped image, kept as a small PNG.
        let mut d = doc();
        d["source"] = json!({"kind": "image", "name": "bark.jpg", "png": null});
        let mut v = value(&d);
        if let Value::Object(kv) = &mut v {
            let src = &mut kv.iter_mut().find(|(k, _)| k == "source").unwrap().1;
            if let Value::Object(s) = src {
                s.iter_mut().find(|(k, _)| k == "png").unwrap().1 = Value::Bytes(png());
            }
        }
        let s = check(&v).unwrap();
        assert!(
            matches!(s.source, Some(Source::Image { ref name, ref png }) if name == "bark.jpg" && png.starts_with(PNG_MAGIC))
        );
    }

    #[test]
    fn parameters_are_the_models_own() {
        // Out of range: clamped, as the render request does; integers rounded.
        let cellular = models::find("cellular").unwrap();
        let mut d = doc();
        let mut p = cellular.defaults();
        p[0] = 1e9;
        d["retrieved"]["params"] = json!(p);
        let s = check(&value(&d)).unwrap();
        assert_eq!(s.retrieved.unwrap().params[0], cellular.params[0].hi);
        // The wrong count names the list.
        assert_eq!(
            field_of("/retrieved/params", json!([1])),
            "retrieved.params"
        );
        assert_eq!(field_of("/source/params", json!([])), "source.params");
        assert_eq!(field_of("/source/params/0", json!("x")), "source.params.0");
    }

    #[test]
    fn every_rule_names_its_field() {
        assert_eq!(field_of("/source", json!(3)), "source");
        assert_eq!(field_of("/source/kind", json!("video")), "source.kind");
        assert_eq!(field_of("/source/model", json!("nope")), "source.model");
        assert_eq!(field_of("/source/seed", json!(-1)), "source.seed");
        assert_eq!(field_of("/source/seed", json!(1.5)), "source.seed");
        assert_eq!(
            field_of("/source/seed", json!(2f64.powi(60))),
            "source.seed"
        );
        assert_eq!(field_of("/predicted/model", json!(1)), "predicted.model");
        assert_eq!(
            field_of("/predicted/scales", json!(vec![5; 11])),
            "predicted.scales"
        );
        assert_eq!(
            field_of("/predicted/scales/3", json!(0)),
            "predicted.scales.3"
        );
        assert_eq!(
            field_of("/predicted/scales/3", json!(4.5)),
            "predicted.scales.3"
        );
        assert_eq!(field_of("/scales", json!(null)), "scales");
        assert_eq!(field_of("/scales/9", json!(9.5)), "scales.9");
        assert_eq!(field_of("/scales/0", json!(f64::NAN)), "scales.0");
        assert_eq!(field_of("/sameModel", json!("yes")), "sameModel");
        assert_eq!(field_of("/retrieved", json!([])), "retrieved");
        assert_eq!(field_of("/retrieved/sample", json!(-2)), "retrieved.sample");
        assert_eq!(field_of("/retrieved/cosine", json!(2)), "retrieved.cosine");
        assert_eq!(field_of("/retrieved/edited", json!(1)), "retrieved.edited");
        assert_eq!(
            field_of("/retrieved/scales/0", json!(10)),
            "retrieved.scales.0"
        );
        let mut d = doc();
        d["source"] = json!({"kind": "image", "name": "a.png", "png": [1, 2]});
        assert_eq!(check(&value(&d)).unwrap_err().field(), Some("source.png"));
        let mut v = value(
            &json!({"scales": vec![5; 12], "source": {"kind": "image", "name": "a.png", "png": null}}),
        );
        if let Value::Object(kv) = &mut v {
            if let Value::Object(s) = &mut kv[1].1 {
                let mut big = PNG_MAGIC.to_vec();
                big.resize(MAX_SOURCE_PNG + 1, 0);
                s[2].1 = Value::Bytes(big);
            }
        }
        let e = check(&v).unwrap_err();
        assert_eq!(e.field(), Some("source.png"));
        assert!(e.to_string().contains("at most"), "{e}");
        assert_eq!(
            check(&value(&json!([1]))).unwrap_err().field(),
            Some("state")
        );
    }

    #[test]
    fn a_checked_document_makes_requests_the_core_accepts() {
        let s = check(&value(&doc())).unwrap();
        let Some(Source::Model {
            model,
            params,
            seed,
        }) = &s.source
        else {
            panic!("a model source")
        };
        assert!(render(&TextureRenderRequest {
            model: model.clone(),
            params: params.clone(),
            seed: *seed,
            size: 16,
        })
        .is_ok());
        let r = s.retrieved.as_ref().unwrap();
        assert!(render(&TextureRenderRequest {
            model: r.model.clone(),
            params: r.params.clone(),
            seed: r.seed,
            size: 16,
        })
        .is_ok());
        // The requested scales are a retrieve request's.
        let req: TextureRetrieveRequest = serde_json::from_value(json!({
            "index": "x", "scales": s.scales, "model": s.predicted.as_ref().unwrap().model, "size": 0,
        }))
        .unwrap();
        assert_eq!(req.scales[11], 8.5);
    }
}
