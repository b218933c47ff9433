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
    // Every model's default render at the dataset's size is a texture the
    // index was trained on the neighbourhood of: most are recognised.
    let size = BuildConfig::default().dataset.size;
    let right = MODELS
        .iter()
        .enumerate()
        .filter(|(i, m)| {
            let img = models::render(m, &m.defaults(), 1, size).unwrap();
            index.analyse(&img).unwrap().model as usize == *i
        })
        .count();
    assert!(
        right * 3 >= MODELS.len() * 2,
        "{right}/{} recognised",
        MODELS.len()
    );
}
