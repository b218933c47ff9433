//! Section 3.1: element positions (random and packed strategies, margins,
//! density, partial placement).
//!
//! A position is the top-left corner of an element's square cell. It is valid
//! when the cell lies inside the image, none of its pixels is occupied, and it
//! lies within the original mask (every pixel, or — with `partial` — at least
//! one). Choosing a position occupies its cell grown by `mx` pixels left and
//! right and `my` pixels top and bottom (negative margins shrink it, letting
//! neighbours overlap). Density is drawn *after* validation: a rejected
//! position still occupies its region, exactly as the paper describes.
use crate::core::error::{Error, Result};
use crate::core::limits;
use crate::core::rng::Rng;
use crate::raster::Limits;
use serde::{Deserialize, Serialize};
use std::collections::VecDeque;

/// Candidates drawn ahead in one batch (density 1 only).
const DRAW_AHEAD: usize = 64;

/// How subsequent positions are chosen after the first (random) one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum PositionStrategy {
    /// Every position is drawn at random among the remaining candidates:
    /// irregular, natural patterns (bark, fur).
    #[default]
    Random,
    /// The eight neighbouring element positions of each accepted one are tried
    /// next (a queue); only when it runs dry is a random candidate drawn:
    /// regular patterns (scales, bricks).
    Packed,
}

/// Parameters of [`PositionSampler`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PositionParams {
    pub strategy: PositionStrategy,
    /// `(mx, my)`; each must satisfy `side + 2·m ≥ 1` so an accepted element
    /// always occupies at least one of its own pixels.
    pub margins: [i32; 2],
    /// Probability in `0..=1` that a valid position is kept.
    pub density: f64,
    /// Accept cells with at least one pixel in the mask instead of all.
    pub partial: bool,
}

/// The position search as a resumable object: [`PositionSampler::run`] does a
/// bounded amount of work, so a huge mask never blocks a browser worker.
pub struct PositionSampler {
    w: i32,
    h: i32,
    side: i32,
    p: PositionParams,
    /// Summed-area table of the original mask, `(w+1)·(h+1)`, while the
    /// candidates are being listed (dropped afterwards).
    sat: Vec<u32>,
    /// Rows of the table, then rows of candidates, done so far (the set-up
    /// is sliced like the search, so a 4096² mask never blocks a step).
    sat_rows: i32,
    cand_rows: i32,
    /// Per top-left corner: the cell is inside the image and passes the mask
    /// test (what `in_mask` asks, precomputed).
    valid: Vec<bool>,
    occupied: Vec<bool>,
    /// Top-left corners (`y·w + x`) valid against the original mask and
    /// still untried, in row-major order until the draws shuffle them.
    candidates: Vec<u32>,
    initial: usize,
    /// Candidates already drawn, not yet tried (see [`DRAW_AHEAD`]).
    ahead: VecDeque<u32>,
    queue: VecDeque<(i32, i32)>,
    rng: Rng,
    positions: Vec<(i32, i32)>,
}

