//! "What is in this image": size, exact and clustered palette, thumbnail.
//!
//! Shared by every tool that reads an image: Fit snaps targets to a palette,
//! Pixel maps colours within the source palette. The CLI (`filigree inspect`)
//! and the browser worker (`inspect` request) call [`inspect`].
use crate::core::error::Result;
use crate::core::job::{Job, Progress, Step};
use crate::core::limits;
use crate::raster::{
    check_tolerance, cluster_counts, colour_counts, decode, Cluster, Leaders, Limits, PaletteEntry,
    RadixSteps, Rgba8Image,
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

/// Units of work (pixels, colours, clusters) per [`InspectJob`] step: a
/// few milliseconds (`filigree bench slices`).
pub const INSPECT_STEP_BUDGET: usize = 1 << 18;

enum Phase {
    /// Packed colours of the opaque-enough pixels; translucent count.
    Collect,
    /// Radix sort of the packed colours.
    SortColours,
    /// Runs of equal colours → (colour, count).
    Runs,
    /// Stable sort by falling count.
    SortCounts,
    /// Leader clustering, most frequent colour first.
    Cluster,
    /// The largest clusters, in listing order.
    Top,
    /// Thumbnail rows.
    Thumbnail,
    Done,
}

/// A cluster ranked by [`crate::raster::cluster_order`] (smaller = listed earlier).
struct Ranked(Cluster);

impl PartialEq for Ranked {
    fn eq(&self, o: &Self) -> bool {
        self.cmp(o).is_eq()
    }
}
impl Eq for Ranked {}
impl PartialOrd for Ranked {
    fn partial_cmp(&self, o: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(o))
    }
}
impl Ord for Ranked {
    fn cmp(&self, o: &Self) -> std::cmp::Ordering {
        crate::raster::cluster_order(&self.0, &o.0)
    }
}

/// [`inspect_image`] in bounded steps of about `budget` pixels (or
/// colours, or clusters) each, for the worker: the answer is the same, field
/// for field. Colours are radix-sorted a slice at a time, clustered a slice
/// at a time, and only the listed clusters are kept sorted (a bounded heap),
/// so no step is proportional to the image.
pub struct InspectJob {
    img: Rgba8Image,
    opts: InspectOptions,
    budget: usize,
    phase: Phase,
    pos: usize,
    translucent: u64,
    px: Vec<u32>,
    colours: RadixSteps<u32>,
    counts: Vec<(u32, u32)>,
    by_count: RadixSteps<(u32, u32)>,
    leaders: Option<Leaders>,
    clusters: Vec<Cluster>,
    cluster_count: usize,
    top: std::collections::BinaryHeap<Ranked>,
    thumb: Option<Rgba8Image>,
}

impl InspectJob {
    /// Inspect an already decoded image; the options are checked first.
    pub fn new(img: Rgba8Image, opts: &InspectOptions) -> Result<InspectJob> {
        check_tolerance(opts.tolerance)?;
        let thumb = img
            .thumbnail_size(opts.thumbnail_side)
            .map(|(w, h)| Rgba8Image::new(w, h));
        Ok(InspectJob {
            px: Vec::with_capacity(img.pixel_count()),
            img,
            opts: *opts,
            budget: INSPECT_STEP_BUDGET,
            phase: Phase::Collect,
            pos: 0,
            translucent: 0,
            colours: RadixSteps::new(),
            counts: vec![],
            by_count: RadixSteps::new(),
            leaders: None,
            clusters: vec![],
            cluster_count: 0,
            top: Default::default(),
            thumb,
        })
    }

    /// The same job with `budget` units per step (tests).
    pub fn with_budget(mut self, budget: usize) -> Self {
        self.budget = budget.max(1);
        self
    }

