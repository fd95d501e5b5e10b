//! Importance in the adaptive counts (docs/method.md, "Importance in the
//! counts"): the factor `alpha_I` at a hit and, through pilot photons, at
//! emission, and the rule that photons are stored only where they are read.
//!
//! `alpha_I(x) = clamp(A(x) / A_ref, ALPHA_I_FLOOR, ALPHA_I_MAX)`, with `A`
//! the importance grid's adjoint (what is read at `x` plus what camera
//! paths bring there from later bounces: the path's *future* contribution,
//! as ADRRS and EARS estimate it) and `A_ref` the adjoint where the lights'
//! photons first land (the mean over pilot photons, weighted by the lights'
//! power). At a hit the paper's `s` and the classic survival `r` both take
//! it, so `m = alpha_I max(s, r)`: since the paper's `s` follows the
//! photon's power, `m` follows power times adjoint over a reference, ADRRS's
//! weight window. A photon where little it does will be seen is rouletted,
//! one that reached a seen place is split more than the paper would.
//! Children carry `power * weight / m` as before, so the map stays
//! unbiased; the floor keeps every survival probability above
//! `ALPHA_I_FLOOR r`, never 0, so a photon in an unseen place that does
//! reach a seen one later is not lost, only made rarer and heavier.

use super::ImportanceGrid;
use crate::raycast::{Ray, RayCaster};
use crate::rng::{hash2, Rng};
use crate::sampling::luminance;
use crate::scene::Scene;
use glam::Vec3;

/// The least `alpha_I`: survival in an unseen place is at least this times
/// the classic survival, so no path is cut off for good.
pub const ALPHA_I_FLOOR: f32 = 1.0 / 16.0;

/// The largest `alpha_I` at a hit: a photon in a seen place splits into at
/// most this many times the paper's count (the wave's split bound counts
/// it, so the memory budget holds).
pub const ALPHA_I_MAX: f32 = 8.0;

/// Pilot photons per light that set `A_ref` and each light's emission
/// `alpha_I` (the mean adjoint at their first hits).
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
    /// The counts' view of `grid` with the reference adjoint `reference`
    /// (none positive: the mean adjoint of the read cells).
    pub fn new(grid: &'a ImportanceGrid, reference: f32) -> Self {
        let r = if reference > 0.0 {
            reference
        } else {
            grid.adjoint_reference()
        };
        ImportanceCounts {
            grid,
            inv_ref: if r > 0.0 { 1.0 / r } else { 0.0 },
        }
    }

    /// `alpha_I` at a non-specular hit `x`, `n` the normal on the side the
    /// photon arrives from.
    pub fn alpha_i(&self, x: Vec3, n: Vec3) -> f32 {
        (self.grid.adjoint(x, n) * self.inv_ref).clamp(ALPHA_I_FLOOR, ALPHA_I_MAX)
    }

    /// Whether a photon at `x` is stored: only within the render's kernel
    /// radius of a read cell ([`ImportanceGrid::within_reach`]).
    pub fn stores(&self, x: Vec3) -> bool {
        self.grid.within_reach(x)
    }

    /// A light's emission `alpha_I` from its pilot photons' mean adjoint:
    /// `clamp(mean / A_ref, ALPHA_I_FLOOR, 1)` (at most the paper's count;
    /// 1 when every pilot photon met a mirror or glass first).
    pub fn emission_alpha(&self, mean_adjoint: Option<f64>) -> f32 {
        mean_adjoint.map_or(1.0, |m| {
            ((m * f64::from(self.inv_ref)) as f32).clamp(ALPHA_I_FLOOR, 1.0)
        })
    }
}

/// Each light's mean adjoint at the first hits of [`PILOT_PHOTONS`] pilot
/// photons: 0 for one that escapes, none counted for one whose first hit
/// is specular (it goes on: its adjoint is not where it stands). `None`
/// when every pilot met a specular surface.
pub fn pilot_adjoints(
    grid: &ImportanceGrid,
    scene: &Scene,
    caster: &dyn RayCaster,
    seed: u64,
) -> Vec<Option<f64>> {
    let eps = scene.ray_epsilon();
    let pilot = hash2(seed, PILOT_SALT);
    let first_hit = |ray: &Ray| -> Option<f64> {
        let Some(h) = caster.intersect(ray) else {
            return Some(0.0);
        };
        let material = scene.materials().get(h.material as usize)?;
        (!material.brdf.is_specular())
            .then(|| f64::from(grid.adjoint(ray.at(h.t), h.facing(ray.dir))))
    };
    scene
        .lights()
        .iter()
        .enumerate()
        .map(|(l, light)| {
            let key = hash2(pilot, l as u64);
            let (mut sum, mut count) = (0.0f64, 0u64);
            for i in 0..PILOT_PHOTONS {
                let mut rng = Rng::new(hash2(key, i));
                let e = light.sample(rng.next_f32(), rng.next_2d(), rng.next_2d());
                let origin = e.origin + e.normal.unwrap_or_default() * eps;
                if let Some(a) = first_hit(&Ray::new(origin, e.direction)) {
                    sum += a;
                    count += 1;
                }
            }
            (count > 0).then(|| sum / count as f64)
        })
        .collect()
}

/// `A_ref`: the lights' pilot means weighted by their power's luminance
/// (0 when no light has one, or none is positive).
pub fn reference_adjoint(scene: &Scene, means: &[Option<f64>]) -> f32 {
    let (mut sum, mut weight) = (0.0f64, 0.0f64);
    for (light, m) in scene.lights().iter().zip(means) {
        if let Some(m) = m {
            let w = f64::from(luminance(light.power()).max(0.0));
            sum += w * m;
            weight += w;
        }
    }
    if weight > 0.0 {
        (sum / weight) as f32
    } else {
        0.0
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
    let (scene, caster) = (prepared.scene(), prepared.caster());
    let means = pilot_adjoints(&grid, scene, caster, seed);
    let reference = reference_adjoint(scene, &means);
    let counts = ImportanceCounts::new(&grid, reference);
    let alphas: Vec<f32> = means.iter().map(|&m| counts.emission_alpha(m)).collect();
    for (plan, &a) in plans.iter_mut().zip(&alphas) {
        plan.photons = scaled_photons(plan.photons, a);
    }
    let report = crate::engine::report::ImportanceReport {
        pass_s: start.elapsed().as_secs_f64(),
        cells: grid.len(),
        emission_alpha_i: alphas,
        reference_adjoint: reference,
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
