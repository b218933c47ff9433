//! Integration tests of pixel-art texturing on the fixture cases
//! (`assets/pixel/cases.json`) and hand-made inputs.
//!
//! `bash scripts/bless.sh pixel` rewrites `tests/golden/pixel/fish.png`
//! and `trunk.png` (the two shipped cases at their parameters, seed 7).
// Index loops mirror the maths (rows, pixels) more plainly than iterator chains here.
#![allow(clippy::needless_range_loop)]
use filigree::pixel::{
    self, laplace, ColourMapKind, ColourStrategy, Elements, PixelInputs, PixelJob, PixelParams,
    PositionStrategy,
};
use filigree::raster::{decode, encode_png, exact_palette, Limits, Rgba8Image};
use std::collections::HashSet;
use std::path::{Path, PathBuf};

fn fixtures() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/pixel")
}

fn image(name: &str) -> Rgba8Image {
    let bytes = std::fs::read(fixtures().join(name)).unwrap();
    decode(&bytes, Limits::default()).unwrap()
}

fn case(name: &str) -> (PixelInputs, PixelParams) {
    let cases: serde_json::Value =
        serde_json::from_slice(&std::fs::read(fixtures().join("cases.json")).unwrap()).unwrap();
    let c = &cases[name];
    let s = |k: &str| c[k].as_str().unwrap().to_string();
    #[derive(serde::Deserialize)]
    struct Strokes {
        strokes: Vec<pixel::Stroke>,
    }
    let strokes: Strokes =
        serde_json::from_slice(&std::fs::read(fixtures().join(s("strokes"))).unwrap()).unwrap();
    let params: PixelParams = serde_json::from_value(c["params"].clone()).unwrap();
    let inputs = PixelInputs {
        source: image(&s("source")),
        mask: image(&s("mask")),
        elements: Elements::Sheet(image(&s("sheet"))),
        strokes: strokes.strokes,
    };
    (inputs, params)
}

fn colours(img: &Rgba8Image) -> HashSet<[u8; 4]> {
    exact_palette(img, 0).into_iter().map(|e| e.rgba).collect()
}

fn mask_of(inputs: &PixelInputs) -> Vec<bool> {
    pixel::inputs::mask_from_image(&inputs.mask)
}

#[test]
fn palette_strategies_add_no_colour() {
    for name in ["fish", "trunk"] {
        for strategy in [
            ColourStrategy::Auto,
            ColourStrategy::Difference,
            ColourStrategy::Border,
        ] {
            for element_colour in [pixel::ElementColour::Region, pixel::ElementColour::Pixel] {
                let (inputs, mut params) = case(name);
                params.colour = strategy;
                params.element_colour = element_colour;
                let before = colours(&inputs.source);
                let out = pixel::texture(inputs, params).unwrap();
                let after = colours(&out.image);
                assert!(
                    after.is_subset(&before),
                    "{name} {strategy:?}: new colours {:?}",
                    after.difference(&before)
                );
                assert!(
                    out.stats.placed > 20,
                    "{name} {strategy:?}: only {} placed",
                    out.stats.placed
                );
                assert_ne!(
                    out.image,
                    image(if name == "fish" {
                        "fish.png"
                    } else {
                        "trunk_unpatterned.png"
                    })
                );
                // Counted independently of `exact_palette`, which produced the stat.
                let distinct: HashSet<[u8; 4]> = out.image.pixels().filter(|p| p[3] > 0).collect();
                assert_eq!(out.stats.colours_after, distinct.len());
            }
        }
    }
}

#[test]
fn hsv_shift_is_the_only_one_adding_colours() {
    let (inputs, mut params) = case("trunk");
    params.colour = ColourStrategy::Hsv;
    let before = colours(&inputs.source);
    let out = pixel::texture(inputs, params).unwrap();
    assert_eq!(out.stats.colour_map_used, ColourMapKind::Hsv);
    assert!(!colours(&out.image).is_subset(&before));
}

#[test]
fn auto_picks_shared_border_on_the_thesis_cases() {
    // Appendix A reports "Auto (SB)" for both.
    for name in ["fish", "trunk"] {
        let (inputs, params) = case(name);
        assert_eq!(
            pixel::texture(inputs, params)
                .unwrap()
                .stats
                .colour_map_used,
            ColourMapKind::Border,
            "{name}"
        );
    }
}

