//! The path builder: `move`, `line`, `quad`, `cubic` (as eight quadratic
//! pieces) and `close` inside `path(...) { }`.
use super::super::lang::Call;
use super::super::sdf::PrimKind;
use super::interp::{Rec, V};
use crate::core::error::Result;
use crate::pattern::geom::bezier::cubic_piece_weights;

impl Rec<'_> {
    pub(super) fn path_cmd(&mut self, c: &Call) -> Result<()> {
        self.at = c.pos;
        let n = match c.name.as_str() {
            "move" | "line" => 2,
            "quad" => 4,
            "cubic" => 6,
            _ => 0,
        };
        let (a, _) = self.args(c, n, &[])?;
        let mut pts = vec![];
        for k in 0..n / 2 {
            pts.push(self.xf_point(a[2 * k], a[2 * k + 1]));
        }
        let pb = self.path.as_ref().expect("in path");
        if c.name == "move" {
            if pb.started {
                return Err(c.pos.err("a path has one move(x, y), at its start; draw separate paths for separate outlines"));
            }
            let pb = self.path.as_mut().expect("in path");
            pb.start = pts[0];
            pb.cur = pts[0];
            pb.started = true;
            return Ok(());
        }
        if !pb.started {
            return Err(c.pos.err("start the path with move(x, y)"));
        }
        let cur = pb.cur;
        match c.name.as_str() {
            "line" => {
                self.push_prim(PrimKind::Segment, &[cur.0, cur.1, pts[0].0, pts[0].1])?;
            }
            "quad" => {
                self.push_prim(
                    PrimKind::Quad,
                    &[cur.0, cur.1, pts[0].0, pts[0].1, pts[1].0, pts[1].1],
                )?;
            }
            "cubic" => {
                // Eight quadratic pieces (see geom::bezier::cubic_piece_weights).
                let ctrl = [cur, pts[0], pts[1], pts[2]];
                let n = 8;
                for k in 0..n {
                    let w = cubic_piece_weights(k as f64 / n as f64, (k + 1) as f64 / n as f64);
                    let mut q = [V::C(0.0); 6];
                    for j in 0..3 {
                        let (mut x, mut y) = (V::C(0.0), V::C(0.0));
                        for i in 0..4 {
                            let tx = self.mul(V::C(w[j][i]), ctrl[i].0);
                            x = self.add(x, tx);
                            let ty = self.mul(V::C(w[j][i]), ctrl[i].1);
                            y = self.add(y, ty);
                        }
                        q[2 * j] = x;
                        q[2 * j + 1] = y;
                    }
                    // Pin the piece end points to the exact cubic end points.
                    if k == 0 {
                        q[0] = cur.0;
                        q[1] = cur.1;
                    }
                    if k == n - 1 {
                        q[4] = pts[2].0;
                        q[5] = pts[2].1;
                    }
                    self.push_prim(PrimKind::Quad, &q)?;
                }
            }
            "close" => {
                let pb = self.path.as_mut().expect("in path");
                pb.closed = true;
                let (s, e) = (pb.cur, pb.start);
                if s != e {
                    self.push_prim(PrimKind::Segment, &[s.0, s.1, e.0, e.1])?;
                }
                self.path.as_mut().expect("in path").cur = e;
                return Ok(());
            }
            _ => unreachable!(),
        }
        let end = *pts.last().expect("end point");
        self.path.as_mut().expect("in path").cur = end;
        Ok(())
    }
}
