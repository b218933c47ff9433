//! Target SDFs from a raster image (paper §4 "Target Image SDF", Fig. 8):
//! per-colour binary masks, then an exact Euclidean distance transform of the
//! mask and of its complement (Felzenszwalb & Huttenlocher 2012), combined
//! into a signed field.
//!
//! An anti-aliased image says more than its masks: a pixel between two
//! palette colours tells how much of it each covers. Snapping keeps that
//! fraction (the pixel's colour projected onto the segment between its two
//! colours), and a channel whose coverage has fractions gets the
//! anti-aliased transform ([`crate::pattern::geom::aa_distance`]), which puts the
//! outline where the image says it is to a fraction of a pixel. A
//! hard-edged channel keeps the transform between pixel centres. Only a
//! pixel that lies along the segment between two palette colours counts
//! as their blend (every pair is tried).
//!
//! An image bigger than the loss grid gets its fields on its own raster,
//! then sampled at the grid's pixel centres: bilinearly near an outline,
//! and, for an anti-aliased channel, as the distance to its edge pieces
//! farther away ([`AaDistance::sample`]: interpolation rounds off ridges).
//! Each channel's coverage (what the image-space loss compares) is read
//! from the sampled field as the pattern's is ([`coverage`]).
//!
//! The distance transforms themselves are shared:
//! [`crate::pattern::geom::distance_transform`], [`crate::pattern::geom::aa_distance`].
use super::field::{edge_cap, Evaluator, Grid, Scene, CAP};
use super::record::Rgb;
use crate::core::error::{Error, Result};
use crate::pattern::geom::aa_distance::{AaDistance, HARD};
use crate::pattern::geom::distance_transform::SignedDistance;
use crate::raster::Rgba8Image;

/// A target: per-channel masks and signed fields on the loss grid.
#[derive(Debug, Clone)]
pub struct Target {
    /// The loss grid (over the program's canvas).
    pub grid: Grid,
    /// Field units per canvas unit (see `LossOptions::units`).
    pub scale: f64,
    /// Channel-major signed fields, same layout as `Evaluator::s`.
    pub sdf: Vec<f64>,
    /// Channel-major coverage: the fraction of each pixel the colour
    /// covers, read from the field with the pattern's own convention
    /// ([`coverage`]), so the image-space loss compares like with like: 0
    /// or 1 for a hard-edged target on its own grid (the masks), fractions
    /// along a sub-pixel outline.
    pub cover: Vec<f64>,
    /// Fraction of pixels farther than the tolerance from every palette colour.
    pub unmatched: f64,
}

/// Largest side at which an image target's fields are computed before they
/// are sampled onto the loss grid (a bigger image is snapped to this side
/// first). Keeps the distance transforms of a target a few milliseconds.
const MAX_FIELD_SIDE: usize = 512;

/// Palette index of every pixel of an `nw × nh` grid laid over the image:
/// nearest palette colour (RGB distance) of the image pixel under each grid
/// pixel's centre. Transparent pixels (alpha < 128) count as background.
/// Returns the indices, each pixel's [`Mix`], and the fraction of pixels
/// farther than `tolerance` from their colour.
pub(crate) fn snap_to_palette_wh(
    img: &Rgba8Image,
    palette: &[Rgb],
    nw: usize,
    nh: usize,
    tolerance: f64,
) -> (Vec<u16>, Vec<Mix>, f64) {
    let mut out = Vec::with_capacity(nw * nh);
    let mut mix = Vec::with_capacity(nw * nh);
    let mut far = 0usize;
    snap_rows(
        img,
        palette,
        nw,
        nh,
        tolerance,
        0..nh,
        (&mut out, &mut mix),
        &mut far,
    );
    (out, mix, far as f64 / (nw * nh) as f64)
}

/// Palette index of every pixel of an `nw × nh` grid laid over the image
/// (the first part of [`snap_to_palette_wh`]): what a person sees as the
/// image's colours, e.g. to compare a fitted render with its target.
pub fn palette_indices(
    img: &Rgba8Image,
    palette: &[Rgb],
    (nw, nh): (usize, usize),
    tolerance: f64,
) -> Vec<u16> {
    snap_to_palette_wh(img, palette, nw, nh, tolerance).0
}

/// Mean intersection over union, over every palette index but 0 (the
/// background) present in either picture, of two pictures as palette
/// indices of the same size: the overlap a designer sees between a fitted
/// render and its target (1 = identical).
pub fn mean_iou(a: &[u16], b: &[u16]) -> f64 {
    let max = a.iter().chain(b).copied().max().unwrap_or(0) as usize;
    let (mut inter, mut union) = (vec![0usize; max + 1], vec![0usize; max + 1]);
    for (&x, &y) in a.iter().zip(b) {
        union[x as usize] += 1;
        if x == y {
            inter[x as usize] += 1;
        } else {
            union[y as usize] += 1;
        }
    }
    let ious: Vec<f64> = (1..=max)
        .filter(|&c| union[c] > 0)
        .map(|c| inter[c] as f64 / union[c] as f64)
        .collect();
    if ious.is_empty() {
        return 1.0;
    }
    ious.iter().sum::<f64>() / ious.len() as f64
}

/// How a pixel mixes its palette colour (its index) with a second one:
/// the second colour's index and the fraction of the pixel the first
/// covers (1 for a pure pixel, ≥ ½ always).
pub(crate) type Mix = (u16, f64);

/// The mix of pixel colour `px` whose nearest palette colour is `a` (squared
/// distance `d2`): the two palette colours `i`, `j` and fraction `t` for
/// which `t·i + (1 − t)·j` is nearest `px`, when that explains `px` better
/// than `a` alone. Every pair is tried, not only pairs with `a`: a thin dark
/// line anti-aliased on white is grey, and grey may be nearest a third
/// colour (blue, say) that is not in the pixel at all. Returns the (index,
/// mix) with the larger fraction first.
fn mix_of(px: [u8; 4], palette: &[Rgb], a: u16, d2: f64) -> (u16, Mix) {
    let pure = (a, (a, 1.0));
    if d2 == 0.0 {
        return pure;
    }
    // (residual, i, j, fraction of i)
    let mut best: Option<(f64, u16, u16, f64)> = None;
    for (i, ci) in palette.iter().enumerate() {
        for (j, cj) in palette.iter().enumerate().skip(i + 1) {
            let ij: [f64; 3] = std::array::from_fn(|k| ci[k] as f64 - cj[k] as f64);
            let l2 = seg2(palette, i as u16, j as u16);
            if l2 == 0.0 {
                continue;
            }
            let pj: [f64; 3] = std::array::from_fn(|k| px[k] as f64 - cj[k] as f64);
            let t = ((pj[0] * ij[0] + pj[1] * ij[1] + pj[2] * ij[2]) / l2).clamp(0.0, 1.0);
            let r: f64 = (0..3).map(|k| (pj[k] - t * ij[k]).powi(2)).sum();
            if best.is_none_or(|b| r < b.0) {
                best = Some((r, i as u16, j as u16, t));
            }
        }
    }
    match best {
        // The pixel must lie along the segment: off it by at most a quarter
        // of its way along from the nearer end. A pixel of three colours
        // (a thin line across an outline) is often nearest some segment,
        // sometimes one to a colour not in it at all.
        Some((r, i, j, t))
            if r < d2
                && t > HARD
                && t < 1.0 - HARD
                && r <= (ALONG * t.min(1.0 - t)).powi(2) * seg2(palette, i, j) =>
        {
            if t >= 0.5 {
                (i, (j, t))
            } else {
                (j, (i, 1.0 - t))
            }
        }
        _ => pure,
    }
}

