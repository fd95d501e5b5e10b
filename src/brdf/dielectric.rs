//! Smooth glass: Fresnel reflection and Snell refraction at a flat interface
//! between air and a dielectric (a delta distribution), or through a
//! thin-walled sheet; and the Fresnel and refraction helpers that
//! [`super::RoughDielectric`] shares.
//!
//! Parameters:
//! - `ior`: index of refraction inside over outside (outside is 1), finite,
//!   in [1, 4]; 1 is an index-matched pass-through (no reflection);
//! - `tint`: transmittance colour (linear RGB, each channel in [0, 1]): the
//!   transmitted sample's weight is multiplied by it (glTF's base colour of a
//!   transmissive material);
//! - `attenuation`: absorption coefficient sigma_a per world unit inside the
//!   volume (each channel finite and >= 0; a caller maps a zero glTF
//!   `attenuationColor` to `f32::MAX`). The model only carries it: the
//!   integrator applies `exp(-sigma_a d)` over a path length `d` inside.
//!   Ignored when `thin`;
//! - `thin`: a thin-walled sheet (glTF `KHR_materials_volume` with
//!   `thicknessFactor` 0): no refraction, the same air on both sides.
//!
//! Frame: local +z is the normal on the *outside* (index 1); `wi` and `wo`
//! both point away from the surface; `w.z < 0` means `w` is inside the
//! dielectric. `wo` may be on either side.
//!
//! [`Transport`] says which way the path runs. In [`Transport::Flux`] mode
//! (photons) `wi` points to where the photon came from and `wo` is its new
//! direction; flux does not change across an interface. In
//! [`Transport::Radiance`] mode (camera paths) `wi` points back to the camera
//! and `wo` to where the path goes next; radiance over eta^2 is what is
//! conserved, so a transmitted weight is scaled by `(eta_wi / eta_wo)^2`,
//! `eta_x` being the index on `x`'s side: `1 / ior^2` entering, `ior^2`
//! leaving (pbrt-v4 `DielectricBxDF::Sample_f`: `ft /= Sqr(etap)` in radiance
//! mode). No scaling when `thin` (air on both sides).
//!
//! Formulas (pbrt-v4 `util/scattering.h`, `FrDielectric` and `Refract`;
//! `bxdfs.h`, `ThinDielectricBxDF`), with `c = |cos theta_i|`, `eta` the
//! index on the far side over the index on `wi`'s side, and
//! `c_t = sqrt(1 - (1 - c^2) / eta^2)`:
//! ```text
//! R_s = ((c - eta c_t) / (c + eta c_t))^2          (s, perpendicular)
//! R_p = ((eta c - c_t) / (eta c + c_t))^2          (p, parallel)
//! F   = (R_s + R_p) / 2,  1 past the critical angle (no c_t)
//! wt  = -wi / eta + (c / eta - c_t) n               (Snell: sin t = sin i / eta)
//! thin slab: R' = R + T^2 R / (1 - R^2) = 2 R / (1 + R),  T' = 1 - R'
//! ```
//! The thin slab sums the light bouncing between its two faces (no
//! absorption); transmission goes straight through, `wo = -wi`.
//!
//! Methods: [`Dielectric::sample`] reflects (`wo` the mirror of `wi`) with
//! probability F (R' when thin) and transmits otherwise, so the weights are
//! exactly 1 for reflection and `tint` for transmission in flux mode (the
//! Fresnel factor cancels the choice), with `pdf = 0` and `specular = true`;
//! past the critical angle it reflects with probability 1. `eval` and `pdf`
//! are 0 (a delta lobe has no density). [`Dielectric::albedo`] is
//! `F + (1 - F) tint` from either side.

use super::phong::check_rgb01;
use super::BrdfSample;
use crate::error::{Error, Result};
use crate::sampling::reflect_z;
use glam::Vec3;

/// Which quantity a path carries, hence which adjoint of the BSDF it uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Transport {
    /// Photons from the lights: `wi` points to where the photon came from,
    /// `wo` is its new direction of travel. No eta^2 factor.
    Flux,
    /// Camera paths: `wi` points back towards the camera, `wo` towards the
    /// light. A transmission is scaled by `(eta_wi / eta_wo)^2`.
    Radiance,
}

