//! `filigree bench fit --designs`: fit every real design of
//! `bench/designs/` (issue 37: drawn outside the team, each with a program
//! written as a user would) with the default settings, the request the
//! Fit button sends, and print each one's mean per-colour IoU.
//!
//! `filigree bench fit --own`: fit every shipped designer example to its
//! own render drawn away from its defaults (issue 9 item 8), and the fish
//! scales to three truths spread over their ranges (issue 9 item 5). These
//! were integration tests of ten seconds each; the unit tests below keep a
//! fast check of both (the cheapest designs, and the scales' hardest
//! truth).
use filigree::core::job::Cancel;
use filigree::core::parallel::run_sharded_threads;
use filigree::pattern::api::{start_fit, FitOutput, FitRequest, Init};
use filigree::pattern::field::Scene;
use filigree::pattern::fit::colour_indices;
use filigree::pattern::generators::generator;
use filigree::pattern::record::{Program, RecordLimits};
use filigree::pattern::render;
use filigree::pattern::target::{mean_iou, palette_indices};
use filigree::raster::{decode, encode_png, Limits};
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
    crate::cmd::print_json(&out)?;
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
    let req = FitRequest {
        program: program.clone(),
        target_png: Some(png.clone()),
        init,
        ..Default::default()
    };
    let t0 = Instant::now();
    let out = fit_on_threads(req, threads).map_err(|e| format!("{name}: {e}"))?;
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

/// Run `req` as `threads` shards, one thread each (the same bits as one).
fn fit_on_threads(mut req: FitRequest, threads: usize) -> Result<FitOutput, String> {
    let jobs = (0..threads)
        .map(|k| {
            req.shards = Some((k, threads));
            start_fit(&req).map_err(|e| e.to_string())
        })
        .collect::<Result<Vec<_>, _>>()?;
    run_sharded_threads(jobs, &Cancel::new(), |_, _| {}).map_err(|e| e.to_string())
}

/// The shipped designer examples (`filigree::pattern::generators`) that
/// `--own` fits to their own renders.
pub const OWN_DESIGNS: &[&str] = &[
    "dots",
    "checkers",
    "crosses",
    "waves",
    "scales",
    "graph-paper",
    "stripes",
    "honeycomb",
];

/// Side of an own-render target in pixels; the IoU is measured at it too.
/// At 96 px the defaults pick a small grid and each fit takes seconds;
/// lines thinner than a pixel there cannot be fitted from it.
const OWN_SIDE: usize = 96;

/// How far from its defaults an own-render target is drawn: this fraction
/// of each parameter's range, alternating in sign (a user's fit starts
/// from the program as written).
const OWN_SHIFT: f64 = 0.12;

/// Fish scales' truths (dx, dy, ox, oy, w) spread over their ranges. The
/// row pitch `dy` has a needle-thin basin (an error moves row `j` by
/// `j·Δdy`), and the last truth once ended with `ox` at its bound and `dx`
/// bent to make up for it (the phase ranges now span a lattice period).
const SCALES_TRUTHS: [[f64; 5]; 3] = [
    [0.15, 0.055, 0.03, 0.05, 0.012],
    [0.19, 0.085, 0.06, 0.02, 0.008],
    [0.17, 0.06, 0.01, 0.07, 0.015],
];

/// The scales' bounds: pitches within 0.001 (a tenth of a pixel at 96 px),
/// the width within 0.0005 (it keeps a small bias, the target's distances
/// being measured between pixel centres), and the picture (the fit may land
/// one lattice vector away: the same picture) at IoU 0.97.
const SCALES_PITCH: f64 = 1e-3;
const SCALES_WIDTH: f64 = 5e-4;
const SCALES_IOU: f64 = 0.97;

/// Fit design `name` with the default request to its render at `truth`
/// (`None`: its defaults moved by [`OWN_SHIFT`]); the row: truth, fitted
/// values, the mean per-colour IoU at [`OWN_SIDE`] and the seconds.
fn own_fit(name: &str, truth: Option<&[f64]>, threads: usize) -> Result<Value, String> {
    let src = generator(name)
        .ok_or_else(|| format!("{name}: no such design"))?
        .source;
    let p = Program::parse(src).map_err(|e| format!("{name}: {e}"))?;
    let scene = Scene::new(
        p.record(&p.defaults(), &RecordLimits::default())
            .map_err(|e| format!("{name}: {e}"))?,
    );
    let truth: Vec<f64> = match truth {
        Some(t) => t.to_vec(),
        None => (scene.rec.float_decls().iter().enumerate())
            .map(|(k, d)| {
                let s = if k % 2 == 0 { OWN_SHIFT } else { -OWN_SHIFT };
                (d.default + s * (d.hi - d.lo)).clamp(d.lo, d.hi)
            })
            .collect(),
    };
    let target = render::render(&scene, &truth, OWN_SIDE, 1).map_err(|e| e.to_string())?;
    let req = FitRequest {
        program: src.into(),
        target_png: Some(encode_png(&target).map_err(|e| e.to_string())?),
        ..Default::default()
    };
    let t0 = Instant::now();
    let out = fit_on_threads(req, threads).map_err(|e| format!("{name}: {e}"))?;
    let secs = t0.elapsed().as_secs_f64();
    let fitted = out.result.params;
    let iou = mean_iou(
        &colour_indices(&scene, &truth, OWN_SIDE).map_err(|e| e.to_string())?,
        &colour_indices(&scene, &fitted, OWN_SIDE).map_err(|e| e.to_string())?,
    );
    Ok(
        json!({"design": name, "iou": iou, "truth": truth, "fitted": fitted,
        "seconds": (secs * 100.0).round() / 100.0}),
    )
}

