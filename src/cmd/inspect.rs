use filigree::inspect::{inspect, InspectOptions};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Image file (PNG, JPEG, WebP, GIF, BMP).
    image: PathBuf,
    /// Print JSON instead of text.
    #[arg(long)]
    json: bool,
    /// RGB distance under which colours are merged into one cluster.
    #[arg(long, default_value_t = 24.0)]
    tolerance: f64,
}

pub fn run(a: Args) -> Result<(), String> {
    let bytes = super::read_file(&a.image)?;
    let opts = InspectOptions {
        tolerance: a.tolerance,
        ..Default::default()
    };
    let r = inspect(&bytes, &opts).map_err(|e| format!("{}: {e}", a.image.display()))?;
    if a.json {
        println!(
            "{}",
            serde_json::to_string_pretty(&r).map_err(|e| e.to_string())?
        );
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
    println!("clusters (tolerance {}):", a.tolerance);
    for c in r.clusters.iter().take(32) {
        let [red, g, b, al] = c.rgba;
        println!(
            "  #{red:02x}{g:02x}{b:02x}{al:02x}  {:>8} px  ({} colours)",
            c.count, c.members
        );
    }
    Ok(())
}
