//! Section 3.4: placement — the average field vector under each element picks
//! the nearest of the eight orientations, the element is coloured per pixel
//! or by the mode colour of its region, and pixels outside the mask are never
//! drawn.
use super::inputs::{Direction8, ElementSheet};
use crate::raster::Rgba8Image;
use serde::{Deserialize, Serialize};

/// How an element takes its colour from the colour map.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ElementColour {
    /// Every drawn pixel takes the colour map's colour at that pixel.
    Pixel,
    /// All drawn pixels take the most frequent colour-map colour under the
    /// element's drawn, in-mask pixels (ties: the smaller RGBA value).
    #[default]
    Region,
}

/// The orientation for an element whose cell is `side`² at (x, y): the
/// nearest direction to the mean of `field` over the cell's in-image pixels,
/// or `default` when that mean is (almost) zero.
pub fn orientation_at(
    field: &[[f32; 2]],
    width: u32,
    height: u32,
    x: i32,
    y: i32,
    side: u32,
    default: Direction8,
) -> Direction8 {
    let mut s = [0.0f64; 2];
    for yy in y.max(0)..(y + side as i32).min(height as i32) {
        for xx in x.max(0)..(x + side as i32).min(width as i32) {
            let v = field[yy as usize * width as usize + xx as usize];
            s[0] += v[0] as f64;
            s[1] += v[1] as f64;
        }
    }
    // `nearest` compares directions by dot product, which is the same as
    // normalising first and taking the closest unit vector.
    Direction8::nearest(s).unwrap_or(default)
}

/// Draw every element onto a copy of `source`. Returns the image and how many
/// elements drew at least one pixel.
#[allow(clippy::too_many_arguments)]
pub fn place(
    source: &Rgba8Image,
    mask: &[bool],
    sheet: &ElementSheet,
    positions: &[(i32, i32)],
    field: &[[f32; 2]],
    colour_map: &Rgba8Image,
    mode: ElementColour,
    default: Direction8,
) -> (Rgba8Image, usize) {
    let mut p = Placer::new(source);
    while !p.copy_source(source, usize::MAX / 2) {}
    let inputs = PlaceInputs {
        mask,
        sheet,
        positions,
        field,
        colour_map,
        mode,
        default,
    };
    while !p.run(&inputs, usize::MAX / 2) {}
    p.finish()
}

/// What [`Placer::run`] reads.
pub struct PlaceInputs<'a> {
    pub mask: &'a [bool],
    pub sheet: &'a ElementSheet,
    pub positions: &'a [(i32, i32)],
    pub field: &'a [[f32; 2]],
    pub colour_map: &'a Rgba8Image,
    pub mode: ElementColour,
    pub default: Direction8,
}

/// Placement as a resumable object: each [`Placer::run`] draws the next
/// elements, about `budget` pixel visits' worth, in position order.
pub struct Placer {
    out: Rgba8Image,
    /// Pixels of the source copied into `out` so far.
    copied: usize,
    next: usize,
    placed: usize,
    pixels: Vec<usize>,
    tally: Vec<([u8; 4], u32)>,
}

impl Placer {
    /// Start from a copy of `source`, made by [`Placer::copy_source`]
    /// (a bounded part per call) before the first [`Placer::run`].
    pub fn new(source: &Rgba8Image) -> Placer {
        Placer {
            // Zeroed pages cost nothing until the copy touches them.
            out: Rgba8Image::new(source.width, source.height),
            copied: 0,
            next: 0,
            placed: 0,
            pixels: Vec::new(),
            tally: Vec::new(),
        }
    }

    /// Copy about `budget` more pixels of `source` (the one given to
    /// [`Placer::new`]); `true` when the copy is complete.
    pub fn copy_source(&mut self, source: &Rgba8Image, budget: usize) -> bool {
        let n = self.out.pixel_count();
        let end = n.min(self.copied.saturating_add(budget.max(1)));
        self.out.data[4 * self.copied..4 * end]
            .copy_from_slice(&source.data[4 * self.copied..4 * end]);
        self.copied = end;
        end == n
    }

    /// Fraction of the positions drawn.
    pub fn fraction(&self, total: usize) -> f64 {
        self.next as f64 / total.max(1) as f64
    }

