//! The Tangle tool's document (what the page keeps, autosaves, saves in a
//! project file and shares), its schema version and its checks: a serde
//! type read by [`crate::core::check::read_document`] (type errors name the
//! field) and a [`Check`] impl for its ranges. Field names are the page's:
//!
//! ```text
//! { example: name | null, grammar: text, seed,
//!   start: null | {kind: "rect", width, height} | {kind: "text", text, height}
//!        | {kind: "svg", svg: text} | {kind: "polygon", points: [[x, y], ...]},
//!   wobble, stroke_width, edits: [{step, params: {name: number}}],
//!   selected: step | null }
//! ```
//!
//! `start`, `edits`, `seed`, `wobble` and `stroke_width` are exactly the
//! `tangle` request's fields ([`super::api::TangleRequest`]): the page sends
//! the document as the request, so the types ([`StartRequest`], [`Edit`])
//! and the ranges ([`WOBBLE`], [`STROKE_WIDTH`], [`MAX_EDITS`],
//! [`MAX_START_SIDE`], ...) are the request's own. Where the document is
//! stricter than a request (an edit names its step; a start is one of the
//! four kinds the page draws) it is read through its own fields first.
//! Unknown fields are dropped, as they always were.
use super::api::{
    Edit, StartRequest, MAX_EDITS, MAX_START_POINTS, MAX_STEPS, STROKE_WIDTH, WOBBLE,
};
use super::examples::EXAMPLES;
use super::MAX_START_SIDE;
use crate::core::check::{null_as_default, read_document, read_part_at, Check, Path};
use crate::core::error::Result;
use crate::core::value::{Value, MAX_SAFE_INTEGER};
use serde::{Deserialize, Deserializer, Serialize};
use std::collections::BTreeMap;

/// Schema version of the Tangle state (the page's `state.version`).
pub const STATE_VERSION: u32 = 1;
/// Longest grammar text, in bytes.
pub const MAX_GRAMMAR_BYTES: usize = 256 * 1024;
/// Longest uploaded SVG start, in bytes.
pub const MAX_SVG_BYTES: usize = 1024 * 1024;
/// Longest typed start word, in characters.
pub const MAX_TEXT_CHARS: usize = 200;
/// Most points of a drawn start polygon.
pub const MAX_POLYGON_POINTS: usize = 10_000;
/// Most parameters one edit sets, and the longest parameter name.
pub const MAX_EDIT_PARAMS: usize = 16;
pub const MAX_PARAM_NAME: usize = 32;

/// A Tangle document. Its `start` is read by [`check`] after the rest,
/// by kind (a field of another kind is dropped, as it always was).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TangleState {
    #[serde(default)]
    pub example: Option<String>,
    pub grammar: String,
    pub seed: u64,
    #[serde(skip_deserializing)]
    pub start: Option<StartRequest>,
    pub wobble: f64,
    pub stroke_width: f64,
    /// Missing or `null`: none.
    #[serde(default, deserialize_with = "edits")]
    pub edits: Vec<Edit>,
    #[serde(default)]
    pub selected: Option<u64>,
}

/// The kinds of start a document holds (the request's [`StartRequest`]
/// also takes `rings`, which the page never keeps).
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "lowercase")]
enum StartKind {
    Rect,
    Text,
    Svg,
    Polygon,
}

