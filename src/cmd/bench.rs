//! `filigree bench <tool>`: benchmarks that print one JSON object.
use clap::Subcommand;
use filigree::inspect::{inspect, InspectOptions};
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
}

pub fn run(w: Which) -> Result<(), String> {
    match w {
        Which::Inspect { repeats, .. } => {
            let png = TEST_PNG_1024;
            let opts = InspectOptions::default();
            let mut secs = vec![];
            for _ in 0..repeats.max(1) {
                let t = Instant::now();
                inspect(png, &opts).map_err(|e| e.to_string())?;
                secs.push(t.elapsed().as_secs_f64());
            }
            let (min, median) = super::min_median(secs);
            let out = json!({"bench": "inspect", "image": "1024x1024 png", "png_bytes": png.len(), "seconds": {"min": min, "median": median}});
            println!("{out}");
            Ok(())
        }
    }
}

/// A 1024² PNG with 65,536 colours (gradients), the same file the browser
/// test `tests/e2e/perf.test.mjs` inspects in the worker, so the two timings compare.
pub const TEST_PNG_1024: &[u8] = include_bytes!("../../tests/fixtures/gradient-1024.png");
