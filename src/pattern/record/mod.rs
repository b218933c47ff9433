//! Running a pattern program once to record its shapes and the tape that
//! computes their fields from the float parameters (paper §3).
//!
//! Control flow (`if`, loop bounds, recursion) is decided at record time and
//! must not depend on a float parameter: doing so is an error at the
//! offending line and column. This keeps one tape valid for every value of
//! the float parameters, so a fit records once and replays thousands of
//! times; value choices that do depend on them are written with
//! `select(c, a, b)`, `min`, `max` or `abs`, which stay on the tape.
//!
//! Files: [`interp`] (the interpreter: scopes, statements, expressions,
//! calls, constant folding onto the tape, the depth and operation budgets),
//! [`shapes`] (shape statements and their style, boolean blocks),
//! [`path`] (the path builder), [`transform`] (translate/rotate/scale).
use super::lang::{parse, Ast};
use super::tape::Op;
use crate::core::error::{Error, Result};
use interp::{builtin_arity, is_statement_name, Flow, Rec, Val, V};

pub use super::lang::{ParamDecl, Pos, MAX_DEPTH};
pub use super::sdf::PrimKind;
pub use super::tape::Tape;

mod interp;
mod path;
mod shapes;
#[cfg(test)]
mod tests;
mod tile;
mod transform;

/// Largest accepted program text.
pub use crate::core::limits::MAX_PROGRAM_BYTES;

/// Limits on one recording run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecordLimits {
    /// Interpreter operations (each statement and expression node counts one).
    pub max_ops: u64,
    /// Shapes emitted, and also primitives: every circle, rectangle, point,
    /// segment and path piece counts, inside paths and boolean blocks too
    /// (a cubic is 8 quadratic pieces).
    pub max_shapes: usize,
    /// Nesting depth while running: blocks, expression nodes and function
    /// calls, added up through every active call. Capped at
    /// [`MAX_DEPTH`], the budget that fits the wasm stack.
    pub max_depth: usize,
}

impl Default for RecordLimits {
    /// One million operations (a few ms), 5,000 shapes and primitives,
    /// nesting depth [`MAX_DEPTH`].
    fn default() -> Self {
        RecordLimits {
            max_ops: crate::core::limits::MAX_PROGRAM_OPS,
            max_shapes: crate::core::limits::MAX_SHAPES,
            max_depth: MAX_DEPTH,
        }
    }
}

/// An RGB colour.
pub type Rgb = [u8; 3];

/// The canvas a program draws on: `[0, w] × [0, h]` in program units, y
/// down, its shorter side 1 (a square canvas is `[0, 1]²`). A fit takes its
/// target image's aspect; programs read the size as `WIDTH` and `HEIGHT`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Canvas {
    pub w: f64,
    pub h: f64,
}

impl Canvas {
    /// `[0, 1]²`.
    pub const SQUARE: Canvas = Canvas { w: 1.0, h: 1.0 };

    /// The canvas of a `width × height` picture: the picture's aspect with
    /// its shorter side 1 (a square picture gives exactly [`Canvas::SQUARE`]).
    pub fn of_pixels(width: usize, height: usize) -> Canvas {
        let (w, h) = (width.max(1), height.max(1));
        let m = w.min(h) as f64;
        Canvas {
            w: w as f64 / m,
            h: h as f64 / m,
        }
    }

    /// Pixels `(columns, rows)` of a grid on this canvas whose longer side
    /// has `n` (the shorter one rounded, at least 1): `(n, n)` on a square.
    pub fn grid(&self, n: usize) -> (usize, usize) {
        let short = |a: f64, b: f64| ((n as f64 * a / b).round() as usize).clamp(1, n.max(1));
        if self.w >= self.h {
            (n, short(self.h, self.w))
        } else {
            (short(self.w, self.h), n)
        }
    }

    /// Whether this is the square canvas.
    pub fn is_square(&self) -> bool {
        self.w == self.h
    }
}

/// One recorded primitive: its kind and the tape nodes of its fields.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prim {
    pub kind: PrimKind,
    pub fields: [u32; 6],
}

/// Boolean combinations of geometries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BoolOp {
    Union,
    Intersect,
    /// The first child minus all others.
    Difference,
}

/// The geometry of a shape.
#[derive(Debug, Clone, PartialEq)]
pub enum Geom {
    /// A single primitive (index into [`Recording::prims`]).
    Prim(u32),
    /// Consecutive segment/quadratic primitives `first..first+len`; a closed
    /// path is signed by its non-zero winding number.
    Path { first: u32, len: u32, closed: bool },
    /// A boolean combination of signed geometries.
    Bool(BoolOp, Vec<Geom>),
}

/// One drawn shape.
#[derive(Debug, Clone, PartialEq)]
pub struct Shape {
    pub geom: Geom,
    /// Palette index of the fill colour, if filled.
    pub fill: Option<u16>,
    /// Palette index of the stroke colour, if stroked.
    pub stroke: Option<u16>,
    /// Tape node of the stroke width (canvas units).
    pub width: u32,
    /// Where the shape was emitted.
    pub pos: Pos,
}

