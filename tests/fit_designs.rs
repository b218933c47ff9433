//! Designer example programs (issue 9 item 8): each shipped design, drawn at
//! parameters away from its defaults (the "perturbed start": a user's fit
//! starts from the program as written), is fitted to its own render with the
//! default settings a user gets (`FitRequest` with only the program and the
//! target image), and the fitted render must match the target.
//!
//! The bound is on the pictures, not the parameters: the mean per-colour
//! IoU of the fitted render against the target (both drawn at the target's
//! 96 px, every non-background colour) is ≥ 0.95. That is what a designer sees, and it is
//! the bound the issue used (1 of 9 designs reached it before); a parameter
//! bound would also punish values the picture does not pin (e.g. a phase
//! that moves a repeating design by exactly one period). The target is 96 px
//! so that the defaults pick a small grid (96) and each fit takes seconds;
//! lines thinner than a pixel there cannot be fitted from it, and the IoU is
//! measured at the resolution the fit saw.
use filigree::core::job::run_quietly;
use filigree::pattern::api::{start_fit, FitRequest};
use filigree::pattern::field::Scene;
use filigree::pattern::fit::colour_indices;
use filigree::pattern::generators::generator;
use filigree::pattern::record::{Program, RecordLimits};
use filigree::pattern::render;
use filigree::pattern::target::mean_iou;
use filigree::raster::encode_png;

/// Side of the target image in pixels; the IoU is measured at it too.
const SIDE: u32 = 96;

/// Fit design `name` to its own render at its defaults moved by `shift`
/// (a fraction of each range, alternating in sign) and return the IoU.
fn fit_own_render(name: &str, shift: f64) -> f64 {
    let src = generator(name).expect("generator").source;
    let p = Program::parse(src).unwrap();
    let scene = Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap());
    let truth: Vec<f64> = scene
        .rec
        .float_decls()
        .iter()
        .enumerate()
        .map(|(k, d)| {
            let s = if k % 2 == 0 { shift } else { -shift };
            (d.default + s * (d.hi - d.lo)).clamp(d.lo, d.hi)
        })
        .collect();
    let png = encode_png(&render::render(&scene, &truth, SIDE as usize, 1).unwrap()).unwrap();
    let req = FitRequest {
        program: src.into(),
        target_png: Some(png),
        ..Default::default()
    };
    let out = run_quietly(start_fit(&req).unwrap()).unwrap();
    let n = SIDE as usize;
    let want = colour_indices(&scene, &truth, n).unwrap();
    let got = colour_indices(&scene, &out.result.params, n).unwrap();
    let iou = mean_iou(&want, &got);
    eprintln!(
        "{name}: IoU {iou:.4}, truth {truth:?}, fitted {:?}",
        out.result.params
    );
    iou
}

macro_rules! design_test {
    ($test:ident, $name:expr) => {
        #[test]
        fn $test() {
            let iou = fit_own_render($name, 0.12);
            assert!(
                iou >= 0.95,
                "{}: mean per-colour IoU {iou:.4} < 0.95",
                $name
            );
        }
    };
}

design_test!(dots_fit_their_own_render, "dots");
design_test!(checkers_fit_their_own_render, "checkers");
design_test!(crosses_fit_their_own_render, "crosses");
design_test!(waves_fit_their_own_render, "waves");
design_test!(scales_fit_their_own_render, "scales");
design_test!(graph_paper_fit_their_own_render, "graph-paper");
design_test!(stripes_fit_their_own_render, "stripes");
design_test!(hexagons_fit_their_own_render, "honeycomb");

