//! Each rule of each tool state and of the project envelope, with its message.
use super::*;
use crate::core::limits::{MAX_IMAGE_SIDE, MAX_STROKE_POINTS};
use crate::core::value::base64_decode;
use serde_json::{json, Value as Json};

fn b64(bytes: &[u8]) -> Json {
    json!({ "$bytes": base64_encode(bytes) })
}

/// A JSON value as a state, `{"$bytes": …}` decoded (as in a project file).
fn val(j: &Json) -> Value {
    Value::read(j, true).unwrap()
}

/// The smallest real PNGs (1×1 and 2×1): a Pixel document's images are
/// checked from their headers.
const PNG_A: &[u8] = &[
    137, 80, 78, 71, 13, 10, 26, 10, 0, 0, 0, 13, 73, 72, 68, 82, 0, 0, 0, 1, 0, 0, 0, 1, 8, 6, 0,
    0, 0, 31, 21, 196, 137, 0, 0, 0, 13, 73, 68, 65, 84, 120, 156, 99, 96, 96, 96, 248, 15, 0, 1,
    4, 1, 0, 95, 229, 195, 75, 0, 0, 0, 0, 73, 69, 78, 68, 174, 66, 96, 130,
];
const PNG_B: &[u8] = &[
    137, 80, 78, 71, 13, 10, 26, 10, 0, 0, 0, 13, 73, 72, 68, 82, 0, 0, 0, 2, 0, 0, 0, 1, 8, 6, 0,
    0, 0, 244, 34, 127, 138, 0, 0, 0, 14, 73, 68, 65, 84, 120, 156, 99, 96, 96, 96, 248, 15, 194,
    0, 6, 3, 1, 255, 207, 135, 198, 112, 0, 0, 0, 0, 73, 69, 78, 68, 174, 66, 96, 130,
];

fn pixel_doc() -> Json {
    json!({
        "example": "fish",
        "source": b64(PNG_A),
        "sheet": b64(PNG_B),
        "sprite": null,
        "mask": {"width": 3, "height": 2, "bits": b64(&[0, 1, 2, 0, 0, 255])},
        "strokes": [[[0, 0], [3.5, 2.5]], [[-1, -1], [4, 3], [1, 1]]],
        "params": {
            "positions": "packed", "density": 0.5, "margins": [-1, 2], "partial": true,
            "colour": "auto", "d_max": 50, "hsv": [0, 0, -30], "exclude": [[0, 0, 0]],
            "element_colour": "region", "annotation_scale": 4, "default_direction": "down",
            "sprite_direction": "up", "seed": 7
        },
        "names": {"source": "fish.png", "sheet": "x".repeat(300)}
    })
}

fn fit_doc() -> Json {
    json!({
        "generator": "stripes",
        "program": "param r in [0, 1] = 0.5;\ncircle(0.5, 0.5, r);\n",
        "values": [0.5, 2],
        "target": {"width": 256, "height": 256, "rgba": b64(&vec![7u8; 256 * 256 * 4])},
        "truth": [0.25, 3],
        "result": {"params": [0.3], "loss": 0.01, "names": ["r", 5], "evaluations": 640},
        "settings": {"budget": "paper", "loss": "l1", "seed": 1}
    })
}

fn pixel_err(edit: impl FnOnce(&mut Json)) -> Error {
    let mut d = pixel_doc();
    edit(&mut d);
    check_state("pixel", 1, &val(&d)).unwrap_err()
}

fn fit_err(edit: impl FnOnce(&mut Json)) -> Error {
    let mut d = fit_doc();
    edit(&mut d);
    check_state("fit", 1, &val(&d)).unwrap_err()
}

#[track_caller]
fn says(e: &Error, field: &str, message: &str) {
    assert_eq!(e.field(), Some(field), "{e}");
    assert_eq!(e.to_string(), message);
}

