//! Raster images: decoding with explicit limits, palettes, thumbnails, PNG out.
mod image_buf;
mod palette;

pub use image_buf::{
    decode, decode_file, decode_png, decode_sent, encode_png, header_size, png_header_size,
    sent_header_size, Decoder, Decoding, HeaderError, HeaderReader, Limits, Rgba8Image,
    DECODE_PIXELS_PER_STEP,
};
pub use palette::{
    check_tolerance, cluster_counts, cluster_order, cluster_palette, colour_counts, count_colours,
    exact_palette, Cluster, ColourCounter, Leaders, PaletteEntry, RadixSteps,
};

/// Plain pixels (defined in core, so a job's progress can carry them).
pub use crate::core::image::RawImage;

impl From<Rgba8Image> for RawImage {
    fn from(img: Rgba8Image) -> Self {
        RawImage {
            width: img.width,
            height: img.height,
            rgba: img.data,
        }
    }
}
