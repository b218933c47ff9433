use crate::core::error::{Error, Result};
use crate::core::limits::{self, rgba_bytes};
use image::{ImageDecoder, ImageFormat, ImageReader};
use std::io::Cursor;

/// Size limits applied before any pixel is decoded. The defaults are
/// [`limits::MAX_IMAGE_SIDE`] and [`limits::MAX_IMAGE_PIXELS`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Limits {
    /// Largest accepted width and height, each.
    pub max_side: u32,
    /// Largest accepted pixel count (width × height).
    pub max_pixels: u64,
}

impl Default for Limits {
    /// 4096 × 4096 per side and at most 16 Mpx: 64 MiB of RGBA, which a
    /// browser tab can hold twice over while a tool works on a copy.
    fn default() -> Self {
        Limits {
            max_side: limits::MAX_IMAGE_SIDE,
            max_pixels: limits::MAX_IMAGE_PIXELS,
        }
    }
}

impl Limits {
    /// Check a declared size against these limits (before anything is
    /// allocated); the error names the limit that was exceeded.
    pub fn check(&self, w: u32, h: u32) -> Result<()> {
        if w > self.max_side || h > self.max_side {
            return Err(Error::limit(format!(
                "{w}×{h} exceeds the {m}×{m} limit",
                m = self.max_side
            )));
        }
        let n = w as u64 * h as u64;
        if n > self.max_pixels {
            return Err(Error::limit(format!(
                "{w}×{h} has {n} pixels, more than the limit of {} pixels",
                self.max_pixels
            )));
        }
        if rgba_bytes(w, h).is_none() {
            return Err(Error::limit(format!(
                "{w}×{h} RGBA ({} bytes) does not fit in this platform's memory",
                n * 4
            )));
        }
        Ok(())
    }
}

/// An 8-bit straight-alpha RGBA image, row-major, no padding.
///
/// Invariant: `data.len() == width * height * 4`.
#[derive(Clone, PartialEq, Eq)]
pub struct Rgba8Image {
    pub width: u32,
    pub height: u32,
    pub data: Vec<u8>,
}

impl std::fmt::Debug for Rgba8Image {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "Rgba8Image({}×{})", self.width, self.height)
    }
}

impl Rgba8Image {
    /// A fully transparent image of a size the caller has already checked
    /// (it comes from an accepted image or a validated request).
    ///
    /// Panics, before allocating, when `width × height × 4` does not fit in
    /// `usize`; sizes that come from input go through [`Rgba8Image::try_new`].
    pub fn new(width: u32, height: u32) -> Self {
        let n = rgba_bytes(width, height).unwrap_or_else(|| {
            panic!("a {width}×{height} RGBA image does not fit in memory (unchecked size)")
        });
        Rgba8Image {
            width,
            height,
            data: vec![0; n],
        }
    }

    /// A fully transparent image whose size comes from input: checked
    /// against the default image limits before anything is allocated.
    pub fn try_new(width: u32, height: u32) -> Result<Self> {
        Limits::default().check(width, height)?;
        Ok(Rgba8Image::new(width, height))
    }

    /// Wrap raw RGBA bytes (e.g. pixels sent by the page), checking the size
    /// against the default image limits and the length against the size. The
    /// arithmetic is done in `u64`, so a declared 65536×65536 cannot wrap to
    /// an empty image on 32-bit targets.
    pub fn from_raw(width: u32, height: u32, data: Vec<u8>) -> Result<Self> {
        Limits::default().check(width, height)?;
        Rgba8Image::from_raw_checked(width, height, data)
    }

    /// The length check of [`Rgba8Image::from_raw`] without the size limits
    /// (the caller has checked its own limits).
    fn from_raw_checked(width: u32, height: u32, data: Vec<u8>) -> Result<Self> {
        let want = width as u64 * height as u64 * 4;
        if data.len() as u64 != want {
            return Err(Error::input(format!(
                "{width}×{height} RGBA needs {want} bytes, got {}",
                data.len()
            )));
        }
        Ok(Rgba8Image {
            width,
            height,
            data,
        })
    }

    /// Check what the public fields promise: a size within the default image
    /// limits and exactly `width × height × 4` bytes. Tools call this on
    /// images handed to them, so a hand-built inconsistent image is an error,
    /// not an out-of-bounds panic later.
    pub fn validate(&self) -> Result<()> {
        Limits::default().check(self.width, self.height)?;
        let want = self.width as u64 * self.height as u64 * 4;
        if self.data.len() as u64 != want {
            return Err(Error::input(format!(
                "the {}×{} image has {} bytes of RGBA; it needs {want}",
                self.width,
                self.height,
                self.data.len()
            )));
        }
        Ok(())
    }

