//! Issue 36's experiments: how well an index trained with given settings
//! recognises textures made by other code (`bench/texture-xset/`), judged
//! on the set's **validation** part; `--split test` is for the one look at
//! the end.
//!
//! `cargo run --release --example texture_xset -- [--per-model N]
//! [--looks L] [--config INDEX_CONFIG_JSON] [--split validation|test]
//! [--xset DIR]`
//!
//! Renders the dataset as `build-index` does (plus `L` random looks per
//! base), holds out the bases `bench texture` holds out (`build::split`,
//! seed 7), trains on the rest, and prints: the held-out bases' accuracy
//! (first crop, main light), their looks' accuracy, and the
//! cross-implementation accuracy, top-3 and per model, with the largest
//! confusions.
// A native experiment: wall-clock time is what it reports.
#![allow(clippy::disallowed_methods)]
use filigree::texture::api;
use filigree::texture::build::{self, BuildConfig, BuildStats};
use filigree::texture::index::{GlobalScaler, Index, IndexConfig};
use filigree::texture::learn::svm::OneVsRest;
use filigree::texture::models::MODELS;
use std::collections::BTreeMap;
use std::time::Instant;

fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mut cfg = BuildConfig::default();
    if let Some(n) = arg(&args, "--per-model") {
        cfg.dataset.per_model = n.parse().expect("--per-model");
    }
    if let Some(n) = arg(&args, "--looks") {
        cfg.dataset.looks = n.parse().expect("--looks");
    }
    if let Some(json) = arg(&args, "--config") {
        let side = cfg.index.pcn.side;
        let v: serde_json::Value = serde_json::from_str(&json).expect("--config JSON");
        cfg.index = serde_json::from_value::<IndexConfig>(v.clone()).expect("--config");
        if v["pcn"]["side"].is_null() {
            cfg.index.pcn.side = side;
        }
        cfg = cfg.synced();
    }
    let split: String = arg(&args, "--split").unwrap_or_else(|| "validation".into());
    let dir = arg(&args, "--xset").unwrap_or_else(|| "target/texture-xset".into());

    let t = Instant::now();
    let mut stats = BuildStats::default();
    let samples = build::labelled(&cfg.dataset, &[], &mut stats).expect("dataset");
    let held = build::split(&samples, 7);
    eprintln!(
        "dataset: {} images in {:.1} s",
        samples.len(),
        t.elapsed().as_secs_f64()
    );
    let names: Vec<String> = MODELS.iter().map(|m| m.id.to_string()).collect();
    let t = Instant::now();
    let train = build::training(&samples, |b| !held[b]);
    let pcn = Index::train_pcn(&train, &cfg.index).expect("filters");
    let features = Index::features(&pcn, &train).expect("features");
    eprintln!("features in {:.1} s", t.elapsed().as_secs_f64());
    let cs: Vec<f64> = arg(&args, "--c").map_or(vec![cfg.index.c_model], |v| {
        v.split(',').map(|c| c.parse().expect("--c")).collect()
    });
    let dim = pcn.config.feature_len();
    let globals = GlobalScaler::fit(&features, dim, cfg.index.global_weight);
    let rows: Vec<Vec<f32>> = features.iter().map(|f| globals.model_row(f, dim)).collect();
    let models: Vec<u16> = train.iter().map(|t| t.model).collect();
    let scale_rows: Vec<Vec<f32>> = features.iter().map(|f| globals.scale_row(f, dim)).collect();
    let mut classes: Vec<u16> = models.clone();
    classes.sort();
    classes.dedup();
    let regions = Index::regions(&scale_rows, &models, &classes);
    drop(scale_rows);
    for c in cs {
        println!("== C = {c}");
        let t = Instant::now();
        let index = Index {
            model_names: names.clone(),
            pcn: pcn.clone(),
            model_classifier: OneVsRest::train(&rows, &models, c),
            globals: globals.clone(),
            confidence: cfg.index.confidence,
            regions: regions.clone(),
            scale_classifiers: Vec::new(),
            measured: None,
            axes: Vec::new(),
            samples: Vec::new(),
        };
        eprintln!("trained in {:.1} s", t.elapsed().as_secs_f64());
        evaluate(&index, &samples, &held, &dir, &split);
    }
}

