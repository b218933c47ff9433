//! `filigree bench tangle`: every shipped grammar expanded natively, with
//! rules, steps, final shapes and vertices, seconds (min/median), beside the
//! paper's Table 1; and, when Python with shapely is installed, the same
//! splits and outlines done with shapely/GEOS in the same run as a
//! baseline (`scripts/tangle_shapely_baseline.py`).
use filigree::core::job::{run_to_end, Cancel};
use filigree::tangle::api::{start_tangle, TangleRequest};
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

pub fn run(repeats: usize, only: Option<&str>) -> Result<(), String> {
    let want = |n: &str| only.is_none_or(|o| o.split(',').any(|x| x.trim() == n));
    let mut rows = vec![];
    for ex in EXAMPLES.iter().filter(|e| want(e.name)) {
        let (mut v, _) = expand(ex.grammar, 1.0, repeats)?;
        v["grammar"] = json!(ex.name);
        rows.push(v);
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
            "about": "each shipped grammar expanded natively (seed 1, default settings); seconds min/median over repeats; the paper's Table 1 (3.1 GHz machine, its own grammars) beside; the shapely baseline is the same grid+outline work in Python/GEOS in this run",
            "rows": rows,
            "baseline": baseline,
            "paper_table1": table1,
        })
    );
    Ok(())
}
