//! The grammar text (paper §3 "Tangle grammar", the operators of §4 and the
//! grammar of Fig. 9; spec T2), parsed into an [`ast::Grammar`].
//!
//! ```text
//! # comments start with '#' or '//' and run to the end of the line
//! curve teeth = zigzag(6, 20)                  // named curves, for splits
//! shape leaf = polyline(0 0, 1 2, 0 4, -1 2)   // named shapes, for place
//! start rect(800, 600) : big_poly              // start shapes (optional)
//! outline(25) : big_poly -> [in, out]
//! regularSplit(teeth, [20, 40], dual = 1) : in -> quads
//! place(20, 25, leaf) : out → [blob, rem]
//! ```
//!
//! One statement a line: a rule `operator(params) : tag -> [tags]` (`→`
//! works for `->`; one output tag may be written bare), a definition
//! `curve NAME = ...` / `shape NAME = ...` (used before or after it is
//! defined), or a start shape `start rect(w, h) : tag`. Parameters are
//! positional or `name = value`; names are those of [`Op::params`] plus
//! `curve`, `shape`, `kind` and `offsets`. Numbers are JSON-like decimals
//! (`-12.5e3`; a leading `+` is allowed) and must be finite. Tags and names
//! are one word `[A-Za-z_][A-Za-z0-9_]*`.
//!
//! Every error is [`Error::Syntax`] at the 1-based line and column (in
//! characters) of the offending token, with a hint; only a text over
//! [`MAX_TEXT_BYTES`] is an [`Error::Limit`]. Syntax errors are found line
//! by line; names of curves and shapes are checked after the whole text.
//!
//! The language is flat: a line is split into tokens and read left to right
//! by loops, with no recursion at all, so no input can exhaust the stack;
//! every size is bounded by the constants below.
use super::ast::{
    CurveDef, Def, DefKind, Grammar, Op, Rule, Start, StartShape, StippleKind, StreamKind,
    MIN_LENGTH,
};
use crate::core::error::{Error, Result};
use glam::DVec2;
use std::collections::HashMap;
use std::fmt::Write as _;

/// Longest grammar text, in bytes.
pub const MAX_TEXT_BYTES: usize = 256 * 1024;
/// Most rules in one grammar.
pub const MAX_RULES: usize = 2_000;
/// Most points of one `polyline(...)` or `polygon(...)`.
pub const MAX_POLYLINE_POINTS: usize = 10_000;
/// Largest length or coordinate, in drawing units (the paper's drawings are
/// 7 to 22 inches across; anything this large is a typo).
pub const MAX_LENGTH: f64 = 1e6;
/// Most offsets in one split's list (the names `offset` .. `offset8` of
/// [`Op::params`]).
pub const MAX_OFFSETS: usize = 8;
/// Largest `k` of `regroup(k)`.
pub const MAX_REGROUP_K: u32 = 1_000_000;
/// Most sides of an `ngon(n)` shape.
pub const MAX_NGON_SIDES: u32 = 1_000;
/// Most characters of a `start text("...")` word.
pub const MAX_START_TEXT_CHARS: usize = 64;
/// Largest `|bulge|` of `arc(bulge)` (height over width).
pub const MAX_BULGE: f64 = 1.0;

/// The built-in curve (for splits) and shape (for placement).
const BUILTIN_CURVE: &str = "line";
const BUILTIN_SHAPE: &str = "circle";

/// Parse a grammar text. Errors are [`Error::Syntax`] with the line and
/// column of the offending token, or [`Error::Limit`] for a text over
/// [`MAX_TEXT_BYTES`].
pub fn parse(text: &str) -> Result<Grammar> {
    if text.len() > MAX_TEXT_BYTES {
        return Err(Error::limit(format!(
            "the grammar is {} bytes; grammars may be at most {MAX_TEXT_BYTES} bytes (MAX_TEXT_BYTES)",
            text.len()
        )));
    }
    let mut p = Parser::default();
    for (i, line) in text.split('\n').enumerate() {
        let toks = lex_line(line, i + 1)?;
        if toks.is_empty() {
            continue;
        }
        check_brackets(&toks, i + 1)?;
        let mut cur = Cursor {
            toks: &toks,
            i: 0,
            line: i + 1,
        };
        p.statement(&mut cur)?;
    }
    p.finish()
}

/// The grammar as text that [`parse`] reads back to the same grammar (up
/// to the recorded lines and columns): definitions, start shapes, rules.
pub fn to_text(g: &Grammar) -> String {
    let mut s = String::new();
    for d in &g.defs {
        let kw = match d.kind {
            DefKind::Curve => "curve",
            DefKind::Shape => "shape",
        };
        let _ = writeln!(s, "{kw} {} = {}", d.name, curve_text(&d.curve));
    }
    for st in &g.start {
        let shape = match &st.shape {
            StartShape::Rect { width, height } => format!("rect({width}, {height})"),
            StartShape::Circle { radius } => format!("circle({radius})"),
            StartShape::Polygon(p) => format!("polygon({})", points_text(p)),
            StartShape::Svg(d) => format!("svg({})", quote(d)),
            StartShape::Text(t) => format!("text({})", quote(t)),
        };
        let _ = writeln!(s, "start {shape} : {}", st.tag);
    }
    for r in &g.rules {
        let args = match &r.op {
            Op::Ungroup | Op::Invert => String::new(),
            Op::Regroup { k } => k.to_string(),
            Op::Split {
                curve,
                offsets,
                dual,
            } => {
                let o: Vec<String> = offsets.iter().map(|o| o.to_string()).collect();
                format!("{curve}, [{}], {}", o.join(", "), *dual as u8)
            }
            Op::Outline { distance } => distance.to_string(),
            Op::Streamline { kind, offset } => format!("{}, {offset}", stream_name(*kind)),
            Op::Place {
                size,
                distance,
                shape,
            } => format!("{size}, {distance}, {shape}"),
            Op::Fill { tone } => tone.to_string(),
            Op::Stipple {
                kind,
                spacing,
                size,
            } => format!("{}, {spacing}, {size}", stipple_name(*kind)),
        };
        let _ = writeln!(
            s,
            "{}({args}) : {} -> [{}]",
            r.op.name(),
            r.tag,
            r.outputs.join(", ")
        );
    }
    s
}

fn curve_text(c: &CurveDef) -> String {
    match c {
        CurveDef::Line => "line".into(),
        CurveDef::Zigzag { amplitude, period } => format!("zigzag({amplitude}, {period})"),
        CurveDef::Wave { amplitude, period } => format!("wave({amplitude}, {period})"),
        CurveDef::Arc { bulge } => format!("arc({bulge})"),
        CurveDef::Polyline(p) => format!("polyline({})", points_text(p)),
        CurveDef::Svg(d) => format!("svg({})", quote(d)),
        CurveDef::Circle => "circle".into(),
        CurveDef::Ngon(n) => format!("ngon({n})"),
    }
}

fn points_text(p: &[DVec2]) -> String {
    let v: Vec<String> = p.iter().map(|p| format!("{} {}", p.x, p.y)).collect();
    v.join(", ")
}

fn quote(s: &str) -> String {
    format!("\"{}\"", s.replace('\\', "\\\\").replace('"', "\\\""))
}

fn stream_name(k: StreamKind) -> &'static str {
    match k {
        StreamKind::Smooth => "smooth",
        StreamKind::Strip => "strip",
        StreamKind::Circular => "circular",
    }
}

fn stipple_name(k: StippleKind) -> &'static str {
    match k {
        StippleKind::Dots => "dots",
        StippleKind::Dashes => "dashes",
        StippleKind::Curves => "curves",
    }
}

// ---------------------------------------------------------------- lexer

#[derive(Debug, Clone, PartialEq)]
enum Tok<'a> {
    Ident(&'a str),
    Num(f64),
    /// The decoded string and its raw text between the quotes (whose
    /// characters are columns `col + 1 ..`).
    Str(String, &'a str),
    /// One of `( ) [ ] , : =`.
    Sym(char),
    /// `->` or `→`.
    Arrow,
}

#[derive(Debug, Clone)]
struct Token<'a> {
    tok: Tok<'a>,
    /// 1-based column of the first character.
    col: usize,
    /// Width in characters.
    width: usize,
}

fn syntax(line: usize, column: usize, message: impl Into<String>) -> Error {
    Error::Syntax {
        line,
        column,
        message: message.into(),
    }
}

fn is_name_start(c: char) -> bool {
    c.is_ascii_alphabetic() || c == '_'
}

fn is_name_char(c: char) -> bool {
    c.is_ascii_alphanumeric() || c == '_'
}

/// The tokens of one line (comments dropped). Columns count characters.
fn lex_line(text: &str, line: usize) -> Result<Vec<Token<'_>>> {
    let chars: Vec<(usize, char)> = text.char_indices().collect();
    let byte = |i: usize| chars.get(i).map_or(text.len(), |c| c.0);
    let at = |i: usize| chars.get(i).map(|c| c.1);
    let mut toks = vec![];
    let mut i = 0;
    while let Some(c) = at(i) {
        let col = i + 1;
        let next = at(i + 1);
        let start = i;
        let tok = match c {
            '#' => break,
            '/' if next == Some('/') => break,
            c if c.is_whitespace() => {
                i += 1;
                continue;
            }
            '"' => {
                i += 1;
                let mut s = String::new();
                loop {
                    match at(i) {
                        None => {
                            return Err(syntax(
                                line,
                                col,
                                "this string is not closed: add '\"' before the end of the line",
                            ))
                        }
                        Some('"') => break,
                        Some('\\') => match at(i + 1) {
                            Some(e @ ('"' | '\\')) => {
                                s.push(e);
                                i += 2;
                            }
                            _ => {
                                return Err(syntax(
                                    line,
                                    i + 1,
                                    "unknown escape in a string: only \\\" and \\\\ are allowed",
                                ))
                            }
                        },
                        Some(c) => {
                            s.push(c);
                            i += 1;
                        }
                    }
                }
                i += 1;
                Tok::Str(s, &text[byte(start + 1)..byte(i - 1)])
            }
            '0'..='9' | '+' | '-' | '.'
                if c.is_ascii_digit() || next.is_some_and(|n| n.is_ascii_digit() || n == '.') =>
            {
                i = lex_number(&chars, i, line)?;
                let s = &text[byte(start)..byte(i)];
                let v: f64 = s
                    .parse()
                    .map_err(|_| syntax(line, col, format!("'{}' is not a number", shown(s))))?;
                if !v.is_finite() {
                    return Err(syntax(
                        line,
                        col,
                        format!("the number '{}' is too large: numbers must be finite", shown(s)),
                    ));
                }
                Tok::Num(v)
            }
            '-' if next == Some('>') => {
                i += 2;
                Tok::Arrow
            }
            '→' => {
                i += 1;
                Tok::Arrow
            }
            '(' | ')' | '[' | ']' | ',' | ':' | '=' => {
                i += 1;
                Tok::Sym(c)
            }
            c if is_name_start(c) => {
                while at(i).is_some_and(is_name_char) {
                    i += 1;
                }
                if let Some(c) = at(i).filter(|c| c.is_alphanumeric()) {
                    return Err(syntax(
                        line,
                        i + 1,
                        format!("names use only the letters A-Z and a-z, digits and '_'; '{c}' is not one of them"),
                    ));
                }
                Tok::Ident(&text[byte(start)..byte(i)])
            }
            '-' => {
                return Err(syntax(
                    line,
                    col,
                    "unexpected '-': the arrow is written '->' (or '→'), a negative number '-3'",
                ))
            }
            c if c.is_alphanumeric() => {
                return Err(syntax(
                    line,
                    col,
                    format!("names use only the letters A-Z and a-z, digits and '_'; '{c}' is not one of them"),
                ))
            }
            c => {
                return Err(syntax(
                    line,
                    col,
                    format!("unexpected character '{c}'"),
                ))
            }
        };
        toks.push(Token {
            tok,
            col,
            width: i - start,
        });
    }
    Ok(toks)
}

