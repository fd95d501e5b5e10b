//! The fraction of light a GGX surface under Schlick's Fresnel reflects at
//! its first facet, tabulated once per process over the incident cosine and
//! the roughness: what the glTF BRDF's energy-conserving diffuse coupling
//! needs at every evaluation (after Kulla and Conty 2017, *Revisiting
//! Physically Based Shading at Imageworks*, one of the couplings the glTF
//! specification's Appendix B points to).
//!
//! `E_F(mu; alpha, f0, f90) = f0 + (f90 - f0) W(mu, alpha)`, with `W` the mean
//! Schlick weight of the visible normals ([`LobeEnergy::schlick`]) at the
//! nodes, bilinear between them. The hemispherical average
//! `E_avg = 2 integral E_F(mu) mu dmu` is that of the interpolated table
//! itself (exact per segment, linear in roughness between the nodes), so a
//! coupling built from both conserves energy to the rounding of the sums,
//! whatever the table's own error.

use super::ggx::{Ggx, LobeEnergy};
use glam::Vec3;
use std::sync::OnceLock;

/// Nodes in the incident cosine, uniform over [0, 1].
const MU_NODES: usize = 32;
/// Nodes in sqrt(alpha), uniform over [sqrt(MIN_ALPHA), 1].
const ROUGH_NODES: usize = 24;
/// The smallest alpha tabulated (the models' lower bound).
const MIN_ALPHA: f32 = 1e-3;
/// The cosine the node at `mu = 0` is computed at (just above the horizon).
const GRAZING: f32 = 1e-4;

struct Table {
    /// `W` per node, `[rough * MU_NODES + mu]`.
    w: Vec<f32>,
    /// `2 integral W mu dmu` per roughness node.
    avg: Vec<f32>,
}

fn table() -> &'static Table {
    static TABLE: OnceLock<Table> = OnceLock::new();
    TABLE.get_or_init(build)
}

fn rough_at(j: usize) -> f32 {
    let r0 = MIN_ALPHA.sqrt();
    r0 + (1.0 - r0) * j as f32 / (ROUGH_NODES - 1) as f32
}

fn build() -> Table {
    let mut w = Vec::with_capacity(ROUGH_NODES * MU_NODES);
    for j in 0..ROUGH_NODES {
        let r = rough_at(j);
        let ggx = Ggx { alpha: r * r };
        for i in 0..MU_NODES {
            let mu = (i as f32 / (MU_NODES - 1) as f32).max(GRAZING);
            let wi = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
            let LobeEnergy { schlick, .. } = ggx.lobe_energy(wi);
            w.push(schlick);
        }
    }
    let avg = w.chunks(MU_NODES).map(hemispherical_average).collect();
    Table { w, avg }
}

/// `2 integral e(mu) mu dmu` of the piecewise-linear `e` over the nodes:
/// on a segment from `a` to `b = a + h` with values `p`, `q`, the integral
/// of the line times `mu` is `h (p (2a + b) + q (a + 2b)) / 6`.
fn hemispherical_average(e: &[f32]) -> f32 {
    let h = 1.0 / (MU_NODES - 1) as f64;
    let sum: f64 = (0..MU_NODES - 1)
        .map(|i| {
            let (a, b) = (i as f64 * h, (i + 1) as f64 * h);
            let (p, q) = (f64::from(e[i]), f64::from(e[i + 1]));
            h * (p * (2.0 * a + b) + q * (a + 2.0 * b)) / 6.0
        })
        .sum();
    (2.0 * sum) as f32
}

/// The roughness node below `alpha` and the weight of the one above.
fn rough_cell(alpha: f32) -> (usize, f32) {
    let r0 = MIN_ALPHA.sqrt();
    let x = (alpha.clamp(MIN_ALPHA, 1.0).sqrt() - r0) / (1.0 - r0) * (ROUGH_NODES - 1) as f32;
    let j = (x as usize).min(ROUGH_NODES - 2);
    (j, (x - j as f32).clamp(0.0, 1.0))
}

