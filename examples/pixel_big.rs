//! Stage timings of Pixel on a big source with a full mask, the worst case the
//! size limits allow: `cargo run --release --example pixel_big -- 4096`.
//! The fish is tiled over the whole square; its strokes are scaled up, the
//! mask is everything, elements are the fish scales. Prints one JSON line with
//! seconds per stage and the longest single job step.
use filigree::core::job::{Job, Step};
use filigree::pixel::{Elements, PixelInputs, PixelJob, PixelParams, Stage};
use filigree::raster::{decode, Limits, Rgba8Image};
use std::time::Instant;

fn main() {
    let side: u32 = std::env::args()
        .nth(1)
        .and_then(|s| s.parse().ok())
        .unwrap_or(4096);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/pixel");
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
    let t = Instant::now();
    let mut job = PixelJob::new(inputs, params).unwrap();
    let setup = t.elapsed().as_secs_f64();
    let mut per = [0.0f64; 5];
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
        let step = job.step().unwrap();
        let dt = t.elapsed().as_secs_f64();
        per[slot] += dt;
        longest[slot] = longest[slot].max(dt);
        steps[slot] += 1;
        if let Step::Done(out) = step {
            break out;
        }
    };
    let total = t_all.elapsed().as_secs_f64();
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
            "longest_step": {"positions": longest[0], "colour_map": longest[1],
                             "orientation": longest[2], "placement": longest[3] + longest[4]},
            "steps": steps,
        })
    );
}
