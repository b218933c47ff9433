//! A tool state as the page holds it: plain JS data read with a bounded
//! reader ([`Value::read`]), and the helpers every tool's `state` module uses
//! to check one (plain words, JS lengths, the largest safe integer), plus
//! base64 for byte fields. Below every tool: `api::project` (project files)
//! and each `src/<tool>/state.rs` read states through it.
use crate::core::error::{Error, Result};
use crate::core::limits;
use serde::de::{self, DeserializeSeed, MapAccess, SeqAccess, Visitor};
use serde::ser::{SerializeMap, SerializeSeq};
use serde::{Deserialize, Deserializer, Serialize, Serializer};
use std::cell::{Cell, RefCell};
use std::collections::HashMap;
use std::fmt;

/// The message for a `{"$bytes": …}` whose text is not base64.
pub const NOT_BASE64: &str = "the project holds image data that is not valid base64";

/// The largest whole number a page's number holds exactly (2^53 − 1).
pub const MAX_SAFE_INTEGER: f64 = 9_007_199_254_740_991.0;

// ------------------------------------------------------------------ values --

/// A state as the page holds it: plain JS data (numbers are doubles, bytes
/// are `Uint8Array`s). Read with a bounded reader ([`Value::read`]): at most
/// [`limits::MAX_STATE_VALUES`] values, nested at most
/// [`limits::MAX_STATE_DEPTH`] deep.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Value {
    /// `null` (and a JS `undefined`).
    #[default]
    Null,
    Bool(bool),
    Number(f64),
    Text(String),
    Bytes(Vec<u8>),
    List(Vec<Value>),
    /// Keys in first-seen order, each once (a repeated key keeps its last value).
    Object(Vec<(String, Value)>),
}

impl Value {
    /// Read a value with any self-describing deserializer (`serde_json`,
    /// `serde_wasm_bindgen`), bounded. `project`: decode `{"$bytes": base64}`
    /// objects (a project file's byte fields) into bytes.
    pub fn read<'de, D: Deserializer<'de>>(d: D, project: bool) -> Result<Value> {
        let ctx = ReadCtx {
            left: Cell::new(limits::MAX_STATE_VALUES),
            failure: RefCell::new(None),
            project,
        };
        let r = Reader {
            ctx: &ctx,
            depth: 0,
        }
        .deserialize(d);
        if let Some(e) = ctx.failure.into_inner() {
            return Err(e);
        }
        r.map_err(|e| Error::input(e.to_string()))
    }

    /// The value of `key` of an object (`None` for a missing key or a non-object).
    pub fn get(&self, key: &str) -> Option<&Value> {
        match self {
            Value::Object(kv) => kv.iter().find(|(k, _)| k == key).map(|(_, v)| v),
            _ => None,
        }
    }

    /// Whether this is JS-`typeof` `object` and not null: an object, a list
    /// or bytes.
    pub fn is_object_like(&self) -> bool {
        matches!(self, Value::Object(_) | Value::List(_) | Value::Bytes(_))
    }

    /// A plain object (not a list, not bytes).
    pub fn is_plain_object(&self) -> bool {
        matches!(self, Value::Object(_))
    }

    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Value::Number(v) => Some(*v),
            _ => None,
        }
    }

    /// A whole number (JS `Number.isInteger`).
    pub fn whole(&self) -> Option<f64> {
        self.as_f64().filter(|v| v.is_finite() && v.fract() == 0.0)
    }

    pub fn as_text(&self) -> Option<&str> {
        match self {
            Value::Text(s) => Some(s),
            _ => None,
        }
    }
}

/// `Option<&Value>` as JS reads it: a missing key and `null` are both "nullish".
pub fn nullish(v: Option<&Value>) -> bool {
    matches!(v, None | Some(Value::Null))
}

/// A number as JS writes it (`3`, `0.5`, `NaN`, `Infinity`).
pub fn js_number(v: f64) -> String {
    if v.is_nan() {
        "NaN".into()
    } else if v.is_infinite() {
        if v > 0.0 { "Infinity" } else { "-Infinity" }.into()
    } else if v.fract() == 0.0 && v.abs() < 1e21 {
        format!("{v:.0}")
    } else {
        format!("{v}")
    }
}

