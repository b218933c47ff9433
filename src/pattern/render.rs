//! Drawing a pattern: a raster from the same colour fields the loss uses
//! (so targets made from parameters match the fields exactly), and SVG.
use super::field::{Evaluator, Grid, Scene};
use super::record::{BoolOp, Geom, Rgb};
use super::sdf::PrimKind;
use crate::core::error::{Error, Result};
use crate::raster::Rgba8Image;
use std::fmt::Write;

/// Largest raster side [`render`] accepts (pixels × supersampling).
pub use crate::core::limits::MAX_RENDER_SIDE;

/// Rasterise the scene with `params` (float parameters) with `size`
/// pixels along the longer side of its canvas (`size × size` on a square
/// one, see [`crate::pattern::record::Canvas::grid`]), averaging
/// `supersample²` samples per pixel (1 = crisp palette colours).
pub fn render(
    scene: &Scene,
    params: &[f64],
    size: usize,
    supersample: usize,
) -> Result<Rgba8Image> {
    let (w, h) = scene.rec.canvas.grid(size);
    render_wh(scene, params, (w, h), supersample)
}

/// [`render`] at `width × height` pixels laid over the canvas (pixels are
/// square when the two have the same aspect).
pub fn render_wh(
    scene: &Scene,
    params: &[f64],
    size: (usize, usize),
    supersample: usize,
) -> Result<Rgba8Image> {
    let mut r = Raster::with_size(scene, params, size, supersample)?;
    while !r.run(scene, u64::MAX) {}
    Ok(r.into_image())
}

/// Where a [`Raster`] is.
enum RasterPhase {
    /// Evaluating the colour fields, big tile by big tile; the next tile.
    Fields(usize),
    /// Turning fields into pixels; the next output row.
    Pixels(usize),
    Done,
}

/// [`render`] in bounded parts, for a job that must not block: the colour
/// fields are evaluated a few tiles at a time, then the pixels are made a
/// few rows at a time. The image is bit for bit that of [`render`].
pub struct Raster {
    /// Output width and height in pixels.
    size: (usize, usize),
    ss: usize,
    ev: Evaluator,
    img: Rgba8Image,
    phase: RasterPhase,
}

impl Raster {
    /// Check the arguments and the parameters (a shape whose coordinates
    /// are not finite is an error) and prepare the evaluation, `size`
    /// pixels along the longer side of the canvas (as [`render`]).
    pub fn new(scene: &Scene, params: &[f64], size: usize, supersample: usize) -> Result<Raster> {
        Raster::with_size(scene, params, scene.rec.canvas.grid(size), supersample)
    }

    /// [`Raster::new`] at `width × height` pixels (as [`render_wh`]).
    pub fn with_size(
        scene: &Scene,
        params: &[f64],
        (width, height): (usize, usize),
        supersample: usize,
    ) -> Result<Raster> {
        let ss = supersample.max(1);
        let side = |size: usize| {
            match size.checked_mul(ss) {
            Some(n) if size > 0 && n <= MAX_RENDER_SIDE => Ok(n),
            _ => Err(Error::limit(format!(
                "render size {size} pixels × {ss} samples per side is outside 1..={MAX_RENDER_SIDE} samples; \
                 lower the size or the supersampling"
            ))),
        }
        };
        let (w, h) = (side(width)?, side(height)?);
        let nodes = checked_nodes(scene, params)?;
        let grid = Grid {
            w,
            h,
            canvas: scene.rec.canvas,
        };
        let mut ev = Evaluator::on(grid, 1.0);
        ev.begin(scene, &nodes, false);
        Ok(Raster {
            size: (width, height),
            ss,
            ev,
            img: Rgba8Image::new(width as u32, height as u32),
            phase: RasterPhase::Fields(0),
        })
    }

