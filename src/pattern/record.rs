//! Running a pattern program once to record its shapes and the tape that
//! computes their fields from the float parameters (paper §3).
//!
//! Control flow (`if`, loop bounds, recursion) is decided at record time and
//! must not depend on a float parameter: doing so is an error at the
//! offending line and column. This keeps one tape valid for every value of
//! the float parameters, so a fit records once and replays thousands of
//! times; value choices that do depend on them are written with
//! `select(c, a, b)`, `min`, `max` or `abs`, which stay on the tape.
use super::lang::{parse, Arg, Ast, BinOp, Call, Expr, FnDecl, ParamDecl, Pos, Stmt};
use super::sdf::{cubic_piece_weights, PrimKind};
use super::tape::{apply, Op, StepFn, Tape};
use crate::core::error::{Error, Result};
use std::collections::HashMap;
use std::rc::Rc;

/// Limits on one recording run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RecordLimits {
    /// Interpreter operations (each statement and expression node counts one).
    pub max_ops: u64,
    /// Shapes emitted.
    pub max_shapes: usize,
    /// Nesting depth of user function calls.
    pub max_depth: usize,
}

impl Default for RecordLimits {
    /// One million operations (a few ms), 5,000 shapes, depth 64.
    fn default() -> Self {
        RecordLimits {
            max_ops: 1_000_000,
            max_shapes: 5_000,
            max_depth: 64,
        }
    }
}

/// An RGB colour.
pub type Rgb = [u8; 3];

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
/// primitives and the tape. Canvas coordinates are `[0, 1]²`, y down.
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
    /// Parse program text; errors carry line and column.
    pub fn parse(src: &str) -> Result<Program> {
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
    /// order; integer ones are rounded) and record shapes and tape.
    pub fn record(&self, values: &[f64], limits: &RecordLimits) -> Result<Recording> {
        if values.len() != self.ast.params.len() {
            return Err(Error::input(format!(
                "the program declares {} parameters but {} values were given",
                self.ast.params.len(),
                values.len()
            )));
        }
        let mut r = Rec::new(&self.ast, *limits);
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
                V::N(r.tape.push(Op::Param(k), v))
            };
            vals.push(if d.integer { v.round() } else { v });
            r.globals.insert(d.name.clone(), Val::Num(val));
        }
        if let Some((bg, pos)) = &self.ast.background {
            r.colours[0] = parse_colour(bg).ok_or_else(|| pos.err(colour_error(bg)))?;
        }
        match r.block(&self.ast.body, true)? {
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
        })
    }
}

fn colour_error(s: &str) -> String {
    format!(
        "'{s}' is not a colour; write \"#rgb\" or \"#rrggbb\" (or black, white, red, green, blue)"
    )
}

/// Parse `#rgb`, `#rrggbb` or a few names.
pub fn parse_colour(s: &str) -> Option<Rgb> {
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

/// A tape value: a known constant or a node.
#[derive(Debug, Clone, Copy, PartialEq)]
enum V {
    C(f64),
    N(u32),
}

#[derive(Debug, Clone)]
enum Val {
    Num(V),
    Str(Rc<str>),
}

enum Flow {
    Normal,
    Return(Option<Val>, Pos),
}

#[derive(Clone, Copy)]
struct Xf {
    cos: V,
    sin: V,
    angle: V,
    scale: V,
    tx: V,
    ty: V,
}

struct PathB {
    start: (V, V),
    cur: (V, V),
    first: u32,
    started: bool,
    closed: bool,
}

fn is_statement_name(n: &str) -> bool {
    matches!(
        n,
        "circle"
            | "point"
            | "segment"
            | "line"
            | "rect"
            | "path"
            | "union"
            | "intersect"
            | "difference"
            | "translate"
            | "rotate"
            | "scale"
            | "move"
            | "quad"
            | "cubic"
            | "close"
    )
}

fn builtin_arity(n: &str) -> Option<(usize, usize)> {
    Some(match n {
        "sin" | "cos" | "tan" | "atan" | "sqrt" | "abs" | "exp" | "ln" | "floor" | "ceil"
        | "round" => (1, 1),
        "atan2" | "pow" | "mod" | "hypot" => (2, 2),
        "min" | "max" => (1, 64),
        "clamp" | "select" | "lerp" | "rgb" => (3, 3),
        _ => return None,
    })
}

/// Named call arguments with their positions.
type Named = HashMap<String, (Val, Pos)>;

struct Rec<'a> {
    fns: HashMap<&'a str, &'a FnDecl>,
    tape: Tape,
    consts: HashMap<u64, u32>,
    globals: HashMap<String, Val>,
    /// Function frames; each is a stack of block scopes.
    frames: Vec<Vec<HashMap<String, Val>>>,
    ops: u64,
    limits: RecordLimits,
    xf: Vec<Xf>,
    bool_sinks: Vec<Vec<Geom>>,
    path: Option<PathB>,
    prims: Vec<Prim>,
    shapes: Vec<Shape>,
    colours: Vec<Rgb>,
}

