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
                    .map_err(|_| syntax(line, col, format!("'{s}' is not a number")))?;
                if !v.is_finite() {
                    return Err(syntax(
                        line,
                        col,
                        format!("the number '{s}' is too large: numbers must be finite"),
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
        chars[start..j].iter().map(|c| c.1).collect::<String>()
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
                    chars[start..i].iter().map(|c| c.1).collect::<String>()
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
            Some(Tok::Ident(n)) => format!("'{n}'"),
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
}

impl Parser {
    fn statement(&mut self, cur: &mut Cursor) -> Result<()> {
        let first = cur.peek().expect("a statement has tokens");
        let second = cur.toks.get(1).map(|t| &t.tok);
        match (&first.tok, second) {
            (Tok::Ident(kw @ ("curve" | "shape")), Some(Tok::Ident(_))) => {
                let kind = if *kw == "curve" {
                    DefKind::Curve
                } else {
                    DefKind::Shape
                };
                self.definition(cur, kind)
            }
            (Tok::Ident("start"), s) if s != Some(&Tok::Sym('(')) => self.start(cur),
            (Tok::Ident(_), _) => self.rule(cur),
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
                format!("unknown operator '{name}': {hint}the operators are {OPERATOR_LIST}"),
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
                cur.found()
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
        let (name, name_col) = cur.ident().expect("checked by statement");
        let kw = match kind {
            DefKind::Curve => "curve",
            DefKind::Shape => "shape",
        };
        if name == BUILTIN_CURVE || name == BUILTIN_SHAPE {
            return Err(cur.err_at(
                name_col,
                format!("'{name}' is built in: give your {kw} another name"),
            ));
        }
        if let Some(d) = self.g.defs.iter().find(|d| d.name == name) {
            return Err(cur.err_at(
                name_col,
                format!(
                    "'{name}' is already defined on line {}: give this {kw} another name",
                    d.line
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
                format!("unknown {kw} '{ctor}': {hint}{ctor_usage}"),
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
            return Err(cur.err_at(col, format!("unknown start shape '{ctor}': {hint}{usage}")));
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
        let Parser { g, refs } = self;
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
            match g.defs.iter().find(|d| d.name == r.name) {
                Some(d) if d.kind == r.kind => {}
                Some(d) => {
                    return Err(syntax(
                        r.line,
                        r.col,
                        format!(
                            "'{}' (line {}) is a {other}, and {} needs a {kw}: define a {kw} and use its name",
                            r.name, d.line, r.op
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
                        DefKind::Curve => format!("curve {} = zigzag(5, 20)", r.name),
                        DefKind::Shape => format!("shape {} = ngon(6)", r.name),
                    };
                    return Err(syntax(
                        r.line,
                        r.col,
                        format!(
                            "unknown {kw} '{}': {hint}use {builtin} or define it on a line of its own, as in {example}",
                            r.name
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
                            "{callee} has no parameter '{k}': {hint}its parameters are {}",
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
                    "unknown {what} '{n}': {hint}it is one of {}",
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
        }) = cur.toks.get(j)
        {
            words.push(w);
            j += 1;
        }
        return Err(cur.err(format!("tags are one word: write {}", words.join("_"))));
    }
    Ok(t.to_string())
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
    (best.0 <= allowed).then_some(best.1)
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
mod tests {}
