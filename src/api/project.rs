//! Project files and tool states: the schema of every tool's document, in
//! the core, in one place.
//!
//! A tool's state (what the page keeps, autosaves, puts in a project file
//! or a share link) is checked here field by field, by the tool's own
//! `state` module ([`crate::pixel::state`], [`crate::pattern::state`],
//! [`inspect_state`]); a rule that is a core request limit (image side,
//! stroke points, program bytes, Pixel parameter ranges) uses that limit,
//! so the page cannot accept a document the core would refuse to run.
//!
//! Two request kinds:
//! - `check-state {tool, version, state}` → the normalised state (what the
//!   page keeps); `state` is as the page holds it (byte fields are
//!   `Uint8Array`s, i.e. serde bytes).
//! - `open-project {text}` → `{tool, stateVersion, checked, state}`: the
//!   text of a `*.filigree.json` file (bounded by
//!   [`limits::MAX_PROJECT_BYTES`]), its envelope checked
//!   (`format`, `version`, `tool`, `stateVersion`, `state`), byte fields
//!   stored as `{"$bytes": base64}` decoded, and the state checked when it
//!   has the tool's current schema version (`checked: true`). A stepped
//!   job ([`OpenProjectJob`]): the text is read a slice at a time by the
//!   resumable [`json::Reader`], then checked, then freed.
//!
//! Older state versions: the page's `migrate` hook (a panel's `state`
//! declaration) turns an older state into the current schema, and the page
//! then asks `check-state`. So `open-project` returns a state of an older
//! version decoded but unchecked (`checked: false`), and `check-state`
//! refuses any version but the current one. A newer version is refused in
//! both, with a message saying to update Filigree.
//!
//! Every error names the field at fault ([`Error::field`], a dotted path
//! such as `mask.bits`, `strokes.0.1`, `params.d_max`) and its message
//! starts with that path, as the page's validators always did.
use crate::core::error::{Error, Result};
use crate::core::limits;
use serde::de::{self, DeserializeSeed, MapAccess, SeqAccess, Visitor};
use serde::ser::{SerializeMap, SerializeSeq};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::borrow::Cow;
use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::fmt;

pub mod json;

/// `format` of a project file.
pub const PROJECT_FORMAT: &str = "filigree-project";
/// Newest project file format this core reads. Format 2 added
/// `stateVersion`; a format-1 file carries a state of version 1.
pub const PROJECT_VERSION: u32 = 2;
/// The largest whole number a page's number holds exactly (2^53 − 1).
pub const MAX_SAFE_INTEGER: f64 = 9_007_199_254_740_991.0;

// ------------------------------------------------------------------ values --

/// A state as the page holds it: plain JS data (numbers are doubles, bytes
/// are `Uint8Array`s). Read with a bounded reader ([`Value::read`]): at most
/// [`limits::MAX_STATE_VALUES`] values, nested at most
/// [`limits::MAX_STATE_DEPTH`] deep.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Value {
    /// `null` (and a JS `undefined`).
    #[default]
    Null,
    Bool(bool),
    Number(f64),
    Text(String),
    Bytes(Vec<u8>),
    List(Vec<Value>),
    /// Keys in first-seen order, each once (a repeated key keeps its last value).
    Object(Vec<(String, Value)>),
}

impl Value {
    /// Read a value with any self-describing deserializer (`serde_json`,
    /// `serde_wasm_bindgen`), bounded. `project`: decode `{"$bytes": base64}`
    /// objects (a project file's byte fields) into bytes.
    pub fn read<'de, D: Deserializer<'de>>(d: D, project: bool) -> Result<Value> {
        let ctx = ReadCtx {
            left: Cell::new(limits::MAX_STATE_VALUES),
            failure: RefCell::new(None),
            project,
        };
        let r = Reader {
            ctx: &ctx,
            depth: 0,
        }
        .deserialize(d);
        if let Some(e) = ctx.failure.into_inner() {
            return Err(e);
        }
        r.map_err(|e| Error::input(e.to_string()))
    }

    /// The value of `key` of an object (`None` for a missing key or a non-object).
    pub fn get(&self, key: &str) -> Option<&Value> {
        match self {
            Value::Object(kv) => kv.iter().find(|(k, _)| k == key).map(|(_, v)| v),
            _ => None,
        }
    }

