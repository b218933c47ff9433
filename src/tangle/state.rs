//! The Tangle tool's document (what the page keeps, autosaves, saves in a
//! project file and shares), its schema version and its checks, field by
//! field (see [`crate::core::value`]). Field names are the page's:
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
//! the document as the request, so the ranges here are the request's own.
use super::api::{
    Edit, StartRequest, MAX_EDITS, MAX_START_POINTS, MAX_STEPS, STROKE_WIDTH, WOBBLE,
};
use super::examples::EXAMPLES;
use super::MAX_START_SIDE;
use crate::core::error::Result;
use crate::core::value::{invalid, js_len, nullish, Value, MAX_SAFE_INTEGER};
use serde::Serialize;
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

/// A checked Tangle document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TangleState {
    pub example: Option<String>,
    pub grammar: String,
    pub seed: u64,
    pub start: Option<StartRequest>,
    pub wobble: f64,
    pub stroke_width: f64,
    pub edits: Vec<Edit>,
    pub selected: Option<u64>,
}

fn whole(v: Option<&Value>, field: &str, max: f64) -> Result<f64> {
    v.and_then(Value::whole)
        .filter(|x| (0.0..=max).contains(x))
        .ok_or_else(|| invalid(field, format!("must be a whole number from 0 to {max}")))
}

fn number_in(v: Option<&Value>, field: &str, (lo, hi): (f64, f64)) -> Result<f64> {
    v.and_then(Value::finite)
        .filter(|x| (lo..=hi).contains(x))
        .ok_or_else(|| invalid(field, format!("must be a number from {lo} to {hi}")))
}

fn side(v: Option<&Value>, field: &str) -> Result<f64> {
    v.and_then(Value::finite)
        .filter(|x| *x > 0.0 && *x <= MAX_START_SIDE)
        .ok_or_else(|| {
            invalid(
                field,
                format!("must be a number above 0 and at most {MAX_START_SIDE}"),
            )
        })
}

fn start(raw: Option<&Value>) -> Result<Option<StartRequest>> {
    if nullish(raw) {
        return Ok(None);
    }
    let s = raw.filter(|s| s.is_plain_object()).ok_or_else(|| {
        invalid(
            "start",
            "must be null or a start shape {kind: rect | text | svg | polygon, ...}",
        )
    })?;
    Ok(Some(match s.get("kind").and_then(Value::as_text) {
        Some("rect") => StartRequest::Rect {
            width: side(s.get("width"), "start.width")?,
            height: side(s.get("height"), "start.height")?,
        },
        Some("text") => {
            let text = s
                .get("text")
                .and_then(Value::as_text)
                .filter(|t| !t.trim().is_empty() && t.chars().count() <= MAX_TEXT_CHARS)
                .ok_or_else(|| {
                    invalid(
                        "start.text",
                        format!("must be a word of 1 to {MAX_TEXT_CHARS} characters"),
                    )
                })?;
            StartRequest::Text {
                text: text.to_string(),
                height: side(s.get("height"), "start.height")?,
            }
        }
        Some("svg") => StartRequest::Svg {
            svg: s
                .get("svg")
                .and_then(Value::as_text)
                .filter(|t| !t.trim().is_empty() && t.len() <= MAX_SVG_BYTES)
                .ok_or_else(|| {
                    invalid(
                        "start.svg",
                        format!("must be the text of an SVG file (at most {MAX_SVG_BYTES} bytes)"),
                    )
                })
                .and_then(|t| {
                    // A document too deep to parse is refused with the state,
                    // not when the tangle grows from it.
                    crate::tangle::geom::svg::check_depth(t)
                        .map_err(|e| invalid("start.svg", e))?;
                    Ok(t)
                })?
                .to_string(),
        },
        Some("polygon") => {
            let max = MAX_POLYGON_POINTS.min(MAX_START_POINTS);
            let list = s
                .get("points")
                .and_then(Value::as_list)
                .filter(|l| (3..=max).contains(&l.len()))
                .ok_or_else(|| {
                    invalid(
                        "start.points",
                        format!("must be a list of 3 to {max} points [x, y]"),
                    )
                })?;
            let mut points = Vec::with_capacity(list.len());
            for (i, p) in list.iter().enumerate() {
                let xy = p
                    .as_list()
                    .filter(|xy| xy.len() == 2)
                    .and_then(|xy| Some([xy[0].finite()?, xy[1].finite()?]))
                    .filter(|xy| xy.iter().all(|c| c.abs() <= MAX_START_SIDE))
                    .ok_or_else(|| {
                        invalid(
                            &format!("start.points.{i}"),
                            format!("must be a point [x, y] of numbers within ±{MAX_START_SIDE}"),
                        )
                    })?;
                points.push(xy);
            }
            StartRequest::Polygon { points }
        }
        _ => {
            return Err(invalid(
                "start.kind",
                "must be one of rect, text, svg, polygon",
            ))
        }
    }))
}