/// A value as JS's `String(v)` writes it (`undefined` for a missing one).
pub fn js_text(v: Option<&Value>) -> String {
    match v {
        None => "undefined".into(),
        Some(Value::Null) => "null".into(),
        Some(Value::Bool(b)) => b.to_string(),
        Some(Value::Number(n)) => js_number(*n),
        Some(Value::Text(s)) => s.clone(),
        Some(Value::Bytes(b)) => b.iter().map(u8::to_string).collect::<Vec<_>>().join(","),
        Some(Value::List(l)) => l
            .iter()
            .map(|x| match x {
                Value::Null => String::new(),
                x => js_text(Some(x)),
            })
            .collect::<Vec<_>>()
            .join(","),
        Some(Value::Object(_)) => "[object Object]".into(),
    }
}

/// The first `n` characters of `s` (JS `slice(0, n)`, counted in characters).
pub fn first_chars(s: &str, n: usize) -> String {
    s.chars().take(n).collect()
}

/// Length of `s` as JS counts it (UTF-16 code units).
pub fn js_len(s: &str) -> usize {
    s.encode_utf16().count()
}

/// An error about `field`: "`field` `why`" (the page's wording), tied to `field`.
pub fn invalid(field: &str, why: impl fmt::Display) -> Error {
    Error::input(format!("{field} {why}")).at(field)
}

/// More than [`limits::MAX_STATE_VALUES`] values in a `what` (`project`, `state`).
pub(crate) fn too_many(what: &str) -> Error {
    Error::limit(format!(
        "the {what} holds more than {} values (the state value limit)",
        limits::MAX_STATE_VALUES
    ))
}

/// Nested deeper than [`limits::MAX_STATE_DEPTH`].
pub(crate) fn too_deep(what: &str) -> Error {
    Error::limit(format!(
        "the {what} is nested too deeply (more than {} levels)",
        limits::MAX_STATE_DEPTH
    ))
}

struct ReadCtx {
    left: Cell<usize>,
    failure: RefCell<Option<Error>>,
    project: bool,
}

impl ReadCtx {
    fn fail<E: de::Error>(&self, e: Error) -> E {
        let msg = e.to_string();
        self.failure.borrow_mut().get_or_insert(e);
        E::custom(msg)
    }
    fn count<E: de::Error>(&self) -> std::result::Result<(), E> {
        match self.left.get().checked_sub(1) {
            Some(n) => {
                self.left.set(n);
                Ok(())
            }
            None => Err(self.fail(too_many(self.what()))),
        }
    }
    fn what(&self) -> &'static str {
        if self.project {
            "project"
        } else {
            "state"
        }
    }
}

#[derive(Clone, Copy)]
struct Reader<'a> {
    ctx: &'a ReadCtx,
    depth: usize,
}

impl<'de> DeserializeSeed<'de> for Reader<'_> {
    type Value = Value;
    fn deserialize<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Value, D::Error> {
        d.deserialize_any(self)
    }
}

impl Reader<'_> {
    fn inner<E: de::Error>(self) -> std::result::Result<Self, E> {
        if self.depth >= limits::MAX_STATE_DEPTH {
            return Err(self.ctx.fail(too_deep(self.ctx.what())));
        }
        Ok(Reader {
            ctx: self.ctx,
            depth: self.depth + 1,
        })
    }
}

