//! Sharded tracing is exact: the shards of a run, merged, give the whole run's
//! map checksum; and merge refuses every bad input, leaving nothing at --out.

use adaptive_pm::embree::{thread_pool, CommittedScene, Device};
use adaptive_pm::engine::{Budget, Mode, Shard, TraceConfig, TraceOutput, Tracer};
use adaptive_pm::photon_file::{
    canonical_frame, merge, photons_checksum, scene_hash, write_photons, ShardInfo,
};
use adaptive_pm::scene::Scene;
use std::path::{Path, PathBuf};

fn gallery() -> Scene {
    Scene::open(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/gallery.gltf")).unwrap()
}

fn cfg(mode: Mode, n_max: u64, shard: Shard) -> TraceConfig {
    let mut c = TraceConfig::new(mode, Budget::NMax(n_max));
    c.seed = 7;
    c.shard = shard;
    c
}

/// Writes `out` as shard `cfg.shard` of a run to `path`.
fn write(path: &Path, scene: &Scene, cfg: &TraceConfig, out: &TraceOutput) {
    let info = ShardInfo {
        scene_hash: scene_hash(scene),
        frame: canonical_frame(scene, &out.plans),
        emitted: out.plans.iter().map(|p| cfg.shard.len_of(p.photons)).sum(),
        emitted_total: out.plans.iter().map(|p| p.photons).sum(),
        budget_bound: out.report.budget_bound,
        kernels: out.report.kernels,
        math: out.report.math,
    };
    write_photons(path, cfg, &info, &out.photons).unwrap();
}

/// Traces every shard of `n` into `dir`, returns their paths.
fn shard_files(
    tracer: &Tracer<CommittedScene>,
    scene: &Scene,
    base: &TraceConfig,
    n: u32,
    dir: &Path,
) -> Vec<PathBuf> {
    (0..n)
        .map(|i| {
            let mut c = base.clone();
            c.shard = Shard::new(i, n).unwrap();
            let out = tracer.trace(&c).unwrap();
            assert!(!out.report.budget_bound);
            let path = dir.join(format!("s{i}of{n}.apm"));
            write(&path, scene, &c, &out);
            path
        })
        .collect()
}

/// Nothing but `keep` in `dir`: no output or temporary was left behind.
fn only(dir: &Path, keep: &[PathBuf]) {
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        assert!(keep.contains(&p), "left behind: {}", p.display());
    }
}

#[test]
fn merged_shards_reproduce_the_single_run_checksum() {
    let device = Device::new().unwrap();
    let pool = thread_pool(0).unwrap();
    for (name, scene) in [
        ("cornell", Scene::cornell().unwrap()),
        ("gallery", gallery()),
    ] {
        let tracer = Tracer::new(scene.clone().commit(&device).unwrap());
        for mode in [Mode::Classic, Mode::Adaptive] {
            let base = cfg(mode, 2000, Shard::WHOLE);
            let whole = pool.install(|| tracer.trace(&base)).unwrap();
            assert!(!whole.report.budget_bound);
            assert!(canonical_frame(&scene, &whole.plans).matches(&whole.frame));
            let expected = photons_checksum(&whole.photons, &whole.frame);
            for n in [1u32, 2, 3, 7] {
                let dir = tempfile::tempdir().unwrap();
                let files = pool.install(|| shard_files(&tracer, &scene, &base, n, dir.path()));
                // Any order of the inputs.
                let mut inputs = files.clone();
                inputs.reverse();
                let out = dir.path().join("map.apm");
                let m = merge(&inputs, &out).unwrap();
                assert_eq!(m.checksum, expected, "{name} {mode:?} N = {n}");
                assert_eq!(m.header.photons as usize, whole.photons.len());
                assert_eq!(m.header.emitted, whole.report.emitted);
                // The shards' photons are the whole run's, as a multiset of records.
                if n == 3 {
                    let mut all: Vec<_> = Vec::new();
                    for i in 0..n {
                        let mut c = base.clone();
                        c.shard = Shard::new(i, n).unwrap();
                        all.extend(pool.install(|| tracer.trace(&c)).unwrap().records());
                    }
                    let key = |r: &adaptive_pm::photon_map::PhotonRecord| {
                        let b = |v: glam::Vec3| v.to_array().map(f32::to_bits);
                        (b(r.position), b(r.power), b(r.direction), r.depth)
                    };
                    let mut a: Vec<_> = all.iter().map(key).collect();
                    let mut w: Vec<_> = whole.records().iter().map(key).collect();
                    a.sort_unstable();
                    w.sort_unstable();
                    assert!(a == w, "{name} {mode:?}: shard records differ bitwise");
                }
            }
        }
    }
}

#[test]
fn density_control_refuses_to_shard() {
    let e = cfg(Mode::Density, 1000, Shard::new(0, 2).unwrap())
        .validate()
        .unwrap_err();
    assert!(
        e.to_string().contains("density control cannot be sharded"),
        "{e}"
    );
    assert!(cfg(Mode::Density, 1000, Shard::WHOLE).validate().is_ok());
}

