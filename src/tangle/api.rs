//! Tangle's request as typed data, shared by `filigree tangle` and the
//! browser worker (`tangle`). Defaults are defined once: the request's
//! `Default`. Errors name the field at fault: `grammar` (a syntax error
//! with line and column), `start`, `edits.N`, `seed`, `max_steps`, ...
//!
//! A request carries the whole document: the grammar, the start, the seed
//! and the user's edits in order (re-expand step N; set step N's
//! parameters). The core replays them, so the page keeps no tangle state of
//! its own and the same request gives the same bytes anywhere.
//!
//! Every answer has an id (`answer`: a hash of the document and its edits,
//! so equal requests give equal ids anywhere). A `keep` request may name
//! the answer the page holds (`base`); an instance that kept the expansion
//! of exactly that answer sends only what changed against it (the answer's
//! `base` is then set): the keys of the base's shapes that are gone, the
//! shapes that are new, and the box around both. Any other instance
//! answers in full (`base: null`). Applied to the base, a delta gives
//! exactly the full answer (`tests/tangle.rs`, `www/tangle/delta.js`).
use super::ast::{CurveDef, Def, DefKind, Grammar, Param, StartShape};
use super::expand::{Ending, Expansion, Progress as Advance, Record, Settings};
use super::{export, grammar, Shape, MAX_START_SIDE};
use crate::core::error::{Error, Result};
use crate::core::job::{Job, Progress, Step};
use crate::core::request_limits as lim;
use crate::tangle::geom::polygon::Polygon;
use glam::DVec2;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, HashMap};
use std::sync::Arc;

/// Start shapes given by the request instead of the grammar's `start`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum StartRequest {
    /// A `width`×`height` rectangle at the origin.
    Rect { width: f64, height: f64 },
    /// A polygon (closed).
    Polygon { points: Vec<[f64; 2]> },
    /// Rings (outer rings and holes, even-odd), e.g. drawn by the user.
    Rings { rings: Vec<Vec<[f64; 2]>> },
    /// Every closed shape of an SVG document (its text).
    Svg { svg: String },
    /// Letter outlines of a word, capitals `height` units tall.
    Text { text: String, height: f64 },
}

/// Flattening tolerance of curves in start shapes, drawing units.
const CURVE_TOLERANCE: f64 = 0.05;

/// Capital height of `start text("...")` letters, drawing units.
pub const LETTER_HEIGHT: f64 = 400.0;

/// A user's edit, replayed in order after the expansion.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct Edit {
    /// Position of the step in the history (0-based) when the edit was made.
    pub step: usize,
    /// Parameters to set on that step's operator (`Op::params` names);
    /// empty: re-expand the step with a new random choice.
    pub params: BTreeMap<String, f64>,
}

/// What to export with the answer.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ExportFormat {
    #[default]
    None,
    Svg,
    Png,
}

/// `tangle` / `filigree tangle`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TangleRequest {
    /// The grammar text.
    pub grammar: String,
    /// Start shapes; `None`: the grammar's `start` lines (or an 800×600
    /// rectangle when it has none). Tagged with the grammar's first start
    /// tag, or the first rule's tag.
    pub start: Option<StartRequest>,
    pub seed: u64,
    /// Step budget.
    pub max_steps: usize,
    /// Shape budget (live shapes).
    pub max_shapes: usize,
    /// Polyline sampling of wobbly curves, drawing units (4: ten points per
    /// wobble wavelength; the paper sampled at 2, which doubles the
    /// vertices and the time for no visible difference at print sizes).
    pub resolution: f64,
    /// Hand-drawn wobble amplitude (0: none) and wavelength.
    pub wobble: f64,
    pub wavelength: f64,
    pub edits: Vec<Edit>,
    /// Export the final tangle as SVG or PNG with the answer.
    pub export: ExportFormat,
    /// Pen width for exports, drawing units.
    pub stroke_width: f64,
    /// PNG width in pixels.
    pub png_width: u32,
    /// Keep this expansion in the instance (the browser's worker) so the
    /// next `keep` request with the same document and more edits only
    /// replays its new edits: editing a step redoes that step's subtree,
    /// not the whole tangle. The answer is the same either way.
    pub keep: bool,
    /// With `keep`: the id (`TangleResponse::answer`) of the answer the
    /// sender holds. An instance that kept that answer's expansion answers
    /// with what changed against it; any other answers in full.
    pub base: Option<String>,
}

impl Default for TangleRequest {
    fn default() -> Self {
        TangleRequest {
            grammar: String::new(),
            start: None,
            seed: 1,
            max_steps: 5_000,
            max_shapes: 50_000,
            resolution: 4.0,
            wobble: 1.0,
            wavelength: 40.0,
            edits: vec![],
            export: ExportFormat::None,
            stroke_width: 1.0,
            png_width: 1600,
            keep: false,
            base: None,
        }
    }
}

/// `tangle-png`: a tangle's final shapes drawn as a PNG, the page's PNG
/// export. The page holds the `tangle` answer and sends its final shapes
/// (`died` −1) in the answer's own layout, so this kind, alone in the small
/// `tangle-png` wasm module, needs no grammar or expansion; natively a
/// `tangle` request with `export: "png"` draws the same
/// [`export::Drawing`], so both give the same bytes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct TanglePngRequest {
    /// x, y of every ring's points, shape after shape (little-endian f32
    /// bytes, as the answer's `points`).
    #[serde(with = "serde_bytes")]
    pub points: Vec<u8>,
    /// Points per ring (little-endian u32 bytes).
    #[serde(with = "serde_bytes")]
    pub rings: Vec<u8>,
    /// Rings per shape (little-endian u32 bytes), the outer ring first.
    #[serde(with = "serde_bytes")]
    pub shapes: Vec<u8>,
    /// Each shape's fill tone (little-endian f32 bytes, as the answer's `fill`).
    #[serde(with = "serde_bytes")]
    pub fill: Vec<u8>,
    /// Each shape's flags (1 white lines, 2 mark, as the answer's `flags`).
    #[serde(with = "serde_bytes")]
    pub flags: Vec<u8>,
    /// Pen width, drawing units, and the PNG's width in pixels: as a
    /// `tangle` request's (same defaults and ranges).
    pub stroke_width: f64,
    pub png_width: u32,
}

impl Default for TanglePngRequest {
    fn default() -> Self {
        let t = TangleRequest::default();
        TanglePngRequest {
            points: vec![],
            rings: vec![],
            shapes: vec![],
            fill: vec![],
            flags: vec![],
            stroke_width: t.stroke_width,
            png_width: t.png_width,
        }
    }
}

/// The answer of `tangle-png`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TanglePngResponse {
    #[serde(with = "serde_bytes")]
    pub png: Vec<u8>,
}

