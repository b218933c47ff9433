//! The pattern language: lexer and parser (paper §3 "Procedural Vector
//! Patterns": a pattern is an arbitrary program placing shapes).
//!
//! ```text
//! // comments run to the end of the line
//! background "#ffffff";                 // canvas colour (default white)
//! param dx in [0.1, 0.3] = 0.2;         // optimised float parameter
//! int param n in [1, 8] = 5;            // structural, never optimised
//! fn cell(x, y, r) { circle(x, y, r, fill: "#1f77b4"); }
//! for i in 0..n {
//!   for j in 0..n { cell(0.1 + i * dx, 0.1 + j * dx, 0.04); }
//! }
//! translate(0.5, 0.5) { rotate(PI / 4) { rect(0, 0, 0.2, 0.1, radius: 0.02, fill: "#000"); } }
//! path(stroke: "#e00", width: 0.01) { move(0.1, 0.1); quad(0.5, 0.0, 0.9, 0.1); }
//! ```
//!
//! `tile(px, py) { … }` / `tile(px, py, shear) { … }` repeats its block
//! over the canvas on the lattice `(col·px + row·shear, row·py)`, with `row`
//! and `col` defined inside; the copies are those that can touch the canvas
//! for any parameter values in range (see `record::tile`).
//!
//! The canvas is `[0, WIDTH] × [0, HEIGHT]`, y down, its shorter side 1:
//! `[0, 1]²` for a square target, `[0, 1.25] × [0, 1]` for a 300 × 240 one.
//! `WIDTH` and `HEIGHT` (like `PI` and `TAU`) are constants a program can
//! read to place shapes relative to the canvas.
//!
//! Statements: `let x = e;`, `x = e;`, `if c { } else { }`, `for i in a..b { }`,
//! `return e;`, calls (shapes, transforms, user functions) optionally followed
//! by a `{ block }`. Expressions: numbers, strings, `+ - * / %`, `^` (power),
//! comparisons, `&&`, `||`, `!`, calls. Colours are strings `"#rgb"`/`"#rrggbb"`.
use crate::core::error::{Error, Result};

/// A place in the source, 1-based.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Pos {
    pub line: usize,
    pub column: usize,
}

impl Pos {
    /// An error at this place.
    pub fn err(self, message: impl Into<String>) -> Error {
        Error::Syntax {
            line: self.line,
            column: self.column,
            message: message.into(),
        }
    }
    /// A limit met at this place (its line and column travel as data).
    pub fn limit(self, message: impl Into<String>) -> Error {
        Error::limit(message).placed(self.line, self.column)
    }
}

