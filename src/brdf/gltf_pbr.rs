//! glTF 2.0's metallic-roughness BRDF, as the specification's Appendix B
//! defines it: a GGX specular lobe with Smith's height-correlated
//! masking-shadowing (`brdf/ggx.rs`, shared with rough glass), Schlick's Fresnel, and a Lambertian
//! base mixed under the dielectric's Fresnel term.
//!
//! Parameters: `base_color` (linear RGB in [0, 1]), `metallic` in [0, 1],
//! `alpha` (glTF's roughness squared) in [[`GltfPbr::MIN_ALPHA`], 1], and the
//! dielectric's Fresnel reflectance at normal incidence `f0_d` (RGB, each
//! channel in [0, 1]) and at grazing incidence `f90_d` in [0, 1]: 0.04 and 1
//! for glTF's default IOR 1.5; `KHR_materials_ior` changes `f0_d`, and
//! `KHR_materials_specular` colours and scales it and scales `f90_d`
//! (`brdf/gltf_map.rs`).
//!
//! With `h = normalize(wi + wo)` and `w = (1 - |wi.h|)^5`:
//! ```text
//! f0       = mix(f0_d, base_color, metallic)
//! f90      = mix(f90_d, 1, metallic)
//! F        = f0 + (f90 - f0) w                     (Schlick, per channel)
//! specular = F D(h) G(wi, wo) / (4 cos_i cos_o)
//! diffuse  = base_color (1 - metallic) / pi
//!            (1 - E_F(cos_i)) (1 - E_F(cos_o)) / (1 - E_avg)
//! f_r      = diffuse + specular
//! ```
//! This is the specification's `mix(dielectric_brdf, metal_brdf, metallic)`:
//! Schlick's term is linear in `f0` and `f90`, so the metal's (`f0 =
//! base_color`, `f90 = 1`) and the dielectric's specular lobes merge into
//! one of Fresnel `F(mix(f0_d, base_color, metallic), mix(f90_d, 1,
//! metallic))`, and only the dielectric carries the diffuse base. `D` is
//! GGX and `G / (4 cos_i cos_o)` the specification's height-correlated
//! visibility term `V`; the tests compare the specular lobe and the metal
//! with the specification's formulas, written there as it gives them.
//!
//! The diffuse base is where this model departs from the specification's
//! *informative* sample code. Its `fresnel_mix` weights the base by
//! `1 - F_d(|wi.h|)` at the half vector, which is not energy conserving
//! (the specification says so): a white glossy dielectric would return up to
//! 1.9 times the light it receives at grazing incidence, and a photon tracer
//! would multiply that at every such bounce. The normative part asks a
//! physically based simulation for a BRDF that is "positive, reciprocal, and
//! energy conserving", and names couplings that are; this is Kulla and
//! Conty's (2017): `E_F(mu)` is the fraction of the light arriving at cosine
//! `mu` that the dielectric's facets (`f0_d`, `f90_d`) reflect at first
//! contact, `f0_d + (f90_d - f0_d) W(mu)` for the strongest channel of a
//! coloured `f0_d` (the specification's `1 - max_value(F)` weight on the
//! base, so that a coloured specular does not tint it, and the lobe, which
//! reflects at most that in any channel, leaves the albedo at most 1), with
//! `W` the mean Schlick weight of the normals
//! visible from that direction, and `E_avg` its cosine-weighted hemispherical
//! average; both are tabulated once over `mu` and the roughness
//! (`brdf/ggx_energy.rs`). The base then reflects exactly
//! `base_color (1 - metallic) (1 - E_F(cos_i))` of the light, the specular
//! lobe at most `E_F(cos_i)` of it (its masking loses some), so the albedo
//! is at most 1; the base is symmetric in the two directions, so the model
//! is reciprocal. At normal incidence on a smooth dielectric the base
//! reflects `0.96 base_color`, as the specification's code does to within
//! half a per cent; towards grazing angles it darkens where the
//! specification's brightens. No multiple-scattering term is added to the
//! GGX lobe, which loses energy at high roughness.
//!
//! Sampling picks the specular lobe with probability
//! `lum(F(cos_i)) / (lum(F(cos_i)) + lum(kd (1 - E_F(cos_i))))`
//! (`kd = base_color (1 - metallic)`), and then draws a normal from the
//! distribution visible from `wi` and reflects `wi` about it (pdf
//! `D_wi(h) / (4 wi.h)`); otherwise a cosine-weighted direction. A reflected
//! direction below the horizon is a failed sample (`None`).
//!
//! Two layers may lie over this base, `KHR_materials_clearcoat`'s coat
//! (`brdf/gltf_coat.rs`) and under it `KHR_materials_sheen`'s sheen
//! (`brdf/gltf_sheen.rs`):
//! ```text
//! f_r = coat + T(cos_i) T(cos_o) (sheen + S(cos_i, cos_o) (diffuse + specular))
//! ```
//! with `T` what the coat lets through and `S` the sheen's albedo scaling.
//! Each layer's weight in the odds is its albedo at `cos_i` beside what it
//! lets through times the lobes below it; the coat is sampled by its
//! visible normals, the sheen by uniform directions over the hemisphere
//! (pdf `1 / (2 pi)`: it gathers where a cosine's pdf vanishes). The pdf
//! is the mixture of all of them, and the albedo takes the base's integrals
//! weighted by what the layers let out (`albedo_under_layers`).

