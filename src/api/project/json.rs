//! A resumable JSON reader for project files, so `open-project` reads a
//! 25 MB file in bounded slices (serde_json cannot stop and resume).
//!
//! It builds exactly the [`Value`] that [`Value::read`] builds from a
//! `serde_json::Deserializer` with `project = true` followed by
//! `Deserializer::end` ([`read_at_once`]): the same JSON grammar (numbers,
//! escapes, surrogate pairs, control characters, trailing characters), the
//! same `{"$bytes": base64}` decoding, the same limits
//! ([`limits::MAX_STATE_VALUES`], [`limits::MAX_STATE_DEPTH`]) checked at
//! the same points with the same errors, and a repeated key keeping its
//! last value at its first place. Only the wording of a syntax error
//! differs; it names what is wrong and its line and column.
//!
//! Nesting is an explicit stack (no recursion), so no depth can overflow
//! the stack. Work is measured in fuel: a byte of input costs 1, a value
//! [`VALUE_COST`]; [`Reader::step`] stops when its fuel is spent, in the
//! middle of a string, a number or the base64 of a `$bytes` field if need
//! be, and goes on from there at the next call.
use crate::core::error::{Error, Result};
use crate::core::limits;
use crate::core::value::{too_deep, too_many, Value};
use std::collections::HashMap;

/// Fuel one value costs besides its bytes (a number is parsed, a value
/// pushed).
pub const VALUE_COST: usize = 16;

/// The message of a `$bytes` field that is not base64 (as [`Value::read`]).
pub use crate::core::value::NOT_BASE64;

/// Read `text` in one go with serde_json ([`Value::read`], `project =
/// true`, then nothing but whitespace may follow): the reference the
/// stepped [`Reader`] agrees with.
pub fn read_at_once(text: &str) -> Result<Value> {
    let mut de = serde_json::Deserializer::from_str(text);
    let v = Value::read(&mut de, true)?;
    de.end().map_err(|e| Error::input(e.to_string()))?;
    Ok(v)
}

/// Read `text` with the stepped [`Reader`], `fuel` per step, to the end.
pub fn read_stepped(text: &str, fuel: usize) -> Result<Value> {
    let mut r = Reader::new();
    loop {
        if let Some(v) = r.step(text, fuel)? {
            return Ok(v);
        }
    }
}

/// An open list or object.
enum Frame {
    List(Vec<Value>),
    Object {
        entries: Vec<(String, Value)>,
        /// Where each key is in `entries`.
        index: HashMap<String, usize>,
        /// The key whose value is being read.
        key: Option<String>,
    },
}

/// Where a number token is.
#[derive(Clone, Copy, PartialEq)]
enum Num {
    /// After `-`: a digit must follow.
    Minus,
    /// After a leading `0`: no digit may follow.
    Zero,
    Int,
    /// After `.`: a digit must follow.
    Dot,
    Frac,
    /// After `e`: a sign or a digit.
    E,
    /// After the exponent's sign: a digit.
    ESign,
    Exp,
}

/// A `$bytes` field being decoded as the page's `atob` decodes it (as
/// [`super::base64_decode`]: ASCII whitespace ignored, up to two `=` at the
/// end when the length is a multiple of 4).
struct Base64 {
    text: String,
    /// Next byte of `text`.
    at: usize,
    acc: u32,
    /// Base64 digits fed into `acc` (not counting `=`).
    digits: usize,
    /// `=` seen since the last digit.
    pads: usize,
    out: Vec<u8>,
}

/// What the reader expects next.
enum Mode {
    /// A value (after whitespace). `after_comma`: a `]` here is a trailing comma.
    Value { after_comma: bool },
    /// Just after `[`: a value or `]`.
    ListStart,
    /// Just after `{`: a key or `}`.
    ObjectStart,
    /// After a value in the open list or object: `,` or its end.
    AfterValue,
    /// After `,` in an object: a key.
    Key,
    /// After a key: `:`.
    Colon,
    /// Inside a string (a key or a value): its text so far, and the
    /// look-ahead for its end (see [`Reader::string`]).
    Str { key: bool, buf: String, end: Ahead },
    /// Inside a number that started at byte `start`.
    Number { start: usize, at: Num },
    /// Decoding the base64 of a `$bytes` object.
    Bytes(Box<Base64>),
    /// The value is read: only whitespace may follow.
    Trailing(Box<Value>),
    /// An error was returned or the value was handed out.
    Over,
}