/// A column of little-endian `N`-byte values; an error names `field` when
/// its length is not a multiple of `N`.
fn le_column<T, const N: usize>(
    bytes: &[u8],
    field: &str,
    read: impl Fn([u8; N]) -> T,
) -> Result<Vec<T>> {
    if !bytes.len().is_multiple_of(N) {
        return Err(Error::input(format!(
            "{} bytes is not a whole number of {N}-byte values",
            bytes.len()
        ))
        .at(field));
    }
    Ok(bytes
        .chunks_exact(N)
        .map(|c| read(c.try_into().expect("N bytes")))
        .collect())
}

impl TanglePngRequest {
    /// The drawing it sends, checked ([`export::Drawing::check`]).
    pub fn drawing(&self) -> Result<export::Drawing> {
        if self.points.len() / 8 > export::MAX_DRAWING_POINTS {
            return Err(Error::limit(format!(
                "{} points; a drawing has at most {}",
                self.points.len() / 8,
                export::MAX_DRAWING_POINTS
            ))
            .at("points"));
        }
        let rings = le_column(&self.shapes, "shapes", u32::from_le_bytes)?;
        let fill = le_column(&self.fill, "fill", f32::from_le_bytes)?;
        if fill.len() != rings.len() || self.flags.len() != rings.len() {
            let field = if fill.len() != rings.len() {
                "fill"
            } else {
                "flags"
            };
            return Err(Error::input(format!(
                "{} shapes, {} fills and {} flags: one of each per shape",
                rings.len(),
                fill.len(),
                self.flags.len()
            ))
            .at(field));
        }
        if let Some(i) = self.flags.iter().position(|&f| f > 3) {
            return Err(Error::input(format!(
                "shape {i}'s flags are {} (1 white lines, 2 mark, or both)",
                self.flags[i]
            ))
            .at("flags"));
        }
        let d = export::Drawing {
            points: le_column(&self.points, "points", f32::from_le_bytes)?,
            rings: le_column(&self.rings, "rings", u32::from_le_bytes)?,
            shapes: rings
                .into_iter()
                .zip(fill)
                .zip(&self.flags)
                .map(|((n, fill), &f)| {
                    let ink = super::Ink {
                        fill,
                        white_lines: f & 1 != 0,
                        mark: f & 2 != 0,
                    };
                    (n, ink)
                })
                .collect(),
        };
        d.check()?;
        Ok(d)
    }
}

/// Start a `tangle-png` job: the request checked now, drawn and encoded
/// when it runs.
pub fn start_png(req: TanglePngRequest) -> Result<impl Job<Output = TanglePngResponse>> {
    lim::finite_in("stroke_width", req.stroke_width, STROKE_WIDTH)?;
    lim::int_in("png_width", req.png_width, (1, export::MAX_PNG_SIDE))?;
    let d = req.drawing()?;
    Ok(crate::core::job::OneShot::new(move || {
        Ok(TanglePngResponse {
            png: export::png(&d, req.png_width, req.stroke_width)?,
        })
    }))
}

/// Hard limits on a request's settings.
pub const MAX_STEPS: usize = 100_000;
pub const MAX_SHAPES: usize = 250_000;
pub const MAX_EDITS: usize = 1_000;
pub const MAX_START_POINTS: usize = 200_000;

/// One shape of the answer. Points are in [`TangleResponse::points`]:
/// this shape's rings follow each other from point `first`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ShapeOut {
    /// Its key: the same shape has the same key in every answer of the
    /// same document (its record's index in the expansion); a delta names
    /// the shapes it removes by key, and the shapes are in key order.
    pub key: u32,
    pub tag: u32,
    pub group: u32,
    pub id: u32,
    /// Position of the step that made it (-1: a start shape).
    pub born: i64,
    /// Position of the step that consumed it (-1: in the final tangle).
    pub died: i64,
    pub first: u32,
    /// Points per ring (the first ring is the outer one).
    pub rings: Vec<u32>,
    pub fill: f32,
    pub white_lines: bool,
    pub mark: bool,
}

/// One step of the answer's history.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepOut {
    /// Index of the rule in the grammar and its line.
    pub rule: usize,
    pub line: usize,
    pub operator: &'static str,
    /// The parameters used.
    pub params: Vec<Param>,
    /// The tag and group it expanded.
    pub tag: u32,
    pub group: u32,
    /// Indices into `shapes`. Sent as the little-endian bytes of the
    /// u32s (the browser views them as a `Uint32Array`): a JS array made
    /// number by number cost the worker ~10 ms for the leaf's 8k indices.
    #[serde(serialize_with = "u32_bytes")]
    pub inputs: Vec<u32>,
    #[serde(serialize_with = "u32_bytes")]
    pub outputs: Vec<u32>,
}

/// Figures of the final tangle.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TangleStats {
    pub rules: usize,
    pub steps: usize,
    /// Shapes in the final tangle and their vertices.
    pub shapes: usize,
    pub vertices: usize,
}

/// The answer of `tangle`: every shape ever made (with the steps that made
/// and consumed it, so any step can be shown) and the history; or, when
/// `base` is set, what changed against the answer `base`.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TangleResponse {
    /// This answer's id: a hash of the document and its edits (equal
    /// requests, equal ids, anywhere). A later request names it as `base`.
    pub answer: String,
    /// `None`: a full answer. `Some(id)`: a delta against the answer `id`:
    /// `shapes` and `points` hold only the shapes added (or changed), and
    /// `removed` the keys of the base's shapes that are gone (or changed).
    /// Everything else (tags, steps, bounds, stats, exports) is in full;
    /// the steps' indices are into the full answer's shapes (the base's
    /// kept shapes and the added ones, in key order), and the kept shapes'
    /// `born`/`died` are read from the steps (a step's outputs were born at
    /// it, its inputs died at it).
    pub base: Option<String>,
    /// Keys of the base's shapes that are gone (a delta; empty in full),
    /// sent as the little-endian bytes of the u32s.
    #[serde(serialize_with = "u32_bytes")]
    pub removed: Vec<u32>,
    /// `[x0, y0, x1, y1]` around the removed and added shapes (a delta;
    /// `None` in full, or when nothing changed): where the picture may differ.
    pub dirty: Option<[f64; 4]>,
    pub tags: Vec<String>,
    /// Sent as columns of little-endian bytes (see [`shape_columns`]): a
    /// village's 36k shapes as 36k JS objects cost the browser ~0.5 s.
    #[serde(serialize_with = "shape_columns")]
    pub shapes: Vec<ShapeOut>,
    /// x, y of every shape's rings (a delta: the added ones'), in order. Sent as the bytes of the
    /// f32s, little-endian (the browser gets a `Uint8Array` it views as a
    /// `Float32Array`, transferred, not a 300k-element JS array).
    #[serde(serialize_with = "f32_bytes")]
    pub points: Vec<f32>,
    pub steps: Vec<StepOut>,
    /// `[x0, y0, x1, y1]` of all shapes.
    pub bounds: [f64; 4],
    /// `null` when complete, or why a budget stopped it.
    pub stopped: Option<String>,
    pub stats: TangleStats,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub svg: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none", with = "opt_bytes")]
    pub png: Option<Vec<u8>>,
}

