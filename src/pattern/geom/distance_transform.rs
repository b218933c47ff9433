//! Exact Euclidean distance transform of a raster mask (Felzenszwalb &
//! Huttenlocher, "Distance Transforms of Sampled Functions", 2012): the
//! lower envelope of parabolas along columns, then rows, in O(w·h).
//!
//! Distances are measured between pixel centres. [`signed_distance`] puts
//! the boundary half a pixel beyond the last inside pixel, so a pixel's
//! value is `d_out − ½` outside and `−(d_in − ½)` inside, which matches an
//! analytic signed field sampled at pixel centres.
//!
//! Both transforms also come in bounded parts ([`Edt`], [`SignedDistance`]:
//! a few columns or rows a call), for a job that must not spend more than a
//! few milliseconds in one slice; the parts give the one-go results bit for
//! bit.

/// "No feature pixel": the squared distance [`edt_squared`] reports then.
pub const INF: f64 = 1e20;

/// Squared Euclidean distance from every pixel to the nearest pixel where
/// `feature` (row-major, `w × h`) is true ([`INF`] when there is none).
/// Exact, O(w·h).
///
/// # Panics
/// When `feature.len() != w * h` (a caller's bug, not an input error).
pub fn edt_squared(feature: &[bool], w: usize, h: usize) -> Vec<f64> {
    let mut e = Edt::new(feature, w, h);
    while !e.step(usize::MAX) {}
    e.into_squared()
}

/// Columns transformed together (one 64-byte cache line of `f64`).
const COLUMN_GROUP: usize = 8;

/// [`edt_squared`] in parts: the column pass, then the row pass, a few
/// lines per [`Edt::step`].
#[derive(Debug, Clone)]
pub struct Edt {
    g: Vec<f64>,
    w: usize,
    h: usize,
    /// Columns done, then rows done.
    cols: usize,
    rows: usize,
    f: Vec<f64>,
    /// A group of columns and their transforms, column-major.
    cf: Vec<f64>,
    cd: Vec<f64>,
    d: Vec<f64>,
    v: Vec<usize>,
    z: Vec<f64>,
}

impl Edt {
    /// Start the transform of `feature` (row-major, `w × h`).
    ///
    /// # Panics
    /// When `feature.len() != w * h` (a caller's bug, not an input error).
    pub fn new(feature: &[bool], w: usize, h: usize) -> Edt {
        assert_eq!(Some(feature.len()), w.checked_mul(h), "mask size");
        let m = w.max(h);
        Edt {
            g: feature.iter().map(|&f| if f { 0.0 } else { INF }).collect(),
            w,
            h,
            cols: 0,
            rows: 0,
            f: vec![0.0; m],
            cf: vec![0.0; COLUMN_GROUP * h],
            cd: vec![0.0; COLUMN_GROUP * h],
            d: vec![0.0; m],
            v: vec![0usize; m],
            z: vec![0.0; m + 1],
        }
    }

    /// Whether both passes are complete.
    pub fn done(&self) -> bool {
        self.cols >= self.w && self.rows >= self.h
    }

    /// Transform whole columns (a group of up to 8 at a time, a column pixel
    /// counting twice) and then rows until about `budget` pixels are done
    /// (one line or group at least); returns whether the transform is complete.
    pub fn step(&mut self, budget: usize) -> bool {
        let (w, h) = (self.w, self.h);
        let mut spent = 0usize;
        while self.cols < w {
            // A few neighbouring columns at once: reading and writing them
            // row by row touches each cache line once, not once per column.
            let x0 = self.cols;
            let k = (w - x0).min(COLUMN_GROUP);
            for y in 0..h {
                for j in 0..k {
                    self.cf[j * h + y] = self.g[y * w + x0 + j];
                }
            }
            for j in 0..k {
                let col = j * h..(j + 1) * h;
                dt1(
                    &self.cf[col.clone()],
                    &mut self.d[..h],
                    &mut self.v,
                    &mut self.z,
                );
                self.cd[col].copy_from_slice(&self.d[..h]);
            }
            for y in 0..h {
                for j in 0..k {
                    self.g[y * w + x0 + j] = self.cd[j * h + y];
                }
            }
            self.cols += k;
            // Columns cost more than rows (strided memory).
            spent = spent.saturating_add(2 * k * h.max(1));
            if spent >= budget {
                return self.done();
            }
        }
        while self.rows < h {
            let y = self.rows;
            self.f[..w].copy_from_slice(&self.g[y * w..(y + 1) * w]);
            dt1(&self.f[..w], &mut self.d[..w], &mut self.v, &mut self.z);
            self.g[y * w..(y + 1) * w].copy_from_slice(&self.d[..w]);
            self.rows += 1;
            spent = spent.saturating_add(w.max(1));
            if spent >= budget {
                return self.done();
            }
        }
        true
    }

