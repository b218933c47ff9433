//! `filigree bench <tool>`: the benchmarks, each printing one JSON object.
//! They measure the library from outside, as the CLI uses it: they are
//! part of the `filigree` binary only when it is built with the `bench`
//! feature (on by default; `--no-default-features --features cli` builds
//! the CLI without them), and never of the library or a wasm module. The
//! CLI (`src/cli/`) only hands `filigree bench`'s arguments to [`run`].
//! Research probes are the package's examples (`src/bench/examples/`,
//! `cargo run --example NAME`).

pub mod fit_bench;
pub mod fit_designs;
pub mod measure;
pub mod micro_bench;
pub mod slices_bench;
pub mod tangle_bench;
pub mod texture_bench;
pub mod texture_xset;

/// Median and minimum of a list of timings (seconds).
pub fn min_median(mut v: Vec<f64>) -> (f64, f64) {
    v.sort_by(|a, b| a.total_cmp(b));
    (v[0], v[v.len() / 2])
}

use self::measure::fixture;
use clap::Subcommand;
use filigree::core::job::{Job, Step};
use filigree::inspect::{inspect, InspectOptions};
use filigree::pixel::{Elements, PixelInputs, PixelJob, PixelParams, Stage};
use filigree::raster::{decode, Limits, Rgba8Image};
use serde_json::json;
use std::time::Instant;