/// The shapes as columns, each the little-endian bytes of one typed
/// array: `count`; `key`, `tag`, `group`, `id`, `first` (u32); `born`, `died`
/// (i32); `fill` (f32); `flags` (u8: 1 white lines, 2 mark);
/// `ring_first` (u32, count + 1 entries: shape i's ring lengths are
/// `rings[ring_first[i]..ring_first[i + 1]]`) and `rings` (u32).
/// `www/tangle/draw.js` (`shapeColumns`) reads them back.
fn shape_columns<S: serde::Serializer>(
    v: &[ShapeOut],
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    use serde::ser::SerializeMap;
    fn col<T, const N: usize>(v: &[ShapeOut], f: impl Fn(&ShapeOut) -> T) -> serde_bytes::ByteBuf
    where
        T: LeBytes<N>,
    {
        let mut out = Vec::with_capacity(N * v.len());
        for x in v {
            out.extend_from_slice(&f(x).le());
        }
        serde_bytes::ByteBuf::from(out)
    }
    let mut ring_first = Vec::with_capacity(4 * (v.len() + 1));
    let mut rings = vec![];
    let mut at = 0u32;
    for x in v {
        ring_first.extend(at.to_le_bytes());
        at += x.rings.len() as u32;
        for r in &x.rings {
            rings.extend_from_slice(&r.to_le_bytes());
        }
    }
    ring_first.extend(at.to_le_bytes());
    let mut m = s.serialize_map(Some(12))?;
    m.serialize_entry("count", &v.len())?;
    m.serialize_entry("key", &col(v, |x| x.key))?;
    m.serialize_entry("tag", &col(v, |x| x.tag))?;
    m.serialize_entry("group", &col(v, |x| x.group))?;
    m.serialize_entry("id", &col(v, |x| x.id))?;
    m.serialize_entry("first", &col(v, |x| x.first))?;
    m.serialize_entry("born", &col(v, |x| x.born as i32))?;
    m.serialize_entry("died", &col(v, |x| x.died as i32))?;
    m.serialize_entry("fill", &col(v, |x| x.fill))?;
    m.serialize_entry(
        "flags",
        &col(v, |x| u8::from(x.white_lines) | (u8::from(x.mark) << 1)),
    )?;
    m.serialize_entry("ring_first", &serde_bytes::ByteBuf::from(ring_first))?;
    m.serialize_entry("rings", &serde_bytes::ByteBuf::from(rings))?;
    m.end()
}

/// Little-endian bytes of a column's element.
trait LeBytes<const N: usize> {
    fn le(self) -> [u8; N];
}
macro_rules! le_bytes {
    ($($t:ty => $n:literal),*) => {$(
        impl LeBytes<$n> for $t {
            fn le(self) -> [u8; $n] {
                self.to_le_bytes()
            }
        }
    )*};
}
le_bytes!(u8 => 1, u32 => 4, i32 => 4, f32 => 4);

/// A slice as the little-endian bytes of its elements.
fn le_bytes<T: LeBytes<N> + Copy, const N: usize, S: serde::Serializer>(
    v: &[T],
    s: S,
) -> std::result::Result<S::Ok, S::Error> {
    let mut bytes = Vec::with_capacity(N * v.len());
    for x in v {
        bytes.extend_from_slice(&x.le());
    }
    serde_bytes::serialize(&bytes, s)
}

fn f32_bytes<S: serde::Serializer>(v: &[f32], s: S) -> std::result::Result<S::Ok, S::Error> {
    le_bytes(v, s)
}

fn u32_bytes<S: serde::Serializer>(v: &[u32], s: S) -> std::result::Result<S::Ok, S::Error> {
    le_bytes(v, s)
}

mod opt_bytes {
    pub fn serialize<S: serde::Serializer>(v: &Option<Vec<u8>>, s: S) -> Result<S::Ok, S::Error> {
        match v {
            Some(b) => serde_bytes::serialize(b, s),
            None => s.serialize_none(),
        }
    }
}

/// Ranges of the request's settings, checked here and in a document (`state.rs`).
pub const WOBBLE: (f64, f64) = (0.0, 50.0);
pub const STROKE_WIDTH: (f64, f64) = (0.0, 100.0);

/// Check the request's settings.
fn check(req: &TangleRequest) -> Result<Settings> {
    lim::int_in("max_steps", req.max_steps, (1, MAX_STEPS))?;
    lim::int_in("max_shapes", req.max_shapes, (1, MAX_SHAPES))?;
    lim::finite_in("resolution", req.resolution, (0.25, 100.0))?;
    lim::finite_in("wobble", req.wobble, WOBBLE)?;
    lim::finite_in("wavelength", req.wavelength, (1.0, 10_000.0))?;
    lim::finite_in("stroke_width", req.stroke_width, STROKE_WIDTH)?;
    lim::int_in("png_width", req.png_width, (1, export::MAX_PNG_SIDE))?;
    if req.edits.len() > MAX_EDITS {
        return Err(Error::limit(format!(
            "{} edits; a tangle keeps at most {MAX_EDITS} (the edit limit)",
            req.edits.len()
        ))
        .at("edits"));
    }
    Ok(Settings {
        seed: req.seed,
        max_steps: req.max_steps,
        max_shapes: req.max_shapes,
        resolution: req.resolution,
        wobble: req.wobble,
        wavelength: req.wavelength,
    })
}

thread_local! {
    /// The grammar text of the last `keep` request and its parse (SVG
    /// curves flattened): a new seed or wobble of the same grammar does
    /// not parse it again.
    static PARSED: std::cell::RefCell<Option<(String, Grammar)>> = const { std::cell::RefCell::new(None) };
    /// Grammars parsed by this instance (tests).
    static PARSES: std::cell::Cell<u64> = const { std::cell::Cell::new(0) };
}

