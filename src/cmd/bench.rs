//! `filigree bench <tool>`: benchmarks that print one JSON object.
use clap::Subcommand;
use filigree::inspect::{inspect, InspectOptions};
use filigree::raster::{encode_png, Rgba8Image};
use serde_json::json;
use std::time::Instant;

#[derive(Subcommand)]
pub enum Which {
    /// Decode + palette + thumbnail of a generated 1024² PNG.
    Inspect {
        #[arg(long, default_value_t = 10)]
        repeats: usize,
        /// Accepted for symmetry with other benches; output is always JSON.
        #[arg(long)]
        json: bool,
    },
    /// Fit every shipped generator to targets drawn from random true
    /// parameters; report parameter MSE, loss and time, the same fits with
    /// image-space L2 from the same initialisation, and evaluations per second.
    Fit {
        /// Accepted for symmetry with other benches; output is always JSON.
        #[arg(long)]
        json: bool,
        /// Quick budget instead of the paper's.
        #[arg(long)]
        quick: bool,
        /// Random targets per generator.
        #[arg(long, default_value_t = 1)]
        seeds: u64,
        /// Comma-separated generator names (default: all).
        #[arg(long)]
        only: Option<String>,
        /// Threads for the GA batches (default: all cores). Throughput figures are always one core.
        #[arg(long)]
        threads: Option<usize>,
        /// Skip the fits; only measure evaluations per second.
        #[arg(long)]
        speed_only: bool,
    },
}

pub fn run(w: Which) -> Result<(), String> {
    match w {
        Which::Fit { quick, seeds, only, threads, speed_only, .. } => {
            super::fit_bench::run(quick, seeds, only.as_deref(), threads, speed_only)
        }
        Which::Inspect { repeats, .. } => {
            let png = test_png(1024);
            let opts = InspectOptions::default();
            let mut secs = vec![];
            for _ in 0..repeats.max(1) {
                let t = Instant::now();
                inspect(&png, &opts).map_err(|e| e.to_string())?;
                secs.push(t.elapsed().as_secs_f64());
            }
            let (min, median) = super::min_median(secs);
            let out = json!({"bench": "inspect", "image": "1024x1024 png", "png_bytes": png.len(), "seconds": {"min": min, "median": median}});
            println!("{out}");
            Ok(())
        }
    }
}

/// A deterministic 1024² test picture with a few hundred colours (gradient
/// bands), the same one the browser e2e test generates for its timing.
pub fn test_png(side: u32) -> Vec<u8> {
    let mut img = Rgba8Image::new(side, side);
    for y in 0..side {
        for x in 0..side {
            img.put(x, y, [(x / 4) as u8, (y / 4) as u8, ((x ^ y) & 0xC0) as u8, 255]);
        }
    }
    encode_png(&img).expect("encoding a valid image")
}
