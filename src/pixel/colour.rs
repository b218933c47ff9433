//! Section 3.2: colour maps — HSV shift, colour difference, shared border and
//! the automatic choice between them with `d_max`.
//!
//! A colour map has one colour per source pixel; placement samples it under
//! each element. Transparent source pixels (alpha 0) are not colours: they map
//! to transparent, never border anything and never count in a palette.
//! CIELAB uses the pure-Rust `libm` so that native and wasm round identically.
use crate::raster::Rgba8Image;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Which colour map to build.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum ColourStrategy {
    /// Shared border unless it changes some region by `d_max` or more in
    /// CIELAB (then colour difference); HSV shift when at most one usable
    /// colour exists.
    #[default]
    Auto,
    /// Shift hue, saturation and value of every pixel (adds new colours).
    Hsv,
    /// Nearest *other* palette colour in CIELAB.
    Difference,
    /// Most frequent colour bordering each contiguous colour region.
    Border,
}

/// The map actually built (what `Auto` resolved to).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum ColourMapKind {
    Hsv,
    Difference,
    Border,
}

impl ColourMapKind {
    /// Lower-case name, as in the CLI and JSON.
    pub fn name(self) -> &'static str {
        match self {
            ColourMapKind::Hsv => "hsv",
            ColourMapKind::Difference => "difference",
            ColourMapKind::Border => "border",
        }
    }
}

/// Settings of the colour stage.
#[derive(Debug, Clone, PartialEq)]
pub struct ColourParams {
    pub strategy: ColourStrategy,
    /// Hue shift in degrees, saturation and value shifts in percentage points.
    pub hsv: [f64; 3],
    /// RGB colours never chosen as element colours (by border or difference)
    /// and ignored when `Auto` counts colours and measures distances.
    pub exclude: Vec<[u8; 3]>,
    /// Largest CIELAB distance (ΔE*76) the shared-border map may move a region's colour.
    pub d_max: f64,
}

/// sRGB (8-bit) to CIELAB (D65).
pub fn lab(c: [u8; 4]) -> [f64; 3] {
    fn lin(v: u8) -> f64 {
        let c = v as f64 / 255.0;
        if c <= 0.04045 {
            c / 12.92
        } else {
            libm::pow((c + 0.055) / 1.055, 2.4)
        }
    }
    fn f(t: f64) -> f64 {
        const D: f64 = 6.0 / 29.0;
        if t > D * D * D {
            libm::cbrt(t)
        } else {
            t / (3.0 * D * D) + 4.0 / 29.0
        }
    }
    let (r, g, b) = (lin(c[0]), lin(c[1]), lin(c[2]));
    let x = (0.4124564 * r + 0.3575761 * g + 0.1804375 * b) / 0.95047;
    let y = 0.2126729 * r + 0.7151522 * g + 0.0721750 * b;
    let z = (0.0193339 * r + 0.1191920 * g + 0.9503041 * b) / 1.08883;
    let (fx, fy, fz) = (f(x), f(y), f(z));
    [116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz)]
}

