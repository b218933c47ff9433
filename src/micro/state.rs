//! The Micro tool's document (what the page keeps, autosaves, saves in a
//! project file and shares), its schema version and its checks, field by
//! field (see [`crate::core::value`]). Field names are the page's:
//!
//! ```text
//! { example: name | null, scene: text,
//!   camera: {yaw, pitch, distance, target: [x, y, z]},
//!   steps: "fixed" | "bisection" | "adaptive",
//!   view: "render" | "slice", z,
//!   shading: "lambert" | "ggx", roughness, specular, absorption,
//!   spp, max_depth }
//! ```
//!
//! Version 2 added the shading fields and `spp` (0: direct shading; N:
//! path tracing, N samples in progressive passes) and `max_depth`; the page
//! migrates version 1 documents by adding the request's defaults, and a
//! document without them is read with those defaults here too.
//!
//! `camera`, `steps` and the shading fields are the `micro-render` request's fields
//! ([`super::api::MicroRenderRequest`]) and `z` the `micro-slice` one's:
//! the ranges here are the requests' own. The scene text is kept as typed,
//! even when it does not parse (the page marks the error in the editor).
use super::api::{MicroRenderRequest, MAX_MICRO_SPP};
use super::examples::EXAMPLES;
use super::render::{Shading, StepMode};
use crate::core::error::Result;
use crate::core::limits::MAX_MICRO_SCENE_BYTES;
use crate::core::value::{invalid, nullish, Value};
use serde::Serialize;

/// Schema version of the Micro state (the page's `state.version`).
pub const STATE_VERSION: u32 = 2;
/// Ranges of the camera (`micro-render` checks the same).
pub const YAW: (f64, f64) = (-1e5, 1e5);
pub const PITCH: (f64, f64) = (-89.9, 89.9);
pub const DISTANCE: (f64, f64) = (1e-9, 1e6);
pub const TARGET: (f64, f64) = (-1e6, 1e6);
/// Range of the slice plane (`micro-slice` checks the same).
pub const Z: (f64, f64) = (-1e6, 1e6);
/// Ranges of the shading fields (`micro-render` checks the same).
pub const ROUGHNESS: (f64, f64) = (0.02, 1.0);
pub const SPECULAR: (f64, f64) = (0.0, 1.0);
pub const ABSORPTION: (f64, f64) = (0.0, 1e6);
pub const MAX_DEPTH: (u32, u32) = (1, 64);

/// The view's camera, as the page orbits and zooms it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct CameraState {
    pub yaw: f64,
    pub pitch: f64,
    pub distance: f64,
    pub target: [f64; 3],
}

/// What the canvas shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum View {
    Render,
    Slice,
}

/// A checked Micro document.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MicroState {
    pub example: Option<String>,
    pub scene: String,
    pub camera: CameraState,
    pub steps: StepMode,
    pub view: View,
    pub z: f64,
    pub shading: Shading,
    pub roughness: f64,
    pub specular: f64,
    pub absorption: f64,
    /// Path tracing: samples per pixel (0: direct shading).
    pub spp: u32,
    pub max_depth: u32,
}

/// A number field that may be left out (then `default`).
fn number_or(raw: &Value, field: &str, range: (f64, f64), default: f64) -> Result<f64> {
    if nullish(raw.get(field)) {
        Ok(default)
    } else {
        number_in(raw.get(field), field, range)
    }
}

/// A whole-number field that may be left out (then `default`).
fn count_or(raw: &Value, field: &str, (lo, hi): (u32, u32), default: u32) -> Result<u32> {
    if nullish(raw.get(field)) {
        return Ok(default);
    }
    raw.get(field)
        .and_then(Value::finite)
        .filter(|x| x.fract() == 0.0 && *x >= lo as f64 && *x <= hi as f64)
        .map(|x| x as u32)
        .ok_or_else(|| invalid(field, format!("must be a whole number from {lo} to {hi}")))
}

fn number_in(v: Option<&Value>, field: &str, (lo, hi): (f64, f64)) -> Result<f64> {
    v.and_then(Value::finite)
        .filter(|x| (lo..=hi).contains(x))
        .ok_or_else(|| invalid(field, format!("must be a number from {lo} to {hi}")))
}

fn camera(raw: Option<&Value>) -> Result<CameraState> {
    let c = raw.filter(|c| c.is_plain_object()).ok_or_else(|| {
        invalid(
            "camera",
            "must be a camera {yaw, pitch, distance, target: [x, y, z]}",
        )
    })?;
    let distance = c
        .get("distance")
        .and_then(Value::finite)
        .filter(|d| *d >= DISTANCE.0 && *d <= DISTANCE.1)
        .ok_or_else(|| {
            invalid(
                "camera.distance",
                format!("must be a number above 0 and at most {}", DISTANCE.1),
            )
        })?;
    let target = c
        .get("target")
        .and_then(Value::as_list)
        .filter(|t| t.len() == 3)
        .and_then(|t| Some([t[0].finite()?, t[1].finite()?, t[2].finite()?]))
        .filter(|t| t.iter().all(|v| (TARGET.0..=TARGET.1).contains(v)))
        .ok_or_else(|| {
            invalid(
                "camera.target",
                format!("must be a point [x, y, z] of numbers within ±{}", TARGET.1),
            )
        })?;
    Ok(CameraState {
        yaw: number_in(c.get("yaw"), "camera.yaw", YAW)?,
        pitch: number_in(c.get("pitch"), "camera.pitch", PITCH)?,
        distance,
        target,
    })
}

