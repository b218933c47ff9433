//! Issue 12: what the paper's D(p) gradient checks select, and whether
//! checks can pay on the multiscale scene. Evaluation counts only (they do
//! not depend on the machine's load); one pass per variant.
//! `cargo run --release --example micro_dp_probe -- [size] [scene.json]`
use filigree::micro::render::{self, relax_for_slope, Camera, Rays};
use filigree::micro::sdf3;
use filigree::micro::Scene;
use glam::DVec3;

#[derive(Clone, Copy, Debug)]
enum Select {
    Never,
    Every(u32),
    /// Entering a cell of this size whose index has
    /// `qx + 2 qy + 3 qz ≡ 0 (mod m)` (the library's D(p)).
    Cells(f64, u32),
}

#[derive(Clone, Copy, Debug)]
enum Check {
    /// Central differences on 3 axes (6 evaluations).
    Grad6,
    /// Central difference along the ray (2 evaluations).
    Dir2,
    /// Forward difference along the ray, reusing the known distance (1).
    Dir1,
}

#[derive(Default, Debug, Clone, Copy)]
struct Count {
    rays: u64,
    evals: u64,
    checks: u64,
    undone: u64,
    hits: u64,
    steps: u64,
    /// Steps at which the paper's Eq. 33 (n = 11, 5, 7) / Eq. 34 held
    /// exactly, in f64 and in f32.
    eq33: u64,
    eq33_f32: u64,
    eq34: u64,
    eq34_f32: u64,
    /// Checks that changed the relaxation.
    changed: u64,
}

fn eq33(p: DVec3) -> (bool, bool) {
    let a = (p.y % 11.0).abs() == 0.0 || ((p.z % 5.0).abs() == 0.0 && (p.x % 7.0).abs() == 0.0);
    let q = p.as_vec3();
    let b = (q.y % 11.0).abs() == 0.0 || ((q.z % 5.0).abs() == 0.0 && (q.x % 7.0).abs() == 0.0);
    (a, b)
}

fn eq34(p: DVec3) -> (bool, bool) {
    let g = |x: f64, y: f64, z: f64| x.sin() * y.cos() + y.sin() * z.cos() + z.sin() * x.cos();
    let q = p.as_vec3();
    let g32 = q.x.sin() * q.y.cos() + q.y.sin() * q.z.cos() + q.z.sin() * q.x.cos();
    (g(p.x, p.y, p.z) == 0.5, g32 == 0.5)
}

