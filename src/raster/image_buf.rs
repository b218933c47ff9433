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
    if bytes.is_empty() {
        return Err(Error::input("the file is empty (0 bytes)"));
    }
    let format = image::guess_format(bytes).map_err(|_| {
        Error::input(
            "this is not an image Filigree can read (expected PNG, JPEG, WebP, GIF or BMP)",
        )
    })?;
    let name = format_name(format);
    let reader = ImageReader::with_format(Cursor::new(bytes), format);
    let decoder = reader
        .into_decoder()
        .map_err(|e| Error::input(format!("the {name} header could not be read: {e}")))?;
    let mut decoder = decoder;
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
        image::ImageError::Limits(e) => Error::limit(format!(
            "decoding this {name} needs more than the decode memory limit of {} MiB ({e})",
            limits::MAX_DECODE_ALLOC >> 20
        )),
        e => Error::input(format!("the {name} data is damaged or truncated ({e})")),
    })?;
    let rgba = img.into_rgba8();
    Rgba8Image::from_raw_checked(w, h, rgba.into_raw())
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
}
