//! Pen-and-ink output of a tangle: SVG (one `<path>` per shape, even-odd
//! fill so holes stay holes) and PNG (anti-aliased with tiny-skia: black
//! strokes on paper white, stroke width a setting).
use super::{Ink, Shape};
use crate::core::error::{Error, Result};
use crate::raster::{encode_png, Rgba8Image};
use crate::tangle::geom::polygon::Polygon;
use glam::DVec2;
use std::fmt::Write;

/// Paper colour.
const PAPER: [u8; 3] = [255, 255, 255];

/// The largest PNG side: every image the core makes keeps to
/// [`crate::core::limits::MAX_IMAGE_SIDE`]. (It was 8192 here, so an export
/// wider or taller than 4096 px drew an up to 8192² pixmap, 256 MB, and
/// was then refused by the image's own limit.)
pub const MAX_PNG_SIDE: u32 = crate::core::limits::MAX_IMAGE_SIDE;

/// Grey of a fill tone (0 = paper, 1 = black).
fn grey(tone: f32) -> u8 {
    (255.0 * (1.0 - tone.clamp(0.0, 1.0))).round() as u8
}

/// The bounding box of shapes, padded by `pad`.
pub fn bounds(shapes: &[&Shape], pad: f64) -> (DVec2, DVec2) {
    let mut lo = DVec2::splat(f64::INFINITY);
    let mut hi = DVec2::splat(f64::NEG_INFINITY);
    for s in shapes {
        let (a, b) = s.poly.bbox();
        lo = lo.min(a);
        hi = hi.max(b);
    }
    if !lo.is_finite() || !hi.is_finite() {
        return (DVec2::ZERO, DVec2::splat(1.0));
    }
    (lo - DVec2::splat(pad), hi + DVec2::splat(pad))
}

fn path_data(poly: &Polygon, out: &mut String) {
    for ring in &poly.rings {
        for (k, p) in ring.iter().enumerate() {
            out.push_str(if k == 0 { "M" } else { " L" });
            write_num(out, p.x);
            out.push(' ');
            write_num(out, p.y);
        }
        out.push_str(" Z ");
    }
}

/// A coordinate with 2 decimals, no trailing zeros (written by hand: the
/// float formatter was a sixth of a large tangle's time).
fn num(v: f64) -> String {
    let mut s = String::new();
    write_num(&mut s, v);
    s
}

fn write_num(out: &mut String, v: f64) {
    let c = (v * 100.0).round();
    if !c.is_finite() || c.abs() >= 9.0e15 {
        let _ = write!(out, "{v}");
        return;
    }
    let c = c as i64;
    if c < 0 {
        out.push('-');
    }
    let a = c.unsigned_abs();
    let _ = write!(out, "{}", a / 100);
    let f = a % 100;
    if f != 0 {
        if f.is_multiple_of(10) {
            let _ = write!(out, ".{}", f / 10);
        } else {
            let _ = write!(out, ".{f:02}");
        }
    }
}

/// The tangle as an SVG document (y down, drawing units).
pub fn svg(shapes: &[&Shape], stroke_width: f64) -> String {
    let (lo, hi) = bounds(shapes, stroke_width.max(0.0) + 2.0);
    let size = hi - lo;
    let mut out = String::new();
    let _ = writeln!(
        out,
        r#"<svg xmlns="http://www.w3.org/2000/svg" viewBox="{} {} {} {}" width="{}" height="{}">"#,
        num(lo.x),
        num(lo.y),
        num(size.x),
        num(size.y),
        num(size.x),
        num(size.y)
    );
    let _ = writeln!(
        out,
        r#"<rect x="{}" y="{}" width="{}" height="{}" fill="rgb({},{},{})"/>"#,
        num(lo.x),
        num(lo.y),
        num(size.x),
        num(size.y),
        PAPER[0],
        PAPER[1],
        PAPER[2]
    );
    let sw = num(stroke_width.max(0.0));
    for s in shapes {
        let mut d = String::new();
        path_data(&s.poly, &mut d);
        let fill = if s.ink.mark {
            "#000".to_string()
        } else if s.ink.fill > 0.0 {
            let g = grey(s.ink.fill);
            format!("rgb({g},{g},{g})")
        } else {
            "none".to_string()
        };
        let stroke = if s.ink.mark {
            "none"
        } else if s.ink.white_lines {
            "#fff"
        } else {
            "#000"
        };
        let _ = writeln!(
            out,
            r#"<path d="{}" fill="{fill}" fill-rule="evenodd" stroke="{stroke}" stroke-width="{sw}" stroke-linejoin="round"/>"#,
            d.trim_end()
        );
    }
    out.push_str("</svg>\n");
    out
}