    pub fn pixel_count(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// The pixel at (x, y) as `[r, g, b, a]`. Panics when out of bounds.
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> [u8; 4] {
        let i = (y as usize * self.width as usize + x as usize) * 4;
        [
            self.data[i],
            self.data[i + 1],
            self.data[i + 2],
            self.data[i + 3],
        ]
    }

    /// The pixel at row-major index `i` (= y·width + x) as `[r, g, b, a]`.
    #[inline]
    pub fn at(&self, i: usize) -> [u8; 4] {
        let d = &self.data[4 * i..4 * i + 4];
        [d[0], d[1], d[2], d[3]]
    }

    #[inline]
    pub fn put(&mut self, x: u32, y: u32, px: [u8; 4]) {
        let i = (y as usize * self.width as usize + x as usize) * 4;
        self.data[i..i + 4].copy_from_slice(&px);
    }

    /// Iterate pixels as `[r, g, b, a]`.
    pub fn pixels(&self) -> impl Iterator<Item = [u8; 4]> + '_ {
        self.data.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]])
    }

    /// Scale down so the longer side is at most `max_side`, averaging each
    /// source box (alpha-weighted so transparent pixels do not darken edges).
    /// Images already small enough are returned unchanged.
    pub fn thumbnail(&self, max_side: u32) -> Rgba8Image {
        match self.thumbnail_size(max_side) {
            None => self.clone(),
            Some((tw, th)) => {
                let mut out = Rgba8Image::new(tw, th);
                for ty in 0..th {
                    self.thumbnail_row(&mut out, ty);
                }
                out
            }
        }
    }

    /// The size of [`Rgba8Image::thumbnail`]'s result, or `None` when it is
    /// the image itself (already small enough).
    pub fn thumbnail_size(&self, max_side: u32) -> Option<(u32, u32)> {
        let max_side = max_side.clamp(1, limits::MAX_THUMBNAIL_SIDE);
        let long = self.width.max(self.height);
        if long <= max_side || long == 0 {
            return None;
        }
        let tw = ((self.width as u64 * max_side as u64) / long as u64).max(1) as u32;
        let th = ((self.height as u64 * max_side as u64) / long as u64).max(1) as u32;
        Some((tw, th))
    }

    /// Row `ty` of a thumbnail `out` sized by [`Rgba8Image::thumbnail_size`]
    /// (so a job can make a thumbnail a few rows at a time).
    pub fn thumbnail_row(&self, out: &mut Rgba8Image, ty: u32) {
        let (tw, th) = (out.width, out.height);
        let y0 = (ty as u64 * self.height as u64 / th as u64) as u32;
        let y1 = (((ty + 1) as u64 * self.height as u64 / th as u64) as u32).max(y0 + 1);
        for tx in 0..tw {
            let x0 = (tx as u64 * self.width as u64 / tw as u64) as u32;
            let x1 = (((tx + 1) as u64 * self.width as u64 / tw as u64) as u32).max(x0 + 1);
            let (mut r, mut g, mut b, mut a, mut n) = (0u64, 0u64, 0u64, 0u64, 0u64);
            for y in y0..y1 {
                for x in x0..x1 {
                    let p = self.get(x, y);
                    let pa = p[3] as u64;
                    r += p[0] as u64 * pa;
                    g += p[1] as u64 * pa;
                    b += p[2] as u64 * pa;
                    a += pa;
                    n += 1;
                }
            }
            // Alpha-weighted mean colour; fully transparent boxes stay transparent.
            let px = match (r.checked_div(a), g.checked_div(a), b.checked_div(a)) {
                (Some(r), Some(g), Some(b)) => [r as u8, g as u8, b as u8, (a / n) as u8],
                _ => [0, 0, 0, 0],
            };
            out.put(tx, ty, px);
        }
    }
}

/// Decode PNG, JPEG, WebP, GIF (first frame) or BMP bytes into RGBA, checking
/// the declared size against `limits` before allocating pixels.
pub fn decode(bytes: &[u8], limits: Limits) -> Result<Rgba8Image> {
    let format = sniff(bytes)?;
    let name = format_name(format);
    let reader = ImageReader::with_format(Cursor::new(bytes), format);
    let decoder = reader.into_decoder().map_err(|e| header_error(e, name))?;
    finish(decoder, name, limits)
}

/// [`decode`] for PNG bytes only: any other format is refused as
/// `unsupported`. It links the PNG decoder alone.
pub fn decode_png(bytes: &[u8], limits: Limits) -> Result<Rgba8Image> {
    let format = sniff(bytes)?;
    if format != ImageFormat::Png {
        return Err(Error::Unsupported(format!(
            "this is a {} file, and only PNG is read here: the page turns an image \
             into PNG before sending it (an internal error)",
            format_name(format)
        )));
    }
    let decoder = image::codecs::png::PngDecoder::new(Cursor::new(bytes))
        .map_err(|e| header_error(e, "PNG"))?;
    finish(decoder, "PNG", limits)
}

/// An image a request of Micro or Texture carries. Natively that is
/// the user's file (the CLI reads it): any format, [`decode`]. In the
/// browser the page has already decoded the user's file and sends PNG
/// (Texture's example, Micro's slice), so the wasm
/// build reads PNG only ([`decode_png`]) and those tools' modules link no
/// JPEG, WebP, GIF or BMP decoder. The same PNG gives the same pixels in
/// both.
pub fn decode_sent(bytes: &[u8], limits: Limits) -> Result<Rgba8Image> {
    #[cfg(target_arch = "wasm32")]
    return decode_png(bytes, limits);
    #[cfg(not(target_arch = "wasm32"))]
    decode(bytes, limits)
}

/// An image file in a request whose page sends pixels instead (Fit: its
/// target upload goes as `rgba`). Natively that is the user's file, read by
/// the CLI or a library user: any format, [`decode`]. In the browser the
/// page decodes the user's image itself, so the wasm build reads no file at
/// all (an encoded image is refused as `unsupported`) and the module links
/// no image decoder.
pub fn decode_file(bytes: &[u8], limits: Limits) -> Result<Rgba8Image> {
    #[cfg(target_arch = "wasm32")]
    {
        let _ = (bytes, limits);
        Err(Error::Unsupported(
            "an image file is read here only natively: the page sends the image's pixels \
             (an internal error)"
                .into(),
        ))
    }
    #[cfg(not(target_arch = "wasm32"))]
    decode(bytes, limits)
}