/// The end (exclusive char index) of the number starting at `i`:
/// `[+-]? digits ('.' digits)? ([eE] [+-]? digits)?`.
fn lex_number(chars: &[(usize, char)], mut i: usize, line: usize) -> Result<usize> {
    let at = |i: usize| chars.get(i).map(|c| c.1);
    let digit = |i: usize| at(i).is_some_and(|c| c.is_ascii_digit());
    let start = i;
    let word_end = |mut j: usize| {
        while at(j).is_some_and(|c| is_name_char(c) || c == '.' || c == '+' || c == '-') {
            j += 1;
        }
        shown(&chars[start..j].iter().map(|c| c.1).collect::<String>())
    };
    if matches!(at(i), Some('+' | '-')) {
        i += 1;
    }
    if !digit(i) {
        let sign = if at(start) == Some('-') { "-" } else { "" };
        return Err(syntax(
            line,
            start + 1,
            format!(
                "a number starts with a digit: write {sign}0.5, not {}",
                word_end(start)
            ),
        ));
    }
    while digit(i) {
        i += 1;
    }
    if at(i) == Some('.') {
        i += 1;
        if !digit(i) {
            return Err(syntax(
                line,
                start + 1,
                format!(
                    "'{}' needs digits after the decimal point: write {}0",
                    word_end(start),
                    shown(&chars[start..i].iter().map(|c| c.1).collect::<String>())
                ),
            ));
        }
        while digit(i) {
            i += 1;
        }
    }
    if matches!(at(i), Some('e' | 'E')) {
        i += 1;
        if matches!(at(i), Some('+' | '-')) {
            i += 1;
        }
        if !digit(i) {
            return Err(syntax(
                line,
                start + 1,
                format!(
                    "'{}' is not a number: an exponent needs digits, as in 1e3",
                    word_end(start)
                ),
            ));
        }
        while digit(i) {
            i += 1;
        }
    }
    if at(i).is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '.') {
        return Err(syntax(
            line,
            start + 1,
            format!(
                "'{}' is not a number: a number is digits with an optional '.' and exponent, as in 12.5 or 1e3",
                word_end(start)
            ),
        ));
    }
    Ok(i)
}

/// Every `(` and `[` of the line is closed by its own kind, on the line.
fn check_brackets(toks: &[Token], line: usize) -> Result<()> {
    let mut open: Vec<(char, usize)> = vec![];
    for t in toks {
        match t.tok {
            Tok::Sym(c @ ('(' | '[')) => open.push((c, t.col)),
            Tok::Sym(c @ (')' | ']')) => {
                let want = if c == ')' { '(' } else { '[' };
                match open.pop() {
                    Some((o, _)) if o == want => {}
                    Some((o, ocol)) => {
                        let close = if o == '(' { ')' } else { ']' };
                        return Err(syntax(
                            line,
                            t.col,
                            format!("'{c}' does not close the '{o}' at column {ocol}: write '{close}' first"),
                        ));
                    }
                    None => {
                        return Err(syntax(
                            line,
                            t.col,
                            format!("'{c}' has no '{want}' before it"),
                        ))
                    }
                }
            }
            _ => {}
        }
    }
    if let Some((o, ocol)) = open.pop() {
        let close = if o == '(' { ')' } else { ']' };
        return Err(syntax(
            line,
            ocol,
            format!("this '{o}' is not closed: add '{close}' before the end of the line (one statement a line)"),
        ));
    }
    Ok(())
}

// --------------------------------------------------------------- parser

/// Reads one line's tokens left to right.
struct Cursor<'t, 'a> {
    toks: &'t [Token<'a>],
    i: usize,
    line: usize,
}

impl<'t, 'a> Cursor<'t, 'a> {
    fn peek(&self) -> Option<&'t Token<'a>> {
        self.toks.get(self.i)
    }
    fn peek_tok(&self) -> Option<&'t Tok<'a>> {
        self.peek().map(|t| &t.tok)
    }
    fn next(&mut self) -> Option<&'t Token<'a>> {
        let t = self.toks.get(self.i);
        self.i += t.is_some() as usize;
        t
    }
    /// Column of the current token, or just after the last one.
    fn col(&self) -> usize {
        match self.peek() {
            Some(t) => t.col,
            None => self.toks.last().map_or(1, |t| t.col + t.width),
        }
    }
    fn err(&self, message: impl Into<String>) -> Error {
        syntax(self.line, self.col(), message)
    }
    fn err_at(&self, col: usize, message: impl Into<String>) -> Error {
        syntax(self.line, col, message)
    }
    fn eat(&mut self, c: char) -> bool {
        if self.peek_tok() == Some(&Tok::Sym(c)) {
            self.i += 1;
            true
        } else {
            false
        }
    }
    /// What the current token is, for "found ..." in messages.
    fn found(&self) -> String {
        match self.peek_tok() {
            None => "the end of the line".into(),
            Some(Tok::Ident(n)) => format!("'{}'", shown(n)),
            Some(Tok::Num(v)) => format!("the number {v}"),
            Some(Tok::Str(..)) => "a string".into(),
            Some(Tok::Sym(c)) => format!("'{c}'"),
            Some(Tok::Arrow) => "'->'".into(),
        }
    }
    fn ident(&mut self) -> Option<(&'a str, usize)> {
        match self.peek() {
            Some(Token {
                tok: Tok::Ident(n),
                col,
                ..
            }) => {
                self.i += 1;
                Some((n, *col))
            }
            _ => None,
        }
    }
    /// The line must end here.
    fn end(&self, what: &str) -> Result<()> {
        match self.peek() {
            None => Ok(()),
            Some(_) => Err(self.err(format!(
                "unexpected {} after {what}: one statement a line",
                self.found()
            ))),
        }
    }
}

/// A parameter value as written.
#[derive(Debug, Clone)]
enum Val<'a> {
    /// One or more numbers separated by spaces (`25`, or a point `3 4`).
    Nums(Vec<f64>),
    Name(&'a str),
    Str(String, &'a str),
    /// `[a, b, ...]`: numbers with their columns.
    List(Vec<(f64, usize)>),
}

#[derive(Debug, Clone)]
struct Arg<'a> {
    /// `name =` and the name's column.
    key: Option<(&'a str, usize)>,
    val: Val<'a>,
    /// Column of the value.
    col: usize,
}

/// A call's parameters and the column of its `)`.
struct Args<'a> {
    list: Vec<Arg<'a>>,
    close: usize,
}

/// One parameter slot of an operator or constructor: the names it goes by
/// as a keyword (the first is its name).
type Slot = &'static [&'static str];

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum OpKind {
    Ungroup,
    Regroup,
    Split,
    Outline,
    Streamline,
    Place,
    Fill,
    Stipple,
    Invert,
}

/// Operator names as written, aliases included.
const OPERATORS: [(&str, OpKind); 13] = [
    ("ungroup", OpKind::Ungroup),
    ("regroup", OpKind::Regroup),
    ("regularSplit", OpKind::Split),
    ("split", OpKind::Split),
    ("outline", OpKind::Outline),
    ("streamlineSplit", OpKind::Streamline),
    ("streamline", OpKind::Streamline),
    ("place", OpKind::Place),
    ("fill", OpKind::Fill),
    ("stippling", OpKind::Stipple),
    ("stipple", OpKind::Stipple),
    ("stipling", OpKind::Stipple),
    ("invert", OpKind::Invert),
];

const OPERATOR_LIST: &str =
    "ungroup, regroup, regularSplit, outline, streamlineSplit, place, fill, stippling, invert";