    /// Whether this is JS-`typeof` `object` and not null: an object, a list
    /// or bytes.
    pub fn is_object_like(&self) -> bool {
        matches!(self, Value::Object(_) | Value::List(_) | Value::Bytes(_))
    }

    /// A plain object (not a list, not bytes).
    pub fn is_plain_object(&self) -> bool {
        matches!(self, Value::Object(_))
    }

    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::Number(v) => Some(*v),
            _ => None,
        }
    }

    /// A finite number.
    pub fn finite(&self) -> Option<f64> {
        self.as_f64().filter(|v| v.is_finite())
    }

    /// A whole number (JS `Number.isInteger`).
    pub fn whole(&self) -> Option<f64> {
        self.finite().filter(|v| v.fract() == 0.0)
    }

    pub fn as_text(&self) -> Option<&str> {
        match self {
            Value::Text(s) => Some(s),
            _ => None,
        }
    }

    pub fn as_list(&self) -> Option<&[Value]> {
        match self {
            Value::List(v) => Some(v),
            _ => None,
        }
    }
}

/// `Option<&Value>` as JS reads it: a missing key and `null` are both "nullish".
pub fn nullish(v: Option<&Value>) -> bool {
    matches!(v, None | Some(Value::Null))
}

/// A number as JS writes it (`3`, `0.5`, `NaN`, `Infinity`).
pub fn js_number(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v.is_infinite() {
        if v > 0.0 { "Infinity" } else { "-Infinity" }.into()
    } else if v.fract() == 0.0 && v.abs() < 1e21 {
        format!("{v:.0}")
    } else {
        format!("{v}")
    }
}

/// A value as JS's `String(v)` writes it (`undefined` for a missing one).
pub fn js_text(v: Option<&Value>) -> String {
    match v {
        None => "undefined".into(),
        Some(Value::Null) => "null".into(),
        Some(Value::Bool(b)) => b.to_string(),
        Some(Value::Number(n)) => js_number(*n),
        Some(Value::Text(s)) => s.clone(),
        Some(Value::Bytes(b)) => b.iter().map(u8::to_string).collect::<Vec<_>>().join(","),
        Some(Value::List(l)) => l
            .iter()
            .map(|x| match x {
                Value::Null => String::new(),
                x => js_text(Some(x)),
            })
            .collect::<Vec<_>>()
            .join(","),
        Some(Value::Object(_)) => "[object Object]".into(),
    }
}

/// The first `n` characters of `s` (JS `slice(0, n)`, counted in characters).
pub fn first_chars(s: &str, n: usize) -> String {
    s.chars().take(n).collect()
}

/// Length of `s` as JS counts it (UTF-16 code units).
pub fn js_len(s: &str) -> usize {
    s.encode_utf16().count()
}

/// An error about `field`: "`field` `why`" (the page's wording), tied to `field`.
pub fn invalid(field: &str, why: impl fmt::Display) -> Error {
    Error::input(format!("{field} {why}")).at(field)
}

/// More than [`limits::MAX_STATE_VALUES`] values in a `what` (`project`, `state`).
fn too_many(what: &str) -> Error {
    Error::limit(format!(
        "the {what} holds more than {} values (the state value limit)",
        limits::MAX_STATE_VALUES
    ))
}

/// Nested deeper than [`limits::MAX_STATE_DEPTH`].
fn too_deep(what: &str) -> Error {
    Error::limit(format!(
        "the {what} is nested too deeply (more than {} levels)",
        limits::MAX_STATE_DEPTH
    ))
}

struct ReadCtx {
    left: Cell<usize>,
    failure: RefCell<Option<Error>>,
    project: bool,
}

impl ReadCtx {
    fn fail<E: de::Error>(&self, e: Error) -> E {
        let msg = e.to_string();
        self.failure.borrow_mut().get_or_insert(e);
        E::custom(msg)
    }
    fn count<E: de::Error>(&self) -> std::result::Result<(), E> {
        match self.left.get().checked_sub(1) {
            Some(n) => {
                self.left.set(n);
                Ok(())
            }
            None => Err(self.fail(too_many(self.what()))),
        }
    }
    fn what(&self) -> &'static str {
        if self.project {
            "project"
        } else {
            "state"
        }
    }
}

#[derive(Clone, Copy)]
struct Reader<'a> {
    ctx: &'a ReadCtx,
    depth: usize,
}

