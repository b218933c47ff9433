//! The Texture tool's document (what the page keeps, autosaves, saves in a
//! project file and shares), its schema version and its checks: a serde
//! type read from the page's [`Value`] ([`read_document`]) and its
//! [`Check`]. Field names are the page's (unknown ones are dropped, as
//! they always were):
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
//!   first, at most the analysis' [`TOP_MODELS`]; missing in older
//!   documents) and whether any model is close (`close`, true when
//!   missing).
//! - `scales` are the twelve requested scales (the sliders), 1–9
//!   ([`SCALE_RANGE`], the `texture-retrieve` request's), fractions
//!   allowed, in [`super::index::SCALES`] order.
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
use super::api::TOP_MODELS;
use super::index::SCALES;
use super::models::{self, Model};
pub use super::scales::SCALE_RANGE;
use crate::core::check::{exactly, exactly_or_null, null_as_default, read_document, Check, Path};
use crate::core::error::Result;
use crate::core::value::{Value, MAX_SAFE_INTEGER};
use serde::{Deserialize, Deserializer, Serialize};

/// Schema version of the Texture state (the page's `state.version`).
pub const STATE_VERSION: u32 = 1;
/// Largest dropped example kept in the document, bytes of PNG.
pub const MAX_SOURCE_PNG: usize = 256 * 1024;
/// Longest example file name, characters.
pub const MAX_NAME: usize = 200;
/// The range of an analysed or retrieved sample's scale: the whole
/// numbers of [`SCALE_RANGE`] (the ratings' Likert scale).
pub const LIKERT: (u8, u8) = (SCALE_RANGE.0 as u8, SCALE_RANGE.1 as u8);

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

/// A source as the page writes it: `kind`, then that kind's fields (read
/// flat, so an error names its field: `source.seed`).
#[derive(Deserialize)]
struct SourceFields {
    kind: SourceKind,
    #[serde(default)]
    model: Option<String>,
    #[serde(default)]
    params: Option<Vec<f64>>,
    #[serde(default)]
    seed: Option<u64>,
    #[serde(default)]
    name: Option<String>,
    #[serde(default, with = "serde_bytes")]
    png: Option<Vec<u8>>,
}

#[derive(Deserialize)]
#[serde(rename_all = "lowercase")]
enum SourceKind {
    Model,
    Image,
}

impl<'de> Deserialize<'de> for Source {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        use serde::de::Error;
        let f = SourceFields::deserialize(d)?;
        Ok(match f.kind {
            SourceKind::Model => Source::Model {
                model: f.model.ok_or_else(|| D::Error::missing_field("model"))?,
                params: f.params.ok_or_else(|| D::Error::missing_field("params"))?,
                seed: f.seed.ok_or_else(|| D::Error::missing_field("seed"))?,
            },
            SourceKind::Image => Source::Image {
                name: f.name.ok_or_else(|| D::Error::missing_field("name"))?,
                png: f.png.ok_or_else(|| D::Error::missing_field("png"))?,
            },
        })
    }
}

/// The core's analysis of the example.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Predicted {
    pub model: String,
    #[serde(deserialize_with = "exactly")]
    pub scales: [u8; 12],
    /// Left out when empty and `close` when true, so a document written
    /// before them opens and saves unchanged.
    #[serde(
        default,
        skip_serializing_if = "Vec::is_empty",
        deserialize_with = "null_as_default"
    )]
    pub top: Vec<Chance>,
    #[serde(
        default = "yes",
        skip_serializing_if = "is_true",
        deserialize_with = "null_as_true"
    )]
    pub close: bool,
}

fn is_true(b: &bool) -> bool {
    *b
}

fn yes() -> bool {
    true
}

/// `null` (or missing, with `default = "yes"`) is true.
fn null_as_true<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<bool, D::Error> {
    Ok(Option::<bool>::deserialize(d)?.unwrap_or(true))
}

/// A model the analysis found likely, with its probability.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Chance {
    pub model: String,
    pub probability: f64,
}

