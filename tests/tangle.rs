//! Tangle end to end through the request layer: every shipped grammar
//! expands to completion and its final shapes tile the start shapes;
//! same seed, same SVG; budgets stop runaway grammars with a message;
//! edits regrow only their subtree; the CLI writes what the request says.
use filigree::api::run_json;
use filigree::core::job::run_quietly;
use filigree::geom::polygon::Polygon;
use filigree::tangle::api::{
    start_tangle, Edit, ExportFormat, StartRequest, TangleRequest, TangleResponse,
};
use filigree::tangle::examples::{example, EXAMPLES};
use std::collections::BTreeMap;

fn run(req: TangleRequest) -> TangleResponse {
    run_quietly(start_tangle(req).unwrap()).unwrap()
}

fn req(grammar: &str) -> TangleRequest {
    TangleRequest {
        grammar: grammar.to_string(),
        ..Default::default()
    }
}

/// The polygon of shape `i` of a response.
fn poly(r: &TangleResponse, i: usize) -> Polygon {
    let s = &r.shapes[i];
    let mut k = s.first as usize;
    let mut rings = vec![];
    for &n in &s.rings {
        let ring = (k..k + n as usize)
            .map(|j| glam::DVec2::new(r.points[2 * j] as f64, r.points[2 * j + 1] as f64))
            .collect();
        rings.push(ring);
        k += n as usize;
    }
    Polygon { rings }
}

fn finals(r: &TangleResponse) -> Vec<usize> {
    (0..r.shapes.len())
        .filter(|&i| r.shapes[i].died == -1)
        .collect()
}

/// Every shipped grammar runs to completion (no budget stop), and the
/// final shapes (decoration marks aside) cover exactly the area of the
/// start shapes: splits, outlines and placement conserve area.
#[test]
fn every_example_expands_and_its_shapes_tile_the_start() {
    for ex in EXAMPLES.iter().filter(|e| e.name != "village") {
        let r = run(req(ex.grammar));
        assert_eq!(r.stopped, None, "{}", ex.name);
        assert!(
            r.stats.steps > 3 && r.stats.shapes > 100,
            "{}: {:?}",
            ex.name,
            r.stats
        );
        let start: f64 = (0..r.shapes.len())
            .filter(|&i| r.shapes[i].born == -1)
            .map(|i| poly(&r, i).area())
            .sum();
        let end: f64 = finals(&r)
            .into_iter()
            .filter(|&i| !r.shapes[i].mark)
            .map(|i| poly(&r, i).area())
            .sum();
        assert!(
            (end - start).abs() < 2e-3 * start,
            "{}: final area {end} vs start {start}",
            ex.name
        );
    }
}

/// Final shapes of a split/outline grammar do not overlap: the union of
/// all of them has the sum of their areas.
#[test]
fn final_shapes_do_not_overlap() {
    let r = run(req(example("checkerboard").unwrap().grammar));
    let polys: Vec<Polygon> = finals(&r)
        .into_iter()
        .filter(|&i| !r.shapes[i].mark)
        .map(|i| poly(&r, i))
        .collect();
    let sum: f64 = polys.iter().map(Polygon::area).sum();
    let union: f64 = Polygon::union_all(&polys).iter().map(Polygon::area).sum();
    assert!((union - sum).abs() < 1e-3 * sum, "{union} vs {sum}");
}

/// The village example reaches the paper's scale (≥ 18,000 shapes).
#[test]
fn the_village_reaches_eighteen_thousand_shapes() {
    let r = run(req(example("village").unwrap().grammar));
    assert_eq!(r.stopped, None);
    assert!(r.stats.shapes >= 18_000, "{:?}", r.stats);
}

#[test]
fn the_same_seed_gives_the_same_svg_and_another_seed_another() {
    let svg = |seed| {
        run(TangleRequest {
            seed,
            export: ExportFormat::Svg,
            ..req(example("leaf").unwrap().grammar)
        })
        .svg
        .unwrap()
    };
    let a = svg(3);
    assert_eq!(a, svg(3));
    assert_ne!(a, svg(4));
    let r = run(TangleRequest {
        seed: 3,
        ..req(example("leaf").unwrap().grammar)
    });
    assert_eq!(a.matches("<path ").count(), r.stats.shapes);
}

