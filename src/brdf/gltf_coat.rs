//! The clear coat of `KHR_materials_clearcoat` as [`super::GltfPbr`]
//! layers it: a colourless GGX lobe of the coat's roughness under Schlick's
//! Fresnel of `f0 = 0.04` (IOR 1.5), of weight `c` (`clearcoatFactor`), over
//! the base material.
//!
//! ```text
//! coat   = c F_c(|wi.h|) D_c(h) G_c(wi, wo) / (4 cos_i cos_o)
//! T(mu)  = 1 - c E_c(mu)
//! f_r    = coat + T(cos_i) T(cos_o) f_base
//! ```
//! `E_c(mu) = 0.04 + 0.96 W(mu)` is the share of the light arriving at
//! cosine `mu` that the coat's facets reflect at first contact (the table
//! the base's coupling uses, `brdf/ggx_energy.rs`), so `T` is what passes
//! through the coat, on the way in and again on the way out. The
//! extension's informative code weights the base by `1 - c F_c(n.v)` on
//! the viewing side only, which is not reciprocal; this symmetric form is,
//! and conserves energy: the coat reflects at most `c E_c(cos_i)` of the
//! light (its masking loses some) and the base at most what the coat lets
//! through, `T(cos_i)` of it times an albedo at most 1.

use super::ggx::{schlick_weight, Ggx};
use super::ggx_energy::schlick_energy_weight;
use glam::Vec3;

/// The coat's Fresnel reflectance at normal incidence (IOR 1.5).
const COAT_F0: f32 = 0.04;

/// A clear coat: weight and GGX roughness ([`Coat::NONE`]: none).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Coat {
    pub(crate) weight: f32,
    pub(crate) ggx: Ggx,
}

impl Coat {
    /// No coat: the base material alone, bit for bit.
    pub(crate) const NONE: Coat = Coat {
        weight: 0.0,
        ggx: Ggx { alpha: 1.0 },
    };

    pub(crate) fn is_none(&self) -> bool {
        self.weight == 0.0
    }

    /// `(c E_c(mu), T(mu))`: what the coat reflects at first contact, and
    /// what it lets through.
    pub(crate) fn reflected_and_transmitted(&self, mu: f32) -> (f32, f32) {
        let r = self.reflected(mu);
        (r, (1.0 - r).max(0.0))
    }

    /// `c E_c(mu)`: what the coat reflects at first contact.
    fn reflected(&self, mu: f32) -> f32 {
        let w = schlick_energy_weight(mu, self.ggx.alpha);
        self.weight * (COAT_F0 + (1.0 - COAT_F0) * w)
    }

    /// `T(mu) = 1 - c E_c(mu)`: what passes through the coat.
    pub(crate) fn transmitted(&self, mu: f32) -> f32 {
        self.reflected_and_transmitted(mu).1
    }

    /// The coat's lobe (both directions above the horizon).
    pub(crate) fn eval(&self, wi: Vec3, wo: Vec3) -> f32 {
        let Some((lobe, h)) = self.ggx.reflection(wi, wo) else {
            return 0.0;
        };
        let fresnel = COAT_F0 + (1.0 - COAT_F0) * schlick_weight(wi.dot(h));
        self.weight * fresnel * lobe
    }

    /// The coat lobe's directional albedo, `c (f0 E1 + (1 - f0) Ew)` by the
    /// lobe's quadrature.
    pub(crate) fn albedo(&self, wi: Vec3) -> f32 {
        let e = self.ggx.lobe_energy(wi);
        self.weight * (COAT_F0 * e.shadowed + (1.0 - COAT_F0) * e.shadowed_schlick)
    }

    /// `integral e(mu) T(mu) 2 mu dmu`, for a base whose entering share is
    /// `e`: the midpoint rule on 256 cells (the tables are piecewise linear
    /// in `mu` on 31 segments, so the product is smooth within each cell).
    pub(crate) fn cosine_weighted_through(&self, e: impl Fn(f32) -> f32) -> f32 {
        const N: usize = 256;
        let mut sum = 0.0;
        for k in 0..N {
            let mu = (k as f32 + 0.5) / N as f32;
            sum += e(mu) * (self.transmitted(mu) * 2.0 * mu);
        }
        sum / N as f32
    }
}
