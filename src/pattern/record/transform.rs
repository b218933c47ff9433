//! Transforms: the current rotation, scale and translation as tape values,
//! applied to points and lengths as shapes are emitted.
use super::super::lang::Call;
use super::super::tape::Op;
use super::interp::{Flow, Rec, Xf, V};
use crate::core::error::Result;

impl Rec<'_> {
    pub(super) fn xf_point(&mut self, x: V, y: V) -> (V, V) {
        let t = *self.xf.last().expect("transform");
        let cx = self.mul(t.cos, x);
        let sy = self.mul(t.sin, y);
        let rx = self.sub(cx, sy);
        let sx = self.mul(t.sin, x);
        let cy = self.mul(t.cos, y);
        let ry = self.add(sx, cy);
        let rx = self.mul(t.scale, rx);
        let ry = self.mul(t.scale, ry);
        (self.add(rx, t.tx), self.add(ry, t.ty))
    }

    pub(super) fn xf_len(&mut self, l: V) -> V {
        let s = self.xf.last().expect("transform").scale;
        self.mul(s, l)
    }

    /// `translate(x, y) { }`, `rotate(angle) { }`, `scale(s) { }`: run the
    /// block with the composed transform.
    pub(super) fn transform_block(&mut self, c: &Call) -> Result<()> {
        let n = if c.name == "translate" { 2 } else { 1 };
        let (a, _) = self.args(c, n, &[])?;
        let t = *self.xf.last().expect("transform");
        let nt = match c.name.as_str() {
            "translate" => {
                let (x, y) = self.xf_point(a[0], a[1]);
                Xf { tx: x, ty: y, ..t }
            }
            "rotate" => {
                let angle = self.add(t.angle, a[0]);
                let cos = self.op(&[angle], |o| Op::Cos(o[0]));
                let sin = self.op(&[angle], |o| Op::Sin(o[0]));
                Xf {
                    angle,
                    cos,
                    sin,
                    ..t
                }
            }
            _ => {
                let scale = self.mul(t.scale, a[0]);
                Xf { scale, ..t }
            }
        };
        self.xf.push(nt);
        let r = self.block(c.block.as_deref().unwrap_or(&[]), false, c.pos);
        self.xf.pop();
        match r? {
            Flow::Normal => Ok(()),
            Flow::Return(_, p) => Err(p.err("'return' inside a transform block is not supported")),
        }
    }
}
