use super::*;
use crate::pattern::lang::MAX_DEPTH;

fn rec(src: &str) -> Result<Recording> {
    let p = Program::parse(src)?;
    p.record(&p.defaults(), &RecordLimits::default())
}

#[test]
fn records_a_grid_with_constant_folding() {
    let r = rec("param dx in [0.1, 0.3] = 0.2;\nint param n in [1, 5] = 3;\n\
                 for i in 0..n { for j in 0..n { circle(0.1 + i * dx, 0.1 + j * dx, 0.05, fill: \"#f00\"); } }")
    .unwrap();
    assert_eq!(r.shapes.len(), 9);
    assert_eq!(r.colours, vec![[255, 255, 255], [255, 0, 0]]);
    // Only dx-dependent arithmetic is on the tape, not the loop counters.
    assert!(r.tape.active_len() < 20, "{}", r.tape.active_len());
    let mut vals = vec![];
    r.tape.forward(&[0.25], &mut vals);
    let p = r.prims[8];
    assert!((vals[p.fields[0] as usize] - 0.6).abs() < 1e-12);
}

#[test]
fn branching_on_a_float_parameter_is_an_error_with_position() {
    let e = rec("param a in [0, 1] = 0.5;\nif a > 0.2 {\n circle(0.5, 0.5, 0.1);\n}").unwrap_err();
    assert!(
        matches!(
            e,
            Error::Syntax {
                line: 2,
                column: 4,
                ..
            }
        ),
        "{e:?}"
    );
    assert!(e.to_string().contains("int param"), "{e}");
    let e = rec("param a in [0, 1] = 0.5;\nfor i in 0..a * 4 { }").unwrap_err();
    assert!(matches!(e, Error::Syntax { line: 2, .. }), "{e:?}");
}

#[test]
fn infinite_loop_and_recursion_hit_limits_with_position() {
    let e = rec("let i = 0;\nfor k in 0..1e12 {\n  i = i + 1;\n}").unwrap_err();
    // A limit, with its place as data (the page marks it from `line`/`column`).
    assert_eq!(e.kind(), "limit", "{e:?}");
    let (line, column) = e.position().expect("a place");
    assert!(line == 2 || line == 3, "{e}");
    assert!(
        e.to_string()
            .starts_with(&format!("line {line}, column {column}: ")),
        "{e}"
    );
    assert!(e.to_string().contains("never end"), "{e}");
    let e = rec("fn f(x) { return f(x + 1); }\nlet y = f(0);").unwrap_err();
    assert_eq!((e.kind(), e.position()), ("limit", Some((1, 20))), "{e}");
    assert!(
        e.to_string().contains("line 1, column 18") && e.to_string().contains("deeper"),
        "{e}"
    );
}

#[test]
fn runtime_errors_name_the_problem() {
    let e = rec("circle(0.5, 0.5);").unwrap_err();
    assert!(
        e.to_string().contains("'circle' takes 3 numbers, got 2"),
        "{e}"
    );
    let e = rec("circle(0.5, 0.5, 0.1, fill: \"#12\");").unwrap_err();
    assert!(e.to_string().contains("not a colour"), "{e}");
    let e = rec("segment(0, 0, 1, 1, fill: \"#fff\");").unwrap_err();
    assert!(e.to_string().contains("no option 'fill'"), "{e}");
    let e = rec("let a = b + 1;").unwrap_err();
    assert_eq!(
        e,
        Error::Syntax {
            line: 1,
            column: 9,
            message: "'b' is not defined".into()
        }
    );
}

#[test]
fn transforms_paths_and_booleans() {
    let r = rec("translate(0.5, 0.5) { rotate(PI / 2) { scale(2) { circle(0.1, 0, 0.05); } } }\n\
                 path(fill: \"#00f\", stroke: \"#0f0\", width: 0.02) { move(0.1, 0.1); quad(0.5, 0, 0.9, 0.1); cubic(1, 0.5, 0.5, 1, 0.1, 0.9); }\n\
                 difference(fill: \"#000\") { rect(0.5, 0.5, 0.4, 0.4); circle(0.5, 0.5, 0.1); }")
    .unwrap();
    assert_eq!(r.shapes.len(), 3);
    let mut v = vec![];
    r.tape.forward(&[], &mut v);
    let c = r.prims[0];
    assert!(
        (v[c.fields[0] as usize] - 0.5).abs() < 1e-12
            && (v[c.fields[1] as usize] - 0.7).abs() < 1e-12
    );
    assert!((v[c.fields[2] as usize] - 0.1).abs() < 1e-12);
    // quad + 8 cubic pieces + closing segment
    assert!(matches!(
        r.shapes[1].geom,
        Geom::Path {
            len: 10,
            closed: true,
            ..
        }
    ));
    assert!(matches!(&r.shapes[2].geom, Geom::Bool(BoolOp::Difference, ch) if ch.len() == 2));
}

