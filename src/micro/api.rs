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
    /// Adaptive: a gradient check every N steps (1: fully adaptive).
    pub check_every: u32,
    /// Adaptive: when > 0, check gradients where the ray enters a new cell
    /// of this size (world units) selected by a congruence of its index
    /// (the paper's polynomial-selected checks) instead of every N steps.
    pub check_cell: f64,
    pub check_modulus: u32,
    /// Adaptive: the longest step, as a multiple of the distance.
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
            max_relax: 4.0,
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

/// A rendered image with its work counters.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MicroRenderResponse {
    pub width: u32,
    pub height: u32,
    #[serde(with = "serde_bytes")]
    pub png: Vec<u8>,
    pub stats: Stats,
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

/// A render in progress: pixels in row order, a bounded slice per step.
pub struct RenderJob {
    scene: Scene,
    rays: Rays,
    trace: Trace,
    shade: Shade,
    width: u32,
    height: u32,
    next: u64,
    rgba: Vec<u8>,
    stats: Stats,
    /// Path tracing: samples per pixel (0: off), pass-major (every pixel's
    /// k-th sample before any pixel's (k+1)-th), summed radiance per pixel.
    spp: u32,
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

/// Check every field of a render request (no tracing yet).
fn check_render(req: &MicroRenderRequest) -> Result<Checked> {
    check_size(req.width, req.height)?;
    let c = &req.camera;
    for (i, v) in c.target.iter().enumerate() {
        lim::finite_in(&format!("camera.target.{i}"), *v, (-1e6, 1e6))?;
    }
    lim::finite_in("camera.distance", c.distance, (1e-9, 1e6))?;
    lim::finite_in("camera.yaw", c.yaw, (-1e5, 1e5))?;
    lim::finite_in("camera.pitch", c.pitch, (-89.9, 89.9))?;
    lim::finite_in("camera.fov", c.fov, (0.001, 170.0))?;
    lim::int_in("check_every", req.check_every, (1, MAX_MICRO_STEPS))?;
    lim::finite_in("check_cell", req.check_cell, (0.0, 1e6))?;
    lim::int_in("check_modulus", req.check_modulus, (1, 1_000_000))?;
    lim::finite_in("max_relax", req.max_relax, (1.0, 16.0))?;
    lim::finite_in("bisection_factor", req.bisection_factor, (1.0, 16.0))?;
    lim::int_in("max_steps", req.max_steps, (1, MAX_MICRO_STEPS))?;
    lim::finite_in("pixel_fraction", req.pixel_fraction, (1e-6, 10.0))?;
    lim::finite_in("bounds", req.bounds, (1e-9, 1e6))?;
    lim::finite_in("absorption", req.absorption, (0.0, 1e6))?;
    lim::finite_in("roughness", req.roughness, (0.02, 1.0))?;
    lim::finite_in("specular", req.specular, (0.0, 1.0))?;
    lim::int_in("spp", req.spp, (0, MAX_MICRO_SPP))?;
    lim::int_in("max_depth", req.max_depth, (1, 64))?;
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
    let n = req.width as usize * req.height as usize * 4;
    Ok(RenderJob {
        scene: c.scene,
        trace: c.trace,
        rays: c.rays,
        shade: c.shade,
        width: req.width,
        height: req.height,
        next: 0,
        rgba: vec![0; n],
        stats: Stats::default(),
        spp: req.spp,
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

impl RenderJob {
    /// Path-trace work item `i`: sample `i / pixels` of pixel `i % pixels`,
    /// from its own generator (so the bytes do not depend on how the job
    /// is stepped).
    fn sample(&mut self, i: u64) {
        let n = self.width as u64 * self.height as u64;
        let (k, px) = (i / n, i % n);
        let (x, y) = (px % self.width as u64, px / self.width as u64);
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
        self.sum[px as usize] += l;
    }

    /// Render pixel `i` (row order) and store it.
    fn pixel(&mut self, i: u64) {
        let (x, y) = (
            (i % self.width as u64) as u32,
            (i / self.width as u64) as u32,
        );
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
}

impl Job for RenderJob {
    type Output = MicroRenderResponse;
    fn step(&mut self) -> Result<Step<MicroRenderResponse>> {
        let pixels = self.width as u64 * self.height as u64;
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
        if self.next < total {
            return Ok(Step::Running(Progress::new(
                self.next as f64 / total as f64,
                if self.spp > 0 {
                    "path tracing"
                } else {
                    "sphere tracing"
                },
            )));
        }
        if self.spp > 0 {
            // Average, then to 8 bits (linear, like the direct shading).
            let inv = 1.0 / self.spp as f64;
            for (px, l) in self.sum.iter().enumerate() {
                let c = *l * inv * 255.0;
                let q = |v: f64| v.round().clamp(0.0, 255.0) as u8;
                self.rgba[px * 4..px * 4 + 4].copy_from_slice(&[q(c.x), q(c.y), q(c.z), 255]);
            }
        }
        let img = Rgba8Image {
            width: self.width,
            height: self.height,
            data: std::mem::take(&mut self.rgba),
        };
        Ok(Step::Done(MicroRenderResponse {
            width: self.width,
            height: self.height,
            png: encode_png(&img)?,
            stats: self.stats,
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
    lim::finite_in("z", req.z, (-1e6, 1e6))?;
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
