//! Issue 36's classifier experiments, features computed once:
//! `cargo run --release --example texture_xset_dump -- OUT_DIR [--looks L]
//! [--per-model N] [--config INDEX_CONFIG_JSON] [--xset DIR] [--scales]`.
//!
//! Renders the dataset as `texture_xset` does, learns the filters from the
//! training bases (the bases `bench texture` holds out, `build::split`
//! seed 7, excluded) and writes every image's feature row
//! ([`Index::image_features`]) to `OUT_DIR/rows.f32` (little-endian, one
//! row after another) with `OUT_DIR/rows.csv` (model, base, held out,
//! look, light, crop, in the paper's §5.2 test set as `bench texture`
//! draws it). The cross-implementation set's **validation** images (never
//! its test part) go to `xset.f32` / `xset.csv`: each image's view rows
//! ([`Index::view_features`]) under the eight rotations and mirrors of the
//! square (transform 0 is the image itself), for test-time augmentation;
//! with `--scales` only these, to `xset-scales.f32` / `.csv`, as read
//! (transform 0) and halved (transform 1, its 2 × 2 means); with
//! `--views-only` only the eight symmetries' rows (for a labelled
//! directory of extra images, e.g. another implementation's renders);
//! with `--write-images DIR` only the dataset's images, as 8-bit PNGs with
//! a `labels.csv` whose last column is 1 for the bases held out.
//! `src/bench/examples/texture_xset_classifiers.py` reads the files;
//! findings in `docs/bench/texture-xset-2026-12-06b.md`.
// A native experiment: wall-clock time is what it reports.
#![allow(clippy::disallowed_methods)]
use filigree::core::parallel::par_map;
use filigree::core::rng::Rng;
use filigree::texture::api;
use filigree::texture::build::{self, BuildConfig, BuildStats};
use filigree::texture::index::{GlobalScaler, Index, IndexConfig};
use filigree::texture::learn::svm::OneVsRest;
use filigree::texture::models::MODELS;
use filigree::texture::Gray;
use std::io::Write;
use std::time::Instant;

