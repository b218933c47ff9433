//! Closed outlines from vector sources: SVG path data and SVG documents
//! (parsed by `svgtypes` and `roxmltree`, the parsers under resvg) and
//! font glyphs, flattened into rings of points by one [`RingBuilder`].
//!
//! Bounded: at most [`MAX_POINTS`] points over all rings, [`MAX_ELEMENTS`]
//! elements read from a document, and curves flattened into at most
//! [`MAX_PIECES`] segments each; a document nests at most [`MAX_DEPTH`]
//! elements deep, checked by a scan of the text before roxmltree (whose
//! parser recurses once per element) reads it, and transforms are
//! accumulated on an explicit stack, never by recursion.
use crate::core::error::{Error, Result};
use crate::tangle::geom::polygon::Polygon;
use glam::DVec2;

/// Most points over all rings of one source.
pub const MAX_POINTS: usize = 200_000;
/// Most elements of an SVG document looked at.
pub const MAX_ELEMENTS: usize = 100_000;
/// Most segments one curve is flattened into.
pub const MAX_PIECES: usize = 256;
/// Deepest element nesting of an SVG document (real drawings nest a few
/// dozen groups; 3,000 nested `<g>` overflowed the worker's stack).
pub const MAX_DEPTH: usize = 256;

/// Refuse a document that nests elements deeper than [`MAX_DEPTH`], by a
/// linear scan of its markup (comments, CDATA, processing instructions, the
/// doctype and quoted attribute values skipped), before any recursive parser
/// sees it. Malformed markup is left to the parser to describe.
pub fn check_depth(text: &str) -> Result<()> {
    let b = text.as_bytes();
    let skip_to = |from: usize, end: &[u8]| -> usize {
        b[from..]
            .windows(end.len())
            .position(|w| w == end)
            .map_or(b.len(), |k| from + k + end.len())
    };
    let (mut i, mut depth) = (0usize, 0usize);
    while i < b.len() {
        if b[i] != b'<' {
            i += 1;
            continue;
        }
        let rest = &b[i..];
        if rest.starts_with(b"<!--") {
            i = skip_to(i + 4, b"-->");
        } else if rest.starts_with(b"<![CDATA[") {
            i = skip_to(i + 9, b"]]>");
        } else if rest.starts_with(b"<?") {
            i = skip_to(i + 2, b"?>");
        } else if rest.starts_with(b"<!") {
            // A doctype, perhaps with an internal subset in [ ].
            let mut j = i + 2;
            let mut square = 0i32;
            while j < b.len() && !(b[j] == b'>' && square <= 0) {
                match b[j] {
                    b'[' => square += 1,
                    b']' => square -= 1,
                    _ => {}
                }
                j += 1;
            }
            i = j + 1;
        } else if rest.starts_with(b"</") {
            depth = depth.saturating_sub(1);
            i = skip_to(i + 2, b">");
        } else {
            // A start tag: to its `>`, outside quoted values.
            let mut j = i + 1;
            let mut quote = 0u8;
            while j < b.len() {
                let c = b[j];
                if quote != 0 {
                    if c == quote {
                        quote = 0;
                    }
                } else if c == b'"' || c == b'\'' {
                    quote = c;
                } else if c == b'>' {
                    break;
                }
                j += 1;
            }
            if j >= b.len() || b[j - 1] != b'/' {
                depth += 1;
                if depth > MAX_DEPTH {
                    return Err(Error::limit(format!(
                        "the SVG file nests elements more than {MAX_DEPTH} deep (the SVG nesting limit)"
                    )));
                }
            }
            i = j + 1;
        }
    }
    Ok(())
}

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

/// One drawn element of an SVG document (`<path>`, `<rect>`, `<circle>`,
/// `<ellipse>`, `<polygon>`, `<polyline>`, closed): its rings with the
/// transforms applied, and how it is painted.
#[derive(Debug, Clone, PartialEq)]
pub struct Element {
    pub rings: Vec<Vec<DVec2>>,
    /// Filled by the nonzero rule: only when the file says
    /// `fill-rule="nonzero"`. Unsaid, nested subpaths are holes (even-odd),
    /// which is what drawing tools mean by a compound path.
    pub nonzero: bool,
    /// Filled white (paper): it can only cut a hole in the ink around it.
    pub paper: bool,
}