impl PositionSampler {
    /// Prepare the search over a `width`×`height` mask for square elements of
    /// `side` pixels.
    pub fn new(
        width: u32,
        height: u32,
        mask: &[bool],
        side: u32,
        p: PositionParams,
        seed: u64,
    ) -> Result<Self> {
        Limits::default().check(width, height)?;
        if side == 0 || side > limits::MAX_ELEMENT_SIDE {
            return Err(Error::limit(format!(
                "the element side {side} is outside 1..={} (the element side limit)",
                limits::MAX_ELEMENT_SIDE
            )));
        }
        if mask.len() as u64 != width as u64 * height as u64 {
            return Err(Error::input(format!(
                "the mask has {} values but the image is {width}×{height}",
                mask.len()
            )));
        }
        let (w, h, s) = (width as i32, height as i32, side as i32);
        for (i, &m) in p.margins.iter().enumerate() {
            if m.unsigned_abs() > limits::MAX_MARGIN as u32 {
                return Err(Error::limit(format!(
                    "margin {} = {m} is beyond the margin limit of ±{} pixels",
                    ["mx", "my"][i],
                    limits::MAX_MARGIN
                )));
            }
            if s as i64 + 2 * (m as i64) < 1 {
                return Err(Error::input(format!(
                    "margin {} = {m} is too negative for {side}-pixel elements: it must be at least {} \
                     so every element still occupies a pixel",
                    ["mx", "my"][i],
                    -((s - 1) / 2)
                )));
            }
        }
        if !(0.0..=1.0).contains(&p.density) {
            return Err(Error::input(format!(
                "density {} is outside 0..=1 (0% to 100%)",
                p.density
            )));
        }
        let n = (w * h) as usize;
        Ok(PositionSampler {
            w,
            h,
            side: s,
            p,
            sat: vec![0u32; (w + 1) as usize * (h + 1) as usize],
            sat_rows: 0,
            cand_rows: 0,
            valid: vec![false; n],
            occupied: vec![false; n],
            candidates: Vec::new(),
            initial: 0,
            ahead: VecDeque::new(),
            queue: VecDeque::new(),
            rng: Rng::new(seed),
            positions: Vec::new(),
        })
    }

    /// Continue listing candidates: about `budget` pixels of work. Returns
    /// the work done; the listing is complete when `cand_rows` passes the
    /// last row a cell can start on.
    fn set_up(&mut self, mask: &[bool], budget: usize) -> usize {
        let (w, h) = (self.w as usize, self.h as usize);
        let stride = w + 1;
        let mut spent = 0;
        while (self.sat_rows as usize) < h && spent < budget {
            let y = self.sat_rows as usize;
            let mut row = 0u32;
            for x in 0..w {
                row += mask[y * w + x] as u32;
                self.sat[(y + 1) * stride + x + 1] = self.sat[y * stride + x + 1] + row;
            }
            self.sat_rows += 1;
            spent += w + 1;
        }
        // Candidates are every corner whose cell passes the mask test on its
        // own: the paper's "random position within the original mask",
        // widened so that with `partial` a cell poking into the mask from
        // outside can be drawn too.
        let last = self.h - self.side;
        while self.sat_rows as usize == h && self.cand_rows <= last && spent < budget {
            let y = self.cand_rows;
            for x in 0..=(self.w - self.side) {
                if self.mask_test(x, y) {
                    let i = (y * self.w + x) as usize;
                    self.valid[i] = true;
                    self.candidates.push(i as u32);
                }
            }
            self.cand_rows += 1;
            spent += w + 1;
        }
        if self.listed() {
            self.sat = Vec::new();
            self.initial = self.candidates.len();
        }
        spent.max(1)
    }

    fn listed(&self) -> bool {
        self.sat_rows == self.h && self.cand_rows > self.h - self.side
    }

    fn mask_count(&self, x: i32, y: i32) -> u32 {
        let stride = (self.w + 1) as usize;
        let (x0, y0, x1, y1) = (
            x as usize,
            y as usize,
            (x + self.side) as usize,
            (y + self.side) as usize,
        );
        self.sat[y1 * stride + x1] + self.sat[y0 * stride + x0]
            - self.sat[y0 * stride + x1]
            - self.sat[y1 * stride + x0]
    }

    /// The mask test of a cell inside the image (needs the summed-area table).
    fn mask_test(&self, x: i32, y: i32) -> bool {
        let n = self.mask_count(x, y);
        if self.p.partial {
            n > 0
        } else {
            n == (self.side * self.side) as u32
        }
    }

    /// Whether the cell at (x, y) is inside the image and passes the mask test.
    fn in_mask(&self, x: i32, y: i32) -> bool {
        if x < 0 || y < 0 || x + self.side > self.w || y + self.side > self.h {
            return false;
        }
        self.valid[(y * self.w + x) as usize]
    }

    fn free(&self, x: i32, y: i32) -> bool {
        (y..y + self.side).all(|yy| {
            let row = (yy * self.w) as usize;
            !self.occupied[row + x as usize..row + (x + self.side) as usize]
                .iter()
                .any(|&o| o)
        })
    }

