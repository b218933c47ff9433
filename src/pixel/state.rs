//! The Pixel tool's document (what the page keeps, autosaves, saves in a
//! project file and shares), its schema version and its checks, field by
//! field (see [`crate::core::value`]). Field names are the page's:
//!
//! ```text
//! { example: "fish" | "trunk" | null, source: bytes, sheet: bytes | null,
//!   sprite: bytes | null, mask: {width, height, bits: bytes},
//!   strokes: [[[x, y], ...], ...], params: PixelParams, names: {source?, sheet?} }
//! ```
//!
//! The ranges of the parameters are the core's request limits
//! ([`crate::core::request_limits`], the same ones `pixel` applies), the
//! image side and stroke points the core's limits ([`crate::core::limits`]).
use super::api::MaskBits;
use super::{ColourStrategy, Direction8, ElementColour, PixelParams, PositionStrategy};
use crate::core::error::{Error, Result};
use crate::core::limits::{MAX_IMAGE_SIDE, MAX_STROKE_POINTS};
use crate::core::request_limits as lim;
use crate::core::value::{
    first_chars, invalid, js_len, js_number, js_text, nullish, Value, MAX_SAFE_INTEGER,
};
use serde::de::value::{Error as DeError, StrDeserializer};
use serde::{Deserialize, Serialize};

/// Schema version of the Pixel state (the page's `state.version`).
pub const STATE_VERSION: u32 = 1;
/// The examples the page ships (`assets/pixel/cases.json`).
pub const EXAMPLES: &[&str] = &["fish", "trunk"];
/// Most strokes in one document.
pub const MAX_STROKES: usize = 10_000;
/// Most points in one stroke.
pub const MAX_STROKE_LEN: usize = 100_000;
/// Most excluded colours.
pub const MAX_EXCLUDED: usize = 256;
/// File names are kept to this many characters.
pub const MAX_NAME_CHARS: usize = 200;

/// A checked Pixel document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PixelState {
    pub example: Option<String>,
    #[serde(with = "serde_bytes")]
    pub source: Vec<u8>,
    #[serde(with = "serde_bytes")]
    pub sheet: Option<Vec<u8>>,
    #[serde(with = "serde_bytes")]
    pub sprite: Option<Vec<u8>>,
    /// One byte per pixel, 0 or 1.
    pub mask: MaskBits,
    /// In source pixels.
    pub strokes: Vec<Vec<[f64; 2]>>,
    /// Exactly the `pixel` request's parameters.
    pub params: PixelParams,
    pub names: Names,
}

/// The file names the page shows.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Names {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sheet: Option<String>,
}

/// How a parameter is checked (the kinds of the page's controls).
enum Rule {
    /// One of these names, read as the core's enum.
    Choice(&'static [&'static str], fn(&str) -> bool),
    /// A finite number in the range.
    Number(f64, f64),
    /// A whole number in the range.
    Whole(f64, f64),
    Flag,
    /// Whole numbers, one range each.
    Wholes(&'static [(f64, f64)], &'static str),
    Colours,
    Seed,
}

fn parses<T: for<'a> Deserialize<'a>>(s: &str) -> bool {
    T::deserialize(StrDeserializer::<DeError>::new(s)).is_ok()
}

const POSITIONS: &[&str] = &["random", "packed"];
const COLOURS: &[&str] = &["auto", "border", "difference", "hsv"];
const ELEMENT_COLOURS: &[&str] = &["region", "pixel"];
/// The eight directions, as the core names them.
pub const DIRECTIONS: &[&str] = &[
    "up",
    "up-right",
    "right",
    "down-right",
    "down",
    "down-left",
    "left",
    "up-left",
];
const MARGINS: &[(f64, f64)] = &[
    (-(lim::MARGIN as f64), lim::MARGIN as f64),
    (-(lim::MARGIN as f64), lim::MARGIN as f64),
];
const HSV: &[(f64, f64)] = &[
    (-lim::HUE_SHIFT, lim::HUE_SHIFT),
    (-lim::SV_SHIFT, lim::SV_SHIFT),
    (-lim::SV_SHIFT, lim::SV_SHIFT),
];