impl OpKind {
    fn name(self) -> &'static str {
        match self {
            OpKind::Ungroup => "ungroup",
            OpKind::Regroup => "regroup",
            OpKind::Split => "regularSplit",
            OpKind::Outline => "outline",
            OpKind::Streamline => "streamlineSplit",
            OpKind::Place => "place",
            OpKind::Fill => "fill",
            OpKind::Stipple => "stippling",
            OpKind::Invert => "invert",
        }
    }
    /// What the operator takes, with an example.
    fn usage(self) -> &'static str {
        match self {
            OpKind::Ungroup => "ungroup takes no parameters: ungroup()",
            OpKind::Regroup => "regroup takes one whole number k >= 1: regroup(2)",
            OpKind::Split => "regularSplit takes a curve, an offset or a list of offsets, and optionally dual (0 or 1): regularSplit(line, 90, 1) or regularSplit(line, [20, 40])",
            OpKind::Outline => "outline takes one distance: outline(25)",
            OpKind::Streamline => "streamlineSplit takes a kind (smooth, strip or circular) and an offset: streamlineSplit(smooth, 10)",
            OpKind::Place => "place takes a size, a distance and optionally a shape: place(20, 25) or place(20, 25, circle)",
            OpKind::Fill => "fill takes an optional tone from 0 (paper) to 1 (black): fill(1)",
            OpKind::Stipple => "stippling takes an optional kind (dots, dashes or curves), spacing and size: stippling(dots, 6, 1)",
            OpKind::Invert => "invert takes no parameters: invert()",
        }
    }
    /// Parameter slots; the first `positional` may be given by position.
    fn slots(self) -> (&'static [Slot], usize) {
        match self {
            OpKind::Ungroup | OpKind::Invert => (&[], 0),
            OpKind::Regroup => (&[&["k"]], 1),
            OpKind::Split => (
                &[
                    &["curve"],
                    &["offset", "offsets"],
                    &["dual"],
                    &["offset2"],
                    &["offset3"],
                    &["offset4"],
                    &["offset5"],
                    &["offset6"],
                    &["offset7"],
                    &["offset8"],
                ],
                3,
            ),
            OpKind::Outline => (&[&["distance"]], 1),
            OpKind::Streamline => (&[&["kind"], &["offset"]], 2),
            OpKind::Place => (&[&["size"], &["distance"], &["shape"]], 3),
            OpKind::Fill => (&[&["tone"]], 1),
            OpKind::Stipple => (&[&["kind"], &["spacing"], &["size"]], 3),
        }
    }
    /// How many output tags a rule of this operator lists (see the
    /// [`super::ast`] module doc).
    fn outputs(self) -> (usize, &'static str) {
        match self {
            OpKind::Outline => (2, "outline gives at most two tags: -> [inner, ring]"),
            OpKind::Place => (2, "place gives at most two tags: -> [placed, remainder]"),
            OpKind::Fill | OpKind::Stipple | OpKind::Invert => (
                2,
                "a decorative operator gives at most two tags: -> [shape, marks]",
            ),
            _ => (1, "this operator gives all its shapes one tag: -> [tag]"),
        }
    }
}

/// A curve or shape name used by a rule, checked once the whole text is read.
struct Ref {
    name: String,
    kind: DefKind,
    op: &'static str,
    line: usize,
    col: usize,
}

#[derive(Default)]
struct Parser {
    g: Grammar,
    refs: Vec<Ref>,
    /// Definition names → their index in `g.defs`.
    names: HashMap<String, usize>,
}

impl Parser {
    fn statement(&mut self, cur: &mut Cursor) -> Result<()> {
        let first = cur.peek().expect("a statement has tokens");
        match &first.tok {
            Tok::Ident("curve") => self.definition(cur, DefKind::Curve),
            Tok::Ident("shape") => self.definition(cur, DefKind::Shape),
            Tok::Ident("start") => self.start(cur),
            Tok::Ident(_) => self.rule(cur),
            _ => Err(cur.err(format!(
                "a line starts with a rule such as outline(25) : big_poly -> [in, out], or with 'curve', 'shape' or 'start'; found {}",
                cur.found()
            ))),
        }
    }

    fn rule(&mut self, cur: &mut Cursor) -> Result<()> {
        let (name, col) = cur.ident().expect("checked by statement");
        let Some(kind) = OPERATORS.iter().find(|o| o.0 == name).map(|o| o.1) else {
            let mut names: Vec<&str> = OPERATORS.iter().map(|o| o.0).collect();
            names.extend(["curve", "shape", "start"]);
            let hint = match closest(name, &names) {
                Some(s) => format!("did you mean {s}? "),
                None => String::new(),
            };
            return Err(cur.err_at(
                col,
                format!(
                    "unknown operator '{}': {hint}the operators are {OPERATOR_LIST}",
                    shown(name)
                ),
            ));
        };
        if self.g.rules.len() >= MAX_RULES {
            return Err(cur.err_at(
                col,
                format!("a grammar may have at most {MAX_RULES} rules (MAX_RULES)"),
            ));
        }
        if cur.peek_tok() != Some(&Tok::Sym('(')) {
            return Err(cur.err(format!(
                "expected '(' after {name}, found {}: operators take parentheses even without parameters; {}",
                cur.found(),
                kind.usage()
            )));
        }
        let args = call_args(cur)?;
        let op = self.op(kind, &args, cur)?;
        if !cur.eat(':') {
            return Err(cur.err(format!(
                "expected ':' and the tag the rule matches after {name}(...), found {}: write {name}(...) : big_poly -> [in, out]",
                cur.found()
            )));
        }
        let tag = one_tag(cur, "the tag this rule matches after ':'")?;
        if cur.peek_tok() != Some(&Tok::Arrow) {
            return Err(cur.err(format!(
                "expected '->' and the output tags after '{tag}', found {}: write {name}(...) : {tag} -> [out]",
                cur.found(),
                tag = shown(&tag)
            )));
        }
        cur.next();
        let outputs = if cur.eat('[') {
            let mut v = vec![];
            if cur.peek_tok() == Some(&Tok::Sym(']')) {
                return Err(
                    cur.err("the output list is empty: give at least one tag, as in [quads]")
                );
            }
            loop {
                let (max, hint) = kind.outputs();
                if v.len() == max {
                    return Err(cur.err(format!("too many output tags: {hint}")));
                }
                v.push(one_tag(cur, "an output tag")?);
                if cur.eat(']') {
                    break;
                }
                if !cur.eat(',') {
                    return Err(cur.err(format!(
                        "expected ',' or ']' in the output tags, found {}",
                        cur.found()
                    )));
                }
            }
            v
        } else if matches!(cur.peek_tok(), Some(Tok::Ident(_))) {
            vec![one_tag(cur, "an output tag")?]
        } else {
            return Err(cur.err(format!(
                "expected the output tags after '->', found {}: write -> [in, out] or -> quads",
                cur.found()
            )));
        };
        cur.end("the output tags")?;
        self.g.rules.push(Rule {
            op,
            tag,
            outputs,
            line: cur.line,
            column: col,
        });
        Ok(())
    }

    fn op(&mut self, kind: OpKind, args: &Args, cur: &Cursor) -> Result<Op> {
        let (slots, positional) = kind.slots();
        let usage = kind.usage();
        let b = bind(args, slots, positional, kind.name(), usage, cur)?;
        let need = |i: usize, what: &str| -> Result<&Arg> {
            b[i].ok_or_else(|| cur.err_at(args.close, format!("missing {what}: {usage}")))
        };
        Ok(match kind {
            OpKind::Ungroup => Op::Ungroup,
            OpKind::Invert => Op::Invert,
            OpKind::Regroup => {
                let a = need(0, "k")?;
                let k = whole(a, "k", 1, MAX_REGROUP_K, usage, cur)?;
                Op::Regroup { k }
            }
            OpKind::Split => {
                let c = need(0, "the curve")?;
                let curve = self.reference(c, DefKind::Curve, kind.name(), usage, cur)?;
                let o = need(1, "the offset")?;
                let mut offsets = match &o.val {
                    Val::List(v) => {
                        if v.len() > MAX_OFFSETS {
                            return Err(cur.err_at(
                                v[MAX_OFFSETS].1,
                                format!(
                                    "a split takes at most {MAX_OFFSETS} offsets (MAX_OFFSETS)"
                                ),
                            ));
                        }
                        let mut out = vec![];
                        for (x, col) in v {
                            out.push(check_length(*x, *col, "an offset", cur)?);
                        }
                        out
                    }
                    _ => vec![length(o, "the offset", usage, cur)?],
                };
                for (n, slot) in b[3..].iter().enumerate() {
                    let Some(a) = slot else { continue };
                    let name = slots[3 + n][0];
                    if offsets.len() != n + 1 {
                        let key = a.key.map_or(a.col, |k| k.1);
                        return Err(cur.err_at(
                            key,
                            format!(
                                "{name} follows offset{}: give the offsets in order, or as a list offsets = [20, 40]",
                                if n == 0 { String::new() } else { (n + 1).to_string() }
                            ),
                        ));
                    }
                    offsets.push(length(a, name, usage, cur)?);
                }
                let dual = match b[2] {
                    Some(a) => flag(a, cur)?,
                    None => false,
                };
                Op::Split {
                    curve,
                    offsets,
                    dual,
                }
            }
            OpKind::Outline => Op::Outline {
                distance: length(need(0, "the distance")?, "the distance", usage, cur)?,
            },
            OpKind::Streamline => {
                let k = need(0, "the kind")?;
                let kind_ = choose(
                    k,
                    "kind",
                    &[
                        ("smooth", StreamKind::Smooth),
                        ("strip", StreamKind::Strip),
                        ("circular", StreamKind::Circular),
                    ],
                    usage,
                    cur,
                )?;
                let offset = length(need(1, "the offset")?, "the offset", usage, cur)?;
                Op::Streamline {
                    kind: kind_,
                    offset,
                }
            }
            OpKind::Place => {
                let size = length(need(0, "the size")?, "the size", usage, cur)?;
                let d = need(1, "the distance")?;
                let distance = in_range(number(d, "the distance", usage, cur)?, 0.0, MAX_LENGTH)
                    .map_err(|m| cur.err_at(d.col, format!("the distance {m}")))?;
                let shape = match b[2] {
                    Some(a) => self.reference(a, DefKind::Shape, kind.name(), usage, cur)?,
                    None => BUILTIN_SHAPE.to_string(),
                };
                Op::Place {
                    size,
                    distance,
                    shape,
                }
            }
            OpKind::Fill => {
                let tone = match b[0] {
                    Some(a) => in_range(number(a, "the tone", usage, cur)?, 0.0, 1.0)
                        .map_err(|m| cur.err_at(a.col, format!("the tone {m}")))?,
                    None => 1.0,
                };
                Op::Fill { tone }
            }
            OpKind::Stipple => {
                let kind_ = match b[0] {
                    Some(a) => choose(
                        a,
                        "kind",
                        &[
                            ("dots", StippleKind::Dots),
                            ("dashes", StippleKind::Dashes),
                            ("curves", StippleKind::Curves),
                        ],
                        usage,
                        cur,
                    )?,
                    None => StippleKind::Dots,
                };
                let spacing = match b[1] {
                    Some(a) => length(a, "the spacing", usage, cur)?,
                    None => 6.0,
                };
                let size = match b[2] {
                    Some(a) => length(a, "the size", usage, cur)?,
                    None => 1.0,
                };
                Op::Stipple {
                    kind: kind_,
                    spacing,
                    size,
                }
            }
        })
    }