    /// Draw elements until about `budget` pixels were visited; `true` when
    /// every position is done.
    pub fn run(&mut self, inp: &PlaceInputs, budget: usize) -> bool {
        debug_assert_eq!(self.copied, self.out.pixel_count(), "copy_source first");
        let (w, h) = (self.out.width as i32, self.out.height as i32);
        let side = inp.sheet.side as i32;
        // Averaging the field and drawing the sprite visit 2·side² pixels.
        let cost = 2 * (side * side) as usize + 1;
        let mut spent = 0;
        let colour_map = inp.colour_map;
        while self.next < inp.positions.len() && spent < budget {
            let (x, y) = inp.positions[self.next];
            self.next += 1;
            spent += cost;
            let dir = orientation_at(
                inp.field,
                self.out.width,
                self.out.height,
                x,
                y,
                inp.sheet.side,
                inp.default,
            );
            let sprite = inp.sheet.sprite(dir);
            let pixels = &mut self.pixels;
            pixels.clear();
            for sy in 0..side {
                for sx in 0..side {
                    let (px, py) = (x + sx, y + sy);
                    if !sprite.on[(sy * side + sx) as usize]
                        || px < 0
                        || py < 0
                        || px >= w
                        || py >= h
                    {
                        continue;
                    }
                    let i = (py * w + px) as usize;
                    // Pixels outside the mask are never drawn, and transparent
                    // colour-map pixels have no colour to give.
                    if inp.mask[i] && colour_map.data[4 * i + 3] > 0 {
                        pixels.push(i);
                    }
                }
            }
            if pixels.is_empty() {
                continue;
            }
            self.placed += 1;
            let cm = |i: usize| -> [u8; 4] {
                let d = &colour_map.data[4 * i..4 * i + 4];
                [d[0], d[1], d[2], d[3]]
            };
            let out = &mut self.out;
            match inp.mode {
                ElementColour::Pixel => {
                    for &i in pixels.iter() {
                        out.data[4 * i..4 * i + 4].copy_from_slice(&cm(i));
                    }
                }
                ElementColour::Region => {
                    let tally = &mut self.tally;
                    tally.clear();
                    for &i in pixels.iter() {
                        let c = cm(i);
                        match tally.iter_mut().find(|e| e.0 == c) {
                            Some(e) => e.1 += 1,
                            None => tally.push((c, 1)),
                        }
                    }
                    let c = tally
                        .iter()
                        .min_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(&b.0)))
                        .expect("non-empty")
                        .0;
                    for &i in pixels.iter() {
                        out.data[4 * i..4 * i + 4].copy_from_slice(&c);
                    }
                }
            }
        }
        self.next == inp.positions.len()
    }

    /// The image and how many elements drew at least one pixel.
    pub fn finish(self) -> (Rgba8Image, usize) {
        (self.out, self.placed)
    }

    /// The image so far.
    pub fn image(&self) -> &Rgba8Image {
        &self.out
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pixel::inputs::ElementSheet;

    fn bar_sheet() -> ElementSheet {
        // A 3×3 vertical bar facing up: all eight orientations from one sprite.
        let mut img = Rgba8Image::new(3, 3);
        for y in 0..3 {
            img.put(1, y, [255, 255, 255, 255]);
        }
        ElementSheet::from_sprite(&img, Direction8::Up).unwrap()
    }

    #[test]
    fn field_picks_orientation_and_default_applies_to_zero() {
        let field = vec![[0.1f32, 1.0]; 16];
        assert_eq!(
            orientation_at(&field, 4, 4, 0, 0, 3, Direction8::Up),
            Direction8::Down
        );
        let zero = vec![[0.0f32; 2]; 16];
        assert_eq!(
            orientation_at(&zero, 4, 4, 0, 0, 3, Direction8::Left),
            Direction8::Left
        );
        // Opposite halves cancel: the default is used rather than a random pick.
        let mut half = vec![[1.0f32, 0.0]; 16];
        for v in half.iter_mut().skip(8) {
            *v = [-1.0, 0.0];
        }
        assert_eq!(
            orientation_at(&half, 4, 4, 0, 0, 4, Direction8::Up),
            Direction8::Up
        );
    }

    #[test]
    fn region_mode_uses_the_mode_and_mask_clips() {
        let mut src = Rgba8Image::new(3, 3);
        for y in 0..3 {
            for x in 0..3 {
                src.put(x, y, [1, 1, 1, 255]);
            }
        }
        let mut cmap = src.clone();
        cmap.put(1, 0, [9, 9, 9, 255]);
        cmap.put(1, 1, [7, 7, 7, 255]);
        cmap.put(1, 2, [7, 7, 7, 255]);
        let mask = vec![true; 9];
        let field = vec![[0.0f32, -1.0]; 9];
        let sheet = bar_sheet();
        let (out, n) = place(
            &src,
            &mask,
            &sheet,
            &[(0, 0)],
            &field,
            &cmap,
            ElementColour::Region,
            Direction8::Up,
        );
        assert_eq!(n, 1);
        for y in 0..3 {
            assert_eq!(out.get(1, y), [7, 7, 7, 255]);
            assert_eq!(out.get(0, y), [1, 1, 1, 255]);
        }
        let (out, _) = place(
            &src,
            &mask,
            &sheet,
            &[(0, 0)],
            &field,
            &cmap,
            ElementColour::Pixel,
            Direction8::Up,
        );
        assert_eq!(out.get(1, 0), [9, 9, 9, 255]);
        // Mask out the middle column's top pixel: it is never drawn.
        let mut m2 = mask.clone();
        m2[1] = false;
        let (out, _) = place(
            &src,
            &m2,
            &sheet,
            &[(0, 0)],
            &field,
            &cmap,
            ElementColour::Pixel,
            Direction8::Up,
        );
        assert_eq!(out.get(1, 0), [1, 1, 1, 255]);
        assert_eq!(out.get(1, 1), [7, 7, 7, 255]);
    }
}
