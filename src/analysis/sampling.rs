//! Step 1 of the analysis: importance samples of the function, then a
//! regular grid of equal-solid-angle strata (`grid_cos_theta` bands of equal
//! `cos theta` width times `grid_phi` sectors). A stratum's value is the mean
//! of the importance samples inside it, or else the function at its centre
//! (paper §2.1.1): importance sampling finds narrow peaks, the strata the low
//! values.
//!
//! Normalisation to unit integral over the hemisphere: closed form for
//! `cos^n` (`(n + 1) / (2 pi)`); for a BRDF, the balance-heuristic
//! combination of the importance samples and the strata centres (treated as
//! stratified uniform samples), whose integrand `f / (N p + S / (2 pi))` is
//! bounded by `2 pi f / S`, so neither a narrow lobe nor a grazing tail can
//! blow it up.

use super::AnalysisParams;
use crate::brdf::{Brdf, BrdfAt};
use crate::rng::{hash2, Rng};
use crate::sampling::{cos_power_hemisphere, luminance, reflect_z, spherical_direction};
use glam::Vec3;
use std::f32::consts::PI;

/// The function under analysis, unnormalised (luminance of RGB).
#[derive(Clone, Copy, Debug)]
pub enum Target<'a> {
    /// Radiance `cos^n theta` of an emitter.
    CosN(f32),
    /// `f_r(wi, .)` of a BRDF for one incident direction `wi` (local frame).
    Brdf(&'a Brdf, Vec3),
}

impl Target<'_> {
    /// The function's value in direction `w` (luminance, >= 0).
    pub fn value(&self, w: Vec3) -> f32 {
        match *self {
            Target::CosN(n) => {
                if w.z <= 0.0 {
                    return 0.0;
                }
                // cos^n = (1 - sin^2)^(n/2), from x and y: exact near the pole,
                // where z = 1 - theta^2/2 has lost its digits (n up to 1e6).
                let s2 = (w.x * w.x + w.y * w.y).min(1.0);
                if s2 >= 1.0 {
                    return if n == 0.0 { 1.0 } else { 0.0 };
                }
                (0.5 * n * (-s2).ln_1p()).exp()
            }
            Target::Brdf(b, wi) => luminance(b.eval(wi, w)).max(0.0),
        }
    }

    /// The target with what its sampler needs of `wi` alone computed once.
    fn prepare(&self) -> Prepared<'_> {
        match *self {
            Target::CosN(n) => Prepared::CosN(n),
            Target::Brdf(b, wi) => Prepared::Brdf(b.at(wi)),
        }
    }

    /// Whether the function lives on the whole sphere (a transmitting
    /// BRDF, a BTDF) rather than the hemisphere about the normal.
    pub fn on_sphere(&self) -> bool {
        matches!(self, Target::Brdf(b, _) if b.is_transmissive())
    }

    fn key(&self) -> u64 {
        match *self {
            Target::CosN(n) => hash2(0xC05, n.to_bits() as u64),
            Target::Brdf(b, wi) => hash2(b.key(), wi.z.to_bits() as u64),
        }
    }
}

/// A [`Target`] prepared for many samples and evaluations ([`BrdfAt`]).
#[derive(Clone, Copy, Debug)]
enum Prepared<'a> {
    CosN(f32),
    Brdf(BrdfAt<'a>),
}

impl Prepared<'_> {
    /// A sampled direction, the function's [`Target::value`] there and the
    /// sampling pdf. A BRDF's value is the one its sampler weighed the
    /// sample with (the same bits as `value` for the reflecting models;
    /// rough glass evaluates it at the sampled microfacet normal, which
    /// `value` recovers from the directions to within rounding), so that
    /// `f` is not evaluated twice.
    fn sample(&self, u: [f32; 2]) -> Option<(Vec3, f32, f32)> {
        match *self {
            Prepared::CosN(n) => {
                let w = cos_power_hemisphere(n, u);
                Some((w, Target::CosN(n).value(w), 0.0))
            }
            Prepared::Brdf(b) => b
                .sample_with_f(u)
                .map(|(s, f)| (s.wo, luminance(f).max(0.0), s.pdf)),
        }
    }
}

