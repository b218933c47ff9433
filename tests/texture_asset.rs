//! The shipped Texture index, `assets/texture-index.bin`: the app fetches
//! it as a static file, so it is committed. Here: it loads, it was built
//! with the current settings for the app's models, and it recognises them.
//! That it is byte for byte what the code builds is checked by
//! `scripts/check-texture-index.sh` (in `scripts/check.sh`), in release:
//! the build takes minutes even there.
use filigree::texture::api;
use filigree::texture::build::BuildConfig;
use filigree::texture::models::{self, MODELS};

/// Percent of the default pictures [`every_models_default_picture_is_recognised_at_unseen_seeds`]
/// needs.
const THRESHOLD_DEFAULTS: usize = 90;

const ASSET: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/texture-index.bin");

fn shipped() -> Vec<u8> {
    std::fs::read(ASSET).expect("assets/texture-index.bin is committed")
}

#[test]
fn the_shipped_index_loads_names_the_apps_models_and_is_small() {
    let bytes = shipped();
    assert!(
        bytes.len() <= 4 << 20,
        "{} bytes: over the 4 MB budget",
        bytes.len()
    );
    let index = api::parse_index(&bytes).unwrap();
    let ids: Vec<&str> = MODELS.iter().map(|m| m.id).collect();
    assert_eq!(index.model_names, ids);
    assert_eq!(index.pcn.config, BuildConfig::default().index.pcn);
    // The index's own base textures (rendered as the dataset does: at twice
    // the size, a quadrant cropped) are what it was trained on: most of
    // them must come back as their model. Chance is 1 in 23.
    let size = BuildConfig::default().dataset.size;
    // Every sixth base (24 of 144): a quick check; `filigree bench texture`
    // measures the index on every held-out image.
    let bases: Vec<_> = index.samples.iter().step_by(4 * 6).collect();
    // The same textures whole, as a person drops a 2·size render: the
    // index reads them at the training crops' pixel scale (a centred
    // window), so they must come back as often. (Resampled whole to
    // `size`, as the index once read every image, 49 of 138 did.)
    let (mut right, mut whole) = (0, 0);
    for s in &bases {
        let m = &MODELS[s.model as usize];
        let params: Vec<f64> = s.params.iter().map(|&v| v as f64).collect();
        let big = models::render(m, &params, s.seed, 2 * size).unwrap();
        let data = (0..size * size)
            .map(|i| big.data[(i / size) * 2 * size + i % size])
            .collect();
        let quadrant = filigree::texture::Gray {
            width: size,
            height: size,
            data,
        };
        right += (index.analyse(&quadrant).unwrap().model == s.model) as usize;
        whole += (index.analyse(&big).unwrap().model == s.model) as usize;
    }
    let n = bases.len();
    eprintln!("training bases recognised: {right}/{n} from a quadrant, {whole}/{n} whole");
    assert!(right * 10 >= n * 8, "{right}/{n} quadrants recognised");
    assert!(whole * 10 >= n * 8, "{whole}/{n} whole textures recognised");
}

/// The app's first picture of every model (its defaults, rendered at the
/// size a person drops) comes back as that model at seeds the index never
/// saw (its base at the defaults has its own seed), and the Texture
/// panel's first example, texton-regular seed 1, always does.
#[test]
fn every_models_default_picture_is_recognised_at_unseen_seeds() {
    let index = api::parse_index(&shipped()).unwrap();
    let side = 2 * BuildConfig::default().dataset.size;
    let (mut right, mut n) = (0, 0);
    for (mi, m) in MODELS.iter().enumerate() {
        // Seed 1 (the panel's), and another unseen seed for every other
        // model: a quick check (the bench draws many more).
        let seeds: &[u64] = if mi % 2 == 0 { &[1, 11] } else { &[1, 12] };
        for &seed in seeds {
            let img = models::render(m, &m.defaults(), seed, side).unwrap();
            let got = index.analyse(&img).unwrap().model as usize;
            if got != mi {
                eprintln!("{} seed {seed}: taken for {}", m.id, MODELS[got].id);
            }
            assert!(
                got == mi || (m.id, seed) != ("texton-regular", 1),
                "the panel's first example is taken for {}",
                MODELS[got].id
            );
            right += (got == mi) as usize;
            n += 1;
        }
    }
    eprintln!("default pictures recognised: {right} of {n}");
    assert!(right * 100 >= n * THRESHOLD_DEFAULTS, "{right} of {n}");
}