/// What the PNG export draws: the final shapes' rings as f32 points (the
/// `tangle` answer's `points`, so the browser, which holds the answer,
/// draws the same picture as the CLI) and each shape's ink. The Tangle
/// module never draws PNG in the browser: the page sends its drawing to
/// the small `tangle-png` module ([`crate::tangle::api::TanglePngRequest`]),
/// loaded on the first PNG export, so the Tangle module links no
/// rasteriser or PNG encoder.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Drawing {
    /// x, y of every ring's points, ring after ring, shape after shape.
    pub points: Vec<f32>,
    /// Points per ring.
    pub rings: Vec<u32>,
    /// Rings per shape (its first ring is the outer one) and its ink.
    pub shapes: Vec<(u32, Ink)>,
}

/// At most this many points in a drawing sent for a PNG (8 bytes each):
/// the largest tangle the limits allow has far fewer.
pub const MAX_DRAWING_POINTS: usize = 1 << 24;

impl Drawing {
    /// The drawing of `shapes`, their points rounded to f32 as the `tangle`
    /// answer sends them.
    pub fn of(shapes: &[&Shape]) -> Drawing {
        let mut d = Drawing::default();
        for s in shapes {
            for ring in &s.poly.rings {
                d.rings.push(ring.len() as u32);
                d.points
                    .extend(ring.iter().flat_map(|p| [p.x as f32, p.y as f32]));
            }
            d.shapes.push((s.poly.rings.len() as u32, s.ink));
        }
        d
    }

    /// Whether its parts fit together: every shape's rings and every ring's
    /// points present, no point more, every coordinate and fill finite.
    /// Errors name the request field at fault (`points`, `rings`, `shapes`,
    /// `fill`).
    pub fn check(&self) -> Result<()> {
        if self.points.len() / 2 > MAX_DRAWING_POINTS {
            return Err(Error::limit(format!(
                "{} points; a drawing has at most {MAX_DRAWING_POINTS}",
                self.points.len() / 2
            ))
            .at("points"));
        }
        let rings: u64 = self.shapes.iter().map(|&(n, _)| n as u64).sum();
        if rings != self.rings.len() as u64 {
            return Err(Error::input(format!(
                "the shapes have {rings} rings but {} ring lengths were sent",
                self.rings.len()
            ))
            .at("rings"));
        }
        let points: u64 = self.rings.iter().map(|&n| n as u64).sum();
        if 2 * points != self.points.len() as u64 {
            return Err(Error::input(format!(
                "the rings have {points} points but {} coordinates were sent",
                self.points.len()
            ))
            .at("points"));
        }
        if let Some(i) = self.points.iter().position(|v| !v.is_finite()) {
            return Err(
                Error::input(format!("coordinate {i} is not a finite number")).at("points"),
            );
        }
        if let Some(i) = self
            .shapes
            .iter()
            .position(|(_, ink)| !ink.fill.is_finite())
        {
            return Err(
                Error::input(format!("shape {i}'s fill is not a finite number")).at("fill"),
            );
        }
        Ok(())
    }