/// A scales row's errors in dx, dy and w, and whether it meets the bounds.
fn scales_verdict(row: &Value) -> (Value, bool) {
    let at = |k: &str, i: usize| row[k][i].as_f64().unwrap_or(f64::NAN);
    let err = |i: usize| (at("fitted", i) - at("truth", i)).abs();
    let (dx, dy, w) = (err(0), err(1), err(4));
    let iou = row["iou"].as_f64().unwrap_or(0.0);
    let good = dx <= SCALES_PITCH && dy <= SCALES_PITCH && w <= SCALES_WIDTH && iou >= SCALES_IOU;
    (json!({"dx": dx, "dy": dy, "w": w}), good)
}

/// `filigree bench fit --own`: every design of [`OWN_DESIGNS`] (or those
/// `only` names) fitted to its own render, then the fish scales at
/// [`SCALES_TRUTHS`]; the bar is IoU 0.95 for each design.
pub fn run_own(only: Option<&str>, threads: usize) -> Result<(), String> {
    let wanted: Option<Vec<&str>> = only.map(|s| s.split(',').map(str::trim).collect());
    if let Some(bad) = wanted.iter().flatten().find(|n| !OWN_DESIGNS.contains(n)) {
        return Err(format!(
            "--only {bad}: the designs are {}",
            OWN_DESIGNS.join(", ")
        ));
    }
    let mut rows = vec![];
    for name in OWN_DESIGNS {
        if wanted.as_ref().is_none_or(|w| w.contains(name)) {
            let row = own_fit(name, None, threads)?;
            eprintln!("{row}");
            rows.push(row);
        }
    }
    let mut scales = vec![];
    if wanted.as_ref().is_none_or(|w| w.contains(&"scales")) {
        for truth in SCALES_TRUTHS {
            let mut row = own_fit("scales", Some(&truth), threads)?;
            let (errors, good) = scales_verdict(&row);
            row["errors"] = errors;
            row["good"] = json!(good);
            eprintln!("{row}");
            scales.push(row);
        }
    }
    let good = rows
        .iter()
        .filter(|r| r["iou"].as_f64().unwrap_or(0.0) >= GOOD_IOU)
        .count();
    let out = json!({"bench": "fit-own", "threads": threads, "side": OWN_SIDE, "shift": OWN_SHIFT,
        "settings": "defaults (the Fit button's request: program and target image only)",
        "good_iou": GOOD_IOU, "good": good, "of": rows.len(), "designs": rows,
        "scales": {"pitch_within": SCALES_PITCH, "width_within": SCALES_WIDTH, "iou_at_least": SCALES_IOU,
            "good": scales.iter().filter(|r| r["good"] == json!(true)).count(), "of": scales.len(),
            "truths": scales}});
    crate::cmd::print_json(&out)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast check of `bench fit --own` (which fits all eight): the
    /// designs whose fits take about a second each fit their own render
    /// with the defaults (mean per-colour IoU ≥ 0.95; 1 of 9 designs
    /// reached it before issue 9).
    #[test]
    fn the_quick_designs_fit_their_own_render() {
        for name in ["dots", "checkers", "crosses", "graph-paper", "stripes"] {
            let row = own_fit(name, None, 1).unwrap();
            let iou = row["iou"].as_f64().unwrap();
            assert!(iou >= GOOD_IOU, "{name}: IoU {iou:.4} < {GOOD_IOU}: {row}");
        }
    }

    /// The fast check of the scales' three truths: the last, whose phase
    /// once ended at its bound with `dx` bent (IoU well below 0.95), gives
    /// the pitches, the width and the picture within the bounds.
    #[test]
    fn scales_recover_pitch_and_width_where_the_phase_once_hit_its_bound() {
        let row = own_fit("scales", Some(&SCALES_TRUTHS[2]), 1).unwrap();
        let (errors, good) = scales_verdict(&row);
        assert!(good, "{row}: errors {errors}");
    }
}
