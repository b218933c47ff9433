//! The shipped Texture index, `assets/texture-index.bin`: the app fetches
//! it as a static file, so it is committed. Here: it loads, it was built
//! with the current settings for the app's models, and it recognises them.
//! That it is byte for byte what the code builds is checked by
//! `scripts/check-texture-index.sh` (in `scripts/check.sh`), in release:
//! the build takes minutes even there.
use filigree::texture::api;
use filigree::texture::build::BuildConfig;
use filigree::texture::models::{self, MODELS};

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
    let bases: Vec<_> = index.samples.iter().step_by(4).collect();
    let right = bases
        .iter()
        .filter(|s| {
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
            index.analyse(&quadrant).unwrap().model == s.model
        })
        .count();
    eprintln!("{right}/{} training bases recognised", bases.len());
    assert!(
        right * 10 >= bases.len() * 8,
        "{right}/{} training bases recognised",
        bases.len()
    );
}
