//! `filigree texture`: inspect the procedural texture models (render one,
//! list them, or a contact sheet of all), and `filigree bench
//! texture-models`: per-model render and dataset times as JSON.
use clap::Subcommand;
use filigree::texture::models::{self, render_height, shade, Light, MODELS};
use filigree::texture::scales;
use filigree::texture::Gray;
use serde_json::json;
use std::path::{Path, PathBuf};

#[derive(Subcommand)]
pub enum Which {
    /// Render one model's shaded texture (or height map) to a grey PNG.
    Render(RenderArgs),
    /// List the models, their families and parameters (JSON; `dataset` is
    /// the part of a parameter's range the training dataset samples).
    Models,
    /// Raw perceptual-scale estimates (JSON) of a model's texture, or of
    /// every model at its defaults when no --model is given.
    Measure {
        #[arg(long)]
        model: Option<String>,
        #[arg(long = "param", value_name = "NAME=VALUE")]
        params: Vec<String>,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        #[arg(long, default_value_t = 128)]
        size: usize,
    },
    /// A contact sheet of every model at its defaults (5 columns) to a PNG.
    Sheet {
        #[arg(long, default_value_t = 128)]
        size: usize,
        #[arg(long, default_value_t = 1)]
        seed: u64,
        #[arg(long)]
        out: PathBuf,
    },
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Model id (see `filigree texture models`) or its paper name.
    #[arg(long)]
    model: String,
    /// A parameter, `name=value` (repeatable); others take their defaults.
    #[arg(long = "param", value_name = "NAME=VALUE")]
    params: Vec<String>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[arg(long, default_value_t = 256)]
    size: usize,
    /// Light azimuth and elevation in degrees (default 135,45).
    #[arg(long, value_name = "AZ,EL")]
    light: Option<String>,
    /// Write the height map instead of the shaded texture.
    #[arg(long)]
    height: bool,
    /// Output PNG.
    #[arg(long)]
    out: PathBuf,
}

/// Largest cell of `texture sheet` (23 models in a 5-column sheet: about
/// 2,600² pixels at this size).
const SHEET_MAX_CELL: usize = 512;

pub fn run(w: Which) -> Result<(), String> {
    match w {
        Which::Render(a) => render(a),
        Which::Models => {
            let list: Vec<_> = MODELS
                .iter()
                .enumerate()
                .map(|(i, m)| {
                    json!({
                        "index": i, "id": m.id, "name": m.name, "family": m.family.name(),
                        "params": m.params.iter().map(|p| json!({
                            "name": p.name, "lo": p.lo, "hi": p.hi, "default": p.default,
                            "integer": p.integer, "dataset": [p.dataset_lo, p.dataset_hi],
                        })).collect::<Vec<_>>(),
                    })
                })
                .collect();
            super::print_json(&list)?;
            Ok(())
        }
        Which::Measure {
            model,
            params,
            seed,
            size,
        } => {
            let chosen: Vec<(&'static models::Model, Vec<f64>)> = match model {
                Some(name) => {
                    let m = models::lookup(&name).map_err(|e| format!("--model: {e}"))?;
                    vec![(m, parse_params(m, &params)?)]
                }
                None => MODELS.iter().map(|m| (m, m.defaults())).collect(),
            };
            let mut out = Vec::new();
            for (m, p) in chosen {
                let g = models::render(m, &p, seed, size).map_err(|e| e.to_string())?;
                let raw = scales::measure(&g).map_err(|e| e.to_string())?;
                let named: serde_json::Map<String, serde_json::Value> = scales::SCALE_NAMES
                    .iter()
                    .zip(raw)
                    .map(|(n, v)| (n.to_string(), json!(v)))
                    .collect();
                out.push(json!({"model": m.id, "params": p, "raw": named}));
            }
            super::print_json(&out)?;
            Ok(())
        }
        Which::Sheet { size, seed, out } => {
            super::out_path(&out, &["png"])?;
            // Checked before the sheet is allocated (20,000 px cells asked for 40 GB).
            if !(models::MIN_SIZE..=SHEET_MAX_CELL).contains(&size) {
                return Err(format!(
                    "--size: a sheet cell is {}..={SHEET_MAX_CELL} pixels (got {size})",
                    models::MIN_SIZE
                ));
            }
            let cols = 5;
            let rows = MODELS.len().div_ceil(cols);
            let gap = 4;
            let mut sheet = Gray::new(cols * (size + gap), rows * (size + gap));
            sheet.data.iter_mut().for_each(|v| *v = 1.0);
            for (i, m) in MODELS.iter().enumerate() {
                let g = models::render(m, &m.defaults(), seed, size).map_err(|e| e.to_string())?;
                let (ox, oy) = ((i % cols) * (size + gap), (i / cols) * (size + gap));
                for y in 0..size {
                    for x in 0..size {
                        sheet.data[(oy + y) * sheet.width + ox + x] = g.at(x, y);
                    }
                }
            }
            write_png(&out, &sheet)
        }
    }
}

fn parse_light(s: &str) -> Result<Light, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--light: expected AZ,EL in degrees, got '{s}'"))?;
    match v[..] {
        [azimuth, elevation] if azimuth.is_finite() && (0.0..=90.0).contains(&elevation) => {
            Ok(Light { azimuth, elevation })
        }
        _ => Err(format!(
            "--light: expected AZ,EL with elevation in 0..=90 degrees, got '{s}'"
        )),
    }
}

fn parse_params(m: &models::Model, params: &[String]) -> Result<Vec<f64>, String> {
    let mut pairs = Vec::new();
    for p in params {
        let (k, v) = p
            .split_once('=')
            .ok_or_else(|| format!("--param: expected NAME=VALUE, got '{p}'"))?;
        let v: f64 = v
            .trim()
            .parse()
            .map_err(|_| format!("--param {k}: '{}' is not a number", super::short(v)))?;
        // Out of range was clamped without a word (frequency=1e308 drew 24).
        if let Some(spec) = m.params.iter().find(|s| s.name == k.trim()) {
            if !(v.is_finite() && (spec.lo..=spec.hi).contains(&v)) {
                return Err(format!(
                    "--param {}: {} is outside the model's range {}..={}",
                    k.trim(),
                    super::short(&format!("{v}")),
                    spec.lo,
                    spec.hi
                ));
            }
        }
        pairs.push((k.trim(), v));
    }
    m.with(&pairs).map_err(|e| format!("--param: {e}"))
}

fn render(a: RenderArgs) -> Result<(), String> {
    super::out_path(&a.out, &["png"])?;
    let m = models::lookup(&a.model).map_err(|e| format!("--model: {e}"))?;
    let params = parse_params(m, &a.params)?;
    let light = a
        .light
        .as_deref()
        .map(parse_light)
        .transpose()?
        .unwrap_or_default();
    let h = render_height(m, &params, a.seed, a.size).map_err(|e| match e.field() {
        Some("size") => format!("--size: {e}"),
        _ => format!("--param: {e}"),
    })?;
    let img = if a.height { h } else { shade(&h, light) };
    write_png(&a.out, &img)
}

fn write_png(path: &Path, g: &Gray) -> Result<(), String> {
    let file = std::fs::File::create(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut enc = png::Encoder::new(
        std::io::BufWriter::new(file),
        g.width as u32,
        g.height as u32,
    );
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    let mut w = enc
        .write_header()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    w.write_image_data(&g.to_bytes())
        .map_err(|e| format!("{}: {e}", path.display()))
}