/// A BRDF's [`Target::value`] and sampling pdf in direction `w`, in one
/// evaluation where the model has one (rough glass: the microfacet
/// normal is recovered once), the same bits as the two calls.
fn value_and_pdf(b: &BrdfAt<'_>, w: Vec3) -> (f32, f32) {
    let (f, pdf) = b.eval_and_pdf(w);
    (luminance(f).max(0.0), pdf)
}

/// What step 1 produces.
#[derive(Clone, Debug, Default)]
pub struct SampleSet {
    /// Importance-sampled directions (failed samples are left out).
    pub dirs: Vec<Vec3>,
    /// Azimuth of each direction in [0, 2 pi) ([`crate::sampling::phi_of`]),
    /// computed once for the strata and the peaks' solid angles.
    pub phis: Vec<f32>,
    /// The normalised function (unit integral, sr^-1) at each direction.
    pub values: Vec<f32>,
    /// Number of importance samples drawn per set (including failed ones).
    pub drawn: usize,
    /// End (exclusive) of each sample set in `dirs` and `values`.
    pub set_ends: Vec<usize>,
    /// Normalised value of each stratum.
    pub strata: Vec<f32>,
    /// Unweighted variance of the stratum values (sr^-2).
    pub variance: f32,
    /// `integral f dw` (unnormalised); 0 for an all-zero function.
    pub integral: f32,
    /// Largest unnormalised `f cos theta` seen at the samples, the strata
    /// centres, the normal and (for a BRDF) the mirror direction.
    pub max_projected: f32,
}

/// The domain of an analysed function: the hemisphere about the normal, or
/// the whole sphere (the lower half mirrors the upper: the same bands of
/// `cos theta` below the horizon, so a sphere has twice the strata).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Domain {
    /// `cos theta` in [0, 1].
    Hemisphere,
    /// `cos theta` in [-1, 1].
    Sphere,
}

impl Domain {
    /// The domain of `target`.
    pub fn of(target: &Target<'_>) -> Self {
        if target.on_sphere() {
            Domain::Sphere
        } else {
            Domain::Hemisphere
        }
    }

    /// Bands of equal `cos theta` width.
    pub fn bands(self, p: &AnalysisParams) -> usize {
        match self {
            Domain::Hemisphere => p.grid_cos_theta,
            Domain::Sphere => 2 * p.grid_cos_theta,
        }
    }

    /// Solid angle (sr).
    pub fn solid_angle(self) -> f32 {
        match self {
            Domain::Hemisphere => 2.0 * PI,
            Domain::Sphere => 4.0 * PI,
        }
    }

    /// The lowest `cos theta`.
    fn lowest_cos(self) -> f32 {
        match self {
            Domain::Hemisphere => 0.0,
            Domain::Sphere => -1.0,
        }
    }
}

/// Equal-solid-angle stratum index of a direction on the hemisphere.
#[inline]
pub fn stratum_of(w: Vec3, p: &AnalysisParams) -> usize {
    stratum_in(Domain::Hemisphere, w, p)
}

/// Centre of stratum `s` of the hemisphere.
#[inline]
pub fn stratum_centre(s: usize, p: &AnalysisParams) -> Vec3 {
    stratum_centre_in(Domain::Hemisphere, s, p)
}

/// Equal-solid-angle stratum index of a direction in `domain`.
#[inline]
pub fn stratum_in(domain: Domain, w: Vec3, p: &AnalysisParams) -> usize {
    stratum_at(domain, w.z, crate::sampling::phi_of(w), p)
}

/// [`stratum_in`] from `cos theta` and the azimuth `phi_of(w)`.
#[inline]
fn stratum_at(domain: Domain, cos_theta: f32, phi: f32, p: &AnalysisParams) -> usize {
    let (kc, kp) = (domain.bands(p), p.grid_phi);
    let lo = domain.lowest_cos();
    let c = (cos_theta.clamp(lo, 1.0) - lo) / (1.0 - lo);
    let i = ((c * kc as f32) as usize).min(kc - 1);
    let j = ((phi / (2.0 * PI) * kp as f32) as usize).min(kp - 1);
    i * kp + j
}

