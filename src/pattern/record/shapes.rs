//! Shape statements: arguments and style, emitting shapes (or handing them
//! to an enclosing boolean block), primitives with their limits.
use super::super::lang::{Arg, Call, Pos};
use super::super::sdf::PrimKind;
use super::interp::PathB;
use super::interp::{Named, Rec, Val, V};
use super::{colour_error, parse_colour, BoolOp, Geom, Prim, Shape};
use crate::core::error::Result;
use std::collections::HashMap;
use std::rc::Rc;

impl Rec<'_> {
    /// Append a primitive drawn by the statement at `self.at`: its fields
    /// must be finite and the primitive count stays within the shape limit.
    pub(super) fn push_prim(&mut self, kind: PrimKind, vals: &[V]) -> Result<u32> {
        let pos = self.at;
        if self.prims.len() >= self.limits.max_shapes {
            return Err(pos.limit(format!(
                "more than {} shapes (every primitive counts: single shapes, path pieces and the \
                 parts of boolean blocks; a cubic is 8 pieces); reduce the counts or the loop sizes",
                self.limits.max_shapes
            )));
        }
        let mut fields = [0u32; 6];
        for (k, &v) in vals.iter().enumerate() {
            self.finite(v, pos, "a coordinate or size of this shape")?;
            fields[k] = self.node(v);
        }
        self.prims.push(Prim { kind, fields });
        Ok((self.prims.len() - 1) as u32)
    }

    pub(super) fn colour(&mut self, v: &Val, pos: Pos) -> Result<u16> {
        let Val::Str(s) = v else {
            return Err(pos.err("a colour must be a string like \"#ff8800\""));
        };
        let rgb = parse_colour(s).ok_or_else(|| pos.err(colour_error(s)))?;
        if let Some(i) = self.colours.iter().position(|c| *c == rgb) {
            return Ok(i as u16);
        }
        if self.colours.len() >= 64 {
            return Err(pos.err("a pattern may use at most 64 colours"));
        }
        self.colours.push(rgb);
        Ok((self.colours.len() - 1) as u16)
    }

    /// Split positional and named arguments; check the named ones.
    pub(super) fn args(
        &mut self,
        c: &Call,
        positional: usize,
        allowed: &[&str],
    ) -> Result<(Vec<V>, Named)> {
        let mut pos_args = vec![];
        let mut named = HashMap::new();
        for Arg { name, value } in &c.args {
            match name {
                None => {
                    if !named.is_empty() {
                        return Err(value
                            .pos()
                            .err("positional arguments must come before named ones"));
                    }
                    pos_args.push(self.num(value)?);
                }
                Some(n) => {
                    if !allowed.contains(&n.as_str()) {
                        let list = if allowed.is_empty() {
                            "none".to_string()
                        } else {
                            allowed.join(", ")
                        };
                        return Err(value.pos().err(format!(
                            "'{}' has no option '{n}' (options: {list})",
                            c.name
                        )));
                    }
                    let v = self.expr(value)?;
                    named.insert(n.clone(), (v, value.pos()));
                }
            }
        }
        if pos_args.len() != positional {
            return Err(c.pos.err(format!(
                "'{}' takes {positional} numbers, got {}",
                c.name,
                pos_args.len()
            )));
        }
        Ok((pos_args, named))
    }

    pub(super) fn named_num(
        &self,
        named: &HashMap<String, (Val, Pos)>,
        key: &str,
        default: f64,
    ) -> Result<V> {
        match named.get(key) {
            None => Ok(V::C(default)),
            Some((Val::Num(v), _)) => Ok(*v),
            Some((Val::Str(_), p)) => Err(p.err(format!("'{key}' must be a number"))),
        }
    }

    /// Emit a finished geometry with its style, or hand it to an enclosing boolean block.
    pub(super) fn emit(
        &mut self,
        c: &Call,
        geom: Geom,
        named: &HashMap<String, (Val, Pos)>,
        closed: bool,
    ) -> Result<()> {
        if !self.bool_sinks.is_empty() {
            if let Some((_, p)) = named
                .get("fill")
                .or(named.get("stroke"))
                .or(named.get("width"))
            {
                return Err(p.err("shapes inside union/intersect/difference take their style from the enclosing block"));
            }
            if !closed {
                return Err(c.pos.err(format!(
                    "'{}' has no inside; boolean blocks need closed shapes",
                    c.name
                )));
            }
            self.bool_sinks.last_mut().expect("sink").push(geom);
            return Ok(());
        }
        let mut fill = match named.get("fill") {
            Some((v, p)) => Some(self.colour(v, *p)?),
            None => None,
        };
        let stroke = match named.get("stroke") {
            Some((v, p)) => Some(self.colour(v, *p)?),
            None => None,
        };
        if fill.is_some() && !closed {
            return Err(named["fill"].1.err(format!(
                "'{}' has no inside to fill; use stroke: instead",
                c.name
            )));
        }
        let stroke = match (fill, stroke) {
            (None, None) => {
                let black = self.colour(&Val::Str(Rc::from("#000000")), c.pos)?;
                if closed {
                    fill = Some(black);
                    None
                } else {
                    Some(black)
                }
            }
            (_, s) => s,
        };
        let w = self.named_num(named, "width", 0.01)?;
        let w = self.xf_len(w);
        self.finite(w, c.pos, "the stroke width")?;
        let width = self.node(w);
        if self.shapes.len() >= self.limits.max_shapes {
            return Err(c.pos.limit(format!(
                "more than {} shapes; reduce the counts or the loop sizes",
                self.limits.max_shapes
            )));
        }
        self.shapes.push(Shape {
            geom,
            fill,
            stroke,
            width,
            pos: c.pos,
        });
        Ok(())
    }

    pub(super) fn shape_stmt(&mut self, c: &Call) -> Result<()> {
        self.at = c.pos;
        let in_path = self.path.is_some();
        let path_cmd = matches!(
            c.name.as_str(),
            "move" | "line" | "quad" | "cubic" | "close"
        );
        if in_path && !path_cmd {
            return Err(c.pos.err(format!(
                "'{}' is not allowed inside a path; use move, line, quad, cubic, close",
                c.name
            )));
        }
        if !in_path && matches!(c.name.as_str(), "move" | "quad" | "cubic" | "close") {
            return Err(c.pos.err(format!(
                "'{}' is a path command; use it inside path(...) {{ }}",
                c.name
            )));
        }
        let needs_block = matches!(
            c.name.as_str(),
            "path"
                | "union"
                | "intersect"
                | "difference"
                | "translate"
                | "rotate"
                | "scale"
                | "tile"
        );
        if needs_block != c.block.is_some() {
            return Err(c.pos.err(if needs_block {
                format!("'{}' needs a {{ block }} after it", c.name)
            } else {
                format!("'{}' does not take a {{ block }}", c.name)
            }));
        }
        if in_path {
            return self.path_cmd(c);
        }
        const STYLE: [&str; 3] = ["fill", "stroke", "width"];
        match c.name.as_str() {
            "circle" => {
                let (a, named) = self.args(c, 3, &STYLE)?;
                let (x, y) = self.xf_point(a[0], a[1]);
                let r = self.xf_len(a[2]);
                let p = self.push_prim(PrimKind::Circle, &[x, y, r])?;
                self.emit(c, Geom::Prim(p), &named, true)
            }
            "point" => {
                let (a, named) = self.args(c, 2, &["stroke", "width"])?;
                let (x, y) = self.xf_point(a[0], a[1]);
                let p = self.push_prim(PrimKind::Point, &[x, y])?;
                self.emit(c, Geom::Prim(p), &named, false)
            }
            "segment" | "line" => {
                let (a, named) = self.args(c, 4, &["stroke", "width"])?;
                let (x0, y0) = self.xf_point(a[0], a[1]);
                let (x1, y1) = self.xf_point(a[2], a[3]);
                let p = self.push_prim(PrimKind::Segment, &[x0, y0, x1, y1])?;
                self.emit(c, Geom::Prim(p), &named, false)
            }
            "rect" => {
                let (a, named) =
                    self.args(c, 4, &["fill", "stroke", "width", "radius", "rotation"])?;
                let (x, y) = self.xf_point(a[0], a[1]);
                let hw = self.mul(a[2], V::C(0.5));
                let hh = self.mul(a[3], V::C(0.5));
                let hw = self.xf_len(hw);
                let hh = self.xf_len(hh);
                let r = self.named_num(&named, "radius", 0.0)?;
                let r = self.xf_len(r);
                let rot = self.named_num(&named, "rotation", 0.0)?;
                let base = self.xf.last().expect("transform").angle;
                let ang = self.add(rot, base);
                let p = self.push_prim(PrimKind::Rect, &[x, y, hw, hh, r, ang])?;
                self.emit(c, Geom::Prim(p), &named, true)
            }
            "path" => {
                let (_, named) = self.args(c, 0, &STYLE)?;
                let first = self.prims.len() as u32;
                self.path = Some(PathB {
                    start: (V::C(0.0), V::C(0.0)),
                    cur: (V::C(0.0), V::C(0.0)),
                    first,
                    started: false,
                    closed: false,
                });
                let r = self.block(c.block.as_deref().unwrap_or(&[]), false, c.pos);
                let mut pb = self.path.take().expect("path builder");
                r?;
                self.at = c.pos;
                let closed = pb.closed || named.contains_key("fill");
                if closed && pb.cur != pb.start && pb.started {
                    let (s, e) = (pb.cur, pb.start);
                    self.push_prim(PrimKind::Segment, &[s.0, s.1, e.0, e.1])?;
                    pb.cur = pb.start;
                }
                let len = self.prims.len() as u32 - pb.first;
                if len == 0 {
                    return Err(c.pos.err(
                        "this path draws nothing; start with move(x, y) and add line/quad/cubic",
                    ));
                }
                self.emit(
                    c,
                    Geom::Path {
                        first: pb.first,
                        len,
                        closed,
                    },
                    &named,
                    closed,
                )
            }
            "union" | "intersect" | "difference" => {
                let (_, named) = self.args(c, 0, &STYLE)?;
                self.bool_sinks.push(vec![]);
                let r = self.block(c.block.as_deref().unwrap_or(&[]), false, c.pos);
                let children = self.bool_sinks.pop().expect("sink");
                r?;
                if children.is_empty() {
                    return Err(c.pos.err(format!("'{}' contains no shapes", c.name)));
                }
                let op = match c.name.as_str() {
                    "union" => BoolOp::Union,
                    "intersect" => BoolOp::Intersect,
                    _ => BoolOp::Difference,
                };
                self.emit(c, Geom::Bool(op, children), &named, true)
            }
            "translate" | "rotate" | "scale" => self.transform_block(c),
            "tile" => self.tile_block(c),
            _ => unreachable!("statement names are listed in is_statement_name"),
        }
    }
}
