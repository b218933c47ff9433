//! How the slider retrieval's shortlist ([`Index::retrieve_among`]) trades
//! the paper's nearest neighbour in the space for slider response:
//! `INDEX=path cargo run --release --example texture_rerank`. The examples
//! are every model at its defaults, seeds 21–23 (neither the index's
//! samples nor the test suite's seeds 1, 11 and 12), analysed as the app
//! analyses a dropped 256² render. For each shortlist length (`K`, list):
//! - for every example and every scale, that slider moved to 9 (and to 1):
//!   how often the retrieved sample's scale rose (fell) and how often it
//!   moved the wrong way;
//! - the example's own predicted scales: the mean cosine of requested and
//!   retrieved scales, and how often the retrieved sample is of the
//!   predicted model;
//! - (once) how many of the examples are predicted as their model;
//! - the mean distance in the space from the requested point to the
//!   retrieved sample, in units of the paper's nearest neighbour's.
#![allow(clippy::disallowed_methods)]
use filigree::texture::api;
use filigree::texture::build::BuildConfig;
use filigree::texture::models::{self, MODELS};

fn main() {
    let path = std::env::var("INDEX").unwrap_or("assets/texture-index.bin".into());
    let index = api::parse_index(&std::fs::read(&path).unwrap()).unwrap();
    let ks: Vec<usize> = std::env::var("K")
        .unwrap_or("1,2,4,8,16,32".into())
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect();
    let side = 2 * BuildConfig::default().dataset.size;
    let mut examples = Vec::new();
    let mut right = 0;
    for (mi, m) in MODELS.iter().enumerate() {
        for seed in [21, 22, 23] {
            let img = models::render(m, &m.defaults(), seed, side).unwrap();
            let a = index.analyse(&img).unwrap();
            right += (a.model as usize == mi) as usize;
            if a.model as usize != mi {
                println!("{} seed {seed}: {}", m.id, MODELS[a.model as usize].id);
            }
            examples.push(a);
        }
    }
    let n = examples.len();
    println!("defaults recognised: {right} of {n}");
    let dist = |p: [f32; 3], i: usize| {
        let c = index.samples[i].coords;
        (0..3)
            .map(|a| (c[a] as f64 - p[a] as f64).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    println!(
        "index {path}: {n} examples, {} samples",
        index.samples.len()
    );
    println!("K | up: rose/fell | down: fell/rose | own: cosine, same model | space distance ×NN");
    for &k in &ks {
        let (mut up_ok, mut up_bad, mut down_ok, mut down_bad) = (0, 0, 0, 0);
        let (mut cos, mut same, mut ratio) = (0.0, 0, 0.0);
        // Per scale: rose when moved to 9, could rise (was below 9).
        let mut per = [(0, 0); 12];
        for a in &examples {
            let own = a.scales.map(|s| s as f32);
            let r = index.retrieve_among(&own, None, k).unwrap();
            let nn = index.retrieve_among(&own, None, 1).unwrap();
            cos += r.cosine;
            same += (index.samples[r.sample].model == a.model) as usize;
            ratio += dist(r.point, r.sample) / dist(nn.point, nn.sample).max(1e-9);
            let before = index.samples[r.sample].scales;
            for s in 0..12 {
                for (to, ok, bad) in [
                    (9.0, &mut up_ok, &mut up_bad),
                    (1.0, &mut down_ok, &mut down_bad),
                ] {
                    let mut req = own;
                    req[s] = to;
                    let after =
                        index.samples[index.retrieve_among(&req, None, k).unwrap().sample].scales;
                    let (b, a2) = (before[s] as i32, after[s] as i32);
                    let dir = if to > 5.0 { a2 - b } else { b - a2 };
                    *ok += (dir > 0) as usize;
                    *bad += (dir < 0) as usize;
                    if to > 5.0 {
                        per[s].0 += (dir > 0) as usize;
                        per[s].1 += (b < 9) as usize;
                    }
                }
            }
        }
        let t = (n * 12) as f64 / 100.0;
        println!(
            "{k} | {:.1}% / {:.1}% | {:.1}% / {:.1}% | {:.3}, {:.1}% | {:.2}",
            up_ok as f64 / t,
            up_bad as f64 / t,
            down_ok as f64 / t,
            down_bad as f64 / t,
            cos / n as f64,
            same as f64 * 100.0 / n as f64,
            ratio / n as f64
        );
        let per: Vec<String> = per.iter().map(|(r, c)| format!("{r}/{c}")).collect();
        println!("  to 9, rose / was below 9, by scale: {}", per.join(" "));
    }
}