    /// The squared distances (call once [`Edt::step`] returned `true`).
    pub fn into_squared(self) -> Vec<f64> {
        debug_assert!(self.done(), "transform not finished");
        self.g
    }
}

/// 1-D squared distance transform: lower envelope of parabolas.
fn dt1(f: &[f64], d: &mut [f64], v: &mut [usize], z: &mut [f64]) {
    let n = f.len();
    if n == 0 {
        return;
    }
    // Only finite samples carry parabolas; with none, everything stays INF.
    let mut k: isize = -1;
    for q in 0..n {
        if f[q] >= INF {
            continue;
        }
        if k < 0 {
            k = 0;
            v[0] = q;
            z[0] = f64::NEG_INFINITY;
            z[1] = f64::INFINITY;
            continue;
        }
        loop {
            let p = v[k as usize];
            let s =
                ((f[q] + (q * q) as f64) - (f[p] + (p * p) as f64)) / (2.0 * (q as f64 - p as f64));
            if s <= z[k as usize] {
                k -= 1;
                if k < 0 {
                    break;
                }
            } else {
                k += 1;
                v[k as usize] = q;
                z[k as usize] = s;
                z[k as usize + 1] = f64::INFINITY;
                break;
            }
        }
        if k < 0 {
            k = 0;
            v[0] = q;
            z[0] = f64::NEG_INFINITY;
            z[1] = f64::INFINITY;
        }
    }
    if k < 0 {
        d.iter_mut().for_each(|x| *x = INF);
        return;
    }
    let mut j = 0usize;
    for (q, dq) in d.iter_mut().enumerate() {
        while z[j + 1] < q as f64 {
            j += 1;
        }
        let p = v[j];
        *dq = (q as f64 - p as f64).powi(2) + f[p];
    }
}

/// Signed distance (in pixels) of a mask, negative inside, `±big` where
/// the mask is full or empty.
pub fn signed_distance(mask: &[bool], w: usize, h: usize, big: f64) -> Vec<f64> {
    let mut s = SignedDistance::new(mask.to_vec(), w, h, big);
    loop {
        if let Some(d) = s.step(usize::MAX) {
            return d;
        }
    }
}

/// [`signed_distance`] in parts: the transform of the mask, then of its
/// complement (each [`Edt`] in parts), then the signed values.
#[derive(Debug, Clone)]
pub struct SignedDistance {
    mask: Vec<bool>,
    w: usize,
    h: usize,
    big: f64,
    to_in: Edt,
    /// Started once `to_in` is complete.
    to_out: Option<Edt>,
}

impl SignedDistance {
    /// Start the signed distance of `mask` (row-major, `w × h`).
    ///
    /// # Panics
    /// When `mask.len() != w * h` (a caller's bug, not an input error).
    pub fn new(mask: Vec<bool>, w: usize, h: usize, big: f64) -> SignedDistance {
        let to_in = Edt::new(&mask, w, h);
        SignedDistance {
            mask,
            w,
            h,
            big,
            to_in,
            to_out: None,
        }
    }