use super::ggx::{schlick_weight, Ggx};
use super::ggx_energy::{average_schlick_weight, schlick_energy_weight};
use super::gltf_coat::Coat;
use super::gltf_sheen::{white_albedo, Sheen};
use super::phong::check_rgb01;
use super::BrdfSample;
use crate::error::{Error, Result};
use crate::sampling::{cosine_hemisphere, cosine_hemisphere_pdf, luminance, uniform_hemisphere};
use glam::Vec3;
use std::f32::consts::FRAC_1_PI;

/// glTF's metallic-roughness BRDF; see the module docs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GltfPbr {
    ggx: Ggx,
    base_color: Vec3,
    metallic: f32,
    f0_d: Vec3,
    f90_d: f32,
    /// `KHR_materials_clearcoat` ([`Coat::NONE`] without it).
    coat: Coat,
    /// `KHR_materials_sheen` ([`Sheen::NONE`] without it), under the coat.
    sheen: Sheen,
    /// `1 / (pi (1 - E_avg))` of the strongest channel, 0 when no light
    /// enters (`E_avg = 1`) or the base has no colour (a metal): stored, as
    /// every diffuse evaluation needs it. The lobe's `f0` and `f90` and the
    /// base's `kd`, a few products each, are computed where used, so that
    /// `Brdf`, which every hit copies, stays small.
    base_scale: f32,
}

/// The pdf of [`uniform_hemisphere`], `1 / (2 pi)`.
const UNIFORM_HEMISPHERE_PDF: f32 = 0.5 * FRAC_1_PI;

/// [`GltfPbr::odds`]: the probabilities of sampling each lobe.
struct Odds {
    coat: f32,
    specular: f32,
    /// The sheen's share of the rest (0 without one).
    sheen: f32,
}

impl GltfPbr {
    /// The smallest alpha accepted (pbrt-v4's `EffectivelySmooth` bound for
    /// GGX): glTF materials smoother than this are clamped to it, or become
    /// a [`super::Mirror`] when metallic.
    pub const MIN_ALPHA: f32 = 1e-3;

    /// The glTF BRDF of `base_color`, `metallic`, GGX `alpha` (roughness
    /// squared) and dielectric reflectance at normal incidence `f0_d`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when a base colour channel, `metallic` or
    /// `f0_d` is NaN or outside [0, 1], or `alpha` NaN or outside
    /// [[`Self::MIN_ALPHA`], 1].
    pub fn new(base_color: Vec3, metallic: f32, alpha: f32, f0_d: f32) -> Result<Self> {
        Self::with_specular(base_color, metallic, alpha, Vec3::splat(f0_d), 1.0)
    }

    /// The glTF BRDF whose dielectric reflects `f0_d` (per channel) at
    /// normal incidence and `f90_d` at grazing incidence: what
    /// `KHR_materials_specular` sets. [`Self::new`] is `f0_d` grey and
    /// `f90_d = 1`.
    ///
    /// # Errors
    /// As [`Self::new`], and when an `f0_d` channel or `f90_d` is NaN or
    /// outside [0, 1].
    pub fn with_specular(
        base_color: Vec3,
        metallic: f32,
        alpha: f32,
        f0_d: Vec3,
        f90_d: f32,
    ) -> Result<Self> {
        if !(Self::MIN_ALPHA..=1.0).contains(&alpha) {
            return Err(Error::param(
                "gltf-pbr alpha",
                format!("must be in [{}, 1], got {alpha}", Self::MIN_ALPHA),
            ));
        }
        for (name, v) in [("gltf-pbr metallic", metallic), ("gltf-pbr f90_d", f90_d)] {
            if !(0.0..=1.0).contains(&v) {
                return Err(Error::param(name, format!("must be in [0, 1], got {v}")));
            }
        }
        let base_color = check_rgb01("gltf-pbr base colour", base_color)?;
        let f0_d = check_rgb01("gltf-pbr f0_d", f0_d)?;
        Ok(Self::derive(
            Ggx { alpha },
            base_color,
            metallic,
            f0_d,
            f90_d,
        ))
    }

    /// The model of checked parameters.
    fn derive(ggx: Ggx, base_color: Vec3, metallic: f32, f0_d: Vec3, f90_d: f32) -> Self {
        let mut b = GltfPbr {
            ggx,
            base_color,
            metallic,
            f0_d,
            f90_d,
            coat: Coat::NONE,
            sheen: Sheen::NONE,
            base_scale: 0.0,
        };
        b.base_scale = b.base_scale_of();
        b
    }