#[test]
fn a_pixel_state_is_checked_and_normalised() {
    let ToolState::Pixel(s) = check_state("pixel", 1, &val(&pixel_doc())).unwrap() else {
        panic!("not a pixel state");
    };
    assert_eq!(s.example.as_deref(), Some("fish"));
    assert_eq!(s.source, PNG_A);
    assert_eq!(s.sheet.as_deref(), Some(PNG_B));
    assert_eq!(s.sprite, None);
    assert_eq!(s.mask.bits, [0, 1, 1, 0, 0, 1], "bits become 0 or 1");
    assert_eq!(s.strokes[1], [[-1.0, -1.0], [4.0, 3.0], [1.0, 1.0]]);
    assert_eq!(s.params.margins, [-1, 2]);
    assert_eq!(s.params.seed, 7);
    assert_eq!(s.names.source.as_deref(), Some("fish.png"));
    assert_eq!(
        s.names.sheet.as_ref().unwrap().len(),
        200,
        "names are cut to 200"
    );
    // The params are exactly the `pixel` request's.
    let v = serde_json::to_value(&s).unwrap();
    let p: crate::pixel::PixelParams = serde_json::from_value(v["params"].clone()).unwrap();
    assert_eq!(p, s.params);
    assert_eq!(v["sprite"], Json::Null);
    // sprite_direction may be absent (the page has no control for it).
    let mut d = pixel_doc();
    d["params"]
        .as_object_mut()
        .unwrap()
        .remove("sprite_direction");
    d["example"] = Json::Null;
    d["names"] = json!("not an object");
    let ToolState::Pixel(s) = check_state("pixel", 1, &val(&d)).unwrap() else {
        panic!()
    };
    assert_eq!(s.example, None);
    assert_eq!(s.names, crate::pixel::state::Names::default());
}

#[test]
fn pixel_images_and_mask_rules() {
    says(
        &check_state("pixel", 1, &val(&json!([1]))).unwrap_err(),
        "state",
        "state is not a Pixel document",
    );
    let e = pixel_err(|d| d["source"] = b64(&[]));
    says(&e, "source", "source must be the bytes of an image file");
    let e = pixel_err(|d| {
        d.as_object_mut().unwrap().remove("source");
    });
    says(&e, "source", "source is missing");
    let e = pixel_err(|d| d["sheet"] = json!("sheet.png"));
    says(
        &e,
        "sheet",
        "sheet must be the bytes of an image file (got string \"sheet.png\")",
    );
    let e = pixel_err(|d| d["sprite"] = json!([1, 2]));
    says(
        &e,
        "sprite",
        "sprite must be the bytes of an image file (got sequence)",
    );
    let e = pixel_err(|d| d["mask"] = Json::Null);
    says(&e, "mask", "mask must be an object (got null)");
    let e = pixel_err(|d| d["mask"]["width"] = json!(0));
    says(
        &e,
        "mask",
        "mask must be 1 to 4096 pixels on each side (found 0×2)",
    );
    let e = pixel_err(|d| d["mask"]["height"] = json!(MAX_IMAGE_SIDE + 1));
    says(
        &e,
        "mask",
        "mask must be 1 to 4096 pixels on each side (found 3×4097)",
    );
    let e = pixel_err(|d| d["mask"]["width"] = json!(2.5));
    says(
        &e,
        "mask.width",
        "mask.width must be a whole number ≥ 0 (got floating point '2.5')",
    );
    // The `pixel` request's mask: a missing side is 0.
    let e = pixel_err(|d| {
        d["mask"].as_object_mut().unwrap().remove("height");
    });
    says(
        &e,
        "mask",
        "mask must be 1 to 4096 pixels on each side (found 3×0)",
    );
    let e = pixel_err(|d| d["mask"]["bits"] = b64(&[1, 0, 1]));
    says(
        &e,
        "mask.bits",
        "mask.bits must hold 6 values (3×2), found 3",
    );
    let e = pixel_err(|d| {
        d["mask"].as_object_mut().unwrap().remove("bits");
    });
    says(
        &e,
        "mask.bits",
        "mask.bits must hold 6 values (3×2), found 0",
    );
    let e = pixel_err(|d| d["mask"]["bits"] = json!([1, 1, 1, 1, 1, 1]));
    says(
        &e,
        "mask.bits",
        "mask.bits must be bytes (a Uint8Array) (got sequence)",
    );
}

