//! The interpreter: runs a program once, folding everything that does not
//! depend on a float parameter into constants and appending the rest to the
//! tape. Every recursion (blocks, expressions, calls) goes through
//! [`Rec::enter`], so one depth budget bounds the stack.
use super::super::lang::{BinOp, Call, Expr, FnDecl, Pos, Stmt, MAX_DEPTH};
use super::super::tape::{apply, Op, StepFn, Tape};
use super::{Geom, Prim, RecordLimits, Rgb, Shape};
use crate::core::error::Result;
use crate::pattern::lang::Ast;
use std::collections::HashMap;
use std::rc::Rc;

/// A tape value: a known constant or a node.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) enum V {
    C(f64),
    N(u32),
}

#[derive(Debug, Clone)]
pub(super) enum Val {
    Num(V),
    Str(Rc<str>),
}

pub(super) enum Flow {
    Normal,
    Return(Option<Val>, Pos),
}

pub(super) fn is_statement_name(n: &str) -> bool {
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
            | "tile"
            | "move"
            | "quad"
            | "cubic"
            | "close"
    )
}

pub(super) fn builtin_arity(n: &str) -> Option<(usize, usize)> {
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
pub(super) type Named = HashMap<String, (Val, Pos)>;

pub(super) struct Rec<'a> {
    pub(super) fns: HashMap<&'a str, &'a FnDecl>,
    pub(super) tape: Tape,
    pub(super) consts: HashMap<u64, u32>,
    pub(super) globals: HashMap<String, Val>,
    /// Function frames; each is a stack of block scopes.
    pub(super) frames: Vec<Vec<HashMap<String, Val>>>,
    pub(super) ops: u64,
    /// The statement being run (for errors found while emitting primitives).
    pub(super) at: Pos,
    /// Where the active user function calls were made, innermost last.
    pub(super) calls: Vec<(&'a str, Pos)>,
    /// Current nesting (blocks, expressions, calls), see [`RecordLimits::max_depth`].
    pub(super) depth: usize,
    pub(super) limits: RecordLimits,
    pub(super) xf: Vec<Xf>,
    pub(super) bool_sinks: Vec<Vec<Geom>>,
    pub(super) path: Option<PathB>,
    pub(super) prims: Vec<Prim>,
    pub(super) shapes: Vec<Shape>,
    pub(super) colours: Vec<Rgb>,
    /// Range of each float parameter (tape `Param(k)`), for `tile` bounds.
    pub(super) ranges: Vec<(f64, f64)>,
    /// The canvas (`WIDTH`, `HEIGHT`, the copies of `tile`).
    pub(super) canvas: super::Canvas,
}

impl<'a> Rec<'a> {
    pub(super) fn new(ast: &'a Ast, limits: RecordLimits) -> Self {
        Rec {
            fns: ast.fns.iter().map(|f| (f.name.as_str(), f)).collect(),
            tape: Tape::new(),
            consts: HashMap::new(),
            globals: HashMap::new(),
            frames: vec![vec![HashMap::new()]],
            ops: 0,
            at: Pos::default(),
            calls: vec![],
            depth: 0,
            limits,
            xf: vec![Xf::identity()],
            bool_sinks: vec![],
            path: None,
            prims: vec![],
            shapes: vec![],
            colours: vec![[255, 255, 255]],
            ranges: vec![],
            canvas: super::Canvas::SQUARE,
        }
    }

    pub(super) fn tick(&mut self, pos: Pos) -> Result<()> {
        self.ops += 1;
        if self.ops > self.limits.max_ops {
            return Err(pos.limit(format!(
                "the program ran more than {} operations; does a loop or a recursion never end?",
                self.limits.max_ops
            )));
        }
        Ok(())
    }

    /// One level deeper; an error past the depth budget. Pair with `leave`.
    pub(super) fn enter(&mut self, pos: Pos) -> Result<()> {
        let max = self.limits.max_depth.min(MAX_DEPTH);
        if self.depth >= max {
            let inside = match self.calls.last() {
                Some((name, p)) => format!(
                    " ({} active calls; the innermost is '{name}' called at line {}, column {})",
                    self.calls.len(),
                    p.line,
                    p.column
                ),
                None => String::new(),
            };
            return Err(pos.limit(format!(
                "blocks, expressions and function calls nested deeper than {max}{inside}; \
                 does a recursion never end?"
            )));
        }
        self.depth += 1;
        Ok(())
    }

    pub(super) fn leave(&mut self) {
        self.depth -= 1;
    }

    /// A value computed at `pos` must be finite (division by zero, `sqrt` or
    /// `ln` of a negative number, overflow ...). Checked on the record-time
    /// value; during a fit other parameter values can still make a tape node
    /// non-finite, and the loss treats such points as invalid.
    pub(super) fn finite(&self, v: V, pos: Pos, what: &str) -> Result<V> {
        let x = self.value(v);
        if x.is_finite() {
            Ok(v)
        } else {
            Err(pos.err(format!(
                "{what} is {} here (a division by zero, sqrt or ln of a negative number, \
                 or a number too large?); every value must be a finite number",
                if x.is_nan() {
                    "not a number"
                } else {
                    "infinite"
                }
            )))
        }
    }

    // ---- tape values -------------------------------------------------

    pub(super) fn value(&self, v: V) -> f64 {
        match v {
            V::C(c) => c,
            V::N(i) => self.tape.init_value(i),
        }
    }

    pub(super) fn node(&mut self, v: V) -> u32 {
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
    pub(super) fn op(&mut self, args: &[V], make: impl Fn(&[u32]) -> Op) -> V {
        let vals: Vec<f64> = args.iter().map(|&a| self.value(a)).collect();
        let local: Vec<u32> = (0..args.len() as u32).collect();
        let v = apply(make(&local), &vals);
        if args.iter().all(|a| matches!(a, V::C(_))) {
            return V::C(v);
        }
        let ids: Vec<u32> = args.iter().map(|&a| self.node(a)).collect();
        V::N(self.tape.push(make(&ids), v))
    }

    pub(super) fn add(&mut self, a: V, b: V) -> V {
        match (a, b) {
            (V::C(x), y) | (y, V::C(x)) if x == 0.0 => y,
            _ => self.op(&[a, b], |o| Op::Add(o[0], o[1])),
        }
    }
    pub(super) fn sub(&mut self, a: V, b: V) -> V {
        if b == V::C(0.0) {
            return a;
        }
        self.op(&[a, b], |o| Op::Sub(o[0], o[1]))
    }
    pub(super) fn mul(&mut self, a: V, b: V) -> V {
        match (a, b) {
            (V::C(x), y) | (y, V::C(x)) if x == 1.0 => y,
            (V::C(x), _) | (_, V::C(x)) if x == 0.0 => V::C(0.0),
            _ => self.op(&[a, b], |o| Op::Mul(o[0], o[1])),
        }
    }

    // ---- scopes ------------------------------------------------------

    pub(super) fn lookup(&self, name: &str) -> Option<Val> {
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

    pub(super) fn assign(&mut self, name: &str, v: Val, pos: Pos) -> Result<()> {
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

    pub(super) fn block(&mut self, stmts: &[Stmt], same_scope: bool, pos: Pos) -> Result<Flow> {
        self.enter(pos)?;
        let r = self.block_inner(stmts, same_scope);
        self.leave();
        r
    }

    pub(super) fn block_inner(&mut self, stmts: &[Stmt], same_scope: bool) -> Result<Flow> {
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

    pub(super) fn num(&mut self, e: &Expr) -> Result<V> {
        match self.expr(e)? {
            Val::Num(v) => Ok(v),
            Val::Str(s) => Err(e
                .pos()
                .err(format!("expected a number but got the string \"{s}\""))),
        }
    }

    /// A number that must be known at record time (control flow).
    pub(super) fn structural(&mut self, e: &Expr, what: &str) -> Result<f64> {
        match self.num(e)? {
            V::C(c) => Ok(c),
            V::N(_) => Err(e.pos().err(format!(
                "{what} depends on a float parameter; the program's structure may only depend on 'int param's \
                 (use select(cond, a, b), min or max to choose values)"
            ))),
        }
    }

    pub(super) fn stmt(&mut self, s: &Stmt) -> Result<Flow> {
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
                return self.block(if c != 0.0 { a } else { b }, false, *pos);
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
                    let r = self.block(body, true, *pos);
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
            Stmt::Block(b, pos) => return self.block(b, false, *pos),
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

    pub(super) fn expr(&mut self, e: &Expr) -> Result<Val> {
        self.enter(e.pos())?;
        let r = self.expr_inner(e);
        self.leave();
        let v = r?;
        if let Val::Num(x) = v {
            // Binary operators are located at the operator, the rest at their start.
            let (pos, what) = match e {
                Expr::Bin(_, _, _, p) => (*p, "the result of this operation"),
                Expr::Call(c) => (c.pos, "the result of this call"),
                _ => (e.pos(), "this value"),
            };
            self.finite(x, pos, what)?;
        }
        Ok(v)
    }

    pub(super) fn expr_inner(&mut self, e: &Expr) -> Result<Val> {
        self.tick(e.pos())?;
        Ok(match e {
            Expr::Num(v, _) => Val::Num(V::C(*v)),
            Expr::Str(s, _) => Val::Str(Rc::from(s.as_str())),
            Expr::Var(n, pos) => match self.lookup(n) {
                Some(v) => v,
                None => match n.as_str() {
                    "PI" => Val::Num(V::C(std::f64::consts::PI)),
                    "TAU" => Val::Num(V::C(std::f64::consts::TAU)),
                    "WIDTH" => Val::Num(V::C(self.canvas.w)),
                    "HEIGHT" => Val::Num(V::C(self.canvas.h)),
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

    pub(super) fn call(&mut self, c: &Call) -> Result<Val> {
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
            "sqrt" => {
                // The tape's sqrt clamps at 0 (for a derivative everywhere);
                // a negative argument in the program itself is a mistake.
                if self.value(a[0]) < 0.0 {
                    return Err(c
                        .pos
                        .err(format!("sqrt of a negative number ({})", self.value(a[0]))));
                }
                self.op(&a, un(Op::Sqrt))
            }
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

    pub(super) fn user_call(&mut self, f: &'a FnDecl, c: &Call) -> Result<Val> {
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
        let mut scope = HashMap::new();
        for (p, a) in f.params.iter().zip(&c.args) {
            let v = self.expr(&a.value)?;
            scope.insert(p.clone(), v);
        }
        self.frames.push(vec![scope]);
        self.calls.push((f.name.as_str(), c.pos));
        let r = self.block(&f.body, true, c.pos);
        self.calls.pop();
        self.frames.pop();
        Ok(match r? {
            Flow::Return(Some(v), _) => v,
            _ => Val::Num(V::C(0.0)),
        })
    }
}

// The path builder's and the transform's data live here with the rest of
// the recorder's state; their methods are in `path.rs` and `transform.rs`.

/// A path being built.
pub(super) struct PathB {
    pub(super) start: (V, V),
    pub(super) cur: (V, V),
    pub(super) first: u32,
    pub(super) started: bool,
    pub(super) closed: bool,
}

/// The current transform (rotation by `angle`, uniform `scale`, then translation).
#[derive(Clone, Copy)]
pub(super) struct Xf {
    pub(super) cos: V,
    pub(super) sin: V,
    pub(super) angle: V,
    pub(super) scale: V,
    pub(super) tx: V,
    pub(super) ty: V,
}

impl Xf {
    /// No transform.
    pub(super) fn identity() -> Xf {
        Xf {
            cos: V::C(1.0),
            sin: V::C(0.0),
            angle: V::C(0.0),
            scale: V::C(1.0),
            tx: V::C(0.0),
            ty: V::C(0.0),
        }
    }
}