    /// The same model under a clear coat of weight `weight`
    /// (`clearcoatFactor`) and GGX `alpha` (`clearcoatRoughnessFactor`
    /// squared), `brdf/gltf_coat.rs`; a weight of 0 is no coat.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when `weight` is NaN or outside [0, 1],
    /// or `alpha` NaN or outside [[`Self::MIN_ALPHA`], 1].
    pub fn with_clearcoat(self, weight: f32, alpha: f32) -> Result<Self> {
        if !(0.0..=1.0).contains(&weight) {
            return Err(Error::param(
                "gltf-pbr clearcoat",
                format!("must be in [0, 1], got {weight}"),
            ));
        }
        if !(Self::MIN_ALPHA..=1.0).contains(&alpha) {
            return Err(Error::param(
                "gltf-pbr clearcoat alpha",
                format!("must be in [{}, 1], got {alpha}", Self::MIN_ALPHA),
            ));
        }
        let coat = match weight == 0.0 {
            true => Coat::NONE,
            false => Coat {
                weight,
                ggx: Ggx { alpha },
            },
        };
        Ok(GltfPbr { coat, ..self })
    }

    /// The clear coat's weight and GGX alpha (weight 0: none).
    pub fn clearcoat(&self) -> (f32, f32) {
        (self.coat.weight, self.coat.ggx.alpha)
    }

    /// The smallest sheen roughness modelled: a smaller one is raised to it
    /// (`brdf/gltf_sheen.rs`).
    pub const MIN_SHEEN_ROUGHNESS: f32 = Sheen::MIN_ROUGHNESS;

    /// The same model under a sheen of colour `color` (`sheenColorFactor`,
    /// linear RGB) and perceptual roughness `roughness`
    /// (`sheenRoughnessFactor`, raised to [`Self::MIN_SHEEN_ROUGHNESS`]),
    /// `brdf/gltf_sheen.rs`; a black colour is no sheen. The sheen lies
    /// under a clear coat, as the extensions order them.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] when a colour channel or `roughness` is
    /// NaN or outside [0, 1].
    pub fn with_sheen(self, color: Vec3, roughness: f32) -> Result<Self> {
        let color = check_rgb01("gltf-pbr sheen colour", color)?;
        if !(0.0..=1.0).contains(&roughness) {
            return Err(Error::param(
                "gltf-pbr sheen roughness",
                format!("must be in [0, 1], got {roughness}"),
            ));
        }
        let sheen = match color.max_element() > 0.0 {
            false => Sheen::NONE,
            true => Sheen {
                color,
                roughness: roughness.max(Sheen::MIN_ROUGHNESS),
            },
        };
        Ok(GltfPbr { sheen, ..self })
    }

    /// The sheen's colour and roughness (black: none).
    pub fn sheen(&self) -> (Vec3, f32) {
        (self.sheen.color, self.sheen.roughness)
    }

    /// [`GltfPbr::base_scale`] of the other parameters.
    fn base_scale_of(&self) -> f32 {
        if self.kd().max_element() <= 0.0 {
            return 0.0;
        }
        let f0 = self.f0_d.max_element();
        let rest = 1.0 - (f0 + (self.f90_d - f0) * average_schlick_weight(self.ggx.alpha));
        if rest > 0.0 {
            FRAC_1_PI / rest
        } else {
            0.0
        }
    }

    /// The same model with another base colour (a texel's), each channel
    /// clamped to [0, 1]: what a textured point needs, without the checks
    /// of [`Self::new`] on the parameters that did not change.
    pub fn with_base_color(&self, base_color: Vec3) -> Self {
        let base_color = base_color.clamp(Vec3::ZERO, Vec3::ONE);
        let base_color = if base_color.is_finite() {
            base_color
        } else {
            self.base_color
        };
        let b = Self::derive(self.ggx, base_color, self.metallic, self.f0_d, self.f90_d);
        GltfPbr {
            coat: self.coat,
            sheen: self.sheen,
            ..b
        }
    }

    /// GGX alpha (glTF's roughness squared).
    pub fn alpha(&self) -> f32 {
        self.ggx.alpha
    }

    /// Base colour.
    pub fn base_color(&self) -> Vec3 {
        self.base_color
    }

    /// Metalness.
    pub fn metallic(&self) -> f32 {
        self.metallic
    }

    /// The dielectric Fresnel reflectance at normal incidence, per channel.
    pub fn dielectric_f0(&self) -> Vec3 {
        self.f0_d
    }

    /// The dielectric Fresnel reflectance at grazing incidence (1 unless
    /// `KHR_materials_specular` scales it).
    pub fn dielectric_f90(&self) -> f32 {
        self.f90_d
    }

    /// The specular lobe's Fresnel reflectance at normal incidence,
    /// `mix(f0_d, base_color, metallic)`.
    pub fn f0(&self) -> Vec3 {
        self.f0_d.lerp(self.base_color, self.metallic)
    }

    /// The specular lobe's Fresnel reflectance at grazing incidence,
    /// `mix(f90_d, 1, metallic)`.
    pub fn f90(&self) -> f32 {
        // Written so that `f90_d = 1` gives 1 exactly, whatever `metallic`.
        self.f90_d + (1.0 - self.f90_d) * self.metallic
    }

    /// The diffuse base's colour, `base_color (1 - metallic)`.
    pub fn kd(&self) -> Vec3 {
        self.base_color * (1.0 - self.metallic)
    }

    /// Schlick's Fresnel of the specular lobe at `|wi.h| = c`, per channel.
    fn fresnel(&self, c: f32) -> Vec3 {
        let f0 = self.f0();
        f0 + (Vec3::splat(self.f90()) - f0) * schlick_weight(c)
    }