#[test]
fn pixel_stroke_rules() {
    let e = pixel_err(|d| d["strokes"] = json!({}));
    says(&e, "strokes", "strokes must be a list (got map)");
    let e = pixel_err(|d| d["strokes"] = json!(vec![[[0, 0], [1, 1]]; 10_001]));
    says(
        &e,
        "strokes",
        "strokes must be a list of at most 10000 strokes",
    );
    let e = pixel_err(|d| d["strokes"] = json!([[[0, 0], [1, 1]], [[0, 0]]]));
    says(
        &e,
        "strokes.1",
        "strokes.1 must be a list of at least 2 points",
    );
    let e = pixel_err(|d| d["strokes"] = json!([[[1, 2], [3, "x"]]]));
    says(
        &e,
        "strokes.0.1",
        "strokes.0.1 must be a point [x, y] of finite numbers (got [3, text])",
    );
    let e = pixel_err(|d| d["strokes"] = json!([[[1, 2], [1, 2, 3]]]));
    assert_eq!(e.field(), Some("strokes.0.1"));
    let e = pixel_err(|d| d["strokes"] = json!([[[1, 2], [4.5, 0]]]));
    says(&e, "strokes.0.1", "strokes.0.1 lies outside the 3×2 image");
    let e = pixel_err(|d| d["strokes"] = json!([[[-1.5, 0], [1, 1]]]));
    says(&e, "strokes.0.0", "strokes.0.0 lies outside the 3×2 image");
    // The core's stroke point limit, not a page figure.
    let e = pixel_err(|d| d["strokes"] = json!(vec![vec![[0, 0]; 50_001]; 5]));
    assert_eq!(e.kind(), "limit");
    says(
        &e,
        "strokes",
        &format!(
            "strokes have 250005 points in all; the stroke point limit is {MAX_STROKE_POINTS}"
        ),
    );
}

#[test]
fn pixel_parameter_rules_use_the_core_limits() {
    let e = pixel_err(|d| d["params"] = json!([]));
    says(&e, "params", "params must be an object (got sequence)");
    let e = pixel_err(|d| d["params"]["dmax"] = json!(3));
    assert_eq!(e.field(), Some("params"));
    assert!(
        e.to_string().starts_with(
            "params has no field 'dmax'; expected one of 'annotation_scale', 'positions', 'density'"
        ),
        "{e}"
    );
    let e = pixel_err(|d| {
        d["params"].as_object_mut().unwrap().remove("seed");
    });
    says(&e, "params.seed", "params.seed is missing");
    let directions =
        "must be one of right, down-right, down, down-left, left, up-left, up, up-right";
    let cases: &[(&str, Json, &str, String)] = &[
        (
            "positions",
            json!("grid"),
            "params.positions",
            "must be one of random, packed".into(),
        ),
        (
            "colour",
            json!(1),
            "params.colour",
            "must be a name (text) (got integer '1')".into(),
        ),
        (
            "colour",
            json!("rgb"),
            "params.colour",
            "must be one of auto, hsv, difference, border".into(),
        ),
        (
            "element_colour",
            json!("Region"),
            "params.element_colour",
            "must be one of pixel, region".into(),
        ),
        (
            "default_direction",
            json!("north"),
            "params.default_direction",
            directions.into(),
        ),
        (
            "sprite_direction",
            json!(null),
            "params.sprite_direction",
            "must be a name (text) (got null)".into(),
        ),
        (
            "density",
            json!(1.5),
            "params.density",
            "must be a number from 0 to 1".into(),
        ),
        (
            "density",
            json!("1"),
            "params.density",
            "must be a number (got string \"1\")".into(),
        ),
        (
            "d_max",
            json!(1000.5),
            "params.d_max",
            "must be a number from 0 to 1000".into(),
        ),
        (
            "d_max",
            json!(-1),
            "params.d_max",
            "must be a number from 0 to 1000".into(),
        ),
        (
            "partial",
            json!(1),
            "params.partial",
            "must be true or false (got integer '1')".into(),
        ),
        (
            "margins",
            json!([0, 4097]),
            "params.margins.1",
            "must be a whole number from -4096 to 4096".into(),
        ),
        (
            "margins",
            json!([0.5, 0]),
            "params.margins.0",
            "must be a whole number (got floating point '0.5')".into(),
        ),
        (
            "margins",
            json!([0]),
            "params.margins",
            "must be a list of 2 (got 1 items)".into(),
        ),
        (
            "hsv",
            json!([361, 0, 0]),
            "params.hsv.0",
            "must be a number from -360 to 360".into(),
        ),
        (
            "hsv",
            json!([0, -101, 0]),
            "params.hsv.1",
            "must be a number from -100 to 100".into(),
        ),
        (
            "hsv",
            json!([0, 0, 0.5]),
            "params.hsv.2",
            "must be a whole number from -100 to 100".into(),
        ),
        (
            "exclude",
            json!([[0, 0, 256]]),
            "params.exclude.0",
            "must be an [r, g, b] colour (whole numbers from 0 to 255) (got [0, 0, 256])".into(),
        ),
        (
            "exclude",
            json!(vec![[0, 0, 0]; 257]),
            "params.exclude",
            "must be a list of at most 256 [r, g, b] colours".into(),
        ),
        (
            "annotation_scale",
            json!(33),
            "params.annotation_scale",
            "must be a whole number from 1 to 32".into(),
        ),
        (
            "annotation_scale",
            json!(2.5),
            "params.annotation_scale",
            "must be a whole number ≥ 0 (got floating point '2.5')".into(),
        ),
        (
            "seed",
            json!(-1),
            "params.seed",
            "must be a whole number ≥ 0 (got integer '-1')".into(),
        ),
        (
            "seed",
            json!(9007199254740992u64),
            "params.seed",
            "must be a whole number ≥ 0 (got floating point '9007199254740992.0')".into(),
        ),
    ];
    for (k, v, field, why) in cases {
        let e = pixel_err(|d| d["params"][*k] = v.clone());
        says(&e, field, &format!("{field} {why}"));
    }
    // Inside the core's limits (wider than the page's sliders) is fine.
    let mut d = pixel_doc();
    d["params"]["d_max"] = json!(1000);
    d["params"]["margins"] = json!([-4096, 4096]);
    d["params"]["hsv"] = json!([-360, 100, -100]);
    d["params"]["seed"] = json!(9007199254740991u64);
    check_state("pixel", 1, &val(&d)).unwrap();
    // And what the state accepts, the `pixel` request accepts.
    let ToolState::Pixel(s) = check_state("pixel", 1, &val(&d)).unwrap() else {
        panic!()
    };
    crate::pixel::api::check_params(&s.params).unwrap();
}

