//! Micro's requests as typed data, shared by `filigree micro` and the
//! browser worker (`micro-render`, `micro-glsl`, `micro-slice`). Defaults are defined
//! once: each request's `Default`. Errors name the field at fault (`scene`,
//! `width`, `camera.fov`, ...); scene errors carry the node path and, for
//! JSON mistakes, the line and column.
use super::glsl;
use super::render::{self, Camera, Rays, Shade, Shading, Stats, StepMode, Trace};
use super::scene::{self, Scene};
use crate::core::error::{Error, Result};
use crate::core::job::{Job, OneShot, Progress, Step};
use crate::core::limits::{MAX_MICRO_PIXELS, MAX_MICRO_SIDE, MAX_MICRO_STEPS};
use crate::core::request_limits as lim;
use crate::raster::{encode_png, Rgba8Image};
use glam::DVec3;
use serde::{Deserialize, Serialize};

/// `micro-render` / `filigree micro render`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MicroRenderRequest {
    /// The scene as JSON text (see `micro::scene`).
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub camera: Camera,
    /// Step strategy: `fixed`, `bisection` or `adaptive`.
    pub steps: StepMode,
    /// Adaptive: a gradient check (the slope along the ray, one extra
    /// evaluation) every N steps, from step N on (1: every step, fully
    /// adaptive).
    pub check_every: u32,
    /// Adaptive: when > 0, check gradients where the ray enters a new cell
    /// of this size (world units) selected by a congruence of its index
    /// (the paper's polynomial-selected checks) instead of every N steps.
    pub check_cell: f64,
    pub check_modulus: u32,
    /// Adaptive: the over-relaxed step, as a multiple of the distance (the
    /// longest step; a gradient check may shorten it, see `render`).
    pub max_relax: f64,
    /// Bisection: step length as a multiple of the distance.
    pub bisection_factor: f64,
    /// Most steps along one ray.
    pub max_steps: u32,
    /// Hit threshold as a fraction of a pixel's footprint.
    pub pixel_fraction: f64,
    /// Half size of the sample box `[−bounds, bounds]³`, world units.
    pub bounds: f64,
    pub color: [u8; 3],
    pub background: [u8; 3],
    /// Direction towards the light.
    pub light: [f64; 3],
    /// Absorption per world unit inside the sample.
    pub absorption: f64,
    /// Surface model: `lambert` or `ggx`.
    pub shading: Shading,
    /// GGX: perceptual roughness in 0.02..=1 (α = roughness²).
    pub roughness: f64,
    /// GGX: reflectance at normal incidence in 0..=1.
    pub specular: f64,
    /// Path tracing: samples per pixel (0: the direct shading above).
    /// Diffuse surfaces, the light by shadow rays, a white sky, Russian
    /// roulette after two bounces; deterministic by `seed`.
    pub spp: u32,
    /// Path tracing: most bounces of one path.
    pub max_depth: u32,
    pub seed: u64,
    /// Path tracing: index of the first sample (progressive passes render
    /// samples `sample_start .. sample_start + spp`; each sample has its own
    /// generator seeded by `seed`, the pixel and the sample index).
    pub sample_start: u32,
    /// Path tracing: also return the summed linear radiance of this
    /// request's samples (`radiance`), for pages that average passes.
    pub radiance: bool,
    /// Render only this rectangle of the `width`×`height` image (default:
    /// all of it). Its pixels are bit for bit those of the whole image.
    /// (Boxed: the request is a variant of `micro-fit`'s sampler.)
    pub tile: Option<Box<Tile>>,
}

/// A rectangle of an image: `w`×`h` pixels from column `x`, row `y`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tile {
    pub x: u32,
    pub y: u32,
    pub w: u32,
    pub h: u32,
}

impl Tile {
    /// `n` horizontal bands of a `width`×`height` image (at most one per row),
    /// top to bottom, heights differing by at most one.
    pub fn bands(width: u32, height: u32, n: u32) -> Vec<Tile> {
        let n = n.clamp(1, height.max(1));
        (0..n)
            .map(|k| {
                let y0 = (height as u64 * k as u64 / n as u64) as u32;
                let y1 = (height as u64 * (k as u64 + 1) / n as u64) as u32;
                Tile {
                    x: 0,
                    y: y0,
                    w: width,
                    h: y1 - y0,
                }
            })
            .filter(|t| t.h > 0)
            .collect()
    }
}