/// The texture shown: a retrieved sample, its parameters perhaps edited.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Retrieved {
    pub model: String,
    pub params: Vec<f64>,
    pub seed: u64,
    #[serde(default)]
    pub sample: Option<u64>,
    #[serde(default, deserialize_with = "exactly_or_null")]
    pub scales: Option<[u8; 12]>,
    #[serde(default)]
    pub cosine: Option<f64>,
    #[serde(default, deserialize_with = "null_as_default")]
    pub edited: bool,
}

/// A Texture document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TextureState {
    #[serde(default)]
    pub source: Option<Source>,
    #[serde(default)]
    pub predicted: Option<Predicted>,
    #[serde(deserialize_with = "exactly")]
    pub scales: [f64; 12],
    #[serde(rename = "sameModel", default, deserialize_with = "null_as_default")]
    pub same_model: bool,
    #[serde(default)]
    pub retrieved: Option<Retrieved>,
}

/// The model of id `id`.
fn model_of(at: &Path, id: &str) -> Result<&'static Model> {
    models::MODELS.iter().find(|m| m.id == id).ok_or_else(|| {
        at.invalid(format!(
            "must be one of the texture models ({})",
            models::MODELS
                .iter()
                .map(|m| m.id)
                .collect::<Vec<_>>()
                .join(", ")
        ))
    })
}

/// A model's parameters: one finite number each (out of range is clamped
/// and integers rounded, as `texture-render` does: see [`normalised`]).
fn check_params(at: &Path, model: &Model, params: &[f64]) -> Result<()> {
    if params.len() != model.params.len() {
        return Err(at.invalid(format!(
            "must hold {} numbers ({}) for model '{}', not {}",
            model.params.len(),
            model
                .params
                .iter()
                .map(|p| p.name)
                .collect::<Vec<_>>()
                .join(", "),
            model.id,
            params.len()
        )));
    }
    for (i, (x, p)) in params.iter().zip(model.params).enumerate() {
        if !x.is_finite() {
            return Err(at.index(i).invalid(format!(
                "({}) must be a number from {} to {}",
                p.name, p.lo, p.hi
            )));
        }
    }
    Ok(())
}

/// Seeds and sample numbers: what a page's number holds exactly.
fn check_seed(at: &Path, seed: u64) -> Result<()> {
    at.whole_in(seed, (0, MAX_SAFE_INTEGER as u64))
}

/// Twelve analysed (or retrieved) scales, each [`LIKERT`].
fn check_likert(at: &Path, scales: &[u8; 12]) -> Result<()> {
    let (lo, hi) = LIKERT;
    for (i, s) in scales.iter().enumerate() {
        if !(lo..=hi).contains(s) {
            return Err(at.index(i).invalid(format!(
                "({}) must be a whole number from {lo} to {hi}",
                SCALES[i]
            )));
        }
    }
    Ok(())
}

impl Check for Source {
    fn check(&self, at: &Path) -> Result<()> {
        match self {
            Source::Model {
                model,
                params,
                seed,
            } => {
                let m = model_of(&at.key("model"), model)?;
                check_params(&at.key("params"), m, params)?;
                check_seed(&at.key("seed"), *seed)
            }
            Source::Image { name, png } => {
                if name.chars().count() > MAX_NAME {
                    return Err(at.key("name").invalid(format!(
                        "must be a file name of at most {MAX_NAME} characters"
                    )));
                }
                if png.len() > MAX_SOURCE_PNG {
                    return Err(at.key("png").invalid(format!(
                        "is {} bytes; a kept example is at most {MAX_SOURCE_PNG} bytes of PNG",
                        png.len()
                    )));
                }
                if !png.starts_with(PNG_MAGIC) {
                    return Err(at.key("png").invalid("must be the bytes of a PNG image"));
                }
                Ok(())
            }
        }
    }
}