#[test]
fn pixel_example_rule() {
    let e = pixel_err(|d| d["example"] = json!("cat"));
    says(&e, "example", "example must be one of fish, trunk or none");
}

#[test]
fn a_fit_state_is_checked_and_normalised() {
    let ToolState::Fit(s) = check_state("fit", 1, &val(&fit_doc())).unwrap() else {
        panic!("not a fit state");
    };
    assert_eq!(s.generator.as_deref(), Some("stripes"));
    assert_eq!(s.values, [0.5, 2.0]);
    assert_eq!(s.target.as_ref().unwrap().rgba.len(), 256 * 256 * 4);
    let r = s.result.as_ref().unwrap();
    assert_eq!(
        r.names.as_deref(),
        Some(&["r".to_string(), "5".to_string()][..])
    );
    assert_eq!(r.evaluations, 640);
    let v = serde_json::to_value(&s).unwrap();
    assert_eq!(
        v["settings"],
        json!({"budget": "paper", "loss": "l1", "seed": 1})
    );
    // Nullable parts.
    let mut d = fit_doc();
    for k in ["generator", "target", "truth", "result"] {
        d[k] = Json::Null;
    }
    d["result"] = json!({"params": [], "loss": 0});
    let ToolState::Fit(s) = check_state("fit", 1, &val(&d)).unwrap() else {
        panic!()
    };
    assert_eq!((s.generator, s.target, s.truth), (None, None, None));
    let r = s.result.unwrap();
    assert_eq!((r.names, r.evaluations), (None, 0));
    let v = serde_json::to_value(check_state("fit", 1, &val(&d)).unwrap()).unwrap();
    assert!(v["result"].get("names").is_none(), "no names: no key");
}

