//! The Texture model classifier's choices, decided on a validation split
//! and never on the test set: `cargo run --example texture_validation --
//! TAG [INDEX_CONFIG_JSON|x] [PER_MODEL] [test]`.
//!
//! Renders the dataset (`PER_MODEL` bases per model, default 24, 128²,
//! two lights × four crops), holds out the bases `bench texture` holds
//! out (`build::split`, seed 7), learns the PCA filters from the rest and
//! caches every image's features in `target/texacc/TAG.bin` (reused when
//! present: TAG names the settings). Then, for each `kind:C` in
//! `VARIANTS` (default `plain:1`; kinds: `plain`, `chi2` (the index's χ²
//! map), `lin` (histograms without the square root), `pow25` (fourth
//! roots)), trains the one-vs-rest model classifier and prints its
//! accuracy on **validation**: a third of each model's training bases
//! (seed 3), trained on the other two thirds. With `test` it trains on all
//! training bases and scores the held-out bases instead: the figures
//! `bench texture` gives (first images, all images), to be run once,
//! after the choice. `PER=1` adds each model's right-out-of-N, `STD=1`
//! standardises the columns, `HALF=1` trains on the even bases only.
// A native experiment: wall-clock time is what it reports.
#![allow(clippy::disallowed_methods)]
use filigree::core::rng::Rng;
use filigree::texture::build::{self, BuildConfig, BuildStats};
use filigree::texture::dataset::DatasetConfig;
use filigree::texture::index::Index;
use filigree::texture::learn::svm::{chi2_map, OneVsRest};
use filigree::texture::models::MODELS;
use std::io::{Read, Write};
use std::time::Instant;

struct Row {
    model: u16,
    base: u32,
    light: u8,
    crop: u8,
    f: Vec<f32>,
}

fn load(path: &str) -> Option<(Vec<Row>, Vec<bool>)> {
    let mut b = Vec::new();
    std::fs::File::open(path).ok()?.read_to_end(&mut b).ok()?;
    let u = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let (n, dim) = (u(0) as usize, u(4) as usize);
    let mut o = 8;
    let mut rows = Vec::new();
    let mut held = Vec::new();
    for _ in 0..n {
        let model = u(o) as u16;
        let base = u(o + 4);
        let light = b[o + 8];
        let crop = b[o + 9];
        held.push(b[o + 10] == 1);
        o += 12;
        let f = (0..dim)
            .map(|k| f32::from_le_bytes(b[o + 4 * k..o + 4 * k + 4].try_into().unwrap()))
            .collect();
        o += 4 * dim;
        rows.push(Row {
            model,
            base,
            light,
            crop,
            f,
        });
    }
    Some((rows, held))
}

fn save(path: &str, rows: &[Row], held: &[bool]) {
    let mut b = Vec::new();
    b.extend((rows.len() as u32).to_le_bytes());
    b.extend((rows[0].f.len() as u32).to_le_bytes());
    for (r, h) in rows.iter().zip(held) {
        b.extend((r.model as u32).to_le_bytes());
        b.extend(r.base.to_le_bytes());
        b.extend([r.light, r.crop, *h as u8, 0]);
        for v in &r.f {
            b.extend(v.to_le_bytes());
        }
    }
    std::fs::File::create(path).unwrap().write_all(&b).unwrap();
}