    fn stage(&self) -> (&'static str, f64) {
        let n = self.img.pixel_count().max(1) as f64;
        let part = |done: usize, of: usize| (done as f64 / of.max(1) as f64).min(1.0);
        match self.phase {
            Phase::Collect => ("reading pixels", 0.1 * part(self.pos, n as usize)),
            Phase::SortColours => ("sorting colours", 0.1 + 0.3 * self.colours.fraction()),
            Phase::Runs => (
                "counting colours",
                0.4 + 0.1 * part(self.pos, self.px.len()),
            ),
            Phase::SortCounts => ("ranking colours", 0.5 + 0.2 * self.by_count.fraction()),
            Phase::Cluster => ("clustering", 0.7 + 0.2 * part(self.pos, self.counts.len())),
            Phase::Top => (
                "ranking clusters",
                0.9 + 0.05 * part(self.pos, self.clusters.len()),
            ),
            Phase::Thumbnail => {
                let h = self.thumb.as_ref().map_or(1, |t| t.height as usize);
                ("thumbnail", 0.95 + 0.05 * part(self.pos, h))
            }
            Phase::Done => ("done", 1.0),
        }
    }

    fn finish(&mut self) -> Inspection {
        let palette = self
            .counts
            .iter()
            .take(self.opts.max_listed_colours)
            .map(|&(c, n)| PaletteEntry {
                rgba: c.to_be_bytes(),
                count: n as u64,
            })
            .collect();
        let top = std::mem::take(&mut self.top).into_sorted_vec();
        Inspection {
            width: self.img.width,
            height: self.img.height,
            colour_count: self.counts.len(),
            translucent_pixels: self.translucent,
            palette,
            cluster_count: self.cluster_count,
            clusters: top.into_iter().map(|r| r.0).collect(),
            thumbnail: match self.thumb.take() {
                Some(t) => t,
                None => self.img.clone(),
            },
        }
    }
}