/// Every parameter: name (the core's `PixelParams` field), whether a
/// document must have it, and its rule.
fn params_schema() -> [(&'static str, bool, Rule); 13] {
    use Rule::*;
    [
        (
            "positions",
            true,
            Choice(POSITIONS, parses::<PositionStrategy>),
        ),
        ("density", true, Number(0.0, 1.0)),
        ("margins", true, Wholes(MARGINS, "")),
        ("partial", true, Flag),
        ("colour", true, Choice(COLOURS, parses::<ColourStrategy>)),
        ("d_max", true, Number(lim::D_MAX.0, lim::D_MAX.1)),
        (
            "hsv",
            true,
            Wholes(HSV, ": a hue shift, then saturation and value shifts"),
        ),
        ("exclude", true, Colours),
        (
            "element_colour",
            true,
            Choice(ELEMENT_COLOURS, parses::<ElementColour>),
        ),
        (
            "annotation_scale",
            true,
            Whole(
                lim::ANNOTATION_SCALE.0 as f64,
                lim::ANNOTATION_SCALE.1 as f64,
            ),
        ),
        (
            "default_direction",
            true,
            Choice(DIRECTIONS, parses::<Direction8>),
        ),
        (
            "sprite_direction",
            false,
            Choice(DIRECTIONS, parses::<Direction8>),
        ),
        ("seed", true, Seed),
    ]
}

fn range_words(lo: f64, hi: f64) -> String {
    format!("from {} to {}", js_number(lo), js_number(hi))
}

/// Check one parameter; sets it in `out`.
fn check_param(name: &str, rule: &Rule, v: &Value, out: &mut PixelParams) -> Result<()> {
    let field = format!("params.{name}");
    match rule {
        Rule::Choice(options, ok) => {
            let s = v
                .as_text()
                .filter(|s| options.contains(s) && ok(s))
                .ok_or_else(|| invalid(&field, format!("must be one of {}", options.join(", "))))?;
            let sd = || StrDeserializer::<DeError>::new(s);
            let bad = |_| invalid(&field, format!("must be one of {}", options.join(", ")));
            match name {
                "positions" => out.positions = PositionStrategy::deserialize(sd()).map_err(bad)?,
                "colour" => out.colour = ColourStrategy::deserialize(sd()).map_err(bad)?,
                "element_colour" => {
                    out.element_colour = ElementColour::deserialize(sd()).map_err(bad)?
                }
                "default_direction" => {
                    out.default_direction = Direction8::deserialize(sd()).map_err(bad)?
                }
                _ => out.sprite_direction = Direction8::deserialize(sd()).map_err(bad)?,
            }
        }
        Rule::Number(lo, hi) | Rule::Whole(lo, hi) => {
            let whole = matches!(rule, Rule::Whole(..));
            let x = if whole { v.whole() } else { v.finite() }
                .filter(|x| (*lo..=*hi).contains(x))
                .ok_or_else(|| {
                    let what = if whole { "a whole number" } else { "a number" };
                    invalid(&field, format!("must be {what} {}", range_words(*lo, *hi)))
                })?;
            match name {
                "density" => out.density = x,
                "d_max" => out.d_max = x,
                _ => out.annotation_scale = x as u32,
            }
        }
        Rule::Flag => {
            out.partial = match v {
                Value::Bool(b) => *b,
                _ => return Err(invalid(&field, "must be true or false")),
            }
        }
        Rule::Wholes(ranges, parts) => {
            let words = if ranges.iter().all(|r| *r == ranges[0]) {
                format!(
                    "must be {} whole numbers {}",
                    ranges.len(),
                    range_words(ranges[0].0, ranges[0].1)
                )
            } else {
                let each: Vec<String> = ranges.iter().map(|r| range_words(r.0, r.1)).collect();
                format!(
                    "must be {} whole numbers{parts} ({})",
                    ranges.len(),
                    each.join(", ")
                )
            };
            let xs: Vec<f64> = v
                .as_list()
                .filter(|l| l.len() == ranges.len())
                .and_then(|l| {
                    l.iter()
                        .zip(ranges.iter())
                        .map(|(x, (lo, hi))| x.whole().filter(|x| (*lo..=*hi).contains(x)))
                        .collect()
                })
                .ok_or_else(|| invalid(&field, words))?;
            if name == "margins" {
                out.margins = [xs[0] as i32, xs[1] as i32];
            } else {
                out.hsv = [xs[0], xs[1], xs[2]];
            }
        }
        Rule::Colours => {
            let bad = || invalid(&field, "must be a list of [r, g, b] colours (0 to 255)");
            let l = v
                .as_list()
                .filter(|l| l.len() <= MAX_EXCLUDED)
                .ok_or_else(bad)?;
            out.exclude = l
                .iter()
                .map(|rgb| {
                    let c = rgb.as_list().filter(|c| c.len() == 3)?;
                    let ch = |x: &Value| x.whole().filter(|x| (0.0..=255.0).contains(x));
                    Some([ch(&c[0])? as u8, ch(&c[1])? as u8, ch(&c[2])? as u8])
                })
                .collect::<Option<Vec<_>>>()
                .ok_or_else(bad)?;
        }
        Rule::Seed => {
            out.seed = v
                .whole()
                .filter(|x| (0.0..=MAX_SAFE_INTEGER).contains(x))
                .ok_or_else(|| invalid(&field, "must be a whole number ≥ 0"))?
                as u64;
        }
    }
    Ok(())
}

fn bytes_of(v: Option<&Value>, field: &str, optional: bool) -> Result<Option<Vec<u8>>> {
    match v {
        None | Some(Value::Null) if optional => Ok(None),
        Some(Value::Bytes(b)) if !b.is_empty() => {
            image_header(b).map_err(|why| invalid(field, why))?;
            Ok(Some(b.clone()))
        }
        _ => Err(invalid(field, "must be the bytes of an image file")),
    }
}

/// The bytes start like an image file the core reads, with a size within
/// the image limit: read from the header alone, nothing decoded (a project
/// whose `source` was 3 bytes that are not a PNG used to open).
fn image_header(bytes: &[u8]) -> std::result::Result<(), String> {
    let reader = image::ImageReader::new(std::io::Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| format!("cannot be read ({e})"))?;
    if reader.format().is_none() {
        return Err("is not an image file (PNG, JPEG, WebP, GIF or BMP)".into());
    }
    let (w, h) = reader.into_dimensions().map_err(|_| {
        "is not a readable image file (its header is damaged or cut short)".to_string()
    })?;
    if w == 0 || h == 0 || w.max(h) > MAX_IMAGE_SIDE {
        return Err(format!(
            "is an image of {w}×{h} pixels; images are 1 to {MAX_IMAGE_SIDE} pixels a side"
        ));
    }
    Ok(())
}

/// Check a Pixel document field by field; the error names the field at fault.
pub fn check(raw: &Value) -> Result<PixelState> {
    if !raw.is_object_like() || raw.as_list().is_some() {
        return Err(invalid("state", "is not a Pixel document"));
    }
    let source = bytes_of(raw.get("source"), "source", false)?.unwrap_or_default();
    let sheet = bytes_of(raw.get("sheet"), "sheet", true)?;
    let sprite = bytes_of(raw.get("sprite"), "sprite", true)?;

    // The mask.
    let m = raw
        .get("mask")
        .filter(|m| m.is_object_like())
        .ok_or_else(|| invalid("mask", "is missing"))?;
    let side = |v: Option<&Value>| {
        v.and_then(Value::whole)
            .filter(|s| (1.0..=MAX_IMAGE_SIDE as f64).contains(s))
    };
    let (width, height) = match (side(m.get("width")), side(m.get("height"))) {
        (Some(w), Some(h)) => (w as u32, h as u32),
        _ => {
            return Err(invalid(
                "mask",
                format!(
                    "must be 1 to {MAX_IMAGE_SIDE} pixels on each side (found {}×{})",
                    js_text(m.get("width")),
                    js_text(m.get("height"))
                ),
            ))
        }
    };
    let n = width as usize * height as usize;
    let bits = match m.get("bits") {
        Some(Value::Bytes(b)) if b.len() == n => b.iter().map(|&b| u8::from(b != 0)).collect(),
        other => {
            let found = match other {
                Some(Value::Bytes(b)) => b.len().to_string(),
                Some(Value::List(l)) => l.len().to_string(),
                Some(Value::Text(t)) => js_len(t).to_string(),
                _ => "none".into(),
            };
            return Err(invalid(
                "mask.bits",
                format!("must hold {n} values ({width}×{height}), found {found}"),
            ));
        }
    };
    let mask = MaskBits {
        width,
        height,
        bits,
    };

    // The strokes.
    let list = raw
        .get("strokes")
        .and_then(Value::as_list)
        .filter(|l| l.len() <= MAX_STROKES)
        .ok_or_else(|| {
            invalid(
                "strokes",
                format!("must be a list of at most {MAX_STROKES} strokes"),
            )
        })?;
    let total: usize = list.iter().filter_map(Value::as_list).map(<[_]>::len).sum();
    if total > MAX_STROKE_POINTS {
        return Err(Error::limit(format!(
            "strokes have {total} points in all; the stroke point limit is {MAX_STROKE_POINTS}"
        ))
        .at("strokes"));
    }
    let (w, h) = (width as f64, height as f64);
    let mut strokes = Vec::with_capacity(list.len());
    for (i, s) in list.iter().enumerate() {
        let s = s
            .as_list()
            .filter(|s| (2..=MAX_STROKE_LEN).contains(&s.len()))
            .ok_or_else(|| {
                invalid(
                    &format!("strokes.{i}"),
                    "must be a list of at least 2 points",
                )
            })?;
        let mut stroke = Vec::with_capacity(s.len());
        for (j, p) in s.iter().enumerate() {
            let field = || format!("strokes.{i}.{j}");
            let [x, y] = p
                .as_list()
                .and_then(|l| match l {
                    [x, y] => Some([x.finite()?, y.finite()?]),
                    _ => None,
                })
                .ok_or_else(|| invalid(&field(), "must be a point [x, y] of finite numbers"))?;
            if x < -1.0 || y < -1.0 || x > w + 1.0 || y > h + 1.0 {
                return Err(invalid(
                    &field(),
                    format!("lies outside the {width}×{height} image"),
                ));
            }
            stroke.push([x, y]);
        }
        strokes.push(stroke);
    }

    // The parameters: every one the page has a control for, none unknown.
    let p = raw
        .get("params")
        .filter(|p| p.is_object_like() && p.as_list().is_none())
        .ok_or_else(|| invalid("params", "are missing"))?;
    let schema = params_schema();
    let mut params = PixelParams::default();
    if let Value::Object(kv) = p {
        for (k, v) in kv {
            let (name, _, rule) = schema.iter().find(|(n, _, _)| n == k).ok_or_else(|| {
                let known: Vec<&str> = schema.iter().map(|(n, _, _)| *n).collect();
                invalid(
                    &format!("params.{k}"),
                    format!("is not a Pixel parameter (they are {})", known.join(", ")),
                )
            })?;
            check_param(name, rule, v, &mut params)?;
        }
    }
    for (name, required, _) in &schema {
        if *required && p.get(name).is_none() {
            return Err(invalid(&format!("params.{name}"), "is missing"));
        }
    }

    let example = match raw.get("example") {
        None | Some(Value::Null) => None,
        Some(v) => Some(
            v.as_text()
                .filter(|e| EXAMPLES.contains(e))
                .ok_or_else(|| {
                    invalid(
                        "example",
                        format!("must be one of {} or none", EXAMPLES.join(", ")),
                    )
                })?
                .to_string(),
        ),
    };
    let name = |k: &str| {
        let n = raw.get("names").and_then(|names| names.get(k));
        (!nullish(n)).then(|| first_chars(&js_text(n), MAX_NAME_CHARS))
    };
    let names = Names {
        source: name("source"),
        sheet: name("sheet"),
    };
    Ok(PixelState {
        example,
        source,
        sheet,
        sprite,
        mask,
        strokes,
        params,
        names,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_choice_is_a_core_name_and_every_default_is_a_choice() {
        for (name, _, rule) in params_schema() {
            if let Rule::Choice(options, ok) = rule {
                for o in options {
                    assert!(ok(o), "{name}: '{o}' is not a core name");
                }
                let d = serde_json::to_value(PixelParams::default()).unwrap();
                let d = d[name].as_str().unwrap().to_string();
                assert!(options.contains(&d.as_str()), "{name}: default {d}");
            }
        }
        // And every core field has a rule.
        let d = serde_json::to_value(PixelParams::default()).unwrap();
        for k in d.as_object().unwrap().keys() {
            assert!(
                params_schema().iter().any(|(n, _, _)| n == k),
                "no rule for {k}"
            );
        }
    }
}
