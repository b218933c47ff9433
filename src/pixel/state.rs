//! The Pixel tool's document (what the page keeps, autosaves, saves in a
//! project file and shares), its schema version and its checks: a serde
//! type read from the page's [`Value`] ([`read_document`]) and its
//! [`Check`]. Field names are the page's:
//!
//! ```text
//! { example: "fish" | "trunk" | null, source: bytes, sheet: bytes | null,
//!   sprite: bytes | null, mask: {width, height, bits: bytes},
//!   strokes: [[[x, y], ...], ...], params: PixelParams, names: {source?, sheet?} }
//! ```
//!
//! `params` and `mask` are the `pixel` request's own types
//! ([`PixelParams`], [`MaskBits`]) and their ranges the request's
//! ([`super::api::ranges`]); a document holds every parameter but
//! `sprite_direction` (the page has a control for each), whole HSV shifts
//! (its sliders step by one) and a seed a page's number holds. The image
//! side and stroke points are the core's limits ([`crate::core::limits`]).
//! Unknown fields are dropped, as they always were, but not in `params`
//! (the request refuses them: a typo is seen).
use super::api::{ranges, MaskBits, Range};
use super::{numbers, PixelParams};
use crate::core::check::{read_document, Check, Path};
use crate::core::error::{Error, Result};
use crate::core::limits::{MAX_IMAGE_SIDE, MAX_STROKE_POINTS};
use crate::core::request_limits as lim;
use crate::core::value::{first_chars, js_text, nullish, Value, MAX_SAFE_INTEGER};
use crate::raster::{HeaderError, HeaderReader};
use serde::de::{self, Visitor};
use serde::{Deserialize, Deserializer, Serialize};
use std::cell::Cell;

/// Schema version of the Pixel state (the page's `state.version`).
pub const STATE_VERSION: u32 = 1;
/// The examples the page ships (`assets/pixel/cases.json`).
pub const EXAMPLES: &[&str] = &["fish", "trunk"];
/// Most strokes in one document.
pub const MAX_STROKES: usize = 10_000;
/// Most points in one stroke.
pub const MAX_STROKE_LEN: usize = 100_000;
/// File names are kept to this many characters.
pub const MAX_NAME_CHARS: usize = 200;
/// The parameters a document may leave out (the request's default): the
/// page has no control for them.
pub const OPTIONAL_PARAMS: &[&str] = &["sprite_direction"];

/// A Pixel document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PixelState {
    #[serde(default)]
    pub example: Option<String>,
    #[serde(
        serialize_with = "serde_bytes::serialize",
        deserialize_with = "image_file"
    )]
    pub source: Vec<u8>,
    #[serde(
        default,
        serialize_with = "serde_bytes::serialize",
        deserialize_with = "image_file_or_null"
    )]
    pub sheet: Option<Vec<u8>>,
    #[serde(
        default,
        serialize_with = "serde_bytes::serialize",
        deserialize_with = "image_file_or_null"
    )]
    pub sprite: Option<Vec<u8>>,
    /// One byte per pixel, 0 or 1 (any other byte is read as 1).
    pub mask: MaskBits,
    /// In source pixels.
    #[serde(deserialize_with = "strokes")]
    pub strokes: Vec<Vec<[f64; 2]>>,
    /// Exactly the `pixel` request's parameters.
    pub params: PixelParams,
    #[serde(default, deserialize_with = "page_names")]
    pub names: Names,
}

/// The file names the page shows.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct Names {
    #[serde(skip_serializing_if = "Option::is_none")]
    pub source: Option<String>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sheet: Option<String>,
}

/// What an image field must be.
const IMAGE_FILE: &str = "the bytes of an image file";

/// Bytes (a `Uint8Array`), refused as "must be the bytes of an image file".
struct ImageFile(Vec<u8>);

impl<'de> Deserialize<'de> for ImageFile {
    fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ImageFile;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str(IMAGE_FILE)
            }
            fn visit_bytes<E: de::Error>(self, b: &[u8]) -> std::result::Result<ImageFile, E> {
                Ok(ImageFile(b.to_vec()))
            }
            fn visit_byte_buf<E: de::Error>(self, b: Vec<u8>) -> std::result::Result<ImageFile, E> {
                Ok(ImageFile(b))
            }
        }
        d.deserialize_byte_buf(V)
    }
}

