//! `filigree build-index` and `filigree texture --index … --image …`: the
//! Texture index from the command line (its benchmark is
//! `filigree-bench`'s `texture_bench.rs`).
//! The pipeline is `filigree::texture::build`; requests are the browser's
//! (`filigree::texture::api`).
use filigree::texture::api::{self, TextureRetrieveRequest};
use filigree::texture::build::{self, BuildConfig};
use filigree::texture::index::SCALES;
use filigree::texture::models::MODELS;
use filigree::texture::scales::parse_ratings;
use serde_json::json;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args)]
pub struct BuildArgs {
    /// Where to write the index (the app serves www/assets/texture-index.bin).
    #[arg(long)]
    out: PathBuf,
    /// Base textures per model (parameter grid points).
    #[arg(long, default_value_t = BuildConfig::default().dataset.per_model)]
    per_model: usize,
    /// Side of every dataset image, pixels.
    #[arg(long, default_value_t = BuildConfig::default().dataset.size)]
    size: usize,
    /// Skip the paper's augmentation (second light, four crops).
    #[arg(long)]
    no_augment: bool,
    /// Human ratings (CSV: id + the twelve scales) replacing the estimates.
    #[arg(long)]
    ratings: Option<PathBuf>,
}

fn read_ratings(path: Option<&Path>) -> Result<Vec<filigree::texture::scales::Rating>, String> {
    let Some(p) = path else { return Ok(Vec::new()) };
    let text = std::fs::read_to_string(p).map_err(|e| format!("{}: {e}", p.display()))?;
    parse_ratings(&text).map_err(|e| format!("{}: {e}", p.display()))
}

pub fn run_build(a: BuildArgs) -> Result<(), String> {
    super::out_path(&a.out, &["bin"])?;
    let cfg = BuildConfig::sized(a.per_model, a.size, !a.no_augment);
    let ratings = read_ratings(a.ratings.as_deref())?;
    let t = Instant::now();
    let (index, stats) = build::build_index(&cfg, &ratings).map_err(|e| e.to_string())?;
    let seconds = t.elapsed().as_secs_f64();
    let bytes = index.to_bytes();
    if let Some(dir) = a.out.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    }
    std::fs::write(&a.out, &bytes).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let out = json!({
        "out": a.out.display().to_string(), "bytes": bytes.len(), "id": api::index_id(&bytes),
        "images": stats.images, "bases": stats.bases, "rated": stats.rated,
        "feature_len": index.pcn.config.feature_len(), "seconds": seconds,
    });
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}

#[derive(clap::Args)]
pub struct QueryArgs {
    /// The index file (`filigree build-index`).
    #[arg(long)]
    index: Option<PathBuf>,
    /// An example texture (PNG, JPEG, ...), at least half the network's window on its short side
    /// (64 px with the shipped index; a smaller picture is refused, not enlarged into a blur).
    #[arg(long)]
    image: Option<PathBuf>,
    /// Change a predicted scale, `name=value` with value 1–9 (repeatable),
    /// e.g. `--set regularity=8`. Names: contrast, repetition, granularity,
    /// randomness, roughness, feature_density, directionality,
    /// structural_complexity, coarseness, regularity, local_orientation,
    /// uniformity.
    #[arg(long = "set", value_name = "NAME=VALUE")]
    set: Vec<String>,
    /// Retrieve only among the predicted model's samples.
    #[arg(long)]
    same_model: bool,
    /// Write the retrieved texture (grey PNG).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Side of the written texture, pixels.
    #[arg(long, default_value_t = api::DEFAULT_SIZE)]
    size: u32,
    /// Print the whole answer as JSON (default: a short summary).
    #[arg(long)]
    json: bool,
}

fn scale_index(name: &str) -> Option<usize> {
    let norm = |s: &str| s.replace([' ', '-'], "_").to_ascii_lowercase();
    SCALES.iter().position(|s| norm(s) == norm(name))
}