/// The result of running a program: shapes in drawing order, their
/// primitives and the tape, on its [`Canvas`] (y down).
#[derive(Debug, Clone)]
pub struct Recording {
    /// The tape computing every field from the float parameters.
    pub tape: Tape,
    /// All declared parameters in declaration order.
    pub params: Vec<ParamDecl>,
    /// Indices (into `params`) of the float parameters; tape `Param(k)` is `params[float_params[k]]`.
    pub float_params: Vec<usize>,
    /// Values of all parameters used while recording.
    pub values: Vec<f64>,
    pub prims: Vec<Prim>,
    pub shapes: Vec<Shape>,
    /// Palette; index 0 is the background.
    pub colours: Vec<Rgb>,
    /// The canvas it was recorded on.
    pub canvas: Canvas,
}

impl Recording {
    /// The float (optimised) parameters.
    pub fn float_decls(&self) -> Vec<&ParamDecl> {
        self.float_params.iter().map(|&i| &self.params[i]).collect()
    }
    /// Record-time values of the float parameters.
    pub fn float_values(&self) -> Vec<f64> {
        self.float_params.iter().map(|&i| self.values[i]).collect()
    }
}

/// A parsed pattern program.
#[derive(Debug, Clone)]
pub struct Program {
    ast: Ast,
}

impl Program {
    /// Parse program text (at most [`MAX_PROGRAM_BYTES`]); errors carry line and column.
    pub fn parse(src: &str) -> Result<Program> {
        if src.len() > MAX_PROGRAM_BYTES {
            return Err(Error::limit(format!(
                "the program is {} bytes; programs may be at most {MAX_PROGRAM_BYTES} bytes",
                src.len()
            )));
        }
        let ast = parse(src)?;
        for f in &ast.fns {
            if builtin_arity(&f.name).is_some() || is_statement_name(&f.name) {
                return Err(f.pos.err(format!(
                    "'{}' is a built-in name; pick another function name",
                    f.name
                )));
            }
        }
        let p = Program { ast };
        Ok(p)
    }
    /// All declared parameters in declaration order.
    pub fn params(&self) -> &[ParamDecl] {
        &self.ast.params
    }
    /// Default values of all parameters.
    pub fn defaults(&self) -> Vec<f64> {
        self.ast.params.iter().map(|p| p.default).collect()
    }
    /// Run the program with `values` (one per declared parameter, declaration
    /// order; integer ones are rounded) and record shapes and tape on the
    /// square canvas.
    pub fn record(&self, values: &[f64], limits: &RecordLimits) -> Result<Recording> {
        self.record_on(values, limits, Canvas::SQUARE)
    }

    /// [`Program::record`] on `canvas` (`WIDTH`, `HEIGHT` and the copies
    /// of `tile` follow it).
    pub fn record_on(
        &self,
        values: &[f64],
        limits: &RecordLimits,
        canvas: Canvas,
    ) -> Result<Recording> {
        if values.len() != self.ast.params.len() {
            return Err(Error::input(format!(
                "the program declares {} parameters but {} values were given",
                self.ast.params.len(),
                values.len()
            )));
        }
        if !(canvas.w.is_finite() && canvas.h.is_finite() && canvas.w > 0.0 && canvas.h > 0.0) {
            return Err(Error::input("the canvas must have a positive, finite size"));
        }
        let mut r = Rec::new(&self.ast, *limits);
        r.canvas = canvas;
        let mut float_params = vec![];
        let mut vals = vec![];
        for (i, (d, &v)) in self.ast.params.iter().zip(values).enumerate() {
            if !v.is_finite() {
                return Err(Error::input(format!(
                    "parameter '{}' has no finite value",
                    d.name
                )));
            }
            let v = v.clamp(d.lo, d.hi);
            let val = if d.integer {
                V::C(v.round())
            } else {
                let k = float_params.len() as u32;
                float_params.push(i);
                r.ranges.push((d.lo, d.hi));
                V::N(r.tape.push(Op::Param(k), v))
            };
            vals.push(if d.integer { v.round() } else { v });
            r.globals.insert(d.name.clone(), Val::Num(val));
        }
        if let Some((bg, pos)) = &self.ast.background {
            r.colours[0] = parse_colour(bg).ok_or_else(|| pos.err(colour_error(bg)))?;
        }
        match r.block(&self.ast.body, true, Pos { line: 1, column: 1 })? {
            Flow::Normal => {}
            Flow::Return(_, pos) => return Err(pos.err("'return' outside a function")),
        }
        Ok(Recording {
            tape: r.tape,
            params: self.ast.params.clone(),
            float_params,
            values: vals,
            prims: r.prims,
            shapes: r.shapes,
            colours: r.colours,
            canvas,
        })
    }
}

fn colour_error(s: &str) -> String {
    format!(
        "'{s}' is not a colour; write \"#rgb\" or \"#rrggbb\" (or black, white, red, green, blue)"
    )
}

/// Parse `#rgb`, `#rrggbb` or a few names.
pub(crate) fn parse_colour(s: &str) -> Option<Rgb> {
    match s {
        "black" => return Some([0, 0, 0]),
        "white" => return Some([255, 255, 255]),
        "red" => return Some([255, 0, 0]),
        "green" => return Some([0, 128, 0]),
        "blue" => return Some([0, 0, 255]),
        _ => {}
    }
    let h = s.strip_prefix('#')?;
    let d: Vec<u8> = h
        .chars()
        .map(|c| c.to_digit(16).map(|v| v as u8))
        .collect::<Option<_>>()?;
    match d.len() {
        3 => Some([d[0] * 17, d[1] * 17, d[2] * 17]),
        6 => Some([d[0] * 16 + d[1], d[2] * 16 + d[3], d[4] * 16 + d[5]]),
        _ => None,
    }
}