/// A one-go decoder: [`decode`], [`decode_png`] or [`decode_sent`]. A
/// [`Decoding`] keeps the one it was given, so a module links only the
/// decoders its requests name.
pub type Decoder = fn(&[u8], Limits) -> Result<Rgba8Image>;

/// Why an image file's header gives no size ([`header_size`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HeaderError {
    /// The bytes do not start like an image file.
    NotImage,
    /// An image file whose header is damaged or cut short.
    Damaged,
    /// An image file of this format, which this reader does not read.
    Unsupported(&'static str),
}

/// A header reader: [`header_size`], [`png_header_size`] or
/// [`sent_header_size`].
pub type HeaderReader = fn(&[u8]) -> std::result::Result<(u32, u32), HeaderError>;

/// The size a PNG, JPEG, WebP, GIF or BMP file declares, read from its
/// header alone (nothing decoded).
pub fn header_size(bytes: &[u8]) -> std::result::Result<(u32, u32), HeaderError> {
    let format = image::guess_format(bytes).map_err(|_| HeaderError::NotImage)?;
    ImageReader::with_format(Cursor::new(bytes), format)
        .into_dimensions()
        .map_err(|_| HeaderError::Damaged)
}

/// [`header_size`] for PNG only: any other image format is
/// [`HeaderError::Unsupported`]. It links the PNG decoder alone.
pub fn png_header_size(bytes: &[u8]) -> std::result::Result<(u32, u32), HeaderError> {
    let format = image::guess_format(bytes).map_err(|_| HeaderError::NotImage)?;
    if format != ImageFormat::Png {
        return Err(HeaderError::Unsupported(format_name(format)));
    }
    image::codecs::png::PngDecoder::new(Cursor::new(bytes))
        .map(|d| d.dimensions())
        .map_err(|_| HeaderError::Damaged)
}

/// The header of an image a document or request carries, as
/// [`decode_sent`] reads it: every format natively, PNG only in wasm.
pub fn sent_header_size(bytes: &[u8]) -> std::result::Result<(u32, u32), HeaderError> {
    #[cfg(target_arch = "wasm32")]
    return png_header_size(bytes);
    #[cfg(not(target_arch = "wasm32"))]
    header_size(bytes)
}

/// The format of `bytes`, from their first bytes.
fn sniff(bytes: &[u8]) -> Result<ImageFormat> {
    if bytes.is_empty() {
        return Err(Error::input("the file is empty (0 bytes)"));
    }
    image::guess_format(bytes).map_err(|_| {
        Error::input(
            "this is not an image Filigree can read (expected PNG, JPEG, WebP, GIF or BMP)",
        )
    })
}

/// A decoder's refusal of a file's header, said plainly.
fn header_error(e: image::ImageError, name: &str) -> Error {
    match e {
        image::ImageError::Limits(_) => over_memory(name),
        e => match plain_reason(&e) {
            Reason::Limit => over_memory(name),
            Reason::Said(why) => {
                Error::input(format!("the {name} header could not be read: {why}"))
            }
        },
    }
}

/// Check a decoder's size against `limits`, bound its memory, and decode.
fn finish<D: ImageDecoder>(mut decoder: D, name: &str, limits: Limits) -> Result<Rgba8Image> {
    let (w, h) = decoder.dimensions();
    if w == 0 || h == 0 {
        return Err(Error::input(format!(
            "the {name} image has no pixels ({w}×{h})"
        )));
    }
    limits.check(w, h)?;
    let mut dl = image::Limits::default();
    dl.max_image_width = Some(limits.max_side);
    dl.max_image_height = Some(limits.max_side);
    dl.max_alloc = Some(limits::MAX_DECODE_ALLOC);
    decoder.set_limits(dl).map_err(|e| {
        Error::limit(format!(
            "the {name} decoder needs more than the decode memory limit of {} MiB ({e})",
            limits::MAX_DECODE_ALLOC >> 20
        ))
    })?;
    let img = image::DynamicImage::from_decoder(decoder).map_err(|e| match e {
        image::ImageError::Limits(_) => over_memory(name),
        e => match plain_reason(&e) {
            Reason::Limit => over_memory(name),
            Reason::Said(why) => {
                Error::input(format!("the {name} data is damaged or truncated ({why})"))
            }
        },
    })?;
    let rgba = img.into_rgba8();
    Rgba8Image::from_raw_checked(w, h, rgba.into_raw())
}

/// The error for a file whose decoding needs more memory than allowed.
fn over_memory(name: &str) -> Error {
    Error::limit(format!(
        "decoding this {name} needs more than the decode memory limit of {} MiB",
        limits::MAX_DECODE_ALLOC >> 20
    ))
}

/// What a decoder's error says, in words fit for a person.
enum Reason {
    /// It ran out of its memory allowance.
    Limit,
    Said(String),
}

/// The decoders' own messages sometimes print their internal structures
/// ("ChunkType { type: IHDR, critical: true, … }") or a bare "Memory limit
/// exceeded": keep a plain sentence, name a memory limit as such, and say
/// only "it could not be decoded" for the rest.
fn plain_reason(e: &image::ImageError) -> Reason {
    let t = e.to_string();
    let lower = t.to_lowercase();
    if lower.contains("memory limit") || lower.contains("limit exceeded") {
        return Reason::Limit;
    }
    if t.contains(['{', '}', '[', ']']) || t.contains("::") || t.len() > 160 {
        let what = if lower.contains("crc") || lower.contains("checksum") {
            "a checksum does not match: the file is damaged"
        } else if lower.contains("chunk") {
            "a chunk of the file is damaged or out of place"
        } else {
            "the decoder could not make sense of it"
        };
        return Reason::Said(what.into());
    }
    Reason::Said(t)
}

