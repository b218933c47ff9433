//! Raster images: decoding with explicit limits, palettes, thumbnails, PNG out.
mod image_buf;
mod palette;

pub use image_buf::{decode, encode_png, Limits, Rgba8Image};
pub use palette::{
    check_tolerance, cluster_counts, cluster_order, cluster_palette, colour_counts, count_colours,
    exact_palette, Cluster, ColourCounter, Leaders, PaletteEntry, RadixSteps,
};
