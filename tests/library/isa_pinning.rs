//! Embree's kernel set, pinned: the photons do not depend on the CPU.
//!
//! Embree runs the widest kernel set the CPU has unless one is pinned, and
//! the sets give other hits, hence other photons, from the same seed. With a
//! set pinned, the map is a function of the scene, the settings and the set
//! alone: the AVX2 checksums below were first recorded on an AVX2-only AMD
//! EPYC and are reproduced with `avx2` pinned on an AVX-512 CPU.

use adaptive_pm::embree::Device;
use adaptive_pm::engine::{Budget, Mode, Shard, TraceConfig, TraceOutput, Tracer};
use adaptive_pm::isa::Isa;
use adaptive_pm::photon_file::{
    canonical_frame, merge, photons_checksum, scene_hash, write_photons, PhotonReader, ShardInfo,
};
use adaptive_pm::scene::Scene;
use std::path::{Path, PathBuf};

fn trace(isa: Isa, mode: Mode, n_max: u64, shard: Shard) -> (Scene, TraceConfig, TraceOutput) {
    let scene = Scene::cornell().unwrap();
    let device = Device::with_isa(isa).unwrap();
    assert_eq!(device.isa(), Some(isa));
    let tracer = Tracer::new(scene.clone().commit(&device).unwrap());
    let mut cfg = TraceConfig::new(mode, Budget::NMax(n_max));
    cfg.shard = shard;
    let out = tracer.trace(&cfg).unwrap();
    assert_eq!(out.report.kernels.map(|k| k.isa), Some(isa));
    (scene, cfg, out)
}

fn checksum(out: &TraceOutput) -> u64 {
    photons_checksum(&out.photons, &out.frame)
}

/// The Cornell box's maps at N_MAX = 3e5 with the AVX2 kernels pinned, as
/// `trace cornell --mode classic|adaptive --n-max 300000 --embree-isa avx2`
/// prints them on any x86-64 host with AVX2. A change that moves them
/// changes every map: record the new values here and in
/// `docs/determinism.md`.
#[test]
fn pinned_avx2_maps_have_the_recorded_checksums() {
    if !Isa::Avx2.is_supported() {
        eprintln!("skipped: this CPU has no AVX2");
        return;
    }
    for (mode, expected) in [
        (Mode::Classic, 0x0ac1_0d16_ca0a_2832_u64),
        (Mode::Adaptive, 0x48b8_7e0d_872d_59cf),
    ] {
        let (_, _, out) = trace(Isa::Avx2, mode, 300_000, Shard::WHOLE);
        assert_eq!(
            checksum(&out),
            expected,
            "{mode:?}: {:016x}, recorded {expected:016x}",
            checksum(&out)
        );
    }
}

/// Every set this CPU runs traces a map that is the same on 1 and 2
/// threads; the sets themselves may differ from each other (they do from
/// AVX on, on the machines of this project).
#[test]
fn every_supported_set_is_deterministic_across_threads() {
    for isa in Isa::supported() {
        let sums: Vec<u64> = [1, 2]
            .into_iter()
            .map(|threads| {
                let pool = adaptive_pm::embree::thread_pool(threads).unwrap();
                pool.install(|| checksum(&trace(isa, Mode::Adaptive, 20_000, Shard::WHOLE).2))
            })
            .collect();
        assert_eq!(sums[0], sums[1], "{isa}: 1 and 2 threads differ");
        eprintln!("{isa}: {:016x}", sums[0]);
    }
}

fn write(dir: &Path, isa: Isa, index: u32) -> PathBuf {
    let shard = Shard::new(index, 2).unwrap();
    let (scene, cfg, out) = trace(isa, Mode::Adaptive, 10_000, shard);
    let info = ShardInfo {
        scene_hash: scene_hash(&scene),
        frame: canonical_frame(&scene, &out.plans),
        emitted: out.plans.iter().map(|p| shard.len_of(p.photons)).sum(),
        emitted_total: out.plans.iter().map(|p| p.photons).sum(),
        budget_bound: out.report.budget_bound,
        kernels: out.report.kernels,
        math: out.report.math,
    };
    let path = dir.join(format!("{isa}-{index}.apm"));
    write_photons(&path, &cfg, &info, &out.photons).unwrap();
    path
}

/// A photon file records its kernel set, and shards of two sets are refused
/// by merge with a message that says why; shards of one set merge.
#[test]
fn merge_refuses_shards_of_different_kernel_sets() {
    let sets = Isa::supported();
    let (a, b) = (sets[0], *sets.last().unwrap());
    let dir = tempfile::tempdir().unwrap();
    let a0 = write(dir.path(), a, 0);
    let reader = PhotonReader::open(&a0).unwrap();
    assert_eq!(reader.header().settings.embree_isa, a.code());
    drop(reader);
    let a1 = write(dir.path(), a, 1);
    merge(&[a0.clone(), a1], &dir.path().join("same.apm")).unwrap();
    if a == b {
        eprintln!("only one kernel set on this CPU: the refusal is not exercised");
        return;
    }
    let b1 = write(dir.path(), b, 1);
    let out = dir.path().join("mixed.apm");
    let e = merge(&[a0, b1], &out).unwrap_err().to_string();
    assert!(
        e.contains("kernel") && e.contains(a.name()) && e.contains(b.name()),
        "{e}"
    );
    assert!(!out.exists());
}

/// Names Embree would take silently (it runs SSE2 for an unknown one) and
/// sets the CPU lacks (it would crash on them) are refused when the device
/// is made.
#[test]
fn bad_kernel_sets_are_refused_before_embree_sees_them() {
    for config in ["isa=avx512skx", "isa=bogus", "verbose=0,max_isa=neon"] {
        let e = Device::with_config(config).unwrap_err().to_string();
        assert!(e.contains("unknown kernel set"), "{config}: {e}");
    }
    if let Some(missing) = Isa::ALL.into_iter().find(|i| !i.is_supported()) {
        let e = Device::with_isa(missing).unwrap_err().to_string();
        assert!(e.contains("cannot run"), "{e}");
    }
    let capped = Device::with_config("max_isa=sse4.2").unwrap();
    assert_eq!(capped.isa(), Some(Isa::native().unwrap().min(Isa::Sse42)));
    assert_eq!(Device::with_config("").unwrap().isa(), Isa::native());
}
