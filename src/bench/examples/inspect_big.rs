//! Inspect a big image with many colours, the worst case for palette
//! clustering. `cargo run --release --example inspect_big -- make 4096 /tmp/all.png`
//! writes a side² PNG whose pixels all differ (every 24-bit colour once at
//! 4096²); `... -- /tmp/all.png 24` inspects it with tolerance 24 and prints
//! one JSON line (CPU seconds, colours, clusters). Run under
//! `/usr/bin/time -v` for the peak memory.
use filigree::inspect::{inspect, InspectOptions};
use filigree::raster::{encode_png, Rgba8Image};

fn cpu() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = f.get(11).and_then(|v| v.parse().ok()).unwrap_or(0.0)
        + f.get(12).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    ticks / 100.0
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("make") {
        let side: u32 = args[1].parse().expect("side");
        let mut img = Rgba8Image::new(side, side);
        for i in 0..side * side {
            // A scrambled order so neighbouring pixels differ a lot.
            let v = i.wrapping_mul(2_654_435_761) & 0xff_ffff;
            let v = if side == 4096 { v } else { i };
            img.put(
                i % side,
                i / side,
                [(v >> 16) as u8, (v >> 8) as u8, v as u8, 255],
            );
        }
        std::fs::write(&args[2], encode_png(&img).expect("png")).expect("write");
        return;
    }
    let bytes = std::fs::read(&args[0]).expect("read");
    let tolerance: f64 = args.get(1).map_or(24.0, |t| t.parse().expect("tolerance"));
    let opts = InspectOptions {
        tolerance,
        ..Default::default()
    };
    let c = cpu();
    let r = inspect(&bytes, &opts).expect("inspect");
    println!(
        "{}",
        serde_json::json!({
            "size": [r.width, r.height], "tolerance": tolerance,
            "colours": r.colour_count, "clusters": r.cluster_count,
            "cpu_seconds": cpu() - c,
        })
    );
}
