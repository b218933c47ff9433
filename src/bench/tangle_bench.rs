//! `filigree bench tangle`: every shipped grammar expanded natively, with
//! rules, steps, final shapes and vertices, seconds (min/median), beside the
//! paper's Table 1; and, when Python with shapely is installed, the same
//! splits and outlines done with shapely/GEOS in the same run as a
//! baseline (`scripts/tangle_shapely_baseline.py`).
use filigree::core::job::{run_to_end, Cancel};
use filigree::tangle::api::{
    answer_id, forget_kept_edits, start_tangle, Edit, TangleRequest, TangleResponse,
};
use filigree::tangle::examples::EXAMPLES;
use serde_json::{json, Value};
use std::time::Instant;

/// The paper's Table 1: name, rules (nodes), steps, shapes, seconds.
const TABLE1: [(&str, u32, u32, u32, f64); 5] = [
    ("siggraph", 48, 216, 1624, 1.6),
    ("tree", 22, 42, 3096, 2.6),
    ("albert", 25, 85, 1590, 1.43),
    ("tiger", 33, 201, 3650, 2.84),
    ("village", 101, 907, 18396, 190.5),
];

/// The grammar the shapely baseline reproduces: a grid of 20-unit cells,
/// each outlined four times (18,000 final shapes), no wobble. The browser's
/// latency bench (`tests/e2e/tangle-latency.bench.mjs`) grows the same file.
pub const BASELINE_GRAMMAR: &str = include_str!("../../bench/tangle-baseline.tangle");

fn expand(grammar: &str, wobble: f64, repeats: usize) -> Result<(Value, f64), String> {
    let mut secs = vec![];
    let mut stats = Value::Null;
    for _ in 0..repeats.max(1) {
        let req = TangleRequest {
            grammar: grammar.to_string(),
            wobble,
            ..Default::default()
        };
        let t = Instant::now();
        let job = start_tangle(req).map_err(|e| e.to_string())?;
        let r = run_to_end(job, &Cancel::new(), |_| {}).map_err(|e| e.to_string())?;
        secs.push(t.elapsed().as_secs_f64());
        stats = json!({
            "rules": r.stats.rules, "steps": r.stats.steps,
            "shapes": r.stats.shapes, "vertices": r.stats.vertices,
            "stopped": r.stopped,
        });
    }
    let (min, median) = super::min_median(secs);
    let mut v = stats;
    v["seconds"] = json!({"min": min, "median": median});
    Ok((v, min))
}

/// Shapes made by step `s` and the steps that depend on it (its subtree).
fn subtree(r: &TangleResponse, s: usize) -> usize {
    let mut made: std::collections::HashSet<u32> = r.steps[s].outputs.iter().copied().collect();
    for st in &r.steps[s + 1..] {
        if st.inputs.iter().any(|i| made.contains(i)) {
            made.extend(st.outputs.iter().copied());
        }
    }
    made.len()
}

/// Bytes of an answer's typed arrays as the worker sends them (shape
/// columns, points, removed keys, the steps' indices), as the latency
/// bench's `answerBytes` counts them in the page.
fn answer_bytes(r: &TangleResponse) -> usize {
    let rings: usize = r.shapes.iter().map(|s| s.rings.len()).sum();
    let columns = r.shapes.len() * (4 * 8 + 1) + 4 * (r.shapes.len() + 1) + 4 * rings;
    let steps: usize = r
        .steps
        .iter()
        .map(|s| 4 * (s.inputs.len() + s.outputs.len()))
        .sum();
    columns + 4 * r.points.len() + 4 * r.removed.len() + steps
}

/// Seconds of wall clock and of this thread's CPU time.
#[derive(Clone, Copy)]
struct Secs {
    wall: f64,
    cpu: Option<f64>,
}

