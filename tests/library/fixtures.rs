//! What several test modules share: a caster of the user's whose answers
//! are Embree's bit for bit, the CPU's vendor (which recorded checksums
//! depend on below AVX-512), and one map of a scene rendered and read per
//! pixel (the gather's tests).

use adaptive_pm::embree::{CommittedScene, Device};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::raycast::{Hit, Ray, RayCaster};
use adaptive_pm::render::{render_with, Image, RenderConfig, RenderMaps, RenderStats};
use adaptive_pm::scene::Scene;

/// A caster of the user's: Embree behind the trait's default (one ray at a
/// time) batch methods, so its answers are Embree's bit for bit.
pub struct OneByOne(pub CommittedScene);

impl RayCaster for OneByOne {
    fn intersect(&self, ray: &Ray) -> Option<Hit> {
        self.0.intersect(ray)
    }
    fn occluded(&self, ray: &Ray) -> bool {
        self.0.occluded(ray)
    }
    fn cuts_alpha_masks(&self) -> bool {
        self.0.cuts_alpha_masks()
    }
}

/// The CPU's vendor string (`vendor_id` of /proc/cpuinfo), if readable.
pub fn cpu_vendor() -> Option<String> {
    let info = std::fs::read_to_string("/proc/cpuinfo").ok()?;
    let line = info.lines().find(|l| l.starts_with("vendor_id"))?;
    Some(line.split(':').nth(1)?.trim().to_string())
}

/// The built-in or glTF scene `scene` traced in the adaptive mode at
/// `n_max` (seed 7), with the maps a render reads.
pub fn traced(scene: &str, n_max: u64) -> (Tracer<CommittedScene>, RenderMaps) {
    let scene = Scene::open(scene).unwrap();
    let tracer = Tracer::new(scene.commit(&Device::new().unwrap()).unwrap());
    let mut t = TraceConfig::new(Mode::Adaptive, Budget::NMax(n_max));
    t.seed = 7;
    let out = tracer.trace(&t).unwrap();
    let maps = RenderConfig::new(8, 8).build_maps(out.photons, out.frame);
    (tracer, maps)
}

/// `maps` rendered by `cfg`.
pub fn rendered(
    tracer: &Tracer<CommittedScene>,
    maps: &RenderMaps,
    cfg: &RenderConfig,
) -> (Image, RenderStats) {
    render_with(tracer.prepared(), Some(maps), None, cfg, &|_, _| {}).unwrap()
}

/// Per pixel, the mean over its channels.
pub fn grey(img: &Image) -> Vec<f64> {
    img.pixels
        .iter()
        .map(|p| p.as_dvec3().element_sum() / 3.0)
        .collect()
}