/// Check a Micro document field by field; the error names the field at fault.
pub fn check(raw: &Value) -> Result<MicroState> {
    if !raw.is_plain_object() {
        return Err(invalid("state", "is not a Micro document"));
    }
    let names = || {
        EXAMPLES
            .iter()
            .map(|e| e.name)
            .collect::<Vec<_>>()
            .join(", ")
    };
    let example = match raw.get("example") {
        None | Some(Value::Null) => None,
        Some(Value::Text(e)) if EXAMPLES.iter().any(|x| x.name == e) => Some(e.clone()),
        Some(_) => {
            return Err(invalid(
                "example",
                format!("must be null or one of {}", names()),
            ))
        }
    };
    let scene = raw
        .get("scene")
        .and_then(Value::as_text)
        .filter(|s| s.len() <= MAX_MICRO_SCENE_BYTES)
        .ok_or_else(|| {
            invalid(
                "scene",
                format!("must be the text of a scene (at most {MAX_MICRO_SCENE_BYTES} bytes)"),
            )
        })?
        .to_string();
    let camera = camera(raw.get("camera"))?;
    let steps = match raw.get("steps").and_then(Value::as_text) {
        Some("fixed") => StepMode::Fixed,
        Some("bisection") => StepMode::Bisection,
        Some("adaptive") => StepMode::Adaptive,
        _ => {
            return Err(invalid(
                "steps",
                "must be one of fixed, bisection, adaptive",
            ))
        }
    };
    let view = match raw.get("view") {
        None | Some(Value::Null) => View::Render,
        Some(Value::Text(v)) if v == "render" => View::Render,
        Some(Value::Text(v)) if v == "slice" => View::Slice,
        Some(_) => return Err(invalid("view", "must be render or slice")),
    };
    let z = if nullish(raw.get("z")) {
        0.0
    } else {
        number_in(raw.get("z"), "z", Z)?
    };
    let d = MicroRenderRequest::default();
    let shading = match raw.get("shading") {
        None | Some(Value::Null) => d.shading,
        Some(Value::Text(v)) if v == "lambert" => Shading::Lambert,
        Some(Value::Text(v)) if v == "ggx" => Shading::Ggx,
        Some(_) => return Err(invalid("shading", "must be lambert or ggx")),
    };
    Ok(MicroState {
        example,
        scene,
        camera,
        steps,
        view,
        z,
        shading,
        roughness: number_or(raw, "roughness", ROUGHNESS, d.roughness)?,
        specular: number_or(raw, "specular", SPECULAR, d.specular)?,
        absorption: number_or(raw, "absorption", ABSORPTION, d.absorption)?,
        spp: count_or(raw, "spp", (0, MAX_MICRO_SPP), d.spp)?,
        max_depth: count_or(raw, "max_depth", MAX_DEPTH, d.max_depth)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::micro::api::{start_render, start_slice, MicroRenderRequest, MicroSliceRequest};
    use serde_json::{json, Value as Json};

    fn value(j: &Json) -> Value {
        Value::read(j, false).unwrap()
    }

    fn doc() -> Json {
        json!({
            "example": "gyroid", "scene": EXAMPLES[0].scene,
            "camera": {"yaw": 35, "pitch": 28, "distance": 3.6, "target": [0, 0, 0]},
            "steps": "adaptive", "view": "slice", "z": 0.25,
            "shading": "ggx", "roughness": 0.5, "specular": 0.1, "absorption": 0.7,
            "spp": 16, "max_depth": 3,
        })
    }

    /// The error's field for `doc()` with `key` set to `v`.
    fn field_of(key: &str, v: Json) -> String {
        let mut d = doc();
        d[key] = v;
        let e = check(&value(&d)).unwrap_err();
        assert!(
            e.to_string().starts_with(e.field().unwrap_or("?")),
            "{e} names its field first"
        );
        e.field().unwrap().to_string()
    }

    #[test]
    fn a_page_document_is_accepted_and_kept() {
        let s = check(&value(&doc())).unwrap();
        assert_eq!(s.example.as_deref(), Some("gyroid"));
        assert_eq!(s.steps, StepMode::Adaptive);
        assert_eq!(s.view, View::Slice);
        assert_eq!(s.camera.distance, 3.6);
        assert_eq!(s.z, 0.25);
        // Checking the normalised state again changes nothing.
        let again = check(&value(&serde_json::to_value(&s).unwrap())).unwrap();
        assert_eq!(again, s);
        // A scene being typed (not valid JSON) is kept as it is.
        let mut d = doc();
        d["scene"] = json!("{\"type\": ");
        assert_eq!(check(&value(&d)).unwrap().scene, "{\"type\": ");
        // view and z may be left out.
        let mut d = doc();
        d.as_object_mut().unwrap().remove("view");
        d.as_object_mut().unwrap().remove("z");
        let s = check(&value(&d)).unwrap();
        assert_eq!((s.view, s.z), (View::Render, 0.0));
        // Version 1 documents (no shading fields) read with the request's defaults.
        let mut d = doc();
        for k in [
            "shading",
            "roughness",
            "specular",
            "absorption",
            "spp",
            "max_depth",
        ] {
            d.as_object_mut().unwrap().remove(k);
        }
        let s = check(&value(&d)).unwrap();
        let r = MicroRenderRequest::default();
        assert_eq!(
            (
                s.shading,
                s.roughness,
                s.specular,
                s.absorption,
                s.spp,
                s.max_depth
            ),
            (
                r.shading,
                r.roughness,
                r.specular,
                r.absorption,
                r.spp,
                r.max_depth
            )
        );
        let s = check(&value(&doc())).unwrap();
        assert_eq!((s.shading, s.spp, s.max_depth), (Shading::Ggx, 16, 3));
    }

    #[test]
    fn every_rule_names_its_field() {
        assert_eq!(field_of("example", json!("nope")), "example");
        assert_eq!(field_of("scene", json!(3)), "scene");
        assert_eq!(
            field_of("scene", json!(" ".repeat(MAX_MICRO_SCENE_BYTES + 1))),
            "scene"
        );
        assert_eq!(field_of("camera", json!([1])), "camera");
        let cam = |k: &str, v: Json| {
            let mut c = doc()["camera"].clone();
            c[k] = v;
            field_of("camera", c)
        };
        assert_eq!(cam("yaw", json!("x")), "camera.yaw");
        assert_eq!(cam("pitch", json!(90)), "camera.pitch");
        assert_eq!(cam("distance", json!(0)), "camera.distance");
        assert_eq!(cam("distance", json!(2e6)), "camera.distance");
        assert_eq!(cam("target", json!([0, 0])), "camera.target");
        assert_eq!(cam("target", json!([0, 0, "1"])), "camera.target");
        assert_eq!(field_of("steps", json!("random")), "steps");
        assert_eq!(field_of("steps", json!(null)), "steps");
        assert_eq!(field_of("view", json!("both")), "view");
        assert_eq!(field_of("z", json!(2e6)), "z");
        assert_eq!(field_of("shading", json!("phong")), "shading");
        assert_eq!(field_of("roughness", json!(0.0)), "roughness");
        assert_eq!(field_of("specular", json!(1.5)), "specular");
        assert_eq!(field_of("absorption", json!(-1)), "absorption");
        assert_eq!(field_of("spp", json!(1.5)), "spp");
        assert_eq!(field_of("spp", json!(MAX_MICRO_SPP + 1)), "spp");
        assert_eq!(field_of("max_depth", json!(0)), "max_depth");
    }

    #[test]
    fn the_limits_are_the_requests() {
        // A document at every range's edge makes requests the core accepts.
        for (yaw, pitch, distance, t) in [
            (YAW.0, PITCH.0, DISTANCE.0, TARGET.0),
            (YAW.1, PITCH.1, DISTANCE.1, TARGET.1),
        ] {
            let mut d = doc();
            d["camera"] =
                json!({"yaw": yaw, "pitch": pitch, "distance": distance, "target": [t, t, t]});
            d["z"] = json!(t);
            let lo = yaw == YAW.0;
            d["roughness"] = json!(if lo { ROUGHNESS.0 } else { ROUGHNESS.1 });
            d["specular"] = json!(if lo { SPECULAR.0 } else { SPECULAR.1 });
            d["absorption"] = json!(if lo { ABSORPTION.0 } else { ABSORPTION.1 });
            d["spp"] = json!(if lo { 0 } else { MAX_MICRO_SPP });
            d["max_depth"] = json!(if lo { MAX_DEPTH.0 } else { MAX_DEPTH.1 });
            let s = check(&value(&d)).unwrap();
            let req: MicroRenderRequest = serde_json::from_value(json!({
                "scene": s.scene, "width": 2, "height": 2, "steps": s.steps,
                "shading": s.shading, "roughness": s.roughness, "specular": s.specular,
                "absorption": s.absorption, "spp": s.spp, "max_depth": s.max_depth,
                "camera": {"yaw": s.camera.yaw, "pitch": s.camera.pitch,
                           "distance": s.camera.distance, "target": s.camera.target},
            }))
            .unwrap();
            assert!(
                start_render(req).is_ok(),
                "camera at {yaw}, {pitch}, {distance}, {t}"
            );
            let req = MicroSliceRequest {
                scene: s.scene.clone(),
                z: s.z,
                width: 2,
                height: 2,
                ..Default::default()
            };
            assert!(start_slice(req).is_ok());
        }
    }
}
