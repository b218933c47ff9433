//! The Texture tool end to end outside the browser: `filigree build-index`
//! writes an index, `filigree texture --index --image` answers from it, the
//! `texture-*` requests load it and answer the same, and damaged indexes
//! are clear errors.
use filigree::texture::api;
use filigree::texture::build::{build_index, BuildConfig};
use filigree::texture::dataset::DatasetConfig;
use filigree::texture::index::IndexConfig;
use filigree::texture::models::{self, MODELS};
use filigree::texture::pcn::PcnConfig;
use std::process::Command;
use std::sync::OnceLock;

fn filigree(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_filigree"))
        .args(args)
        .output()
        .unwrap()
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("filigree-texture-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d.join(name)
}

/// A small index (2 bases per model at 32², small filters), built once.
fn small_index() -> &'static Vec<u8> {
    static BYTES: OnceLock<Vec<u8>> = OnceLock::new();
    BYTES.get_or_init(|| {
        let cfg = BuildConfig {
            dataset: DatasetConfig {
                per_model: 3,
                size: 32,
                ..DatasetConfig::default()
            },
            index: IndexConfig {
                pcn: PcnConfig {
                    k1: 5,
                    k2: 5,
                    l1: 4,
                    l2: 8,
                    side: 32,
                    ..PcnConfig::default()
                },
                isomap_k: 6,
                ..IndexConfig::default()
            },
        };
        build_index(&cfg, &[]).unwrap().0.to_bytes()
    })
}

/// The `texture-index` request's answer for `bytes` (the worker now holds it).
fn load_index(bytes: &[u8]) -> serde_json::Value {
    filigree::api::run_json(
        "texture-index",
        &serde_json::json!({ "bytes": bytes }).to_string(),
    )
    .unwrap()
}