impl<'de> DeserializeSeed<'de> for Reader<'_> {
    type Value = Value;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl Reader<'_> {
    fn inner<E: de::Error>(self) -> std::result::Result<Self, E> {
        if self.depth >= limits::MAX_STATE_DEPTH {
            return Err(self.ctx.fail(too_deep(self.ctx.what())));
        }
        Ok(Reader {
            ctx: self.ctx,
            depth: self.depth + 1,
        })
    }
}

impl<'de> Visitor<'de> for Reader<'_> {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("plain data")
    }
    fn visit_unit<E: de::Error>(self) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Null)
    }
    fn visit_none<E: de::Error>(self) -> std::result::Result<Value, E> {
        self.visit_unit()
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Value, D::Error> {
        d.deserialize_any(self)
    }
    fn visit_bool<E: de::Error>(self, v: bool) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Bool(v))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Number(v as f64))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Number(v as f64))
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Number(v))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Text(v.to_string()))
    }
    fn visit_string<E: de::Error>(self, v: String) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Text(v))
    }
    fn visit_bytes<E: de::Error>(self, v: &[u8]) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Bytes(v.to_vec()))
    }
    fn visit_byte_buf<E: de::Error>(self, v: Vec<u8>) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Bytes(v))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<Value, A::Error> {
        self.ctx.count()?;
        let inner = self.inner()?;
        let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(4096));
        while let Some(v) = seq.next_element_seed(inner)? {
            out.push(v);
        }
        Ok(Value::List(out))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<Value, A::Error> {
        self.ctx.count()?;
        let inner = self.inner()?;
        let mut out: Vec<(String, Value)> = Vec::new();
        let mut index: HashMap<String, usize> = HashMap::new();
        while let Some(k) = map.next_key::<String>()? {
            let v = map.next_value_seed(inner)?;
            match index.get(&k) {
                Some(&i) => out[i].1 = v,
                None => {
                    index.insert(k.clone(), out.len());
                    out.push((k, v));
                }
            }
        }
        if self.ctx.project {
            if let Some(Value::Text(b64)) = index.get("$bytes").map(|&i| &out[i].1) {
                return match base64_decode(b64) {
                    Some(bytes) => Ok(Value::Bytes(bytes)),
                    None => Err(self.ctx.fail(Error::input(json::NOT_BASE64))),
                };
            }
        }
        Ok(Value::Object(out))
    }
}

impl<'de> Deserialize<'de> for Value {
    /// A value as the page sends it (no `$bytes` decoding), bounded.
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Value, D::Error> {
        Value::read(d, false).map_err(|e| de::Error::custom(e.to_string()))
    }
}

impl Serialize for Value {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Value::Null => s.serialize_unit(),
            Value::Bool(b) => s.serialize_bool(*b),
            Value::Number(n) if n.fract() == 0.0 && n.abs() <= MAX_SAFE_INTEGER => {
                s.serialize_i64(*n as i64)
            }
            Value::Number(n) => s.serialize_f64(*n),
            Value::Text(t) => s.serialize_str(t),
            Value::Bytes(b) => s.serialize_bytes(b),
            Value::List(l) => {
                let mut seq = s.serialize_seq(Some(l.len()))?;
                for v in l {
                    seq.serialize_element(v)?;
                }
                seq.end()
            }
            Value::Object(kv) => {
                let mut m = s.serialize_map(Some(kv.len()))?;
                for (k, v) in kv {
                    m.serialize_entry(k, v)?;
                }
                m.end()
            }
        }
    }
}

// ------------------------------------------------------------------ base64 --

/// Decode base64 as the page's `atob` does: ASCII whitespace ignored,
/// padding optional; `None` if it is not base64.
pub fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let mut s: Vec<u8> = text
        .bytes()
        .filter(|b| !matches!(b, b' ' | b'\t' | b'\n' | b'\x0c' | b'\r'))
        .collect();
    if s.len().is_multiple_of(4) {
        for _ in 0..2 {
            if s.last() == Some(&b'=') {
                s.pop();
            }
        }
    }
    if s.len() % 4 == 1 {
        return None;
    }
    let val = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 2);
    for chunk in s.chunks(4) {
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= val(c)? << (18 - 6 * i);
        }
        let n = chunk.len() - 1; // bytes in this chunk
        for i in 0..n {
            out.push((acc >> (16 - 8 * i)) as u8);
        }
    }
    Some(out)
}

