//! Every model: deterministic, seeded, parameter-sensitive, never constant
//! or NaN at its default and at the corners of its parameter box.
use super::*;

fn stats(g: &Gray) -> (f32, f32, bool) {
    let (lo, hi) = g
        .data
        .iter()
        .fold((f32::MAX, f32::MIN), |(l, h), &v| (l.min(v), h.max(v)));
    (lo, hi, g.data.iter().all(|v| v.is_finite()))
}

/// The corners of a model's parameter box: all of them for ≤ 4 parameters,
/// otherwise all-low, all-high and the two alternating patterns.
fn corners(m: &Model) -> Vec<Vec<f64>> {
    let k = m.params.len();
    let pick = |mask: u32| -> Vec<f64> {
        m.params
            .iter()
            .enumerate()
            .map(|(i, p)| if mask >> i & 1 == 1 { p.hi } else { p.lo })
            .collect()
    };
    if k <= 4 {
        (0..1u32 << k).map(pick).collect()
    } else {
        [0u32, u32::MAX, 0x5555_5555, 0xaaaa_aaaa]
            .into_iter()
            .map(pick)
            .collect()
    }
}

#[test]
fn there_are_23_models_with_unique_ids_and_sane_parameter_specs() {
    let mut ids: Vec<&str> = MODELS.iter().map(|m| m.id).collect();
    ids.sort();
    ids.dedup();
    assert_eq!(ids.len(), 23);
    for m in &MODELS {
        assert!(find(m.id).is_some());
        for p in m.params {
            assert!(
                p.lo < p.hi && (p.lo..=p.hi).contains(&p.default),
                "{}.{}",
                m.id,
                p.name
            );
        }
    }
}

#[test]
fn every_model_renders_a_varied_finite_image_at_its_default_and_corners() {
    for m in &MODELS {
        let mut cases = vec![m.defaults()];
        cases.extend(corners(m));
        for params in cases {
            let g = render_height(m, &params, 3, 64).unwrap();
            let (lo, hi, finite) = stats(&g);
            assert!(finite, "{} {params:?} has non-finite heights", m.id);
            assert!(hi - lo > 0.05, "{} {params:?} is flat ({lo}..{hi})", m.id);
            let s = shade(&g, Light::DEFAULT);
            let (slo, shi, sfinite) = stats(&s);
            assert!(
                sfinite && shi - slo > 0.01,
                "{} {params:?} shades flat",
                m.id
            );
        }
    }
}

#[test]
fn rendering_is_deterministic_and_seeded() {
    for m in &MODELS {
        let d = m.defaults();
        let a = render_height(m, &d, 7, 40).unwrap();
        let b = render_height(m, &d, 7, 40).unwrap();
        assert_eq!(a, b, "{}", m.id);
    }
    // Models with randomness give another texture for another seed.
    for m in MODELS
        .iter()
        .filter(|m| !matches!(m.id, "texton-regular" | "islamic" | "matrix-transformation"))
    {
        let d = m.defaults();
        let a = render_height(m, &d, 7, 40).unwrap();
        let b = render_height(m, &d, 8, 40).unwrap();
        assert_ne!(a, b, "{} ignores its seed", m.id);
    }
}

#[test]
fn every_parameter_changes_the_image() {
    for m in &MODELS {
        let d = m.defaults();
        let base = render_height(m, &d, 5, 48).unwrap();
        for (i, p) in m.params.iter().enumerate() {
            let mut q = d.clone();
            // Move to whichever end is further from the default.
            q[i] = if p.hi - p.default > p.default - p.lo {
                p.hi
            } else {
                p.lo
            };
            let other = render_height(m, &q, 5, 48).unwrap();
            assert_ne!(base, other, "{}.{} has no effect", m.id, p.name);
        }
    }
}

#[test]
fn bad_parameters_are_typed_errors_and_out_of_range_values_clamp() {
    let m = find("perlin").unwrap();
    let mut p = m.defaults();
    p[2] = f64::NAN;
    let e = render_height(m, &p, 1, 32).unwrap_err();
    assert_eq!(e.field(), Some("params.persistence"));
    assert_eq!(e.kind(), "invalid-input");
    let e = render_height(m, &[1.0], 1, 32).unwrap_err();
    assert_eq!(e.field(), Some("params"));
    let e = render_height(m, &m.defaults(), 1, 4).unwrap_err();
    assert_eq!((e.kind(), e.field()), ("limit", Some("size")));
    let mut hi = m.defaults();
    hi[0] = 1e9;
    let mut top = m.defaults();
    top[0] = m.params[0].hi;
    assert_eq!(
        render_height(m, &hi, 1, 32).unwrap(),
        render_height(m, &top, 1, 32).unwrap()
    );
    assert!(m.with(&[("nope", 1.0)]).is_err());
    assert!(lookup("no-such-model").is_err());
}

#[test]
fn models_tile_and_keep_their_look_across_sizes() {
    // The same texture at 64² and 128²: the larger, box-downsampled, is
    // close to the smaller (coordinates are image units).
    for m in &MODELS {
        let d = m.defaults();
        let a = render_height(m, &d, 11, 64).unwrap();
        let b = render_height(m, &d, 11, 128).unwrap();
        let mut err = 0.0f32;
        for y in 0..64 {
            for x in 0..64 {
                let s = (b.at(2 * x, 2 * y)
                    + b.at(2 * x + 1, 2 * y)
                    + b.at(2 * x, 2 * y + 1)
                    + b.at(2 * x + 1, 2 * y + 1))
                    / 4.0;
                err += (s - a.at(x, y)).abs();
            }
        }
        let mean = err / 4096.0;
        // Random-walk and probability-map textons depend on the pixel grid
        // only through rasterisation; automata and reaction–diffusion run
        // on their own grid. Everything should agree within a loose bound.
        assert!(
            mean < 0.12,
            "{}: mean difference {mean} between 64² and 128²",
            m.id
        );
    }
}

#[test]
fn shading_lights_slopes_facing_the_light() {
    // A ramp rising to the right (+x): a light from the left (azimuth 180°)
    // sees its slope facing it, so it is brighter than under a light from
    // the right.
    let mut g = Gray::new(32, 32);
    for y in 0..32 {
        for x in 0..32 {
            g.data[y * 32 + x] = (x as f32 / 31.0 * std::f32::consts::PI).sin() * 0.5;
        }
    }
    let left = shade(
        &g,
        Light {
            azimuth: 180.0,
            elevation: 45.0,
        },
    );
    let right = shade(
        &g,
        Light {
            azimuth: 0.0,
            elevation: 45.0,
        },
    );
    // On the rising part (x small), normals tilt toward −x.
    assert!(left.at(5, 10) > right.at(5, 10));
    let flat = shade(&Gray::new(8, 8), Light::DEFAULT);
    assert!((flat.at(3, 3) - std::f32::consts::FRAC_1_SQRT_2).abs() < 1e-5);
}
