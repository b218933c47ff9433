use super::Rgba8Image;
use crate::core::error::{Error, Result};
use crate::core::limits;
use serde::Serialize;

/// One exact colour of an image and how many pixels have it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PaletteEntry {
    pub rgba: [u8; 4],
    pub count: u64,
}

/// `[r, g, b, a]` packed so that `u32` order is the array's lexicographic order.
#[inline]
fn pack(c: [u8; 4]) -> u32 {
    u32::from_be_bytes(c)
}

/// Every distinct colour of the opaque-enough pixels (alpha > `min_alpha`)
/// with its pixel count, most frequent first, ties broken by colour so the
/// order is deterministic. Compact (8 bytes a colour) and linear in the
/// pixel count: the colours are radix-sorted, not hashed, so an image with
/// 16 million distinct colours needs no hash table of 16 million entries.
pub fn colour_counts(img: &Rgba8Image, min_alpha: u8) -> Vec<([u8; 4], u32)> {
    let mut px: Vec<u32> = img
        .pixels()
        .filter(|p| p[3] > min_alpha)
        .map(pack)
        .collect();
    radix_sort(&mut px);
    let mut v: Vec<(u32, u32)> = Vec::new();
    for &c in &px {
        match v.last_mut() {
            Some(last) if last.0 == c => last.1 += 1,
            _ => v.push((c, 1)),
        }
    }
    drop(px);
    // Sorted by colour already; a stable sort by falling count keeps colour
    // order among equal counts (and is linear when all counts are equal).
    v.sort_by_key(|e| std::cmp::Reverse(e.1));
    v.into_iter().map(|(c, n)| (c.to_be_bytes(), n)).collect()
}

/// Sort `u32`s ascending: LSD radix sort, four passes of one byte, for big
/// inputs (linear, one extra buffer); the standard sort for small ones.
fn radix_sort(v: &mut Vec<u32>) {
    if v.len() < 1 << 16 {
        v.sort_unstable();
        return;
    }
    let mut buf = vec![0u32; v.len()];
    for shift in [0u32, 8, 16, 24] {
        let mut count = [0usize; 257];
        for &x in v.iter() {
            count[((x >> shift) & 0xff) as usize + 1] += 1;
        }
        if count.contains(&v.len()) {
            continue; // every key has the same byte here: nothing moves
        }
        for i in 0..256 {
            count[i + 1] += count[i];
        }
        for &x in v.iter() {
            let b = ((x >> shift) & 0xff) as usize;
            buf[count[b]] = x;
            count[b] += 1;
        }
        std::mem::swap(v, &mut buf);
    }
}

/// LSD radix sort by a `u32` key (four passes of one byte), resumable
/// between any two elements so a job can spread a sort of millions over
/// slices. Stable: equal keys keep their order.
pub struct RadixSteps<T> {
    pass: u32,
    scatter: bool,
    pos: usize,
    count: [usize; 257],
    buf: Vec<T>,
}

impl<T: Copy + Default> Default for RadixSteps<T> {
    fn default() -> Self {
        RadixSteps {
            pass: 0,
            scatter: false,
            pos: 0,
            count: [0; 257],
            buf: Vec::new(),
        }
    }
}

impl<T: Copy + Default> RadixSteps<T> {
    pub fn new() -> Self {
        Self::default()
    }

    /// Go on sorting `v` by `key` for about `budget` elements; `true` when sorted.
    pub fn run(&mut self, v: &mut Vec<T>, key: impl Fn(&T) -> u32, budget: usize) -> bool {
        let budget = budget.max(1);
        let mut spent = 0;
        while self.pass < 4 && spent < budget {
            let shift = 8 * self.pass;
            let byte = |x: &T| ((key(x) >> shift) & 0xff) as usize;
            let end = v.len().min(self.pos + budget - spent);
            if !self.scatter {
                for x in &v[self.pos..end] {
                    self.count[byte(x) + 1] += 1;
                }
            } else {
                for x in &v[self.pos..end] {
                    let b = byte(x);
                    self.buf[self.count[b]] = *x;
                    self.count[b] += 1;
                }
            }
            spent += end - self.pos + 1;
            self.pos = end;
            if end < v.len() {
                continue;
            }
            self.pos = 0;
            if self.scatter {
                std::mem::swap(v, &mut self.buf);
                self.next_pass();
            } else if self.count.contains(&v.len()) {
                // Every key has the same byte here: nothing moves.
                self.next_pass();
            } else {
                for i in 0..256 {
                    self.count[i + 1] += self.count[i];
                }
                if self.buf.len() != v.len() {
                    self.buf = vec![T::default(); v.len()];
                }
                self.scatter = true;
            }
        }
        if self.pass == 4 {
            self.buf = Vec::new();
        }
        self.pass == 4
    }

