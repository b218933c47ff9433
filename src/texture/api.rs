//! The Texture tool's requests, shared by the CLI and the browser.
//!
//! - `texture-models`: the procedural models and their parameters.
//! - `texture-render`: one model's texture (height map shaded under the
//!   fixed light) as grey bytes.
//! - `texture-index`: parse an index file and keep it in this worker (the
//!   browser fetches the static asset once and sends it here); answers its
//!   id, the model names and the scale names.
//! - `texture-analyse`: an example image → predicted model and scales.
//! - `texture-retrieve`: requested scales (and optionally one model) → the
//!   sample [`Index::retrieve`] picks, its parameters, the cosine
//!   similarity, and its texture rendered live.
//!
//! Analysis and retrieval name the index they expect by id; a worker that
//! holds another (or none) answers an error on field `index`, and the page
//! sends `texture-index` and tries again.
use super::index::{Index, SCALES};
use super::models::{self, Model, MODELS};
use super::Gray;
use crate::core::error::{Error, Result};
use crate::core::job::{Job, OneShot};
use crate::raster::{decode_sent, Limits};
use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::rc::Rc;

/// Default side of rendered textures, pixels.
pub const DEFAULT_SIZE: u32 = 256;
/// Largest side a request may render.
pub const MAX_RENDER: u32 = 1024;

thread_local! {
    /// The index this worker holds, with its id.
    static LOADED: RefCell<Option<(String, Rc<Index>)>> = const { RefCell::new(None) };
}

/// An index's id: its checksum (the file's last 8 bytes) in hex.
pub fn index_id(bytes: &[u8]) -> String {
    let tail: [u8; 8] = bytes[bytes.len().saturating_sub(8)..]
        .try_into()
        .unwrap_or([0; 8]);
    format!("{:016x}", u64::from_le_bytes(tail))
}

/// A parameter as the page shows it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ParamInfo {
    pub name: &'static str,
    pub lo: f64,
    pub hi: f64,
    pub default: f64,
    pub integer: bool,
}

/// A model as the page shows it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelInfo {
    pub id: &'static str,
    pub name: &'static str,
    pub family: &'static str,
    pub params: Vec<ParamInfo>,
}

fn info(m: &Model) -> ModelInfo {
    ModelInfo {
        id: m.id,
        name: m.name,
        family: m.family.name(),
        params: m
            .params
            .iter()
            .map(|p| ParamInfo {
                name: p.name,
                lo: p.lo,
                hi: p.hi,
                default: p.default,
                integer: p.integer,
            })
            .collect(),
    }
}

/// Every model, in id order.
pub fn model_infos() -> Vec<ModelInfo> {
    MODELS.iter().map(info).collect()
}

/// `texture-render`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TextureRenderRequest {
    /// Model id (`perlin`, ...).
    pub model: String,
    /// One value per parameter in the model's order; empty: the defaults.
    pub params: Vec<f64>,
    pub seed: u64,
    pub size: u32,
}

impl Default for TextureRenderRequest {
    fn default() -> Self {
        TextureRenderRequest {
            model: String::new(),
            params: Vec::new(),
            seed: 1,
            size: DEFAULT_SIZE,
        }
    }
}

/// A rendered texture.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TextureImage {
    pub model: &'static str,
    pub params: Vec<f64>,
    pub seed: u64,
    pub size: u32,
    /// `size²` grey bytes, row-major.
    #[serde(with = "serde_bytes")]
    pub gray: Vec<u8>,
}

fn check_size(size: u32) -> Result<usize> {
    if !(models::MIN_SIZE as u32..=MAX_RENDER).contains(&size) {
        return Err(Error::input(format!(
            "size must be {} to {MAX_RENDER} pixels",
            models::MIN_SIZE
        ))
        .at("size"));
    }
    Ok(size as usize)
}