pub fn run_query(a: QueryArgs) -> Result<(), String> {
    let (Some(index_path), Some(image_path)) = (a.index.as_ref(), a.image.as_ref()) else {
        return Err("texture: give --index I and --image IMG, or a subcommand (render, models, sheet); see --help".into());
    };
    if let Some(out) = &a.out {
        super::out_path(out, &["png"])?;
        let (lo, hi) = (
            filigree::texture::models::MIN_SIZE,
            filigree::texture::models::MAX_SIZE,
        );
        if !(lo..=hi).contains(&(a.size as usize)) {
            return Err(format!(
                "--size: the retrieved texture written to {} must be {lo}..={hi} pixels (got {})",
                out.display(),
                a.size
            ));
        }
    }
    let bytes = std::fs::read(index_path).map_err(|e| format!("{}: {e}", index_path.display()))?;
    let index = api::parse_index(&bytes).map_err(|e| format!("{}: {e}", index_path.display()))?;
    let img_bytes =
        std::fs::read(image_path).map_err(|e| format!("{}: {e}", image_path.display()))?;
    let gray =
        api::decode_gray(&img_bytes).map_err(|e| format!("{}: {e}", image_path.display()))?;
    let analysis = api::analyse(&index, &gray).map_err(|e| e.to_string())?;
    let mut scales: [f32; 12] = analysis.scales.map(|v| v as f32);
    for s in &a.set {
        let (k, v) = s
            .split_once('=')
            .ok_or_else(|| format!("--set {s}: expected NAME=VALUE"))?;
        let i = scale_index(k.trim()).ok_or_else(|| {
            format!(
                "--set {s}: unknown scale '{k}' (known: {})",
                SCALES.join(", ")
            )
        })?;
        let v: f32 = v
            .trim()
            .parse()
            .map_err(|_| format!("--set {s}: '{v}' is not a number"))?;
        let (lo, hi) = filigree::texture::scales::SCALE_RANGE;
        if !(lo..=hi).contains(&(v as f64)) {
            return Err(format!("--set {s}: scales run from {lo} to {hi}"));
        }
        scales[i] = v;
    }
    let req = TextureRetrieveRequest {
        index: String::new(),
        scales,
        model: if a.same_model {
            analysis.model.to_string()
        } else {
            String::new()
        },
        size: if a.out.is_some() { a.size } else { 0 },
    };
    let got = api::retrieve(&index, &req).map_err(|e| e.to_string())?;
    if let (Some(out), Some(img)) = (&a.out, &got.image) {
        let png = image::GrayImage::from_raw(img.size, img.size, img.gray.clone())
            .ok_or("internal: image size")?;
        png.save(out)
            .map_err(|e| format!("{}: {e}", out.display()))?;
    }
    let named = |s: &[f32]| {
        SCALES
            .iter()
            .zip(s)
            .map(|(n, v)| (n.to_string(), json!(v)))
            .collect::<serde_json::Map<_, _>>()
    };
    let model = MODELS
        .iter()
        .find(|m| m.id == got.model)
        .ok_or("internal: model")?;
    let params: serde_json::Map<_, _> = model
        .params
        .iter()
        .zip(&got.params)
        .map(|(p, v)| (p.name.to_string(), json!(v)))
        .collect();
    let retrieved: Vec<f32> = got.scales.iter().map(|&v| v as f32).collect();
    let answer = json!({
        "predicted": {"model": analysis.model, "model_name": analysis.model_name, "scales": named(&analysis.scales.map(|v| v as f32))},
        "top": analysis.top.iter().map(|c| json!({"model": c.model, "model_name": c.model_name, "probability": c.probability})).collect::<Vec<_>>(),
        "close": analysis.close,
        "requested": named(&scales),
        "retrieved": {"model": got.model, "model_name": got.model_name, "params": params, "seed": got.seed, "scales": named(&retrieved), "sample": got.sample},
        "cosine": got.cosine,
    });
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&answer).map_err(|e| e.to_string())?
        );
    } else {
        if analysis.close {
            println!(
                "predicted model: {} ({})",
                analysis.model_name, analysis.model
            );
        } else {
            println!(
                "predicted model: no close model (the image is far from every model in the index)"
            );
        }
        println!(
            "{}: {}",
            if analysis.close {
                "most likely"
            } else {
                "nearest"
            },
            analysis
                .top
                .iter()
                .map(|c| format!("{} {:.0}%", c.model_name, 100.0 * c.probability))
                .collect::<Vec<_>>()
                .join(", ")
        );
        println!(
            "predicted scales: {}",
            SCALES
                .iter()
                .zip(analysis.scales)
                .map(|(n, v)| format!("{n} {v}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
        println!(
            "retrieved: {} with {}",
            got.model_name,
            serde_json::to_string(&params).unwrap_or_default()
        );
        println!("cosine(requested, retrieved scales) = {:.3}", got.cosine);
    }
    Ok(())
}