#[test]
fn fit_rules() {
    says(
        &check_state("fit", 1, &val(&json!("x"))).unwrap_err(),
        "state",
        "state is not a Fit document",
    );
    let long = "x".repeat(101);
    let program_why = format!(
        "program must be the text of a program (at most {} bytes)",
        crate::core::limits::MAX_PROGRAM_BYTES
    );
    let big_program = "c".repeat(crate::core::limits::MAX_PROGRAM_BYTES + 1);
    let cases: Vec<(&str, Json, &str, String)> = vec![
        (
            "generator",
            json!(long),
            "generator",
            "generator must be a generator name (at most 100 characters)".into(),
        ),
        (
            "generator",
            json!(3),
            "generator",
            "generator must be text (got integer '3')".into(),
        ),
        ("program", json!("  \n"), "program", program_why.clone()),
        (
            "program",
            json!(big_program),
            "program",
            program_why.clone(),
        ),
        (
            "program",
            Json::Null,
            "program",
            "program must be text (got null)".into(),
        ),
        (
            "values",
            json!(vec![0.0; 1001]),
            "values",
            "values must be a list of at most 1000 finite numbers".into(),
        ),
        (
            "values",
            json!([1, "2"]),
            "values.1",
            "values.1 must be a number (got string \"2\")".into(),
        ),
        (
            "target",
            json!({"width": 128, "height": 128, "rgba": b64(&[0; 4])}),
            "target",
            "target must be 256 pixels along its longer side (and at least 1 along the other)"
                .into(),
        ),
        (
            "target",
            json!({"width": 256.5, "height": 256, "rgba": b64(&[0; 4])}),
            "target.width",
            "target.width must be a whole number ≥ 0 (got floating point '256.5')".into(),
        ),
        (
            // An upload's aspect (256 × 205) is a target; its pixels must fit.
            "target",
            json!({"width": 256, "height": 205, "rgba": b64(&[0; 4])}),
            "target.rgba",
            "target.rgba must hold 209920 bytes".into(),
        ),
        (
            "target",
            json!({"width": 256, "height": 256, "rgba": b64(&[0; 4])}),
            "target.rgba",
            "target.rgba must hold 262144 bytes".into(),
        ),
        (
            "truth",
            json!([1]),
            "truth",
            "truth must have one value per parameter (2)".into(),
        ),
        (
            "truth",
            json!("1,2"),
            "truth",
            "truth must be a list (got string \"1,2\")".into(),
        ),
        (
            "result",
            json!(5),
            "result",
            "result must be an object (got integer '5')".into(),
        ),
        (
            "result",
            json!({"loss": 1}),
            "result.params",
            "result.params is missing".into(),
        ),
        (
            "result",
            json!({"params": [], "loss": -1}),
            "result.loss",
            "result.loss must be a finite number ≥ 0".into(),
        ),
        (
            "result",
            json!({"params": [], "loss": 1, "evaluations": 1.5}),
            "result.evaluations",
            "result.evaluations must be a whole number ≥ 0 (got floating point '1.5')".into(),
        ),
        (
            "result",
            json!({"params": [], "loss": 1, "names": "r"}),
            "result.names",
            "result.names must be a list (got string \"r\")".into(),
        ),
        (
            "settings",
            json!(1),
            "settings",
            "settings must be an object (got integer '1')".into(),
        ),
    ];
    for (k, v, field, message) in cases {
        let e = fit_err(|d| d[k] = v.clone());
        says(&e, field, &message);
    }
    let e = fit_err(|d| d["settings"]["budget"] = json!("slow"));
    says(
        &e,
        "settings.budget",
        "settings.budget must be one of quick, paper",
    );
    let e = fit_err(|d| d["settings"]["loss"] = json!("l3"));
    says(
        &e,
        "settings.loss",
        "settings.loss must be one of sdf, l1, pyramid, image",
    );
    let e = fit_err(|d| d["settings"]["seed"] = json!(-2));
    says(
        &e,
        "settings.seed",
        "settings.seed must be a whole number ≥ 0 (got integer '-2')",
    );
}

#[test]
fn inspect_state_rules() {
    let s = check_state("inspect", 1, &val(&json!({"name": 42, "bytes": b64(b"x")}))).unwrap();
    assert_eq!(
        s,
        ToolState::Inspect(inspect_state::InspectState {
            name: Some("42".into()),
            bytes: Some(b"x".to_vec())
        })
    );
    check_state("inspect", 1, &val(&json!({}))).unwrap();
    let e = check_state("inspect", 1, &val(&json!({"bytes": "x"}))).unwrap_err();
    says(&e, "bytes", "bytes must be the bytes of an image file");
    let e = check_state("inspect", 1, &val(&json!(null))).unwrap_err();
    says(&e, "state", "state is not an Inspect document");
}

