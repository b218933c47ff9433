//! "What is in this image": size, exact and clustered palette, thumbnail.
//!
//! Shared by every tool that reads an image: Fit snaps targets to a palette,
//! Pixel maps colours within the source palette. The CLI (`filigree inspect`)
//! and the browser worker (`inspect` request) call [`inspect`].
use crate::core::error::Result;
use crate::core::limits;
use crate::raster::{
    check_tolerance, cluster_counts, colour_counts, decode, Cluster, Limits, PaletteEntry,
    Rgba8Image,
};
use serde::Serialize;

/// Options for [`inspect`].
#[derive(Debug, Clone, Copy)]
pub struct InspectOptions {
    pub limits: Limits,
    /// RGB distance under which colours are merged in `clusters`: a finite
    /// number in `0..=442` ([`limits::MAX_TOLERANCE`]).
    pub tolerance: f64,
    /// Longer side of the thumbnail, in pixels (at most
    /// [`limits::MAX_THUMBNAIL_SIDE`]).
    pub thumbnail_side: u32,
    /// At most this many exact colours are listed (the count is always exact).
    pub max_listed_colours: usize,
    /// At most this many clusters are listed (the count is always exact).
    pub max_listed_clusters: usize,
}

impl Default for InspectOptions {
    fn default() -> Self {
        InspectOptions {
            limits: Limits::default(),
            tolerance: 24.0,
            thumbnail_side: 128,
            max_listed_colours: limits::MAX_LISTED_COLOURS,
            max_listed_clusters: limits::MAX_LISTED_CLUSTERS,
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
    /// Clusters of colours merged within the tolerance (in all).
    pub cluster_count: usize,
    /// The largest clusters (at most `max_listed_clusters`).
    pub clusters: Vec<Cluster>,
    #[serde(skip)]
    pub thumbnail: Rgba8Image,
}

/// Decode `bytes` and describe the image. The options are checked first
/// (a bad tolerance fails before any decoding).
pub fn inspect(bytes: &[u8], opts: &InspectOptions) -> Result<Inspection> {
    check_tolerance(opts.tolerance)?;
    let img = decode(bytes, opts.limits)?;
    inspect_image(&img, opts)
}

/// Describe an already decoded image. Linear in the pixel count (plus the
/// near-linear clustering, see [`crate::raster::cluster_palette`]).
pub fn inspect_image(img: &Rgba8Image, opts: &InspectOptions) -> Result<Inspection> {
    check_tolerance(opts.tolerance)?;
    let exact = colour_counts(img, 0);
    let mut clusters = cluster_counts(&exact, opts.tolerance)?;
    let cluster_count = clusters.len();
    clusters.truncate(opts.max_listed_clusters);
    let translucent_pixels = img.pixels().filter(|p| p[3] < 255).count() as u64;
    let colour_count = exact.len();
    let palette = exact
        .iter()
        .take(opts.max_listed_colours)
        .map(|&(rgba, count)| PaletteEntry {
            rgba,
            count: count as u64,
        })
        .collect();
    drop(exact);
    Ok(Inspection {
        width: img.width,
        height: img.height,
        colour_count,
        translucent_pixels,
        palette,
        cluster_count,
        clusters,
        thumbnail: img.thumbnail(opts.thumbnail_side),
    })
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

    #[test]
    fn bad_tolerance_is_refused_before_decoding() {
        for t in [f64::NAN, -5.0, 1000.0, f64::NEG_INFINITY] {
            let opts = InspectOptions {
                tolerance: t,
                ..Default::default()
            };
            // Not even an image: the tolerance is what is reported.
            let e = inspect(b"not an image", &opts).unwrap_err().to_string();
            assert!(e.starts_with("tolerance "), "{t}: {e}");
        }
    }

    #[test]
    fn clusters_are_counted_in_full_and_listed_up_to_the_cap() {
        // 64×64 distinct greys-and-reds, tolerance 0: 4096 clusters, 1024 listed.
        let mut img = Rgba8Image::new(64, 64);
        for y in 0..64 {
            for x in 0..64 {
                img.put(x, y, [x as u8 * 4, y as u8 * 4, 7, 255]);
            }
        }
        let opts = InspectOptions {
            tolerance: 0.0,
            ..Default::default()
        };
        let r = inspect_image(&img, &opts).unwrap();
        assert_eq!(r.colour_count, 4096);
        assert_eq!(r.cluster_count, 4096);
        assert_eq!(r.clusters.len(), limits::MAX_LISTED_CLUSTERS);
        assert_eq!(r.palette.len(), limits::MAX_LISTED_COLOURS);
        // Tolerance 4 merges each colour with its grid neighbours.
        let r = inspect_image(
            &img,
            &InspectOptions {
                tolerance: 4.0,
                ..Default::default()
            },
        )
        .unwrap();
        assert!(
            r.cluster_count < 4096 && r.cluster_count > 100,
            "{}",
            r.cluster_count
        );
        let members: usize = r.clusters.iter().map(|c| c.members).sum();
        if r.cluster_count <= limits::MAX_LISTED_CLUSTERS {
            assert_eq!(members, 4096);
        } else {
            assert!(members < 4096);
        }
    }
}
