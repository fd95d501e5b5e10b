//! Importance in the adaptive counts (docs/method.md, "Importance in the
//! counts"): the factor `alpha_I` at a hit and, through pilot photons, at
//! emission, and the rule that photons are stored only where they are read.
//!
//! `alpha_I(x) = clamp(A(x) / A_ref, ALPHA_I_FLOOR, 1)`, with `A` the
//! importance grid's adjoint (what is read at `x` plus what camera paths
//! bring there from later bounces: the path's *future* contribution, as
//! ADRRS and EARS estimate it) and `A_ref` its mean over the read cells.
//! At a hit the paper's `s` and the classic survival `r` both take it, so
//! `m = alpha_I max(s, r)`: a photon where nothing it does will be seen is
//! rouletted, one where it will be seen keeps the paper's count. Children
//! carry `power * weight / m` as before, so the map stays unbiased; the
//! floor keeps every survival probability above `ALPHA_I_FLOOR r`, never
//! 0, so a photon in an unseen place that does reach a seen one later is
//! not lost, only made rarer and heavier. `alpha_I <= 1` keeps the
//! wave's split bound (`s <= alpha_E N_MAX`) and so the memory budget.

use super::ImportanceGrid;
use crate::raycast::{Ray, RayCaster};
use crate::rng::{hash2, Rng};
use crate::scene::Scene;
use glam::Vec3;

/// The least `alpha_I`: survival in an unseen place is at least this times
/// the classic survival, so no path is cut off for good.
pub const ALPHA_I_FLOOR: f32 = 1.0 / 16.0;

/// Pilot photons per light that set its emission's `alpha_I`: the mean of
/// `alpha_I` at their first hits (2 % noise on a mean of values in
/// `[1/16, 1]`).
pub const PILOT_PHOTONS: u64 = 1024;

/// Salt of the pilot photons' keys: never a traced photon's key.
const PILOT_SALT: u64 = 0x9170_7F07_0000_0001;

/// The importance grid as the tracer reads it.
#[derive(Clone, Copy, Debug)]
pub struct ImportanceCounts<'a> {
    grid: &'a ImportanceGrid,
    inv_ref: f32,
}

impl<'a> ImportanceCounts<'a> {
    /// The counts' view of `grid`.
    pub fn new(grid: &'a ImportanceGrid) -> Self {
        let r = grid.adjoint_reference();
        ImportanceCounts {
            grid,
            inv_ref: if r > 0.0 { 1.0 / r } else { 0.0 },
        }
    }

    /// `alpha_I` at a non-specular hit `x`, `n` the normal on the side the
    /// photon arrives from.
    pub fn alpha_i(&self, x: Vec3, n: Vec3) -> f32 {
        (self.grid.adjoint(x, n) * self.inv_ref).clamp(ALPHA_I_FLOOR, 1.0)
    }

    /// Whether a photon arriving at `x` on the side of `n` is stored: only
    /// in a read cell or next to one.
    pub fn stores(&self, x: Vec3, n: Vec3) -> bool {
        self.grid.near_read(x, n)
    }

    /// Each light's emission `alpha_I`: the mean over [`PILOT_PHOTONS`]
    /// pilot photons of `alpha_I` at their first hit (1 at a specular one,
    /// whose photon goes on; the floor for one that escapes).
    pub fn emission(&self, scene: &Scene, caster: &dyn RayCaster, seed: u64) -> Vec<f32> {
        let eps = scene.ray_epsilon();
        let pilot = hash2(seed, PILOT_SALT);
        (0..scene.lights().len())
            .map(|l| {
                let light = &scene.lights()[l];
                let key = hash2(pilot, l as u64);
                let sum: f64 = (0..PILOT_PHOTONS)
                    .map(|i| {
                        let mut rng = Rng::new(hash2(key, i));
                        let e = light.sample(rng.next_f32(), rng.next_2d(), rng.next_2d());
                        let origin = e.origin + e.normal.unwrap_or_default() * eps;
                        let ray = Ray::new(origin, e.direction);
                        f64::from(self.first_hit_alpha(scene, caster, &ray))
                    })
                    .sum();
                (sum / PILOT_PHOTONS as f64) as f32
            })
            .collect()
    }

    fn first_hit_alpha(&self, scene: &Scene, caster: &dyn RayCaster, ray: &Ray) -> f32 {
        let Some(h) = caster.intersect(ray) else {
            return ALPHA_I_FLOOR;
        };
        let specular = scene
            .materials()
            .get(h.material as usize)
            .is_none_or(|m| m.brdf.is_specular());
        if specular {
            return 1.0;
        }
        self.alpha_i(ray.at(h.t), h.facing(ray.dir))
    }
}

/// `photons` scaled by `alpha`, at least one when there was one: the light's
/// photons carry its power over the new count, so the estimate is unbiased.
pub fn scaled_photons(photons: u64, alpha: f32) -> u64 {
    if photons == 0 {
        0
    } else {
        ((photons as f64 * f64::from(alpha)).round() as u64).max(1)
    }
}

/// The importance pass of a trace, frozen, and the lights' photon counts
/// scaled by their emission `alpha_I`: what the tracer runs before its
/// photons (the whole pass, whatever the photon shard, so that every shard
/// splits as the whole run does).
///
/// # Errors
/// What [`super::importance_pass`] reports.
pub fn prepare<C: RayCaster>(
    prepared: &crate::scene::PreparedScene<C>,
    cfg: &super::ImportanceConfig,
    seed: u64,
    plans: &mut [crate::engine::counts::LightPlan],
) -> crate::Result<(ImportanceGrid, crate::engine::report::ImportanceReport)> {
    let start = std::time::Instant::now();
    let grid = super::importance_pass(prepared, cfg)?.freeze();
    let alphas = ImportanceCounts::new(&grid).emission(prepared.scene(), prepared.caster(), seed);
    for (plan, &a) in plans.iter_mut().zip(&alphas) {
        plan.photons = scaled_photons(plan.photons, a);
    }
    let report = crate::engine::report::ImportanceReport {
        pass_s: start.elapsed().as_secs_f64(),
        cells: grid.len(),
        emission_alpha_i: alphas,
        unread: 0,
    };
    Ok((grid, report))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scaled_counts_keep_a_photon_and_round() {
        assert_eq!(scaled_photons(0, 0.5), 0);
        assert_eq!(scaled_photons(1000, 0.5), 500);
        assert_eq!(scaled_photons(3, ALPHA_I_FLOOR), 1);
        assert_eq!(scaled_photons(1000, 1.0), 1000);
    }
}
