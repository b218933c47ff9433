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
    Block(Vec<Stmt>),
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
}

/// Parse program text. Errors carry line and column.
pub fn parse(src: &str) -> Result<Ast> {
    let mut p = Parser {
        toks: lex(src)?,
        i: 0,
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
        } else if p.is_ident("background") && matches!(p.toks[p.i + 1].0, Tok::Str(_)) {
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

impl Parser {
    fn pos(&self) -> Pos {
        self.toks[self.i].1
    }
    fn at_eof(&self) -> bool {
        self.toks[self.i].0 == Tok::Eof
    }
    fn next(&mut self) -> (Tok, Pos) {
        let t = self.toks[self.i].clone();
        if t.0 != Tok::Eof {
            self.i += 1;
        }
        t
    }
    fn is_sym(&self, s: &str) -> bool {
        matches!(&self.toks[self.i].0, Tok::Sym(x) if *x == s)
    }
    fn is_ident(&self, s: &str) -> bool {
        matches!(&self.toks[self.i].0, Tok::Ident(x) if x == s)
    }
    fn peek_ident(&self, k: usize, s: &str) -> bool {
        matches!(self.toks.get(self.i + k), Some((Tok::Ident(x), _)) if x == s)
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
        match &self.toks[self.i].0 {
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
        match self.toks[self.i].clone() {
            (Tok::Ident(s), p) => {
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
    fn block(&mut self) -> Result<Vec<Stmt>> {
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
            return Ok(Stmt::Block(self.block()?));
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
        if let Tok::Ident(name) = self.toks[self.i].0.clone() {
            if matches!(self.toks[self.i + 1].0, Tok::Sym("=")) {
                self.i += 2;
                let e = self.expr()?;
                self.expect(";")?;
                return Ok(Stmt::Assign(name, e, pos));
            }
            if matches!(self.toks[self.i + 1].0, Tok::Sym("(")) {
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
        }
        Err(pos.err(format!(
            "expected a statement (let, if, for, return, a call or an assignment) but found {}",
            self.describe()
        )))
    }
    fn if_stmt(&mut self) -> Result<Stmt> {
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
                let named = match (&self.toks[self.i].0, &self.toks[self.i + 1].0) {
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
        'outer: loop {
            for (s, op) in LEVELS[level] {
                if self.is_sym(s) {
                    let pos = self.pos();
                    self.next();
                    let rhs = self.binary(level + 1)?;
                    lhs = Expr::Bin(*op, Box::new(lhs), Box::new(rhs), pos);
                    continue 'outer;
                }
            }
            return Ok(lhs);
        }
    }
    fn unary(&mut self) -> Result<Expr> {
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
            _ => {
                self.i -= 1;
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
}