    /// Test one position; on success keep it (with probability ρ), occupy its
    /// region and, when packing, queue its eight neighbours.
    fn try_position(&mut self, x: i32, y: i32) {
        if !self.in_mask(x, y) {
            return;
        }
        self.try_valid(x, y);
    }

    /// [`PositionSampler::try_position`] for a corner known to pass the mask
    /// test (every drawn candidate does).
    fn try_valid(&mut self, x: i32, y: i32) {
        if !self.free(x, y) {
            return;
        }
        if self.p.density >= 1.0 || self.rng.f64() < self.p.density {
            self.positions.push((x, y));
        }
        let [mx, my] = self.p.margins;
        let (x0, x1) = ((x - mx).max(0), (x + self.side + mx).min(self.w));
        let (y0, y1) = ((y - my).max(0), (y + self.side + my).min(self.h));
        for yy in y0..y1 {
            let row = (yy * self.w) as usize;
            self.occupied[row + x0 as usize..row + x1 as usize].fill(true);
        }
        if self.p.strategy == PositionStrategy::Packed {
            // Neighbours sit one element plus one margin away, so a packed
            // pattern is a regular grid with gaps of exactly (mx, my).
            let (px, py) = (self.side + mx, self.side + my);
            for (dx, dy) in [
                (-1, -1),
                (0, -1),
                (1, -1),
                (-1, 0),
                (1, 0),
                (-1, 1),
                (0, 1),
                (1, 1),
            ] {
                self.queue.push_back((x + dx * px, y + dy * py));
            }
        }
    }

    /// Work until about `budget` pixel tests have been made or the search is
    /// over. Returns `true` when no suitable position is left. `mask` is the
    /// one given to [`PositionSampler::new`] (read while listing candidates).
    pub fn run(&mut self, mask: &[bool], budget: usize) -> bool {
        let mut spent = 0usize;
        if !self.listed() {
            spent += self.set_up(mask, budget);
            if !self.listed() {
                return false;
            }
        }
        let cost = (self.side * self.side) as usize + 1;
        while spent < budget {
            spent += cost;
            if let Some((x, y)) = self.queue.pop_front() {
                self.try_position(x, y);
                continue;
            }
            if self.ahead.is_empty() && self.p.density >= 1.0 {
                self.draw_ahead();
            }
            if let Some(c) = self.ahead.pop_front() {
                let c = c as i32;
                self.try_valid(c % self.w, c / self.w);
            } else if !self.candidates.is_empty() {
                let i = self.rng.below(self.candidates.len());
                let c = self.candidates.swap_remove(i) as i32;
                self.try_valid(c % self.w, c / self.w);
            } else {
                return true;
            }
        }
        self.queue.is_empty() && self.candidates.is_empty() && self.ahead.is_empty()
    }

    /// Draw the next [`DRAW_AHEAD`] candidates at once. With density 1 the
    /// draws use the random stream alone (nothing else draws from it and
    /// every draw removes one candidate whatever its outcome), so drawing
    /// early gives exactly the same sequence; doing it in a batch lets the
    /// memory reads of many random candidates overlap instead of waiting
    /// for each in turn.
    fn draw_ahead(&mut self) {
        let mut touch = false;
        for _ in 0..DRAW_AHEAD.min(self.candidates.len()) {
            let i = self.rng.below(self.candidates.len());
            let c = self.candidates.swap_remove(i);
            // Read the cell's first occupancy byte now, so the test later
            // finds it in cache.
            touch ^= self.occupied[c as usize];
            self.ahead.push_back(c);
        }
        std::hint::black_box(touch);
    }

    /// Rough fraction of the search done, for progress reports.
    pub fn fraction(&self) -> f64 {
        if !self.listed() {
            return 0.05 * (self.sat_rows + self.cand_rows.max(0)) as f64 / (2 * self.h) as f64;
        }
        let left = self.candidates.len() + self.ahead.len();
        0.05 + 0.95 * (1.0 - left as f64 / self.initial.max(1) as f64)
    }