impl<'a> Rec<'a> {
    fn new(ast: &'a Ast, limits: RecordLimits) -> Self {
        Rec {
            fns: ast.fns.iter().map(|f| (f.name.as_str(), f)).collect(),
            tape: Tape::new(),
            consts: HashMap::new(),
            globals: HashMap::new(),
            frames: vec![vec![HashMap::new()]],
            ops: 0,
            limits,
            xf: vec![Xf {
                cos: V::C(1.0),
                sin: V::C(0.0),
                angle: V::C(0.0),
                scale: V::C(1.0),
                tx: V::C(0.0),
                ty: V::C(0.0),
            }],
            bool_sinks: vec![],
            path: None,
            prims: vec![],
            shapes: vec![],
            colours: vec![[255, 255, 255]],
        }
    }

    fn tick(&mut self, pos: Pos) -> Result<()> {
        self.ops += 1;
        if self.ops > self.limits.max_ops {
            return Err(Error::limit(format!(
                "line {}, column {}: the program ran more than {} operations; does a loop or a recursion never end?",
                pos.line, pos.column, self.limits.max_ops
            )));
        }
        Ok(())
    }

    // ---- tape values -------------------------------------------------

    fn value(&self, v: V) -> f64 {
        match v {
            V::C(c) => c,
            V::N(i) => self.tape.init_value(i),
        }
    }

    fn node(&mut self, v: V) -> u32 {
        match v {
            V::N(i) => i,
            V::C(c) => {
                let key = c.to_bits();
                if let Some(&i) = self.consts.get(&key) {
                    return i;
                }
                let i = self.tape.push(Op::Const, c);
                self.consts.insert(key, i);
                i
            }
        }
    }

    /// Apply `make(operands)` folding constants.
    fn op(&mut self, args: &[V], make: impl Fn(&[u32]) -> Op) -> V {
        let vals: Vec<f64> = args.iter().map(|&a| self.value(a)).collect();
        let local: Vec<u32> = (0..args.len() as u32).collect();
        let v = apply(make(&local), &vals);
        if args.iter().all(|a| matches!(a, V::C(_))) {
            return V::C(v);
        }
        let ids: Vec<u32> = args.iter().map(|&a| self.node(a)).collect();
        V::N(self.tape.push(make(&ids), v))
    }

    fn add(&mut self, a: V, b: V) -> V {
        match (a, b) {
            (V::C(x), y) | (y, V::C(x)) if x == 0.0 => y,
            _ => self.op(&[a, b], |o| Op::Add(o[0], o[1])),
        }
    }
    fn sub(&mut self, a: V, b: V) -> V {
        if b == V::C(0.0) {
            return a;
        }
        self.op(&[a, b], |o| Op::Sub(o[0], o[1]))
    }
    fn mul(&mut self, a: V, b: V) -> V {
        match (a, b) {
            (V::C(x), y) | (y, V::C(x)) if x == 1.0 => y,
            (V::C(x), _) | (_, V::C(x)) if x == 0.0 => V::C(0.0),
            _ => self.op(&[a, b], |o| Op::Mul(o[0], o[1])),
        }
    }

    // ---- scopes ------------------------------------------------------

    fn lookup(&self, name: &str) -> Option<Val> {
        let frame = self.frames.last().expect("a frame");
        for scope in frame.iter().rev() {
            if let Some(v) = scope.get(name) {
                return Some(v.clone());
            }
        }
        if self.frames.len() > 1 {
            // Functions also see top-level variables.
            for scope in self.frames[0].iter().rev() {
                if let Some(v) = scope.get(name) {
                    return Some(v.clone());
                }
            }
        }
        self.globals.get(name).cloned()
    }

