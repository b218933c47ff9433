//! `filigree fit` and `filigree render`: flags → the same request structs
//! the browser sends (`fit`, `render-pattern`, see `filigree::pattern::api`)
//! → the same core jobs. Defaults come from the requests, not from here.
use super::{drive, explain, print_request, put, request, Origins};
use filigree::core::job::Cancel;
use filigree::core::parallel::run_sharded_threads;
use filigree::pattern::api::{start_fit, start_render, FitRequest, RenderPatternRequest};
use filigree::pattern::generators::{generator, GENERATORS};
use serde_json::{json, Map, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args)]
#[command(
    after_help = "Defaults (the same request the browser's Fit button sends):
  --init periodic     the global stage for repeating designs: 1024 low-resolution
                      candidates compared by their spectra (period and angle, not
                      phase), then the phase swept around the 6 best, at full
                      resolution (--init genetic: the paper's GA)
  --budget quick      3 candidates x 120 Adam iterations (GA 64 x 8 generations
                      with --init genetic)
  --grid              an image target's longer side, 32..=128 px (a bigger image's
                      distance fields are computed at its resolution and sampled);
                      64 with --target-params
  --polish 100        image-space Adam iterations after an sdf/l1/pyramid fit
                      (0 after --loss image)
  --max-seconds 30    generations and iterations are scaled down when the fit's
                      estimated time (from the work of one evaluation) exceeds it
The canvas takes the target image's aspect, its shorter side 1 (a 300x240 target
is [0, 1.25] x [0, 1]; programs read WIDTH and HEIGHT); the grid is its longer
side, and --out and the SVG are the target's size: nothing is stretched.
The loss printed is the fit's own (--loss, sdf by default), named; with a polish
the image-space loss after it is printed too."
)]
pub struct FitArgs {
    /// Program file (.flg) or the name of a shipped generator (e.g. circles-grid).
    #[arg(long)]
    program: String,
    /// Target image (PNG, JPEG, ...). Colours are snapped to the program's palette.
    #[arg(long, required_unless_present = "target_params")]
    target: Option<PathBuf>,
    /// Instead of an image: draw the target from these parameters (JSON object or file).
    #[arg(long)]
    target_params: Option<String>,
    /// Values for the integer (structural) parameters: JSON object or file; others default.
    #[arg(long)]
    params: Option<String>,
    /// quick (default) | paper
    #[arg(long)]
    budget: Option<String>,
    /// sdf (default) | l1 | pyramid | image
    #[arg(long)]
    loss: Option<String>,
    /// periodic (default: spectra, then a phase sweep) | genetic (ga, the paper's) | random | nelder-mead (nm)
    #[arg(long)]
    init: Option<String>,
    /// Loss grid's longer side in pixels, 8..=256 (default: an image target's longer side, 32..=128;
    /// the budget's, 64 quick / 128 paper, for --target-params).
    #[arg(long)]
    grid: Option<usize>,
    /// Field units in the loss: pixels (default) | canvas.
    #[arg(long)]
    units: Option<String>,
    /// Seed of every random choice (default 1).
    #[arg(long)]
    seed: Option<u64>,
    /// Threads, one shard of the fit each, 1..=64 (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// RGB distance within which a target pixel matches a palette colour, 0..=442 (default 60).
    #[arg(long, allow_hyphen_values = true)]
    tolerance: Option<f64>,
    /// Adam iterations on the image-space loss after the fit (default 100, 0 with --loss image;
    /// 0 = off, the paper's method).
    #[arg(long)]
    polish: Option<usize>,
    /// Time bound in seconds, 0.1..=3600 (default 30): generations and iterations are scaled
    /// down when the estimated time exceeds it (estimated from the work, not the clock).
    #[arg(long)]
    max_seconds: Option<f64>,
    /// Print JSON.
    #[arg(long)]
    json: bool,
    /// Write the fitted pattern as SVG, sized like the target image (512 px without one).
    #[arg(long)]
    svg: Option<PathBuf>,
    /// Write the fitted pattern to this file, .png or .svg, sized like the target image
    /// (512 px without one; the longer side at most 2048).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Print the request (as the browser would send it) and exit.
    #[arg(long, hide = true)]
    print_request: bool,
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Program file (.flg) or the name of a shipped generator.
    #[arg(long)]
    program: String,
    /// Parameter values: JSON object {"name": value} or a file holding one; missing ones default.
    #[arg(long)]
    params: Option<String>,
    /// Output file; .png or .svg.
    #[arg(long)]
    out: PathBuf,
    /// Width in pixels, 1..=2048 (default 512).
    #[arg(long)]
    size: Option<usize>,
    /// Height in pixels, 1..=2048 (default: the width). The canvas takes the
    /// picture's aspect, its shorter side 1 (WIDTH and HEIGHT in the program).
    #[arg(long)]
    height: Option<usize>,
    /// Samples per pixel side for PNG anti-aliasing, 1..=4 (default 1 = exact palette colours).
    #[arg(long)]
    supersample: Option<usize>,
    /// Print the request (as the browser would send it) and exit.
    #[arg(long, hide = true)]
    print_request: bool,
}