/// The start at `at` (`null` or missing: none): its kind, then that kind's
/// fields, as the request's [`StartRequest`]; an error names the field
/// (`start.width`, `start.points.2.1`).
fn read_start(raw: Option<&Value>, at: &Path) -> Result<Option<StartRequest>> {
    #[derive(Deserialize)]
    struct Kind {
        kind: StartKind,
    }
    #[derive(Deserialize)]
    struct Rect {
        width: f64,
        height: f64,
    }
    #[derive(Deserialize)]
    struct Word {
        text: String,
        height: f64,
    }
    #[derive(Deserialize)]
    struct Svg {
        svg: String,
    }
    #[derive(Deserialize)]
    struct Polygon {
        points: Vec<Point>,
    }
    #[derive(Deserialize)]
    struct Point([f64; 2]);
    let Some(raw) = raw.filter(|s| !matches!(s, Value::Null)) else {
        return Ok(None);
    };
    let Kind { kind } = read_part_at(raw, at)?;
    Ok(Some(match kind {
        StartKind::Rect => {
            let Rect { width, height } = read_part_at(raw, at)?;
            StartRequest::Rect { width, height }
        }
        StartKind::Text => {
            let Word { text, height } = read_part_at(raw, at)?;
            StartRequest::Text { text, height }
        }
        StartKind::Svg => {
            let Svg { svg } = read_part_at(raw, at)?;
            StartRequest::Svg { svg }
        }
        StartKind::Polygon => {
            let Polygon { points } = read_part_at(raw, at)?;
            StartRequest::Polygon {
                points: points.into_iter().map(|p| p.0).collect(),
            }
        }
    }))
}

/// An edit as the document holds it: its step is always named (a
/// request's defaults to 0); `params` missing or `null` is none.
#[derive(Deserialize)]
struct EditFields {
    step: u64,
    #[serde(default, deserialize_with = "null_as_default")]
    params: BTreeMap<String, f64>,
}

/// `deserialize_with`: the edits (`null`: none) as the request's [`Edit`]s.
fn edits<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Vec<Edit>, D::Error> {
    let list: Option<Vec<EditFields>> = Option::deserialize(d)?;
    Ok(list
        .unwrap_or_default()
        .into_iter()
        .map(|e| Edit {
            // Beyond a (32-bit) usize: past any step, refused by the check.
            step: usize::try_from(e.step).unwrap_or(usize::MAX),
            params: e.params,
        })
        .collect())
}

/// The last step a document may name.
const LAST_STEP: usize = MAX_STEPS - 1;

/// A side of a start shape: above 0, at most [`MAX_START_SIDE`].
fn side(at: &Path, v: f64) -> Result<()> {
    if v.is_finite() && v > 0.0 && v <= MAX_START_SIDE {
        Ok(())
    } else {
        Err(at.invalid(format!(
            "must be a number above 0 and at most {MAX_START_SIDE}"
        )))
    }
}

/// Every field's rules but the start's ([`check`] reads and checks it).
impl Check for TangleState {
    fn check(&self, at: &Path) -> Result<()> {
        if let Some(e) = &self.example {
            if !EXAMPLES.iter().any(|x| x.name == e) {
                let names: Vec<_> = EXAMPLES.iter().map(|e| e.name).collect();
                return Err(at
                    .key("example")
                    .invalid(format!("must be null or one of {}", names.join(", "))));
            }
        }
        if self.grammar.len() > MAX_GRAMMAR_BYTES {
            return Err(at.key("grammar").invalid(format!(
                "must be the text of a grammar (at most {MAX_GRAMMAR_BYTES} bytes)"
            )));
        }
        at.key("seed")
            .whole_in(self.seed, (0, MAX_SAFE_INTEGER as u64))?;
        at.key("wobble").number_in(self.wobble, WOBBLE)?;
        at.key("stroke_width")
            .number_in(self.stroke_width, STROKE_WIDTH)?;
        if self.edits.len() > MAX_EDITS {
            return Err(at.key("edits").invalid(format!(
                "must be a list of at most {MAX_EDITS} edits (the edit limit)"
            )));
        }
        self.edits.check(&at.key("edits"))?;
        if let Some(s) = self.selected {
            at.key("selected").whole_in(s, (0, LAST_STEP as u64))?;
        }
        Ok(())
    }
}

