//! `adaptive-pm bench cornell` from the command line: `--json` prints exactly
//! one JSON object, bad input fails with a clear message before any tracing.

use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_adaptive-pm"))
}

#[test]
fn json_prints_one_object_with_the_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .args(["bench", "cornell", "--n-sweep", "0,50", "--n-max", "2000"])
        .args(["--modes", "classic,adaptive", "--json", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut objects = serde_json::Deserializer::from_str(&text).into_iter::<serde_json::Value>();
    let v = objects.next().unwrap().unwrap();
    assert!(objects.next().is_none(), "more than one JSON value");
    let runs = v["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 4);
    assert_eq!(runs[1]["mode"], "adaptive");
    assert_eq!(runs[2]["n"], 50.0);
    assert!(v["reference_max_density"].as_f64().unwrap() > 0.0);
    assert!(v["reference_sigma_density"].as_f64().unwrap() > 0.0);
    assert!(v["elapsed_s"].as_f64().unwrap() > 0.0);
    assert_eq!(v["out_dir"].as_str().unwrap(), dir.path().to_str().unwrap());
    assert_eq!(v["scene"], "cornell-empty", "the paper's scene by default");
    for r in runs {
        // mesh names carry their primitive: `floor#0`
        let mesh = r["max_density_primary_mesh"].as_str().unwrap();
        let mesh = mesh.split('#').next().unwrap();
        assert!(
            [
                "floor",
                "ceiling",
                "back_wall",
                "green_wall",
                "red_wall",
                "light"
            ]
            .contains(&mesh),
            "{mesh}"
        );
        let at = r["max_density_primary_at"].as_array().unwrap();
        assert_eq!(at.len(), 3);
    }
    assert!(dir.path().join("fig7a_max_density.svg").exists());
}

#[test]
fn a_malformed_sweep_shows_the_syntax() {
    let out = bin()
        .args(["bench", "cornell", "--n-sweep", "5..1"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("A..B:STEP"), "{err}");
}

#[test]
fn an_unwritable_output_folder_is_an_error_before_tracing() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("a-file");
    std::fs::write(&file, b"x").unwrap();
    let t = std::time::Instant::now();
    let out = bin()
        .args(["bench", "cornell", "--out"])
        .arg(file.join("sub"))
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("output folder"), "{err}");
    // the default sweep takes minutes: failing fast means nothing was traced
    assert!(t.elapsed().as_secs() < 10);
}

#[test]
fn scene_from_a_file_is_named_in_the_output() {
    let dir = tempfile::tempdir().unwrap();
    let file = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/cornell_box.gltf");
    let out = bin()
        .args(["bench", "cornell", "--n-sweep", "10", "--n-max", "2000"])
        .args(["--modes", "adaptive", "--json", "--scene", file, "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["scene"], file);
    let summary = std::fs::read_to_string(dir.path().join("summary.json")).unwrap();
    let s: serde_json::Value = serde_json::from_str(&summary).unwrap();
    assert_eq!(s["results"]["scene"], file);
    let runs = std::fs::read_to_string(dir.path().join("runs.csv")).unwrap();
    assert!(runs
        .lines()
        .next()
        .unwrap()
        .contains("max_density_primary_mesh"));
    assert!(dir.path().join("claims.md").exists());
}

#[test]
fn a_bad_scene_name_lists_the_built_in_names() {
    let dir = tempfile::tempdir().unwrap();
    let out = bin()
        .args(["bench", "cornell", "--scene", "cornel", "--out"])
        .arg(dir.path())
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cornell-empty") && err.contains("cornell,") && err.contains("cornel"),
        "{err}"
    );
}