/// How far (relative) off the segment between two palette colours a pixel
/// may lie and still count as their mix: see [`mix_of`].
const ALONG: f64 = 0.25;

/// Squared RGB distance between palette colours `i` and `j`.
fn seg2(palette: &[Rgb], i: u16, j: u16) -> f64 {
    let (a, b) = (palette[i as usize], palette[j as usize]);
    (0..3).map(|k| (a[k] as f64 - b[k] as f64).powi(2)).sum()
}

/// Rows `rows` of [`snap_to_palette_wh`]: appends their indices to `out`
/// and counts the pixels beyond the tolerance in `far`.
#[allow(clippy::too_many_arguments)]
fn snap_rows(
    img: &Rgba8Image,
    palette: &[Rgb],
    nw: usize,
    nh: usize,
    tolerance: f64,
    rows: std::ops::Range<usize>,
    (out, mix): (&mut Vec<u16>, &mut Vec<Mix>),
    far: &mut usize,
) {
    let (w, h) = (img.width as usize, img.height as usize);
    for y in rows {
        for x in 0..nw {
            let sx = (((x as f64 + 0.5) * w as f64 / nw as f64) as usize).min(w - 1);
            let sy = (((y as f64 + 0.5) * h as f64 / nh as f64) as usize).min(h - 1);
            let px = img.get(sx as u32, sy as u32);
            if px[3] < 128 {
                out.push(0);
                mix.push((0, 1.0));
                continue;
            }
            let mut best = (f64::INFINITY, 0u16);
            for (i, c) in palette.iter().enumerate() {
                let d: f64 = (0..3)
                    .map(|k| (px[k] as f64 - c[k] as f64).powi(2))
                    .sum::<f64>();
                if d < best.0 {
                    best = (d, i as u16);
                }
            }
            if best.0.sqrt() > tolerance {
                *far += 1;
            }
            let (i, m) = mix_of(px, palette, best.1, best.0);
            out.push(i);
            mix.push(m);
        }
    }
}

/// The size of the raster an image target's fields are computed on: the
/// image's own (its longer side at most [`MAX_FIELD_SIDE`] or the grid's
/// longer side, the aspect kept), or the grid's when the image is no
/// bigger than the grid.
fn field_side(img: &Rgba8Image, grid: &Grid) -> (usize, usize) {
    let (w, h) = (img.width as usize, img.height as usize);
    let cap = MAX_FIELD_SIDE.max(grid.w.max(grid.h));
    let (fw, fh) = if w.max(h) <= cap {
        (w, h)
    } else if w == h {
        (cap, cap)
    } else {
        let k = cap as f64 / w.max(h) as f64;
        let r = |v: usize| ((v as f64 * k).round() as usize).clamp(1, cap);
        (r(w), r(h))
    };
    if fw <= grid.w && fh <= grid.h {
        (grid.w, grid.h)
    } else {
        (fw.max(1), fh.max(1))
    }
}

/// The error for a target whose pixels mostly match no colour of the program.
fn unmatched_error(scene: &Scene, far: f64, tolerance: f64) -> Error {
    let names: Vec<String> = scene
        .rec
        .colours
        .iter()
        .map(|c| format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2]))
        .collect();
    Error::input(format!(
        "{:.0}% of the target's pixels are not close to any colour of the program ({}); \
         draw the target in these colours or raise the tolerance (now {tolerance})",
        far * 100.0,
        names.join(", ")
    ))
}

/// Value of the `w × h` field `f` at (u, v) in pixel-centre coordinates
/// (pixel i's centre is at i), bilinear, clamped at the borders.
fn bilinear(f: &[f64], w: usize, h: usize, u: f64, v: f64) -> f64 {
    let u = u.clamp(0.0, (w - 1) as f64);
    let v = v.clamp(0.0, (h - 1) as f64);
    let (x0, y0) = (u.floor() as usize, v.floor() as usize);
    let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
    let (fx, fy) = (u - x0 as f64, v - y0 as f64);
    let at = |x: usize, y: usize| f[y * w + x];
    let top = at(x0, y0) * (1.0 - fx) + at(x1, y0) * fx;
    let bottom = at(x0, y1) * (1.0 - fx) + at(x1, y1) * fx;
    top * (1.0 - fy) + bottom * fy
}

impl Target {
    /// Build the per-channel target fields from palette indices on the
    /// grid of `n` pixels along the longer side of the scene's canvas
    /// ([`Grid::on`]; `n × n` on a square one).
    pub fn from_indices(scene: &Scene, idx: &[u16], n: usize, scale: f64) -> Target {
        let g = Grid::on(scene.rec.canvas, n);
        TargetBuild::fields(idx.to_vec(), vec![], g.w, g.h, g, scale, 0.0).finish(scene)
    }

    /// A target with no fields yet (on `grid`), to be replaced by one a
    /// [`TargetBuild`] completes.
    pub(crate) fn pending(grid: Grid, scale: f64) -> Target {
        Target {
            grid,
            scale,
            sdf: vec![],
            cover: vec![],
            unmatched: 0.0,
        }
    }