/// Encode bytes as base64 with padding (the page's `btoa`).
pub fn base64_encode(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let acc = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(A[(acc >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

// ------------------------------------------------------------------- tools --

/// A tool that has a document: its id, its title (as the page names it)
/// and its current state schema version.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ToolSchema {
    pub id: &'static str,
    pub title: &'static str,
    pub version: u32,
}

/// Every tool whose state the core checks.
pub const TOOLS: &[ToolSchema] = &[
    ToolSchema {
        id: "pixel",
        title: "Pixel",
        version: crate::pixel::state::STATE_VERSION,
    },
    ToolSchema {
        id: "fit",
        title: "Fit",
        version: crate::pattern::state::STATE_VERSION,
    },
    ToolSchema {
        id: "tangle",
        title: "Tangle",
        version: crate::tangle::state::STATE_VERSION,
    },
    ToolSchema {
        id: "micro",
        title: "Micro",
        version: crate::micro::state::STATE_VERSION,
    },
    ToolSchema {
        id: "texture",
        title: "Texture",
        version: crate::texture::state::STATE_VERSION,
    },
    ToolSchema {
        id: "inspect",
        title: "Inspect image",
        version: inspect_state::STATE_VERSION,
    },
];

/// The schema of tool `id`.
pub fn tool(id: &str) -> Option<&'static ToolSchema> {
    TOOLS.iter().find(|t| t.id == id)
}

/// A checked, normalised state of any tool (serialised as the state alone).
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ToolState {
    Pixel(Box<crate::pixel::state::PixelState>),
    Fit(Box<crate::pattern::state::FitState>),
    Tangle(Box<crate::tangle::state::TangleState>),
    Micro(Box<crate::micro::state::MicroState>),
    Texture(Box<crate::texture::state::TextureState>),
    Inspect(inspect_state::InspectState),
}

/// Check a state of `tool` whose schema version is `version`.
pub fn check_state(tool_id: &str, version: u64, state: &Value) -> Result<ToolState> {
    let t = tool(tool_id).ok_or_else(|| {
        Error::input(format!(
            "Filigree has no tool '{tool_id}' (it has {})",
            TOOLS.iter().map(|t| t.id).collect::<Vec<_>>().join(", ")
        ))
        .at("tool")
    })?;
    check_version(t, version)?;
    Ok(match t.id {
        "pixel" => ToolState::Pixel(Box::new(crate::pixel::state::check(state)?)),
        "fit" => ToolState::Fit(Box::new(crate::pattern::state::check(state)?)),
        "tangle" => ToolState::Tangle(Box::new(crate::tangle::state::check(state)?)),
        "micro" => ToolState::Micro(Box::new(crate::micro::state::check(state)?)),
        "texture" => ToolState::Texture(Box::new(crate::texture::state::check(state)?)),
        _ => ToolState::Inspect(inspect_state::check(state)?),
    })
}

fn check_version(t: &ToolSchema, version: u64) -> Result<()> {
    if version == 0 {
        return Err(Error::input("the state has no schema version").at("version"));
    }
    if version > t.version as u64 {
        return Err(Error::input(format!(
            "it was made by a newer Filigree ({} state version {version}); update Filigree to open it",
            t.title
        ))
        .at("version"));
    }
    if version < t.version as u64 {
        return Err(Error::input(format!(
            "{} state version {version} must be migrated to version {} before it is checked",
            t.title, t.version
        ))
        .at("version"));
    }
    Ok(())
}

// ---------------------------------------------------------------- requests --

/// `check-state`: a tool's state as the page holds it.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct CheckStateRequest {
    /// The tool (`pixel`, `fit`, `inspect`).
    pub tool: String,
    /// The state's schema version (after the page's migration: the tool's current one).
    pub version: u64,
    pub state: Value,
}

/// `open-project`: the text of a project file.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OpenProjectRequest {
    pub text: String,
}

/// A state from a project file: checked, or (older schema) decoded only.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(untagged)]
pub enum ProjectState {
    Checked(ToolState),
    /// An older schema version: the page migrates it, then asks `check-state`.
    Raw(Value),
}

/// The answer of `open-project`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OpenedProject {
    pub tool: String,
    #[serde(rename = "stateVersion")]
    pub state_version: u32,
    /// Whether `state` is checked (its version is the tool's current one).
    pub checked: bool,
    pub state: ProjectState,
}

/// `check-state`.
pub fn run_check_state(req: &CheckStateRequest) -> Result<ToolState> {
    check_state(&req.tool, req.version, &req.state)
}

