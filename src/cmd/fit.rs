//! `filigree fit` and `filigree render`: fit a pattern program to an image,
//! draw a program with given parameters.
use filigree::core::job::Cancel;
use filigree::core::parallel::run_sharded_threads;
use filigree::pattern::fit::{Budget, FitJob, FitOptions, TargetSource};
use filigree::pattern::generators::{generator, GENERATORS};
use filigree::pattern::loss::{LossKind, SdfUnits};
use filigree::pattern::optim::InitMethod;
use filigree::pattern::record::Program;
use filigree::pattern::{field::Scene, record::RecordLimits, render};
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args)]
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
    /// quick | paper
    #[arg(long, default_value = "paper")]
    budget: String,
    /// sdf | l1 | pyramid | image
    #[arg(long, default_value = "sdf")]
    loss: String,
    /// genetic | random | nelder-mead
    #[arg(long, default_value = "genetic")]
    init: String,
    /// Loss grid side in pixels (default: 128 for paper, 64 for quick).
    #[arg(long)]
    grid: Option<usize>,
    /// Field units in the loss: pixels | canvas.
    #[arg(long, default_value = "pixels")]
    units: String,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Threads for the initialisation (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// RGB distance within which a target pixel matches a palette colour.
    #[arg(long, default_value_t = 60.0)]
    tolerance: f64,
    /// Adam iterations on the image-space loss after the fit (0 = off, the paper's method).
    #[arg(long, default_value_t = 0)]
    polish: usize,
    /// Print JSON.
    #[arg(long)]
    json: bool,
    /// Write the fitted pattern as SVG.
    #[arg(long)]
    svg: Option<PathBuf>,
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
    /// Side in pixels.
    #[arg(long, default_value_t = 512)]
    size: usize,
    /// Samples per pixel side for PNG anti-aliasing (1 = exact palette colours).
    #[arg(long, default_value_t = 1)]
    supersample: usize,
}

/// Load a program from a file or by generator name.
pub fn load_program(spec: &str) -> Result<(String, Program), String> {
    let p = Path::new(spec);
    let (name, src) = if p.exists() {
        let bytes = super::read_file(p)?;
        (
            spec.to_string(),
            String::from_utf8(bytes).map_err(|_| format!("{spec}: not UTF-8 text"))?,
        )
    } else if let Some(g) = generator(spec) {
        (g.name.to_string(), g.source.to_string())
    } else {
        let names: Vec<&str> = GENERATORS.iter().map(|g| g.name).collect();
        return Err(format!(
            "'{spec}' is neither a file nor a generator ({})",
            names.join(", ")
        ));
    };
    let prog = Program::parse(&src).map_err(|e| format!("{name}: {e}"))?;
    Ok((name, prog))
}

/// Parameter values from a JSON object (inline or file), defaults elsewhere.
pub fn param_values(prog: &Program, spec: Option<&str>) -> Result<Vec<f64>, String> {
    let mut vals = prog.defaults();
    let Some(spec) = spec else { return Ok(vals) };
    let text = if spec.trim_start().starts_with('{') {
        spec.to_string()
    } else {
        String::from_utf8(super::read_file(Path::new(spec))?)
            .map_err(|_| format!("{spec}: not UTF-8"))?
    };
    let v: Value = serde_json::from_str(&text).map_err(|e| format!("parameters: {e}"))?;
    let obj = v
        .as_object()
        .ok_or("parameters must be a JSON object {\"name\": number}")?;
    for (k, x) in obj {
        let i = prog
            .params()
            .iter()
            .position(|p| &p.name == k)
            .ok_or_else(|| {
                let names: Vec<&str> = prog.params().iter().map(|p| p.name.as_str()).collect();
                format!(
                    "the program has no parameter '{k}' (it has {})",
                    names.join(", ")
                )
            })?;
        vals[i] = x
            .as_f64()
            .ok_or_else(|| format!("parameter '{k}' must be a number"))?;
    }
    Ok(vals)
}

fn float_of(prog: &Program, vals: &[f64]) -> Vec<f64> {
    prog.params()
        .iter()
        .zip(vals)
        .filter(|(p, _)| !p.integer)
        .map(|(_, v)| *v)
        .collect()
}