/// Centre of stratum `s` of `domain`.
#[inline]
pub fn stratum_centre_in(domain: Domain, s: usize, p: &AnalysisParams) -> Vec3 {
    let (i, j) = (s / p.grid_phi, s % p.grid_phi);
    let lo = domain.lowest_cos();
    let c = lo + (i as f32 + 0.5) / domain.bands(p) as f32 * (1.0 - lo);
    let phi = (j as f32 + 0.5) / p.grid_phi as f32 * 2.0 * PI;
    spherical_direction(c, phi)
}

/// How the importance samples' primary points `u` in [0, 1)^2 are placed
/// before the function's own sampler maps them onto the hemisphere.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Placement {
    /// The paper's "échantillonnage préférentiel et stratifié": a
    /// Hammersley set (`u0 = (i + o) / N`, `u1` = the base-2 radical inverse
    /// of `i` digit-scrambled), one offset `o` and one scramble from
    /// [`AnalysisParams::seed`] shared by **every** function. The set is
    /// stratified in every elementary interval of area `1 / N` (for N a power
    /// of two), and since the same points feed every function, a sharper lobe
    /// is the same point pattern pulled closer to its axis: for `cos^n`, and
    /// for Phong's lobe about the mirror direction, the clustering sees
    /// self-similar sets as n grows, so `alpha_D` cannot jump back up
    /// between neighbouring exponents by the luck of a sample set.
    #[default]
    Stratified,
    /// Independent uniform points from a per-function seed (the estimator
    /// before stratification, kept for comparison as `paper-iid`): one
    /// unlucky set can break a lobe into groups under the 10 % floor.
    Iid,
}

/// The base-2 radical inverse of `i` (van der Corput), as 32 bits.
#[inline]
fn radical_inverse_bits(i: u32) -> u32 {
    i.reverse_bits()
}

/// The `p.samples` primary points of set `set` of `placement` for `target`.
/// Stratified sets interleave: set k of K is shifted by `(k + o) / K` of one
/// stratum along `u0`, so the K sets together form one stratified set of
/// `K * samples` points.
fn points(
    target: &Target<'_>,
    placement: Placement,
    set: usize,
    p: &AnalysisParams,
) -> Vec<[f32; 2]> {
    const ONE_MINUS: f32 = 0.999_999_94;
    let n = p.samples;
    match placement {
        Placement::Stratified => {
            let mut rng = Rng::new(hash2(p.seed, 0x57A7));
            let offset = (set as f32 + rng.next_f32()) / p.sets as f32;
            let mut rng = Rng::new(hash2(hash2(p.seed, 0x57A8), set as u64));
            let scramble = rng.next_u32();
            (0..n)
                .map(|i| {
                    let u0 = (i as f32 + offset) / n as f32;
                    let bits = radical_inverse_bits(i as u32) ^ scramble;
                    let u1 = (bits >> 8) as f32 * (1.0 / (1u32 << 24) as f32);
                    [u0.min(ONE_MINUS), u1.min(ONE_MINUS)]
                })
                .collect()
        }
        Placement::Iid => {
            let mut rng = Rng::new(hash2(hash2(p.seed, target.key()), set as u64));
            (0..n)
                .map(|_| {
                    let r = rng.next_2d();
                    [r[0].min(ONE_MINUS), r[1].min(ONE_MINUS)]
                })
                .collect()
        }
    }
}