/// Every slider, moved to 9 (or 1), retrieves a texture whose scale rose
/// (fell) for most examples and almost never one whose scale went the
/// other way. Examples: every model's defaults at seeds 11 and 12 (not
/// the index's), analysed as a drop; the request is the predicted scales
/// with one slider moved. (Before the shortlist, with the paper's nearest
/// neighbour only, 49% rose and 11% fell on the index of 2026-12-03b;
/// the regularity slider, which the browser test moves, rose for 27 of 46
/// and fell for 3.)
#[test]
fn each_slider_moves_the_retrieved_scale_its_way() {
    let index = api::parse_index(&shipped()).unwrap();
    let side = 2 * BuildConfig::default().dataset.size;
    let (mut right, mut wrong, mut n) = (0, 0, 0);
    let (mut regularity_up, mut regularity_n) = (0, 0);
    for (mi, m) in MODELS.iter().enumerate() {
        // One unseen seed per model, alternating (a quick check; the bench
        // moves every slider for every held-out base).
        for seed in [11 + (mi as u64 % 2)] {
            let img = models::render(m, &m.defaults(), seed, side).unwrap();
            let own = index.analyse(&img).unwrap().scales.map(|s| s as f32);
            let before = index.samples[index.retrieve(&own, None).unwrap().sample].scales;
            for k in 0..12 {
                for to in [1.0, 9.0] {
                    let mut req = own;
                    req[k] = to;
                    let after = index.samples[index.retrieve(&req, None).unwrap().sample].scales;
                    let moved = after[k] as i32 - before[k] as i32;
                    let way = if to > 5.0 { moved } else { -moved };
                    right += (way > 0) as usize;
                    wrong += (way < 0) as usize;
                    n += 1;
                    if k == 9 && to > 5.0 {
                        regularity_up += (way > 0) as usize;
                        regularity_n += 1;
                    }
                }
            }
        }
    }
    eprintln!(
        "sliders: the retrieved scale moved their way {right}, the other way {wrong}, of {n}; \
         regularity to 9 rose for {regularity_up} of {regularity_n}"
    );
    assert!(right * 100 >= n * 55, "{right} of {n} moved their way");
    assert!(wrong * 100 <= n * 5, "{wrong} of {n} moved the other way");
    // Regularity, the slider the browser test moves: 55% before issue 36
    // widened the models (mosaic cells, star textons, ...; the space is
    // built from the new dataset's scales); 10 of 23 since. A regression
    // left for later (noted with issue 36), held from going further.
    assert!(
        regularity_up * 100 >= regularity_n * 40,
        "regularity rose for {regularity_up} of {regularity_n}"
    );
}

/// A grey level for each point of the unit square.
type Picture = fn(f32, f32) -> f32;

/// Issue 36: the index says how sure it is. Every model's default picture
/// (unseen seed) gets three models with probabilities, most likely first,
/// and is close to the index; pictures that are no procedural texture (a
/// flat grey, a ramp, a few large shapes) are "no close model". (A page of
/// text is not caught: it reads as an arrangement of textons;
/// `Confidence`.)
#[test]
fn the_index_lists_likely_models_and_knows_when_nothing_is_close() {
    let index = api::parse_index(&shipped()).unwrap();
    let side = 2 * BuildConfig::default().dataset.size;
    let mut close = 0;
    for m in MODELS.iter() {
        let img = models::render(m, &m.defaults(), 11, side).unwrap();
        let a = api::analyse(&index, &img).unwrap();
        assert_eq!(a.top.len(), api::TOP_MODELS);
        assert_eq!(a.top[0].model, a.model, "the prediction is the likeliest");
        let p: Vec<f64> = a.top.iter().map(|c| c.probability).collect();
        assert!(
            p.windows(2).all(|w| w[0] >= w[1]) && p.iter().sum::<f64>() <= 1.0 + 1e-9,
            "{p:?}"
        );
        if !a.close {
            eprintln!("{}: no close model", m.id);
        }
        close += a.close as usize;
    }
    assert!(
        close * 10 >= MODELS.len() * 9,
        "{close} of {} close",
        MODELS.len()
    );
    let pictures: [(&str, Picture); 3] = [
        ("flat", |_, _| 0.5),
        ("ramp", |x, _| x),
        ("shapes", |x, y| {
            let disc = (x - 0.35).powi(2) + (y - 0.4).powi(2) < 0.06;
            let bar = (0.55..0.9).contains(&x) && (0.6..0.8).contains(&y);
            if disc {
                0.1
            } else if bar {
                0.6
            } else {
                0.9
            }
        }),
    ];
    for (name, f) in pictures {
        let mut g = filigree::texture::Gray::new(side, side);
        for y in 0..side {
            for x in 0..side {
                g.data[y * side + x] = f(x as f32 / side as f32, y as f32 / side as f32);
            }
        }
        let a = api::analyse(&index, &g).unwrap();
        assert!(!a.close, "{name} is taken as close to {}", a.model);
        assert_eq!(
            a.top.len(),
            api::TOP_MODELS,
            "{name}: the nearest are still listed"
        );
    }
}