    /// Build a target from an image on the grid of `n` pixels along the
    /// longer side of the scene's canvas: snap pixels to the program's
    /// palette (background included) and compute the fields. The image is
    /// laid over the canvas; record the program on the image's canvas
    /// ([`crate::pattern::record::Canvas::of_pixels`]) so nothing is
    /// stretched (a fit does).
    ///
    /// Fails when more than half of the pixels are farther than `tolerance`
    /// (RGB distance, 0..441) from every colour the program uses.
    pub fn from_image(
        scene: &Scene,
        img: &Rgba8Image,
        n: usize,
        scale: f64,
        tolerance: f64,
    ) -> Result<Target> {
        if img.width == 0 || img.height == 0 {
            return Err(Error::input("the target image is empty"));
        }
        let g = Grid::on(scene.rec.canvas, n);
        let (fw, fh) = field_side(img, &g);
        let (idx, mix, far) = snap_to_palette_wh(img, &scene.rec.colours, fw, fh, tolerance);
        if far > 0.5 {
            return Err(unmatched_error(scene, far, tolerance));
        }
        Ok(TargetBuild::fields(idx, mix, fw, fh, g, scale, far).finish(scene))
    }
}

/// Work units of a [`TargetBuild`]: pixels visited (times the palette size
/// when snapping), item evaluations when drawing; about 5–20 ns each.
pub type BuildWork = u64;

/// A [`Target`] built in bounded parts, for a job that must not spend more
/// than a few milliseconds in one slice: snapping an image to the palette a
/// few rows at a time (or drawing the program a few tiles at a time), then
/// per channel the signed distance a few lines at a time
/// ([`SignedDistance`]) and its values on the grid a few rows at a time.
/// The result is bit for bit [`Target::from_image`] / [`Target::from_indices`]
/// of the same input.
pub struct TargetBuild {
    grid: Grid,
    scale: f64,
    stage: Stage,
    sdf: Vec<f64>,
    cover: Vec<f64>,
    unmatched: f64,
}

enum Stage {
    /// Snapping the image's rows onto the `fw × fh` field raster.
    Snap {
        img: Rgba8Image,
        tolerance: f64,
        fw: usize,
        fh: usize,
        idx: Vec<u16>,
        mix: Vec<Mix>,
        far: usize,
    },
    /// Drawing the program on the grid, a few big tiles at a time ...
    Draw {
        ev: Evaluator,
        next_tile: usize,
    },
    /// ... then reading its palette index at every pixel.
    Pick {
        ev: Evaluator,
        idx: Vec<u16>,
    },
    /// The fields of palette indices on a `fw × fh` raster: channel
    /// `channel`'s signed distance in the making ...
    Field {
        idx: Vec<u16>,
        mix: Vec<Mix>,
        fw: usize,
        fh: usize,
        channel: usize,
        sd: Option<Transform>,
    },
    /// ... and its values on the grid, row `row` next.
    Sample {
        idx: Vec<u16>,
        mix: Vec<Mix>,
        fw: usize,
        fh: usize,
        channel: usize,
        d: Vec<f64>,
        /// The anti-aliased transform that gave `d`, to sample between pixels.
        aa: Option<Box<AaDistance>>,
        row: usize,
    },
    Done,
}

impl TargetBuild {
    /// The target of `img` snapped to the program's palette (see
    /// [`Target::from_image`]); fails at once only when the image is empty.
    pub fn image(
        scene: &Scene,
        img: Rgba8Image,
        n: usize,
        scale: f64,
        tolerance: f64,
    ) -> Result<TargetBuild> {
        if img.width == 0 || img.height == 0 {
            return Err(Error::input("the target image is empty"));
        }
        let g = Grid::on(scene.rec.canvas, n);
        let (fw, fh) = field_side(&img, &g);
        Ok(TargetBuild {
            stage: Stage::Snap {
                img,
                tolerance,
                fw,
                fh,
                idx: Vec::with_capacity(fw * fh),
                mix: Vec::with_capacity(fw * fh),
                far: 0,
            },
            ..TargetBuild::empty(g, scale)
        })
    }

    /// The target of the program drawn with `params` on the grid
    /// (palette index per pixel, as [`crate::pattern::fit::colour_indices`]).
    /// Fails at once when the parameters give shapes that are not finite.
    pub fn drawn(scene: &Scene, params: &[f64], n: usize, scale: f64) -> Result<TargetBuild> {
        let nodes = super::render::checked_nodes(scene, params)?;
        let g = Grid::on(scene.rec.canvas, n);
        let mut ev = Evaluator::on(g, 1.0);
        ev.begin(scene, &nodes, false);
        Ok(TargetBuild {
            stage: Stage::Draw { ev, next_tile: 0 },
            ..TargetBuild::empty(g, scale)
        })
    }

    fn empty(grid: Grid, scale: f64) -> TargetBuild {
        TargetBuild {
            grid,
            scale,
            stage: Stage::Done,
            sdf: vec![],
            cover: vec![],
            unmatched: 0.0,
        }
    }

    /// The fields of palette indices on a `fw × fh` raster covering the
    /// canvas: computed there, then taken as they are (the grid's own
    /// size) or sampled bilinearly at the centres of the grid's pixels;
    /// the coverage is read from the field in grid pixels ([`coverage`]).
    fn fields(
        idx: Vec<u16>,
        mix: Vec<Mix>,
        fw: usize,
        fh: usize,
        grid: Grid,
        scale: f64,
        unmatched: f64,
    ) -> TargetBuild {
        TargetBuild {
            stage: Stage::Field {
                idx,
                mix,
                fw,
                fh,
                channel: 0,
                sd: None,
            },
            unmatched,
            ..TargetBuild::empty(grid, scale)
        }
    }

    /// Run to the end in one go.
    fn finish(mut self, scene: &Scene) -> Target {
        loop {
            match self.step(scene, BuildWork::MAX) {
                Ok(Some(t)) => return t,
                Ok(None) => {}
                Err(_) => unreachable!("only snapping fails, and it is done"),
            }
        }
    }

    /// A rough fraction done (for progress).
    pub fn fraction(&self, scene: &Scene) -> f64 {
        let nc = scene.channels.len().max(1) as f64;
        match &self.stage {
            Stage::Snap { fh, idx, fw, .. } => 0.2 * idx.len() as f64 / (fw * fh).max(1) as f64,
            Stage::Draw { ev, next_tile } => 0.2 * *next_tile as f64 / ev.tiles().max(1) as f64,
            Stage::Pick { .. } => 0.2,
            Stage::Field { channel, .. } => 0.2 + 0.8 * *channel as f64 / nc,
            Stage::Sample { channel, row, .. } => {
                0.2 + 0.8 * (*channel as f64 + 0.9 + 0.1 * *row as f64 / self.grid.h as f64) / nc
            }
            Stage::Done => 1.0,
        }
    }

