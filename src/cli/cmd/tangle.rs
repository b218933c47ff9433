//! `filigree tangle`: flags → the browser's `tangle` request → the same
//! core job. Defaults come from the request, not from here.
use super::{drive, explain, print_request, put, request, Origins};
use filigree::tangle::api::{start_tangle, ExportFormat, StartRequest, TangleRequest};
use serde_json::{Map, Value};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Grammar file (rules `op(params) : tag -> [tags]`, see assets/tangle/).
    #[arg(long)]
    grammar: PathBuf,
    /// Start from the shapes an SVG file draws: nested shapes become holes,
    /// overlapping ones one shape, white fills cut holes; scaled to fit the
    /// grammar's start shapes (800×600 when it has none), whatever the file's units.
    #[arg(long, value_name = "SVG", conflicts_with_all = ["text", "rect"])]
    start: Option<PathBuf>,
    /// Start from the letter outlines of a typed word.
    #[arg(long, value_name = "WORD", conflicts_with = "rect")]
    text: Option<String>,
    /// Capital height of --text letters, drawing units (default 400).
    #[arg(long)]
    text_height: Option<f64>,
    /// Start from a rectangle WIDTHxHEIGHT (drawing units) instead of the grammar's start.
    #[arg(long, value_name = "WxH")]
    rect: Option<String>,
    /// Random seed (rule choices, placement, wobble).
    #[arg(long)]
    seed: Option<u64>,
    /// Step budget.
    #[arg(long)]
    steps: Option<usize>,
    /// Shape budget (live shapes).
    #[arg(long)]
    max_shapes: Option<usize>,
    /// Hand-drawn wobble amplitude in drawing units (0: straight lines).
    #[arg(long)]
    wobble: Option<f64>,
    /// Pen width in drawing units.
    #[arg(long)]
    stroke_width: Option<f64>,
    /// PNG width in pixels.
    #[arg(long)]
    png_width: Option<u32>,
    /// Output: .svg or .png.
    #[arg(long)]
    out: PathBuf,
    /// Print a JSON summary (steps, shapes, vertices) instead of text.
    #[arg(long)]
    json: bool,
    /// Print the request (as the browser would send it) and exit.
    #[arg(long, hide = true)]
    print_request: bool,
}

pub fn run(a: Args) -> Result<(), String> {
    super::out_path(&a.out, &["svg", "png"])?;
    let origins: Origins = vec![
        ("grammar", a.grammar.display().to_string()),
        ("max_steps", "--steps".into()),
        ("start", "--rect".into()),
        (
            "start.svg",
            a.start
                .as_ref()
                .map_or("--start".into(), |p| p.display().to_string()),
        ),
        ("start.text", "--text".into()),
    ];
    let mut o = Map::new();
    put(&mut o, "seed", "--seed", a.seed)?;
    put(&mut o, "max_steps", "--steps", a.steps)?;
    put(&mut o, "max_shapes", "--max-shapes", a.max_shapes)?;
    put(&mut o, "wobble", "--wobble", a.wobble)?;
    put(&mut o, "stroke_width", "--stroke-width", a.stroke_width)?;
    put(&mut o, "png_width", "--png-width", a.png_width)?;
    let mut req: TangleRequest = request("tangle", Value::Object(o), &origins)?;
    let text = super::read_file(&a.grammar)?;
    req.grammar = String::from_utf8(text)
        .map_err(|_| format!("{}: the grammar is not UTF-8 text", a.grammar.display()))?;
    if let Some(path) = &a.start {
        let svg = String::from_utf8(super::read_file(path)?)
            .map_err(|_| format!("{}: the SVG file is not UTF-8 text", path.display()))?;
        req.start = Some(StartRequest::Svg { svg });
    }
    if let Some(text) = &a.text {
        req.start = Some(StartRequest::Text {
            text: text.clone(),
            height: a
                .text_height
                .unwrap_or(filigree::tangle::api::LETTER_HEIGHT),
        });
    }
    if let Some(r) = &a.rect {
        let (w, h) = r
            .split_once(['x', 'X', '×'])
            .and_then(|(w, h)| Some((w.trim().parse().ok()?, h.trim().parse().ok()?)))
            .ok_or_else(|| format!("--rect: '{r}' is not WIDTHxHEIGHT, e.g. 800x600"))?;
        req.start = Some(StartRequest::Rect {
            width: w,
            height: h,
        });
    }
    let ext = a
        .out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    req.export = match ext.as_deref() {
        Some("svg") => ExportFormat::Svg,
        Some("png") => ExportFormat::Png,
        _ => {
            return Err(format!(
                "--out: '{}' must end in .svg or .png",
                a.out.display()
            ))
        }
    };
    if a.print_request {
        return print_request(&req);
    }
    let job = start_tangle(req).map_err(|e| explain(e, &origins))?;
    let r = drive(job, a.json, &origins)?;
    let bytes = match (r.svg, r.png) {
        (Some(s), _) => s.into_bytes(),
        (_, Some(p)) => p,
        _ => unreachable!("an export was asked for"),
    };
    std::fs::write(&a.out, bytes).map_err(|e| format!("{}: {e}", a.out.display()))?;
    if let Some(m) = &r.stopped {
        eprintln!("warning: {m}");
    }
    if a.json {
        println!(
            "{}",
            serde_json::to_string(&r.stats).map_err(|e| e.to_string())?
        );
    } else {
        println!(
            "{}: {} steps, {} shapes, {} vertices",
            a.out.display(),
            r.stats.steps,
            r.stats.shapes,
            r.stats.vertices
        );
    }
    Ok(())
}