fn image_file<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Vec<u8>, D::Error> {
    Ok(ImageFile::deserialize(d)?.0)
}

fn image_file_or_null<'de, D: Deserializer<'de>>(
    d: D,
) -> std::result::Result<Option<Vec<u8>>, D::Error> {
    Ok(Option::<ImageFile>::deserialize(d)?.map(|f| f.0))
}

/// Strokes: lists of points `[x, y]`, each a pair of finite numbers.
fn strokes<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Vec<Vec<[f64; 2]>>, D::Error> {
    struct Point([f64; 2]);
    impl<'de> Deserialize<'de> for Point {
        fn deserialize<D: Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
            numbers(d, "a point [x, y] of finite numbers", f64::is_finite).map(Point)
        }
    }
    let list = Vec::<Vec<Point>>::deserialize(d)?;
    Ok(list
        .into_iter()
        .map(|s| s.into_iter().map(|p| p.0).collect())
        .collect())
}

/// The names as the page's `String(name)` writes them, cut to
/// [`MAX_NAME_CHARS`]; anything but an object is no names.
fn page_names<'de, D: Deserializer<'de>>(d: D) -> std::result::Result<Names, D::Error> {
    let v = Value::deserialize(d)?;
    let name = |k: &str| {
        let n = v.get(k);
        (!nullish(n)).then(|| first_chars(&js_text(n), MAX_NAME_CHARS))
    };
    Ok(Names {
        source: name("source"),
        sheet: name("sheet"),
    })
}

/// The bytes start like an image file the core reads, with a size within
/// the image limit: read from the header alone, nothing decoded (a project
/// whose `source` was 3 bytes that are not a PNG used to open). Natively
/// every format the CLI reads; in wasm PNG only, as the Pixel module
/// decodes ([`crate::raster::sent_header_size`]): the page turns any other
/// format into PNG before a document reaches the core, so another format
/// here is `unsupported`.
fn image_header(at: &Path, bytes: &[u8]) -> Result<()> {
    image_header_with(at, bytes, crate::raster::sent_header_size)
}

/// [`image_header`] with the header reader `size`.
fn image_header_with(at: &Path, bytes: &[u8], size: HeaderReader) -> Result<()> {
    if bytes.is_empty() {
        return Err(at.invalid(format!("must be {IMAGE_FILE}")));
    }
    let (w, h) = size(bytes).map_err(|e| match e {
        HeaderError::NotImage => at.invalid("is not an image file (PNG, JPEG, WebP, GIF or BMP)"),
        HeaderError::Damaged => {
            at.invalid("is not a readable image file (its header is damaged or cut short)")
        }
        HeaderError::Unsupported(format) => Error::Unsupported(format!(
            "{} is a {format} file, and only PNG is read here: the page turns an image into \
             PNG before the document reaches the core (an internal error)",
            at.as_str()
        ))
        .at(at.as_str()),
    })?;
    if w == 0 || h == 0 || w.max(h) > MAX_IMAGE_SIDE {
        return Err(at.invalid(format!(
            "is an image of {w}×{h} pixels; images are 1 to {MAX_IMAGE_SIDE} pixels a side"
        )));
    }
    Ok(())
}

impl Check for PixelState {
    fn check(&self, at: &Path) -> Result<()> {
        image_header(&at.key("source"), &self.source)?;
        for (k, b) in [("sheet", &self.sheet), ("sprite", &self.sprite)] {
            if let Some(b) = b {
                image_header(&at.key(k), b)?;
            }
        }
        self.mask.check(&at.key("mask"))?;
        check_strokes(&at.key("strokes"), &self.strokes, &self.mask)?;
        self.params.check(&at.key("params"))?;
        if let Some(e) = &self.example {
            if !EXAMPLES.contains(&e.as_str()) {
                return Err(at
                    .key("example")
                    .invalid(format!("must be one of {} or none", EXAMPLES.join(", "))));
            }
        }
        Ok(())
    }
}

impl Check for MaskBits {
    fn check(&self, at: &Path) -> Result<()> {
        let (w, h) = (self.width, self.height);
        if !(1..=MAX_IMAGE_SIDE).contains(&w) || !(1..=MAX_IMAGE_SIDE).contains(&h) {
            return Err(at.invalid(format!(
                "must be 1 to {MAX_IMAGE_SIDE} pixels on each side (found {w}×{h})"
            )));
        }
        let n = w as usize * h as usize;
        if self.bits.len() != n {
            return Err(at.key("bits").invalid(format!(
                "must hold {n} values ({w}×{h}), found {}",
                self.bits.len()
            )));
        }
        Ok(())
    }
}