    /// The positions chosen so far (top-left corners), in the order chosen.
    pub fn positions(&self) -> &[(i32, i32)] {
        &self.positions
    }

    /// Finish and hand over the positions.
    pub fn into_positions(self) -> Vec<(i32, i32)> {
        self.positions
    }
}

/// Run the whole search at once.
pub fn find_positions(
    width: u32,
    height: u32,
    mask: &[bool],
    side: u32,
    p: PositionParams,
    seed: u64,
) -> Result<Vec<(i32, i32)>> {
    let mut s = PositionSampler::new(width, height, mask, side, p, seed)?;
    while !s.run(mask, usize::MAX / 2) {}
    Ok(s.into_positions())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(strategy: PositionStrategy) -> PositionParams {
        PositionParams {
            strategy,
            margins: [0, 0],
            density: 1.0,
            partial: false,
        }
    }

    /// Lattice points (pitch `p`) through `first` whose cells fit in a `w`×`h` image.
    fn lattice_count(first: (i32, i32), p: i32, side: i32, w: i32, h: i32) -> usize {
        let fits = |o: i32, n: i32| {
            (0..=n - side)
                .filter(|v| (v - o).rem_euclid(p) == 0)
                .count()
        };
        fits(first.0, w) * fits(first.1, h)
    }

    #[test]
    fn packed_fills_the_lattice_of_the_first_position() {
        // On a full 40×40 mask the leftover strips beside the lattice are
        // narrower than an element, so every position must lie on the regular
        // grid through the random first one, and all of that grid must be used.
        let mask = vec![true; 40 * 40];
        for seed in 0..10 {
            let pos =
                find_positions(40, 40, &mask, 4, params(PositionStrategy::Packed), seed).unwrap();
            let first = pos[0];
            for p in &pos {
                assert_eq!(
                    ((p.0 - first.0).rem_euclid(4), (p.1 - first.1).rem_euclid(4)),
                    (0, 0),
                    "seed {seed}: {p:?}"
                );
            }
            assert_eq!(pos.len(), lattice_count(first, 4, 4, 40, 40), "seed {seed}");
        }
    }

    #[test]
    fn margins_space_packed_elements() {
        let mask = vec![true; 40 * 40];
        let p = PositionParams {
            margins: [2, 1],
            ..params(PositionStrategy::Packed)
        };
        let pos = find_positions(40, 40, &mask, 4, p, 3).unwrap();
        for (i, a) in pos.iter().enumerate() {
            for b in &pos[i + 1..] {
                let gap_x = (a.0 - b.0).abs() - 4;
                let gap_y = (a.1 - b.1).abs() - 4;
                assert!(gap_x >= 2 || gap_y >= 1, "{a:?} {b:?}");
            }
        }
    }

    #[test]
    fn negative_margins_allow_overlap_but_not_duplicates() {
        let mask = vec![true; 30 * 30];
        let p = PositionParams {
            margins: [-1, -1],
            ..params(PositionStrategy::Random)
        };
        let pos = find_positions(30, 30, &mask, 4, p, 9).unwrap();
        let overlapping = pos.iter().enumerate().any(|(i, a)| {
            pos[i + 1..]
                .iter()
                .any(|b| (a.0 - b.0).abs() < 4 && (a.1 - b.1).abs() < 4)
        });
        assert!(overlapping, "margins (-1,-1) should let some cells overlap");
        for (i, a) in pos.iter().enumerate() {
            for b in &pos[i + 1..] {
                // Occupied regions are the inner 2×2 of each cell: they never overlap.
                assert!(
                    (a.0 - b.0).abs() >= 2 || (a.1 - b.1).abs() >= 2,
                    "{a:?} {b:?}"
                );
            }
        }
        let too_neg = PositionParams {
            margins: [-2, 0],
            ..p
        };
        let e = PositionSampler::new(30, 30, &mask, 4, too_neg, 0)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("mx = -2") && e.contains("at least -1"), "{e}");
    }

    #[test]
    fn density_thins_but_keeps_occupancy() {
        let mask = vec![true; 64 * 64];
        let full = find_positions(64, 64, &mask, 4, params(PositionStrategy::Packed), 1).unwrap();
        let half = PositionParams {
            density: 0.5,
            ..params(PositionStrategy::Packed)
        };
        let some = find_positions(64, 64, &mask, 4, half, 1).unwrap();
        // Same seed: the same first position, and rejected positions still
        // occupy their cells, so the kept ones are a subset of the full run's
        // lattice (about half of it).
        assert!(full.len() >= 225, "{}", full.len());
        let n = full.len() as f64;
        assert!(
            (some.len() as f64 - n / 2.0).abs() < 4.0 * (n / 4.0).sqrt(),
            "{} of {n}",
            some.len()
        );
        let first = full[0];
        assert!(some
            .iter()
            .all(|p| (p.0 - first.0) % 4 == 0 && (p.1 - first.1) % 4 == 0));
    }

    #[test]
    fn partial_accepts_cells_touching_the_mask() {
        // One mask pixel: only partial placement can use it, and only cells covering it.
        let mut mask = vec![false; 10 * 10];
        mask[5 * 10 + 5] = true;
        assert!(
            find_positions(10, 10, &mask, 3, params(PositionStrategy::Random), 0)
                .unwrap()
                .is_empty()
        );
        let p = PositionParams {
            partial: true,
            ..params(PositionStrategy::Random)
        };
        let pos = find_positions(10, 10, &mask, 3, p, 0).unwrap();
        assert_eq!(pos.len(), 1);
        let (x, y) = pos[0];
        assert!((3..=5).contains(&x) && (3..=5).contains(&y), "{pos:?}");
    }

    #[test]
    fn same_seed_same_positions() {
        let mask: Vec<bool> = (0..50 * 40)
            .map(|i| (i % 50) > 3 && (i / 50) < 35)
            .collect();
        let p = PositionParams {
            density: 0.7,
            ..params(PositionStrategy::Random)
        };
        let a = find_positions(50, 40, &mask, 5, p, 42).unwrap();
        assert_eq!(a, find_positions(50, 40, &mask, 5, p, 42).unwrap());
        assert_ne!(a, find_positions(50, 40, &mask, 5, p, 43).unwrap());
    }

    #[test]
    fn huge_margins_are_refused_not_wrapped() {
        // 2147483647 once wrapped `side + 2·m` to a small number and placed
        // elements everywhere; now it is a named limit error, both signs.
        let mask = vec![true; 20 * 20];
        for m in [
            i32::MAX,
            i32::MIN,
            limits::MAX_MARGIN + 1,
            -(limits::MAX_MARGIN + 1),
        ] {
            for margins in [[m, 0], [0, m]] {
                let p = PositionParams {
                    margins,
                    ..params(PositionStrategy::Packed)
                };
                let e = PositionSampler::new(20, 20, &mask, 4, p, 0)
                    .err()
                    .expect("refused")
                    .to_string();
                assert!(e.contains("margin limit of ±4096"), "{m}: {e}");
            }
        }
        // The largest allowed margin works: one element, nothing else fits.
        let p = PositionParams {
            margins: [limits::MAX_MARGIN, limits::MAX_MARGIN],
            ..params(PositionStrategy::Packed)
        };
        assert_eq!(find_positions(20, 20, &mask, 4, p, 0).unwrap().len(), 1);
    }

    #[test]
    fn mask_size_and_density_are_checked() {
        let e = PositionSampler::new(5, 5, &[true; 24], 2, params(PositionStrategy::Random), 0)
            .err()
            .unwrap()
            .to_string();
        assert!(e.contains("24 values") && e.contains("5×5"), "{e}");
        let p = PositionParams {
            density: f64::NAN,
            ..params(PositionStrategy::Random)
        };
        assert!(PositionSampler::new(5, 5, &[true; 25], 2, p, 0).is_err());
    }
}