/// How far a string's look-ahead for its closing quote has come.
#[derive(Clone, Copy)]
enum Ahead {
    /// Scanned to this byte.
    At(usize),
    /// Done: the string's raw bytes end at or before this one.
    Found,
}

/// The reader's state between steps (the text is passed to every step).
pub struct Reader {
    pos: usize,
    /// Line (1-based) of `pos` and the byte where that line starts.
    line: usize,
    line_start: usize,
    stack: Vec<Frame>,
    mode: Mode,
    /// Values that may still be read.
    left: usize,
}

impl Default for Reader {
    fn default() -> Self {
        Self::new()
    }
}

/// What the next byte after whitespace is.
enum Peek {
    Byte(u8),
    Eof,
    /// The fuel ran out in whitespace.
    Later,
}

fn hex4(b: &[u8]) -> Option<u16> {
    let mut n = 0u16;
    for &c in b {
        n = n << 4 | (c as char).to_digit(16)? as u16;
    }
    Some(n)
}

/// The value of a base64 digit (255: not one).
const fn b64_table() -> [u8; 256] {
    let mut t = [255u8; 256];
    let mut i = 0;
    while i < 26 {
        t[b'A' as usize + i] = i as u8;
        t[b'a' as usize + i] = 26 + i as u8;
        i += 1;
    }
    let mut d = 0;
    while d < 10 {
        t[b'0' as usize + d] = 52 + d as u8;
        d += 1;
    }
    t[b'+' as usize] = 62;
    t[b'/' as usize] = 63;
    t
}
const B64: [u8; 256] = b64_table();

/// A number token's value, parsed by serde_json itself (so every digit
/// rule and rounding is serde_json's): what [`Value::read`]'s visitor makes
/// of `visit_u64`/`visit_i64`/`visit_f64`.
fn number(token: &str) -> std::result::Result<f64, serde_json::Error> {
    struct F;
    impl serde::de::Visitor<'_> for F {
        type Value = f64;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a number")
        }
        fn visit_u64<E>(self, v: u64) -> std::result::Result<f64, E> {
            Ok(v as f64)
        }
        fn visit_i64<E>(self, v: i64) -> std::result::Result<f64, E> {
            Ok(v as f64)
        }
        fn visit_f64<E>(self, v: f64) -> std::result::Result<f64, E> {
            Ok(v)
        }
    }
    let mut de = serde_json::Deserializer::from_str(token);
    let v = serde::Deserializer::deserialize_any(&mut de, F)?;
    de.end()?;
    Ok(v)
}

impl Reader {
    pub fn new() -> Self {
        Reader {
            pos: 0,
            line: 1,
            line_start: 0,
            stack: vec![],
            mode: Mode::Value { after_comma: false },
            left: limits::MAX_STATE_VALUES,
        }
    }

    /// How far into the text the reader is (bytes).
    pub fn position(&self) -> usize {
        self.pos
    }

    /// A syntax error at byte `at` (on the current line).
    fn syntax(&self, what: &str, at: usize) -> Error {
        Error::input(format!(
            "{what} at line {} column {}",
            self.line,
            at.saturating_sub(self.line_start) + 1
        ))
    }

    /// Skip whitespace (as serde_json: space, tab, CR, LF).
    fn ws(&mut self, b: &[u8], fuel: &mut usize) -> Peek {
        while let Some(&c) = b.get(self.pos) {
            match c {
                b' ' | b'\t' | b'\r' | b'\n' => {
                    self.pos += 1;
                    if c == b'\n' {
                        self.line += 1;
                        self.line_start = self.pos;
                    }
                    *fuel = fuel.saturating_sub(1);
                    if *fuel == 0 {
                        return Peek::Later;
                    }
                }
                c => return Peek::Byte(c),
            }
        }
        Peek::Eof
    }

    fn count(&mut self) -> Result<()> {
        self.left = self
            .left
            .checked_sub(1)
            .ok_or_else(|| too_many("project"))?;
        Ok(())
    }

