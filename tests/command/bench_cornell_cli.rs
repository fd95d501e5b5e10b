//! `adaptive-pm bench cornell` from the command line: `--json` prints exactly
//! one JSON object, bad input fails with a clear message before any tracing.
//! Also `bench render`'s reruns.

use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_adaptive-pm"))
}

/// Runs `cmd`, asserts it succeeded (its stderr the message) and returns
/// its output.
fn run_ok(cmd: &mut Command) -> Output {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

#[test]
fn json_prints_one_object_with_the_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = run_ok(
        bin()
            .args(["bench", "cornell", "--n-sweep", "0,50", "--n-max", "2000"])
            .args(["--modes", "classic,adaptive", "--json", "--out"])
            .arg(dir.path()),
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
    let out = run_ok(
        bin()
            .args(["bench", "cornell", "--n-sweep", "10", "--n-max", "2000"])
            .args(["--modes", "adaptive", "--json", "--scene", file, "--out"])
            .arg(dir.path()),
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

/// `bench render --reruns 2`: the fastest photon render at the target and
/// the path tracer timed twice more, each rerun's ratio and the median of
/// the three in the JSON, with the gather, k and cache stride it ran with.
#[test]
fn bench_render_reruns_report_their_ratios_and_median() {
    let out = run_ok(
        bin()
            .args(["bench", "render", "cornell", "--size", "16"])
            .args([
                "--reference-spp",
                "64",
                "--path-spp",
                "8",
                "--n-max",
                "3000",
            ])
            .args(["--max-spp", "64", "--target", "0.5", "--reruns", "2"])
            .args(["--final-gather", "1", "--k", "40", "--threads", "1"])
            .args(["--cache-stride", "16"]),
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        (v["final_gather"].as_u64(), v["k"].as_u64()),
        (Some(1), Some(40))
    );
    assert_eq!(v["cache_stride"].as_u64(), Some(16));
    let result = &v["result"];
    let reruns = result["reruns"].as_array().unwrap();
    assert_eq!(reruns.len(), 2);
    let mut ratios: Vec<f64> = reruns
        .iter()
        .map(|r| r["ratio"].as_f64().unwrap())
        .chain([result["ratio"].as_f64().unwrap()])
        .collect();
    for r in reruns {
        let (p, t) = (
            r["photon_s"].as_f64().unwrap(),
            r["path_time_to_target_s"].as_f64().unwrap(),
        );
        assert!(p > 0.0 && t > 0.0 && (r["ratio"].as_f64().unwrap() - p / t).abs() < 1e-12);
    }
    ratios.sort_by(f64::total_cmp);
    assert_eq!(result["median_ratio"].as_f64(), Some(ratios[1]));
}

/// `bench render` refuses a cache stride the renderer would refuse, before
/// any rendering, naming the setting.
#[test]
fn bench_render_refuses_a_bad_cache_stride() {
    let out = bin()
        .args([
            "bench",
            "render",
            "cornell",
            "--size",
            "16",
            "--cache-stride",
            "1",
        ])
        .output()
        .unwrap();
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cache stride") && err.contains("got 1"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
}
