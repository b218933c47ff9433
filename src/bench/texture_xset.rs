//! `bench texture --xset DIR`: how the index reads textures made by other
//! code than ours (issue 36). `DIR` holds the set `bench/texture-xset/`
//! writes: 256² grey PNGs and `labels.csv` (`file,model,split,variant`,
//! `model` a paper name). Reported for one split: top-1 and top-3
//! accuracy, the expected calibration error of the top probability,
//! how often the index said "no close model", and accuracy per model and
//! per family with the largest confusions between families.
use filigree::texture::api;
use filigree::texture::index::Index;
use filigree::texture::models::MODELS;
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::Path;

/// Bins of the calibration error (equal widths of the top probability).
const ECE_BINS: usize = 10;

/// One labelled image of the set.
struct Item {
    file: String,
    model: usize,
}

fn read_labels(dir: &Path, split: &str) -> Result<Vec<Item>, String> {
    let path = dir.join("labels.csv");
    let text = std::fs::read_to_string(&path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut out = Vec::new();
    for (no, line) in text.lines().enumerate().skip(1) {
        let cols: Vec<&str> = line.splitn(4, ',').collect();
        if cols.len() < 3 {
            return Err(format!(
                "{}:{}: expected file,model,split",
                path.display(),
                no + 1
            ));
        }
        if split != "all" && cols[2] != split {
            continue;
        }
        let model = MODELS
            .iter()
            .position(|m| m.name == cols[1] || m.id == cols[1])
            .ok_or_else(|| format!("{}:{}: unknown model '{}'", path.display(), no + 1, cols[1]))?;
        out.push(Item {
            file: cols[0].to_string(),
            model,
        });
    }
    if out.is_empty() {
        return Err(format!("{}: no image in split '{split}'", path.display()));
    }
    Ok(out)
}

/// The expected calibration error: `(confidence, right)` pairs binned by
/// confidence, the gap between each bin's accuracy and mean confidence
/// weighted by its share.
pub fn expected_calibration_error(pairs: &[(f64, bool)]) -> f64 {
    let mut bins = [(0.0f64, 0usize, 0usize); ECE_BINS];
    for &(p, right) in pairs {
        let b = ((p * ECE_BINS as f64) as usize).min(ECE_BINS - 1);
        bins[b].0 += p;
        bins[b].1 += right as usize;
        bins[b].2 += 1;
    }
    let n = pairs.len().max(1) as f64;
    bins.iter()
        .filter(|b| b.2 > 0)
        .map(|&(conf, right, k)| (right as f64 / k as f64 - conf / k as f64).abs() * k as f64 / n)
        .sum()
}

/// Reads every image of `split` in `dir` with `index`.
pub fn evaluate(index: &Index, dir: &Path, split: &str) -> Result<Value, String> {
    let items = read_labels(dir, split)?;
    let (mut top1, mut top3, mut not_close) = (0usize, 0usize, 0usize);
    let mut pairs = Vec::new();
    let mut per_model = vec![(0usize, 0usize); MODELS.len()];
    let mut per_family: BTreeMap<&str, (usize, usize, usize)> = BTreeMap::new();
    let mut family_confusion: BTreeMap<(&str, &str), usize> = BTreeMap::new();
    let mut model_confusion: BTreeMap<(usize, usize), usize> = BTreeMap::new();
    for it in &items {
        let path = dir.join(&it.file);
        let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let img = api::decode_gray(&bytes).map_err(|e| format!("{}: {e}", path.display()))?;
        let reading = index
            .read_models(&img)
            .map_err(|e| format!("{}: {e}", path.display()))?;
        let got = reading.ranked[0].0 as usize;
        let right = got == it.model;
        top1 += right as usize;
        top3 += reading
            .ranked
            .iter()
            .take(3)
            .any(|r| r.0 as usize == it.model) as usize;
        not_close += (!reading.close) as usize;
        pairs.push((reading.ranked[0].1, right));
        per_model[it.model].1 += 1;
        per_model[it.model].0 += right as usize;
        let (want_f, got_f) = (MODELS[it.model].family.name(), MODELS[got].family.name());
        let f = per_family.entry(want_f).or_default();
        f.0 += right as usize;
        f.1 += (want_f == got_f) as usize;
        f.2 += 1;
        if want_f != got_f {
            *family_confusion.entry((want_f, got_f)).or_default() += 1;
        }
        if !right {
            *model_confusion.entry((it.model, got)).or_default() += 1;
        }
    }
    let n = items.len() as f64;
    let mut fam: Vec<_> = family_confusion.into_iter().collect();
    fam.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    let mut models: Vec<_> = model_confusion.into_iter().collect();
    models.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)));
    Ok(json!({
        "split": split,
        "images": items.len(),
        "accuracy": top1 as f64 / n,
        "top3_accuracy": top3 as f64 / n,
        "expected_calibration_error": expected_calibration_error(&pairs),
        "no_close_model": not_close as f64 / n,
        "per_model": MODELS.iter().zip(&per_model).filter(|(_, c)| c.1 > 0)
            .map(|(m, c)| json!({"model": m.id, "right": c.0, "of": c.1}))
            .collect::<Vec<_>>(),
        "per_family": per_family.iter()
            .map(|(f, c)| json!({"family": f, "model_right": c.0, "family_right": c.1, "of": c.2}))
            .collect::<Vec<_>>(),
        "family_confusion": fam.iter().take(12)
            .map(|((a, b), k)| json!([a, b, k])).collect::<Vec<_>>(),
        "model_confusion": models.iter().take(15)
            .map(|((a, b), k)| json!([MODELS[*a].id, MODELS[*b].id, k])).collect::<Vec<_>>(),
    }))
}

/// `bench texture-xset`: the index file at `index` on `split` of the set.
pub fn run(index: &Path, dir: &Path, split: &str) -> Result<(), String> {
    let bytes = std::fs::read(index).map_err(|e| format!("{}: {e}", index.display()))?;
    let index = api::parse_index(&bytes).map_err(|e| format!("{}: {e}", index.display()))?;
    let out = evaluate(&index, dir, split)?;
    crate::cmd::print_json(&out)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_calibration_error_is_the_weighted_gap_per_bin() {
        // Perfectly calibrated: 0.95 confidence, 19 of 20 right.
        let mut pairs: Vec<(f64, bool)> = (0..20).map(|i| (0.95, i != 0)).collect();
        assert!(expected_calibration_error(&pairs) < 1e-12);
        // Over-confident half: 10 more at 0.9 confidence, all wrong: that
        // bin's gap is 0.9 and it holds a third of the pairs.
        pairs.extend((0..10).map(|_| (0.9, false)));
        let e = expected_calibration_error(&pairs);
        assert!((e - 0.3).abs() < 1e-9, "{e}");
    }
}
