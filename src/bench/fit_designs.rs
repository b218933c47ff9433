//! `filigree bench fit --designs`: fit every real design of
//! `bench/designs/` (issue 37: drawn outside the team, each with a program
//! written as a user would) with the default settings, the request the
//! Fit button sends, and print each one's mean per-colour IoU.
use filigree::core::job::Cancel;
use filigree::core::parallel::run_sharded_threads;
use filigree::pattern::api::{start_fit, FitRequest, Init};
use filigree::pattern::field::Scene;
use filigree::pattern::fit::colour_indices;
use filigree::pattern::record::{Program, RecordLimits};
use filigree::pattern::target::{mean_iou, palette_indices};
use filigree::raster::{decode, Limits};
use serde_json::{json, Value};
use std::path::Path;
use std::time::Instant;

/// IoU a design must reach to count as fitted (the bar).
const GOOD_IOU: f64 = 0.95;

/// RGB tolerance of the comparison (the fit's default).
const TOLERANCE: f64 = 60.0;

/// Fit the designs of `dir` whose split is `split` (`validation`, `test`
/// or `all`; `only` names some), from their crisp PNGs or with `hard`
/// their anti-aliased ones, starting with `init`, on `threads` threads.
pub fn run(
    dir: &Path,
    (split, only): (&str, Option<&str>),
    hard: bool,
    init: &str,
    threads: usize,
) -> Result<(), String> {
    let init: Init = serde_json::from_value(json!(init))
        .map_err(|_| format!("--init {init}: use periodic, genetic, random or nelder-mead"))?;
    if !["validation", "test", "all"].contains(&split) {
        return Err(format!(
            "--split {split}: use validation, test or all (choose on validation; look at test once)"
        ));
    }
    let list = dir.join("designs.json");
    let designs: Vec<Value> = serde_json::from_str(
        &std::fs::read_to_string(&list).map_err(|e| format!("{}: {e}", list.display()))?,
    )
    .map_err(|e| format!("{}: {e}", list.display()))?;
    let wanted: Option<Vec<&str>> = only.map(|s| s.split(',').map(str::trim).collect());
    let mut rows = vec![];
    for d in &designs {
        let name = d["name"]
            .as_str()
            .ok_or("designs.json: a design without a name")?;
        let its_split = d["split"].as_str().unwrap_or("");
        if (split != "all" && its_split != split)
            || wanted.as_ref().is_some_and(|w| !w.contains(&name))
        {
            continue;
        }
        let row = fit_design(dir, name, (hard, init), threads)?;
        eprintln!("{row}");
        rows.push(json!({"split": its_split, "kind": d["kind"], "row": row}));
    }
    let good = rows
        .iter()
        .filter(|r| r["row"]["iou"].as_f64().unwrap_or(0.0) >= GOOD_IOU)
        .count();
    let out = json!({"bench": "fit-designs", "split": split, "hard": hard, "init": init, "threads": threads,
        "settings": "defaults (the Fit button's request: program and target image only)",
        "good_iou": GOOD_IOU, "good": good, "of": rows.len(), "designs": rows});
    println!(
        "{}",
        serde_json::to_string_pretty(&out).map_err(|e| e.to_string())?
    );
    Ok(())
}

/// Fit one design with the defaults; its IoU at the target's size.
fn fit_design(
    dir: &Path,
    name: &str,
    (hard, init): (bool, Init),
    threads: usize,
) -> Result<Value, String> {
    let read = |file: String| {
        let p = dir.join(&file);
        std::fs::read(&p).map_err(|e| format!("{}: {e}", p.display()))
    };
    let program = String::from_utf8(read(format!("{name}.flg"))?)
        .map_err(|_| format!("{name}.flg is not UTF-8"))?;
    let png = read(format!("{name}{}.png", if hard { "_hard" } else { "" }))?;
    let truth: Value = serde_json::from_slice(&read(format!("{name}.truth.json"))?)
        .map_err(|e| format!("{name}.truth.json: {e}"))?;
    let mut req = FitRequest {
        program: program.clone(),
        target_png: Some(png.clone()),
        init,
        ..Default::default()
    };
    let t0 = Instant::now();
    let jobs = (0..threads)
        .map(|k| {
            req.shards = Some((k, threads));
            start_fit(&req).map_err(|e| format!("{name}: {e}"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let out =
        run_sharded_threads(jobs, &Cancel::new(), |_, _| {}).map_err(|e| format!("{name}: {e}"))?;
    let secs = t0.elapsed().as_secs_f64();
    let img = decode(&png, Limits::default()).map_err(|e| format!("{name}: {e}"))?;
    let p = Program::parse(&program).map_err(|e| format!("{name}: {e}"))?;
    let scene = Scene::new(
        p.record_on(
            &p.defaults(),
            &RecordLimits::default(),
            filigree::pattern::fit::image_canvas(&img),
        )
        .map_err(|e| format!("{name}: {e}"))?,
    );
    let (w, h) = (img.width as usize, img.height as usize);
    let want = palette_indices(&img, &scene.rec.colours, (w, h), TOLERANCE);
    let got = colour_indices(&scene, &out.result.params, w.max(h)).map_err(|e| e.to_string())?;
    let iou = mean_iou(&want, &got);
    Ok(
        json!({"design": name, "iou": (iou * 1e4).round() / 1e4, "seconds": (secs * 100.0).round() / 100.0,
        "loss": out.result.loss, "evaluations": out.result.evaluations,
        "fitted": out.named, "truth": truth}),
    )
}
