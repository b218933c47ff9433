//! Rotation-invariant uniform local binary patterns (Ojala, Pietikäinen &
//! Mäenpää, "Multiresolution gray-scale and rotation invariant texture
//! classification with local binary patterns", TPAMI 2002), beside PCN-2
//! for issue 36: textures made by other programs come under other lights,
//! tone curves and rotations, and these histograms do not change with any
//! monotonic grey-level change and little with a rotation, where PCN-2's
//! learnt filters are oriented.
//!
//! Each pixel compares `P` neighbours on a circle of radius `R`
//! (bilinear) with itself; the pattern's code is its number of brighter
//! neighbours when the circle has at most two 0/1 transitions
//! ("uniform"), else `P + 1`: `P + 2` codes, the same for every rotation
//! of the pattern. The operators (8, 1), (16, 2) and (24, 3) are counted
//! at [`LBP_OPERATORS`], on the image and on each halving of it (box
//! averages, [`lbp_histograms`]'s `scales`), each histogram normalised and
//! square-rooted like PCN-2's.
use super::Gray;

/// The (neighbours, radius) operators at every scale.
pub const LBP_OPERATORS: [(usize, f32); 3] = [(8, 1.0), (16, 2.0), (24, 3.0)];

/// A neighbour counts as brighter when it exceeds the centre by this much
/// (an 8-bit grey level's half step): without it, noise on a flat area
/// would draw random codes.
const THRESHOLD: f32 = 0.5 / 255.0;

/// Histogram bins at one scale.
pub fn bins_per_scale() -> usize {
    LBP_OPERATORS.iter().map(|&(p, _)| p + 2).sum()
}

/// The histograms of `img` at `scales` scales (the image, then halved
/// `scales − 1` times while at least 16 pixels a side remain; missing
/// scales give zero histograms), `scales · bins_per_scale()` values.
pub fn lbp_histograms(img: &Gray, scales: usize) -> Vec<f32> {
    let mut out = Vec::with_capacity(scales * bins_per_scale());
    let mut level = img.clone();
    for s in 0..scales {
        if s > 0 {
            level = halve(&level);
        }
        for &(p, r) in &LBP_OPERATORS {
            out.extend(histogram(&level, p, r));
        }
    }
    out
}

fn halve(g: &Gray) -> Gray {
    let (w, h) = (g.width / 2, g.height / 2);
    let mut out = Gray::new(w, h);
    for y in 0..h {
        for x in 0..w {
            out.data[y * w + x] = 0.25
                * (g.at(2 * x, 2 * y)
                    + g.at(2 * x + 1, 2 * y)
                    + g.at(2 * x, 2 * y + 1)
                    + g.at(2 * x + 1, 2 * y + 1));
        }
    }
    out
}

