//! Sharding from the command line: shards picked from the scheduler's
//! environment merge to `trace --json`'s checksum; `render --map` renders a
//! merged map exactly as the whole run's map file; tiles assemble into the
//! whole image; bad input is a clear error with nothing left at --out.

use adaptive_pm::render::Image;
use serde_json::Value;
use std::path::Path;
use std::process::Command;

const TRACE: [&str; 6] = ["--mode", "adaptive", "--n-max", "3000", "--seed", "5"];

fn run(args: &[&str], env: &[(&str, &str)]) -> (i32, String, String) {
    let mut c = Command::new(env!("CARGO_BIN_EXE_adaptive-pm"));
    for v in [
        "SLURM_ARRAY_TASK_ID",
        "SLURM_ARRAY_TASK_MIN",
        "SLURM_ARRAY_TASK_COUNT",
        "SLURM_ARRAY_TASK_STEP",
        "JOB_COMPLETION_INDEX",
    ] {
        c.env_remove(v);
    }
    let out = c.args(args).envs(env.iter().copied()).output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    let code = out.status.code().unwrap_or(-1);
    (code, String::from_utf8_lossy(&out.stdout).to_string(), err)
}

fn json(args: &[&str], env: &[(&str, &str)]) -> Value {
    let (code, out, err) = run(args, env);
    assert_eq!(code, 0, "{args:?}: {err}");
    serde_json::from_str(out.trim()).unwrap()
}

fn trace(out: &Path, extra: &[&str], env: &[(&str, &str)]) -> Value {
    let mut a = vec!["trace", "cornell", "--json", "--out", out.to_str().unwrap()];
    a.extend(TRACE);
    a.extend(extra);
    json(&a, env)
}

#[test]
fn scheduler_shards_merge_to_the_single_checksum_and_render_the_same() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n).to_str().unwrap().to_string();
    let whole = trace(Path::new(&d("whole.apm")), &[], &[]);
    // A Slurm array 4..=6 (SLURM_ARRAY_TASK_MIN = 4) and an Indexed Job of 3.
    let mut slurm = Vec::new();
    for id in ["4", "5", "6"] {
        let env = [
            ("SLURM_ARRAY_TASK_ID", id),
            ("SLURM_ARRAY_TASK_MIN", "4"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ];
        let v = trace(Path::new(&d(&format!("slurm{id}.apm"))), &[], &env);
        slurm.push(d(&format!("slurm{id}.apm")));
        assert_eq!(v["shard"], format!("{}/3", id.parse::<u32>().unwrap() - 4));
    }
    let mut k8s = Vec::new();
    for i in ["0", "1", "2"] {
        let p = d(&format!("k8s{i}.apm"));
        trace(
            Path::new(&p),
            &["--shards", "3"],
            &[("JOB_COMPLETION_INDEX", i)],
        );
        k8s.push(p);
    }
    for (name, files) in [("slurm", &slurm), ("k8s", &k8s)] {
        let mut a = vec!["merge", "--json", "--out"];
        let out = d(&format!("{name}-map.apm"));
        a.push(&out);
        a.extend(files.iter().map(String::as_str));
        let m = json(&a, &[]);
        assert_eq!(m["checksum"], whole["checksum"], "{name}");
        assert_eq!(m["photons"], whole["stored"], "{name}");
    }
    // The merged map is the whole run's map file, photon for photon.
    let bytes = |p: &str| std::fs::read(p).unwrap();
    assert_eq!(
        bytes(&d("slurm-map.apm"))[4096..],
        bytes(&d("k8s-map.apm"))[4096..]
    );
    // render --map: the merged map renders as the whole run's file; tiles assemble to it.
    let render = |map: &str, out: &str, tile: Option<&str>| {
        let mut a = vec![
            "render", "cornell", "--map", map, "--width", "40", "--height", "30", "--spp", "1",
            "--out", out,
        ];
        if let Some(t) = tile {
            a.extend(["--tile", t]);
        }
        let (code, _, err) = run(&a, &[]);
        assert_eq!(code, 0, "{err}");
    };
    render(&d("whole.apm"), &d("whole.exr"), None);
    render(&d("slurm-map.apm"), &d("merged.exr"), None);
    let img = |p: &str| Image::read_exr(p).unwrap();
    assert_eq!(img(&d("whole.exr")), img(&d("merged.exr")));
    let tiles: Vec<String> = (0..4).map(|i| d(&format!("tile{i}.exr"))).collect();
    for (i, t) in tiles.iter().enumerate() {
        render(&d("slurm-map.apm"), t, Some(&format!("{i}/4")));
    }
    let mut a = vec!["assemble", "--out"];
    let full = d("assembled.exr");
    a.push(&full);
    a.extend(tiles.iter().rev().map(String::as_str));
    let (code, _, err) = run(&a, &[]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(img(&full), img(&d("merged.exr")));
    // A missing tile is refused, nothing written.
    let bad = d("bad.exr");
    let (code, _, err) = run(
        &["assemble", "--out", &bad, &tiles[0], &tiles[2], &tiles[3]],
        &[],
    );
    assert_ne!(code, 0);
    assert!(err.contains("missing"), "{err}");
    assert!(!Path::new(&bad).exists());
    // Merge refuses a missing shard: non-zero exit, clear message, no output.
    let out = d("partial.apm");
    let (code, _, err) = run(&["merge", "--out", &out, &slurm[0], &slurm[2]], &[]);
    assert_ne!(code, 0);
    assert!(err.contains("missing shard(s) 1 of 3"), "{err}");
    assert!(!Path::new(&out).exists());
}

/// Trace arguments, environment, and the words the error must contain.
type Case<'a> = (&'a [&'a str], &'a [(&'a str, &'a str)], &'a str);

#[test]
fn bad_shard_requests_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.apm");
    let o = out.to_str().unwrap();
    let cases: [Case; 4] = [
        (
            &["--mode", "density", "--shard", "0/2", "--out", o],
            &[],
            "density control cannot be sharded",
        ),
        (&["--shard", "3/3", "--out", o], &[], "not below the count"),
        (
            &["--out", o],
            &[("JOB_COMPLETION_INDEX", "1")],
            "--shards N",
        ),
        (&["--shard", "0/2"], &[], "--shard needs --out"),
    ];
    for (args, env, expect) in cases {
        let mut a = vec!["trace", "cornell", "-n", "100"];
        a.extend(args);
        let (code, _, err) = run(&a, env);
        assert_ne!(code, 0, "{args:?}");
        assert!(err.contains(expect), "{args:?}: {err}");
        assert!(!out.exists());
    }
}
