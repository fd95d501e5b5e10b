//! Cook–Torrance microfacet reflection: Beckmann distribution, Schlick
//! Fresnel, Torrance–Sparrow V-cavity shadowing, plus an optional diffuse
//! base (used by the glTF mapping for dielectrics).
//!
//! Parameters:
//! - `m`: Beckmann roughness (RMS slope), in [[`CookTorrance::MIN_ROUGHNESS`], 1];
//!   smoother surfaces are [`super::Mirror`]s;
//! - `f0`: Fresnel reflectance at normal incidence (linear RGB, [0, 1]);
//! - `kd`: diffuse base reflectance (linear RGB, [0, 1]; zero for a metal).
//!
//! ```text
//! f_r = kd / pi (1 - F(cos_i)) (1 - F(cos_o))  +  D(h) F(wi.h) G / (4 cos_i cos_o)
//! D(h) = exp(-tan^2 theta_h / m^2) / (pi m^2 cos^4 theta_h)
//! F(c) = f0 + (1 - f0) (1 - c)^5
//! G    = min(1, 2 cos_h cos_o / (wo.h), 2 cos_h cos_i / (wo.h))
//! ```
//! The diffuse base keeps only light the Fresnel term did not reflect, on the
//! way in and on the way out; that keeps the model reciprocal, and the tests
//! check `albedo <= 1` numerically over roughness, `f0` and incidence (it is
//! an approximation of energy conservation, not a proof).
//!
//! Sampling picks the specular lobe with probability
//! `lum(F(cos_i)) / (lum(F(cos_i)) + lum(kd (1 - F(cos_i))))`, and then draws
//! a half vector from `D(h) cos theta_h` (`tan^2 theta_h = -m^2 ln(1 - u)`),
//! whose solid-angle pdf for `wo` is `D cos theta_h / (4 |wo.h|)`; otherwise a
//! cosine-weighted direction. A reflected direction below the horizon is a
//! failed sample (`None`).

use super::phong::check_rgb01;
use super::BrdfSample;
use crate::error::{Error, Result};
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf, luminance};
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// The Cook–Torrance BRDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CookTorrance {
    m: f32,
    f0: Vec3,
    kd: Vec3,
}

/// Schlick's Fresnel approximation per channel.
#[inline]
fn schlick(f0: Vec3, c: f32) -> Vec3 {
    let k = (1.0 - c.clamp(0.0, 1.0)).powi(5);
    f0 + (Vec3::ONE - f0) * k
}

impl CookTorrance {
    /// The smallest roughness accepted: below it the lobe is narrower than f32
    /// directions resolve (about 1e-4 rad); use a mirror instead.
    pub const MIN_ROUGHNESS: f32 = 1e-4;

    /// A Cook–Torrance BRDF.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when `m` is NaN or outside
    /// [[`Self::MIN_ROUGHNESS`], 1], or a reflectance channel is outside [0, 1].
    pub fn new(m: f32, f0: Vec3, kd: Vec3) -> Result<Self> {
        if !(Self::MIN_ROUGHNESS..=1.0).contains(&m) {
            return Err(Error::param(
                "cook-torrance roughness",
                format!("must be in [{}, 1], got {m}", Self::MIN_ROUGHNESS),
            ));
        }
        Ok(CookTorrance {
            m,
            f0: check_rgb01("cook-torrance f0", f0)?,
            kd: check_rgb01("cook-torrance kd", kd)?,
        })
    }

    /// Beckmann roughness.
    pub fn roughness(&self) -> f32 {
        self.m
    }

    /// Fresnel reflectance at normal incidence.
    pub fn f0(&self) -> Vec3 {
        self.f0
    }

    /// Diffuse base reflectance.
    pub fn kd(&self) -> Vec3 {
        self.kd
    }

    /// Beckmann `D(h)`, with `tan^2` from the components (exact near the pole).
    fn d(&self, h: Vec3) -> f32 {
        if h.z <= 0.0 {
            return 0.0;
        }
        let c2 = h.z * h.z;
        let tan2 = (h.x * h.x + h.y * h.y) / c2;
        let m2 = self.m * self.m;
        (-tan2 / m2).exp() / (PI * m2 * c2 * c2)
    }