impl Default for MicroRenderRequest {
    fn default() -> Self {
        MicroRenderRequest {
            scene: String::new(),
            width: 256,
            height: 256,
            camera: Camera::default(),
            steps: StepMode::Fixed,
            check_every: 10,
            check_cell: 0.0,
            check_modulus: 3,
            max_relax: 1.5,
            bisection_factor: 1.5,
            max_steps: 512,
            pixel_fraction: 0.5,
            bounds: 1.0,
            color: [214, 190, 150],
            background: [24, 26, 30],
            light: [0.45, -0.35, 0.82],
            absorption: 0.0,
            shading: Shading::Lambert,
            roughness: 0.35,
            specular: 0.04,
            spp: 0,
            max_depth: 4,
            seed: 1,
            sample_start: 0,
            radiance: false,
            tile: None,
        }
    }
}

/// `micro-slice` / `filigree micro slice`: the field on the plane `z`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct MicroSliceRequest {
    pub scene: String,
    pub z: f64,
    /// Centre of the view (x, y) and its half width, world units.
    pub center: [f64; 2],
    pub half: f64,
    pub width: u32,
    pub height: u32,
    /// Grey ramp instead of the inside/outside colour map.
    pub grey: bool,
}

impl Default for MicroSliceRequest {
    fn default() -> Self {
        MicroSliceRequest {
            scene: String::new(),
            z: 0.0,
            center: [0.0, 0.0],
            half: 1.0,
            width: 256,
            height: 256,
            grey: false,
        }
    }
}

/// A rendered image (the whole image or its tile) with its work counters.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MicroRenderResponse {
    /// The PNG's size: the tile's when the request names one.
    pub width: u32,
    pub height: u32,
    /// Where the PNG goes in the whole image (the whole image by default).
    pub tile: Tile,
    #[serde(with = "serde_bytes")]
    pub png: Vec<u8>,
    pub stats: Stats,
    /// With `radiance` and `spp` > 0: per pixel of the PNG, row order, the
    /// sum of its samples' linear R, G, B (1 = full colour) as 32-bit
    /// little-endian floats; else empty.
    #[serde(with = "serde_bytes")]
    pub radiance: Vec<u8>,
}

/// A slice image with the field's range on it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MicroSliceResponse {
    pub width: u32,
    pub height: u32,
    #[serde(with = "serde_bytes")]
    pub png: Vec<u8>,
    pub min: f64,
    pub max: f64,
    /// Fraction of pixels inside the structure (value < 0).
    pub inside: f64,
}

fn check_size(width: u32, height: u32) -> Result<()> {
    lim::int_in("width", width, (1, MAX_MICRO_SIDE))?;
    lim::int_in("height", height, (1, MAX_MICRO_SIDE))?;
    if width as u64 * height as u64 > MAX_MICRO_PIXELS {
        return Err(Error::limit(format!(
            "{width}×{height} is more than {MAX_MICRO_PIXELS} pixels"
        ))
        .at("width"));
    }
    Ok(())
}

/// Scene evaluations per job step: a few milliseconds of work.
const EVALS_PER_STEP: u64 = 60_000;

/// The work one render job may do, in evaluation units (scene evaluations,
/// counted as it traces, × [`Scene::eval_cost`], so native and wasm stop
/// at the same place): about a minute natively on one core (25–85 s on
/// the shipped scenes). The size checks
/// bound the samples, not what each costs (a path's bounces, a ray's steps
/// through a scene of many nodes), so a path tracer's cost is projected
/// from its first pass and refused then, and any render is stopped once it
/// passes the budget by a quarter.
pub const MAX_MICRO_RENDER_WORK: u64 = 6_000_000_000;