/// At most [`MAX_STROKES`] strokes and [`MAX_STROKE_POINTS`] points in
/// all, each stroke 2 to [`MAX_STROKE_LEN`] points within a pixel of the
/// mask's image.
fn check_strokes(at: &Path, strokes: &[Vec<[f64; 2]>], mask: &MaskBits) -> Result<()> {
    if strokes.len() > MAX_STROKES {
        return Err(at.invalid(format!("must be a list of at most {MAX_STROKES} strokes")));
    }
    let total: usize = strokes.iter().map(Vec::len).sum();
    if total > MAX_STROKE_POINTS {
        return Err(Error::limit(format!(
            "strokes have {total} points in all; the stroke point limit is {MAX_STROKE_POINTS}"
        ))
        .at(at.as_str()));
    }
    let (w, h) = (mask.width as f64, mask.height as f64);
    for (i, s) in strokes.iter().enumerate() {
        if s.len() < 2 {
            return Err(at.index(i).invalid("must be a list of at least 2 points"));
        }
        if s.len() > MAX_STROKE_LEN {
            return Err(at
                .index(i)
                .invalid(format!("must be a list of at most {MAX_STROKE_LEN} points")));
        }
        for (j, &[x, y]) in s.iter().enumerate() {
            if x < -1.0 || y < -1.0 || x > w + 1.0 || y > h + 1.0 {
                return Err(at.index(i).index(j).invalid(format!(
                    "lies outside the {}×{} image",
                    mask.width, mask.height
                )));
            }
        }
    }
    Ok(())
}

impl Check for PixelParams {
    /// The request's ranges ([`ranges`]) in a document's words; a document
    /// also holds whole HSV shifts, at most [`lim::EXCLUDED`] excluded
    /// colours and a seed a page's number holds.
    fn check(&self, at: &Path) -> Result<()> {
        for (field, range) in ranges(self) {
            let at = at.key(field);
            match range {
                // The page's HSV sliders step by one: a document's shifts
                // have always been whole.
                Range::Number(v, (lo, hi)) if field.starts_with("hsv.") && v.fract() != 0.0 => {
                    return Err(at.invalid(format!("must be a whole number from {lo} to {hi}")))
                }
                Range::Number(v, r) => at.number_in(v, r)?,
                Range::Whole(v, r) => at.whole_in(v, r)?,
            }
        }
        if self.exclude.len() > lim::EXCLUDED {
            return Err(at.key("exclude").invalid(format!(
                "must be a list of at most {} [r, g, b] colours",
                lim::EXCLUDED
            )));
        }
        at.key("seed")
            .whole_in(self.seed, (0, MAX_SAFE_INTEGER as u64))
    }
}

/// The fields of `T` as serde names them (what its derived `Deserialize`
/// asks a deserializer for).
fn fields_of<T: for<'de> Deserialize<'de>>() -> &'static [&'static str] {
    struct Fields(Cell<&'static [&'static str]>);
    impl<'de> Deserializer<'de> for &Fields {
        type Error = de::value::Error;
        fn deserialize_any<V: Visitor<'de>>(
            self,
            _: V,
        ) -> std::result::Result<V::Value, Self::Error> {
            Err(de::Error::custom("not a struct"))
        }
        fn deserialize_struct<V: Visitor<'de>>(
            self,
            _: &'static str,
            fields: &'static [&'static str],
            _: V,
        ) -> std::result::Result<V::Value, Self::Error> {
            self.0.set(fields);
            Err(de::Error::custom("fields read"))
        }
        serde::forward_to_deserialize_any! {
            bool i8 i16 i32 i64 i128 u8 u16 u32 u64 u128 f32 f64 char str string
            bytes byte_buf option unit unit_struct newtype_struct seq tuple
            tuple_struct map enum identifier ignored_any
        }
    }
    let f = Fields(Cell::new(&[]));
    let _ = T::deserialize(&f);
    f.0.get()
}