    fn assign(&mut self, name: &str, v: Val, pos: Pos) -> Result<()> {
        let nframes = self.frames.len();
        for fi in [nframes - 1, 0] {
            for scope in self.frames[fi].iter_mut().rev() {
                if let Some(slot) = scope.get_mut(name) {
                    *slot = v;
                    return Ok(());
                }
            }
            if nframes == 1 {
                break;
            }
        }
        if self.globals.contains_key(name) {
            return Err(pos.err(format!(
                "'{name}' is a parameter and cannot be assigned; use 'let {name}2 = ...;'"
            )));
        }
        Err(pos.err(format!(
            "'{name}' is not defined; declare it first with 'let {name} = ...;'"
        )))
    }

    // ---- statements --------------------------------------------------

    fn block(&mut self, stmts: &[Stmt], same_scope: bool) -> Result<Flow> {
        if !same_scope {
            self.frames.last_mut().expect("frame").push(HashMap::new());
        }
        let mut out = Flow::Normal;
        for s in stmts {
            match self.stmt(s)? {
                Flow::Normal => {}
                r => {
                    out = r;
                    break;
                }
            }
        }
        if !same_scope {
            self.frames.last_mut().expect("frame").pop();
        }
        Ok(out)
    }

    fn num(&mut self, e: &Expr) -> Result<V> {
        match self.expr(e)? {
            Val::Num(v) => Ok(v),
            Val::Str(s) => Err(e
                .pos()
                .err(format!("expected a number but got the string \"{s}\""))),
        }
    }

    /// A number that must be known at record time (control flow).
    fn structural(&mut self, e: &Expr, what: &str) -> Result<f64> {
        match self.num(e)? {
            V::C(c) => Ok(c),
            V::N(_) => Err(e.pos().err(format!(
                "{what} depends on a float parameter; the program's structure may only depend on 'int param's \
                 (use select(cond, a, b), min or max to choose values)"
            ))),
        }
    }

    fn stmt(&mut self, s: &Stmt) -> Result<Flow> {
        match s {
            Stmt::Let(name, e, pos) => {
                self.tick(*pos)?;
                let v = self.expr(e)?;
                self.frames
                    .last_mut()
                    .expect("frame")
                    .last_mut()
                    .expect("scope")
                    .insert(name.clone(), v);
            }
            Stmt::Assign(name, e, pos) => {
                self.tick(*pos)?;
                let v = self.expr(e)?;
                self.assign(name, v, *pos)?;
            }
            Stmt::If(c, a, b, pos) => {
                self.tick(*pos)?;
                let c = self.structural(c, "this condition")?;
                return self.block(if c != 0.0 { a } else { b }, false);
            }
            Stmt::For(var, a, b, body, pos) => {
                let lo = self.structural(a, "this loop's start")?;
                let hi = self.structural(b, "this loop's end")?;
                let mut i = lo;
                while i < hi {
                    self.tick(*pos)?;
                    let frame = self.frames.last_mut().expect("frame");
                    frame.push(HashMap::new());
                    frame
                        .last_mut()
                        .expect("scope")
                        .insert(var.clone(), Val::Num(V::C(i)));
                    let r = self.block(body, true);
                    self.frames.last_mut().expect("frame").pop();
                    if let Flow::Return(v, p) = r? {
                        return Ok(Flow::Return(v, p));
                    }
                    i += 1.0;
                }
            }
            Stmt::Return(e, pos) => {
                self.tick(*pos)?;
                let v = match e {
                    Some(e) => Some(self.expr(e)?),
                    None => None,
                };
                return Ok(Flow::Return(v, *pos));
            }
            Stmt::Block(b) => return self.block(b, false),
            Stmt::Call(c) => {
                self.tick(c.pos)?;
                if is_statement_name(&c.name) && !self.fns.contains_key(c.name.as_str()) {
                    self.shape_stmt(c)?;
                } else {
                    if c.block.is_some() {
                        return Err(c
                            .pos
                            .err(format!("'{}' does not take a {{ block }}", c.name)));
                    }
                    self.call(c)?;
                }
            }
        }
        Ok(Flow::Normal)
    }

    // ---- expressions -------------------------------------------------

