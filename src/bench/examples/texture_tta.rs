//! Texture model classifier: test-time augmentation and global features,
//! decided on a validation split (never on the test set):
//! `cargo run --release --example texture_tta -- TAG [test]`.
//!
//! Renders the shipped dataset (`BuildConfig::default()`: 24 bases per
//! model, 128², two lights × four quadrant crops of a 256² render; the
//! cache is per TAG, so a TAG names one dataset), holds out `bench texture`'s bases
//! (seed 7), learns the filters from the rest and caches, per image, the
//! PCN features of the image, its mirror image and its transpose, and a
//! few global values (see `globals`); per base and light also the features
//! of the 256² render read as the index reads a user's image (its centre
//! 128 window). Validation: a third of each model's training bases (seed
//! 3), trained on the other two thirds; `test` trains on all training
//! bases and scores the held-out ones. `VARIANTS` = `base:C`, `glob:C:W`
//! (global values standardised, times W, beside the χ² map), `aug:C`
//! (mirror and transpose also train), `rbf:C:W:G` (an exact Gaussian
//! kernel on the same rows, γ = G / the mean squared distance).
//!
//! Other settings (environment): `PER_MODEL=n` and `SIZE=n` (the dataset's
//! bases per model and image side, the network's window following it),
//! `TRAIN_BASES=k` (train on k of each model's training bases: a learning
//! curve), `PAPER=1` (the paper's random 25% of every model's images as the
//! evaluation set), `TRAINACC=1` (score the training images themselves),
//! `FOLD=k`, `NOFLIP=1`, `SHIPPED_GLOBALS=1`, `CONF=1`, `MISSES=…`, `PER=1`.
// An experiment tool: wall-clock time is what it reports, and index loops
// over parallel columns read plainest.
#![allow(
    clippy::disallowed_methods,
    clippy::needless_range_loop,
    clippy::type_complexity
)]
use filigree::core::parallel::par_map;
use filigree::core::rng::Rng;
use filigree::texture::build::{self, BuildConfig, BuildStats};
use filigree::texture::index::Index;
use filigree::texture::learn::svm::{chi2_map, OneVsRest};
use filigree::texture::models::MODELS;
use filigree::texture::Gray;
use std::io::{Read, Write};
use std::time::Instant;

#[derive(Clone)]
struct Row {
    model: u16,
    base: u32,
    light: u8,
    crop: u8,
    held: bool,
    f: Vec<f32>,
    fx: Vec<f32>,
    ft: Vec<f32>,
    g: Vec<f32>,
}

fn mirror(g: &Gray) -> Gray {
    let mut o = g.clone();
    for y in 0..g.height {
        for x in 0..g.width {
            o.data[y * g.width + x] = g.at(g.width - 1 - x, y);
        }
    }
    o
}

fn transpose(g: &Gray) -> Gray {
    let mut o = Gray::new(g.height, g.width);
    for y in 0..g.height {
        for x in 0..g.width {
            o.data[x * g.height + y] = g.at(x, y);
        }
    }
    o
}

/// Global values of the 128² view: the 12 raw scale measures, the
/// log power in 13 radial octave-ish bands, and 3 grey-level moments.
fn globals(v: &Gray) -> Vec<f32> {
    if std::env::var("SHIPPED_GLOBALS").is_ok() {
        return filigree::texture::globals::measure(v).unwrap();
    }
    let mut out: Vec<f32> = filigree::texture::scales::measure(v)
        .unwrap()
        .iter()
        .map(|&x| x as f32)
        .collect();
    let n = v.width;
    let m = v.data.iter().map(|&x| x as f64).sum::<f64>() / (n * n) as f64;
    let mut re: Vec<f32> = v.data.iter().map(|&x| (x as f64 - m) as f32).collect();
    let mut im = vec![0f32; n * n];
    filigree::geom::fft::fft2(&mut re, &mut im, n, n, false).unwrap();
    let edges = [
        0.5, 1.5, 2.5, 3.5, 5.0, 7.0, 10.0, 14.0, 20.0, 28.0, 40.0, 56.0, 80.0, 200.0,
    ];
    let mut band = vec![0f64; edges.len() - 1];
    let mut total = 0.0;
    for y in 0..n {
        for x in 0..n {
            let fx = if x < n / 2 {
                x as f64
            } else {
                x as f64 - n as f64
            };
            let fy = if y < n / 2 {
                y as f64
            } else {
                y as f64 - n as f64
            };
            let r = (fx * fx + fy * fy).sqrt();
            let p = (re[y * n + x] as f64).powi(2) + (im[y * n + x] as f64).powi(2);
            total += p;
            if let Some(b) = (0..band.len()).find(|&b| r >= edges[b] && r < edges[b + 1]) {
                band[b] += p;
            }
        }
    }
    out.extend(
        band.iter()
            .map(|&b| (b / total.max(1e-12) + 1e-6).log10() as f32),
    );
    let sd = (v.data.iter().map(|&x| (x as f64 - m).powi(2)).sum::<f64>() / (n * n) as f64)
        .sqrt()
        .max(1e-9);
    let mom = |k: i32| {
        v.data
            .iter()
            .map(|&x| ((x as f64 - m) / sd).powi(k))
            .sum::<f64>()
            / (n * n) as f64
    };
    out.extend([sd as f32, mom(3) as f32, mom(4).max(1e-6).ln() as f32]);
    out
}