    /// A curve or shape name, remembered to be checked at the end.
    fn reference(
        &mut self,
        a: &Arg,
        kind: DefKind,
        op: &'static str,
        usage: &str,
        cur: &Cursor,
    ) -> Result<String> {
        let what = match kind {
            DefKind::Curve => "the curve",
            DefKind::Shape => "the shape",
        };
        let Val::Name(n) = a.val else {
            return Err(cur.err_at(a.col, format!("{what} is a name: {usage}")));
        };
        self.refs.push(Ref {
            name: n.to_string(),
            kind,
            op,
            line: cur.line,
            col: a.col,
        });
        Ok(n.to_string())
    }

    fn definition(&mut self, cur: &mut Cursor, kind: DefKind) -> Result<()> {
        cur.next();
        let kw = match kind {
            DefKind::Curve => "curve",
            DefKind::Shape => "shape",
        };
        let Some((name, name_col)) = cur.ident() else {
            return Err(cur.err(format!(
                "expected the {kw}'s name after '{kw}', found {}: write {}",
                cur.found(),
                if kind == DefKind::Curve {
                    "curve teeth = zigzag(5, 20)"
                } else {
                    "shape hex = ngon(6)"
                }
            )));
        };
        if name == BUILTIN_CURVE || name == BUILTIN_SHAPE {
            return Err(cur.err_at(
                name_col,
                format!("'{name}' is built in: give your {kw} another name"),
            ));
        }
        if let Some(&i) = self.names.get(name) {
            return Err(cur.err_at(
                name_col,
                format!(
                    "'{}' is already defined on line {}: give this {kw} another name",
                    shown(name),
                    self.g.defs[i].line
                ),
            ));
        }
        if !cur.eat('=') {
            return Err(cur.err(format!(
                "expected '=' after the {kw} name, found {}: write {kw} {name} = {}",
                cur.found(),
                if kind == DefKind::Curve {
                    "zigzag(5, 20)"
                } else {
                    "ngon(6)"
                }
            )));
        }
        let ctor_usage = match kind {
            DefKind::Curve => "a curve is line, zigzag(amplitude, period), wave(amplitude, period), arc(bulge), polyline(x y, x y, ...) or svg(\"path data\")",
            DefKind::Shape => "a shape is circle, ngon(n), polyline(x y, x y, ...) or svg(\"path data\")",
        };
        let Some((ctor, ctor_col)) = cur.ident() else {
            return Err(cur.err(format!(
                "expected a {kw}, found {}: {ctor_usage}",
                cur.found()
            )));
        };
        let names: &[&str] = match kind {
            DefKind::Curve => &["line", "zigzag", "wave", "arc", "polyline", "svg"],
            DefKind::Shape => &["circle", "ngon", "polyline", "svg"],
        };
        if !names.contains(&ctor) {
            let hint = match closest(ctor, names) {
                Some(s) => format!("did you mean {s}? "),
                None => String::new(),
            };
            return Err(cur.err_at(
                ctor_col,
                format!("unknown {kw} '{}': {hint}{ctor_usage}", shown(ctor)),
            ));
        }
        let args = if cur.peek_tok() == Some(&Tok::Sym('(')) {
            call_args(cur)?
        } else if matches!(ctor, "line" | "circle") {
            Args {
                list: vec![],
                close: cur.col(),
            }
        } else {
            return Err(cur.err(format!(
                "expected '(' after {ctor}, found {}: {ctor_usage}",
                cur.found()
            )));
        };
        let closed = kind == DefKind::Shape;
        let curve = match ctor {
            "line" | "circle" => {
                bind(&args, &[], 0, ctor, ctor_usage, cur)?;
                if ctor == "line" {
                    CurveDef::Line
                } else {
                    CurveDef::Circle
                }
            }
            "zigzag" | "wave" => {
                let usage = if ctor == "zigzag" {
                    "zigzag takes an amplitude and a period: zigzag(5, 20)"
                } else {
                    "wave takes an amplitude and a period: wave(5, 20)"
                };
                let b = bind(&args, &[&["amplitude"], &["period"]], 2, ctor, usage, cur)?;
                let missing = |w: &str| cur.err_at(args.close, format!("missing {w}: {usage}"));
                let a = b[0].ok_or_else(|| missing("the amplitude"))?;
                let amplitude = in_range(number(a, "the amplitude", usage, cur)?, 0.0, MAX_LENGTH)
                    .map_err(|m| cur.err_at(a.col, format!("the amplitude {m}")))?;
                let period = length(
                    b[1].ok_or_else(|| missing("the period"))?,
                    "the period",
                    usage,
                    cur,
                )?;
                if ctor == "zigzag" {
                    CurveDef::Zigzag { amplitude, period }
                } else {
                    CurveDef::Wave { amplitude, period }
                }
            }
            "arc" => {
                let usage = "arc takes a bulge, its height over its width, from -1 to 1: arc(0.3)";
                let b = bind(&args, &[&["bulge"]], 1, ctor, usage, cur)?;
                let a = b[0]
                    .ok_or_else(|| cur.err_at(args.close, format!("missing the bulge: {usage}")))?;
                let bulge = in_range(number(a, "the bulge", usage, cur)?, -MAX_BULGE, MAX_BULGE)
                    .map_err(|m| cur.err_at(a.col, format!("the bulge {m} (MAX_BULGE)")))?;
                CurveDef::Arc { bulge }
            }
            "ngon" => {
                let usage = "ngon takes a number of sides: ngon(6)";
                let b = bind(&args, &[&["n"]], 1, ctor, usage, cur)?;
                let a =
                    b[0].ok_or_else(|| cur.err_at(args.close, format!("missing n: {usage}")))?;
                CurveDef::Ngon(whole(a, "n", 3, MAX_NGON_SIDES, usage, cur)?)
            }
            "polyline" => {
                CurveDef::Polyline(points(&args, if closed { 3 } else { 2 }, "polyline", cur)?)
            }
            _ => CurveDef::Svg(svg_arg(&args, cur)?),
        };
        cur.end(&format!("the {kw} definition"))?;
        self.names.insert(name.to_string(), self.g.defs.len());
        self.g.defs.push(Def {
            name: name.to_string(),
            kind,
            curve,
            line: cur.line,
        });
        Ok(())
    }

    fn start(&mut self, cur: &mut Cursor) -> Result<()> {
        cur.next();
        let usage = "a start shape is rect(width, height), circle(radius), polygon(x y, x y, ...), svg(\"path data\") or text(\"WORD\"): start rect(800, 600) : big_poly";
        let Some((ctor, col)) = cur.ident() else {
            return Err(cur.err(format!(
                "expected a shape after 'start', found {}: {usage}",
                cur.found()
            )));
        };
        let names = ["rect", "circle", "polygon", "svg", "text"];
        if !names.contains(&ctor) {
            let hint = match closest(ctor, &names) {
                Some(s) => format!("did you mean {s}? "),
                None => String::new(),
            };
            return Err(cur.err_at(
                col,
                format!("unknown start shape '{}': {hint}{usage}", shown(ctor)),
            ));
        }
        if cur.peek_tok() != Some(&Tok::Sym('(')) {
            return Err(cur.err(format!(
                "expected '(' after {ctor}, found {}: {usage}",
                cur.found()
            )));
        }
        let args = call_args(cur)?;
        let shape = match ctor {
            "rect" => {
                let u = "rect takes a width and a height: rect(800, 600)";
                let b = bind(&args, &[&["width"], &["height"]], 2, ctor, u, cur)?;
                let missing = |w: &str| cur.err_at(args.close, format!("missing {w}: {u}"));
                let width = length(
                    b[0].ok_or_else(|| missing("the width"))?,
                    "the width",
                    u,
                    cur,
                )?;
                let height = length(
                    b[1].ok_or_else(|| missing("the height"))?,
                    "the height",
                    u,
                    cur,
                )?;
                StartShape::Rect { width, height }
            }
            "circle" => {
                let u = "circle takes a radius: circle(300)";
                let b = bind(&args, &[&["radius"]], 1, ctor, u, cur)?;
                let a =
                    b[0].ok_or_else(|| cur.err_at(args.close, format!("missing the radius: {u}")))?;
                StartShape::Circle {
                    radius: length(a, "the radius", u, cur)?,
                }
            }
            "polygon" => StartShape::Polygon(points(&args, 3, "polygon", cur)?),
            "svg" => StartShape::Svg(svg_arg(&args, cur)?),
            _ => {
                let u = "text takes a word in quotes: text(\"TANGLE\")";
                let b = bind(&args, &[&["word"]], 1, ctor, u, cur)?;
                let a =
                    b[0].ok_or_else(|| cur.err_at(args.close, format!("missing the word: {u}")))?;
                let Val::Str(s, raw) = &a.val else {
                    return Err(cur.err_at(a.col, format!("the word is a string in quotes: {u}")));
                };
                if s.trim().is_empty() {
                    return Err(cur.err_at(a.col, format!("the word is empty: {u}")));
                }
                if let Some(i) = raw.chars().position(char::is_control) {
                    return Err(cur.err_at(
                        a.col + 1 + i,
                        "the word has a control character (a tab?): use letters, digits and spaces",
                    ));
                }
                let n = s.chars().count();
                if n > MAX_START_TEXT_CHARS {
                    return Err(cur.err_at(
                        a.col,
                        format!("the word has {n} characters; at most {MAX_START_TEXT_CHARS} (MAX_START_TEXT_CHARS)"),
                    ));
                }
                StartShape::Text(s.clone())
            }
        };
        if !cur.eat(':') {
            return Err(cur.err(format!(
                "expected ':' and the start shape's tag after {ctor}(...), found {}: write start {ctor}(...) : big_poly",
                cur.found()
            )));
        }
        let tag = one_tag(cur, "the start shape's tag after ':'")?;
        cur.end("the start shape's tag")?;
        self.g.start.push(Start {
            shape,
            tag,
            line: cur.line,
        });
        Ok(())
    }