    /// Do about `budget` units of work (item evaluations while the fields
    /// are evaluated, then samples × channels while pixels are made), at
    /// least one big tile or one row; `true` when the image is finished.
    pub fn run(&mut self, scene: &Scene, budget: u64) -> bool {
        let mut spent = 0u64;
        loop {
            match self.phase {
                RasterPhase::Fields(t) => {
                    let before = self.ev.raw_work();
                    self.ev.eval_tiles(scene, false, t..t + 1);
                    spent += self.ev.raw_work() - before + 1;
                    self.phase = if t + 1 >= self.ev.tiles() {
                        self.ev.finish(scene);
                        RasterPhase::Pixels(0)
                    } else {
                        RasterPhase::Fields(t + 1)
                    };
                }
                RasterPhase::Pixels(y) => {
                    self.row(scene, y);
                    spent += (self.size.0 * self.ss * self.ss * scene.channels.len().max(1)) as u64;
                    self.phase = if y + 1 >= self.size.1 {
                        RasterPhase::Done
                    } else {
                        RasterPhase::Pixels(y + 1)
                    };
                }
                RasterPhase::Done => return true,
            }
            if spent >= budget {
                return matches!(self.phase, RasterPhase::Done);
            }
        }
    }

    /// Output row `y`: the average colour of each pixel's samples.
    fn row(&mut self, scene: &Scene, y: usize) {
        let (ss, n) = (self.ss, self.ev.grid.w);
        let pal = &scene.rec.colours;
        for x in 0..self.size.0 {
            let mut acc = [0u32; 3];
            for sy in 0..ss {
                for sx in 0..ss {
                    let i = (y * ss + sy) * n + x * ss + sx;
                    let c = pal[self.ev.colour_index(scene, i) as usize];
                    for k in 0..3 {
                        acc[k] += c[k] as u32;
                    }
                }
            }
            let d = (ss * ss) as u32;
            self.img.put(
                x as u32,
                y as u32,
                [
                    ((acc[0] + d / 2) / d) as u8,
                    ((acc[1] + d / 2) / d) as u8,
                    ((acc[2] + d / 2) / d) as u8,
                    255,
                ],
            );
        }
    }

    /// How far along, `0..=1`: fields count for three quarters.
    pub fn fraction(&self) -> f64 {
        match self.phase {
            RasterPhase::Fields(t) => 0.75 * t as f64 / self.ev.tiles().max(1) as f64,
            RasterPhase::Pixels(y) => 0.75 + 0.25 * y as f64 / self.size.1.max(1) as f64,
            RasterPhase::Done => 1.0,
        }
    }

    /// What the next [`Raster::run`] works on, for progress reports.
    pub fn stage(&self) -> &'static str {
        match self.phase {
            RasterPhase::Fields(_) => "drawing: colour fields",
            RasterPhase::Pixels(_) | RasterPhase::Done => "drawing: pixels",
        }
    }

    /// The finished image (call after [`Raster::run`] returned `true`).
    pub fn into_image(self) -> Rgba8Image {
        self.img
    }
}

/// The tape's node values at `params`, checked: the right number of
/// parameters, and every shape's coordinates and sizes finite.
pub(crate) fn checked_nodes(scene: &Scene, params: &[f64]) -> Result<Vec<f64>> {
    if params.len() != scene.rec.float_params.len() {
        return Err(Error::input(format!(
            "the program has {} float parameters but {} values were given",
            scene.rec.float_params.len(),
            params.len()
        )));
    }
    let mut nodes = vec![];
    scene.rec.tape.forward(params, &mut nodes);
    if !scene.shapes_finite(&nodes) {
        return Err(Error::input(
            "with these parameter values a shape's coordinates or sizes are not finite numbers \
             (a division by zero in the program?)",
        ));
    }
    Ok(nodes)
}

fn hex(c: Rgb) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

fn num(v: f64) -> String {
    let s = format!("{v:.3}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.to_string()
    }
}

struct SvgOut<'a> {
    scene: &'a Scene,
    vals: &'a [f64],
    k: f64,
    /// The viewBox's width and height (the canvas in pixels), as written.
    view: (String, String),
    defs: String,
    masks: usize,
}