#[test]
fn versions_and_tools() {
    let s = val(&pixel_doc());
    let e = check_state("pixel", 2, &s).unwrap_err();
    says(
        &e,
        "version",
        "it was made by a newer Filigree (Pixel state version 2); update Filigree to open it",
    );
    let e = check_state("pixel", 0, &s).unwrap_err();
    says(&e, "version", "the state has no schema version");
    let e = check_state("paint", 1, &s).unwrap_err();
    says(
        &e,
        "tool",
        "Filigree has no tool 'paint' (it has pixel, fit, tangle, micro, texture, inspect)",
    );
    // A new version needs the page's migration from the old one (the
    // panel's `state.migrate`): bump this list only with one.
    let migrated = [("micro", 2)];
    for t in TOOLS {
        let want = migrated
            .iter()
            .find(|(id, _)| *id == t.id)
            .map_or(1, |(_, v)| *v);
        assert_eq!(
            t.version, want,
            "{}: a new version needs a page migration",
            t.id
        );
        assert!(crate::api::KINDS.contains(&"check-state"));
    }
}

// ---------------------------------------------------------------- projects --

fn project(tool: &str, state: Json) -> String {
    json!({"format": "filigree-project", "version": 2, "tool": tool, "stateVersion": 1, "state": state})
        .to_string()
}

#[track_caller]
fn refused(text: &str, message: &str) -> Error {
    let e = open_project(text).unwrap_err();
    assert_eq!(e.to_string(), message);
    e
}

#[cfg(feature = "json")]
#[test]
fn a_project_file_opens_checked() {
    let p = open_project(&project("pixel", pixel_doc())).unwrap();
    assert_eq!(
        (p.tool.as_str(), p.state_version, p.checked),
        ("pixel", 1, true)
    );
    let want = check_state("pixel", 1, &val(&pixel_doc())).unwrap();
    assert_eq!(p.state, ProjectState::Checked(want.clone()));
    // Saved again (as the page writes it) and reopened: the same state.
    let again = project_text("pixel", 1, &want).unwrap();
    assert_eq!(
        open_project(&again).unwrap().state,
        ProjectState::Checked(want)
    );
    // A format-1 file has no stateVersion: its state is version 1.
    let v1 = json!({"format": "filigree-project", "version": 1, "tool": "fit", "state": fit_doc()});
    let p = open_project(&v1.to_string()).unwrap();
    assert_eq!((p.state_version, p.checked), (1, true));
    // A state error is the state's message, naming its field.
    let mut d = pixel_doc();
    d["mask"]["bits"] = b64(&[1, 0, 1]);
    let e = refused(
        &project("pixel", d),
        "mask.bits must hold 6 values (3×2), found 3",
    );
    assert_eq!(e.field(), Some("mask.bits"));
}

#[test]
fn project_envelope_rules() {
    let e = open_project("hello").unwrap_err();
    assert!(
        e.to_string()
            .starts_with("not a Filigree project: the file is not valid JSON ("),
        "{e}"
    );
    let e = open_project(&format!("{} x", project("fit", fit_doc()))).unwrap_err();
    assert!(e.to_string().contains("not valid JSON"), "{e}");
    let ok = |edit: &dyn Fn(&mut Json)| {
        let mut d: Json = serde_json::from_str(&project("fit", fit_doc())).unwrap();
        edit(&mut d);
        d.to_string()
    };
    refused(
        &ok(&|d| d["format"] = json!("other")),
        "not a Filigree project: \"format\" is missing or different",
    );
    refused(
        "[1]",
        "not a Filigree project: \"format\" is missing or different",
    );
    refused(
        &ok(&|d| d["version"] = json!(0)),
        "not a Filigree project: \"version\" is missing",
    );
    refused(
        &ok(&|d| d["version"] = json!(1.5)),
        "not a Filigree project: \"version\" is missing",
    );
    refused(
        &ok(&|d| d["version"] = json!(99)),
        "this project was saved by a newer Filigree (file format 99); update Filigree to open it",
    );
    refused(
        &ok(&|d| d["tool"] = json!("")),
        "not a Filigree project: \"tool\" is missing",
    );
    refused(
        &ok(&|d| d["stateVersion"] = Json::Null),
        "not a Filigree project: \"stateVersion\" is missing",
    );
    refused(
        &ok(&|d| d["state"] = json!("x")),
        "not a Filigree project: \"state\" is missing",
    );
    let e = refused(
        &ok(&|d| d["tool"] = json!("paint")),
        "it is a project of a tool this Filigree does not have ('paint')",
    );
    assert_eq!(e.field(), Some("tool"));
    refused(
        &ok(&|d| d["stateVersion"] = json!(3)),
        "it was made by a newer Filigree (Fit state version 3); update Filigree to open it",
    );
    refused(
        &ok(&|d| d["state"]["target"]["rgba"] = json!({"$bytes": "not base64!"})),
        "not a Filigree project: the project holds image data that is not valid base64",
    );
}

