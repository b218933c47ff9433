//! `filigree inspect`: flags → the browser's `inspect` request → the same core job.
use super::{drive, explain, print_request, put, request, Origins};
use filigree::api::inspect::{start_inspect, InspectRequest};
use serde_json::{Map, Value};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Image file (PNG, JPEG, WebP, GIF, BMP).
    image: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// RGB distance under which colours are merged into one cluster, 0..=442 (default 24).
    #[arg(long, allow_hyphen_values = true)]
    tolerance: Option<f64>,
    /// Print the request (as the browser would send it) and exit.
    #[arg(long, hide = true)]
    print_request: bool,
}

pub fn run(a: Args) -> Result<(), String> {
    let origins: Origins = vec![("bytes", a.image.display().to_string())];
    let mut o = Map::new();
    put(&mut o, "tolerance", "--tolerance", a.tolerance)?;
    let mut req: InspectRequest = request("inspect", Value::Object(o), &origins)?;
    req.bytes = super::read_file(&a.image)?;
    if a.print_request {
        return print_request(&req);
    }
    let tolerance = req.tolerance;
    let job = start_inspect(req).map_err(|e| explain(e, &origins))?;
    let r = drive(job, true, &origins)?.info;
    if a.json {
        super::print_json(&r)?;
        return Ok(());
    }
    println!(
        "{}: {}×{}, {} colours, {} translucent pixels",
        a.image.display(),
        r.width,
        r.height,
        r.colour_count,
        r.translucent_pixels
    );
    println!("clusters (tolerance {tolerance}):");
    for c in r.clusters.iter().take(32) {
        let [red, g, b, al] = c.rgba;
        println!(
            "  #{red:02x}{g:02x}{b:02x}{al:02x}  {:>8} px  ({} colours)",
            c.count, c.members
        );
    }
    Ok(())
}