#[derive(Debug, Clone, PartialEq)]
enum Tok {
    Num(f64),
    Str(String),
    Ident(String),
    Sym(&'static str),
    Eof,
}

const SYMS: [&str; 26] = [
    "..", "==", "!=", "<=", ">=", "&&", "||", "+", "-", "*", "/", "%", "^", "<", ">", "!", "=",
    "(", ")", "{", "}", "[", "]", ",", ";", ":",
];

fn lex(src: &str) -> Result<Vec<(Tok, Pos)>> {
    let chars: Vec<char> = src.chars().collect();
    let mut out = vec![];
    let (mut i, mut line, mut col) = (0usize, 1usize, 1usize);
    while i < chars.len() {
        let c = chars[i];
        let pos = Pos { line, column: col };
        if c == '\n' {
            i += 1;
            line += 1;
            col = 1;
            continue;
        }
        if c.is_whitespace() {
            i += 1;
            col += 1;
            continue;
        }
        if c == '/' && chars.get(i + 1) == Some(&'/') {
            while i < chars.len() && chars[i] != '\n' {
                i += 1;
            }
            continue;
        }
        if c.is_ascii_digit() || (c == '.' && chars.get(i + 1).is_some_and(|d| d.is_ascii_digit()))
        {
            let start = i;
            while i < chars.len()
                && (chars[i].is_ascii_digit()
                    || (chars[i] == '.' && chars.get(i + 1) != Some(&'.')))
            {
                i += 1;
            }
            if i < chars.len() && (chars[i] == 'e' || chars[i] == 'E') {
                let save = i;
                i += 1;
                if i < chars.len() && (chars[i] == '+' || chars[i] == '-') {
                    i += 1;
                }
                if i < chars.len() && chars[i].is_ascii_digit() {
                    while i < chars.len() && chars[i].is_ascii_digit() {
                        i += 1;
                    }
                } else {
                    i = save;
                }
            }
            let text: String = chars[start..i].iter().collect();
            let v: f64 = text
                .parse()
                .map_err(|_| pos.err(format!("bad number '{text}'")))?;
            if !v.is_finite() {
                return Err(pos.err(format!(
                    "the number '{text}' is too large; numbers must be finite (at most about 1.8e308)"
                )));
            }
            col += i - start;
            out.push((Tok::Num(v), pos));
            continue;
        }
        if c.is_alphabetic() || c == '_' {
            let start = i;
            while i < chars.len() && (chars[i].is_alphanumeric() || chars[i] == '_') {
                i += 1;
            }
            col += i - start;
            out.push((Tok::Ident(chars[start..i].iter().collect()), pos));
            continue;
        }
        if c == '"' {
            let start = i + 1;
            i += 1;
            while i < chars.len() && chars[i] != '"' && chars[i] != '\n' {
                i += 1;
            }
            if i >= chars.len() || chars[i] != '"' {
                return Err(pos.err("unterminated string: add the closing '\"' on the same line"));
            }
            let s: String = chars[start..i].iter().collect();
            i += 1;
            col += s.chars().count() + 2;
            out.push((Tok::Str(s), pos));
            continue;
        }
        let rest: String = chars[i..(i + 2).min(chars.len())].iter().collect();
        let sym = SYMS.iter().find(|s| rest.starts_with(**s));
        match sym {
            Some(s) => {
                i += s.len();
                col += s.len();
                out.push((Tok::Sym(s), pos));
            }
            None => return Err(pos.err(format!("unexpected character '{c}'"))),
        }
    }
    out.push((Tok::Eof, Pos { line, column: col }));
    Ok(out)
}

/// Binary operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BinOp {
    Add,
    Sub,
    Mul,
    Div,
    Mod,
    Pow,
    Lt,
    Le,
    Gt,
    Ge,
    Eq,
    Ne,
    And,
    Or,
}

/// Expressions.
#[derive(Debug, Clone, PartialEq)]
pub enum Expr {
    Num(f64, Pos),
    Str(String, Pos),
    Var(String, Pos),
    Neg(Box<Expr>, Pos),
    Not(Box<Expr>, Pos),
    Bin(BinOp, Box<Expr>, Box<Expr>, Pos),
    Call(Call),
}

impl Expr {
    /// Where the expression starts.
    pub fn pos(&self) -> Pos {
        match self {
            Expr::Num(_, p)
            | Expr::Str(_, p)
            | Expr::Var(_, p)
            | Expr::Neg(_, p)
            | Expr::Not(_, p) => *p,
            Expr::Bin(_, a, _, _) => a.pos(),
            Expr::Call(c) => c.pos,
        }
    }
}

/// A call argument, positional or `name: value`.
#[derive(Debug, Clone, PartialEq)]
pub struct Arg {
    pub name: Option<String>,
    pub value: Expr,
}

/// A call, with an optional block (`translate(x, y) { ... }`).
#[derive(Debug, Clone, PartialEq)]
pub struct Call {
    pub name: String,
    pub args: Vec<Arg>,
    pub block: Option<Vec<Stmt>>,
    pub pos: Pos,
}

