//! `filigree bench tangle`: every shipped grammar expanded natively, with
//! rules, steps, final shapes and vertices, seconds (min/median), beside the
//! paper's Table 1; and, when Python with shapely is installed, the same
//! splits and outlines done with shapely/GEOS in the same run as a
//! baseline (`scripts/tangle_shapely_baseline.py`).
use filigree::core::job::{run_to_end, Cancel};
use filigree::tangle::api::{start_tangle, Edit, TangleRequest, TangleResponse};
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
/// each outlined four times (18,000 final shapes), no wobble.
pub const BASELINE_GRAMMAR: &str = "start rect(1200, 1200) : sheet
regularSplit(line, 20, 1) : sheet -> [cell]
outline(2) : cell -> [a, ra]
outline(2) : a -> [b, rb]
outline(2) : b -> [c, rc]
outline(2) : c -> [d, rd]
";

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

fn timed(req: TangleRequest) -> Result<(TangleResponse, f64, bool), String> {
    let t = Instant::now();
    let job = start_tangle(req).map_err(|e| e.to_string())?;
    let reused = job.reused();
    let r = run_to_end(job, &Cancel::new(), |_| {}).map_err(|e| e.to_string())?;
    Ok((r, t.elapsed().as_secs_f64(), reused))
}

/// Issue 10's edit figure: a parameter edit on the step with the largest
/// subtree of at most 2,000 shapes, answered from the kept expansion
/// (what the browser's worker does) against a replay from scratch, and the
/// answer alone (the same request again: nothing to regrow).
fn edit_row(name: &str, grammar: &str, repeats: usize) -> Result<Value, String> {
    let doc = TangleRequest {
        grammar: grammar.to_string(),
        keep: true,
        ..Default::default()
    };
    let (base, _, _) = timed(doc.clone())?;
    let Some((step, size)) = (0..base.steps.len())
        .filter(|&k| !base.steps[k].params.is_empty())
        .map(|k| (k, subtree(&base, k)))
        .filter(|&(_, n)| n <= 2000)
        .max_by_key(|&(k, n)| (n, std::cmp::Reverse(k)))
    else {
        return Ok(json!({"grammar": name, "edit": "no step with parameters"}));
    };
    let p = &base.steps[step].params[0];
    let mut secs = (vec![], vec![], vec![]);
    for rep in 0..repeats.max(1) {
        let value = (p.value * (0.8 + 0.05 * rep as f64)).clamp(p.min, p.max);
        let edit = Edit {
            step,
            params: [(p.name.to_string(), value)].into(),
        };
        let edited = TangleRequest {
            edits: vec![edit],
            ..doc.clone()
        };
        timed(doc.clone())?; // the document as kept, unedited
        let (_, kept, reused) = timed(edited.clone())?;
        let (_, again, _) = timed(edited.clone())?;
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
    let mm = |v: Vec<f64>| {
        let (min, median) = super::min_median(v);
        json!({"min": min, "median": median})
    };
    let kept_min = secs.0.iter().copied().fold(f64::INFINITY, f64::min);
    let scratch_min = secs.2.iter().copied().fold(f64::INFINITY, f64::min);
    Ok(json!({
        "grammar": name,
        "step": step,
        "operator": base.steps[step].operator,
        "parameter": p.name,
        "subtree_shapes": size,
        "shapes_in_answer": base.shapes.len(),
        "kept_edit_seconds": mm(secs.0),
        "answer_only_seconds": mm(secs.1),
        "scratch_edit_seconds": mm(secs.2),
        "speedup_kept_vs_scratch": scratch_min / kept_min,
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
        edits.push(edit_row(ex.name, ex.grammar, repeats)?);
    }
    let mut baseline = Value::Null;
    if want("baseline") {
        let (mut ours, min) = expand(BASELINE_GRAMMAR, 0.0, repeats)?;
        let script = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("scripts/tangle_shapely_baseline.py");
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
            "about": "each shipped grammar expanded natively (seed 1, default settings); seconds min/median over repeats; the paper's Table 1 (3.1 GHz machine, its own grammars) beside; the shapely baseline is the same grid+outline work in Python/GEOS in this run; edits: one step's parameter changed, answered from the kept expansion (as the browser's worker does) vs replayed from scratch, and the answer alone",
            "rows": rows,
            "edits": edits,
            "baseline": baseline,
            "paper_table1": table1,
        })
    );
    Ok(())
}
