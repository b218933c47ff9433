//! Property tests of pixel placement on random masks, sheets, sprites,
//! strokes and settings (small sizes, so the whole file runs in seconds).
//!
//! For every run:
//! - no pixel outside the mask changes;
//! - every changed pixel is drawn by a placed element (its oriented sprite,
//!   at its position, inside the mask), and with margins ≥ 0 no two elements
//!   draw the same pixel (with negative margins, which the method allows to
//!   overlap, the occupied cores never overlap);
//! - the palette-based colour maps add no colour: the result's colours are
//!   a subset of the source's (auto only turns to the HSV shift, which adds
//!   colours by design, when the source has at most one usable colour).
use filigree::pixel::{
    self, inputs::ElementSheet, placement::orientation_at, ColourMapKind, ColourStrategy,
    Direction8, ElementColour, Elements, PixelInputs, PixelParams, PositionStrategy,
};
use filigree::raster::Rgba8Image;
use proptest::prelude::*;
use std::collections::HashSet;

#[derive(Debug, Clone)]
struct Case {
    w: u32,
    h: u32,
    palette: Vec<[u8; 4]>,
    /// Palette index per pixel (row-major).
    colours: Vec<usize>,
    mask: Vec<bool>,
    /// Element side and on-bits of the sprite (or of all nine sheet cells).
    side: u32,
    sheet: bool,
    bits: Vec<bool>,
    strokes: Vec<Vec<[f32; 2]>>,
    params: PixelParams,
}

fn case() -> impl Strategy<Value = Case> {
    (4u32..20, 4u32..20, 1u32..5, any::<bool>()).prop_flat_map(|(w, h, side, sheet)| {
        let n = (w * h) as usize;
        let cells = if sheet { 9 } else { 1 };
        let bits = (side * side) as usize * cells;
        let colour = (
            any::<u8>(),
            any::<u8>(),
            any::<u8>(),
            prop_oneof![Just(255u8), Just(0u8), 1u8..255],
        )
            .prop_map(|(r, g, b, a)| [r, g, b, a]);
        let palette = prop::collection::vec(colour, 2..6).prop_map(|mut p| {
            // The first two colours are opaque so the source is never empty,
            // and black (the default exclusion) is often present.
            p[0][3] = 255;
            p[1] = [0, 0, 0, 255];
            p
        });
        let point = (-1.0f32..w as f32 + 1.0, -1.0f32..h as f32 + 1.0).prop_map(|(x, y)| [x, y]);
        let strokes = prop::collection::vec(prop::collection::vec(point, 1..5), 0..3);
        let max_neg = -(((side as i32) - 1) / 2);
        let margins = [max_neg..3i32, max_neg..3i32];
        let params = (
            prop_oneof![
                Just(PositionStrategy::Random),
                Just(PositionStrategy::Packed)
            ],
            margins,
            prop_oneof![Just(1.0f64), 0.0f64..1.0],
            any::<bool>(),
            prop_oneof![
                Just(ColourStrategy::Auto),
                Just(ColourStrategy::Difference),
                Just(ColourStrategy::Border)
            ],
            prop_oneof![Just(ElementColour::Region), Just(ElementColour::Pixel)],
            0usize..8,
            any::<u64>(),
            1u32..5,
        )
            .prop_map(
                |(positions, margins, density, partial, colour, element_colour, dir, seed, k)| {
                    PixelParams {
                        annotation_scale: k,
                        positions,
                        density,
                        margins,
                        partial,
                        colour,
                        element_colour,
                        default_direction: Direction8::ALL[dir],
                        seed,
                        ..PixelParams::default()
                    }
                },
            );
        (
            Just((w, h, side, sheet)),
            palette,
            prop::collection::vec(0usize..6, n),
            prop::collection::vec(prop::bool::weighted(0.8), n),
            prop::collection::vec(prop::bool::weighted(0.6), bits),
            strokes,
            params,
        )
            .prop_map(
                |((w, h, side, sheet), palette, colours, mask, bits, strokes, params)| {
                    let colours = colours.into_iter().map(|c| c % palette.len()).collect();
                    Case {
                        w,
                        h,
                        palette,
                        colours,
                        mask,
                        side,
                        sheet,
                        bits,
                        strokes,
                        params,
                    }
                },
            )
    })
}

impl Case {
    fn inputs(&self) -> PixelInputs {
        let mut source = Rgba8Image::new(self.w, self.h);
        let mut mask = Rgba8Image::new(self.w, self.h);
        for i in 0..(self.w * self.h) as usize {
            let (x, y) = (i as u32 % self.w, i as u32 / self.w);
            source.put(x, y, self.palette[self.colours[i]]);
            if self.mask[i] {
                mask.put(x, y, [255; 4]);
            }
        }
        let s = self.side;
        let elements = if self.sheet {
            let mut img = Rgba8Image::new(3 * s, 3 * s);
            for cell in 0..9u32 {
                let (cx, cy) = (cell % 3 * s, cell / 3 * s);
                for k in 0..s * s {
                    if self.bits[(cell * s * s + k) as usize] {
                        img.put(cx + k % s, cy + k / s, [255; 4]);
                    }
                }
            }
            Elements::Sheet(img)
        } else {
            let mut img = Rgba8Image::new(s, s);
            for k in 0..s * s {
                if self.bits[k as usize] {
                    img.put(k % s, k / s, [255; 4]);
                }
            }
            Elements::Sprite(img)
        };
        PixelInputs {
            source,
            mask,
            elements,
            strokes: self.strokes.clone(),
        }
    }
}

