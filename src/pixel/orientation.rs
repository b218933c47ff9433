//! Section 3.3 (annotations): brush strokes drawn on a view upscaled by K
//! become one vector per annotated source pixel; the Laplace solve in
//! [`super::laplace`] fills in the rest.
//!
//! A stroke is a polyline in source-pixel coordinates (floats; (0, 0) is the
//! top-left corner of the top-left pixel). Its points are scaled by K and the
//! segments rasterised (Bresenham) on the K× grid; each pixel on that path
//! gets the unit vector to the next pixel of the path (the last pixel repeats
//! the previous vector). Downscaling averages, per source pixel, the vectors
//! of all path pixels inside its K×K block. Unit steps are used so diagonal
//! steps (length √2 on the grid) do not outweigh straight ones.
use crate::core::error::{Error, Result};

/// A stroke: points `[x, y]` in source-pixel coordinates.
pub type Stroke = Vec<[f32; 2]>;

pub use crate::core::limits::{MAX_ANNOTATION_PATH, MAX_ANNOTATION_SCALE, MAX_STROKE_POINTS};

/// Annotated pixels and their averaged vectors.
#[derive(Debug, Clone, PartialEq)]
pub struct Annotations {
    pub width: u32,
    pub height: u32,
    /// `true` where at least one stroke pixel landed.
    pub fixed: Vec<bool>,
    /// Averaged vector where `fixed`, zero elsewhere.
    pub values: Vec<[f64; 2]>,
}

impl Annotations {
    /// Number of annotated pixels.
    pub fn count(&self) -> usize {
        self.fixed.iter().filter(|&&f| f).count()
    }
}

/// Check strokes against the image: finite points within one pixel of it.
pub fn check_strokes(width: u32, height: u32, strokes: &[Stroke]) -> Result<()> {
    let total: usize = strokes.iter().map(Vec::len).sum();
    if total > MAX_STROKE_POINTS {
        return Err(Error::limit(format!(
            "the strokes have {total} points in all; the stroke point limit is {MAX_STROKE_POINTS}"
        )));
    }
    let (w, h) = (width as f32, height as f32);
    for (s, stroke) in strokes.iter().enumerate() {
        for (k, p) in stroke.iter().enumerate() {
            let ok = p[0].is_finite()
                && p[1].is_finite()
                && p[0] >= -1.0
                && p[1] >= -1.0
                && p[0] <= w + 1.0
                && p[1] <= h + 1.0;
            if !ok {
                return Err(Error::input(format!(
                    "stroke {} point {} ({}, {}) is outside the {width}×{height} image \
                     (points are in source pixels, from -1 to size + 1)",
                    s + 1,
                    k + 1,
                    p[0],
                    p[1]
                )));
            }
        }
    }
    Ok(())
}

/// Annotated pixels only: `(row-major index, averaged vector)`, by index.
pub type SparseAnnotations = Vec<(u32, [f64; 2])>;

/// Rasterise strokes at scale `k` and average down to source pixels.
pub fn annotate(width: u32, height: u32, strokes: &[Stroke], k: u32) -> Result<Annotations> {
    let sparse = annotate_sparse(width, height, strokes, k)?;
    let n = width as usize * height as usize;
    let mut fixed = vec![false; n];
    let mut values = vec![[0.0, 0.0]; n];
    for (i, v) in sparse {
        fixed[i as usize] = true;
        values[i as usize] = v;
    }
    Ok(Annotations {
        width,
        height,
        fixed,
        values,
    })
}

/// The rasterised path length of `strokes` at scale `k`, in K× grid pixels
/// (computed from the points alone, before anything is rasterised).
pub fn path_length(strokes: &[Stroke], k: u32) -> u64 {
    let kf = k as f64;
    let g = |p: &[f32; 2]| {
        (
            (p[0] as f64 * kf).floor() as i64,
            (p[1] as f64 * kf).floor() as i64,
        )
    };
    strokes
        .iter()
        .map(|s| {
            1 + s
                .windows(2)
                .map(|w| {
                    let (a, b) = (g(&w[0]), g(&w[1]));
                    (a.0 - b.0).unsigned_abs().max((a.1 - b.1).unsigned_abs())
                })
                .sum::<u64>()
        })
        .sum()
}