#[test]
fn shards_fit_a_budget_the_whole_run_exceeds() {
    let scene = Scene::cornell().unwrap();
    let device = Device::new().unwrap();
    let pool = thread_pool(0).unwrap();
    let tracer = Tracer::new(scene.clone().commit(&device).unwrap());
    let base = cfg(Mode::Classic, 20_000, Shard::WHOLE);
    let whole = pool.install(|| tracer.trace(&base)).unwrap();
    let expected = photons_checksum(&whole.photons, &whole.frame);
    // A budget for about a third of the whole map: the whole run is refused (or bound).
    let bytes = adaptive_pm::engine::tracer::BYTES_PER_STORED_PHOTON;
    let mut small = base.clone();
    small.memory_budget = Some(whole.photons.len() as u64 / 3 * bytes);
    match pool.install(|| tracer.trace(&small)) {
        Err(adaptive_pm::Error::Budget { .. }) => {}
        Ok(bound) => assert!(bound.report.budget_bound),
        Err(e) => panic!("{e}"),
    }
    let dir = tempfile::tempdir().unwrap();
    let files = pool.install(|| shard_files(&tracer, &scene, &small, 5, dir.path()));
    let m = merge(&files, &dir.path().join("map.apm")).unwrap();
    assert_eq!(m.checksum, expected);
}

/// Shards of one run, plus files for every bad case.
struct Bad {
    dir: tempfile::TempDir,
    good: Vec<PathBuf>,
}

fn bad_cases() -> Bad {
    let scene = Scene::cornell().unwrap();
    let device = Device::new().unwrap();
    let pool = thread_pool(0).unwrap();
    let tracer = Tracer::new(scene.clone().commit(&device).unwrap());
    let dir = tempfile::tempdir().unwrap();
    let base = cfg(Mode::Adaptive, 500, Shard::WHOLE);
    let good = pool.install(|| shard_files(&tracer, &scene, &base, 3, dir.path()));
    // Shard 1 of another seed, and of another scene (cos^4 light).
    let mut other = base.clone();
    other.seed = 8;
    other.shard = Shard::new(1, 3).unwrap();
    let out = pool.install(|| tracer.trace(&other)).unwrap();
    write(&dir.path().join("seed8.apm"), &scene, &other, &out);
    let mut sharp = Scene::cornell().unwrap();
    sharp.set_cosn(adaptive_pm::emitter::CosN::new(4.0).unwrap());
    let t2 = Tracer::new(sharp.clone().commit(&device).unwrap());
    let mut c = base.clone();
    c.shard = Shard::new(1, 3).unwrap();
    let out = pool.install(|| t2.trace(&c)).unwrap();
    write(&dir.path().join("sharp.apm"), &sharp, &c, &out);
    Bad { dir, good }
}

fn refused(inputs: &[PathBuf], dir: &Path, expect: &str) {
    let out = dir.join("merged.apm");
    let e = merge(inputs, &out).unwrap_err().to_string();
    assert!(e.contains(expect), "expected `{expect}` in: {e}");
    assert!(!out.exists());
    let names: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        !names.iter().any(|n| n.contains("merged")),
        "left: {names:?}"
    );
}

#[test]
fn merge_refuses_every_bad_case_and_leaves_nothing() {
    let b = bad_cases();
    let d = b.dir.path();
    let g = &b.good;
    let with = |i: usize, p: PathBuf| {
        let mut v = g.clone();
        v[i] = p;
        v
    };
    refused(&with(1, d.join("sharp.apm")), d, "different scenes");
    refused(&with(1, d.join("seed8.apm")), d, "different settings");
    refused(&g[..2], d, "missing shard(s) 2 of 3");
    refused(&[g.clone(), vec![g[0].clone()]].concat(), d, "given twice");
    refused(&[], d, "no shard given");
    // Truncated: the last photon cut off.
    let t = d.join("truncated.apm");
    let bytes = std::fs::read(&g[2]).unwrap();
    std::fs::write(&t, &bytes[..bytes.len() - 20]).unwrap();
    refused(&with(2, t), d, "truncated");
    // One bit flipped in a photon, then in the header.
    for (at, name) in [(4096 + 5, "photon.apm"), (3000, "header.apm")] {
        let mut c = bytes.clone();
        c[at] ^= 0x10;
        let p = d.join(name);
        std::fs::write(&p, &c).unwrap();
        refused(&with(2, p), d, "checksum mismatch");
    }
    // Not a photon file at all.
    let junk = d.join("junk.apm");
    std::fs::write(&junk, vec![7u8; 5000]).unwrap();
    refused(&with(0, junk), d, "bad magic");
    // The good set still merges.
    let out = d.join("ok.apm");
    merge(g, &out).unwrap();
    let mut keep = g.clone();
    keep.extend(
        [
            "seed8",
            "sharp",
            "truncated",
            "photon",
            "header",
            "junk",
            "ok",
        ]
        .map(|n| d.join(format!("{n}.apm"))),
    );
    only(d, &keep);
}