    fn p_spec(&self, cos_i: f32) -> f32 {
        let f = schlick(self.f0, cos_i);
        super::lobe_share(luminance(f), luminance(self.kd * (Vec3::ONE - f)))
    }

    /// The diffuse base's factor of `wi`, `kd / pi (1 - F(cos_i))`.
    fn diffuse_in(&self, cos_i: f32) -> Vec3 {
        self.kd * FRAC_1_PI * (Vec3::ONE - schlick(self.f0, cos_i))
    }

    /// The specular term, `F G / (4 cos_i cos_o) * D`, from the half vector
    /// `h` and `d = D(h)`, which the pdf needs too.
    fn specular(&self, wi: Vec3, wo: Vec3, h: Vec3, d: f32) -> Vec3 {
        if d == 0.0 {
            return Vec3::ZERO;
        }
        let oh = wo.dot(h).max(1e-8);
        let g = (2.0 * h.z * wo.z / oh).min(2.0 * h.z * wi.z / oh).min(1.0);
        schlick(self.f0, wi.dot(h)) * (d * g / (4.0 * wi.z * wo.z))
    }

    /// [`Self::eval`] above the horizon from `diffuse_in(wi.z)`, `h` and
    /// `D(h)`.
    fn eval_given(&self, diffuse_in: Vec3, wi: Vec3, wo: Vec3, h: Vec3, d: f32) -> Vec3 {
        diffuse_in * (Vec3::ONE - schlick(self.f0, wo.z)) + self.specular(wi, wo, h, d)
    }

    /// [`Self::pdf`] above the horizon from `p_spec(wi.z)`, `h` and `D(h)`.
    fn pdf_given(&self, ps: f32, wo: Vec3, h: Vec3, d: f32) -> f32 {
        let oh = wo.dot(h);
        let spec = if oh > 0.0 { d * h.z / (4.0 * oh) } else { 0.0 };
        ps * spec + (1.0 - ps) * cosine_hemisphere_pdf(wo.z)
    }

    /// Evaluates the BRDF.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (wi + wo).normalize_or_zero();
        self.eval_given(self.diffuse_in(wi.z), wi, wo, h, self.d(h))
    }

    /// This BRDF seen from `wi`, for many pairs and samples from it.
    pub(crate) fn at(&self, wi: Vec3) -> CookTorranceAt<'_> {
        CookTorranceAt {
            b: self,
            wi,
            p_spec: self.p_spec(wi.z),
            diffuse_in: self.diffuse_in(wi.z),
        }
    }

    /// A Beckmann half vector, `pdf(h) = D(h) cos theta_h`.
    fn sample_h(&self, u: [f32; 2]) -> Vec3 {
        let tan2 = -self.m * self.m * (1.0 - u[0]).max(f32::MIN_POSITIVE).ln();
        let t = tan2.sqrt();
        let phi = 2.0 * PI * u[1];
        Vec3::new(t * phi.cos(), t * phi.sin(), 1.0).normalize()
    }

    /// Samples the specular or the diffuse lobe (see the module docs).
    pub fn sample(&self, wi: Vec3, u: [f32; 2]) -> Option<BrdfSample> {
        self.sample_with_f(wi, u).map(|(s, _)| s)
    }

    /// [`Self::sample`] and the value `f(wi, wo)` it was weighted with.
    pub(crate) fn sample_with_f(&self, wi: Vec3, u: [f32; 2]) -> Option<(BrdfSample, Vec3)> {
        if wi.z <= 0.0 {
            return None;
        }
        self.at(wi).sample_with_f(u)
    }

    /// Solid-angle pdf of [`CookTorrance::sample`].
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let h = (wi + wo).normalize_or_zero();
        self.pdf_given(self.p_spec(wi.z), wo, h, self.d(h))
    }

    /// Directional albedo. Diffuse part in closed form
    /// (`kd (1 - F(cos_i)) (1 - f0) 20/21`, since the cosine-weighted mean of
    /// Schlick's `(1 - c)^5` is 1/21); specular part by a 16 x 16 midpoint
    /// quadrature of the half-vector sampler, whose weight
    /// `F G (wo.h) / (cos_i cos_h)` does not contain D and so stays smooth for
    /// every roughness. 256 evaluations: cache it if it is needed per hit.
    pub fn albedo(&self, wi: Vec3) -> Vec3 {
        if wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        let diffuse =
            self.kd * (Vec3::ONE - schlick(self.f0, wi.z)) * (Vec3::ONE - self.f0) * (20.0 / 21.0);
        const N: usize = 16;
        let mut spec = Vec3::ZERO;
        for a in 0..N {
            for b in 0..N {
                let u = [(a as f32 + 0.5) / N as f32, (b as f32 + 0.5) / N as f32];
                let h = self.sample_h(u);
                let ih = wi.dot(h);
                let wo = 2.0 * ih * h - wi;
                if wo.z <= 0.0 || ih <= 0.0 {
                    continue;
                }
                let g = (2.0 * h.z * wo.z / ih).min(2.0 * h.z * wi.z / ih).min(1.0);
                spec += schlick(self.f0, ih) * (g * ih / (wi.z * h.z));
            }
        }
        diffuse + spec / (N * N) as f32
    }
}