    /// `1 - E_F(mu)`: the share of the light arriving at cosine `mu` that
    /// enters the dielectric base, by the strongest channel of a coloured
    /// `f0_d` (the specification's `1 - max_value(F)`: the base is not
    /// tinted by the complement of the specular colour).
    fn entering(&self, mu: f32) -> f32 {
        let f0 = self.f0_d.max_element();
        let w = schlick_energy_weight(mu, self.ggx.alpha);
        (1.0 - (f0 + (self.f90_d - f0) * w)).max(0.0)
    }

    /// The diffuse base's value for a pair of cosines (module docs).
    fn diffuse(&self, cos_i: f32, cos_o: f32) -> Vec3 {
        if self.base_scale == 0.0 {
            return Vec3::ZERO;
        }
        self.kd() * (self.entering(cos_i) * self.entering(cos_o) * self.base_scale)
    }

    /// The base's albedo `kd (1 - E_F(cos_i))`.
    fn albedo_of_base(&self, cos_i: f32) -> Vec3 {
        if self.base_scale == 0.0 {
            return Vec3::ZERO;
        }
        self.kd() * self.entering(cos_i)
    }

    /// The probabilities of sampling, from cosine `cos_i`, the coat (0
    /// without one: its reflection beside what it lets through times the
    /// base's lobes' weights) and then the base's specular lobe.
    fn odds(&self, cos_i: f32) -> Odds {
        let mut specular = luminance(self.fresnel(cos_i));
        let mut rest = luminance(self.albedo_of_base(cos_i));
        let mut sheen = 0.0;
        if !self.sheen.is_none() {
            let e = white_albedo(cos_i, self.sheen.roughness);
            let through = (1.0 - self.sheen.color.max_element() * e).max(0.0);
            let lobe = luminance(self.sheen.color) * e;
            specular *= through;
            sheen = super::lobe_share(lobe, rest * through);
            rest = rest * through + lobe;
        }
        let coat = match self.coat.is_none() {
            true => 0.0,
            false => {
                let (reflected, through) = self.coat.reflected_and_transmitted(cos_i);
                super::lobe_share(reflected, through * (specular + rest))
            }
        };
        Odds {
            coat,
            specular: super::lobe_share(specular, rest),
            sheen,
        }
    }