impl SvgOut<'_> {
    fn f(&self, prim: u32, i: usize) -> f64 {
        self.vals[self.scene.rec.prims[prim as usize].fields[i] as usize]
    }
    fn p(&self, v: f64) -> String {
        num(v * self.k)
    }

    /// One element drawing geometry `g` with the given style attributes.
    fn element(&mut self, g: &Geom, style: &str) -> String {
        match g {
            Geom::Prim(i) => {
                let i = *i;
                let kind = self.scene.rec.prims[i as usize].kind;
                let f = |k| self.f(i, k);
                match kind {
                    PrimKind::Circle => format!("<circle cx=\"{}\" cy=\"{}\" r=\"{}\" {style}/>", self.p(f(0)), self.p(f(1)), self.p(f(2).max(0.0))),
                    PrimKind::Point => format!("<line x1=\"{0}\" y1=\"{1}\" x2=\"{0}\" y2=\"{1}\" stroke-linecap=\"round\" {style}/>", self.p(f(0)), self.p(f(1))),
                    PrimKind::Segment => format!(
                        "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke-linecap=\"round\" {style}/>",
                        self.p(f(0)),
                        self.p(f(1)),
                        self.p(f(2)),
                        self.p(f(3))
                    ),
                    PrimKind::Rect => {
                        let (hw, hh) = (f(2).max(0.0), f(3).max(0.0));
                        let r = f(4).clamp(0.0, hw.min(hh));
                        format!(
                            "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" rx=\"{}\" transform=\"rotate({} {} {})\" {style}/>",
                            self.p(f(0) - hw),
                            self.p(f(1) - hh),
                            self.p(2.0 * hw),
                            self.p(2.0 * hh),
                            self.p(r),
                            num(f(5).to_degrees()),
                            self.p(f(0)),
                            self.p(f(1))
                        )
                    }
                    PrimKind::Quad => {
                        let d = self.path_d(i, 1, false);
                        format!("<path d=\"{d}\" {style}/>")
                    }
                }
            }
            Geom::Path { first, len, closed } => {
                let d = self.path_d(*first, *len, *closed);
                format!("<path d=\"{d}\" fill-rule=\"nonzero\" stroke-linejoin=\"round\" stroke-linecap=\"round\" {style}/>")
            }
            Geom::Bool(..) => {
                let id = self.mask(g);
                format!(
                    "<rect width=\"{0}\" height=\"{0}\" mask=\"url(#{id})\" {style}/>",
                    num(self.k)
                )
            }
        }
    }

    fn path_d(&self, first: u32, len: u32, closed: bool) -> String {
        let mut d = String::new();
        for i in first..first + len {
            let kind = self.scene.rec.prims[i as usize].kind;
            let f = |k| self.f(i, k);
            if i == first {
                let _ = write!(d, "M{} {}", self.p(f(0)), self.p(f(1)));
            }
            match kind {
                PrimKind::Segment => {
                    let _ = write!(d, " L{} {}", self.p(f(2)), self.p(f(3)));
                }
                _ => {
                    let _ = write!(
                        d,
                        " Q{} {} {} {}",
                        self.p(f(2)),
                        self.p(f(3)),
                        self.p(f(4)),
                        self.p(f(5))
                    );
                }
            }
        }
        if closed {
            d.push_str(" Z");
        }
        d
    }

    /// A mask (white = inside) for a boolean geometry; returns its id.
    fn mask(&mut self, g: &Geom) -> String {
        let Geom::Bool(op, ch) = g else {
            unreachable!("masks are only made for boolean geometries")
        };
        let id = format!("m{}", self.masks);
        self.masks += 1;
        let white = "fill=\"#fff\"";
        let black = "fill=\"#000\"";
        let mut body = String::new();
        match op {
            BoolOp::Union => {
                for c in ch {
                    body += &self.element(c, white);
                }
            }
            BoolOp::Difference => {
                body += &self.element(&ch[0], white);
                for c in &ch[1..] {
                    body += &self.element(c, black);
                }
            }
            BoolOp::Intersect => {
                let mut inner = self.element(&ch[0], white);
                for c in &ch[1..] {
                    let sub = Geom::Bool(BoolOp::Union, vec![c.clone()]);
                    let m = self.mask(&sub);
                    inner = format!("<g mask=\"url(#{m})\">{inner}</g>");
                }
                body += &inner;
            }
        }
        let _ = write!(
            self.defs,
            "<mask id=\"{id}\" maskUnits=\"userSpaceOnUse\" x=\"0\" y=\"0\" width=\"{}\" height=\"{}\">{body}</mask>",
            self.view.0,
            self.view.1
        );
        id
    }
}

