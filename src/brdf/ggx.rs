//! The GGX (Trowbridge–Reitz) microfacet distribution with Smith's
//! height-correlated masking-shadowing, shared by the models built on it:
//! [`super::RoughDielectric`] (glass) and [`super::GltfPbr`] (glTF's
//! metallic-roughness BRDF). Isotropic, in the local frame (normal = +z).
//!
//! ```text
//! D(m)      = alpha^2 / (pi (alpha^2 m.z^2 + m.x^2 + m.y^2)^2)
//! Lambda(w) = (sqrt(1 + alpha^2 tan^2 theta_w) - 1) / 2
//! G1(w) = 1 / (1 + Lambda(w)),  G(wi, wo) = 1 / (1 + Lambda(wi) + Lambda(wo))
//! D_wi(m) = G1(wi) D(m) |wi.m| / |wi.z|          (visible normals)
//! ```
//! `D` and `Lambda` are written with the vector's components, so they stay
//! exact near the pole where `tan` and `1 - cos` lose digits. Normals are
//! sampled from `D_wi` as Heitz (2018, *Sampling the GGX Distribution of
//! Visible Normals*) does, in pbrt-v4's `Sample_wm` form
//! (`src/pbrt/util/scattering.h`).

use glam::Vec3;
use std::f32::consts::PI;

/// Integrals over the normals a GGX surface shows to `wi`
/// ([`Ggx::lobe_energy`]); under Schlick's Fresnel of reflectance `f0`,
/// which is linear in `f0`:
/// - the lobe reflects `f0 shadowed + (1 - f0) shadowed_schlick`: the
///   integral of `G(wi, wo) / G1(wi)` over the normals whose reflection
///   stays above the horizon, the second weighted by `(1 - wi.m)^5`;
/// - the facets first met reflect `f0 + (1 - f0) schlick` (`schlick` the
///   mean of `(1 - wi.m)^5` over every visible normal) and let the rest
///   into the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct LobeEnergy {
    pub(crate) shadowed: f32,
    pub(crate) shadowed_schlick: f32,
    pub(crate) schlick: f32,
}

/// An isotropic GGX distribution of roughness `alpha` (checked by the
/// models that hold one).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Ggx {
    pub(crate) alpha: f32,
}

impl Ggx {
    /// `D(m)` for `m` on the upper hemisphere (0 below).
    pub(crate) fn d(&self, m: Vec3) -> f32 {
        if m.z <= 0.0 {
            return 0.0;
        }
        let a2 = self.alpha * self.alpha;
        let t = a2 * m.z * m.z + m.x * m.x + m.y * m.y;
        a2 / (PI * t * t)
    }

    /// Smith's `Lambda(w)`, side-independent, in a form without
    /// cancellation at small `alpha^2 tan^2`.
    pub(crate) fn lambda(&self, w: Vec3) -> f32 {
        let x = self.alpha * self.alpha * (w.x * w.x + w.y * w.y) / (w.z * w.z);
        if !x.is_finite() {
            return f32::INFINITY;
        }
        0.5 * x / ((1.0 + x).sqrt() + 1.0)
    }

    /// Smith's masking `G1(w)`.
    pub(crate) fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    /// Height-correlated masking-shadowing `G(wi, wo)` (Heitz 2014).
    pub(crate) fn g(&self, wi: Vec3, wo: Vec3) -> f32 {
        self.g_given(self.lambda(wi), wo)
    }

    /// [`Self::g`] from `Lambda(wi)`, for many `wo` from one `wi`.
    #[inline]
    pub(crate) fn g_given(&self, lambda_wi: f32, wo: Vec3) -> f32 {
        1.0 / (1.0 + lambda_wi + self.lambda(wo))
    }

    /// The density of normals visible from `wi`,
    /// `D_wi(m) = G1(wi) D(m) |wi.m| / |wi.z|` (0 for a normal facing away
    /// from `wi`).
    pub(crate) fn d_visible(&self, wi: Vec3, m: Vec3) -> f32 {
        Self::d_visible_given(self.g1(wi), self.d(m), wi, m)
    }