    /// Evaluates the BRDF (0 when either direction is below the horizon).
    pub fn eval(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return Vec3::ZERO;
        }
        let mut base = self.diffuse(wi.z, wo.z) + self.specular(wi, wo);
        if !self.sheen.is_none() {
            base = base * self.sheen.scaling(wi.z, wo.z) + self.sheen.eval(wi, wo);
        }
        if self.coat.is_none() {
            return base;
        }
        let through = self.coat.transmitted(wi.z) * self.coat.transmitted(wo.z);
        base * through + Vec3::splat(self.coat.eval(wi, wo))
    }

    /// The specular lobe `F D G / (4 cos_i cos_o)` (both directions above
    /// the horizon).
    fn specular(&self, wi: Vec3, wo: Vec3) -> Vec3 {
        let Some((lobe, h)) = self.ggx.reflection(wi, wo) else {
            return Vec3::ZERO;
        };
        self.fresnel(wi.dot(h)) * lobe
    }

    /// Samples the coat, the specular lobe, or the cosine (the diffuse
    /// base and the sheen; see the module docs).
    pub fn sample(&self, wi: Vec3, u: [f32; 2]) -> Option<BrdfSample> {
        self.sample_with_f(wi, u).map(|(s, _)| s)
    }

    /// [`Self::sample`] and the value `f(wi, wo)` it was weighted with.
    pub(crate) fn sample_with_f(&self, wi: Vec3, u: [f32; 2]) -> Option<(BrdfSample, Vec3)> {
        if wi.z.is_nan() || wi.z <= 0.0 {
            return None;
        }
        let mut u = u;
        let odds = self.odds(wi.z);
        if !self.coat.is_none() {
            match super::pick_lobe(u[0], odds.coat) {
                (true, u0) => {
                    let wo = self.coat.ggx.sample_reflection(wi, [u0, u[1]])?;
                    return self.weighted(wi, wo, &odds);
                }
                (false, u0) => u[0] = u0,
            }
        }
        let wo = match super::pick_lobe(u[0], odds.specular) {
            (true, u0) => self.ggx.sample_reflection(wi, [u0, u[1]])?,
            (false, u0) if self.sheen.is_none() => cosine_hemisphere([u0, u[1]]),
            // The sheen gathers at grazing directions, where the cosine's
            // pdf vanishes: uniform directions keep its weights bounded.
            (false, u0) => match super::pick_lobe(u0, odds.sheen) {
                (true, u1) => uniform_hemisphere([u1, u[1]]),
                (false, u1) => cosine_hemisphere([u1, u[1]]),
            },
        };
        self.weighted(wi, wo, &odds)
    }

    /// The sample of direction `wo`, weighted by the whole BRDF and pdf.
    fn weighted(&self, wi: Vec3, wo: Vec3, odds: &Odds) -> Option<(BrdfSample, Vec3)> {
        if wo.z <= 0.0 {
            return None;
        }
        let f = self.eval(wi, wo);
        super::weighted_sample(wo, self.pdf_given(wi, wo, odds), f).map(|s| (s, f))
    }

    /// Solid-angle pdf of [`GltfPbr::sample`].
    pub fn pdf(&self, wi: Vec3, wo: Vec3) -> f32 {
        if wi.z <= 0.0 || wo.z <= 0.0 {
            return 0.0;
        }
        self.pdf_given(wi, wo, &self.odds(wi.z))
    }

    /// [`Self::pdf`] given the lobes' odds at `wi` (both directions above
    /// the horizon).
    fn pdf_given(&self, wi: Vec3, wo: Vec3, odds: &Odds) -> f32 {
        let ps = odds.specular;
        let spec = self.ggx.reflection_pdf(wi, wo);
        let mut rest = cosine_hemisphere_pdf(wo.z);
        if !self.sheen.is_none() {
            let pu = odds.sheen;
            rest = pu * UNIFORM_HEMISPHERE_PDF + (1.0 - pu) * rest;
        }
        let base = ps * spec + (1.0 - ps) * rest;
        if self.coat.is_none() {
            return base;
        }
        let pc = odds.coat;
        pc * self.coat.ggx.reflection_pdf(wi, wo) + (1.0 - pc) * base
    }

    /// Directional albedo, per channel: the base's
    /// `kd (1 - E_F(cos_i))` in closed form (module docs), and the
    /// specular lobe's `f0 E1 + (f90 - f0) Ew` from a 32 x 32 quadrature of
    /// the visible-normal sampler (`Ggx::lobe_energy`). 1024 evaluations,
    /// about 3 300 under a sheen: cache it if it is needed per hit.
    pub fn albedo(&self, wi: Vec3) -> Vec3 {
        if wi.z.is_nan() || wi.z <= 0.0 {
            return Vec3::ZERO;
        }
        if !self.sheen.is_none() {
            return self.albedo_under_layers(wi);
        }
        if self.coat.is_none() {
            return self.albedo_of_base(wi.z) + self.albedo_of_specular(wi);
        }
        // Under a coat: what it lets in, times what the base sends out
        // through it (the base's integrals weighted by T(cos_o)).
        let through = |wo: Vec3| f64::from(self.coat.transmitted(wo.z));
        let specular = self.specular_of(self.ggx.lobe_energy_weighted(wi, through));
        let diffuse = match self.kd().max_element() > 0.0 {
            true => {
                let out = self.coat.cosine_weighted_through(|mu| self.entering(mu));
                self.albedo_of_base(wi.z) * out * (std::f32::consts::PI * self.base_scale)
            }
            false => Vec3::ZERO,
        };
        Vec3::splat(self.coat.albedo(wi)) + self.coat.transmitted(wi.z) * (diffuse + specular)
    }

    /// [`Self::albedo`] under a sheen, and under a coat if there is one:
    /// the base's integrals weighted by what the sheen lets through
    /// `S(cos_i, cos_o)` and the coat lets out `T(cos_o)`, the sheen's by
    /// the latter, all under what the coat lets in, `T(cos_i)`.
    fn albedo_under_layers(&self, wi: Vec3) -> Vec3 {
        let coat_out = |mu: f32| match self.coat.is_none() {
            true => 1.0,
            false => self.coat.transmitted(mu),
        };
        let out = |mu: f32| coat_out(mu) * self.sheen.scaling(wi.z, mu);
        let specular =
            self.specular_of(self.ggx.lobe_energy_weighted(wi, |wo| f64::from(out(wo.z))));
        let diffuse = match self.kd().max_element() > 0.0 {
            true => {
                let through = cosine_weighted(|mu| self.entering(mu) * out(mu));
                self.albedo_of_base(wi.z) * through * (std::f32::consts::PI * self.base_scale)
            }
            false => Vec3::ZERO,
        };
        let sheen = self.sheen.albedo_weighted(wi, |wo| coat_out(wo.z));
        let inner = diffuse + specular + sheen;
        match self.coat.is_none() {
            true => inner,
            false => Vec3::splat(self.coat.albedo(wi)) + self.coat.transmitted(wi.z) * inner,
        }
    }

    /// The specular lobe's share of [`Self::albedo`].
    fn albedo_of_specular(&self, wi: Vec3) -> Vec3 {
        self.specular_of(self.ggx.lobe_energy(wi))
    }

    /// The specular lobe's albedo from its moments.
    fn specular_of(&self, e: super::ggx::LobeEnergy) -> Vec3 {
        let f0 = self.f0();
        f0 * e.shadowed + (Vec3::splat(self.f90()) - f0) * e.shadowed_schlick
    }
}