    fn next_pass(&mut self) {
        self.pass += 1;
        self.scatter = false;
        self.count = [0; 257];
    }

    /// Passes done, `0..=4` (a quarter each).
    pub fn fraction(&self) -> f64 {
        self.pass as f64 / 4.0
    }
}

/// Counts the distinct colours of pixels with alpha > `min_alpha`, a slice
/// of pixels at a time (so a 16 Mpx image never blocks one job step), and
/// can stop early once more than a limit are seen.
#[derive(Default)]
pub struct ColourCounter {
    seen: std::collections::HashSet<u32, BuildMix>,
    next: usize,
}

impl ColourCounter {
    pub fn new() -> Self {
        Self::default()
    }

    /// Look at up to `budget` more pixels; `true` when the whole image has
    /// been seen or more than `limit` colours were found.
    pub fn run(&mut self, img: &Rgba8Image, min_alpha: u8, budget: usize, limit: usize) -> bool {
        let n = img.pixel_count();
        let end = n.min(self.next.saturating_add(budget.max(1)));
        let mut last = None;
        for c in img.data[4 * self.next..4 * end].chunks_exact(4) {
            if c[3] > min_alpha {
                let v = u32::from_be_bytes([c[0], c[1], c[2], c[3]]);
                // Pixel art repeats colours along rows: skip the hash then.
                if last != Some(v) {
                    self.seen.insert(v);
                    last = Some(v);
                }
            }
        }
        self.next = end;
        self.next == n || self.seen.len() > limit
    }

    /// Distinct colours seen so far.
    pub fn count(&self) -> usize {
        self.seen.len()
    }
}

/// The number of distinct colours (alpha > `min_alpha`), or `None` as soon as
/// there are more than `limit`.
pub fn count_colours(img: &Rgba8Image, min_alpha: u8, limit: usize) -> Option<usize> {
    let mut c = ColourCounter::new();
    while !c.run(img, min_alpha, 1 << 20, limit) {}
    (c.count() <= limit).then_some(c.count())
}

/// A fast, fixed (so deterministic) hash for packed colours.
#[derive(Default, Clone, Copy)]
pub struct BuildMix;

/// The hasher of [`BuildMix`]: one multiply of the packed colour.
#[derive(Default)]
pub struct Mix(u64);

impl std::hash::BuildHasher for BuildMix {
    type Hasher = Mix;
    fn build_hasher(&self) -> Mix {
        Mix(0)
    }
}

impl std::hash::Hasher for Mix {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0.rotate_left(8) ^ b as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.0 = (v as u64 ^ 0x5851_F42D_4C95_7F2D).wrapping_mul(0x9E37_79B9_7F4A_7C15);
        self.0 ^= self.0 >> 29;
    }
}

/// Every distinct colour of the opaque-enough pixels (alpha > `min_alpha`),
/// most frequent first; ties broken by colour so the order is deterministic.
pub fn exact_palette(img: &Rgba8Image, min_alpha: u8) -> Vec<PaletteEntry> {
    colour_counts(img, min_alpha)
        .into_iter()
        .map(|(rgba, count)| PaletteEntry {
            rgba,
            count: count as u64,
        })
        .collect()
}

/// A group of similar colours, represented by its most frequent member.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Cluster {
    /// The most frequent exact colour of the group.
    pub rgba: [u8; 4],
    /// Pixels in the whole group.
    pub count: u64,
    /// How many exact colours were merged into it.
    pub members: usize,
}

/// Check a clustering tolerance: a finite RGB distance in
/// `0..=`[`limits::MAX_TOLERANCE`]. The message names the field `tolerance`.
pub fn check_tolerance(tolerance: f64) -> Result<()> {
    if tolerance.is_finite() && (0.0..=limits::MAX_TOLERANCE).contains(&tolerance) {
        Ok(())
    } else {
        Err(Error::input(format!(
            "tolerance {tolerance} is not an RGB distance: it must be a number from 0 to {} \
             (442 already merges every colour)",
            limits::MAX_TOLERANCE
        )))
    }
}

