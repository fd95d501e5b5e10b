//! A BRDF's `alpha_D` over incident angles, stored compactly.
//!
//! Isotropic BRDFs depend on theta_in only. `theta_in_bins` nodes sit at the
//! cell centres of a uniform grid over [0, 90°]; each holds `alpha_D`
//! quantised on a log scale to a `u16` (`q = round(65535 ln(alpha) /
//! ln(alpha_min))`: 1 is exact, `alpha_min` is exact, relative step
//! `ln(1/alpha_min) / 65535`, 1.1e-4 for the default floor). 64 nodes take
//! 128 bytes, in line with the paper's ~250 bytes per function. A look-up is
//! O(1): one `acos` and a linear interpolation in theta_in between the two
//! nearest nodes (clamped at the ends).

use std::f32::consts::FRAC_PI_2;
use std::time::Duration;

/// `alpha_D(theta_in)` of one BRDF.
#[derive(Clone, Debug, PartialEq)]
pub struct DirectionalityTable {
    q: Box<[u16]>,
    ln_alpha_min: f32,
    alpha_min: f32,
    /// Total time spent in step 1 over all incident angles.
    pub sample_time: Duration,
    /// Total time spent clustering over all incident angles.
    pub cluster_time: Duration,
}

impl DirectionalityTable {
    /// Builds a table from `alpha_D` at the nodes (each clamped to
    /// [`alpha_min`, 1]); at least two nodes.
    pub(crate) fn from_values(
        alphas: &[f32],
        alpha_min: f32,
        sample_time: Duration,
        cluster_time: Duration,
    ) -> Self {
        let ln_min = alpha_min.ln();
        let q = alphas
            .iter()
            .map(|&a| {
                let a = a.clamp(alpha_min, 1.0);
                if a <= alpha_min {
                    u16::MAX
                } else {
                    ((a.ln() / ln_min) * 65535.0).round().clamp(0.0, 65535.0) as u16
                }
            })
            .collect();
        DirectionalityTable {
            q,
            ln_alpha_min: ln_min,
            alpha_min,
            sample_time,
            cluster_time,
        }
    }

    /// The incident angle (radians) of node `k` of `bins`.
    pub fn node_theta(k: usize, bins: usize) -> f32 {
        (k as f32 + 0.5) * FRAC_PI_2 / bins as f32
    }

    /// Number of nodes.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// Always false (a table has at least two nodes).
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// Bytes of the stored values.
    pub fn size_bytes(&self) -> usize {
        self.q.len() * std::mem::size_of::<u16>()
    }

    /// The dequantised value at node `k`.
    pub fn node(&self, k: usize) -> f32 {
        match self.q[k] {
            0 => 1.0,
            u16::MAX => self.alpha_min,
            q => (q as f32 / 65535.0 * self.ln_alpha_min).exp(),
        }
    }

    /// `alpha_D` for an incident direction of cosine `cos_theta_in`, O(1).
    /// Values outside [0, 1] are clamped; NaN reads as normal incidence.
    pub fn alpha_d(&self, cos_theta_in: f32) -> f32 {
        let n = self.q.len();
        let c = if cos_theta_in.is_nan() {
            1.0
        } else {
            cos_theta_in.clamp(0.0, 1.0)
        };
        let x = c.acos() / FRAC_PI_2 * n as f32 - 0.5;
        if x <= 0.0 {
            return self.node(0);
        }
        let k = (x as usize).min(n - 2);
        let t = (x - k as f32).min(1.0);
        let (a, b) = (self.node(k), self.node(k + 1));
        a + (b - a) * t
    }

    /// The values at every node, normal incidence first.
    pub fn values(&self) -> Vec<f32> {
        (0..self.q.len()).map(|k| self.node(k)).collect()
    }
}
