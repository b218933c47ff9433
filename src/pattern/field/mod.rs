//! Per-colour pattern SDFs (paper §4 "Pattern Distance Fields" and the
//! "on top" operator, Fig. 6/7).
//!
//! For every colour `c` of the pattern the field starts as "nothing"
//! (`+cap`), or "everything" (`−cap`) for the background colour, and each
//! shape, in drawing order, is applied with the paper's operator
//!
//! ```text
//! OnTop(B, F, c) = union(B, union(S, F))   c = stroke,  c = fill
//!                  diff(B, union(S, F))    c ≠ stroke,  c ≠ fill
//!                  diff(union(B, S), F)    c = stroke,  c ≠ fill
//!                  union(diff(B, S), F)    c ≠ stroke,  c = fill
//! ```
//!
//! with `S` the stroke geometry `|d| − w/2` and `F` the fill geometry. As in
//! the paper's formulas (which need `S` and `F` disjoint) a stroked shape's
//! fill is its interior inset by half the stroke width, `d + w/2`, which is
//! exactly the part of the fill a renderer leaves visible under the stroke.
//! `union = min`, `diff(a, b) = max(a, −b)`; boolean shapes (`union`,
//! `intersect`, `difference` blocks) combine signed geometries with min/max.
//!
//! Every value is therefore ± one primitive's distance (plus a width term):
//! the evaluator remembers that "winner" per pixel and colour, which makes
//! the derivative of the field with respect to the primitive's fields (and
//! from there, by the tape, to the parameters) exact.
//!
//! Culling: the canvas is cut into 8×8-pixel tiles. All distances are
//! 1-Lipschitz, so a value at the tile centre bounds it over the tile to
//! ±(half diagonal). Consecutive operations of the same kind on a colour
//! form a run (`min` over its items commutes); items whose lower bound
//! exceeds the run's smallest upper bound, and runs that cannot change the
//! running interval, are dropped for that tile. Cost then follows the shapes
//! near each tile, not every shape for every pixel. The same interval
//! bounds a channel over a small tile: where it lies beyond the cap (along
//! the canvas border, where the cap is the distance to the edge) the
//! block is the cap, and no item is evaluated.
//!
//! Files: [`scene`] (compiling a recording into per-colour operation lists,
//! the geometry of compound shapes), [`tiles`] (the evaluator: two-level
//! tile culling, per-pixel evaluation), [`lanes`] (the 4-lane kernel for
//! chains of circles, points and segments), [`backward`] (from field
//! adjoints to tape nodes through each pixel's winner, kept as a 64-bit
//! code, [`win_code`]).

mod backward;
mod lanes;
mod scene;
mod tiles;

pub use scene::{prim_kinds, Channel, Scene};

use crate::pattern::record::Canvas;
pub use tiles::Evaluator;

/// "Farther than anything on the canvas", in canvas units.
pub(crate) const CAP: f64 = 2.0;

/// A loss or raster grid laid over a canvas: `w × h` pixels covering
/// `[0, canvas.w] × [0, canvas.h]`. Pixels are square when `w : h` is the
/// canvas's aspect, and nearly so otherwise (the shorter side is rounded);
/// on the square canvas an `n × n` grid is exactly the grid as it always was.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    pub w: usize,
    pub h: usize,
    pub canvas: Canvas,
}

impl Grid {
    /// `n × n` on the square canvas.
    pub fn square(n: usize) -> Grid {
        Grid {
            w: n,
            h: n,
            canvas: Canvas::SQUARE,
        }
    }

    /// The grid on `canvas` whose longer side has `n` pixels ([`Canvas::grid`]).
    pub fn on(canvas: Canvas, n: usize) -> Grid {
        let (w, h) = canvas.grid(n);
        Grid { w, h, canvas }
    }

    /// Pixels in the grid.
    pub fn len(&self) -> usize {
        self.w * self.h
    }

    /// Whether it has no pixels.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Pixels per canvas unit along x and y (`n` both on an `n × n` square).
    #[inline]
    pub fn ppu(&self) -> (f64, f64) {
        (self.w as f64 / self.canvas.w, self.h as f64 / self.canvas.h)
    }

    /// Pixels per canvas unit along the longer side: the unit of the
    /// "pixels" loss units (`n` on an `n × n` square).
    pub fn long_ppu(&self) -> f64 {
        if self.canvas.w >= self.canvas.h {
            self.w as f64 / self.canvas.w
        } else {
            self.h as f64 / self.canvas.h
        }
    }