/// Statements.
#[derive(Debug, Clone, PartialEq)]
pub enum Stmt {
    Let(String, Expr, Pos),
    Assign(String, Expr, Pos),
    If(Expr, Vec<Stmt>, Vec<Stmt>, Pos),
    For(String, Expr, Expr, Vec<Stmt>, Pos),
    Return(Option<Expr>, Pos),
    Call(Call),
    /// A `{ ... }` block and where it opens.
    Block(Vec<Stmt>, Pos),
}

/// A declared parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamDecl {
    /// Name used in the program.
    pub name: String,
    /// Lower bound (inclusive).
    pub lo: f64,
    /// Upper bound (inclusive), `> lo`.
    pub hi: f64,
    /// Default value, within `[lo, hi]`.
    pub default: f64,
    /// Integer (structural, never optimised) or float (optimised).
    pub integer: bool,
    /// Where it is declared.
    pub pos: Pos,
}

/// A user function.
#[derive(Debug, Clone, PartialEq)]
pub struct FnDecl {
    pub name: String,
    pub params: Vec<String>,
    pub body: Vec<Stmt>,
    pub pos: Pos,
}

/// A parsed program.
#[derive(Debug, Clone, PartialEq)]
pub struct Ast {
    /// Parameters in declaration order.
    pub params: Vec<ParamDecl>,
    /// User functions.
    pub fns: Vec<FnDecl>,
    /// Top-level statements in order.
    pub body: Vec<Stmt>,
    /// `background "#..."`, if given.
    pub background: Option<(String, Pos)>,
}

struct Parser {
    toks: Vec<(Tok, Pos)>,
    i: usize,
    /// Current nesting (blocks, parentheses, unary operators).
    depth: usize,
}

/// The one nesting budget of the language, shared by the parser and the
/// recorder (see [`crate::pattern::record::RecordLimits::max_depth`]).
///
/// Both recurse: the parser once per nested block, parenthesis, unary
/// operator or chained binary operator, the recorder once per nested block,
/// expression node and function call *while running* (so recursion through
/// user functions adds up the nesting of every active call). Each unit costs
/// a few stack frames, and the release wasm in a browser worker has far less
/// stack than a native thread: V8 stops wasm at about 1 MB of native stack
/// ("RangeError: Maximum call stack size exceeded") and the wasm shadow stack
/// in linear memory is 1 MiB (overflowing it is "memory access out of
/// bounds").
///
/// Measured in Chromium's worker with the release wasm (after `wasm-opt -O3`)
/// and no budget, the deepest program of each kind that still ran was (in
/// units of this budget per level): 477 nested calls `abs(abs(…))`, 603
/// parentheses, 989 nested transforms, 461 levels of plain recursion, 1,110
/// nested `if`s, 106 levels of a recursion through 10 nested blocks each
/// (≈ 1,200 units); before `wasm-opt` the figures were similar (491, 566,
/// 833, 673, 1,233 — there the shadow stack overflowed first —, 118).
/// 160 leaves a safety factor of at least 3 for every kind
/// (`tests/e2e/pattern-depth.test.mjs` runs the deepest programs the budget
/// allows there) while ordinary programs stay far below it: 158 chained
/// operators, 78 levels of plain recursion.
pub const MAX_DEPTH: usize = crate::core::limits::MAX_NESTING;

/// Deepest nesting the parser accepts.
const MAX_NESTING: usize = MAX_DEPTH;

