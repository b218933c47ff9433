//! Section 3 (introduction): the three input images — source, binary mask and
//! an element sheet with eight orientations 45° apart — and their checks.
use crate::core::error::{Error, Result};
use crate::raster::Rgba8Image;
use serde::{Deserialize, Serialize};

/// Sprite pixels with alpha above this are drawn (reference tool convention).
pub const SPRITE_ALPHA: u8 = 10;

pub use crate::core::limits::MAX_ELEMENT_SIDE;

/// One of the eight element orientations, in image coordinates (y down).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Hash, PartialOrd, Ord)]
#[serde(rename_all = "kebab-case")]
pub enum Direction8 {
    Right,
    DownRight,
    Down,
    DownLeft,
    Left,
    UpLeft,
    Up,
    UpRight,
}

impl Direction8 {
    /// All eight, in order of increasing angle (clockwise on screen, from right).
    pub const ALL: [Direction8; 8] = [
        Direction8::Right,
        Direction8::DownRight,
        Direction8::Down,
        Direction8::DownLeft,
        Direction8::Left,
        Direction8::UpLeft,
        Direction8::Up,
        Direction8::UpRight,
    ];

    /// Position in [`Direction8::ALL`] (angle / 45°).
    pub fn index(self) -> usize {
        self as usize
    }

    /// The grid step `(dx, dy)`, each in `-1..=1`.
    pub fn step(self) -> (i32, i32) {
        const STEPS: [(i32, i32); 8] = [
            (1, 0),
            (1, 1),
            (0, 1),
            (-1, 1),
            (-1, 0),
            (-1, -1),
            (0, -1),
            (1, -1),
        ];
        STEPS[self.index()]
    }

    /// Unit vector of this direction.
    pub fn unit(self) -> [f64; 2] {
        let (dx, dy) = self.step();
        let s = if dx != 0 && dy != 0 {
            std::f64::consts::FRAC_1_SQRT_2
        } else {
            1.0
        };
        [dx as f64 * s, dy as f64 * s]
    }

    /// The name used in sheets, errors and JSON ("up-left", "down", ...).
    pub fn name(self) -> &'static str {
        const NAMES: [&str; 8] = [
            "right",
            "down-right",
            "down",
            "down-left",
            "left",
            "up-left",
            "up",
            "up-right",
        ];
        NAMES[self.index()]
    }

    /// The direction whose unit vector has the largest dot product with `v`
    /// (ties go to the earlier one in [`Direction8::ALL`]); `None` when `v` is
    /// (almost) zero or not finite. No trigonometry, so native and wasm agree
    /// bit for bit.
    pub fn nearest(v: [f64; 2]) -> Option<Direction8> {
        let len2 = v[0] * v[0] + v[1] * v[1];
        // Written so NaN fails too.
        if !len2.is_finite() || len2 <= 1e-24 || len2.is_nan() {
            return None;
        }
        let mut best = Direction8::Right;
        let mut best_dot = f64::NEG_INFINITY;
        for d in Direction8::ALL {
            let u = d.unit();
            let dot = u[0] * v[0] + u[1] * v[1];
            if dot > best_dot {
                best_dot = dot;
                best = d;
            }
        }
        Some(best)
    }
}

/// A square boolean sprite: `true` where the element draws a pixel.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Sprite {
    /// Width and height (cells are square).
    pub side: u32,
    /// Row-major, `side * side` entries.
    pub on: Vec<bool>,
}

impl Sprite {
    fn get(&self, x: u32, y: u32) -> bool {
        self.on[(y * self.side + x) as usize]
    }
    fn count(&self) -> usize {
        self.on.iter().filter(|&&b| b).count()
    }
}

/// The eight oriented variants of one element, all the same square size.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ElementSheet {
    /// Side of every cell in pixels.
    pub side: u32,
    /// Indexed by [`Direction8::index`].
    pub sprites: Vec<Sprite>,
}

impl ElementSheet {
    /// The sprite for `d`.
    pub fn sprite(&self, d: Direction8) -> &Sprite {
        &self.sprites[d.index()]
    }

