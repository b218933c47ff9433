//! Project files as today's app saves them open in the core (`open-project`)
//! as exactly the document the app saved, and a checked state saved again
//! opens again unchanged. (Each rule and message: unit tests in
//! `src/api/project/tests.rs`.)
use crate::support::app_projects;

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
fn texture_projects_saved_by_the_app_round_trip() {
    for image in [true, false] {
        let saved = norm(&texture_doc(image));
        let (p, got) = opened_state(&project_text("texture", 1, saved.clone()));
        assert_eq!((p.tool.as_str(), p.state_version), ("texture", 1));
        assert_eq!(got, saved, "image source: {image}");
        let (_, again) = opened_state(&project::project_text("texture", 1, &p.state).unwrap());
        assert_eq!(again, got);
    }
    // A bad field is named with its path.
    let mut d = texture_doc(false);
    d["retrieved"]["params"] = serde_json::json!([1, 2]);
    let e = project::open_project(&project_text("texture", 1, d)).unwrap_err();
    assert_eq!(e.field(), Some("retrieved.params"), "{e}");
}

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

/// A pixel project with a `side`² mask (`side`² bytes, as base64 in the file).
fn big_pixel_project(side: usize) -> String {
    let mut doc = pixel_example("fish");
    doc["mask"] = serde_json::json!({
        "width": side, "height": side,
        "bits": bytes(&(0..side * side).map(|i| (i % 3 == 0) as u8).collect::<Vec<_>>()),
    });
    project_text("pixel", 1, doc)
}

/// `open-project` as the worker runs it (the registry's job): a big file
/// is read over many steps, not in one, with progress that only grows, and
/// the answer is the one `open_project` gives.
#[test]
fn a_big_project_opens_over_many_steps() {
    use filigree::api::Response;
    use filigree::core::job::Step;
    let text = big_pixel_project(2048);
    assert!(text.len() > 5_000_000, "{} bytes", text.len());
    let payload = serde_json::json!({ "text": text }).to_string();
    let mut job = filigree::api::start(
        "open-project",
        &mut serde_json::Deserializer::from_str(&payload),
    )
    .unwrap();
    let mut fractions = vec![];
    let out = loop {
        match job.step().unwrap() {
            Step::Running(p) => fractions.push(p.fraction),
            Step::Done(out) => break out,
        }
    };
    // At most READ_FUEL bytes of text a reading step: 5.6 MB take 6 or more.
    let reading = (text.len() / project::READ_FUEL).max(1);
    assert!(fractions.len() > reading, "{} steps", fractions.len());
    assert!(fractions.windows(2).all(|w| w[0] <= w[1]), "{fractions:?}");
    let Response::Project(p) = out else {
        panic!("not a project")
    };
    assert_eq!(*p, project::open_project(&text).unwrap());
    let ProjectState::Checked(filigree::api::project::ToolState::Pixel(s)) = &p.state else {
        panic!("unchecked")
    };
    assert_eq!((s.mask.width, s.mask.bits.len()), (2048, 2048 * 2048));
    assert_eq!(
        s.mask.bits.iter().filter(|&&b| b == 1).count(),
        2048 * 2048 / 3 + 1
    );
}

/// A cancel between two steps of reading stops `open-project`.
#[test]
fn opening_a_project_can_be_cancelled_between_steps() {
    use filigree::core::job::{run_to_end, Cancel};
    let text = big_pixel_project(2048);
    let cancel = Cancel::new();
    let mut steps = 0;
    let r = run_to_end(
        project::start_open_project(
            project::OpenProjectRequest {
                text,
                unchecked: false,
            },
            project::check_any,
        ),
        &cancel,
        |_| {
            steps += 1;
            if steps == 2 {
                cancel.cancel();
            }
        },
    );
    assert_eq!(r, Err(filigree::Error::Cancelled));
    assert_eq!(steps, 2);
}

/// A file that is not JSON is refused with what is wrong and where.
#[test]
fn a_broken_project_file_says_where() {
    let e = project::open_project("{\"format\": \"filigree-project\",\n  \"version\": 2,,\n}")
        .unwrap_err();
    assert_eq!(e.kind(), "invalid-input");
    assert_eq!(
        e.to_string(),
        "not a Filigree project: the file is not valid JSON (a key that is not a string at line 2 column 16)"
    );
    let mut text = big_pixel_project(64);
    let at = text.find("\"state\":{").unwrap() + 9;
    text.insert_str(at, "\"x\": [1, 2 3], ");
    let e = project::open_project(&text).unwrap_err();
    assert_eq!(
        e.to_string(),
        format!(
            "not a Filigree project: the file is not valid JSON (expected `,` or `]` in a list at line 1 column {})",
            at + 12
        )
    );
}

/// Issue 34 item 7: a project or scene file saved with a UTF-8 byte order
/// mark (as Windows editors write) said "expected value at line 1 column 1".
#[test]
fn a_byte_order_mark_is_not_part_of_the_json() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fish.filigree.json");
    let text = std::fs::read_to_string(path).unwrap();
    let with_bom = format!("\u{feff}{text}");
    let p = project::open_project(&with_bom).unwrap();
    assert_eq!(p.tool, "pixel");
    let scene = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("assets/micro/gyroid.json"),
    )
    .unwrap();
    filigree::micro::scene::parse(&format!("\u{feff}{scene}")).unwrap();
}

/// Issue 34 item 6: a Pixel project whose `source` was 3 bytes that are
/// not an image opened (and failed only when the tool ran).
#[test]
fn a_pixel_project_whose_source_is_not_an_image_is_refused() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fish.filigree.json");
    let mut doc: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    doc["state"]["source"] = serde_json::json!({"$bytes": "AQID"});
    let e = project::open_project(&doc.to_string()).unwrap_err();
    assert_eq!(e.field(), Some("source"), "{e}");
    assert!(e.to_string().contains("is not an image file"), "{e}");
}
