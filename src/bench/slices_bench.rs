//! `filigree bench slices`: how long one `step()` of each request kind takes
//! at its largest realistic size. The browser worker runs steps until ~15 ms
//! have passed, so a step far over that delays cancellation and progress.
//! Each request is built as the worker builds it (its `start_*` function),
//! the start call is timed as a slice of its own, then every step is timed.
use super::measure::thread_cpu_ms;
use filigree::api::inspect::{start_decode, start_inspect, DecodeImageRequest, InspectRequest};
use filigree::core::job::{Job, Step};
use filigree::pattern::api::{
    start_eval, start_fit, start_render, EvalPoints, FitEvalRequest, FitRequest,
    RenderPatternRequest,
};
use filigree::pattern::generators::generator;
use filigree::pixel::api::{start_pixel, MaskBits, PixelRequest};
use filigree::raster::{decode, encode_png, Limits, Rgba8Image};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::time::Instant;

/// Step timings of one request.
struct Timing {
    start_ms: f64,
    /// The start call in thread CPU time (when available).
    start_cpu_ms: Option<f64>,
    steps_ms: Vec<f64>,
    /// The same steps in thread CPU time (empty where not available).
    cpu_ms: Vec<f64>,
    /// Per stage (the stage reported before the step): step count and max ms.
    stages: BTreeMap<String, (usize, f64)>,
    /// The first few steps over 20 ms CPU: (step index, stage, ms).
    slow: Vec<(usize, String, f64)>,
    total_s: f64,
}

fn time_job<J: Job>(start: impl FnOnce() -> filigree::Result<J>) -> Result<Timing, String> {
    let t_all = Instant::now();
    let c = thread_cpu_ms();
    let t = Instant::now();
    let mut job = start().map_err(|e| e.to_string())?;
    let start_ms = t.elapsed().as_secs_f64() * 1e3;
    let start_cpu_ms = c.zip(thread_cpu_ms()).map(|(a, b)| b - a);
    let mut steps_ms = vec![];
    let mut cpu_ms = vec![];
    let mut slow = vec![];
    let mut stages: BTreeMap<String, (usize, f64)> = BTreeMap::new();
    // A step is named after the stage the step before it reported (what the
    // job said it would do next), so the worst stage can be found.
    let mut doing = "first step".to_string();
    loop {
        let c = thread_cpu_ms();
        let t = Instant::now();
        let step = job.step().map_err(|e| e.to_string())?;
        let ms = t.elapsed().as_secs_f64() * 1e3;
        steps_ms.push(ms);
        if let (Some(a), Some(b)) = (c, thread_cpu_ms()) {
            cpu_ms.push(b - a);
        }
        let name = match &step {
            Step::Running(p) => std::mem::replace(&mut doing, p.stage.clone()),
            Step::Done(_) => std::mem::take(&mut doing),
        };
        let cpu = cpu_ms.last().copied().unwrap_or(ms);
        if cpu > 20.0 && slow.len() < 8 {
            slow.push((steps_ms.len() - 1, name.clone(), round(cpu)));
        }
        let e = stages.entry(name).or_insert((0, 0.0));
        e.0 += 1;
        e.1 = e.1.max(cpu);
        if let Step::Done(out) = step {
            drop(out);
            break;
        }
    }
    Ok(Timing {
        start_ms,
        start_cpu_ms,
        steps_ms,
        cpu_ms,
        stages,
        slow,
        total_s: t_all.elapsed().as_secs_f64(),
    })
}

fn report(kind: &str, what: &str, t: Timing) -> Value {
    let stats = |v: &[f64]| {
        let mut v = v.to_vec();
        v.sort_by(|a, b| a.total_cmp(b));
        let at = |q: f64| {
            v.get(((v.len() as f64 - 1.0) * q).round() as usize)
                .copied()
        };
        json!({
            "median_ms": at(0.5).map(round),
            "p95_ms": at(0.95).map(round),
            "max_ms": v.last().copied().map(round),
        })
    };
    let stages: serde_json::Map<String, Value> = t
        .stages
        .into_iter()
        .map(|(k, (n, m))| (k, json!({"steps": n, "max_ms": round(m)})))
        .collect();
    let out = json!({
        "kind": kind,
        "input": what,
        "steps": t.steps_ms.len(),
        "start_ms": round(t.start_ms),
        "start_cpu_ms": t.start_cpu_ms.map(round),
        "wall": stats(&t.steps_ms),
        "cpu": stats(&t.cpu_ms),
        "total_s": (t.total_s * 1e3).round() / 1e3,
        "stages": stages,
        "slow_steps": t.slow,
    });
    eprintln!("{out}");
    out
}

fn round(ms: f64) -> f64 {
    (ms * 100.0).round() / 100.0
}