#[test]
fn non_finite_values_are_located_errors() {
    for (src, line, column) in [
        ("let a = 1 / 0;", 1, 11),
        ("let a = 0 / 0;", 1, 11),
        ("let z = 0;\nlet a = 2 % z;", 2, 11),
        ("let a = sqrt(-1);", 1, 9),
        ("let a = ln(0);", 1, 9),
        ("let a = pow(-8, 1 / 3);", 1, 9),
        ("let a = 1e200 * 1e200;", 1, 15),
        ("let a = exp(1000);", 1, 9),
        ("let a = -1e308 - 1e308;", 1, 16),
        (
            "param s in [1, 2];\ncircle(0.5, 0.5, 1e300 * s * 1e10);",
            2,
            28,
        ),
        (
            "scale(1e200) { scale(1e200) { circle(0.5, 0.5, 0.1); } }",
            1,
            31,
        ),
        (
            "circle(0.5, 0.5, 0.1, width: 1e308 * 10, stroke: \"#000\");",
            1,
            36,
        ),
    ] {
        let e = rec(src).unwrap_err();
        match &e {
            Error::Syntax {
                line: l, column: c, ..
            } => assert_eq!((*l, *c), (line, column), "{src}: {e}"),
            _ => panic!("{src}: {e:?}"),
        }
        let m = e.to_string();
        assert!(m.contains("finite") || m.contains("negative"), "{src}: {m}");
    }
}

#[test]
fn primitives_inside_paths_and_booleans_count_against_the_limit() {
    #[allow(clippy::disallowed_methods)] // a native test timing the limit
    let t = std::time::Instant::now();
    let e = rec("union() { for i in 0..100000 { circle(0.5, 0.5, 0.1); } }").unwrap_err();
    assert_eq!(e.kind(), "limit", "{e:?}");
    assert_eq!(e.position().map(|p| p.0), Some(1), "{e:?}");
    assert!(
        e.to_string()
            .contains("more than 5000 shapes (every primitive counts"),
        "{e}"
    );
    let e = rec("path(stroke: \"#000\") { move(0, 0); for i in 0..140000 { line(i % 2, 0.5); } }")
        .unwrap_err();
    assert!(
        e.to_string()
            .contains("more than 5000 shapes (every primitive counts"),
        "{e}"
    );
    assert!(e.to_string().contains("line 1, column"), "{e}");
    let e =
        rec("path(stroke: \"#000\") { move(0, 0); for i in 0..700 { cubic(0, 1, 1, 0, 1, 1); } }")
            .unwrap_err();
    assert!(e.to_string().contains("a cubic is 8 pieces"), "{e}");
    // Well under a second each (they stop at the limit, not at the end of the loop).
    assert!(t.elapsed().as_secs_f64() < 2.0, "{:?}", t.elapsed());
    // At the limit is fine.
    let r = rec("union() { for i in 0..4999 { circle(0.5, 0.5, 0.1); } circle(0.5, 0.5, 0.2); }")
        .unwrap();
    assert_eq!(r.prims.len(), 5000);
}

