//! Model accuracy of several index files on one common set of textures
//! that none of them trained on: `INDEXES=a.bin,b.bin cargo run --release
//! --example texture_compare`. Every model gets `PER` (default 10)
//! parameter points drawn uniformly inside its dataset ranges (seed
//! `SEED`, default 1000), each rendered at 256² with its own seed and read
//! as the app reads a drop. Held-out splits differ between datasets of
//! different sizes; this set does not, so it compares indexes directly.
#![allow(clippy::disallowed_methods)]
use filigree::core::rng::Rng;
use filigree::texture::api;
use filigree::texture::build::BuildConfig;
use filigree::texture::dataset::random_point;
use filigree::texture::models::{self, MODELS};

fn main() {
    let paths: Vec<String> = std::env::var("INDEXES")
        .unwrap_or("assets/texture-index.bin".into())
        .split(',')
        .map(String::from)
        .collect();
    let per: usize = std::env::var("PER").map_or(10, |v| v.parse().unwrap());
    let seed: u64 = std::env::var("SEED").map_or(1000, |v| v.parse().unwrap());
    let indexes: Vec<_> = paths
        .iter()
        .map(|p| api::parse_index(&std::fs::read(p).unwrap()).unwrap())
        .collect();
    let side = 2 * BuildConfig::default().dataset.size;
    let mut rng = Rng::new(seed);
    let mut right = vec![0usize; indexes.len()];
    let mut by_model = vec![vec![0usize; MODELS.len()]; indexes.len()];
    let mut n = 0;
    for (mi, m) in MODELS.iter().enumerate() {
        for _ in 0..per {
            let params = random_point(m, &mut rng);
            let img = models::render(m, &params, rng.next_u64() >> 11, side).unwrap();
            for (k, index) in indexes.iter().enumerate() {
                let ok = index.analyse(&img).unwrap().model as usize == mi;
                right[k] += ok as usize;
                by_model[k][mi] += ok as usize;
            }
            n += 1;
        }
    }
    for (k, p) in paths.iter().enumerate() {
        println!(
            "{p}: {} of {n} ({:.1}%)",
            right[k],
            right[k] as f64 * 100.0 / n as f64
        );
        let per_model: Vec<String> = MODELS
            .iter()
            .zip(&by_model[k])
            .map(|(m, r)| format!("{} {r}", m.id))
            .collect();
        println!("  {}", per_model.join(", "));
    }
}