    fn expr(&mut self, e: &Expr) -> Result<Val> {
        self.tick(e.pos())?;
        Ok(match e {
            Expr::Num(v, _) => Val::Num(V::C(*v)),
            Expr::Str(s, _) => Val::Str(Rc::from(s.as_str())),
            Expr::Var(n, pos) => match self.lookup(n) {
                Some(v) => v,
                None => match n.as_str() {
                    "PI" => Val::Num(V::C(std::f64::consts::PI)),
                    "TAU" => Val::Num(V::C(std::f64::consts::TAU)),
                    _ => return Err(pos.err(format!("'{n}' is not defined"))),
                },
            },
            Expr::Neg(a, _) => {
                let a = self.num(a)?;
                Val::Num(self.op(&[a], |o| Op::Neg(o[0])))
            }
            Expr::Not(a, _) => {
                let a = self.num(a)?;
                Val::Num(self.op(&[a], |o| Op::Step(StepFn::Not, o[0], o[0])))
            }
            Expr::Bin(op, a, b, _) => {
                let (a, b) = (self.num(a)?, self.num(b)?);
                let step = |f: StepFn| move |o: &[u32]| Op::Step(f, o[0], o[1]);
                Val::Num(match op {
                    BinOp::Add => self.add(a, b),
                    BinOp::Sub => self.sub(a, b),
                    BinOp::Mul => self.mul(a, b),
                    BinOp::Div => self.op(&[a, b], |o| Op::Div(o[0], o[1])),
                    BinOp::Mod => self.op(&[a, b], |o| Op::Mod(o[0], o[1])),
                    BinOp::Pow => self.op(&[a, b], |o| Op::Pow(o[0], o[1])),
                    BinOp::Lt => self.op(&[a, b], step(StepFn::Lt)),
                    BinOp::Le => self.op(&[a, b], step(StepFn::Le)),
                    BinOp::Gt => self.op(&[a, b], step(StepFn::Gt)),
                    BinOp::Ge => self.op(&[a, b], step(StepFn::Ge)),
                    BinOp::Eq => self.op(&[a, b], step(StepFn::Eq)),
                    BinOp::Ne => self.op(&[a, b], step(StepFn::Ne)),
                    BinOp::And => self.op(&[a, b], step(StepFn::And)),
                    BinOp::Or => self.op(&[a, b], step(StepFn::Or)),
                })
            }
            Expr::Call(c) => {
                if c.block.is_some() {
                    return Err(c.pos.err("a call with a block cannot be used as a value"));
                }
                if is_statement_name(&c.name) && !self.fns.contains_key(c.name.as_str()) {
                    return Err(c.pos.err(format!(
                        "'{}' draws a shape; use it as a statement, not as a value",
                        c.name
                    )));
                }
                self.call(c)?
            }
        })
    }

    fn call(&mut self, c: &Call) -> Result<Val> {
        if let Some(f) = self.fns.get(c.name.as_str()).copied() {
            return self.user_call(f, c);
        }
        let Some((lo, hi)) = builtin_arity(&c.name) else {
            return Err(c.pos.err(format!("unknown function '{}'", c.name)));
        };
        if let Some(a) = c.args.iter().find(|a| a.name.is_some()) {
            return Err(a
                .value
                .pos()
                .err(format!("'{}' takes no named arguments", c.name)));
        }
        if c.args.len() < lo || c.args.len() > hi {
            let want = if lo == hi {
                format!("{lo}")
            } else {
                format!("{lo} to {hi}")
            };
            return Err(c.pos.err(format!(
                "'{}' takes {want} arguments, got {}",
                c.name,
                c.args.len()
            )));
        }
        let mut a = vec![];
        for arg in &c.args {
            a.push(self.num(&arg.value)?);
        }
        let un = |f: fn(u32) -> Op| move |o: &[u32]| f(o[0]);
        Ok(Val::Num(match c.name.as_str() {
            "sin" => self.op(&a, un(Op::Sin)),
            "cos" => self.op(&a, un(Op::Cos)),
            "tan" => self.op(&a, un(Op::Tan)),
            "atan" => self.op(&a, un(Op::Atan)),
            "sqrt" => self.op(&a, un(Op::Sqrt)),
            "abs" => self.op(&a, un(Op::Abs)),
            "exp" => self.op(&a, un(Op::Exp)),
            "ln" => self.op(&a, un(Op::Ln)),
            "floor" => self.op(&a, |o| Op::Step(StepFn::Floor, o[0], o[0])),
            "ceil" => self.op(&a, |o| Op::Step(StepFn::Ceil, o[0], o[0])),
            "round" => self.op(&a, |o| Op::Step(StepFn::Round, o[0], o[0])),
            "atan2" => self.op(&a, |o| Op::Atan2(o[0], o[1])),
            "pow" => self.op(&a, |o| Op::Pow(o[0], o[1])),
            "mod" => self.op(&a, |o| Op::Mod(o[0], o[1])),
            "hypot" => {
                let x2 = self.mul(a[0], a[0]);
                let y2 = self.mul(a[1], a[1]);
                let s = self.add(x2, y2);
                self.op(&[s], |o| Op::Sqrt(o[0]))
            }
            "min" | "max" => {
                let mut acc = a[0];
                for &x in &a[1..] {
                    acc = if c.name == "min" {
                        self.op(&[acc, x], |o| Op::Min(o[0], o[1]))
                    } else {
                        self.op(&[acc, x], |o| Op::Max(o[0], o[1]))
                    };
                }
                acc
            }
            "clamp" => {
                let m = self.op(&[a[0], a[1]], |o| Op::Max(o[0], o[1]));
                self.op(&[m, a[2]], |o| Op::Min(o[0], o[1]))
            }
            "select" => match a[0] {
                V::C(c) => {
                    if c != 0.0 {
                        a[1]
                    } else {
                        a[2]
                    }
                }
                _ => self.op(&a, |o| Op::Select(o[0], o[1], o[2])),
            },
            "lerp" => {
                let d = self.sub(a[1], a[0]);
                let t = self.mul(d, a[2]);
                self.add(a[0], t)
            }
            "rgb" => {
                let mut s = String::from("#");
                for (arg, v) in c.args.iter().zip(&a) {
                    match v {
                        V::C(x) => {
                            s.push_str(&format!("{:02x}", x.round().clamp(0.0, 255.0) as u8))
                        }
                        V::N(_) => {
                            return Err(arg
                                .value
                                .pos()
                                .err("colours cannot depend on float parameters"))
                        }
                    }
                }
                return Ok(Val::Str(Rc::from(s.as_str())));
            }
            _ => unreachable!("arity table and dispatch agree"),
        }))
    }

