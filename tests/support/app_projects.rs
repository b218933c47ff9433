//! Project files as today's app writes them (`www/app/project.js`
//! `projectText`: `{format, version: 2, tool, stateVersion, state}` with
//! byte fields as `{"$bytes": base64}`), built from the shipped examples the
//! way the panels build their documents (`exampleDoc` in
//! `www/pixel/panel.js`, `generatorDoc` in `www/fit/panel.js`). Shared by
//! `tests/project.rs` and the fuzz seeds (`tests/fuzz_corpus.rs`).
#![allow(dead_code)]

use filigree::api::project::base64_encode;
use serde_json::{json, Value as Json};
use std::path::Path;

pub fn asset(name: &str) -> Vec<u8> {
    std::fs::read(
        Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("assets/pixel")
            .join(name),
    )
    .unwrap()
}

pub fn bytes(b: &[u8]) -> Json {
    json!({ "$bytes": base64_encode(b) })
}

/// The text `projectText(tool, stateVersion, state)` writes.
pub fn project_text(tool: &str, state_version: u32, state: Json) -> String {
    json!({"format": "filigree-project", "version": 2, "tool": tool,
           "stateVersion": state_version, "state": state})
    .to_string()
}

/// A Pixel example's document (`fish` or `trunk`), bytes as `{"$bytes"}`.
pub fn pixel_example(name: &str) -> Json {
    let cases: Json = serde_json::from_slice(&asset("cases.json")).unwrap();
    let case = &cases[name];
    let file = |k: &str| case[k].as_str().unwrap().to_string();
    let mask = filigree::pixel::api::mask_bits(&filigree::pixel::api::PixelMaskRequest {
        bytes: asset(&file("mask")),
    })
    .unwrap();
    let strokes: Json = serde_json::from_slice(&asset(&file("strokes"))).unwrap();
    let mut params = serde_json::to_value(filigree::pixel::PixelParams::default()).unwrap();
    for (k, v) in case["params"].as_object().unwrap() {
        params[k] = v.clone();
    }
    json!({
        "example": name,
        "source": bytes(&asset(&file("source"))),
        "sheet": bytes(&asset(&file("sheet"))),
        "sprite": null,
        "mask": {"width": mask.width, "height": mask.height, "bits": bytes(&mask.bits)},
        "strokes": strokes["strokes"],
        "params": params,
        "names": {"source": file("source"), "sheet": file("sheet")},
    })
}

/// A Fit document for generator `g` at its defaults; with `fitted`, a
/// target made from values (truth) and a result, as after a fit.
pub fn fit_doc(g: &str, fitted: bool) -> Json {
    let gen = filigree::pattern::generators::generator(g).unwrap();
    let info = filigree::pattern::api::program_info(&filigree::pattern::api::PatternInfoRequest {
        program: gen.source.into(),
        params: Default::default(),
    })
    .unwrap();
    let values: Vec<f64> = info.params.iter().map(|p| p.default).collect();
    let names: Vec<&str> = info.params.iter().map(|p| p.name.as_str()).collect();
    let mut doc = json!({
        "generator": g, "program": gen.source, "values": values,
        "target": null, "truth": null, "result": null,
        "settings": {"budget": "quick", "loss": "sdf", "seed": 1},
    });
    if fitted {
        let side = 256usize;
        let rgba: Vec<u8> = (0..side * side * 4)
            .map(|i| if i % 4 == 3 { 255 } else { (i / 7) as u8 })
            .collect();
        doc["target"] = json!({"width": side, "height": side, "rgba": bytes(&rgba)});
        doc["truth"] = json!(values);
        doc["result"] =
            json!({"params": values, "loss": 0.0123, "names": names, "evaluations": 512});
    }
    doc
}

/// An Inspect document.
pub fn inspect_doc() -> Json {
    json!({"name": "fish.png", "bytes": bytes(&asset("fish.png"))})
}

/// A Texture document as the page saves it: a dropped example kept as a
/// small grey PNG (`image: true`) or a rendered model, its analysis, the
/// requested scales and an edited retrieval.
pub fn texture_doc(image: bool) -> Json {
    use filigree::texture::models::find;
    let source = if image {
        json!({"kind": "image", "name": "fish.png", "png": bytes(&asset("fish.png"))})
    } else {
        json!({"kind": "model", "model": "texton-regular", "params": find("texton-regular").unwrap().defaults(), "seed": 3})
    };
    json!({
        "source": source,
        "predicted": {"model": "texton-regular", "scales": [3, 8, 4, 2, 5, 5, 6, 4, 5, 8, 6, 7]},
        "scales": [3, 8, 4, 2, 5, 5, 6, 4, 5, 9, 6, 7.5],
        "sameModel": false,
        "retrieved": {"model": "perlin", "params": find("perlin").unwrap().defaults(), "seed": 4_503_599_627_370_497u64,
                      "sample": 17, "scales": [3, 8, 4, 2, 5, 5, 6, 4, 5, 9, 6, 7], "cosine": 0.99, "edited": true},
    })
}