#[derive(Subcommand)]
pub enum Which {
    /// Decode + palette + thumbnail of a generated 1024² PNG.
    Inspect {
        #[arg(long, default_value_t = 10)]
        repeats: usize,
        /// Accepted for symmetry with other benches; output is always JSON.
        #[arg(long)]
        json: bool,
    },
    /// Fit every shipped generator to targets drawn from random true
    /// parameters; report parameter MSE, loss and time, the same fits with
    /// image-space L2 from the same initialisation, and evaluations per second.
    Fit {
        /// Accepted for symmetry with other benches; output is always JSON.
        #[arg(long)]
        json: bool,
        /// Quick budget instead of the paper's.
        #[arg(long)]
        quick: bool,
        /// Random targets per generator.
        #[arg(long, default_value_t = 1)]
        seeds: u64,
        /// Comma-separated generator names (default: all).
        #[arg(long)]
        only: Option<String>,
        /// Threads for the GA batches (default: all cores). Throughput figures are always one core.
        #[arg(long)]
        threads: Option<usize>,
        /// Skip the fits; only measure evaluations per second.
        #[arg(long)]
        speed_only: bool,
        /// Write each throughput case (parameters, target fields, our loss and
        /// gradient) as JSON into this directory, for bench/jax_fit_reference.py.
        #[arg(long)]
        export_jax: Option<String>,
        /// Instead: fit the real designs of `bench/designs/` with the
        /// default settings and print each one's mean per-colour IoU.
        #[arg(long)]
        designs: bool,
        /// With --designs: validation (default), test or all. Choose on
        /// validation; look at test once, at the end.
        #[arg(long, default_value = "validation")]
        split: String,
        /// With --designs: fit the anti-aliased `_hard` PNGs.
        #[arg(long)]
        hard: bool,
        /// With --designs: how the fit starts, periodic (the default) or
        /// genetic (the paper's GA: the "before" figures of issue 37).
        #[arg(long, default_value = "periodic")]
        init: String,
        /// With --designs: the designs' folder.
        #[arg(long, default_value = "bench/designs")]
        designs_dir: std::path::PathBuf,
        /// Instead: fit every shipped designer example to its own render
        /// drawn away from its defaults, and the fish scales to three
        /// truths (issue 9); --only names some.
        #[arg(long, conflicts_with = "designs")]
        own: bool,
    },
    /// Step times of every request kind at its largest realistic size
    /// (render-pattern 2048², fit-eval at grid 1024, pixel 4096² full mask,
    /// inspect 4096² every colour, fit quick, decode-image of a big PNG).
    Slices {
        /// Comma-separated kinds to run (default: all).
        #[arg(long)]
        only: Option<String>,
        /// Accepted for symmetry with other benches; output is always JSON.
        #[arg(long)]
        json: bool,
    },
    /// Texture: the paper's Tables 1–3 (model and scale accuracy on a
    /// held-out quarter of every model's base textures and under the
    /// paper's random image split, space regressions' R²),
    /// PCN-2 seconds per 256² texture, retrieval ms, index size.
    Texture {
        /// Base textures per model (default: the shipped index's).
        #[arg(long, default_value_t = filigree::texture::build::BuildConfig::default().dataset.per_model)]
        per_model: usize,
        #[arg(long, default_value_t = 128)]
        size: usize,
        /// Skip the second light and the crops.
        #[arg(long)]
        no_augment: bool,
        /// The index settings as JSON (IndexConfig; missing fields default),
        /// e.g. '{"c_model": 1, "pcn": {"hash_bits": 8}}'.
        #[arg(long)]
        index_config: Option<String>,
        /// Random looks per base (default: the shipped index's).
        #[arg(long)]
        looks: Option<usize>,
        /// The cross-implementation set (`python3 bench/texture-xset/make_set.py DIR`);
        /// skipped with a note when DIR has no labels.csv.
        #[arg(long, default_value = "target/texture-xset")]
        xset: std::path::PathBuf,
        /// Which part of it: validation (for choices), test (once, at the end) or all.
        #[arg(long, default_value = "validation")]
        xset_split: String,
        #[arg(long)]
        json: bool,
    },
    /// Texture: a built index (the shipped one by default) on the
    /// cross-implementation set: accuracy, top-3, calibration, "no close
    /// model", per model and family (issue 36).
    TextureXset {
        #[arg(long, default_value = "assets/texture-index.bin")]
        index: std::path::PathBuf,
        #[arg(long, default_value = "target/texture-xset")]
        xset: std::path::PathBuf,
        /// validation (for choices), test (once, at the end) or all.
        #[arg(long, default_value = "validation")]
        split: String,
        #[arg(long)]
        json: bool,
    },
    /// Texture models: render ms per model at SIZE², dataset time at DATASET_SIZE².
    TextureModels {
        #[arg(long, default_value_t = 5)]
        repeats: usize,
        #[arg(long, default_value_t = 256)]
        size: usize,
        /// 0 skips the dataset.
        #[arg(long, default_value_t = 128)]
        dataset_size: usize,
        #[arg(long, default_value_t = 2)]
        threads: usize,
        /// The dataset with the paper's augmentation (2 lights × 4 crops).
        #[arg(long)]
        augmented: bool,
        #[arg(long)]
        json: bool,
    },
    /// Tangle: every shipped grammar expanded (rules, steps, shapes, vertices,
    /// seconds) beside the paper's Table 1, and a shapely/GEOS baseline run
    /// in the same process when Python has shapely.
    Tangle {
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Comma-separated grammar names, or `baseline` (default: all).
        #[arg(long)]
        only: Option<String>,
        /// Accepted for symmetry with other benches; output is always JSON.
        #[arg(long)]
        json: bool,
    },
    /// Micro: render time per sphere-tracing step strategy (paper Table 2),
    /// a fibrous volume made three ways at four noise scales (Table 1) and
    /// reconstruction per microstructure and optimiser (Table 3).
    Micro {
        #[arg(long, default_value_t = 3)]
        repeats: usize,
        /// Image side in pixels.
        #[arg(long, default_value_t = 160)]
        size: u32,
        /// Only `render` (Tables 1 and 2), `fit` (Table 3) or `loss` (one
        /// loss evaluation at 32³ and its split).
        #[arg(long)]
        only: Option<String>,
        /// Table 3: two problems, one seed, a short budget.
        #[arg(long)]
        quick: bool,
        /// Table 3: seeds per problem and optimiser.
        #[arg(long, default_value_t = 3)]
        seeds: u64,
        /// Table 3: threads (shards of each fit); default all cores.
        #[arg(long)]
        threads: Option<usize>,
        /// Accepted for symmetry with other benches; output is always JSON.
        #[arg(long)]
        json: bool,
    },
    /// Pixel-art texturing: the fish and trunk cases stage by stage, plus a 512² Laplace solve.
    Pixel {
        #[arg(long, default_value_t = 10)]
        repeats: usize,
        /// Accepted for symmetry with other benches; output is always JSON.
        #[arg(long)]
        json: bool,
    },
}