    /// Read a 3×3 sheet: the cell at column dx+1, row dy+1 points in
    /// direction (dx, dy) (y down); the centre cell is ignored. Both sides must
    /// be divisible by 3 and the cells square; every used cell must draw at
    /// least one pixel (alpha > 10).
    pub fn from_sheet(img: &Rgba8Image) -> Result<Self> {
        let (w, h) = (img.width, img.height);
        if w % 3 != 0 || h % 3 != 0 || w != h {
            return Err(Error::input(format!(
                "the element sheet is {w}×{h} pixels, but it must be a 3×3 grid of square cells \
                 (width and height equal and divisible by 3, e.g. 18×18 for 6×6 elements; \
                 the cell at column dx+1, row dy+1 points in direction (dx, dy), centre unused)"
            )));
        }
        let side = w / 3;
        check_side(side, "element sheet cell")?;
        let mut sprites = Vec::with_capacity(8);
        for d in Direction8::ALL {
            let (dx, dy) = d.step();
            let (cx, cy) = ((dx + 1) as u32 * side, (dy + 1) as u32 * side);
            let mut on = Vec::with_capacity((side * side) as usize);
            for y in 0..side {
                for x in 0..side {
                    on.push(img.get(cx + x, cy + y)[3] > SPRITE_ALPHA);
                }
            }
            let s = Sprite { side, on };
            if s.count() == 0 {
                return Err(Error::input(format!(
                    "cell '{}' (column {}, row {}) of the {w}×{h} element sheet draws nothing: \
                     no pixel has alpha > {SPRITE_ALPHA}",
                    d.name(),
                    dx + 2,
                    dy + 2
                )));
            }
            sprites.push(s);
        }
        Ok(ElementSheet { side, sprites })
    }

    /// Turn one sprite, drawn pointing in `facing`, into all eight
    /// orientations. Multiples of 90° are exact rotations (no pixel lost or
    /// invented). The remaining 45° is a nearest-neighbour rotation of a 4×
    /// Scale2x-upscaled copy (a light RotSprite): sampling the smoothed
    /// upscale keeps diagonal edges clean while every output pixel is still
    /// either fully on or off. Rotation is about the cell centre and keeps the
    /// cell size, so pixels rotated past the cell's corners are dropped.
    /// A non-square sprite is centred on a square transparent cell first.
    pub fn from_sprite(img: &Rgba8Image, facing: Direction8) -> Result<Self> {
        let side = img.width.max(img.height);
        check_side(side, "element sprite")?;
        let (ox, oy) = ((side - img.width) / 2, (side - img.height) / 2);
        let mut on = vec![false; (side * side) as usize];
        for y in 0..img.height {
            for x in 0..img.width {
                on[((y + oy) * side + x + ox) as usize] = img.get(x, y)[3] > SPRITE_ALPHA;
            }
        }
        let base = Sprite { side, on };
        if base.count() == 0 {
            return Err(Error::input(format!(
                "the {}×{} element sprite draws nothing: no pixel has alpha > {SPRITE_ALPHA}",
                img.width, img.height
            )));
        }
        let big = scale2x(&scale2x(&base));
        let mut sprites = Vec::with_capacity(8);
        for d in Direction8::ALL {
            // Steps of 45° clockwise (on screen) from `facing` to `d`.
            let k = (d.index() + 8 - facing.index()) % 8;
            let mut s = base.clone();
            for _ in 0..k / 2 {
                s = rotate90(&s);
            }
            if k % 2 == 1 {
                let quarter_big = rotate_big(&big, k / 2);
                s = rotate45(&quarter_big, side);
            }
            if s.count() == 0 {
                return Err(Error::input(format!(
                    "the element sprite vanishes when turned to '{}'; draw it larger",
                    d.name()
                )));
            }
            sprites.push(s);
        }
        Ok(ElementSheet { side, sprites })
    }
}

fn check_side(side: u32, what: &str) -> Result<()> {
    if side == 0 {
        return Err(Error::input(format!("the {what} is empty (0 pixels wide)")));
    }
    if side > MAX_ELEMENT_SIDE {
        return Err(Error::limit(format!(
            "the {what} is {side} pixels wide; the element side limit is {MAX_ELEMENT_SIDE} pixels"
        )));
    }
    Ok(())
}

/// Exact 90° clockwise (on screen) rotation: direction (1,0) becomes (0,1).
fn rotate90(s: &Sprite) -> Sprite {
    let n = s.side;
    let mut on = vec![false; (n * n) as usize];
    for y in 0..n {
        for x in 0..n {
            // (x, y) -> (n-1-y, x)
            on[(x * n + (n - 1 - y)) as usize] = s.get(x, y);
        }
    }
    Sprite { side: n, on }
}

fn rotate_big(s: &Sprite, quarters: usize) -> Sprite {
    let mut s = s.clone();
    for _ in 0..quarters {
        s = rotate90(&s);
    }
    s
}