/// The request's grammar, parsed and its SVG curves flattened; with
/// `cache` (a `keep` request), the last one is reused when the text is
/// the same and kept for the next one.
fn parse_grammar(text: &str, cache: bool) -> Result<Grammar> {
    if cache {
        let hit = PARSED.with_borrow(|p| {
            p.as_ref()
                .filter(|(t, _)| t == text)
                .map(|(_, g)| g.clone())
        });
        if let Some(g) = hit {
            return Ok(g);
        }
    }
    PARSES.set(PARSES.get() + 1);
    let mut g = grammar::parse(text).map_err(|e| e.at("grammar"))?;
    flatten_svg_defs(&mut g)?;
    if cache {
        PARSED.with_borrow_mut(|p| *p = Some((text.to_string(), g.clone())));
    }
    Ok(g)
}

/// How many grammar texts this instance (thread) has parsed (tests: an
/// edit, or a new seed of the same grammar, parses none).
pub fn grammar_parses() -> u64 {
    PARSES.get()
}

/// Refuses start shapes of more than [`MAX_START_POINTS`] points.
fn start_point_limit(n: usize, field: &str) -> Result<()> {
    if n > MAX_START_POINTS {
        return Err(Error::limit(format!(
            "the start shapes have {n} points; at most {MAX_START_POINTS} (the start point limit)"
        ))
        .at(field.to_string()));
    }
    Ok(())
}

/// Polygons of start rings, within the start point limit and with area.
fn start_polys(rings: Vec<Vec<DVec2>>, field: &str) -> Result<Vec<Polygon>> {
    start_point_limit(rings.iter().map(Vec::len).sum(), field)?;
    let v = Polygon::new(rings).ok_or_else(|| {
        Error::input(format!(
            "start shape points must be finite numbers within ±{}",
            crate::tangle::geom::polygon::MAX_COORD
        ))
        .at(field.to_string())
    })?;
    if v.is_empty() {
        return Err(Error::input("the start shape has no area").at(field.to_string()));
    }
    let (lo, hi) = Polygon::bbox_all(&v);
    let side = (hi - lo).max_element();
    if side > MAX_START_SIDE {
        return Err(Error::input(format!(
            "the start shape is {} units across; start shapes are at most {MAX_START_SIDE} \
             units across (scale it down: operators work at the page's scale)",
            lim::short_number(side)
        ))
        .at(field.to_string()));
    }
    Ok(v)
}

/// A start rectangle at the origin, of a drawable size.
fn start_rect(w: f64, h: f64, field: &str) -> Result<Polygon> {
    if !(w.is_finite() && h.is_finite() && w > 0.0 && h > 0.0 && w.max(h) <= MAX_START_SIDE) {
        return Err(Error::input(format!(
            "a start rectangle is between 0 and {MAX_START_SIDE} units a side (got {}×{})",
            lim::short_number(w),
            lim::short_number(h)
        ))
        .at(field.to_string()));
    }
    Ok(Polygon::rect(DVec2::ZERO, DVec2::new(w, h)))
}

/// The start shapes (polygon, tag).
fn start_shapes(req: &TangleRequest, g: &Grammar) -> Result<Vec<(Polygon, String)>> {
    let tag = g
        .start
        .first()
        .map(|s| s.tag.clone())
        .or_else(|| g.rules.first().map(|r| r.tag.clone()))
        .unwrap_or_default();
    let pt = |p: &[f64; 2]| DVec2::new(p[0], p[1]);
    let one = |p: Vec<Polygon>| p.into_iter().map(|q| (q, tag.clone())).collect::<Vec<_>>();
    match &req.start {
        Some(StartRequest::Rect { width, height }) => {
            Ok(vec![(start_rect(*width, *height, "start")?, tag.clone())])
        }
        Some(StartRequest::Polygon { points }) => Ok(one(start_polys(
            vec![points.iter().map(pt).collect()],
            "start.points",
        )?)),
        Some(StartRequest::Rings { rings }) => Ok(one(start_polys(
            rings.iter().map(|r| r.iter().map(pt).collect()).collect(),
            "start.rings",
        )?)),
        Some(StartRequest::Svg { svg }) => {
            // Fitted into the frame the grammar was written for: its own
            // start shapes' box (an 800×600 rectangle when it has none), so
            // its distances mean the same on any file's units.
            let frame = match g.start.is_empty() {
                true => (DVec2::ZERO, DVec2::new(800.0, 600.0)),
                false => {
                    let starts = grammar_starts(g)?;
                    Polygon::bbox_all(starts.iter().map(|(p, _)| p))
                }
            };
            let n = crate::tangle::geom::svg::document_polygons(svg, CURVE_TOLERANCE, Some(frame))
                .map_err(|e| e.at("start.svg"))?;
            start_point_limit(n.iter().map(Polygon::vertices).sum(), "start.svg")?;
            Ok(one(n))
        }
        Some(StartRequest::Text { text, height }) => Ok(one(start_polys(
            super::letters::text_rings(text, *height).map_err(|e| e.at("start.text"))?,
            "start.text",
        )?)),
        None if g.start.is_empty() => Ok(vec![(start_rect(800.0, 600.0, "start")?, tag.clone())]),
        None => grammar_starts(g),
    }
}

/// The grammar's `start` lines' shapes (polygon, tag), built with the
/// checks of [`start_shapes`].
fn grammar_starts(g: &Grammar) -> Result<Vec<(Polygon, String)>> {
    let mut out = vec![];
    for s in &g.start {
        let field = "grammar";
        let made = match &s.shape {
            StartShape::Rect { width, height } => vec![start_rect(*width, *height, field)?],
            StartShape::Circle { radius } => {
                if !(*radius > 0.0 && 2.0 * radius <= MAX_START_SIDE) {
                    return Err(Error::input(format!(
                        "a start circle's diameter is at most {MAX_START_SIDE} units (got radius {})",
                        lim::short_number(*radius)
                    ))
                    .at(field.to_string()));
                }
                let n = (std::f64::consts::TAU * radius / 2.0).clamp(16.0, 4096.0);
                vec![Polygon::circle(DVec2::splat(*radius), *radius, n as usize)]
            }
            StartShape::Polygon(pts) => start_polys(vec![pts.clone()], field)?,
            StartShape::Svg(d) => start_polys(
                crate::tangle::geom::svg::path_rings(d, CURVE_TOLERANCE)
                    .map_err(|e| at_line(e, s.line))?,
                field,
            )?,
            StartShape::Text(t) => start_polys(
                super::letters::text_rings(t, LETTER_HEIGHT).map_err(|e| at_line(e, s.line))?,
                field,
            )?,
        };
        out.extend(made.into_iter().map(|p| (p, s.tag.clone())));
    }
    Ok(out)
}

/// `curve c = svg("...")` and `shape s = svg("...")` as polylines.
fn flatten_svg_defs(g: &mut Grammar) -> Result<()> {
    for d in &mut g.defs {
        if let CurveDef::Svg(path) = &d.curve {
            let rings = crate::tangle::geom::svg::path_rings(path, CURVE_TOLERANCE)
                .map_err(|e| at_line(e, d.line))?;
            let Some(first) = rings.into_iter().next() else {
                return Err(at_line(Error::input("the SVG path has no points"), d.line));
            };
            d.curve = CurveDef::Polyline(first);
        }
    }
    Ok(())
}

