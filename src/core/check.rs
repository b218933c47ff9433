//! Typed documents: a tool's document is a serde type, read from the page's
//! [`Value`] by [`read_document`] (type errors name the field, through
//! `serde_path_to_error`), then checked by its [`Check`] impl (ranges and
//! rules between fields). The ranges are the request's own constants (each
//! defined once, in the tool's `api.rs` or [`crate::core::request_limits`]),
//! so a document the page keeps is one the core runs.
//!
//! Also the wording of serde's errors, in one place: a request's
//! (`api::request`, "`field` must be …", a `bad-request`) and a document's
//! ("field must be …", an `invalid-input`: the user's file, not the page).
use crate::core::error::{Error, Result};
use crate::core::value::{js_len, Value};
use serde::Deserialize;
use std::fmt;

/// A dotted field path in a document (`settings.seed`, `edits.3.step`);
/// the root is named `state`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Path(String);

impl Path {
    /// The document itself.
    pub fn root() -> Path {
        Path::default()
    }

    /// Field `key` of this one.
    pub fn key(&self, key: &str) -> Path {
        if self.0.is_empty() {
            Path(key.to_string())
        } else {
            Path(format!("{}.{key}", self.0))
        }
    }

    /// Item `i` of this list.
    pub fn index(&self, i: usize) -> Path {
        self.key(&i.to_string())
    }

    /// The dotted path (`state` at the root).
    pub fn as_str(&self) -> &str {
        if self.0.is_empty() {
            "state"
        } else {
            &self.0
        }
    }

    /// An error about this field: "`path` `why`", tied to the path.
    pub fn invalid(&self, why: impl fmt::Display) -> Error {
        Error::input(format!("{} {why}", self.as_str())).at(self.as_str())
    }

    /// `v` must be finite and within `lo..=hi`.
    pub fn number_in(&self, v: f64, (lo, hi): (f64, f64)) -> Result<()> {
        if v.is_finite() && (lo..=hi).contains(&v) {
            Ok(())
        } else {
            Err(self.invalid(format!("must be a number from {lo} to {hi}")))
        }
    }

    /// `v` must be within `lo..=hi` (whole numbers).
    pub fn whole_in<T: PartialOrd + fmt::Display>(&self, v: T, (lo, hi): (T, T)) -> Result<()> {
        if lo <= v && v <= hi {
            Ok(())
        } else {
            Err(self.invalid(format!("must be a whole number from {lo} to {hi}")))
        }
    }

    /// `text` must be at most `max` UTF-16 units (as the page counts).
    pub fn js_len_at_most(&self, text: &str, max: usize, why: impl fmt::Display) -> Result<()> {
        if js_len(text) <= max {
            Ok(())
        } else {
            Err(self.invalid(why))
        }
    }
}

