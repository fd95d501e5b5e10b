//! Ray throughput through Embree: the raw `embree-sys` shim call (the
//! `unsafe` baseline) against the safe wrapper's single-ray and batch paths
//! (both batch kernels), on one thread.
//!
//! Sweep: three scenes (the built-in Cornell box with `bench rays`' incoherent
//! rays: origins area-uniform on the surfaces, cosine directions; a closed box
//! of 12 triangles; the same box with every face tessellated into
//! 2 x 64 x 64 triangles, 49k in all) times ray sets (incoherent: random
//! origins inside, uniform directions, as photon paths are; coherent: a grid
//! of parallel rays, as camera rays are).
//!
//! A second group, `tracer`, puts the photon tracer itself (classic mode,
//! N_MAX = 1e5, one thread, shading and storage included) beside the raw
//! call on incoherent rays of the same scene, both in rays per second: the
//! tracer's share of raw Embree throughput, on the Cornell box, on the same
//! box with every triangle but the light's split into 1024 (30 722
//! triangles) and into 65 536 (1 966 082 triangles): the same photons,
//! dearer rays; and on the gallery.
//!
//! Timed in *thread CPU time* (`CLOCK_THREAD_CPUTIME_ID`) on Linux, not wall
//! time: the development machine runs several jobs on 2 cores and wall-clock
//! runs of the same code varied by 2x. CPU time still counts cache misses
//! caused by neighbours but not time spent descheduled. Other systems fall
//! back to wall time.

use adaptive_pm::embree::{
    set_flush_denormals, thread_pool, BatchKernel, CommittedScene, Device, Ray, SceneBuilder,
};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::rng::Rng;
use adaptive_pm::sampling::spherical_direction;
use adaptive_pm::scene::{PreparedScene, Scene};
use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use embree_sys as sys;
use glam::Vec3;
use std::time::Duration;

#[path = "common/subdivided.rs"]
mod subdivided;
use subdivided::subdivided;

const RAYS: usize = 1 << 16;

/// CPU time consumed by the calling thread.
#[cfg(target_os = "linux")]
fn thread_time() -> Duration {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; the clock id is a constant
    // Linux supports.
    let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    assert_eq!(rc, 0, "clock_gettime(CLOCK_THREAD_CPUTIME_ID) failed");
    Duration::new(ts.tv_sec as u64, ts.tv_nsec as u32)
}

/// Elsewhere: time since the first call (wall time).
#[cfg(not(target_os = "linux"))]
fn thread_time() -> Duration {
    static START: std::sync::OnceLock<std::time::Instant> = std::sync::OnceLock::new();
    START.get_or_init(std::time::Instant::now).elapsed()
}

/// Runs `f` `iters` times and returns the thread time it took.
fn timed<R>(iters: u64, mut f: impl FnMut() -> R) -> Duration {
    let start = thread_time();
    for _ in 0..iters {
        black_box(f());
    }
    thread_time() - start
}

/// The six faces of `[lo, hi]`, each an `n x n` grid of quads, outward wound.
fn add_box(b: &mut SceneBuilder<'_>, lo: Vec3, hi: Vec3, n: u32) {
    for axis in 0..3 {
        for side in 0..2 {
            let (bi, ci) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut positions = Vec::new();
            for j in 0..=n {
                for i in 0..=n {
                    let mut p = if side == 1 { hi } else { lo };
                    p[bi] = lo[bi] + (hi[bi] - lo[bi]) * i as f32 / n as f32;
                    p[ci] = lo[ci] + (hi[ci] - lo[ci]) * j as f32 / n as f32;
                    positions.push(p);
                }
            }
            let mut tris = Vec::new();
            for j in 0..n {
                for i in 0..n {
                    let v = |di: u32, dj: u32| (j + dj) * (n + 1) + i + di;
                    let (a, b2, c, d) = (v(0, 0), v(1, 0), v(1, 1), v(0, 1));
                    if side == 1 {
                        tris.extend([[a, b2, c], [a, c, d]]);
                    } else {
                        tris.extend([[a, c, b2], [a, d, c]]);
                    }
                }
            }
            b.add_triangles(&positions, &tris, (2 * axis + side) as u32)
                .unwrap();
        }
    }
}

fn scene(device: &Device, n: u32) -> CommittedScene {
    let mut b = device.scene_builder().unwrap();
    add_box(&mut b, Vec3::splat(-1.0), Vec3::splat(1.0), n);
    b.commit().unwrap()
}

fn incoherent_rays() -> Vec<Ray> {
    let mut rng = Rng::new(1);
    (0..RAYS)
        .map(|_| {
            let o = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 1.8 - 0.9;
            let [u, v] = rng.next_2d();
            Ray::new(
                o,
                spherical_direction(1.0 - 2.0 * u, std::f32::consts::TAU * v),
            )
        })
        .collect()
}

fn coherent_rays() -> Vec<Ray> {
    let side = (RAYS as f64).sqrt() as usize;
    (0..RAYS)
        .map(|k| {
            let (i, j) = ((k % side) as f32, (k / side) as f32);
            let o = Vec3::new(
                -0.9 + 1.8 * i / side as f32,
                -0.9 + 1.8 * j / side as f32,
                0.9,
            );
            Ray::new(o, Vec3::new(0.1, 0.05, -1.0))
        })
        .collect()
}