#[test]
fn no_overlap_and_nothing_outside_the_mask() {
    for name in ["fish", "trunk"] {
        for strategy in [PositionStrategy::Random, PositionStrategy::Packed] {
            for margins in [[0, 0], [1, 2]] {
                let (inputs, mut params) = case(name);
                params.positions = strategy;
                params.margins = margins;
                let mask = mask_of(&inputs);
                let src = inputs.source.clone();
                let out = pixel::texture(inputs, params.clone()).unwrap();
                let w = src.width as usize;
                // Nothing outside the mask changes.
                for i in 0..src.pixel_count() {
                    if !mask[i] {
                        assert_eq!(
                            src.data[4 * i..4 * i + 4],
                            out.image.data[4 * i..4 * i + 4],
                            "{name}: pixel {} {}",
                            i % w,
                            i / w
                        );
                    }
                }
                // Cells never overlap, and are at least the margins apart.
                let cell = if name == "fish" { 6 } else { 4 };
                let p = &out.positions;
                for (i, a) in p.iter().enumerate() {
                    for b in &p[i + 1..] {
                        let gx = (a.0 - b.0).abs() - cell;
                        let gy = (a.1 - b.1).abs() - cell;
                        assert!(
                            gx >= margins[0] || gy >= margins[1],
                            "{name} {strategy:?} {margins:?}: {a:?} {b:?}"
                        );
                    }
                }
                // Without `partial`, every cell is fully inside the mask.
                params.partial = false;
                let (inputs, _) = case(name);
                let out = pixel::texture(inputs, params).unwrap();
                for &(x, y) in &out.positions {
                    for yy in y..y + cell {
                        for xx in x..x + cell {
                            assert!(
                                mask[yy as usize * w + xx as usize],
                                "{name}: cell at {x},{y}"
                            );
                        }
                    }
                }
            }
        }
    }
}

