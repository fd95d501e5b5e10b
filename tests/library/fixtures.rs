//! What several test modules share: a caster of the user's whose answers
//! are Embree's bit for bit, and the CPU's vendor (which recorded checksums
//! depend on below AVX-512).

use adaptive_pm::embree::CommittedScene;
use adaptive_pm::raycast::{Hit, Ray, RayCaster};

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