/// Pixels a [`Decoding`] step of a job decodes: a few milliseconds
/// (`filigree bench slices`).
pub const DECODE_PIXELS_PER_STEP: usize = 131_072;

/// [`decode`] in bounded parts, for a job that must not block: a
/// non-interlaced PNG is decoded a few rows a [`Decoding::step`] (with the
/// `png` crate, converted to RGBA exactly as [`decode`] converts it, for
/// every colour type and bit depth); any other file, an interlaced PNG
/// included, is decoded in one go by the first step, with the [`Decoder`]
/// it was started with ([`decode`] for [`Decoding::new`], [`decode_sent`]
/// for [`Decoding::sent`]). The image, and any error, are that decoder's:
/// on an error the bytes are decoded once more in one go to give its
/// message.
pub struct Decoding {
    bytes: Shared,
    limits: Limits,
    png: Option<PngRows>,
    done: bool,
    /// What decodes a file that is not read in parts, and gives the error
    /// of one that fails part way.
    whole: Decoder,
}

/// The file's bytes, shared by the row reader and the one-go fallback.
#[derive(Clone)]
struct Shared(std::sync::Arc<Vec<u8>>);

impl AsRef<[u8]> for Shared {
    fn as_ref(&self) -> &[u8] {
        &self.0
    }
}

struct PngRows {
    reader: png::Reader<Cursor<Shared>>,
    colour: png::ColorType,
    sixteen: bool,
    out: Rgba8Image,
    row: u32,
}

impl Decoding {
    /// Start decoding `bytes` of any format [`decode`] reads; only the
    /// header of a PNG is read here.
    pub fn new(bytes: Vec<u8>, limits: Limits) -> Decoding {
        Decoding::with(bytes, limits, decode)
    }

    /// [`Decoding::new`] as [`decode_sent`] reads: every format natively,
    /// PNG only in wasm (any other format is refused as `unsupported`).
    pub fn sent(bytes: Vec<u8>, limits: Limits) -> Decoding {
        Decoding::with(bytes, limits, decode_sent)
    }

    /// Start decoding `bytes`, with `whole` for what is not read in parts
    /// ([`decode`], [`decode_png`] or [`decode_sent`]).
    pub fn with(bytes: Vec<u8>, limits: Limits, whole: Decoder) -> Decoding {
        let bytes = Shared(std::sync::Arc::new(bytes));
        let png = PngRows::start(&bytes, limits);
        Decoding {
            bytes,
            limits,
            png,
            done: false,
            whole,
        }
    }

    /// Whether the file is decoded in parts (a non-interlaced PNG of a
    /// colour type the parts support) rather than in one go.
    pub fn in_parts(&self) -> bool {
        self.png.is_some()
    }

    /// Decode about `budget` more pixels (a row at least); the image once
    /// complete (then an error if called again).
    pub fn step(&mut self, budget: usize) -> Result<Option<Rgba8Image>> {
        if self.done {
            return Err(Error::input("this image has already been decoded"));
        }
        let Some(p) = &mut self.png else {
            self.done = true;
            return (self.whole)(self.bytes.as_ref(), self.limits).map(Some);
        };
        let mut spent = 0usize;
        while p.row < p.out.height && spent < budget.max(1) {
            match p.next_row() {
                Ok(()) => spent += p.out.width as usize,
                Err(()) => {
                    // Whatever went wrong, report it as the one-go decode does.
                    self.done = true;
                    return match (self.whole)(self.bytes.as_ref(), self.limits) {
                        Err(e) => Err(e),
                        Ok(_) => Err(Error::input("the PNG data could not be read row by row")),
                    };
                }
            }
        }
        if p.row < p.out.height {
            return Ok(None);
        }
        self.done = true;
        let p = self.png.take().expect("rows");
        Ok(Some(p.out))
    }

    /// Fraction of the rows decoded.
    pub fn fraction(&self) -> f64 {
        match &self.png {
            Some(p) => p.row as f64 / p.out.height.max(1) as f64,
            None => 0.0,
        }
    }
}

impl PngRows {
    /// The header of a PNG that can be decoded row by row (`None`: decode
    /// it in one go, which also gives any error).
    fn start(bytes: &Shared, limits: Limits) -> Option<PngRows> {
        if image::guess_format(bytes.as_ref()).ok()? != ImageFormat::Png {
            return None;
        }
        // As the `image` crate sets up its PNG decoder.
        let max = usize::try_from(image::Limits::default().max_alloc.unwrap_or(u64::MAX))
            .unwrap_or(usize::MAX);
        let mut d =
            png::Decoder::new_with_limits(Cursor::new(bytes.clone()), png::Limits { bytes: max });
        d.set_ignore_text_chunk(false);
        d.set_transformations(png::Transformations::EXPAND);
        let reader = d.read_info().ok()?;
        let info = reader.info();
        let (w, h) = (info.width, info.height);
        if info.interlaced || w == 0 || h == 0 || limits.check(w, h).is_err() {
            return None;
        }
        let (colour, depth) = reader.output_color_type();
        let sixteen = match depth {
            png::BitDepth::Eight => false,
            png::BitDepth::Sixteen => true,
            _ => return None,
        };
        if colour == png::ColorType::Indexed {
            return None;
        }
        Some(PngRows {
            reader,
            colour,
            sixteen,
            out: Rgba8Image::new(w, h),
            row: 0,
        })
    }