/// A render in progress: pixels in row order, a bounded slice per step.
pub struct RenderJob {
    scene: Scene,
    rays: Rays,
    trace: Trace,
    shade: Shade,
    width: u32,
    /// The rectangle rendered; `next` counts its pixels in row order.
    tile: Tile,
    next: u64,
    rgba: Vec<u8>,
    stats: Stats,
    /// Path tracing: samples per pixel (0: off), pass-major (every pixel's
    /// k-th sample before any pixel's (k+1)-th), summed radiance per pixel.
    spp: u32,
    sample_start: u32,
    want_radiance: bool,
    seed: u64,
    path: render::PathSettings,
    sum: Vec<DVec3>,
}

impl RenderJob {
    /// The scene being rendered.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }
}

/// A checked render request: the scene and everything a trace needs.
struct Checked {
    scene: Scene,
    rays: Rays,
    trace: Trace,
    shade: Shade,
}

/// Ranges of the camera (`micro-render`, `micro-glsl`) and of the slice
/// plane (`micro-slice`), checked here and in a document (`state.rs`).
pub const YAW: (f64, f64) = (-1e5, 1e5);
pub const PITCH: (f64, f64) = (-89.9, 89.9);
pub const DISTANCE: (f64, f64) = (1e-9, 1e6);
pub const TARGET: (f64, f64) = (-1e6, 1e6);
pub const Z: (f64, f64) = (-1e6, 1e6);
/// Ranges of the shading fields, checked here and in a document.
pub const ROUGHNESS: (f64, f64) = (0.02, 1.0);
pub const SPECULAR: (f64, f64) = (0.0, 1.0);
pub const ABSORPTION: (f64, f64) = (0.0, 1e6);
pub const SPP: (u32, u32) = (0, MAX_MICRO_SPP);
pub const MAX_DEPTH: (u32, u32) = (1, 64);

/// Check every field of a render request (no tracing yet).
fn check_render(req: &MicroRenderRequest) -> Result<Checked> {
    check_size(req.width, req.height)?;
    let c = &req.camera;
    for (i, v) in c.target.iter().enumerate() {
        lim::finite_in(&format!("camera.target.{i}"), *v, TARGET)?;
    }
    lim::finite_in("camera.distance", c.distance, DISTANCE)?;
    lim::finite_in("camera.yaw", c.yaw, YAW)?;
    lim::finite_in("camera.pitch", c.pitch, PITCH)?;
    lim::finite_in("camera.fov", c.fov, (0.001, 170.0))?;
    lim::int_in("check_every", req.check_every, (1, MAX_MICRO_STEPS))?;
    lim::finite_in("check_cell", req.check_cell, (0.0, 1e6))?;
    lim::int_in("check_modulus", req.check_modulus, (1, 1_000_000))?;
    lim::finite_in("max_relax", req.max_relax, (1.0, 16.0))?;
    lim::finite_in("bisection_factor", req.bisection_factor, (1.0, 16.0))?;
    lim::int_in("max_steps", req.max_steps, (1, MAX_MICRO_STEPS))?;
    lim::finite_in("pixel_fraction", req.pixel_fraction, (1e-6, 10.0))?;
    lim::finite_in("bounds", req.bounds, (1e-9, 1e6))?;
    lim::finite_in("absorption", req.absorption, ABSORPTION)?;
    lim::finite_in("roughness", req.roughness, ROUGHNESS)?;
    lim::finite_in("specular", req.specular, SPECULAR)?;
    lim::int_in("spp", req.spp, SPP)?;
    lim::int_in("max_depth", req.max_depth, MAX_DEPTH)?;
    lim::int_in(
        "sample_start",
        req.sample_start,
        (0, MAX_MICRO_SAMPLE_START),
    )?;
    if let Some(&t) = req.tile.as_deref() {
        if t.w == 0
            || t.h == 0
            || t.x as u64 + t.w as u64 > req.width as u64
            || t.y as u64 + t.h as u64 > req.height as u64
        {
            return Err(Error::input(format!(
                "tile {}×{} at ({}, {}) must be a non-empty rectangle inside the {}×{} image",
                t.w, t.h, t.x, t.y, req.width, req.height
            ))
            .at("tile"));
        }
    }
    if req.spp as u64 * req.width as u64 * req.height as u64 > MAX_MICRO_PIXELS * 64 {
        return Err(Error::limit(format!(
            "{} samples per pixel at {}×{} is more than {} samples in all",
            req.spp,
            req.width,
            req.height,
            MAX_MICRO_PIXELS * 64
        ))
        .at("spp"));
    }
    for (i, v) in req.light.iter().enumerate() {
        lim::finite_in(&format!("light.{i}"), *v, (-1e6, 1e6))?;
    }
    let light = DVec3::from_array(req.light);
    if light.length() < 1e-9 {
        return Err(Error::input("`light` must not be the zero vector").at("light"));
    }
    let scene = scene::parse(&req.scene)?;
    let rays = Rays::new(&req.camera, req.width, req.height);
    Ok(Checked {
        scene,
        trace: Trace {
            mode: req.steps,
            check_every: req.check_every,
            check_cell: req.check_cell,
            check_modulus: req.check_modulus,
            max_relax: req.max_relax,
            bisection_factor: req.bisection_factor,
            max_steps: req.max_steps,
            precision: rays.pixel_angle() * req.pixel_fraction,
            bounds: req.bounds,
        },
        rays,
        shade: Shade {
            color: req.color,
            background: req.background,
            light: light.normalize(),
            absorption: req.absorption,
            shading: req.shading,
            roughness: req.roughness,
            specular: req.specular,
        },
    })
}