/// Runs step 1 on `target` (call [`AnalysisParams::validate`] first): the
/// `p.sets` sample sets, one after the other, and the strata and the
/// normalisation from all of them together (they interleave into one
/// stratified set of `p.sets * p.samples` points).
pub fn sample(target: Target<'_>, placement: Placement, p: &AnalysisParams) -> SampleSet {
    let n = p.samples * p.sets;
    let domain = Domain::of(&target);
    let s_count = domain.bands(p) * p.grid_phi;
    let mut dirs = Vec::with_capacity(n);
    let mut raw = Vec::with_capacity(n);
    let mut pdfs = Vec::with_capacity(n);
    let mut set_ends = Vec::with_capacity(p.sets);
    let prepared = target.prepare();
    for set in 0..p.sets {
        for u in points(&target, placement, set, p) {
            if let Some((w, value, pdf)) = prepared.sample(u) {
                if (w.z > 0.0 || domain == Domain::Sphere) && w.is_finite() {
                    dirs.push(w);
                    raw.push(value);
                    pdfs.push(pdf);
                }
            }
        }
        set_ends.push(dirs.len());
    }

    let phis: Vec<f32> = dirs.iter().map(|&w| crate::sampling::phi_of(w)).collect();
    let mut sum = vec![0.0f64; s_count];
    let mut cnt = vec![0u32; s_count];
    for ((w, &phi), &v) in dirs.iter().zip(&phis).zip(&raw) {
        let s = stratum_at(domain, w.z, phi, p);
        sum[s] += v as f64;
        cnt[s] += 1;
    }
    let mut max_projected = 0.0f32;
    let uniform = s_count as f64 / domain.solid_angle() as f64;
    let (integral, strata_raw) = match target {
        Target::CosN(e) => {
            let strata: Vec<f64> = (0..s_count)
                .map(|s| {
                    if cnt[s] > 0 {
                        sum[s] / cnt[s] as f64
                    } else {
                        target.value(stratum_centre(s, p)) as f64
                    }
                })
                .collect();
            max_projected = 1.0;
            (2.0 * std::f64::consts::PI / (e as f64 + 1.0), strata)
        }
        Target::Brdf(b, wi) => {
            let b = b.at(wi);
            // Balance heuristic over both sample sets (module docs).
            let mut integral = 0.0f64;
            for ((w, &v), &pdf) in dirs.iter().zip(&raw).zip(&pdfs) {
                integral += v as f64 / (n as f64 * pdf as f64 + uniform);
                max_projected = max_projected.max(v * w.z.abs());
            }
            let mut strata = Vec::with_capacity(s_count);
            for s in 0..s_count {
                let c = stratum_centre_in(domain, s, p);
                let (v, pdf) = value_and_pdf(&b, c);
                integral += v as f64 / (n as f64 * pdf as f64 + uniform);
                max_projected = max_projected.max(v * c.z.abs());
                strata.push(if cnt[s] > 0 {
                    sum[s] / cnt[s] as f64
                } else {
                    v as f64
                });
            }
            for w in [Vec3::Z, reflect_z(wi)] {
                max_projected = max_projected.max(target.value(w) * w.z);
            }
            (integral, strata)
        }
    };

    if integral.is_nan() || integral <= 0.0 || !integral.is_finite() {
        // All-zero function: reported diffuse by the caller.
        return SampleSet {
            drawn: p.samples,
            ..SampleSet::default()
        };
    }
    // A function on the sphere is normalised to integral 2 there: the
    // hemisphere's scale, so that the diffuse level 1 / (2 pi) of the
    // clustering and the variance threshold mean what they mean for a
    // reflecting function (a diffuse transmitter's values sit at the
    // diffuse level, like a Lambert BRDF's).
    let inv = match domain {
        Domain::Hemisphere => 1.0 / integral,
        Domain::Sphere => 2.0 / integral,
    };
    let strata: Vec<f32> = strata_raw.iter().map(|v| (v * inv) as f32).collect();
    let mean = strata.iter().map(|&v| v as f64).sum::<f64>() / s_count as f64;
    let variance = strata
        .iter()
        .map(|&v| (v as f64 - mean).powi(2))
        .sum::<f64>()
        / s_count as f64;
    SampleSet {
        values: raw.iter().map(|&v| (v as f64 * inv) as f32).collect(),
        dirs,
        phis,
        drawn: p.samples,
        set_ends,
        strata,
        variance: variance as f32,
        integral: integral as f32,
        max_projected,
    }
}