/// A Cook–Torrance BRDF seen from one `wi` ([`CookTorrance::at`]), with
/// the lobe choice's probability and the diffuse base's factor of `wi`
/// computed once, and `f` and the pdf of a pair from one half vector and
/// one `D`: the directionality analysis samples and evaluates thousands of
/// directions from one `wi`. The operations per pair are those of the
/// per-pair methods, so the bits are theirs.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CookTorranceAt<'a> {
    b: &'a CookTorrance,
    wi: Vec3,
    p_spec: f32,
    diffuse_in: Vec3,
}

impl CookTorranceAt<'_> {
    /// `(eval(wi, wo), pdf(wi, wo))`.
    pub(crate) fn eval_and_pdf(&self, wo: Vec3) -> (Vec3, f32) {
        let (b, wi) = (self.b, self.wi);
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return (Vec3::ZERO, 0.0);
        }
        let h = (wi + wo).normalize_or_zero();
        let d = b.d(h);
        (
            b.eval_given(self.diffuse_in, wi, wo, h, d),
            b.pdf_given(self.p_spec, wo, h, d),
        )
    }

    /// [`CookTorrance::sample_with_f`] from this `wi`.
    pub(crate) fn sample_with_f(&self, u: [f32; 2]) -> Option<(BrdfSample, Vec3)> {
        let (b, wi) = (self.b, self.wi);
        if wi.z <= 0.0 {
            return None;
        }
        let wo = match super::pick_lobe(u[0], self.p_spec) {
            (true, u0) => {
                let h = b.sample_h([u0, u[1]]);
                2.0 * wi.dot(h) * h - wi
            }
            (false, u0) => cosine_hemisphere([u0, u[1]]),
        };
        if wo.z <= 0.0 {
            return None;
        }
        let (f, pdf) = self.eval_and_pdf(wo);
        super::weighted_sample(wo, pdf, f).map(|s| (s, f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rejects_bad_parameters() {
        assert!(CookTorrance::new(0.0, Vec3::ONE, Vec3::ZERO).is_err());
        assert!(CookTorrance::new(f32::NAN, Vec3::ONE, Vec3::ZERO).is_err());
        assert!(CookTorrance::new(1.5, Vec3::ONE, Vec3::ZERO).is_err());
        assert!(CookTorrance::new(0.3, Vec3::splat(1.1), Vec3::ZERO).is_err());
        assert!(CookTorrance::new(0.3, Vec3::ONE, Vec3::splat(-0.1)).is_err());
    }

    #[test]
    fn beckmann_is_normalised() {
        // integral D(h) cos theta_h dh = 1, midpoint rule in (tan^2 theta_h) space
        // is what the sampler inverts, so check with a plain (cos, phi) grid instead.
        for m in [0.1f32, 0.3, 1.0] {
            let ct = CookTorrance::new(m, Vec3::ONE, Vec3::ZERO).unwrap();
            let n = 4000;
            let mut s = 0.0f64;
            for k in 0..n {
                let c = (k as f32 + 0.5) / n as f32;
                let h = crate::sampling::spherical_direction(c, 0.0);
                s += (ct.d(h) * c) as f64 * 2.0 * std::f64::consts::PI / n as f64;
            }
            assert!((s - 1.0).abs() < 2e-3, "m={m}: {s}");
        }
    }
}