/// Families of programs that nest as deeply as the language allows:
/// `(name, program for depth k)`.
type Family = (&'static str, Box<dyn Fn(usize) -> String>);

pub(crate) fn deep_families() -> Vec<Family> {
    const C: &str = "circle(0.5, 0.5, 0.1);";
    vec![
        (
            "parentheses",
            Box::new(|k| format!("let a = {}1{};\n{C}", "(".repeat(k), ")".repeat(k))),
        ),
        (
            "negations",
            Box::new(|k| format!("let a = {}1;\n{C}", "-".repeat(k))),
        ),
        (
            "operator chain",
            Box::new(|k| format!("let a = 1{};\n{C}", " + 1".repeat(k))),
        ),
        (
            "powers",
            Box::new(|k| format!("let a = 1{};\n{C}", " ^ 1".repeat(k))),
        ),
        (
            "calls",
            Box::new(|k| format!("let a = {}1{};\n{C}", "abs(".repeat(k), ")".repeat(k))),
        ),
        (
            "blocks",
            Box::new(|k| format!("{}{C}{}", "{ ".repeat(k), " }".repeat(k))),
        ),
        (
            "ifs",
            Box::new(|k| format!("{}{C}{}", "if 1 { ".repeat(k), " }".repeat(k))),
        ),
        (
            "fors",
            Box::new(|k| format!("{}{C}{}", "for i in 0..1 { ".repeat(k), " }".repeat(k))),
        ),
        (
            "translates",
            Box::new(|k| format!("{}{C}{}", "translate(0, 0) { ".repeat(k), " }".repeat(k))),
        ),
        (
            "rotates",
            Box::new(|k| format!("{}{C}{}", "rotate(0.1) { ".repeat(k), " }".repeat(k))),
        ),
        (
            "unions",
            Box::new(|k| {
                format!(
                    "{}{C}{}",
                    "union(fill: \"#000\") { ".repeat(k.min(1))
                        + &"union() { ".repeat(k.saturating_sub(1)),
                    " }".repeat(k)
                )
            }),
        ),
        (
            "recursion",
            Box::new(|k| format!("fn f(n) {{ if n > 0 {{ f(n - 1); }} {C} }}\nf({k});")),
        ),
        (
            "recursion through blocks",
            Box::new(|k| {
                format!("fn f(n) {{ if n > 0 {{ {{ {{ {{ {{ {{ {{ {{ {{ f(n - 1); }} }} }} }} }} }} }} }} }} }}\nf({k});\n{C}")
            }),
        ),
        (
            "recursion through transforms",
            Box::new(|k| {
                format!("fn f(n) {{ if n > 0 {{ translate(0.001, 0) {{ rotate(0.01) {{ f(n - 1); }} }} }} {C} }}\nf({k});")
            }),
        ),
        (
            "recursion in arguments",
            Box::new(|k| {
                format!("fn f(n) {{ if n > 0 {{ return f(n - 1) + 1; }} return 0; }}\nlet a = f({k});\n{C}")
            }),
        ),
    ]
}

/// Parse, record, compile, draw and write SVG (everything that recurses
/// over a program's nesting).
pub(crate) fn run_all(src: &str) -> Result<()> {
    let p = Program::parse(src)?;
    let r = p.record(&p.defaults(), &RecordLimits::default())?;
    let fl = r.float_values();
    let scene = crate::pattern::field::Scene::new(r);
    crate::pattern::render::render(&scene, &fl, 8, 1)?;
    crate::pattern::render::svg(&scene, &fl, 8.0)?;
    Ok(())
}

/// The largest k for which a family's program runs (by bisection), and
/// the error at k + 1.
pub(crate) fn deepest(make: &dyn Fn(usize) -> String) -> (usize, Error) {
    let (mut lo, mut hi) = (0usize, 4 * MAX_DEPTH);
    run_all(&make(lo)).unwrap();
    assert!(run_all(&make(hi)).is_err(), "{hi} levels allowed");
    while hi - lo > 1 {
        let mid = (lo + hi) / 2;
        if run_all(&make(mid)).is_ok() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo, run_all(&make(hi)).unwrap_err())
}

/// Every family nests up to the one budget and stops with a located
/// error beyond it, in a thread whose stack is only 1 MiB (the default
/// wasm stack; the e2e test checks the release wasm in the worker).
#[test]
fn depth_budget_bounds_every_kind_of_nesting() {
    let h = std::thread::Builder::new()
        .stack_size(1 << 20)
        .spawn(|| {
            let mut report = vec![];
            for (name, make) in deep_families() {
                let (k, e) = deepest(&*make);
                let m = e.to_string();
                assert!(m.contains("nested"), "{name}: {m}");
                assert!(
                    m.contains("line ") || matches!(e, Error::Syntax { .. }),
                    "{name}: {m}"
                );
                // Ordinary programs are far from the limit.
                assert!(k >= 12, "{name}: only {k} levels");
                report.push(format!("{name}: {k}"));
            }
            report
        })
        .unwrap();
    let report = h.join().expect("no stack overflow");
    eprintln!("deepest programs: {}", report.join(", "));
}

#[test]
fn endless_recursion_names_the_call() {
    let e = rec("fn f(x) { return f(x + 1); }\nlet y = f(0);").unwrap_err();
    let m = e.to_string();
    assert!(
        m.contains("nested deeper than") && m.contains("'f' called at line 1, column 18"),
        "{m}"
    );
}

use proptest::prelude::*;

/// Smooth expressions over the float parameters `a`, `b`, `c` (no
/// kinks, denominators bounded away from 0), from a small grammar.
fn smooth_expr() -> impl Strategy<Value = String> {
    let leaf = prop_oneof![
        prop_oneof![Just("a"), Just("b"), Just("c")].prop_map(String::from),
        (-2.0f64..2.0).prop_map(|v| format!("{v:.3}")),
        (0u32..4).prop_map(|i| format!("i + {i}")),
    ];
    leaf.prop_recursive(4, 24, 2, |e| {
        prop_oneof![
            (e.clone(), e.clone()).prop_map(|(x, y)| format!("({x} + {y})")),
            (e.clone(), e.clone()).prop_map(|(x, y)| format!("({x} - {y})")),
            (e.clone(), e.clone()).prop_map(|(x, y)| format!("({x} * {y})")),
            (e.clone(), e.clone()).prop_map(|(x, y)| format!("({x} / (2 + sin({y})))")),
            e.clone().prop_map(|x| format!("-({x})")),
            e.clone().prop_map(|x| format!("sin({x})")),
            e.clone().prop_map(|x| format!("cos({x})")),
            e.clone().prop_map(|x| format!("atan({x})")),
            e.clone().prop_map(|x| format!("exp(sin({x}))")),
            e.clone().prop_map(|x| format!("ln(2 + cos({x}))")),
            e.clone().prop_map(|x| format!("sqrt(1 + ({x}) ^ 2)")),
            (e.clone(), e.clone()).prop_map(|(x, y)| format!("hypot(1 + sin({x}) ^ 2, {y})")),
            (e.clone(), e.clone()).prop_map(|(x, y)| format!("atan2(2 + sin({x}), {y})")),
            (e.clone(), e.clone()).prop_map(|(x, y)| format!("pow(1.5 + sin({x}), cos({y}))")),
            (e.clone(), e.clone(), e.clone()).prop_map(|(x, y, z)| format!("lerp({x}, {y}, {z})")),
            (e.clone(), e).prop_map(|(x, y)| format!("tan(0.5 * sin({x})) + {y} * 0.5")),
        ]
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1000))]
    /// On random programs (lets, a loop, a user function, a transform),
    /// the recorded tape (1) replays to exactly what recording at other
    /// parameter values computes and (2) its reverse sweep equals central
    /// differences of the replay.
    #[test]
    fn tape_gradient_equals_central_differences(
        e1 in smooth_expr(),
        e2 in smooth_expr(),
        e3 in smooth_expr(),
        at in proptest::collection::vec(0.2f64..0.8, 3),
        to in proptest::collection::vec(0.2f64..0.8, 3),
    ) {
        let src = format!(
            "param a in [0, 1] = 0.5;\nparam b in [0, 1] = 0.5;\nparam c in [0, 1] = 0.5;\n\
             fn g(u, v) {{ return u * 0.5 + v; }}\n\
             for i in 0..2 {{\n  let x = {e1};\n  let y = g({e2}, x);\n  \
             translate(0.1 * i, 0) {{ rotate(0.3) {{ circle(x, y, {e3}, stroke: \"#000\"); }} }}\n}}"
        );
        let p = Program::parse(&src).unwrap();
        let limits = RecordLimits::default();
        let r = p.record(&at, &limits).unwrap();
        let outputs: Vec<u32> = r.prims.iter().flat_map(|q| q.fields[..3].to_vec()).collect();
        // (1) Replay at `to` = recording at `to`.
        let r2 = p.record(&to, &limits).unwrap();
        let mut v = vec![];
        r.tape.forward(&to, &mut v);
        let mut v2 = vec![];
        r2.tape.forward(&to, &mut v2);
        for (q, q2) in r.prims.iter().zip(&r2.prims) {
            for k in 0..3 {
                let (x, y) = (v[q.fields[k] as usize], v2[q2.fields[k] as usize]);
                prop_assert!((x - y).abs() <= 1e-12 * (1.0 + y.abs()), "replay {} vs record {}", x, y);
            }
        }
        // (2) Gradient of a random weighting of the outputs.
        let w: Vec<f64> = (0..outputs.len()).map(|k| 1.0 + 0.37 * k as f64).collect();
        let f = |params: &[f64]| {
            let mut v = vec![];
            r.tape.forward(params, &mut v);
            outputs.iter().zip(&w).map(|(&o, &wk)| wk * v[o as usize]).sum::<f64>()
        };
        let mut vals = vec![];
        r.tape.forward(&at, &mut vals);
        let mut adj = vec![0.0; r.tape.len()];
        for (&o, &wk) in outputs.iter().zip(&w) {
            adj[o as usize] += wk;
        }
        let mut grad = vec![0.0; 3];
        r.tape.backward(&vals, &mut adj, &mut grad);
        for k in 0..3 {
            let h = 1e-6;
            let (mut lo, mut hi) = (at.clone(), at.clone());
            lo[k] -= h;
            hi[k] += h;
            let fd = (f(&hi) - f(&lo)) / (2.0 * h);
            prop_assert!(
                (fd - grad[k]).abs() <= 1e-5 * (1.0 + fd.abs().max(grad[k].abs())),
                "d/d{}: tape {} vs central difference {}\n{}", ["a", "b", "c"][k], grad[k], fd, src
            );
        }
    }
}