/// Most drawn elements of a document combined into start shapes.
pub const MAX_DRAWN: usize = 5_000;
/// Most work spent measuring which elements lie inside which (the
/// vertices of every pair whose boxes nest, summed; about a second), so a
/// file of thousands of concentric rings, or of many shapes inside one
/// huge outline, cannot take minutes.
pub const MAX_NESTING_WORK: usize = 4_000_000;
/// How deep `<use>` references may chain (a reference cycle stops here).
const MAX_USE_DEPTH: u8 = 8;

/// What inherits down the tree: transform, fill rule, paper fill.
#[derive(Clone, Copy)]
struct Inherited {
    transform: [f64; 6],
    nonzero: bool,
    paper: bool,
    uses: u8,
    /// Reached through `<use>`: a `<symbol>` is drawn then.
    used: bool,
}

/// A presentation property of `node`: its `style` attribute's declaration
/// if any (it wins), else the attribute of that name.
fn property<'a>(node: &roxmltree::Node<'a, '_>, name: &str) -> Option<&'a str> {
    let from_style = node.attribute("style").and_then(|style| {
        style.split(';').find_map(|decl| {
            let (k, v) = decl.split_once(':')?;
            (k.trim() == name).then(|| v.trim())
        })
    });
    from_style.or_else(|| node.attribute(name)).map(str::trim)
}

/// Whether a `fill` value is paper white (`white`, `#fff`, `rgb(255,…)`,
/// near-white); `None` when it does not say (inherit).
fn paper_fill(v: &str) -> Option<bool> {
    if v == "inherit" {
        return None;
    }
    Some(match svgtypes::Paint::from_str(v) {
        Ok(svgtypes::Paint::Color(c)) => c.alpha > 0 && c.red.min(c.green).min(c.blue) >= 245,
        _ => false,
    })
}