/// Group colours whose RGB distance (Euclidean, 0..441) to a cluster's
/// representative is at most `tolerance`. Greedy leader clustering over the
/// exact palette in frequency order: the most common colours become the
/// representatives, so anti-aliasing and JPEG noise fold into the colours a
/// person would name; each colour joins the *first-made* representative
/// within the tolerance. Deterministic. Clusters are sorted by falling count
/// (ties by colour).
///
/// Cost: near-linear in the number of colours. Representatives are filed in
/// a grid of cubes of side 2·tolerance, so each colour compares only with
/// the representatives of the (at most 8) cubes its tolerance ball touches;
/// representatives are more than `tolerance` apart, so a cube holds few.
/// Fails on a tolerance outside `0..=442` (see [`check_tolerance`]).
pub fn cluster_palette(exact: &[PaletteEntry], tolerance: f64) -> Result<Vec<Cluster>> {
    check_tolerance(tolerance)?;
    Ok(leader_clusters(
        exact.iter().map(|e| (e.rgba, e.count)),
        exact.len(),
        tolerance,
    ))
}

/// [`cluster_palette`] over [`colour_counts`]' compact list.
pub fn cluster_counts(counts: &[([u8; 4], u32)], tolerance: f64) -> Result<Vec<Cluster>> {
    check_tolerance(tolerance)?;
    Ok(leader_clusters(
        counts.iter().map(|&(c, n)| (c, n as u64)),
        counts.len(),
        tolerance,
    ))
}

/// Below this many colours the plain O(colours × clusters) scan is cheaper
/// than setting up the grid (and is the definition the grid must match).
const GRID_FROM: usize = 2048;

fn leader_clusters(
    entries: impl Iterator<Item = ([u8; 4], u64)>,
    n: usize,
    tolerance: f64,
) -> Vec<Cluster> {
    let mut l = Leaders::new(tolerance, n);
    for (rgba, count) in entries {
        l.add(rgba, count);
    }
    let mut clusters = l.into_clusters();
    clusters.sort_by(cluster_order);
    clusters
}

/// The order clusters are listed in: falling count, ties by colour.
pub fn cluster_order(a: &Cluster, b: &Cluster) -> std::cmp::Ordering {
    b.count.cmp(&a.count).then(a.rgba.cmp(&b.rgba))
}

/// Greedy leader clustering fed one colour at a time, most frequent first
/// (see [`cluster_palette`]), so a job can spread it over slices.
pub struct Leaders {
    tol2: f64,
    clusters: Vec<Cluster>,
    /// Representatives by cube, from [`GRID_FROM`] colours on.
    grid: Option<Grid>,
}

impl Leaders {
    /// Clustering of `n` colours with a tolerance already checked
    /// ([`check_tolerance`]).
    pub fn new(tolerance: f64, n: usize) -> Leaders {
        Leaders {
            tol2: tolerance * tolerance,
            clusters: Vec::new(),
            grid: (n >= GRID_FROM).then(|| Grid::new(tolerance)),
        }
    }

    /// The next colour (in falling frequency) and its pixel count. Returns
    /// the representatives it was compared with (a work measure).
    pub fn add(&mut self, rgba: [u8; 4], count: u64) -> usize {
        let tol2 = self.tol2;
        let (found, work) = match &self.grid {
            None => {
                let k = self
                    .clusters
                    .iter()
                    .position(|c| rgb_dist2(c.rgba, rgba) <= tol2);
                (k, k.map_or(self.clusters.len(), |k| k + 1))
            }
            Some(g) => g.first_within(&self.clusters, rgba, tol2),
        };
        match found {
            Some(k) => {
                let c = &mut self.clusters[k];
                c.count += count;
                c.members += 1;
            }
            None => {
                if let Some(g) = &mut self.grid {
                    g.file(self.clusters.len(), rgba);
                }
                self.clusters.push(Cluster {
                    rgba,
                    count,
                    members: 1,
                });
            }
        }
        work
    }

    /// Clusters so far.
    pub fn len(&self) -> usize {
        self.clusters.len()
    }

    /// Whether no colour was added.
    pub fn is_empty(&self) -> bool {
        self.clusters.is_empty()
    }

    /// The clusters in the order they were made.
    pub fn into_clusters(self) -> Vec<Cluster> {
        self.clusters
    }
}

/// Cluster representatives filed by cube: `head[cube]` is the newest
/// representative in it (+1, 0 = none) and `next[k]` the one filed before k.
struct Grid {
    side: f64,
    /// The tolerance plus a hair, so round-off in `tolerance²` can never
    /// leave a representative the exact test accepts outside the searched cubes.
    reach: f64,
    /// Cubes per axis.
    n: usize,
    head: Vec<u32>,
    next: Vec<u32>,
}