pub fn options(
    budget: &str,
    loss: &str,
    init: &str,
    grid: Option<usize>,
    units: &str,
    seed: u64,
) -> Result<FitOptions, String> {
    let b =
        Budget::parse(budget).ok_or_else(|| format!("unknown budget '{budget}' (quick, paper)"))?;
    let mut o = FitOptions::budget(b);
    o.loss.kind = LossKind::parse(loss)
        .ok_or_else(|| format!("unknown loss '{loss}' (sdf, l1, pyramid, image)"))?;
    o.init = match init {
        "genetic" | "ga" => InitMethod::Genetic,
        "random" => InitMethod::Random,
        "nelder-mead" | "nm" => InitMethod::NelderMead,
        _ => {
            return Err(format!(
                "unknown init '{init}' (genetic, random, nelder-mead)"
            ))
        }
    };
    if let Some(g) = grid {
        o.loss.grid = g;
    }
    o.loss.units = match units {
        "pixels" => SdfUnits::Pixels,
        "canvas" => SdfUnits::Canvas,
        _ => return Err(format!("unknown units '{units}' (pixels, canvas)")),
    };
    o.seed = seed;
    Ok(o)
}

pub fn run_fit(a: FitArgs) -> Result<(), String> {
    let (name, prog) = load_program(&a.program)?;
    let vals = param_values(&prog, a.params.as_deref())?;
    let mut opts = options(&a.budget, &a.loss, &a.init, a.grid, &a.units, a.seed)?;
    opts.polish = a.polish;
    let threads = super::threads(a.threads)?;
    let target_img;
    let target_vals;
    let target = match (&a.target, &a.target_params) {
        (Some(path), _) => {
            target_img = super::read_image(path)?;
            TargetSource::Image(&target_img, a.tolerance)
        }
        (None, Some(spec)) => {
            target_vals = float_of(&prog, &param_values(&prog, Some(spec))?);
            TargetSource::Params(&target_vals)
        }
        (None, None) => return Err("give --target IMAGE or --target-params JSON".into()),
    };
    let t0 = Instant::now();
    // One shard per thread, exchanged by the same driver contract as the
    // browser's worker pool; the result equals a one-thread fit.
    let jobs = (0..threads)
        .map(|k| {
            let mut o = opts;
            o.shards = (k, threads);
            FitJob::new(&prog, &vals, &target, o).map_err(|e| format!("{name}: {e}"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let scene = jobs[0].objective().scene.clone();
    let mut last = 0.0;
    let quiet = a.json;
    let r = run_sharded_threads(jobs, &Cancel::new(), |k, p| {
        if !quiet && k == 0 && (p.fraction - last >= 0.05) {
            last = p.fraction;
            eprintln!(
                "{:>3.0}%  {}  best loss {:.5}",
                p.fraction * 100.0,
                p.stage,
                p.figure.unwrap_or(f64::NAN)
            );
        }
    })
    .map_err(|e| e.to_string())?;
    let secs = t0.elapsed().as_secs_f64();
    if let Some(out) = &a.svg {
        let s = render::svg(&scene, &r.params, 512.0).map_err(|e| e.to_string())?;
        std::fs::write(out, s).map_err(|e| format!("{}: {e}", out.display()))?;
    }
    if a.json {
        let params: Map<String, Value> = r
            .names
            .iter()
            .zip(&r.params)
            .map(|(n, v)| (n.clone(), json!(v)))
            .collect();
        let out = json!({"program": name, "params": params, "loss": r.loss, "init_loss": r.init_loss, "polish_loss": r.polish_loss,
            "evaluations": r.evaluations, "seconds": secs, "history": r.history});
        println!("{out}");
    } else {
        for (n, v) in r.names.iter().zip(&r.params) {
            println!("{n:>14} = {v:.5}");
        }
        println!(
            "loss {:.6} (after initialisation {:.6}), {} evaluations, {secs:.2} s",
            r.loss, r.init_loss, r.evaluations
        );
    }
    Ok(())
}

pub fn run_render(a: RenderArgs) -> Result<(), String> {
    let (name, prog) = load_program(&a.program)?;
    let vals = param_values(&prog, a.params.as_deref())?;
    let rec = prog
        .record(&vals, &RecordLimits::default())
        .map_err(|e| format!("{name}: {e}"))?;
    let fl = rec.float_values();
    let scene = Scene::new(rec);
    let ext = a
        .out
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase();
    let bytes = match ext.as_str() {
        "svg" => render::svg(&scene, &fl, a.size as f64)
            .map_err(|e| e.to_string())?
            .into_bytes(),
        "png" => {
            let img =
                render::render(&scene, &fl, a.size, a.supersample).map_err(|e| e.to_string())?;
            filigree::raster::encode_png(&img).map_err(|e| e.to_string())?
        }
        _ => {
            return Err(format!(
                "{}: the output must end in .png or .svg",
                a.out.display()
            ))
        }
    };
    std::fs::write(&a.out, bytes).map_err(|e| format!("{}: {e}", a.out.display()))
}