    fn user_call(&mut self, f: &'a FnDecl, c: &Call) -> Result<Val> {
        if c.args.len() != f.params.len() {
            return Err(c.pos.err(format!(
                "'{}' takes {} arguments, got {}",
                f.name,
                f.params.len(),
                c.args.len()
            )));
        }
        if let Some(a) = c.args.iter().find(|a| a.name.is_some()) {
            return Err(a
                .value
                .pos()
                .err(format!("'{}' takes no named arguments", f.name)));
        }
        if self.frames.len() > self.limits.max_depth {
            return Err(Error::limit(format!(
                "line {}, column {}: function calls nested deeper than {}; does a recursion never end?",
                c.pos.line, c.pos.column, self.limits.max_depth
            )));
        }
        let mut scope = HashMap::new();
        for (p, a) in f.params.iter().zip(&c.args) {
            let v = self.expr(&a.value)?;
            scope.insert(p.clone(), v);
        }
        self.frames.push(vec![scope]);
        let r = self.block(&f.body, true);
        self.frames.pop();
        Ok(match r? {
            Flow::Return(Some(v), _) => v,
            _ => Val::Num(V::C(0.0)),
        })
    }

    // ---- shapes ------------------------------------------------------

    fn xf_point(&mut self, x: V, y: V) -> (V, V) {
        let t = *self.xf.last().expect("transform");
        let cx = self.mul(t.cos, x);
        let sy = self.mul(t.sin, y);
        let rx = self.sub(cx, sy);
        let sx = self.mul(t.sin, x);
        let cy = self.mul(t.cos, y);
        let ry = self.add(sx, cy);
        let rx = self.mul(t.scale, rx);
        let ry = self.mul(t.scale, ry);
        (self.add(rx, t.tx), self.add(ry, t.ty))
    }

    fn xf_len(&mut self, l: V) -> V {
        let s = self.xf.last().expect("transform").scale;
        self.mul(s, l)
    }

    fn push_prim(&mut self, kind: PrimKind, vals: &[V]) -> u32 {
        let mut fields = [0u32; 6];
        for (k, &v) in vals.iter().enumerate() {
            fields[k] = self.node(v);
        }
        self.prims.push(Prim { kind, fields });
        (self.prims.len() - 1) as u32
    }

    fn colour(&mut self, v: &Val, pos: Pos) -> Result<u16> {
        let Val::Str(s) = v else {
            return Err(pos.err("a colour must be a string like \"#ff8800\""));
        };
        let rgb = parse_colour(s).ok_or_else(|| pos.err(colour_error(s)))?;
        if let Some(i) = self.colours.iter().position(|c| *c == rgb) {
            return Ok(i as u16);
        }
        if self.colours.len() >= 64 {
            return Err(pos.err("a pattern may use at most 64 colours"));
        }
        self.colours.push(rgb);
        Ok((self.colours.len() - 1) as u16)
    }

