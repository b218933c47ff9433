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
use filigree::raster::encode_png;

/// Side of the target image in pixels; the IoU is measured at it too.
const SIDE: u32 = 96;

/// Mean IoU over the non-background colours present in either picture.
fn mean_iou(a: &[u16], b: &[u16]) -> f64 {
    let max = a.iter().chain(b).copied().max().unwrap_or(0);
    let mut ious = vec![];
    for c in 1..=max {
        let inter = a
            .iter()
            .zip(b)
            .filter(|(x, y)| **x == c && **y == c)
            .count();
        let union = a
            .iter()
            .zip(b)
            .filter(|(x, y)| **x == c || **y == c)
            .count();
        if union > 0 {
            ious.push(inter as f64 / union as f64);
        }
    }
    ious.iter().sum::<f64>() / ious.len().max(1) as f64
}

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
