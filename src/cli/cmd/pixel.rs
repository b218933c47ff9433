//! `filigree pixel`: flags → the browser's `pixel` request (see
//! `filigree::pixel::api`) → the same core job. Defaults come from the
//! request ([`filigree::pixel::PixelParams`]'s `Default`), not from here.
use super::{drive, explain, print_request, put, request, Origins};
use filigree::pixel::api::{mask_bits, start_pixel, PixelMaskRequest, PixelRequest};
use filigree::pixel::{PixelParams, Stroke};
use filigree::raster::encode_png;
use serde::Deserialize;
use serde_json::{Map, Value};
use std::path::{Path, PathBuf};

#[derive(clap::Args)]
pub struct Args {
    /// Source pixel art (PNG, ...).
    #[arg(long)]
    source: PathBuf,
    /// Mask, same size as the source: opaque (or, without transparency, bright) pixels are textured.
    #[arg(long)]
    mask: PathBuf,
    /// Element sheet: a 3×3 grid of square cells; cell (dx+1, dy+1) points in direction (dx, dy).
    #[arg(long, required_unless_present = "sprite", conflicts_with = "sprite")]
    sheet: Option<PathBuf>,
    /// A single element sprite (drawn pointing up unless --sprite-direction says otherwise),
    /// turned into the eight orientations automatically.
    #[arg(long)]
    sprite: Option<PathBuf>,
    /// Strokes JSON: {"strokes": [[[x, y], [x, y], ...], ...]} in source pixels; may be empty.
    #[arg(long)]
    strokes: PathBuf,
    /// Upscale factor K of the annotation grid, 1..=32 (default 4).
    #[arg(long)]
    annotation_scale: Option<u32>,
    /// Position strategy: random (default) | packed.
    #[arg(long)]
    positions: Option<String>,
    /// Density ρ: 0..1, or a percentage such as 80% (default 1).
    #[arg(long)]
    density: Option<String>,
    /// Margins MX,MY in pixels, may be negative, e.g. -1,-1 (default 0,0).
    #[arg(long, allow_hyphen_values = true)]
    margins: Option<String>,
    /// Allow elements only partly inside the mask.
    #[arg(long)]
    partial: bool,
    /// Colour map strategy: auto (default) | hsv | difference | border.
    #[arg(long)]
    colour: Option<String>,
    /// HSV shift DH,DS,DV: hue in degrees, saturation and value in percentage points (default 0,0,-30).
    #[arg(long, allow_hyphen_values = true)]
    hsv: Option<String>,
    /// Colours never used for elements, e.g. '#000000,#ffffff'; 'none' for no exclusion (default #000000).
    #[arg(long)]
    exclude: Option<String>,
    /// Maximum CIELAB distance for the automatic colour choice (default 50).
    #[arg(long, allow_hyphen_values = true)]
    dmax: Option<f64>,
    /// Element colouring: region (default) | pixel.
    #[arg(long)]
    element_colour: Option<String>,
    /// Orientation used without strokes: right, down-right, down (default), ..., up-right.
    #[arg(long)]
    default_direction: Option<String>,
    /// Which way a --sprite points as drawn (default up).
    #[arg(long)]
    sprite_direction: Option<String>,
    /// Seed of every random choice (default 0).
    #[arg(long)]
    seed: Option<u64>,
    /// Output PNG.
    #[arg(long)]
    out: PathBuf,
    /// Print the request (as the browser would send it) and exit.
    #[arg(long, hide = true)]
    print_request: bool,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StrokesFile {
    strokes: Vec<Stroke>,
}

/// Read a strokes JSON file, naming it (and the line/column) on error.
pub fn read_strokes(path: &Path) -> Result<Vec<Stroke>, String> {
    let bytes = super::read_file(path)?;
    let text = bytes.strip_prefix("\u{feff}".as_bytes()).unwrap_or(&bytes);
    let f: StrokesFile = serde_json::from_slice(text).map_err(|e| {
        format!(
            "{}: {e} (expected {{\"strokes\": [[[x, y], [x, y], ...], ...]}})",
            path.display()
        )
    })?;
    Ok(f.strokes)
}

fn numbers<const N: usize>(s: &str, what: &str) -> Result<[f64; N], String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("--{what} '{s}': expected {N} comma-separated numbers"))?;
    v.try_into()
        .map_err(|_| format!("--{what} '{s}': expected {N} comma-separated numbers"))
}

fn parse_density(s: &str) -> Result<f64, String> {
    let (t, scale) = match s.strip_suffix('%') {
        Some(t) => (t, 100.0),
        None => (s, 1.0),
    };
    let v: f64 = t
        .trim()
        .parse()
        .map_err(|_| format!("--density '{s}': expected 0..1 or a percentage like 80%"))?;
    Ok(v / scale)
}

fn parse_colours(s: &str) -> Result<Vec<[u8; 3]>, String> {
    if s.trim().is_empty() || s.trim().eq_ignore_ascii_case("none") {
        return Ok(vec![]);
    }
    s.split(',')
        .map(|t| {
            let h = t.trim().trim_start_matches('#');
            let ok = h.len() == 6 && h.chars().all(|c| c.is_ascii_hexdigit());
            if !ok {
                return Err(format!(
                    "--exclude: '{}' is not a colour like #1a2b3c",
                    t.trim()
                ));
            }
            let b = |i: usize| u8::from_str_radix(&h[i..i + 2], 16).expect("checked hex");
            Ok([b(0), b(2), b(4)])
        })
        .collect()
}

