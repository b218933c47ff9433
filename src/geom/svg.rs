//! Closed outlines from vector sources: SVG path data and SVG documents
//! (parsed by `svgtypes` and `roxmltree`, the parsers under resvg) and
//! font glyphs, flattened into rings of points by one [`RingBuilder`].
//!
//! Bounded: at most [`MAX_POINTS`] points over all rings, [`MAX_ELEMENTS`]
//! elements read from a document, and curves flattened into at most
//! [`MAX_PIECES`] segments each; a document nests as deep as roxmltree
//! allows (it refuses deep nesting itself) and transforms are accumulated
//! on an explicit stack, never by recursion.
use crate::core::error::{Error, Result};
use glam::DVec2;

/// Most points over all rings of one source.
pub const MAX_POINTS: usize = 200_000;
/// Most elements of an SVG document looked at.
pub const MAX_ELEMENTS: usize = 100_000;
/// Most segments one curve is flattened into.
pub const MAX_PIECES: usize = 256;

/// Accumulates rings from move/line/curve/close commands, flattening
/// curves so no piece deviates more than `tolerance` from the curve.
pub struct RingBuilder {
    rings: Vec<Vec<DVec2>>,
    cur: Vec<DVec2>,
    points: usize,
    tolerance: f64,
    /// An affine map applied to every point: `[a, b, c, d, e, f]`.
    pub transform: [f64; 6],
    overflow: bool,
}