/// Check a render request and set the job up (no tracing yet).
pub fn start_render(req: MicroRenderRequest) -> Result<RenderJob> {
    let c = check_render(&req)?;
    let tile = req.tile.as_deref().copied().unwrap_or(Tile {
        x: 0,
        y: 0,
        w: req.width,
        h: req.height,
    });
    let n = tile.w as usize * tile.h as usize * 4;
    Ok(RenderJob {
        scene: c.scene,
        trace: c.trace,
        rays: c.rays,
        shade: c.shade,
        width: req.width,
        tile,
        next: 0,
        rgba: vec![0; n],
        stats: Stats::default(),
        spp: req.spp,
        sample_start: req.sample_start,
        want_radiance: req.radiance,
        seed: req.seed,
        path: render::PathSettings {
            max_depth: req.max_depth,
            roulette_after: 2,
        },
        sum: if req.spp > 0 {
            vec![DVec3::ZERO; n / 4]
        } else {
            vec![]
        },
    })
}

/// `micro-glsl`: the WebGL2 shader pair drawing what `micro-render` would
/// draw for the same request. The camera and the image size are uniforms
/// the page sets per frame (`u_origin`, `u_forward`, `u_right`, `u_up`,
/// `u_tan_half`, `u_res`). Output 0 is the picture; output 1 (RGBA32UI)
/// counts each ray's work like [`Stats`]: steps, field evaluations,
/// hit | out-of-steps << 1 | undone steps << 2, gradient checks.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MicroGlslResponse {
    pub vertex: String,
    pub fragment: String,
    /// GLSL functions generated for the scene's nodes.
    pub functions: usize,
}

/// Check a render request (the same checks as `micro-render`) and generate
/// its shader; one step, no tracing.
pub fn start_glsl(req: MicroRenderRequest) -> Result<impl Job<Output = MicroGlslResponse>> {
    let c = check_render(&req)?;
    let p = glsl::program(
        &c.scene,
        &glsl::Settings {
            trace: c.trace,
            pixel_fraction: req.pixel_fraction,
            shade: c.shade,
        },
    )?;
    Ok(OneShot::new(move || {
        Ok(MicroGlslResponse {
            vertex: p.vertex,
            fragment: p.fragment,
            functions: p.functions,
        })
    }))
}

/// Most path-tracing samples per pixel.
pub const MAX_MICRO_SPP: u32 = 4096;
/// Highest index of a first sample (progressive passes).
pub const MAX_MICRO_SAMPLE_START: u32 = 1 << 20;

impl RenderJob {
    /// Pixel `i` of the tile (row order): its column and row in the whole image.
    fn at(&self, i: u64) -> (u32, u32) {
        let w = self.tile.w as u64;
        (self.tile.x + (i % w) as u32, self.tile.y + (i / w) as u32)
    }