/// An error about a grammar line, as a syntax error there.
fn at_line(e: Error, line: usize) -> Error {
    Error::Syntax {
        line,
        column: 1,
        message: e.to_string(),
    }
    .at("grammar")
}

/// The motifs `place` can use: `circle` and the grammar's shapes, each
/// normalised to the unit disc.
fn motifs(g: &Grammar) -> HashMap<String, Polygon> {
    let mut m = HashMap::new();
    m.insert("circle".to_string(), Polygon::circle(DVec2::ZERO, 1.0, 32));
    for Def {
        name, kind, curve, ..
    } in &g.defs
    {
        if *kind != DefKind::Shape {
            continue;
        }
        let poly = match curve {
            CurveDef::Circle => Some(Polygon::circle(DVec2::ZERO, 1.0, 32)),
            CurveDef::Ngon(n) => Some(Polygon::circle(
                DVec2::ZERO,
                1.0,
                (*n as usize).clamp(3, 64),
            )),
            CurveDef::Polyline(pts) => Polygon::new(vec![pts.clone()])
                .and_then(|v| v.into_iter().next())
                .and_then(|p| super::place::normalise_motif(&p)),
            _ => None,
        };
        if let Some(p) = poly {
            m.insert(name.clone(), p);
        }
    }
    m
}

/// The expansions a `keep` request left in this instance (one per wasm
/// worker; natively, per thread), for one document: snapshots after some
/// of its edits (the first with none). A request for the same document
/// continues from the snapshot with the longest run of its leading edits:
/// more edits replay only the new ones, a slider drag (the last edit
/// replaced) and an undo (the last edit dropped) start from the snapshot
/// before that edit. Either way the same operations run on the same state
/// as a replay from scratch, so the answer's bytes are the same.
struct Kept {
    /// The request, with what does not change the expansion cleared.
    document: TangleRequest,
    /// Least recently used first; the one without edits is never dropped.
    snapshots: Vec<Snapshot>,
}

/// An expansion after some of a document's edits.
struct Snapshot {
    edits: Vec<Edit>,
    x: Expansion,
    /// The id of its answer ([`answer_id`]).
    id: String,
}

impl Snapshot {
    fn new(document: &TangleRequest, edits: Vec<Edit>, x: Expansion) -> Snapshot {
        let id = id_of(document, &edits);
        Snapshot { edits, x, id }
    }
}

/// Snapshots kept besides the unedited expansion.
const EDITED_SNAPSHOTS: usize = 4;

thread_local! {
    static KEPT: std::cell::RefCell<Option<Kept>> = const { std::cell::RefCell::new(None) };
}

/// `req` without its edits and the fields that only shape the answer.
fn document_of(req: &TangleRequest) -> TangleRequest {
    TangleRequest {
        edits: vec![],
        export: ExportFormat::None,
        stroke_width: 0.0,
        png_width: 1,
        keep: false,
        base: None,
        ..req.clone()
    }
}

/// The id of the answer of `document` (from [`document_of`]) after
/// `edits`: FNV-1a (128 bits) of their `Debug` text, which is the same on
/// every platform.
fn id_of(document: &TangleRequest, edits: &[Edit]) -> String {
    let text = format!("{:?}", (document, edits));
    let mut h: u128 = 0x6c62_272e_07bb_0142_62b8_2175_6295_c58d;
    for b in text.bytes() {
        h ^= u128::from(b);
        h = h.wrapping_mul(0x0000_0000_0100_0000_0000_0000_0000_013b);
    }
    format!("{h:032x}")
}

/// The id of `req`'s answer (`TangleResponse::answer`): equal for requests
/// that grow the same tangle, whatever they export.
pub fn answer_id(req: &TangleRequest) -> String {
    id_of(&document_of(req), &req.edits)
}

/// A kept expansion for `req` and how many of its edits it has done, if
/// this instance has one for its document. A snapshot with all of the
/// request's edits is handed over (the job keeps it again); one with fewer
/// is copied, so it stays for the next drag or undo.
fn take_kept(req: &TangleRequest) -> Option<(Expansion, usize)> {
    KEPT.with_borrow_mut(|kept| {
        let k = kept.as_mut().filter(|k| k.document == document_of(req))?;
        let best = (0..k.snapshots.len())
            .filter(|&i| req.edits.starts_with(&k.snapshots[i].edits))
            .max_by_key(|&i| k.snapshots[i].edits.len())?;
        let done = k.snapshots[best].edits.len();
        if done == req.edits.len() {
            return Some((k.snapshots.remove(best).x, done));
        }
        Some((k.snapshots[best].x.clone(), done))
    })
}

/// Forget any kept expansion (tests; a worker never needs to).
pub fn forget_kept() {
    KEPT.with_borrow_mut(|k| *k = None);
}

/// Forget the kept snapshots after edits, keeping the unedited expansion:
/// the next drag or undo replays all its edits, as before snapshots were
/// kept (`bench tangle` measures both in one run).
pub fn forget_kept_edits() {
    KEPT.with_borrow_mut(|k| {
        if let Some(k) = k.as_mut() {
            k.snapshots.retain(|s| s.edits.is_empty());
        }
    });
}

/// A `tangle` request as a job: the expansion a bounded part a step, then
/// each edit, then the answer.
pub struct TangleJob {
    /// `None` once answered (a `keep` job hands it to the instance).
    x: Option<Expansion>,
    edits: std::vec::IntoIter<Edit>,
    edit_no: usize,
    /// Edits the starting expansion had done already (a kept snapshot).
    done: usize,
    /// With `keep`: snapshots to keep besides the final expansion (the
    /// unedited one when it was grown here, the one before the last edit).
    saved: Vec<(Vec<Edit>, Expansion)>,
    reused: bool,
    req: TangleRequest,
}

/// Check a `tangle` request and set its expansion up.
pub fn start_tangle(req: TangleRequest) -> Result<TangleJob> {
    let settings = check(&req)?;
    let kept = if req.keep { take_kept(&req) } else { None };
    let (x, done, reused) = match kept {
        // The kept expansion holds its grammar: nothing is parsed.
        Some((x, done)) => (x, done, true),
        None => {
            let g = parse_grammar(&req.grammar, req.keep)?;
            let start = start_shapes(&req, &g)?;
            let m = motifs(&g);
            (Expansion::new(g, start, m, settings)?, 0, false)
        }
    };
    Ok(TangleJob {
        x: Some(x),
        edits: req.edits.clone().split_off(done).into_iter(),
        edit_no: done,
        done,
        saved: vec![],
        reused,
        req,
    })
}