/// Load a program's text from a file or by generator name; also its display name.
pub fn load_program(spec: &str) -> Result<(String, String), String> {
    let p = Path::new(spec);
    if p.exists() {
        let bytes = super::read_file(p)?;
        let text = String::from_utf8(bytes).map_err(|_| format!("{spec}: not UTF-8 text"))?;
        Ok((spec.to_string(), text))
    } else if let Some(g) = generator(spec) {
        Ok((g.name.to_string(), g.source.to_string()))
    } else {
        let names: Vec<&str> = GENERATORS.iter().map(|g| g.name).collect();
        Err(format!(
            "'{spec}' is neither a file nor a generator ({})",
            names.join(", ")
        ))
    }
}

/// Parameter values from a JSON object given inline or as a file.
pub fn param_map(spec: &str, flag: &str) -> Result<BTreeMap<String, f64>, String> {
    // JSON text when it looks like JSON or no such file exists; else a file.
    let t = spec.trim_start();
    let looks_like_json = t.starts_with(['{', '[', '"']) || t == "null" || t.parse::<f64>().is_ok();
    let text = if looks_like_json || !Path::new(spec).is_file() {
        spec.to_string()
    } else {
        String::from_utf8(super::read_file(Path::new(spec))?)
            .map_err(|_| format!("{flag}: {spec}: not UTF-8 text"))?
    };
    let text = super::strip_bom(&text);
    let value: Value = serde_json::from_str(text).map_err(|e| {
        if looks_like_json || Path::new(spec).is_file() {
            format!("{flag}: not valid JSON ({e}); expected an object {{\"name\": number}}")
        } else {
            format!(
                "{flag}: '{}' is neither a JSON object {{\"name\": number}} nor a file",
                super::short(spec)
            )
        }
    })?;
    let Value::Object(map) = value else {
        return Err(format!(
            "{flag}: expected a JSON object {{\"name\": number}} (got {})",
            super::short(&value.to_string())
        ));
    };
    map.into_iter()
        .map(|(k, v)| match v.as_f64() {
            Some(x) if x.is_finite() => Ok((k, x)),
            _ => Err(format!(
                "{flag}: parameter '{}' must be a finite number (got {})",
                super::short(&k),
                super::short(&v.to_string())
            )),
        })
        .collect()
}

impl FitArgs {
    /// The `fit` request these flags describe, and the program's display name.
    fn request(&self) -> Result<(FitRequest, String, Origins), String> {
        let (name, program) = load_program(&self.program)?;
        let mut origins: Origins = vec![
            ("program", name.clone()),
            ("params", "--params".into()),
            ("target_params", "--target-params".into()),
        ];
        if let Some(t) = &self.target {
            origins.push(("target_png", t.display().to_string()));
        }
        let mut o = Map::new();
        put(&mut o, "budget", "--budget", self.budget.as_ref())?;
        put(&mut o, "loss", "--loss", self.loss.as_ref())?;
        put(&mut o, "init", "--init", self.init.as_ref())?;
        put(&mut o, "grid", "--grid", self.grid)?;
        put(&mut o, "units", "--units", self.units.as_ref())?;
        put(&mut o, "seed", "--seed", self.seed)?;
        put(&mut o, "tolerance", "--tolerance", self.tolerance)?;
        put(&mut o, "polish", "--polish", self.polish)?;
        put(&mut o, "max_seconds", "--max-seconds", self.max_seconds)?;
        let mut req: FitRequest = request("fit", Value::Object(o), &origins)?;
        req.program = program;
        if let Some(p) = &self.params {
            req.params = param_map(p, "--params")?;
        }
        match (&self.target, &self.target_params) {
            (Some(path), _) => req.target_png = Some(super::read_file(path)?),
            (None, Some(spec)) => req.target_params = Some(param_map(spec, "--target-params")?),
            (None, None) => return Err("give --target IMAGE or --target-params JSON".into()),
        }
        Ok((req, name, origins))
    }
}

/// The lower-case extension of an output path, which must be .png or .svg.
fn output_kind(path: &Path) -> Result<String, String> {
    super::out_path(path, &["png", "svg"])
}

