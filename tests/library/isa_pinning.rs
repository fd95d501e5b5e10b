//! Embree's kernel set, pinned: the photons do not depend on the CPU.
//!
//! Embree runs the widest kernel set the CPU has unless one is pinned, and
//! the sets give other hits, hence other photons, from the same seed. With a
//! set pinned, the map is a function of the scene, the settings, the set
//! and, below AVX-512, the CPU's vendor: the AVX2 checksums below were first
//! recorded on an AVX2-only AMD EPYC and are reproduced with `avx2` pinned on
//! an AVX-512 one; Intel's differ, and AVX-512's are the same on both.

use crate::fixtures::cpu_vendor;
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

/// The Cornell box's maps at N_MAX = 3e5 (classic, adaptive) with a kernel
/// set pinned, as `trace cornell --mode classic|adaptive --n-max 300000
/// --embree-isa ISA` prints them (`tools/isa_checksums.sh`), by CPU vendor.
/// The AVX-512 maps are the same on Intel and AMD; the SSE and AVX2 ones are
/// not, though each is the same on every CPU of one vendor: those kernels
/// use `rcpps`/`rsqrtps`, whose 12-bit approximations each vendor computes
/// its own way, while AVX-512's `rcp14`/`rsqrt14` are specified exactly
/// (docs/determinism.md). A change that moves them changes every map:
/// record the new values here and in `docs/determinism/isa_checksums.md`.
const RECORDED: [(Option<&str>, Isa, [u64; 2]); 5] = [
    (
        Some("AuthenticAMD"),
        Isa::Sse2,
        [0x9a59_2bd3_6a8f_740f, 0xf633_72ac_b14d_c786],
    ),
    (
        Some("GenuineIntel"),
        Isa::Sse2,
        [0x7e7c_d0f1_c3a4_0b61, 0x62ee_d19f_cd0c_762f],
    ),
    (
        Some("AuthenticAMD"),
        Isa::Avx2,
        [0x0ac1_0d16_ca0a_2832, 0x48b8_7e0d_872d_59cf],
    ),
    (
        Some("GenuineIntel"),
        Isa::Avx2,
        [0x1f58_bfcc_1f0e_bf5a, 0x94dc_e814_7cd6_2450],
    ),
    (
        None,
        Isa::Avx512,
        [0x8118_91c9_451d_cd35, 0x146a_762e_ee2b_d9cd],
    ),
];

#[test]
fn pinned_maps_have_the_recorded_checksums() {
    let vendor = cpu_vendor();
    let mut checked = 0;
    for (who, isa, expected) in RECORDED {
        if !isa.is_supported() || who.is_some_and(|w| vendor.as_deref() != Some(w)) {
            continue;
        }
        for (mode, expected) in [Mode::Classic, Mode::Adaptive].into_iter().zip(expected) {
            let (_, _, out) = trace(isa, mode, 300_000, Shard::WHOLE);
            assert_eq!(
                checksum(&out),
                expected,
                "{isa} {mode:?} on {vendor:?}: {:016x}, recorded {expected:016x}",
                checksum(&out)
            );
            checked += 1;
        }
    }
    eprintln!("{checked} recorded checksums reproduced on {vendor:?}");
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