#[test]
fn project_reading_is_bounded() {
    let deep = format!("{}{}", "[".repeat(100), "]".repeat(100));
    let e = open_project(&deep).unwrap_err();
    assert_eq!(e.kind(), "limit");
    assert_eq!(
        e.to_string(),
        "not a Filigree project: the project is nested too deeply (more than 64 levels)"
    );
    // Far deeper than serde_json's own limit: still the same answer, no overflow.
    let deeper = "[".repeat(100_000);
    assert_eq!(open_project(&deeper).unwrap_err().kind(), "limit");
    let many = format!("[{}0]", "0,".repeat(limits::MAX_STATE_VALUES));
    let e = open_project(&many).unwrap_err();
    assert_eq!(e.kind(), "limit");
    assert!(e.to_string().contains("the state value limit"), "{e}");
    let huge = " ".repeat(limits::MAX_PROJECT_BYTES + 1);
    let e = open_project(&huge).unwrap_err();
    assert_eq!((e.kind(), e.field()), ("limit", Some("text")));
    assert!(e.to_string().contains("the project file limit"), "{e}");
}

#[test]
fn repeated_keys_keep_the_last_value_like_json_parse() {
    let v = Value::read(
        &mut serde_json::Deserializer::from_str(r#"{"a": 1, "b": 2, "a": 3}"#),
        false,
    )
    .unwrap();
    assert_eq!(
        v,
        Value::Object(vec![
            ("a".into(), Value::Number(3.0)),
            ("b".into(), Value::Number(2.0))
        ])
    );
}

#[test]
fn base64_is_read_as_atob_reads_it() {
    for n in 0..10u8 {
        let bytes: Vec<u8> = (0..n).map(|i| i.wrapping_mul(97)).collect();
        let text = base64_encode(&bytes);
        assert_eq!(base64_decode(&text).unwrap(), bytes);
        assert_eq!(base64_decode(text.trim_end_matches('=')).unwrap(), bytes);
    }
    assert_eq!(base64_encode(b"Man"), "TWFu");
    assert_eq!(base64_encode(b"Ma"), "TWE=");
    assert_eq!(base64_decode(" TW\nFu ").unwrap(), b"Man");
    assert_eq!(base64_decode("TWE").unwrap(), b"Ma");
    assert!(base64_decode("TWFuT").is_none(), "length 1 mod 4");
    assert!(base64_decode("TW=u").is_none());
    assert!(base64_decode("TWF*").is_none());
}

#[cfg(feature = "json")]
#[test]
fn both_kinds_run_through_the_registry() {
    let text = serde_json::to_string(&project("pixel", pixel_doc())).unwrap();
    let out = crate::api::run_json("open-project", &format!(r#"{{"text": {text}}}"#)).unwrap();
    assert_eq!(out["tool"], "pixel");
    assert_eq!(out["stateVersion"], 1);
    assert_eq!(out["checked"], true);
    assert_eq!(out["state"]["mask"]["bits"], json!([0, 1, 1, 0, 0, 1]));
    let state = json!({"name": "a.png", "bytes": null});
    let out = crate::api::run_json(
        "check-state",
        &json!({"tool": "inspect", "version": 1, "state": state}).to_string(),
    )
    .unwrap();
    assert_eq!(out, json!({"name": "a.png", "bytes": null}));
    let e = crate::api::run_json(
        "check-state",
        r#"{"tool": "fit", "version": 1, "state": {}}"#,
    )
    .unwrap_err();
    says(&e, "program", "program is missing");
    let e = crate::api::run_json("open-project", r#"{"text": "{}"}"#).unwrap_err();
    assert_eq!(e.kind(), "invalid-input");
}
