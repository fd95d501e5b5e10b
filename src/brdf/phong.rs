//! Modified Phong (Lafortune & Willems 1994): a diffuse term plus a
//! normalised power-cosine lobe around the mirror direction.
//!
//! Parameters:
//! - `kd`: diffuse reflectance (linear RGB, each channel in [0, 1]);
//! - `ks`: specular reflectance (linear RGB, each channel in [0, 1]);
//! - `exponent` e >= 0 (finite; 1e6 is a near-mirror and stays finite).
//!
//! `f_r = kd / pi + ks (e + 2) / (2 pi) cos^e(alpha)`, alpha the angle between
//! `wo` and the mirror of `wi`. The `(e + 2) / (2 pi)` normalisation makes the
//! lobe's albedo at normal incidence exactly `ks`, and at most `ks` elsewhere,
//! so `kd + ks <= 1` per channel is energy conserving; the constructor rejects
//! anything else. The model is reciprocal (`wo . mirror(wi) = wi . mirror(wo)`).
//!
//! Sampling picks the diffuse lobe (cosine-weighted) or the specular lobe (a
//! power-cosine lobe of exponent e about the mirror direction) with
//! probabilities proportional to the luminances of `kd` and `ks`; a specular
//! direction below the horizon is a failed sample (`None`), so the pdf is that
//! of a sub-probability distribution, which Monte Carlo estimators allow.

use super::BrdfSample;
use crate::error::{Error, Result};
use crate::sampling::{
    cos_power_hemisphere, cos_power_hemisphere_pdf, cosine_hemisphere, cosine_hemisphere_pdf,
    luminance, reflect_z, Frame,
};
use glam::Vec3;
use std::f32::consts::{FRAC_1_PI, PI};

/// The modified Phong BRDF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phong {
    kd: Vec3,
    ks: Vec3,
    exponent: f32,
    /// Probability of sampling the specular lobe.
    p_spec: f32,
}

/// Checks a reflectance: every channel finite and in [0, 1].
pub(crate) fn check_rgb01(name: &'static str, v: Vec3) -> Result<Vec3> {
    if v.is_finite() && v.min_element() >= 0.0 && v.max_element() <= 1.0 {
        Ok(v)
    } else {
        Err(Error::param(
            name,
            format!("every channel must be in [0, 1], got {v}"),
        ))
    }
}

impl Phong {
    /// A modified Phong BRDF.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when a reflectance channel is outside
    /// [0, 1] or NaN, when `kd + ks > 1` in some channel, or when the exponent
    /// is NaN, infinite or negative.
    pub fn new(kd: Vec3, ks: Vec3, exponent: f32) -> Result<Self> {
        let kd = check_rgb01("phong kd", kd)?;
        let ks = check_rgb01("phong ks", ks)?;
        let exponent = crate::error::check_non_negative("phong exponent", exponent)?;
        // A small slack for values such as 0.7 + 0.3 that round above 1.
        if (kd + ks).max_element() > 1.0 + 1e-6 {
            return Err(Error::param(
                "phong kd + ks",
                format!(
                    "must be <= 1 per channel for energy conservation, got {}",
                    kd + ks
                ),
            ));
        }
        let (ld, ls) = (luminance(kd), luminance(ks));
        let p_spec = if ld + ls > 0.0 { ls / (ld + ls) } else { 0.0 };
        Ok(Phong {
            kd,
            ks,
            exponent,
            p_spec,
        })
    }

    /// Diffuse reflectance.
    pub fn kd(&self) -> Vec3 {
        self.kd
    }

    /// Specular reflectance.
    pub fn ks(&self) -> Vec3 {
        self.ks
    }

    /// The Phong exponent.
    pub fn exponent(&self) -> f32 {
        self.exponent
    }

    /// `(e + 2) / (2 pi) cos^e(alpha)`, the specular lobe without `ks`.
    fn lobe(&self, wi: Vec3, wo: Vec3) -> f32 {
        let c = wo.dot(reflect_z(wi));
        if c <= 0.0 {
            return 0.0;
        }
        (self.exponent + 2.0) * 0.5 * FRAC_1_PI * c.min(1.0).powf(self.exponent)
    }