fn evaluate(
    index: &Index,
    samples: &[(filigree::texture::dataset::Sample, [u8; 12])],
    held: &[bool],
    dir: &str,
    split: &str,
) {
    let t = Instant::now();
    let (mut first_right, mut first_n, mut look_right, mut look_n) = (0, 0, 0, 0);
    let mut seen = std::collections::HashSet::new();
    for (s, _) in samples {
        if !held[s.base] {
            continue;
        }
        if s.look.is_some() {
            look_n += 1;
            look_right +=
                (index.read_models(&s.image).unwrap().ranked[0].0 as usize == s.model) as usize;
        } else if s.light_index == 0 && seen.insert(s.base) {
            first_n += 1;
            first_right +=
                (index.read_models(&s.image).unwrap().ranked[0].0 as usize == s.model) as usize;
        }
    }
    println!(
        "held-out bases: {first_right}/{first_n} = {:.3}; their looks: {look_right}/{look_n} = {:.3}",
        first_right as f64 / first_n.max(1) as f64,
        look_right as f64 / look_n.max(1) as f64
    );

    let labels = std::fs::read_to_string(format!("{dir}/labels.csv")).expect("labels.csv");
    let (mut n, mut top1, mut top3) = (0, 0, 0);
    let mut per: BTreeMap<&str, (usize, usize)> = BTreeMap::new();
    let mut confusion: BTreeMap<(String, String), usize> = BTreeMap::new();
    let mut raw: Vec<(Vec<f64>, usize)> = Vec::new();
    let mut distances: Vec<f64> = Vec::new();
    for line in labels.lines().skip(1) {
        // file,model,split,variant (the model may hold commas? it does not).
        let cols: Vec<&str> = line.splitn(4, ',').collect();
        if cols.len() < 3 || cols[2] != split {
            continue;
        }
        let want = MODELS
            .iter()
            .position(|m| m.name == cols[1])
            .unwrap_or_else(|| panic!("unknown model {}", cols[1]));
        let bytes = std::fs::read(format!("{dir}/{}", cols[0])).expect("image");
        let img = api::decode_gray(&bytes).expect("decode");
        let views = index.view_features(&img).expect("features");
        let reading = index.read_views(&views);
        distances.push(reading.distance);
        let ranked = reading.ranked;
        // The classifier's scores averaged over the views, in its class order.
        let mut mean = vec![0f64; index.model_classifier.classes.len()];
        for f in &views {
            for (m, v) in mean.iter_mut().zip(index.model_scores(f)) {
                *m += v / views.len() as f64;
            }
        }
        raw.push((
            mean,
            index
                .model_classifier
                .classes
                .iter()
                .position(|&c| c as usize == want)
                .unwrap(),
        ));
        n += 1;
        let got = ranked[0].0 as usize;
        top1 += (got == want) as usize;
        top3 += ranked.iter().take(3).any(|r| r.0 as usize == want) as usize;
        let e = per.entry(MODELS[want].name).or_default();
        e.1 += 1;
        if got == want {
            e.0 += 1;
        } else {
            *confusion
                .entry((MODELS[want].name.into(), MODELS[got].name.into()))
                .or_default() += 1;
        }
    }
    println!(
        "xset {split}: top-1 {top1}/{n} = {:.3}, top-3 {top3}/{n} = {:.3} ({:.1} s)",
        top1 as f64 / n.max(1) as f64,
        top3 as f64 / n.max(1) as f64,
        t.elapsed().as_secs_f64()
    );
    // The temperature that minimises the right models' negative
    // log-likelihood, and the best scores' spread (closeness).
    let nll = |t: f64| -> f64 {
        raw.iter()
            .map(|(s, want)| {
                let best = s.iter().copied().fold(f64::NEG_INFINITY, f64::max);
                let z: f64 = s.iter().map(|v| ((v - best) / t).exp()).sum();
                -(((s[*want] - best) / t).exp() / z).ln()
            })
            .sum::<f64>()
            / raw.len().max(1) as f64
    };
    let mut best_t = (f64::INFINITY, 1.0);
    for i in 0..60 {
        let t = 0.02 * 1.12f64.powi(i);
        let v = nll(t);
        if v < best_t.0 {
            best_t = (v, t);
        }
    }
    println!(
        "temperature {:.3} (NLL {:.3}; at 1: {:.3})",
        best_t.1,
        best_t.0,
        nll(1.0)
    );
    let mut bests = distances.clone();
    bests.sort_by(f64::total_cmp);
    let q = |p: f64| bests[((bests.len() - 1) as f64 * p) as usize];
    println!(
        "closeness percentiles 50/90/95/98/99%: {:.3} {:.3} {:.3} {:.3} {:.3}",
        q(0.5),
        q(0.9),
        q(0.95),
        q(0.98),
        q(0.99)
    );
    if let Ok(dir) = std::fs::read_dir("target/texture-negatives") {
        let mut names: Vec<_> = dir.flatten().map(|e| e.path()).collect();
        names.sort();
        for p in names {
            let img = api::decode_gray(&std::fs::read(&p).unwrap()).unwrap();
            let r = index.read_models(&img).unwrap();
            println!(
                "  negative {}: closeness {:.3} ({})",
                p.display(),
                r.distance,
                MODELS[r.ranked[0].0 as usize].id
            );
        }
    }
    for (m, (r, k)) in &per {
        println!("  {r}/{k}  {m}");
    }
    let mut conf: Vec<_> = confusion.into_iter().collect();
    conf.sort_by_key(|c| std::cmp::Reverse(c.1));
    for ((a, b), k) in conf.iter().take(15) {
        println!("  {k}x {a} -> {b}");
    }
}