impl fmt::Display for Path {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// The rules of a document part that its type does not say: ranges, sizes,
/// agreements between fields. `at` is the part's path, for messages.
pub trait Check {
    fn check(&self, at: &Path) -> Result<()>;
}

impl<T: Check> Check for Option<T> {
    fn check(&self, at: &Path) -> Result<()> {
        self.as_ref().map_or(Ok(()), |v| v.check(at))
    }
}

impl<T: Check> Check for Vec<T> {
    fn check(&self, at: &Path) -> Result<()> {
        self.iter()
            .enumerate()
            .try_for_each(|(i, v)| v.check(&at.index(i)))
    }
}

/// Read a document of `title`'s tool: it must be an object; its type is
/// read from it (an error names the field and what it must be), then
/// checked.
pub fn read_document<'a, T: Deserialize<'a> + Check>(raw: &'a Value, title: &str) -> Result<T> {
    if !raw.is_plain_object() {
        return Err(Path::root().invalid(format!("is not a {title} document")));
    }
    let doc: T = read_part(raw)?;
    doc.check(&Path::root())?;
    Ok(doc)
}

/// Read a part of a document as `T` (no [`Check`]); an error names the
/// field (`settings.seed`) and says what it must be.
pub fn read_part<'a, T: Deserialize<'a>>(raw: &'a Value) -> Result<T> {
    serde_path_to_error::deserialize(raw).map_err(|e| {
        let mut field = dotted(e.path());
        let msg = e.inner().to_string();
        // An unknown field's path ends with its key: the object is at fault.
        if msg.starts_with("unknown field ") {
            field = field.rsplit_once('.').map_or("", |(p, _)| p).to_string();
        }
        let text = describe(Style::Document, &field, &msg);
        // A missing field is the field itself.
        let at = match msg.strip_prefix("missing field ") {
            Some(f) => Path(field).key(f.trim_matches('`')),
            None => Path(field),
        };
        Error::input(text).at(at.as_str())
    })
}

/// `params.d_max`, `points.3` (no leading dot; empty at the root).
pub fn dotted(path: &serde_path_to_error::Path) -> String {
    use serde_path_to_error::Segment;
    path.iter()
        .filter_map(|s| match s {
            Segment::Seq { index } => Some(index.to_string()),
            Segment::Map { key } | Segment::Enum { variant: key } => Some(key.clone()),
            Segment::Unknown => None,
        })
        .collect::<Vec<_>>()
        .join(".")
}

/// Whose words: a request's (fields in backticks, the root "the request")
/// or a document's (fields plain, the root "state").
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Style {
    Request,
    Document,
}

/// What a serde "expected" clause asks for, in words.
fn wanted(expected: &str) -> String {
    let e = expected.trim();
    let words = match e {
        "a string" | "a borrowed string" | "a character" => "text",
        "f64" | "f32" => "a number",
        "u8" | "u16" | "u32" | "u64" | "usize" => "a whole number ≥ 0",
        "i8" | "i16" | "i32" | "i64" | "isize" => "a whole number",
        "a boolean" => "true or false",
        "a sequence" => "a list",
        "a map" => "an object",
        "byte array" | "a byte array" | "a byte buf" | "bytes" => "bytes (a Uint8Array)",
        _ if e.starts_with("struct ") => "an object",
        _ if e.starts_with("enum ") || e.starts_with("variant identifier") => "a name (text)",
        _ if e.starts_with("a tuple of size ") || e.starts_with("an array of length ") => {
            return format!("a list of {}", e.rsplit(' ').next().unwrap_or("?"));
        }
        _ => return e.to_string(),
    };
    words.to_string()
}

/// What serde says it got, in words.
fn got(what: &str) -> String {
    match what.trim() {
        "unit value" | "null" => "null".into(),
        "floating point `NaN`" => "NaN".into(),
        w => w.replace('`', "'"),
    }
}

/// The names in a serde list ("`a`, `b` or `c`", "one of `a`, `b`").
fn names(list: &str) -> String {
    list.split('`')
        .skip(1)
        .step_by(2)
        .collect::<Vec<_>>()
        .join(", ")
}

/// Rewrite serde's message ("invalid type: unit value, expected a string")
/// about `field` (dotted, empty at the root) in words: "`program` must be
/// text (got null)" (a request's), "program must be text (got null)" (a
/// document's).
pub fn describe(style: Style, field: &str, msg: &str) -> String {
    let name = match (style, field.is_empty()) {
        (Style::Request, true) => "the request".to_string(),
        (Style::Request, false) => format!("`{field}`"),
        (Style::Document, true) => "state".to_string(),
        (Style::Document, false) => field.to_string(),
    };
    // serde_wasm_bindgen's errors are JS `Error`s: "Error: invalid type: ...".
    let msg = msg.strip_prefix("Error: ").unwrap_or(msg);
    let msg = msg
        .split(" at line ")
        .next()
        .unwrap_or(msg)
        .trim()
        .to_string();
    if let Some(rest) = msg
        .strip_prefix("invalid type: ")
        .or_else(|| msg.strip_prefix("invalid value: "))
    {
        match rest.split_once(", expected ") {
            Some((g, e)) => format!("{name} must be {} (got {})", wanted(e), got(g)),
            None => format!("{name}: {msg}"),
        }
    } else if let Some(rest) = msg.strip_prefix("missing field ") {
        let f = rest.trim_matches('`');
        let full = if field.is_empty() {
            f.to_string()
        } else {
            format!("{field}.{f}")
        };
        match style {
            Style::Request => format!("`{full}` is missing"),
            Style::Document => format!("{full} is missing"),
        }
    } else if let Some(rest) = msg.strip_prefix("unknown variant ") {
        match (style, rest.split_once(", expected ")) {
            (Style::Request, Some((v, e))) => format!(
                "{name} is {}; expected {}",
                v.replace('`', "'"),
                e.replace('`', "'")
            ),
            (Style::Document, Some((_, e))) => format!("{name} must be one of {}", names(e)),
            (_, None) => format!("{name}: {msg}"),
        }
    } else if let Some(rest) = msg.strip_prefix("unknown field ") {
        match rest.split_once(", expected ") {
            Some((f, e)) => format!(
                "{name} has no field {}; expected {}",
                f.replace('`', "'"),
                e.replace('`', "'")
            ),
            None => format!("{name} has no field {}", rest.replace('`', "'")),
        }
    } else if let Some(rest) = msg.strip_prefix("invalid length ") {
        match rest.split_once(", expected ") {
            Some((n, e)) => format!("{name} must be {} (got {n} items)", wanted(e)),
            None => format!("{name}: {msg}"),
        }
    } else {
        match style {
            Style::Request => format!("{name}: {msg}"),
            // A type's own refusal (`deserialize_with`) says "must be …".
            Style::Document => format!("{name} {msg}"),
        }
    }
}

/// `deserialize_with`: `null` (or a missing field, with `#[serde(default)]`)
/// is the type's default.
pub fn null_as_default<'de, D, T>(d: D) -> std::result::Result<T, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de> + Default,
{
    Ok(Option::<T>::deserialize(d)?.unwrap_or_default())
}

// ------------------------------------------------- document helpers --
// `&Value` reads UTF-8 bytes as text and stops a fixed-size array after its
// `N` items: these read text as text only and a list as exactly `N` items.

/// [`read_part`] of a part found at `at` (its fields' paths start there).
pub fn read_part_at<'a, T: Deserialize<'a>>(raw: &'a Value, at: &Path) -> Result<T> {
    serde_path_to_error::deserialize(raw).map_err(|e| {
        let inner = dotted(e.path());
        let mut field = match inner.is_empty() {
            true => at.0.clone(),
            false => at.key(&inner).0,
        };
        let msg = e.inner().to_string();
        if msg.starts_with("unknown field ") {
            field = field.rsplit_once('.').map_or("", |(p, _)| p).to_string();
        }
        let text = describe(Style::Document, &field, &msg);
        let at = match msg.strip_prefix("missing field ") {
            Some(f) => Path(field).key(f.trim_matches('`')),
            None => Path(field),
        };
        Error::input(text).at(at.as_str())
    })
}

/// `deserialize_with` for a fixed-size list (`[T; N]`): exactly `N` items.
/// (A [`Value`] list read as an array stops after `N` items and would drop
/// the rest: `[1, 2, 3]` is not a point `[x, y]`.)
pub fn exactly<'de, D, T, const N: usize>(d: D) -> std::result::Result<[T; N], D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    let list = Vec::<T>::deserialize(d)?;
    let n = list.len();
    list.try_into().map_err(|_| {
        serde::de::Error::invalid_length(n, &format!("an array of length {N}").as_str())
    })
}