impl Grid {
    fn new(tolerance: f64) -> Grid {
        // Side 2·tolerance: a ball of radius `tolerance` meets at most two
        // cubes per axis. At least 1, as RGB values are whole numbers.
        let side = (2.0 * tolerance).max(1.0);
        let n = (256.0 / side).ceil() as usize;
        Grid {
            side,
            reach: tolerance + 1e-6,
            n,
            head: vec![0; n * n * n],
            next: Vec::new(),
        }
    }

    fn cell(&self, v: f64) -> usize {
        ((v / self.side).floor().max(0.0) as usize).min(self.n - 1)
    }

    fn file(&mut self, k: usize, c: [u8; 4]) {
        let (x, y, z) = (
            self.cell(c[0] as f64),
            self.cell(c[1] as f64),
            self.cell(c[2] as f64),
        );
        let cube = (x * self.n + y) * self.n + z;
        debug_assert_eq!(self.next.len(), k);
        self.next.push(self.head[cube]);
        self.head[cube] = k as u32 + 1;
    }

    /// The smallest cluster index whose representative is within the
    /// tolerance of `c` (exactly the test of the plain scan), and how many
    /// representatives were looked at.
    fn first_within(&self, clusters: &[Cluster], c: [u8; 4], tol2: f64) -> (Option<usize>, usize) {
        let range = |v: u8| {
            let v = v as f64;
            (self.cell(v - self.reach), self.cell(v + self.reach))
        };
        let (rx, ry, rz) = (range(c[0]), range(c[1]), range(c[2]));
        let mut best: Option<usize> = None;
        let mut looked = 0;
        for x in rx.0..=rx.1 {
            for y in ry.0..=ry.1 {
                for z in rz.0..=rz.1 {
                    let mut k = self.head[(x * self.n + y) * self.n + z];
                    while k != 0 {
                        let i = k as usize - 1;
                        looked += 1;
                        if best.is_none_or(|b| i < b) && rgb_dist2(clusters[i].rgba, c) <= tol2 {
                            best = Some(i);
                        }
                        k = self.next[i];
                    }
                }
            }
        }
        (best, looked)
    }
}

