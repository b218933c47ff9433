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
//!   has the tool's current schema version (`checked: true`; with
//!   `unchecked: true` never: the page converts a state before it asks
//!   `check-state`). A stepped
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
#[cfg(feature = "json")]
use serde::ser::{SerializeMap, SerializeSeq};
#[cfg(feature = "json")]
use serde::Serializer;
use serde::{Deserialize, Serialize};
use std::borrow::Cow;

pub mod json;

use crate::core::value::js_number;
// A project's values (`core::value`, below the tools): the project reader's
// callers outside the crate (the CLI's benches, tests, fuzzers) take them
// from here.
pub use crate::core::value::{base64_encode, Value};

/// `format` of a project file.
pub const PROJECT_FORMAT: &str = "filigree-project";
/// Newest project file format this core reads. Format 2 added
/// `stateVersion`; a format-1 file carries a state of version 1.
pub const PROJECT_VERSION: u32 = 2;

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

/// Checks the states of some tools: `Some` for a tool it knows, `None`
/// for one it leaves to another module (the wasm module of each tool checks
/// only its own tool's states, so it carries no other tool's code;
/// [`check_any`] knows them all).
pub type StateCheck = fn(&str, &Value) -> Option<Result<ToolState>>;

/// Every tool's state check (natively: the CLI, tests, fuzzers).
pub fn check_any(tool_id: &str, state: &Value) -> Option<Result<ToolState>> {
    let checks: [StateCheck; 6] = [
        check_pixel,
        check_fit,
        check_tangle,
        check_micro,
        check_texture,
        check_inspect,
    ];
    checks.iter().find_map(|c| c(tool_id, state))
}

/// Checks no tool's state: an unchecked `open-project`
/// ([`OpenProjectRequest::unchecked`]), and the module that holds no
/// documents (Tangle's PNG export), which leaves them to their tools'.
pub fn check_none(_tool_id: &str, _state: &Value) -> Option<Result<ToolState>> {
    None
}

/// One tool's state check, as a [`StateCheck`].
macro_rules! state_check {
    ($name:ident, $id:literal, $variant:ident, $check:path) => {
        #[doc = concat!("The `", $id, "` tool's state check, as a [`StateCheck`].")]
        pub fn $name(tool_id: &str, state: &Value) -> Option<Result<ToolState>> {
            (tool_id == $id).then(|| $check(state).map(|s| ToolState::$variant(s.into())))
        }
    };
}
state_check!(check_pixel, "pixel", Pixel, crate::pixel::state::check);
state_check!(check_fit, "fit", Fit, crate::pattern::state::check);
state_check!(check_tangle, "tangle", Tangle, crate::tangle::state::check);
state_check!(check_micro, "micro", Micro, crate::micro::state::check);
state_check!(
    check_texture,
    "texture",
    Texture,
    crate::texture::state::check
);
state_check!(check_inspect, "inspect", Inspect, inspect_state::check);

/// Check a state of `tool` whose schema version is `version`.
pub fn check_state(tool_id: &str, version: u64, state: &Value) -> Result<ToolState> {
    check_state_with(tool_id, version, state, check_any)
}

/// [`check_state`] with only the checks of `checks`.
pub fn check_state_with(
    tool_id: &str,
    version: u64,
    state: &Value,
    checks: StateCheck,
) -> Result<ToolState> {
    let t = tool(tool_id).ok_or_else(|| {
        Error::input(format!(
            "Filigree has no tool '{tool_id}' (it has {})",
            TOOLS.iter().map(|t| t.id).collect::<Vec<_>>().join(", ")
        ))
        .at("tool")
    })?;
    check_version(t, version)?;
    checks(t.id, state).unwrap_or_else(|| {
        Err(Error::input(format!(
            "this part of Filigree does not check {} documents (they are checked by the {} tool's module)",
            t.title, t.id
        ))
        .at("tool"))
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
    /// Leave the state unchecked (`checked: false`) whatever its version:
    /// the page converts it first (Pixel's images into PNG, the only format
    /// its module reads), then asks `check-state`, as for any document
    /// from outside.
    pub unchecked: bool,
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
pub fn run_check_state(req: &CheckStateRequest, checks: StateCheck) -> Result<ToolState> {
    check_state_with(&req.tool, req.version, &req.state, checks)
}

/// `open-project`: parse, check the envelope, decode, check the state, to
/// the end (the stepped [`OpenProjectJob`] run in one go).
pub fn open_project(text: &str) -> Result<OpenedProject> {
    crate::core::job::run_quietly(OpenProjectJob::new(Cow::Borrowed(text)))
}

/// `open-project` as the worker runs it: the text read in slices of
/// [`READ_FUEL`] ([`json::Reader`]), then the envelope and the state
/// checked in one more step.
pub fn start_open_project(req: OpenProjectRequest, checks: StateCheck) -> OpenProjectJob<'static> {
    let checks = if req.unchecked { check_none } else { checks };
    OpenProjectJob::new(Cow::Owned(req.text)).checking(checks)
}

/// Fuel of one reading step of `open-project` (see [`json::Reader::step`]):
/// about 1 MB of text, a few ms (`filigree bench slices --only open-project`).
pub const READ_FUEL: usize = 1 << 20;

/// The stepped `open-project` request.
pub struct OpenProjectJob<'a> {
    text: Cow<'a, str>,
    stage: OpenStage,
    /// The tools whose states it checks; another tool's state comes back
    /// unchecked (`checked: false`), for the page to check in its module.
    checks: StateCheck,
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
            checks: check_any,
        }
    }

    /// Check only the states `checks` knows.
    pub fn checking(mut self, checks: StateCheck) -> Self {
        self.checks = checks;
        self
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
                // A byte order mark (Windows editors write one) is not part of the JSON.
                if let Some(rest) = self.text.strip_prefix('\u{feff}') {
                    self.text = Cow::Owned(rest.to_string());
                }
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
                let out = check_project(&mut doc, self.checks)?;
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
fn check_project(doc: &mut Value, checks: StateCheck) -> Result<OpenedProject> {
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
    let checked = if state_version == t.version {
        checks(t.id, state).transpose()?
    } else {
        None
    };
    let (checked, state) = if let Some(s) = checked {
        (true, ProjectState::Checked(s))
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
    let state = crate::core::value::to_value(state).map_err(Error::input)?;
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
// ------------------------------------------------------------------ inspect --

/// The Inspect tool's state: the image being inspected and its file name.
pub mod inspect_state {
    use crate::core::error::Result;
    use crate::core::value::{first_chars, invalid, js_text, nullish, Value};
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