#[test]
fn a_runaway_grammar_is_stopped_with_a_clear_message() {
    let r = run(TangleRequest {
        max_shapes: 2_000,
        ..req("regularSplit(line, 30, 1) : a -> [a]\n")
    });
    let m = r.stopped.expect("stopped");
    assert!(
        m.contains("shape budget of 2000") && m.contains("line 1"),
        "{m}"
    );
    let r = run(TangleRequest {
        max_steps: 40,
        ..req("ungroup() : a -> [a]\n")
    });
    assert!(r.stopped.unwrap().contains("step budget"));
}

#[test]
fn grammar_errors_name_the_field_line_and_column() {
    let e = start_tangle(req("outline(25) : a -> [b]\nplace(20, 25 : b -> [c]\n"))
        .err()
        .unwrap();
    assert_eq!(e.field(), Some("grammar"));
    let (line, _) = e.position().expect("a syntax error");
    assert_eq!(line, 2);
    let e = run_json(
        "tangle",
        r#"{"grammar": "outline(2) : a -> [b]", "max_shapes": 0}"#,
    )
    .err()
    .unwrap();
    assert_eq!(e.field(), Some("max_shapes"));
}

/// Editing a step's parameter regrows only its subtree: every final
/// shape not made by that step or its dependents is unchanged.
#[test]
fn an_edit_regrows_only_its_subtree() {
    let g = "start rect(400, 400) : a
regularSplit(line, 100, 1) : a -> [q]
ungroup() : q -> [u]
outline(10) : u -> [in, ring]
regularSplit(line, 8, 0) : in -> [s]
";
    let base = run(req(g));
    // The third outline step.
    let step = base
        .steps
        .iter()
        .enumerate()
        .filter(|(_, s)| s.operator == "outline")
        .nth(2)
        .unwrap()
        .0;
    let mut params = BTreeMap::new();
    params.insert("distance".to_string(), 30.0);
    let edited = run(TangleRequest {
        edits: vec![Edit { step, params }],
        ..req(g)
    });
    assert_eq!(edited.stats.steps, base.stats.steps);
    let key = |r: &TangleResponse, i: usize| {
        let p = poly(r, i);
        (
            p.centroid().x.round() as i64,
            p.centroid().y.round() as i64,
            (p.area() * 10.0).round() as i64,
        )
    };
    let mut a: Vec<_> = finals(&base).into_iter().map(|i| key(&base, i)).collect();
    let mut b: Vec<_> = finals(&edited)
        .into_iter()
        .map(|i| key(&edited, i))
        .collect();
    a.sort();
    b.sort();
    let same = a.iter().filter(|k| b.binary_search(k).is_ok()).count();
    // 16 cells; one cell's ring and slices changed, the other 15 did not.
    assert!(
        same >= a.len() * 15 / 16 - 2 && same < a.len(),
        "{same} of {}",
        a.len()
    );
    let e = run_json(
        "tangle",
        &format!(
            r#"{{"grammar": {}, "edits": [{{"step": 999, "params": {{}}}}]}}"#,
            serde_json::to_string(g).unwrap()
        ),
    )
    .err()
    .unwrap();
    assert_eq!(e.field(), Some("edits.0"));
}