/// Parse program text. Errors carry line and column.
pub fn parse(src: &str) -> Result<Ast> {
    let mut p = Parser {
        toks: lex(src)?,
        i: 0,
        depth: 0,
    };
    let mut ast = Ast {
        params: vec![],
        fns: vec![],
        body: vec![],
        background: None,
    };
    while !p.at_eof() {
        let pos = p.pos();
        if p.is_ident("param") || (p.is_ident("int") && p.peek_ident(1, "param")) {
            let integer = p.is_ident("int");
            if integer {
                p.next();
            }
            p.next();
            let (name, npos) = p.ident()?;
            p.expect_ident("in")?;
            p.expect("[")?;
            let lo = p.const_expr()?;
            p.expect(",")?;
            let hi = p.const_expr()?;
            p.expect("]")?;
            let default = if p.eat("=") {
                p.const_expr()?
            } else {
                0.5 * (lo + hi)
            };
            p.expect(";")?;
            if lo >= hi {
                return Err(npos.err(format!("parameter '{name}': range [{lo}, {hi}] is empty; write [low, high] with low < high")));
            }
            if !(hi - lo).is_finite() {
                return Err(npos.err(format!(
                    "parameter '{name}': range [{lo}, {hi}] is too wide; its width must be a finite number"
                )));
            }
            if !(lo..=hi).contains(&default) {
                return Err(npos.err(format!(
                    "parameter '{name}': default {default} is outside [{lo}, {hi}]"
                )));
            }
            if integer && (lo.fract() != 0.0 || hi.fract() != 0.0 || default.fract() != 0.0) {
                return Err(npos.err(format!(
                    "int parameter '{name}': bounds and default must be whole numbers"
                )));
            }
            if ast.params.iter().any(|q| q.name == name) {
                return Err(npos.err(format!("parameter '{name}' is declared twice")));
            }
            ast.params.push(ParamDecl {
                name,
                lo,
                hi,
                default,
                integer,
                pos,
            });
        } else if p.is_ident("fn") {
            p.next();
            let (name, npos) = p.ident()?;
            p.expect("(")?;
            let mut params = vec![];
            if !p.eat(")") {
                loop {
                    params.push(p.ident()?.0);
                    if p.eat(")") {
                        break;
                    }
                    p.expect(",")?;
                }
            }
            let body = p.block()?;
            if ast.fns.iter().any(|f| f.name == name) {
                return Err(npos.err(format!("function '{name}' is defined twice")));
            }
            ast.fns.push(FnDecl {
                name,
                params,
                body,
                pos: npos,
            });
        } else if p.is_ident("background") && matches!(p.tok(1), Tok::Str(_)) {
            p.next();
            if let (Tok::Str(s), spos) = p.next() {
                ast.background = Some((s, spos));
            }
            p.expect(";")?;
        } else {
            ast.body.push(p.stmt()?);
        }
    }
    Ok(ast)
}

