//! A tangle grammar as data: what [`super::grammar::parse`] gives and the
//! expansion ([`super::expand`]) runs. One place for the operators, their
//! parameters (with names, for the browser's parameter sliders) and their
//! output tags.
//!
//! Output tags follow Fig. 9 of the paper, where a rule lists its tags in
//! this order: `outline(d) : t -> [inner, ring]`, `place(s, d) : t ->
//! [placed, remainder]`, a decorative operator `-> [shape, marks]`; every
//! other operator gives all its shapes the first tag. (The paper's formal
//! definitions list the outline ring and the placement remainder first;
//! its own grammar, Fig. 9, does the opposite, and we follow the grammar.)
use glam::DVec2;
use serde::{Deserialize, Serialize};

/// A whole grammar file.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Grammar {
    /// Named curves (for splits) and shapes (for placement), in file order.
    pub defs: Vec<Def>,
    /// Start shapes declared in the file (`start rect(800, 600) : poly`).
    pub start: Vec<Start>,
    /// Production rules in file order (a rule's index is its id).
    pub rules: Vec<Rule>,
}

/// `curve NAME = ...` or `shape NAME = ...`.
#[derive(Debug, Clone, PartialEq)]
pub struct Def {
    pub name: String,
    pub kind: DefKind,
    pub curve: CurveDef,
    /// 1-based line of the definition.
    pub line: usize,
}

/// Whether a definition is an open curve or a closed shape.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum DefKind {
    Curve,
    Shape,
}

/// A curve or shape. Split curves are in a local frame: `x` runs across
/// the shape (perpendicular to its orientation), `y` along it; a curve is
/// stretched (open curves: `polyline`, `svg`, `arc`) or repeated
/// (`zigzag`, `wave`) to span the shape. Shapes for placement are centred
/// and scaled to the placement size.
#[derive(Debug, Clone, PartialEq)]
pub enum CurveDef {
    /// A straight line (`line`, built in).
    Line,
    /// A triangle wave: `zigzag(amplitude, period)`.
    Zigzag { amplitude: f64, period: f64 },
    /// A sine wave: `wave(amplitude, period)`.
    Wave { amplitude: f64, period: f64 },
    /// A circular arc whose height is `bulge` times its width: `arc(bulge)`.
    Arc { bulge: f64 },
    /// Points `polyline(x y, x y, ...)` (a closed shape when a `shape`).
    Polyline(Vec<DVec2>),
    /// An SVG path's `d` attribute: `svg("M 0 0 C ...")`.
    Svg(String),
    /// A circle (`circle`, built in): for placement.
    Circle,
    /// A regular polygon `ngon(n)`: for placement.
    Ngon(u32),
}

/// `start SHAPE : tag`.
#[derive(Debug, Clone, PartialEq)]
pub struct Start {
    pub shape: StartShape,
    pub tag: String,
    pub line: usize,
}

/// A start shape.
#[derive(Debug, Clone, PartialEq)]
pub enum StartShape {
    /// `rect(width, height)` with its corner at the origin.
    Rect { width: f64, height: f64 },
    /// `circle(radius)` centred at `(radius, radius)`.
    Circle { radius: f64 },
    /// `polygon(x y, x y, ...)`.
    Polygon(Vec<DVec2>),
    /// `svg("d")`: every subpath a ring, nested rings holes.
    Svg(String),
    /// `text("WORD")`: letter outlines.
    Text(String),
}

/// `op(params) : tag -> [tags]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Rule {
    pub op: Op,
    /// The tag the rule matches.
    pub tag: String,
    /// Output tags (see the module doc for their order per operator).
    pub outputs: Vec<String>,
    /// 1-based line and column of the rule's first character.
    pub line: usize,
    pub column: usize,
}

/// The field a streamline split follows (paper §4.2).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StreamKind {
    /// Boundary vectors along the boundary: streamlines follow the outline.
    Smooth,
    /// Boundary vectors `(P+1 − P) + (P−1 − P)`, turned inwards: strips.
    Strip,
    /// Perpendicular to the direction to a point (the shape's centroid, or
    /// `at` in shape-box fractions): circles around it.
    Circular,
}

/// What stippling scatters.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StippleKind {
    Dots,
    Dashes,
    Curves,
}