/// Scale2x (AdvMAME2x) on a boolean image: doubles the size, rounding
/// staircase corners into diagonals instead of blocks.
fn scale2x(s: &Sprite) -> Sprite {
    let n = s.side as i64;
    let get = |x: i64, y: i64, d: bool| -> bool {
        if x < 0 || y < 0 || x >= n || y >= n {
            d
        } else {
            s.get(x as u32, y as u32)
        }
    };
    let m = (n * 2) as u32;
    let mut on = vec![false; (m * m) as usize];
    for y in 0..n {
        for x in 0..n {
            let p = get(x, y, false);
            // Out-of-range neighbours repeat the centre so edges stay as drawn.
            let a = get(x, y - 1, p);
            let b = get(x + 1, y, p);
            let c = get(x - 1, y, p);
            let d = get(x, y + 1, p);
            let e0 = if c == a && c != d && a != b { a } else { p };
            let e1 = if a == b && a != c && b != d { b } else { p };
            let e2 = if d == c && d != b && c != a { c } else { p };
            let e3 = if b == d && b != a && d != c { d } else { p };
            let (ox, oy) = ((x * 2) as u32, (y * 2) as u32);
            on[(oy * m + ox) as usize] = e0;
            on[(oy * m + ox + 1) as usize] = e1;
            on[((oy + 1) * m + ox) as usize] = e2;
            on[((oy + 1) * m + ox + 1) as usize] = e3;
        }
    }
    Sprite { side: m, on }
}

/// Rotate 45° clockwise (on screen) by sampling the 4× upscaled `big` at the
/// inverse-rotated centre of every output pixel of a `side`² cell.
fn rotate45(big: &Sprite, side: u32) -> Sprite {
    let scale = big.side as f64 / side as f64;
    let c = side as f64 / 2.0;
    let r = std::f64::consts::FRAC_1_SQRT_2;
    let mut on = vec![false; (side * side) as usize];
    for oy in 0..side {
        for ox in 0..side {
            let (px, py) = (ox as f64 + 0.5 - c, oy as f64 + 0.5 - c);
            // Inverse of a +45° rotation (x' = x cos - y sin, y' = x sin + y cos).
            let qx = px * r + py * r + c;
            let qy = -px * r + py * r + c;
            let (bx, by) = ((qx * scale).floor(), (qy * scale).floor());
            if bx >= 0.0 && by >= 0.0 && bx < big.side as f64 && by < big.side as f64 {
                on[(oy * side + ox) as usize] = big.get(bx as u32, by as u32);
            }
        }
    }
    Sprite { side, on }
}

/// Read a mask image: `true` where textured. Masks with transparency use
/// alpha (alpha > 127 is inside, the reference tool's convention); fully
/// opaque masks use brightness (white/bright inside, dark outside), so a
/// black-and-white mask painted without alpha works too.
pub fn mask_from_image(img: &Rgba8Image) -> Vec<bool> {
    let has_alpha = img.pixels().any(|p| p[3] < 128);
    img.pixels()
        .map(|p| {
            if has_alpha {
                p[3] > 127
            } else {
                // Rec. 601 luma in integer arithmetic.
                (299 * p[0] as u32 + 587 * p[1] as u32 + 114 * p[2] as u32) / 1000 > 127
            }
        })
        .collect()
}

