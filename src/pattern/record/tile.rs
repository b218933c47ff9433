//! `tile(px, py) { … }` and `tile(px, py, shear) { … }`: a block repeated
//! over the canvas on the lattice `(col·px + row·shear, row·py)`.
//!
//! Each copy runs the block translated to its lattice point, with the
//! integers `row` and `col` defined inside it (the copy at the origin is
//! row 0, column 0; use them for alternation such as `(row + col) % 2`).
//! Copies are drawn row by row from the top, left to right, so a later row
//! lies on top of an earlier one (painter's order, e.g. fish scales).
//!
//! **Which copies.** The recorder emits every copy that can touch the
//! canvas `[0, WIDTH] × [0, HEIGHT]` (`[0, 1]²` when square) for *some* values of the float parameters within their
//! declared ranges, and only those; the set depends on the ranges (and the
//! integer parameters), never on the float values, so one tape serves a
//! whole fit. It is found from interval bounds over the ranges
//! ([`crate::pattern::tape::Tape::bounds`]):
//!
//! - the pitches `px`, `py` and the `shear` are bounded over the ranges;
//!   `px` and `py` must be positive for every value in range;
//! - **the block's extent is measured**: the block is recorded once at the
//!   origin for each of `row`, `col` ∈ {0, 1} (so parity-dependent bodies
//!   are covered) into a scratch recording, and the bounds of every
//!   primitive it draws (plus half its stroke width) over the ranges give a
//!   box that holds the copy for every parameter value. The scratch shapes
//!   are then dropped. A body whose extent grows with `row` or `col` beyond
//!   their parity is not covered by this measurement: put growing offsets in
//!   the lattice (`px`, `py`, `shear`), not in the body;
//! - a copy is emitted when its box, shifted by the bounds of its lattice
//!   point, meets the canvas on both axes (the bounds treat parameters as
//!   independent, so a copy that could only touch for a combination no
//!   single parameter vector gives may still be emitted; none that can touch
//!   is left out).
//!
//! The number of copies counts against the shape limit before any is drawn,
//! and every primitive they draw counts as usual. `tile` may not be nested
//! in a transform, another tile, a path or a boolean block: the lattice is
//! in canvas coordinates (transforms inside the block are fine).
use super::super::lang::Call;
use super::super::sdf::PrimKind;
use super::interp::Xf;
use super::interp::{Flow, Rec, Val, V};
use crate::core::error::Result;
use std::collections::HashMap;

/// An interval `(lo, hi)`.
type Iv = (f64, f64);

/// `k · [lo, hi]`.
fn scale_iv(k: f64, (lo, hi): Iv) -> Iv {
    let (a, b) = (k * lo, k * hi);
    (a.min(b), a.max(b))
}