/// The fitted pattern as a PNG of `width × height`: the same
/// `render-pattern` request the browser sends, on the target's canvas (its
/// aspect), so nothing is stretched.
fn fitted_png(
    req: &FitRequest,
    out: &filigree::pattern::api::FitOutput,
    origins: &Origins,
) -> Result<Vec<u8>, String> {
    let mut params = req.params.clone();
    params.extend(out.named.iter().map(|(k, v)| (k.clone(), *v)));
    let r = RenderPatternRequest {
        program: req.program.clone(),
        params,
        size: out.width as usize,
        height: Some(out.height as usize),
        ..RenderPatternRequest::default()
    };
    let job = start_render(r).map_err(|e| explain(e, origins))?;
    let r = drive(job, true, origins)?;
    let img = filigree::raster::Rgba8Image::from_raw(r.image.width, r.image.height, r.image.rgba)
        .map_err(|e| e.to_string())?;
    filigree::raster::encode_png(&img).map_err(|e| e.to_string())
}

pub fn run_fit(a: FitArgs) -> Result<(), String> {
    let (mut req, name, origins) = a.request()?;
    if a.print_request {
        return print_request(&req);
    }
    let out_kind = a.out.as_deref().map(output_kind).transpose()?;
    if let Some(path) = &a.svg {
        super::out_path(path, &["svg"])?;
    }
    let threads = super::threads(a.threads)?;
    let t0 = Instant::now();
    // One shard per thread, exchanged by the same driver contract as the
    // browser's worker pool; the result equals a one-thread fit.
    let jobs = (0..threads)
        .map(|k| {
            req.shards = Some((k, threads));
            start_fit(&req).map_err(|e| explain(e, &origins))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let mut last = -1.0;
    let quiet = a.json;
    let out = run_sharded_threads(jobs, &Cancel::new(), |k, p| {
        if !quiet && k == 0 && p.fraction - last >= 0.05 {
            last = p.fraction;
            eprintln!(
                "{:>3.0}%  {}  best loss {:.5}",
                p.fraction * 100.0,
                p.stage,
                p.figure.unwrap_or(f64::NAN)
            );
        }
    })
    .map_err(|e| explain(e, &origins))?;
    let secs = t0.elapsed().as_secs_f64();
    let r = &out.result;
    // The result is printed before the files are written: a failed write
    // never loses it.
    if a.json {
        let params: Map<String, Value> = r
            .names
            .iter()
            .zip(&r.params)
            .map(|(n, v)| (n.clone(), json!(v)))
            .collect();
        let j = json!({"program": name, "params": params, "loss_name": out.loss_name, "loss": r.loss, "init_loss": r.init_loss, "polish_loss": r.polish_loss,
            "evaluations": r.evaluations, "seconds": secs, "history": r.history});
        println!("{j}");
    } else {
        for (n, v) in r.names.iter().zip(&r.params) {
            println!("{n:>14} = {v:.5}");
        }
        let name = serde_json::to_value(out.loss_name)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string))
            .unwrap_or_default();
        println!(
            "{name} loss {:.6} (after initialisation {:.6}), {} evaluations, {secs:.2} s",
            r.loss, r.init_loss, r.evaluations
        );
        if let Some(p) = r.polish_loss {
            println!("image loss after the polish {p:.6}");
        }
    }
    if let Some(path) = &a.svg {
        std::fs::write(path, &out.svg)
            .map_err(|e| format!("{}: {e} (the fit's result is above)", path.display()))?;
    }
    if let (Some(path), Some(kind)) = (&a.out, &out_kind) {
        let bytes = if kind == "svg" {
            out.svg.clone().into_bytes()
        } else {
            req.shards = None;
            fitted_png(&req, &out, &origins)?
        };
        std::fs::write(path, bytes)
            .map_err(|e| format!("{}: {e} (the fit's result is above)", path.display()))?;
    }
    Ok(())
}

pub fn run_render(a: RenderArgs) -> Result<(), String> {
    let (name, program) = load_program(&a.program)?;
    let origins: Origins = vec![("program", name), ("params", "--params".into())];
    let mut o = Map::new();
    put(&mut o, "size", "--size", a.size)?;
    put(&mut o, "height", "--height", a.height)?;
    put(&mut o, "supersample", "--supersample", a.supersample)?;
    let mut req: RenderPatternRequest = request("render-pattern", Value::Object(o), &origins)?;
    req.program = program;
    if let Some(p) = &a.params {
        req.params = param_map(p, "--params")?;
    }
    if a.print_request {
        return print_request(&req);
    }
    let ext = output_kind(&a.out)?;
    let job = start_render(req).map_err(|e| explain(e, &origins))?;
    let r = drive(job, true, &origins)?;
    let bytes = if ext == "svg" {
        r.svg.into_bytes()
    } else {
        let img =
            filigree::raster::Rgba8Image::from_raw(r.image.width, r.image.height, r.image.rgba)
                .map_err(|e| e.to_string())?;
        filigree::raster::encode_png(&img).map_err(|e| e.to_string())?
    };
    std::fs::write(&a.out, bytes).map_err(|e| format!("{}: {e}", a.out.display()))
}