/// Scales convergence (issue 9 item 5). Fish scales fitted to their own
/// render with the default settings recover the row pitch, the scale pitch
/// and the ring width, from truths spread over the ranges.
///
/// What went wrong before, with the loss scanned along each parameter from
/// a truth (dx .16, dy .07, ox .04, oy .04, w .01; SDF loss, 96 grid):
/// - the row pitch `dy` has a needle-thin basin: the loss is 0.065 at the
///   truth and back at its plateau (2.1) 0.004 away, because an error in
///   `dy` moves row `j` by `j·Δdy` and the twentieth row is then a whole row
///   off; on that plateau the lower bound (2.05 at dy .05) beats everything
///   near the truth (2.1–2.4), since denser, thinner rings lie closer to any
///   target ring. A search that misses the needle ends at the lower bound
///   of `dy`, and of `w` with it: what the issue saw.
/// - the phase (`ox`, `oy`) had ranges shorter than one lattice period, so
///   the equivalent placement nearest to where the search went could lie
///   outside them: the fit then stopped at the bound of `ox` and bent `dx`
///   to make up for it (truth dx .17, ox .01, oy .07 → fitted dx .174, ox
///   .08 at its bound, oy .012; IoU well below 0.95).
///
/// The fix is in the program: the phase ranges span a whole lattice
/// period, so every shift of the design has a representative in range (the
/// third truth below is the case above; it now converges). The needle in
/// `dy` is unchanged: the default search (GA over the ranges, Adam, then the
/// image polish at the target's resolution) finds it for all three truths
/// here, but a search that misses it still ends at the lower bound. The
/// fit may land on a placement one lattice vector away from the truth (the
/// same picture), so the phase is checked through the render (IoU ≥ 0.97; 0.985–0.99 today)
/// and the pitches and width by value: within 0.001 (a tenth of a pixel at
/// the 96 px target) and 0.0005 (the width keeps a small bias, the target's
/// distances being measured between pixel centres).
#[test]
fn scales_recover_pitch_and_width() {
    let src = generator("scales").expect("generator").source;
    let p = Program::parse(src).unwrap();
    let scene = Scene::new(p.record(&p.defaults(), &RecordLimits::default()).unwrap());
    let names: Vec<&str> = scene
        .rec
        .float_decls()
        .iter()
        .map(|d| d.name.as_str())
        .collect();
    assert_eq!(names, ["dx", "dy", "ox", "oy", "w"]);
    let mut failures = vec![];
    for truth in [
        [0.15, 0.055, 0.03, 0.05, 0.012],
        [0.19, 0.085, 0.06, 0.02, 0.008],
        [0.17, 0.06, 0.01, 0.07, 0.015],
    ] {
        let png = encode_png(&render::render(&scene, &truth, SIDE as usize, 1).unwrap()).unwrap();
        let req = FitRequest {
            program: src.into(),
            target_png: Some(png),
            ..Default::default()
        };
        let out = run_quietly(start_fit(&req).unwrap()).unwrap();
        let f = &out.result.params;
        let n = SIDE as usize;
        let iou = mean_iou(
            &colour_indices(&scene, &truth, n).unwrap(),
            &colour_indices(&scene, f, n).unwrap(),
        );
        eprintln!("scales: truth {truth:?}, fitted {f:?}, IoU {iou:.4}");
        let (edx, edy, ew) = (
            (f[0] - truth[0]).abs(),
            (f[1] - truth[1]).abs(),
            (f[4] - truth[4]).abs(),
        );
        if !(edx <= 1e-3 && edy <= 1e-3 && ew <= 5e-4 && iou >= 0.97) {
            failures.push(format!(
                "truth {truth:?}: fitted {f:?} (|Δdx| {edx:.2e}, |Δdy| {edy:.2e}, |Δw| {ew:.2e}, IoU {iou:.4})"
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Fit `bench/designs/<name>` (a real design drawn outside the team, with
/// its program written as a user would) with the default request plus
/// `init`, and return the mean per-colour IoU at the target's size.
fn fit_real_design(name: &str, init: filigree::pattern::api::Init) -> f64 {
    use filigree::pattern::fit::image_canvas;
    use filigree::pattern::target::palette_indices;
    use filigree::raster::{decode, Limits};
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("bench/designs");
    let src = std::fs::read_to_string(dir.join(format!("{name}.flg"))).unwrap();
    let png = std::fs::read(dir.join(format!("{name}.png"))).unwrap();
    let req = FitRequest {
        program: src.clone(),
        target_png: Some(png.clone()),
        init,
        ..Default::default()
    };
    let out = run_quietly(start_fit(&req).unwrap()).unwrap();
    let img = decode(&png, Limits::default()).unwrap();
    let p = Program::parse(&src).unwrap();
    let rec = p
        .record_on(&p.defaults(), &RecordLimits::default(), image_canvas(&img))
        .unwrap();
    let scene = Scene::new(rec);
    let (w, h) = (img.width as usize, img.height as usize);
    let want = palette_indices(&img, &scene.rec.colours, (w, h), 60.0);
    let got = colour_indices(&scene, &out.result.params, w.max(h)).unwrap();
    let iou = mean_iou(&want, &got);
    eprintln!("{name} ({init:?}): IoU {iou:.4}, fitted {:?}", out.named);
    iou
}

/// Issue 37: the default fit's global stage (spectra, then a phase sweep)
/// finds the basin of a periodic parameter that the paper's GA misses. The
/// diagonal stripes of `bench/designs/` (a validation design: 45° stripes,
/// the program's initial angle −0.62 and range [−1.2, −0.4]) ended at the
/// angle's bound with the GA (IoU 0.24 on 2026-12-04: stripes at ~28°, the
/// spacing at its bound); the default now draws them (IoU ≥ 0.95).
#[test]
fn the_global_stage_finds_the_stripes_basin_the_ga_misses() {
    use filigree::pattern::api::Init;
    let ga = fit_real_design("diagonal-stripes", Init::Genetic);
    assert!(
        ga < 0.95,
        "the GA found it after all (IoU {ga:.4}): pick a harder design"
    );
    let iou = fit_real_design("diagonal-stripes", Init::Periodic);
    assert!(iou >= 0.95, "default fit: IoU {iou:.4} < 0.95");
}

/// Issue 37: fish scales (seigaiha) from `bench/designs/` (validation):
/// the GA drew scales about half the size with rows out of step (IoU 0.32);
/// the default fit's global stage gets the scale radius, the row pitch and
/// the phase.
#[test]
fn the_default_fit_draws_real_fish_scales() {
    let iou = fit_real_design("seigaiha", filigree::pattern::api::Init::Periodic);
    assert!(iou >= 0.95, "seigaiha: IoU {iou:.4} < 0.95");
}