pub fn run(w: Which) -> Result<(), String> {
    match w {
        Which::Fit {
            only,
            threads,
            own: true,
            ..
        } => fit_designs::run_own(only.as_deref(), crate::cmd::threads(threads)?),
        Which::Fit {
            only,
            threads,
            designs: true,
            split,
            hard,
            designs_dir,
            init,
            ..
        } => fit_designs::run(
            &designs_dir,
            (&split, only.as_deref()),
            hard,
            &init,
            crate::cmd::threads(threads)?,
        ),
        Which::Fit {
            quick,
            seeds,
            only,
            threads,
            speed_only,
            export_jax,
            ..
        } => fit_bench::run(
            quick,
            seeds,
            only.as_deref(),
            threads,
            speed_only,
            export_jax.as_deref(),
        ),
        Which::Inspect { repeats, .. } => {
            let png = TEST_PNG_1024;
            let opts = InspectOptions::default();
            let mut secs = vec![];
            for _ in 0..repeats.max(1) {
                let t = Instant::now();
                inspect(png, &opts).map_err(|e| e.to_string())?;
                secs.push(t.elapsed().as_secs_f64());
            }
            let (min, median) = min_median(secs);
            let out = json!({"bench": "inspect", "image": "1024x1024 png", "png_bytes": png.len(), "seconds": {"min": min, "median": median}});
            println!("{out}");
            Ok(())
        }
        Which::Texture {
            per_model,
            size,
            no_augment,
            index_config,
            looks,
            xset,
            xset_split,
            ..
        } => texture_bench::bench(texture_bench::BenchArgs {
            per_model,
            size,
            augment: !no_augment,
            index: index_config,
            looks,
            xset,
            xset_split,
        }),
        Which::Slices { only, .. } => slices_bench::run(only.as_deref()),
        Which::TextureXset {
            index, xset, split, ..
        } => texture_xset::run(&index, &xset, &split),
        Which::TextureModels {
            repeats,
            size,
            dataset_size,
            threads,
            augmented,
            ..
        } => texture_bench::models(repeats, size, dataset_size, threads, augmented),
        Which::Tangle { repeats, only, .. } => tangle_bench::run(repeats, only.as_deref()),
        Which::Micro {
            repeats,
            size,
            only,
            quick,
            seeds,
            threads,
            ..
        } => {
            let only = only.as_deref();
            if !matches!(only, None | Some("render") | Some("fit") | Some("loss")) {
                return Err("--only: expected `render`, `fit` or `loss`".into());
            }
            let parts = micro_bench::Parts {
                render: only.is_none() || only == Some("render"),
                fit: only.is_none() || only == Some("fit"),
                loss: only == Some("loss"),
                quick,
                seeds,
                threads: crate::cmd::threads(threads)?,
            };
            micro_bench::run(repeats, size, parts)
        }
        Which::Pixel { repeats, .. } => {
            println!("{}", pixel_bench(repeats.max(1))?);
            Ok(())
        }
    }
}

/// A 1024² PNG with 65,536 colours (gradients), the same file the browser
/// test `tests/e2e/perf.test.mjs` inspects in the worker, so the two timings compare.
pub const TEST_PNG_1024: &[u8] = include_bytes!("../../tests/fixtures/gradient-1024.png");
/// Inputs and parameters of one case of `assets/pixel/cases.json`.
fn pixel_case(name: &str) -> Result<(PixelInputs, PixelParams), String> {
    let cases: serde_json::Value =
        serde_json::from_slice(fixture("cases.json")?).map_err(|e| e.to_string())?;
    let c = &cases[name];
    let file = |k: &str| -> Result<&'static [u8], String> {
        fixture(
            c[k].as_str()
                .ok_or_else(|| format!("case {name}: no {k}"))?,
        )
    };
    let img = |k: &str| -> Result<Rgba8Image, String> {
        decode(file(k)?, Limits::default()).map_err(|e| format!("{name} {k}: {e}"))
    };
    #[derive(serde::Deserialize)]
    struct Strokes {
        strokes: Vec<filigree::pixel::Stroke>,
    }
    let strokes: Strokes = serde_json::from_slice(file("strokes")?).map_err(|e| e.to_string())?;
    let params: PixelParams =
        serde_json::from_value(c["params"].clone()).map_err(|e| format!("case {name}: {e}"))?;
    let inputs = PixelInputs {
        source: img("source")?,
        mask: img("mask")?,
        elements: Elements::Sheet(img("sheet")?),
        strokes: strokes.strokes,
    };
    Ok((inputs, params))
}