impl Rec<'_> {
    /// Bounds of a tape value over the parameter ranges.
    fn bound_of(&self, v: V, all: &[Iv]) -> Iv {
        match v {
            V::C(c) => (c, c),
            V::N(i) => all[i as usize],
        }
    }

    /// Run the tile body once for copy (`row`, `col`) with the lattice
    /// translation `(tx, ty)`.
    fn tile_copy(&mut self, c: &Call, row: f64, col: f64, tx: V, ty: V) -> Result<()> {
        self.xf.push(Xf {
            tx,
            ty,
            ..Xf::identity()
        });
        let frame = self.frames.last_mut().expect("frame");
        let mut scope = HashMap::new();
        scope.insert("row".to_string(), Val::Num(V::C(row)));
        scope.insert("col".to_string(), Val::Num(V::C(col)));
        frame.push(scope);
        let r = self.block(c.block.as_deref().unwrap_or(&[]), true, c.pos);
        self.frames.last_mut().expect("frame").pop();
        self.xf.pop();
        match r? {
            Flow::Normal => Ok(()),
            Flow::Return(_, p) => Err(p.err("'return' inside a tile block is not supported")),
        }
    }

    /// The box holding one copy of the body (relative to its lattice point)
    /// for every parameter value in range, measured by a scratch recording.
    fn tile_extent(&mut self, c: &Call) -> Result<(Iv, Iv)> {
        let (tape_len, prims_len, shapes_len) =
            (self.tape.len(), self.prims.len(), self.shapes.len());
        let mut run = || -> Result<()> {
            for (row, col) in [(0.0, 0.0), (0.0, 1.0), (1.0, 0.0), (1.0, 1.0)] {
                self.tile_copy(c, row, col, V::C(0.0), V::C(0.0))?;
            }
            Ok(())
        };
        let r = run();
        let all = self.tape.bounds(&self.ranges);
        let mut x = (f64::INFINITY, f64::NEG_INFINITY);
        let mut y = x;
        let mut grow = |px: Iv, py: Iv, pad: f64| {
            x = (x.0.min(px.0 - pad), x.1.max(px.1 + pad));
            y = (y.0.min(py.0 - pad), y.1.max(py.1 + pad));
        };
        let b = |i: u32| all[i as usize];
        for p in &self.prims[prims_len..] {
            let f = p.fields;
            match p.kind {
                PrimKind::Point => grow(b(f[0]), b(f[1]), 0.0),
                PrimKind::Circle => {
                    let r = b(f[2]).0.abs().max(b(f[2]).1.abs());
                    grow(b(f[0]), b(f[1]), r)
                }
                PrimKind::Rect => {
                    let m = |iv: Iv| iv.0.abs().max(iv.1.abs());
                    grow(b(f[0]), b(f[1]), m(b(f[2])) + m(b(f[3])) + m(b(f[4])))
                }
                PrimKind::Segment => {
                    grow(b(f[0]), b(f[1]), 0.0);
                    grow(b(f[2]), b(f[3]), 0.0)
                }
                PrimKind::Quad => {
                    grow(b(f[0]), b(f[1]), 0.0);
                    grow(b(f[2]), b(f[3]), 0.0);
                    grow(b(f[4]), b(f[5]), 0.0)
                }
            }
        }
        let half_stroke = self.shapes[shapes_len..]
            .iter()
            .filter(|s| s.stroke.is_some())
            .map(|s| 0.5 * b(s.width).0.abs().max(b(s.width).1.abs()))
            .fold(0.0, f64::max);
        let drew = self.prims.len() > prims_len;
        // Drop the scratch recording.
        self.tape.truncate(tape_len);
        self.consts.retain(|_, i| (*i as usize) < tape_len);
        self.prims.truncate(prims_len);
        self.shapes.truncate(shapes_len);
        r?;
        if !drew {
            return Err(c
                .pos
                .err("this tile block draws nothing; put shapes inside it"));
        }
        let x = (x.0 - half_stroke, x.1 + half_stroke);
        let y = (y.0 - half_stroke, y.1 + half_stroke);
        if !(x.0.is_finite() && x.1.is_finite() && y.0.is_finite() && y.1.is_finite()) {
            return Err(c.pos.err(
                "cannot bound where this tile's copy lies over the parameter ranges \
                 (a division by a range holding 0, tan near its asymptote, ln near 0 …?); \
                 keep the block's coordinates to + - * and sin/cos of parameters",
            ));
        }
        Ok((x, y))
    }

    /// `tile(px, py[, shear]) { … }`: see the module docs.
    pub(super) fn tile_block(&mut self, c: &Call) -> Result<()> {
        if self.xf.len() > 1 {
            return Err(c.pos.err(
                "'tile' cannot be nested in a transform or another tile: its lattice is in \
                 canvas coordinates; move the transform inside the tile block",
            ));
        }
        if !self.bool_sinks.is_empty() {
            return Err(c.pos.err(
                "'tile' cannot be used inside union/intersect/difference; put the boolean block inside the tile",
            ));
        }
        let n = c.args.iter().filter(|a| a.name.is_none()).count();
        if !(2..=3).contains(&n) || c.args.iter().any(|a| a.name.is_some()) {
            return Err(c.pos.err(format!(
                "'tile' takes 2 or 3 numbers, got {}: write tile(px, py) {{ … }} or \
                 tile(px, py, shear) {{ … }} (column pitch, row pitch, row shift)",
                c.args.len()
            )));
        }
        let (a, _) = self.args(c, n, &[])?;
        let (px, py) = (a[0], a[1]);
        let shear = a.get(2).copied().unwrap_or(V::C(0.0));
        let all = self.tape.bounds(&self.ranges);
        let (pxb, pyb, shb) = (
            self.bound_of(px, &all),
            self.bound_of(py, &all),
            self.bound_of(shear, &all),
        );
        for (what, iv, arg) in [("column pitch px", pxb, 0), ("row pitch py", pyb, 1)] {
            if !(iv.0 > 0.0 && iv.1.is_finite()) {
                return Err(c.args[arg].value.pos().err(format!(
                    "the tile's {what} must be positive for every parameter value in range; \
                     here it can be as small as {} (narrow the parameter ranges)",
                    iv.0
                )));
            }
        }
        if !(shb.0.is_finite() && shb.1.is_finite()) {
            return Err(c.args[2]
                .value
                .pos()
                .err("cannot bound the tile's shear over the parameter ranges"));
        }
        let (xe, ye) = self.tile_extent(c)?;
        let limit = self.limits.max_shapes;
        let too_many = |count: f64| {
            c.pos.limit(format!(
                "this tile needs {count} or more copies to cover the canvas for every parameter \
                 value in range (pitches as small as {:.4} × {:.4}); at most {limit} are allowed: \
                 narrow the parameter ranges or enlarge the pitches",
                pxb.0, pyb.0
            ))
        };
        // Candidate index range for offsets k·[lo, hi] + s with the box [e0, e1]
        // on an axis of the canvas `[0, side]`: k·p + s + e1 ≥ 0 and
        // k·p + s + e0 ≤ side for some p in [lo, hi].
        let (cw, ch) = (self.canvas.w, self.canvas.h);
        let candidates = |(lo, hi): Iv, s: Iv, e: Iv, side: f64| -> (f64, f64) {
            let a = -e.1 - s.1;
            let b = side - e.0 - s.0;
            (
                (a / lo).min(a / hi).floor() - 1.0,
                (b / lo).max(b / hi).ceil() + 1.0,
            )
        };
        let touches = |k: f64, p: Iv, s: Iv, e: Iv, side: f64| {
            let o = scale_iv(k, p);
            o.1 + s.1 + e.1 >= 0.0 && o.0 + s.0 + e.0 <= side
        };
        let (j0, j1) = candidates(pyb, (0.0, 0.0), ye, ch);
        // Non-finite ends (pitches near 0 or huge extents) are refused too,
        // so the loops below always end.
        if !(j0.is_finite() && j1.is_finite() && j1 - j0 <= limit as f64) {
            return Err(too_many(j1 - j0));
        }
        let mut copies: Vec<(f64, f64)> = vec![];
        let mut j = j0;
        while j <= j1 {
            if touches(j, pyb, (0.0, 0.0), ye, ch) {
                let s = scale_iv(j, shb);
                let (i0, i1) = candidates(pxb, s, xe, cw);
                if !(i0.is_finite() && i1.is_finite())
                    || i1 - i0 + copies.len() as f64 > 2.0 * limit as f64
                {
                    return Err(too_many(i1 - i0 + copies.len() as f64));
                }
                let mut i = i0;
                while i <= i1 {
                    if touches(i, pxb, s, xe, cw) {
                        copies.push((j, i));
                    }
                    i += 1.0;
                }
                if copies.len() > limit {
                    return Err(too_many(copies.len() as f64));
                }
            }
            j += 1.0;
        }
        for (row, col) in copies {
            self.tick(c.pos)?;
            let cx = self.mul(V::C(col), px);
            let sx = self.mul(V::C(row), shear);
            let tx = self.add(cx, sx);
            let ty = self.mul(V::C(row), py);
            self.tile_copy(c, row, col, tx, ty)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::super::{Program, RecordLimits, Recording};
    use crate::core::error::{Error, Result};
    use crate::pattern::field::Scene;
    use crate::pattern::fit::colour_indices;

    fn rec_at(src: &str, values: Option<&[f64]>) -> Result<Recording> {
        let p = Program::parse(src)?;
        let v = values.map(|v| v.to_vec()).unwrap_or_else(|| p.defaults());
        p.record(&v, &RecordLimits::default())
    }

    #[test]
    fn a_constant_tile_emits_exactly_the_copies_that_touch_the_canvas() {
        // Circles of radius 0.05 every 0.25: columns and rows 0..=4 touch
        // [0, 1]; -1 (right edge at -0.2) and 5 (left edge at 1.2) do not.
        let r = rec_at("tile(0.25, 0.25) { circle(0, 0, 0.05); }", None).unwrap();
        assert_eq!(r.shapes.len(), 25);
        // A shear shifts each row; the copies follow it.
        let r = rec_at("tile(0.25, 0.5, 0.125) { circle(0, 0, 0.05); }", None).unwrap();
        // Row 0 (y 0): x = 0, .25, … 1 → 5; row 1 (y .5): x = .125 + k/4 → -0.125? no
        // (its right edge is -0.075), .125 … .875 → 4; row 2 (y 1): x = .25 k + .25 → 0 … 1 → 5.
        assert_eq!(r.shapes.len(), 14);
    }

    #[test]
    fn the_copy_count_is_fixed_while_float_parameters_move() {
        let src = "param dx in [0.1, 0.2] = 0.15;\nparam dy in [0.12, 0.2] = 0.15;\n\
                   param ox in [0.0, 0.1] = 0.05;\nparam r in [0.02, 0.04] = 0.03;\n\
                   param sh in [-0.05, 0.05] = 0.0;\n\
                   tile(dx, dy, sh) { if (row + col) % 2 == 0 { circle(ox, 0.03, r, fill: \"#f00\"); } \
                   else { circle(ox, 0.03, r, fill: \"#00f\"); } }";
        let counts: Vec<(usize, usize, usize)> = [
            [0.1, 0.12, 0.0, 0.02, -0.05],
            [0.2, 0.2, 0.1, 0.04, 0.05],
            [0.15, 0.15, 0.05, 0.03, 0.0],
        ]
        .iter()
        .map(|v| {
            let r = rec_at(src, Some(v)).unwrap();
            (r.shapes.len(), r.prims.len(), r.tape.len())
        })
        .collect();
        assert!(counts.iter().all(|c| *c == counts[0]), "{counts:?}");
        // And it is no larger than needed: at most one extra copy per row
        // and column beyond what the smallest pitches need (10 + 2 by 8.3 + 2).
        assert!(counts[0].0 <= 13 * 11, "{counts:?}");
    }

    /// On a canvas that is not square the copies cover all of it, and only
    /// the copies that touch it are emitted: `[0, 1.5] × [0, 1]` holds
    /// columns 0..=6 and rows 0..=4 of a 0.25 lattice; `[0, 1] × [0, 1.25]`
    /// columns 0..=4 and rows 0..=5. `WIDTH` and `HEIGHT` read the canvas.
    #[test]
    fn a_tile_covers_a_canvas_that_is_not_square() {
        use super::super::Canvas;
        let p = Program::parse("tile(0.25, 0.25) { circle(0, 0, 0.05); }").unwrap();
        for ((w, h), copies) in [((300, 200), 7 * 5), ((200, 250), 5 * 6), ((64, 64), 25)] {
            let canvas = Canvas::of_pixels(w, h);
            let r = p.record_on(&[], &RecordLimits::default(), canvas).unwrap();
            assert_eq!(r.shapes.len(), copies, "{w} × {h}");
            assert_eq!(r.canvas, canvas);
        }
        let centre = |src: &str, canvas: Canvas| -> (f64, f64) {
            let p = Program::parse(src).unwrap();
            let r = p.record_on(&[], &RecordLimits::default(), canvas).unwrap();
            let mut v = vec![];
            r.tape.forward(&[], &mut v);
            let f = r.prims[0].fields;
            (v[f[0] as usize], v[f[1] as usize])
        };
        let src = "circle(WIDTH / 2, HEIGHT / 2, 0.1);";
        assert_eq!(centre(src, Canvas::of_pixels(300, 240)), (0.625, 0.5));
        assert_eq!(centre(src, Canvas::SQUARE), (0.5, 0.5));
        // A name the program defines itself wins over the canvas's.
        let src = "let WIDTH = 3; circle(WIDTH, 0, 0.1);";
        assert_eq!(centre(src, Canvas::SQUARE), (3.0, 0.0));
    }

    /// At the ends of every range (smallest and largest pitch, offset and
    /// size), the tile draws the same picture as a loop placing copies far
    /// past every edge (41 × 41 copies): no band along any edge is left
    /// empty and no copy is missing inside.
    #[test]
    fn copies_cover_the_canvas_at_the_range_extremes() {
        let head = "background \"#ffffff\";\nparam d in [0.1, 0.25] = 0.2;\n\
                    param ox in [0.0, 0.2] = 0.1;\nparam w in [0.3, 0.6] = 0.5;\n";
        let body = "rect(ox, 0.02, w * d, w * d, fill: \"#000000\", rotation: 0.3); \
                    circle(ox + 0.5 * d, 0.02, 0.2 * d, fill: \"#ff0000\");";
        let tiled = format!("{head}tile(d, d, 0.3 * d) {{ {body} }}");
        let looped = format!(
            "{head}for row in -20..21 {{ for col in -20..21 {{ \
             translate(col * d + row * 0.3 * d, row * d) {{ {body} }} }} }}"
        );
        let scene = |src: &str| {
            let p = Program::parse(src).unwrap();
            Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap())
        };
        let (t, l) = (scene(&tiled), scene(&looped));
        // 229 copies: about 12 × 12 at the smallest pitch, plus those a row's
        // shift (0.3·d, bounded independently of d) may bring in.
        assert!(t.rec.shapes.len() <= 2 * 240, "{}", t.rec.shapes.len());
        let n = 96;
        for v in [
            [0.1, 0.0, 0.3],
            [0.25, 0.2, 0.6],
            [0.25, 0.0, 0.3],
            [0.1, 0.2, 0.6],
            [0.1, 0.2, 0.3],
        ] {
            let a = colour_indices(&t, &v, n).unwrap();
            let b = colour_indices(&l, &v, n).unwrap();
            let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
            assert_eq!(
                differ, 0,
                "{v:?}: {differ} pixels differ from the loop's render"
            );
        }
    }

    #[test]
    fn tile_errors_are_located_and_say_the_fix() {
        let located = |src: &str, line: usize, needle: &str| {
            let e = rec_at(src, None).unwrap_err();
            let msg = e.to_string();
            assert!(msg.contains(needle), "{src}: {msg}");
            assert!(msg.contains(&format!("line {line}")), "{src}: {msg}");
        };
        located(
            "param d in [-0.1, 0.2] = 0.1;\ntile(d, 0.2) { circle(0, 0, 0.1); }",
            2,
            "must be positive",
        );
        located(
            "tile(0.001, 0.001) { circle(0, 0, 0.01); }",
            1,
            "at most 5000",
        );
        // Pitches so small that the candidate rows overflow to infinity
        // (on both ends) are refused, not looped over.
        located(
            "param p in [1e-310, 2e-310] = 1.5e-310;\ntile(p, p) { circle(2, 2, 0.01); }",
            2,
            "at most 5000",
        );
        located(
            "param p in [1e-310, 2e-310] = 1.5e-310;\ntile(0.5, p) { circle(0.1, 0.1, 0.01); }",
            2,
            "at most 5000",
        );
        located(
            "translate(0.1, 0.1) {\n  tile(0.2, 0.2) { circle(0, 0, 0.1); }\n}",
            2,
            "cannot be nested",
        );
        located(
            "let a = 1;\ntile(0.2, 0.2) { let b = 2; }",
            2,
            "draws nothing",
        );
        located("tile(0.2) { circle(0, 0, 0.1); }", 1, "tile(px, py)");
        located("tile(0.2, 0.2);", 1, "needs a { block }");
        located(
            "param d in [0.1, 0.2] = 0.15;\ntile(d, d) { circle(ln(d - 0.1), 0, 0.1); }",
            2,
            "cannot bound",
        );
        let e = Program::parse("tile {\n circle(0, 0, 0.1);\n}").unwrap_err();
        assert!(
            matches!(
                e,
                Error::Syntax {
                    line: 1,
                    column: 1,
                    ..
                }
            ) && e.to_string().contains("tile() {"),
            "{e}"
        );
    }
}