    /// Centres of the pixel columns and rows in canvas units, `(i + ½)·cell`.
    pub fn centres(&self) -> (Vec<f64>, Vec<f64>) {
        let (px, py) = self.ppu();
        let (ix, iy) = (1.0 / px, 1.0 / py);
        (
            (0..self.w).map(|i| (i as f64 + 0.5) * ix).collect(),
            (0..self.h).map(|i| (i as f64 + 0.5) * iy).collect(),
        )
    }

    /// [`edge_cap`] of the columns and of the rows: `edge_cap(x, y) =
    /// min(cols[x], rows[y])`.
    pub(crate) fn edges(&self) -> (Vec<f64>, Vec<f64>) {
        let (px, py) = self.ppu();
        let axis = |n: usize, p: f64| -> Vec<f64> {
            (0..n)
                .map(|i| (i.min(n - 1 - i) as f64 + 0.5) / p)
                .collect()
        };
        (axis(self.w, px), axis(self.h, py))
    }
}

/// The largest field magnitude at pixel `(x, y)` of `grid`, in canvas
/// units: the distance from the pixel's centre to the canvas edge.
///
/// A target image shows only the canvas, so its distance transform cannot
/// see a shape (or a shape's outside) beyond the edge, while a pattern's
/// field can: a stripe running past the edge, or a dot just outside it,
/// changes the pattern's field near the edge but not the target's, and the
/// loss at the true parameters was far from zero for every tiled design.
/// Both sides therefore take the field's magnitude up to the distance to
/// the canvas edge and no further: with `d` the true signed distance, the
/// target's (in-canvas) distance transform is at least `|d|` and equals it
/// whenever the nearest boundary point is on the canvas, which it is when
/// `|d|` is below the distance to the edge, so `min(|d|, edge)` is the same
/// on both sides. (It is the field of a world in which the ring of pixels
/// just outside the canvas is both inside and outside every colour.) The
/// sign, and so every colour, is unchanged.
#[inline]
pub(crate) fn edge_cap(x: usize, y: usize, grid: &Grid) -> f64 {
    let (px, py) = grid.ppu();
    let ex = (x.min(grid.w - 1 - x) as f64 + 0.5) / px;
    let ey = (y.min(grid.h - 1 - y) as f64 + 0.5) / py;
    ex.min(ey)
}
pub(crate) const NONE: u32 = u32::MAX;
/// Big and small tile sides in pixels (two-level culling).
pub(crate) const T1: usize = 16;
pub(crate) const T2: usize = 4;

/// How an item changes a colour's field.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum CombineOp {
    /// `min(B, X)`
    Union,
    /// `max(B, −X)`
    Diff,
}

/// What decided a field value at one pixel: `S = psign·prim(p) + wcoef·width + const`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Win {
    /// Primitive index, or `u32::MAX` when no shape reached the pixel (value is the cap).
    pub prim: u32,
    /// Tape node of the stroke width involved.
    pub wnode: u32,
    pub psign: f32,
    pub wcoef: f32,
}

pub(crate) const NO_WIN: Win = Win {
    prim: NONE,
    wnode: 0,
    psign: 0.0,
    wcoef: 0.0,
};

/// A pixel's winner as the evaluator stores it: 64 bits, `prim << 32 |
/// item << 4 | (sign < 0) << 2 | below << 1 | flipped`, where `below` is
/// the primitive's distance not ≥ 0 (the side [`Scene::win_of`] reads for
/// strokes) and `flipped` a difference's negation; [`NO_CODE`] for none.
/// Neighbouring pixels mostly share a code, and the record ([`Win`]) is
/// made from it once per run ([`Scene::decode_win`]). Items are below
/// 2²⁸ (two per shape at most, and shapes are limited far below that).
#[inline(always)]
pub(crate) fn win_code(item: u32, h: &Hit, flipped: bool) -> u64 {
    debug_assert!(item < 1 << 28);
    (h.prim as u64) << 32
        | (item as u64) << 4
        | ((h.sign < 0.0) as u64) << 2
        | ((h.d < 0.0 || h.d.is_nan()) as u64) << 1
        | flipped as u64
}

/// No winner: the value is clamped (or nothing reached the pixel).
pub(crate) const NO_CODE: u64 = u64::MAX;

#[derive(Debug, Clone, Copy)]
pub(crate) struct Hit {
    pub(crate) d: f64,
    pub(crate) prim: u32,
    pub(crate) sign: f64,
}