    /// Evaluates the BRDF.
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.kd * FRAC_1_PI + self.ks * self.lobe(wi, wo)
    }

    /// Samples the diffuse or the specular lobe (see the module docs).
    pub fn sample(&self, wi: Vec3, u: [f32; 2]) -> Option<BrdfSample> {
        self.sample_with_f(wi, u).map(|(s, _)| s)
    }

    /// [`Self::sample`] and the value `f(wi, wo)` it was weighted with.
    pub(crate) fn sample_with_f(&self, wi: Vec3, u: [f32; 2]) -> Option<(BrdfSample, Vec3)> {
        if wi.z <= 0.0 || (self.kd == Vec3::ZERO && self.ks == Vec3::ZERO) {
            return None;
        }
        let wo = match super::pick_lobe(u[0], self.p_spec) {
            (true, u0) => {
                let local = cos_power_hemisphere(self.exponent, [u0, u[1]]);
                Frame::from_normal(reflect_z(wi)).world_from_local(local)
            }
            (false, u0) => cosine_hemisphere([u0, u[1]]),
        };
        if wo.z <= 0.0 {
            return None;
        }
        let f = self.eval(wi, wo);
        super::weighted_sample(wo, self.pdf(wi, wo), f).map(|s| (s, f))
    }

    /// Solid-angle pdf of [`Phong::sample`].
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        let c = wo.dot(reflect_z(wi));
        let spec = cos_power_hemisphere_pdf(self.exponent, c.min(1.0));
        self.p_spec * spec + (1.0 - self.p_spec) * cosine_hemisphere_pdf(wo.z)
    }

    /// Directional albedo: `kd + ks * S(theta_i)`, with `S` the share of the
    /// normalised lobe above the horizon, by a 64-point quadrature (error
    /// below 1e-4 for every exponent, because the variable change
    /// `t = cos^(e+1) alpha` makes the integrand smooth).
    pub fn albedo(&self, wi: Vec3) -> Vec3 {
        if wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        self.kd + self.ks * lobe_albedo(self.exponent, wi.z.min(1.0))
    }
}

/// `integral (e+2)/(2 pi) cos^e(alpha) cos(theta_o) dwo` over the upper
/// hemisphere, for a lobe centred at polar angle theta_r (cosine `cos_r`).
///
/// In lobe coordinates (alpha, psi), `cos theta_o = a + b cos psi` with
/// `a = cos alpha cos_r`, `b = sin alpha sin_r`; the psi integral of
/// `max(0, a + b cos psi)` is closed-form, and `t = cos^(e+1) alpha` turns the
/// alpha integral into `1/(e+1) integral_0^1 g(t^(1/(e+1))) dt`.
fn lobe_albedo(e: f32, cos_r: f32) -> f32 {
    const N: usize = 64;
    let sin_r = (1.0 - cos_r * cos_r).max(0.0).sqrt();
    let mut sum = 0.0f32;
    for k in 0..N {
        let t = (k as f32 + 0.5) / N as f32;
        let ca = t.powf(1.0 / (e + 1.0));
        let sa = (1.0 - ca * ca).max(0.0).sqrt();
        let (a, b) = (ca * cos_r, sa * sin_r);
        let g = if a >= b {
            2.0 * PI * a
        } else if a <= -b {
            0.0
        } else {
            2.0 * (a * (-a / b).clamp(-1.0, 1.0).acos() + (b * b - a * a).max(0.0).sqrt())
        };
        sum += g;
    }
    (e + 2.0) / (2.0 * PI * (e + 1.0)) * sum / N as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lobe_albedo_is_one_at_normal_incidence_and_falls_towards_grazing() {
        for e in [0.0, 1.0, 10.0, 1e3, 1e6] {
            let a0 = lobe_albedo(e, 1.0);
            assert!((a0 - 1.0).abs() < 1e-3, "e={e}: {a0}");
            let mut prev = a0;
            for c in [0.8, 0.5, 0.2, 0.01] {
                let a = lobe_albedo(e, c);
                assert!(
                    a <= prev + 1e-4 && a.is_finite(),
                    "e={e} c={c}: {a} > {prev}"
                );
                prev = a;
            }
        }
    }

    #[test]
    fn rejects_bad_parameters() {
        assert!(Phong::new(Vec3::splat(0.6), Vec3::splat(0.6), 10.0).is_err());
        assert!(Phong::new(Vec3::splat(0.5), Vec3::splat(0.5), f32::NAN).is_err());
        assert!(Phong::new(Vec3::splat(-0.1), Vec3::splat(0.5), 1.0).is_err());
        assert!(Phong::new(Vec3::splat(0.5), Vec3::splat(0.5), -1.0).is_err());
        assert!(Phong::new(Vec3::splat(0.5), Vec3::new(0.5, f32::NAN, 0.0), 1.0).is_err());
    }
}