/// `open-project`: parse, check the envelope, decode, check the state, to
/// the end (the stepped [`OpenProjectJob`] run in one go).
pub fn open_project(text: &str) -> Result<OpenedProject> {
    crate::core::job::run_quietly(OpenProjectJob::new(Cow::Borrowed(text)))
}

/// `open-project` as the worker runs it: the text read in slices of
/// [`READ_FUEL`] ([`json::Reader`]), then the envelope and the state
/// checked in one more step.
pub fn start_open_project(req: OpenProjectRequest) -> OpenProjectJob<'static> {
    OpenProjectJob::new(Cow::Owned(req.text))
}

/// Fuel of one reading step of `open-project` (see [`json::Reader::step`]):
/// about 1 MB of text, a few ms (`filigree bench slices --only open-project`).
pub const READ_FUEL: usize = 1 << 20;

/// The stepped `open-project` request.
pub struct OpenProjectJob<'a> {
    text: Cow<'a, str>,
    stage: OpenStage,
}

enum OpenStage {
    /// The size is not checked yet.
    Start,
    Read(json::Reader),
    /// The file is read: check it.
    Check(Value),
    /// Checked: the document's values freed a bounded number a step (the
    /// points of 200,000 stroke points are as many allocations).
    Free(Vec<Drain>, Box<OpenedProject>),
    Over,
}

/// A list or object being freed.
enum Drain {
    List(std::vec::IntoIter<Value>),
    Object(std::vec::IntoIter<(String, Value)>),
}

/// Values freed in one step of [`OpenStage::Free`].
const FREE_PER_STEP: usize = 50_000;

/// Free up to `n` values of the stack; whether all are freed.
fn free_some(stack: &mut Vec<Drain>, n: usize) -> bool {
    for _ in 0..n {
        let next = match stack.last_mut() {
            None => return true,
            Some(Drain::List(it)) => it.next(),
            Some(Drain::Object(it)) => it.next().map(|(_, v)| v),
        };
        match next {
            None => {
                stack.pop();
            }
            Some(Value::List(l)) => stack.push(Drain::List(l.into_iter())),
            Some(Value::Object(o)) => stack.push(Drain::Object(o.into_iter())),
            Some(v) => drop(v),
        }
    }
    stack.is_empty()
}

impl<'a> OpenProjectJob<'a> {
    pub fn new(text: Cow<'a, str>) -> Self {
        OpenProjectJob {
            text,
            stage: OpenStage::Start,
        }
    }
}

fn not_a_project(why: &str) -> Error {
    Error::input(format!("not a Filigree project: {why}"))
}

/// A reading error as `open-project` words it: a limit stays a limit, bad
/// base64 is said as such, anything else is "not valid JSON (...)".
fn reading_error(e: Error) -> Error {
    match e {
        Error::Limit(m) => Error::limit(format!("not a Filigree project: {m}")),
        e if e.to_string() == json::NOT_BASE64 => not_a_project(json::NOT_BASE64),
        e => not_a_project(&format!("the file is not valid JSON ({e})")),
    }
}

impl crate::core::job::Job for OpenProjectJob<'_> {
    type Output = OpenedProject;
    fn step(&mut self) -> Result<crate::core::job::Step<OpenedProject>> {
        use crate::core::job::{Progress, Step};
        match std::mem::replace(&mut self.stage, OpenStage::Over) {
            OpenStage::Start => {
                let text = &self.text;
                if text.len() > limits::MAX_PROJECT_BYTES {
                    return Err(Error::limit(format!(
                        "not a Filigree project: the file is {} bytes; project files may be at most {} bytes (the project file limit)",
                        text.len(),
                        limits::MAX_PROJECT_BYTES
                    ))
                    .at("text"));
                }
                self.stage = OpenStage::Read(json::Reader::new());
                Ok(Step::Running(Progress::new(
                    0.0,
                    "reading the project file",
                )))
            }
            OpenStage::Read(mut r) => match r.step(&self.text, READ_FUEL).map_err(reading_error)? {
                Some(doc) => {
                    // The text is not needed any more.
                    self.text = Cow::Borrowed("");
                    self.stage = OpenStage::Check(doc);
                    Ok(Step::Running(Progress::new(0.9, "checking the project")))
                }
                None => {
                    let done = r.position() as f64 / self.text.len().max(1) as f64;
                    self.stage = OpenStage::Read(r);
                    Ok(Step::Running(Progress::new(
                        0.9 * done,
                        "reading the project file",
                    )))
                }
            },
            OpenStage::Check(mut doc) => {
                let out = check_project(&mut doc)?;
                self.stage =
                    OpenStage::Free(vec![Drain::List(vec![doc].into_iter())], Box::new(out));
                Ok(Step::Running(Progress::new(
                    0.95,
                    "freeing the file's data",
                )))
            }
            OpenStage::Free(mut stack, out) => {
                if free_some(&mut stack, FREE_PER_STEP) {
                    return Ok(Step::Done(*out));
                }
                self.stage = OpenStage::Free(stack, out);
                Ok(Step::Running(Progress::new(
                    0.95,
                    "freeing the file's data",
                )))
            }
            OpenStage::Over => Err(Error::input("this job has already finished")),
        }
    }
}

