//! Each estimator moves the right way on textures built to differ in its
//! property; the quantile mapping and the ratings CSV behave.
use super::*;
use crate::core::rng::Rng;
use crate::texture::models::{find, render, render_height};

const N: usize = 128;

fn image(f: impl Fn(f64, f64) -> f64) -> Gray {
    let mut g = Gray::new(N, N);
    for y in 0..N {
        for x in 0..N {
            g.data[y * N + x] = f(x as f64 / N as f64, y as f64 / N as f64).clamp(0.0, 1.0) as f32;
        }
    }
    g
}

/// Sinusoidal stripes: `cycles` per image side along direction `angle`.
fn stripes(cycles: f64, angle: f64, amp: f64) -> Gray {
    let (c, s) = (angle.cos(), angle.sin());
    image(|x, y| 0.5 + amp * (std::f64::consts::TAU * cycles * (x * c + y * s)).sin())
}

/// Smooth isotropic noise: white noise blurred (wrapped) `r` times.
fn noise(seed: u64, amp: f64, r: usize) -> Gray {
    let mut rng = Rng::new(seed);
    let mut v: Vec<f32> = (0..N * N).map(|_| rng.f64() as f32).collect();
    for _ in 0..3 {
        crate::texture::models::common::box_blur(&mut v, N, r);
    }
    crate::texture::models::common::normalise(&mut v);
    let mut g = Gray::new(N, N);
    for (o, x) in g.data.iter_mut().zip(&v) {
        *o = (0.5 + amp * (*x as f64 - 0.5) * 2.0) as f32;
    }
    g
}

fn model(id: &str, pairs: &[(&str, f64)], seed: u64) -> Gray {
    let m = find(id).unwrap();
    render(m, &m.with(pairs).unwrap(), seed, N).unwrap()
}

fn scale(g: &Gray, name: &str) -> f64 {
    let i = SCALE_NAMES.iter().position(|&n| n == name).unwrap();
    measure(g).unwrap()[i]
}

/// `more` must score higher than `less` on `name`.
fn rises(name: &str, less: &Gray, more: &Gray) {
    let (a, b) = (scale(less, name), scale(more, name));
    assert!(b > a, "{name}: expected {b} > {a}");
}

#[test]
fn contrast_rises_with_amplitude() {
    rises("contrast", &noise(1, 0.1, 2), &noise(1, 0.4, 2));
    rises(
        "contrast",
        &stripes(8.0, 0.3, 0.1),
        &stripes(8.0, 0.3, 0.45),
    );
}

#[test]
fn repetition_rises_for_periodic_textures() {
    rises("repetition", &noise(2, 0.4, 2), &stripes(6.0, 0.0, 0.4));
    let random = model(
        "texton-random-grid",
        &[("jitter", 0.5), ("rotation", 1.0)],
        3,
    );
    let regular = model("texton-regular", &[], 3);
    rises("repetition", &random, &regular);
}

#[test]
fn regularity_falls_and_randomness_rises_with_random_placement() {
    let regular = model(
        "texton-random-grid",
        &[("jitter", 0.0), ("rotation", 0.0)],
        4,
    );
    let jittered = model(
        "texton-random-grid",
        &[("jitter", 0.5), ("rotation", 1.0)],
        4,
    );
    rises("regularity", &jittered, &regular);
    rises("randomness", &regular, &jittered);
    let lattice = model("texton-regular", &[("shape", 0.0)], 4);
    let scattered = model(
        "texton-addition",
        &[("count", 64.0), ("size_variation", 0.0)],
        4,
    );
    rises("regularity", &scattered, &lattice);
    rises("randomness", &lattice, &scattered);
}

#[test]
fn granularity_rises_with_small_grains() {
    let grains = model("texton-addition", &[("count", 400.0), ("size", 0.02)], 5);
    let smooth = model("perlin", &[("frequency", 3.0), ("octaves", 1.0)], 5);
    rises("granularity", &smooth, &grains);
    rises("granularity", &stripes(10.0, 0.4, 0.4), &grains);
}

#[test]
fn roughness_rises_as_the_spectrum_flattens() {
    let smooth = model("fractal-one-over-f", &[("beta", 3.5)], 6);
    let rough = model("fractal-one-over-f", &[("beta", 0.5)], 6);
    rises("roughness", &smooth, &rough);
}

