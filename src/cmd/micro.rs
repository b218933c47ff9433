//! `filigree micro`: flags → the browser's `micro-render` / `micro-slice`
//! requests → the same core jobs. Defaults come from the requests.
use super::{drive, print_request, put, request, Origins};
use clap::Subcommand;
use filigree::micro::api::{start_render, start_slice, MicroRenderRequest, MicroSliceRequest};
use serde_json::{json, Map, Value};
use std::path::{Path, PathBuf};

#[derive(Subcommand)]
pub enum Which {
    /// Sphere-trace a scene (JSON, see assets/micro/) to a PNG.
    Render(Box<RenderArgs>),
    /// The scene's signed distance on the plane z = Z, colour-mapped, to a PNG.
    Slice(SliceArgs),
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
    /// Adaptive steps: a gradient check every N steps.
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
    }
}

fn render(a: RenderArgs) -> Result<(), String> {
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
    let job = start_render(req).map_err(|e| super::explain(e, &origins))?;
    let out = drive(job, a.json, &origins)?;
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