impl Check for StartRequest {
    fn check(&self, at: &Path) -> Result<()> {
        match self {
            StartRequest::Rect { width, height } => {
                side(&at.key("width"), *width)?;
                side(&at.key("height"), *height)
            }
            StartRequest::Text { text, height } => {
                if text.trim().is_empty() || text.chars().count() > MAX_TEXT_CHARS {
                    return Err(at.key("text").invalid(format!(
                        "must be a word of 1 to {MAX_TEXT_CHARS} characters"
                    )));
                }
                side(&at.key("height"), *height)
            }
            StartRequest::Svg { svg } => {
                let at = at.key("svg");
                if svg.trim().is_empty() || svg.len() > MAX_SVG_BYTES {
                    return Err(at.invalid(format!(
                        "must be the text of an SVG file (at most {MAX_SVG_BYTES} bytes)"
                    )));
                }
                // A document too deep to parse is refused with the state,
                // not when the tangle grows from it.
                crate::tangle::geom::svg::check_depth(svg).map_err(|e| at.invalid(e))
            }
            StartRequest::Polygon { points } => {
                let max = MAX_POLYGON_POINTS.min(MAX_START_POINTS);
                if !(3..=max).contains(&points.len()) {
                    return Err(at
                        .key("points")
                        .invalid(format!("must be a list of 3 to {max} points [x, y]")));
                }
                for (i, p) in points.iter().enumerate() {
                    if !p.iter().all(|c| c.is_finite() && c.abs() <= MAX_START_SIDE) {
                        return Err(at.key("points").index(i).invalid(format!(
                            "must be a point [x, y] of numbers within ±{MAX_START_SIDE}"
                        )));
                    }
                }
                Ok(())
            }
            // Not a document's (its type has no `rings`).
            StartRequest::Rings { .. } => Err(at
                .key("kind")
                .invalid("must be one of rect, text, svg, polygon")),
        }
    }
}

impl Check for Edit {
    fn check(&self, at: &Path) -> Result<()> {
        at.key("step").whole_in(self.step, (0, LAST_STEP))?;
        let params = at.key("params");
        if self.params.len() > MAX_EDIT_PARAMS {
            return Err(params.invalid(format!(
                "must be an object of at most {MAX_EDIT_PARAMS} parameters {{name: number}}"
            )));
        }
        for (k, v) in &self.params {
            if k.is_empty() {
                return Err(params.invalid(format!(
                    "names parameters of 1 to {MAX_PARAM_NAME} characters"
                )));
            }
            params.js_len_at_most(
                k,
                MAX_PARAM_NAME,
                format!("names parameters of 1 to {MAX_PARAM_NAME} characters"),
            )?;
            if !v.is_finite() {
                return Err(params.key(k).invalid("must be a finite number"));
            }
        }
        Ok(())
    }
}