    /// Decode the next row into `out`.
    fn next_row(&mut self) -> std::result::Result<(), ()> {
        let w = self.out.width as usize;
        let y = self.row as usize;
        let row = self.reader.next_row().map_err(|_| ())?.ok_or(())?;
        let data = row.data();
        let channels = match self.colour {
            png::ColorType::Grayscale => 1,
            png::ColorType::GrayscaleAlpha => 2,
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
            png::ColorType::Indexed => return Err(()),
        };
        let bytes = if self.sixteen { 2 } else { 1 };
        if data.len() < w * channels * bytes {
            return Err(());
        }
        let out = &mut self.out.data[4 * w * y..4 * w * (y + 1)];
        // A sample as 8 bits, as the `image` crate narrows 16-bit ones.
        let sixteen = self.sixteen;
        let at = |i: usize| -> u8 {
            if sixteen {
                let v = u16::from_be_bytes([data[2 * i], data[2 * i + 1]]);
                ((v as u32 + 128) / 257) as u8
            } else {
                data[i]
            }
        };
        for (x, px) in out.chunks_exact_mut(4).enumerate() {
            let i = x * channels;
            px.copy_from_slice(&match channels {
                1 => {
                    let l = at(i);
                    [l, l, l, 255]
                }
                2 => {
                    let l = at(i);
                    [l, l, l, at(i + 1)]
                }
                3 => [at(i), at(i + 1), at(i + 2), 255],
                _ => [at(i), at(i + 1), at(i + 2), at(i + 3)],
            });
        }
        self.row += 1;
        Ok(())
    }
}

fn format_name(f: ImageFormat) -> &'static str {
    match f {
        ImageFormat::Png => "PNG",
        ImageFormat::Jpeg => "JPEG",
        ImageFormat::WebP => "WebP",
        ImageFormat::Gif => "GIF",
        ImageFormat::Bmp => "BMP",
        _ => "image",
    }
}

/// Encode as an 8-bit RGBA PNG.
pub fn encode_png(img: &Rgba8Image) -> Result<Vec<u8>> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(
            &img.data,
            img.width,
            img.height,
            image::ExtendedColorType::Rgba8,
        )
        .map_err(|e| Error::input(format!("could not encode PNG: {e}")))?;
    Ok(out)
}