/// Check a project file's envelope and its state.
fn check_project(doc: &mut Value) -> Result<OpenedProject> {
    let nope = not_a_project;
    if doc.get("format").and_then(Value::as_text) != Some(PROJECT_FORMAT) {
        return Err(nope("\"format\" is missing or different"));
    }
    let version = doc
        .get("version")
        .and_then(Value::whole)
        .filter(|v| *v >= 1.0)
        .ok_or_else(|| nope("\"version\" is missing"))?;
    if version > PROJECT_VERSION as f64 {
        return Err(Error::input(format!(
            "this project was saved by a newer Filigree (file format {}); update Filigree to open it",
            js_number(version)
        )));
    }
    let tool_id = doc
        .get("tool")
        .and_then(Value::as_text)
        .filter(|t| !t.is_empty())
        .ok_or_else(|| nope("\"tool\" is missing"))?;
    let state_version = if version == 1.0 {
        1.0
    } else {
        doc.get("stateVersion")
            .and_then(Value::whole)
            .filter(|v| *v >= 1.0)
            .ok_or_else(|| nope("\"stateVersion\" is missing"))?
    };
    let state = doc
        .get("state")
        .filter(|s| s.is_object_like())
        .ok_or_else(|| nope("\"state\" is missing"))?;
    let t = tool(tool_id).ok_or_else(|| {
        Error::input(format!(
            "it is a project of a tool this Filigree does not have ('{tool_id}')"
        ))
        .at("tool")
    })?;
    if state_version > t.version as f64 {
        check_version(t, state_version as u64)?;
    }
    let state_version = state_version as u32;
    let (checked, state) = if state_version == t.version {
        (
            true,
            ProjectState::Checked(check_state(t.id, state_version as u64, state)?),
        )
    } else {
        // Moved out of the document, not copied.
        let state = match doc {
            Value::Object(kv) => kv
                .iter_mut()
                .find(|(k, _)| k == "state")
                .map(|(_, v)| std::mem::take(v))
                .unwrap_or_default(),
            _ => Value::Null,
        };
        (false, ProjectState::Raw(state))
    };
    Ok(OpenedProject {
        tool: t.id.to_string(),
        state_version,
        checked,
        state,
    })
}

#[cfg(feature = "json")]
/// The text of a project file, as the page's `projectText` writes it: byte
/// fields as `{"$bytes": base64}`. For tests, seeds and fuzzing (feature
/// `json`; the page writes its own files, so the wasm build leaves it out).
pub fn project_text(tool: &str, state_version: u32, state: &impl Serialize) -> Result<String> {
    let state = to_value(state).map_err(Error::input)?;
    let doc = Value::Object(vec![
        ("format".into(), Value::Text(PROJECT_FORMAT.into())),
        ("version".into(), Value::Number(PROJECT_VERSION.into())),
        ("tool".into(), Value::Text(tool.into())),
        ("stateVersion".into(), Value::Number(state_version.into())),
        ("state".into(), state),
    ]);
    serde_json::to_string(&Bytes64(&doc)).map_err(|e| Error::input(e.to_string()))
}

#[cfg(feature = "json")]
/// Serialises a value with bytes as `{"$bytes": base64}`.
struct Bytes64<'a>(&'a Value);

