//! Stage timings of Pixel on a big source with a full mask, the worst case the
//! size limits allow: `cargo run --release --example pixel_big -- 4096`.
//! The fish is tiled over the whole square; its strokes are scaled up, the
//! mask is everything, elements are the fish scales. Prints one JSON line with
//! seconds per stage (wall and CPU) and the longest single job step (wall).
// A native benchmark: wall-clock time is what it measures (never built for wasm).
#![allow(clippy::disallowed_methods)]
use filigree::core::job::{Job, Step};
use filigree::pixel::{Elements, PixelInputs, PixelJob, PixelParams, Stage};
use filigree::raster::{decode, Limits, Rgba8Image};
use std::time::Instant;

/// CPU seconds (user + system) of this process so far, from /proc (Linux;
/// 0 elsewhere). On a busy machine wall time says little, CPU time does.
fn cpu() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the parenthesised command name; utime and stime are 14 and 15.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11).and_then(|v| v.parse().ok()).unwrap_or(0.0)
        + f.get(12).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    ticks / 100.0
}

fn main() {
    let side: u32 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(4096);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/pixel");
    let img = |n: &str| decode(&std::fs::read(dir.join(n)).unwrap(), Limits::default()).unwrap();
    let fish = img("fish.png");
    let mut source = Rgba8Image::new(side, side);
    for y in 0..side {
        for x in 0..side {
            let p = fish.get(x % fish.width, y % fish.height);
            // Transparent background of the fish becomes a flat sea colour.
            source.put(x, y, if p[3] == 0 { [30, 60, 120, 255] } else { p });
        }
    }
    let mut mask = Rgba8Image::new(side, side);
    mask.data.fill(255);
    #[derive(serde::Deserialize)]
    struct Strokes {
        strokes: Vec<filigree::pixel::Stroke>,
    }
    let s: Strokes =
        serde_json::from_slice(&std::fs::read(dir.join("fish_strokes.json")).unwrap()).unwrap();
    let k = side as f32 / fish.width as f32;
    let strokes = s
        .strokes
        .iter()
        .map(|st| st.iter().map(|p| [p[0] * k, p[1] * k]).collect())
        .collect();
    let inputs = PixelInputs {
        source,
        mask,
        elements: Elements::Sheet(img("fish_scale.png")),
        strokes,
    };
    let params = PixelParams {
        positions: filigree::pixel::PositionStrategy::Random,
        seed: 7,
        ..PixelParams::default()
    };
    let t_all = Instant::now();
    let c_all = cpu();
    let t = Instant::now();
    let mut job = PixelJob::new(inputs, params).unwrap();
    let setup = t.elapsed().as_secs_f64();
    let setup_cpu = cpu() - c_all;
    let mut per = [0.0f64; 5];
    let mut per_cpu = [0.0f64; 5];
    let mut longest = [0.0f64; 5];
    let mut steps = [0usize; 5];
    let out = loop {
        let slot = match job.stage() {
            Stage::Positions => 0,
            Stage::ColourMap => 1,
            Stage::Orientation => 2,
            Stage::Placement => 3,
            Stage::Done => 4,
        };
        let t = Instant::now();
        let c = cpu();
        let step = job.step().unwrap();
        let dt = t.elapsed().as_secs_f64();
        per_cpu[slot] += cpu() - c;
        per[slot] += dt;
        longest[slot] = longest[slot].max(dt);
        steps[slot] += 1;
        if let Step::Done(out) = step {
            break out;
        }
    };
    let total = t_all.elapsed().as_secs_f64();
    let total_cpu = cpu() - c_all;
    println!(
        "{}",
        serde_json::json!({
            "side": side,
            "placed": out.stats.placed,
            "positions": out.stats.positions,
            "solve": out.stats.solve,
            "colour_map": out.stats.colour_map_used.name(),
            "seconds": {"setup": setup, "positions": per[0], "colour_map": per[1],
                        "orientation": per[2], "placement": per[3] + per[4], "total": total},
            "cpu_seconds": {"setup": setup_cpu, "positions": per_cpu[0], "colour_map": per_cpu[1],
                        "orientation": per_cpu[2], "placement": per_cpu[3] + per_cpu[4], "total": total_cpu},
            "longest_step": {"positions": longest[0], "colour_map": longest[1],
                             "orientation": longest[2], "placement": longest[3] + longest[4]},
            "steps": steps,
        })
    );
}