fn edits(raw: Option<&Value>) -> Result<Vec<Edit>> {
    if nullish(raw) {
        return Ok(vec![]);
    }
    let list = raw
        .and_then(Value::as_list)
        .filter(|l| l.len() <= MAX_EDITS)
        .ok_or_else(|| {
            invalid(
                "edits",
                format!("must be a list of at most {MAX_EDITS} edits (the edit limit)"),
            )
        })?;
    let mut out = Vec::with_capacity(list.len());
    for (i, e) in list.iter().enumerate() {
        let field = format!("edits.{i}");
        if !e.is_plain_object() {
            return Err(invalid(&field, "must be an edit {step, params}"));
        }
        let step = whole(
            e.get("step"),
            &format!("{field}.step"),
            MAX_STEPS as f64 - 1.0,
        )?;
        let mut params = BTreeMap::new();
        match e.get("params") {
            None | Some(Value::Null) => {}
            Some(Value::Object(kv)) if kv.len() <= MAX_EDIT_PARAMS => {
                for (k, v) in kv {
                    let pf = format!("{field}.params.{k}");
                    if k.is_empty() || js_len(k) > MAX_PARAM_NAME {
                        return Err(invalid(
                            &format!("{field}.params"),
                            format!("names parameters of 1 to {MAX_PARAM_NAME} characters"),
                        ));
                    }
                    let v = v
                        .finite()
                        .ok_or_else(|| invalid(&pf, "must be a finite number"))?;
                    params.insert(k.clone(), v);
                }
            }
            Some(_) => {
                return Err(invalid(
                    &format!("{field}.params"),
                    format!(
                    "must be an object of at most {MAX_EDIT_PARAMS} parameters {{name: number}}"
                ),
                ))
            }
        }
        out.push(Edit {
            step: step as usize,
            params,
        });
    }
    Ok(out)
}

/// Check a Tangle document field by field; the error names the field at fault.
pub fn check(raw: &Value) -> Result<TangleState> {
    if !raw.is_plain_object() {
        return Err(invalid("state", "is not a Tangle document"));
    }
    let example = match raw.get("example") {
        None | Some(Value::Null) => None,
        Some(Value::Text(e)) if EXAMPLES.iter().any(|x| x.name == e) => Some(e.clone()),
        Some(_) => {
            return Err(invalid(
                "example",
                format!(
                    "must be null or one of {}",
                    EXAMPLES
                        .iter()
                        .map(|e| e.name)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ))
        }
    };
    let grammar = raw
        .get("grammar")
        .and_then(Value::as_text)
        .filter(|g| g.len() <= MAX_GRAMMAR_BYTES)
        .ok_or_else(|| {
            invalid(
                "grammar",
                format!("must be the text of a grammar (at most {MAX_GRAMMAR_BYTES} bytes)"),
            )
        })?
        .to_string();
    let seed = whole(raw.get("seed"), "seed", MAX_SAFE_INTEGER)? as u64;
    let start = start(raw.get("start"))?;
    let wobble = number_in(raw.get("wobble"), "wobble", WOBBLE)?;
    let stroke_width = number_in(raw.get("stroke_width"), "stroke_width", STROKE_WIDTH)?;
    let edits = edits(raw.get("edits"))?;
    let selected = match raw.get("selected") {
        None | Some(Value::Null) => None,
        s => Some(whole(s, "selected", MAX_STEPS as f64 - 1.0)? as u64),
    };
    Ok(TangleState {
        example,
        grammar,
        seed,
        start,
        wobble,
        stroke_width,
        edits,
        selected,
    })
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
            "start.points.2"
        );
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

    #[test]
    fn the_limits_are_the_requests() {
        let d = TangleRequest::default();
        assert!((WOBBLE.0..=WOBBLE.1).contains(&d.wobble));
        assert!((STROKE_WIDTH.0..=STROKE_WIDTH.1).contains(&d.stroke_width));
        // A document at the edit limit is accepted.
        let mut j = doc();
        j["edits"] = json!((0..MAX_EDITS)
            .map(|k| json!({"step": k, "params": {}}))
            .collect::<Vec<_>>());
        assert_eq!(check(&value(&j)).unwrap().edits.len(), MAX_EDITS);
    }
}
