//! `filigree micro`: flags → the browser's `micro-render` / `micro-slice` /
//! `micro-fit` requests → the same core jobs. Defaults come from the requests.
use super::{drive, print_request, put, request, Origins};
use clap::Subcommand;
use filigree::core::job::Cancel;
use filigree::core::parallel::run_sharded_threads;
use filigree::micro::api::{
    render_threads, start_render, start_slice, MicroRenderRequest, MicroSliceRequest,
};
use filigree::micro::fit_api::{start_fit, FitParam, FitTarget, MicroFitRequest};
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};

#[derive(Subcommand)]
pub enum Which {
    /// Sphere-trace a scene (JSON, see assets/micro/) to a PNG.
    Render(Box<RenderArgs>),
    /// The scene's signed distance on the plane z = Z, colour-mapped, to a PNG.
    Slice(SliceArgs),
    /// Fit numbers of a scene to a target (reconstruction, paper §6) and
    /// write the fitted scene; prints a JSON summary.
    ///
    /// The target (--target) is one of: a scene file (.json), sampled on the
    /// same grid; a raw volume (.f32: grid³ little-endian floats, x fastest);
    /// or slice images (.png, given N times for N planes, N a power of two
    /// ≤ grid, each grid×grid, grey g meaning distance (2g − 1)·--range, dark
    /// inside). With --image the target is a picture instead (analysis by
    /// synthesis): a .png (sides powers of two), or a .json scene rendered
    /// at --size with the same default camera.
    Fit(Box<FitArgs>),
}

#[derive(clap::Args)]
pub struct FitArgs {
    /// Scene file (JSON) whose values are the start.
    #[arg(long)]
    scene: PathBuf,
    /// Target: scene .json, volume .f32, or slice .png (repeat for a stack).
    #[arg(long, required = true)]
    target: Vec<PathBuf>,
    /// Output: the fitted scene (JSON).
    #[arg(long)]
    out: PathBuf,
    /// A parameter to fit: POINTER=LO:HI, e.g. /period=0.1:1 (JSON pointer
    /// into the scene). POINTER,POINTER2=LO:HI ties several numbers. Repeat
    /// for more parameters.
    #[arg(long = "param", required = true, value_name = "POINTER=LO:HI")]
    params: Vec<String>,
    /// The target is a picture (analysis by synthesis, Eq. 39).
    #[arg(long)]
    image: bool,
    /// Samples per side (power of two).
    #[arg(long)]
    grid: Option<u32>,
    /// Half size of the sample box.
    #[arg(long)]
    half: Option<f64>,
    /// Centre of the sample box X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    center: Option<String>,
    /// cmaes, nelder-mead or powell.
    #[arg(long)]
    optimizer: Option<String>,
    /// Loss evaluations in all.
    #[arg(long)]
    budget: Option<u32>,
    /// CMA-ES samples per generation (0: automatic).
    #[arg(long)]
    population: Option<u32>,
    /// CMA-ES initial step (fraction of each range).
    #[arg(long)]
    sigma: Option<f64>,
    #[arg(long)]
    seed: Option<u64>,
    /// Volume targets: fit in coarse-to-fine stages (blurred power
    /// profiles, then amplitudes, then the paper's loss): true or false.
    #[arg(long, value_name = "BOOL")]
    coarse_to_fine: Option<bool>,
    /// Slice targets: the distance that white (and black) stands for.
    #[arg(long)]
    range: Option<f64>,
    /// Image targets rendered from a scene: WIDTHxHEIGHT (powers of two).
    #[arg(long, value_name = "WxH")]
    size: Option<String>,
    /// Worker threads (shards of the population); default all cores.
    #[arg(long)]
    threads: Option<usize>,
    /// Print only the JSON summary (no progress).
    #[arg(long)]
    json: bool,
    /// Print the request (as the browser would send it) and exit.
    #[arg(long, hide = true)]
    print_request: bool,
}