/// Solve `A x = b` densely by Gaussian elimination with partial pivoting.
fn gauss(mut a: Vec<Vec<f64>>, mut b: Vec<f64>) -> Vec<f64> {
    let n = b.len();
    for k in 0..n {
        let piv = (k..n)
            .max_by(|&i, &j| a[i][k].abs().total_cmp(&a[j][k].abs()))
            .unwrap();
        a.swap(k, piv);
        b.swap(k, piv);
        for i in k + 1..n {
            let f = a[i][k] / a[k][k];
            for j in k..n {
                a[i][j] -= f * a[k][j];
            }
            b[i] -= f * b[k];
        }
    }
    let mut x = vec![0.0; n];
    for i in (0..n).rev() {
        let s: f64 = (i + 1..n).map(|j| a[i][j] * x[j]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    x
}

#[test]
fn laplace_matches_a_dense_solve() {
    // 13×9 grid, Neumann border, a few scattered constraints.
    let (w, h) = (13usize, 9usize);
    let mut fixed = vec![false; w * h];
    let mut values = vec![[0.0; 2]; w * h];
    for (x, y, v) in [
        (1, 1, [1.0, 0.0]),
        (11, 2, [0.0, -1.0]),
        (6, 7, [-0.5, 0.5]),
        (7, 7, [-0.6, 0.4]),
        (3, 5, [0.2, 0.9]),
    ] {
        fixed[y * w + x] = true;
        values[y * w + x] = v;
    }
    let (field, _) = laplace::solve(w, h, fixed.clone(), values.clone());
    // Constraints hold exactly.
    for i in 0..w * h {
        if fixed[i] {
            assert_eq!(field[i], values[i]);
        }
    }
    // Dense system over all pixels: fixed rows are identity.
    let n = w * h;
    for c in 0..2 {
        let mut a = vec![vec![0.0; n]; n];
        let mut b = vec![0.0; n];
        for y in 0..h {
            for x in 0..w {
                let i = y * w + x;
                if fixed[i] {
                    a[i][i] = 1.0;
                    b[i] = values[i][c];
                    continue;
                }
                let nbrs: Vec<usize> = [
                    (x > 0, i.wrapping_sub(1)),
                    (x + 1 < w, i + 1),
                    (y > 0, i.wrapping_sub(w)),
                    (y + 1 < h, i + w),
                ]
                .into_iter()
                .filter(|t| t.0)
                .map(|t| t.1)
                .collect();
                a[i][i] = nbrs.len() as f64;
                for j in nbrs {
                    a[i][j] = -1.0;
                }
            }
        }
        let x = gauss(a.clone(), b);
        for i in 0..n {
            assert!(
                (x[i] - field[i][c]).abs() < 1e-7,
                "component {c} pixel {i}: dense {} vs {}",
                x[i],
                field[i][c]
            );
            if !fixed[i] {
                let lap: f64 = (0..n).map(|j| a[i][j] * field[j][c]).sum();
                assert!(lap.abs() < 1e-7, "Laplacian {lap} at free pixel {i}");
            }
        }
    }
}

#[test]
fn strokes_steer_orientations_and_no_strokes_use_the_default() {
    let (mut inputs, mut params) = case("fish");
    inputs.strokes.clear();
    params.default_direction = pixel::Direction8::Left;
    let out = pixel::texture(inputs, params).unwrap();
    assert!(out.stats.solve.is_none());
    assert!(out.field.iter().all(|v| *v == [-1.0, 0.0]));
    // One stroke pointing up: the whole field points up (Neumann boundary keeps it unit length).
    let (mut inputs, params) = case("fish");
    inputs.strokes = vec![vec![[60.0, 80.0], [60.0, 40.0]]];
    let out = pixel::texture(inputs, params).unwrap();
    for v in &out.field {
        assert!((v[0]).abs() < 1e-5 && (v[1] + 1.0).abs() < 1e-5, "{v:?}");
    }
}

#[test]
fn same_seed_same_bytes_and_golden_fish() {
    let run = |seed: u64| {
        let (inputs, mut params) = case("fish");
        params.seed = seed;
        pixel::texture(inputs, params).unwrap()
    };
    let a = run(7);
    let b = run(7);
    assert_eq!(a.image, b.image);
    assert_eq!(a.field, b.field);
    let (inputs, params) = case("trunk");
    let other = pixel::texture(
        inputs,
        PixelParams {
            seed: 8,
            ..params.clone()
        },
    )
    .unwrap();
    let (inputs, _) = case("trunk");
    assert_ne!(
        other.image,
        pixel::texture(inputs, params).unwrap().image,
        "a different seed should move the bark"
    );

    check_golden("fish", &a.image);
}

/// Compare with `tests/golden/pixel/<name>.png` (FILIGREE_BLESS=1 rewrites it).
fn check_golden(name: &str, img: &Rgba8Image) {
    let golden =
        Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("tests/golden/pixel/{name}.png"));
    if std::env::var("FILIGREE_BLESS").is_ok_and(|v| v == "1") {
        std::fs::create_dir_all(golden.parent().unwrap()).unwrap();
        std::fs::write(&golden, encode_png(img).unwrap()).unwrap();
    }
    let want = decode(
        &std::fs::read(&golden).expect("golden missing: run with FILIGREE_BLESS=1"),
        Limits::default(),
    )
    .unwrap();
    assert!(
        want == *img,
        "{name} differs from tests/golden/pixel/{name}.png (FILIGREE_BLESS=1 rewrites it if the change is intended)"
    );
}

#[test]
fn golden_trunk() {
    // The random-positions case (the fish is packed), so the sampler's
    // draw order is pinned too.
    let (inputs, params) = case("trunk");
    check_golden("trunk", &pixel::texture(inputs, params).unwrap().image);
}

#[test]
fn job_steps_through_the_stages_in_order() {
    let (inputs, params) = case("fish");
    let mut job = PixelJob::new(inputs, params).unwrap();
    let mut stages = vec![job.stage()];
    let mut last = 0.0;
    loop {
        match filigree::core::job::Job::step(&mut job).unwrap() {
            filigree::core::job::Step::Running(p) => {
                assert!(p.fraction >= last);
                last = p.fraction;
            }
            filigree::core::job::Step::Done(_) => {}
        }
        if stages.last() != Some(&job.stage()) {
            stages.push(job.stage());
        }
        if job.stage() == pixel::Stage::Done {
            break;
        }
    }
    use pixel::Stage::*;
    assert_eq!(
        stages,
        vec![Positions, ColourMap, Orientation, Placement, Done]
    );
}

#[test]
fn bad_inputs_get_clear_errors() {
    let err = |inputs: PixelInputs| {
        PixelJob::new(inputs, PixelParams::default())
            .err()
            .expect("should fail")
            .to_string()
    };
    let (base, _) = case("trunk");

    let mut i = base.clone();
    i.mask = image("fish_body_boundary.png");
    let e = err(i);
    assert!(
        e.contains("128×128") && e.contains("64×64") && e.contains("same size"),
        "{e}"
    );

    let mut i = base.clone();
    i.elements = Elements::Sheet(Rgba8Image::new(13, 12));
    let e = err(i);
    assert!(e.contains("13×12") && e.contains("3×3 grid"), "{e}");

    let mut i = base.clone();
    i.mask = Rgba8Image::new(64, 64);
    let e = err(i);
    assert!(e.contains("mask is empty"), "{e}");

    let mut i = base.clone();
    i.source = Rgba8Image::new(64, 64);
    let e = err(i);
    assert!(e.contains("fully transparent"), "{e}");

    let mut i = base.clone();
    i.strokes = vec![vec![[1.0, 1.0], [500.0, 2.0]]];
    let e = err(i);
    assert!(e.contains("stroke 1 point 2"), "{e}");

    let e = PixelJob::new(
        base.clone(),
        PixelParams {
            margins: [-3, 0],
            ..PixelParams::default()
        },
    )
    .err()
    .unwrap()
    .to_string();
    assert!(e.contains("mx = -3"), "{e}");
}

/// The "up" cell of the fish sheet as a lone sprite.
fn fish_up_sprite() -> Rgba8Image {
    let sheet = image("fish_scale.png");
    let side = sheet.width / 3;
    let mut sprite = Rgba8Image::new(side, side);
    for y in 0..side {
        for x in 0..side {
            sprite.put(x, y, sheet.get(side + x, y));
        }
    }
    sprite
}

/// Draw an element sheet back into a 3×3 sheet image.
fn sheet_image(sheet: &pixel::inputs::ElementSheet) -> Rgba8Image {
    let s = sheet.side;
    let mut img = Rgba8Image::new(3 * s, 3 * s);
    for d in pixel::Direction8::ALL {
        let (dx, dy) = d.step();
        let (cx, cy) = ((dx + 1) as u32 * s, (dy + 1) as u32 * s);
        let sp = sheet.sprite(d);
        for y in 0..s {
            for x in 0..s {
                if sp.on[(y * s + x) as usize] {
                    img.put(cx + x, cy + y, [255, 255, 255, 255]);
                }
            }
        }
    }
    img
}

#[test]
fn single_sprite_works_like_a_sheet() {
    // The fish sheet's right, down and left cells are exact quarter turns of
    // its up cell, so a lone "up" sprite turned by the program must give
    // those very cells; and wherever only axis directions are used (no
    // strokes, an axis default) the sprite's result must equal the sheet's
    // byte for byte.
    let sprite = fish_up_sprite();
    let from_sprite =
        pixel::inputs::ElementSheet::from_sprite(&sprite, pixel::Direction8::Up).unwrap();
    let from_sheet = pixel::inputs::ElementSheet::from_sheet(&image("fish_scale.png")).unwrap();
    use pixel::Direction8::*;
    for d in [Up, Right, Down, Left] {
        assert_eq!(from_sprite.sprite(d), from_sheet.sprite(d), "{d:?}");
    }
    for d in [Up, Right, Down, Left] {
        let run = |elements: Elements| {
            let (mut inputs, mut params) = case("fish");
            inputs.strokes.clear();
            inputs.elements = elements;
            params.default_direction = d;
            pixel::texture(inputs, params).unwrap()
        };
        let a = run(Elements::Sprite(sprite.clone()));
        let b = run(Elements::Sheet(image("fish_scale.png")));
        assert!(a.stats.placed > 20, "{d:?}: {}", a.stats.placed);
        assert_eq!(a.positions, b.positions, "{d:?}");
        assert!(a.image == b.image, "{d:?}: sprite and sheet results differ");
    }
}

#[test]
fn single_sprite_equals_the_sheet_of_its_eight_turns() {
    // With strokes (all eight directions in play) a lone sprite behaves
    // exactly like a sheet drawn from its eight turns.
    let sprite = fish_up_sprite();
    let turns = pixel::inputs::ElementSheet::from_sprite(&sprite, pixel::Direction8::Up).unwrap();
    let sheet = sheet_image(&turns);
    assert_eq!(
        pixel::inputs::ElementSheet::from_sheet(&sheet).unwrap(),
        turns
    );
    let run = |elements: Elements| {
        let (mut inputs, params) = case("fish");
        inputs.elements = elements;
        pixel::texture(inputs, params).unwrap()
    };
    let a = run(Elements::Sprite(sprite));
    let b = run(Elements::Sheet(sheet));
    assert!(a.stats.placed > 20);
    assert_eq!(a.positions, b.positions);
    assert!(
        a.image == b.image,
        "sprite and sheet-of-turns results differ"
    );
    // And a diagonal (a 45° turn, not a quarter turn) is really used.
    let dirs: HashSet<_> = a
        .positions
        .iter()
        .map(|&(x, y)| {
            pixel::placement::orientation_at(&a.field, 128, 128, x, y, 6, pixel::Direction8::Down)
        })
        .collect();
    assert!(
        dirs.iter().any(|d| {
            let (dx, dy) = d.step();
            dx != 0 && dy != 0
        }),
        "{dirs:?}"
    );
}