/// The square-rooted, normalised riu2 histogram of operator (`p`, `r`)
/// over the pixels whose circle lies inside the image (zeros when none).
fn histogram(g: &Gray, p: usize, r: f32) -> Vec<f32> {
    let mut hist = vec![0u32; p + 2];
    let margin = r.ceil() as usize + 1;
    let (w, h) = (g.width, g.height);
    if w <= 2 * margin || h <= 2 * margin {
        return vec![0.0; p + 2];
    }
    // Neighbour offsets, counter-clockwise from +x (y down).
    let offsets: Vec<(f32, f32)> = (0..p)
        .map(|i| {
            let a = std::f64::consts::TAU * i as f64 / p as f64;
            let (dx, dy) = (r as f64 * libm::cos(a), -(r as f64) * libm::sin(a));
            // Snap values within 1e-6 of an integer (axis neighbours) so
            // their lookups are exact.
            let snap = |v: f64| {
                if (v - libm::round(v)).abs() < 1e-6 {
                    libm::round(v)
                } else {
                    v
                }
            };
            (snap(dx) as f32, snap(dy) as f32)
        })
        .collect();
    let mut bits = vec![false; p];
    for y in margin..h - margin {
        for x in margin..w - margin {
            let c = g.at(x, y);
            for (b, &(dx, dy)) in bits.iter_mut().zip(&offsets) {
                let (sx, sy) = (x as f32 + dx, y as f32 + dy);
                let (x0, y0) = (sx.floor(), sy.floor());
                let (fx, fy) = (sx - x0, sy - y0);
                let (xi, yi) = (x0 as usize, y0 as usize);
                let v = if fx == 0.0 && fy == 0.0 {
                    g.at(xi, yi)
                } else {
                    let top = g.at(xi, yi) * (1.0 - fx) + g.at(xi + 1, yi) * fx;
                    let bottom = g.at(xi, yi + 1) * (1.0 - fx) + g.at(xi + 1, yi + 1) * fx;
                    top * (1.0 - fy) + bottom * fy
                };
                *b = v - c > THRESHOLD;
            }
            let transitions = (0..p).filter(|&i| bits[i] != bits[(i + 1) % p]).count();
            let code = if transitions <= 2 {
                bits.iter().filter(|&&b| b).count()
            } else {
                p + 1
            };
            hist[code] += 1;
        }
    }
    let n = ((w - 2 * margin) * (h - 2 * margin)) as f32;
    hist.iter().map(|&k| (k as f32 / n).sqrt()).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spots(side: usize, gamma: f32, transpose: bool) -> Gray {
        let mut g = Gray::new(side, side);
        for y in 0..side {
            for x in 0..side {
                let (u, v) = if transpose { (y, x) } else { (x, y) };
                let s =
                    ((u as f32 * 0.45).sin() * (v as f32 * 0.3).cos() * 0.5 + 0.5).clamp(0.0, 1.0);
                g.data[y * side + x] = s.powf(gamma);
            }
        }
        g
    }

    #[test]
    fn histograms_are_unit_and_blind_to_a_tone_curve() {
        let a = lbp_histograms(&spots(64, 1.0, false), 2);
        assert_eq!(a.len(), 2 * bins_per_scale());
        let mut at = 0;
        for &(p, _) in LBP_OPERATORS.iter().chain(&LBP_OPERATORS) {
            let sum: f32 = a[at..at + p + 2].iter().map(|v| v * v).sum();
            assert!((sum - 1.0).abs() < 1e-4, "{sum}");
            at += p + 2;
        }
        // A gamma keeps the order of the pixels; only the bilinear
        // neighbours and the threshold move codes, so the histograms move
        // far less than for another texture.
        let l1 = |p: &[f32], q: &[f32]| p.iter().zip(q).map(|(x, y)| (x - y).abs()).sum::<f32>();
        let toned = l1(&a, &lbp_histograms(&spots(64, 1.6, false), 2));
        let mut other = Gray::new(64, 64);
        for (i, v) in other.data.iter_mut().enumerate() {
            *v = ((i * 7919) % 257) as f32 / 256.0;
        }
        let different = l1(&a, &lbp_histograms(&other, 2));
        assert!(toned * 3.0 < different, "{toned} vs {different}");
    }

    #[test]
    fn a_quarter_turn_leaves_the_histograms_alone() {
        // Transposing and flipping is a quarter turn for the circle's
        // samples at the axes; riu2 codes count bits, so they are equal
        // up to the diagonal neighbours' interpolation.
        let a = lbp_histograms(&spots(64, 1.0, false), 1);
        let t = spots(64, 1.0, true);
        let d: f32 = a
            .iter()
            .zip(&lbp_histograms(&t, 1))
            .map(|(x, y)| (x - y).abs())
            .sum();
        assert!(d < 0.1, "{d}");
    }

    #[test]
    fn a_flat_or_tiny_image_gives_finite_histograms() {
        let flat = Gray {
            width: 32,
            height: 32,
            data: vec![0.5; 32 * 32],
        };
        let h = lbp_histograms(&flat, 3);
        assert!(h.iter().all(|v| v.is_finite()));
        // Every pattern on a flat image is "no neighbour brighter".
        assert_eq!(h[0], 1.0);
        let tiny = Gray::new(4, 4);
        assert!(lbp_histograms(&tiny, 2).iter().all(|&v| v == 0.0));
    }
}
