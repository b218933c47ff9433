//! Loss and loss+gradient evaluations of one generator at one grid, for
//! profilers (callgrind counts instructions; wall time is printed too):
//! `cargo run --release --example fit_speed -- stripes-dots 128 2000 [grad]`.
// A native benchmark: wall-clock time is what it measures (never built for wasm).
#![allow(clippy::disallowed_methods)]
use filigree::pattern::field::Scene;
use filigree::pattern::fit::colour_indices;
use filigree::pattern::generators::GENERATORS;
use filigree::pattern::loss::{LossOptions, Objective};
use filigree::pattern::record::{Program, RecordLimits};
use filigree::pattern::target::Target;
use std::time::Instant;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map(String::as_str).unwrap_or("stripes-dots");
    let grid: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(128);
    let n: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(2000);
    let grad = args.get(4).is_some_and(|s| s == "grad");
    let g = GENERATORS
        .iter()
        .find(|g| g.name == name)
        .expect("generator");
    let prog = Program::parse(g.source).expect("parse");
    let rec = prog
        .record(&prog.defaults(), &RecordLimits::default())
        .expect("record");
    let decls = rec.float_decls();
    let lo: Vec<f64> = decls.iter().map(|d| d.lo).collect();
    let hi: Vec<f64> = decls.iter().map(|d| d.hi).collect();
    let scene = Scene::new(rec);
    let truth: Vec<f64> = lo.iter().zip(&hi).map(|(l, h)| l + 0.6 * (h - l)).collect();
    let loss = LossOptions {
        grid,
        ..LossOptions::default()
    };
    let idx = colour_indices(&scene, &truth, grid).expect("indices");
    let t = Target::from_indices(&scene, &idx, grid, loss.scale());
    let mut obj = Objective::new(scene, t, loss);
    let p: Vec<f64> = lo
        .iter()
        .zip(&hi)
        .map(|(l, h)| l + 0.45 * (h - l))
        .collect();
    if args.get(4).is_some_and(|s| s == "split") {
        split(&obj.scene.clone(), &obj.target.clone(), &loss, &p, n);
        return;
    }
    let mut gr = vec![0.0; p.len()];
    let t0 = Instant::now();
    let mut acc = 0.0;
    for _ in 0..n {
        acc += if grad {
            obj.loss_grad(&p, &mut gr)
        } else {
            obj.loss(&p)
        };
    }
    let s = t0.elapsed().as_secs_f64();
    println!("{{\"generator\":\"{name}\",\"grid\":{grid},\"grad\":{grad},\"per_s\":{:.0},\"checksum\":{acc:e},\"g0\":{:e}}}", n as f64 / s, gr[0]);
}

/// `-- NAME GRID N split`: the parts of one loss+gradient evaluation timed
/// apart (fields without and with winners, the backward pass).
#[allow(dead_code)]
pub fn split(scene: &Scene, t: &Target, loss: &LossOptions, p: &[f64], n: usize) {
    use filigree::pattern::field::Evaluator;
    let mut nodes = vec![];
    scene.rec.tape.forward(p, &mut nodes);
    let canvas = scene.rec.canvas;
    let mut ev = Evaluator::on(
        filigree::pattern::field::Grid::on(canvas, loss.grid),
        loss.scale_on(canvas),
    );
    let time = |f: &mut dyn FnMut()| {
        let t0 = Instant::now();
        for _ in 0..n {
            f();
        }
        t0.elapsed().as_secs_f64() / n as f64 * 1e6
    };
    if std::env::var("ONLY_EVAL").is_ok() {
        time(&mut || ev.eval(scene, &nodes, false));
        return;
    }
    if std::env::var("ONLY_WINNERS").is_ok() {
        time(&mut || ev.eval(scene, &nodes, true));
        return;
    }
    let a = time(&mut || ev.eval(scene, &nodes, false));
    let b = time(&mut || ev.eval(scene, &nodes, true));
    let ds: Vec<f64> =
        ev.s.iter()
            .zip(&t.sdf)
            .map(|(s, t)| 2.0 * (s - t) / 1e4)
            .collect();
    let mut adj = vec![0.0; nodes.len()];
    let c = time(&mut || ev.backward(scene, &ds, &mut adj));
    // Target normals as `loss::normals` makes them (for timing only).
    let (w, h) = (t.grid.w, t.grid.h);
    let mut tn = vec![];
    for ch in t.sdf.chunks(w * h) {
        for y in 0..h {
            for x in 0..w {
                let (xm, xp) = (x.saturating_sub(1), (x + 1).min(w - 1));
                let (ym, yp) = (y.saturating_sub(1), (y + 1).min(h - 1));
                let gx = (ch[y * w + xp] - ch[y * w + xm]) / (xp - xm).max(1) as f64;
                let gy = (ch[yp * w + x] - ch[ym * w + x]) / (yp - ym).max(1) as f64;
                let l = (gx * gx + gy * gy).sqrt();
                tn.push(if l > 1e-12 {
                    [gx / l, gy / l]
                } else {
                    [0.0, 0.0]
                });
            }
        }
    }
    let mut dsv = vec![0.0; ev.s.len()];
    let d = time(&mut || {
        std::hint::black_box(filigree::pattern::loss::loss(loss, &ev.s, t, &tn, None));
    });
    if std::env::var("ONLY_LOSS_GRAD").is_ok() {
        for _ in 0..n {
            std::hint::black_box(filigree::pattern::loss::loss(
                loss,
                &ev.s,
                t,
                &tn,
                Some(&mut dsv),
            ));
        }
        return;
    }
    let e = time(&mut || {
        std::hint::black_box(filigree::pattern::loss::loss(
            loss,
            &ev.s,
            t,
            &tn,
            Some(&mut dsv),
        ));
    });
    println!("{{\"eval_us\":{a:.1},\"eval_winners_us\":{b:.1},\"backward_us\":{c:.1},\"loss_us\":{d:.1},\"loss_grad_us\":{e:.1}}}");
}