use image::ImageEncoder;

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 34: a PNG whose header checksum is wrong was refused with the
    /// decoder's internals ("while decoding ChunkType { type: IHDR,
    /// critical: true, … } chunk"); a decoder's bare "Memory limit
    /// exceeded" now names the decode memory limit.
    /// The PNG-only reader the Fit, Micro and Texture modules use in the
    /// browser gives `decode`'s pixels and errors for PNG, and refuses any
    /// other format by its kind (the page sends PNG; this would catch a
    /// page that sends the user's JPEG as it is).
    #[test]
    fn decode_png_reads_what_decode_reads_and_refuses_other_formats() {
        use image::codecs::png::PngEncoder;
        use image::{ExtendedColorType, ImageEncoder};
        let (w, h) = (7u32, 5u32);
        let n = (w * h) as usize;
        let px: Vec<u8> = (0..n * 4).map(|i| (i * 37 % 251) as u8).collect();
        let mut pngs = vec![];
        for (data, ty) in [
            (px.clone(), ExtendedColorType::Rgba8),
            (px[..n * 2].to_vec(), ExtendedColorType::La8),
            (px[..n * 2].to_vec(), ExtendedColorType::L16),
            (px[..n * 3].to_vec(), ExtendedColorType::Rgb8),
        ] {
            let mut out = vec![];
            PngEncoder::new(&mut out)
                .write_image(&data, w, h, ty)
                .unwrap();
            pngs.push(out);
        }
        for png in &pngs {
            let a = decode(png, Limits::default()).unwrap();
            let b = decode_png(png, Limits::default()).unwrap();
            assert_eq!((a.width, a.height, &a.data), (b.width, b.height, &b.data));
        }
        let cut = &pngs[0][..pngs[0].len() - 20];
        assert_eq!(
            decode(cut, Limits::default()).unwrap_err(),
            decode_png(cut, Limits::default()).unwrap_err()
        );
        let small = Limits {
            max_side: 4,
            max_pixels: 16,
        };
        assert_eq!(
            decode(&pngs[0], small).unwrap_err(),
            decode_png(&pngs[0], small).unwrap_err()
        );
        let mut jpeg = vec![];
        image::codecs::jpeg::JpegEncoder::new(&mut jpeg)
            .write_image(&px[..n * 3], w, h, ExtendedColorType::Rgb8)
            .unwrap();
        assert!(decode(&jpeg, Limits::default()).is_ok());
        let e = decode_png(&jpeg, Limits::default()).unwrap_err();
        assert_eq!(e.kind(), "unsupported", "{e}");
        assert!(e.to_string().contains("JPEG"), "{e}");
        // Natively a request's image is the user's file: any format.
        assert!(decode_sent(&jpeg, Limits::default()).is_ok());
    }

    /// A [`Decoding`] started with [`decode_png`] (the Pixel module's
    /// `pixel` and `decode-image` in wasm, [`Decoding::sent`]) gives
    /// [`Decoding::new`]'s pixels for a PNG read in parts and for one read
    /// in one go (interlaced), and refuses a JPEG as `unsupported`; the
    /// PNG-only header reader gives the every-format one's size for a PNG
    /// and refuses a JPEG by its format (a Pixel document checked in wasm).
    #[test]
    fn png_only_decoding_and_header_read_pngs_alike_and_refuse_a_jpeg() {
        use image::{ExtendedColorType, ImageEncoder};
        let (w, h) = (9u32, 6u32);
        let px: Vec<u8> = (0..w * h * 4).map(|i| (i * 53 % 241) as u8).collect();
        let png = encode_png(&Rgba8Image::from_raw(w, h, px.clone()).unwrap()).unwrap();
        let interlaced = interlaced_png();
        let mut jpeg = vec![];
        image::codecs::jpeg::JpegEncoder::new(&mut jpeg)
            .write_image(&px[..(w * h * 3) as usize], w, h, ExtendedColorType::Rgb8)
            .unwrap();
        let all = |mut d: Decoding| loop {
            if let Some(img) = d.step(7)? {
                return Ok::<_, Error>(img);
            }
        };
        for (bytes, parts) in [(&png, true), (&interlaced, false)] {
            let every = Decoding::new(bytes.clone(), Limits::default());
            let only = Decoding::with(bytes.clone(), Limits::default(), decode_png);
            assert_eq!((every.in_parts(), only.in_parts()), (parts, parts));
            let (a, b) = (all(every).unwrap(), all(only).unwrap());
            assert_eq!((a.width, a.height, &a.data), (b.width, b.height, &b.data));
            assert_eq!(header_size(bytes), png_header_size(bytes));
            assert_eq!(header_size(bytes), Ok((a.width, a.height)));
        }
        assert!(all(Decoding::new(jpeg.clone(), Limits::default())).is_ok());
        let e = all(Decoding::with(jpeg.clone(), Limits::default(), decode_png)).unwrap_err();
        assert_eq!(e.kind(), "unsupported", "{e}");
        assert_eq!(header_size(&jpeg), Ok((w, h)));
        assert_eq!(
            png_header_size(&jpeg),
            Err(HeaderError::Unsupported("JPEG"))
        );
        for f in [header_size, png_header_size] {
            assert_eq!(f(b"not an image"), Err(HeaderError::NotImage));
            assert_eq!(f(&png[..20]), Err(HeaderError::Damaged));
        }
        // Natively what a request or a document carries is read in any format.
        assert!(all(Decoding::sent(jpeg.clone(), Limits::default())).is_ok());
        assert_eq!(sent_header_size(&jpeg), Ok((w, h)));
    }

    #[test]
    fn decoder_errors_are_said_plainly() {
        let mut png = encode_png(&Rgba8Image::new(4, 4)).unwrap();
        // The IHDR chunk's CRC: bytes 29..33 (signature 8, length 4, type 4, data 13).
        png[29] ^= 0xff;
        let e = decode(&png, Limits::default()).unwrap_err().to_string();
        assert!(!e.contains("ChunkType") && !e.contains('{'), "{e}");
        assert!(e.contains("checksum") && e.contains("PNG"), "{e}");
        let mem = image::ImageError::Decoding(image::error::DecodingError::new(
            image::error::ImageFormatHint::Exact(image::ImageFormat::Png),
            "Memory limit exceeded",
        ));
        assert!(matches!(plain_reason(&mem), Reason::Limit));
        assert!(over_memory("PNG")
            .to_string()
            .contains("decode memory limit of"));
        let kept = image::ImageError::Decoding(image::error::DecodingError::new(
            image::error::ImageFormatHint::Exact(image::ImageFormat::Png),
            "unexpected end of file",
        ));
        assert!(
            matches!(plain_reason(&kept), Reason::Said(w) if w.ends_with("unexpected end of file"))
        );
    }

    fn checker(w: u32, h: u32) -> Rgba8Image {
        let mut img = Rgba8Image::new(w, h);
        for y in 0..h {
            for x in 0..w {
                let v = if (x + y) % 2 == 0 { 255 } else { 0 };
                img.put(x, y, [v, 0, 255 - v, 255]);
            }
        }
        img
    }

    #[test]
    fn png_round_trip() {
        let img = checker(5, 3);
        let png = encode_png(&img).unwrap();
        assert_eq!(decode(&png, Limits::default()).unwrap(), img);
    }

    #[test]
    fn empty_file_is_named() {
        let e = decode(&[], Limits::default()).unwrap_err();
        assert!(e.to_string().contains("empty"), "{e}");
    }

    #[test]
    fn not_an_image_is_named() {
        let e = decode(b"hello, this is text", Limits::default()).unwrap_err();
        assert!(e.to_string().contains("not an image"), "{e}");
    }

    #[test]
    fn truncated_png_is_named() {
        let png = encode_png(&checker(64, 64)).unwrap();
        let e = decode(&png[..png.len() / 2], Limits::default()).unwrap_err();
        assert!(e.to_string().contains("truncated"), "{e}");
    }

    #[test]
    fn too_large_is_refused_before_decoding() {
        let png = encode_png(&checker(40, 30)).unwrap();
        let limits = Limits {
            max_side: 32,
            max_pixels: 1 << 20,
        };
        let e = decode(&png, limits).unwrap_err();
        assert_eq!(e.to_string(), "40×30 exceeds the 32×32 limit");
        let limits = Limits {
            max_side: 64,
            max_pixels: 1000,
        };
        assert!(matches!(decode(&png, limits), Err(Error::Limit(_))));
    }

    #[test]
    fn raw_sizes_that_wrap_on_32_bits_are_refused_before_allocating() {
        // 65536² × 4 = 2^34 and 32768² × 4 = 2^32 both wrap to 0 in a 32-bit
        // usize: an empty buffer must never pass as such an image.
        for (w, h) in [(65536, 65536), (32768, 32768), (u32::MAX, 2), (2, u32::MAX)] {
            // Computed in u64 (as the check does) the size is far above 32 bits.
            assert!(w as u64 * h as u64 * 4 > u32::MAX as u64);
            let e = Rgba8Image::from_raw(w, h, vec![]).unwrap_err();
            assert!(matches!(e, Error::Limit(_)), "{w}×{h}: {e}");
            assert!(e.to_string().contains("limit"), "{e}");
            let e = Rgba8Image::try_new(w, h).unwrap_err();
            assert!(matches!(e, Error::Limit(_)), "{w}×{h}: {e}");
        }
        // Without the size limits the byte count itself is checked in u64.
        let open = Limits {
            max_side: u32::MAX,
            max_pixels: u64::MAX,
        };
        let r = open.check(65536, 65536);
        assert_eq!(r.is_ok(), usize::BITS > 32, "{r:?}");
        let e = Rgba8Image::from_raw_checked(65536, 65536, vec![]).unwrap_err();
        assert!(e.to_string().contains("17179869184 bytes"), "{e}");
    }

    #[test]
    fn raw_length_and_limits_are_named() {
        let e = Rgba8Image::from_raw(2, 2, vec![0; 15]).unwrap_err();
        assert_eq!(e.to_string(), "2×2 RGBA needs 16 bytes, got 15");
        assert!(Rgba8Image::from_raw(2, 2, vec![0; 16]).is_ok());
        let e = Rgba8Image::from_raw(5000, 1, vec![0; 20000]).unwrap_err();
        assert_eq!(e.to_string(), "5000×1 exceeds the 4096×4096 limit");
        let tight = Limits {
            max_side: 100,
            max_pixels: 50,
        };
        let e = tight.check(10, 6).unwrap_err().to_string();
        assert_eq!(e, "10×6 has 60 pixels, more than the limit of 50 pixels");
    }

    #[test]
    fn thumbnail_keeps_aspect_and_averages() {
        let img = checker(100, 50);
        let t = img.thumbnail(10);
        assert_eq!((t.width, t.height), (10, 5));
        let p = t.get(0, 0);
        assert!((120..=135).contains(&p[0]), "{p:?}");
        assert_eq!(img.thumbnail(200), img);
    }

    /// A PNG of `w × h` of the given type with pseudo-random samples (and
    /// an optional tRNS chunk), written with the `png` crate.
    fn png_of(
        colour: png::ColorType,
        depth: png::BitDepth,
        trns: Option<&[u8]>,
        seed: u32,
    ) -> Vec<u8> {
        let (w, h) = (13u32, 7u32);
        let bits = depth as usize;
        let channels = match colour {
            png::ColorType::Grayscale | png::ColorType::Indexed => 1,
            png::ColorType::GrayscaleAlpha => 2,
            png::ColorType::Rgb => 3,
            png::ColorType::Rgba => 4,
        };
        let line = (w as usize * channels * bits).div_ceil(8);
        let mut state = seed.wrapping_mul(2654435761).max(1);
        let mut data: Vec<u8> = (0..line * h as usize)
            .map(|_| {
                state ^= state << 13;
                state ^= state >> 17;
                state ^= state << 5;
                (state >> 11) as u8
            })
            .collect();
        if colour == png::ColorType::Indexed {
            // Indices below the palette's 5 entries.
            let per = 8 / bits;
            for b in data.iter_mut() {
                let mut v = 0u8;
                for k in 0..per {
                    let idx = ((*b as usize >> (k * bits)) % 5) as u8 & ((1u16 << bits) - 1) as u8;
                    v |= idx.min(((1u16 << bits) - 1) as u8) << (k * bits);
                }
                *b = v;
            }
        }
        let mut out = vec![];
        {
            let mut e = png::Encoder::new(&mut out, w, h);
            e.set_color(colour);
            e.set_depth(depth);
            if colour == png::ColorType::Indexed {
                e.set_palette(vec![
                    0, 0, 0, 255, 10, 20, 30, 200, 100, 7, 8, 9, 250, 251, 252,
                ]);
            }
            if let Some(t) = trns {
                e.set_trns(t.to_vec());
            }
            let mut wr = e.write_header().unwrap();
            wr.write_image_data(&data).unwrap();
        }
        out
    }

    fn decode_in_parts(bytes: &[u8], budget: usize) -> (Result<Rgba8Image>, usize, bool) {
        let mut d = Decoding::new(bytes.to_vec(), Limits::default());
        let parts = d.in_parts();
        let mut steps = 0;
        loop {
            steps += 1;
            match d.step(budget) {
                Ok(Some(img)) => return (Ok(img), steps, parts),
                Ok(None) => {}
                Err(e) => return (Err(e), steps, parts),
            }
        }
    }

    /// Every PNG colour type and bit depth (palette, grey and RGB with and
    /// without tRNS) decoded a row a step equals the one-go decode byte for
    /// byte.
    #[test]
    fn decoding_in_parts_gives_the_same_bytes_for_every_png_type() {
        use png::{BitDepth as B, ColorType as C};
        let cases: Vec<(C, B, Option<&[u8]>)> = vec![
            (C::Grayscale, B::One, None),
            (C::Grayscale, B::Two, None),
            (C::Grayscale, B::Four, None),
            (C::Grayscale, B::Eight, None),
            (C::Grayscale, B::Sixteen, None),
            (C::Grayscale, B::Eight, Some(&[0, 77])),
            (C::Grayscale, B::Four, Some(&[0, 3])),
            (C::Grayscale, B::Sixteen, Some(&[1, 2])),
            (C::GrayscaleAlpha, B::Eight, None),
            (C::GrayscaleAlpha, B::Sixteen, None),
            (C::Rgb, B::Eight, None),
            (C::Rgb, B::Sixteen, None),
            (C::Rgb, B::Eight, Some(&[0, 1, 0, 2, 0, 3])),
            (C::Rgb, B::Sixteen, Some(&[0, 1, 0, 2, 0, 3])),
            (C::Rgba, B::Eight, None),
            (C::Rgba, B::Sixteen, None),
            (C::Indexed, B::One, None),
            (C::Indexed, B::Two, None),
            (C::Indexed, B::Four, Some(&[255, 0, 128])),
            (C::Indexed, B::Eight, None),
            (C::Indexed, B::Eight, Some(&[255, 0, 128, 7, 1])),
        ];
        for (k, (c, b, t)) in cases.iter().enumerate() {
            let bytes = png_of(*c, *b, *t, k as u32 + 1);
            let want = decode(&bytes, Limits::default()).unwrap();
            for budget in [1, 40, usize::MAX] {
                let (got, steps, parts) = decode_in_parts(&bytes, budget);
                assert_eq!(got.unwrap(), want, "{c:?} {b:?} tRNS {t:?}");
                assert!(parts, "{c:?} {b:?}: decoded in parts");
                if budget == 1 {
                    assert_eq!(steps, want.height as usize, "a row a step");
                }
            }
        }
    }

    /// An interlaced 8×8 8-bit grey PNG written by hand (Adam7 passes,
    /// filter 0, stored deflate blocks).
    fn interlaced_png() -> Vec<u8> {
        fn crc(data: &[u8]) -> u32 {
            let mut c = !0u32;
            for &b in data {
                c ^= b as u32;
                for _ in 0..8 {
                    c = if c & 1 != 0 {
                        0xEDB8_8320 ^ (c >> 1)
                    } else {
                        c >> 1
                    };
                }
            }
            !c
        }
        fn chunk(out: &mut Vec<u8>, kind: &[u8], data: &[u8]) {
            out.extend((data.len() as u32).to_be_bytes());
            let mut body = kind.to_vec();
            body.extend(data);
            out.extend(&body);
            out.extend(crc(&body).to_be_bytes());
        }
        // Adam7 pass sizes of an 8×8 image: (columns, rows).
        let passes = [(1, 1), (1, 1), (2, 1), (2, 2), (4, 2), (4, 4), (8, 4)];
        let mut raw = vec![];
        let mut v = 3u8;
        for (w, h) in passes {
            for _ in 0..h {
                // Filter type 0, then the row's samples.
                let row = std::iter::once(0).chain((0..w).map(|_| {
                    v = v.wrapping_mul(37).wrapping_add(11);
                    v
                }));
                raw.extend(row.collect::<Vec<u8>>());
            }
        }
        let (mut a, mut b) = (1u32, 0u32);
        for &x in &raw {
            a = (a + x as u32) % 65521;
            b = (b + a) % 65521;
        }
        let mut z = vec![0x78, 0x01, 0x01];
        z.extend((raw.len() as u16).to_le_bytes());
        z.extend((!(raw.len() as u16)).to_le_bytes());
        z.extend(&raw);
        z.extend(((b << 16) | a).to_be_bytes());
        let mut out = vec![137, 80, 78, 71, 13, 10, 26, 10];
        let mut ihdr = vec![];
        ihdr.extend(8u32.to_be_bytes());
        ihdr.extend(8u32.to_be_bytes());
        ihdr.extend([8, 0, 0, 0, 1]);
        chunk(&mut out, b"IHDR", &ihdr);
        chunk(&mut out, b"IDAT", &z);
        chunk(&mut out, b"IEND", &[]);
        out
    }

    #[test]
    fn an_interlaced_png_is_decoded_in_one_go() {
        let bytes = interlaced_png();
        let want = decode(&bytes, Limits::default()).unwrap();
        assert_eq!((want.width, want.height), (8, 8));
        let (got, steps, parts) = decode_in_parts(&bytes, 1);
        assert!(!parts, "interlaced: no rows in order to read");
        assert_eq!((got.unwrap(), steps), (want, 1));
    }

    #[test]
    fn decoding_in_parts_fails_as_decode_does() {
        let png = encode_png(&checker(64, 64)).unwrap();
        for bytes in [
            &png[..png.len() / 2],
            &png[..40],
            &b"not an image"[..],
            &[][..],
        ] {
            let want = decode(bytes, Limits::default()).unwrap_err();
            let (got, _, _) = decode_in_parts(bytes, 10);
            assert_eq!(got.unwrap_err(), want);
        }
        let limits = Limits {
            max_side: 32,
            max_pixels: 1 << 20,
        };
        let want = decode(&png, limits).unwrap_err();
        let mut d = Decoding::new(png.clone(), limits);
        assert!(!d.in_parts(), "over the limits: one go, which refuses it");
        assert_eq!(d.step(10).unwrap_err(), want);
    }
}