/// The baseline: fill `RTCRayHit` by hand and call the shim, count hits.
fn raw(scene: &CommittedScene, rays: &[Ray]) -> usize {
    let mut hits = 0;
    for r in rays {
        let mut rh = sys::RTCRayHit {
            ray: sys::RTCRay {
                org_x: r.origin.x,
                org_y: r.origin.y,
                org_z: r.origin.z,
                tnear: r.tnear,
                dir_x: r.dir.x,
                dir_y: r.dir.y,
                dir_z: r.dir.z,
                time: 0.0,
                tfar: r.tfar,
                mask: u32::MAX,
                id: 0,
                flags: 0,
            },
            ..Default::default()
        };
        rh.hit.geomID = sys::RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID.fill(sys::RTC_INVALID_GEOMETRY_ID);
        // SAFETY: the scene is committed and outlives the call; `rh` is an
        // initialised `RTCRayHit` owned by this thread.
        unsafe { sys::apm_intersect1(scene.raw(), &mut rh) };
        hits += usize::from(rh.hit.geomID != sys::RTC_INVALID_GEOMETRY_ID);
    }
    hits
}

/// `bench rays`' incoherent rays on any scene's surfaces.
fn surface_rays(scene: &Scene) -> Vec<Ray> {
    scene
        .surface_sampler()
        .incoherent_rays(RAYS, 1, scene.ray_epsilon())
}

fn bench_rays(c: &mut Criterion) {
    set_flush_denormals();
    let device = Device::new().unwrap();
    let mut group = c.benchmark_group("rays");
    group.throughput(Throughput::Elements(RAYS as u64));
    group.sample_size(20);
    group.measurement_time(Duration::from_secs(3));
    let cornell = Scene::cornell().unwrap();
    let mut cases = vec![(
        "cornell",
        cornell.embree_geometry(&device).unwrap(),
        vec![("incoherent", surface_rays(&cornell))],
    )];
    for (scene_name, n) in [("box12", 1), ("box49k", 64)] {
        cases.push((
            scene_name,
            scene(&device, n),
            vec![
                ("incoherent", incoherent_rays()),
                ("coherent", coherent_rays()),
            ],
        ));
    }
    for (scene_name, scene, ray_sets) in &cases {
        for (ray_name, rays) in ray_sets {
            let id = |path: &str| BenchmarkId::new(path, format!("{scene_name}/{ray_name}"));
            let mut hits = vec![None; rays.len()];
            group.bench_function(id("raw"), |b| {
                b.iter_custom(|iters| timed(iters, || raw(scene, black_box(rays))))
            });
            group.bench_function(id("single"), |b| {
                b.iter_custom(|iters| {
                    timed(iters, || {
                        black_box(rays)
                            .iter()
                            .filter(|r| scene.intersect(r).is_some())
                            .count()
                    })
                })
            });
            for (name, kernel) in [
                ("batch_single", BatchKernel::Single),
                ("batch_packet8", BatchKernel::Packet8),
                ("batch_packet16", BatchKernel::Packet16),
            ] {
                group.bench_function(id(name), |b| {
                    b.iter_custom(|iters| {
                        timed(iters, || {
                            scene.intersect_batch_with(kernel, black_box(rays), &mut hits);
                            hits.iter().filter(|h| h.is_some()).count()
                        })
                    })
                });
            }
        }
    }
    group.finish();
}

/// The tracer's rays per second against raw Embree on the same scene and thread.
fn bench_tracer(c: &mut Criterion) {
    let device = Device::new().unwrap();
    let pool = thread_pool(1).unwrap();
    let cfg = TraceConfig::new(Mode::Classic, Budget::NMax(100_000));
    let gallery = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/gallery.gltf");
    let mut group = c.benchmark_group("tracer");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(5));
    // The Cornell box (32 triangles); the same box with every triangle but
    // the light's split into 4^5 (30 722 triangles) and into 4^8 (1 966 082
    // triangles): the same photons, dearer rays; and the gallery (988
    // triangles, glossy surfaces, four lights). The tracer's share of raw
    // Embree grows with the cost of a ray.
    let cornell = Scene::cornell().unwrap();
    for (name, scene) in [
        ("cornell_2m", subdivided(&cornell, 8, false)),
        ("cornell_30k", subdivided(&cornell, 5, false)),
        ("cornell", cornell),
        ("gallery", Scene::load(gallery).unwrap()),
    ] {
        let rt = scene.embree_geometry(&device).unwrap();
        let tracer = Tracer::new(PreparedScene::new(scene.clone(), &rt).unwrap());
        // The ray count of a run is fixed by its seed.
        let rays_per_trace = pool.install(|| tracer.trace(&cfg).unwrap().report.rays);
        let rays = surface_rays(&scene);
        group.throughput(Throughput::Elements(rays.len() as u64));
        group.bench_function(format!("raw_{name}_incoherent"), |b| {
            b.iter_custom(|iters| pool.install(|| timed(iters, || raw(&rt, black_box(&rays)))))
        });
        group.throughput(Throughput::Elements(rays_per_trace));
        group.bench_function(format!("classic_trace_{name}"), |b| {
            b.iter_custom(|iters| {
                pool.install(|| {
                    timed(iters, || {
                        tracer.trace(black_box(&cfg)).unwrap().photons.len()
                    })
                })
            })
        });
    }
    group.finish();
}

// No plots: criterion's plotters backend needs a system font, which these
// machines lack (it panicked after the first measurement); the numbers are
// in the terminal and in target/criterion.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench_rays, bench_tracer
}
criterion_main!(benches);
