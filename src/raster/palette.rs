use super::Rgba8Image;
use serde::Serialize;
use std::collections::HashMap;

/// One exact colour of an image and how many pixels have it.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct PaletteEntry {
    pub rgba: [u8; 4],
    pub count: u64,
}

/// Every distinct colour of the opaque-enough pixels (alpha > `min_alpha`),
/// most frequent first; ties broken by colour so the order is deterministic.
pub fn exact_palette(img: &Rgba8Image, min_alpha: u8) -> Vec<PaletteEntry> {
    let mut counts: HashMap<[u8; 4], u64> = HashMap::new();
    for p in img.pixels().filter(|p| p[3] > min_alpha) {
        *counts.entry(p).or_insert(0) += 1;
    }
    let mut v: Vec<PaletteEntry> = counts
        .into_iter()
        .map(|(rgba, count)| PaletteEntry { rgba, count })
        .collect();
    v.sort_by(|a, b| b.count.cmp(&a.count).then(a.rgba.cmp(&b.rgba)));
    v
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

/// Group colours whose RGB distance (Euclidean, 0..441) to a cluster's
/// representative is at most `tolerance`. Greedy leader clustering over the
/// exact palette in frequency order: the most common colours become the
/// representatives, so anti-aliasing and JPEG noise fold into the colours a
/// person would name. Deterministic; O(colours × clusters).
pub fn cluster_palette(exact: &[PaletteEntry], tolerance: f64) -> Vec<Cluster> {
    let tol2 = tolerance * tolerance;
    let mut clusters: Vec<Cluster> = Vec::new();
    for e in exact {
        let near = clusters
            .iter_mut()
            .find(|c| rgb_dist2(c.rgba, e.rgba) <= tol2);
        match near {
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
        let c = cluster_palette(&exact, 10.0);
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
        assert_eq!(cluster_palette(&exact, 0.0).len(), 4);
    }
}
