//! The `filigree` binary end to end: arguments in, files and JSON out.
use std::process::Command;

fn filigree(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_filigree"))
        .args(args)
        .output()
        .expect("run filigree")
}

#[test]
fn version_and_help() {
    let out = filigree(&["--version"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains(env!("CARGO_PKG_VERSION")));
    let help = String::from_utf8_lossy(&filigree(&["--help"]).stdout).to_string();
    assert!(help.contains("inspect"), "{help}");
}

#[test]
fn inspect_json_reports_size_and_palette() {
    let out = filigree(&["inspect", "tests/fixtures/fish.png", "--json"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["width"], 128);
    assert_eq!(v["height"], 128);
    assert_eq!(v["colour_count"], 3);
    assert_eq!(
        v["palette"][0]["rgba"],
        serde_json::json!([82, 99, 202, 255])
    );
}

#[test]
fn inspect_errors_name_the_file_and_the_problem() {
    let dir = std::env::temp_dir().join(format!("filigree-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bad = dir.join("bad.png");
    std::fs::write(&bad, b"not a png at all").unwrap();
    let out = filigree(&["inspect", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("bad.png") && err.contains("not an image"),
        "{err}"
    );
    let out = filigree(&["inspect", "does/not/exist.png"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("does/not/exist.png"));
}
