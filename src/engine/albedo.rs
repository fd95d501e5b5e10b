//! Directional albedo per material, tabulated once per run: the classic
//! survival probability `r = max channel of the albedo` is needed at every
//! hit, and some models integrate it numerically (Cook–Torrance: 256 BRDF
//! evaluations a call), which would dominate tracing.
//!
//! Any `r` in (0, 1] keeps the estimate unbiased (children carry
//! `power * weight / m`), so interpolating the table only changes variance.

use crate::brdf::Brdf;
use glam::Vec3;

/// Table nodes, uniform in `cos(theta_in)` over [0, 1].
pub const ALBEDO_NODES: usize = 33;

/// The albedo of one BRDF over the incident angle.
#[derive(Clone, Debug, PartialEq)]
pub struct AlbedoTable {
    values: Vec<Vec3>,
}

impl AlbedoTable {
    /// Tabulates `brdf.albedo` at [`ALBEDO_NODES`] incident cosines.
    pub fn new(brdf: &Brdf) -> Self {
        let values = (0..ALBEDO_NODES)
            .map(|i| {
                // The node at cos = 0 is taken just above the horizon.
                let c = (i as f32 / (ALBEDO_NODES - 1) as f32).max(1e-3);
                let wi = Vec3::new((1.0 - c * c).max(0.0).sqrt(), 0.0, c);
                brdf.albedo(wi).clamp(Vec3::ZERO, Vec3::ONE)
            })
            .collect();
        AlbedoTable { values }
    }

    /// Linear interpolation at `cos_theta_in` (clamped to [0, 1]).
    #[inline]
    pub fn at(&self, cos_theta_in: f32) -> Vec3 {
        let x = cos_theta_in.clamp(0.0, 1.0) * (ALBEDO_NODES - 1) as f32;
        let i = (x as usize).min(ALBEDO_NODES - 2);
        let t = x - i as f32;
        self.values[i].lerp(self.values[i + 1], t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::brdf::{CookTorrance, Lambert};

    #[test]
    fn table_matches_the_model_between_nodes() {
        let l: Brdf = Lambert::new(Vec3::new(0.2, 0.5, 0.9)).unwrap().into();
        let t = AlbedoTable::new(&l);
        assert!((t.at(0.37) - Vec3::new(0.2, 0.5, 0.9)).abs().max_element() < 1e-6);
        let ct: Brdf = CookTorrance::new(0.3, Vec3::splat(0.9), Vec3::ZERO)
            .unwrap()
            .into();
        let t = AlbedoTable::new(&ct);
        for c in [0.2f32, 0.55, 0.9] {
            let wi = Vec3::new((1.0 - c * c).sqrt(), 0.0, c);
            let exact = ct.albedo(wi);
            // a smooth function of the angle, sampled every 1/32 in cos
            assert!(
                (t.at(c) - exact).abs().max_element() < 0.02,
                "{c}: {} vs {exact}",
                t.at(c)
            );
        }
    }
}