/// Where each request field came from.
fn origins(a: &Args) -> Origins {
    let mut o: Origins = vec![
        ("source", a.source.display().to_string()),
        ("mask", a.mask.display().to_string()),
        ("strokes", a.strokes.display().to_string()),
        ("params.d_max", "--dmax".into()),
        ("params", "the Pixel settings".into()),
    ];
    if let Some(p) = &a.sheet {
        o.push(("sheet", p.display().to_string()));
    }
    if let Some(p) = &a.sprite {
        o.push(("sprite", p.display().to_string()));
    }
    for (field, flag) in [
        ("params.annotation_scale", "--annotation-scale"),
        ("params.positions", "--positions"),
        ("params.density", "--density"),
        ("params.margins", "--margins"),
        ("params.colour", "--colour"),
        ("params.hsv", "--hsv"),
        ("params.exclude", "--exclude"),
        ("params.element_colour", "--element-colour"),
        ("params.default_direction", "--default-direction"),
        ("params.sprite_direction", "--sprite-direction"),
        ("params.seed", "--seed"),
    ] {
        o.push((field, flag.into()));
    }
    o
}

/// The given flags as [`PixelParams`] (missing ones at their defaults).
fn params(a: &Args, origins: &Origins) -> Result<PixelParams, String> {
    let mut p = Map::new();
    put(
        &mut p,
        "annotation_scale",
        "--annotation-scale",
        a.annotation_scale,
    )?;
    put(&mut p, "positions", "--positions", a.positions.as_ref())?;
    if let Some(d) = &a.density {
        put(&mut p, "density", "--density", Some(parse_density(d)?))?;
    }
    if let Some(m) = &a.margins {
        let m = numbers::<2>(m, "margins")?;
        if m.iter().any(|v| v.fract() != 0.0) {
            return Err(format!("--margins '{m:?}': margins are whole pixels"));
        }
        // Whole numbers as JSON integers; out-of-range ones are rejected by the request.
        put(
            &mut p,
            "margins",
            "--margins",
            Some([m[0] as i64, m[1] as i64]),
        )?;
    }
    if a.partial {
        put(&mut p, "partial", "--partial", Some(true))?;
    }
    put(&mut p, "colour", "--colour", a.colour.as_ref())?;
    if let Some(h) = &a.hsv {
        put(&mut p, "hsv", "--hsv", Some(numbers::<3>(h, "hsv")?))?;
    }
    if let Some(e) = &a.exclude {
        put(&mut p, "exclude", "--exclude", Some(parse_colours(e)?))?;
    }
    put(&mut p, "d_max", "--dmax", a.dmax)?;
    put(
        &mut p,
        "element_colour",
        "--element-colour",
        a.element_colour.as_ref(),
    )?;
    put(
        &mut p,
        "default_direction",
        "--default-direction",
        a.default_direction.as_ref(),
    )?;
    put(
        &mut p,
        "sprite_direction",
        "--sprite-direction",
        a.sprite_direction.as_ref(),
    )?;
    put(&mut p, "seed", "--seed", a.seed)?;
    let mut o = Map::new();
    o.insert("params".into(), Value::Object(p));
    let req: PixelRequest = request("pixel", Value::Object(o), origins)?;
    Ok(req.params)
}

pub fn run(a: Args) -> Result<(), String> {
    super::out_path(&a.out, &["png"])?;
    let origins = origins(&a);
    let params = params(&a, &origins)?;
    let mask_origin: Origins = vec![("bytes", a.mask.display().to_string())];
    let mask = mask_bits(&PixelMaskRequest {
        bytes: super::read_file(&a.mask)?,
    })
    .map_err(|e| explain(e, &mask_origin))?;
    let req = PixelRequest {
        source: super::read_file(&a.source)?,
        mask,
        sheet: a.sheet.as_deref().map(super::read_file).transpose()?,
        sprite: a.sprite.as_deref().map(super::read_file).transpose()?,
        strokes: read_strokes(&a.strokes)?,
        params,
    };
    if a.print_request {
        return print_request(&req);
    }
    let job = start_pixel(req).map_err(|e| explain(e, &origins))?;
    let out = drive(job, true, &origins)?;
    let png = encode_png(&out.image).map_err(|e| e.to_string())?;
    std::fs::write(&a.out, png).map_err(|e| format!("{}: {e}", a.out.display()))?;
    let s = &out.stats;
    println!(
        "{}: {}×{}, {} elements placed ({} positions), colours {} → {}, colour map: {}, {} annotated pixels{}",
        a.out.display(),
        out.image.width,
        out.image.height,
        s.placed,
        s.positions,
        s.colours_before,
        s.colours_after,
        s.colour_map_used.name(),
        s.annotated_pixels,
        s.solve.map_or(String::new(), |v| format!(", Laplace solve {}+{} CG iterations", v.iterations[0], v.iterations[1]))
    );
    Ok(())
}