#[derive(clap::Args)]
pub struct RenderArgs {
    /// Scene file (JSON).
    #[arg(long)]
    scene: PathBuf,
    /// Output PNG.
    #[arg(long)]
    out: PathBuf,
    /// Image size WIDTHxHEIGHT in pixels.
    #[arg(long, value_name = "WxH")]
    size: Option<String>,
    /// Step strategy: fixed, bisection or adaptive.
    #[arg(long)]
    steps: Option<String>,
    /// Adaptive steps: a gradient check every N steps (from step N on).
    #[arg(long)]
    check_every: Option<u32>,
    /// Most steps along one ray.
    #[arg(long)]
    max_steps: Option<u32>,
    /// Camera distance from its target (zoom).
    #[arg(long)]
    distance: Option<f64>,
    /// Camera azimuth and elevation, degrees.
    #[arg(long, allow_hyphen_values = true)]
    yaw: Option<f64>,
    #[arg(long, allow_hyphen_values = true)]
    pitch: Option<f64>,
    /// Vertical field of view, degrees.
    #[arg(long)]
    fov: Option<f64>,
    /// Camera target X,Y,Z.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    target: Option<String>,
    /// Half size of the sample box.
    #[arg(long)]
    bounds: Option<f64>,
    /// Absorption per world unit inside the sample.
    #[arg(long)]
    absorption: Option<f64>,
    /// Surface model: lambert or ggx (with --roughness).
    #[arg(long)]
    shading: Option<String>,
    #[arg(long)]
    roughness: Option<f64>,
    /// Path trace with N samples per pixel (0: direct shading).
    #[arg(long)]
    spp: Option<u32>,
    /// Path tracing: most bounces of one path.
    #[arg(long)]
    max_depth: Option<u32>,
    /// GGX: reflectance at normal incidence (0..1).
    #[arg(long)]
    specular: Option<f64>,
    /// Path tracing: the seed of every pixel's samples.
    #[arg(long)]
    seed: Option<u64>,
    /// Render in bands on N threads (the same bytes as one thread).
    #[arg(long)]
    threads: Option<usize>,
    /// Print the work counters as JSON.
    #[arg(long)]
    json: bool,
    /// Print the request (as the browser would send it) and exit.
    #[arg(long, hide = true)]
    print_request: bool,
}

#[derive(clap::Args)]
pub struct SliceArgs {
    /// Scene file (JSON).
    #[arg(long)]
    scene: PathBuf,
    /// Height of the slice plane.
    #[arg(long, allow_hyphen_values = true)]
    z: Option<f64>,
    /// Output PNG.
    #[arg(long)]
    out: PathBuf,
    /// Image size WIDTHxHEIGHT in pixels.
    #[arg(long, value_name = "WxH")]
    size: Option<String>,
    /// Half width of the view (world units).
    #[arg(long)]
    half: Option<f64>,
    /// Grey ramp instead of the inside/outside colour map.
    #[arg(long)]
    grey: bool,
    /// Print the value range as JSON.
    #[arg(long)]
    json: bool,
    /// Print the request (as the browser would send it) and exit.
    #[arg(long, hide = true)]
    print_request: bool,
}

fn size(o: &mut Map<String, Value>, s: &Option<String>) -> Result<(), String> {
    if let Some(s) = s {
        let (w, h) = s
            .split_once(['x', 'X'])
            .and_then(|(w, h)| Some((w.trim().parse::<u32>().ok()?, h.trim().parse::<u32>().ok()?)))
            .ok_or_else(|| format!("--size: expected WIDTHxHEIGHT such as 512x384 (got '{s}')"))?;
        o.insert("width".into(), json!(w));
        o.insert("height".into(), json!(h));
    }
    Ok(())
}

fn scene_text(path: &Path) -> Result<String, String> {
    String::from_utf8(super::read_file(path)?)
        .map_err(|_| format!("{}: the scene is not UTF-8 text", path.display()))
}

fn write(path: &Path, bytes: &[u8]) -> Result<(), String> {
    std::fs::write(path, bytes).map_err(|e| format!("{}: {e}", path.display()))
}

pub fn run(which: Which) -> Result<(), String> {
    match which {
        Which::Render(a) => render(*a),
        Which::Slice(a) => slice(a),
        Which::Fit(a) => fit(*a),
    }
}

/// `POINTER[,POINTER...]=LO:HI`.
fn parse_param(s: &str) -> Result<FitParam, String> {
    let bad = || format!("--param: expected POINTER=LO:HI such as /period=0.1:1 (got '{s}')");
    let (ptrs, range) = s.rsplit_once('=').ok_or_else(bad)?;
    let (lo, hi) = range.split_once(':').ok_or_else(bad)?;
    let lo: f64 = lo.trim().parse().map_err(|_| bad())?;
    let hi: f64 = hi.trim().parse().map_err(|_| bad())?;
    let mut ptrs = ptrs.split(',').map(|p| p.trim().to_string());
    let pointer = ptrs.next().filter(|p| !p.is_empty()).ok_or_else(bad)?;
    Ok(FitParam {
        pointer,
        lo,
        hi,
        also: ptrs.collect(),
    })
}

fn ext(p: &Path) -> String {
    p.extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_ascii_lowercase()
}

