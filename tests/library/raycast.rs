//! The engine's ray-casting seam: a tracer that owns its scene and can be
//! stored and shared across threads, a caster of the user's own, and the
//! mismatches that must be errors rather than panics.

use crate::fixtures::OneByOne;
use adaptive_pm::embree::{thread_pool, CommittedScene, Device};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::raycast::{Hit, Ray, RayCaster};
use adaptive_pm::render::{render, render_path, PathPart, RenderConfig, View};
use adaptive_pm::scene::{PreparedScene, Scene};
use adaptive_pm::Error;
use std::sync::Arc;

fn checksum(tracer: &Tracer<impl RayCaster>, cfg: &TraceConfig) -> u64 {
    let out = tracer.trace(cfg).unwrap();
    out.into_map().checksum()
}

/// A renderer's struct holding a tracer: compiles only if the tracer is `'static`.
struct Renderer {
    tracer: Arc<Tracer<CommittedScene>>,
}

#[test]
fn a_stored_tracer_traces_from_two_threads_with_the_same_map() {
    let device = Device::new().unwrap();
    let r = Renderer {
        tracer: Arc::new(Tracer::new(
            Scene::cornell().unwrap().commit(&device).unwrap(),
        )),
    };
    let cfg = TraceConfig::new(Mode::Adaptive, Budget::NMax(20_000));
    let pool = thread_pool(1).unwrap();
    let alone = pool.install(|| checksum(&r.tracer, &cfg));
    let sums: Vec<u64> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..2)
            .map(|_| {
                let t = Arc::clone(&r.tracer);
                let cfg = &cfg;
                s.spawn(move || thread_pool(1).unwrap().install(|| checksum(&t, cfg)))
            })
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    assert_eq!(sums, vec![alone, alone]);
    // The analyses are handed on to a new tracer.
    let cache = r.tracer.analysis_cache().expect("analysed");
    let again = Tracer::new(Scene::cornell().unwrap().commit(&device).unwrap()).with_cache(cache);
    assert_eq!(pool.install(|| checksum(&again, &cfg)), alone);
}

#[test]
fn a_user_caster_drives_the_engine_to_the_same_map() {
    let device = Device::new().unwrap();
    let scene = Scene::cornell().unwrap();
    let own = OneByOne(scene.embree_geometry(&device).unwrap());
    let mine = Tracer::new(PreparedScene::new(scene.clone(), own).unwrap());
    let embree = Tracer::new(scene.commit(&device).unwrap());
    let pool = thread_pool(2).unwrap();
    for mode in [Mode::Classic, Mode::Adaptive] {
        let cfg = TraceConfig::new(mode, Budget::NMax(10_000));
        assert_eq!(
            pool.install(|| checksum(&mine, &cfg)),
            pool.install(|| checksum(&embree, &cfg)),
            "{mode:?}"
        );
    }
}

/// A caster that reports a material the scene does not have.
struct BadMaterial(CommittedScene);

impl RayCaster for BadMaterial {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray).map(|h| Hit { material: 42, ..h })
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.0.occluded(ray)
    }
}

#[test]
fn mismatches_are_errors_not_panics() {
    let device = Device::new().unwrap();
    let cornell = Scene::cornell().unwrap();
    let bad = BadMaterial(cornell.embree_geometry(&device).unwrap());
    let tracer = Tracer::new(PreparedScene::new(cornell.clone(), bad).unwrap());
    let e = tracer
        .trace(&TraceConfig::new(Mode::Classic, Budget::NMax(1000)))
        .unwrap_err();
    assert!(matches!(e, Error::InvalidScene(_)), "{e}");
    assert!(e.to_string().contains("material 42"), "{e}");

    // Another scene's Embree geometry: one mesh fewer.
    let n = cornell.meshes().len();
    let other = rebuilt(&cornell, n - 1, |m| m);
    let rt = other.embree_geometry(&device).unwrap();
    let e = PreparedScene::new(cornell.clone(), rt).unwrap_err();
    assert!(matches!(e, Error::InvalidScene(_)), "{e}");
    // Same mesh count, materials swapped.
    let a = cornell.meshes()[0].material;
    let j = (1..n)
        .find(|&j| cornell.meshes()[j].material != a)
        .expect("the Cornell box has several materials");
    let b = cornell.meshes()[j].material;
    let swapped = rebuilt(&cornell, n, |m| {
        if m == a {
            b
        } else if m == b {
            a
        } else {
            m
        }
    });
    let rt = Arc::new(swapped.embree_geometry(&device).unwrap());
    assert!(PreparedScene::new(cornell, Arc::clone(&rt)).is_err());
    assert!(PreparedScene::new(swapped, rt).is_ok());
}

/// An edit of a hit.
type HitEdit = fn(Hit) -> Hit;

/// A caster that breaks the contract one way: Embree's hits, edited.
struct Garbled(CommittedScene, HitEdit);

impl RayCaster for Garbled {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray).map(self.1)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.0.occluded(ray)
    }
}

/// A NaN distance, a normal of zero, a mesh or triangle the scene does not
/// have, a material it does not have: the trace, the photon render and the
/// path tracer each fail with an error naming the hit, never a map or an
/// image quietly missing those photons or pixels.
#[test]
fn hits_that_break_the_contract_fail_the_trace_and_the_render() {
    let device = Device::new().unwrap();
    let cornell = Scene::cornell().unwrap();
    let cases: [(HitEdit, &str); 5] = [
        (|h| Hit { t: f32::NAN, ..h }, "t = NaN"),
        (
            |h| Hit {
                ng: glam::Vec3::ZERO,
                ..h
            },
            "normal",
        ),
        (|h| Hit { geom_id: 999, ..h }, "mesh 999"),
        (
            |h| Hit {
                prim_id: 1 << 30,
                ..h
            },
            "triangle 1073741824",
        ),
        (|h| Hit { material: 42, ..h }, "material 42"),
    ];
    let mut rc = RenderConfig::new(8, 8);
    rc.view = View::DirectOnly;
    for (edit, says) in cases {
        let caster = Garbled(cornell.embree_geometry(&device).unwrap(), edit);
        let tracer = Tracer::new(PreparedScene::new(cornell.clone(), caster).unwrap());
        let e = tracer
            .trace(&TraceConfig::new(Mode::Classic, Budget::NMax(1000)))
            .unwrap_err();
        assert!(
            matches!(e, Error::InvalidScene(_)) && e.to_string().contains(says),
            "{e}"
        );
        let e = render(tracer.prepared(), None, &rc).unwrap_err();
        assert!(e.to_string().contains(says), "photon render: {e}");
        let e = render_path(tracer.prepared(), &rc, PathPart::Full).unwrap_err();
        assert!(e.to_string().contains(says), "path tracer: {e}");
    }
}

/// `src` with its first `meshes` meshes, their materials renamed by `material`.
fn rebuilt(src: &Scene, meshes: usize, material: impl Fn(usize) -> usize) -> Scene {
    let mut scene = Scene::new();
    for m in src.materials() {
        scene.add_material(m.clone());
    }
    for mesh in &src.meshes()[..meshes] {
        let (name, pos, idx) = (
            mesh.name.clone(),
            mesh.positions.clone(),
            mesh.indices.clone(),
        );
        scene
            .add_mesh(name, pos, idx, material(mesh.material))
            .unwrap();
    }
    if let Some(c) = src.camera() {
        scene.set_camera(c).unwrap();
    }
    scene
}