/// The s- and p-polarised Fresnel reflectances `(R_s, R_p)` of a dielectric
/// interface (see the module docs). `cos_i` is the cosine of the incident
/// direction with the normal: positive on the normal's side, where `eta` is
/// the index across the interface over the index on that side; negative
/// from the other side (then `eta` is inverted). `(1, 1)` past the critical
/// angle.
pub fn fresnel_s_p(cos_i: f32, eta: f32) -> (f32, f32) {
    let (mut c, mut eta) = (cos_i.clamp(-1.0, 1.0), eta);
    if c < 0.0 {
        eta = 1.0 / eta;
        c = -c;
    }
    let sin2_t = (1.0 - c * c) / (eta * eta);
    if sin2_t >= 1.0 {
        return (1.0, 1.0);
    }
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let r_s = (c - eta * cos_t) / (c + eta * cos_t);
    let r_p = (eta * c - cos_t) / (eta * c + cos_t);
    (r_s * r_s, r_p * r_p)
}

/// The unpolarised Fresnel reflectance `(R_s + R_p) / 2` (pbrt-v4
/// `FrDielectric`): `cos_i` and `eta` as in [`fresnel_s_p`], so a negative
/// `cos_i` is light from inside; 1 past the critical angle.
pub fn fresnel_dielectric(cos_i: f32, eta: f32) -> f32 {
    let (s, p) = fresnel_s_p(cos_i, eta);
    0.5 * (s + p)
}

/// The reflectance of a thin non-absorbing slab, both faces counted
/// (pbrt-v4 `ThinDielectricBxDF`): `R + T^2 R / (1 - R^2) = 2 R / (1 + R)`
/// with `R = fresnel_dielectric(|cos_i|, eta)`. Air on both sides, so the
/// side of `cos_i` does not matter.
pub fn thin_slab_reflectance(cos_i: f32, eta: f32) -> f32 {
    let r = fresnel_dielectric(cos_i.abs(), eta);
    if r < 1.0 {
        2.0 * r / (1.0 + r)
    } else {
        1.0
    }
}

/// The refracted direction of `wi` (pointing away from the surface) through
/// an interface of unit normal `n`, or `None` past the critical angle
/// (pbrt-v4 `Refract`). `eta` is the index on the side `n` does not point
/// to over the index on the side it points to (`ior` for the outward
/// normal); `wi` may be on either side. The result points away on the other
/// side.
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let (mut cos_i, mut eta, mut n) = (n.dot(wi), eta, n);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some(-wi / eta + (cos_i / eta - cos_t) * n)
}

/// `(eta_wi / eta_wo)^2` of a transmission from the side of `wi` to the other
/// (`1 / ior^2` entering, `ior^2` leaving) in radiance mode, 1 in flux mode.
#[inline]
pub(crate) fn radiance_scale(wi_z: f32, ior: f32, mode: Transport) -> f32 {
    match mode {
        Transport::Flux => 1.0,
        Transport::Radiance if wi_z > 0.0 => 1.0 / (ior * ior),
        Transport::Radiance => ior * ior,
    }
}

/// Checks an index of refraction: finite and in [1, 4].
pub(crate) fn check_ior(name: &'static str, ior: f32) -> Result<f32> {
    if (1.0..=4.0).contains(&ior) {
        Ok(ior)
    } else {
        Err(Error::param(
            name,
            format!("must be a finite number in [1, 4], got {ior}"),
        ))
    }
}

/// Checks an absorption coefficient: every channel finite and >= 0.
pub(crate) fn check_attenuation(name: &'static str, v: Vec3) -> Result<Vec3> {
    if v.is_finite() && v.min_element() >= 0.0 {
        Ok(v)
    } else {
        Err(Error::param(
            name,
            format!("every channel must be a finite number >= 0, got {v}"),
        ))
    }
}

/// Smooth glass (a delta distribution); see the module docs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Dielectric {
    ior: f32,
    tint: Vec3,
    attenuation: Vec3,
    thin: bool,
}

impl Dielectric {
    /// Smooth glass of index `ior` (inside over outside), transmittance
    /// `tint`, absorption coefficient `attenuation` (per world unit, ignored
    /// when `thin`), thin-walled or not.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when `ior` is NaN or outside [1, 4], a
    /// `tint` channel is NaN or outside [0, 1], or an `attenuation` channel
    /// is NaN, infinite or negative.
    pub fn new(ior: f32, tint: Vec3, attenuation: Vec3, thin: bool) -> Result<Self> {
        Ok(Dielectric {
            ior: check_ior("dielectric ior", ior)?,
            tint: check_rgb01("dielectric tint", tint)?,
            attenuation: check_attenuation("dielectric attenuation", attenuation)?,
            thin,
        })
    }