fn colours(img: &Rgba8Image) -> HashSet<[u8; 4]> {
    img.pixels().filter(|p| p[3] > 0).collect()
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 200, ..ProptestConfig::default() })]

    #[test]
    fn placement_stays_in_the_mask_never_overlaps_and_adds_no_colour(c in case()) {
        let inputs = c.inputs();
        let sheet = match &inputs.elements {
            Elements::Sheet(img) => ElementSheet::from_sheet(img),
            Elements::Sprite(img) => ElementSheet::from_sprite(img, c.params.sprite_direction),
        };
        let source = inputs.source.clone();
        let mask = pixel::inputs::mask_from_image(&inputs.mask);
        let out = pixel::texture(inputs, c.params.clone());
        let (Ok(sheet), Ok(out)) = (sheet, out) else {
            // Only inputs the method must refuse may fail: a sheet cell or a
            // turned sprite that draws nothing, or an empty mask.
            let refused = c.mask.iter().all(|&m| !m)
                || match &c.inputs().elements {
                    Elements::Sheet(img) => ElementSheet::from_sheet(img).is_err(),
                    Elements::Sprite(img) => {
                        ElementSheet::from_sprite(img, c.params.sprite_direction).is_err()
                    }
                };
            prop_assert!(refused, "unexpected failure");
            return Ok(());
        };
        let (w, h) = (c.w as i32, c.h as i32);
        let side = sheet.side as i32;
        // Pixels each element draws: its oriented sprite's on-pixels at its
        // position, inside the image and the mask.
        let mut drawn_by: Vec<Option<usize>> = vec![None; (w * h) as usize];
        let no_overlap = c.params.margins.iter().all(|&m| m >= 0);
        for (k, &(x, y)) in out.positions.iter().enumerate() {
            let dir = orientation_at(&out.field, c.w, c.h, x, y, sheet.side, c.params.default_direction);
            let sprite = sheet.sprite(dir);
            for sy in 0..side {
                for sx in 0..side {
                    let (px, py) = (x + sx, y + sy);
                    if !sprite.on[(sy * side + sx) as usize] || px < 0 || py < 0 || px >= w || py >= h {
                        continue;
                    }
                    let i = (py * w + px) as usize;
                    if !mask[i] {
                        continue;
                    }
                    if no_overlap {
                        prop_assert!(drawn_by[i].is_none(), "elements {:?} and {k} both draw pixel ({px}, {py})", drawn_by[i]);
                    }
                    drawn_by[i] = Some(k);
                }
            }
        }
        for i in 0..(w * h) as usize {
            let before = &source.data[4 * i..4 * i + 4];
            let after = &out.image.data[4 * i..4 * i + 4];
            if before != after {
                prop_assert!(mask[i], "pixel {} {} outside the mask changed", i as i32 % w, i as i32 / w);
                prop_assert!(drawn_by[i].is_some(), "pixel {} {} changed but no element draws it", i as i32 % w, i as i32 / w);
            }
        }
        // A position is only taken when its cell is clear of every region
        // occupied before it (earlier cells grown, or shrunk, by the margins).
        let [mx, my] = c.params.margins;
        let region = |&(x, y): &(i32, i32)| (x - mx, y - my, x + side + mx, y + side + my);
        let cell = |&(x, y): &(i32, i32)| (x, y, x + side, y + side);
        for (i, a) in out.positions.iter().enumerate() {
            let a = region(a);
            for b in &out.positions[i + 1..] {
                let b = cell(b);
                let apart = a.2 <= b.0 || b.2 <= a.0 || a.3 <= b.1 || b.3 <= a.1;
                prop_assert!(apart, "cell {b:?} overlaps the earlier occupied region {a:?}");
            }
        }
        // Auto falls back to the HSV shift (which adds colours by design)
        // only when the source has at most one usable colour.
        if out.stats.colour_map_used == ColourMapKind::Hsv {
            prop_assert_eq!(c.params.colour, ColourStrategy::Auto);
            let usable = colours(&source).into_iter().filter(|p| !c.params.exclude.contains(&[p[0], p[1], p[2]])).count();
            prop_assert!(usable <= 1, "auto chose HSV with {usable} usable colours");
            return Ok(());
        }
        let (before, after) = (colours(&source), colours(&out.image));
        prop_assert!(after.is_subset(&before), "new colours {:?}", after.difference(&before).collect::<Vec<_>>());
    }
}