impl Job for InspectJob {
    type Output = Inspection;
    fn step(&mut self) -> Result<Step<Inspection>> {
        let budget = self.budget;
        let mut spent = 0usize;
        while spent < budget {
            match self.phase {
                Phase::Collect => {
                    let n = self.img.pixel_count();
                    let end = n.min(self.pos + budget - spent);
                    for c in self.img.data[4 * self.pos..4 * end].chunks_exact(4) {
                        if c[3] < 255 {
                            self.translucent += 1;
                        }
                        if c[3] > 0 {
                            self.px.push(u32::from_be_bytes([c[0], c[1], c[2], c[3]]));
                        }
                    }
                    spent += end - self.pos + 1;
                    self.pos = end;
                    if end == n {
                        self.pos = 0;
                        self.phase = Phase::SortColours;
                    }
                }
                Phase::SortColours => {
                    if self.colours.run(&mut self.px, |&c| c, budget - spent) {
                        self.phase = Phase::Runs;
                    }
                    spent = budget;
                }
                Phase::Runs => {
                    let end = self.px.len().min(self.pos + budget - spent);
                    for &c in &self.px[self.pos..end] {
                        match self.counts.last_mut() {
                            Some(last) if last.0 == c => last.1 += 1,
                            _ => self.counts.push((c, 1)),
                        }
                    }
                    spent += end - self.pos + 1;
                    self.pos = end;
                    if end == self.px.len() {
                        self.px = Vec::new();
                        self.colours = RadixSteps::new();
                        self.pos = 0;
                        self.phase = Phase::SortCounts;
                    }
                }
                Phase::SortCounts => {
                    // Stable by falling count: equal counts stay in colour order.
                    if self
                        .by_count
                        .run(&mut self.counts, |e| !e.1, budget - spent)
                    {
                        self.leaders = Some(Leaders::new(self.opts.tolerance, self.counts.len()));
                        self.phase = Phase::Cluster;
                    }
                    spent = budget;
                }
                Phase::Cluster => {
                    let leaders = self.leaders.as_mut().expect("made before clustering");
                    // Each colour costs the representatives it is compared with.
                    while self.pos < self.counts.len() && spent < budget {
                        let (c, n) = self.counts[self.pos];
                        spent += 1 + leaders.add(c.to_be_bytes(), n as u64);
                        self.pos += 1;
                    }
                    if self.pos == self.counts.len() {
                        self.clusters = self.leaders.take().expect("present").into_clusters();
                        self.cluster_count = self.clusters.len();
                        self.pos = 0;
                        self.phase = Phase::Top;
                    }
                }
                Phase::Top => {
                    let k = self.opts.max_listed_clusters;
                    let end = self.clusters.len().min(self.pos + budget - spent);
                    for c in &self.clusters[self.pos..end] {
                        if self.top.len() < k {
                            self.top.push(Ranked(c.clone()));
                        } else if self
                            .top
                            .peek()
                            .is_some_and(|w| crate::raster::cluster_order(c, &w.0).is_lt())
                        {
                            self.top.pop();
                            self.top.push(Ranked(c.clone()));
                        }
                    }
                    spent += end - self.pos + 1;
                    self.pos = end;
                    if end == self.clusters.len() {
                        self.clusters = Vec::new();
                        self.pos = 0;
                        self.phase = Phase::Thumbnail;
                    }
                }
                Phase::Thumbnail => {
                    let Some(t) = self.thumb.as_mut() else {
                        self.phase = Phase::Done;
                        continue;
                    };
                    let per_row = (self.img.pixel_count() / t.height.max(1) as usize).max(1);
                    while self.pos < t.height as usize && spent < budget {
                        self.img.thumbnail_row(t, self.pos as u32);
                        self.pos += 1;
                        spent += per_row;
                    }
                    if self.pos == t.height as usize {
                        self.phase = Phase::Done;
                    }
                }
                Phase::Done => return Ok(Step::Done(self.finish())),
            }
        }
        if matches!(self.phase, Phase::Done) {
            return Ok(Step::Done(self.finish()));
        }
        let (stage, f) = self.stage();
        Ok(Step::Running(Progress::new(f, stage)))
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

    /// The job in small steps answers exactly what [`inspect_image`] does:
    /// big images (radix paths), many colours (the clustering grid), more
    /// clusters than are listed, translucent pixels, any tolerance.
    #[test]
    fn stepped_inspection_equals_one_go() {
        let mut rng = crate::core::rng::Rng::new(3);
        let mut img = Rgba8Image::new(300, 280);
        for y in 0..280 {
            for x in 0..300 {
                let c = if (x / 40 + y / 40) % 3 == 0 {
                    [200, 30, 30, 255]
                } else {
                    [
                        rng.below(256) as u8,
                        (x % 64) as u8,
                        (y % 16) as u8 * 9,
                        [0, 128, 255, 255][rng.below(4)],
                    ]
                };
                img.put(x, y, c);
            }
        }
        let small = img.thumbnail(100);
        for im in [&img, &small] {
            for tolerance in [0.0, 3.0, 24.0, 442.0] {
                let opts = InspectOptions {
                    tolerance,
                    ..Default::default()
                };
                let want = inspect_image(im, &opts).unwrap();
                for budget in [1000, usize::MAX] {
                    let mut job = InspectJob::new(im.clone(), &opts)
                        .unwrap()
                        .with_budget(budget);
                    let mut steps = 0;
                    let mut last = 0.0;
                    let got = loop {
                        steps += 1;
                        match job.step().unwrap() {
                            Step::Running(p) => {
                                assert!(p.fraction >= last && p.fraction < 1.0, "{p:?}");
                                last = p.fraction;
                            }
                            Step::Done(r) => break r,
                        }
                    };
                    if budget == 1000 {
                        assert!(steps > im.pixel_count() / 1000, "{steps} steps");
                    }
                    let t = format!("tolerance {tolerance} budget {budget}");
                    assert_eq!(
                        (
                            got.width,
                            got.height,
                            got.colour_count,
                            got.translucent_pixels
                        ),
                        (
                            want.width,
                            want.height,
                            want.colour_count,
                            want.translucent_pixels
                        ),
                        "{t}"
                    );
                    assert_eq!(got.palette, want.palette, "{t}");
                    assert_eq!(got.cluster_count, want.cluster_count, "{t}");
                    assert_eq!(got.clusters, want.clusters, "{t}");
                    assert!(got.thumbnail == want.thumbnail, "{t}");
                }
            }
        }
    }
}