fn fit_target(a: &FitArgs) -> Result<FitTarget, String> {
    let first = &a.target[0];
    let kind = ext(first);
    if a.target.iter().any(|t| ext(t) != kind) {
        return Err(
            "--target: give one scene (.json), one volume (.f32), or .png slices, not a mix".into(),
        );
    }
    if a.image {
        if a.target.len() != 1 {
            return Err("--target: an image target is one .png or one .json scene".into());
        }
        return match kind.as_str() {
            "png" => Ok(FitTarget::Image {
                png: Some(serde_bytes::ByteBuf::from(super::read_file(first)?)),
                scene: None,
            }),
            "json" => Ok(FitTarget::Image {
                png: None,
                scene: Some(scene_text(first)?),
            }),
            _ => Err(format!(
                "--target: {}: an image target is a .png or a .json scene",
                first.display()
            )),
        };
    }
    match kind.as_str() {
        "json" if a.target.len() == 1 => Ok(FitTarget::Scene {
            scene: scene_text(first)?,
        }),
        "f32" if a.target.len() == 1 => {
            let bytes = super::read_file(first)?;
            if bytes.len() % 4 != 0 {
                return Err(format!(
                    "{}: a raw volume is little-endian f32 values ({} bytes is not a multiple of 4)",
                    first.display(),
                    bytes.len()
                ));
            }
            Ok(FitTarget::Volume {
                values: bytes
                    .chunks_exact(4)
                    .map(|c| f32::from_le_bytes([c[0], c[1], c[2], c[3]]) as f64)
                    .collect(),
            })
        }
        "png" => Ok(FitTarget::Slices {
            pngs: a
                .target
                .iter()
                .map(|p| super::read_file(p).map(serde_bytes::ByteBuf::from))
                .collect::<Result<_, _>>()?,
            range: a.range.unwrap_or(1.0),
        }),
        _ => Err(format!(
            "--target: {}: expected a scene (.json), a raw volume (.f32) or slices (.png); \
             one scene or volume at a time",
            first.display()
        )),
    }
}

