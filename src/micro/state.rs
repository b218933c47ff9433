//! The Micro tool's document (what the page keeps, autosaves, saves in a
//! project file and shares), its schema version and its checks: a serde
//! type read by [`crate::core::check::read_document`] (type errors name the
//! field) and a [`Check`] impl for its ranges. Field names are the page's:
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
//! document without them (or with `null`) is read with those defaults here
//! too (as are a missing `view` and `z`).
//!
//! `camera`, `steps` and the shading fields are the `micro-render` request's fields
//! ([`super::api::MicroRenderRequest`]) and `z` the `micro-slice` one's:
//! their types ([`StepMode`], [`Shading`]), defaults (the requests'
//! `Default`) and ranges ([`YAW`], [`ROUGHNESS`], ...) are the requests'
//! own. The scene text is kept as typed, even when it does not parse (the
//! page marks the error in the editor). Unknown fields are dropped, as they
//! always were (a camera's `fov` too: the page's camera has none).
use super::api::{
    MicroRenderRequest, MicroSliceRequest, ABSORPTION, DISTANCE, MAX_DEPTH, PITCH, ROUGHNESS,
    SPECULAR, SPP, TARGET, YAW, Z,
};
use super::examples::EXAMPLES;
use super::render::{Shading, StepMode};
use crate::core::check::{read_document, Check, Path};
use crate::core::error::Result;
use crate::core::limits::MAX_MICRO_SCENE_BYTES;
use crate::core::value::Value;
use serde::{Deserialize, Serialize};

/// Schema version of the Micro state (the page's `state.version`).
pub const STATE_VERSION: u32 = 2;

/// The view's camera, as the page orbits and zooms it (the request's
/// [`super::render::Camera`] without the field of view).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CameraState {
    pub yaw: f64,
    pub pitch: f64,
    pub distance: f64,
    pub target: [f64; 3],
}

/// What the canvas shows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum View {
    #[default]
    Render,
    Slice,
}

/// A Micro document.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "MicroFields")]
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

/// A Micro document as it is read: the fields older documents lack may be
/// missing or `null` (then the requests' defaults, in [`MicroState`]'s
/// `From`).
#[derive(Deserialize)]
struct MicroFields {
    #[serde(default)]
    example: Option<String>,
    scene: String,
    camera: CameraState,
    steps: StepMode,
    view: Option<View>,
    z: Option<f64>,
    shading: Option<Shading>,
    roughness: Option<f64>,
    specular: Option<f64>,
    absorption: Option<f64>,
    spp: Option<u64>,
    max_depth: Option<u64>,
}

impl From<MicroFields> for MicroState {
    fn from(f: MicroFields) -> MicroState {
        let r = MicroRenderRequest::default();
        // Beyond u32: out of range, refused by the check.
        let count =
            |v: Option<u64>, default: u32| v.map_or(default, |v| v.try_into().unwrap_or(u32::MAX));
        MicroState {
            example: f.example,
            scene: f.scene,
            camera: f.camera,
            steps: f.steps,
            view: f.view.unwrap_or_default(),
            z: f.z.unwrap_or(MicroSliceRequest::default().z),
            shading: f.shading.unwrap_or(r.shading),
            roughness: f.roughness.unwrap_or(r.roughness),
            specular: f.specular.unwrap_or(r.specular),
            absorption: f.absorption.unwrap_or(r.absorption),
            spp: count(f.spp, r.spp),
            max_depth: count(f.max_depth, r.max_depth),
        }
    }
}

impl Check for MicroState {
    fn check(&self, at: &Path) -> Result<()> {
        if let Some(e) = &self.example {
            if !EXAMPLES.iter().any(|x| x.name == e) {
                let names: Vec<_> = EXAMPLES.iter().map(|e| e.name).collect();
                return Err(at
                    .key("example")
                    .invalid(format!("must be null or one of {}", names.join(", "))));
            }
        }
        if self.scene.len() > MAX_MICRO_SCENE_BYTES {
            return Err(at.key("scene").invalid(format!(
                "must be the text of a scene (at most {MAX_MICRO_SCENE_BYTES} bytes)"
            )));
        }
        self.camera.check(&at.key("camera"))?;
        at.key("z").number_in(self.z, Z)?;
        at.key("roughness").number_in(self.roughness, ROUGHNESS)?;
        at.key("specular").number_in(self.specular, SPECULAR)?;
        at.key("absorption")
            .number_in(self.absorption, ABSORPTION)?;
        at.key("spp").whole_in(self.spp, SPP)?;
        at.key("max_depth").whole_in(self.max_depth, MAX_DEPTH)
    }
}

impl Check for CameraState {
    fn check(&self, at: &Path) -> Result<()> {
        at.key("yaw").number_in(self.yaw, YAW)?;
        at.key("pitch").number_in(self.pitch, PITCH)?;
        let d = self.distance;
        if !(d.is_finite() && (DISTANCE.0..=DISTANCE.1).contains(&d)) {
            return Err(at.key("distance").invalid(format!(
                "must be a number above 0 and at most {}",
                DISTANCE.1
            )));
        }
        let target = at.key("target");
        self.target
            .iter()
            .enumerate()
            .try_for_each(|(i, v)| target.index(i).number_in(*v, TARGET))
    }
}