    /// [`Self::d_visible`] from `G1(wi)` and `D(m)`, which the callers that
    /// evaluate many pairs, or `D` for `f` too, have already.
    #[inline]
    pub(crate) fn d_visible_given(g1_wi: f32, d_m: f32, wi: Vec3, m: Vec3) -> f32 {
        let im = wi.dot(m);
        if im * wi.z <= 0.0 {
            return 0.0;
        }
        g1_wi * d_m * im.abs() / wi.z.abs()
    }

    /// The reflection lobe `D(h) G(wi, wo) / (4 cos_i cos_o)` (both
    /// directions above the horizon) and its half vector `h`; `None` when
    /// `wi + wo` has no direction. The cosines' product is floored so that
    /// two that underflow do not give 0 / 0.
    pub(crate) fn reflection(&self, wi: Vec3, wo: Vec3) -> Option<(f32, Vec3)> {
        let h = (wi + wo).try_normalize()?;
        let cosines = (4.0 * wi.z * wo.z).max(f32::MIN_POSITIVE);
        Some((self.d(h) * self.g(wi, wo) / cosines, h))
    }

    /// A direction reflected about a normal drawn from [`Self::d_visible`];
    /// `None` when the normal faces away from `wi`.
    pub(crate) fn sample_reflection(&self, wi: Vec3, u: [f32; 2]) -> Option<Vec3> {
        let m = self.sample_m(wi, u);
        let im = wi.dot(m);
        (im > 0.0).then(|| (2.0 * im * m - wi).normalize())
    }

    /// Solid-angle pdf of [`Self::sample_reflection`]: `D_wi(h) / (4 wi.h)`.
    pub(crate) fn reflection_pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        match (wi + wo).try_normalize() {
            Some(h) if wi.dot(h) > 0.0 => self.d_visible(wi, h) / (4.0 * wi.dot(h)),
            _ => 0.0,
        }
    }

    /// A microfacet normal drawn from [`Self::d_visible`] (pbrt-v4
    /// `Sample_wm`, isotropic): a uniform disk point warped onto the
    /// projected visible hemisphere of the stretched `wi` (of `-wi` when
    /// `wi` is below the surface).
    pub(crate) fn sample_m(&self, wi: Vec3, u: [f32; 2]) -> Vec3 {
        self.visible_frame(wi).sample_m(u)
    }

    /// The frame of the stretched `wi` that [`Self::sample_m`] warps its
    /// disk point in: it depends on `wi` alone, so a caller drawing many
    /// normals from one `wi` builds it once.
    pub(crate) fn visible_frame(&self, wi: Vec3) -> VisibleFrame {
        let a = self.alpha;
        let mut wh = Vec3::new(a * wi.x, a * wi.y, wi.z).normalize();
        if wh.z < 0.0 {
            wh = -wh;
        }
        let t1 = if wh.z < 0.99999 {
            Vec3::Z.cross(wh).normalize()
        } else {
            Vec3::X
        };
        let t2 = wh.cross(t1);
        VisibleFrame { a, wh, t1, t2 }
    }

    /// Moments of the normals visible from `wi` (upper hemisphere), by a
    /// 32 x 32 midpoint quadrature of [`Self::sample_m`]'s uniforms, the
    /// radial one warped as `u0 = 1 - (1 - t)^3` (weight `3 (1 - t)^2`,
    /// normalised) towards GGX's grazing tail; the integrands have no `D`
    /// in them and stay smooth at every alpha. See [`LobeEnergy`].
    pub(crate) fn lobe_energy(&self, wi: Vec3) -> LobeEnergy {
        self.lobe_energy_weighted(wi, |_| 1.0)
    }

    /// [`Self::lobe_energy`] with each reflected direction's share of the
    /// shadowed moments multiplied by `weight(wo)` (what a layer above lets
    /// out towards `wo`; 1 gives [`Self::lobe_energy`] bit for bit).
    pub(crate) fn lobe_energy_weighted(
        &self,
        wi: Vec3,
        weight: impl Fn(Vec3) -> f64,
    ) -> LobeEnergy {
        const N: usize = 32;
        let (mut e1, mut ew, mut w_all, mut total) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
        for a in 0..N {
            let s = 1.0 - (a as f64 + 0.5) / N as f64;
            let (u0, w) = ((1.0 - s * s * s) as f32, 3.0 * s * s);
            total += w;
            for b in 0..N {
                let m = self.sample_m(wi, [u0, (b as f32 + 0.5) / N as f32]);
                let im = wi.dot(m);
                if im <= 0.0 {
                    continue;
                }
                let schlick = w * f64::from((1.0 - im.min(1.0)).powi(5));
                w_all += schlick;
                let wo = (2.0 * im * m - wi).normalize();
                if wo.z <= 0.0 {
                    continue;
                }
                let g = f64::from(self.g(wi, wo) / self.g1(wi)) * weight(wo);
                e1 += w * g;
                ew += schlick * g;
            }
        }
        let n = total * N as f64;
        LobeEnergy {
            shadowed: (e1 / n) as f32,
            shadowed_schlick: (ew / n) as f32,
            schlick: (w_all / n) as f32,
        }
    }
}

