//! Tangle end to end through the request layer: every shipped grammar
//! expands to completion and its final shapes tile the start shapes;
//! same seed, same SVG; budgets stop runaway grammars with a message;
//! edits regrow only their subtree; the CLI writes what the request says.
use filigree::api::run_json;
use filigree::core::job::run_quietly;
use filigree::tangle::api::{
    start_tangle, Edit, ExportFormat, StartRequest, TangleRequest, TangleResponse,
};
use filigree::tangle::examples::{example, EXAMPLES};
use filigree::tangle::geom::polygon::Polygon;
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

/// Issue 34 items 2–3: grammars that recurse through fine work ran for
/// minutes and gigabytes under the default budgets (5,000 steps, 50,000
/// shapes). The work and point budgets (counted, not timed, so the same
/// natively and in wasm) stop them at a step named by its rule and line,
/// and the tangle so far is kept.
#[test]
fn runaway_work_is_stopped_by_the_work_and_point_budgets() {
    for (grammar, why) in [
        // 10.7 s and 1.66 GB natively before.
        ("regularSplit(line, 100, 0) : a -> [a]\n", "work budget"),
        // 87.6 s and 569 MB natively before.
        ("outline(10) : a -> [a]\n", "budget of"),
        // A mutual cycle: 39.6 s before.
        (
            "outline(10) : a -> [b, b]\noutline(10) : b -> [a, a]\n",
            "budget of",
        ),
    ] {
        let r = run(req(grammar));
        let m = r
            .stopped
            .unwrap_or_else(|| panic!("{grammar}: not stopped"));
        assert!(m.contains(why) && m.contains("(line "), "{grammar}: {m}");
        assert!(r.stats.steps > 0, "{grammar}: the steps so far are kept");
    }
    // One step of a million-unit rectangle asked for four million pieces;
    // such a start is now refused, and a split too fine for the points it
    // would make stops before it runs.
    let e = start_tangle(req(
        "start rect(1000000, 1000000) : a\nregularSplit(line, 1, 0) : a -> [b]\n",
    ))
    .err()
    .map(|e| e.to_string());
    assert!(
        e.as_deref()
            .is_some_and(|m| m.contains("between 0 and 20000 units a side")),
        "{e:?}"
    );
    let r = run(req(
        "start rect(20000, 20000) : a\nregularSplit(line, 1, 0) : a -> [b]\n",
    ));
    let m = r.stopped.expect("stopped");
    assert!(
        m.contains("stopped at step 1") && m.contains("budget of"),
        "{m}"
    );
    let e = start_tangle(TangleRequest {
        start: Some(filigree::tangle::api::StartRequest::Text {
            text: "Hi".into(),
            height: 100_000.0,
        }),
        ..req("outline(4) : a -> [b, c]\n")
    })
    .err()
    .map(|e| e.to_string());
    assert!(e.is_some_and(|m| m.contains("letter height")));
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

/// Random edit sessions on the leaf (new edits on any step with
/// parameters, a slider drag replacing the last edit, re-expansions,
/// undos): every `keep` answer regrown from what the instance kept is byte
/// for byte the answer of a replay from scratch, and a drag or an undo
/// starts from the snapshot before the last edit instead of replaying all
/// of them.
#[test]
fn kept_regrows_equal_fresh_expansions_for_random_edits() {
    use filigree::tangle::api::forget_kept;
    let g = example("leaf").unwrap().grammar;
    // A small fixed generator: the sessions are the same on every run.
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut next = move |n: usize| {
        state = state
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        ((state >> 33) % n as u64) as usize
    };
    for session in 0..2u64 {
        forget_kept();
        let seed = 1 + session;
        let doc = TangleRequest { seed, ..req(g) };
        let mut edits: Vec<Edit> = vec![];
        let mut last = run(TangleRequest {
            keep: true,
            ..doc.clone()
        });
        for round in 0..9 {
            let action = if edits.is_empty() { 0 } else { next(4) };
            // The least of the request's edits the kept state must have done.
            let expect_done;
            match action {
                // A new edit: a parameter of a random step, or a re-draw.
                0 | 1 => {
                    expect_done = edits.len();
                    let with: Vec<usize> = (0..last.steps.len())
                        .filter(|&k| !last.steps[k].params.is_empty())
                        .collect();
                    let step = with[next(with.len())];
                    let params = if action == 1 {
                        BTreeMap::new()
                    } else {
                        let p = &last.steps[step].params[next(last.steps[step].params.len())];
                        let f = 0.85 + 0.05 * next(9) as f64;
                        let v = (p.value * f).clamp(p.min, p.max);
                        let v = if p.integer { v.round() } else { v };
                        BTreeMap::from([(p.name.to_string(), v)])
                    };
                    edits.push(Edit { step, params });
                }
                // A drag: the last edit's value moves.
                2 => {
                    expect_done = edits.len() - 1;
                    let e = edits.last_mut().unwrap();
                    for v in e.params.values_mut() {
                        *v *= 1.0 + 0.02 * (1 + next(5)) as f64;
                    }
                    if e.params.is_empty() {
                        // A re-draw again: the same request, answered as kept.
                        continue;
                    }
                }
                // An undo.
                _ => {
                    edits.pop();
                    expect_done = edits.len();
                }
            }
            let r = TangleRequest {
                edits: edits.clone(),
                export: if round % 3 == 0 {
                    ExportFormat::Svg
                } else {
                    ExportFormat::None
                },
                ..doc.clone()
            };
            let scratch = run(r.clone());
            let job = start_tangle(TangleRequest { keep: true, ..r }).unwrap();
            assert!(job.reused(), "session {session} round {round}");
            let done = job.reused_edits();
            assert!(
                done >= expect_done,
                "session {session} round {round}: continued after {done} of {} edits, expected at least {expect_done}",
                edits.len()
            );
            let kept = run_quietly(job).unwrap();
            assert_eq!(kept, scratch, "session {session} round {round}: {edits:?}");
            last = kept;
        }
    }
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

/// A drawing tool's SVG: a 24-unit icon on a white background, a disc with
/// a white bar cut out of it, and a dot overlapping the disc's rim.
const ICON: &str = r##"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 24 24">
  <rect width="24" height="24" fill="#fff"/>
  <circle cx="12" cy="12" r="10" fill="#222"/>
  <rect x="11" y="6" width="2" height="12" fill="white"/>
  <circle cx="21" cy="12" r="2"/>
</svg>"##;

#[test]
fn an_uploaded_svg_is_fitted_into_the_frame_the_grammar_was_written_for() {
    let frame_of = |grammar: &str| {
        let r = run(TangleRequest {
            start: Some(StartRequest::Svg { svg: ICON.into() }),
            max_steps: 1,
            ..req(grammar)
        });
        let starts: Vec<Polygon> = (0..r.shapes.len())
            .filter(|&i| r.shapes[i].born == -1)
            .map(|i| poly(&r, i))
            .collect();
        (starts.clone(), Polygon::bbox_all(&starts))
    };
    // The grammar's own start: a 720-unit square, so the 21-unit-wide ink
    // (disc x 2..22, dot to 23) is scaled ×720/21 and sits in it.
    let (starts, (lo, hi)) = frame_of("start rect(720, 720) : a\noutline(6) : a -> [b, c]\n");
    assert_eq!(
        starts.len(),
        1,
        "the dot overlapping the rim is part of the disc"
    );
    assert_eq!(
        starts[0].rings.len(),
        2,
        "the white bar is a hole, the background paper"
    );
    assert!(
        (hi.x - lo.x - 720.0).abs() < 0.01 && lo.x.abs() < 0.01,
        "{lo} {hi}"
    );
    assert!(lo.y > 0.0 && hi.y < 720.0, "centred: {lo} {hi}");
    let s2 = (720.0f64 / 21.0).powi(2);
    let (disc, dot) = (std::f64::consts::PI * 100.0, std::f64::consts::PI * 4.0);
    let a = starts[0].area() / s2;
    assert!(
        a > disc - 24.0 && a < disc - 24.0 + dot,
        "{a}: the disc less the bar, plus part of the dot"
    );
    // No start line: the 800×600 rectangle the grammar would start from.
    let (_, (lo, hi)) = frame_of("outline(6) : a -> [b, c]\n");
    assert!(
        lo.y.abs() < 0.01 && (hi.y - 600.0).abs() < 0.01,
        "{lo} {hi}"
    );
    assert!(lo.x > 0.0 && hi.x < 800.0, "{lo} {hi}");
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

/// The answer's shapes, points and steps' shape indices cross to the
/// browser as little-endian bytes: decoding them gives back every field of
/// every shape, every point and every step's inputs and outputs (what
/// `www/tangle/draw.js` reads).
#[test]
fn shapes_and_points_serialise_as_byte_columns_that_decode_exactly() {
    let r = run(req(example("checkerboard").unwrap().grammar));
    let v = serde_json::to_value(&r).unwrap();
    let bytes = |name: &str| -> Vec<u8> {
        let c = if name == "points" {
            &v["points"]
        } else {
            &v["shapes"][name]
        };
        c.as_array()
            .unwrap()
            .iter()
            .map(|b| b.as_u64().unwrap() as u8)
            .collect()
    };
    let u32s = |name: &str| -> Vec<u32> {
        bytes(name)
            .chunks(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    let n = r.shapes.len();
    assert_eq!(v["shapes"]["count"], n);
    let (tag, group, id, first) = (u32s("tag"), u32s("group"), u32s("id"), u32s("first"));
    let (born, died, fill) = (u32s("born"), u32s("died"), u32s("fill"));
    let (flags, ring_first, rings) = (bytes("flags"), u32s("ring_first"), u32s("rings"));
    assert_eq!(ring_first.len(), n + 1);
    for (i, s) in r.shapes.iter().enumerate() {
        assert_eq!(
            (tag[i], group[i], id[i], first[i]),
            (s.tag, s.group, s.id, s.first)
        );
        assert_eq!(
            (born[i] as i32, died[i] as i32),
            (s.born as i32, s.died as i32)
        );
        assert_eq!(f32::from_bits(fill[i]), s.fill);
        assert_eq!(flags[i], u8::from(s.white_lines) | (u8::from(s.mark) << 1));
        assert_eq!(
            rings[ring_first[i] as usize..ring_first[i + 1] as usize],
            s.rings[..]
        );
    }
    let pts: Vec<f32> = u32s("points").into_iter().map(f32::from_bits).collect();
    assert_eq!(pts, r.points);
    // Each step's input and output shape indices: u32 bytes too.
    let le = |c: &serde_json::Value| -> Vec<u32> {
        let b: Vec<u8> = c
            .as_array()
            .unwrap()
            .iter()
            .map(|b| b.as_u64().unwrap() as u8)
            .collect();
        b.chunks(4)
            .map(|c| u32::from_le_bytes(c.try_into().unwrap()))
            .collect()
    };
    assert_eq!(v["steps"].as_array().unwrap().len(), r.steps.len());
    for (k, st) in r.steps.iter().enumerate() {
        assert_eq!(le(&v["steps"][k]["inputs"]), st.inputs, "step {k}");
        assert_eq!(le(&v["steps"][k]["outputs"]), st.outputs, "step {k}");
    }
    assert!(r.steps.iter().any(|s| s.outputs.len() > 1));
    assert!(r.shapes.iter().any(|s| s.died >= 0) && r.shapes.iter().any(|s| s.born == -1));
}

/// Issue 34 item 7: an edit whose value is NaN (a JS number the page can
/// send) said "outline has no parameter 'distance' (it has: distance)".
#[test]
fn an_edit_with_a_nan_value_says_so() {
    let e = start_tangle(TangleRequest {
        edits: vec![Edit {
            step: 0,
            params: BTreeMap::from([("distance".to_string(), f64::NAN)]),
        }],
        ..req("outline(4) : a -> [b, c]\n")
    })
    .and_then(run_quietly)
    .expect_err("refused");
    assert_eq!(e.field(), Some("edits.0.params.distance"), "{e}");
    assert!(
        e.to_string()
            .contains("distance must be a finite number (got NaN)"),
        "{e}"
    );
}

/// `base` with delta `d` applied as the page applies it
/// (`www/tangle/delta.js`): the base's shapes without the removed keys,
/// plus the added shapes, in key order; points laid out again; every
/// shape's `born`/`died` read from the steps.
fn apply_delta(base: &TangleResponse, d: &TangleResponse) -> TangleResponse {
    assert_eq!(
        d.base.as_deref(),
        Some(base.answer.as_str()),
        "a delta of this base"
    );
    let gone: std::collections::HashSet<u32> = d.removed.iter().copied().collect();
    assert_eq!(gone.len(), d.removed.len(), "each key removed once");
    let points_of = |r: &TangleResponse, i: usize| {
        let s = &r.shapes[i];
        let n: u32 = s.rings.iter().sum();
        r.points[2 * s.first as usize..2 * (s.first + n) as usize].to_vec()
    };
    let mut all: Vec<(filigree::tangle::api::ShapeOut, Vec<f32>)> = vec![];
    for (i, s) in base.shapes.iter().enumerate() {
        if !gone.contains(&s.key) {
            all.push((s.clone(), points_of(base, i)));
        }
    }
    for (i, s) in d.shapes.iter().enumerate() {
        all.push((s.clone(), points_of(d, i)));
    }
    all.sort_by_key(|(s, _)| s.key);
    assert!(
        all.windows(2).all(|w| w[0].0.key < w[1].0.key),
        "keys are unique"
    );
    let mut points = vec![];
    let mut shapes = vec![];
    for (mut s, p) in all {
        s.first = (points.len() / 2) as u32;
        (s.born, s.died) = (-1, -1);
        points.extend(p);
        shapes.push(s);
    }
    for (k, st) in d.steps.iter().enumerate() {
        for &o in &st.outputs {
            shapes[o as usize].born = k as i64;
        }
        for &i in &st.inputs {
            shapes[i as usize].died = k as i64;
        }
    }
    TangleResponse {
        base: None,
        removed: vec![],
        dirty: None,
        shapes,
        points,
        ..d.clone()
    }
}

/// Answers that name the answer the page holds (`base`): where the
/// instance kept that answer's expansion, the answer is a delta, and the
/// base with the delta applied is exactly the full answer a fresh replay
/// gives (shapes column by column, points, steps, exports), over several
/// grammars and edit sessions (new edits, a drag replacing the last edit,
/// re-draws, undo and redo, the same request again); where it did not (a
/// fresh instance, an unknown id, another document), the answer is in full
/// and equal to the fresh one. An edit's delta is a small part of the
/// answer, and its dirty box holds every removed and added shape.
#[test]
fn a_delta_applied_to_its_base_is_the_full_answer() {
    use filigree::tangle::api::{answer_id, forget_kept};
    for name in ["leaf", "checkerboard", "pebbles", "streamlines"] {
        forget_kept();
        let g = example(name).unwrap().grammar;
        let doc = req(g);
        let first = run(TangleRequest {
            keep: true,
            ..doc.clone()
        });
        assert_eq!(first.base, None, "{name}: nothing held yet: in full");
        assert_eq!(first.answer, answer_id(&doc));
        let with: Vec<usize> = (0..first.steps.len())
            .filter(|&k| !first.steps[k].params.is_empty())
            .collect();
        assert!(with.len() >= 2, "{name}: steps with parameters");
        let p = |k: usize, f: f64| {
            let q = &first.steps[k].params[0];
            let v = (q.value * f).clamp(q.min, q.max);
            let v = if q.integer { v.round() } else { v };
            Edit {
                step: k,
                params: BTreeMap::from([(q.name.to_string(), v)]),
            }
        };
        let reroll = |k: usize| Edit {
            step: k,
            params: BTreeMap::new(),
        };
        let (a, b) = (with[with.len() - 1], with[with.len() / 2]);
        // Each document of the session after the one before (the page's base).
        let session: Vec<Vec<Edit>> = vec![
            vec![p(a, 0.7)],                        // an edit
            vec![p(a, 0.75)],                       // dragged: the last edit replaced
            vec![p(a, 0.75), p(b, 1.2)],            // another edit
            vec![p(a, 0.75)],                       // undo
            vec![p(a, 0.75), p(b, 1.2)],            // redo
            vec![p(a, 0.75), p(b, 1.2)],            // the same again (an export)
            vec![p(a, 0.75), p(b, 1.2), reroll(a)], // a re-draw
            vec![],                                 // undo to the start
        ];
        let mut held = first.clone();
        let mut deltas = 0;
        for (round, edits) in session.into_iter().enumerate() {
            let r = TangleRequest {
                edits,
                export: if round == 5 {
                    ExportFormat::Svg
                } else {
                    ExportFormat::None
                },
                ..doc.clone()
            };
            let full = run(r.clone());
            let got = run(TangleRequest {
                keep: true,
                base: Some(held.answer.clone()),
                ..r.clone()
            });
            assert_eq!(got.answer, full.answer, "{name} round {round}");
            let Some(_) = got.base else {
                panic!("{name} round {round}: the instance holds the base, yet answered in full");
            };
            deltas += 1;
            let applied = apply_delta(&held, &got);
            assert_eq!(applied, full, "{name} round {round}");
            if round == 5 {
                assert!(
                    got.shapes.is_empty() && got.removed.is_empty(),
                    "{name}: nothing changed"
                );
                assert_eq!(got.dirty, None);
            } else if round < 5 {
                assert!(
                    got.shapes.len() < full.shapes.len(),
                    "{name} round {round}: the delta adds {} of {} shapes",
                    got.shapes.len(),
                    full.shapes.len()
                );
            }
            // The dirty box holds every removed and added shape.
            if let Some([x0, y0, x1, y1]) = got.dirty {
                let inside = |q: &Polygon| {
                    let (lo, hi) = q.bbox();
                    let e = 1e-3;
                    lo.x >= x0 - e && lo.y >= y0 - e && hi.x <= x1 + e && hi.y <= y1 + e
                };
                for i in 0..got.shapes.len() {
                    assert!(
                        inside(&poly(&got, i)),
                        "{name} round {round}: added shape {i}"
                    );
                }
                for (i, s) in held.shapes.iter().enumerate() {
                    if got.removed.contains(&s.key) {
                        assert!(
                            inside(&poly(&held, i)),
                            "{name} round {round}: removed key {}",
                            s.key
                        );
                    }
                }
            } else {
                assert!(got.shapes.is_empty() && got.removed.is_empty());
            }
            held = applied;
        }
        assert_eq!(deltas, 8);
        // An instance that does not hold the base (a fresh worker) answers in full.
        let edits = vec![p(a, 0.6)];
        let full = run(TangleRequest {
            edits: edits.clone(),
            ..doc.clone()
        });
        forget_kept();
        let got = run(TangleRequest {
            keep: true,
            base: Some(held.answer.clone()),
            edits: edits.clone(),
            ..doc.clone()
        });
        assert_eq!(got.base, None, "{name}: base not held: in full");
        assert_eq!(got, full, "{name}: the full answer is the fresh one");
        // An id no answer has, and another document's answer: in full.
        for base in ["0123".to_string(), first_answer_of_seed(g, 7)] {
            let got = run(TangleRequest {
                keep: true,
                base: Some(base),
                edits: edits.clone(),
                ..doc.clone()
            });
            assert_eq!(got.base, None, "{name}");
            assert_eq!(got, full, "{name}");
        }
        // Without `keep` a base is not read.
        let got = run(TangleRequest {
            base: Some(full.answer.clone()),
            edits,
            ..doc.clone()
        });
        assert_eq!(got.base, None);
    }
    forget_kept();
}

fn first_answer_of_seed(g: &str, seed: u64) -> String {
    filigree::tangle::api::answer_id(&TangleRequest { seed, ..req(g) })
}

/// The grammar is parsed once per text: an edit of a kept expansion and a
/// new seed or wobble of the same grammar parse nothing; another grammar
/// text is parsed.
#[test]
fn a_kept_grammar_is_not_parsed_again() {
    use filigree::tangle::api::{forget_kept, grammar_parses};
    forget_kept();
    let g = example("leaf").unwrap().grammar;
    let doc = TangleRequest {
        keep: true,
        ..req(g)
    };
    let r = run(doc.clone());
    let parses = grammar_parses();
    let k = (0..r.steps.len())
        .find(|&k| r.steps[k].operator == "outline")
        .unwrap();
    for d in [3.0, 4.0, 5.0] {
        run(TangleRequest {
            edits: vec![Edit {
                step: k,
                params: BTreeMap::from([("distance".to_string(), d)]),
            }],
            ..doc.clone()
        });
    }
    run(TangleRequest {
        seed: 5,
        ..doc.clone()
    });
    run(TangleRequest {
        wobble: 2.0,
        ..doc.clone()
    });
    assert_eq!(
        grammar_parses(),
        parses,
        "the same text is not parsed again"
    );
    run(TangleRequest {
        keep: true,
        ..req(example("pebbles").unwrap().grammar)
    });
    assert_eq!(grammar_parses(), parses + 1, "another text is parsed");
    forget_kept();
}