fn png_of(model: &str, size: usize) -> Vec<u8> {
    let m = models::lookup(model).unwrap();
    let g = models::render(m, &m.defaults(), 5, size).unwrap();
    let img = image::GrayImage::from_raw(size as u32, size as u32, g.to_bytes()).unwrap();
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

#[test]
fn the_cli_answers_an_example_with_a_model_scales_and_a_rendered_texture() {
    let index = tmp("small.bin");
    std::fs::write(&index, small_index()).unwrap();
    let example = tmp("example.png");
    std::fs::write(&example, png_of("perlin", 48)).unwrap();
    let out = tmp("out.png");
    let o = filigree(&[
        "texture",
        "--index",
        index.to_str().unwrap(),
        "--image",
        example.to_str().unwrap(),
        "--set",
        "regularity=9",
        "--set",
        "local orientation=2",
        "--out",
        out.to_str().unwrap(),
        "--size",
        "40",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(
        MODELS.iter().any(|m| m.id == v["predicted"]["model"]),
        "{v}"
    );
    assert_eq!(v["requested"]["regularity"], 9.0);
    assert_eq!(v["requested"]["local_orientation"], 2.0);
    assert!(v["cosine"].as_f64().unwrap() > 0.0);
    let written = image::open(&out).unwrap();
    assert_eq!((written.width(), written.height()), (40, 40));
    // The retrieved parameters are the model's, by name.
    let m = models::lookup(v["retrieved"]["model"].as_str().unwrap()).unwrap();
    assert_eq!(
        v["retrieved"]["params"].as_object().unwrap().len(),
        m.params.len()
    );
}

#[test]
fn the_cli_names_bad_indexes_images_and_scales() {
    let bytes = small_index();
    let good = tmp("good.bin");
    std::fs::write(&good, bytes).unwrap();
    let example = tmp("ex2.png");
    std::fs::write(&example, png_of("cellular", 32)).unwrap();
    let mut damaged = bytes.clone();
    let mid = damaged.len() / 3;
    damaged[mid] ^= 0xff;
    let bad = tmp("bad.bin");
    std::fs::write(&bad, &damaged).unwrap();
    let run = |index: &std::path::Path, extra: &[&str]| {
        let mut args = vec![
            "texture",
            "--index",
            index.to_str().unwrap(),
            "--image",
            example.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        let o = filigree(&args);
        assert!(!o.status.success());
        String::from_utf8_lossy(&o.stderr).to_string()
    };
    assert!(run(&bad, &[]).contains("corrupt"));
    assert!(run(&good, &["--set", "loudness=3"]).contains("unknown scale"));
    assert!(run(&good, &["--set", "contrast=12"]).contains("1 to 9"));
    let o = filigree(&["texture"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--index"));
}

#[test]
fn requests_load_the_index_by_id_and_answer_like_the_library() {
    let bytes = small_index();
    let loaded = load_index(bytes);
    let id = loaded["id"].as_str().unwrap().to_string();
    assert_eq!(id, api::index_id(bytes));
    assert_eq!(loaded["models"].as_array().unwrap().len(), MODELS.len());
    let png = png_of("islamic", 40);
    let a = filigree::api::run_json(
        "texture-analyse",
        &serde_json::json!({ "index": id, "bytes": png }).to_string(),
    )
    .unwrap();
    let index = api::parse_index(bytes).unwrap();
    let want = api::analyse(&index, &api::decode_gray(&png).unwrap()).unwrap();
    assert_eq!(a["model"], want.model);
    assert_eq!(a["scales"], serde_json::json!(want.scales));
    // The three likeliest models with probabilities, the first the
    // prediction, and whether any is close (issue 36).
    let top = a["top"].as_array().unwrap();
    assert_eq!(top.len(), api::TOP_MODELS);
    assert_eq!(top[0]["model"], a["model"]);
    assert!(top
        .windows(2)
        .all(|w| w[0]["probability"].as_f64() >= w[1]["probability"].as_f64()));
    assert_eq!(a["close"], serde_json::json!(want.close));
    let r = filigree::api::run_json(
        "texture-retrieve",
        &serde_json::json!({ "index": id, "scales": [5, 5, 5, 5, 5, 5, 5, 5, 5, 9, 5, 5], "model": a["model"], "size": 24 }).to_string(),
    )
    .unwrap();
    assert_eq!(r["model"], a["model"], "stays within the predicted model");
    assert_eq!(r["image"]["gray"].as_array().unwrap().len(), 24 * 24);
    // Another id: the worker says which field is wrong.
    let e = filigree::api::run_json("texture-retrieve", r#"{"index": "feed"}"#).unwrap_err();
    assert_eq!(e.field(), Some("index"));
    let e = filigree::api::run_json("texture-index", r#"{"bytes": [1, 2, 3]}"#).unwrap_err();
    assert!(
        e.to_string().contains("not a Filigree texture index"),
        "{e}"
    );
}

/// Writes the `texture_index` fuzz corpus: the small index, and copies
/// truncated and with a byte flipped (run by hand:
/// `cargo test --test integration texture::write_fuzz_seeds -- --ignored`).
#[test]
#[ignore]
fn write_fuzz_seeds() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("fuzz/corpus/texture_index");
    std::fs::create_dir_all(&dir).unwrap();
    let b = small_index();
    std::fs::write(dir.join("small.bin"), b).unwrap();
    std::fs::write(dir.join("truncated.bin"), &b[..b.len() / 2]).unwrap();
    let mut f = b.clone();
    f[100] ^= 1;
    std::fs::write(dir.join("flipped.bin"), f).unwrap();
    std::fs::write(dir.join("magic-only.bin"), &b[..20]).unwrap();
    let mut v = b.clone();
    v[16] = filigree::texture::index::VERSION as u8 + 1;
    std::fs::write(dir.join("other-version.bin"), v).unwrap();
    std::fs::write(dir.join("empty.bin"), b"").unwrap();
}

/// A picture too small to read as a texture (a 10×10 icon) is refused with
/// a clear error that says its size and the minimum, not analysed from the
/// blur its enlargement would be; the smallest accepted size is half the
/// network's window (16 pixels for this index's 32).
#[test]
fn a_tiny_example_is_refused_with_its_size_and_the_minimum() {
    let loaded = load_index(small_index());
    let id = loaded["id"].as_str().unwrap().to_string();
    let analyse = |side: usize| {
        filigree::api::run_json(
            "texture-analyse",
            &serde_json::json!({ "index": id, "bytes": png_of("islamic", side) }).to_string(),
        )
    };
    let e = analyse(10).unwrap_err();
    assert_eq!(e.field(), Some("bytes"));
    let msg = e.to_string();
    assert!(
        msg.contains("10×10 pixels") && msg.contains("at least 16"),
        "{msg}"
    );
    assert!(analyse(15).is_err(), "one pixel under the minimum");
    assert!(analyse(16).is_ok(), "the minimum itself is analysed");
}
