//! How many photons: per light at emission, per hit when splitting
//! (docs/method.md, "The three factors" and "Photon counts").
//!
//! - classic and density control: `N_l = N_MAX * P_l / sum P` (luminance of RGB power).
//! - adaptive: `N_l = alpha_E * alpha_A * alpha_D * N_MAX` with `alpha_E = P_l / max P`,
//!   `alpha_A = A_l / max A` (punctual lights: `alpha_A = 1`), `alpha_D` from the
//!   directionality analysis of the emission profile (point lights: 1; spot lights:
//!   the cone's solid angle over 2 pi, a uniform emitter restricted to the cone;
//!   directional lights: `alpha_min`, a delta in direction, which splitting at
//!   emission cannot spread).
//!
//! In every mode a light with positive power emits at least one photon, unless
//! `N_MAX = 0` (Q = 0), which means no photon at all.

use super::config::Mode;
use crate::analysis::AnalysisCache;
use crate::error::Result;
use crate::sampling::luminance;
use crate::scene::{Light, Scene};
use glam::Vec3;

/// The emission of one light.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct LightPlan {
    /// Energy factor (adaptive; 1 otherwise).
    pub alpha_e: f32,
    /// Area factor (adaptive; 1 otherwise).
    pub alpha_a: f32,
    /// Directionality factor (adaptive; 1 otherwise).
    pub alpha_d: f32,
    /// Photons emitted.
    pub photons: u64,
    /// Luminance of the light's power.
    pub power_luminance: f32,
}

/// The per-light photon counts of a run.
///
/// # Errors
/// What the directionality analysis reports for an invalid profile.
pub fn plan_emission(
    scene: &Scene,
    mode: Mode,
    n_max: u64,
    cache: &mut AnalysisCache,
) -> Result<Vec<LightPlan>> {
    let lums: Vec<f64> = scene
        .lights
        .iter()
        .map(|l| luminance(l.power()).max(0.0) as f64)
        .collect();
    let total: f64 = lums.iter().sum();
    let max_lum = lums.iter().cloned().fold(0.0, f64::max);
    let max_area = scene
        .lights
        .iter()
        .filter_map(Light::area)
        .fold(0.0f32, f32::max);
    let at_least_one = |lum: f64, n: f64| -> u64 {
        if n_max == 0 || lum <= 0.0 {
            0
        } else {
            (n.round() as u64).max(1)
        }
    };
    let mut plans = Vec::with_capacity(scene.lights.len());
    for (light, &lum) in scene.lights.iter().zip(&lums) {
        let plan = match mode {
            Mode::Classic | Mode::Density => LightPlan {
                alpha_e: 1.0,
                alpha_a: 1.0,
                alpha_d: 1.0,
                photons: at_least_one(lum, n_max as f64 * lum / total.max(f64::MIN_POSITIVE)),
                power_luminance: lum as f32,
            },
            Mode::Adaptive => {
                let alpha_e = if max_lum > 0.0 {
                    (lum / max_lum) as f32
                } else {
                    0.0
                };
                let alpha_a = match light.area() {
                    Some(a) if max_area > 0.0 => a / max_area,
                    _ => 1.0,
                };
                let alpha_d = match light {
                    Light::Area(a) => cache.emitter(&a.emission.profile)?,
                    Light::Point(_) => 1.0,
                    Light::Spot(s) => (1.0 - s.cos_outer).clamp(cache.params().alpha_min, 1.0),
                    Light::Directional(_) => cache.params().alpha_min,
                };
                let n = alpha_e as f64 * alpha_a as f64 * alpha_d as f64 * n_max as f64;
                LightPlan {
                    alpha_e,
                    alpha_a,
                    alpha_d,
                    photons: at_least_one(lum, n),
                    power_luminance: lum as f32,
                }
            }
        };
        plans.push(plan);
    }
    Ok(plans)
}

/// Power each photon of light `l` carries (before the sample's own weight).
pub fn photon_power(light: &Light, plan: &LightPlan) -> Vec3 {
    if plan.photons == 0 {
        Vec3::ZERO
    } else {
        light.power() / plan.photons as f32
    }
}

/// The expected number of children at a hit: `m = max(s, r)`, capped at `cap`.
/// Returns `m` and whether the cap bound.
///
/// `s = alpha_E(photon) * alpha_D(BRDF, w_in) * N_MAX` is the paper's split
/// count, `r` the classic survival probability. While `s < r` this is Russian
/// roulette; above it, splitting. Every child carries `power * weight / m`, so the
/// estimate is unbiased whatever `m` is.
pub fn expected_children(s: f64, r: f64, cap: u32) -> (f64, bool) {
    let m = s.max(r);
    if m > cap as f64 {
        (cap as f64, true)
    } else {
        (m, false)
    }
}

/// `floor(m)`, plus one with probability `frac(m)`: an integer with mean `m`
/// (`m >= 0`; a negative or NaN `m` gives 0, one above `u32::MAX` gives
/// `u32::MAX`).
pub fn round_stochastic(m: f64, u: f32) -> u32 {
    // A truncating cast is the floor for m >= 0, without `floor` (a libm
    // call on baseline x86-64, at every hit).
    let f = m as u32;
    f.saturating_add(u32::from((u as f64) < m - f as f64))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stochastic_rounding_has_mean_m() {
        for m in [0.0, 0.3, 1.0, 2.75, 17.5] {
            let n = 100_000;
            let sum: u64 = (0..n)
                .map(|i| round_stochastic(m, (i as f32 + 0.5) / n as f32) as u64)
                .sum();
            // a stratified u gives the mean to within 1/n
            assert!((sum as f64 / n as f64 - m).abs() < 2.0 / n as f64, "m={m}");
        }
        for (m, want) in [
            (-0.5, 0),
            (f64::NAN, 0),
            (1e12, u32::MAX),
            (4294967295.5, u32::MAX),
        ] {
            assert_eq!(round_stochastic(m, 0.0), want, "m={m}");
        }
    }

    #[test]
    fn split_rule_hands_over_to_russian_roulette_and_caps() {
        assert_eq!(expected_children(0.1, 0.7, 100), (0.7, false));
        assert_eq!(expected_children(3.5, 0.7, 100), (3.5, false));
        assert_eq!(expected_children(1e9, 0.7, 100), (100.0, true));
    }
}