#[test]
fn feature_density_rises_with_more_textons() {
    let few = model("texton-addition", &[("count", 20.0), ("size", 0.04)], 7);
    let many = model("texton-addition", &[("count", 300.0), ("size", 0.04)], 7);
    rises("feature_density", &few, &many);
}

#[test]
fn directionality_rises_for_stripes_and_local_orientation_for_curved_stripes() {
    let iso = noise(8, 0.4, 2);
    let straight = stripes(8.0, 0.5, 0.4);
    // Concentric rings: oriented everywhere, but in every direction.
    let rings = image(|x, y| {
        let r = ((x - 0.5).powi(2) + (y - 0.5).powi(2)).sqrt();
        0.5 + 0.4 * (std::f64::consts::TAU * 10.0 * r).sin()
    });
    rises("directionality", &iso, &straight);
    rises("directionality", &rings, &straight);
    rises("local_orientation", &iso, &rings);
    let dots = model("texton-regular", &[("shape", 0.0)], 8);
    rises("local_orientation", &dots, &rings);
}

#[test]
fn structural_complexity_rises_from_stripes_to_mixed_structures() {
    let simple = stripes(4.0, 0.0, 0.4);
    let mixed = model("fusion-perlin-texton", &[], 9);
    rises("structural_complexity", &simple, &mixed);
    let rough = model("fractal-one-over-f", &[("beta", 0.8)], 9);
    rises("structural_complexity", &simple, &rough);
}

#[test]
fn coarseness_rises_with_feature_size() {
    let fine = model("perlin", &[("frequency", 16.0), ("octaves", 1.0)], 10);
    let coarse = model("perlin", &[("frequency", 3.0), ("octaves", 1.0)], 10);
    rises("coarseness", &fine, &coarse);
    rises(
        "coarseness",
        &stripes(24.0, 0.0, 0.4),
        &stripes(3.0, 0.0, 0.4),
    );
}

#[test]
fn uniformity_falls_when_the_texture_changes_across_the_image() {
    let even = noise(11, 0.4, 1);
    let mut ramp = even.clone();
    for y in 0..N {
        for x in 0..N {
            let k = x as f32 / N as f32;
            let v = &mut ramp.data[y * N + x];
            *v = 0.5 + (*v - 0.5) * k;
        }
    }
    rises("uniformity", &ramp, &even);
}

#[test]
fn measures_are_finite_on_every_model_and_on_flat_images() {
    for m in crate::texture::models::MODELS.iter() {
        let g = render(m, &m.defaults(), 1, 64).unwrap();
        let s = measure(&g).unwrap();
        assert!(s.iter().all(|v| v.is_finite()), "{}: {s:?}", m.id);
    }
    let flat = Gray::new(40, 40);
    assert!(measure(&flat).unwrap().iter().all(|v| v.is_finite()));
    assert!(measure(&Gray::new(8, 8)).is_err());
    // Size does not matter much: the same texture at 128² and 256².
    let m = find("cellular").unwrap();
    let a = measure(&render(m, &m.defaults(), 2, 128).unwrap()).unwrap();
    let h = render_height(m, &m.defaults(), 2, 256).unwrap();
    let b = measure(&crate::texture::models::shade(
        &h,
        crate::texture::models::Light::DEFAULT,
    ))
    .unwrap();
    assert!(
        (a[0] - b[0]).abs() < 0.25 * a[0].abs().max(1e-3),
        "{a:?} {b:?}"
    );
}

#[test]
fn quantiles_map_a_dataset_evenly_to_1_through_9() {
    let raw: Vec<Scales> = (0..900).map(|i| [i as f64; N_SCALES]).collect();
    let q = ScaleQuantiles::fit(&raw).unwrap();
    let mut counts = [0usize; 10];
    for r in &raw {
        let l = q.to_likert(r);
        assert!(l.iter().all(|&v| (1..=9).contains(&v)));
        counts[l[0] as usize] += 1;
    }
    for c in &counts[1..] {
        assert!((95..=105).contains(c), "{counts:?}");
    }
    assert_eq!(q.to_likert(&[-1e9; N_SCALES]), [1; N_SCALES]);
    assert_eq!(q.to_likert(&[1e9; N_SCALES]), [9; N_SCALES]);
    assert!(ScaleQuantiles::fit(&[]).is_err());
    assert!(ScaleQuantiles::fit(&[[f64::NAN; N_SCALES]]).is_err());
}