/// An image with every pixel a different colour (4096² = 2^24 pixels: every
/// RGB colour exactly once), the worst case of `inspect`.
fn every_colour(side: u32) -> Rgba8Image {
    let mut img = Rgba8Image::new(side, side);
    for (i, px) in img.data.chunks_exact_mut(4).enumerate() {
        // A bijection of the index, so neighbours differ in every channel.
        let v = (i as u32).wrapping_mul(0x9E3779B1) & 0xFF_FFFF;
        px.copy_from_slice(&[(v >> 16) as u8, (v >> 8) as u8, v as u8, 255]);
    }
    img
}

/// `img` scaled up by a whole factor (nearest neighbour).
fn upscale(img: &Rgba8Image, k: u32) -> Rgba8Image {
    let mut out = Rgba8Image::new(img.width * k, img.height * k);
    for y in 0..out.height {
        for x in 0..out.width {
            out.put(x, y, img.get(x / k, y / k));
        }
    }
    out
}

fn png(img: &Rgba8Image) -> Result<Vec<u8>, String> {
    encode_png(img).map_err(|e| e.to_string())
}

/// A program of `n` circles on a grid in two colours (at most the shape limit).
fn many_circles(n: usize) -> String {
    let side = (n as f64).sqrt().ceil() as usize;
    format!(
        "background \"#ffffff\";\nfor i in 0..{side} {{ for j in 0..{side} {{ \
         circle((i + 0.5) / {side}, (j + 0.5) / {side}, 0.7 / {side}, fill: \"#{}\"); }} }}\n",
        "aa3311"
    )
}

pub fn run(only: Option<&str>) -> Result<(), String> {
    let want = |k: &str| only.is_none_or(|o| o.split(',').any(|w| w == k));
    let mut rows = vec![];
    let prog = |name: &str| -> Result<String, String> {
        Ok(generator(name)
            .ok_or_else(|| format!("no generator {name}"))?
            .source
            .to_string())
    };
    if want("render-pattern") {
        let req = RenderPatternRequest {
            program: prog("circles-mix")?,
            size: 2048,
            ..Default::default()
        };
        rows.push(report(
            "render-pattern",
            "circles-mix 2048² ×1",
            time_job(|| start_render(req))?,
        ));
        let req = RenderPatternRequest {
            program: many_circles(4900),
            size: 2048,
            supersample: 2,
            ..Default::default()
        };
        rows.push(report(
            "render-pattern",
            "4,900 circles 2048² ×2 (4096² samples)",
            time_job(|| start_render(req))?,
        ));
    }
    if want("fit-eval") {
        let g = "circles-mix";
        let req = FitEvalRequest {
            program: prog(g)?,
            target_params: Some(BTreeMap::new()),
            grid: Some(1024),
            extra: EvalPoints { points: vec![] },
            ..Default::default()
        };
        // Points: the program's defaults, four times (the values do not
        // matter for timing; the count does).
        let p =
            filigree::pattern::record::Program::parse(&req.program).map_err(|e| e.to_string())?;
        let rec = p
            .record(
                &p.defaults(),
                &filigree::pattern::record::RecordLimits::default(),
            )
            .map_err(|e| e.to_string())?;
        let x = rec.float_values();
        let req = FitEvalRequest {
            extra: EvalPoints { points: vec![x; 4] },
            ..req
        };
        rows.push(report(
            "fit-eval",
            "circles-mix, grid 1024, 4 points",
            time_job(|| start_eval(req))?,
        ));
    }
    if want("fit") {
        let req = FitRequest {
            program: prog("circles-mix")?,
            target_params: Some(BTreeMap::new()),
            ..Default::default()
        };
        rows.push(report(
            "fit",
            "circles-mix, quick budget",
            time_job(|| start_fit(&req))?,
        ));
    }
    if want("fit") {
        // The target's preparation and the evaluations at a fit's biggest
        // grid (256): a 1024² image target, a short search after it.
        let program = prog("circles-mix")?;
        let mut render = start_render(RenderPatternRequest {
            program: program.clone(),
            size: 1024,
            ..Default::default()
        })
        .map_err(|e| e.to_string())?;
        let image = loop {
            if let Step::Done(r) = render.step().map_err(|e| e.to_string())? {
                break r.image;
            }
        };
        let req = FitRequest {
            program,
            target_rgba: Some(filigree::pattern::api::RawRgba {
                width: image.width,
                height: image.height,
                rgba: image.rgba,
            }),
            grid: Some(filigree::core::request_limits::FIT_GRID.1),
            population: Some(4),
            generations: Some(1),
            candidates: Some(1),
            iterations: Some(2),
            ..Default::default()
        };
        rows.push(report(
            "fit",
            "circles-mix, grid 256, 1024² image target, 4 + 2 evaluations",
            time_job(|| start_fit(&req))?,
        ));
    }
    if want("pixel") {
        let fish = decode(super::measure::fixture("fish.png")?, Limits::default())
            .map_err(|e| e.to_string())?;
        let k = 32;
        let source = upscale(&fish, k);
        let (w, h) = (source.width, source.height);
        #[derive(serde::Deserialize)]
        struct Strokes {
            strokes: Vec<filigree::pixel::Stroke>,
        }
        let s: Strokes = serde_json::from_slice(super::measure::fixture("fish_strokes.json")?)
            .map_err(|e| e.to_string())?;
        let strokes = s
            .strokes
            .into_iter()
            .map(|st| {
                st.into_iter()
                    .map(|p| [p[0] * k as f32, p[1] * k as f32])
                    .collect()
            })
            .collect();
        let req = PixelRequest {
            source: png(&source)?,
            mask: MaskBits {
                width: w,
                height: h,
                bits: vec![1; (w * h) as usize],
            },
            sheet: Some(super::measure::fixture("fish_scale.png")?.to_vec()),
            sprite: None,
            strokes,
            params: filigree::pixel::PixelParams {
                annotation_scale: 4,
                seed: 7,
                ..Default::default()
            },
        };
        rows.push(report(
            "pixel",
            "fish ×32 = 4096², full mask, fish strokes ×32",
            time_job(|| start_pixel(req))?,
        ));
    }
    let big = if want("inspect") || want("decode-image") {
        png(&every_colour(4096))?
    } else {
        vec![]
    };
    if want("inspect") {
        let req = InspectRequest {
            bytes: big.clone(),
            ..Default::default()
        };
        rows.push(report(
            "inspect",
            "4096² PNG, every pixel a different colour",
            time_job(|| start_inspect(req))?,
        ));
    }
    if want("decode-image") {
        let req = DecodeImageRequest { bytes: big };
        rows.push(report(
            "decode-image",
            "4096² PNG, every pixel a different colour",
            time_job(|| Ok(start_decode(req)))?,
        ));
    }
    if want("open-project") {
        let text = big_project()?;
        let what = format!(
            "{:.1} MB pixel project: 4096² mask, 200,000 stroke points",
            text.len() as f64 / 1e6
        );
        rows.push(report(
            "open-project",
            &what,
            time_job(|| {
                Ok(filigree::api::project::start_open_project(
                    filigree::api::project::OpenProjectRequest {
                        text: text.clone(),
                        unchecked: false,
                    },
                    filigree::api::project::check_any,
                ))
            })?,
        ));
        // Baselines in the same run: the whole request as one step, and
        // the one-go serde_json reading it was before it was stepped.
        rows.push(report(
            "open-project",
            &format!("{what}; baseline: the whole request in one step"),
            time_job(|| {
                Ok(filigree::core::job::OneShot::new(|| {
                    filigree::api::project::open_project(&text)
                }))
            })?,
        ));
        rows.push(report(
            "open-project",
            &format!("{what}; baseline: reading it in one go with serde_json (before)"),
            time_job(|| {
                Ok(filigree::core::job::OneShot::new(|| {
                    filigree::api::project::json::read_at_once(&text)
                }))
            })?,
        ));
    }
    println!(
        "{}",
        json!({
            "bench": "slices",
            "about": "one row per request: steps; the start call (request checks and decoding, one slice in the worker) in ms, wall and thread CPU; median, 95th percentile and max step time in ms as wall clock and as this thread's CPU time (which a busy machine does not inflate); total seconds; per stage (the stage reported before the step) the step count and max CPU ms",
            "rows": rows,
        })
    );
    Ok(())
}

