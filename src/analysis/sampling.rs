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
use crate::brdf::Brdf;
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

    fn sample(&self, u: [f32; 2]) -> Option<(Vec3, f32)> {
        match *self {
            Target::CosN(n) => Some((cos_power_hemisphere(n, u), 0.0)),
            Target::Brdf(b, wi) => b.sample(wi, u).map(|s| (s.wo, s.pdf)),
        }
    }

    fn key(&self) -> u64 {
        match *self {
            Target::CosN(n) => hash2(0xC05, n.to_bits() as u64),
            Target::Brdf(b, wi) => hash2(b.key(), wi.z.to_bits() as u64),
        }
    }
}

/// What step 1 produces.
#[derive(Clone, Debug, Default)]
pub struct SampleSet {
    /// Importance-sampled directions (failed samples are left out).
    pub dirs: Vec<Vec3>,
    /// The normalised function (unit integral, sr^-1) at each direction.
    pub values: Vec<f32>,
    /// Number of importance samples drawn (including failed ones).
    pub drawn: usize,
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

/// Equal-solid-angle stratum index of a direction.
#[inline]
pub fn stratum_of(w: Vec3, p: &AnalysisParams) -> usize {
    let (kc, kp) = (p.grid_cos_theta, p.grid_phi);
    let i = ((w.z.clamp(0.0, 1.0) * kc as f32) as usize).min(kc - 1);
    let j = ((crate::sampling::phi_of(w) / (2.0 * PI) * kp as f32) as usize).min(kp - 1);
    i * kp + j
}

/// Centre of stratum `s`.
#[inline]
pub fn stratum_centre(s: usize, p: &AnalysisParams) -> Vec3 {
    let (i, j) = (s / p.grid_phi, s % p.grid_phi);
    let c = (i as f32 + 0.5) / p.grid_cos_theta as f32;
    let phi = (j as f32 + 0.5) / p.grid_phi as f32 * 2.0 * PI;
    spherical_direction(c, phi)
}

/// Runs step 1 on `target` (call [`AnalysisParams::validate`] first).
pub fn sample(target: Target<'_>, p: &AnalysisParams) -> SampleSet {
    let n = p.samples;
    let s_count = p.grid_cos_theta * p.grid_phi;
    let mut rng = Rng::new(hash2(p.seed, target.key()));
    // Jittered u on a k x k grid, the remainder plain random: fewer clumps
    // for the same count.
    let k = (n as f64).sqrt() as usize;
    let mut dirs = Vec::with_capacity(n);
    let mut raw = Vec::with_capacity(n);
    let mut pdfs = Vec::with_capacity(n);
    for i in 0..n {
        let r = rng.next_2d();
        let u = if i < k * k {
            [
                ((i / k) as f32 + r[0]) / k as f32,
                ((i % k) as f32 + r[1]) / k as f32,
            ]
        } else {
            r
        };
        let u = [u[0].min(0.999_999_94), u[1].min(0.999_999_94)];
        if let Some((w, pdf)) = target.sample(u) {
            if w.z > 0.0 && w.is_finite() {
                dirs.push(w);
                raw.push(target.value(w));
                pdfs.push(pdf);
            }
        }
    }

    let mut sum = vec![0.0f64; s_count];
    let mut cnt = vec![0u32; s_count];
    for (w, &v) in dirs.iter().zip(&raw) {
        let s = stratum_of(*w, p);
        sum[s] += v as f64;
        cnt[s] += 1;
    }
    let mut max_projected = 0.0f32;
    let uniform = s_count as f64 / (2.0 * std::f64::consts::PI);
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
            // Balance heuristic over both sample sets (module docs).
            let mut integral = 0.0f64;
            for ((w, &v), &pdf) in dirs.iter().zip(&raw).zip(&pdfs) {
                integral += v as f64 / (n as f64 * pdf as f64 + uniform);
                max_projected = max_projected.max(v * w.z);
            }
            let mut strata = Vec::with_capacity(s_count);
            for s in 0..s_count {
                let c = stratum_centre(s, p);
                let v = target.value(c);
                integral += v as f64 / (n as f64 * b.pdf(wi, c) as f64 + uniform);
                max_projected = max_projected.max(v * c.z);
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
            drawn: n,
            ..SampleSet::default()
        };
    }
    let inv = 1.0 / integral;
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
        drawn: n,
        strata,
        variance: variance as f32,
        integral: integral as f32,
        max_projected,
    }
}