fn header() -> String {
    format!("id,{}", SCALE_NAMES.join(","))
}

#[test]
fn ratings_csv_reads_columns_in_any_order_and_replaces_estimates() {
    let mut names: Vec<&str> = SCALE_NAMES.to_vec();
    names.reverse();
    let text = format!(
        "\u{feff}# human ratings\r\nSample,{}\r\n\"perlin-0001\",{}\n\nb,{}\n",
        names
            .iter()
            .map(|n| n.replace('_', " "))
            .collect::<Vec<_>>()
            .join(","),
        (1..=12)
            .map(|v| format!("{}", 1.0 + v as f64 * 0.5))
            .collect::<Vec<_>>()
            .join(","),
        ["5"; 12].join(", "),
    );
    let r = parse_ratings(&text).unwrap();
    assert_eq!(r.len(), 2);
    assert_eq!(r[0].id, "perlin-0001");
    // The first value column is the last scale (uniformity).
    assert_eq!(r[0].scales[11], 1.5);
    assert_eq!(r[0].scales[0], 7.0);
    let ids = vec!["x".to_string(), "b".to_string()];
    let mut est = [[2.0; N_SCALES]; 2];
    assert_eq!(apply_ratings(&ids, &mut est, &r), 1);
    assert_eq!(est[0], [2.0; N_SCALES]);
    assert_eq!(est[1], [5.0; N_SCALES]);
}

#[test]
fn ratings_csv_errors_name_the_line_and_column() {
    let row = |v: &str| format!("s1,{}", [v; 12].join(","));
    let cases: Vec<(String, (usize, usize))> = vec![
        (String::new(), (1, 1)),
        ("name,contrast".into(), (1, 1)),
        (header().replace("contrast", "contrastt"), (1, 4)),
        (header().replace("repetition", "contrast"), (1, 13)),
        (format!("{}\n{}", header(), row("10")), (2, 4)),
        (format!("{}\n{}", header(), row("x")), (2, 4)),
        (format!("{}\n{}\n{}", header(), row("3"), row("4")), (3, 1)),
        (format!("{}\ns1,1,2", header()), (2, 1)),
        (
            format!("{}\n\"s1,{}", header(), ["3"; 12].join(",")),
            (2, 1),
        ),
        (
            format!("{}\n\"s\"x,{}", header(), ["3"; 12].join(",")),
            (2, 4),
        ),
        (format!("{}\n ,{}", header(), ["3"; 12].join(",")), (2, 1)),
    ];
    for (text, (line, col)) in cases {
        let e = parse_ratings(&text).unwrap_err();
        assert_eq!(e.kind(), "syntax", "{text:?}: {e}");
        assert_eq!(e.position(), Some((line, col)), "{text:?}: {e}");
    }
    let nan = format!("{}\n{}", header(), row("NaN"));
    assert!(parse_ratings(&nan).is_err());
}

/// The box filter gives, bit for bit, each pixel's wrapped (2r + 1)²
/// neighbourhood summed row by row and then line by line, in the order
/// `at` reads it.
#[test]
fn box_mean_is_the_wrapped_neighbourhood_mean() {
    let mut r = Rng::new(5);
    let w: Vec<f64> = (0..WORK * WORK).map(|_| r.f64()).collect();
    for radius in [1, 3, 16] {
        let got = box_mean(&w, radius);
        let k = 1.0 / (2 * radius + 1) as f64;
        let d = radius as isize;
        let mut tmp = vec![0.0; WORK * WORK];
        for y in 0..WORK as isize {
            for x in 0..WORK as isize {
                tmp[y as usize * WORK + x as usize] =
                    (-d..=d).fold(0.0, |s, i| s + at(&w, x + i, y)) * k;
            }
        }
        for y in 0..WORK as isize {
            for x in 0..WORK as isize {
                let want = (-d..=d).fold(0.0, |s, i| s + at(&tmp, x, y + i)) * k;
                assert_eq!(
                    got[y as usize * WORK + x as usize],
                    want,
                    "r {radius} at ({x}, {y})"
                );
            }
        }
    }
}