/// Euclidean distance in CIELAB.
pub fn lab_distance(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Shift hue (degrees), saturation and value (percentage points) of one colour.
/// Only arithmetic, so every platform rounds the same.
pub fn hsv_shift(c: [u8; 4], d: [f64; 3]) -> [u8; 4] {
    let (r, g, b) = (
        c[0] as f64 / 255.0,
        c[1] as f64 / 255.0,
        c[2] as f64 / 255.0,
    );
    let max = r.max(g).max(b);
    let min = r.min(g).min(b);
    let delta = max - min;
    let mut h = if delta == 0.0 {
        0.0
    } else if max == r {
        60.0 * ((g - b) / delta)
    } else if max == g {
        60.0 * ((b - r) / delta + 2.0)
    } else {
        60.0 * ((r - g) / delta + 4.0)
    };
    let s = if max == 0.0 { 0.0 } else { delta / max };
    h = (h + d[0]).rem_euclid(360.0);
    let s = (s + d[1] / 100.0).clamp(0.0, 1.0);
    let v = (max + d[2] / 100.0).clamp(0.0, 1.0);
    let cc = v * s;
    let hp = h / 60.0;
    let x = cc * (1.0 - ((hp % 2.0) - 1.0).abs());
    let (r1, g1, b1) = match hp as u32 {
        0 => (cc, x, 0.0),
        1 => (x, cc, 0.0),
        2 => (0.0, cc, x),
        3 => (0.0, x, cc),
        4 => (x, 0.0, cc),
        _ => (cc, 0.0, x),
    };
    let m = v - cc;
    let q = |u: f64| ((u + m) * 255.0).round().clamp(0.0, 255.0) as u8;
    [q(r1), q(g1), q(b1), c[3]]
}

fn rgb(c: [u8; 4]) -> [u8; 3] {
    [c[0], c[1], c[2]]
}

/// Contiguous (4-connected) regions of one exact colour.
pub struct Regions {
    /// Region index per pixel; `u32::MAX` for transparent pixels.
    pub label: Vec<u32>,
    /// Colour of each region.
    pub colour: Vec<[u8; 4]>,
    /// Pixel indices of each region, concatenated; region r is
    /// `pixels[start[r]..start[r + 1]]`.
    pub pixels: Vec<u32>,
    pub start: Vec<u32>,
}

#[cfg(test)] // the one-go reference that ColourMapper is checked against
/// Label contiguous colour regions with 4-connectivity: in pixel art a
/// diagonal touch does not join two areas of flat colour.
pub fn regions(img: &Rgba8Image) -> Regions {
    let (w, h) = (img.width as usize, img.height as usize);
    let px = |i: usize| img.at(i);
    let mut label = vec![u32::MAX; w * h];
    let (mut colour, mut pixels, mut start) = (Vec::new(), Vec::with_capacity(w * h), vec![0u32]);
    let mut stack = Vec::new();
    for seed in 0..w * h {
        if label[seed] != u32::MAX || px(seed)[3] == 0 {
            continue;
        }
        let r = colour.len() as u32;
        let c = px(seed);
        colour.push(c);
        label[seed] = r;
        stack.push(seed);
        while let Some(i) = stack.pop() {
            pixels.push(i as u32);
            let (x, y) = (i % w, i / w);
            let mut visit = |j: usize| {
                if label[j] == u32::MAX && px(j) == c {
                    label[j] = r;
                    stack.push(j);
                }
            };
            if x > 0 {
                visit(i - 1);
            }
            if x + 1 < w {
                visit(i + 1);
            }
            if y > 0 {
                visit(i - w);
            }
            if y + 1 < h {
                visit(i + w);
            }
        }
        start.push(pixels.len() as u32);
    }
    Regions {
        label,
        colour,
        pixels,
        start,
    }
}

#[cfg(test)] // the one-go reference that ColourMapper is checked against
/// Palette of an image: distinct colours of non-transparent pixels, sorted.
fn palette(img: &Rgba8Image) -> Vec<[u8; 4]> {
    let mut seen: HashMap<[u8; 4], ()> = HashMap::new();
    for p in img.pixels().filter(|p| p[3] > 0) {
        seen.insert(p, ());
    }
    // Sorted, so nothing downstream depends on hash order.
    let mut v: Vec<[u8; 4]> = seen.into_keys().collect();
    v.sort_unstable();
    v
}

/// Map each palette colour to its nearest *other* palette colour in CIELAB,
/// skipping excluded colours (ties: the smaller RGBA value). A colour with no
/// other usable colour keeps itself.
pub fn difference_table(pal: &[[u8; 4]], exclude: &[[u8; 3]]) -> HashMap<[u8; 4], [u8; 4]> {
    let labs: Vec<[f64; 3]> = pal.iter().map(|&c| lab(c)).collect();
    let mut out = HashMap::new();
    for (i, &c) in pal.iter().enumerate() {
        let mut best: Option<(f64, usize)> = None;
        for (j, &o) in pal.iter().enumerate() {
            if j == i || exclude.contains(&rgb(o)) {
                continue;
            }
            let d = lab_distance(labs[i], labs[j]);
            // `pal` is sorted, so strict `<` keeps the smaller colour on ties.
            if best.is_none_or(|(bd, _)| d < bd) {
                best = Some((d, j));
            }
        }
        out.insert(c, best.map_or(c, |(_, j)| pal[j]));
    }
    out
}

#[cfg(test)] // the one-go reference that ColourMapper is checked against
/// The shared-border colour of every region: the most frequent colour among
/// the distinct pixels 4-adjacent to it (transparent and excluded colours
/// skipped). Ties go to the colour nearer the region's own in CIELAB, then to
/// the smaller RGBA value. `None` when no usable colour borders the region.
pub fn border_colours(
    img: &Rgba8Image,
    reg: &Regions,
    exclude: &[[u8; 3]],
) -> Vec<Option<[u8; 4]>> {
    let (w, h) = (img.width as usize, img.height as usize);
    let px = |i: usize| img.at(i);
    // stamp[j] == r + 1 means pixel j was already counted for region r.
    let mut stamp = vec![0u32; w * h];
    let mut out = Vec::with_capacity(reg.colour.len());
    let mut counts: Vec<([u8; 4], u32)> = Vec::new();
    for r in 0..reg.colour.len() {
        counts.clear();
        let own = &reg.pixels[reg.start[r] as usize..reg.start[r + 1] as usize];
        for &i in own {
            let i = i as usize;
            let (x, y) = (i % w, i / w);
            let mut nb = [usize::MAX; 4];
            if x > 0 {
                nb[0] = i - 1;
            }
            if x + 1 < w {
                nb[1] = i + 1;
            }
            if y > 0 {
                nb[2] = i - w;
            }
            if y + 1 < h {
                nb[3] = i + w;
            }
            for j in nb {
                if j == usize::MAX || reg.label[j] == r as u32 || stamp[j] == r as u32 + 1 {
                    continue;
                }
                stamp[j] = r as u32 + 1;
                let c = px(j);
                if c[3] == 0 || exclude.contains(&rgb(c)) {
                    continue;
                }
                match counts.iter_mut().find(|e| e.0 == c) {
                    Some(e) => e.1 += 1,
                    None => counts.push((c, 1)),
                }
            }
        }
        let own_lab = lab(reg.colour[r]);
        let best = counts
            .iter()
            .map(|&(c, n)| (n, lab_distance(own_lab, lab(c)), c))
            .min_by(|a, b| b.0.cmp(&a.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
        out.push(best.map(|b| b.2));
    }
    out
}

/// A colour map and which strategy produced it.
pub struct ColourMap {
    pub map: Rgba8Image,
    pub kind: ColourMapKind,
}

#[cfg(test)] // the one-go reference that ColourMapper is checked against
/// Build the colour map for `src` (Section 3.2). `mask` limits which regions
/// the automatic choice inspects: only regions that can receive elements
/// matter for how stark the result looks.
pub fn colour_map(src: &Rgba8Image, mask: &[bool], p: &ColourParams) -> ColourMap {
    let kind = match p.strategy {
        ColourStrategy::Hsv => ColourMapKind::Hsv,
        ColourStrategy::Difference => ColourMapKind::Difference,
        ColourStrategy::Border => ColourMapKind::Border,
        ColourStrategy::Auto => {
            let pal = palette(src);
            let usable = pal
                .iter()
                .filter(|c| !p.exclude.contains(&rgb(**c)))
                .count();
            if usable <= 1 {
                ColourMapKind::Hsv
            } else {
                let reg = regions(src);
                let border = border_colours(src, &reg, &p.exclude);
                let diff = difference_table(&pal, &p.exclude);
                let far = (0..reg.colour.len()).any(|r| {
                    let own = reg.colour[r];
                    let px = &reg.pixels[reg.start[r] as usize..reg.start[r + 1] as usize];
                    if p.exclude.contains(&rgb(own)) || !px.iter().any(|&i| mask[i as usize]) {
                        return false;
                    }
                    let to = border[r].unwrap_or(diff[&own]);
                    lab_distance(lab(own), lab(to)) >= p.d_max
                });
                let map = border_map(src, &reg, &border, &diff);
                if !far {
                    return ColourMap {
                        map,
                        kind: ColourMapKind::Border,
                    };
                }
                ColourMapKind::Difference
            }
        }
    };
    let map = match kind {
        ColourMapKind::Hsv => {
            let mut m = src.clone();
            for c in m.data.chunks_exact_mut(4) {
                if c[3] > 0 {
                    let s = hsv_shift([c[0], c[1], c[2], c[3]], p.hsv);
                    c.copy_from_slice(&s);
                }
            }
            m
        }
        ColourMapKind::Difference => {
            let table = difference_table(&palette(src), &p.exclude);
            let mut m = src.clone();
            for c in m.data.chunks_exact_mut(4) {
                if c[3] > 0 {
                    c.copy_from_slice(&table[&[c[0], c[1], c[2], c[3]]]);
                }
            }
            m
        }
        ColourMapKind::Border => {
            let reg = regions(src);
            let border = border_colours(src, &reg, &p.exclude);
            let diff = difference_table(&palette(src), &p.exclude);
            border_map(src, &reg, &border, &diff)
        }
    };
    ColourMap { map, kind }
}

#[cfg(test)] // the one-go reference that ColourMapper is checked against
/// Paint every region with its border colour. A region bordered only by
/// transparent or excluded pixels (e.g. a one-colour sprite inside a black
/// outline) falls back to its colour-difference colour, which is still a
/// palette colour, instead of keeping its own and hiding the elements.
fn border_map(
    src: &Rgba8Image,
    reg: &Regions,
    border: &[Option<[u8; 4]>],
    diff: &HashMap<[u8; 4], [u8; 4]>,
) -> Rgba8Image {
    let mut m = Rgba8Image::new(src.width, src.height);
    for (i, &l) in reg.label.iter().enumerate() {
        if l != u32::MAX {
            let c = border[l as usize].unwrap_or_else(|| diff[&reg.colour[l as usize]]);
            m.data[4 * i..4 * i + 4].copy_from_slice(&c);
        }
    }
    m
}

/// Where a [`ColourMapper`] is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MapPhase {
    Palette,
    Regions,
    Border,
    Diff,
    Far,
    Paint,
    Done,
}

/// [`colour_map`] in bounded steps: each phase (palette, regions, border
/// colours, difference table, the automatic choice, painting) goes on for
/// about `budget` pixels (or table entries) per [`ColourMapper::run`]. The
/// map is the one [`colour_map`] makes, byte for byte.
pub struct ColourMapper {
    p: ColourParams,
    phase: MapPhase,
    /// What the map will be, once decided.
    kind: ColourMapKind,
    pos: usize,
    seen: std::collections::HashSet<[u8; 4]>,
    pal: Vec<[u8; 4]>,
    labs: Vec<[f64; 3]>,
    // Regions under construction (see [`regions`]; here a label is the
    // region + 1 and 0 means none).
    reg: Regions,
    stack: Vec<usize>,
    current: Option<(u32, [u8; 4])>,
    // Border colours under construction (see [`border_colours`]).
    border: Vec<Option<[u8; 4]>>,
    stamp: Vec<u32>,
    counts: Vec<([u8; 4], u32)>,
    /// Offset inside the current region (border colours, the `far` test).
    k: usize,
    diff: HashMap<[u8; 4], [u8; 4]>,
    map: Rgba8Image,
}

impl ColourMapper {
    pub fn new(src: &Rgba8Image, p: &ColourParams) -> ColourMapper {
        let (phase, kind) = match p.strategy {
            ColourStrategy::Hsv => (MapPhase::Paint, ColourMapKind::Hsv),
            ColourStrategy::Difference => (MapPhase::Palette, ColourMapKind::Difference),
            ColourStrategy::Border => (MapPhase::Palette, ColourMapKind::Border),
            // Decided after the `far` test.
            ColourStrategy::Auto => (MapPhase::Palette, ColourMapKind::Border),
        };
        ColourMapper {
            p: p.clone(),
            phase,
            kind,
            pos: 0,
            seen: Default::default(),
            pal: vec![],
            labs: vec![],
            reg: Regions {
                label: vec![],
                colour: vec![],
                pixels: vec![],
                start: vec![0],
            },
            stack: vec![],
            current: None,
            border: vec![],
            stamp: vec![],
            counts: vec![],
            k: 0,
            diff: HashMap::new(),
            map: Rgba8Image::new(src.width, src.height),
        }
    }

    /// Go on for about `budget` units of work; `true` when the map is made.
    pub fn run(&mut self, src: &Rgba8Image, mask: &[bool], budget: usize) -> bool {
        let budget = budget.max(1);
        let mut spent = 0usize;
        let n = src.pixel_count();
        let (w, h) = (src.width as usize, src.height as usize);
        while spent < budget {
            match self.phase {
                MapPhase::Palette => {
                    let end = n.min(self.pos + budget - spent);
                    for i in self.pos..end {
                        let c = src.at(i);
                        if c[3] > 0 {
                            self.seen.insert(c);
                        }
                    }
                    spent += end - self.pos;
                    self.pos = end;
                    if end == n {
                        let mut v: Vec<[u8; 4]> =
                            std::mem::take(&mut self.seen).into_iter().collect();
                        v.sort_unstable();
                        self.pal = v;
                        self.labs = self.pal.iter().map(|&c| lab(c)).collect();
                        self.pos = 0;
                        self.phase = match self.p.strategy {
                            ColourStrategy::Difference => MapPhase::Diff,
                            ColourStrategy::Auto
                                if self
                                    .pal
                                    .iter()
                                    .filter(|c| !self.p.exclude.contains(&rgb(**c)))
                                    .count()
                                    <= 1 =>
                            {
                                self.kind = ColourMapKind::Hsv;
                                MapPhase::Paint
                            }
                            _ => {
                                // Labels are region + 1 here (0 = none): a zeroed
                                // allocation costs nothing until touched.
                                self.reg.label = vec![0; n];
                                self.reg.pixels = Vec::with_capacity(n);
                                MapPhase::Regions
                            }
                        };
                    }
                }
                MapPhase::Regions => {
                    // `regions`, resumable between any two pixels (labels + 1).
                    let reg = &mut self.reg;
                    if let Some((r, c)) = self.current {
                        while spent < budget {
                            let Some(i) = self.stack.pop() else { break };
                            reg.pixels.push(i as u32);
                            let (x, y) = (i % w, i / w);
                            let mut visit = |j: usize| {
                                if reg.label[j] == 0 && src.at(j) == c {
                                    reg.label[j] = r + 1;
                                    self.stack.push(j);
                                }
                            };
                            if x > 0 {
                                visit(i - 1);
                            }
                            if x + 1 < w {
                                visit(i + 1);
                            }
                            if y > 0 {
                                visit(i - w);
                            }
                            if y + 1 < h {
                                visit(i + w);
                            }
                            spent += 1;
                        }
                        if !self.stack.is_empty() {
                            continue;
                        }
                        reg.start.push(reg.pixels.len() as u32);
                        self.current = None;
                    }
                    while self.pos < n && spent < budget {
                        let seed = self.pos;
                        if reg.label[seed] == 0 && src.at(seed)[3] != 0 {
                            break;
                        }
                        self.pos += 1;
                        spent += 1;
                    }
                    if self.pos == n {
                        self.pos = 0;
                        self.stamp = vec![0u32; n];
                        self.phase = MapPhase::Border;
                    } else if spent < budget {
                        let seed = self.pos;
                        let r = reg.colour.len() as u32;
                        let c = src.at(seed);
                        reg.colour.push(c);
                        reg.label[seed] = r + 1;
                        self.stack.push(seed);
                        self.current = Some((r, c));
                        self.pos += 1;
                        spent += 1;
                    }
                }
                MapPhase::Border => {
                    // `border_colours`, resumable inside a region.
                    let reg = &self.reg;
                    let r = self.pos;
                    if r == reg.colour.len() {
                        self.stamp = vec![];
                        self.pos = 0;
                        self.phase = MapPhase::Diff;
                        continue;
                    }
                    let own = &reg.pixels[reg.start[r] as usize..reg.start[r + 1] as usize];
                    while self.k < own.len() && spent < budget {
                        let i = own[self.k] as usize;
                        let (x, y) = (i % w, i / w);
                        let mut nb = [usize::MAX; 4];
                        if x > 0 {
                            nb[0] = i - 1;
                        }
                        if x + 1 < w {
                            nb[1] = i + 1;
                        }
                        if y > 0 {
                            nb[2] = i - w;
                        }
                        if y + 1 < h {
                            nb[3] = i + w;
                        }
                        for j in nb {
                            if j == usize::MAX
                                || reg.label[j] == r as u32 + 1
                                || self.stamp[j] == r as u32 + 1
                            {
                                continue;
                            }
                            self.stamp[j] = r as u32 + 1;
                            let c = src.at(j);
                            if c[3] == 0 || self.p.exclude.contains(&rgb(c)) {
                                continue;
                            }
                            match self.counts.iter_mut().find(|e| e.0 == c) {
                                Some(e) => e.1 += 1,
                                None => self.counts.push((c, 1)),
                            }
                        }
                        self.k += 1;
                        spent += 1;
                    }
                    if self.k < own.len() {
                        continue;
                    }
                    let own_lab = lab(reg.colour[r]);
                    let best = self
                        .counts
                        .iter()
                        .map(|&(c, n)| (n, lab_distance(own_lab, lab(c)), c))
                        .min_by(|a, b| b.0.cmp(&a.0).then(a.1.total_cmp(&b.1)).then(a.2.cmp(&b.2)));
                    self.border.push(best.map(|b| b.2));
                    self.counts.clear();
                    self.k = 0;
                    self.pos += 1;
                    spent += 1;
                }
                MapPhase::Diff => {
                    // `difference_table`, a colour (one row of distances) at a time.
                    let pal = &self.pal;
                    while self.pos < pal.len() && spent < budget {
                        let i = self.pos;
                        let mut best: Option<(f64, usize)> = None;
                        for (j, &o) in pal.iter().enumerate() {
                            if j == i || self.p.exclude.contains(&rgb(o)) {
                                continue;
                            }
                            let d = lab_distance(self.labs[i], self.labs[j]);
                            if best.is_none_or(|(bd, _)| d < bd) {
                                best = Some((d, j));
                            }
                        }
                        self.diff
                            .insert(pal[i], best.map_or(pal[i], |(_, j)| pal[j]));
                        self.pos += 1;
                        spent += pal.len().max(1);
                    }
                    if self.pos == pal.len() {
                        self.pos = 0;
                        self.phase = if self.p.strategy == ColourStrategy::Auto {
                            MapPhase::Far
                        } else {
                            MapPhase::Paint
                        };
                    }
                }
                MapPhase::Far => {
                    // Would the shared-border map move a region that can
                    // receive elements by `d_max` or more?
                    let reg = &self.reg;
                    let r = self.pos;
                    if r == reg.colour.len() {
                        self.pos = 0;
                        self.phase = MapPhase::Paint;
                        continue;
                    }
                    let own = reg.colour[r];
                    let px = &reg.pixels[reg.start[r] as usize..reg.start[r + 1] as usize];
                    let mut hit = false;
                    if !self.p.exclude.contains(&rgb(own)) {
                        while self.k < px.len() && spent < budget {
                            if mask[px[self.k] as usize] {
                                hit = true;
                                break;
                            }
                            self.k += 1;
                            spent += 1;
                        }
                        if !hit && self.k < px.len() {
                            continue;
                        }
                    }
                    spent += 1;
                    self.k = 0;
                    self.pos += 1;
                    if hit {
                        let to = self.border[r].unwrap_or(self.diff[&own]);
                        if lab_distance(lab(own), lab(to)) >= self.p.d_max {
                            self.kind = ColourMapKind::Difference;
                            self.pos = 0;
                            self.phase = MapPhase::Paint;
                        }
                    }
                }
                MapPhase::Paint => {
                    let end = n.min(self.pos + budget - spent);
                    let out = &mut self.map.data[4 * self.pos..4 * end];
                    let inp = &src.data[4 * self.pos..4 * end];
                    match self.kind {
                        ColourMapKind::Hsv => {
                            for (o, c) in out.chunks_exact_mut(4).zip(inp.chunks_exact(4)) {
                                let c = [c[0], c[1], c[2], c[3]];
                                o.copy_from_slice(&if c[3] > 0 {
                                    hsv_shift(c, self.p.hsv)
                                } else {
                                    c
                                });
                            }
                        }
                        ColourMapKind::Difference => {
                            for (o, c) in out.chunks_exact_mut(4).zip(inp.chunks_exact(4)) {
                                let c = [c[0], c[1], c[2], c[3]];
                                o.copy_from_slice(&if c[3] > 0 { self.diff[&c] } else { c });
                            }
                        }
                        ColourMapKind::Border => {
                            let label = &self.reg.label[self.pos..end];
                            for (o, &l) in out.chunks_exact_mut(4).zip(label) {
                                if l != 0 {
                                    let r = l as usize - 1;
                                    let c = self.border[r]
                                        .unwrap_or_else(|| self.diff[&self.reg.colour[r]]);
                                    o.copy_from_slice(&c);
                                }
                            }
                        }
                    }
                    spent += end - self.pos;
                    self.pos = end;
                    if end == n {
                        self.phase = MapPhase::Done;
                    }
                }
                MapPhase::Done => return true,
            }
        }
        self.phase == MapPhase::Done
    }

    /// How far along, `0..=1` (by phase, then position in it).
    pub fn fraction(&self) -> f64 {
        let k = match self.phase {
            MapPhase::Palette => 0,
            MapPhase::Regions => 1,
            MapPhase::Border => 2,
            MapPhase::Diff => 3,
            MapPhase::Far => 4,
            MapPhase::Paint => 5,
            MapPhase::Done => return 1.0,
        };
        let total = match self.phase {
            MapPhase::Border | MapPhase::Far => self.reg.colour.len(),
            MapPhase::Diff => self.pal.len(),
            _ => self.map.pixel_count(),
        };
        (k as f64 + (self.pos as f64 / total.max(1) as f64).min(1.0)) / 6.0
    }

    /// The finished map (after [`ColourMapper::run`] returned `true`).
    pub fn finish(self) -> ColourMap {
        ColourMap {
            map: self.map,
            kind: self.kind,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const K: [u8; 4] = [0, 0, 0, 255];
    const R: [u8; 4] = [200, 30, 30, 255];
    const G: [u8; 4] = [30, 160, 40, 255];
    const B: [u8; 4] = [40, 40, 200, 255];
    const P: [u8; 4] = [220, 40, 60, 255];

    fn img(rows: &[&[[u8; 4]]]) -> Rgba8Image {
        let mut m = Rgba8Image::new(rows[0].len() as u32, rows.len() as u32);
        for (y, r) in rows.iter().enumerate() {
            for (x, &c) in r.iter().enumerate() {
                m.put(x as u32, y as u32, c);
            }
        }
        m
    }

    fn params(strategy: ColourStrategy) -> ColourParams {
        ColourParams {
            strategy,
            hsv: [0.0, 0.0, -30.0],
            exclude: vec![[0, 0, 0]],
            d_max: 50.0,
        }
    }

    #[test]
    fn lab_matches_reference_values() {
        let w = lab([255, 255, 255, 255]);
        assert!(
            (w[0] - 100.0).abs() < 0.01 && w[1].abs() < 0.01 && w[2].abs() < 0.01,
            "{w:?}"
        );
        // sRGB red is L 53.24, a 80.09, b 67.20.
        let r = lab([255, 0, 0, 255]);
        assert!(
            (r[0] - 53.24).abs() < 0.02
                && (r[1] - 80.09).abs() < 0.05
                && (r[2] - 67.20).abs() < 0.05,
            "{r:?}"
        );
    }

    #[test]
    fn hsv_shift_round_trips_and_shifts() {
        for c in [
            [12, 200, 99, 255],
            [255, 255, 255, 7],
            [0, 0, 0, 255],
            [128, 64, 250, 255],
        ] {
            assert_eq!(hsv_shift(c, [0.0, 0.0, 0.0]), c);
        }
        assert_eq!(
            hsv_shift([255, 0, 0, 255], [120.0, 0.0, 0.0]),
            [0, 255, 0, 255]
        );
        assert_eq!(
            hsv_shift([200, 100, 100, 255], [0.0, 0.0, -100.0]),
            [0, 0, 0, 255]
        );
        assert_eq!(
            hsv_shift([200, 100, 100, 255], [0.0, -100.0, 0.0]),
            [200, 200, 200, 255]
        );
    }

    #[test]
    fn difference_picks_nearest_other_colour_in_lab() {
        // P (pinkish red) is nearest to R, R to P; G's nearest other is... not
        // black (excluded) — B or R/P, whichever is nearer in Lab.
        let src = img(&[&[R, P, G, B, K]]);
        let m = colour_map(&src, &[true; 5], &params(ColourStrategy::Difference));
        assert_eq!(m.kind, ColourMapKind::Difference);
        assert_eq!(m.map.get(0, 0), P);
        assert_eq!(m.map.get(1, 0), R);
        let lg = lab(G);
        let want_g = [R, P, B]
            .into_iter()
            .min_by(|a, b| lab_distance(lg, lab(*a)).total_cmp(&lab_distance(lg, lab(*b))))
            .unwrap();
        assert_eq!(m.map.get(2, 0), want_g);
        // Black itself may be recoloured (it is a source colour) but never chosen.
        for x in 0..5 {
            assert_ne!(m.map.get(x, 0), K);
        }
        // Without the exclusion, black's nearest other colour is chosen as usual
        // and blue's nearest may be black.
        let no_ex = ColourParams {
            exclude: vec![],
            ..params(ColourStrategy::Difference)
        };
        let m = colour_map(&src, &[true; 5], &no_ex);
        let lb = lab(B);
        let want_b = [R, P, G, K]
            .into_iter()
            .min_by(|a, b| lab_distance(lb, lab(*a)).total_cmp(&lab_distance(lb, lab(*b))))
            .unwrap();
        assert_eq!(m.map.get(3, 0), want_b);
    }

    #[test]
    fn border_picks_most_frequent_neighbour_skipping_excluded() {
        // The R region (2×2 in the middle) is bordered by 4 K, 3 G, 1 B pixels.
        // Black is excluded, so G wins; without exclusion K wins.
        let src = img(&[&[K, K, K, K], &[G, R, R, K], &[G, R, R, B], &[G, G, K, K]]);
        // Counting distinct bordering pixels: above (1,0),(2,0)=K,K; right
        // (3,1)=K,(3,2)=B; below (1,3)=G,(2,3)=K; left (0,1),(0,2)=G,G.
        // K:4, G:3, B:1.
        let mask = vec![true; 16];
        let m = colour_map(&src, &mask, &params(ColourStrategy::Border));
        assert_eq!(m.kind, ColourMapKind::Border);
        assert_eq!(m.map.get(1, 1), G);
        assert_eq!(m.map.get(2, 2), G);
        let no_ex = ColourParams {
            exclude: vec![],
            ..params(ColourStrategy::Border)
        };
        assert_eq!(colour_map(&src, &mask, &no_ex).map.get(1, 1), K);
    }

    #[test]
    fn transparent_pixels_stay_transparent_and_do_not_border() {
        let t = [0, 0, 0, 0];
        let src = img(&[&[t, t, t], &[t, R, G], &[t, t, t]]);
        let m = colour_map(&src, &[true; 9], &params(ColourStrategy::Border));
        assert_eq!(m.map.get(0, 0), t);
        assert_eq!(m.map.get(1, 1), G);
        assert_eq!(m.map.get(2, 1), R);
    }

    #[test]
    fn auto_selects_by_palette_and_distance() {
        // One usable colour (plus excluded black): HSV shift.
        let one = img(&[&[R, R, K]]);
        assert_eq!(
            colour_map(&one, &[true; 3], &params(ColourStrategy::Auto)).kind,
            ColourMapKind::Hsv
        );
        // R and P are close (shared border moves each by < 50): border.
        let close = img(&[&[R, R, P, P]]);
        assert!(lab_distance(lab(R), lab(P)) < 50.0);
        assert_eq!(
            colour_map(&close, &[true; 4], &params(ColourStrategy::Auto)).kind,
            ColourMapKind::Border
        );
        // R next to B: far apart, so colour difference.
        let far = img(&[&[R, R, B, B]]);
        assert!(lab_distance(lab(R), lab(B)) >= 50.0);
        let m = colour_map(&far, &[true; 4], &params(ColourStrategy::Auto));
        assert_eq!(m.kind, ColourMapKind::Difference);
        // ... unless d_max is raised above the distance.
        let lax = ColourParams {
            d_max: 500.0,
            ..params(ColourStrategy::Auto)
        };
        assert_eq!(
            colour_map(&far, &[true; 4], &lax).kind,
            ColourMapKind::Border
        );
        // Regions outside the mask do not count: with no region under the
        // mask nothing is "too far", so shared border stays.
        assert_eq!(
            colour_map(&far, &[false; 4], &params(ColourStrategy::Auto)).kind,
            ColourMapKind::Border
        );
    }

    /// The stepped colour map equals the one-go map byte for byte, for
    /// every strategy, on the thesis images (and one scaled up, so regions
    /// span many steps), whatever the budget.
    #[test]
    fn stepping_the_colour_map_gives_the_same_bytes_as_one_go() {
        use crate::raster::{decode, Limits};
        let fish = decode(
            include_bytes!("../../assets/pixel/fish.png"),
            Limits::default(),
        )
        .unwrap();
        let trunk = decode(
            include_bytes!("../../assets/pixel/trunk_unpatterned.png"),
            Limits::default(),
        )
        .unwrap();
        let mut big = Rgba8Image::new(fish.width * 3, fish.height * 3);
        for y in 0..big.height {
            for x in 0..big.width {
                big.put(x, y, fish.get(x / 3, y / 3));
            }
        }
        for img in [&fish, &trunk, &big] {
            // A mask over part of the image only.
            let mask: Vec<bool> = (0..img.pixel_count()).map(|i| i % 7 < 3).collect();
            for strategy in [
                ColourStrategy::Auto,
                ColourStrategy::Border,
                ColourStrategy::Difference,
                ColourStrategy::Hsv,
            ] {
                for d_max in [50.0, 1.0] {
                    let p = ColourParams {
                        strategy,
                        hsv: [20.0, 5.0, -30.0],
                        exclude: vec![[0, 0, 0]],
                        d_max,
                    };
                    let want = colour_map(img, &mask, &p);
                    for budget in [1, 37, 5000, usize::MAX] {
                        let mut m = ColourMapper::new(img, &p);
                        let mut runs = 1;
                        let mut last = 0.0;
                        while !m.run(img, &mask, budget) {
                            runs += 1;
                            assert!(m.fraction() >= last && m.fraction() < 1.0);
                            last = m.fraction();
                        }
                        if budget == 1 {
                            assert!(runs >= img.pixel_count(), "{runs}");
                        }
                        let got = m.finish();
                        assert_eq!(got.kind, want.kind, "{strategy:?} d_max {d_max}");
                        assert!(
                            got.map == want.map,
                            "{strategy:?} d_max {d_max} budget {budget}: the maps differ"
                        );
                    }
                }
            }
        }
    }
}
