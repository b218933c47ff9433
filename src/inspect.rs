//! "What is in this image": size, exact and clustered palette, thumbnail.
//!
//! Shared by every tool that reads an image: Fit snaps targets to a palette,
//! Pixel maps colours within the source palette. The CLI (`filigree inspect`)
//! and the browser worker (`inspect` request) call [`inspect`].
use crate::core::error::Result;
use crate::raster::{cluster_palette, decode, Cluster, Limits, PaletteEntry, Rgba8Image};
use serde::Serialize;

/// Options for [`inspect`].
#[derive(Debug, Clone, Copy)]
pub struct InspectOptions {
    pub limits: Limits,
    /// RGB distance under which colours are merged in `clusters`.
    pub tolerance: f64,
    /// Longer side of the thumbnail, in pixels.
    pub thumbnail_side: u32,
    /// At most this many exact colours are listed (the count is always exact).
    pub max_listed_colours: usize,
}

impl Default for InspectOptions {
    fn default() -> Self {
        InspectOptions {
            limits: Limits::default(),
            tolerance: 24.0,
            thumbnail_side: 128,
            max_listed_colours: 256,
        }
    }
}

/// The answer of [`inspect`].
#[derive(Debug, Clone, Serialize)]
pub struct Inspection {
    pub width: u32,
    pub height: u32,
    /// Distinct exact colours among pixels with alpha > 0.
    pub colour_count: usize,
    /// Pixels with alpha < 255.
    pub translucent_pixels: u64,
    /// The most frequent exact colours (at most `max_listed_colours`).
    pub palette: Vec<PaletteEntry>,
    /// Colours merged within the tolerance.
    pub clusters: Vec<Cluster>,
    #[serde(skip)]
    pub thumbnail: Rgba8Image,
}

/// Decode `bytes` and describe the image.
pub fn inspect(bytes: &[u8], opts: &InspectOptions) -> Result<Inspection> {
    let img = decode(bytes, opts.limits)?;
    Ok(inspect_image(&img, opts))
}

/// Describe an already decoded image.
pub fn inspect_image(img: &Rgba8Image, opts: &InspectOptions) -> Inspection {
    let exact = crate::raster::exact_palette(img, 0);
    let clusters = cluster_palette(&exact, opts.tolerance);
    let translucent_pixels = img.pixels().filter(|p| p[3] < 255).count() as u64;
    let colour_count = exact.len();
    let mut palette = exact;
    palette.truncate(opts.max_listed_colours);
    Inspection {
        width: img.width,
        height: img.height,
        colour_count,
        translucent_pixels,
        palette,
        clusters,
        thumbnail: img.thumbnail(opts.thumbnail_side),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::raster::encode_png;

    #[test]
    fn inspects_a_png() {
        let mut img = Rgba8Image::new(300, 100);
        for y in 0..100 {
            for x in 0..300 {
                img.put(
                    x,
                    y,
                    if x < 100 {
                        [10, 20, 30, 255]
                    } else {
                        [250, 240, 230, 255]
                    },
                );
            }
        }
        let r = inspect(&encode_png(&img).unwrap(), &InspectOptions::default()).unwrap();
        assert_eq!((r.width, r.height, r.colour_count), (300, 100, 2));
        assert_eq!(r.palette[0].rgba, [250, 240, 230, 255]);
        assert_eq!(r.palette[0].count, 20000);
        assert_eq!((r.thumbnail.width, r.thumbnail.height), (128, 42));
        assert_eq!(r.translucent_pixels, 0);
    }
}