impl RingBuilder {
    pub fn new(tolerance: f64) -> Self {
        RingBuilder {
            rings: vec![],
            cur: vec![],
            points: 0,
            tolerance: tolerance.max(1e-6),
            transform: [1.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            overflow: false,
        }
    }

    fn map(&self, p: DVec2) -> DVec2 {
        let [a, b, c, d, e, f] = self.transform;
        DVec2::new(a * p.x + c * p.y + e, b * p.x + d * p.y + f)
    }

    fn push(&mut self, p: DVec2) {
        if self.points >= MAX_POINTS || !p.is_finite() {
            self.overflow |= self.points >= MAX_POINTS;
            return;
        }
        self.points += 1;
        self.cur.push(p);
    }

    fn last(&self) -> DVec2 {
        self.cur.last().copied().unwrap_or(DVec2::ZERO)
    }

    pub fn move_to(&mut self, p: DVec2) {
        self.close();
        let p = self.map(p);
        self.push(p);
    }

    pub fn line_to(&mut self, p: DVec2) {
        let p = self.map(p);
        self.push(p);
    }

    /// A quadratic Bézier from the current point.
    pub fn quad_to(&mut self, c: DVec2, p: DVec2) {
        let (a, c, p) = (self.last(), self.map(c), self.map(p));
        let n = self.pieces((a - 2.0 * c + p).length() * 0.25);
        for i in 1..=n {
            let t = i as f64 / n as f64;
            let u = 1.0 - t;
            self.push(a * (u * u) + c * (2.0 * u * t) + p * (t * t));
        }
    }

    /// A cubic Bézier from the current point.
    pub fn cubic_to(&mut self, c1: DVec2, c2: DVec2, p: DVec2) {
        let (a, c1, c2, p) = (self.last(), self.map(c1), self.map(c2), self.map(p));
        let dev = (a - 2.0 * c1 + c2)
            .length()
            .max((c1 - 2.0 * c2 + p).length())
            * 0.75;
        let n = self.pieces(dev);
        for i in 1..=n {
            let t = i as f64 / n as f64;
            let u = 1.0 - t;
            self.push(
                a * (u * u * u) + c1 * (3.0 * u * u * t) + c2 * (3.0 * u * t * t) + p * (t * t * t),
            );
        }
    }

    /// Segments for a curve whose second differences are about `dev`.
    fn pieces(&self, dev: f64) -> usize {
        let n = (dev / self.tolerance).sqrt().ceil();
        if n.is_finite() {
            (n as usize).clamp(1, MAX_PIECES)
        } else {
            1
        }
    }

    /// End the current ring (every subpath is a closed outline here).
    pub fn close(&mut self) {
        let ring = std::mem::take(&mut self.cur);
        if ring.len() >= 3 {
            self.rings.push(ring);
        }
    }

    /// The rings, or an error if the point limit was reached.
    pub fn finish(mut self) -> Result<Vec<Vec<DVec2>>> {
        self.close();
        if self.overflow {
            return Err(Error::limit(format!(
                "the outline has more than {MAX_POINTS} points (the outline point limit)"
            )));
        }
        Ok(self.rings)
    }
}

/// Rings of SVG path data (`d`), every subpath closed.
pub fn path_rings(d: &str, tolerance: f64) -> Result<Vec<Vec<DVec2>>> {
    let mut b = RingBuilder::new(tolerance);
    add_path(&mut b, d)?;
    b.finish()
}

fn add_path(b: &mut RingBuilder, d: &str) -> Result<()> {
    use svgtypes::SimplePathSegment as S;
    for seg in svgtypes::SimplifyingPathParser::from(d) {
        let seg = seg.map_err(|e| Error::input(format!("the SVG path data is not valid: {e}")))?;
        match seg {
            S::MoveTo { x, y } => b.move_to(DVec2::new(x, y)),
            S::LineTo { x, y } => b.line_to(DVec2::new(x, y)),
            S::CurveTo {
                x1,
                y1,
                x2,
                y2,
                x,
                y,
            } => b.cubic_to(DVec2::new(x1, y1), DVec2::new(x2, y2), DVec2::new(x, y)),
            S::Quadratic { x1, y1, x, y } => b.quad_to(DVec2::new(x1, y1), DVec2::new(x, y)),
            S::ClosePath => b.close(),
        }
    }
    b.close();
    Ok(())
}

/// Rings of every closed shape in an SVG document: `<path>`, `<rect>`,
/// `<circle>`, `<ellipse>`, `<polygon>` (and `<polyline>`, closed), with
/// `transform`s applied. Nested rings are holes under the even-odd rule.
pub fn document_rings(text: &str, tolerance: f64) -> Result<Vec<Vec<DVec2>>> {
    let doc = roxmltree::Document::parse(text)
        .map_err(|e| Error::input(format!("the SVG file is not valid XML: {e}")))?;
    let mut b = RingBuilder::new(tolerance);
    // Depth-first with an explicit stack of (node, transform).
    let mut stack = vec![(doc.root_element(), [1.0, 0.0, 0.0, 1.0, 0.0, 0.0])];
    let mut seen = 0usize;
    while let Some((node, parent)) = stack.pop() {
        seen += 1;
        if seen > MAX_ELEMENTS {
            return Err(Error::limit(format!(
                "the SVG file has more than {MAX_ELEMENTS} elements (the SVG element limit)"
            )));
        }
        let t = match node.attribute("transform") {
            Some(s) => {
                let m: svgtypes::Transform = s
                    .parse()
                    .map_err(|e| Error::input(format!("an SVG transform is not valid: {e}")))?;
                compose(parent, [m.a, m.b, m.c, m.d, m.e, m.f])
            }
            None => parent,
        };
        b.transform = t;
        let num = |name: &str| -> f64 {
            node.attribute(name)
                .and_then(|v| v.parse::<svgtypes::Number>().ok())
                .map_or(0.0, |n| n.0)
        };
        match node.tag_name().name() {
            "path" => add_path(&mut b, node.attribute("d").unwrap_or(""))?,
            "rect" => {
                let (x, y, w, h) = (num("x"), num("y"), num("width"), num("height"));
                if w > 0.0 && h > 0.0 {
                    b.move_to(DVec2::new(x, y));
                    b.line_to(DVec2::new(x + w, y));
                    b.line_to(DVec2::new(x + w, y + h));
                    b.line_to(DVec2::new(x, y + h));
                    b.close();
                }
            }
            "circle" | "ellipse" => {
                let (cx, cy) = (num("cx"), num("cy"));
                let (rx, ry) = if node.tag_name().name() == "circle" {
                    (num("r"), num("r"))
                } else {
                    (num("rx"), num("ry"))
                };
                if rx > 0.0 && ry > 0.0 {
                    // Four cubic quarter arcs.
                    let k = 0.552_284_749_8;
                    let c = DVec2::new(cx, cy);
                    let (ex, ey) = (DVec2::new(rx, 0.0), DVec2::new(0.0, ry));
                    b.move_to(c + ex);
                    for (p, q) in [(ex, ey), (ey, -ex), (-ex, -ey), (-ey, ex)] {
                        b.cubic_to(c + p + q * k, c + q + p * k, c + q);
                    }
                    b.close();
                }
            }
            "polygon" | "polyline" => {
                let mut first = true;
                for (x, y) in svgtypes::PointsParser::from(node.attribute("points").unwrap_or("")) {
                    if first {
                        b.move_to(DVec2::new(x, y));
                        first = false;
                    } else {
                        b.line_to(DVec2::new(x, y));
                    }
                }
                b.close();
            }
            // Not drawn: definitions, masks, text.
            "defs" | "clipPath" | "mask" | "symbol" | "pattern" | "marker" | "text" | "style" => {
                continue
            }
            _ => {}
        }
        // Children in reverse so they are visited in document order.
        let kids: Vec<_> = node.children().filter(|n| n.is_element()).collect();
        stack.extend(kids.into_iter().rev().map(|k| (k, t)));
    }
    let rings = b.finish()?;
    if rings.is_empty() {
        return Err(Error::input(
            "the SVG file has no closed shape (path, rect, circle, ellipse or polygon)",
        ));
    }
    Ok(rings)
}

/// `outer ∘ inner` for affine maps `[a, b, c, d, e, f]`.
fn compose(o: [f64; 6], i: [f64; 6]) -> [f64; 6] {
    [
        o[0] * i[0] + o[2] * i[1],
        o[1] * i[0] + o[3] * i[1],
        o[0] * i[2] + o[2] * i[3],
        o[1] * i[2] + o[3] * i[3],
        o[0] * i[4] + o[2] * i[5] + o[4],
        o[1] * i[4] + o[3] * i[5] + o[5],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geom::polygon::Polygon;

    fn area(rings: Vec<Vec<DVec2>>) -> f64 {
        Polygon::new(rings).unwrap().iter().map(Polygon::area).sum()
    }

    #[test]
    fn path_data_with_a_hole_and_curves() {
        let r = path_rings("M0 0 H10 V10 H0 Z M2 2 v6 h6 v-6 z", 0.1).unwrap();
        assert_eq!(r.len(), 2);
        assert!((area(r) - 64.0).abs() < 1e-9);
        let c = path_rings("M 0 5 A 5 5 0 1 0 10 5 A 5 5 0 1 0 0 5 Z", 0.01).unwrap();
        let a = area(c);
        assert!((a - std::f64::consts::PI * 25.0).abs() < 0.2, "{a}");
        assert!(path_rings("M 0 0 L x", 0.1).is_err());
    }

    #[test]
    fn documents_apply_transforms_and_skip_defs() {
        let svg = r#"<svg xmlns="http://www.w3.org/2000/svg">
          <defs><rect width="99" height="99"/></defs>
          <g transform="translate(100 0) scale(2)">
            <rect x="0" y="0" width="10" height="5"/>
            <circle cx="30" cy="30" r="5"/>
          </g>
          <polygon points="0,0 4,0 4,4"/>
        </svg>"#;
        let rings = document_rings(svg, 0.01).unwrap();
        assert_eq!(rings.len(), 3);
        let (lo, hi) = Polygon {
            rings: vec![rings[0].clone()],
        }
        .bbox();
        assert_eq!((lo, hi), (DVec2::new(100.0, 0.0), DVec2::new(120.0, 10.0)));
        let a = area(vec![rings[1].clone()]);
        assert!((a - std::f64::consts::PI * 100.0).abs() < 1.0, "{a}");
        assert!(document_rings("<svg", 0.1).is_err());
        assert!(document_rings(r#"<svg xmlns="http://www.w3.org/2000/svg"/>"#, 0.1).is_err());
    }

    #[test]
    fn outlines_are_bounded() {
        let many = format!("M0 0 {}", "L1 1 ".repeat(MAX_POINTS + 5));
        let e = path_rings(&many, 0.1).unwrap_err();
        assert!(e.to_string().contains("point limit"), "{e}");
        // A huge curve is flattened into at most MAX_PIECES segments.
        let r = path_rings("M0 0 C 1e9 0 1e9 1e9 0 1e9 Z", 1e-6).unwrap();
        assert!(r[0].len() <= MAX_PIECES + 2);
    }
}