    /// Split positional and named arguments; check the named ones.
    fn args(&mut self, c: &Call, positional: usize, allowed: &[&str]) -> Result<(Vec<V>, Named)> {
        let mut pos_args = vec![];
        let mut named = HashMap::new();
        for Arg { name, value } in &c.args {
            match name {
                None => {
                    if !named.is_empty() {
                        return Err(value
                            .pos()
                            .err("positional arguments must come before named ones"));
                    }
                    pos_args.push(self.num(value)?);
                }
                Some(n) => {
                    if !allowed.contains(&n.as_str()) {
                        let list = if allowed.is_empty() {
                            "none".to_string()
                        } else {
                            allowed.join(", ")
                        };
                        return Err(value.pos().err(format!(
                            "'{}' has no option '{n}' (options: {list})",
                            c.name
                        )));
                    }
                    let v = self.expr(value)?;
                    named.insert(n.clone(), (v, value.pos()));
                }
            }
        }
        if pos_args.len() != positional {
            return Err(c.pos.err(format!(
                "'{}' takes {positional} numbers, got {}",
                c.name,
                pos_args.len()
            )));
        }
        Ok((pos_args, named))
    }

    fn named_num(&self, named: &HashMap<String, (Val, Pos)>, key: &str, default: f64) -> Result<V> {
        match named.get(key) {
            None => Ok(V::C(default)),
            Some((Val::Num(v), _)) => Ok(*v),
            Some((Val::Str(_), p)) => Err(p.err(format!("'{key}' must be a number"))),
        }
    }

    /// Emit a finished geometry with its style, or hand it to an enclosing boolean block.
    fn emit(
        &mut self,
        c: &Call,
        geom: Geom,
        named: &HashMap<String, (Val, Pos)>,
        closed: bool,
    ) -> Result<()> {
        if !self.bool_sinks.is_empty() {
            if let Some((_, p)) = named
                .get("fill")
                .or(named.get("stroke"))
                .or(named.get("width"))
            {
                return Err(p.err("shapes inside union/intersect/difference take their style from the enclosing block"));
            }
            if !closed {
                return Err(c.pos.err(format!(
                    "'{}' has no inside; boolean blocks need closed shapes",
                    c.name
                )));
            }
            self.bool_sinks.last_mut().expect("sink").push(geom);
            return Ok(());
        }
        let mut fill = match named.get("fill") {
            Some((v, p)) => Some(self.colour(v, *p)?),
            None => None,
        };
        let stroke = match named.get("stroke") {
            Some((v, p)) => Some(self.colour(v, *p)?),
            None => None,
        };
        if fill.is_some() && !closed {
            return Err(named["fill"].1.err(format!(
                "'{}' has no inside to fill; use stroke: instead",
                c.name
            )));
        }
        let stroke = match (fill, stroke) {
            (None, None) => {
                let black = self.colour(&Val::Str(Rc::from("#000000")), c.pos)?;
                if closed {
                    fill = Some(black);
                    None
                } else {
                    Some(black)
                }
            }
            (_, s) => s,
        };
        let w = self.named_num(named, "width", 0.01)?;
        let w = self.xf_len(w);
        let width = self.node(w);
        if self.shapes.len() >= self.limits.max_shapes {
            return Err(Error::limit(format!(
                "line {}, column {}: more than {} shapes; reduce the counts or the loop sizes",
                c.pos.line, c.pos.column, self.limits.max_shapes
            )));
        }
        self.shapes.push(Shape {
            geom,
            fill,
            stroke,
            width,
            pos: c.pos,
        });
        Ok(())
    }

