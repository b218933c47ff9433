//! `filigree pixel`: texture pixel art with oriented elements (see `filigree::pixel`).
use filigree::pixel::{self, inputs, orientation, Elements, PixelInputs, PixelParams, Stroke};
use filigree::raster::encode_png;
use serde::Deserialize;
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
    /// Upscale factor K of the annotation grid (1..=32).
    #[arg(long, default_value_t = 4)]
    annotation_scale: u32,
    /// Position strategy.
    #[arg(long, default_value = "random", value_parser = ["random", "packed"])]
    positions: String,
    /// Density ρ: 0..1, or a percentage such as 80%.
    #[arg(long, default_value = "1")]
    density: String,
    /// Margins MX,MY in pixels (may be negative, e.g. -1,-1).
    #[arg(long, default_value = "0,0", allow_hyphen_values = true)]
    margins: String,
    /// Allow elements only partly inside the mask.
    #[arg(long)]
    partial: bool,
    /// Colour map strategy.
    #[arg(long, default_value = "auto", value_parser = ["auto", "hsv", "difference", "border"])]
    colour: String,
    /// HSV shift DH,DS,DV: hue in degrees, saturation and value in percentage points.
    #[arg(long, default_value = "0,0,-30", allow_hyphen_values = true)]
    hsv: String,
    /// Colours never used for elements, e.g. '#000000,#ffffff'; 'none' for no exclusion.
    #[arg(long, default_value = "#000000")]
    exclude: String,
    /// Maximum CIELAB distance for the automatic colour choice.
    #[arg(long, default_value_t = 50.0)]
    dmax: f64,
    /// Element colouring.
    #[arg(long, default_value = "region", value_parser = ["region", "pixel"])]
    element_colour: String,
    /// Orientation used without strokes (right, down-right, down, ..., up-right).
    #[arg(long, default_value = "down")]
    default_direction: String,
    /// Which way a --sprite points as drawn.
    #[arg(long, default_value = "up")]
    sprite_direction: String,
    /// Seed of every random choice.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Output PNG.
    #[arg(long)]
    out: PathBuf,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StrokesFile {
    strokes: Vec<Stroke>,
}

/// Read a strokes JSON file, naming it (and the line/column) on error.
pub fn read_strokes(path: &Path) -> Result<Vec<Stroke>, String> {
    let text = super::read_file(path)?;
    let f: StrokesFile = serde_json::from_slice(&text).map_err(|e| {
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

fn enum_from<T: for<'de> Deserialize<'de>>(value: &str, flag: &str) -> Result<T, String> {
    serde_json::from_value(serde_json::Value::String(value.to_string()))
        .map_err(|e| format!("--{flag} '{value}': {e}"))
}

/// Turn the flags into [`PixelParams`].
fn params(a: &Args) -> Result<PixelParams, String> {
    let m = numbers::<2>(&a.margins, "margins")?;
    if m.iter().any(|v| v.fract() != 0.0) {
        return Err(format!(
            "--margins '{}': margins are whole pixels",
            a.margins
        ));
    }
    Ok(PixelParams {
        annotation_scale: a.annotation_scale,
        positions: enum_from(&a.positions, "positions")?,
        density: parse_density(&a.density)?,
        margins: [m[0] as i32, m[1] as i32],
        partial: a.partial,
        colour: enum_from(&a.colour, "colour")?,
        hsv: numbers::<3>(&a.hsv, "hsv")?,
        exclude: parse_colours(&a.exclude)?,
        d_max: a.dmax,
        element_colour: enum_from(&a.element_colour, "element-colour")?,
        default_direction: enum_from(&a.default_direction, "default-direction")?,
        sprite_direction: enum_from(&a.sprite_direction, "sprite-direction")?,
        seed: a.seed,
    })
}

pub fn run(a: Args) -> Result<(), String> {
    let params = params(&a)?;
    let source = super::read_image(&a.source)?;
    let mask = super::read_image(&a.mask)?;
    // Check here too, so each error can name the file it is about.
    inputs::check_source_and_mask(&source, &mask)
        .map_err(|e| format!("{} / {}: {e}", a.source.display(), a.mask.display()))?;
    let elements = match (&a.sheet, &a.sprite) {
        (Some(p), _) => {
            let img = super::read_image(p)?;
            pixel::ElementSheet::from_sheet(&img).map_err(|e| format!("{}: {e}", p.display()))?;
            Elements::Sheet(img)
        }
        (None, Some(p)) => {
            let img = super::read_image(p)?;
            pixel::ElementSheet::from_sprite(&img, params.sprite_direction)
                .map_err(|e| format!("{}: {e}", p.display()))?;
            Elements::Sprite(img)
        }
        (None, None) => return Err("give the element as --sheet FILE or --sprite FILE".into()),
    };
    let strokes = read_strokes(&a.strokes)?;
    orientation::check_strokes(source.width, source.height, &strokes)
        .map_err(|e| format!("{}: {e}", a.strokes.display()))?;
    let out = pixel::texture(
        PixelInputs {
            source,
            mask,
            elements,
            strokes,
        },
        params,
    )
    .map_err(|e| e.to_string())?;
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