impl Check for Predicted {
    fn check(&self, at: &Path) -> Result<()> {
        model_of(&at.key("model"), &self.model)?;
        check_likert(&at.key("scales"), &self.scales)?;
        if self.top.len() > TOP_MODELS {
            return Err(at
                .key("top")
                .invalid(format!("must be a list of at most {TOP_MODELS} models")));
        }
        self.top.check(&at.key("top"))
    }
}

impl Check for Chance {
    fn check(&self, at: &Path) -> Result<()> {
        model_of(&at.key("model"), &self.model)?;
        at.key("probability")
            .number_in(self.probability, (0.0, 1.0))
    }
}

impl Check for Retrieved {
    fn check(&self, at: &Path) -> Result<()> {
        let m = model_of(&at.key("model"), &self.model)?;
        check_params(&at.key("params"), m, &self.params)?;
        check_seed(&at.key("seed"), self.seed)?;
        if let Some(s) = self.sample {
            check_seed(&at.key("sample"), s)?;
        }
        if let Some(s) = &self.scales {
            check_likert(&at.key("scales"), s)?;
        }
        if let Some(c) = self.cosine {
            at.key("cosine").number_in(c, (-1.0, 1.0))?;
        }
        Ok(())
    }
}

impl Check for TextureState {
    fn check(&self, at: &Path) -> Result<()> {
        self.source.check(&at.key("source"))?;
        self.predicted.check(&at.key("predicted"))?;
        let (lo, hi) = SCALE_RANGE;
        for (i, s) in self.scales.iter().enumerate() {
            if !(s.is_finite() && (lo..=hi).contains(s)) {
                return Err(at.key("scales").index(i).invalid(format!(
                    "({}) must be a number from {lo} to {hi}",
                    SCALES[i]
                )));
            }
        }
        self.retrieved.check(&at.key("retrieved"))
    }
}

/// A checked model's parameters as `texture-render` uses them: clamped to
/// their ranges, integers rounded ([`Model::check`]).
fn normalised(model: &str, params: &mut Vec<f64>) -> Result<()> {
    let m = models::lookup(model)?;
    *params = m.check(params)?;
    Ok(())
}