/// An operator with its parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum Op {
    /// `ungroup()`: every shape its own new group.
    Ungroup,
    /// `regroup(k)`: shape `s` to new group `s mod k`.
    Regroup { k: u32 },
    /// `regularSplit(curve, offset | [offsets], dual)`.
    Split {
        curve: String,
        offsets: Vec<f64>,
        dual: bool,
    },
    /// `outline(d)`: inset by `d`; inner shapes and the ring.
    Outline { distance: f64 },
    /// `streamlineSplit(kind, offset)`.
    Streamline { kind: StreamKind, offset: f64 },
    /// `place(size, distance[, shape])`: copies of a shape packed inside.
    Place {
        size: f64,
        distance: f64,
        shape: String,
    },
    /// `fill(tone)`: ink the shape, tone 0 (paper) ..= 1 (black).
    Fill { tone: f64 },
    /// `stippling(kind, spacing, size)`: marks scattered inside.
    Stipple {
        kind: StippleKind,
        spacing: f64,
        size: f64,
    },
    /// `invert()`: black shape, white lines.
    Invert,
}

/// A numeric parameter of an operator, as the browser edits it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Param {
    pub name: &'static str,
    pub value: f64,
    /// A sensible slider range.
    pub min: f64,
    pub max: f64,
    /// Whole numbers only.
    pub integer: bool,
}

impl Op {
    /// The operator's name as written in grammars.
    pub fn name(&self) -> &'static str {
        match self {
            Op::Ungroup => "ungroup",
            Op::Regroup { .. } => "regroup",
            Op::Split { .. } => "regularSplit",
            Op::Outline { .. } => "outline",
            Op::Streamline { .. } => "streamlineSplit",
            Op::Place { .. } => "place",
            Op::Fill { .. } => "fill",
            Op::Stipple { .. } => "stippling",
            Op::Invert => "invert",
        }
    }

    /// Its numeric parameters (what a step's editor shows).
    pub fn params(&self) -> Vec<Param> {
        let p = |name, value, min, max, integer| Param {
            name,
            value,
            min,
            max,
            integer,
        };
        match self {
            Op::Ungroup | Op::Invert => vec![],
            Op::Regroup { k } => vec![p("k", *k as f64, 1.0, 8.0, true)],
            Op::Split { offsets, dual, .. } => {
                let mut v: Vec<Param> = offsets
                    .iter()
                    .enumerate()
                    .map(|(i, o)| p(OFFSET_NAMES[i.min(7)], *o, 1.0, 200.0, false))
                    .collect();
                v.push(p("dual", *dual as u8 as f64, 0.0, 1.0, true));
                v
            }
            Op::Outline { distance } => vec![p("distance", *distance, 0.5, 100.0, false)],
            Op::Streamline { offset, .. } => vec![p("offset", *offset, 1.0, 100.0, false)],
            Op::Place { size, distance, .. } => vec![
                p("size", *size, 1.0, 200.0, false),
                p("distance", *distance, 0.0, 200.0, false),
            ],
            Op::Fill { tone } => vec![p("tone", *tone, 0.0, 1.0, false)],
            Op::Stipple { spacing, size, .. } => vec![
                p("spacing", *spacing, 1.0, 50.0, false),
                p("size", *size, 0.2, 20.0, false),
            ],
        }
    }

    /// The operator with parameter `name` set to `value` (clamped to what
    /// the operator accepts); `None` for an unknown name.
    pub fn with_param(&self, name: &str, value: f64) -> Option<Op> {
        if !value.is_finite() {
            return None;
        }
        let mut op = self.clone();
        match &mut op {
            Op::Regroup { k } if name == "k" => *k = value.round().clamp(1.0, 1e6) as u32,
            Op::Split { offsets, dual, .. } => {
                if name == "dual" {
                    *dual = value >= 0.5;
                } else {
                    let i = OFFSET_NAMES.iter().position(|n| *n == name)?;
                    *offsets.get_mut(i)? = value.max(MIN_LENGTH);
                }
            }
            Op::Outline { distance } if name == "distance" => *distance = value.max(MIN_LENGTH),
            Op::Streamline { offset, .. } if name == "offset" => *offset = value.max(MIN_LENGTH),
            Op::Place { size, .. } if name == "size" => *size = value.max(MIN_LENGTH),
            Op::Place { distance, .. } if name == "distance" => *distance = value.max(0.0),
            Op::Fill { tone } if name == "tone" => *tone = value.clamp(0.0, 1.0),
            Op::Stipple { spacing, .. } if name == "spacing" => *spacing = value.max(MIN_LENGTH),
            Op::Stipple { size, .. } if name == "size" => *size = value.max(MIN_LENGTH),
            _ => return None,
        }
        Some(op)
    }
}

/// Names of a split's offsets in [`Op::params`].
const OFFSET_NAMES: [&str; 8] = [
    "offset", "offset2", "offset3", "offset4", "offset5", "offset6", "offset7", "offset8",
];

/// Smallest length parameter (offsets, distances, sizes) in drawing units:
/// anything smaller would make a runaway number of pieces.
pub const MIN_LENGTH: f64 = 0.5;