// Every token access goes through `tok`/`pos`, which read past the end as
// the final `Eof` token: a truncated program (`circle(`, `f(1,`) then meets
// "end of program" in an error message instead of an index out of bounds.
impl Parser {
    /// The token `k` places ahead (`Eof` past the end).
    fn tok(&self, k: usize) -> &Tok {
        self.toks
            .get(self.i.saturating_add(k))
            .map_or(&Tok::Eof, |t| &t.0)
    }
    fn pos(&self) -> Pos {
        self.toks
            .get(self.i)
            .or(self.toks.last())
            .map_or(Pos::default(), |t| t.1)
    }
    fn at_eof(&self) -> bool {
        *self.tok(0) == Tok::Eof
    }
    fn next(&mut self) -> (Tok, Pos) {
        let t = (self.tok(0).clone(), self.pos());
        if t.0 != Tok::Eof {
            self.i += 1;
        }
        t
    }
    fn is_sym(&self, s: &str) -> bool {
        matches!(self.tok(0), Tok::Sym(x) if *x == s)
    }
    fn is_ident(&self, s: &str) -> bool {
        matches!(self.tok(0), Tok::Ident(x) if x == s)
    }
    fn peek_ident(&self, k: usize, s: &str) -> bool {
        matches!(self.tok(k), Tok::Ident(x) if x == s)
    }
    fn eat(&mut self, s: &str) -> bool {
        if self.is_sym(s) {
            self.i += 1;
            true
        } else {
            false
        }
    }
    fn describe(&self) -> String {
        match self.tok(0) {
            Tok::Num(v) => format!("number {v}"),
            Tok::Str(s) => format!("string \"{s}\""),
            Tok::Ident(s) => format!("'{s}'"),
            Tok::Sym(s) => format!("'{s}'"),
            Tok::Eof => "end of program".into(),
        }
    }
    fn expect(&mut self, s: &str) -> Result<()> {
        if self.eat(s) {
            Ok(())
        } else {
            Err(self
                .pos()
                .err(format!("expected '{s}' but found {}", self.describe())))
        }
    }
    fn expect_ident(&mut self, s: &str) -> Result<()> {
        if self.is_ident(s) {
            self.i += 1;
            Ok(())
        } else {
            Err(self
                .pos()
                .err(format!("expected '{s}' but found {}", self.describe())))
        }
    }
    fn ident(&mut self) -> Result<(String, Pos)> {
        match self.tok(0).clone() {
            Tok::Ident(s) => {
                let p = self.pos();
                self.i += 1;
                Ok((s, p))
            }
            _ => Err(self
                .pos()
                .err(format!("expected a name but found {}", self.describe()))),
        }
    }
    /// Literal numbers with unary minus, `PI`, and `* /` between them.
    fn const_expr(&mut self) -> Result<f64> {
        let pos = self.pos();
        let e = self.expr()?;
        fn ev(e: &Expr) -> Option<f64> {
            match e {
                Expr::Num(v, _) => Some(*v),
                Expr::Neg(a, _) => ev(a).map(|v| -v),
                Expr::Var(n, _) if n == "PI" => Some(std::f64::consts::PI),
                Expr::Var(n, _) if n == "TAU" => Some(std::f64::consts::TAU),
                Expr::Bin(op, a, b, _) => {
                    let (a, b) = (ev(a)?, ev(b)?);
                    Some(match op {
                        BinOp::Add => a + b,
                        BinOp::Sub => a - b,
                        BinOp::Mul => a * b,
                        BinOp::Div => a / b,
                        _ => return None,
                    })
                }
                _ => None,
            }
        }
        ev(&e)
            .filter(|v| v.is_finite())
            .ok_or_else(|| pos.err("expected a constant number here (literals, PI, + - * /)"))
    }
    fn enter(&mut self) -> Result<()> {
        self.depth += 1;
        if self.depth > MAX_NESTING {
            return Err(self.pos().err(format!(
                "nested more than {MAX_NESTING} levels deep (blocks, calls, brackets and \
                     each operator of a chain such as a + b + c count as levels; split a long \
                     chain with let)"
            )));
        }
        Ok(())
    }

    fn block(&mut self) -> Result<Vec<Stmt>> {
        self.enter()?;
        let r = self.block_inner();
        self.depth -= 1;
        r
    }

    fn block_inner(&mut self) -> Result<Vec<Stmt>> {
        self.expect("{")?;
        let mut v = vec![];
        while !self.eat("}") {
            if self.at_eof() {
                return Err(self.pos().err("missing '}' at end of block"));
            }
            v.push(self.stmt()?);
        }
        Ok(v)
    }
    fn stmt(&mut self) -> Result<Stmt> {
        let pos = self.pos();
        if self.is_sym("{") {
            return Ok(Stmt::Block(self.block()?, pos));
        }
        if self.is_ident("let") {
            self.next();
            let (name, _) = self.ident()?;
            self.expect("=")?;
            let e = self.expr()?;
            self.expect(";")?;
            return Ok(Stmt::Let(name, e, pos));
        }
        if self.is_ident("if") {
            return self.if_stmt();
        }
        if self.is_ident("for") {
            self.next();
            let (var, _) = self.ident()?;
            self.expect_ident("in")?;
            let a = self.expr()?;
            self.expect("..")?;
            let b = self.expr()?;
            let body = self.block()?;
            return Ok(Stmt::For(var, a, b, body, pos));
        }
        if self.is_ident("return") {
            self.next();
            if self.eat(";") {
                return Ok(Stmt::Return(None, pos));
            }
            let e = self.expr()?;
            self.expect(";")?;
            return Ok(Stmt::Return(Some(e), pos));
        }
        if let Tok::Ident(name) = self.tok(0).clone() {
            if matches!(self.tok(1), Tok::Sym("=")) {
                self.i += 2;
                let e = self.expr()?;
                self.expect(";")?;
                return Ok(Stmt::Assign(name, e, pos));
            }
            if matches!(self.tok(1), Tok::Sym("(")) {
                self.i += 1;
                let mut call = self.call_args(name, pos)?;
                if self.is_sym("{") {
                    call.block = Some(self.block()?);
                    self.eat(";");
                } else {
                    self.expect(";")?;
                }
                return Ok(Stmt::Call(call));
            }
            // `union { … }`: a block call without its argument list. Say the fix.
            if matches!(self.tok(1), Tok::Sym("{")) {
                return Err(pos.err(format!(
                    "`{name}` needs its argument list before the block: write `{name}() {{ … }}` \
                     (or `{name}(fill: \"#000000\") {{ … }}` with arguments)"
                )));
            }
        }
        Err(pos.err(format!(
            "expected a statement (let, if, for, return, a call or an assignment) but found {}",
            self.describe()
        )))
    }
    fn if_stmt(&mut self) -> Result<Stmt> {
        self.enter()?;
        let r = self.if_inner();
        self.depth -= 1;
        r
    }