fn min_median_json(v: Vec<f64>) -> serde_json::Value {
    let (min, median) = min_median(v);
    json!({"min": min, "median": median})
}

fn pixel_bench(repeats: usize) -> Result<serde_json::Value, String> {
    let mut cases = vec![];
    for name in ["fish", "trunk"] {
        let (inputs, params) = pixel_case(name)?;
        // Seconds per stage per repeat: setup (input checks), positions,
        // colour map, orientation solve, placement, total. Stages are timed
        // at the job's step boundaries, so this is exactly what the browser runs.
        let mut secs: Vec<Vec<f64>> = vec![vec![]; 6];
        let mut last = None;
        for _ in 0..repeats {
            let t_all = Instant::now();
            let mut per = [0.0f64; 6];
            let t = Instant::now();
            let mut job =
                PixelJob::new(inputs.clone(), params.clone()).map_err(|e| e.to_string())?;
            per[0] = t.elapsed().as_secs_f64();
            let out = loop {
                let slot = match job.stage() {
                    Stage::Positions => 1,
                    Stage::ColourMap => 2,
                    Stage::Orientation => 3,
                    Stage::Placement | Stage::Done => 4,
                };
                let t = Instant::now();
                let step = job.step().map_err(|e| e.to_string())?;
                per[slot] += t.elapsed().as_secs_f64();
                if let Step::Done(out) = step {
                    break out;
                }
            };
            per[5] = t_all.elapsed().as_secs_f64();
            for (k, v) in per.iter().enumerate() {
                secs[k].push(*v);
            }
            last = Some(out);
        }
        let out = last.expect("at least one repeat");
        let s = &out.stats;
        let mut it = secs.into_iter().map(min_median_json);
        let mut next = || it.next().expect("six stages");
        cases.push(json!({
            "case": name,
            "size": [out.image.width, out.image.height],
            "placed": s.placed,
            "positions": s.positions,
            "colours_before": s.colours_before,
            "colours_after": s.colours_after,
            "colour_map_used": s.colour_map_used.name(),
            "annotated_pixels": s.annotated_pixels,
            "solve_iterations": s.solve.map(|v| v.iterations),
            "seconds": {
                "setup": next(), "positions": next(), "colour_map": next(),
                "orientation_solve": next(), "placement": next(), "total": next()
            }
        }));
    }
    // A 512² field with three annotated strokes, for scale.
    let side = 512usize;
    let strokes: Vec<filigree::pixel::Stroke> = vec![
        vec![[40.0, 60.0], [250.0, 120.0], [470.0, 80.0]],
        vec![[60.0, 450.0], [256.0, 300.0], [450.0, 460.0]],
        vec![[256.0, 180.0], [256.0, 260.0]],
    ];
    let ann = filigree::pixel::orientation::annotate(side as u32, side as u32, &strokes, 4)
        .map_err(|e| e.to_string())?;
    let mut times = vec![];
    let mut stats = None;
    for _ in 0..repeats {
        let t = Instant::now();
        let (_, st) =
            filigree::pixel::laplace::solve(side, side, ann.fixed.clone(), ann.values.clone());
        times.push(t.elapsed().as_secs_f64());
        stats = Some(st);
    }
    Ok(json!({
        "bench": "pixel",
        "repeats": repeats,
        "cases": cases,
        "laplace_512": {"size": [side, side], "annotated_pixels": ann.count(), "iterations": stats.map(|s| s.iterations), "seconds": min_median_json(times)}
    }))
}