    /// Path-trace work item `i`: sample `sample_start + i / pixels` of tile
    /// pixel `i % pixels`, from its own generator seeded by the sample index
    /// and the pixel's index in the whole image (so the bytes depend neither
    /// on how the job is stepped nor on the tiling).
    fn sample(&mut self, i: u64) {
        let n = self.tile.w as u64 * self.tile.h as u64;
        let (k, j) = (self.sample_start as u64 + i / n, i % n);
        let (x, y) = self.at(j);
        let px = y as u64 * self.width as u64 + x as u64;
        let mut rng = crate::core::rng::Rng::new(
            self.seed
                .wrapping_mul(0x2545_F491_4F6C_DD1D)
                .wrapping_add(px.wrapping_mul(0x9E37_79B9))
                ^ k.wrapping_mul(0xD1B5_4A32_D192_ED03),
        );
        let d = self.rays.dir_at(x as f64 + rng.f64(), y as f64 + rng.f64());
        let l = render::path_radiance(
            &self.scene,
            self.rays.origin,
            d,
            &self.trace,
            &self.shade,
            &self.path,
            &mut rng,
            &mut self.stats,
        );
        self.sum[j as usize] += l;
    }

    /// Render pixel `i` of the tile (row order) and store it.
    fn pixel(&mut self, i: u64) {
        let (x, y) = self.at(i);
        let d = self.rays.dir(x, y);
        let o = self.rays.origin;
        let t = render::trace(&self.scene, o, d, &self.trace, &mut self.stats);
        let px = render::shade(
            &self.scene,
            o,
            d,
            t,
            &self.trace,
            &self.shade,
            &mut self.stats,
        );
        let k = i as usize * 4;
        self.rgba[k..k + 4].copy_from_slice(&px);
    }

    /// Work a bounded slice (a few milliseconds); the fraction done, or
    /// `None` once every pixel is rendered; an error once the render is
    /// seen to need more than [`MAX_MICRO_RENDER_WORK`].
    fn advance(&mut self) -> Result<Option<f64>> {
        let pixels = self.tile.w as u64 * self.tile.h as u64;
        let total = pixels * self.spp.max(1) as u64;
        let budget = self.stats.sdf_evals + EVALS_PER_STEP;
        while self.next < total && self.stats.sdf_evals < budget {
            if self.spp > 0 {
                self.sample(self.next);
            } else {
                self.pixel(self.next);
            }
            self.next += 1;
        }
        self.check_work(pixels, total)?;
        Ok((self.next < total).then(|| self.next as f64 / total as f64))
    }

    /// [`MAX_MICRO_RENDER_WORK`]: the work done so far, and (once a whole
    /// pass is done) the work the remaining passes will take at its rate.
    fn check_work(&self, pixels: u64, total: u64) -> Result<()> {
        let done = self.stats.sdf_evals as f64 * self.scene.eval_cost() as f64;
        let projected = if self.next >= pixels && self.next < total {
            done / self.next as f64 * total as f64
        } else {
            done
        };
        let (limit, over) = if projected > done {
            (MAX_MICRO_RENDER_WORK as f64, projected)
        } else {
            (1.25 * MAX_MICRO_RENDER_WORK as f64, done)
        };
        if over <= limit {
            return Ok(());
        }
        let what = if self.spp > 0 {
            format!(
                "{} samples per pixel of this scene at {}×{}",
                self.spp, self.tile.w, self.tile.h
            )
        } else {
            format!("this scene at {}×{}", self.tile.w, self.tile.h)
        };
        Err(Error::limit(format!(
            "{what} would take about {over:.1e} units of work, more than the {:.1e} one render \
             may do (about a minute on one core); use fewer samples per pixel, a smaller image, \
             fewer steps or a simpler scene",
            MAX_MICRO_RENDER_WORK as f64,
        ))
        .at(if self.spp > 0 { "spp" } else { "width" }))
    }

