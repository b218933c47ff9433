//! Raster images: decoding with explicit limits, palettes, thumbnails, PNG out.
mod image_buf;
mod palette;

use serde::{Deserialize, Serialize};

pub use image_buf::{
    decode, decode_png, decode_sent, encode_png, Decoding, Limits, Rgba8Image,
    DECODE_PIXELS_PER_STEP,
};
pub use palette::{
    check_tolerance, cluster_counts, cluster_order, cluster_palette, colour_counts, count_colours,
    exact_palette, Cluster, ColourCounter, Leaders, PaletteEntry, RadixSteps,
};

/// An image as it crosses the boundary undecoded: straight RGBA bytes
/// (a `Uint8Array` in the browser).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RawImage {
    pub width: u32,
    pub height: u32,
    #[serde(with = "serde_bytes")]
    pub rgba: Vec<u8>,
}

impl From<Rgba8Image> for RawImage {
    fn from(img: Rgba8Image) -> Self {
        RawImage {
            width: img.width,
            height: img.height,
            rgba: img.data,
        }
    }
}