/// Schlick's weight `(1 - c)^5` (`c` clamped to [0, 1]).
#[inline]
pub(crate) fn schlick_weight(c: f32) -> f32 {
    (1.0 - c.clamp(0.0, 1.0)).powi(5)
}

/// [`Ggx::visible_frame`]: the stretched `wi` (turned to +z) and two
/// tangents, and alpha.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct VisibleFrame {
    a: f32,
    wh: Vec3,
    t1: Vec3,
    t2: Vec3,
}

impl VisibleFrame {
    /// [`Ggx::sample_m`] in this frame.
    pub(crate) fn sample_m(&self, u: [f32; 2]) -> Vec3 {
        let VisibleFrame { a, wh, t1, t2 } = *self;
        let r = u[0].sqrt();
        let phi = 2.0 * PI * u[1];
        let (px, py) = (r * phi.cos(), r * phi.sin());
        let h = (1.0 - px * px).max(0.0).sqrt();
        let s = 0.5 * (1.0 + wh.z);
        let py = (1.0 - s) * h + s * py;
        let pz = (1.0 - px * px - py * py).max(0.0).sqrt();
        let nh = px * t1 + py * t2 + pz * wh;
        Vec3::new(a * nh.x, a * nh.y, nh.z.max(1e-6)).normalize()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::spherical_direction;

    #[test]
    fn ggx_is_normalised() {
        // integral D(m) cos theta_m dm = 1 on a (cos, phi) midpoint grid.
        for alpha in [0.05f32, 0.3, 1.0] {
            let g = Ggx { alpha };
            let n = 20_000;
            let mut s = 0.0f64;
            for k in 0..n {
                let c = (k as f32 + 0.5) / n as f32;
                s += (g.d(spherical_direction(c, 0.0)) * c) as f64 * 2.0 * std::f64::consts::PI
                    / n as f64;
            }
            assert!((s - 1.0).abs() < 2e-3, "alpha={alpha}: {s}");
        }
    }

    #[test]
    fn visible_normals_are_normalised() {
        // integral D_wi(m) dm = 1 (Heitz 2014's constraint on G1).
        for alpha in [0.1f32, 0.5, 1.0] {
            let g = Ggx { alpha };
            for wi in [
                Vec3::new(0.6, 0.0, 0.8),
                Vec3::new(-0.3, 0.4, -0.866).normalize(),
                Vec3::new(0.995, 0.0, 0.0999).normalize(),
            ] {
                let (nc, np) = (2000, 256);
                let mut s = 0.0f64;
                for i in 0..nc {
                    for j in 0..np {
                        let c = (i as f32 + 0.5) / nc as f32;
                        let phi = (j as f32 + 0.5) / np as f32 * 2.0 * PI;
                        s += g.d_visible(wi, spherical_direction(c, phi)) as f64;
                    }
                }
                s *= 2.0 * std::f64::consts::PI / (nc * np) as f64;
                assert!((s - 1.0).abs() < 5e-3, "alpha={alpha} wi={wi}: {s}");
            }
        }
    }
}