fn timed(req: TangleRequest) -> Result<(TangleResponse, Secs, bool), String> {
    let c = super::measure::thread_cpu_ms();
    let t = Instant::now();
    let job = start_tangle(req).map_err(|e| e.to_string())?;
    let reused = job.reused();
    let r = run_to_end(job, &Cancel::new(), |_| {}).map_err(|e| e.to_string())?;
    let wall = t.elapsed().as_secs_f64();
    let cpu = c
        .zip(super::measure::thread_cpu_ms())
        .map(|(a, b)| (b - a) * 1e-3);
    Ok((r, Secs { wall, cpu }, reused))
}

/// Issue 10's edit figure: a parameter edit on the step with the largest
/// subtree of at most 2,000 shapes, answered from the kept expansion
/// (what the browser's worker does) against a replay from scratch, and the
/// answer alone (the same request again: nothing to regrow). With
/// `operator`, only its steps are candidates.
fn edit_row(
    name: &str,
    grammar: &str,
    operator: Option<&str>,
    repeats: usize,
) -> Result<Value, String> {
    let doc = TangleRequest {
        grammar: grammar.to_string(),
        keep: true,
        ..Default::default()
    };
    let (base, _, _) = timed(doc.clone())?;
    let Some((step, size)) = (0..base.steps.len())
        .filter(|&k| {
            !base.steps[k].params.is_empty() && operator.is_none_or(|o| base.steps[k].operator == o)
        })
        .map(|k| (k, subtree(&base, k)))
        .filter(|&(_, n)| n <= 2000)
        .max_by_key(|&(k, n)| (n, std::cmp::Reverse(k)))
    else {
        return Ok(json!({"grammar": name, "edit": "no step with parameters"}));
    };
    let p = &base.steps[step].params[0];
    let mut secs = (vec![], vec![], vec![]);
    let mut drags = (vec![], vec![]);
    let mut deltas = vec![];
    let mut bytes = (0, 0, 0, 0);
    for rep in 0..repeats.max(1) {
        let value = (p.value * (0.8 + 0.05 * rep as f64)).clamp(p.min, p.max);
        let edit = Edit {
            step,
            params: [(p.name.to_string(), value)].into(),
        };
        let edited = TangleRequest {
            edits: vec![edit.clone()],
            ..doc.clone()
        };
        timed(doc.clone())?; // the document as kept, unedited
        let (r1, kept, reused) = timed(edited.clone())?;
        // A second edit of the same step (where it was regrown), dragged:
        // each move replaces the last edit. Kept snapshots start it after
        // the first edit; without them (before) both edits are replayed.
        let group = base.steps[step].group;
        if let Some(pos) = r1.steps.iter().position(|s| s.group == group) {
            let second = |f: f64| TangleRequest {
                edits: vec![
                    edit.clone(),
                    Edit {
                        step: pos,
                        params: [(p.name.to_string(), (value * f).clamp(p.min, p.max))].into(),
                    },
                ],
                ..doc.clone()
            };
            timed(second(1.1))?; // the drag's first move
            drags.0.push(timed(second(1.12))?.1);
            forget_kept_edits();
            drags.1.push(timed(second(1.14))?.1);
        }
        let (_, again, _) = timed(edited.clone())?;
        // The same edit answered as the page asks for it: a delta against the
        // answer it shows (the unedited tangle, kept again first; the edited
        // snapshots forgotten, so the edit regrows its subtree as above).
        forget_kept_edits();
        timed(doc.clone())?;
        let (d, delta, _) = timed(TangleRequest {
            base: Some(answer_id(&doc)),
            ..edited.clone()
        })?;
        if d.base.is_none() {
            return Err(format!("{name}: the edit was not answered with a delta"));
        }
        deltas.push(delta);
        bytes = (
            answer_bytes(&r1),
            answer_bytes(&d),
            d.shapes.len(),
            d.removed.len(),
        );
        let (_, scratch, _) = timed(TangleRequest {
            keep: false,
            ..edited
        })?;
        if !reused {
            return Err(format!("{name}: the edit did not reuse the kept expansion"));
        }
        secs.0.push(kept);
        secs.1.push(again);
        secs.2.push(scratch);
    }
    let mm = |v: Vec<Secs>| {
        let cpu: Option<Vec<f64>> = v.iter().map(|s| s.cpu).collect();
        let (min, median) = super::min_median(v.iter().map(|s| s.wall).collect());
        let cpu_median = cpu.map(|c| super::min_median(c).1);
        json!({"min": min, "median": median, "cpu_median": cpu_median})
    };
    let kept_min = secs.0.iter().map(|s| s.wall).fold(f64::INFINITY, f64::min);
    let scratch_min = secs.2.iter().map(|s| s.wall).fold(f64::INFINITY, f64::min);
    Ok(json!({
        "grammar": name,
        "step": step,
        "operator": base.steps[step].operator,
        "parameter": p.name,
        "subtree_shapes": size,
        "shapes_in_answer": base.shapes.len(),
        "kept_edit_seconds": mm(secs.0),
        "kept_edit_delta_seconds": mm(deltas),
        "answer_bytes": {"full": bytes.0, "delta": bytes.1},
        "delta_shapes": {"added": bytes.2, "removed": bytes.3},
        "answer_only_seconds": mm(secs.1),
        "scratch_edit_seconds": mm(secs.2),
        "speedup_kept_vs_scratch": scratch_min / kept_min,
        "drag_move_seconds": mm(drags.0),
        "drag_move_seconds_before": mm(drags.1),
    }))
}