    /// Index of refraction, inside over outside.
    pub fn ior(&self) -> f32 {
        self.ior
    }

    /// Transmittance colour.
    pub fn tint(&self) -> Vec3 {
        self.tint
    }

    /// Absorption coefficient per world unit (not applied here; ignored when thin).
    pub fn attenuation(&self) -> Vec3 {
        self.attenuation
    }

    /// True for a thin-walled sheet (no refraction).
    pub fn thin(&self) -> bool {
        self.thin
    }

    /// The reflectance seen from `wi`: F, or the slab's R' when thin.
    fn reflectance(&self, wi: Vec3) -> f32 {
        if self.thin {
            thin_slab_reflectance(wi.z, self.ior)
        } else {
            fresnel_dielectric(wi.z, self.ior)
        }
    }

    /// Always 0: a delta lobe has no finite value.
    pub fn eval(&self, _wi: Vec3, _wo: Vec3, _mode: Transport) -> Vec3 {
        Vec3::ZERO
    }

    /// Reflection with probability F (R' when thin), weight 1; otherwise
    /// transmission (refracted, or `-wi` when thin), weight `tint` times the
    /// radiance-mode `(eta_wi / eta_wo)^2`. `u[0]` makes the choice, `u[1]`
    /// is unused. `None` for a grazing (`wi.z == 0`) or non-finite `wi`.
    pub fn sample(&self, wi: Vec3, u: [f32; 2], mode: Transport) -> Option<BrdfSample> {
        if !wi.is_finite() || wi.z == 0.0 {
            return None;
        }
        let delta = |wo: Vec3, weight: Vec3| BrdfSample {
            wo,
            weight,
            pdf: 0.0,
            specular: true,
        };
        if u[0] < self.reflectance(wi) {
            return Some(delta(reflect_z(wi), Vec3::ONE));
        }
        if self.thin {
            return Some(delta(-wi, self.tint));
        }
        // F < 1 here, so there is a refracted direction (up to rounding at
        // the critical angle, where F is 1 anyway).
        let wo = refract(wi, Vec3::Z, self.ior)?;
        Some(delta(wo, self.tint * radiance_scale(wi.z, self.ior, mode)))
    }

    /// Always 0 (delta).
    pub fn pdf(&self, _wi: Vec3, _wo: Vec3) -> f32 {
        0.0
    }

    /// The reflected plus transmitted fraction of flux from `wi` (either
    /// side): `F + (1 - F) tint`, R' for F when thin; 0 for a grazing or
    /// non-finite `wi`, where [`Dielectric::sample`] fails.
    pub fn albedo(&self, wi: Vec3) -> Vec3 {
        if !wi.is_finite() || wi.z == 0.0 {
            return Vec3::ZERO;
        }
        let r = self.reflectance(wi);
        Vec3::splat(r) + (1.0 - r) * self.tint
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fresnel_at_normal_incidence_is_the_closed_form() {
        // ((n - 1) / (n + 1))^2 from both sides.
        for eta in [1.0f32, 1.33, 1.5, 2.4, 4.0] {
            let want = ((eta - 1.0) / (eta + 1.0)).powi(2);
            assert!((fresnel_dielectric(1.0, eta) - want).abs() < 1e-6);
            assert!((fresnel_dielectric(-1.0, eta) - want).abs() < 1e-6);
        }
    }

    #[test]
    fn refract_through_index_one_is_straight() {
        let wi = Vec3::new(0.3, -0.2, 0.9).normalize();
        let wo = refract(wi, Vec3::Z, 1.0).unwrap();
        assert!((wo + wi).length() < 1e-6);
    }

    #[test]
    fn constructor_checks_and_getters() {
        let d =
            Dielectric::new(1.5, Vec3::splat(0.5), Vec3::new(0.0, 1.0, f32::MAX), true).unwrap();
        assert_eq!(
            (d.ior(), d.tint(), d.attenuation(), d.thin()),
            (1.5, Vec3::splat(0.5), Vec3::new(0.0, 1.0, f32::MAX), true)
        );
        let e = Dielectric::new(0.9, Vec3::ONE, Vec3::ZERO, false).unwrap_err();
        assert!(e.to_string().contains("0.9"), "{e}");
        assert!(Dielectric::new(1.5, Vec3::ONE, Vec3::splat(f32::INFINITY), false).is_err());
    }
}