/// [`exactly`] for an optional list (`null` or missing: `None`, with
/// `#[serde(default)]`).
pub fn exactly_or_null<'de, D, T, const N: usize>(
    d: D,
) -> std::result::Result<Option<[T; N]>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    #[derive(Deserialize)]
    #[serde(transparent, bound(deserialize = "T: Deserialize<'de>"))]
    struct Exactly<T, const N: usize>(#[serde(deserialize_with = "exactly")] [T; N]);
    Ok(Option::<Exactly<T, N>>::deserialize(d)?.map(|e| e.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde::Deserialize;

    #[derive(Debug, Deserialize, PartialEq)]
    #[serde(deny_unknown_fields)]
    struct Doc {
        n: u32,
        #[serde(default)]
        list: Option<Vec<f64>>,
        #[serde(with = "serde_bytes", default)]
        bytes: Vec<u8>,
    }
    impl Check for Doc {
        fn check(&self, at: &Path) -> Result<()> {
            at.key("n").whole_in(self.n, (1, 9))
        }
    }

    fn read(j: serde_json::Value) -> Result<Doc> {
        read_document(&Value::read(&j, true).unwrap(), "Test")
    }

    #[test]
    fn types_and_rules_name_their_fields() {
        use serde_json::json;
        let ok = read(json!({"n": 3, "list": [1, 2.5], "bytes": {"$bytes": "AQI="}})).unwrap();
        assert_eq!(ok.bytes, [1, 2]);
        let cases = [
            (json!([]), "state", "state is not a Test document"),
            (json!({}), "n", "n is missing"),
            (json!({"n": 0}), "n", "n must be a whole number from 1 to 9"),
            (
                json!({"n": 2.5}),
                "n",
                "n must be a whole number ≥ 0 (got floating point '2.5')",
            ),
            (
                json!({"n": 1, "list": [1, "x"]}),
                "list.1",
                "list.1 must be a number (got string \"x\")",
            ),
            // A list of numbers is not bytes; a list is never read as a struct.
            (
                json!({"n": 1, "bytes": [1, 2]}),
                "bytes",
                "bytes must be bytes (a Uint8Array) (got sequence)",
            ),
            (
                json!({"n": 1, "m": 2}),
                "state",
                "state has no field 'm'; expected one of 'n', 'list', 'bytes'",
            ),
        ];
        for (j, field, message) in cases {
            let e = read(j).unwrap_err();
            assert_eq!((e.field(), e.to_string().as_str()), (Some(field), message));
            assert_eq!(
                e.kind(),
                "invalid-input",
                "a document's fault is the user's"
            );
        }
        let big = read(json!({"n": 1e10})).unwrap_err();
        assert_eq!(big.field(), Some("n"), "{big}");
        let too_big = read(json!({"n": 1e300})).unwrap_err();
        assert_eq!(too_big.field(), Some("n"), "{too_big}");
    }

    /// The `&Value` reader reads text as text only (a page's bytes are not a
    /// name) and a fixed-size array as exactly its items (`[1, 2, 3]` is
    /// not a point: the third was once dropped).
    #[test]
    fn text_is_not_bytes_and_an_array_has_exactly_its_items() {
        use serde_json::json;
        #[derive(Debug, Deserialize)]
        #[allow(dead_code)]
        struct Named {
            name: String,
            point: [f64; 2],
        }
        impl Check for Named {
            fn check(&self, _: &Path) -> Result<()> {
                Ok(())
            }
        }
        let read = |j: serde_json::Value| -> Result<Named> {
            read_document(&Value::read(&j, true).unwrap(), "Test")
        };
        assert!(read(json!({"name": "a", "point": [1, 2]})).is_ok());
        let e = read(json!({"name": {"$bytes": "AQI="}, "point": [1, 2]})).unwrap_err();
        assert_eq!(e.field(), Some("name"), "{e}");
        for point in [json!([1, 2, 3]), json!([1])] {
            let e = read(json!({"name": "a", "point": point})).unwrap_err();
            assert_eq!(e.field(), Some("point"), "{e}");
        }
    }
}
