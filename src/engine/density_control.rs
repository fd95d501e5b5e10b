//! Density control (Suykens & Willems, *Density control for photon maps*,
//! EGWR 2000), as RenderPark implements it:
//!
//! - the map under construction is a [`GrowingMap`], queried as it grows;
//! - the current density at a new photon is `k / (pi r^2)` over its `k = 20`
//!   nearest stored photons on the same side of the surface (photons that
//!   arrived on the other side, `direction . n > 0`, are not counted);
//! - the photon is stored with probability 1 when that density is below the
//!   target and 0 above it;
//! - a rejected photon's power is split equally among those `k` neighbours, so
//!   the map's total power is kept.
//!
//! The test is done with one radius query: `r_t = sqrt(k / (pi target))` is the
//! radius at which `k` photons make exactly the target density, so the density
//! is above the target iff `k` same-side photons lie within `r_t`.
//!
//! Photons are offered in the wave's deterministic order, so the result does
//! not depend on the thread count. This pass is sequential, which is the
//! method's cost (the paper's Fig. 7b).

use crate::error::Result;
use crate::photon_map::{GrowingMap, Neighbor, PhotonRecord};
use glam::Vec3;

pub(super) struct DensityControl {
    map: GrowingMap,
    radius: f32,
    k: usize,
    accepted: u64,
    rejected: u64,
    scratch: Vec<Neighbor>,
}

impl DensityControl {
    pub fn new(bounds: (Vec3, Vec3), target: f64, k: usize) -> Result<Self> {
        let radius = (k as f64 / (std::f64::consts::PI * target)).sqrt() as f32;
        // A cell never smaller than 2^-20 of the scene, so the grid stays small.
        let extent = (bounds.1 - bounds.0).max_element().max(f32::MIN_POSITIVE);
        let cell = radius.max(extent * 1e-6);
        Ok(DensityControl {
            map: GrowingMap::new(bounds.0, bounds.1, cell)?,
            radius,
            k,
            accepted: 0,
            rejected: 0,
            scratch: Vec::with_capacity(k),
        })
    }

    pub fn offer(&mut self, records: &[PhotonRecord], normals: &[Vec3]) {
        for (rec, n) in records.iter().zip(normals) {
            self.map
                .nearest_k(rec.position, self.k, self.radius, &mut self.scratch);
            let same_side = self
                .scratch
                .iter()
                .filter(|nb| self.map.photon(nb.index).direction.dot(*n) < 0.0)
                .count();
            if same_side >= self.k {
                let share = rec.power / same_side as f32;
                for nb in &self.scratch {
                    if self.map.photon(nb.index).direction.dot(*n) < 0.0 {
                        self.map.add_power(nb.index, share);
                    }
                }
                self.rejected += 1;
            } else {
                self.map.insert(*rec);
                self.accepted += 1;
            }
        }
    }

    pub fn counts(&self) -> (u64, u64) {
        (self.accepted, self.rejected)
    }

    pub fn into_records(self) -> Vec<PhotonRecord> {
        self.map.into_records()
    }
}