/// Check the source/mask pair and return the mask as booleans.
pub fn check_source_and_mask(source: &Rgba8Image, mask: &Rgba8Image) -> Result<Vec<bool>> {
    source.validate()?;
    mask.validate()?;
    if (source.width, source.height) != (mask.width, mask.height) {
        return Err(Error::input(format!(
            "the mask is {}×{} pixels but the source image is {}×{}; they must be the same size",
            mask.width, mask.height, source.width, source.height
        )));
    }
    if source.pixels().all(|p| p[3] == 0) {
        return Err(Error::input(format!(
            "the {}×{} source image is fully transparent: there is nothing to texture",
            source.width, source.height
        )));
    }
    let m = mask_from_image(mask);
    if !m.iter().any(|&b| b) {
        return Err(Error::input(format!(
            "the {}×{} mask is empty: no pixel is marked for texturing \
             (inside = opaque pixels, or bright pixels when the mask has no transparency)",
            mask.width, mask.height
        )));
    }
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sprite_img(rows: &[&str]) -> Rgba8Image {
        let mut img = Rgba8Image::new(rows[0].len() as u32, rows.len() as u32);
        for (y, r) in rows.iter().enumerate() {
            for (x, c) in r.chars().enumerate() {
                if c == '#' {
                    img.put(x as u32, y as u32, [255, 255, 255, 255]);
                }
            }
        }
        img
    }

    fn rows(s: &Sprite) -> Vec<String> {
        (0..s.side)
            .map(|y| {
                (0..s.side)
                    .map(|x| if s.get(x, y) { '#' } else { '.' })
                    .collect()
            })
            .collect()
    }

    #[test]
    fn nearest_direction_snaps_by_angle() {
        assert_eq!(Direction8::nearest([1.0, 0.1]), Some(Direction8::Right));
        assert_eq!(Direction8::nearest([0.0, 5.0]), Some(Direction8::Down));
        assert_eq!(Direction8::nearest([-3.0, -3.1]), Some(Direction8::UpLeft));
        assert_eq!(Direction8::nearest([0.3, -1.0]), Some(Direction8::Up));
        // Magnitude does not matter: a short vector snaps the same as a long one.
        assert_eq!(
            Direction8::nearest([1e-6, -0.9e-6]),
            Some(Direction8::UpRight)
        );
        assert_eq!(Direction8::nearest([0.0, 0.0]), None);
        assert_eq!(Direction8::nearest([f64::NAN, 1.0]), None);
    }

    #[test]
    fn sprite_axis_rotations_are_exact() {
        // An "arrow" pointing up.
        let img = sprite_img(&["..#..", ".###.", "#.#.#", "..#..", "..#.."]);
        let sheet = ElementSheet::from_sprite(&img, Direction8::Up).unwrap();
        assert_eq!(
            rows(sheet.sprite(Direction8::Up)),
            vec!["..#..", ".###.", "#.#.#", "..#..", "..#.."]
        );
        assert_eq!(
            rows(sheet.sprite(Direction8::Right)),
            vec!["..#..", "...#.", "#####", "...#.", "..#.."]
        );
        assert_eq!(
            rows(sheet.sprite(Direction8::Down)),
            vec!["..#..", "..#..", "#.#.#", ".###.", "..#.."]
        );
        assert_eq!(
            rows(sheet.sprite(Direction8::Left)),
            vec!["..#..", ".#...", "#####", ".#...", "..#.."]
        );
        for d in Direction8::ALL {
            assert!(sheet.sprite(d).count() > 0, "{d:?}");
        }
    }

    #[test]
    fn sprite_diagonal_points_the_right_way() {
        // A vertical bar rotated 45° clockwise becomes a "/" diagonal (up-right).
        let img = sprite_img(&["..#..", "..#..", "..#..", "..#..", "..#.."]);
        let sheet = ElementSheet::from_sprite(&img, Direction8::Up).unwrap();
        let s = sheet.sprite(Direction8::UpRight);
        assert!(s.get(3, 1) && s.get(2, 2) && s.get(1, 3), "{:?}", rows(s));
        assert!(!s.get(1, 1) && !s.get(3, 3), "{:?}", rows(s));
        let s = sheet.sprite(Direction8::UpLeft);
        assert!(s.get(1, 1) && s.get(2, 2) && s.get(3, 3), "{:?}", rows(s));
        assert!(!s.get(3, 1) && !s.get(1, 3), "{:?}", rows(s));
    }

    #[test]
    fn sheet_cells_map_to_directions() {
        // 9×9 sheet with 3×3 cells; mark one distinct pixel per cell.
        let mut img = Rgba8Image::new(9, 9);
        for d in Direction8::ALL {
            let (dx, dy) = d.step();
            let (cx, cy) = ((dx + 1) as u32 * 3, (dy + 1) as u32 * 3);
            img.put(
                cx + d.index() as u32 % 3,
                cy + d.index() as u32 / 3,
                [0, 0, 0, 11],
            );
        }
        let sheet = ElementSheet::from_sheet(&img).unwrap();
        for d in Direction8::ALL {
            let s = sheet.sprite(d);
            assert_eq!(s.count(), 1);
            assert!(s.get(d.index() as u32 % 3, d.index() as u32 / 3), "{d:?}");
        }
    }

    #[test]
    fn sheet_errors_name_the_layout() {
        let e = ElementSheet::from_sheet(&Rgba8Image::new(20, 18))
            .unwrap_err()
            .to_string();
        assert!(e.contains("20×18") && e.contains("3×3 grid"), "{e}");
        let e = ElementSheet::from_sheet(&Rgba8Image::new(18, 9))
            .unwrap_err()
            .to_string();
        assert!(e.contains("square"), "{e}");
        let mut img = Rgba8Image::new(9, 9);
        img.put(0, 0, [0, 0, 0, 255]);
        let e = ElementSheet::from_sheet(&img).unwrap_err().to_string();
        assert!(
            e.contains("draws nothing") && e.contains("alpha > 10"),
            "{e}"
        );
    }

    #[test]
    fn mask_uses_alpha_or_brightness() {
        let mut img = Rgba8Image::new(2, 1);
        img.put(0, 0, [10, 20, 200, 255]);
        assert_eq!(mask_from_image(&img), vec![true, false]);
        let mut bw = Rgba8Image::new(2, 1);
        bw.put(0, 0, [255, 255, 255, 255]);
        bw.put(1, 0, [0, 0, 0, 255]);
        assert_eq!(mask_from_image(&bw), vec![true, false]);
    }
}