/// A `keep` request continues from the expansion the instance kept for
/// the same document: more edits replay only the new ones, other edits
/// (an undo, a changed value) replay on a copy of the unedited expansion,
/// and another document starts afresh. Every answer is the one a request
/// from scratch gives, byte for byte.
#[test]
fn a_kept_expansion_answers_edits_exactly_as_a_replay_from_scratch() {
    use filigree::tangle::api::forget_kept;
    forget_kept();
    let g = example("leaf").unwrap().grammar;
    let edit = |step: usize, d: f64| Edit {
        step,
        params: BTreeMap::from([("distance".to_string(), d)]),
    };
    let base = run(req(g));
    let outlines: Vec<usize> = (0..base.steps.len())
        .filter(|&k| base.steps[k].operator == "outline")
        .collect();
    assert!(outlines.len() >= 3, "{outlines:?}");
    let (a, b) = (outlines[outlines.len() - 1], outlines[outlines.len() - 2]);
    let reroll = Edit {
        step: a,
        params: BTreeMap::new(),
    };
    let sequence: Vec<(Vec<Edit>, u64, bool)> = vec![
        (vec![], 1, false),                            // new document: expand
        (vec![edit(a, 3.0)], 1, true),                 // one more edit
        (vec![edit(a, 3.0), edit(b, 4.0)], 1, true),   // and another
        (vec![edit(a, 3.0)], 1, true),                 // undo: from the fresh copy
        (vec![edit(a, 5.0)], 1, true),                 // a changed value
        (vec![edit(a, 5.0), reroll.clone()], 1, true), // a re-expansion
        (vec![edit(a, 5.0)], 2, false),                // another seed: afresh
        (vec![], 2, true),                             // its unedited tangle
    ];
    for (edits, seed, reused) in sequence {
        let r = TangleRequest {
            edits: edits.clone(),
            seed,
            export: ExportFormat::Svg,
            ..req(g)
        };
        let scratch = run(r.clone());
        let job = start_tangle(TangleRequest { keep: true, ..r }).unwrap();
        assert_eq!(job.reused(), reused, "{edits:?} seed {seed}");
        let kept = run_quietly(job).unwrap();
        assert_eq!(kept, scratch, "{edits:?} seed {seed}");
    }
    // A request without `keep` neither reads nor replaces what is kept.
    run(TangleRequest { seed: 9, ..req(g) });
    let job = start_tangle(TangleRequest {
        keep: true,
        seed: 2,
        ..req(g)
    })
    .unwrap();
    assert!(job.reused());
    forget_kept();
}

#[test]
fn start_shapes_from_text_svg_and_rings() {
    let g = "outline(6) : a -> [b, c]\n";
    let r = run(TangleRequest {
        start: Some(StartRequest::Text {
            text: "Hi".into(),
            height: 200.0,
        }),
        ..req(g)
    });
    let starts = r.shapes.iter().filter(|s| s.born == -1).count();
    assert_eq!(starts, 3, "H, the i's stem and its dot");
    let svg = r#"<svg xmlns="http://www.w3.org/2000/svg"><path d="M0 0H100V100H0Z M20 20V80H80V20Z"/></svg>"#;
    let r = run(TangleRequest {
        start: Some(StartRequest::Svg { svg: svg.into() }),
        ..req(g)
    });
    assert_eq!(poly(&r, 0).rings.len(), 2, "the nested path is a hole");
    let bad = start_tangle(TangleRequest {
        start: Some(StartRequest::Svg { svg: "<svg".into() }),
        ..req(g)
    })
    .err()
    .unwrap();
    assert_eq!(bad.field(), Some("start.svg"));
}

#[test]
fn the_cli_writes_the_svg_the_request_makes() {
    let dir = std::env::temp_dir().join(format!("filigree-tangle-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("leaf.svg");
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_filigree"))
        .args([
            "tangle",
            "--grammar",
            "assets/tangle/leaf.tangle",
            "--seed",
            "2",
            "--out",
        ])
        .arg(&out)
        .output()
        .unwrap();
    assert!(
        st.status.success(),
        "{}",
        String::from_utf8_lossy(&st.stderr)
    );
    let want = run(TangleRequest {
        seed: 2,
        export: ExportFormat::Svg,
        ..req(example("leaf").unwrap().grammar)
    })
    .svg
    .unwrap();
    assert_eq!(std::fs::read_to_string(&out).unwrap(), want);
    let bad = dir.join("bad.tangle");
    std::fs::write(&bad, "outline(25) : a -> [b]\nfrobnicate(3) : b -> [c]\n").unwrap();
    let st = std::process::Command::new(env!("CARGO_BIN_EXE_filigree"))
        .args(["tangle", "--grammar"])
        .arg(&bad)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    assert!(!st.status.success());
    let err = String::from_utf8_lossy(&st.stderr);
    assert!(
        err.contains("bad.tangle") && err.contains("line 2"),
        "{err}"
    );
}