/// A pixel project as the page saves it, at the limits: a 4096² mask (its
/// bits as base64, 22 MB), 200,000 stroke points in 200 strokes.
fn big_project() -> Result<String, String> {
    use filigree::api::project::base64_encode;
    let side = 4096usize;
    let bits: Vec<u8> = (0..side * side)
        .map(|i| {
            let (x, y) = ((i % side) as f64 - 2048.0, (i / side) as f64 - 2048.0);
            u8::from(x * x + y * y < 1800.0 * 1800.0)
        })
        .collect();
    let strokes: Vec<Vec<[f64; 2]>> = (0..200)
        .map(|s| {
            (0..1000)
                .map(|j| {
                    let t = (s * 1000 + j) as f64;
                    let r = |v: f64| (v * 100.0).round() / 100.0;
                    [r((t * 7.31) % 4096.0), r((t * 3.77 + 11.0) % 4096.0)]
                })
                .collect()
        })
        .collect();
    let b = |bytes: &[u8]| json!({ "$bytes": base64_encode(bytes) });
    let params =
        serde_json::to_value(filigree::pixel::PixelParams::default()).map_err(|e| e.to_string())?;
    let state = json!({
        "example": null,
        "source": b(super::measure::fixture("fish.png")?),
        "sheet": b(super::measure::fixture("fish_scale.png")?),
        "sprite": null,
        "mask": {"width": side, "height": side, "bits": b(&bits)},
        "strokes": strokes,
        "params": params,
        "names": {"source": "big.png", "sheet": "fish_scale.png"},
    });
    Ok(
        json!({"format": "filigree-project", "version": 2, "tool": "pixel",
              "stateVersion": 1, "state": state})
        .to_string(),
    )
}