    /// The finished tile's pixels (after [`Self::advance`] returned `None`).
    fn take_rgba(&mut self) -> Rgba8Image {
        if self.spp > 0 {
            // Average, then to 8 bits (linear, like the direct shading).
            let inv = 1.0 / self.spp as f64;
            for (px, l) in self.sum.iter().enumerate() {
                let c = *l * inv * 255.0;
                let q = |v: f64| v.round().clamp(0.0, 255.0) as u8;
                self.rgba[px * 4..px * 4 + 4].copy_from_slice(&[q(c.x), q(c.y), q(c.z), 255]);
            }
        }
        Rgba8Image {
            width: self.tile.w,
            height: self.tile.h,
            data: std::mem::take(&mut self.rgba),
        }
    }

    /// The tile this job renders.
    pub fn tile(&self) -> Tile {
        self.tile
    }

    /// Render to the end without encoding: the tile's pixels and the work
    /// counters (for drivers that assemble tiles, such as the CLI's
    /// `--threads`). Checks `cancel` between slices.
    pub fn run_rgba(mut self, cancel: &crate::core::job::Cancel) -> Result<(Rgba8Image, Stats)> {
        while self.advance()?.is_some() {
            if cancel.is_cancelled() {
                return Err(Error::Cancelled);
            }
        }
        Ok((self.take_rgba(), self.stats))
    }
}

/// Put tiles rendered by [`RenderJob::run_rgba`] together into the whole
/// `width`×`height` image's response (PNG bytes equal to one job's).
pub fn assemble(
    width: u32,
    height: u32,
    parts: &[(Tile, Rgba8Image, Stats)],
) -> Result<MicroRenderResponse> {
    let mut data = vec![0u8; width as usize * height as usize * 4];
    let mut stats = Stats::default();
    let mut covered = 0u64;
    for (t, img, st) in parts {
        if t.x + t.w > width || t.y + t.h > height || img.width != t.w || img.height != t.h {
            return Err(Error::input("a tile does not fit its image").at("tile"));
        }
        let row = t.w as usize * 4;
        for r in 0..t.h as usize {
            let dst = ((t.y as usize + r) * width as usize + t.x as usize) * 4;
            data[dst..dst + row].copy_from_slice(&img.data[r * row..(r + 1) * row]);
        }
        covered += t.w as u64 * t.h as u64;
        stats.add(st);
    }
    if covered != width as u64 * height as u64 {
        return Err(Error::input("the tiles do not cover the image").at("tile"));
    }
    let img = Rgba8Image {
        width,
        height,
        data,
    };
    Ok(MicroRenderResponse {
        width,
        height,
        tile: Tile {
            x: 0,
            y: 0,
            w: width,
            h: height,
        },
        png: encode_png(&img)?,
        stats,
        radiance: vec![],
    })
}

impl Job for RenderJob {
    type Output = MicroRenderResponse;
    fn step(&mut self) -> Result<Step<MicroRenderResponse>> {
        if let Some(f) = self.advance()? {
            return Ok(Step::Running(Progress::new(
                f,
                if self.spp > 0 {
                    "path tracing"
                } else {
                    "sphere tracing"
                },
            )));
        }
        let img = self.take_rgba();
        let radiance = if self.want_radiance {
            let mut b = Vec::with_capacity(self.sum.len() * 12);
            for l in &self.sum {
                for v in [l.x, l.y, l.z] {
                    b.extend_from_slice(&(v as f32).to_le_bytes());
                }
            }
            b
        } else {
            vec![]
        };
        Ok(Step::Done(MicroRenderResponse {
            width: img.width,
            height: img.height,
            tile: self.tile,
            png: encode_png(&img)?,
            stats: self.stats,
            radiance,
        }))
    }
}

/// A slice in progress (rows of samples; colours once the range is known).
pub struct SliceJob {
    scene: Scene,
    req: MicroSliceRequest,
    values: Vec<f64>,
}

pub fn start_slice(req: MicroSliceRequest) -> Result<SliceJob> {
    check_size(req.width, req.height)?;
    lim::finite_in("z", req.z, Z)?;
    lim::finite_in("center.0", req.center[0], (-1e6, 1e6))?;
    lim::finite_in("center.1", req.center[1], (-1e6, 1e6))?;
    lim::finite_in("half", req.half, (1e-12, 1e6))?;
    let scene = scene::parse(&req.scene)?;
    let n = req.width as usize * req.height as usize;
    Ok(SliceJob {
        scene,
        values: Vec::with_capacity(n),
        req,
    })
}