    fn if_inner(&mut self) -> Result<Stmt> {
        let pos = self.pos();
        self.next();
        let c = self.expr()?;
        let then = self.block()?;
        let els = if self.is_ident("else") {
            self.next();
            if self.is_ident("if") {
                vec![self.if_stmt()?]
            } else {
                self.block()?
            }
        } else {
            vec![]
        };
        Ok(Stmt::If(c, then, els, pos))
    }
    fn call_args(&mut self, name: String, pos: Pos) -> Result<Call> {
        self.expect("(")?;
        let mut args = vec![];
        if !self.eat(")") {
            loop {
                let named = match (self.tok(0), self.tok(1)) {
                    (Tok::Ident(n), Tok::Sym(":")) => Some(n.clone()),
                    _ => None,
                };
                if named.is_some() {
                    self.i += 2;
                }
                let value = self.expr()?;
                args.push(Arg { name: named, value });
                if self.eat(")") {
                    break;
                }
                self.expect(",")?;
            }
        }
        Ok(Call {
            name,
            args,
            block: None,
            pos,
        })
    }
    fn expr(&mut self) -> Result<Expr> {
        self.binary(0)
    }
    fn binary(&mut self, level: usize) -> Result<Expr> {
        const LEVELS: [&[(&str, BinOp)]; 5] = [
            &[("||", BinOp::Or)],
            &[("&&", BinOp::And)],
            &[
                ("==", BinOp::Eq),
                ("!=", BinOp::Ne),
                ("<=", BinOp::Le),
                (">=", BinOp::Ge),
                ("<", BinOp::Lt),
                (">", BinOp::Gt),
            ],
            &[("+", BinOp::Add), ("-", BinOp::Sub)],
            &[("*", BinOp::Mul), ("/", BinOp::Div), ("%", BinOp::Mod)],
        ];
        if level == LEVELS.len() {
            return self.unary();
        }
        let mut lhs = self.binary(level + 1)?;
        // Each operator of a chain nests the tree one level deeper (`a+b+c`
        // is `(a+b)+c`), so it counts against the nesting limit.
        let start = self.depth;
        let r = 'outer: loop {
            for (s, op) in LEVELS[level] {
                if self.is_sym(s) {
                    let pos = self.pos();
                    self.next();
                    if let Err(e) = self.enter() {
                        break 'outer Err(e);
                    }
                    let rhs = match self.binary(level + 1) {
                        Ok(r) => r,
                        Err(e) => break 'outer Err(e),
                    };
                    lhs = Expr::Bin(*op, Box::new(lhs), Box::new(rhs), pos);
                    continue 'outer;
                }
            }
            break Ok(lhs);
        };
        self.depth = start;
        r
    }
    fn unary(&mut self) -> Result<Expr> {
        self.enter()?;
        let r = self.unary_inner();
        self.depth -= 1;
        r
    }

    fn unary_inner(&mut self) -> Result<Expr> {
        let pos = self.pos();
        if self.eat("-") {
            return Ok(Expr::Neg(Box::new(self.unary()?), pos));
        }
        if self.eat("!") {
            return Ok(Expr::Not(Box::new(self.unary()?), pos));
        }
        let base = self.primary()?;
        if self.is_sym("^") {
            let p = self.pos();
            self.next();
            let e = self.unary()?; // right-associative
            return Ok(Expr::Bin(BinOp::Pow, Box::new(base), Box::new(e), p));
        }
        Ok(base)
    }
    fn primary(&mut self) -> Result<Expr> {
        let pos = self.pos();
        if self.at_eof() {
            return Err(pos.err("expected a value but the program ended"));
        }
        match self.next() {
            (Tok::Num(v), _) => Ok(Expr::Num(v, pos)),
            (Tok::Str(s), _) => Ok(Expr::Str(s, pos)),
            (Tok::Ident(n), _) => {
                if self.is_sym("(") {
                    Ok(Expr::Call(self.call_args(n, pos)?))
                } else if n == "true" || n == "false" {
                    Ok(Expr::Num(if n == "true" { 1.0 } else { 0.0 }, pos))
                } else {
                    Ok(Expr::Var(n, pos))
                }
            }
            (Tok::Sym("("), _) => {
                let e = self.expr()?;
                self.expect(")")?;
                Ok(e)
            }
            (t, _) => {
                // `next` consumed it (it is not `Eof`): step back to describe it.
                self.i = self.i.saturating_sub(1);
                debug_assert_eq!(*self.tok(0), t);
                Err(pos.err(format!("expected a value but found {}", self.describe())))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_params_functions_and_statements() {
        let ast = parse(
            "param a in [0, 1] = 0.25;\nint param n in [1, 4] = 2;\nfn f(x) { return x * 2; }\n\
             for i in 0..n { if i > 0 { circle(f(i), a, 0.1, fill: \"#f00\"); } else { let z = -a ^ 2; } }",
        )
        .unwrap();
        assert_eq!(ast.params.len(), 2);
        assert!(ast.params[1].integer);
        assert_eq!(ast.params[0].default, 0.25);
        assert_eq!(ast.fns[0].params, vec!["x".to_string()]);
        assert_eq!(ast.body.len(), 1);
    }

    #[test]
    fn a_block_call_without_parentheses_gets_the_fix_suggested() {
        for name in ["union", "path", "translate"] {
            let e = parse(&format!(
                "param a in [0, 1] = 0.5;\n{name} {{\n  circle(a, a, 0.1);\n}}"
            ))
            .unwrap_err();
            let msg = e.to_string();
            assert!(msg.contains(&format!("write `{name}() {{ … }}`")), "{msg}");
            assert!(msg.contains("line 2, column 1"), "{msg}");
        }
    }

    #[test]
    fn deep_nesting_is_an_error_not_a_crash() {
        let src = format!("let a = {}1{};", "(".repeat(100_000), ")".repeat(100_000));
        let e = parse(&src).unwrap_err();
        assert!(e.to_string().contains("nested more than"), "{e}");
        let src = format!("let a = {}1;", "-".repeat(100_000));
        assert!(parse(&src).is_err());
        let src = format!("{}{}", "{".repeat(100_000), "}".repeat(100_000));
        assert!(parse(&src).is_err());
        let src = format!("let a = 1{};", " + 1".repeat(100_000));
        assert!(parse(&src)
            .unwrap_err()
            .to_string()
            .contains("nested more than"));
        let src = format!("if 1 {{ }}{}", " else if 1 { }".repeat(100_000));
        assert!(parse(&src).is_err());
        // Ordinary programs are far from the limit.
        parse(&format!("let a = 1{};", " + 1".repeat(150))).unwrap();
    }

    #[test]
    fn syntax_errors_have_line_and_column() {
        let e = parse("let a = 1;\nlet b = (2 + ;\n").unwrap_err();
        assert_eq!(
            e,
            Error::Syntax {
                line: 2,
                column: 14,
                message: "expected a value but found ';'".into()
            }
        );
        let e = parse("param a in [1, 0];").unwrap_err();
        assert!(
            matches!(
                e,
                Error::Syntax {
                    line: 1,
                    column: 7,
                    ..
                }
            ),
            "{e:?}"
        );
        let e = parse("circle(0.5, 0.5, 0.1)\ncircle(1,1,1);").unwrap_err();
        assert!(
            matches!(
                e,
                Error::Syntax {
                    line: 2,
                    column: 1,
                    ..
                }
            ),
            "{e:?}"
        );
        let e = parse("let s = \"abc;\n").unwrap_err();
        assert!(e.to_string().contains("unterminated string"), "{e}");
    }

    /// Every prefix of a program (as a user typing it produces) parses to a
    /// value or an error, never a panic.
    #[test]
    fn truncated_programs_are_errors_not_panics() {
        let mut sources: Vec<&str> = crate::pattern::generators::GENERATORS
            .iter()
            .map(|g| g.source)
            .collect();
        let extra = "background \"#fff\";\nparam a in [-PI, 2 * PI] = 0;\nint param n in [1, 4] = 2;\n\
                     fn f(x, y) { if x > 0 && !(y < 1) || x == 2 { return -x ^ 2 % 3; } else if y { return f(x - 1, y); } }\n\
                     for i in 0..n { translate(i, a) { circle(f(i, 1), .5e-1, 1.5E+1, fill: rgb(1, 2, 3)); } }\n\
                     path(stroke: \"#e00\") { move(0, 0); quad(1, 0, 1, 1); close(); }\n";
        sources.push(extra);
        for src in sources {
            for (end, _) in src.char_indices() {
                let _ = parse(&src[..end]);
            }
            parse(src).unwrap();
        }
        for src in [
            "circle(",
            "f(1,",
            "f(1, ",
            "circle(x:",
            "let a = ",
            "let a = (1",
            "param a in [",
            "param a in [0, 1] =",
            "int param",
            "fn f(",
            "fn f(x,",
            "fn f(x) {",
            "background \"#fff\"",
            "if 1 { } else",
            "for i in 0..",
            "translate(0, 0) {",
            "a =",
            "return",
        ] {
            let e = parse(src).expect_err(src);
            assert!(matches!(e, Error::Syntax { .. }), "{src}: {e:?}");
            assert!(
                e.to_string().contains("end of program")
                    || e.to_string().contains("ended")
                    || e.to_string().contains("missing '}'"),
                "{src}: {e}"
            );
        }
    }

    #[test]
    fn numbers_and_ranges_must_be_finite() {
        let e = parse("let a = 1e999;").unwrap_err();
        assert!(
            matches!(
                e,
                Error::Syntax {
                    line: 1,
                    column: 9,
                    ..
                }
            ) && e.to_string().contains("1e999"),
            "{e:?}"
        );
        let e = parse("param a in [-1e308, 1e308];").unwrap_err();
        assert!(
            matches!(
                e,
                Error::Syntax {
                    line: 1,
                    column: 7,
                    ..
                }
            ) && e.to_string().contains("'a'")
                && e.to_string().contains("finite"),
            "{e:?}"
        );
        let e = parse("param b in [0, 1e308 * 10];").unwrap_err();
        assert!(e.to_string().contains("constant number"), "{e}");
        let e = parse("param c in [1, 1];").unwrap_err();
        assert!(e.to_string().contains("'c'"), "{e}");
        parse("param d in [-1e300, 1e300];").unwrap();
    }
}