/// Read and check a Micro document; the error names the field at fault.
pub fn check(raw: &Value) -> Result<MicroState> {
    read_document(raw, "Micro")
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::micro::api::{start_render, start_slice, MAX_MICRO_SPP};
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
        assert_eq!(cam("target", json!([0, 0, "1"])), "camera.target.2");
        assert_eq!(cam("target", json!([0, 0, 2e6])), "camera.target.2");
        assert_eq!(cam("target", json!([0, 0, 0, 0])), "camera.target");
        // Text is text, not bytes (a page's Uint8Array).
        let mut v = value(&doc());
        if let Value::Object(kv) = &mut v {
            for (_, x) in kv.iter_mut().filter(|(k, _)| k == "scene") {
                *x = Value::Bytes(b"{}".to_vec());
            }
        }
        assert_eq!(check(&v).unwrap_err().field(), Some("scene"));
        assert_eq!(field_of("camera", json!({"yaw": 1})), "camera.pitch");
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

    /// `doc()` with `edit` applied.
    fn with(edit: impl Fn(&mut Json)) -> Json {
        let mut d = doc();
        edit(&mut d);
        d
    }

    /// The `micro-render` (or, for `z`, `micro-slice`) request the page
    /// sends for document `d`, checked by the core; `Err(field)` when refused.
    fn request(d: &Json, slice: bool) -> std::result::Result<(), String> {
        // A value the request's type cannot hold (`spp: -1`) is refused
        // as it is read.
        fn read<T: serde::de::DeserializeOwned>(j: Json) -> std::result::Result<T, String> {
            serde_path_to_error::deserialize(j).map_err(|e| crate::core::check::dotted(e.path()))
        }
        let started = if slice {
            let req = json!({"scene": d["scene"], "z": d["z"], "width": 2, "height": 2});
            start_slice(read(req)?).map(drop)
        } else {
            let mut req =
                json!({"scene": d["scene"], "width": 2, "height": 2, "camera": d["camera"]});
            for k in [
                "steps",
                "shading",
                "roughness",
                "specular",
                "absorption",
                "spp",
                "max_depth",
            ] {
                req[k] = d[k].clone();
            }
            start_render(read(req)?).map(drop)
        };
        started.map_err(|e| e.field().unwrap_or("?").to_string())
    }

    #[test]
    fn every_range_is_inside_or_out_by_one() {
        let num = |v: f64| json!(v);
        let up = |v: f64| json!(v.next_up());
        let down = |v: f64| json!(v.next_down());
        // (field, the range's end just inside, just outside)
        let mut cases: Vec<(&str, Json, Json)> = vec![];
        for (field, (lo, hi)) in [
            ("camera.yaw", YAW),
            ("camera.pitch", PITCH),
            ("camera.distance", DISTANCE),
            ("camera.target.0", TARGET),
            ("camera.target.2", TARGET),
            ("z", Z),
            ("roughness", ROUGHNESS),
            ("specular", SPECULAR),
            ("absorption", ABSORPTION),
        ] {
            cases.push((field, num(lo), down(lo)));
            cases.push((field, num(hi), up(hi)));
        }
        for (field, (lo, hi)) in [("spp", SPP), ("max_depth", MAX_DEPTH)] {
            if lo > 0 {
                cases.push((field, json!(lo), json!(lo - 1)));
            } else {
                cases.push((field, json!(lo), json!(-1)));
            }
            cases.push((field, json!(hi), json!(hi + 1)));
        }
        assert_eq!(SPP.1, MAX_MICRO_SPP);
        for (field, inside, outside) in cases {
            let set = |v: &Json| {
                with(|d| {
                    let mut at = &mut *d;
                    for k in field.split('.') {
                        at = match k.parse::<usize>() {
                            Ok(i) => &mut at[i],
                            Err(_) => &mut at[k],
                        };
                    }
                    *at = v.clone();
                })
            };
            let (inside, outside) = (set(&inside), set(&outside));
            check(&value(&inside)).unwrap_or_else(|e| panic!("{field} inside: {e}"));
            let e = check(&value(&outside)).unwrap_err();
            assert_eq!(e.field(), Some(field), "{e}");
            assert!(e.to_string().starts_with(field), "{e}");
            // The request the page sends for the same document agrees,
            // naming the same field.
            let slice = field == "z";
            request(&inside, slice).unwrap_or_else(|f| panic!("{field} inside, as a request: {f}"));
            assert_eq!(request(&outside, slice), Err(field.to_string()));
        }
        // The scene's size is the core's limit.
        let scene = |n: usize| with(|d| d["scene"] = json!(" ".repeat(n)));
        check(&value(&scene(MAX_MICRO_SCENE_BYTES))).unwrap();
        assert_eq!(
            check(&value(&scene(MAX_MICRO_SCENE_BYTES + 1)))
                .unwrap_err()
                .field(),
            Some("scene")
        );
        // NaN, which a page's number can be, is not a number here.
        let mut v = value(&doc());
        if let Value::Object(kv) = &mut v {
            for (_, x) in kv.iter_mut().filter(|(k, _)| k == "roughness") {
                *x = Value::Number(f64::NAN);
            }
        }
        assert_eq!(check(&v).unwrap_err().field(), Some("roughness"));
    }

    #[test]
    fn unknown_fields_are_dropped_as_they_always_were() {
        let plain = check(&value(&doc())).unwrap();
        let extra = with(|d| {
            d["extra"] = json!(1);
            d["camera"]["fov"] = json!(40);
        });
        assert_eq!(check(&value(&extra)).unwrap(), plain);
        // `null` in a field a version 1 document lacks is its default too.
        let s = check(&value(&with(|d| {
            d["roughness"] = json!(null);
            d["spp"] = json!(null);
            d["view"] = json!(null);
        })))
        .unwrap();
        let r = MicroRenderRequest::default();
        assert_eq!(
            (s.roughness, s.spp, s.view),
            (r.roughness, r.spp, View::Render)
        );
    }
}