/// [`annotate`] without the dense arrays: memory and work grow with the
/// strokes' length, not with the image. Vectors are summed per pixel in path
/// order, exactly as the dense version does, so the averages are the same bits.
pub fn annotate_sparse(
    width: u32,
    height: u32,
    strokes: &[Stroke],
    k: u32,
) -> Result<SparseAnnotations> {
    if k == 0 || k > MAX_ANNOTATION_SCALE {
        return Err(Error::limit(format!(
            "annotation scale {k} is outside 1..={MAX_ANNOTATION_SCALE} (the annotation scale limit)"
        )));
    }
    check_strokes(width, height, strokes)?;
    let len = path_length(strokes, k);
    if len > MAX_ANNOTATION_PATH {
        return Err(Error::limit(format!(
            "the strokes are {len} pixels long on the {k}× annotation grid; \
             the stroke length limit is {MAX_ANNOTATION_PATH} (draw fewer or shorter strokes, \
             or lower the annotation scale)"
        )));
    }
    let (w, h) = (width as usize, height as usize);
    // Per annotated pixel: running sum and count, in first-visit order.
    let mut slot: std::collections::HashMap<u32, usize> = std::collections::HashMap::new();
    let mut acc: Vec<(u32, [f64; 2], u32)> = Vec::new();
    let mut path: Vec<(i64, i64)> = Vec::new();
    for stroke in strokes {
        path.clear();
        let kf = k as f64;
        let pts: Vec<(i64, i64)> = stroke
            .iter()
            .map(|p| {
                (
                    (p[0] as f64 * kf).floor() as i64,
                    (p[1] as f64 * kf).floor() as i64,
                )
            })
            .collect();
        for (i, &p) in pts.iter().enumerate() {
            if i == 0 {
                path.push(p);
            } else {
                bresenham(pts[i - 1], p, &mut path);
            }
        }
        path.dedup();
        if path.len() < 2 {
            // A dot has no direction.
            continue;
        }
        for i in 0..path.len() {
            let (a, b) = if i + 1 < path.len() {
                (path[i], path[i + 1])
            } else {
                (path[i - 1], path[i])
            };
            let (dx, dy) = ((b.0 - a.0) as f64, (b.1 - a.1) as f64);
            let len = (dx * dx + dy * dy).sqrt();
            let (sx, sy) = (
                path[i].0.div_euclid(k as i64),
                path[i].1.div_euclid(k as i64),
            );
            if sx < 0 || sy < 0 || sx >= w as i64 || sy >= h as i64 {
                continue;
            }
            let j = (sy as usize * w + sx as usize) as u32;
            let e = *slot.entry(j).or_insert_with(|| {
                acc.push((j, [0.0, 0.0], 0));
                acc.len() - 1
            });
            let a = &mut acc[e];
            a.1[0] += dx / len;
            a.1[1] += dy / len;
            a.2 += 1;
        }
    }
    let mut out: SparseAnnotations = acc
        .into_iter()
        .map(|(j, s, c)| (j, [s[0] / c as f64, s[1] / c as f64]))
        .collect();
    out.sort_unstable_by_key(|e| e.0);
    Ok(out)
}

/// Append the 8-connected line from `a` (exclusive) to `b` (inclusive).
fn bresenham(a: (i64, i64), b: (i64, i64), out: &mut Vec<(i64, i64)>) {
    let (mut x, mut y) = a;
    let (dx, dy) = ((b.0 - a.0).abs(), -(b.1 - a.1).abs());
    let (sx, sy) = ((b.0 - a.0).signum(), (b.1 - a.1).signum());
    let mut err = dx + dy;
    while (x, y) != b {
        let e2 = 2 * err;
        if e2 >= dy {
            err += dy;
            x += sx;
        }
        if e2 <= dx {
            err += dx;
            y += sy;
        }
        out.push((x, y));
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn horizontal_stroke_annotates_its_row_pointing_right() {
        let a = annotate(10, 5, &[vec![[1.2, 2.5], [7.9, 2.5]]], 4).unwrap();
        for x in 0..10 {
            let i = 2 * 10 + x;
            assert_eq!(a.fixed[i], (1..=7).contains(&x), "x={x}");
            if a.fixed[i] {
                assert_eq!(a.values[i], [1.0, 0.0]);
            }
        }
        assert_eq!(a.count(), 7);
    }

    #[test]
    fn reversed_stroke_reverses_vectors_and_diagonals_are_unit() {
        let a = annotate(8, 8, &[vec![[7.5, 7.5], [0.5, 0.5]]], 3).unwrap();
        let r = std::f64::consts::FRAC_1_SQRT_2;
        for i in 0..8 {
            let v = a.values[i * 8 + i];
            assert!(a.fixed[i * 8 + i]);
            assert!(
                (v[0] + r).abs() < 1e-12 && (v[1] + r).abs() < 1e-12,
                "{v:?}"
            );
        }
    }

    #[test]
    fn crossing_strokes_average() {
        // One stroke right, one down, crossing pixel (2, 2).
        let a = annotate(
            5,
            5,
            &[vec![[0.5, 2.5], [4.5, 2.5]], vec![[2.5, 0.5], [2.5, 4.5]]],
            1,
        )
        .unwrap();
        let v = a.values[2 * 5 + 2];
        assert!(
            (v[0] - 0.5).abs() < 1e-12 && (v[1] - 0.5).abs() < 1e-12,
            "{v:?}"
        );
    }

    #[test]
    fn bad_strokes_are_named() {
        let e = annotate(
            10,
            10,
            &[vec![[1.0, 1.0]], vec![[0.0, 0.0], [50.0, 3.0]]],
            4,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("stroke 2 point 2") && e.contains("10×10"), "{e}");
        let e = annotate(10, 10, &[], 0).unwrap_err().to_string();
        assert!(e.contains("annotation scale 0"), "{e}");
        // A single point or a stroke inside one upscaled pixel annotates nothing.
        assert_eq!(
            annotate(10, 10, &[vec![[3.0, 3.0]], vec![[3.1, 3.1], [3.2, 3.2]]], 4)
                .unwrap()
                .count(),
            0
        );
    }

    #[test]
    fn overlong_strokes_are_refused_before_rasterising() {
        // 200 back-and-forth segments across a 4096-pixel image at K = 32:
        // about 26 million grid pixels, far past the limit.
        let stroke: Stroke = (0..200)
            .map(|i| [if i % 2 == 0 { 0.0 } else { 4095.0 }, 10.0])
            .collect();
        let e = annotate_sparse(4096, 4096, &[stroke], 32)
            .unwrap_err()
            .to_string();
        assert!(e.contains("stroke length limit"), "{e}");
    }

    #[test]
    fn sparse_and_dense_agree() {
        let strokes = vec![
            vec![[0.5, 2.5], [9.5, 3.7], [2.0, 8.0]],
            vec![[2.5, 0.5], [2.5, 9.5]],
        ];
        let d = annotate(10, 10, &strokes, 3).unwrap();
        let s = annotate_sparse(10, 10, &strokes, 3).unwrap();
        assert_eq!(s.len(), d.count());
        for (i, v) in s {
            assert!(d.fixed[i as usize]);
            assert_eq!(d.values[i as usize], v);
        }
    }
}
