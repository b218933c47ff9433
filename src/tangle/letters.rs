//! Letter outlines for start shapes (`start text("WORD")`, the CLI's
//! `--text`, the browser's typed word): glyphs of DejaVu Sans Bold (a
//! subset shipped in `assets/fonts/`, licence beside it), flattened by
//! [`crate::tangle::geom::svg::RingBuilder`], laid out left to right on a baseline
//! with the font's advances, y down like the rest of a drawing.
use crate::core::error::{Error, Result};
use crate::tangle::geom::svg::RingBuilder;
use glam::DVec2;

static FONT: &[u8] = include_bytes!("../../assets/fonts/DejaVuSans-Bold-subset.ttf");

/// The most characters a word may have.
pub const MAX_LETTERS: usize = 64;

struct Pen<'a> {
    b: &'a mut RingBuilder,
    scale: f64,
    origin: DVec2,
}

impl Pen<'_> {
    fn p(&self, x: f32, y: f32) -> DVec2 {
        // Font units are y up; the drawing is y down.
        self.origin + DVec2::new(x as f64, -(y as f64)) * self.scale
    }
}

impl ttf_parser::OutlineBuilder for Pen<'_> {
    fn move_to(&mut self, x: f32, y: f32) {
        let p = self.p(x, y);
        self.b.move_to(p);
    }
    fn line_to(&mut self, x: f32, y: f32) {
        let p = self.p(x, y);
        self.b.line_to(p);
    }
    fn quad_to(&mut self, x1: f32, y1: f32, x: f32, y: f32) {
        let (c, p) = (self.p(x1, y1), self.p(x, y));
        self.b.quad_to(c, p);
    }
    fn curve_to(&mut self, x1: f32, y1: f32, x2: f32, y2: f32, x: f32, y: f32) {
        let (c1, c2, p) = (self.p(x1, y1), self.p(x2, y2), self.p(x, y));
        self.b.cubic_to(c1, c2, p);
    }
    fn close(&mut self) {
        self.b.close();
    }
}

/// The outlines of `text` with capitals `height` units tall, the first
/// letter's top-left near the origin. Rings in even-odd order (holes of
/// letters such as `A`, `O` are nested rings).
pub fn text_rings(text: &str, height: f64) -> Result<Vec<Vec<DVec2>>> {
    let n = text.chars().count();
    if n == 0 || text.trim().is_empty() {
        return Err(Error::input("type at least one letter"));
    }
    if n > MAX_LETTERS {
        return Err(Error::limit(format!(
            "{n} characters; a word has at most {MAX_LETTERS} (the letter limit)"
        )));
    }
    let max = super::MAX_START_SIDE;
    if !(height.is_finite() && height > 0.0 && height <= max) {
        return Err(Error::input(format!(
            "the letter height must be between 0 and {max} (got {height:.6e})"
        )));
    }
    let face = ttf_parser::Face::parse(FONT, 0)
        .map_err(|e| Error::input(format!("the shipped font cannot be read: {e}")))?;
    let cap = face.capital_height().filter(|&c| c > 0).unwrap_or(1493) as f64;
    let scale = height / cap;
    let mut b = RingBuilder::new(height / 400.0);
    let mut x = 0.0;
    let mut missing = vec![];
    for ch in text.chars() {
        let Some(g) = face.glyph_index(ch) else {
            missing.push(ch);
            continue;
        };
        let mut pen = Pen {
            b: &mut b,
            scale,
            origin: DVec2::new(x, height),
        };
        face.outline_glyph(g, &mut pen);
        x += face.glyph_hor_advance(g).unwrap_or(0) as f64 * scale;
    }
    if !missing.is_empty() {
        return Err(Error::input(format!(
            "the letter font has no {}: use A–Z, a–z, digits and Latin-1 letters",
            missing
                .iter()
                .map(|c| format!("'{c}'"))
                .collect::<Vec<_>>()
                .join(", ")
        )));
    }
    let rings = b.finish()?;
    if rings.is_empty() {
        return Err(Error::input("the text has no visible letter"));
    }
    Ok(rings)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tangle::geom::polygon::Polygon;

    #[test]
    fn letters_have_holes_and_the_asked_height() {
        let rings = text_rings("AO", 100.0).unwrap();
        let polys = Polygon::new(rings).unwrap();
        assert_eq!(polys.len(), 2, "one polygon per letter");
        assert!(
            polys.iter().all(|p| p.rings.len() == 2),
            "A and O have a hole each"
        );
        let (lo, hi) = polys[0].bbox();
        assert!(
            (hi.y - lo.y - 100.0).abs() < 2.0,
            "cap height: {}",
            hi.y - lo.y
        );
        assert!(lo.y.abs() < 2.0, "top at the origin: {}", lo.y);
        assert!(polys[1].bbox().0.x > polys[0].bbox().0.x, "left to right");
    }

    #[test]
    fn bad_words_are_refused_clearly() {
        assert!(text_rings("", 10.0).is_err());
        assert!(text_rings("   ", 10.0).is_err());
        let e = text_rings("A☃", 10.0).unwrap_err();
        assert!(e.to_string().contains("'☃'"), "{e}");
        assert!(text_rings(&"A".repeat(MAX_LETTERS + 1), 10.0).is_err());
        assert!(text_rings("A", f64::NAN).is_err());
    }
}