    fn shape_stmt(&mut self, c: &Call) -> Result<()> {
        let in_path = self.path.is_some();
        let path_cmd = matches!(
            c.name.as_str(),
            "move" | "line" | "quad" | "cubic" | "close"
        );
        if in_path && !path_cmd {
            return Err(c.pos.err(format!(
                "'{}' is not allowed inside a path; use move, line, quad, cubic, close",
                c.name
            )));
        }
        if !in_path && matches!(c.name.as_str(), "move" | "quad" | "cubic" | "close") {
            return Err(c.pos.err(format!(
                "'{}' is a path command; use it inside path(...) {{ }}",
                c.name
            )));
        }
        let needs_block = matches!(
            c.name.as_str(),
            "path" | "union" | "intersect" | "difference" | "translate" | "rotate" | "scale"
        );
        if needs_block != c.block.is_some() {
            return Err(c.pos.err(if needs_block {
                format!("'{}' needs a {{ block }} after it", c.name)
            } else {
                format!("'{}' does not take a {{ block }}", c.name)
            }));
        }
        if in_path {
            return self.path_cmd(c);
        }
        const STYLE: [&str; 3] = ["fill", "stroke", "width"];
        match c.name.as_str() {
            "circle" => {
                let (a, named) = self.args(c, 3, &STYLE)?;
                let (x, y) = self.xf_point(a[0], a[1]);
                let r = self.xf_len(a[2]);
                let p = self.push_prim(PrimKind::Circle, &[x, y, r]);
                self.emit(c, Geom::Prim(p), &named, true)
            }
            "point" => {
                let (a, named) = self.args(c, 2, &["stroke", "width"])?;
                let (x, y) = self.xf_point(a[0], a[1]);
                let p = self.push_prim(PrimKind::Point, &[x, y]);
                self.emit(c, Geom::Prim(p), &named, false)
            }
            "segment" | "line" => {
                let (a, named) = self.args(c, 4, &["stroke", "width"])?;
                let (x0, y0) = self.xf_point(a[0], a[1]);
                let (x1, y1) = self.xf_point(a[2], a[3]);
                let p = self.push_prim(PrimKind::Segment, &[x0, y0, x1, y1]);
                self.emit(c, Geom::Prim(p), &named, false)
            }
            "rect" => {
                let (a, named) =
                    self.args(c, 4, &["fill", "stroke", "width", "radius", "rotation"])?;
                let (x, y) = self.xf_point(a[0], a[1]);
                let hw = self.mul(a[2], V::C(0.5));
                let hh = self.mul(a[3], V::C(0.5));
                let hw = self.xf_len(hw);
                let hh = self.xf_len(hh);
                let r = self.named_num(&named, "radius", 0.0)?;
                let r = self.xf_len(r);
                let rot = self.named_num(&named, "rotation", 0.0)?;
                let base = self.xf.last().expect("transform").angle;
                let ang = self.add(rot, base);
                let p = self.push_prim(PrimKind::Rect, &[x, y, hw, hh, r, ang]);
                self.emit(c, Geom::Prim(p), &named, true)
            }
            "path" => {
                let (_, named) = self.args(c, 0, &STYLE)?;
                let first = self.prims.len() as u32;
                self.path = Some(PathB {
                    start: (V::C(0.0), V::C(0.0)),
                    cur: (V::C(0.0), V::C(0.0)),
                    first,
                    started: false,
                    closed: false,
                });
                let r = self.block(c.block.as_deref().unwrap_or(&[]), false);
                let mut pb = self.path.take().expect("path builder");
                r?;
                let closed = pb.closed || named.contains_key("fill");
                if closed && pb.cur != pb.start && pb.started {
                    let (s, e) = (pb.cur, pb.start);
                    self.push_prim(PrimKind::Segment, &[s.0, s.1, e.0, e.1]);
                    pb.cur = pb.start;
                }
                let len = self.prims.len() as u32 - pb.first;
                if len == 0 {
                    return Err(c.pos.err(
                        "this path draws nothing; start with move(x, y) and add line/quad/cubic",
                    ));
                }
                self.emit(
                    c,
                    Geom::Path {
                        first: pb.first,
                        len,
                        closed,
                    },
                    &named,
                    closed,
                )
            }
            "union" | "intersect" | "difference" => {
                let (_, named) = self.args(c, 0, &STYLE)?;
                self.bool_sinks.push(vec![]);
                let r = self.block(c.block.as_deref().unwrap_or(&[]), false);
                let children = self.bool_sinks.pop().expect("sink");
                r?;
                if children.is_empty() {
                    return Err(c.pos.err(format!("'{}' contains no shapes", c.name)));
                }
                let op = match c.name.as_str() {
                    "union" => BoolOp::Union,
                    "intersect" => BoolOp::Intersect,
                    _ => BoolOp::Difference,
                };
                self.emit(c, Geom::Bool(op, children), &named, true)
            }
            "translate" | "rotate" | "scale" => {
                let n = if c.name == "translate" { 2 } else { 1 };
                let (a, _) = self.args(c, n, &[])?;
                let t = *self.xf.last().expect("transform");
                let nt = match c.name.as_str() {
                    "translate" => {
                        let (x, y) = self.xf_point(a[0], a[1]);
                        Xf { tx: x, ty: y, ..t }
                    }
                    "rotate" => {
                        let angle = self.add(t.angle, a[0]);
                        let cos = self.op(&[angle], |o| Op::Cos(o[0]));
                        let sin = self.op(&[angle], |o| Op::Sin(o[0]));
                        Xf {
                            angle,
                            cos,
                            sin,
                            ..t
                        }
                    }
                    _ => {
                        let scale = self.mul(t.scale, a[0]);
                        Xf { scale, ..t }
                    }
                };
                self.xf.push(nt);
                let r = self.block(c.block.as_deref().unwrap_or(&[]), false);
                self.xf.pop();
                match r? {
                    Flow::Normal => Ok(()),
                    Flow::Return(_, p) => {
                        Err(p.err("'return' inside a transform block is not supported"))
                    }
                }
            }
            _ => unreachable!("statement names are listed in is_statement_name"),
        }
    }