    /// Go on for about `budget` work units (one row, tile or line at
    /// least); the target once it is complete. Fails when the image's
    /// pixels mostly match no colour of the program. Must not be called
    /// again after it returned the target or an error.
    pub fn step(&mut self, scene: &Scene, budget: BuildWork) -> Result<Option<Target>> {
        let budget = budget.max(1);
        let mut spent: BuildWork = 0;
        let (g, scale) = (self.grid, self.scale);
        let (gw, gh, nn) = (g.w, g.h, g.len());
        // Grid pixels per canvas unit (`n` on an `n × n` square).
        let ppu = g.long_ppu();
        while spent < budget {
            match &mut self.stage {
                Stage::Snap {
                    img,
                    tolerance,
                    fw,
                    fh,
                    idx,
                    mix,
                    far,
                } => {
                    let (fw, fh) = (*fw, *fh);
                    let y = idx.len() / fw;
                    if y < fh {
                        let palette = &scene.rec.colours;
                        snap_rows(img, palette, fw, fh, *tolerance, y..y + 1, (idx, mix), far);
                        // (The nearest colour, then every pair for a mix.)
                        let pairs = palette.len() * palette.len().saturating_sub(1) / 2;
                        spent =
                            spent.saturating_add((fw * (palette.len() + 1 + pairs)) as BuildWork);
                        continue;
                    }
                    let far = *far as f64 / (fw * fh) as f64;
                    if far > 0.5 {
                        let e = unmatched_error(scene, far, *tolerance);
                        self.stage = Stage::Done;
                        return Err(e);
                    }
                    let idx = std::mem::take(idx);
                    let mix = std::mem::take(mix);
                    *self = TargetBuild::fields(idx, mix, fw, fh, g, scale, far);
                }
                Stage::Draw { ev, next_tile } => {
                    let before = ev.raw_work();
                    while *next_tile < ev.tiles() && ev.raw_work() - before < budget - spent {
                        let t = *next_tile;
                        ev.eval_tiles(scene, false, t..t + 1);
                        *next_tile += 1;
                    }
                    spent = spent.saturating_add(ev.raw_work() - before + 1);
                    if *next_tile >= ev.tiles() {
                        ev.finish(scene);
                        let ev = std::mem::replace(ev, Evaluator::new(0, 1.0));
                        self.stage = Stage::Pick {
                            ev,
                            idx: Vec::with_capacity(nn),
                        };
                    }
                }
                Stage::Pick { ev, idx } => {
                    let i = idx.len();
                    let end = (i + gw).min(nn);
                    idx.extend((i..end).map(|i| ev.colour_index(scene, i)));
                    spent = spent.saturating_add(((end - i) * scene.channels.len()) as BuildWork);
                    if end == nn {
                        let idx = std::mem::take(idx);
                        *self = TargetBuild::fields(idx, vec![], gw, gh, g, scale, 0.0);
                    }
                }
                Stage::Field {
                    idx,
                    mix,
                    fw,
                    fh,
                    channel,
                    sd,
                } => {
                    let (fw, fh, c) = (*fw, *fh, *channel);
                    if c == scene.channels.len() {
                        let t = Target {
                            grid: g,
                            scale,
                            sdf: std::mem::take(&mut self.sdf),
                            cover: std::mem::take(&mut self.cover),
                            unmatched: self.unmatched,
                        };
                        self.stage = Stage::Done;
                        return Ok(Some(t));
                    }
                    if c == 0 && self.sdf.is_empty() {
                        let cap = scene.channels.len() * nn;
                        self.sdf.reserve_exact(cap);
                        self.cover.reserve_exact(cap);
                    }
                    let sd = match sd {
                        Some(sd) => sd,
                        None => {
                            let colour = scene.channels[c].colour;
                            spent = spent.saturating_add((fw * fh) as BuildWork);
                            let big = if (fw, fh) == (gw, gh) {
                                CAP * ppu
                            } else {
                                CAP / fine_pixel(&g, fw, fh)
                            };
                            sd.insert(Transform::new(idx, mix, colour, fw, fh, big))
                        }
                    };
                    let left = usize::try_from(budget - spent.min(budget)).unwrap_or(usize::MAX);
                    let lines_before = spent;
                    match sd.step(left) {
                        Some(d) => {
                            spent = spent.saturating_add(2 * (fw * fh) as BuildWork);
                            let idx = std::mem::take(idx);
                            let mix = std::mem::take(mix);
                            // An anti-aliased field is sampled from its edge pieces.
                            let aa = match std::mem::replace(sd, Transform::Done) {
                                Transform::Aa(t) => Some(t),
                                _ => None,
                            };
                            self.stage = Stage::Sample {
                                idx,
                                mix,
                                fw,
                                fh,
                                channel: c,
                                d,
                                aa,
                                row: 0,
                            };
                        }
                        None => {
                            // The transform did about `left` pixels (one line at least).
                            spent = lines_before.saturating_add(left.max(fw.max(fh)) as BuildWork);
                        }
                    }
                }
                Stage::Sample {
                    idx,
                    mix,
                    fw,
                    fh,
                    channel,
                    d,
                    aa,
                    row,
                } => {
                    let (fw, fh, c) = (*fw, *fh, *channel);
                    if (fw, fh) == (gw, gh) {
                        // The grid's own fields: all rows at once (a copy).
                        let px_to_units = scale / ppu;
                        self.sdf.extend(
                            d.iter().enumerate().map(|(i, v)| {
                                edge_clamp(v * px_to_units, i % gw, i / gw, &g, scale)
                            }),
                        );
                        self.cover.extend(d.iter().map(|&v| coverage(v)));
                        spent = spent.saturating_add((nn / 4) as BuildWork);
                        *row = gh;
                    } else {
                        let px = fine_pixel(&g, fw, fh);
                        let (sx, sy) = (fw as f64 / gw as f64, fh as f64 / gh as f64);
                        let y = *row;
                        let v = (y as f64 + 0.5) * sy - 0.5;
                        for x in 0..gw {
                            let u = (x as f64 + 0.5) * sx - 0.5;
                            let canvas = match aa {
                                Some(t) => t.sample(u, v),
                                None => bilinear(d, fw, fh, u, v),
                            } * px;
                            self.cover.push(coverage(canvas * ppu));
                            self.sdf.push(edge_clamp(canvas * scale, x, y, &g, scale));
                        }
                        // (Away from the outline an anti-aliased field
                        // looks at up to 16 edge pieces a pixel.)
                        let per_pixel = if aa.is_some() { 20 } else { 4 };
                        spent = spent.saturating_add(per_pixel * gw as BuildWork);
                        *row += 1;
                    }
                    if *row == gh {
                        let idx = std::mem::take(idx);
                        let mix = std::mem::take(mix);
                        self.stage = Stage::Field {
                            idx,
                            mix,
                            fw,
                            fh,
                            channel: c + 1,
                            sd: None,
                        };
                    }
                }
                Stage::Done => unreachable!("a finished target build was stepped"),
            }
        }
        Ok(None)
    }
}

