//! The perceptual space's axis regressions (paper §4.2, Table 3) on a
//! validation split of the bases: `cargo run --release --example
//! texture_space`. The space is Isomap over every base's twelve scales (as
//! `Index::fit` builds it); each axis regresses its coordinate on a subset
//! of the scales (the top three by |Pearson r| and every other with |r| ≥
//! `MC`) with a Gaussian-kernel SVR. Here the subset and the SVR are fitted
//! on two thirds of the training bases and scored (R², as `bench texture`
//! prints) on the other third; `bench texture`'s held-out bases (seed 7)
//! are never scored. Settings (environment): `PER_MODEL`, `K` (Isomap
//! neighbours, list), `MC` (list), `GAMMA` (γ × subset size, list), `C`
//! (list), `EPS`.
#![allow(clippy::disallowed_methods)]
use filigree::core::rng::Rng;
use filigree::texture::build::{self, BuildConfig, BuildStats};
use filigree::texture::learn::isomap::{isomap, pearson};
use filigree::texture::learn::svm::Svr;
use filigree::texture::models::MODELS;

fn list(name: &str, default: &str) -> Vec<f64> {
    std::env::var(name)
        .unwrap_or(default.into())
        .split(',')
        .map(|v| v.parse().unwrap())
        .collect()
}

fn main() {
    let mut cfg = BuildConfig::default();
    if let Ok(n) = std::env::var("PER_MODEL") {
        cfg.dataset.per_model = n.parse().unwrap();
    }
    let mut stats = BuildStats::default();
    let samples = build::labelled(&cfg.dataset, &[], &mut stats).unwrap();
    let held = build::split(&samples, 7);
    // One record per base: model, scales, held out.
    let mut bases: Vec<(u16, [u8; 12], usize)> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for (s, l) in &samples {
        if seen.insert(s.base) {
            bases.push((s.model as u16, *l, s.base));
        }
    }
    let n = bases.len();
    // Validation: a third of each model's training bases (seed 3).
    let mut val = vec![false; n];
    let mut rng = Rng::new(3);
    for m in 0..MODELS.len() as u16 {
        let mut ids: Vec<usize> = (0..n)
            .filter(|&i| bases[i].0 == m && !held[bases[i].2])
            .collect();
        rng.shuffle(&mut ids);
        let third = ids.len() / 3;
        for &i in ids.iter().take(third) {
            val[i] = true;
        }
    }
    let fit: Vec<usize> = (0..n).filter(|&i| !held[bases[i].2] && !val[i]).collect();
    let ev: Vec<usize> = (0..n).filter(|&i| val[i]).collect();
    eprintln!("{n} bases, {} fit, {} validation", fit.len(), ev.len());
    let mut d = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            d[i * n + j] = bases[i]
                .1
                .iter()
                .zip(&bases[j].1)
                .map(|(a, b)| (*a as f64 - *b as f64).powi(2))
                .sum::<f64>()
                .sqrt();
        }
    }
    let unit = |s: &[u8; 12], subset: &[usize]| -> Vec<f32> {
        subset.iter().map(|&k| (s[k] as f32 - 1.0) / 8.0).collect()
    };
    let eps: f64 = std::env::var("EPS").map_or(0.05, |v| v.parse().unwrap());
    for k in list("K", "10") {
        let y = isomap(&d, n, k as usize, 3).unwrap();
        for mc in list("MC", "0.3") {
            for g in list("GAMMA", "8") {
                for c in list("C", "10") {
                    let mut line = format!("k {k} mc {mc} γ·|s| {g} C {c}:");
                    for a in 0..3 {
                        let target: Vec<f64> = (0..n).map(|i| y[i * 3 + a]).collect();
                        let mut ranked: Vec<(usize, f64)> = (0..12)
                            .map(|s| {
                                let xs: Vec<f64> =
                                    fit.iter().map(|&i| bases[i].1[s] as f64).collect();
                                let ts: Vec<f64> = fit.iter().map(|&i| target[i]).collect();
                                (s, pearson(&xs, &ts).abs())
                            })
                            .collect();
                        ranked.sort_by(|p, q| q.1.total_cmp(&p.1).then(p.0.cmp(&q.0)));
                        let subset: Vec<usize> = ranked
                            .iter()
                            .enumerate()
                            .filter(|(r, (_, c))| *r < 3 || *c >= mc)
                            .map(|(_, (s, _))| *s)
                            .collect();
                        let mean = fit.iter().map(|&i| target[i]).sum::<f64>() / fit.len() as f64;
                        let spread = (fit.iter().map(|&i| (target[i] - mean).powi(2)).sum::<f64>()
                            / fit.len() as f64)
                            .sqrt()
                            .max(1e-9);
                        let rows: Vec<Vec<f32>> =
                            fit.iter().map(|&i| unit(&bases[i].1, &subset)).collect();
                        let z: Vec<f64> = fit.iter().map(|&i| target[i] / spread).collect();
                        let svr = Svr::train(&rows, &z, c, eps, g / subset.len() as f64);
                        let score = |ids: &[usize]| {
                            let p: Vec<f64> = ids
                                .iter()
                                .map(|&i| svr.predict(&unit(&bases[i].1, &subset)) * spread)
                                .collect();
                            let t: Vec<f64> = ids.iter().map(|&i| target[i]).collect();
                            pearson(&p, &t).powi(2)
                        };
                        line += &format!(
                            " {} R² {:.3} (fit {:.3}, {} scales)",
                            ["X", "Y", "Z"][a],
                            score(&ev),
                            score(&fit),
                            subset.len()
                        );
                    }
                    println!("{line}");
                }
            }
        }
    }
}