pub fn run(repeats: usize, only: Option<&str>) -> Result<(), String> {
    let want = |n: &str| only.is_none_or(|o| o.split(',').any(|x| x.trim() == n));
    let mut rows = vec![];
    for ex in EXAMPLES.iter().filter(|e| want(e.name)) {
        let (mut v, _) = expand(ex.grammar, 1.0, repeats)?;
        v["grammar"] = json!(ex.name);
        rows.push(v);
    }
    let mut edits = vec![];
    for ex in EXAMPLES
        .iter()
        .filter(|e| want(e.name) && ["leaf", "village"].contains(&e.name))
    {
        edits.push(edit_row(ex.name, ex.grammar, None, repeats)?);
        if ex.name == "leaf" {
            // The step the browser's latency bench edits.
            edits.push(edit_row(ex.name, ex.grammar, Some("outline"), repeats)?);
        }
    }
    let mut baseline = Value::Null;
    if want("baseline") {
        let (mut ours, min) = expand(BASELINE_GRAMMAR, 0.0, repeats)?;
        let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../scripts/tangle_shapely_baseline.py");
        let shapely = std::process::Command::new("python3")
            .arg(&script)
            .arg(repeats.max(1).to_string())
            .output()
            .ok()
            .filter(|o| o.status.success())
            .and_then(|o| serde_json::from_slice::<Value>(&o.stdout).ok());
        ours["grammar"] = json!("baseline (grid + 4 outlines, no wobble)");
        let ratio = shapely
            .as_ref()
            .and_then(|s| s["seconds"]["min"].as_f64())
            .map(|s| s / min);
        baseline = json!({
            "ours": ours,
            "shapely": shapely.unwrap_or(json!("not measured: python3 with shapely is not installed")),
            "speedup_vs_shapely": ratio,
        });
    }
    let table1: Vec<Value> = TABLE1
        .iter()
        .map(|(n, r, s, sh, t)| json!({"name": n, "rules": r, "steps": s, "shapes": sh, "seconds": t}))
        .collect();
    println!(
        "{}",
        json!({
            "bench": "tangle",
            "about": "each shipped grammar expanded natively (seed 1, default settings); seconds min/median over repeats; the paper's Table 1 (3.1 GHz machine, its own grammars) beside; the shapely baseline is the same grid+outline work in Python/GEOS in this run; edits: one step's parameter changed, answered from the kept expansion (as the browser's worker does) vs replayed from scratch, and the answer alone; a drag move of a second edit of that step (the last edit replaced) from the snapshot before it, and before (all edits replayed); cpu_median: this thread's CPU seconds (CLOCK_THREAD_CPUTIME_ID), which the load does not inflate",
            "rows": rows,
            "edits": edits,
            "baseline": baseline,
            "paper_table1": table1,
        })
    );
    Ok(())
}