/// The signed distance of one channel: between pixel centres for a
/// hard-edged channel, anti-aliased when some pixel is partly its colour.
enum Transform {
    Hard(Box<SignedDistance>),
    Aa(Box<AaDistance>),
    /// Handed on once complete.
    Done,
}

impl Transform {
    /// The transform of the channel of palette colour `colour`, from the
    /// pixels' indices and mixes (`mix` empty: every pixel pure).
    fn new(idx: &[u16], mix: &[Mix], colour: u16, w: usize, h: usize, big: f64) -> Transform {
        let coverage = |k: usize| -> f64 {
            match mix.get(k) {
                Some(&(b, t)) if idx[k] == colour => {
                    if b == colour {
                        1.0
                    } else {
                        t
                    }
                }
                Some(&(b, t)) if b == colour => 1.0 - t,
                Some(_) => 0.0,
                None => f64::from(u8::from(idx[k] == colour)),
            }
        };
        let soft = (0..idx.len()).any(|k| {
            let a = coverage(k);
            a > HARD && a < 1.0 - HARD
        });
        if soft {
            Transform::Aa(Box::new(AaDistance::new(
                (0..idx.len()).map(coverage).collect(),
                w,
                h,
                big,
            )))
        } else {
            let m: Vec<bool> = idx.iter().map(|&i| i == colour).collect();
            Transform::Hard(Box::new(SignedDistance::new(m, w, h, big)))
        }
    }

    fn step(&mut self, budget: usize) -> Option<Vec<f64>> {
        match self {
            Transform::Hard(s) => s.step(budget),
            Transform::Aa(s) => s.step(budget),
            Transform::Done => unreachable!("a finished transform was stepped"),
        }
    }
}

/// A target value `v` (in `scale` units per canvas unit) at pixel `(x, y)`
/// of `grid`, its magnitude taken no farther than the canvas edge, as the
/// pattern's fields are ([`edge_cap`]): the image shows nothing past the
/// edge, so both sides see the same world.
#[inline]
fn edge_clamp(v: f64, x: usize, y: usize, grid: &Grid, scale: f64) -> f64 {
    let cap = edge_cap(x, y, grid) * scale;
    v.clamp(-cap, cap)
}

/// The size of one pixel of a `fw × fh` raster covering the canvas of
/// `grid`, in canvas units: distances there are measured in pixels of the
/// mean size (square pixels when the raster has the canvas's aspect).
fn fine_pixel(grid: &Grid, fw: usize, fh: usize) -> f64 {
    (grid.canvas.w * grid.canvas.h).sqrt() / ((fw * fh) as f64).sqrt()
}