fn put(b: &mut Vec<u8>, v: &[f32]) {
    b.extend((v.len() as u32).to_le_bytes());
    for x in v {
        b.extend(x.to_le_bytes());
    }
}

struct Cur<'a>(&'a [u8], usize);
impl Cur<'_> {
    fn u32(&mut self) -> u32 {
        self.1 += 4;
        u32::from_le_bytes(self.0[self.1 - 4..self.1].try_into().unwrap())
    }
    fn v(&mut self) -> Vec<f32> {
        let n = self.u32() as usize;
        (0..n).map(|_| f32::from_bits(self.u32())).collect()
    }
}

fn save(path: &str, rows: &[Row], centre: &[Row]) {
    let mut b = Vec::new();
    for set in [rows, centre] {
        b.extend((set.len() as u32).to_le_bytes());
        for r in set {
            b.extend((r.model as u32).to_le_bytes());
            b.extend(r.base.to_le_bytes());
            b.extend([r.light, r.crop, r.held as u8, 0]);
            put(&mut b, &r.f);
            put(&mut b, &r.fx);
            put(&mut b, &r.ft);
            put(&mut b, &r.g);
        }
    }
    std::fs::File::create(path).unwrap().write_all(&b).unwrap();
}

fn load(path: &str) -> Option<(Vec<Row>, Vec<Row>)> {
    let mut b = Vec::new();
    std::fs::File::open(path).ok()?.read_to_end(&mut b).ok()?;
    let mut c = Cur(&b, 0);
    let mut sets = Vec::new();
    for _ in 0..2 {
        let n = c.u32() as usize;
        let mut set = Vec::with_capacity(n);
        for _ in 0..n {
            let model = c.u32() as u16;
            let base = c.u32();
            let t = c.u32().to_le_bytes();
            set.push(Row {
                model,
                base,
                light: t[0],
                crop: t[1],
                held: t[2] == 1,
                f: c.v(),
                fx: c.v(),
                ft: c.v(),
                g: c.v(),
            });
        }
        sets.push(set);
    }
    let centre = sets.pop().unwrap();
    Some((sets.pop().unwrap(), centre))
}