impl<'de> Visitor<'de> for Reader<'_> {
    type Value = Value;

    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("plain data")
    }
    fn visit_unit<E: de::Error>(self) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Null)
    }
    fn visit_none<E: de::Error>(self) -> std::result::Result<Value, E> {
        self.visit_unit()
    }
    fn visit_some<D: Deserializer<'de>>(self, d: D) -> std::result::Result<Value, D::Error> {
        d.deserialize_any(self)
    }
    fn visit_bool<E: de::Error>(self, v: bool) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Bool(v))
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Number(v as f64))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Number(v as f64))
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Number(v))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Text(v.to_string()))
    }
    fn visit_string<E: de::Error>(self, v: String) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Text(v))
    }
    fn visit_bytes<E: de::Error>(self, v: &[u8]) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Bytes(v.to_vec()))
    }
    fn visit_byte_buf<E: de::Error>(self, v: Vec<u8>) -> std::result::Result<Value, E> {
        self.ctx.count()?;
        Ok(Value::Bytes(v))
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> std::result::Result<Value, A::Error> {
        self.ctx.count()?;
        let inner = self.inner()?;
        let mut out = Vec::with_capacity(seq.size_hint().unwrap_or(0).min(4096));
        while let Some(v) = seq.next_element_seed(inner)? {
            out.push(v);
        }
        Ok(Value::List(out))
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> std::result::Result<Value, A::Error> {
        self.ctx.count()?;
        let inner = self.inner()?;
        let mut out: Vec<(String, Value)> = Vec::new();
        let mut index: HashMap<String, usize> = HashMap::new();
        while let Some(k) = map.next_key::<String>()? {
            let v = map.next_value_seed(inner)?;
            match index.get(&k) {
                Some(&i) => out[i].1 = v,
                None => {
                    index.insert(k.clone(), out.len());
                    out.push((k, v));
                }
            }
        }
        if self.ctx.project {
            if let Some(Value::Text(b64)) = index.get("$bytes").map(|&i| &out[i].1) {
                return match base64_decode(b64) {
                    Some(bytes) => Ok(Value::Bytes(bytes)),
                    None => Err(self.ctx.fail(Error::input(NOT_BASE64))),
                };
            }
        }
        Ok(Value::Object(out))
    }
}

impl<'de> Deserialize<'de> for Value {
    /// A value as the page sends it (no `$bytes` decoding), bounded.
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Value, D::Error> {
        Value::read(d, false).map_err(|e| de::Error::custom(e.to_string()))
    }
}

impl Serialize for Value {
    fn serialize<S: Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        match self {
            Value::Null => s.serialize_unit(),
            Value::Bool(b) => s.serialize_bool(*b),
            Value::Number(n) if n.fract() == 0.0 && n.abs() <= MAX_SAFE_INTEGER => {
                s.serialize_i64(*n as i64)
            }
            Value::Number(n) => s.serialize_f64(*n),
            Value::Text(t) => s.serialize_str(t),
            Value::Bytes(b) => s.serialize_bytes(b),
            Value::List(l) => {
                let mut seq = s.serialize_seq(Some(l.len()))?;
                for v in l {
                    seq.serialize_element(v)?;
                }
                seq.end()
            }
            Value::Object(kv) => {
                let mut m = s.serialize_map(Some(kv.len()))?;
                for (k, v) in kv {
                    m.serialize_entry(k, v)?;
                }
                m.end()
            }
        }
    }
}

// ------------------------------------------------------------------ base64 --

/// Decode base64 as the page's `atob` does: ASCII whitespace ignored,
/// padding optional; `None` if it is not base64.
pub fn base64_decode(text: &str) -> Option<Vec<u8>> {
    let mut s: Vec<u8> = text
        .bytes()
        .filter(|b| !matches!(b, b' ' | b'\t' | b'\n' | b'\x0c' | b'\r'))
        .collect();
    if s.len().is_multiple_of(4) {
        for _ in 0..2 {
            if s.last() == Some(&b'=') {
                s.pop();
            }
        }
    }
    if s.len() % 4 == 1 {
        return None;
    }
    let val = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 2);
    for chunk in s.chunks(4) {
        let mut acc = 0u32;
        for (i, &c) in chunk.iter().enumerate() {
            acc |= val(c)? << (18 - 6 * i);
        }
        let n = chunk.len() - 1; // bytes in this chunk
        for i in 0..n {
            out.push((acc >> (16 - 8 * i)) as u8);
        }
    }
    Some(out)
}