/// Every drawn element of an SVG document, in document order, with
/// `transform`s (under `root`), `fill-rule` and `fill` inherited as SVG
/// does; `<use>` references drawn where they are used (also `<symbol>`s);
/// definitions, masks, text and `display: none` parts skipped. Curves are
/// flattened to within `tolerance` after the transforms.
pub fn document_elements(text: &str, tolerance: f64, root: [f64; 6]) -> Result<Vec<Element>> {
    check_depth(text)?;
    let doc = roxmltree::Document::parse(text)
        .map_err(|e| Error::input(format!("the SVG file is not valid XML: {e}")))?;
    let ids: std::collections::HashMap<&str, roxmltree::Node> = doc
        .descendants()
        .filter_map(|n| Some((n.attribute("id")?, n)))
        .collect();
    let mut b = RingBuilder::new(tolerance);
    // (first ring, nonzero, paper) of each element; its rings end where the next begin.
    let mut spans: Vec<(usize, bool, bool)> = vec![];
    // Depth-first with an explicit stack, never by recursion.
    let top = Inherited {
        transform: root,
        nonzero: false,
        paper: false,
        uses: 0,
        used: false,
    };
    let mut stack = vec![(doc.root_element(), top)];
    let mut seen = 0usize;
    while let Some((node, parent)) = stack.pop() {
        seen += 1;
        if seen > MAX_ELEMENTS {
            return Err(Error::limit(format!(
                "the SVG file has more than {MAX_ELEMENTS} elements (the SVG element limit)"
            )));
        }
        if property(&node, "display") == Some("none") {
            continue;
        }
        let mut here = parent;
        if let Some(s) = node.attribute("transform") {
            let m: svgtypes::Transform = s
                .parse()
                .map_err(|e| Error::input(format!("an SVG transform is not valid: {e}")))?;
            here.transform = compose(parent.transform, [m.a, m.b, m.c, m.d, m.e, m.f]);
        }
        match property(&node, "fill-rule") {
            Some("nonzero") => here.nonzero = true,
            Some("evenodd") => here.nonzero = false,
            _ => {}
        }
        if let Some(p) = property(&node, "fill").and_then(paper_fill) {
            here.paper = p;
        }
        b.transform = here.transform;
        let num = |name: &str| -> f64 {
            node.attribute(name)
                .and_then(|v| v.parse::<svgtypes::Number>().ok())
                .map_or(0.0, |n| n.0)
        };
        let first = b.rings.len();
        let mut drawn = true;
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
            "use" => {
                let href = node
                    .attribute("href")
                    .or_else(|| node.attribute(("http://www.w3.org/1999/xlink", "href")));
                let target = href
                    .and_then(|h| h.strip_prefix('#'))
                    .and_then(|id| ids.get(id));
                if let Some(&target) = target {
                    if here.uses >= MAX_USE_DEPTH {
                        return Err(Error::limit(format!(
                            "the SVG file's <use> references chain more than {MAX_USE_DEPTH} deep \
                             (or in a cycle; the SVG reference limit)"
                        )));
                    }
                    let mut inner = here;
                    inner.transform =
                        compose(here.transform, [1.0, 0.0, 0.0, 1.0, num("x"), num("y")]);
                    inner.uses += 1;
                    inner.used = true;
                    stack.push((target, inner));
                }
                continue;
            }
            "symbol" if here.used => drawn = false,
            // Not drawn: definitions, masks, text.
            "defs" | "clipPath" | "mask" | "symbol" | "pattern" | "marker" | "text" | "style" => {
                continue
            }
            _ => drawn = false,
        }
        if drawn {
            b.close();
            if b.rings.len() > first {
                spans.push((first, here.nonzero, here.paper));
            }
        }
        // Children in reverse so they are visited in document order.
        let kids: Vec<_> = node.children().filter(|n| n.is_element()).collect();
        stack.extend(kids.into_iter().rev().map(|k| (k, here)));
    }
    let mut rings = b.finish()?;
    let mut out = Vec::with_capacity(spans.len());
    for &(first, nonzero, paper) in spans.iter().rev() {
        out.push(Element {
            rings: rings.split_off(first),
            nonzero,
            paper,
        });
    }
    out.reverse();
    Ok(out)
}

/// The start shapes an SVG document draws, as polygons with holes: each
/// element's region (its fill rule), then the ink the drawing shows.
/// Elements inside another element are holes in it, inside a hole ink
/// again (the nesting of the issue's "nested paths become holes", across
/// elements as within one); elements that only overlap are one shape
/// (their union); white-filled elements cut what was drawn before them (a
/// white letter on a black disc) and are paper under what comes after (a
/// white background). `frame` (min, max):
/// the drawing is scaled, keeping its proportions, and centred to fit it,
/// and curves are flattened to `tolerance` at that scale (a 24-unit icon
/// and a 2,000-unit poster give the same tangle).
pub fn document_polygons(
    text: &str,
    tolerance: f64,
    frame: Option<(DVec2, DVec2)>,
) -> Result<Vec<Polygon>> {
    let identity = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0];
    let mut elements = document_elements(text, tolerance, identity)?;
    if let Some(frame) = frame {
        // Flattened again at the fitted scale, then fitted once more: the
        // finer polyline reaches further out along the curves than the
        // first one, whose box set the scale.
        if let Some(fit) = fit_into(&elements, frame) {
            elements = document_elements(text, tolerance, fit)?;
            if let Some([s, _, _, _, e, f]) = fit_into(&elements, frame) {
                for p in elements
                    .iter_mut()
                    .flat_map(|e| e.rings.iter_mut().flatten())
                {
                    *p = *p * s + DVec2::new(e, f);
                }
            }
        }
    }
    let polys = ink_of(&elements)?;
    if polys.is_empty() {
        return Err(Error::input(
            "the SVG file has no closed shape with area (path, rect, circle, ellipse or polygon)",
        ));
    }
    Ok(polys)
}