impl TangleJob {
    /// Whether a `keep` request continues from the expansion this
    /// instance kept (tests and benchmarks; the answer is the same).
    pub fn reused(&self) -> bool {
        self.reused
    }

    /// How many of the request's edits the kept expansion it continues
    /// from had done (0 without one): the rest are replayed.
    pub fn reused_edits(&self) -> usize {
        self.done
    }

    /// Apply the next edit to `x`; `false` when none is left.
    fn next_edit(&mut self, x: &mut Expansion) -> Result<bool> {
        let Some(e) = self.edits.next() else {
            return Ok(false);
        };
        // Before the first edit of a tangle grown here and before the last
        // edit: the states a later request most likely starts from.
        let n = self.req.edits.len();
        if self.req.keep
            && ((self.edit_no == 0 && !self.reused)
                || (self.edit_no + 1 == n && self.edit_no > self.done))
        {
            self.saved
                .push((self.req.edits[..self.edit_no].to_vec(), x.clone()));
        }
        let field = format!("edits.{}", self.edit_no);
        self.edit_no += 1;
        let Some(step) = x.steps.get(e.step) else {
            return Err(Error::input(format!(
                "edit {} is for step {}, but the tangle has {} steps",
                self.edit_no,
                e.step + 1,
                x.steps.len()
            ))
            .at(field));
        };
        let op = if e.params.is_empty() {
            None
        } else {
            let mut op = step.op.clone();
            for (name, v) in &e.params {
                if !v.is_finite() {
                    // NaN said "outline has no parameter 'distance' (it has: distance)".
                    return Err(Error::input(format!(
                        "edit {}: {name} must be a finite number (got {v})",
                        self.edit_no
                    ))
                    .at(format!("{field}.params.{name}")));
                }
                op = op.with_param(name, *v).ok_or_else(|| {
                    Error::input(format!(
                        "{} has no parameter '{name}' (it has: {})",
                        op.name(),
                        op.params()
                            .iter()
                            .map(|p| p.name)
                            .collect::<Vec<_>>()
                            .join(", ")
                    ))
                    .at(format!("{field}.params"))
                })?;
            }
            Some(op)
        };
        x.reexpand(e.step, op).map_err(|e| e.at(field))?;
        Ok(true)
    }

    /// The answer for the grown expansion `x`: a delta against the
    /// request's `base` when this instance holds that answer's expansion
    /// (or `x` is it), else in full.
    fn answer(&self, x: &Expansion) -> Result<TangleResponse> {
        let id = answer_id(&self.req);
        let Some(base) = self.req.base.as_deref().filter(|_| self.req.keep) else {
            return answer(x, &self.req, id, None);
        };
        if base == id {
            return answer(x, &self.req, id, Some((x, base)));
        }
        KEPT.with_borrow(|kept| {
            let held = kept
                .as_ref()
                .filter(|k| k.document == document_of(&self.req))
                .and_then(|k| k.snapshots.iter().find(|s| s.id == base));
            answer(x, &self.req, id, held.map(|s| (&s.x, base)))
        })
    }

    /// Leave the expansion `x` (and the snapshots saved on the way) in the
    /// instance for the next `keep` request.
    fn keep(&mut self, x: Expansion) {
        let document = document_of(&self.req);
        let mut add = std::mem::take(&mut self.saved);
        add.push((std::mem::take(&mut self.req.edits), x));
        let reused = self.reused;
        KEPT.with_borrow_mut(|kept| {
            if !kept.as_ref().is_some_and(|k| k.document == document) {
                // Another document's: replaced by this one, when it was
                // grown here (so its unedited expansion is among `add`).
                if reused {
                    return;
                }
                *kept = Some(Kept {
                    document,
                    snapshots: vec![],
                });
            }
            let Some(k) = kept.as_mut() else { return };
            for (edits, x) in add {
                k.snapshots.retain(|s| s.edits != edits);
                k.snapshots.push(Snapshot::new(&k.document, edits, x));
            }
            while k.snapshots.len() > EDITED_SNAPSHOTS + 1 {
                let Some(i) = k.snapshots.iter().position(|s| !s.edits.is_empty()) else {
                    break;
                };
                k.snapshots.remove(i);
            }
        });
    }
}

impl Job for TangleJob {
    type Output = TangleResponse;
    fn step(&mut self) -> Result<Step<TangleResponse>> {
        let Some(mut x) = self.x.take() else {
            return Err(Error::input("this tangle job has already answered"));
        };
        // A slice: expansion work until ~a few ms of shapes are done.
        for _ in 0..4 {
            match x.work()? {
                Advance::Working | Advance::Stepped(_) => {}
                Advance::Ended => {
                    if self.next_edit(&mut x)? {
                        continue;
                    }
                    let r = self.answer(&x)?;
                    if self.req.keep {
                        self.keep(x);
                    }
                    return Ok(Step::Done(r));
                }
            }
        }
        let f = (x.steps.len() as f64 / self.req.max_steps as f64).min(0.99);
        let live = x.live();
        self.x = Some(x);
        Ok(Step::Running(
            Progress::new(f, "expanding").with_figure(live as f64),
        ))
    }
}

/// The full answer for an expansion grown for `req`.
pub fn respond(x: &Expansion, req: &TangleRequest) -> Result<TangleResponse> {
    answer(x, req, answer_id(req), None)
}

/// Whether record `r` of `x` is shown exactly as record `b` of `xb`: the
/// same polygon (shared, not equal: records after the expansions parted
/// never share one), tag, group, id and ink, and both consumed or neither
/// (so the final picture differs only where a delta says).
fn same_shape(xb: &Expansion, b: &Record, x: &Expansion, r: &Record) -> bool {
    let (p, q) = (&b.shape, &r.shape);
    Arc::ptr_eq(&p.poly, &q.poly)
        && p.tag == q.tag
        && xb.tags.get(p.tag as usize) == x.tags.get(q.tag as usize)
        && p.group == q.group
        && p.id == q.id
        && p.ink == q.ink
        && b.died.is_some() == r.died.is_some()
}