/// Renders a model's texture; the parameters are checked (and returned as
/// used).
pub fn render(req: &TextureRenderRequest) -> Result<TextureImage> {
    let model = models::lookup(&req.model).map_err(|e| e.at("model"))?;
    let size = check_size(req.size)?;
    let params = if req.params.is_empty() {
        model.defaults()
    } else {
        model.check(&req.params).map_err(|e| e.at("params"))?
    };
    let img = models::render(model, &params, req.seed, size)?;
    Ok(TextureImage {
        model: model.id,
        params,
        seed: req.seed,
        size: req.size,
        gray: img.to_bytes(),
    })
}

pub fn start_render(req: TextureRenderRequest) -> Result<impl Job<Output = TextureImage>> {
    models::lookup(&req.model).map_err(|e| e.at("model"))?;
    check_size(req.size)?;
    Ok(OneShot::new(move || render(&req)))
}

/// `texture-index`: the index file's bytes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TextureIndexRequest {
    #[serde(with = "serde_bytes")]
    pub bytes: Vec<u8>,
}

/// What a loaded index holds.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TextureIndexResponse {
    pub id: String,
    pub models: Vec<String>,
    pub scales: [&'static str; 12],
    pub samples: usize,
    pub bytes: usize,
}

/// Parses an index and checks that its models are this app's models.
pub fn parse_index(bytes: &[u8]) -> Result<Index> {
    let index = Index::from_bytes(bytes).map_err(|e| e.at("bytes"))?;
    let ours: Vec<&str> = MODELS.iter().map(|m| m.id).collect();
    if index
        .model_names
        .iter()
        .map(String::as_str)
        .ne(ours.iter().copied())
    {
        return Err(Error::input("the texture index was built for other models than this app's; rebuild it with `filigree build-index`").at("bytes"));
    }
    for s in &index.samples {
        MODELS[s.model as usize]
            .check(&s.params.iter().map(|&v| v as f64).collect::<Vec<_>>())
            .map_err(|e| e.at("bytes"))?;
    }
    Ok(index)
}

pub fn start_index(req: TextureIndexRequest) -> impl Job<Output = TextureIndexResponse> {
    OneShot::new(move || {
        let id = index_id(&req.bytes);
        let index = parse_index(&req.bytes)?;
        let out = TextureIndexResponse {
            id: id.clone(),
            models: index.model_names.clone(),
            scales: SCALES,
            samples: index.samples.len(),
            bytes: req.bytes.len(),
        };
        LOADED.with(|l| *l.borrow_mut() = Some((id, Rc::new(index))));
        Ok(out)
    })
}

fn loaded(id: &str) -> Result<Rc<Index>> {
    LOADED.with(|l| match &*l.borrow() {
        Some((have, index)) if have == id => Ok(index.clone()),
        _ => Err(Error::input(
            "this worker does not hold that texture index; send `texture-index` first",
        )
        .at("index")),
    })
}

/// `texture-analyse`: an encoded image (PNG, JPEG, ...).
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TextureAnalyseRequest {
    pub index: String,
    #[serde(with = "serde_bytes")]
    pub bytes: Vec<u8>,
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TextureAnalysis {
    /// The most likely model (`top[0]`), even when it is not close.
    pub model: &'static str,
    pub model_name: &'static str,
    pub scales: [u8; 12],
    /// The [`TOP_MODELS`] most likely models with their calibrated
    /// probabilities ([`crate::texture::index::Confidence`]).
    pub top: Vec<ModelChance>,
    /// False when the image is far from every model in the index ("no
    /// close model"): then `top` names the nearest, not a match.
    pub close: bool,
}

/// How many models an analysis lists.
pub const TOP_MODELS: usize = 3;

/// A model and the probability that it drew the example.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ModelChance {
    pub model: &'static str,
    pub model_name: &'static str,
    pub probability: f64,
}