/// `min` as a select, for hot loops whose `a` is never NaN: `b` only when
/// it is below `a` (a NaN `b` leaves `a`, as `f64::min` does). `f64::min`'s
/// NaN handling costs a dependent chain of five instructions.
#[inline(always)]
pub(super) fn lesser(a: f64, b: f64) -> f64 {
    if b < a {
        b
    } else {
        a
    }
}

/// `max` as a select, like [`lesser`].
#[inline(always)]
pub(super) fn greater(a: f64, b: f64) -> f64 {
    if b > a {
        b
    } else {
        a
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::record::{Program, RecordLimits};
    use crate::pattern::sdf;

    fn scene(src: &str) -> Scene {
        let p = Program::parse(src).unwrap();
        Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap())
    }

    fn fields(sc: &Scene, n: usize) -> Evaluator {
        let mut e = Evaluator::new(n, 1.0);
        let mut nodes = vec![];
        sc.rec.tape.forward(&sc.rec.float_values(), &mut nodes);
        e.eval(sc, &nodes, true);
        e
    }

    fn at(e: &Evaluator, sc: &Scene, colour: [u8; 3], x: f64, y: f64) -> f64 {
        let c = sc
            .channels
            .iter()
            .position(|ch| sc.rec.colours[ch.colour as usize] == colour)
            .expect("channel");
        let n = e.grid.w;
        let (i, j) = ((x * n as f64) as usize, (y * n as f64) as usize);
        e.s[c * n * n + j * n + i]
    }

    /// The paper's four cases on a hand-built scene: a red square (blue
    /// stroke) drawn over a wide blue disc, over a red disc.
    #[test]
    fn on_top_operator_four_cases() {
        let sc = scene(
            "circle(0.5, 0.5, 0.45, fill: \"#ff0000\");\n\
             circle(0.5, 0.5, 0.35, fill: \"#0000ff\");\n\
             rect(0.5, 0.5, 0.4, 0.4, fill: \"#ff0000\", stroke: \"#0000ff\", width: 0.04);\n\
             circle(0.5, 0.5, 0.05, fill: \"#00ff00\", stroke: \"#00ff00\", width: 0.02);",
        );
        let e = fields(&sc, 200);
        let (red, blue, green) = ([255, 0, 0], [0, 0, 255], [0, 255, 0]);
        // Case c = fill ≠ stroke (red): the rect's inset fill adds red inside ...
        assert!(at(&e, &sc, red, 0.35, 0.5) < 0.0);
        // ... case c = stroke ≠ fill (blue): its stroke ring is blue ...
        assert!(at(&e, &sc, blue, 0.3, 0.5) < 0.0);
        assert!(at(&e, &sc, red, 0.3, 0.5) > 0.0);
        // ... and the stroke removes blue from the inside (fill is not blue).
        assert!(at(&e, &sc, blue, 0.4, 0.5) > 0.0);
        // Case c ≠ stroke, c ≠ fill: the green dot removes red and blue.
        assert!(at(&e, &sc, red, 0.5, 0.5) > 0.0 && at(&e, &sc, blue, 0.5, 0.5) > 0.0);
        // Case c = stroke = fill: the green dot (with its stroke) is green out to r + w/2.
        // At the pixel centre (0.5025, 0.5025): union(S, F) = F = d + w/2.
        let g = at(&e, &sc, green, 0.5, 0.5);
        let d = 0.0025 * 2f64.sqrt() - 0.05;
        assert!((g - (d + 0.01)).abs() < 1e-9, "{g}");
        assert!(at(&e, &sc, green, 0.5, 0.555) < 0.0 && at(&e, &sc, green, 0.5, 0.565) > 0.0);
        // Outside the square but inside the blue disc: blue; red disc ring outside: red.
        assert!(at(&e, &sc, blue, 0.5, 0.18) < 0.0);
        assert!(at(&e, &sc, red, 0.5, 0.1) < 0.0);
        assert!(at(&e, &sc, blue, 0.5, 0.1) > 0.0);
    }

    /// A shape in the background colour: the background becomes a channel
    /// that starts full and is cut by other shapes, then restored.
    #[test]
    fn background_colour_as_a_channel() {
        let sc = scene(
            "background \"#ffffff\";\ncircle(0.5, 0.5, 0.3, fill: \"#000000\");\ncircle(0.5, 0.5, 0.1, fill: \"#ffffff\");",
        );
        assert_eq!(sc.channels.len(), 2);
        let bg = sc.channels.iter().find(|c| c.colour == 0).unwrap();
        assert_eq!(bg.init, -1.0);
        let e = fields(&sc, 100);
        let (white, black) = ([255, 255, 255], [0, 0, 0]);
        assert!(at(&e, &sc, white, 0.05, 0.05) < 0.0); // canvas corner
        assert!(at(&e, &sc, white, 0.5, 0.5) < 0.0); // the white dot
        assert!(at(&e, &sc, white, 0.5, 0.3) > 0.0 && at(&e, &sc, black, 0.5, 0.3) < 0.0); // the black ring
        assert!(at(&e, &sc, black, 0.5, 0.5) > 0.0);
        let idx = e.colour_indices(&sc);
        assert_eq!(idx[50 * 100 + 50], 0);
        assert_eq!(idx[30 * 100 + 50], 1);
    }

    /// Culling never changes a value: compare with a brute-force evaluation
    /// that applies every operation at every pixel.
    #[test]
    fn culled_fields_equal_brute_force() {
        // Plain filled circles in two colours drawn over each other: the
        // 4-lane circle kernel, with unions and differences.
        check_brute_force(
            "for i in 0..7 { for j in 0..7 { circle(0.05 + i * 0.15, 0.07 + j * 0.14, 0.06, fill: \"#aa0000\"); } }\n\
             for k in 0..9 { circle(0.1 + k * 0.1, 0.5 + 0.3 * sin(k), 0.08, fill: \"#0000aa\"); }",
            61,
        );
        check_brute_force(SCENE, 61);
        // Filled and stroked circles over each other (fill inset, stroke, both cases).
        check_brute_force(
            "for j in 0..5 { for i in 0..6 { circle(0.05 + i * 0.19 + (j % 2) * 0.09, 0.05 + j * 0.2, 0.11, fill: \"#5dade2\", stroke: \"#1b4f72\", width: 0.015); } }\n\
             point(0.5, 0.5, stroke: \"#5dade2\", width: 0.05);",
            61,
        );
    }

    /// Blocks where a channel is beyond its cap all over (along the
    /// canvas border, where the cap is the distance to the edge) are
    /// written without evaluating items: on both sides of zero, through
    /// the lane kernel (circles) and the per-pixel path (a rectangle), the
    /// values still equal brute force.
    #[test]
    fn blocks_beyond_the_cap_equal_brute_force() {
        check_brute_force_with(
            "circle(0.5, 0.5, 0.9, fill: \"#aa0000\");\n\
             circle(0.5, 0.5, 0.05, fill: \"#0000aa\");\n\
             rect(0.3, 0.3, 0.1, 0.2, fill: \"#00aa00\");\n\
             difference(fill: \"#aaaa00\") { rect(0, 0, 1, 1); circle(0.5, 0.5, 0.3); }",
            64,
            false,
        );
    }

    const SCENE: &str = "for i in 0..6 { for j in 0..6 { circle(0.1 + i * 0.16, 0.1 + j * 0.16, 0.05, fill: \"#112233\"); } }\n\
             for k in 0..5 { segment(0, k * 0.2 + 0.05, 1, k * 0.2 + 0.1, stroke: \"#aa0000\", width: 0.02); }\n\
             path(fill: \"#00aa00\", stroke: \"#112233\", width: 0.01) { move(0.2, 0.2); quad(0.5, 0.0, 0.8, 0.2); line(0.5, 0.8); close(); }\n\
             difference(fill: \"#ffffff\") { rect(0.7, 0.7, 0.2, 0.2, radius: 0.03, rotation: 0.3); circle(0.7, 0.7, 0.05); }";

    fn check_brute_force(src: &str, n: usize) {
        check_brute_force_with(src, n, true);
    }

    fn check_brute_force_with(src: &str, n: usize, expect_savings: bool) {
        let sc = scene(src);
        let e = fields(&sc, n);
        let mut nodes = vec![];
        sc.rec.tape.forward(&sc.rec.float_values(), &mut nodes);
        let mut g = Evaluator::new(n, 1.0);
        g.gather(&sc, &nodes);
        for (c, ch) in sc.channels.iter().enumerate() {
            for y in 0..n {
                for x in 0..n {
                    let p = [(x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64];
                    let mut b = ch.init * CAP;
                    for &(op, it) in &ch.ops {
                        let v = sc
                            .item(&sc.items[it as usize], &g.prim_vals, &g.widths, p)
                            .0;
                        b = match op {
                            CombineOp::Union => b.min(v),
                            CombineOp::Diff => b.max(-v),
                        };
                    }
                    let cap = CAP.min(edge_cap(x, y, &Grid::square(n)));
                    let want = b.clamp(-cap, cap);
                    let got = e.s[c * n * n + y * n + x];
                    // The winner record explains the value exactly.
                    let w = e.winner(&sc, c * n * n + y * n + x);
                    if w.prim != NONE {
                        let prim = &sc.rec.prims[w.prim as usize];
                        let pv = sdf::value(prim.kind, &g.prim_vals[w.prim as usize], p);
                        let implied =
                            w.psign as f64 * pv + w.wcoef as f64 * nodes[w.wnode as usize].max(0.0);
                        assert!(
                            (implied - got).abs() < 1e-9,
                            "winner at ({x},{y}) implies {implied}, value {got}"
                        );
                    } else {
                        assert_eq!(got.abs(), cap);
                    }
                    assert!(
                        (got - want).abs() < 1e-12,
                        "channel {c} pixel ({x},{y}): {got} vs {want}"
                    );
                }
            }
        }
        assert!(
            !expect_savings
                || (e.work as f64)
                    < (sc.items.len() * n * n * sc.channels.len()) as f64 * sc.cost / 2.0,
            "culling saved little: {}",
            e.work
        );
    }

    /// An evaluation spread over tile ranges of any size (as a job spreads
    /// it over slices) gives the same fields, winners and work as one
    /// `eval` call, also when the evaluator is reused between evaluations.
    #[test]
    fn evaluating_in_tile_ranges_gives_the_same_bits_as_one_go() {
        let sc = scene(SCENE);
        let mut nodes = vec![];
        sc.rec.tape.forward(&sc.rec.float_values(), &mut nodes);
        for n in [37, 64, 100] {
            let mut one = Evaluator::new(n, 3.0);
            one.eval(&sc, &nodes, true);
            let mut parts = Evaluator::new(n, 3.0);
            for chunk in [1, 2, 5, 1000] {
                parts.begin(&sc, &nodes, true);
                let tiles = parts.tiles();
                assert_eq!(tiles, n.div_ceil(T1).pow(2));
                let mut t = 0;
                while t < tiles {
                    parts.eval_tiles(&sc, true, t..(t + chunk).min(tiles));
                    t += chunk;
                }
                parts.finish(&sc);
                assert_eq!(parts.work, one.work, "n {n} chunk {chunk}");
                assert!(
                    parts
                        .s
                        .iter()
                        .zip(&one.s)
                        .all(|(a, b)| a.to_bits() == b.to_bits()),
                    "n {n} chunk {chunk}: fields differ"
                );
                assert_eq!(parts.win, one.win, "n {n} chunk {chunk}");
            }
        }
    }

    /// An evaluation is a function of its point alone: an evaluator reused
    /// over a sequence of points gives at each the bits of a fresh one.
    /// (Its memo of the items a big tile uses once kept marks from the
    /// evaluation before, so an item could be left out of a tile: a sharded
    /// fit, whose shards evaluate different points first, then ended
    /// elsewhere than one fit. Found by the browser's diagonal-stripes fit.)
    #[test]
    fn a_reused_evaluator_gives_the_bits_of_a_fresh_one() {
        let src = "background \"#0d3b66\";\n\
             param angle in [-1.2, -0.4] = -0.62;\n\
             param spacing in [0.09, 0.2] = 0.115;\n\
             param width in [0.03, 0.08] = 0.04;\n\
             let c = cos(angle); let s = sin(angle);\n\
             for k in 0..20 { let d = (k - 10) * spacing;\n\
               segment(0.5 - s * d - c, 0.5 + c * d - s, 0.5 - s * d + c, 0.5 + c * d + s, stroke: \"#f4d35e\", width: width); }\n\
             for i in 0..4 { circle(0.2 + i * 0.2, 0.5, width * 2, fill: \"#aa0000\"); }";
        let sc = scene(src);
        let mut rng = crate::core::rng::Rng::new(7);
        let mut reused = Evaluator::new(96, 1.0);
        let mut nodes = vec![];
        for point in 0..40 {
            let values = [
                -1.2 + 0.8 * rng.f64(),
                0.09 + 0.11 * rng.f64(),
                0.03 + 0.05 * rng.f64(),
            ];
            sc.rec.tape.forward(&values, &mut nodes);
            reused.eval(&sc, &nodes, point % 2 == 0);
            let mut fresh = Evaluator::new(96, 1.0);
            fresh.eval(&sc, &nodes, point % 2 == 0);
            assert!(
                reused
                    .s
                    .iter()
                    .zip(&fresh.s)
                    .all(|(a, b)| a.to_bits() == b.to_bits()),
                "point {point} {values:?}: the fields depend on the evaluation before"
            );
            assert_eq!(reused.work, fresh.work, "point {point}");
        }
    }

    use proptest::prelude::*;

    /// A number in `[lo, hi)` written with 3 decimals.
    fn num(lo: f64, hi: f64) -> BoxedStrategy<String> {
        (lo..hi).prop_map(|v| format!("{v:.3}")).boxed()
    }

    /// One random shape statement of any kind the evaluator handles
    /// differently: circles, points, segments (4-lane kernel), rectangles,
    /// paths with lines and quadratics (open and closed), booleans, each
    /// filled and/or stroked in one of three colours.
    fn shape() -> impl Strategy<Value = String> {
        let colour = prop_oneof![Just("#aa0000"), Just("#00aa00"), Just("#0000aa")];
        let style = (colour.clone(), colour, 0..3usize, num(0.002, 0.05))
            .prop_map(|(f, s, which, w)| match which {
                0 => format!("fill: \"{f}\""),
                1 => format!("stroke: \"{s}\", width: {w}"),
                _ => format!("fill: \"{f}\", stroke: \"{s}\", width: {w}"),
            })
            .boxed();
        let p = || num(-0.1, 1.1);
        let circle = (p(), p(), num(0.0, 0.3))
            .prop_map(|(x, y, r)| format!("circle({x}, {y}, {r}"))
            .boxed();
        let rect = (
            p(),
            p(),
            num(0.01, 0.5),
            num(0.01, 0.5),
            num(0.0, 0.1),
            num(-3.2, 3.2),
        )
            .prop_map(|(x, y, w, h, r, a)| {
                format!("rect({x}, {y}, {w}, {h}, radius: {r}, rotation: {a}")
            })
            .boxed();
        let closed = prop_oneof![circle, rect].boxed();
        let styled_closed =
            (closed.clone(), style.clone()).prop_map(|(c, s)| format!("{c}, {s});"));
        let stroke = (
            prop_oneof![Just("#aa0000"), Just("#0000aa")],
            num(0.002, 0.05),
        )
            .prop_map(|(c, w)| format!("stroke: \"{c}\", width: {w}"))
            .boxed();
        let open = prop_oneof![
            (p(), p(), stroke.clone()).prop_map(|(x, y, s)| format!("point({x}, {y}, {s});")),
            (p(), p(), p(), p(), stroke.clone())
                .prop_map(|(a, b, c, d, s)| format!("segment({a}, {b}, {c}, {d}, {s});")),
        ];
        let piece = prop_oneof![
            (p(), p()).prop_map(|(x, y)| format!("line({x}, {y});")),
            (p(), p(), p(), p()).prop_map(|(a, b, c, d)| format!("quad({a}, {b}, {c}, {d});")),
        ];
        let path = (
            p(),
            p(),
            proptest::collection::vec(piece, 1..5),
            any::<bool>(),
            style.clone(),
        )
            .prop_map(|(x, y, pieces, close, s)| {
                let s = if close {
                    s
                } else {
                    "stroke: \"#00aa00\", width: 0.01".into()
                };
                let close = if close { " close();" } else { "" };
                format!("path({s}) {{ move({x}, {y}); {}{close} }}", pieces.concat())
            });
        let boolean = (
            prop_oneof![Just("union"), Just("intersect"), Just("difference")],
            proptest::collection::vec(closed, 1..4),
            style,
        )
            .prop_map(|(op, parts, s)| {
                let parts: Vec<String> = parts.into_iter().map(|c| format!("{c});")).collect();
                format!("{op}({s}) {{ {} }}", parts.concat())
            });
        prop_oneof![3 => styled_closed, 2 => open, 1 => path, 1 => boolean]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]
        /// The culled, tiled, lane-vectorised evaluation equals applying
        /// every operation of every channel at every pixel, and each
        /// pixel's winner record reproduces its value, on random scenes.
        #[test]
        fn sampled_fields_equal_brute_force_on_random_scenes(
            shapes in proptest::collection::vec(shape(), 1..14),
            background in any::<bool>(),
            n in 9usize..40,
        ) {
            let mut src = shapes.join("\n");
            if background {
                // A shape in the background colour makes it a channel.
                src.push_str("\ncircle(0.4, 0.6, 0.2, fill: \"#ffffff\");");
            }
            check_brute_force_with(&src, n, false);
        }
    }
}