    fn finish(self) -> Result<Grammar> {
        let Parser { g, refs, names } = self;
        for r in &refs {
            let builtin = match r.kind {
                DefKind::Curve => BUILTIN_CURVE,
                DefKind::Shape => BUILTIN_SHAPE,
            };
            let (kw, other) = match r.kind {
                DefKind::Curve => ("curve", "shape"),
                DefKind::Shape => ("shape", "curve"),
            };
            if r.name == builtin {
                continue;
            }
            match names.get(&r.name).map(|&i| &g.defs[i]) {
                Some(d) if d.kind == r.kind => {}
                Some(d) => {
                    return Err(syntax(
                        r.line,
                        r.col,
                        format!(
                            "'{}' (line {}) is a {other}, and {} needs a {kw}: define a {kw} and use its name",
                            shown(&r.name),
                            d.line,
                            r.op
                        ),
                    ))
                }
                None => {
                    let mut names: Vec<&str> = g
                        .defs
                        .iter()
                        .filter(|d| d.kind == r.kind)
                        .map(|d| d.name.as_str())
                        .collect();
                    names.push(builtin);
                    let hint = match closest(&r.name, &names) {
                        Some(s) => format!("did you mean {s}? "),
                        None => String::new(),
                    };
                    let example = match r.kind {
                        DefKind::Curve => format!("curve {} = zigzag(5, 20)", shown(&r.name)),
                        DefKind::Shape => format!("shape {} = ngon(6)", shown(&r.name)),
                    };
                    return Err(syntax(
                        r.line,
                        r.col,
                        format!(
                            "unknown {kw} '{}': {hint}use {builtin} or define it on a line of its own, as in {example}",
                            shown(&r.name)
                        ),
                    ));
                }
            }
        }
        if g.rules.is_empty() {
            return Err(syntax(
                1,
                1,
                "the grammar has no rules: add one a line, such as outline(25) : big_poly -> [in, out]",
            ));
        }
        Ok(g)
    }
}

/// `( arg, arg, ... )`; the cursor is on the `(` (brackets are balanced,
/// [`check_brackets`]).
fn call_args<'a>(cur: &mut Cursor<'_, 'a>) -> Result<Args<'a>> {
    cur.next();
    let mut list = vec![];
    if let Some(t) = cur.peek().filter(|t| t.tok == Tok::Sym(')')) {
        cur.next();
        return Ok(Args { list, close: t.col });
    }
    loop {
        let key = match (cur.peek_tok(), cur.toks.get(cur.i + 1).map(|t| &t.tok)) {
            (Some(Tok::Ident(_)), Some(Tok::Sym('='))) => {
                let k = cur.ident();
                cur.next();
                k
            }
            _ => None,
        };
        let col = cur.col();
        let val = match cur.peek_tok() {
            Some(Tok::Num(_)) => {
                let mut v = vec![];
                while let Some(Tok::Num(x)) = cur.peek_tok() {
                    v.push(*x);
                    cur.next();
                }
                Val::Nums(v)
            }
            Some(Tok::Ident(n)) => {
                cur.next();
                Val::Name(n)
            }
            Some(Tok::Str(s, raw)) => {
                cur.next();
                Val::Str(s.clone(), raw)
            }
            Some(Tok::Sym('[')) => {
                cur.next();
                let mut v = vec![];
                loop {
                    match cur.peek() {
                        Some(Token {
                            tok: Tok::Num(x),
                            col,
                            ..
                        }) => {
                            v.push((*x, *col));
                            cur.next();
                        }
                        Some(Token {
                            tok: Tok::Sym(']'),
                            ..
                        }) if v.is_empty() => {
                            return Err(cur.err("the list is empty: write numbers separated by commas, as in [20, 40]"))
                        }
                        _ => {
                            return Err(cur.err(format!(
                                "expected a number in the list, found {}: a list is numbers separated by commas, as in [20, 40]",
                                cur.found()
                            )))
                        }
                    }
                    if cur.eat(']') {
                        break;
                    }
                    if !cur.eat(',') {
                        return Err(cur.err(format!(
                            "expected ',' or ']' in the list, found {}: a list is numbers separated by commas, as in [20, 40]",
                            cur.found()
                        )));
                    }
                }
                Val::List(v)
            }
            _ => {
                return Err(cur.err(format!(
                    "expected a parameter (a number, a name, a \"string\" or a [list]), found {}",
                    cur.found()
                )))
            }
        };
        list.push(Arg { key, val, col });
        let col = cur.col();
        if cur.eat(')') {
            return Ok(Args { list, close: col });
        }
        if !cur.eat(',') {
            return Err(cur.err(format!(
                "expected ',' or ')' after a parameter, found {}",
                cur.found()
            )));
        }
    }
}

/// Match `args` to `slots` (positional first, then `name = value`).
fn bind<'x, 'a>(
    args: &'x Args<'a>,
    slots: &[Slot],
    positional: usize,
    callee: &str,
    usage: &str,
    cur: &Cursor,
) -> Result<Vec<Option<&'x Arg<'a>>>> {
    let mut b: Vec<Option<&Arg>> = vec![None; slots.len()];
    let mut seen_key = false;
    for (i, a) in args.list.iter().enumerate() {
        match a.key {
            None => {
                if seen_key {
                    return Err(cur.err_at(
                        a.col,
                        "positional parameters come before the named ones (name = value)",
                    ));
                }
                if i >= positional {
                    return Err(cur.err_at(a.col, format!("too many parameters: {usage}")));
                }
                b[i] = Some(a);
            }
            Some((k, kcol)) => {
                seen_key = true;
                let Some(s) = slots.iter().position(|s| s.contains(&k)) else {
                    let names: Vec<&str> = slots.iter().flat_map(|s| s.iter().copied()).collect();
                    let msg = if names.is_empty() {
                        format!("{callee} has no parameters: {usage}")
                    } else {
                        let hint = match closest(k, &names) {
                            Some(s) => format!("did you mean {s}? "),
                            None => String::new(),
                        };
                        let first: Vec<&str> = slots.iter().map(|s| s[0]).collect();
                        format!(
                            "{callee} has no parameter '{}': {hint}its parameters are {}",
                            shown(k),
                            first.join(", ")
                        )
                    };
                    return Err(cur.err_at(kcol, msg));
                };
                if b[s].is_some() {
                    return Err(cur.err_at(kcol, format!("'{}' is given twice", slots[s][0])));
                }
                b[s] = Some(a);
            }
        }
    }
    Ok(b)
}

fn number(a: &Arg, what: &str, usage: &str, cur: &Cursor) -> Result<f64> {
    match &a.val {
        Val::Nums(v) if v.len() == 1 => Ok(v[0]),
        Val::Nums(v) => Err(cur.err_at(
            a.col,
            format!(
                "{what} is one number, found {} numbers: separate parameters with commas",
                v.len()
            ),
        )),
        _ => Err(cur.err_at(a.col, format!("{what} is a number: {usage}"))),
    }
}

/// `Err(" must be ...")` when `v` is outside `[lo, hi]`.
fn in_range(v: f64, lo: f64, hi: f64) -> std::result::Result<f64, String> {
    if (lo..=hi).contains(&v) {
        Ok(v)
    } else {
        Err(format!("must be from {lo} to {hi}; it is {v}"))
    }
}

fn check_length(v: f64, col: usize, what: &str, cur: &Cursor) -> Result<f64> {
    if v < MIN_LENGTH {
        return Err(cur.err_at(
            col,
            format!("{what} must be at least {MIN_LENGTH} (MIN_LENGTH); it is {v}: smaller lengths make a runaway number of pieces"),
        ));
    }
    if v > MAX_LENGTH {
        return Err(cur.err_at(
            col,
            format!("{what} must be at most {MAX_LENGTH} (MAX_LENGTH); it is {v}"),
        ));
    }
    Ok(v)
}

fn length(a: &Arg, what: &str, usage: &str, cur: &Cursor) -> Result<f64> {
    check_length(number(a, what, usage, cur)?, a.col, what, cur)
}

fn whole(a: &Arg, what: &str, lo: u32, hi: u32, usage: &str, cur: &Cursor) -> Result<u32> {
    let v = number(a, what, usage, cur)?;
    if v.fract() != 0.0 {
        return Err(cur.err_at(a.col, format!("{what} is a whole number, not {v}: {usage}")));
    }
    if v < lo as f64 || v > hi as f64 {
        return Err(cur.err_at(
            a.col,
            format!("{what} must be from {lo} to {hi}; it is {v}: {usage}"),
        ));
    }
    Ok(v as u32)
}

/// `dual`: 0, 1, false or true.
fn flag(a: &Arg, cur: &Cursor) -> Result<bool> {
    match &a.val {
        Val::Nums(v) if v.len() == 1 && v[0] == 0.0 => Ok(false),
        Val::Nums(v) if v.len() == 1 && v[0] == 1.0 => Ok(true),
        Val::Name("false") => Ok(false),
        Val::Name("true") => Ok(true),
        _ => Err(cur.err_at(
            a.col,
            "dual is 0 or 1 (or false or true): 1 splits a second time across, into a grid",
        )),
    }
}

fn choose<T: Copy>(
    a: &Arg,
    what: &str,
    options: &[(&str, T)],
    usage: &str,
    cur: &Cursor,
) -> Result<T> {
    let names: Vec<&str> = options.iter().map(|o| o.0).collect();
    let Val::Name(n) = a.val else {
        return Err(cur.err_at(a.col, format!("the {what} is a name: {usage}")));
    };
    match options.iter().find(|o| o.0 == n) {
        Some(o) => Ok(o.1),
        None => {
            let hint = match closest(n, &names) {
                Some(s) => format!("did you mean {s}? "),
                None => String::new(),
            };
            Err(cur.err_at(
                a.col,
                format!(
                    "unknown {what} '{}': {hint}it is one of {}",
                    shown(n),
                    names.join(", ")
                ),
            ))
        }
    }
}

/// `x y, x y, ...` with at least `min` points.
fn points(args: &Args, min: usize, callee: &str, cur: &Cursor) -> Result<Vec<DVec2>> {
    let usage =
        format!("{callee} takes points 'x y' separated by commas: {callee}(0 0, 10 0, 5 8)");
    if args.list.len() > MAX_POLYLINE_POINTS {
        return Err(cur.err_at(
            args.list[MAX_POLYLINE_POINTS].col,
            format!("{callee} has more than {MAX_POLYLINE_POINTS} points (MAX_POLYLINE_POINTS)"),
        ));
    }
    let mut pts = Vec::with_capacity(args.list.len());
    for a in &args.list {
        if let Some((_, kcol)) = a.key {
            return Err(cur.err_at(kcol, format!("{callee} takes no named parameters: {usage}")));
        }
        let Val::Nums(v) = &a.val else {
            return Err(cur.err_at(a.col, format!("a point is two numbers: {usage}")));
        };
        if v.len() != 2 {
            return Err(cur.err_at(
                a.col,
                format!("a point is two numbers 'x y', found {}: {usage}", v.len()),
            ));
        }
        if v.iter().any(|x| x.abs() > MAX_LENGTH) {
            return Err(cur.err_at(
                a.col,
                format!("coordinates must be from -{MAX_LENGTH} to {MAX_LENGTH} (MAX_LENGTH)"),
            ));
        }
        pts.push(DVec2::new(v[0], v[1]));
    }
    if pts.len() < min {
        return Err(cur.err_at(
            args.close,
            format!(
                "{callee} needs at least {min} points, found {}: {usage}",
                pts.len()
            ),
        ));
    }
    if min >= 3 {
        let area2: f64 = (0..pts.len())
            .map(|i| pts[i].perp_dot(pts[(i + 1) % pts.len()]))
            .sum();
        if area2 == 0.0 {
            return Err(cur.err_at(
                args.list[0].col,
                format!("this {callee} encloses no area: its points lie on a line"),
            ));
        }
    }
    Ok(pts)
}