fn compute(cfg: &BuildConfig) -> (Vec<Row>, Vec<Row>) {
    // NOFLIP=1: no mirror / transpose features (a third of the time; the
    // flip variants then read the plain features).
    let flips = std::env::var("NOFLIP").is_err();
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
    let idx: Vec<usize> = (0..samples.len()).collect();
    let rows = par_map(&idx, |&i| {
        let s = &samples[i].0;
        let img = &s.image;
        Row {
            model: s.model as u16,
            base: s.base as u32,
            light: s.light_index as u8,
            crop: s.crop.unwrap_or(0),
            held: held[s.base],
            f: pcn.features(img).unwrap(),
            fx: if flips {
                pcn.features(&mirror(img)).unwrap()
            } else {
                Vec::new()
            },
            ft: if flips {
                pcn.features(&transpose(img)).unwrap()
            } else {
                Vec::new()
            },
            g: globals(&pcn.config.view(img).unwrap()),
        }
    });
    eprintln!("features in {:.0} s", t.elapsed().as_secs_f64());
    // The 256² renders, from their quadrants, read as a user's image.
    let firsts: Vec<usize> = (0..samples.len())
        .filter(|&i| samples[i].0.crop == Some(0))
        .collect();
    let centre = par_map(&firsts, |&i| {
        let s = &samples[i].0;
        let n = s.image.width;
        let mut big = Gray::new(2 * n, 2 * n);
        for q in 0..4u8 {
            let c = &samples[i + q as usize].0;
            assert_eq!(
                (c.base, c.light_index, c.crop),
                (s.base, s.light_index, Some(q))
            );
            let (ox, oy) = ((q as usize % 2) * n, (q as usize / 2) * n);
            for y in 0..n {
                for x in 0..n {
                    big.data[(oy + y) * 2 * n + ox + x] = c.image.at(x, y);
                }
            }
        }
        Row {
            model: s.model as u16,
            base: s.base as u32,
            light: s.light_index as u8,
            crop: 255,
            held: held[s.base],
            f: pcn.features(&big).unwrap(),
            fx: Vec::new(),
            ft: Vec::new(),
            g: globals(&pcn.config.view(&big).unwrap()),
        }
    });
    (rows, centre)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let tag = &args[1];
    let test = args.iter().any(|a| a == "test");
    let mut cfg = BuildConfig::default();
    // PER_MODEL=n: a dataset grid of n bases per model instead of 24.
    if let Ok(n) = std::env::var("PER_MODEL") {
        cfg.dataset.per_model = n.parse().unwrap();
    }
    // SIZE=n: dataset images (and the network's window) n² instead of 128².
    if let Ok(n) = std::env::var("SIZE") {
        cfg.dataset.size = n.parse().unwrap();
        cfg.index.pcn.side = cfg.dataset.size;
        cfg = cfg.synced();
    }
    std::fs::create_dir_all("target/texacc").unwrap();
    let path = format!("target/texacc/{tag}.bin");
    let (mut rows, mut centre) = match load(&path) {
        Some(x) => x,
        None => {
            let x = compute(&cfg);
            save(&path, &x.0, &x.1);
            x
        }
    };
    for r in rows.iter_mut().chain(centre.iter_mut()) {
        if r.fx.is_empty() {
            r.fx = r.f.clone();
            r.ft = r.f.clone();
        }
        for x in r.g.iter_mut() {
            if !x.is_finite() {
                *x = -14.0;
            }
        }
    }
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
        // FOLD=k (0, 1, 2): which third of the training bases validates
        // (0 by default; the three folds together cover every training base).
        let k: usize = std::env::var("FOLD").map_or(0, |v| v.parse().unwrap());
        let third = bases.len() / 3;
        for &b in bases.iter().skip(k * third).take(third) {
            val_base.insert(b);
        }
    }
    // PAPER=1: the paper's protocol, a random 25% of each model's images
    // (every base's) evaluated, the rest trained; TRAINACC=1: the training
    // images themselves evaluated.
    let paper = std::env::var("PAPER").is_ok();
    let train_acc = std::env::var("TRAINACC").is_ok();
    let mut paper_eval = std::collections::HashSet::new();
    if paper {
        let mut rng = Rng::new(11);
        for m in 0..MODELS.len() as u16 {
            let mut ids: Vec<(u32, u8, u8)> = rows
                .iter()
                .filter(|r| r.model == m)
                .map(|r| (r.base, r.light, r.crop))
                .collect();
            rng.shuffle(&mut ids);
            let q = ids.len() / 4;
            paper_eval.extend(ids.into_iter().take(q));
        }
    }
    let is_eval = |r: &Row| {
        if paper {
            r.crop != 255 && paper_eval.contains(&(r.base, r.light, r.crop))
        } else if test {
            r.held
        } else {
            !r.held && val_base.contains(&r.base)
        }
    };
    // TRAIN_BASES=k: train on only k of each model's training bases
    // (shuffled with seed 5), for a learning curve.
    let mut dropped = std::collections::HashSet::new();
    if let Ok(k) = std::env::var("TRAIN_BASES") {
        let k: usize = k.parse().unwrap();
        let mut rng = Rng::new(5);
        for m in 0..MODELS.len() as u16 {
            let mut bases: Vec<u32> = rows
                .iter()
                .filter(|r| r.model == m && !r.held && (test || !val_base.contains(&r.base)))
                .map(|r| r.base)
                .collect();
            bases.sort_unstable();
            bases.dedup();
            rng.shuffle(&mut bases);
            dropped.extend(bases.into_iter().skip(k));
        }
    }
    let is_train = |r: &Row| {
        !dropped.contains(&r.base)
            && if paper {
                !paper_eval.contains(&(r.base, r.light, r.crop))
            } else if test {
                !r.held
            } else {
                !r.held && !val_base.contains(&r.base)
            }
    };
    let tr: Vec<&Row> = rows.iter().filter(|r| is_train(r)).collect();
    let ev: Vec<&Row> = if train_acc {
        tr.clone()
    } else {
        rows.iter().filter(|r| is_eval(r)).collect()
    };
    let evc: Vec<&Row> = centre.iter().filter(|r| is_eval(r)).collect();
    eprintln!(
        "{} train, {} eval, {} eval 256² renders ({})",
        tr.len(),
        ev.len(),
        evc.len(),
        if test { "TEST" } else { "validation" }
    );
    // Standardisation of the global values over the training rows.
    let gd = tr[0].g.len();
    let mut mu = vec![0f64; gd];
    let mut sd = vec![0f64; gd];
    for r in &tr {
        for k in 0..gd {
            mu[k] += r.g[k] as f64 / tr.len() as f64;
        }
    }
    for r in &tr {
        for k in 0..gd {
            sd[k] += (r.g[k] as f64 - mu[k]).powi(2) / tr.len() as f64;
        }
    }
    let variants: Vec<String> = std::env::var("VARIANTS")
        .unwrap_or("base:10".into())
        .split(',')
        .map(String::from)
        .collect();
    for v in variants {
        let parts: Vec<&str> = v.split(':').collect();
        let kind = parts[0];
        let c: f64 = parts[1].parse().unwrap();
        let w: f32 = parts.get(2).map_or(0.0, |s| s.parse().unwrap());
        let gmask: Vec<bool> = match parts.get(3) {
            Some(&"scales") => (0..gd).map(|k| k < 12).collect(),
            Some(&"spec") => (0..gd).map(|k| (12..25).contains(&k)).collect(),
            Some(&"mom") => (0..gd).map(|k| k >= 25).collect(),
            _ => vec![true; gd],
        };
        let map = |f: &[f32], g: &[f32]| -> Vec<f32> {
            let mut x = chi2_map(f);
            if kind == "glob" || kind == "rbf" {
                for k in 0..gd {
                    if gmask[k] {
                        let z = (g[k] as f64 - mu[k]) / (sd[k].sqrt() + 1e-9);
                        x.push(w * z.clamp(-5.0, 5.0) as f32);
                    }
                }
            }
            x
        };
        if kind == "rbf" {
            // Exact RBF kernel on the χ² map and the global values, one
            // vs rest: an upper bound for what the features can carry.
            let t = Instant::now();
            let xs: Vec<Vec<f32>> = tr.iter().map(|r| map(&r.f, &r.g)).collect();
            let nrm: Vec<f64> = xs
                .iter()
                .map(|x| x.iter().map(|v| (*v as f64).powi(2)).sum())
                .collect();
            let n = xs.len();
            let ids: Vec<usize> = (0..n).collect();
            let dots: Vec<Vec<f64>> = par_map(&ids, |&i| {
                (0..n)
                    .map(|j| {
                        xs[i]
                            .iter()
                            .zip(&xs[j])
                            .map(|(a, b)| *a as f64 * *b as f64)
                            .sum()
                    })
                    .collect()
            });
            let mut mean_d = 0.0;
            for i in 0..n {
                for j in 0..n {
                    mean_d += (nrm[i] + nrm[j] - 2.0 * dots[i][j]).max(0.0);
                }
            }
            mean_d /= (n * n) as f64;
            let gamma = parts.get(3).map_or(1.0, |g| g.parse::<f64>().unwrap()) / mean_d;
            let mut k = vec![0.0; n * n];
            for i in 0..n {
                for j in 0..n {
                    k[i * n + j] = (-gamma * (nrm[i] + nrm[j] - 2.0 * dots[i][j]).max(0.0)).exp();
                }
            }
            drop(dots);
            let gram = filigree::texture::learn::svm::Gram { n, k };
            let classes: Vec<u16> = (0..MODELS.len() as u16).collect();
            let duals = par_map(&classes, |&m| {
                let pos: Vec<bool> = tr.iter().map(|r| r.model == m).collect();
                filigree::texture::learn::svm::train_svc(&gram, &pos, c)
            });
            let train_s = t.elapsed().as_secs_f64();
            let sc = par_map(&ev, |r| {
                let x = map(&r.f, &r.g);
                let nx: f64 = x.iter().map(|v| (*v as f64).powi(2)).sum();
                let kx: Vec<f64> = (0..n)
                    .map(|j| {
                        let d: f64 = x
                            .iter()
                            .zip(&xs[j])
                            .map(|(a, b)| *a as f64 * *b as f64)
                            .sum();
                        (-gamma * (nx + nrm[j] - 2.0 * d).max(0.0)).exp()
                    })
                    .collect();
                duals
                    .iter()
                    .map(|d| d.coef.iter().zip(&kx).map(|(a, b)| a * b).sum::<f64>() - d.rho)
                    .collect::<Vec<f64>>()
            });
            let am =
                |s: &[f64]| (0..s.len()).fold(0, |b, i| if s[i] > s[b] { i } else { b }) as u16;
            let right = ev.iter().zip(&sc).filter(|(r, s)| am(s) == r.model).count();
            let mut q2: std::collections::BTreeMap<(u32, u8), (u16, Vec<f64>)> = Default::default();
            for (r, s) in ev.iter().zip(&sc) {
                if r.crop == 0 || r.crop == 3 {
                    let e = q2
                        .entry((r.base, r.light))
                        .or_insert((r.model, vec![0.0; s.len()]));
                    e.1.iter_mut().zip(s).for_each(|(a, b)| *a += b);
                }
            }
            let q2r = q2.values().filter(|(m, s)| am(s) == *m).count();
            let nsv: usize = duals
                .iter()
                .map(|d| d.coef.iter().filter(|a| a.abs() > 0.0).count())
                .sum();
            println!(
                "{tag} {v} [{train_s:.0} s train, {nsv} sv]: 128² images {:.1}% | 2 diagonal windows {:.1}%",
                100.0 * right as f64 / ev.len() as f64,
                100.0 * q2r as f64 / q2.len().max(1) as f64
            );
            continue;
        }
        let t = Instant::now();
        let mut xs: Vec<Vec<f32>> = Vec::new();
        let mut labels: Vec<u16> = Vec::new();
        for r in &tr {
            xs.push(map(&r.f, &r.g));
            labels.push(r.model);
            if kind == "aug" {
                xs.push(map(&r.fx, &r.g));
                labels.push(r.model);
                xs.push(map(&r.ft, &r.g));
                labels.push(r.model);
            }
        }
        let clf = OneVsRest::train(&xs, &labels, c);
        drop(xs);
        let train_s = t.elapsed().as_secs_f64();
        let score = |f: &[f32], g: &[f32]| clf.scores(&map(f, g));
        let argmax = |s: &[f64]| {
            let b = (0..s.len()).fold(0, |b, i| if s[i] > s[b] { i } else { b });
            clf.classes[b]
        };
        let add = |a: &mut Vec<f64>, b: &[f64]| a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
        // Per image: single, + mirror, + mirror + transpose.
        let per: Vec<[Vec<f64>; 3]> = par_map(&ev, |r| {
            [score(&r.f, &r.g), score(&r.fx, &r.g), score(&r.ft, &r.g)]
        });
        let (mut one, mut two, mut three, mut n) = (0, 0, 0, 0);
        let (mut one1, mut three1, mut n1) = (0, 0, 0);
        let mut quad: std::collections::BTreeMap<(u32, u8), (u16, Vec<f64>, Vec<f64>)> =
            Default::default();
        let mut per_model = vec![(0usize, 0usize); MODELS.len()];
        for (r, s) in ev.iter().zip(&per) {
            n += 1;
            let a = argmax(&s[0]) == r.model;
            let mut t2 = s[0].clone();
            add(&mut t2, &s[1]);
            let b = argmax(&t2) == r.model;
            let mut t3 = t2.clone();
            add(&mut t3, &s[2]);
            let c3 = argmax(&t3) == r.model;
            one += a as usize;
            two += b as usize;
            three += c3 as usize;
            if r.light == 0 && r.crop == 0 {
                n1 += 1;
                one1 += a as usize;
                three1 += c3 as usize;
            }
            let e = quad.entry((r.base, r.light)).or_insert((
                r.model,
                vec![0.0; s[0].len()],
                vec![0.0; s[0].len()],
            ));
            add(&mut e.1, &s[0]);
            add(&mut e.2, &t3);
        }
        let (mut q1, mut q3, mut qn) = (0, 0, 0);
        for (m, s1, s3) in quad.values() {
            qn += 1;
            q1 += (argmax(s1) == *m) as usize;
            let ok = argmax(s3) == *m;
            q3 += ok as usize;
        }
        // Cheaper reads of a 256² render: two diagonal windows; four
        // windows' PCN features with the centre view's global values.
        let gc: std::collections::HashMap<(u32, u8), &Row> =
            evc.iter().map(|r| ((r.base, r.light), *r)).collect();
        let mut q2: std::collections::BTreeMap<(u32, u8), (u16, Vec<f64>)> = Default::default();
        let mut q4c: std::collections::BTreeMap<(u32, u8), (u16, Vec<f64>)> = Default::default();
        for (r, s) in ev.iter().zip(&per) {
            if r.crop == 0 || r.crop == 3 {
                let e = q2
                    .entry((r.base, r.light))
                    .or_insert((r.model, vec![0.0; s[0].len()]));
                add(&mut e.1, &s[0]);
            }
            let e = q4c
                .entry((r.base, r.light))
                .or_insert((r.model, vec![0.0; s[0].len()]));
            if let Some(c) = gc.get(&(r.base, r.light)) {
                add(&mut e.1, &score(&r.f, &c.g));
            }
        }
        let acc = |m: &std::collections::BTreeMap<(u32, u8), (u16, Vec<f64>)>| {
            m.values().filter(|(k, s)| argmax(s) == *k).count()
        };
        println!(
            "  256² renders: 2 diagonal windows {:.1}%, 4 windows with the centre's global values {:.1}%",
            100.0 * acc(&q2) as f64 / q2.len().max(1) as f64,
            100.0 * acc(&q4c) as f64 / q4c.len().max(1) as f64
        );
        let mut cen = 0;
        for r in &evc {
            let ok = argmax(&score(&r.f, &r.g)) == r.model;
            cen += ok as usize;
        }
        for (r, s) in ev.iter().zip(&per) {
            let ok = argmax(&s[0]) == r.model;
            per_model[r.model as usize].1 += 1;
            per_model[r.model as usize].0 += ok as usize;
        }
        let pc = |a: usize, b: usize| 100.0 * a as f64 / b.max(1) as f64;
        println!(
            "{tag} {v} [{train_s:.0} s train]: 128² images: single {:.1}% first {:.1}% | +mirror {:.1}% | +mirror+transpose {:.1}% first {:.1}% || 256² renders ({qn}): centre window {:.1}% | 4 quadrants {:.1}% | 4 quadrants × 3 {:.1}%",
            pc(one, n),
            pc(one1, n1),
            pc(two, n),
            pc(three, n),
            pc(three1, n1),
            pc(cen, evc.len()),
            pc(q1, qn),
            pc(q3, qn),
        );
        if std::env::var("CONF").is_ok() {
            // Per model: right out of its evaluated images, and what the
            // misses were taken for (all images; first images in brackets).
            let mut conf = vec![vec![(0usize, 0usize); MODELS.len()]; MODELS.len()];
            for (r, s) in ev.iter().zip(&per) {
                let p = argmax(&s[0]) as usize;
                let e = &mut conf[r.model as usize][p];
                e.0 += 1;
                if r.light == 0 && r.crop == 0 {
                    e.1 += 1;
                }
            }
            for (m, row) in conf.iter().enumerate() {
                let tot: usize = row.iter().map(|x| x.0).sum();
                let tot1: usize = row.iter().map(|x| x.1).sum();
                let mut miss: Vec<(usize, usize, usize)> = row
                    .iter()
                    .enumerate()
                    .filter(|&(p, x)| p != m && x.0 > 0)
                    .map(|(p, x)| (x.0, x.1, p))
                    .collect();
                miss.sort_unstable_by(|a, b| b.cmp(a));
                println!(
                    "  {:24} {:3}/{:3} ({}/{}) | {}",
                    MODELS[m].id,
                    row[m].0,
                    tot,
                    row[m].1,
                    tot1,
                    miss.iter()
                        .map(|(a, b, p)| format!("{} {a} ({b})", MODELS[*p].id))
                        .collect::<Vec<_>>()
                        .join(", ")
                );
            }
            if let Ok(ids) = std::env::var("MISSES") {
                // Each missed image of these models: base, light, crop, taken for.
                for (r, s) in ev.iter().zip(&per) {
                    let p = argmax(&s[0]) as usize;
                    if p != r.model as usize
                        && ids.split(',').any(|i| i == MODELS[r.model as usize].id)
                    {
                        println!(
                            "  miss {} base {} light {} crop {} -> {}",
                            MODELS[r.model as usize].id, r.base, r.light, r.crop, MODELS[p].id
                        );
                    }
                }
            }
        }
        if std::env::var("PER").is_ok() {
            println!(
                "  {}",
                per_model
                    .iter()
                    .enumerate()
                    .map(|(m, (a, b))| format!("{}={a}/{b}", MODELS[m].id))
                    .collect::<Vec<_>>()
                    .join(" ")
            );
        }
    }
}
