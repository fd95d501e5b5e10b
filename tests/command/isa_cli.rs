//! `--embree-isa` and `ADAPTIVE_PM_EMBREE_ISA` as a user meets them: the
//! JSON says which kernels traced, the flag wins over the variable, a bad
//! name is a clear error, and a sharded run pinned to one set merges to the
//! single run's checksum.

use adaptive_pm::isa::{Isa, ISA_ENV};
use serde_json::Value;
use std::process::{Command, Output};

fn apm(args: &[&str], env: Option<&str>) -> Output {
    let mut c = Command::new(env!("CARGO_BIN_EXE_adaptive-pm"));
    c.args(args).env_remove(ISA_ENV);
    if let Some(v) = env {
        c.env(ISA_ENV, v);
    }
    c.output().expect("the binary runs")
}

fn trace_json(args: &[&str], env: Option<&str>) -> Value {
    let mut all = vec!["trace", "cornell", "--n-max", "4000", "--json"];
    all.extend_from_slice(args);
    let o = apm(&all, env);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    serde_json::from_slice(&o.stdout).unwrap()
}

#[test]
fn the_json_names_the_kernels_and_the_flag_wins_over_the_variable() {
    let native = Isa::native().unwrap();
    assert_eq!(trace_json(&[], None)["embree_isa"], native.name());
    let narrow = Isa::Sse2;
    assert_eq!(trace_json(&[], Some("sse2"))["embree_isa"], narrow.name());
    let flag = trace_json(&["--embree-isa", native.name()], Some("sse2"));
    assert_eq!(flag["embree_isa"], native.name());
    // The same pin, by flag or by variable, is the same map.
    let by_flag = trace_json(&["--embree-isa", "sse2"], None);
    assert_eq!(
        by_flag["checksum"],
        trace_json(&[], Some("SSE2"))["checksum"]
    );
}

#[test]
fn bad_kernel_sets_are_clear_errors() {
    for (args, env) in [
        (vec!["--embree-isa", "avx512skx"], None),
        (vec![], Some("neon")),
    ] {
        let mut all = vec!["trace", "cornell", "--n-max", "1000"];
        all.extend(args);
        let o = apm(&all, env);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success(), "{all:?} {env:?} succeeded");
        assert!(
            err.contains("unknown kernel set") && err.contains("avx2"),
            "{err}"
        );
        assert!(!err.contains("panicked"), "{err}");
    }
    if let Some(missing) = Isa::ALL.into_iter().find(|i| !i.is_supported()) {
        let o = apm(&["trace", "cornell", "--embree-isa", missing.name()], None);
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success() && err.contains("cannot run"), "{err}");
    }
}

/// Two shards pinned to one set merge to the pinned single run's checksum;
/// a shard of another set is refused by `merge`.
#[test]
fn pinned_shards_merge_to_the_pinned_run_and_mixed_ones_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let shard = |isa: &str, i: u32| {
        let path = dir.path().join(format!("{isa}-{i}.apm"));
        let o = apm(
            &[
                "trace",
                "cornell",
                "--n-max",
                "6000",
                "--embree-isa",
                isa,
                "--shard",
                &format!("{i}/2"),
                "--out",
                path.to_str().unwrap(),
            ],
            None,
        );
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        path
    };
    let sets = Isa::supported();
    let (a, b) = (sets[0].name(), sets.last().unwrap().name());
    let merged = dir.path().join("merged.apm");
    let (s0, s1) = (shard(a, 0), shard(a, 1));
    let o = apm(
        &[
            "merge",
            s0.to_str().unwrap(),
            s1.to_str().unwrap(),
            "--out",
            merged.to_str().unwrap(),
            "--json",
        ],
        None,
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m: Value = serde_json::from_slice(&o.stdout).unwrap();
    let whole = apm(
        &[
            "trace",
            "cornell",
            "--n-max",
            "6000",
            "--embree-isa",
            a,
            "--json",
        ],
        None,
    );
    let whole: Value = serde_json::from_slice(&whole.stdout).unwrap();
    assert_eq!(m["checksum"], whole["checksum"], "{m}");
    if a == b {
        return;
    }
    let other = shard(b, 1);
    let out = dir.path().join("mixed.apm");
    let o = apm(
        &[
            "merge",
            s0.to_str().unwrap(),
            other.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ],
        None,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("kernel"), "{err}");
    assert!(!out.exists());
}