/// Characters of SVG path data.
fn is_path_char(c: char) -> bool {
    c.is_ascii_digit() || "MmLlHhVvCcSsQqTtAaZz+-.,eE".contains(c) || c == ' ' || c == '\t'
}

/// `svg("path data")`.
fn svg_arg(args: &Args, cur: &Cursor) -> Result<String> {
    let u = "svg takes the path data of an SVG <path> in quotes: svg(\"M 0 0 L 10 0 L 5 8 Z\")";
    let b = bind(args, &[&["d"]], 1, "svg", u, cur)?;
    let a = b[0].ok_or_else(|| cur.err_at(args.close, format!("missing the path data: {u}")))?;
    let Val::Str(s, raw) = &a.val else {
        return Err(cur.err_at(a.col, format!("the path data is a string in quotes: {u}")));
    };
    if let Some((i, c)) = raw.chars().enumerate().find(|(_, c)| !is_path_char(*c)) {
        return Err(cur.err_at(
            a.col + 1 + i,
            format!("'{c}' is not part of SVG path data (commands MLHVCSQTAZ, numbers, spaces and commas)"),
        ));
    }
    if !s.chars().any(|c| c.is_ascii_digit()) || !s.trim_start().starts_with(['M', 'm']) {
        return Err(cur.err_at(
            a.col,
            format!("the path data must start with a move 'M x y': {u}"),
        ));
    }
    Ok(s.clone())
}

/// A tag: one word (`what` names it in messages).
fn one_tag(cur: &mut Cursor, what: &str) -> Result<String> {
    let Some((t, _)) = cur.ident() else {
        return Err(cur.err(format!("expected {what}, found {}", cur.found())));
    };
    if let Some(Tok::Ident(_)) = cur.peek_tok() {
        let mut words = vec![t];
        let mut j = cur.i;
        while let Some(Token {
            tok: Tok::Ident(w), ..
        }) = cur.toks.get(j).filter(|_| words.len() <= 8)
        {
            words.push(w);
            j += 1;
        }
        let joined = words.join("_");
        return Err(cur.err(if words.len() <= 8 {
            format!("tags are one word: write {}", shown(&joined))
        } else {
            "tags are one word: join the words with '_'".to_string()
        }));
    }
    Ok(t.to_string())
}

/// `s` cut to 40 characters for a message.
fn shown(s: &str) -> String {
    match s.char_indices().nth(40) {
        Some((i, _)) => format!("{}…", &s[..i]),
        None => s.to_string(),
    }
}

/// The closest of `names` to `word` when it is close enough to be a typo
/// (case is ignored).
fn closest<'n>(word: &str, names: &[&'n str]) -> Option<&'n str> {
    if word.len() > 64 {
        return None;
    }
    let w = word.to_ascii_lowercase();
    let best = names
        .iter()
        .map(|n| (edit_distance(&w, &n.to_ascii_lowercase()), *n))
        .min_by_key(|(d, _)| *d)?;
    let allowed = if w.len() >= 5 { 2 } else { 1 };
    if best.0 <= allowed {
        return Some(best.1);
    }
    // An abbreviation: `dist` for `distance`.
    let prefix = names
        .iter()
        .find(|n| w.len() >= 3 && n.to_ascii_lowercase().starts_with(&w));
    prefix.copied()
}

fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    let mut row = vec![0; b.len() + 1];
    for (i, ca) in a.chars().enumerate() {
        row[0] = i + 1;
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + (ca != *cb) as usize;
            row[j + 1] = sub.min(prev[j + 1] + 1).min(row[j] + 1);
        }
        std::mem::swap(&mut prev, &mut row);
    }
    prev[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    const LEAF: &str = include_str!("../../assets/tangle/leaf.tangle");

    fn rule_of(g: &Grammar, i: usize) -> (&Op, &str, Vec<&str>) {
        let r = &g.rules[i];
        (
            &r.op,
            r.tag.as_str(),
            r.outputs.iter().map(String::as_str).collect(),
        )
    }

    fn split(offset: f64, dual: bool) -> Op {
        Op::Split {
            curve: "line".into(),
            offsets: vec![offset],
            dual,
        }
    }

    #[test]
    fn fig9_leaf_parses_to_its_twelve_rules() {
        let g = parse(LEAF).unwrap();
        let outline = |distance| Op::Outline { distance };
        let expected: Vec<(Op, &str, Vec<&str>)> = vec![
            (outline(25.0), "big_poly", vec!["in", "out"]),
            (
                Op::Place {
                    size: 20.0,
                    distance: 25.0,
                    shape: "circle".into(),
                },
                "out",
                vec!["blob", "rem"],
            ),
            (split(90.0, true), "in", vec!["quads"]),
            (Op::Regroup { k: 2 }, "quads", vec!["ung_quads"]),
            (outline(7.0), "ung_quads", vec!["in_2", "out_2"]),
            (outline(5.0), "in_2", vec!["in_3", "out_3"]),
            (
                Op::Stipple {
                    kind: StippleKind::Dots,
                    spacing: 6.0,
                    size: 1.0,
                },
                "in_3",
                vec!["term", "term"],
            ),
            (split(50.0, false), "ung_quads", vec!["slices"]),
            (Op::Regroup { k: 2 }, "slices", vec!["reg_slices"]),
            (split(10.0, false), "reg_slices", vec!["final"]),
            (outline(3.0), "final", vec!["tiny", "tiny_out"]),
            (Op::Invert, "rem", vec!["term", "term"]),
        ];
        assert_eq!(g.rules.len(), 12);
        for (i, (op, tag, outputs)) in expected.iter().enumerate() {
            assert_eq!(
                rule_of(&g, i),
                (op, *tag, outputs.clone()),
                "rule {}",
                i + 1
            );
        }
        // Rules keep their place in the file.
        let first = LEAF
            .lines()
            .position(|l| l.starts_with("outline(25)"))
            .unwrap()
            + 1;
        assert_eq!((g.rules[0].line, g.rules[0].column), (first, 1));
        assert_eq!(g.rules[11].line, first + 11);
        assert_eq!(
            g.start,
            vec![Start {
                shape: StartShape::Rect {
                    width: 800.0,
                    height: 600.0
                },
                tag: "big_poly".into(),
                line: first - 2,
            }]
        );
        assert!(g.defs.is_empty());
    }

    /// (text, line, column, a piece of the message)
    const ERRORS: &[(&str, usize, usize, &str)] = &[
        // unknown operators, with the closest name
        (
            "outlin(25) : a -> [b]",
            1,
            1,
            "unknown operator 'outlin': did you mean outline?",
        ),
        (
            "# c\n\n  regularsplit(line, 9) : a -> b",
            3,
            3,
            "did you mean regularSplit?",
        ),
        (
            "cruve c = line\noutline(3) : a -> b",
            1,
            1,
            "did you mean curve?",
        ),
        (
            "frobnicate(1) : a -> b",
            1,
            1,
            "the operators are ungroup, regroup",
        ),
        // parameter count and type
        (
            "outline(25, 3) : a -> [b]",
            1,
            13,
            "too many parameters: outline takes one distance: outline(25)",
        ),
        (
            "outline() : a -> [b]",
            1,
            9,
            "missing the distance: outline takes one distance: outline(25)",
        ),
        (
            "outline(x) : a -> [b]",
            1,
            9,
            "the distance is a number: outline takes one distance",
        ),
        (
            "outline(2 5) : a -> [b]",
            1,
            9,
            "found 2 numbers: separate parameters with commas",
        ),
        (
            "ungroup(1) : a -> b",
            1,
            9,
            "too many parameters: ungroup takes no parameters",
        ),
        (
            "invert : a -> b",
            1,
            8,
            "operators take parentheses even without parameters",
        ),
        (
            "place(20) : a -> b",
            1,
            9,
            "missing the distance: place takes a size, a distance",
        ),
        (
            "streamlineSplit(smoth, 5) : a -> b",
            1,
            17,
            "unknown kind 'smoth': did you mean smooth?",
        ),
        ("stippling(dits) : a -> b", 1, 11, "did you mean dots?"),
        (
            "regularSplit(line, 10, 2) : a -> b",
            1,
            24,
            "dual is 0 or 1",
        ),
        ("regularSplit(3, 10) : a -> b", 1, 14, "the curve is a name"),
        (
            "regularSplit(line, [10, x]) : a -> b",
            1,
            25,
            "expected a number in the list",
        ),
        (
            "regularSplit(line, []) : a -> b",
            1,
            21,
            "the list is empty",
        ),
        (
            "regularSplit(line, [1, 2, 3, 4, 5, 6, 7, 8, 9]) : a -> b",
            1,
            45,
            "at most 8 offsets (MAX_OFFSETS)",
        ),
        (
            "regularSplit(line, 10, offset3 = 5) : a -> b",
            1,
            24,
            "offset3 follows offset2",
        ),
        // lengths and ranges
        ("outline(0.2) : a -> [b]", 1, 9, "at least 0.5 (MIN_LENGTH)"),
        ("outline(-4) : a -> [b]", 1, 9, "at least 0.5 (MIN_LENGTH)"),
        (
            "outline(2e6) : a -> [b]",
            1,
            9,
            "at most 1000000 (MAX_LENGTH)",
        ),
        (
            "regularSplit(line, [10, 0.1]) : a -> b",
            1,
            25,
            "an offset must be at least 0.5",
        ),
        (
            "place(20, -1) : a -> b",
            1,
            11,
            "the distance must be from 0",
        ),
        ("fill(2) : a -> b", 1, 6, "the tone must be from 0 to 1"),
        ("regroup(0) : a -> b", 1, 9, "k must be from 1 to 1000000"),
        ("regroup(1.5) : a -> b", 1, 9, "k is a whole number"),
        (
            "stippling(dots, 6, 0) : a -> b",
            1,
            20,
            "the size must be at least 0.5",
        ),
        // keyword arguments
        (
            "outline(dist = 3) : a -> b",
            1,
            9,
            "outline has no parameter 'dist': did you mean distance?",
        ),
        (
            "place(size = 3, 4) : a -> b",
            1,
            17,
            "positional parameters come before the named ones",
        ),
        (
            "outline(25, distance = 3) : a -> b",
            1,
            13,
            "'distance' is given twice",
        ),
        ("invert(x = 1) : a -> b", 1, 8, "invert has no parameters"),
        // curve and shape names
        (
            "outline(1) : a -> b\nregularSplit(zz, 10) : a -> [b]",
            2,
            14,
            "unknown curve 'zz': use line or define it",
        ),
        (
            "curve teeth = zigzag(1, 4)\nregularSplit(teth, 10) : a -> [b]",
            2,
            14,
            "did you mean teeth?",
        ),
        (
            "place(20, 25, blob) : a -> b",
            1,
            15,
            "unknown shape 'blob'",
        ),
        (
            "shape s = ngon(6)\nregularSplit(s, 10) : a -> b",
            2,
            14,
            "'s' (line 1) is a shape, and regularSplit needs a curve",
        ),
        (
            "curve c = line\nplace(3, 3, c) : a -> b",
            2,
            13,
            "'c' (line 1) is a curve, and place needs a shape",
        ),
        (
            "curve c = line\ncurve c = wave(1, 2)\nfill() : a -> b",
            2,
            7,
            "'c' is already defined on line 1",
        ),
        (
            "curve c = line\nshape c = circle\nfill() : a -> b",
            2,
            7,
            "already defined on line 1",
        ),
        (
            "curve line = zigzag(1, 2)\nfill() : a -> b",
            1,
            7,
            "'line' is built in",
        ),
        (
            "curve z = zigzog(1, 2)\nfill() : a -> b",
            1,
            11,
            "unknown curve 'zigzog': did you mean zigzag?",
        ),
        (
            "shape z = zigzag(1, 2)\nfill() : a -> b",
            1,
            11,
            "a shape is circle, ngon(n)",
        ),
        (
            "curve z = zigzag(1, 0)\nfill() : a -> b",
            1,
            21,
            "the period must be at least 0.5",
        ),
        (
            "curve z = arc(3)\nfill() : a -> b",
            1,
            15,
            "the bulge must be from -1 to 1",
        ),
        (
            "shape z = ngon(2)\nfill() : a -> b",
            1,
            16,
            "n must be from 3 to 1000",
        ),
        (
            "shape z = polyline(0 0, 1 1)\nfill() : a -> b",
            1,
            28,
            "polyline needs at least 3 points",
        ),
        (
            "shape z = polyline(0 0, 1 1, 2 2)\nfill() : a -> b",
            1,
            20,
            "encloses no area",
        ),
        (
            "curve z = polyline(0 0, 1 1 1)\nfill() : a -> b",
            1,
            25,
            "a point is two numbers 'x y', found 3",
        ),
        (
            "shape s = svg(\"M 0 0 L 1 x\")\nfill() : a -> b",
            1,
            26,
            "'x' is not part of SVG path data",
        ),
        (
            "shape s = svg(\"0 0 L 1 1\")\nfill() : a -> b",
            1,
            15,
            "must start with a move",
        ),
        (
            "curve z = wave(1, 2) extra\nfill() : a -> b",
            1,
            22,
            "unexpected 'extra' after the curve definition",
        ),
        // tags, ':' and '->'
        (
            "outline(25) : big poly -> [in, out]",
            1,
            19,
            "tags are one word: write big_poly",
        ),
        (
            "outline(25) : a -> [in, tiny out piece]",
            1,
            30,
            "tags are one word: write tiny_out_piece",
        ),
        (
            "outline(25) big_poly -> [a]",
            1,
            13,
            "expected ':' and the tag the rule matches",
        ),
        (
            "outline(25) : big_poly [a]",
            1,
            24,
            "expected '->' and the output tags after 'big_poly'",
        ),
        ("outline(25) : big_poly", 1, 23, "expected '->'"),
        (
            "outline(25) : -> [a]",
            1,
            15,
            "expected the tag this rule matches",
        ),
        (
            "outline(25) : a -> 3",
            1,
            20,
            "expected the output tags after '->'",
        ),
        (
            "outline(25) : a -> [b] c",
            1,
            24,
            "unexpected 'c' after the output tags: one statement a line",
        ),
        // output counts
        (
            "regularSplit(line, 10) : a -> [b, c]",
            1,
            35,
            "too many output tags: this operator gives all its shapes one tag",
        ),
        (
            "outline(25) : a -> [b, c, d]",
            1,
            27,
            "outline gives at most two tags",
        ),
        (
            "place(2, 2) : a -> [b, c, d]",
            1,
            27,
            "place gives at most two tags",
        ),
        (
            "fill() : a -> [b, c, d]",
            1,
            22,
            "a decorative operator gives at most two tags",
        ),
        ("outline(25) : a -> []", 1, 21, "the output list is empty"),
        // brackets and strings
        (
            "start svg(\"M 0 0 L 1 1) : a",
            1,
            11,
            "this string is not closed",
        ),
        ("start text(\"a\\q\") : a", 1, 14, "unknown escape"),
        (
            "outline(25 : a -> [b]",
            1,
            8,
            "this '(' is not closed: add ')'",
        ),
        (
            "regularSplit(line, [10, 20) : a -> [b]",
            1,
            27,
            "')' does not close the '[' at column 20",
        ),
        ("outline(25)) : a -> [b]", 1, 12, "')' has no '(' before it"),
        // numbers and characters
        (
            "outline(1e999) : a -> b",
            1,
            9,
            "too large: numbers must be finite",
        ),
        ("outline(.5) : a -> b", 1, 9, "write 0.5"),
        (
            "outline(1.) : a -> b",
            1,
            9,
            "needs digits after the decimal point: write 1.0",
        ),
        ("outline(1e) : a -> b", 1, 9, "an exponent needs digits"),
        ("outline(25px) : a -> b", 1, 9, "'25px' is not a number"),
        ("outline(25) : a - b", 1, 17, "the arrow is written '->'"),
        (
            "outline(25) : a → [b, c, d]",
            1,
            26,
            "outline gives at most two tags",
        ),
        ("outline(25) : a → [über]", 1, 20, "'ü' is not one of them"),
        (
            "outline(25) : a -> [b] ; fill() : a -> b",
            1,
            24,
            "unexpected character ';'",
        ),
        ("= 3", 1, 1, "a line starts with a rule"),
        // start shapes
        (
            "start square(3) : a\nfill() : a -> b",
            1,
            7,
            "unknown start shape 'square'",
        ),
        (
            "start rect(800) : a\nfill() : a -> b",
            1,
            15,
            "missing the height",
        ),
        (
            "start rect(800, 600) a\nfill() : a -> b",
            1,
            22,
            "expected ':' and the start shape's tag",
        ),
        (
            "start text(\"\") : a\nfill() : a -> b",
            1,
            12,
            "the word is empty",
        ),
        (
            "start polygon(0 0, 1 0) : a\nfill() : a -> b",
            1,
            23,
            "polygon needs at least 3 points",
        ),
        (
            "curve = line\nfill() : a -> b",
            1,
            7,
            "expected the curve's name after 'curve'",
        ),
        (
            "start\nfill() : a -> b",
            1,
            6,
            "expected a shape after 'start'",
        ),
        // a grammar without rules
        ("", 1, 1, "the grammar has no rules"),
        (
            "# only a comment\ncurve c = line\n",
            1,
            1,
            "the grammar has no rules",
        ),
    ];

    #[test]
    fn syntax_errors_point_at_the_offending_token() {
        let mut failures = vec![];
        for (text, line, column, piece) in ERRORS {
            match parse(text) {
                Err(Error::Syntax {
                    line: l,
                    column: c,
                    message,
                }) => {
                    if (l, c) != (*line, *column) || !message.contains(piece) {
                        failures.push(format!(
                            "{text:?}: got {l}:{c} {message:?}, want {line}:{column} …{piece}…"
                        ));
                    }
                }
                other => failures.push(format!("{text:?}: got {other:?}")),
            }
        }
        assert!(failures.is_empty(), "{}", failures.join("\n"));
    }

    #[test]
    fn numbers_round_trip_exactly() {
        let values = [
            0.5,
            1.0,
            25.0,
            10.1 + 0.2,
            10.0 / 3.0,
            std::f64::consts::PI * 1000.0,
            MAX_LENGTH,
            999_999.999_999_999_9,
            0.500_000_000_000_000_1,
            123.456e2,
        ];
        for v in values {
            for text in [
                format!("{v}"),
                format!("{v:?}"),
                format!("{v:e}"),
                format!("+{v}"),
            ] {
                let g = parse(&format!("outline({text}) : a -> b")).unwrap();
                match g.rules[0].op {
                    Op::Outline { distance } => {
                        assert_eq!(distance.to_bits(), v.to_bits(), "{text}")
                    }
                    ref op => panic!("{op:?}"),
                }
            }
        }
        // Signs, exponents and negative zero in coordinates.
        let g = parse(
            "shape s = polyline(-0 0, 1e2 -2.5E-1, +3 4e+1, -1.25e-3 1E0)\nplace(1, 0, s) : a -> b",
        )
        .unwrap();
        let CurveDef::Polyline(p) = &g.defs[0].curve else {
            panic!("{:?}", g.defs[0])
        };
        let want = [(-0.0, 0.0), (100.0, -0.25), (3.0, 40.0), (-0.00125, 1.0)];
        for (p, (x, y)) in p.iter().zip(want) {
            assert_eq!(
                (p.x.to_bits(), p.y.to_bits()),
                (f64::to_bits(x), f64::to_bits(y))
            );
        }
        // What `to_text` writes reads back bit for bit.
        let again = parse(&to_text(&g)).unwrap();
        assert_eq!(positionless(again), positionless(g));
    }

    #[test]
    fn keyword_arguments_name_any_parameter() {
        let g = parse(
            "curve teeth = zigzag(period = 20, amplitude = 5)\n\
             shape hex = ngon(n = 6)\n\
             regularSplit(dual = true, offsets = [20, 40], curve = teeth) : a -> b\n\
             split(line, offset = 10, offset2 = 30, offset3 = 50) : b -> c\n\
             place(distance = 4, size = 12, shape = hex) : c -> [d, e]\n\
             streamline(offset = 8, kind = circular) : d -> f\n\
             stipple(size = 2, kind = dashes) : f -> [g, h]\n\
             fill(tone = 0.25) : g -> h\n\
             regroup(k = 3) : h -> i\n\
             outline(distance = 7) : i -> [j, k]\n\
             start rect(height = 600, width = 800) : a\n\
             start circle(radius = 50) : a\n\
             start text(word = \"TANGLE\") : a",
        )
        .unwrap();
        let ops: Vec<&Op> = g.rules.iter().map(|r| &r.op).collect();
        assert_eq!(
            ops,
            [
                &Op::Split {
                    curve: "teeth".into(),
                    offsets: vec![20.0, 40.0],
                    dual: true
                },
                &Op::Split {
                    curve: "line".into(),
                    offsets: vec![10.0, 30.0, 50.0],
                    dual: false
                },
                &Op::Place {
                    size: 12.0,
                    distance: 4.0,
                    shape: "hex".into()
                },
                &Op::Streamline {
                    kind: StreamKind::Circular,
                    offset: 8.0
                },
                &Op::Stipple {
                    kind: StippleKind::Dashes,
                    spacing: 6.0,
                    size: 2.0
                },
                &Op::Fill { tone: 0.25 },
                &Op::Regroup { k: 3 },
                &Op::Outline { distance: 7.0 },
            ]
        );
        assert_eq!(
            g.defs[0].curve,
            CurveDef::Zigzag {
                amplitude: 5.0,
                period: 20.0
            }
        );
        assert_eq!(g.defs[1].curve, CurveDef::Ngon(6));
        let shapes: Vec<&StartShape> = g.start.iter().map(|s| &s.shape).collect();
        assert_eq!(
            shapes,
            [
                &StartShape::Rect {
                    width: 800.0,
                    height: 600.0
                },
                &StartShape::Circle { radius: 50.0 },
                &StartShape::Text("TANGLE".into()),
            ]
        );
        // What the parser accepts, with_param keeps as it is.
        for r in &g.rules {
            for p in r.op.params() {
                assert_eq!(r.op.with_param(p.name, p.value), Some(r.op.clone()));
            }
        }
    }

    #[test]
    fn aliases_defaults_comments_and_arrows() {
        let g = parse(
            "// a comment\r\n\
             \t# another\r\n\
             \r\n\
             stipling() : a → [b, c]   # trailing comment\r\n\
             stippling(curves) : a -> b // and another\n\
             fill() : b -> c\n\
             place(5, 0) : c -> d\n\
             streamlineSplit(strip, 3) : d -> e\n\
             regularSplit(wiggle, 3, false) : e -> f\n\
             curve wiggle = svg(\"M 0 0 C 1 2, 3 -4, 5.5e1 6 z\")\n\
             shape star = polyline(0 0, 2 5, 4 0, 0 3, 4 3)\n\
             curve bow = arc(-0.5)\n\
             curve w = wave(0, 10)\n\
             curve l = polyline(0 0, 0 10)\n\
             shape round = circle()\n\
             ungroup() : f -> g",
        )
        .unwrap();
        let ops: Vec<&Op> = g.rules.iter().map(|r| &r.op).collect();
        let stipple = |kind| Op::Stipple {
            kind,
            spacing: 6.0,
            size: 1.0,
        };
        assert_eq!(ops[0], &stipple(StippleKind::Dots));
        assert_eq!(ops[1], &stipple(StippleKind::Curves));
        assert_eq!(ops[2], &Op::Fill { tone: 1.0 });
        assert_eq!(
            ops[3],
            &Op::Place {
                size: 5.0,
                distance: 0.0,
                shape: "circle".into()
            }
        );
        assert_eq!(
            ops[4],
            &Op::Streamline {
                kind: StreamKind::Strip,
                offset: 3.0
            }
        );
        assert!(matches!(ops[5], Op::Split { dual: false, curve, .. } if curve == "wiggle"));
        assert_eq!(ops[6], &Op::Ungroup);
        assert_eq!((g.rules[0].line, g.rules[0].column), (4, 1));
        assert_eq!(g.rules[0].outputs, ["b", "c"]);
        assert_eq!(g.rules[1].outputs, ["b"]);
        let defs: Vec<(&str, DefKind, usize)> = g
            .defs
            .iter()
            .map(|d| (d.name.as_str(), d.kind, d.line))
            .collect();
        assert_eq!(
            defs,
            [
                ("wiggle", DefKind::Curve, 10),
                ("star", DefKind::Shape, 11),
                ("bow", DefKind::Curve, 12),
                ("w", DefKind::Curve, 13),
                ("l", DefKind::Curve, 14),
                ("round", DefKind::Shape, 15),
            ]
        );
        assert_eq!(g.defs[2].curve, CurveDef::Arc { bulge: -0.5 });
        assert_eq!(g.defs[5].curve, CurveDef::Circle);
    }

    /// The grammar without its lines and columns.
    fn positionless(mut g: Grammar) -> Grammar {
        g.defs.iter_mut().for_each(|d| d.line = 0);
        g.start.iter_mut().for_each(|s| s.line = 0);
        g.rules.iter_mut().for_each(|r| (r.line, r.column) = (0, 0));
        g
    }

    #[test]
    fn to_text_reads_back_to_the_same_grammar() {
        let texts = [
            LEAF.to_string(),
            "curve c = wave(2.5, 12)\nshape s = svg(\"M 0 0 L 4 0 L 2 3 Z\")\nshape t = ngon(5)\n\
             start polygon(0 0, 10 0, 5 8) : a\nstart svg(\"M0 0h10v10z\") : a\nstart text(\"a \\\"q\\\" \\\\\") : b\n\
             regularSplit(c, [3, 4.5], 1) : a -> [b]\nplace(3, 1, s) : b -> [c, d]\n\
             streamlineSplit(circular, 7) : c -> e\nfill(0.3) : d -> f\n"
                .to_string(),
        ];
        for t in texts {
            let g = parse(&t).unwrap();
            let written = to_text(&g);
            let again = parse(&written).unwrap_or_else(|e| panic!("{written}\n{e}"));
            assert_eq!(positionless(again), positionless(g), "{written}");
        }
    }

    #[test]
    fn limits_are_named_and_bound_the_input() {
        let long = format!("fill() : a -> b\n{}", "#".repeat(MAX_TEXT_BYTES));
        let e = parse(&long).unwrap_err();
        assert_eq!(e.kind(), "limit");
        assert!(e.to_string().contains("MAX_TEXT_BYTES"), "{e}");

        let mut many = "fill() : a -> b\n".repeat(MAX_RULES);
        assert_eq!(parse(&many).unwrap().rules.len(), MAX_RULES);
        many.push_str("fill() : a -> b\n");
        let e = parse(&many).unwrap_err();
        assert_eq!(e.position(), Some((MAX_RULES + 1, 1)));
        assert!(e.to_string().contains("MAX_RULES"), "{e}");

        let pts = |n: usize| {
            let p: Vec<String> = (0..n).map(|i| format!("{i} {}", i % 2)).collect();
            format!("curve c = polyline({})\nfill() : a -> b", p.join(","))
        };
        let g = parse(&pts(MAX_POLYLINE_POINTS)).unwrap();
        assert!(
            matches!(&g.defs[0].curve, CurveDef::Polyline(p) if p.len() == MAX_POLYLINE_POINTS)
        );
        let text = pts(MAX_POLYLINE_POINTS + 1);
        let e = parse(&text).unwrap_err();
        let col = text.find(&format!(",{} ", MAX_POLYLINE_POINTS)).unwrap() + 2;
        assert_eq!(e.position(), Some((1, col)));
        assert!(e.to_string().contains("MAX_POLYLINE_POINTS"), "{e}");

        let word = "W".repeat(MAX_START_TEXT_CHARS + 1);
        let e = parse(&format!("start text(\"{word}\") : a\nfill() : a -> b")).unwrap_err();
        assert!(e.to_string().contains("MAX_START_TEXT_CHARS"), "{e}");
    }

    #[test]
    fn deep_brackets_and_garbage_neither_panic_nor_recurse() {
        // 200k nested brackets: the parser has no recursion to overflow.
        let deep = format!(
            "outline({}25{}) : a -> b",
            "(".repeat(100_000),
            ")".repeat(100_000)
        );
        let e = parse(&deep).unwrap_err();
        assert_eq!(e.position(), Some((1, 9)));
        let deep = format!("outline({}25) : a -> b", "[".repeat(100_000));
        assert!(parse(&deep).is_err());
        // One-byte corruptions of the leaf parse or fail at a position
        // inside the text.
        let bytes = LEAF.as_bytes();
        for i in (0..bytes.len()).step_by(5) {
            for b in [
                b'(', b')', b'[', b']', b':', b'"', b'-', b'>', b' ', b'\n', b'9', b'x', 0xE2,
            ] {
                let mut v = bytes.to_vec();
                v[i] = b;
                let text = String::from_utf8_lossy(&v);
                if let Err(e) = parse(&text) {
                    let (l, c) = e.position().expect("a syntax error");
                    let n = text.split('\n').nth(l - 1).map(|l| l.chars().count());
                    assert!(
                        n.is_some_and(|n| c >= 1 && c <= n + 1),
                        "{e} for byte {i} = {b}"
                    );
                }
            }
        }
    }

    #[test]
    fn messages_quote_at_most_a_few_words_of_the_input() {
        let long = "x".repeat(100_000);
        for text in [
            format!("{long}(1) : a -> b"),
            format!("outline(1) : a -> b\nregularSplit({long}, 3) : a -> b"),
            format!("outline({}.) : a -> b", "1".repeat(100_000)),
            format!("outline(1) : a b {} -> c", "w ".repeat(50_000)),
        ] {
            let e = parse(&text).unwrap_err();
            assert!(e.to_string().len() < 400, "{}", &e.to_string()[..400]);
        }
    }

    #[test]
    fn names_may_be_used_before_they_are_defined() {
        let g = parse("regularSplit(teeth, 10) : a -> b\ncurve teeth = zigzag(3, 9)").unwrap();
        assert_eq!(g.defs[0].name, "teeth");
        assert!(matches!(&g.rules[0].op, Op::Split { curve, .. } if curve == "teeth"));
    }
}