#[cfg(feature = "json")]
impl Serialize for Bytes64<'_> {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self.0 {
            Value::Bytes(b) => {
                let mut m = s.serialize_map(Some(1))?;
                m.serialize_entry("$bytes", &base64_encode(b))?;
                m.end()
            }
            Value::List(l) => {
                let mut seq = s.serialize_seq(Some(l.len()))?;
                for v in l {
                    seq.serialize_element(&Bytes64(v))?;
                }
                seq.end()
            }
            Value::Object(kv) => {
                let mut m = s.serialize_map(Some(kv.len()))?;
                for (k, v) in kv {
                    m.serialize_entry(k, &Bytes64(v))?;
                }
                m.end()
            }
            v => v.serialize(s),
        }
    }
}

#[cfg(feature = "json")]
/// Any serialisable value as a [`Value`] (bytes stay bytes).
pub fn to_value(v: &(impl Serialize + ?Sized)) -> std::result::Result<Value, String> {
    v.serialize(value_ser::ValueSerializer).map_err(|e| e.0)
}

#[cfg(feature = "json")]
mod value_ser {
    //! A small serde `Serializer` into [`Value`] (bytes stay bytes), so a
    //! typed state can be written as a project file.
    use super::Value;
    use serde::ser::{self, Serialize};
    use std::fmt;