/// `render::trace`'s adaptive loop with the selection, the kind of check,
/// the relaxation without checks (`w0`) and the cap a check may set (`wmax`).
#[allow(clippy::too_many_arguments)]
fn trace(
    scene: &Scene,
    o: DVec3,
    d: DVec3,
    precision: f64,
    sel: Select,
    check: Check,
    w0: f64,
    wmax: f64,
    local: bool,
    c: &mut Count,
) -> Option<f64> {
    c.rays += 1;
    let (t0, t1) = render::clip(o, d, 1.0 + 1e-9 + 1e-12)?;
    let f = |t: f64, c: &mut Count| {
        c.evals += 1;
        render::field(scene, 1.0, o + d * t)
    };
    let tiny = 1e-12 * (1.0 + t1);
    let mut t = t0;
    let mut dist = f(t, c);
    let mut relax = w0;
    let mut cooldown = false;
    let mut last_cell = DVec3::NAN;
    for i in 0..512u32 {
        let eps = precision * t.max(tiny);
        if dist < eps {
            return Some(t);
        }
        if t > t1 {
            return None;
        }
        c.steps += 1;
        let p = o + d * t;
        let (a, b) = eq33(p);
        c.eq33 += a as u64;
        c.eq33_f32 += b as u64;
        let (a, b) = eq34(p);
        c.eq34 += a as u64;
        c.eq34_f32 += b as u64;
        let want = match sel {
            Select::Never => false,
            Select::Every(n) => i % n == 0 && (i > 0 || n <= 1),
            Select::Cells(cell, m) => {
                let q = (p / cell).floor();
                let fresh = q != last_cell;
                last_cell = q;
                fresh && i > 0 && (q.x + 2.0 * q.y + 3.0 * q.z).rem_euclid(m as f64) == 0.0
            }
        };
        if local {
            relax = w0;
        }
        if want && dist >= 2.0 * eps {
            c.checks += 1;
            let h = (precision * t).max(1e-9);
            let slope = match check {
                Check::Grad6 => {
                    let g = sdf3::gradient(
                        &mut |q| {
                            c.evals += 1;
                            render::field(scene, 1.0, q)
                        },
                        p,
                        h,
                    );
                    -g.dot(d)
                }
                Check::Dir2 => {
                    let a = f(t + h, c);
                    let b = f(t - h, c);
                    -(a - b) / (2.0 * h)
                }
                Check::Dir1 => {
                    let a = f(t + h, c);
                    -(a - dist) / h
                }
            };
            let r = relax_for_slope(slope, wmax);
            c.changed += (r != relax) as u64;
            relax = r;
        }
        let step = if cooldown { 1.0 } else { relax };
        cooldown = false;
        let (tp, dp) = (t, dist);
        t += dist * step;
        dist = f(t, c);
        if step > 1.0 && (dist < 0.0 || dp + dist < (t - tp) * (1.0 - 1e-12)) {
            c.undone += 1;
            cooldown = true;
            let (tr, dr) = (t, dist);
            t = tp + dp;
            dist = f(t, c);
            if dr >= 0.0 && dist + dr >= (tr - t) * (1.0 + 1e-12) {
                t = tr;
                dist = dr;
            }
        }
    }
    None
}

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let size: u32 = a.get(1).and_then(|s| s.parse().ok()).unwrap_or(160);
    let path = a
        .get(2)
        .cloned()
        .unwrap_or("assets/micro/multiscale.json".into());
    let scene =
        filigree::micro::parse(&std::fs::read_to_string(&path).expect("scene")).expect("parse");
    let rays = Rays::new(&Camera::default(), size, size);
    let precision = rays.pixel_angle() * 0.5;
    // Fixed steps for the ratio: the library's trace.
    let fixed = {
        let tr = render::Trace {
            mode: render::StepMode::Fixed,
            check_every: 10,
            check_cell: 0.0,
            check_modulus: 3,
            max_relax: 1.5,
            bisection_factor: 1.5,
            max_steps: 512,
            precision,
            bounds: 1.0,
        };
        let mut st = render::Stats::default();
        for y in 0..size {
            for x in 0..size {
                render::trace(&scene, rays.origin, rays.dir(x, y), &tr, &mut st);
            }
        }
        st.sdf_evals as f64
    };
    println!("{path} {size}²: trace evaluations (no normals), ratios to fixed steps");
    println!("| selection | check | ω0 | ω max | local | evals/ray | /fixed | checks/ray | changed/ray | undone/ray | hits | eq33 f64/f32 | eq34 f64/f32 | steps |");
    let mut variants = vec![(Select::Never, Check::Grad6, 1.5, 1.5, false)];
    let local_only = std::env::var("PROBE_LOCAL").is_ok();
    for local in [false, true] {
        if local_only && !local {
            continue;
        }
        for check in [Check::Grad6, Check::Dir2, Check::Dir1] {
            if local_only && !matches!(check, Check::Dir1) {
                continue;
            }
            for wmax in [1.5, 2.0, 3.0] {
                for sel in [
                    Select::Every(1),
                    Select::Every(3),
                    Select::Every(10),
                    Select::Cells(0.25, 3),
                    Select::Cells(0.1, 3),
                    Select::Cells(0.04, 3),
                ] {
                    variants.push((sel, check, 1.5, wmax, local));
                }
            }
        }
    }
    for (sel, check, w0, wmax, local) in variants {
        let mut c = Count::default();
        for y in 0..size {
            for x in 0..size {
                let d = rays.dir(x, y);
                if trace(
                    &scene,
                    rays.origin,
                    d,
                    precision,
                    sel,
                    check,
                    w0,
                    wmax,
                    local,
                    &mut c,
                )
                .is_some()
                {
                    c.hits += 1;
                }
            }
        }
        let r = c.rays as f64;
        println!(
            "| {sel:?} | {check:?} | {w0} | {wmax} | {local} | {:.3} | {:.3} | {:.3} | {:.3} | {:.3} | {} | {}/{} | {}/{} | {} |",
            c.evals as f64 / r,
            c.evals as f64 / fixed,
            c.checks as f64 / r,
            c.changed as f64 / r,
            c.undone as f64 / r,
            c.hits,
            c.eq33,
            c.eq33_f32,
            c.eq34,
            c.eq34_f32,
            c.steps
        );
    }
}
