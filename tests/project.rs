//! Project files as today's app saves them open in the core (`open-project`)
//! as exactly the document the app saved, and a checked state saved again
//! opens again unchanged. (Each rule and message: unit tests in
//! `src/api/project/tests.rs`.)
#[path = "support/app_projects.rs"]
mod app_projects;

use app_projects::*;
use filigree::api::project::{self, ProjectState};
use serde_json::Value as Json;
use std::path::Path;

/// `j` with every whole number written as an integer (JS has one number
/// type; `2` and `2.0` are the same number there).
fn norm(j: &Json) -> Json {
    serde_json::to_value(project::Value::read(j, false).unwrap()).unwrap()
}

/// What the page holds after opening: the core's answer as JSON, with byte
/// fields written back as `{"$bytes"}` (so it compares with the saved state).
fn opened_state(text: &str) -> (project::OpenedProject, Json) {
    let p = project::open_project(text).unwrap();
    assert!(p.checked, "the current state version is checked");
    let ProjectState::Checked(state) = &p.state else {
        panic!("unchecked")
    };
    let saved = project::project_text(&p.tool, p.state_version, state).unwrap();
    let doc: Json = serde_json::from_str(&saved).unwrap();
    (p, norm(&doc["state"]))
}

#[test]
fn pixel_projects_saved_by_the_app_round_trip() {
    for name in ["fish", "trunk"] {
        let saved = norm(&pixel_example(name));
        let text = project_text("pixel", 1, saved.clone());
        let (p, got) = opened_state(&text);
        assert_eq!((p.tool.as_str(), p.state_version), ("pixel", 1));
        // Every field the app saved comes back as saved (the params are all
        // the core's PixelParams; the app's document has them all too).
        assert_eq!(got, saved, "{name}");
        // And once more: open → save → open is a fixed point.
        let (_, again) = opened_state(&project::project_text("pixel", 1, &p.state).unwrap());
        assert_eq!(again, got);
    }
}

#[test]
fn fit_and_inspect_projects_saved_by_the_app_round_trip() {
    for fitted in [false, true] {
        let saved = norm(&fit_doc("stripes", fitted));
        let (p, got) = opened_state(&project_text("fit", 1, saved.clone()));
        assert_eq!(p.tool, "fit");
        assert_eq!(got, saved, "fitted: {fitted}");
    }
    let (p, got) = opened_state(&project_text("inspect", 1, inspect_doc()));
    assert_eq!(p.tool, "inspect");
    assert_eq!(got, norm(&inspect_doc()));
}

/// A project file downloaded from the running app (Save project on the
/// fish example, `tests/fixtures/fish.filigree.json`) opens unchanged.
#[test]
fn a_file_saved_by_the_app_opens() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fish.filigree.json");
    let text = std::fs::read_to_string(path).unwrap();
    let file = norm(&serde_json::from_str(&text).unwrap());
    let (p, got) = opened_state(&text);
    assert_eq!((p.tool.as_str(), p.state_version), ("pixel", 1));
    assert_eq!(got["mask"], file["state"]["mask"]);
    assert_eq!(got["source"], file["state"]["source"]);
    assert_eq!(got["strokes"], file["state"]["strokes"]);
    assert_eq!(got["names"], file["state"]["names"]);
    assert_eq!(got["params"], file["state"]["params"]);
    // The app's file is the same document the example builder makes.
    assert_eq!(got, norm(&pixel_example("fish")));
}