    #[derive(Debug)]
    pub struct SerError(pub String);
    impl fmt::Display for SerError {
        fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str(&self.0)
        }
    }
    impl std::error::Error for SerError {}
    impl ser::Error for SerError {
        fn custom<T: fmt::Display>(msg: T) -> Self {
            SerError(msg.to_string())
        }
    }

    pub struct ValueSerializer;
    type R = Result<Value, SerError>;

    pub struct Seq(Vec<Value>);
    pub struct Map(Vec<(String, Value)>, Option<String>);

    impl ser::Serializer for ValueSerializer {
        type Ok = Value;
        type Error = SerError;
        type SerializeSeq = Seq;
        type SerializeTuple = Seq;
        type SerializeTupleStruct = Seq;
        type SerializeTupleVariant = Seq;
        type SerializeMap = Map;
        type SerializeStruct = Map;
        type SerializeStructVariant = Map;
        fn serialize_bool(self, v: bool) -> R {
            Ok(Value::Bool(v))
        }
        fn serialize_i8(self, v: i8) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_i16(self, v: i16) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_i32(self, v: i32) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_i64(self, v: i64) -> R {
            Ok(Value::Number(v as f64))
        }
        fn serialize_u8(self, v: u8) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_u16(self, v: u16) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_u32(self, v: u32) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_u64(self, v: u64) -> R {
            Ok(Value::Number(v as f64))
        }
        fn serialize_f32(self, v: f32) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_f64(self, v: f64) -> R {
            Ok(Value::Number(v))
        }
        fn serialize_char(self, v: char) -> R {
            Ok(Value::Text(v.to_string()))
        }
        fn serialize_str(self, v: &str) -> R {
            Ok(Value::Text(v.into()))
        }
        fn serialize_bytes(self, v: &[u8]) -> R {
            Ok(Value::Bytes(v.to_vec()))
        }
        fn serialize_none(self) -> R {
            Ok(Value::Null)
        }
        fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> R {
            v.serialize(self)
        }
        fn serialize_unit(self) -> R {
            Ok(Value::Null)
        }
        fn serialize_unit_struct(self, _: &'static str) -> R {
            Ok(Value::Null)
        }
        fn serialize_unit_variant(self, _: &'static str, _: u32, v: &'static str) -> R {
            Ok(Value::Text(v.into()))
        }
        fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, v: &T) -> R {
            v.serialize(self)
        }
        fn serialize_newtype_variant<T: Serialize + ?Sized>(
            self,
            _: &'static str,
            _: u32,
            variant: &'static str,
            v: &T,
        ) -> R {
            Ok(Value::Object(vec![(variant.into(), v.serialize(self)?)]))
        }
        fn serialize_seq(self, len: Option<usize>) -> Result<Seq, SerError> {
            Ok(Seq(Vec::with_capacity(len.unwrap_or(0).min(4096))))
        }
        fn serialize_tuple(self, len: usize) -> Result<Seq, SerError> {
            self.serialize_seq(Some(len))
        }
        fn serialize_tuple_struct(self, _: &'static str, len: usize) -> Result<Seq, SerError> {
            self.serialize_seq(Some(len))
        }
        fn serialize_tuple_variant(
            self,
            _: &'static str,
            _: u32,
            _: &'static str,
            _: usize,
        ) -> Result<Seq, SerError> {
            Err(SerError("tuple variants are not plain data".into()))
        }
        fn serialize_map(self, _: Option<usize>) -> Result<Map, SerError> {
            Ok(Map(vec![], None))
        }
        fn serialize_struct(self, _: &'static str, _: usize) -> Result<Map, SerError> {
            Ok(Map(vec![], None))
        }
        fn serialize_struct_variant(
            self,
            _: &'static str,
            _: u32,
            _: &'static str,
            _: usize,
        ) -> Result<Map, SerError> {
            Err(SerError("struct variants are not plain data".into()))
        }
    }

    impl ser::SerializeSeq for Seq {
        type Ok = Value;
        type Error = SerError;
        fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SerError> {
            self.0.push(v.serialize(ValueSerializer)?);
            Ok(())
        }
        fn end(self) -> R {
            Ok(Value::List(self.0))
        }
    }
    impl ser::SerializeTuple for Seq {
        type Ok = Value;
        type Error = SerError;
        fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SerError> {
            ser::SerializeSeq::serialize_element(self, v)
        }
        fn end(self) -> R {
            Ok(Value::List(self.0))
        }
    }
    impl ser::SerializeTupleStruct for Seq {
        type Ok = Value;
        type Error = SerError;
        fn serialize_field<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SerError> {
            ser::SerializeSeq::serialize_element(self, v)
        }
        fn end(self) -> R {
            Ok(Value::List(self.0))
        }
    }
    impl ser::SerializeTupleVariant for Seq {
        type Ok = Value;
        type Error = SerError;
        fn serialize_field<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SerError> {
            ser::SerializeSeq::serialize_element(self, v)
        }
        fn end(self) -> R {
            Ok(Value::List(self.0))
        }
    }
    impl ser::SerializeMap for Map {
        type Ok = Value;
        type Error = SerError;
        fn serialize_key<T: Serialize + ?Sized>(&mut self, k: &T) -> Result<(), SerError> {
            match k.serialize(ValueSerializer)? {
                Value::Text(k) => {
                    self.1 = Some(k);
                    Ok(())
                }
                _ => Err(SerError("map keys must be text".into())),
            }
        }
        fn serialize_value<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SerError> {
            let k = self.1.take().unwrap_or_default();
            self.0.push((k, v.serialize(ValueSerializer)?));
            Ok(())
        }
        fn end(self) -> R {
            Ok(Value::Object(self.0))
        }
    }
    impl ser::SerializeStruct for Map {
        type Ok = Value;
        type Error = SerError;
        fn serialize_field<T: Serialize + ?Sized>(
            &mut self,
            k: &'static str,
            v: &T,
        ) -> Result<(), SerError> {
            self.0.push((k.into(), v.serialize(ValueSerializer)?));
            Ok(())
        }
        fn end(self) -> R {
            Ok(Value::Object(self.0))
        }
    }
    impl ser::SerializeStructVariant for Map {
        type Ok = Value;
        type Error = SerError;
        fn serialize_field<T: Serialize + ?Sized>(
            &mut self,
            k: &'static str,
            v: &T,
        ) -> Result<(), SerError> {
            ser::SerializeStruct::serialize_field(self, k, v)
        }
        fn end(self) -> R {
            Ok(Value::Object(self.0))
        }
    }
}

// ------------------------------------------------------------------ inspect --

/// The Inspect tool's state: the image being inspected and its file name.
pub mod inspect_state {
    use super::{first_chars, invalid, js_text, nullish, Value};
    use crate::core::error::Result;
    use serde::Serialize;

    pub const STATE_VERSION: u32 = 1;
    /// File names are kept to this many characters.
    pub const MAX_NAME_CHARS: usize = 200;

    #[derive(Debug, Clone, PartialEq, Serialize)]
    pub struct InspectState {
        pub name: Option<String>,
        #[serde(with = "serde_bytes")]
        pub bytes: Option<Vec<u8>>,
    }

    pub fn check(raw: &Value) -> Result<InspectState> {
        if !raw.is_object_like() {
            return Err(invalid("state", "is not an Inspect document"));
        }
        let name = raw.get("name");
        let name = (!nullish(name)).then(|| first_chars(&js_text(name), MAX_NAME_CHARS));
        let bytes = match raw.get("bytes") {
            None | Some(Value::Null) => None,
            Some(Value::Bytes(b)) => Some(b.clone()),
            Some(_) => return Err(invalid("bytes", "must be the bytes of an image file")),
        };
        Ok(InspectState { name, bytes })
    }
}

#[cfg(test)]
mod tests;