/// `integral e(mu) 2 mu dmu` over [0, 1] by the midpoint rule on 256 cells
/// (the tables are piecewise linear in `mu` or `sqrt(mu)`, so `e` is
/// smooth within each). `Coat::cosine_weighted_through` is the same rule
/// with the coat's `T` inside; it keeps its own loop so that a coated
/// model's albedo keeps the bits it had before the sheen.
fn cosine_weighted(e: impl Fn(f32) -> f32) -> f32 {
    const N: usize = 256;
    let mut sum = 0.0;
    for k in 0..N {
        let mu = (k as f32 + 0.5) / N as f32;
        sum += e(mu) * 2.0 * mu;
    }
    sum / N as f32
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::spherical_direction;
    use std::f64::consts::PI;

    /// The specification's formulas (Appendix B, "Specular BRDF" and
    /// "Metal BRDF and Dielectric BRDF"), in f64, as it writes them:
    /// `(metal_brdf, the dielectric's specular layer specular_brdf *
    /// dielectric_fresnel)` per channel.
    fn spec_reference(base: [f64; 3], roughness: f64, l: Vec3, v: Vec3) -> ([f64; 3], f64) {
        let (l, v) = (l.as_dvec3(), v.as_dvec3());
        let n = glam::DVec3::Z;
        let h = (l + v).normalize();
        let a = roughness * roughness;
        let a2 = a * a;
        let (nl, nv, nh, vh) = (n.dot(l), n.dot(v), n.dot(h), v.dot(h));
        let d = a2 / (PI * (nh * nh * (a2 - 1.0) + 1.0).powi(2));
        let vis = 1.0
            / (2.0
                * (nv.abs() * (a2 + (1.0 - a2) * nl * nl).sqrt()
                    + nl.abs() * (a2 + (1.0 - a2) * nv * nv).sqrt()));
        let specular_brdf = vis * d;
        let fresnel_w = (1.0 - vh.abs()).powi(5);
        let dielectric_fresnel = 0.04 + (1.0 - 0.04) * fresnel_w;
        let metal = base.map(|c| (c + (1.0 - c) * fresnel_w) * specular_brdf);
        (metal, specular_brdf * dielectric_fresnel)
    }

    const DIRS: [(f32, f32, f32, f32); 5] = [
        (0.9, 0.0, 0.8, 2.0),
        (0.5, 0.0, 0.5, 3.0),
        (0.2, 1.0, 0.95, 4.0),
        (0.05, 0.5, 0.3, 1.0),
        (1.0, 0.0, 0.999, 0.1),
    ];

    fn assert_close(got: f32, want: f64, what: &str) {
        let rel = (f64::from(got) - want).abs() / want.max(1e-3);
        assert!(rel < 2e-4, "{what}: {got} vs {want}");
    }

    #[test]
    fn metal_and_specular_layer_match_the_specification_at_fixed_angles() {
        let base = Vec3::new(0.9, 0.6, 0.2);
        for roughness in [0.05f32, 0.3, 0.7, 1.0] {
            let alpha = roughness * roughness;
            let metal = GltfPbr::new(base, 1.0, alpha, 0.04).unwrap();
            let plastic = GltfPbr::new(base, 0.0, alpha, 0.04).unwrap();
            for (ci, pi, co, po) in DIRS {
                let (l, v) = (spherical_direction(ci, pi), spherical_direction(co, po));
                let what = format!("r={roughness} cos {ci} {co}");
                let (want_metal, want_layer) =
                    spec_reference(base.as_dvec3().to_array(), roughness.into(), l, v);
                for (g, w) in metal.eval(l, v).to_array().into_iter().zip(want_metal) {
                    assert_close(g, w, &format!("metal {what}"));
                }
                // The dielectric: its specular layer is the specification's;
                // the base is the energy-conserving coupling.
                let layer = plastic.specular(l, v);
                assert_close(layer.x, want_layer, &format!("dielectric layer {what}"));
                let sum = layer + plastic.diffuse(ci, co);
                let err = (plastic.eval(l, v) - sum).abs().max_element();
                assert!(err <= 1e-6 * sum.max_element().max(1.0), "{what}: {err}");
            }
        }
    }

    #[test]
    fn the_base_is_close_to_the_specifications_at_normal_incidence() {
        // A smooth white dielectric lit head-on: the specification's base
        // reflects the cosine-weighted mean of 1 - F_d(wi.h), this one
        // 1 - E_F(1) = 0.96.
        let b = GltfPbr::new(Vec3::ONE, 0.0, GltfPbr::MIN_ALPHA, 0.04).unwrap();
        let base_albedo = (b.albedo(Vec3::Z) - b.albedo_of_specular(Vec3::Z)).x;
        let n = 400;
        let mut spec = 0.0f64;
        for i in 0..n {
            let mu = (i as f64 + 0.5) / n as f64;
            // The half vector between the normal and a direction of cosine mu.
            let vh = ((1.0 + mu) / 2.0).sqrt();
            spec += 2.0 * mu * (1.0 - (0.04 + 0.96 * (1.0 - vh).powi(5))) / n as f64;
        }
        assert!(
            (f64::from(base_albedo) - spec).abs() < 5e-3,
            "{base_albedo} vs {spec}"
        );
    }

    #[test]
    fn albedo_is_at_most_one() {
        // The case the specification's sample code gets wrong: a white,
        // smooth dielectric at grazing incidence (1.9 there).
        let mut worst = 0.0f32;
        let coloured = Vec3::new(0.5, 0.02, 1.0);
        let dielectrics = [0.0f32, 0.04, 0.17, 0.5, 1.0]
            .map(|f| (Vec3::splat(f), 1.0))
            .into_iter()
            .chain([(coloured, 1.0), (coloured, 0.5), (Vec3::splat(0.3), 0.0)]);
        let coats = [(0.0f32, 1.0f32), (1.0, 1e-3), (0.5, 0.2), (1.0, 1.0)];
        for ((f0_d, f90_d), (coat, coat_alpha)) in dielectrics.flat_map(|d| coats.map(|c| (d, c))) {
            for metallic in [0.0f32, 0.5, 1.0] {
                for k in (0..=10).step_by(2) {
                    let r = 0.032 + (1.0 - 0.032) * k as f32 / 10.0;
                    let b = GltfPbr::with_specular(Vec3::ONE, metallic, r * r, f0_d, f90_d)
                        .and_then(|b| b.with_clearcoat(coat, coat_alpha))
                        .unwrap();
                    for j in 0..=25 {
                        let c = (j as f32 / 25.0).max(1e-3);
                        let a = b.albedo(spherical_direction(c, 0.0));
                        worst = worst.max(a.max_element());
                    }
                }
            }
        }
        assert!(worst <= 1.0 + 2e-3, "largest albedo {worst}");
    }

    #[test]
    fn a_coloured_f0_and_an_f90_below_one_are_the_extensions_fresnel() {
        // KHR_materials_specular's dielectric layer: specular_brdf times
        // f0 + (f90 - f0) (1 - |v.h|)^5, per channel; the metal keeps f90 = 1.
        let (f0, f90) = (Vec3::new(0.1, 0.02, 0.3), 0.6f32);
        let base = Vec3::new(0.7, 0.5, 0.9);
        for roughness in [0.1f32, 0.5, 0.9] {
            let b = GltfPbr::with_specular(base, 0.25, roughness * roughness, f0, f90).unwrap();
            assert!((b.f90() - (0.6 + 0.4 * 0.25)).abs() < 1e-6);
            for (ci, pi, co, po) in DIRS {
                let (l, v) = (spherical_direction(ci, pi), spherical_direction(co, po));
                let (_, layer) = spec_reference([0.0; 3], roughness.into(), l, v);
                // The reference's dielectric layer is specular_brdf (0.04 + 0.96 w).
                let h = (l + v).normalize();
                let w = f64::from((1.0 - v.dot(h).abs()).powi(5));
                let specular_brdf = layer / (0.04 + 0.96 * w);
                let f0_mix = f0.lerp(base, 0.25).as_dvec3();
                let f90_mix = f64::from(b.f90());
                let got = b.specular(l, v);
                for (g, f) in got.to_array().into_iter().zip(f0_mix.to_array()) {
                    let want = specular_brdf * (f + (f90_mix - f) * w);
                    assert_close(g, want, &format!("r={roughness} cos {ci} {co}"));
                }
                // Reciprocal, base included.
                let (a, r) = (b.eval(l, v), b.eval(v, l));
                assert!((a - r).abs().max_element() <= 1e-5 * a.max_element().max(1.0));
            }
        }
    }

    #[test]
    fn a_coloured_specular_does_not_tint_the_base() {
        // The specification's 1 - max_value(F): a white base under a red
        // specular of f0 (1, 0, 0) is black, not cyan; under (0.3, 0.1,
        // 0.05) it is grey, as under a grey f0 of 0.3.
        let red = GltfPbr::with_specular(Vec3::ONE, 0.0, 0.25, Vec3::X, 1.0).unwrap();
        assert_eq!(red.diffuse(0.7, 0.4), Vec3::ZERO);
        let f0 = Vec3::new(0.3, 0.1, 0.05);
        let warm = GltfPbr::with_specular(Vec3::ONE, 0.0, 0.25, f0, 1.0).unwrap();
        let grey = GltfPbr::with_specular(Vec3::ONE, 0.0, 0.25, Vec3::splat(0.3), 1.0).unwrap();
        for (ci, co) in [(0.9f32, 0.2f32), (0.5, 0.5), (0.05, 0.8)] {
            let d = warm.diffuse(ci, co);
            assert!(d.x == d.y && d.y == d.z, "{d}");
            assert_eq!(d, grey.diffuse(ci, co));
        }
    }

    #[test]
    fn no_dielectric_reflection_leaves_a_lambertian_base() {
        // f0_d = f90_d = 0 (specularFactor 0): the base takes all the light.
        let b = GltfPbr::with_specular(Vec3::splat(0.6), 0.0, 0.3, Vec3::ZERO, 0.0).unwrap();
        for (ci, pi, co, po) in DIRS {
            let (l, v) = (spherical_direction(ci, pi), spherical_direction(co, po));
            let want = 0.6 * std::f32::consts::FRAC_1_PI;
            assert!((b.eval(l, v) - Vec3::splat(want)).abs().max_element() < 1e-7);
        }
    }

    #[test]
    fn the_coat_is_the_extensions_lobe_over_the_base_seen_through_it_twice() {
        let base = GltfPbr::new(Vec3::new(0.8, 0.2, 0.1), 0.3, 0.25, 0.04).unwrap();
        for (weight, roughness) in [(1.0f32, 0.1f32), (0.4, 0.6)] {
            let alpha = roughness * roughness;
            let coated = base.with_clearcoat(weight, alpha).unwrap();
            let through = |mu: f32| {
                let w = super::super::ggx_energy::schlick_energy_weight(mu, alpha);
                1.0 - weight * (0.04 + 0.96 * w)
            };
            for (ci, pi, co, po) in DIRS {
                let (l, v) = (spherical_direction(ci, pi), spherical_direction(co, po));
                // The coat's lobe: the specification's dielectric layer
                // (its specular_brdf times a Fresnel of 0.04), weighted.
                let (_, layer) = spec_reference([0.0; 3], roughness.into(), l, v);
                let want = base.eval(l, v) * (through(l.z) * through(v.z));
                let got = coated.eval(l, v) - Vec3::splat(weight * layer as f32);
                let err = (got - want).abs().max_element();
                let what = format!("{weight} {ci} {co}: {got} vs {want}");
                assert!(err <= 1e-4 * want.max_element().max(1.0), "{what}");
                let (a, r) = (coated.eval(l, v), coated.eval(v, l));
                assert!((a - r).abs().max_element() <= 1e-5 * a.max_element().max(1.0));
            }
        }
        // Weight 0 is no coat at all.
        assert_eq!(base.with_clearcoat(0.0, 0.3).unwrap(), base);
        assert!(base.with_clearcoat(1.5, 0.3).is_err());
        assert!(base.with_clearcoat(0.5, 0.0).is_err());
    }

    #[test]
    fn the_sheen_is_its_lobe_over_the_base_scaled_by_what_it_reflects() {
        let base = GltfPbr::new(Vec3::new(0.8, 0.2, 0.1), 0.3, 0.25, 0.04).unwrap();
        for (color, roughness) in [(Vec3::new(0.9, 0.4, 0.6), 0.3f32), (Vec3::splat(1.0), 0.8)] {
            let sheened = base.with_sheen(color, roughness).unwrap();
            let layer = super::super::gltf_sheen::Sheen { color, roughness };
            let reflected = |mu: f32| {
                color.max_element() * super::super::gltf_sheen::white_albedo(mu, roughness)
            };
            for (ci, pi, co, po) in DIRS {
                let (l, v) = (spherical_direction(ci, pi), spherical_direction(co, po));
                let scale = (1.0 - reflected(l.z)).min(1.0 - reflected(v.z)).max(0.0);
                let want = base.eval(l, v) * scale + layer.eval(l, v);
                let got = sheened.eval(l, v);
                let err = (got - want).abs().max_element();
                assert!(err <= 1e-5 * want.max_element().max(1.0), "{got} vs {want}");
                let (a, r) = (sheened.eval(l, v), sheened.eval(v, l));
                assert!((a - r).abs().max_element() <= 1e-5 * a.max_element().max(1.0));
            }
        }
        // A black sheen is none at all; the roughness is raised to its floor.
        assert_eq!(base.with_sheen(Vec3::ZERO, 0.5).unwrap(), base);
        let smooth = base.with_sheen(Vec3::ONE, 0.0).unwrap();
        assert_eq!(smooth.sheen(), (Vec3::ONE, GltfPbr::MIN_SHEEN_ROUGHNESS));
        assert!(base.with_sheen(Vec3::new(1.5, 0.0, 0.0), 0.3).is_err());
        assert!(base.with_sheen(Vec3::ONE, -0.1).is_err());
        assert!(base.with_sheen(Vec3::ONE, f32::NAN).is_err());
    }

    #[test]
    fn a_sheen_over_a_black_base_reflects_its_lobes_albedo() {
        // No specular (f0 = f90 = 0), no diffuse (black): the sheen alone,
        // whose albedo is its colour times the white lobe's, under 1.
        let black = GltfPbr::with_specular(Vec3::ZERO, 0.0, 0.25, Vec3::ZERO, 0.0).unwrap();
        for roughness in [0.07f32, 0.3, 1.0] {
            let b = black
                .with_sheen(Vec3::new(1.0, 0.5, 0.25), roughness)
                .unwrap();
            for mu in [1.0f32, 0.5, 0.1, 0.01] {
                let wi = Vec3::new((1.0 - mu * mu).sqrt(), 0.0, mu);
                let a = b.albedo(wi);
                // The table reads high (by up to 0.07, at grazing incidence).
                let e = super::super::gltf_sheen::white_albedo(mu, roughness);
                assert!(
                    a.x <= e + 1e-4 && a.x <= 1.0 + 1e-4,
                    "{roughness} {mu}: {a} {e}"
                );
                assert!(a.x >= e - 0.07 && a.x > 0.0, "{roughness} {mu}: {a} {e}");
                assert!((a.y - 0.5 * a.x).abs() <= 1e-6 && (a.z - 0.25 * a.x).abs() <= 1e-6);
            }
        }
    }

    #[test]
    fn specular_albedo_of_a_white_metal_is_ggx_energy() {
        // f0 = 1: the albedo is GGX's single-scattering energy, 1 as alpha
        // goes to 0, below 1 otherwise.
        for alpha in [GltfPbr::MIN_ALPHA, 0.1, 0.5, 1.0] {
            let b = GltfPbr::new(Vec3::ONE, 1.0, alpha, 0.04).unwrap();
            let a = b.albedo(Vec3::Z);
            assert!(a.max_element() <= 1.0 + 1e-4, "alpha={alpha}: {a}");
            assert!((a.x - a.y).abs() < 1e-6 && (a.x - a.z).abs() < 1e-6);
            if alpha < 0.01 {
                assert!(a.x > 0.999, "alpha={alpha}: {a}");
            }
        }
    }
}
