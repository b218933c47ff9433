//! The Texture scale classifiers' choices, decided on a validation split
//! and never on the test set: `cargo run --release --example
//! texture_scales -- TAG [PER_MODEL]`, with `VARIANTS=kind:C,...`.
//!
//! Renders the index's dataset (default settings, `PER_MODEL` bases per
//! model), holds out the bases `bench texture` holds out
//! (`build::split`, seed 7) and never reads them. The features (PCN-2
//! filters learnt from the training bases, then the global values) and
//! every image's twelve labels are cached in `target/texacc/TAG.scales`.
//! Validation: a third of each model's training bases (seed 3), the
//! classifiers trained on the other two thirds.
//!
//! Kinds: `pcn` (the PCN features, as the index's scale classifiers
//! read them), `pcng` (the PCN features, then the standardised global
//! values), `chi2g` (the model classifier's row: the χ² map of the PCN
//! features, then the standardised global values). Prints, per variant,
//! the mean over the twelve scales of exact and within-one accuracy on
//! the validation bases' first images and on all their images.
// A native experiment: wall-clock time is what it reports.
#![allow(clippy::disallowed_methods)]
use filigree::core::rng::Rng;
use filigree::texture::build::{self, BuildConfig, BuildStats};
use filigree::texture::dataset::DatasetConfig;
use filigree::texture::index::{GlobalScaler, Index};
use filigree::texture::learn::svm::OneVsRest;
use filigree::texture::models::MODELS;
use filigree::texture::scales::ScaleQuantiles;
use std::io::{Read, Write};
use std::time::Instant;

struct Row {
    model: u16,
    base: u32,
    first: bool,
    held: bool,
    labels: [u8; 12],
    f: Vec<f32>,
}

fn load(path: &str) -> Option<(usize, Vec<Row>)> {
    let mut b = Vec::new();
    std::fs::File::open(path).ok()?.read_to_end(&mut b).ok()?;
    let u = |o: usize| u32::from_le_bytes(b[o..o + 4].try_into().unwrap());
    let (n, len, dim) = (u(0) as usize, u(4) as usize, u(8) as usize);
    let mut o = 12;
    let mut rows = Vec::new();
    for _ in 0..n {
        let model = u(o) as u16;
        let base = u(o + 4);
        let first = b[o + 8] == 1;
        let held = b[o + 9] == 1;
        let labels: [u8; 12] = b[o + 12..o + 24].try_into().unwrap();
        o += 24;
        let f = (0..len)
            .map(|k| f32::from_le_bytes(b[o + 4 * k..o + 4 * k + 4].try_into().unwrap()))
            .collect();
        o += 4 * len;
        rows.push(Row {
            model,
            base,
            first,
            held,
            labels,
            f,
        });
    }
    Some((dim, rows))
}

fn save(path: &str, dim: usize, rows: &[Row]) {
    let mut b = Vec::new();
    b.extend((rows.len() as u32).to_le_bytes());
    b.extend((rows[0].f.len() as u32).to_le_bytes());
    b.extend((dim as u32).to_le_bytes());
    for r in rows {
        b.extend((r.model as u32).to_le_bytes());
        b.extend(r.base.to_le_bytes());
        b.extend([r.first as u8, r.held as u8, 0, 0]);
        b.extend(r.labels);
        for v in &r.f {
            b.extend(v.to_le_bytes());
        }
    }
    std::fs::File::create(path).unwrap().write_all(&b).unwrap();
}