    /// A value is complete: into the open container, or it is the whole text.
    fn complete(&mut self, v: Value) {
        self.mode = Mode::AfterValue;
        match self.stack.last_mut() {
            Some(Frame::List(items)) => items.push(v),
            Some(Frame::Object {
                entries,
                index,
                key,
            }) => {
                let k = key.take().unwrap_or_default();
                match index.get(&k) {
                    Some(&i) => entries[i].1 = v,
                    None => {
                        index.insert(k.clone(), entries.len());
                        entries.push((k, v));
                    }
                }
            }
            None => self.mode = Mode::Trailing(Box::new(v)),
        }
    }

    /// `[` or `{` was read: counted, then the depth checked (as the visitor).
    fn open(&mut self, frame: Frame) -> Result<()> {
        self.count()?;
        if self.stack.len() >= limits::MAX_STATE_DEPTH {
            return Err(too_deep("project"));
        }
        self.mode = match frame {
            Frame::List(_) => Mode::ListStart,
            Frame::Object { .. } => Mode::ObjectStart,
        };
        self.stack.push(frame);
        Ok(())
    }

    /// The `]` or `}` at `pos` closes the innermost container.
    fn close(&mut self) -> Result<()> {
        self.pos += 1;
        match self.stack.pop() {
            Some(Frame::List(items)) => self.complete(Value::List(items)),
            Some(Frame::Object {
                mut entries, index, ..
            }) => {
                if let Some(&i) = index.get("$bytes") {
                    if let Value::Text(t) = &mut entries[i].1 {
                        let text = std::mem::take(t);
                        self.mode = Mode::Bytes(Box::new(Base64 {
                            out: Vec::with_capacity(text.len() / 4 * 3 + 2),
                            text,
                            at: 0,
                            acc: 0,
                            digits: 0,
                            pads: 0,
                        }));
                        return Ok(());
                    }
                }
                self.complete(Value::Object(entries))
            }
            None => return Err(self.syntax("unexpected end of a list or object", self.pos)),
        }
        Ok(())
    }

    /// Read on for about `fuel` units of work; `Some(value)` once the whole
    /// text is read. After an error or the value, the reader is spent.
    pub fn step(&mut self, text: &str, fuel: usize) -> Result<Option<Value>> {
        let b = text.as_bytes();
        let mut fuel = fuel.max(1);
        while fuel > 0 {
            let mode = std::mem::replace(&mut self.mode, Mode::Over);
            match mode {
                Mode::Over => return Err(Error::input("the project reader has already finished")),
                Mode::Value { after_comma } => match self.ws(b, &mut fuel) {
                    Peek::Later => self.mode = mode,
                    Peek::Eof => {
                        return Err(self.syntax("end of file where a value should be", self.pos))
                    }
                    Peek::Byte(c) => self.value(b, c, after_comma, &mut fuel)?,
                },
                Mode::ListStart => match self.ws(b, &mut fuel) {
                    Peek::Later => self.mode = mode,
                    Peek::Eof => return Err(self.syntax("end of file inside a list", self.pos)),
                    Peek::Byte(b']') => self.close()?,
                    Peek::Byte(_) => self.mode = Mode::Value { after_comma: false },
                },
                Mode::ObjectStart | Mode::Key => {
                    let start = matches!(mode, Mode::ObjectStart);
                    match self.ws(b, &mut fuel) {
                        Peek::Later => self.mode = mode,
                        Peek::Eof if start => {
                            return Err(self.syntax("end of file inside an object", self.pos))
                        }
                        Peek::Eof => {
                            return Err(self.syntax("end of file where a key should be", self.pos))
                        }
                        Peek::Byte(b'}') if start => self.close()?,
                        Peek::Byte(b'}') => {
                            return Err(self.syntax("a comma before `}` (trailing comma)", self.pos))
                        }
                        Peek::Byte(b'"') => {
                            self.pos += 1;
                            self.mode = Mode::Str {
                                key: true,
                                buf: String::new(),
                                end: Ahead::At(self.pos),
                            };
                        }
                        Peek::Byte(_) => {
                            return Err(self.syntax("a key that is not a string", self.pos))
                        }
                    }
                }
                Mode::Colon => match self.ws(b, &mut fuel) {
                    Peek::Later => self.mode = mode,
                    Peek::Eof => return Err(self.syntax("end of file inside an object", self.pos)),
                    Peek::Byte(b':') => {
                        self.pos += 1;
                        self.mode = Mode::Value { after_comma: false };
                    }
                    Peek::Byte(_) => return Err(self.syntax("expected `:` after a key", self.pos)),
                },
                Mode::AfterValue => {
                    let list = matches!(self.stack.last(), Some(Frame::List(_)));
                    match self.ws(b, &mut fuel) {
                        Peek::Later => self.mode = mode,
                        Peek::Eof if list => {
                            return Err(self.syntax("end of file inside a list", self.pos))
                        }
                        Peek::Eof => {
                            return Err(self.syntax("end of file inside an object", self.pos))
                        }
                        Peek::Byte(b']') if list => self.close()?,
                        Peek::Byte(b'}') if !list => self.close()?,
                        Peek::Byte(b',') => {
                            self.pos += 1;
                            self.mode = if list {
                                Mode::Value { after_comma: true }
                            } else {
                                Mode::Key
                            };
                        }
                        Peek::Byte(_) if list => {
                            return Err(self.syntax("expected `,` or `]` in a list", self.pos))
                        }
                        Peek::Byte(_) => {
                            return Err(self.syntax("expected `,` or `}` in an object", self.pos))
                        }
                    }
                }
                Mode::Str { key, buf, end } => self.string(text, key, buf, end, &mut fuel)?,
                Mode::Number { start, at } => self.number(text, start, at, &mut fuel)?,
                Mode::Bytes(d) => self.base64(d, &mut fuel)?,
                Mode::Trailing(v) => match self.ws(b, &mut fuel) {
                    Peek::Later => self.mode = Mode::Trailing(v),
                    Peek::Eof => return Ok(Some(*v)),
                    Peek::Byte(_) => {
                        return Err(self.syntax("trailing characters after the value", self.pos))
                    }
                },
            }
        }
        Ok(None)
    }

