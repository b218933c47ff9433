//! A contact sheet of one model's dataset grid, as the classifier sees it:
//! `cargo run --release --example texture_grid_sheet -- MODEL OUT.png [PER_MODEL] [full]`.
//!
//! Every base of the shipped dataset plan (`PER_MODEL` bases per model,
//! default 24) rendered at 256² under the main light; each tile is the
//! base's first 128² crop (what a training image is), or with `full` the
//! whole 256² render. Tiles in grid order (the first parameter varies
//! fastest), six to a row; the parameters are printed in the same order.
// An inspection tool: index loops over tiles read plainest.
#![allow(clippy::needless_range_loop)]
use filigree::texture::dataset::{plan, render_base, DatasetConfig};
use filigree::texture::models::MODELS;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let id = &args[1];
    let out = &args[2];
    let per: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(24);
    let full = args.iter().any(|a| a == "full");
    let cfg = DatasetConfig {
        per_model: per,
        size: 128,
        ..DatasetConfig::default()
    }
    .augmented();
    let m = MODELS.iter().position(|m| m.id == id).expect("model id");
    let specs: Vec<_> = plan(&cfg)
        .unwrap()
        .into_iter()
        .filter(|s| s.model == m)
        .collect();
    let t = if full { 256 } else { 128 };
    let cols = 6;
    let rows = specs.len().div_ceil(cols);
    let (w, h) = (cols * (t + 4), rows * (t + 4));
    let mut px = vec![255u8; w * h];
    for (k, s) in specs.iter().enumerate() {
        let names: Vec<String> = MODELS[m]
            .params
            .iter()
            .zip(&s.params)
            .map(|(p, v)| format!("{}={v:.3}", p.name))
            .collect();
        println!("{k:2}: {}", names.join(" "));
        let tile = if full {
            let mut c = cfg.clone();
            c.crops = false;
            c.size = 256;
            c.lights.truncate(1);
            render_base(&c, s).unwrap().remove(0).image
        } else {
            render_base(&cfg, s).unwrap().remove(0).image
        };
        let (ox, oy) = ((k % cols) * (t + 4), (k / cols) * (t + 4));
        for y in 0..t {
            for x in 0..t {
                px[(oy + y) * w + ox + x] = (tile.at(x, y).clamp(0.0, 1.0) * 255.0).round() as u8;
            }
        }
    }
    let file = std::fs::File::create(out).unwrap();
    let mut enc = png::Encoder::new(std::io::BufWriter::new(file), w as u32, h as u32);
    enc.set_color(png::ColorType::Grayscale);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header().unwrap().write_image_data(&px).unwrap();
}