/// The answer `id` for an expansion: in full, or with `base` (the base
/// answer's expansion and id) what changed against it.
fn answer(
    x: &Expansion,
    req: &TangleRequest,
    id: String,
    base: Option<(&Expansion, &str)>,
) -> Result<TangleResponse> {
    let pos: HashMap<u32, usize> = x.steps.iter().enumerate().map(|(k, s)| (s.id, k)).collect();
    let step_pos = |id: Option<u32>| id.and_then(|i| pos.get(&i)).map_or(-1, |&k| k as i64);
    let mut index = vec![u32::MAX; x.records.len()];
    let mut shapes = Vec::with_capacity(if base.is_some() { 64 } else { x.records.len() });
    let mut points = vec![];
    if base.is_none() {
        let total: usize = x.records.iter().map(|r| r.shape.poly.vertices()).sum();
        points.reserve(2 * total);
    }
    let (mut lo, mut hi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let mut removed = vec![];
    let (mut dlo, mut dhi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    let mut dirty = |p: &Polygon| {
        let (a, b) = p.bbox();
        dlo = dlo.min(a);
        dhi = dhi.max(b);
    };
    let base_len = base.map_or(0, |(b, _)| b.records.len());
    let mut shown = 0u32;
    // `i` reads the records of both expansions, which may differ in length.
    #[allow(clippy::needless_range_loop)]
    for i in 0..x.records.len().max(base_len) {
        let here = (i < x.records.len() && !x.is_removed(i)).then(|| &x.records[i]);
        let before = base
            .filter(|(b, _)| i < b.records.len() && !b.is_removed(i))
            .map(|(b, _)| (b, &b.records[i]));
        let kept = match (here, before) {
            (Some(r), Some((xb, b))) => same_shape(xb, b, x, r),
            _ => false,
        };
        if let (Some((_, b)), false) = (before, kept) {
            removed.push(i as u32);
            dirty(&b.shape.poly);
        }
        let Some(r) = here else { continue };
        index[i] = shown;
        shown += 1;
        let s = &r.shape;
        if kept {
            let (a, b) = s.poly.bbox();
            lo = lo.min(a);
            hi = hi.max(b);
            continue;
        }
        if base.is_some() {
            dirty(&s.poly);
        }
        let first = (points.len() / 2) as u32;
        for ring in &s.poly.rings {
            let at = points.len();
            points.resize(at + 2 * ring.len(), 0.0);
            for (o, p) in points[at..].chunks_exact_mut(2).zip(ring) {
                o[0] = p.x as f32;
                o[1] = p.y as f32;
            }
            for p in ring {
                lo = lo.min(*p);
                hi = hi.max(*p);
            }
        }
        shapes.push(ShapeOut {
            key: i as u32,
            tag: s.tag,
            group: s.group,
            id: s.id,
            born: step_pos(r.born),
            died: step_pos(r.died),
            first,
            rings: s.poly.rings.iter().map(|r| r.len() as u32).collect(),
            fill: s.ink.fill,
            white_lines: s.ink.white_lines,
            mark: s.ink.mark,
        });
    }
    let steps = x
        .steps
        .iter()
        .map(|s| {
            let rule = &x.grammar().rules[s.rule];
            StepOut {
                rule: s.rule,
                line: rule.line,
                operator: s.op.name(),
                params: s.op.params(),
                tag: x.records[s.inputs[0] as usize].shape.tag,
                group: s.group,
                inputs: s.inputs.iter().map(|&i| index[i as usize]).collect(),
                outputs: s.outputs.iter().map(|&i| index[i as usize]).collect(),
            }
        })
        .collect();
    let finals: Vec<&Shape> = final_shapes(x);
    let stats = TangleStats {
        rules: x.grammar().rules.len(),
        steps: x.steps.len(),
        shapes: finals.len(),
        vertices: finals.iter().map(|s| s.poly.vertices()).sum(),
    };
    let (svg, png) = match req.export {
        ExportFormat::None => (None, None),
        ExportFormat::Svg => (Some(export::svg(&finals, req.stroke_width)), None),
        ExportFormat::Png => (None, Some(png_export(&finals, req)?)),
    };
    if !lo.is_finite() {
        (lo, hi) = (DVec2::ZERO, DVec2::ZERO);
    }
    Ok(TangleResponse {
        answer: id,
        base: base.map(|(_, b)| b.to_string()),
        removed,
        dirty: (base.is_some() && dlo.is_finite()).then_some([dlo.x, dlo.y, dhi.x, dhi.y]),
        tags: x.tags.clone(),
        shapes,
        points,
        steps,
        bounds: [lo.x, lo.y, hi.x, hi.y],
        stopped: match &x.ending {
            Some(Ending::Stopped(m)) => Some(m.clone()),
            _ => None,
        },
        stats,
        svg,
        png,
    })
}

/// A `tangle` request's PNG export: natively the drawing of its final
/// shapes ([`export::png`]); in the browser the page sends that drawing to
/// the `tangle-png` module instead ([`TanglePngRequest`]), so the Tangle
/// module links no rasteriser and refuses it.
fn png_export(finals: &[&Shape], req: &TangleRequest) -> Result<Vec<u8>> {
    #[cfg(target_arch = "wasm32")]
    {
        let _ = (finals, req);
        Err(Error::Unsupported(
            "in the browser a tangle's PNG is drawn by the tangle-png module: send its final \
             shapes as a tangle-png request"
                .into(),
        )
        .at("export"))
    }
    #[cfg(not(target_arch = "wasm32"))]
    export::png(
        &export::Drawing::of(finals),
        req.png_width,
        req.stroke_width,
    )
}

/// The shapes of the final tangle, in the order they were made.
pub fn final_shapes(x: &Expansion) -> Vec<&Shape> {
    x.records
        .iter()
        .enumerate()
        .filter(|(i, r)| r.died.is_none() && !x.is_removed(*i))
        .map(|(_, r)| &r.shape)
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tangle::ast::Op;

    /// The leaf example at seed 1, as the Tangle panel first shows it: one
    /// square's 5-unit inset came back from the offset engine as two pieces
    /// sharing its diagonal (a pentagon and a triangle), drawn with a line
    /// across the square. Every outline step's inner pieces of one shape
    /// must be apart: the union of any two of them is still two pieces.
    #[test]
    fn each_outline_gives_an_inset_whose_pieces_do_not_touch() {
        let req = TangleRequest {
            grammar: crate::tangle::examples::EXAMPLES[0].grammar.into(),
            seed: 1,
            ..Default::default()
        };
        assert_eq!(crate::tangle::examples::EXAMPLES[0].name, "leaf");
        let mut x = start_tangle(req).unwrap().x.take().unwrap();
        x.run().unwrap();
        let outlines: Vec<_> = x
            .steps
            .iter()
            .filter(|s| matches!(s.op, Op::Outline { .. }))
            .collect();
        assert!(outlines.len() >= 4, "the leaf has outline steps");
        for s in outlines {
            let inner_tag = &x.grammar().rules[s.rule].outputs[0];
            for &input in &s.inputs {
                // The inner pieces this input gave: the step's outputs with the
                // inner tag whose box lies inside the input's.
                let (lo, hi) = x.records[input as usize].shape.poly.bbox();
                let pieces: Vec<&Polygon> = s
                    .outputs
                    .iter()
                    .map(|&o| &x.records[o as usize].shape)
                    .filter(|sh| &x.tags[sh.tag as usize] == inner_tag)
                    .map(|sh| &*sh.poly)
                    .filter(|p| {
                        let (a, b) = p.bbox();
                        a.x >= lo.x && a.y >= lo.y && b.x <= hi.x && b.y <= hi.y
                    })
                    .collect();
                for (i, a) in pieces.iter().enumerate() {
                    for b in &pieces[..i] {
                        let u = Polygon::union_all(&[(*a).clone(), (*b).clone()]);
                        assert_eq!(u.len(), 2, "two inset pieces of shape {input} touch");
                    }
                }
            }
        }
    }
}

#[cfg(test)]
mod png_tests {
    use super::*;
    use crate::core::job::run_quietly;

    /// The little-endian bytes of `v`'s values.
    fn le<T: Copy, const N: usize>(v: impl IntoIterator<Item = T>, f: fn(T) -> [u8; N]) -> Vec<u8> {
        v.into_iter().flat_map(f).collect()
    }

    /// What the page sends (`www/tangle/export.js` `drawingOf`): the final
    /// shapes (`died` −1) of a full answer, in the answer's own layout.
    fn drawing_of(r: &TangleResponse) -> TanglePngRequest {
        let finals: Vec<&ShapeOut> = r.shapes.iter().filter(|s| s.died == -1).collect();
        let mut points = vec![];
        for s in &finals {
            let n: u32 = s.rings.iter().sum();
            let at = 2 * s.first as usize;
            points.extend_from_slice(&r.points[at..at + 2 * n as usize]);
        }
        TanglePngRequest {
            points: le(points, f32::to_le_bytes),
            rings: le(
                finals.iter().flat_map(|s| s.rings.clone()),
                u32::to_le_bytes,
            ),
            shapes: le(
                finals.iter().map(|s| s.rings.len() as u32),
                u32::to_le_bytes,
            ),
            fill: le(finals.iter().map(|s| s.fill), f32::to_le_bytes),
            flags: finals
                .iter()
                .map(|s| s.white_lines as u8 | (s.mark as u8) << 1)
                .collect(),
            ..Default::default()
        }
    }

    fn tangle(req: TangleRequest) -> TangleResponse {
        run_quietly(start_tangle(req).unwrap()).unwrap()
    }

    fn png(req: TanglePngRequest) -> Result<Vec<u8>> {
        Ok(run_quietly(start_png(req)?)?.png)
    }

    /// The browser's PNG export (the page's drawing of the answer, drawn by
    /// the `tangle-png` module) is the CLI's (`tangle` with `export: png`),
    /// byte for byte, for every shipped example: between them they have
    /// fills, marks, white lines and holes.
    #[test]
    fn the_png_of_the_answers_final_shapes_is_the_tangle_export() {
        let (mut marks, mut fills, mut white, mut holes) = (0, 0, 0, 0);
        for ex in crate::tangle::examples::EXAMPLES {
            let req = TangleRequest {
                grammar: ex.grammar.into(),
                seed: 3,
                stroke_width: 1.5,
                png_width: 300,
                ..Default::default()
            };
            let cli = tangle(TangleRequest {
                export: ExportFormat::Png,
                ..req.clone()
            })
            .png
            .unwrap();
            let answer = tangle(req);
            let sent = drawing_of(&answer);
            marks += sent.flags.iter().filter(|&&f| f & 2 != 0).count();
            white += sent.flags.iter().filter(|&&f| f & 1 != 0).count();
            fills += sent.fill.chunks_exact(4).filter(|f| f != &[0; 4]).count();
            holes += sent.shapes.chunks_exact(4).filter(|n| n[0] > 1).count();
            let page = png(TanglePngRequest {
                stroke_width: 1.5,
                png_width: 300,
                ..sent
            })
            .unwrap();
            assert!(cli == page, "{}: the two PNGs differ", ex.name);
            let img = crate::raster::decode(&page, crate::raster::Limits::default()).unwrap();
            assert_eq!(img.width, 300, "{}", ex.name);
            assert!(
                img.data.chunks_exact(4).any(|p| p[0] < 64),
                "{}: ink on the paper",
                ex.name
            );
        }
        assert!(
            marks > 0 && fills > 0 && white > 0 && holes > 0,
            "marks {marks}, fills {fills}, white lines {white}, holes {holes}"
        );
    }

    /// A drawing whose parts do not fit together, or whose numbers are not
    /// finite, is refused, naming the field; nothing is drawn.
    #[test]
    fn a_png_request_whose_parts_do_not_fit_is_refused_naming_the_field() {
        // One square: 4 points in one ring of one shape.
        let square = TanglePngRequest {
            points: le(
                [0.0f32, 0.0, 10.0, 0.0, 10.0, 10.0, 0.0, 10.0],
                f32::to_le_bytes,
            ),
            rings: le([4u32], u32::to_le_bytes),
            shapes: le([1u32], u32::to_le_bytes),
            fill: le([0.5f32], f32::to_le_bytes),
            flags: vec![0],
            png_width: 64,
            ..Default::default()
        };
        assert!(png(square.clone()).is_ok());
        let field = |r: TanglePngRequest| match png(r) {
            Err(e) => e.field().unwrap_or("").to_string(),
            Ok(_) => panic!("accepted"),
        };
        let mut r = square.clone();
        r.points.pop();
        assert_eq!(field(r), "points", "not whole f32s");
        let mut r = square.clone();
        r.points
            .extend_from_slice(&le([1.0f32, 1.0], f32::to_le_bytes));
        assert_eq!(field(r), "points", "a point more than the rings have");
        let mut r = square.clone();
        r.points[0..4].copy_from_slice(&f32::NAN.to_le_bytes());
        assert_eq!(field(r), "points", "NaN");
        let mut r = square.clone();
        r.shapes = le([2u32], u32::to_le_bytes);
        assert_eq!(field(r), "rings", "a ring fewer than the shapes have");
        let mut r = square.clone();
        r.rings = le([u32::MAX], u32::to_le_bytes);
        assert_eq!(field(r), "points", "a ring longer than the points");
        let mut r = square.clone();
        r.fill.clear();
        assert_eq!(field(r), "fill");
        let mut r = square.clone();
        r.fill = le([f32::INFINITY], f32::to_le_bytes);
        assert_eq!(field(r), "fill");
        let mut r = square.clone();
        r.flags = vec![4];
        assert_eq!(field(r), "flags");
        let mut r = square.clone();
        r.png_width = 0;
        assert_eq!(field(r), "png_width");
        let mut r = square;
        r.stroke_width = f64::NAN;
        assert_eq!(field(r), "stroke_width");
    }
}
