//! The page's table of wasm modules (`www/app/protocol.js` MODULE_KINDS and
//! SHARED_KINDS) is the core's (`api::Module`): a kind the page sends to
//! the wrong module would fail as "served by the X module".
use filigree::api::{module_of, Module, IMAGE_KINDS, KINDS, SHARED_KINDS};
use std::collections::BTreeMap;

/// `name: ['a', 'b'],` lines of MODULE_KINDS (a name may be quoted,
/// `//` lines are comments), and the SHARED_KINDS list.
fn page_tables() -> (BTreeMap<String, Vec<String>>, Vec<String>, Vec<String>) {
    let js = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/www/app/protocol.js"))
        .expect("www/app/protocol.js");
    let strings = |s: &str| -> Vec<String> {
        s.split('\'')
            .skip(1)
            .step_by(2)
            .map(str::to_string)
            .collect()
    };
    let body = js
        .split("export const MODULE_KINDS = Object.freeze({")
        .nth(1)
        .and_then(|s| s.split("});").next())
        .expect("MODULE_KINDS in protocol.js");
    let mut modules = BTreeMap::new();
    for line in body
        .lines()
        .map(str::trim)
        .filter(|l| !l.is_empty() && !l.starts_with("//"))
    {
        let (name, list) = line.split_once(':').expect("name: [kinds]");
        modules.insert(name.trim().trim_matches('\'').to_string(), strings(list));
    }
    let shared = js
        .split("export const SHARED_KINDS = Object.freeze(")
        .nth(1)
        .and_then(|s| s.split(");").next())
        .expect("SHARED_KINDS in protocol.js");
    let images = js
        .split("export const IMAGE_MODULES = Object.freeze(")
        .nth(1)
        .and_then(|s| s.split(");").next())
        .expect("IMAGE_MODULES in protocol.js");
    (modules, strings(shared), strings(images))
}

#[test]
fn the_pages_module_table_is_the_cores() {
    let (page, shared, images) = page_tables();
    let core: BTreeMap<String, Vec<String>> = Module::ALL
        .iter()
        .map(|m| {
            (
                m.name().to_string(),
                m.kinds().iter().map(|k| k.to_string()).collect(),
            )
        })
        .collect();
    assert_eq!(page, core);
    assert_eq!(shared, SHARED_KINDS);
    let core_images: Vec<&str> = Module::ALL
        .iter()
        .filter(|m| m.images())
        .map(|m| m.name())
        .collect();
    assert_eq!(images, core_images);
    assert_eq!(Module::Inspect.kinds(), IMAGE_KINDS);
}

#[test]
fn every_kind_has_one_module_or_is_shared() {
    for kind in KINDS {
        let owners = Module::ALL
            .iter()
            .filter(|m| m.kinds().contains(kind))
            .count();
        let shared = SHARED_KINDS.contains(kind);
        assert!(
            (owners == 1 && !shared) || (owners == 0 && shared),
            "{kind}: {owners} modules, shared {shared}"
        );
        assert_eq!(module_of(kind).is_some(), !shared, "{kind}");
    }
}

/// The error of a refused request (its job is not `Debug`).
fn refused<T>(r: filigree::Result<T>) -> filigree::Error {
    match r {
        Err(e) => e,
        Ok(_) => panic!("the request was accepted"),
    }
}

#[test]
fn a_module_refuses_another_modules_kinds_and_documents() {
    use filigree::api::{start_pixel, start_texture};
    let de = |s: &'static str| serde_json::Deserializer::from_str(s);
    let e = refused(start_pixel("render-pattern", &mut de("{}")));
    assert!(e.to_string().contains("served by the fit module"), "{e}");
    // Tangle reads no images, and Fit, Micro and Texture read the PNGs
    // their pages make: their modules serve no Inspect kinds (and in wasm
    // link no JPEG, WebP, GIF or BMP decoder).
    let inspect_kind = |e: filigree::Error| {
        assert!(
            e.to_string().contains("served by the inspect module"),
            "{e}"
        )
    };
    inspect_kind(refused(filigree::api::start_tangle(
        "decode-image",
        &mut de("{}"),
    )));
    inspect_kind(refused(filigree::api::start_fit(
        "decode-image",
        &mut de("{}"),
    )));
    inspect_kind(refused(filigree::api::start_micro(
        "decode-image",
        &mut de("{}"),
    )));
    inspect_kind(refused(start_texture("decode-image", &mut de("{}"))));
    // The Pixel page draws its source and sheet with `decode-image` in its
    // own module (it loads no other), which reads them as its `pixel`
    // requests do: PNG only in wasm, every format natively.
    assert!(start_pixel("decode-image", &mut de(r#"{"bytes": []}"#)).is_ok());
    assert!(Module::Pixel.image_decoder().is_some() && Module::Inspect.image_decoder().is_some());
    // The Texture module checks Texture documents, not Fit ones.
    let e = refused(
        start_texture(
            "check-state",
            &mut de(r#"{"tool": "fit", "version": 1, "state": {}}"#),
        )
        .and_then(filigree::core::job::run_quietly),
    );
    assert!(
        e.to_string().contains("checked by the fit tool's module"),
        "{e}"
    );
    // A project of another tool opens unchecked, for its own module to check.
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/fixtures/fish.filigree.json"
    ))
    .unwrap();
    let payload = serde_json::json!({ "text": text }).to_string();
    let job = start_texture(
        "open-project",
        &mut serde_json::Deserializer::from_str(&payload),
    )
    .unwrap();
    let opened = serde_json::to_value(filigree::core::job::run_quietly(job).unwrap()).unwrap();
    assert_eq!(opened["tool"], "pixel");
    assert_eq!(opened["checked"], false);
    let job = start_pixel(
        "open-project",
        &mut serde_json::Deserializer::from_str(&payload),
    )
    .unwrap();
    let opened = serde_json::to_value(filigree::core::job::run_quietly(job).unwrap()).unwrap();
    assert_eq!(opened["checked"], true);
    // The page opens a project unchecked, to convert its state before the
    // check (Pixel's images into PNG: www/app/core-state.js checkState).
    let payload = serde_json::json!({ "text": text, "unchecked": true }).to_string();
    let job = start_pixel(
        "open-project",
        &mut serde_json::Deserializer::from_str(&payload),
    )
    .unwrap();
    let opened = serde_json::to_value(filigree::core::job::run_quietly(job).unwrap()).unwrap();
    assert_eq!(
        (&opened["tool"], &opened["checked"]),
        (&"pixel".into(), &false.into())
    );
}