    fn path_cmd(&mut self, c: &Call) -> Result<()> {
        let n = match c.name.as_str() {
            "move" | "line" => 2,
            "quad" => 4,
            "cubic" => 6,
            _ => 0,
        };
        let (a, _) = self.args(c, n, &[])?;
        let mut pts = vec![];
        for k in 0..n / 2 {
            pts.push(self.xf_point(a[2 * k], a[2 * k + 1]));
        }
        let pb = self.path.as_ref().expect("in path");
        if c.name == "move" {
            if pb.started {
                return Err(c.pos.err("a path has one move(x, y), at its start; draw separate paths for separate outlines"));
            }
            let pb = self.path.as_mut().expect("in path");
            pb.start = pts[0];
            pb.cur = pts[0];
            pb.started = true;
            return Ok(());
        }
        if !pb.started {
            return Err(c.pos.err("start the path with move(x, y)"));
        }
        let cur = pb.cur;
        match c.name.as_str() {
            "line" => {
                self.push_prim(PrimKind::Segment, &[cur.0, cur.1, pts[0].0, pts[0].1]);
            }
            "quad" => {
                self.push_prim(
                    PrimKind::Quad,
                    &[cur.0, cur.1, pts[0].0, pts[0].1, pts[1].0, pts[1].1],
                );
            }
            "cubic" => {
                // Eight quadratic pieces (see sdf::cubic_piece_weights).
                let ctrl = [cur, pts[0], pts[1], pts[2]];
                let n = 8;
                for k in 0..n {
                    let w = cubic_piece_weights(k as f64 / n as f64, (k + 1) as f64 / n as f64);
                    let mut q = [V::C(0.0); 6];
                    for j in 0..3 {
                        let (mut x, mut y) = (V::C(0.0), V::C(0.0));
                        for i in 0..4 {
                            let tx = self.mul(V::C(w[j][i]), ctrl[i].0);
                            x = self.add(x, tx);
                            let ty = self.mul(V::C(w[j][i]), ctrl[i].1);
                            y = self.add(y, ty);
                        }
                        q[2 * j] = x;
                        q[2 * j + 1] = y;
                    }
                    // Pin the piece end points to the exact cubic end points.
                    if k == 0 {
                        q[0] = cur.0;
                        q[1] = cur.1;
                    }
                    if k == n - 1 {
                        q[4] = pts[2].0;
                        q[5] = pts[2].1;
                    }
                    self.push_prim(PrimKind::Quad, &q);
                }
            }
            "close" => {
                let pb = self.path.as_mut().expect("in path");
                pb.closed = true;
                let (s, e) = (pb.cur, pb.start);
                if s != e {
                    self.push_prim(PrimKind::Segment, &[s.0, s.1, e.0, e.1]);
                }
                self.path.as_mut().expect("in path").cur = e;
                return Ok(());
            }
            _ => unreachable!(),
        }
        let end = *pts.last().expect("end point");
        self.path.as_mut().expect("in path").cur = end;
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

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
        let e =
            rec("param a in [0, 1] = 0.5;\nif a > 0.2 {\n circle(0.5, 0.5, 0.1);\n}").unwrap_err();
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
        assert!(matches!(e, Error::Limit(_)), "{e:?}");
        assert!(
            e.to_string().contains("line 3") || e.to_string().contains("line 2"),
            "{e}"
        );
        assert!(e.to_string().contains("never end"), "{e}");
        let e = rec("fn f(x) { return f(x + 1); }\nlet y = f(0);").unwrap_err();
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
}