fn fit(a: FitArgs) -> Result<(), String> {
    super::out_path(&a.out, &["json"])?;
    let origins: Origins = vec![
        ("scene", a.scene.display().to_string()),
        ("target", "--target".into()),
        ("params", "--param".into()),
        ("render.width", "--size".into()),
        ("render.height", "--size".into()),
    ];
    let mut o = Map::new();
    put(&mut o, "grid", "--grid", a.grid)?;
    put(&mut o, "half", "--half", a.half)?;
    put(&mut o, "optimizer", "--optimizer", a.optimizer.clone())?;
    put(&mut o, "budget", "--budget", a.budget)?;
    put(&mut o, "population", "--population", a.population)?;
    put(&mut o, "sigma", "--sigma", a.sigma)?;
    put(&mut o, "seed", "--seed", a.seed)?;
    put(
        &mut o,
        "coarse_to_fine",
        "--coarse-to-fine",
        a.coarse_to_fine,
    )?;
    if let Some(c) = &a.center {
        let v: Vec<f64> = c
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("--center: expected X,Y,Z (got '{c}')"))?;
        if v.len() != 3 {
            return Err(format!(
                "--center: expected three numbers X,Y,Z (got '{c}')"
            ));
        }
        put(&mut o, "center", "--center", Some(v))?;
    }
    if a.size.is_some() {
        let mut r = Map::new();
        size(&mut r, &a.size)?;
        o.insert("render".into(), Value::Object(r));
    }
    let mut req: MicroFitRequest = request("micro-fit", Value::Object(o), &origins)?;
    req.scene = scene_text(&a.scene)?;
    req.params = a
        .params
        .iter()
        .map(|p| parse_param(p))
        .collect::<Result<_, _>>()?;
    req.target = fit_target(&a)?;
    if a.print_request {
        return print_request(&req);
    }
    let threads = super::threads(a.threads)?;
    let t0 = std::time::Instant::now();
    // One shard per thread; the result equals a one-thread fit.
    let jobs = (0..threads)
        .map(|k| {
            start_fit(MicroFitRequest {
                shards: Some((k, threads)),
                ..req.clone()
            })
            .map_err(|e| super::explain(e, &origins))
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
    .map_err(|e| super::explain(e, &origins))?;
    let secs = t0.elapsed().as_secs_f64();
    let params: Vec<Value> = req
        .params
        .iter()
        .zip(&out.values)
        .map(|(p, v)| json!({"pointer": p.pointer, "value": v}))
        .collect();
    println!(
        "{}",
        json!({
            "params": params,
            "loss": out.loss,
            "initial_loss": out.initial_loss,
            "validation": out.validation,
            "evaluations": out.evaluations,
            "seconds": secs,
            "ms_per_eval": secs * 1e3 / out.evaluations.max(1) as f64,
            "threads": threads,
            "optimizer": req.optimizer,
            "out": a.out.display().to_string(),
        })
    );
    // After the result is printed: a failed write never loses it.
    write(&a.out, out.scene.as_bytes()).map_err(|e| format!("{e} (the fit's result is above)"))
}

fn render(a: RenderArgs) -> Result<(), String> {
    super::out_path(&a.out, &["png"])?;
    let origins: Origins = vec![
        ("scene", a.scene.display().to_string()),
        ("width", "--size".into()),
        ("height", "--size".into()),
        ("camera.distance", "--distance".into()),
        ("camera.yaw", "--yaw".into()),
        ("camera.pitch", "--pitch".into()),
        ("camera.fov", "--fov".into()),
        ("camera.target", "--target".into()),
    ];
    let mut o = Map::new();
    size(&mut o, &a.size)?;
    put(&mut o, "steps", "--steps", a.steps)?;
    put(&mut o, "check_every", "--check-every", a.check_every)?;
    put(&mut o, "max_steps", "--max-steps", a.max_steps)?;
    put(&mut o, "bounds", "--bounds", a.bounds)?;
    put(&mut o, "absorption", "--absorption", a.absorption)?;
    put(&mut o, "shading", "--shading", a.shading)?;
    put(&mut o, "roughness", "--roughness", a.roughness)?;
    put(&mut o, "spp", "--spp", a.spp)?;
    put(&mut o, "max_depth", "--max-depth", a.max_depth)?;
    put(&mut o, "specular", "--specular", a.specular)?;
    put(&mut o, "seed", "--seed", a.seed)?;
    let mut cam = Map::new();
    put(&mut cam, "distance", "--distance", a.distance)?;
    put(&mut cam, "yaw", "--yaw", a.yaw)?;
    put(&mut cam, "pitch", "--pitch", a.pitch)?;
    put(&mut cam, "fov", "--fov", a.fov)?;
    if let Some(t) = &a.target {
        let v: Vec<f64> = t
            .split(',')
            .map(|x| x.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| format!("--target: expected X,Y,Z (got '{t}')"))?;
        if v.len() != 3 {
            return Err(format!(
                "--target: expected three numbers X,Y,Z (got '{t}')"
            ));
        }
        put(&mut cam, "target", "--target", Some(v))?;
    }
    if !cam.is_empty() {
        o.insert("camera".into(), Value::Object(cam));
    }
    let mut req: MicroRenderRequest = request("micro-render", Value::Object(o), &origins)?;
    req.scene = scene_text(&a.scene)?;
    if a.print_request {
        return print_request(&req);
    }
    let out = match a.threads {
        // One job, with progress.
        None => {
            let job = start_render(req).map_err(|e| super::explain(e, &origins))?;
            drive(job, a.json, &origins)?
        }
        // Bands on scoped threads (four per thread, for balance).
        Some(n) => {
            let n = super::threads(Some(n))?;
            render_threads(&req, n, n as u32 * 4, &Cancel::new())
                .map_err(|e| super::explain(e, &origins))?
        }
    };
    write(&a.out, &out.png)?;
    if a.json {
        println!(
            "{}",
            json!({"width": out.width, "height": out.height, "stats": out.stats})
        );
    } else {
        let s = out.stats;
        eprintln!(
            "{}: {}×{}, {} rays, {} hits, {} steps, {} SDF evaluations",
            a.out.display(),
            out.width,
            out.height,
            s.rays,
            s.hits,
            s.steps,
            s.sdf_evals
        );
    }
    Ok(())
}

fn slice(a: SliceArgs) -> Result<(), String> {
    super::out_path(&a.out, &["png"])?;
    let origins: Origins = vec![
        ("scene", a.scene.display().to_string()),
        ("width", "--size".into()),
        ("height", "--size".into()),
    ];
    let mut o = Map::new();
    size(&mut o, &a.size)?;
    put(&mut o, "z", "--z", a.z)?;
    put(&mut o, "half", "--half", a.half)?;
    if a.grey {
        o.insert("grey".into(), json!(true));
    }
    let mut req: MicroSliceRequest = request("micro-slice", Value::Object(o), &origins)?;
    req.scene = scene_text(&a.scene)?;
    if a.print_request {
        return print_request(&req);
    }
    let job = start_slice(req).map_err(|e| super::explain(e, &origins))?;
    let out = drive(job, a.json, &origins)?;
    write(&a.out, &out.png)?;
    if a.json {
        println!(
            "{}",
            json!({"width": out.width, "height": out.height, "min": out.min, "max": out.max, "inside": out.inside})
        );
    } else {
        eprintln!(
            "{}: {}×{}, distance {:.4} … {:.4}, {:.1}% inside",
            a.out.display(),
            out.width,
            out.height,
            out.min,
            out.max,
            out.inside * 100.0
        );
    }
    Ok(())
}