fn arg(args: &[String], name: &str) -> Option<String> {
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

/// The image under the `t`-th of the square's eight symmetries.
fn dihedral(img: &Gray, t: usize) -> Gray {
    let (w, h) = (img.width, img.height);
    let transpose = t & 4 != 0;
    let (ow, oh) = if transpose { (h, w) } else { (w, h) };
    let mut out = Gray {
        width: ow,
        height: oh,
        data: vec![0.0; w * h],
    };
    for y in 0..oh {
        for x in 0..ow {
            let (mut sx, mut sy) = if transpose { (y, x) } else { (x, y) };
            if t & 1 != 0 {
                sx = w - 1 - sx;
            }
            if t & 2 != 0 {
                sy = h - 1 - sy;
            }
            out.data[y * ow + x] = img.data[sy * w + sx];
        }
    }
    out
}

/// One validation image's view row: its model, transform, view and features.
type ViewRow = (usize, usize, usize, Vec<f32>);

fn write_rows(path: &str, rows: &[Vec<f32>]) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(path).unwrap());
    for r in rows {
        for v in r {
            f.write_all(&v.to_le_bytes()).unwrap();
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let out = args.get(1).expect("OUT_DIR").clone();
    std::fs::create_dir_all(&out).unwrap();
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
    if let Some(dir) = arg(&args, "--write-images") {
        // The dataset's images as 8-bit PNGs with rows.csv's order in
        // labels.csv, for probes that compute their own features.
        std::fs::create_dir_all(&dir).unwrap();
        let mut csv = String::from("file,model,split,variant\n");
        for (i, (s, _)) in samples.iter().enumerate() {
            let g = &s.image;
            let px: Vec<u8> = g
                .data
                .iter()
                .map(|v| (v.clamp(0.0, 1.0) * 255.0).round() as u8)
                .collect();
            let img = image::GrayImage::from_raw(g.width as u32, g.height as u32, px).unwrap();
            let name = format!("d{i:05}.png");
            img.save(format!("{dir}/{name}")).unwrap();
            csv += &format!(
                "{name},{},validation,{}\n",
                MODELS[s.model].name, held[s.base] as u8
            );
        }
        std::fs::write(format!("{dir}/labels.csv"), csv).unwrap();
        return;
    }
    let train = build::training(&samples, |b| !held[b]);
    let pcn = Index::train_pcn(&train, &cfg.index).expect("filters");
    drop(train);
    let scales = args.iter().any(|a| a == "--scales");
    if scales {
        return xset(&out, &dir, pcn, &cfg, true);
    }
    if args.iter().any(|a| a == "--views-only") {
        return xset(&out, &dir, pcn, &cfg, false);
    }
    let t = Instant::now();
    let rows: Vec<Vec<f32>> = par_map(&samples, |(s, _)| {
        Index::image_features(&pcn, &s.image).expect("features")
    });
    eprintln!(
        "features in {:.1} s (dim {})",
        t.elapsed().as_secs_f64(),
        pcn.config.feature_len()
    );
    // The paper's §5.2 test set, drawn as `bench texture` draws it.
    let mut rng = Rng::new(11);
    let mut paper_test = vec![false; samples.len()];
    for m in 0..MODELS.len() {
        let mut mine: Vec<usize> = (0..samples.len())
            .filter(|&i| samples[i].0.model == m && samples[i].0.look.is_none())
            .collect();
        rng.shuffle(&mut mine);
        for &i in mine.iter().take(mine.len() / 4) {
            paper_test[i] = true;
        }
    }
    write_rows(&format!("{out}/rows.f32"), &rows);
    let mut csv = String::from("model,base,held,look,light,crop,paper_test,dim\n");
    for (i, (s, _)) in samples.iter().enumerate() {
        csv += &format!(
            "{},{},{},{},{},{},{},{}\n",
            s.model,
            s.base,
            held[s.base] as u8,
            s.look.is_some() as u8,
            s.light_index,
            s.crop.map_or(-1, |c| c as i32),
            paper_test[i] as u8,
            pcn.config.feature_len()
        );
    }
    std::fs::write(format!("{out}/rows.csv"), csv).unwrap();
    xset(&out, &dir, pcn, &cfg, false);
}

/// Half the image's side: the mean of each 2 × 2 block.
fn halved(img: &Gray) -> Gray {
    let (w, h) = (img.width / 2, img.height / 2);
    let mut out = Gray {
        width: w,
        height: h,
        data: vec![0.0; w * h],
    };
    for y in 0..h {
        for x in 0..w {
            let at = |dx: usize, dy: usize| img.data[(2 * y + dy) * img.width + 2 * x + dx];
            out.data[y * w + x] = (at(0, 0) + at(1, 0) + at(0, 1) + at(1, 1)) / 4.0;
        }
    }
    out
}

/// The validation images' view rows under the eight symmetries, or (with
/// `scales`) as read and halved (transforms 0 and 1).
fn xset(out: &str, dir: &str, pcn: filigree::texture::pcn::Pcn, cfg: &BuildConfig, scales: bool) {
    let names: Vec<String> = MODELS.iter().map(|m| m.id.to_string()).collect();
    let index = Index {
        model_names: names,
        pcn,
        model_classifier: OneVsRest {
            classes: Vec::new(),
            machines: Vec::new(),
        },
        globals: GlobalScaler {
            mean: Vec::new(),
            sd: Vec::new(),
            weight: 1.0,
        },
        confidence: cfg.index.confidence,
        regions: Vec::new(),
        scale_classifiers: Vec::new(),
        measured: None,
        axes: Vec::new(),
        samples: Vec::new(),
    };
    let labels = std::fs::read_to_string(format!("{dir}/labels.csv")).expect("labels.csv");
    let mut jobs: Vec<(usize, String)> = Vec::new();
    for line in labels.lines().skip(1) {
        let cols: Vec<&str> = line.splitn(4, ',').collect();
        if cols.len() < 3 || cols[2] != "validation" {
            continue;
        }
        let want = MODELS
            .iter()
            .position(|m| m.name == cols[1])
            .expect("model");
        jobs.push((want, cols[0].to_string()));
    }
    let t = Instant::now();
    let per: Vec<Vec<ViewRow>> = par_map(&jobs, |(want, file)| {
        let img = api::decode_gray(&std::fs::read(format!("{dir}/{file}")).unwrap()).unwrap();
        let mut v = Vec::new();
        let reads: Vec<Gray> = if scales {
            vec![img.clone(), halved(&img)]
        } else {
            (0..8).map(|t| dihedral(&img, t)).collect()
        };
        for (t, read) in reads.iter().enumerate() {
            for (k, f) in index.view_features(read).unwrap().into_iter().enumerate() {
                v.push((*want, t, k, f));
            }
        }
        v
    });
    eprintln!("xset features in {:.1} s", t.elapsed().as_secs_f64());
    let mut rows = Vec::new();
    let mut csv = String::from("image,model,transform,view\n");
    for (i, v) in per.into_iter().enumerate() {
        for (m, t, k, f) in v {
            csv += &format!("{i},{m},{t},{k}\n");
            rows.push(f);
        }
    }
    let tag = if scales { "xset-scales" } else { "xset" };
    write_rows(&format!("{out}/{tag}.f32"), &rows);
    std::fs::write(format!("{out}/{tag}.csv"), csv).unwrap();
}