fn compute(cfg: &BuildConfig) -> (Vec<Row>, Vec<bool>) {
    let mut stats = BuildStats::default();
    let t = Instant::now();
    let samples = build::labelled(&cfg.dataset, &[], &mut stats).unwrap();
    eprintln!(
        "dataset {} images in {:.0} s",
        samples.len(),
        t.elapsed().as_secs_f64()
    );
    let held = build::split(&samples, 7);
    let all = build::training(&samples, |_| true);
    let train: Vec<_> = (0..samples.len())
        .filter(|&i| !held[samples[i].0.base])
        .map(|i| all[i].clone())
        .collect();
    let t = Instant::now();
    let pcn = Index::train_pcn(&train, &cfg.index).unwrap();
    // The PCN features only (Index::features appends the global values).
    let dim = pcn.config.feature_len();
    let feats: Vec<Vec<f32>> = Index::features(&pcn, &all)
        .unwrap()
        .into_iter()
        .map(|f| f[..dim].to_vec())
        .collect();
    eprintln!(
        "features in {:.0} s, dim {}",
        t.elapsed().as_secs_f64(),
        feats[0].len()
    );
    let rows = samples
        .iter()
        .zip(feats)
        .map(|((s, _), f)| Row {
            model: s.model as u16,
            base: s.base as u32,
            light: s.light_index as u8,
            crop: s.crop.unwrap_or(0),
            f,
        })
        .collect();
    let h = samples.iter().map(|(s, _)| held[s.base]).collect();
    (rows, h)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let tag = &args[1];
    let per_model: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(24);
    let test = args.iter().any(|a| a == "test");
    let mut cfg = BuildConfig {
        dataset: DatasetConfig {
            per_model,
            size: 128,
            ..DatasetConfig::default()
        }
        .augmented(),
        ..BuildConfig::default()
    };
    if let Some(j) = args.get(2).filter(|s| s.starts_with('{')) {
        cfg.index = serde_json::from_str(j).unwrap();
    }
    let cfg = cfg.synced();
    std::fs::create_dir_all("target/texacc").unwrap();
    let path = format!("target/texacc/{tag}.bin");
    let (rows, held) = match load(&path) {
        Some(x) => x,
        None => {
            let x = compute(&cfg);
            save(&path, &x.0, &x.1);
            x
        }
    };
    // Validation: a third of each model's training bases (seed 3).
    let mut val_base = std::collections::HashSet::new();
    let mut rng = Rng::new(3);
    for m in 0..MODELS.len() as u16 {
        let mut bases: Vec<u32> = rows
            .iter()
            .zip(&held)
            .filter(|(r, h)| r.model == m && !**h)
            .map(|(r, _)| r.base)
            .collect();
        bases.sort_unstable();
        bases.dedup();
        rng.shuffle(&mut bases);
        for &b in bases.iter().take(bases.len() / 3) {
            val_base.insert(b);
        }
    }
    let half = std::env::var("HALF").is_ok();
    let (mut tr, ev): (Vec<usize>, Vec<usize>) = if test {
        (
            (0..rows.len()).filter(|&i| !held[i]).collect(),
            (0..rows.len()).filter(|&i| held[i]).collect(),
        )
    } else {
        (
            (0..rows.len())
                .filter(|&i| !held[i] && !val_base.contains(&rows[i].base))
                .collect(),
            (0..rows.len())
                .filter(|&i| !held[i] && val_base.contains(&rows[i].base))
                .collect(),
        )
    };
    if half {
        tr.retain(|&i| rows[i].base % 2 == 0);
    }
    eprintln!(
        "{} train, {} eval ({})",
        tr.len(),
        ev.len(),
        if test { "TEST" } else { "validation" }
    );
    let variants: Vec<String> = std::env::var("VARIANTS")
        .unwrap_or("plain:1".into())
        .split(',')
        .map(String::from)
        .collect();
    for v in variants {
        let (kind, c) = v.split_once(':').unwrap();
        let c: f64 = c.parse().unwrap();
        let map = |f: &[f32]| -> Vec<f32> {
            match kind {
                "plain" => f.to_vec(),
                "chi2" => chi2_map(f),
                "pow25" => f.iter().map(|x| x.sqrt()).collect(),
                "lin" => f.iter().map(|x| x * x).collect(),
                _ => panic!("{kind}"),
            }
        };
        let t = Instant::now();
        let mut xs: Vec<Vec<f32>> = tr.iter().map(|&i| map(&rows[i].f)).collect();
        let mut ys: Vec<Vec<f32>> = ev.iter().map(|&i| map(&rows[i].f)).collect();
        if std::env::var("STD").is_ok() {
            let d = xs[0].len();
            let n = xs.len() as f64;
            let mut mu = vec![0f64; d];
            let mut sd = vec![0f64; d];
            for x in &xs {
                for k in 0..d {
                    mu[k] += x[k] as f64 / n;
                }
            }
            for x in &xs {
                for k in 0..d {
                    sd[k] += (x[k] as f64 - mu[k]).powi(2) / n;
                }
            }
            for x in xs.iter_mut().chain(ys.iter_mut()) {
                for k in 0..d {
                    x[k] = ((x[k] as f64 - mu[k]) / (sd[k].sqrt() + 1e-3)) as f32;
                }
            }
        }
        let labels: Vec<u16> = tr.iter().map(|&i| rows[i].model).collect();
        let clf = OneVsRest::train(&xs, &labels, c);
        let mut right = 0;
        let mut first_right = 0;
        let mut first_n = 0;
        let mut per = vec![(0usize, 0usize); MODELS.len()];
        for (k, &i) in ev.iter().enumerate() {
            let ok = clf.predict(&ys[k]) == rows[i].model;
            right += ok as usize;
            per[rows[i].model as usize].1 += 1;
            per[rows[i].model as usize].0 += ok as usize;
            if rows[i].light == 0 && rows[i].crop == 0 {
                first_n += 1;
                first_right += ok as usize;
            }
        }
        println!(
            "{tag} {v}: all {:.1}% ({right}/{}), first {:.1}% ({first_right}/{first_n}) [{:.0} s] {}",
            100.0 * right as f64 / ev.len() as f64,
            ev.len(),
            100.0 * first_right as f64 / first_n.max(1) as f64,
            t.elapsed().as_secs_f64(),
            if std::env::var("PER").is_ok() {
                per.iter()
                    .enumerate()
                    .map(|(m, (a, b))| format!("{}={a}/{b}", MODELS[m].id))
                    .collect::<Vec<_>>()
                    .join(" ")
            } else {
                String::new()
            }
        );
    }
}