/// The map (uniform scale, then offset) that fits the box of the ink
/// elements' points into `frame`, centred; `None` when they have no extent.
fn fit_into(elements: &[Element], (lo, hi): (DVec2, DVec2)) -> Option<[f64; 6]> {
    let ink = elements.iter().filter(|e| !e.paper);
    let (mut blo, mut bhi) = (DVec2::splat(f64::INFINITY), DVec2::splat(f64::NEG_INFINITY));
    for p in ink.flat_map(|e| e.rings.iter().flatten()) {
        blo = blo.min(*p);
        bhi = bhi.max(*p);
    }
    let (size, span) = (hi - lo, bhi - blo);
    let scale = [size.x / span.x, size.y / span.y]
        .into_iter()
        .filter(|s| s.is_finite() && *s > 0.0)
        .fold(f64::INFINITY, f64::min);
    scale.is_finite().then(|| {
        let offset = lo + (size - span * scale) * 0.5 - blo * scale;
        [scale, 0.0, 0.0, scale, offset.x, offset.y]
    })
}

/// The ink of drawn elements (see [`document_polygons`]).
fn ink_of(elements: &[Element]) -> Result<Vec<Polygon>> {
    if elements.len() > MAX_DRAWN {
        return Err(Error::limit(format!(
            "the SVG file draws {} shapes; at most {MAX_DRAWN} (the SVG shape limit)",
            elements.len()
        )));
    }
    // (polygons, area, box, paper) of each element with area, in document order.
    let mut regions = vec![];
    for e in elements {
        let made = if e.nonzero {
            Polygon::new_nonzero(e.rings.clone())
        } else {
            Polygon::new(e.rings.clone())
        };
        let made = made.ok_or_else(|| {
            Error::input(format!(
                "SVG coordinates must be finite numbers within ±{}",
                super::polygon::MAX_COORD
            ))
        })?;
        if !made.is_empty() {
            let area: f64 = made.iter().map(Polygon::area).sum();
            let (lo, hi) = Polygon::bbox_all(&made);
            regions.push((made, area, lo, hi, e.paper));
        }
    }
    let boxed = |(lo, hi): (DVec2, DVec2), (ilo, ihi): (DVec2, DVec2)| {
        lo.cmple(ilo).all() && hi.cmpge(ihi).all()
    };
    let overlap = |(lo, hi): (DVec2, DVec2), (olo, ohi): (DVec2, DVec2)| {
        lo.cmple(ohi).all() && olo.cmple(hi).all()
    };
    let ink_at: Vec<usize> = (0..regions.len()).filter(|&k| !regions[k].4).collect();
    // Which ink element contains which (measured exactly where the boxes
    // nest). Of two equal regions the earlier contains the later, and the
    // later is a duplicate, dropped (a path drawn twice is one shape).
    let same = |a: f64, b: f64| (a - b).abs() <= 1e-6 * a.max(b);
    let mut work = 0usize;
    let mut contains = vec![];
    for &j in &ink_at {
        let (rj, aj, loj, hij, _) = &regions[j];
        for &i in &ink_at {
            let (ri, ai, loi, hii, _) = &regions[i];
            let larger = if same(*ai, *aj) { i < j } else { ai > aj };
            if i == j || !larger || !boxed((*loi, *hii), (*loj, *hij)) {
                continue;
            }
            work += rj.iter().chain(ri).map(Polygon::vertices).sum::<usize>();
            if work > MAX_NESTING_WORK {
                return Err(Error::limit(format!(
                    "the SVG file's shapes lie one inside the other too often to sort out (more \
                     than {MAX_NESTING_WORK} vertices compared; the SVG nesting limit)"
                )));
            }
            let outside: f64 = rj
                .iter()
                .flat_map(|p| p.difference_all(ri))
                .map(|p| p.area())
                .sum();
            if outside <= 1e-6 * aj {
                contains.push((i, j));
            }
        }
    }
    let mut duplicate = vec![false; regions.len()];
    for &(i, j) in &contains {
        duplicate[j] |= same(regions[i].1, regions[j].1);
    }
    // Depth: how many ink elements contain each one; even depths are ink,
    // odd ones holes, layer by layer from the outside in.
    let mut depth = vec![0usize; regions.len()];
    for &(i, j) in &contains {
        if !duplicate[i] {
            depth[j] += 1;
        }
    }
    let deepest = depth.iter().copied().max().unwrap_or(0);
    let mut ink: Vec<Polygon> = vec![];
    for d in 0..=deepest {
        let layer: Vec<Polygon> = ink_at
            .iter()
            .filter(|&&k| !duplicate[k] && depth[k] == d)
            .flat_map(|&k| regions[k].0.iter().cloned())
            .collect();
        if layer.is_empty() {
            continue;
        }
        ink = if d % 2 == 0 {
            ink.extend(layer);
            Polygon::union_all(&ink)
        } else {
            ink.iter().flat_map(|p| p.difference_all(&layer)).collect()
        };
    }
    // White paints over what was drawn before it (painter's order): a white
    // element after some ink it overlaps cuts it; one before all the ink it
    // overlaps (a white background) is paper under the drawing.
    let cuts: Vec<Polygon> = (0..regions.len())
        .filter(|&p| {
            let (_, _, lo, hi, paper) = &regions[p];
            *paper
                && ink_at
                    .iter()
                    .any(|&k| k < p && overlap((*lo, *hi), (regions[k].2, regions[k].3)))
        })
        .flat_map(|p| regions[p].0.iter().cloned())
        .collect();
    if !cuts.is_empty() {
        ink = ink.iter().flat_map(|p| p.difference_all(&cuts)).collect();
    }
    Ok(ink)
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
    use crate::tangle::geom::polygon::Polygon;

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

    const ID: [f64; 6] = [1.0, 0.0, 0.0, 1.0, 0.0, 0.0];

    fn svg(body: &str) -> String {
        format!(
            r#"<svg xmlns="http://www.w3.org/2000/svg" xmlns:xlink="http://www.w3.org/1999/xlink">{body}</svg>"#
        )
    }

    /// Total area and number of rings of a document's start shapes.
    fn ink(body: &str) -> (f64, usize) {
        let p = document_polygons(&svg(body), 0.01, None).unwrap();
        (
            p.iter().map(Polygon::area).sum(),
            p.iter().map(|q| q.rings.len()).sum(),
        )
    }

    #[test]
    fn documents_apply_transforms_and_skip_defs() {
        let doc = svg(r#"
          <defs><rect width="99" height="99"/></defs>
          <g transform="translate(100 0) scale(2)">
            <rect x="0" y="0" width="10" height="5"/>
            <circle cx="30" cy="30" r="5"/>
          </g>
          <polygon points="0,0 4,0 4,4"/>
          <g style="display: none"><rect width="50" height="50"/></g>"#);
        let e = document_elements(&doc, 0.01, ID).unwrap();
        assert_eq!(e.len(), 3);
        let (lo, hi) = Polygon {
            rings: e[0].rings.clone(),
        }
        .bbox();
        assert_eq!((lo, hi), (DVec2::new(100.0, 0.0), DVec2::new(120.0, 10.0)));
        let a = area(e[1].rings.clone());
        assert!((a - std::f64::consts::PI * 100.0).abs() < 1.0, "{a}");
        assert!(document_polygons("<svg", 0.1, None).is_err());
        assert!(document_polygons(&svg(""), 0.1, None).is_err());
    }

    #[test]
    fn overlapping_elements_are_one_shape_and_nested_ones_holes() {
        // Two squares overlapping by 5×10: their union, not a lens-shaped hole.
        let (a, rings) =
            ink(r#"<rect width="10" height="10"/><rect x="5" width="10" height="10"/>"#);
        assert!((a - 150.0).abs() < 1e-6 && rings == 1, "{a} {rings}");
        // Nested elements alternate: ink, hole, ink again.
        let (a, rings) = ink(
            r#"<rect width="100" height="100"/><rect x="20" y="20" width="60" height="60"/>
               <rect x="40" y="40" width="20" height="20"/>"#,
        );
        assert!((a - (10000.0 - 3600.0 + 400.0)).abs() < 1e-6, "{a}");
        assert_eq!(rings, 3);
        // A dot in the counter of a ring is not inside the ring's region: ink.
        let (a, _) = ink(
            r#"<path d="M0 0H30V30H0Z M10 10H20V20H10Z"/><rect x="12" y="12" width="6" height="6"/>"#,
        );
        assert!((a - (900.0 - 100.0 + 36.0)).abs() < 1e-6, "{a}");
        // A path drawn twice is one shape, not a shape with itself as a hole.
        let (a, _) = ink(r#"<rect width="10" height="10"/><rect width="10" height="10"/>"#);
        assert!((a - 100.0).abs() < 1e-6, "{a}");
    }

    #[test]
    fn white_fills_cut_holes_and_a_white_background_is_paper() {
        let (a, rings) = ink(r##"<rect width="200" height="200" fill="#ffffff"/>
               <circle cx="100" cy="100" r="50" style="fill: #222"/>
               <rect x="90" y="70" width="20" height="60" fill="white"/>"##);
        let disc = std::f64::consts::PI * 2500.0;
        assert!((a - (disc - 1200.0)).abs() < 1.0, "{a}");
        assert_eq!(rings, 2, "the disc and the white bar as its hole");
        // A white stripe drawn over part of a disc cuts it (painter's order),
        // though it is not inside it.
        let (a, _) = ink(
            r#"<rect width="100" height="100"/><rect x="40" y="-10" width="20" height="120" fill="white"/>"#,
        );
        assert!((a - 8000.0).abs() < 1e-6, "{a}");
        // Inherited from a group, overridden by a child.
        let e = document_elements(
            &svg(r#"<g fill="white"><rect width="1" height="1"/><rect width="1" height="1" fill="red"/></g>"#),
            0.01,
            ID,
        )
        .unwrap();
        assert_eq!((e[0].paper, e[1].paper), (true, false));
    }

    #[test]
    fn fill_rule_nonzero_is_honoured_and_unsaid_means_nested_subpaths_are_holes() {
        // Both subpaths wind the same way.
        let d = "M0 0H10V10H0Z M2 2H8V8H2Z";
        let (a, _) = ink(&format!(r#"<path d="{d}"/>"#));
        assert!((a - 64.0).abs() < 1e-9, "{a}");
        let (a, _) = ink(&format!(r#"<path d="{d}" fill-rule="evenodd"/>"#));
        assert!((a - 64.0).abs() < 1e-9, "{a}");
        let (a, _) = ink(&format!(
            r#"<g style="fill-rule:nonzero"><path d="{d}"/></g>"#
        ));
        assert!((a - 100.0).abs() < 1e-9, "{a}");
        // Nonzero with the inner subpath the other way round: a hole.
        let (a, _) = ink(r#"<path fill-rule="nonzero" d="M0 0H10V10H0Z M2 2V8H8V2Z"/>"#);
        assert!((a - 64.0).abs() < 1e-9, "{a}");
    }

    #[test]
    fn use_draws_what_it_references_and_a_cycle_is_an_error() {
        let e = document_elements(
            &svg(r##"<defs><symbol id="s"><rect width="2" height="2"/></symbol></defs>
                  <use xlink:href="#s" x="10" y="5"/><use href="#s" x="20"/><use href="#nothing"/>"##),
            0.01,
            ID,
        )
        .unwrap();
        assert_eq!(e.len(), 2);
        let lo = |k: usize| {
            e[k].rings[0]
                .iter()
                .fold(DVec2::splat(1e9), |a, &p| a.min(p))
        };
        assert_eq!(
            (lo(0), lo(1)),
            (DVec2::new(10.0, 5.0), DVec2::new(20.0, 0.0))
        );
        let cycle = svg(r##"<g id="a"><rect width="1" height="1"/><use href="#a" x="1"/></g>"##);
        let err = document_polygons(&cycle, 0.01, None).unwrap_err();
        assert!(err.to_string().contains("reference limit"), "{err}");
    }

    #[test]
    fn a_frame_fits_the_drawing_at_any_units_with_smooth_curves() {
        let icon = r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 24 24"><circle cx="12" cy="12" r="10"/></svg>"#;
        let frame = (DVec2::ZERO, DVec2::new(800.0, 600.0));
        let p = document_polygons(icon, 0.05, Some(frame)).unwrap();
        let (lo, hi) = Polygon::bbox_all(&p);
        assert!(
            (lo - DVec2::new(100.0, 0.0)).abs().max_element() < 1e-9,
            "{lo}"
        );
        assert!(
            (hi - DVec2::new(700.0, 600.0)).abs().max_element() < 1e-9,
            "{hi}"
        );
        // Flattened at the fitted scale: within 0.05 of the true circle.
        let c = DVec2::new(400.0, 300.0);
        let a = p[0].area();
        assert!(
            (a - std::f64::consts::PI * 90_000.0).abs() < 0.05 * 2.0 * std::f64::consts::PI * 300.0,
            "{a}"
        );
        for w in p[0].rings[0].windows(2) {
            let mid = ((w[0] + w[1]) * 0.5 - c).length();
            assert!(
                300.0 - mid < 0.06,
                "a chord {} inside the circle",
                300.0 - mid
            );
        }
    }

    #[test]
    fn many_shapes_inside_one_huge_outline_are_refused_quickly() {
        // A 100,000-point outline around 400 dots: every dot's nesting would be a
        // boolean with the whole outline (minutes); the work cap stops it first.
        let n = 100_000;
        let ring: String = (0..n)
            .map(|k| {
                let t = std::f64::consts::TAU * k as f64 / n as f64;
                format!(
                    "{}{:.4} {:.4} ",
                    if k == 0 { "M" } else { "L" },
                    500.0 + 500.0 * t.cos(),
                    500.0 + 500.0 * t.sin()
                )
            })
            .collect();
        let dots: String = (0..400)
            .map(|k| {
                format!(
                    r#"<circle cx="{}" cy="{}" r="3"/>"#,
                    300 + (k % 20) * 20,
                    300 + (k / 20) * 20
                )
            })
            .collect();
        let err = document_polygons(&svg(&format!(r#"<path d="{ring}Z"/>{dots}"#)), 0.05, None)
            .unwrap_err();
        assert!(err.to_string().contains("nesting limit"), "{err}");
    }

    #[test]
    fn deep_nesting_is_refused_before_parsing_natively_without_overflow() {
        // 12,000 levels overflowed the CLI's stack in roxmltree's parser.
        for (open, close) in [("<g>", "</g>"), ("<g transform=\"scale(1)\">", "</g>")] {
            let doc = format!(
                "<svg xmlns=\"http://www.w3.org/2000/svg\">{}<rect width=\"1\" height=\"1\"/>{}</svg>",
                open.repeat(12_000),
                close.repeat(12_000)
            );
            let e = document_elements(&doc, 0.1, [1.0, 0.0, 0.0, 1.0, 0.0, 0.0]).unwrap_err();
            assert_eq!(e.kind(), "limit");
            assert!(e.to_string().contains("more than 256 deep"), "{e}");
        }
        // At the limit it parses; comments, CDATA, quotes and self-closing
        // tags do not count as levels.
        let ok = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\"><!-- <g><g> --><![CDATA[<g>]]>{}<rect title=\"a>b\" width=\"1\" height=\"1\"/><path d=\"M0 0L1 0L1 1Z\"/>{}</svg>",
            "<g>".repeat(MAX_DEPTH - 1),
            "</g>".repeat(MAX_DEPTH - 1)
        );
        check_depth(&ok).unwrap();
        assert!(check_depth(&format!("<svg>{}", "<g>".repeat(MAX_DEPTH))).is_err());
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