/// An SVG document of the scene with `params`, `size` pixels along the
/// longer side of its canvas (`size × size` on a square one). Strokes of
/// boolean shapes are not exported (SVG cannot stroke a mask).
pub fn svg(scene: &Scene, params: &[f64], size: f64) -> Result<String> {
    let c = scene.rec.canvas;
    let long = c.w.max(c.h);
    svg_sized(scene, params, size * (c.w / long), size * (c.h / long))
}

/// [`svg`] `width × height` pixels: the canvas scaled uniformly to fit
/// (its `viewBox` is the canvas in pixels, so a size of the canvas's
/// aspect is filled exactly and nothing is ever stretched).
pub fn svg_sized(scene: &Scene, params: &[f64], width: f64, height: f64) -> Result<String> {
    if params.len() != scene.rec.float_params.len() {
        return Err(Error::input(format!(
            "the program has {} float parameters but {} values were given",
            scene.rec.float_params.len(),
            params.len()
        )));
    }
    let mut vals = vec![];
    scene.rec.tape.forward(params, &mut vals);
    let c = scene.rec.canvas;
    // Pixels per canvas unit (`size` on a square canvas drawn square).
    let k = (width / c.w).min(height / c.h);
    let (vw, vh) = (num(k * c.w), num(k * c.h));
    let mut out = SvgOut {
        scene,
        vals: &vals,
        k,
        view: (vw.clone(), vh.clone()),
        defs: String::new(),
        masks: 0,
    };
    let mut body = String::new();
    let pal = &scene.rec.colours;
    for s in &scene.rec.shapes {
        let w = out.p(vals[s.width as usize].max(0.0));
        let fill = s
            .fill
            .map(|c| format!("fill=\"{}\"", hex(pal[c as usize])))
            .unwrap_or_else(|| "fill=\"none\"".into());
        let style = match s.stroke {
            Some(c) if !matches!(s.geom, Geom::Bool(..)) => format!(
                "{fill} stroke=\"{}\" stroke-width=\"{w}\"",
                hex(pal[c as usize])
            ),
            _ => fill,
        };
        body += &out.element(&s.geom, &style);
        body.push('\n');
    }
    Ok(format!(
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" viewBox=\"0 0 {vw} {vh}\">\n<defs>{}</defs>\n<rect width=\"{vw}\" height=\"{vh}\" fill=\"{}\"/>\n{body}</svg>\n",
        num(width),
        num(height),
        out.defs,
        hex(pal[0])
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pattern::record::{Program, RecordLimits};

    /// The raster as it was made before it was stepped: every sample's
    /// colour index at once, then the average of each pixel's samples.
    fn one_go(scene: &Scene, params: &[f64], size: usize, ss: usize) -> Rgba8Image {
        let n = size * ss;
        let idx = crate::pattern::fit::colour_indices(scene, params, n).unwrap();
        let pal = &scene.rec.colours;
        let mut img = Rgba8Image::new(size as u32, size as u32);
        for y in 0..size {
            for x in 0..size {
                let mut acc = [0u32; 3];
                for sy in 0..ss {
                    for sx in 0..ss {
                        let c = pal[idx[(y * ss + sy) * n + x * ss + sx] as usize];
                        for k in 0..3 {
                            acc[k] += c[k] as u32;
                        }
                    }
                }
                let d = (ss * ss) as u32;
                let px = [0, 1, 2].map(|k| ((acc[k] + d / 2) / d) as u8);
                img.put(x as u32, y as u32, [px[0], px[1], px[2], 255]);
            }
        }
        img
    }

    #[test]
    fn stepping_the_raster_gives_the_same_bits_as_one_go() {
        let p = Program::parse(
            "background \"#eeeeee\";\nfor i in 0..9 { circle(0.1 * i + 0.05, 0.3 + 0.04 * i, 0.07, fill: \"#aa0000\", stroke: \"#0000aa\", width: 0.01); }\n\
             segment(0.1, 0.6, 0.9, 0.9, stroke: \"#00aa00\", width: 0.03);\n\
             path(fill: \"#0000aa\") { move(0.6, 0.6); quad(0.9, 0.6, 0.9, 0.9); line(0.6, 0.9); }\n\
             difference(fill: \"#00aa00\") { rect(0.3, 0.8, 0.2, 0.15, radius: 0.02, rotation: 0.4); circle(0.3, 0.8, 0.05); }",
        )
        .unwrap();
        let scene = Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap());
        let fl = scene.rec.float_values();
        for (size, ss) in [(50, 1), (37, 3), (64, 2)] {
            let want = one_go(&scene, &fl, size, ss);
            let mut r = Raster::new(&scene, &fl, size, ss).unwrap();
            let mut runs = 1;
            let mut last = 0.0;
            while !r.run(&scene, 1) {
                runs += 1;
                assert!(r.fraction() > last && r.fraction() < 1.0);
                last = r.fraction();
            }
            // Budget 1: one big tile or one row per call.
            let tiles = (size * ss).div_ceil(16).pow(2);
            assert_eq!(runs, tiles + size, "size {size} ×{ss}");
            assert_eq!(r.into_image(), want, "size {size} ×{ss}");
            assert_eq!(render(&scene, &fl, size, ss).unwrap(), want);
        }
    }

    #[test]
    fn raster_and_svg_of_every_shape_kind() {
        let p = Program::parse(
            "background \"#eeeeee\";\nparam r in [0.05, 0.2] = 0.1;\ncircle(0.25, 0.25, r, fill: \"#ff0000\");\n\
             rect(0.75, 0.25, 0.3, 0.2, radius: 0.03, rotation: 0.2, fill: \"#00ff00\", stroke: \"#0000ff\", width: 0.02);\n\
             segment(0.1, 0.6, 0.4, 0.9, stroke: \"#0000ff\", width: 0.03);\npoint(0.5, 0.5, width: 0.05);\n\
             path(fill: \"#ff0000\") { move(0.6, 0.6); quad(0.9, 0.6, 0.9, 0.9); line(0.6, 0.9); }\n\
             difference(fill: \"#00ff00\") { circle(0.5, 0.8, 0.1); circle(0.5, 0.8, 0.05); }",
        )
        .unwrap();
        let scene = Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap());
        let img = render(&scene, &[0.1], 100, 1).unwrap();
        assert_eq!(img.get(25, 25), [255, 0, 0, 255]);
        assert_eq!(img.get(2, 98), [238, 238, 238, 255]);
        assert_eq!(img.get(75, 25), [0, 255, 0, 255]);
        assert_eq!(img.get(50, 50), [0, 0, 0, 255]);
        assert_eq!(img.get(50, 80), [238, 238, 238, 255]); // hole of the difference
        assert_eq!(img.get(50, 72), [0, 255, 0, 255]);
        let s = svg(&scene, &[0.1], 100.0).unwrap();
        assert!(
            s.contains("<circle cx=\"25\" cy=\"25\" r=\"10\" fill=\"#ff0000\"/>"),
            "{s}"
        );
        assert!(s.contains("mask=\"url(#m0)\""));
        assert!(s.contains(" Q90 60 90 90 L60 90 L60 60 Z"), "{s}");
        assert!(render(&scene, &[0.1], 5000, 1).is_err());
        // size × supersample would wrap (2 × 2^63 = 0 in 64 bits): a limit error.
        for (size, ss) in [(2, 1usize << 63), (usize::MAX, 2), (1024, 5)] {
            let e = render(&scene, &[0.1], size, ss).unwrap_err();
            assert!(matches!(e, Error::Limit(_)), "{e:?}");
            assert!(e.to_string().contains("4096"), "{e}");
        }
        // Parameters that make a coordinate non-finite: an error, not a picture.
        let p = Program::parse("param a in [0, 1] = 0.25;\ncircle(0.5, 0.5, 0.1 / (a - 0.5));")
            .unwrap();
        let scene = Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap());
        assert!(render(&scene, &[0.25], 16, 1).is_ok());
        let e = render(&scene, &[0.5], 16, 1).unwrap_err();
        assert!(e.to_string().contains("not finite"), "{e}");
    }
}