fn rgb_dist2(a: [u8; 4], b: [u8; 4]) -> f64 {
    (0..3).map(|i| (a[i] as f64 - b[i] as f64).powi(2)).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_counts_and_orders() {
        let mut img = Rgba8Image::new(3, 2);
        img.put(0, 0, [255, 0, 0, 255]);
        img.put(1, 0, [255, 0, 0, 255]);
        img.put(2, 0, [0, 0, 255, 255]);
        // (0,1),(1,1),(2,1) stay transparent and are skipped.
        let p = exact_palette(&img, 0);
        assert_eq!(
            p,
            vec![
                PaletteEntry {
                    rgba: [255, 0, 0, 255],
                    count: 2
                },
                PaletteEntry {
                    rgba: [0, 0, 255, 255],
                    count: 1
                },
            ]
        );
    }

    #[test]
    fn clustering_merges_near_colours_only() {
        let exact = vec![
            PaletteEntry {
                rgba: [200, 10, 10, 255],
                count: 50,
            },
            PaletteEntry {
                rgba: [0, 0, 250, 255],
                count: 30,
            },
            PaletteEntry {
                rgba: [205, 12, 8, 255],
                count: 5,
            },
            PaletteEntry {
                rgba: [3, 2, 255, 255],
                count: 2,
            },
        ];
        let c = cluster_palette(&exact, 10.0).unwrap();
        assert_eq!(c.len(), 2);
        assert_eq!(
            c[0],
            Cluster {
                rgba: [200, 10, 10, 255],
                count: 55,
                members: 2
            }
        );
        assert_eq!(
            c[1],
            Cluster {
                rgba: [0, 0, 250, 255],
                count: 32,
                members: 2
            }
        );
        assert_eq!(cluster_palette(&exact, 0.0).unwrap().len(), 4);
    }

    /// The plain definition: first representative in creation order.
    fn plain(exact: &[PaletteEntry], tol: f64) -> Vec<Cluster> {
        let tol2 = tol * tol;
        let mut clusters: Vec<Cluster> = Vec::new();
        for e in exact {
            match clusters
                .iter_mut()
                .find(|c| rgb_dist2(c.rgba, e.rgba) <= tol2)
            {
                Some(c) => {
                    c.count += e.count;
                    c.members += 1;
                }
                None => clusters.push(Cluster {
                    rgba: e.rgba,
                    count: e.count,
                    members: 1,
                }),
            }
        }
        clusters.sort_by(|a, b| b.count.cmp(&a.count).then(a.rgba.cmp(&b.rgba)));
        clusters
    }

    #[test]
    fn grid_clustering_equals_the_plain_scan() {
        // Above GRID_FROM colours the grid is used; it must give exactly the
        // clusters of the O(colours × clusters) definition, for tolerances
        // from "alpha-only merges" to "everything is one cluster".
        let mut rng = crate::core::rng::Rng::new(5);
        for (k, tol) in [0.0, 0.5, 1.0, 1.5, 3.0, 7.3, 24.0, 60.0, 200.0, 442.0]
            .into_iter()
            .enumerate()
        {
            let n = GRID_FROM + 1500 + 300 * k;
            // Clumped colours (like anti-aliasing round a few inks) plus noise,
            // some sharing RGB with a different alpha.
            let mut img = Rgba8Image::new(n as u32, 1);
            for x in 0..n as u32 {
                let base = [
                    (rng.below(4) * 80) as u8,
                    (rng.below(3) * 120) as u8,
                    40,
                    255,
                ];
                let j = |v: u8, r: &mut crate::core::rng::Rng| v.saturating_add(r.below(30) as u8);
                let a = if rng.below(10) == 0 { 128 } else { 255 };
                let c = [
                    j(base[0], &mut rng),
                    j(base[1], &mut rng),
                    j(base[2], &mut rng),
                    a,
                ];
                img.put(x, 0, c);
            }
            let exact = exact_palette(&img, 0);
            assert!(exact.len() >= GRID_FROM, "{} colours", exact.len());
            let got = cluster_palette(&exact, tol).unwrap();
            assert_eq!(got, plain(&exact, tol), "tolerance {tol}");
            let counts = colour_counts(&img, 0);
            assert_eq!(
                cluster_counts(&counts, tol).unwrap(),
                got,
                "tolerance {tol}"
            );
        }
    }

    #[test]
    fn tolerance_must_be_a_finite_distance() {
        let exact = vec![PaletteEntry {
            rgba: [1, 2, 3, 255],
            count: 1,
        }];
        for bad in [f64::NAN, f64::INFINITY, -1.0, -0.001, 442.5, 1e300] {
            let e = cluster_palette(&exact, bad).unwrap_err().to_string();
            assert!(e.contains("tolerance") && e.contains("0 to 442"), "{e}");
        }
        for ok in [0.0, 24.0, 442.0] {
            assert_eq!(cluster_palette(&exact, ok).unwrap().len(), 1);
        }
    }

    #[test]
    fn colour_counts_match_a_hash_count_on_big_images() {
        // Big enough for the radix sort path.
        let (w, h) = (300u32, 300u32);
        let mut img = Rgba8Image::new(w, h);
        let mut rng = crate::core::rng::Rng::new(1);
        let mut want: std::collections::HashMap<[u8; 4], u64> = Default::default();
        for y in 0..h {
            for x in 0..w {
                let c = [
                    rng.below(256) as u8,
                    rng.below(4) as u8,
                    (x % 7) as u8,
                    [0, 10, 255][rng.below(3)],
                ];
                img.put(x, y, c);
                if c[3] > 10 {
                    *want.entry(c).or_default() += 1;
                }
            }
        }
        let mut want: Vec<PaletteEntry> = want
            .into_iter()
            .map(|(rgba, count)| PaletteEntry { rgba, count })
            .collect();
        want.sort_by(|a, b| b.count.cmp(&a.count).then(a.rgba.cmp(&b.rgba)));
        assert_eq!(exact_palette(&img, 10), want);
    }

    #[test]
    fn counter_counts_and_stops_at_the_limit() {
        let mut img = Rgba8Image::new(50, 40);
        for y in 0..40 {
            for x in 0..50 {
                img.put(
                    x,
                    y,
                    [
                        (x / 5) as u8,
                        (y / 4) as u8,
                        0,
                        if x == 0 { 0 } else { 255 },
                    ],
                );
            }
        }
        let want = exact_palette(&img, 0).len();
        assert_eq!(want, 100);
        assert_eq!(count_colours(&img, 0, 1000), Some(want));
        assert_eq!(count_colours(&img, 0, 100), Some(100));
        assert_eq!(count_colours(&img, 0, 99), None);
        let mut c = ColourCounter::new();
        let mut steps = 0;
        while !c.run(&img, 0, 7, usize::MAX) {
            steps += 1;
        }
        assert!(steps > 100);
        assert_eq!(c.count(), want);
    }
}