impl SliceJob {
    /// World point of pixel (x, y): x right, y up, square pixels of side
    /// `2 half / width`.
    pub fn point(req: &MicroSliceRequest, x: u32, y: u32) -> DVec3 {
        let s = 2.0 * req.half / req.width as f64;
        DVec3::new(
            req.center[0] + (x as f64 + 0.5 - req.width as f64 * 0.5) * s,
            req.center[1] + (req.height as f64 * 0.5 - y as f64 - 0.5) * s,
            req.z,
        )
    }
}

impl Job for SliceJob {
    type Output = MicroSliceResponse;
    fn step(&mut self) -> Result<Step<MicroSliceResponse>> {
        let (w, h) = (self.req.width, self.req.height);
        let total = w as usize * h as usize;
        let stop = (self.values.len() + (EVALS_PER_STEP as usize / 4)).min(total);
        while self.values.len() < stop {
            let i = self.values.len();
            let p = Self::point(&self.req, (i % w as usize) as u32, (i / w as usize) as u32);
            self.values.push(self.scene.eval(p));
        }
        if self.values.len() < total {
            return Ok(Step::Running(Progress::new(
                self.values.len() as f64 / total as f64,
                "sampling the field",
            )));
        }
        let finite = self.values.iter().copied().filter(|v| v.is_finite());
        let (min, max) = finite.fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), v| {
            (a.min(v), b.max(v))
        });
        let range = min.abs().max(max.abs()).max(1e-300);
        let band = self.req.half / 8.0;
        let mut data = Vec::with_capacity(total * 4);
        let mut inside = 0usize;
        for &v in &self.values {
            inside += (v < 0.0) as usize;
            let v = if v.is_finite() { v } else { range };
            data.extend_from_slice(&render::slice_colour(v, band, self.req.grey, range));
        }
        let img = Rgba8Image {
            width: w,
            height: h,
            data,
        };
        Ok(Step::Done(MicroSliceResponse {
            width: w,
            height: h,
            png: encode_png(&img)?,
            min: if min.is_finite() { min } else { 0.0 },
            max: if max.is_finite() { max } else { 0.0 },
            inside: inside as f64 / total as f64,
        }))
    }
}

/// Render a request in `tiles` horizontal bands on `threads` scoped threads
/// (each takes the next band until none is left) and assemble the bands:
/// the PNG bytes equal one job's for the same request (`tests/micro.rs`).
/// A request naming a tile renders that tile in bands the same way.
#[cfg(not(target_arch = "wasm32"))]
pub fn render_threads(
    req: &MicroRenderRequest,
    threads: usize,
    tiles: u32,
    cancel: &crate::core::job::Cancel,
) -> Result<MicroRenderResponse> {
    // Check once (errors name the request's fields), then one job per band.
    let whole = start_render(req.clone())?.tile();
    let bands: Vec<Tile> = Tile::bands(whole.w, whole.h, tiles)
        .into_iter()
        .map(|b| Tile {
            x: whole.x,
            y: whole.y + b.y,
            w: whole.w,
            h: b.h,
        })
        .collect();
    let parts = crate::core::parallel::par_map_threads(&bands, threads, |&t| {
        start_render(MicroRenderRequest {
            tile: Some(Box::new(t)),
            ..req.clone()
        })
        .and_then(|job| job.run_rgba(cancel))
        .map(|(img, st)| (t, img, st))
    });
    let mut done = Vec::with_capacity(parts.len());
    for p in parts {
        done.push(p?);
    }
    // Shift the bands to the tile's own corner before assembling.
    let local: Vec<_> = done
        .into_iter()
        .map(|(t, img, st)| {
            (
                Tile {
                    x: t.x - whole.x,
                    y: t.y - whole.y,
                    ..t
                },
                img,
                st,
            )
        })
        .collect();
    let mut out = assemble(whole.w, whole.h, &local)?;
    out.tile = whole;
    Ok(out)
}