/// Encode bytes as base64 with padding (the page's `btoa`).
pub fn base64_encode(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(bytes.len().div_ceil(3) * 4);
    for chunk in bytes.chunks(3) {
        let b = [
            chunk[0],
            *chunk.get(1).unwrap_or(&0),
            *chunk.get(2).unwrap_or(&0),
        ];
        let acc = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(A[(acc >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[cfg(feature = "json")]
/// Any serialisable value as a [`Value`] (bytes stay bytes).
pub fn to_value(v: &(impl Serialize + ?Sized)) -> std::result::Result<Value, String> {
    v.serialize(value_ser::ValueSerializer).map_err(|e| e.0)
}

#[cfg(feature = "json")]
mod value_ser {
    //! A small serde `Serializer` into [`Value`] (bytes stay bytes), so a
    //! typed state can be written as a project file.
    use super::Value;
    use serde::ser::{self, Serialize};
    use std::fmt;

    #[derive(Debug)]
    pub struct SerError(pub String);
    impl fmt::Display for SerError {
        fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
            f.write_str(&self.0)
        }
    }
    impl std::error::Error for SerError {}
    impl ser::Error for SerError {
        fn custom<T: fmt::Display>(msg: T) -> Self {
            SerError(msg.to_string())
        }
    }

    pub struct ValueSerializer;
    type R = Result<Value, SerError>;

    pub struct Seq(Vec<Value>);
    pub struct Map(Vec<(String, Value)>, Option<String>);

    impl ser::Serializer for ValueSerializer {
        type Ok = Value;
        type Error = SerError;
        type SerializeSeq = Seq;
        type SerializeTuple = Seq;
        type SerializeTupleStruct = Seq;
        type SerializeTupleVariant = Seq;
        type SerializeMap = Map;
        type SerializeStruct = Map;
        type SerializeStructVariant = Map;
        fn serialize_bool(self, v: bool) -> R {
            Ok(Value::Bool(v))
        }
        fn serialize_i8(self, v: i8) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_i16(self, v: i16) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_i32(self, v: i32) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_i64(self, v: i64) -> R {
            Ok(Value::Number(v as f64))
        }
        fn serialize_u8(self, v: u8) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_u16(self, v: u16) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_u32(self, v: u32) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_u64(self, v: u64) -> R {
            Ok(Value::Number(v as f64))
        }
        fn serialize_f32(self, v: f32) -> R {
            Ok(Value::Number(v.into()))
        }
        fn serialize_f64(self, v: f64) -> R {
            Ok(Value::Number(v))
        }
        fn serialize_char(self, v: char) -> R {
            Ok(Value::Text(v.to_string()))
        }
        fn serialize_str(self, v: &str) -> R {
            Ok(Value::Text(v.into()))
        }
        fn serialize_bytes(self, v: &[u8]) -> R {
            Ok(Value::Bytes(v.to_vec()))
        }
        fn serialize_none(self) -> R {
            Ok(Value::Null)
        }
        fn serialize_some<T: Serialize + ?Sized>(self, v: &T) -> R {
            v.serialize(self)
        }
        fn serialize_unit(self) -> R {
            Ok(Value::Null)
        }
        fn serialize_unit_struct(self, _: &'static str) -> R {
            Ok(Value::Null)
        }
        fn serialize_unit_variant(self, _: &'static str, _: u32, v: &'static str) -> R {
            Ok(Value::Text(v.into()))
        }
        fn serialize_newtype_struct<T: Serialize + ?Sized>(self, _: &'static str, v: &T) -> R {
            v.serialize(self)
        }
        fn serialize_newtype_variant<T: Serialize + ?Sized>(
            self,
            _: &'static str,
            _: u32,
            variant: &'static str,
            v: &T,
        ) -> R {
            Ok(Value::Object(vec![(variant.into(), v.serialize(self)?)]))
        }
        fn serialize_seq(self, len: Option<usize>) -> Result<Seq, SerError> {
            Ok(Seq(Vec::with_capacity(len.unwrap_or(0).min(4096))))
        }
        fn serialize_tuple(self, len: usize) -> Result<Seq, SerError> {
            self.serialize_seq(Some(len))
        }
        fn serialize_tuple_struct(self, _: &'static str, len: usize) -> Result<Seq, SerError> {
            self.serialize_seq(Some(len))
        }
        fn serialize_tuple_variant(
            self,
            _: &'static str,
            _: u32,
            _: &'static str,
            _: usize,
        ) -> Result<Seq, SerError> {
            Err(SerError("tuple variants are not plain data".into()))
        }
        fn serialize_map(self, _: Option<usize>) -> Result<Map, SerError> {
            Ok(Map(vec![], None))
        }
        fn serialize_struct(self, _: &'static str, _: usize) -> Result<Map, SerError> {
            Ok(Map(vec![], None))
        }
        fn serialize_struct_variant(
            self,
            _: &'static str,
            _: u32,
            _: &'static str,
            _: usize,
        ) -> Result<Map, SerError> {
            Err(SerError("struct variants are not plain data".into()))
        }
    }

    impl ser::SerializeSeq for Seq {
        type Ok = Value;
        type Error = SerError;
        fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SerError> {
            self.0.push(v.serialize(ValueSerializer)?);
            Ok(())
        }
        fn end(self) -> R {
            Ok(Value::List(self.0))
        }
    }
    impl ser::SerializeTuple for Seq {
        type Ok = Value;
        type Error = SerError;
        fn serialize_element<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SerError> {
            ser::SerializeSeq::serialize_element(self, v)
        }
        fn end(self) -> R {
            Ok(Value::List(self.0))
        }
    }
    impl ser::SerializeTupleStruct for Seq {
        type Ok = Value;
        type Error = SerError;
        fn serialize_field<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SerError> {
            ser::SerializeSeq::serialize_element(self, v)
        }
        fn end(self) -> R {
            Ok(Value::List(self.0))
        }
    }
    impl ser::SerializeTupleVariant for Seq {
        type Ok = Value;
        type Error = SerError;
        fn serialize_field<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SerError> {
            ser::SerializeSeq::serialize_element(self, v)
        }
        fn end(self) -> R {
            Ok(Value::List(self.0))
        }
    }
    impl ser::SerializeMap for Map {
        type Ok = Value;
        type Error = SerError;
        fn serialize_key<T: Serialize + ?Sized>(&mut self, k: &T) -> Result<(), SerError> {
            match k.serialize(ValueSerializer)? {
                Value::Text(k) => {
                    self.1 = Some(k);
                    Ok(())
                }
                _ => Err(SerError("map keys must be text".into())),
            }
        }
        fn serialize_value<T: Serialize + ?Sized>(&mut self, v: &T) -> Result<(), SerError> {
            let k = self.1.take().unwrap_or_default();
            self.0.push((k, v.serialize(ValueSerializer)?));
            Ok(())
        }
        fn end(self) -> R {
            Ok(Value::Object(self.0))
        }
    }
    impl ser::SerializeStruct for Map {
        type Ok = Value;
        type Error = SerError;
        fn serialize_field<T: Serialize + ?Sized>(
            &mut self,
            k: &'static str,
            v: &T,
        ) -> Result<(), SerError> {
            self.0.push((k.into(), v.serialize(ValueSerializer)?));
            Ok(())
        }
        fn end(self) -> R {
            Ok(Value::Object(self.0))
        }
    }
    impl ser::SerializeStructVariant for Map {
        type Ok = Value;
        type Error = SerError;
        fn serialize_field<T: Serialize + ?Sized>(
            &mut self,
            k: &'static str,
            v: &T,
        ) -> Result<(), SerError> {
            ser::SerializeStruct::serialize_field(self, k, v)
        }
        fn end(self) -> R {
            Ok(Value::Object(self.0))
        }
    }
}

// ------------------------------------------------------- typed reading --

/// A [`Value`] read as a serde type (`T::deserialize(&value)`), so a
/// document is described once, by its type. Strict where JS data is loose:
/// a struct or map must be an object (never a list read by position), a
/// list must be a list, bytes must be bytes (never a list of numbers), a
/// whole number within ±[`MAX_SAFE_INTEGER`] is an integer (so it fits
/// `u32`, `u64` ...) and any other number a float (so `2.5` or `1e300` does
/// not), and `null` is `None` of an `Option`.
impl<'de> Deserializer<'de> for &'de Value {
    type Error = de::value::Error;

    fn deserialize_any<V: Visitor<'de>>(self, v: V) -> std::result::Result<V::Value, Self::Error> {
        match self {
            Value::Null => v.visit_unit(),
            Value::Bool(b) => v.visit_bool(*b),
            Value::Number(n) if n.fract() == 0.0 && n.abs() <= MAX_SAFE_INTEGER => {
                if *n >= 0.0 {
                    v.visit_u64(*n as u64)
                } else {
                    v.visit_i64(*n as i64)
                }
            }
            Value::Number(n) => v.visit_f64(*n),
            Value::Text(t) => v.visit_borrowed_str(t),
            Value::Bytes(b) => v.visit_borrowed_bytes(b),
            Value::List(l) => {
                // A fixed-size array takes exactly its items: `[1, 2, 3]`
                // is not a point `[x, y]` (the rest is not dropped).
                let mut seq = de::value::SeqDeserializer::new(l.iter());
                let out = v.visit_seq(&mut seq)?;
                seq.end()?;
                Ok(out)
            }
            Value::Object(kv) => v.visit_map(de::value::MapDeserializer::new(
                kv.iter().map(|(k, v)| (k.as_str(), v)),
            )),
        }
    }

    fn deserialize_str<V: Visitor<'de>>(self, v: V) -> std::result::Result<V::Value, Self::Error> {
        match self {
            // Text is text; bytes (a page's Uint8Array) are not.
            Value::Text(t) => v.visit_borrowed_str(t),
            other => Err(de::Error::invalid_type(other.unexpected(), &v)),
        }
    }

    fn deserialize_string<V: Visitor<'de>>(
        self,
        v: V,
    ) -> std::result::Result<V::Value, Self::Error> {
        self.deserialize_str(v)
    }

    fn deserialize_option<V: Visitor<'de>>(
        self,
        v: V,
    ) -> std::result::Result<V::Value, Self::Error> {
        match self {
            Value::Null => v.visit_none(),
            _ => v.visit_some(self),
        }
    }

    fn deserialize_f64<V: Visitor<'de>>(self, v: V) -> std::result::Result<V::Value, Self::Error> {
        match self {
            // NaN and ±∞ (a page's numbers) reach the type's own check.
            Value::Number(n) => v.visit_f64(*n),
            _ => self.deserialize_any(v),
        }
    }

    fn deserialize_f32<V: Visitor<'de>>(self, v: V) -> std::result::Result<V::Value, Self::Error> {
        self.deserialize_f64(v)
    }

    fn deserialize_bytes<V: Visitor<'de>>(
        self,
        v: V,
    ) -> std::result::Result<V::Value, Self::Error> {
        match self {
            Value::Bytes(b) => v.visit_borrowed_bytes(b),
            other => Err(de::Error::invalid_type(other.unexpected(), &v)),
        }
    }

    fn deserialize_byte_buf<V: Visitor<'de>>(
        self,
        v: V,
    ) -> std::result::Result<V::Value, Self::Error> {
        self.deserialize_bytes(v)
    }

    fn deserialize_seq<V: Visitor<'de>>(self, v: V) -> std::result::Result<V::Value, Self::Error> {
        match self {
            Value::List(_) => self.deserialize_any(v),
            other => Err(de::Error::invalid_type(other.unexpected(), &v)),
        }
    }

    fn deserialize_tuple<V: Visitor<'de>>(
        self,
        _len: usize,
        v: V,
    ) -> std::result::Result<V::Value, Self::Error> {
        self.deserialize_seq(v)
    }

    fn deserialize_tuple_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _len: usize,
        v: V,
    ) -> std::result::Result<V::Value, Self::Error> {
        self.deserialize_seq(v)
    }

    fn deserialize_map<V: Visitor<'de>>(self, v: V) -> std::result::Result<V::Value, Self::Error> {
        match self {
            Value::Object(_) => self.deserialize_any(v),
            other => Err(de::Error::invalid_type(other.unexpected(), &v)),
        }
    }

    fn deserialize_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _fields: &'static [&'static str],
        v: V,
    ) -> std::result::Result<V::Value, Self::Error> {
        self.deserialize_map(v)
    }

    fn deserialize_enum<V: Visitor<'de>>(
        self,
        _name: &'static str,
        _variants: &'static [&'static str],
        v: V,
    ) -> std::result::Result<V::Value, Self::Error> {
        match self {
            Value::Text(t) => v.visit_enum(de::value::BorrowedStrDeserializer::new(t)),
            other => Err(de::Error::invalid_type(other.unexpected(), &v)),
        }
    }

    fn deserialize_newtype_struct<V: Visitor<'de>>(
        self,
        _name: &'static str,
        v: V,
    ) -> std::result::Result<V::Value, Self::Error> {
        v.visit_newtype_struct(self)
    }

    serde::forward_to_deserialize_any! {
        bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 char
        unit unit_struct identifier ignored_any
    }
}

impl<'de> de::IntoDeserializer<'de, de::value::Error> for &'de Value {
    type Deserializer = Self;
    fn into_deserializer(self) -> Self {
        self
    }
}

impl Value {
    /// What serde's messages call this value.
    fn unexpected(&self) -> de::Unexpected<'_> {
        match self {
            Value::Null => de::Unexpected::Unit,
            Value::Bool(b) => de::Unexpected::Bool(*b),
            Value::Number(n) if n.fract() == 0.0 && n.abs() <= MAX_SAFE_INTEGER => {
                if *n >= 0.0 {
                    de::Unexpected::Unsigned(*n as u64)
                } else {
                    de::Unexpected::Signed(*n as i64)
                }
            }
            Value::Number(n) => de::Unexpected::Float(*n),
            Value::Text(t) => de::Unexpected::Str(t),
            Value::Bytes(b) => de::Unexpected::Bytes(b),
            Value::List(_) => de::Unexpected::Seq,
            Value::Object(_) => de::Unexpected::Map,
        }
    }
}