fn compute(cfg: &BuildConfig) -> (usize, Vec<Row>) {
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
    let dim = pcn.config.feature_len();
    let feats = Index::features(&pcn, &all).unwrap();
    eprintln!("features in {:.0} s", t.elapsed().as_secs_f64());
    let rows = samples
        .iter()
        .zip(all)
        .zip(feats)
        .map(|(((s, l), t), f)| Row {
            model: s.model as u16,
            base: s.base as u32,
            first: t.base,
            held: held[s.base],
            labels: *l,
            f,
        })
        .collect();
    (dim, rows)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let tag = &args[1];
    let per_model: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(24);
    let cfg = BuildConfig {
        dataset: DatasetConfig {
            per_model,
            ..BuildConfig::default().dataset
        },
        ..BuildConfig::default()
    }
    .synced();
    std::fs::create_dir_all("target/texacc").unwrap();
    let path = format!("target/texacc/{tag}.scales");
    let (dim, rows) = match load(&path) {
        Some(x) => x,
        None => {
            let x = compute(&cfg);
            save(&path, x.0, &x.1);
            x
        }
    };
    // Validation: a third of each model's training bases (seed 3).
    let mut val_base = std::collections::HashSet::new();
    let mut rng = Rng::new(3);
    for m in 0..MODELS.len() as u16 {
        let mut bases: Vec<u32> = rows
            .iter()
            .filter(|r| r.model == m && !r.held)
            .map(|r| r.base)
            .collect();
        bases.sort_unstable();
        bases.dedup();
        rng.shuffle(&mut bases);
        for &b in bases.iter().take(bases.len() / 3) {
            val_base.insert(b);
        }
    }
    let tr: Vec<&Row> = rows
        .iter()
        .filter(|r| !r.held && !val_base.contains(&r.base))
        .collect();
    let ev: Vec<&Row> = rows
        .iter()
        .filter(|r| !r.held && val_base.contains(&r.base))
        .collect();
    eprintln!("{} train, {} validation images", tr.len(), ev.len());
    let train_f: Vec<Vec<f32>> = tr.iter().map(|r| r.f.clone()).collect();
    let gw: f64 = std::env::var("GW")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    let scaler = GlobalScaler::fit(&train_f, dim, gw);
    // The raw scale measures are the first twelve global values.
    let raw = |f: &[f32]| -> [f64; 12] { std::array::from_fn(|k| f[dim + k] as f64) };
    let quantiles = ScaleQuantiles::fit(&tr.iter().map(|r| raw(&r.f)).collect::<Vec<_>>()).unwrap();
    let tw: f32 = std::env::var("TW")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(1.0);
    // Each measure's position among the cut points (0–8, piecewise
    // linear), as eight ramps clamp(q − j, 0, 1).
    let ramps = |f: &[f32]| -> Vec<f32> {
        let r = raw(f);
        let mut out = Vec::new();
        for (k, e) in quantiles.edges.iter().enumerate() {
            let x = r[k];
            let q = if x <= e[0] {
                0.0
            } else if x >= e[7] {
                8.0
            } else {
                let j = (0..7).find(|&j| x <= e[j + 1]).unwrap();
                j as f64 + (x - e[j]) / (e[j + 1] - e[j]).max(1e-12)
            };
            for j in 0..8 {
                out.push(tw * (q - j as f64).clamp(0.0, 1.0) as f32);
            }
        }
        out
    };
    {
        let (mut e1, mut n1, mut c1) = (0usize, 0usize, 0usize);
        for r in ev.iter().filter(|r| r.first) {
            let l = quantiles.to_likert(&raw(&r.f));
            for (got, want) in l.iter().zip(&r.labels) {
                c1 += 1;
                e1 += (got == want) as usize;
                n1 += (got.abs_diff(*want) <= 1) as usize;
            }
        }
        println!(
            "{tag} measured (no learning): first images exact {:.1}% within one {:.1}%",
            100.0 * e1 as f64 / c1 as f64,
            100.0 * n1 as f64 / c1 as f64
        );
    }
    let variants: Vec<String> = std::env::var("VARIANTS")
        .unwrap_or("pcn:1".into())
        .split(',')
        .map(String::from)
        .collect();
    for v in variants {
        let (kind, c) = v.split_once(':').unwrap();
        let c: f64 = c.parse().unwrap();
        let map = |f: &[f32]| -> Vec<f32> {
            match kind {
                "pcn" => f[..dim].to_vec(),
                "pcng" => {
                    let mut out = f[..dim].to_vec();
                    let row = scaler.model_row(f, dim);
                    out.extend_from_slice(&row[row.len() - (f.len() - dim)..]);
                    out
                }
                "chi2g" => scaler.model_row(f, dim),
                "ramp" => {
                    let mut out = f[..dim].to_vec();
                    let row = scaler.model_row(f, dim);
                    out.extend_from_slice(&row[row.len() - (f.len() - dim)..]);
                    out.extend(ramps(f));
                    out
                }
                "ramponly" => ramps(f),
                _ => panic!("unknown kind {kind}"),
            }
        };
        let t = Instant::now();
        let xs: Vec<Vec<f32>> = tr.iter().map(|r| map(&r.f)).collect();
        let ys: Vec<Vec<f32>> = ev.iter().map(|r| map(&r.f)).collect();
        let mut per = Vec::new();
        let (mut fe, mut fn_, mut ae, mut an) = (0.0, 0.0, 0.0, 0.0);
        for k in 0..12 {
            let labels: Vec<u16> = tr.iter().map(|r| r.labels[k] as u16).collect();
            let clf = OneVsRest::train(&xs, &labels, c);
            let (mut e1, mut n1, mut c1, mut e, mut n) = (0, 0, 0, 0, 0);
            for (r, y) in ev.iter().zip(&ys) {
                let got = clf.predict(y) as i32;
                let want = r.labels[k] as i32;
                e += (got == want) as usize;
                n += ((got - want).abs() <= 1) as usize;
                if r.first {
                    c1 += 1;
                    e1 += (got == want) as usize;
                    n1 += ((got - want).abs() <= 1) as usize;
                }
            }
            let m = ev.len() as f64;
            per.push(format!("{:.0}", 100.0 * e1 as f64 / c1 as f64));
            fe += e1 as f64 / c1 as f64 / 12.0;
            fn_ += n1 as f64 / c1 as f64 / 12.0;
            ae += e as f64 / m / 12.0;
            an += n as f64 / m / 12.0;
        }
        println!(
            "{tag} {v}: first images exact {:.1}% within one {:.1}%; all images exact {:.1}% \
             within one {:.1}% [{:.0} s] per scale (first, exact): {}",
            100.0 * fe,
            100.0 * fn_,
            100.0 * ae,
            100.0 * an,
            t.elapsed().as_secs_f64(),
            per.join(" ")
        );
    }
}