/// `W(mu, alpha)`: the mean Schlick weight `(1 - |wi.m|)^5` of the normals
/// visible from cosine `mu` on a GGX surface of `alpha`. Schlick's Fresnel
/// `f0 + (f90 - f0) w` is linear in the weight, so the facets reflect
/// `E_F = f0 + (f90 - f0) W` of the light at first contact, for any `f0`
/// and `f90` (per channel when `f0` is coloured); the rest enters the
/// surface.
pub(crate) fn schlick_energy_weight(mu: f32, alpha: f32) -> f32 {
    let t = table();
    let (j, v) = rough_cell(alpha);
    let x = mu.clamp(0.0, 1.0) * (MU_NODES - 1) as f32;
    let i = (x as usize).min(MU_NODES - 2);
    let u = x - i as f32;
    let row = |j: usize| {
        let k = j * MU_NODES + i;
        t.w[k] + (t.w[k + 1] - t.w[k]) * u
    };
    row(j) + (row(j + 1) - row(j)) * v
}

/// `2 integral W(mu) mu dmu`, exactly for the interpolated table: `E_avg =
/// f0 + (f90 - f0)` times it.
pub(crate) fn average_schlick_weight(alpha: f32) -> f32 {
    let t = table();
    let (j, v) = rough_cell(alpha);
    t.avg[j] + (t.avg[j + 1] - t.avg[j]) * v
}

/// `E_F(mu; alpha, f0)` with `f90 = 1`.
#[cfg(test)]
fn fresnel_energy(mu: f32, alpha: f32, f0: f32) -> f32 {
    f0 + (1.0 - f0) * schlick_energy_weight(mu, alpha)
}

/// `E_avg(alpha, f0) = 2 integral fresnel_energy(mu) mu dmu` with `f90 = 1`.
#[cfg(test)]
fn average_fresnel_energy(alpha: f32, f0: f32) -> f32 {
    f0 + (1.0 - f0) * average_schlick_weight(alpha)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_smooth_surface_reflects_what_schlick_says() {
        // alpha -> 0: every visible normal is the surface's.
        for mu in [1.0f32, 0.7, 0.3] {
            let want = 0.04 + 0.96 * (1.0 - mu).powi(5);
            let got = fresnel_energy(mu, MIN_ALPHA, 0.04);
            assert!((got - want).abs() < 2e-3, "mu={mu}: {got} vs {want}");
        }
        // 2 integral (1 - mu)^5 mu dmu = 2 B(2, 6) = 1/21.
        let want = 0.04 + 0.96 / 21.0;
        assert!((average_fresnel_energy(MIN_ALPHA, 0.04) - want).abs() < 2e-3);
        assert_eq!(fresnel_energy(0.3, 0.5, 1.0), 1.0);
    }

    #[test]
    fn the_table_matches_the_quadrature_between_nodes() {
        for (mu, alpha) in [(0.55f32, 0.2f32), (0.13, 0.6), (0.9, 0.05), (0.02, 1.0)] {
            let wi = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
            let w = Ggx { alpha }.lobe_energy(wi).schlick;
            let want = 0.04 + 0.96 * w;
            let got = fresnel_energy(mu, alpha, 0.04);
            assert!((got - want).abs() < 5e-3, "{mu} {alpha}: {got} vs {want}");
        }
    }

    #[test]
    fn the_average_is_the_interpolants_integral() {
        // A fine midpoint rule over the interpolated table.
        for alpha in [0.01f32, 0.3, 0.77, 1.0] {
            let n = 20_000;
            let s: f64 = (0..n)
                .map(|k| {
                    let mu = (k as f64 + 0.5) / n as f64;
                    2.0 * f64::from(fresnel_energy(mu as f32, alpha, 0.0)) * mu / n as f64
                })
                .sum();
            let got = f64::from(average_fresnel_energy(alpha, 0.0));
            assert!((got - s).abs() < 1e-5, "alpha={alpha}: {got} vs {s}");
        }
    }
}