/// Read and check a Tangle document; the error names the field at fault.
pub fn check(raw: &Value) -> Result<TangleState> {
    let mut doc: TangleState = read_document(raw, "Tangle")?;
    let at = Path::root().key("start");
    doc.start = read_start(raw.get("start"), &at)?;
    doc.start.check(&at)?;
    Ok(doc)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tangle::api::TangleRequest;
    use serde_json::{json, Value as Json};

    fn value(j: &Json) -> Value {
        Value::read(j, false).unwrap()
    }

    fn doc() -> Json {
        json!({
            "example": "leaf", "grammar": EXAMPLES[0].grammar, "seed": 1, "start": null,
            "wobble": 1, "stroke_width": 1,
            "edits": [{"step": 3, "params": {"distance": 12.5}}, {"step": 0, "params": {}}],
            "selected": 3,
        })
    }

    /// The error's field for `doc()` with `key` set to `v`.
    fn field_of(key: &str, v: Json) -> String {
        let mut d = doc();
        d[key] = v;
        let e = check(&value(&d)).unwrap_err();
        assert!(
            e.to_string().starts_with(e.field().unwrap_or("?")),
            "{e} names its field first"
        );
        e.field().unwrap().to_string()
    }

    #[test]
    fn a_page_document_is_accepted_and_kept() {
        let s = check(&value(&doc())).unwrap();
        assert_eq!(s.example.as_deref(), Some("leaf"));
        assert_eq!(s.edits.len(), 2);
        assert_eq!(s.edits[0].params["distance"], 12.5);
        assert!(s.edits[1].params.is_empty());
        assert_eq!(s.selected, Some(3));
        // Checking the normalised state again changes nothing.
        let again = check(&value(&serde_json::to_value(&s).unwrap())).unwrap();
        assert_eq!(again, s);
    }

    #[test]
    fn every_start_kind_round_trips_as_the_request_reads_it() {
        for start in [
            json!({"kind": "rect", "width": 400, "height": 300}),
            json!({"kind": "text", "text": "Tangle", "height": 200}),
            json!({"kind": "svg", "svg": "<svg><path d='M0 0H10V10Z'/></svg>"}),
            json!({"kind": "polygon", "points": [[0, 0], [10, 0], [5, 8]]}),
        ] {
            let mut d = doc();
            d["start"] = start.clone();
            let s = check(&value(&d)).unwrap();
            // The state's start is the request's start, field for field.
            let req: TangleRequest =
                serde_json::from_value(json!({"grammar": "", "start": start})).unwrap();
            assert_eq!(s.start, req.start);
        }
    }

    #[test]
    fn every_rule_names_its_field() {
        assert_eq!(field_of("example", json!("nope")), "example");
        assert_eq!(field_of("grammar", json!(3)), "grammar");
        assert_eq!(
            field_of("grammar", json!("#".repeat(MAX_GRAMMAR_BYTES + 1))),
            "grammar"
        );
        assert_eq!(field_of("seed", json!(-1)), "seed");
        assert_eq!(field_of("seed", json!(1.5)), "seed");
        assert_eq!(field_of("wobble", json!(51)), "wobble");
        assert_eq!(field_of("stroke_width", json!("1")), "stroke_width");
        assert_eq!(field_of("selected", json!(-2)), "selected");
        assert_eq!(field_of("start", json!([1])), "start");
        assert_eq!(field_of("start", json!({"kind": "circle"})), "start.kind");
        assert_eq!(
            field_of("start", json!({"kind": "rect", "width": 0, "height": 3})),
            "start.width"
        );
        assert_eq!(
            field_of("start", json!({"kind": "text", "text": " ", "height": 3})),
            "start.text"
        );
        assert_eq!(
            field_of("start", json!({"kind": "svg", "svg": ""})),
            "start.svg"
        );
        let deep = format!("<svg>{}</svg>", "<g>".repeat(3000));
        assert_eq!(
            field_of("start", json!({"kind": "svg", "svg": deep})),
            "start.svg"
        );
        assert_eq!(
            field_of(
                "start",
                json!({"kind": "polygon", "points": [[0, 0], [1, 1]]})
            ),
            "start.points"
        );
        assert_eq!(
            field_of(
                "start",
                json!({"kind": "polygon", "points": [[0, 0], [1, 1], [1, "x"]]})
            ),
            "start.points.2.1"
        );
        assert_eq!(
            field_of(
                "start",
                json!({"kind": "polygon", "points": [[0, 0], [1, 1], [1]]})
            ),
            "start.points.2"
        );
        assert_eq!(field_of("start", json!({"kind": "rect"})), "start.width");
        assert_eq!(
            field_of(
                "start",
                json!({"kind": "polygon", "points": [[0, 0], [1, 1], [1, 2, 3]]})
            ),
            "start.points.2"
        );
        // Text is text, not bytes (a page's Uint8Array).
        for key in ["grammar", "example"] {
            let mut v = value(&doc());
            if let Value::Object(kv) = &mut v {
                for (_, x) in kv.iter_mut().filter(|(k, _)| k == key) {
                    *x = Value::Bytes(b"leaf".to_vec());
                }
            }
            assert_eq!(check(&v).unwrap_err().field(), Some(key));
        }
        assert_eq!(field_of("start", json!({"kind": "rings"})), "start.kind");
        assert_eq!(field_of("edits", json!({})), "edits");
        let many: Vec<Json> = (0..=MAX_EDITS).map(|_| json!({"step": 0})).collect();
        assert_eq!(field_of("edits", json!(many)), "edits");
        assert_eq!(field_of("edits", json!([{"step": -1}])), "edits.0.step");
        assert_eq!(
            field_of("edits", json!([{"step": 0}, {"step": 1, "params": [1]}])),
            "edits.1.params"
        );
        assert_eq!(
            field_of("edits", json!([{"step": 0, "params": {"distance": "far"}}])),
            "edits.0.params.distance"
        );
    }

    /// `doc()` with `edit` applied.
    fn with(edit: impl Fn(&mut Json)) -> Json {
        let mut d = doc();
        edit(&mut d);
        d
    }

    /// The `tangle` request the page sends for document `d`.
    fn request(d: &Json) -> Result<crate::tangle::api::TangleJob> {
        let req: TangleRequest = serde_json::from_value(d.clone()).unwrap();
        crate::tangle::api::start_tangle(req)
    }

    #[test]
    fn every_range_is_inside_or_out_by_one() {
        let up = |v: f64| json!(v.next_up());
        let down = |v: f64| json!(v.next_down());
        let start = |s: Json| with(move |d| d["start"] = s.clone());
        let rect = |w: Json, h: Json| start(json!({"kind": "rect", "width": w, "height": h}));
        let m = MAX_START_SIDE;
        let tri = |x: Json| start(json!({"kind": "polygon", "points": [[0, 0], [m, 0], [x, m]]}));
        let poly = |n: usize| {
            let pts: Vec<Json> = (0..n).map(|i| json!([i % 7, i % 5])).collect();
            start(json!({"kind": "polygon", "points": pts}))
        };
        let edits = |n: usize| {
            let e: Vec<Json> = (0..n).map(|_| json!({"step": 0})).collect();
            with(move |d| d["edits"] = json!(e))
        };
        let params = |n: usize| {
            let p: serde_json::Map<_, _> = (0..n).map(|i| (format!("p{i}"), json!(i))).collect();
            with(move |d| d["edits"] = json!([{"step": 0, "params": p}]))
        };
        let name = |k: String| with(move |d| d["edits"] = json!([{"step": 0, "params": {&k: 1}}]));
        let word = |t: String| start(json!({"kind": "text", "text": t, "height": 10}));
        let svg =
            |n: usize| start(json!({"kind": "svg", "svg": format!("<svg>{}", " ".repeat(n - 5))}));
        // (inside, outside, the document's field, the request's field when
        // the `tangle` request checks the same range)
        let cases: Vec<(Json, Json, &str, Option<&str>)> = vec![
            (
                with(|d| d["wobble"] = json!(WOBBLE.1)),
                with(|d| d["wobble"] = up(WOBBLE.1)),
                "wobble",
                Some("wobble"),
            ),
            (
                with(|d| d["wobble"] = json!(WOBBLE.0)),
                with(|d| d["wobble"] = down(WOBBLE.0)),
                "wobble",
                Some("wobble"),
            ),
            (
                with(|d| d["stroke_width"] = json!(STROKE_WIDTH.1)),
                with(|d| d["stroke_width"] = up(STROKE_WIDTH.1)),
                "stroke_width",
                Some("stroke_width"),
            ),
            (
                with(|d| d["stroke_width"] = json!(STROKE_WIDTH.0)),
                with(|d| d["stroke_width"] = down(STROKE_WIDTH.0)),
                "stroke_width",
                Some("stroke_width"),
            ),
            (
                edits(MAX_EDITS),
                edits(MAX_EDITS + 1),
                "edits",
                Some("edits"),
            ),
            (
                rect(json!(m), json!(1)),
                rect(up(m), json!(1)),
                "start.width",
                Some("start"),
            ),
            (
                rect(json!(1), json!(m)),
                rect(json!(1), up(m)),
                "start.height",
                Some("start"),
            ),
            (tri(json!(0)), tri(up(m)), "start.points.2", None),
            // The request's polygons are snapped to the overlay's grid:
            // one ulp over is below its precision, one unit is not.
            (
                tri(json!(0)),
                tri(json!(m + 1.0)),
                "start.points.2",
                Some("start.points"),
            ),
            (
                with(|d| d["seed"] = json!(MAX_SAFE_INTEGER)),
                with(|d| d["seed"] = json!(-1)),
                "seed",
                None,
            ),
            (
                with(|d| d["grammar"] = json!("#".repeat(MAX_GRAMMAR_BYTES))),
                with(|d| d["grammar"] = json!("#".repeat(MAX_GRAMMAR_BYTES + 1))),
                "grammar",
                None,
            ),
            (
                with(|d| d["selected"] = json!(LAST_STEP)),
                with(|d| d["selected"] = json!(MAX_STEPS)),
                "selected",
                None,
            ),
            (
                with(|d| d["edits"] = json!([{"step": LAST_STEP}])),
                with(|d| d["edits"] = json!([{"step": MAX_STEPS}])),
                "edits.0.step",
                None,
            ),
            (
                params(MAX_EDIT_PARAMS),
                params(MAX_EDIT_PARAMS + 1),
                "edits.0.params",
                None,
            ),
            // JS counts a name's length in UTF-16 units: 😀 is two.
            (
                name("😀".repeat(MAX_PARAM_NAME / 2)),
                name(format!("{}a", "😀".repeat(MAX_PARAM_NAME / 2))),
                "edits.0.params",
                None,
            ),
            (
                name("a".into()),
                name(String::new()),
                "edits.0.params",
                None,
            ),
            (
                poly(MAX_POLYGON_POINTS),
                poly(MAX_POLYGON_POINTS + 1),
                "start.points",
                None,
            ),
            (poly(3), poly(2), "start.points", None),
            (
                word("😀".repeat(MAX_TEXT_CHARS)),
                word("😀".repeat(MAX_TEXT_CHARS + 1)),
                "start.text",
                None,
            ),
            (
                svg(MAX_SVG_BYTES),
                svg(MAX_SVG_BYTES + 1),
                "start.svg",
                None,
            ),
        ];
        for (inside, outside, field, req) in cases {
            check(&value(&inside)).unwrap_or_else(|e| panic!("{field} inside: {e}"));
            let e = check(&value(&outside)).unwrap_err();
            assert_eq!(e.field(), Some(field), "{e}");
            assert!(e.to_string().starts_with(field), "{e}");
            if let Some(req_field) = req {
                // The request the page sends for the same document agrees.
                request(&inside).unwrap_or_else(|e| panic!("{field} inside, as a request: {e}"));
                let Some(e) = request(&outside).err() else {
                    panic!("{field} outside, as a request: accepted")
                };
                assert_eq!(e.field(), Some(req_field), "{e}");
            }
        }
        // NaN and ±∞, which a page's numbers can be, are not numbers here.
        for (key, at) in [("wobble", "wobble"), ("stroke_width", "stroke_width")] {
            let mut v = value(&doc());
            if let Value::Object(kv) = &mut v {
                for (_, x) in kv.iter_mut().filter(|(k, _)| k == key) {
                    *x = Value::Number(f64::NAN);
                }
            }
            assert_eq!(check(&v).unwrap_err().field(), Some(at));
        }
    }

    #[test]
    fn unknown_fields_are_dropped_as_they_always_were() {
        let plain = check(&value(&doc())).unwrap();
        let extra = with(|d| {
            d["extra"] = json!(1);
            d["edits"][0]["why"] = json!("x");
        });
        assert_eq!(check(&value(&extra)).unwrap(), plain);
        let rect = |extra: bool| {
            let mut s = json!({"kind": "rect", "width": 4, "height": 3});
            if extra {
                s["label"] = json!("box");
                // Another kind's field, even of the wrong type.
                s["text"] = json!(3);
            }
            check(&value(&with(|d| d["start"] = s.clone()))).unwrap()
        };
        assert_eq!(rect(true), rect(false));
        // Optional fields older documents lack: none.
        let mut d = doc();
        for k in ["example", "start", "edits", "selected"] {
            d.as_object_mut().unwrap().remove(k);
        }
        let s = check(&value(&d)).unwrap();
        assert_eq!(
            (s.example, s.start, s.edits, s.selected),
            (None, None, vec![], None)
        );
        let s = check(&value(&with(|d| {
            d["edits"] = json!([{"step": 2, "params": null}])
        })))
        .unwrap();
        assert_eq!(
            s.edits,
            [Edit {
                step: 2,
                params: BTreeMap::new()
            }]
        );
    }
}