/// Read and check a Pixel document; the error names the field at fault.
pub fn check(raw: &Value) -> Result<PixelState> {
    let mut doc: PixelState = read_document(raw, "Pixel")?;
    // A request may leave any parameter out (its default); a document
    // holds every one the page has a control for.
    if let Some(p) = raw.get("params") {
        for name in fields_of::<PixelParams>() {
            if !OPTIONAL_PARAMS.contains(name) && p.get(name).is_none() {
                return Err(Path::root().key("params").key(name).invalid("is missing"));
            }
        }
    }
    for b in &mut doc.mask.bits {
        *b = u8::from(*b != 0);
    }
    Ok(doc)
}

#[cfg(test)]
mod tests {
    //! The document and the `pixel` request agree: each range just inside
    //! is accepted, just outside refused naming the field, by both.
    use super::*;
    use crate::core::value::base64_encode;
    use crate::pixel::api::check_params;
    use serde_json::{json, Value as Json};

    /// A document's image checked as the Pixel module checks it in wasm
    /// (PNG only): a PNG as natively, a JPEG refused as `unsupported` naming
    /// the field (the page converts it first), where natively it is read.
    #[test]
    fn a_png_only_check_reads_a_png_as_natively_and_refuses_a_jpeg() {
        use crate::raster::{header_size, png_header_size};
        use image::{ExtendedColorType, ImageEncoder};
        let at = Path::root().key("sheet");
        let png = crate::raster::encode_png(&crate::raster::Rgba8Image::new(5, 4)).unwrap();
        let mut jpeg = vec![];
        image::codecs::jpeg::JpegEncoder::new(&mut jpeg)
            .write_image(&[9; 5 * 4 * 3], 5, 4, ExtendedColorType::Rgb8)
            .unwrap();
        assert!(image_header_with(&at, &png, png_header_size).is_ok());
        assert!(image_header_with(&at, &jpeg, header_size).is_ok());
        let e = image_header_with(&at, &jpeg, png_header_size).unwrap_err();
        assert_eq!(e.kind(), "unsupported", "{e}");
        assert_eq!(e.field(), Some("sheet"), "{e}");
        assert!(e.to_string().contains("JPEG"), "{e}");
        for size in [header_size, png_header_size] {
            let e = image_header_with(&at, b"GIF", size).unwrap_err();
            assert_eq!(e.kind(), "invalid-input", "{e}");
            let big =
                crate::raster::encode_png(&crate::raster::Rgba8Image::new(MAX_IMAGE_SIDE + 1, 1))
                    .unwrap();
            let e = image_header_with(&at, &big, size).unwrap_err();
            assert!(e.to_string().contains("pixels a side"), "{e}");
        }
        // Natively a document's images are read in any format.
        assert!(image_header(&at, &jpeg).is_ok());
    }

    fn png(w: u32, h: u32) -> Json {
        let img = crate::raster::Rgba8Image::from_raw(w, h, vec![255; (w * h * 4) as usize]);
        let bytes = crate::raster::encode_png(&img.unwrap()).unwrap();
        json!({ "$bytes": base64_encode(&bytes) })
    }

    fn doc() -> Json {
        json!({
            "example": null, "source": png(3, 2), "sheet": png(3, 3), "sprite": null,
            "mask": {"width": 3, "height": 2, "bits": {"$bytes": base64_encode(&[1; 6])}},
            "strokes": [[[0, 0], [3, 2]]],
            "params": serde_json::to_value(PixelParams::default()).unwrap(),
            "names": {"source": "a.png"}
        })
    }

    fn with(edit: impl FnOnce(&mut Json)) -> Json {
        let mut d = doc();
        edit(&mut d);
        d
    }

    /// `{"$bytes": …}` decoded, as in a project file.
    fn read(j: &Json) -> Result<PixelState> {
        check(&Value::read(j, true).unwrap())
    }

    #[track_caller]
    fn refused(j: &Json, field: &str) -> Error {
        let e = read(j).unwrap_err();
        assert_eq!(e.field(), Some(field), "{e}");
        assert!(e.to_string().starts_with(field), "{e} names {field} first");
        e
    }

    /// The request with `params.<field>` (dotted) set to `v`, checked.
    fn request(field: &str, v: &Json) -> Result<()> {
        let mut p = serde_json::to_value(PixelParams::default()).unwrap();
        *p.pointer_mut(&format!("/{}", field.replace('.', "/")))
            .unwrap() = v.clone();
        check_params(&serde_json::from_value(p).unwrap())
    }