/// The fraction of a pixel a colour covers, from the colour's signed
/// distance at the pixel's centre in pixels of the grid: 1 − (d + ½)
/// clamped to [0, 1], the box filter's coverage of a straight edge across
/// the pixel along an axis. The image-space loss reads the pattern's and
/// the target's coverage both through this, so at the truth they agree
/// wherever the two fields do.
#[inline]
pub(crate) fn coverage(d_px: f64) -> f64 {
    (0.5 - d_px).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::record::{Program, RecordLimits};

    /// A black disc on white, drawn at `side`² with each pixel black when its
    /// centre is inside; the disc's exact signed distance in canvas units.
    fn disc(side: u32, c: (f64, f64), r: f64) -> (Scene, Rgba8Image, impl Fn(f64, f64) -> f64) {
        let src = format!(
            "background \"#ffffff\";\nparam r in [0.05, 0.4] = {r};\ncircle({}, {}, r, fill: \"#000000\");",
            c.0, c.1
        );
        let p = Program::parse(&src).unwrap();
        let scene = Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap());
        let mut img = Rgba8Image::new(side, side);
        let s = side as f64;
        for y in 0..side {
            for x in 0..side {
                let d = ((x as f64 + 0.5) / s - c.0).hypot((y as f64 + 0.5) / s - c.1) - r;
                img.put(
                    x,
                    y,
                    if d < 0.0 {
                        [0, 0, 0, 255]
                    } else {
                        [255, 255, 255, 255]
                    },
                );
            }
        }
        (scene, img, move |x: f64, y: f64| {
            (x - c.0).hypot(y - c.1) - r
        })
    }

    /// Mean signed and largest error (in grid pixels) of the disc's target
    /// field near its edge, against the exact distance at the cell centres.
    fn field_errors(side: u32, n: usize) -> (f64, f64) {
        let (scene, img, exact) = disc(side, (0.48, 0.53), 0.27);
        let t = Target::from_image(&scene, &img, n, n as f64, 60.0).unwrap();
        let k = scene
            .channels
            .iter()
            .position(|ch| scene.rec.colours[ch.colour as usize] == [0, 0, 0])
            .unwrap();
        let f = &t.sdf[k * n * n..(k + 1) * n * n];
        let (mut sum, mut worst, mut count) = (0.0, 0.0f64, 0usize);
        for y in 0..n {
            for x in 0..n {
                let truth =
                    exact((x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64) * n as f64;
                if truth.abs() < 3.0 {
                    let e = f[y * n + x] - truth;
                    sum += e;
                    worst = worst.max(e.abs());
                    count += 1;
                }
            }
        }
        (sum / count as f64, worst)
    }

    #[test]
    fn an_image_bigger_than_the_grid_gives_the_field_at_the_cell_centres() {
        // 256 px images on 64 and 128 grids (what the browser sends), and an
        // odd ratio. Snapping to the grid first took the pixel right of and
        // below every cell centre: the disc came out shifted by half an image
        // pixel, a bias the fit then reproduced.
        for (side, n) in [(256, 64), (256, 128), (300, 64), (512, 128)] {
            let (mean, worst) = field_errors(side, n);
            let fine_px = n as f64 / side as f64; // one image pixel in grid pixels
            assert!(
                mean.abs() < 0.15 * fine_px + 0.01,
                "{side}→{n}: mean error {mean}"
            );
            assert!(
                worst < 0.75 * fine_px + 0.05,
                "{side}→{n}: largest error {worst}"
            );
        }
    }

    /// The fields as they were computed before the build was stepped: one
    /// signed distance per channel, then taken as they are or sampled.
    fn reference(scene: &Scene, idx: &[u16], fw: usize, fh: usize, n: usize, scale: f64) -> Target {
        use crate::pattern::geom::distance_transform::signed_distance;
        let (mut sdf, mut mask) = (vec![], vec![]);
        for ch in &scene.channels {
            let m: Vec<bool> = idx.iter().map(|&i| i == ch.colour).collect();
            if (fw, fh) == (n, n) {
                let d = signed_distance(&m, n, n, CAP * n as f64);
                sdf.extend(d.iter().enumerate().map(|(i, v)| {
                    edge_clamp(
                        v * (scale / n as f64),
                        i % n,
                        i / n,
                        &Grid::square(n),
                        scale,
                    )
                }));
                // A hard channel's coverage is its mask.
                mask.extend(m.iter().map(|&b| if b { 1.0 } else { 0.0 }));
            } else {
                let px = 1.0 / ((fw * fh) as f64).sqrt();
                let d = signed_distance(&m, fw, fh, CAP / px);
                let (sx, sy) = (fw as f64 / n as f64, fh as f64 / n as f64);
                for y in 0..n {
                    for x in 0..n {
                        let (u, v) = ((x as f64 + 0.5) * sx - 0.5, (y as f64 + 0.5) * sy - 0.5);
                        let value = bilinear(&d, fw, fh, u, v) * px;
                        sdf.push(edge_clamp(value * scale, x, y, &Grid::square(n), scale));
                        mask.push((0.5 - value * n as f64).clamp(0.0, 1.0));
                    }
                }
            }
        }
        Target {
            grid: Grid::square(n),
            scale,
            sdf,
            cover: mask,
            unmatched: 0.0,
        }
    }

    fn same_bits(a: &Target, b: &Target) -> bool {
        a.grid == b.grid
            && a.sdf.len() == b.sdf.len()
            && a.sdf
                .iter()
                .zip(&b.sdf)
                .all(|(x, y)| x.to_bits() == y.to_bits())
            && a.cover == b.cover
            && a.unmatched.to_bits() == b.unmatched.to_bits()
    }

    /// Run a build to the end with `budget` work units a step.
    fn stepped(scene: &Scene, mut b: TargetBuild, budget: BuildWork) -> (Target, usize) {
        let mut steps = 0;
        loop {
            steps += 1;
            let before = b.fraction(scene);
            if let Some(t) = b.step(scene, budget).unwrap() {
                return (t, steps);
            }
            assert!(b.fraction(scene) >= before, "progress goes back");
        }
    }

    /// An image target built a few rows/lines at a time equals the one-go
    /// target bit for bit, and both equal the fields as computed before the
    /// build was stepped, for images bigger than, equal to and smaller than
    /// the grid.
    #[test]
    fn stepping_gives_the_same_bits() {
        for (side, n) in [(100, 32), (32, 32), (20, 32), (37, 16)] {
            let (scene, img, _) = disc(side, (0.45, 0.55), 0.3);
            let one_go = Target::from_image(&scene, &img, n, n as f64, 60.0).unwrap();
            let (fw, fh) = field_side(&img, &Grid::square(n));
            let (idx, _, _) = snap_to_palette_wh(&img, &scene.rec.colours, fw, fh, 60.0);
            assert!(same_bits(
                &one_go,
                &reference(&scene, &idx, fw, fh, n, n as f64)
            ));
            for budget in [1, 500, 1 << 40] {
                let b = TargetBuild::image(&scene, img.clone(), n, n as f64, 60.0).unwrap();
                let (t, steps) = stepped(&scene, b, budget);
                assert!(same_bits(&t, &one_go), "{side}→{n}, budget {budget}");
                if budget == 1 {
                    // A row a step while snapping, a row or a group of 8
                    // columns a step in each transform.
                    let channels = scene.channels.len();
                    assert!(steps > fh + channels * 2 * (fw / 8 + fh), "{steps} steps");
                }
            }
        }
        // A target drawn by the program itself.
        let (scene, _, _) = disc(8, (0.4, 0.6), 0.25);
        let n = 48;
        let x = scene.rec.float_values();
        let idx = crate::pattern::fit::colour_indices(&scene, &x, n).unwrap();
        let one_go = Target::from_indices(&scene, &idx, n, 3.0);
        assert!(same_bits(&one_go, &reference(&scene, &idx, n, n, n, 3.0)));
        for budget in [1, 700, 1 << 40] {
            let b = TargetBuild::drawn(&scene, &x, n, 3.0).unwrap();
            let (t, _) = stepped(&scene, b, budget);
            assert!(same_bits(&t, &one_go), "drawn, budget {budget}");
        }
    }

    /// A pixel's mix: every blend of two palette colours is read back as
    /// those two colours (to a rounding), even when the blend is nearest a
    /// third colour (grey, between the dark line and white, is nearest
    /// blue); a pixel of three colours is not read as a blend with a colour
    /// that is not in it.
    #[test]
    fn a_pixel_is_read_as_the_blend_of_the_two_colours_it_mixes() {
        let palette: [Rgb; 4] = [
            [255, 255, 255],
            [46, 134, 193],
            [243, 156, 18],
            [28, 40, 51],
        ];
        let nearest = |px: [u8; 4]| -> (u16, f64) {
            let mut best = (0u16, f64::INFINITY);
            for (i, c) in palette.iter().enumerate() {
                let d: f64 = (0..3).map(|k| (px[k] as f64 - c[k] as f64).powi(2)).sum();
                if d < best.1 {
                    best = (i as u16, d);
                }
            }
            best
        };
        for i in 0..4u16 {
            for j in 0..4u16 {
                if i == j {
                    continue;
                }
                for t in [0.1, 0.3, 0.45, 0.55, 0.7, 0.9] {
                    let (a, b) = (palette[i as usize], palette[j as usize]);
                    let px: [u8; 4] = std::array::from_fn(|k| {
                        if k == 3 {
                            255
                        } else {
                            (t * a[k] as f64 + (1.0 - t) * b[k] as f64).round() as u8
                        }
                    });
                    let (near, d2) = nearest(px);
                    let (major, (minor, f)) = mix_of(px, &palette, near, d2);
                    let (want_major, want_minor, want_f) =
                        if t >= 0.5 { (i, j, t) } else { (j, i, 1.0 - t) };
                    assert_eq!(
                        (major, minor),
                        (want_major, want_minor),
                        "{i}/{j} at {t}: {px:?}"
                    );
                    assert!((f - want_f).abs() < 0.01, "{i}/{j} at {t}: {f}");
                }
            }
        }
        // Grey between the dark line and white is nearest blue.
        let grey = [141, 147, 153, 255];
        assert_eq!(nearest(grey).0, 1);
        let (near, d2) = nearest(grey);
        let (major, (minor, _)) = mix_of(grey, &palette, near, d2);
        assert_eq!((major.min(minor), major.max(minor)), (0, 3));
        // Blue with a little white and dark (a thin dark line across the
        // edge of a blue stripe) lies near the blue–orange segment: it is
        // blue, not a blend with orange.
        let three = [70, 137, 183, 255];
        let (near, d2) = nearest(three);
        assert_eq!(mix_of(three, &palette, near, d2), (1, (1, 1.0)));
    }

    #[test]
    fn a_target_matching_no_colour_fails_while_it_is_built() {
        let (scene, mut img, _) = disc(40, (0.5, 0.5), 0.2);
        for px in img.data.chunks_exact_mut(4) {
            px.copy_from_slice(&[0, 200, 0, 255]);
        }
        let mut b = TargetBuild::image(&scene, img.clone(), 16, 16.0, 30.0).unwrap();
        let e = loop {
            match b.step(&scene, 10) {
                Ok(Some(_)) => panic!("a green image matched"),
                Ok(None) => {}
                Err(e) => break e,
            }
        };
        let want = Target::from_image(&scene, &img, 16, 16.0, 30.0).unwrap_err();
        assert_eq!(e.to_string(), want.to_string());
        assert!(e.to_string().contains("100% of the target's pixels"), "{e}");
    }

    #[test]
    fn an_image_the_size_of_the_grid_keeps_the_exact_grid_fields() {
        let (scene, img, _) = disc(64, (0.5, 0.5), 0.2);
        let t = Target::from_image(&scene, &img, 64, 64.0, 60.0).unwrap();
        let (idx, _, _) = snap_to_palette_wh(&img, &scene.rec.colours, 64, 64, 60.0);
        let g = Target::from_indices(&scene, &idx, 64, 64.0);
        assert_eq!(t.sdf, g.sdf);
        assert_eq!(t.cover, g.cover);
    }

    /// The largest error, in grid pixels, of channel `colour`'s target field
    /// against `exact` (canvas units) over the grid pixels within 3 pixels
    /// of the outline and 4 pixels from the canvas edge (where fields are
    /// capped at the edge distance).
    fn worst_error(
        scene: &Scene,
        t: &Target,
        colour: Rgb,
        exact: &dyn Fn(f64, f64) -> f64,
    ) -> (f64, usize) {
        let n = t.grid.w;
        let k = scene
            .channels
            .iter()
            .position(|ch| scene.rec.colours[ch.colour as usize] == colour)
            .unwrap();
        let f = &t.sdf[k * n * n..(k + 1) * n * n];
        let to_px = n as f64 / t.scale;
        let (mut worst, mut count) = (0.0f64, 0);
        for y in 4..n - 4 {
            for x in 4..n - 4 {
                let truth =
                    exact((x as f64 + 0.5) / n as f64, (y as f64 + 0.5) / n as f64) * n as f64;
                if truth.abs() < 3.0 {
                    worst = worst.max((f[y * n + x] * to_px - truth).abs());
                    count += 1;
                }
            }
        }
        (worst, count)
    }

    /// An anti-aliased drawing uploaded in the browser goes through
    /// `pattern-snap` (what the user sees) before it becomes the target:
    /// the snap keeps its edge pixels as blends of two palette colours, so
    /// the target built from the snapped picture still has its outline to a
    /// tenth of a pixel. (Snapped to hard colours, as before, it was off by
    /// about half a pixel.)
    #[test]
    fn an_uploaded_antialiased_target_keeps_its_subpixel_edges_through_the_snap() {
        use crate::pattern::api::{snap_target, PatternSnapRequest};
        use crate::pattern::render::render;
        use crate::raster::encode_png;
        let src = "background \"#ffffff\";\ncircle(0.48, 0.53, 0.27, fill: \"#203040\");";
        let exact = |x: f64, y: f64| (x - 0.48).hypot(y - 0.53) - 0.27;
        let p = Program::parse(src).unwrap();
        let scene = Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap());
        let img = render(&scene, &scene.rec.float_values(), 256, 8).unwrap();
        let snapped = snap_target(&PatternSnapRequest {
            program: src.into(),
            bytes: encode_png(&img).unwrap(),
            size: 256,
            ..PatternSnapRequest::default()
        })
        .unwrap();
        let palette = &scene.rec.colours;
        let blends = snapped
            .image
            .rgba
            .chunks_exact(4)
            .filter(|px| !palette.iter().any(|c| c[..] == px[..3]))
            .count();
        assert!(blends > 100, "{blends} edge pixels kept as blends");
        let shown = Rgba8Image::from_raw(256, 256, snapped.image.rgba).unwrap();
        let t = Target::from_image(&scene, &shown, 128, 128.0, 60.0).unwrap();
        let (worst, count) = worst_error(&scene, &t, [0x20, 0x30, 0x40], &exact);
        assert!(count > 100, "{count} pixels near the outline");
        assert!(worst < 0.1, "largest error {worst} px after the snap");
    }

    /// A disc and a slanted band drawn anti-aliased by the renderer: the
    /// target field is within a tenth of a grid pixel of the true signed
    /// distance at every pixel within 3 pixels of the outline, on a grid the
    /// image's size and on one half of it. The fields of the same image
    /// snapped to hard masks (what targets were before, distances between
    /// pixel centres) are off by a quarter to half a pixel.
    #[test]
    fn an_antialiased_target_puts_the_outline_to_a_tenth_of_a_pixel() {
        use crate::pattern::render::render;
        // The band is wide enough (7 grid pixels at 96²) that its ridge stays
        // farther than 3 pixels from the outline: sampling a finer field
        // bilinearly rounds a ridge off by up to half a fine pixel.
        let (a, w) = (0.47f64, 0.075);
        let (sa, ca) = a.sin_cos();
        type Shape = (String, Box<dyn Fn(f64, f64) -> f64>);
        let shapes: [Shape; 2] = [
            (
                "circle(0.48, 0.53, 0.27, fill: \"#000000\");".into(),
                Box::new(|x: f64, y: f64| (x - 0.48).hypot(y - 0.53) - 0.27),
            ),
            (
                format!(
                    "segment(0.5 - 2 * cos({a}), 0.5 - 2 * sin({a}), 0.5 + 2 * cos({a}), \
                     0.5 + 2 * sin({a}), stroke: \"#000000\", width: {w});"
                ),
                Box::new(move |x: f64, y: f64| ((x - 0.5) * sa - (y - 0.5) * ca).abs() - w / 2.0),
            ),
        ];
        for (shape, exact) in &shapes {
            let src = format!("background \"#ffffff\";\n{shape}");
            let p = Program::parse(&src).unwrap();
            let scene = Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap());
            let x = scene.rec.float_values();
            for (side, n) in [(128usize, 128usize), (256, 128), (192, 96)] {
                let img = render(&scene, &x, side, 8).unwrap();
                let t = Target::from_image(&scene, &img, n, n as f64, 60.0).unwrap();
                let (worst, count) = worst_error(&scene, &t, [0, 0, 0], exact);
                assert!(count > 100, "{count} pixels near the outline");
                // The same image as hard masks: the fields before.
                let (fw, fh) = field_side(&img, &Grid::square(n));
                let (idx, _, _) = snap_to_palette_wh(&img, &scene.rec.colours, fw, fh, 60.0);
                let hard = TargetBuild::fields(idx, vec![], fw, fh, Grid::square(n), n as f64, 0.0)
                    .finish(&scene);
                let (before, _) = worst_error(&scene, &hard, [0, 0, 0], exact);
                eprintln!(
                    "{shape} {side}→{n}: largest error {worst:.3} px (hard masks {before:.3})"
                );
                assert!(worst < 0.1, "{shape} {side}→{n}: largest error {worst} px");
                // The hard masks fail the same bound.
                assert!(before > 0.2, "{shape} {side}→{n}: hard masks {before} px");
            }
        }
    }

    /// An anti-aliased image's target (fractional coverage, the
    /// anti-aliased transform) built a few rows at a time equals the one-go
    /// target bit for bit.
    #[test]
    fn stepping_an_antialiased_target_gives_the_same_bits() {
        let (scene, _, _) = disc(8, (0.45, 0.55), 0.3);
        let x = scene.rec.float_values();
        for (side, n) in [(64usize, 32usize), (32, 32), (20, 32)] {
            let img = crate::pattern::render::render(&scene, &x, side, 4).unwrap();
            let one_go = Target::from_image(&scene, &img, n, n as f64, 60.0).unwrap();
            for budget in [1, 500, 1 << 40] {
                let b = TargetBuild::image(&scene, img.clone(), n, n as f64, 60.0).unwrap();
                let (t, _) = stepped(&scene, b, budget);
                assert!(same_bits(&t, &one_go), "{side}→{n}, budget {budget}");
            }
        }
    }

    /// Any image gives a target or an error, never a panic: noise in any
    /// colour, a single pixel, one flat colour, a thin sliver.
    #[test]
    fn any_image_gives_a_target_or_an_error() {
        let (scene, _, _) = disc(8, (0.5, 0.5), 0.2);
        let mut rng = crate::core::rng::Rng::new(17);
        let mut images = vec![];
        for (w, h) in [(1u32, 1u32), (1, 40), (37, 2), (50, 50)] {
            let mut noise = Rgba8Image::new(w, h);
            let mut grey = Rgba8Image::new(w, h);
            for y in 0..h {
                for x in 0..w {
                    let px: [u8; 4] = std::array::from_fn(|_| rng.below(256) as u8);
                    noise.put(x, y, px);
                    let g = (x * 255 / w.max(1)) as u8;
                    grey.put(x, y, [g, g, g, 255]);
                }
            }
            images.push(noise);
            images.push(grey);
        }
        for img in images {
            // On the square canvas (stretched) and on the image's own.
            let canvas = crate::pattern::fit::image_canvas(&img);
            let rec = scene.rec.clone();
            let own = Scene::new(crate::pattern::record::Recording { canvas, ..rec });
            for sc in [&scene, &own] {
                for n in [1, 16, 33] {
                    match Target::from_image(sc, &img, n, n as f64, 200.0) {
                        Ok(t) => {
                            assert_eq!((t.grid.w, t.grid.h), canvas_grid(sc, n));
                            assert_eq!(t.sdf.len(), sc.channels.len() * t.grid.len());
                            assert!(t.sdf.iter().all(|v| v.is_finite()));
                        }
                        Err(e) => {
                            assert!(e.to_string().contains("not close to any colour"), "{e}")
                        }
                    }
                }
            }
        }
    }

    fn canvas_grid(scene: &Scene, n: usize) -> (usize, usize) {
        scene.rec.canvas.grid(n)
    }

    /// A 300 × 240 disc image on its own canvas ([0, 1.25] × [0, 1]) on a
    /// grid of its size: the target's field is the disc's exact distance
    /// (a round disc, not an ellipse), to half a pixel, the grid 300 × 240.
    #[test]
    fn a_non_square_image_gives_round_fields_on_its_canvas() {
        use crate::pattern::record::Canvas;
        let canvas = Canvas::of_pixels(300, 240);
        let src = "background \"#ffffff\";\ncircle(0.7, 0.45, 0.3, fill: \"#000000\");";
        let p = Program::parse(src).unwrap();
        let rec = p
            .record_on(&p.defaults(), &RecordLimits::default(), canvas)
            .unwrap();
        let scene = Scene::new(rec);
        let img = crate::pattern::render::render(&scene, &[], 300, 1).unwrap();
        assert_eq!((img.width, img.height), (300, 240));
        let t = Target::from_image(&scene, &img, 300, 240.0, 60.0).unwrap();
        assert_eq!((t.grid.w, t.grid.h), (300, 240));
        let k = scene
            .channels
            .iter()
            .position(|ch| scene.rec.colours[ch.colour as usize] == [0, 0, 0])
            .unwrap();
        let f = &t.sdf[k * t.grid.len()..(k + 1) * t.grid.len()];
        let mut near = 0;
        for y in 0..240 {
            for x in 0..300 {
                let (u, v) = ((x as f64 + 0.5) / 240.0, (y as f64 + 0.5) / 240.0);
                let truth = ((u - 0.7).hypot(v - 0.45) - 0.3) * 240.0;
                if truth.abs() < 3.0 {
                    near += 1;
                    let e = (f[y * 300 + x] - truth).abs();
                    assert!(e <= 0.75, "pixel ({x}, {y}): {} vs {truth}", f[y * 300 + x]);
                }
            }
        }
        assert!(near > 1000, "{near} pixels near the outline");
    }
}