/// Read and check a Texture document; the error names the field at fault.
pub fn check(raw: &Value) -> Result<TextureState> {
    let mut doc: TextureState = read_document(raw, "Texture")?;
    if let Some(Source::Model { model, params, .. }) = &mut doc.source {
        normalised(model, params)?;
    }
    if let Some(r) = &mut doc.retrieved {
        normalised(&r.model, &mut r.params)?;
    }
    Ok(doc)
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

    #[test]
    fn every_range_is_inside_or_out_by_one() {
        use crate::texture::index::check_requested;
        let (lo, hi) = SCALE_RANGE;
        // The requested scales: the document's and `texture-retrieve`'s.
        for (inside, outside) in [(lo, lo - 1e-6), (hi, hi + 1e-6)] {
            let mut d = doc();
            d["scales"][4] = json!(inside);
            check(&value(&d)).unwrap_or_else(|e| panic!("scales {inside}: {e}"));
            let mut req = [5.0f32; 12];
            req[4] = inside as f32;
            check_requested(&req).unwrap();
            assert_eq!(field_of("/scales/4", json!(outside)), "scales.4");
            req[4] = outside as f32;
            assert_eq!(check_requested(&req).unwrap_err().field(), Some("scales"));
        }
        let p = |path: &str| path.trim_start_matches('/').replace('/', ".");
        let safe = MAX_SAFE_INTEGER as u64;
        let chances = |n: usize| json!(vec![json!({"model": "perlin", "probability": 0.1}); n]);
        let cases: Vec<(&str, Json, Json)> = vec![
            ("/predicted/scales/0", json!(LIKERT.0), json!(LIKERT.0 - 1)),
            ("/predicted/scales/11", json!(LIKERT.1), json!(LIKERT.1 + 1)),
            ("/retrieved/scales/3", json!(LIKERT.1), json!(LIKERT.1 + 1)),
            (
                "/predicted/top/0/probability",
                json!(1.0),
                json!(1.0 + 1e-9),
            ),
            ("/predicted/top/1/probability", json!(0.0), json!(-1e-9)),
            (
                "/predicted/top",
                chances(TOP_MODELS),
                chances(TOP_MODELS + 1),
            ),
            ("/retrieved/cosine", json!(-1.0), json!(-1.0 - 1e-9)),
            ("/retrieved/cosine", json!(1.0), json!(1.0 + 1e-9)),
            ("/source/seed", json!(safe), json!(safe + 1)),
            ("/retrieved/seed", json!(0), json!(-1)),
            ("/retrieved/sample", json!(safe), json!(safe + 1)),
        ];
        for (path, inside, outside) in cases {
            let mut d = doc();
            *d.pointer_mut(path).unwrap() = inside.clone();
            check(&value(&d)).unwrap_or_else(|e| panic!("{path} = {inside}: {e}"));
            assert_eq!(
                field_of(path, outside.clone()),
                p(path),
                "{path} = {outside}"
            );
        }
        // A dropped example's name and PNG.
        let image = |name: usize, png: usize| {
            let mut v = value(&json!({"scales": vec![5; 12],
                "source": {"kind": "image", "name": "n".repeat(name), "png": null}}));
            if let Value::Object(kv) = &mut v {
                if let Value::Object(s) = &mut kv[1].1 {
                    let mut b = PNG_MAGIC.to_vec();
                    b.resize(png, 0);
                    s[2].1 = Value::Bytes(b);
                }
            }
            check(&v)
        };
        image(MAX_NAME, MAX_SOURCE_PNG).unwrap();
        assert_eq!(
            image(MAX_NAME + 1, 100).unwrap_err().field(),
            Some("source.name")
        );
        assert_eq!(
            image(10, MAX_SOURCE_PNG + 1).unwrap_err().field(),
            Some("source.png")
        );
    }

    #[test]
    fn lists_hold_exactly_their_items() {
        // A list read as an array must not drop what is past its end.
        let mut d = doc();
        d["scales"] = json!(vec![5; 13]);
        let e = check(&value(&d)).unwrap_err();
        assert_eq!(e.field(), Some("scales"));
        assert_eq!(e.to_string(), "scales must be a list of 12 (got 13 items)");
        assert_eq!(
            field_of("/predicted/scales", json!(vec![5; 13])),
            "predicted.scales"
        );
        assert_eq!(
            field_of("/retrieved/scales", json!(vec![5; 11])),
            "retrieved.scales"
        );
        // null is no scales.
        let mut d = doc();
        d["retrieved"]["scales"] = Json::Null;
        assert_eq!(check(&value(&d)).unwrap().retrieved.unwrap().scales, None);
    }

    #[test]
    fn unknown_fields_are_dropped_and_missing_ones_named() {
        let plain = check(&value(&doc())).unwrap();
        let mut d = doc();
        d["extra"] = json!(1);
        d["source"]["name"] = json!("a model source has no name");
        d["predicted"]["extra"] = json!(2);
        d["predicted"]["top"][0]["extra"] = json!(3);
        d["retrieved"]["extra"] = json!(4);
        assert_eq!(check(&value(&d)).unwrap(), plain);
        for (part, key) in [
            ("source", "seed"),
            ("source", "kind"),
            ("retrieved", "params"),
            ("predicted", "model"),
        ] {
            let mut d = doc();
            d[part].as_object_mut().unwrap().remove(key);
            let e = check(&value(&d)).unwrap_err();
            assert_eq!(e.field(), Some(format!("{part}.{key}").as_str()), "{e}");
            assert_eq!(e.to_string(), format!("{part}.{key} is missing"));
        }
        let mut d = doc();
        d["source"] = json!({"kind": "image", "png": null});
        assert_eq!(check(&value(&d)).unwrap_err().field(), Some("source.name"));
        assert_eq!(field_of("/source/kind", json!("video")), "source.kind");
        let mut d = doc();
        d["source"]["kind"] = json!("video");
        assert_eq!(
            check(&value(&d)).unwrap_err().to_string(),
            "source.kind must be one of model, image"
        );
    }
}