/// An encoded image as grey levels (Rec. 709 luma over white for alpha).
pub fn decode_gray(bytes: &[u8]) -> Result<Gray> {
    let img = decode_sent(bytes, Limits::default()).map_err(|e| e.at("bytes"))?;
    let mut g = Gray::new(img.width as usize, img.height as usize);
    for (o, px) in g.data.iter_mut().zip(img.pixels()) {
        let a = px[3] as f32 / 255.0;
        let luma = (0.2126 * px[0] as f32 + 0.7152 * px[1] as f32 + 0.0722 * px[2] as f32) / 255.0;
        *o = luma * a + (1.0 - a);
    }
    Ok(g)
}

/// Predicted model and scales of an image with a given index.
pub fn analyse(index: &Index, img: &Gray) -> Result<TextureAnalysis> {
    let a = index.analyse(img)?;
    let m = &MODELS[a.model as usize];
    let top = a
        .reading
        .ranked
        .iter()
        .take(TOP_MODELS)
        .map(|&(k, probability)| ModelChance {
            model: MODELS[k as usize].id,
            model_name: MODELS[k as usize].name,
            probability,
        })
        .collect();
    Ok(TextureAnalysis {
        model: m.id,
        model_name: m.name,
        scales: a.scales,
        top,
        close: a.reading.close,
    })
}

pub fn start_analyse(req: TextureAnalyseRequest) -> Result<impl Job<Output = TextureAnalysis>> {
    let index = loaded(&req.index)?;
    Ok(OneShot::new(move || {
        analyse(&index, &decode_gray(&req.bytes)?)
    }))
}

/// `texture-retrieve`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TextureRetrieveRequest {
    pub index: String,
    /// The twelve requested scales, 1–9 (fractions allowed).
    pub scales: [f32; 12],
    /// Stay within this model (id); empty: any.
    pub model: String,
    /// Side of the rendered answer; 0 renders nothing.
    pub size: u32,
}

impl Default for TextureRetrieveRequest {
    fn default() -> Self {
        TextureRetrieveRequest {
            index: String::new(),
            scales: [5.0; 12],
            model: String::new(),
            size: DEFAULT_SIZE,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TextureRetrieval {
    pub sample: usize,
    pub model: &'static str,
    pub model_name: &'static str,
    pub params: Vec<f64>,
    pub seed: u64,
    /// The retrieved sample's scales.
    pub scales: [u8; 12],
    /// Cosine similarity of requested and retrieved scales.
    pub cosine: f64,
    /// The request's point in the perceptual space.
    pub point: [f32; 3],
    #[serde(skip_serializing_if = "Option::is_none")]
    pub image: Option<TextureImage>,
}

/// The sample [`Index::retrieve`] picks for the requested scales, rendered
/// at `size`.
pub fn retrieve(index: &Index, req: &TextureRetrieveRequest) -> Result<TextureRetrieval> {
    let within = if req.model.is_empty() {
        None
    } else {
        let m = models::lookup(&req.model).map_err(|e| e.at("model"))?;
        Some(MODELS.iter().position(|x| x.id == m.id).expect("looked up") as u16)
    };
    let r = index.retrieve(&req.scales, within)?;
    let s = &index.samples[r.sample];
    let m = &MODELS[s.model as usize];
    let params: Vec<f64> = s.params.iter().map(|&v| v as f64).collect();
    let image = if req.size == 0 {
        None
    } else {
        Some(render(&TextureRenderRequest {
            model: m.id.into(),
            params: params.clone(),
            seed: s.seed,
            size: req.size,
        })?)
    };
    Ok(TextureRetrieval {
        sample: r.sample,
        model: m.id,
        model_name: m.name,
        params,
        seed: s.seed,
        scales: s.scales,
        cosine: r.cosine,
        point: r.point,
        image,
    })
}

pub fn start_retrieve(req: TextureRetrieveRequest) -> Result<impl Job<Output = TextureRetrieval>> {
    if req.size != 0 {
        check_size(req.size)?;
    }
    let index = loaded(&req.index)?;
    Ok(OneShot::new(move || retrieve(&index, &req)))
}