    /// The first byte `c` of a value is at `pos`.
    fn value(&mut self, b: &[u8], c: u8, after_comma: bool, fuel: &mut usize) -> Result<()> {
        *fuel = fuel.saturating_sub(VALUE_COST);
        let lit = |word: &'static [u8], v: Value, r: &mut Self| -> Result<()> {
            let rest = &b[r.pos..];
            if rest.starts_with(word) {
                r.pos += word.len();
                r.count()?;
                r.complete(v);
                Ok(())
            } else {
                let what = if word.starts_with(rest) {
                    "end of file inside a literal"
                } else {
                    "an unknown word (expected null, true or false)"
                };
                Err(r.syntax(what, r.pos))
            }
        };
        match c {
            b'n' => lit(b"null", Value::Null, self),
            b't' => lit(b"true", Value::Bool(true), self),
            b'f' => lit(b"false", Value::Bool(false), self),
            b'-' | b'0'..=b'9' => {
                let at = match c {
                    b'-' => Num::Minus,
                    b'0' => Num::Zero,
                    _ => Num::Int,
                };
                self.mode = Mode::Number {
                    start: self.pos,
                    at,
                };
                self.pos += 1;
                Ok(())
            }
            b'"' => {
                self.pos += 1;
                self.mode = Mode::Str {
                    key: false,
                    buf: String::new(),
                    end: Ahead::At(self.pos),
                };
                Ok(())
            }
            b'[' => {
                self.pos += 1;
                self.open(Frame::List(vec![]))
            }
            b'{' => {
                self.pos += 1;
                self.open(Frame::Object {
                    entries: vec![],
                    index: HashMap::new(),
                    key: None,
                })
            }
            b']' if after_comma => {
                Err(self.syntax("a comma before `]` (trailing comma)", self.pos))
            }
            _ => Err(self.syntax("expected a value", self.pos)),
        }
    }

    /// Inside a string. First a look-ahead for its closing quote (half
    /// of a unit a byte), so its text is allocated once at its final size
    /// (a 22 MB base64 string is not grown by copying); then its text is
    /// copied up to `fuel` bytes a step, stopping at its end, an escape or a
    /// control character.
    fn string(
        &mut self,
        text: &str,
        key: bool,
        mut buf: String,
        mut end: Ahead,
        fuel: &mut usize,
    ) -> Result<()> {
        let b = text.as_bytes();
        if let Ahead::At(from) = end {
            let lim = b.len().min(from.saturating_add(fuel.saturating_mul(2)));
            let mut at = from;
            while at < lim {
                match b[at] {
                    b'\\' => at += 2,
                    b'"' => break,
                    c if c < 0x20 => break,
                    _ => at += 1,
                }
            }
            *fuel = fuel.saturating_sub((at.min(lim) - from).div_ceil(2));
            if at < lim || lim == b.len() {
                // Escapes only shorten the text.
                buf.reserve(at.min(b.len()) - self.pos);
                end = Ahead::Found;
            } else {
                *fuel = 0;
                self.mode = Mode::Str {
                    key,
                    buf,
                    end: Ahead::At(at),
                };
                return Ok(());
            }
            if *fuel == 0 {
                self.mode = Mode::Str { key, buf, end };
                return Ok(());
            }
        }
        let mut lim = b.len().min(self.pos.saturating_add(*fuel));
        let run = &b[self.pos..lim];
        let stop = run
            .iter()
            .position(|&c| c == b'"' || c == b'\\' || c < 0x20);
        let Some(i) = stop else {
            if lim == b.len() {
                return Err(self.syntax("end of file inside a string", lim));
            }
            // Stop at a character boundary (at least one character on).
            while !text.is_char_boundary(lim) {
                lim += 1;
            }
            buf.push_str(&text[self.pos..lim]);
            *fuel = fuel.saturating_sub(lim - self.pos);
            self.pos = lim;
            self.mode = Mode::Str { key, buf, end };
            return Ok(());
        };
        // `"`, `\` and control characters are ASCII: a character boundary.
        buf.push_str(&text[self.pos..self.pos + i]);
        *fuel = fuel.saturating_sub(i + 1);
        self.pos += i;
        match b[self.pos] {
            b'"' => {
                self.pos += 1;
                if key {
                    if let Some(Frame::Object { key, .. }) = self.stack.last_mut() {
                        *key = Some(buf);
                    }
                    self.mode = Mode::Colon;
                } else {
                    *fuel = fuel.saturating_sub(VALUE_COST);
                    self.count()?;
                    self.complete(Value::Text(buf));
                }
                Ok(())
            }
            b'\\' => {
                self.escape(b, &mut buf)?;
                self.mode = Mode::Str { key, buf, end };
                Ok(())
            }
            _ => Err(self.syntax(
                "a control character (U+0000 to U+001F) inside a string",
                self.pos,
            )),
        }
    }

    /// The escape whose `\` is at `pos`, as serde_json reads it: the
    /// characters are `" \ / b f n r t` and `u` with four hex digits; a
    /// surrogate must be a high one followed by `\u` and a low one.
    fn escape(&mut self, b: &[u8], buf: &mut String) -> Result<()> {
        let at = self.pos;
        let eof = |r: &Self| r.syntax("end of file inside a string", b.len());
        let c = *b.get(at + 1).ok_or_else(|| eof(self))?;
        self.pos = at + 2;
        let simple = match c {
            b'"' => b'"',
            b'\\' => b'\\',
            b'/' => b'/',
            b'b' => 8,
            b'f' => 12,
            b'n' => b'\n',
            b'r' => b'\r',
            b't' => b'\t',
            b'u' => 0,
            _ => return Err(self.syntax("an unknown escape in a string", at)),
        };
        if c != b'u' {
            buf.push(simple as char);
            return Ok(());
        }
        let hex = |r: &Self, from: usize| -> Result<u16> {
            let d = b.get(from..from + 4).ok_or_else(|| eof(r))?;
            hex4(d).ok_or_else(|| r.syntax("a \\u escape without four hex digits", from))
        };
        let n = hex(self, at + 2)?;
        self.pos = at + 6;
        let ch = match n {
            0xDC00..=0xDFFF => {
                return Err(self.syntax("a lone low surrogate in a \\u escape", at));
            }
            0xD800..=0xDBFF => {
                match b.get(at + 6..at + 8) {
                    Some(b"\\u") => {}
                    Some(_) => {
                        return Err(self
                            .syntax("a high surrogate \\u escape not followed by a low one", at))
                    }
                    None if b.get(at + 6).is_none_or(|&c| c == b'\\') => return Err(eof(self)),
                    None => {
                        return Err(self
                            .syntax("a high surrogate \\u escape not followed by a low one", at))
                    }
                }
                let n2 = hex(self, at + 8)?;
                if !(0xDC00..=0xDFFF).contains(&n2) {
                    return Err(
                        self.syntax("a high surrogate \\u escape not followed by a low one", at)
                    );
                }
                self.pos = at + 12;
                char::from_u32((((n - 0xD800) as u32) << 10 | (n2 - 0xDC00) as u32) + 0x1_0000)
            }
            n => char::from_u32(n as u32),
        };
        let ch = ch.ok_or_else(|| self.syntax("an invalid \\u escape", at))?;
        buf.push(ch);
        Ok(())
    }

    /// Inside a number token: scan its digits (the JSON grammar, as
    /// serde_json's), then let serde_json turn the token into a number.
    fn number(&mut self, text: &str, start: usize, mut at: Num, fuel: &mut usize) -> Result<()> {
        let b = text.as_bytes();
        let bad = |r: &Self, pos: usize| r.syntax("an invalid number", pos);
        loop {
            let Some(&c) = b.get(self.pos) else {
                if matches!(at, Num::Minus | Num::Dot | Num::E | Num::ESign) {
                    return Err(self.syntax("end of file inside a number", self.pos));
                }
                break;
            };
            let digit = c.is_ascii_digit();
            at = match (at, c) {
                (Num::Minus, b'0') => Num::Zero,
                (Num::Minus | Num::Int, _) if digit => Num::Int,
                (Num::Zero, _) if digit => return Err(bad(self, self.pos)),
                (Num::Zero | Num::Int, b'.') => Num::Dot,
                (Num::Dot | Num::Frac, _) if digit => Num::Frac,
                (Num::Zero | Num::Int | Num::Frac, b'e' | b'E') => Num::E,
                (Num::E, b'+' | b'-') => Num::ESign,
                (Num::E | Num::ESign | Num::Exp, _) if digit => Num::Exp,
                (Num::Minus | Num::Dot | Num::E | Num::ESign, _) => {
                    return Err(bad(self, self.pos))
                }
                _ => break,
            };
            self.pos += 1;
            *fuel = fuel.saturating_sub(1);
            if *fuel == 0 {
                self.mode = Mode::Number { start, at };
                return Ok(());
            }
        }
        let v = number(&text[start..self.pos]).map_err(|e| {
            let why = if e.to_string().contains("out of range") {
                "a number out of range"
            } else {
                "an invalid number"
            };
            self.syntax(why, start)
        })?;
        *fuel = fuel.saturating_sub(VALUE_COST);
        self.count()?;
        self.complete(Value::Number(v));
        Ok(())
    }

    /// Decode up to `fuel` bytes of a `$bytes` field's base64.
    fn base64(&mut self, mut d: Box<Base64>, fuel: &mut usize) -> Result<()> {
        let t = d.text.as_bytes();
        let end = t.len().min(d.at.saturating_add(*fuel));
        for &c in &t[d.at..end] {
            match c {
                b' ' | b'\t' | b'\n' | b'\x0c' | b'\r' => {}
                b'=' => d.pads += 1,
                c => {
                    let v = B64[c as usize];
                    // Not base64, or a digit after `=`.
                    if v == 255 || d.pads > 0 {
                        return Err(Error::input(NOT_BASE64));
                    }
                    d.acc = d.acc << 6 | v as u32;
                    d.digits += 1;
                    if d.digits.is_multiple_of(4) {
                        let a = d.acc;
                        d.out
                            .extend_from_slice(&[(a >> 16) as u8, (a >> 8) as u8, a as u8]);
                        d.acc = 0;
                    }
                }
            }
        }
        *fuel -= end - d.at;
        d.at = end;
        if end < t.len() {
            self.mode = Mode::Bytes(d);
            return Ok(());
        }
        // The end: up to two `=` are padding when the length with them is a
        // multiple of 4; any other `=` is not base64, nor is a last group
        // of one digit.
        let total = d.digits + d.pads;
        let pad = if total.is_multiple_of(4) {
            d.pads.min(2)
        } else {
            0
        };
        let rest = d.digits % 4;
        if d.pads > pad || rest == 1 {
            return Err(Error::input(NOT_BASE64));
        }
        if rest > 1 {
            let a = d.acc << (6 * (4 - rest));
            d.out.push((a >> 16) as u8);
            if rest == 3 {
                d.out.push((a >> 8) as u8);
            }
        }
        *fuel = fuel.saturating_sub(VALUE_COST);
        let out = std::mem::take(&mut d.out);
        self.complete(Value::Bytes(out));
        Ok(())
    }
}

#[cfg(test)]
mod tests;