    /// Go on for about `budget` pixels of work (one line at least); the
    /// field once it is complete, as [`signed_distance`] gives it. Must not
    /// be called again after it returned the field.
    pub fn step(&mut self, budget: usize) -> Option<Vec<f64>> {
        if !self.to_in.done() {
            self.to_in.step(budget);
            return None;
        }
        let out = match &mut self.to_out {
            Some(e) => e,
            None => {
                let outside: Vec<bool> = self.mask.iter().map(|&m| !m).collect();
                self.to_out.insert(Edt::new(&outside, self.w, self.h))
            }
        };
        if !out.done() {
            out.step(budget);
            return None;
        }
        let big = self.big;
        let to_in = &self.to_in.g;
        let to_out = &out.g;
        Some(
            self.mask
                .iter()
                .enumerate()
                .map(|(i, &m)| {
                    if m {
                        -(to_out[i].sqrt() - 0.5).min(big)
                    } else {
                        (to_in[i].sqrt() - 0.5).min(big)
                    }
                })
                .collect(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::core::rng::Rng;
    use proptest::prelude::*;

    #[test]
    fn edt_equals_brute_force_on_random_masks() {
        let mut r = Rng::new(3);
        for case in 0..40 {
            let (w, h) = (1 + r.below(23), 1 + r.below(17));
            let density = [0.02, 0.1, 0.5, 0.9][case % 4];
            let m: Vec<bool> = (0..w * h).map(|_| r.f64() < density).collect();
            let got = edt_squared(&m, w, h);
            for y in 0..h {
                for x in 0..w {
                    let mut best = INF;
                    for yy in 0..h {
                        for xx in 0..w {
                            if m[yy * w + xx] {
                                let d =
                                    (x as f64 - xx as f64).powi(2) + (y as f64 - yy as f64).powi(2);
                                best = best.min(d);
                            }
                        }
                    }
                    assert_eq!(got[y * w + x], best, "case {case} {w}x{h} at ({x},{y})");
                }
            }
        }
    }

    #[test]
    fn signed_distance_of_a_disc_is_close_to_analytic() {
        let n = 64;
        let m: Vec<bool> = (0..n * n)
            .map(|i| {
                let (x, y) = ((i % n) as f64 + 0.5, (i / n) as f64 + 0.5);
                ((x - 32.0).powi(2) + (y - 32.0).powi(2)).sqrt() < 12.0
            })
            .collect();
        let s = signed_distance(&m, n, n, 1e9);
        for (i, v) in s.iter().enumerate() {
            let (x, y) = ((i % n) as f64 + 0.5, (i / n) as f64 + 0.5);
            let exact = ((x - 32.0).powi(2) + (y - 32.0).powi(2)).sqrt() - 12.0;
            assert!((v - exact).abs() < 1.0, "pixel {i}: {v} vs {exact}");
        }
    }

    /// The transforms done a few lines at a time give the one-go results
    /// bit for bit (including empty and full masks and 1-pixel sides).
    #[test]
    fn stepping_gives_the_same_bits() {
        let mut r = Rng::new(11);
        for case in 0..24 {
            let (w, h) = (1 + r.below(40), 1 + r.below(30));
            let density = [0.0, 0.03, 0.4, 1.0][case % 4];
            let m: Vec<bool> = (0..w * h).map(|_| r.f64() < density).collect();
            let want = edt_squared(&m, w, h);
            let want_signed = signed_distance(&m, w, h, 50.0);
            for budget in [0, 1, w.min(h), 3 * w + 1] {
                let mut e = Edt::new(&m, w, h);
                while !e.step(budget) {}
                let got = e.into_squared();
                assert!(got
                    .iter()
                    .zip(&want)
                    .all(|(a, b)| a.to_bits() == b.to_bits()));
                let mut s = SignedDistance::new(m.clone(), w, h, 50.0);
                let mut steps = 0;
                let got = loop {
                    steps += 1;
                    if let Some(d) = s.step(budget) {
                        break d;
                    }
                };
                if budget <= 1 {
                    let groups = w.div_ceil(COLUMN_GROUP);
                    assert_eq!(
                        steps,
                        2 * (groups + h) + 1,
                        "a column group or a row a step"
                    );
                }
                assert!(got
                    .iter()
                    .zip(&want_signed)
                    .all(|(a, b)| a.to_bits() == b.to_bits()));
            }
        }
    }

    fn brute(m: &[bool], w: usize, h: usize) -> Vec<f64> {
        let mut out = vec![INF; w * h];
        for y in 0..h {
            for x in 0..w {
                for yy in 0..h {
                    for xx in 0..w {
                        if m[yy * w + xx] {
                            let d = (x as f64 - xx as f64).powi(2) + (y as f64 - yy as f64).powi(2);
                            out[y * w + x] = out[y * w + x].min(d);
                        }
                    }
                }
            }
        }
        out
    }

    /// A random mask: any size up to 24², any density.
    fn mask() -> impl Strategy<Value = (usize, usize, Vec<bool>)> {
        (1usize..=24, 1usize..=24, 0.0f64..=1.0).prop_flat_map(|(w, h, p)| {
            (
                Just(w),
                Just(h),
                proptest::collection::vec(proptest::bool::weighted(p), w * h),
            )
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(1000))]
        /// The transform equals brute force exactly on random masks of any
        /// shape and density (empty and full masks included), and the
        /// signed field is consistent with it.
        #[test]
        fn edt_equals_brute_force_property((w, h, m) in mask()) {
            let got = edt_squared(&m, w, h);
            prop_assert_eq!(&got, &brute(&m, w, h));
            // Signed: negative exactly inside, at least half a pixel from 0.
            let s = signed_distance(&m, w, h, 1e9);
            for i in 0..w * h {
                prop_assert!(m[i] == (s[i] < 0.0) && s[i].abs() >= 0.5, "{} at {}", s[i], i);
            }
        }
    }
}