    /// The box around its points padded by `pad` (a unit box when empty).
    fn bounds(&self, pad: f64) -> (DVec2, DVec2) {
        let mut lo = DVec2::splat(f64::INFINITY);
        let mut hi = DVec2::splat(f64::NEG_INFINITY);
        for p in self.points.chunks_exact(2) {
            let p = DVec2::new(p[0] as f64, p[1] as f64);
            lo = lo.min(p);
            hi = hi.max(p);
        }
        if !lo.is_finite() || !hi.is_finite() {
            return (DVec2::ZERO, DVec2::splat(1.0));
        }
        (lo - DVec2::splat(pad), hi + DVec2::splat(pad))
    }
}

/// The drawing as a PNG `width` pixels wide (height to scale).
pub fn png(d: &Drawing, width: u32, stroke_width: f64) -> Result<Vec<u8>> {
    let img = raster(d, width, stroke_width)?;
    encode_png(&img)
}

/// The drawing rasterised: white paper, black ink, anti-aliased.
pub fn raster(d: &Drawing, width: u32, stroke_width: f64) -> Result<Rgba8Image> {
    use tiny_skia::{FillRule, Paint, PathBuilder, Pixmap, Stroke, Transform};
    d.check()?;
    let (lo, hi) = d.bounds(stroke_width.max(0.0) + 2.0);
    let size = hi - lo;
    if !(1..=MAX_PNG_SIDE).contains(&width) {
        return Err(Error::limit(format!(
            "a PNG is 1 to {MAX_PNG_SIDE} pixels wide (asked for {width})"
        ))
        .at("png_width"));
    }
    let scale = width as f64 / size.x.max(1e-9);
    // The height the picture needs at this width, checked before anything
    // is drawn (clamping it cut a tall tangle's bottom off).
    let height = (size.y * scale).ceil().max(1.0);
    if height > MAX_PNG_SIDE as f64 {
        let fits = ((MAX_PNG_SIDE as f64 * size.x / size.y).floor() as u32).max(1);
        return Err(Error::limit(format!(
            "at {width} px wide this PNG would be {height} px tall, over the {MAX_PNG_SIDE} px \
             limit of an image; at most {fits} px wide fits"
        ))
        .at("png_width"));
    }
    let height = height as u32;
    let mut pm = Pixmap::new(width, height)
        .ok_or_else(|| Error::limit(format!("a {width}×{height} image cannot be made")))?;
    pm.fill(tiny_skia::Color::from_rgba8(
        PAPER[0], PAPER[1], PAPER[2], 255,
    ));
    let t = Transform::from_row(
        scale as f32,
        0.0,
        0.0,
        scale as f32,
        (-lo.x * scale) as f32,
        (-lo.y * scale) as f32,
    );
    let stroke = Stroke {
        width: stroke_width.max(0.0) as f32,
        line_join: tiny_skia::LineJoin::Round,
        ..Default::default()
    };
    let (mut ring, mut at) = (0, 0);
    for &(n, ink) in &d.shapes {
        let mut pb = PathBuilder::new();
        for &len in &d.rings[ring..ring + n as usize] {
            let pts = &d.points[at..at + 2 * len as usize];
            for (k, p) in pts.chunks_exact(2).enumerate() {
                if k == 0 {
                    pb.move_to(p[0], p[1]);
                } else {
                    pb.line_to(p[0], p[1]);
                }
            }
            pb.close();
            at += 2 * len as usize;
        }
        ring += n as usize;
        let Some(path) = pb.finish() else { continue };
        let mut paint = Paint {
            anti_alias: true,
            ..Default::default()
        };
        if ink.mark || ink.fill > 0.0 {
            let g = if ink.mark { 0 } else { grey(ink.fill) };
            paint.set_color_rgba8(g, g, g, 255);
            pm.fill_path(&path, &paint, FillRule::EvenOdd, t, None);
        }
        if !ink.mark && stroke.width > 0.0 {
            let g = if ink.white_lines { 255 } else { 0 };
            paint.set_color_rgba8(g, g, g, 255);
            pm.stroke_path(&path, &paint, &stroke, t, None);
        }
    }
    // Everything is opaque over the paper, so premultiplied = straight.
    Rgba8Image::from_raw(width, height, pm.take())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    fn shape(poly: Polygon, ink: Ink) -> Shape {
        Shape {
            tag: 0,
            group: 0,
            id: 0,
            poly: Arc::new(poly),
            dir: DVec2::Y,
            ink,
        }
    }

    #[test]
    fn svg_has_one_path_per_shape_with_even_odd_holes() {
        let ring = Polygon::rect(DVec2::ZERO, DVec2::splat(10.0))
            .difference(&Polygon::rect(DVec2::splat(3.0), DVec2::splat(6.0)))
            .remove(0);
        let a = shape(ring, Ink::default());
        let b = shape(
            Polygon::circle(DVec2::splat(20.0), 2.0, 8),
            Ink {
                mark: true,
                ..Default::default()
            },
        );
        let s = svg(&[&a, &b], 1.0);
        assert_eq!(s.matches("<path ").count(), 2);
        assert_eq!(s.matches(r#"fill-rule="evenodd""#).count(), 2);
        // The ring's path has two subpaths (outer + hole).
        let first = s.lines().find(|l| l.starts_with("<path")).unwrap();
        assert_eq!(first.matches('M').count(), 2, "{first}");
    }

    #[test]
    fn numbers_have_two_decimals_at_most() {
        for (v, want) in [
            (0.0, "0"),
            (-0.001, "0"),
            (1.5, "1.5"),
            (-2.25, "-2.25"),
            (3.105, "3.11"),
            (10.0, "10"),
            (-0.07, "-0.07"),
            (123456.789, "123456.79"),
        ] {
            assert_eq!(num(v), want, "{v}");
        }
    }

    #[test]
    fn png_draws_black_lines_on_white_paper() {
        let a = shape(
            Polygon::rect(DVec2::ZERO, DVec2::splat(100.0)),
            Ink::default(),
        );
        let img = raster(&Drawing::of(&[&a]), 208, 2.0).unwrap();
        assert_eq!(img.width, 208);
        let (w, h) = (img.width, img.height);
        assert_eq!(
            img.get(w / 2, h / 2),
            [255, 255, 255, 255],
            "inside is paper"
        );
        // The outline at x = 0 is 2 units + 1 px of padding in: (2+2)·2 px.
        let edge = img.get(8, h / 2);
        assert!(edge[0] < 80, "the line is inked: {edge:?}");
        assert!(raster(&Drawing::of(&[&a]), 0, 1.0).is_err());
    }

    /// A tall, narrow tangle is refused, before a pixmap is made, at a width
    /// whose height would be over the image limit; the error names the width
    /// and says what fits, and that width draws the whole picture.
    #[test]
    fn a_png_taller_than_the_limit_is_refused_naming_its_width() {
        let tall = shape(
            Polygon::rect(DVec2::ZERO, DVec2::new(100.0, 2000.0)),
            Ink::default(),
        );
        let d = Drawing::of(&[&tall]);
        let e = raster(&d, 400, 1.0).unwrap_err();
        assert_eq!(e.kind(), "limit");
        assert_eq!(e.field(), Some("png_width"));
        let fits: u32 = e
            .to_string()
            .split("at most ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .and_then(|n| n.parse().ok())
            .unwrap_or_else(|| panic!("{e}"));
        let img = raster(&d, fits, 1.0).unwrap();
        assert!(img.height <= MAX_PNG_SIDE, "{}", img.height);
        assert!(
            raster(&d, fits + 1, 1.0).is_err(),
            "{fits} px is the widest that fits"
        );
        // The bottom of the outline is inked: nothing was cut off.
        let bottom = (img.height - 12..img.height)
            .flat_map(|y| (0..img.width).map(move |x| (x, y)))
            .any(|(x, y)| img.get(x, y)[0] < 128);
        assert!(bottom, "the bottom edge is drawn");
        assert!(raster(&d, MAX_PNG_SIDE + 1, 1.0).is_err());
    }
}