    #[test]
    fn every_range_is_inside_or_out_by_one() {
        read(&doc()).unwrap();
        let mut rows = 0;
        for (field, range) in ranges(&PixelParams::default()) {
            // (inside, outside) at each end.
            let ends: Vec<(Json, Json)> = match range {
                Range::Whole(_, (lo, hi)) => {
                    vec![(json!(lo), json!(lo - 1)), (json!(hi), json!(hi + 1))]
                }
                // A document's HSV shifts are whole: one past is a whole step.
                Range::Number(_, (lo, hi)) if field.starts_with("hsv.") => {
                    vec![(json!(lo), json!(lo - 1.0)), (json!(hi), json!(hi + 1.0))]
                }
                Range::Number(_, (lo, hi)) => {
                    let e = 1e-9 * hi.abs().max(1.0);
                    vec![(json!(lo), json!(lo - e)), (json!(hi), json!(hi + e))]
                }
            };
            let pointer = format!("/params/{}", field.replace('.', "/"));
            let named = format!("params.{field}");
            for (inside, outside) in ends {
                let set = |v: &Json| with(|d| *d.pointer_mut(&pointer).unwrap() = v.clone());
                read(&set(&inside)).unwrap_or_else(|e| panic!("{named} = {inside}: {e}"));
                request(field, &inside).unwrap_or_else(|e| panic!("{named} = {inside}: {e}"));
                let e = refused(&set(&outside), &named);
                assert!(e.to_string().contains(" from "), "{e} says the range");
                let e = request(field, &outside).unwrap_err();
                assert_eq!(e.field(), Some(named.as_str()), "{e}");
                rows += 1;
            }
        }
        assert_eq!(rows, 16, "eight ranges, two ends each");

        // Ranges the document adds, and the document's own sizes.
        let colours = |n: usize| json!(vec![[0, 0, 0]; n]);
        let strokes = |n: usize, len: usize| json!(vec![vec![[1, 1]; len]; n]);
        let cases: Vec<(Json, Json, &str)> = vec![
            (
                with(|d| d["params"]["exclude"] = colours(lim::EXCLUDED)),
                with(|d| d["params"]["exclude"] = colours(lim::EXCLUDED + 1)),
                "params.exclude",
            ),
            (
                with(|d| d["params"]["exclude"] = json!([[0, 0, 255]])),
                with(|d| d["params"]["exclude"] = json!([[0, 0, 256]])),
                "params.exclude.0",
            ),
            (
                with(|d| d["params"]["seed"] = json!(MAX_SAFE_INTEGER)),
                with(|d| d["params"]["seed"] = json!(MAX_SAFE_INTEGER + 1.0)),
                "params.seed",
            ),
            (
                with(|d| d["params"]["hsv"] = json!([1, 0, 0])),
                with(|d| d["params"]["hsv"] = json!([0.5, 0, 0])),
                "params.hsv.0",
            ),
            (
                with(|d| d["strokes"] = strokes(MAX_STROKES, 2)),
                with(|d| d["strokes"] = strokes(MAX_STROKES + 1, 2)),
                "strokes",
            ),
            (
                with(|d| d["strokes"] = strokes(1, MAX_STROKE_LEN)),
                with(|d| d["strokes"] = strokes(1, MAX_STROKE_LEN + 1)),
                "strokes.0",
            ),
            (
                with(|d| d["strokes"] = strokes(2, MAX_STROKE_POINTS / 2)),
                with(|d| {
                    d["strokes"] = json!([
                        vec![[1, 1]; MAX_STROKE_POINTS / 2],
                        vec![[1, 1]; MAX_STROKE_POINTS / 2 + 1]
                    ])
                }),
                "strokes",
            ),
            (
                with(|d| d["strokes"] = json!([[[-1, -1], [4, 3]]])),
                with(|d| d["strokes"] = json!([[[-1, -1], [4.001, 3]]])),
                "strokes.0.1",
            ),
            (
                with(|d| d["example"] = json!("trunk")),
                with(|d| d["example"] = json!("trunks")),
                "example",
            ),
        ];
        for (inside, outside, field) in cases {
            read(&inside).unwrap_or_else(|e| panic!("{field} inside: {e}"));
            refused(&outside, field);
        }
        // The request refuses as many colours too; its seed is any u64 (the
        // CLI's), a document's one a page's number holds.
        let mut p = PixelParams {
            exclude: vec![[0, 0, 0]; lim::EXCLUDED + 1],
            ..Default::default()
        };
        assert_eq!(
            check_params(&p).unwrap_err().field(),
            Some("params.exclude")
        );
        p.exclude.clear();
        p.seed = u64::MAX;
        check_params(&p).unwrap();
        // The mask's side is the image limit.
        let side = |w: u32| {
            with(|d| {
                d["mask"] = json!({"width": w, "height": 1,
                    "bits": {"$bytes": base64_encode(&vec![1; w as usize])}});
                d["strokes"] = json!([]);
            })
        };
        read(&side(MAX_IMAGE_SIDE)).unwrap();
        let e = refused(&side(MAX_IMAGE_SIDE + 1), "mask");
        assert_eq!(
            e.to_string(),
            "mask must be 1 to 4096 pixels on each side (found 4097×1)"
        );
    }

