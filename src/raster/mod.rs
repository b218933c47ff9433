//! Raster images: decoding with explicit limits, palettes, thumbnails, PNG out.
mod image_buf;
mod palette;

pub use image_buf::{decode, encode_png, Limits, Rgba8Image};
pub use palette::{cluster_palette, exact_palette, Cluster, PaletteEntry};