    #[test]
    fn lists_hold_exactly_their_items() {
        // A list read as an array must not drop what is past its end.
        let cases: Vec<(Json, &str, &str)> = vec![
            (
                with(|d| d["params"]["margins"] = json!([0, 0, 7])),
                "params.margins",
                "params.margins must be a list of 2 (got 3 items)",
            ),
            (
                with(|d| d["params"]["hsv"] = json!([0, 0])),
                "params.hsv",
                "params.hsv must be a list of 3 (got 2 items)",
            ),
            (
                with(|d| d["params"]["exclude"] = json!([[0, 0, 0, 0]])),
                "params.exclude.0",
                "params.exclude.0 must be an [r, g, b] colour (whole numbers from 0 to 255) (got a list of 4 items)",
            ),
            (
                with(|d| d["strokes"] = json!([[[1, 2], [1, 2, 3]]])),
                "strokes.0.1",
                "strokes.0.1 must be a point [x, y] of finite numbers (got a list of 3 items)",
            ),
            (
                with(|d| d["strokes"] = json!([[[1, 2], [3, "x"]]])),
                "strokes.0.1",
                "strokes.0.1 must be a point [x, y] of finite numbers (got [3, text])",
            ),
        ];
        for (d, field, message) in cases {
            assert_eq!(refused(&d, field).to_string(), message);
        }
        // NaN, which a page's number can be, is not a point.
        let mut v = Value::read(doc(), true).unwrap();
        if let Value::Object(kv) = &mut v {
            for (_, s) in kv.iter_mut().filter(|(k, _)| k == "strokes") {
                let p = Value::List(vec![Value::Number(f64::NAN), Value::Number(1.0)]);
                *s = Value::List(vec![Value::List(vec![p.clone(), p])]);
            }
        }
        assert_eq!(check(&v).unwrap_err().field(), Some("strokes.0.0"));
    }

    #[test]
    fn unknown_fields_are_refused_in_params_only() {
        let e = refused(&with(|d| d["params"]["dmax"] = json!(3)), "params");
        assert!(
            e.to_string()
                .starts_with("params has no field 'dmax'; expected one of"),
            "{e}"
        );
        // Elsewhere they are dropped, as they always were.
        let plain = read(&doc()).unwrap();
        let extra = with(|d| {
            d["extra"] = json!(1);
            d["mask"]["extra"] = json!(2);
            d["names"]["extra"] = json!(3);
        });
        assert_eq!(read(&extra).unwrap(), plain);
    }

    #[test]
    fn a_document_holds_every_parameter_the_page_has_a_control_for() {
        let names = fields_of::<PixelParams>();
        let all = serde_json::to_value(PixelParams::default()).unwrap();
        let mut keys: Vec<&str> = all
            .as_object()
            .unwrap()
            .keys()
            .map(String::as_str)
            .collect();
        let mut sorted = names.to_vec();
        keys.sort();
        sorted.sort();
        assert_eq!(sorted, keys, "every field of PixelParams");
        for name in names {
            let d = with(|d| {
                d["params"].as_object_mut().unwrap().remove(*name);
            });
            if OPTIONAL_PARAMS.contains(name) {
                let s = read(&d).unwrap();
                assert_eq!(
                    s.params.sprite_direction,
                    PixelParams::default().sprite_direction
                );
            } else {
                let e = refused(&d, &format!("params.{name}"));
                assert_eq!(e.to_string(), format!("params.{name} is missing"));
            }
        }
    }
}
