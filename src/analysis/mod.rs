//! Directionality analysis of emission profiles and BRDFs (paper §2.1;
//! docs/method.md, "Directionality analysis"): `alpha_D` in [`alpha_min`, 1],
//! 1 for a diffuse function, towards 0 for a single sharp direction.
//!
//! The analysed function is the emitter's radiance `cos^n` or a BRDF's
//! `f_r(wi, .)` (luminance of RGB; `f`, not `f cos`), normalised to unit
//! integral over the hemisphere. Two estimators:
//! - [`Estimator::Paper`] (default): [`sampling`] (importance samples placed
//!   by a stratified low-discrepancy set shared by every function, the
//!   paper's "échantillonnage préférentiel et stratifié", + equal-solid-angle
//!   strata) → variance of the strata against
//!   `variance_threshold` (below: `alpha_D = 1`) → [`cluster`] (greedy
//!   complete linkage above the diffuse level, O(m^2)) → peaks holding at
//!   least `min_peak_fraction` of the samples → `alpha_D = sum omega_i / 2 pi`
//!   from [`solid_angle`];
//! - [`Estimator::PaperIid`]: the same with independent random importance
//!   samples per function (kept for comparison; not monotone in `n`);
//! - [`Estimator::PeakDensity`]: `alpha_D = 1 / (pi max p)` with `p` the
//!   normalised density of the re-emitted direction (`f cos / integral f cos`):
//!   closed form `2 / (n + 2)` for `cos^n`; for a BRDF the maximum is taken
//!   over the importance samples, the strata centres, the normal and the
//!   mirror direction, and the normalisation is the BRDF's albedo.
//!
//! Both are clamped to [`alpha_min`, 1]. Documented special cases: a delta
//! BRDF (mirror) gets `alpha_min` and a Lambert BRDF 1, both without sampling; an all-zero function
//! (albedo 0, or an incident direction at or below the horizon) is reported
//! diffuse, `alpha_D = 1` with no peaks, the limit of a vanishing diffuse
//! albedo (its photon count is 0 anyway through `alpha_E`).
//!
//! A transmitting BRDF (rough glass) scatters over the whole sphere, so it
//! is analysed there ([`sampling::Domain::Sphere`]): twice the strata,
//! normalised to the hemisphere's scale (integral 2) so that the variance
//! threshold and the clustering's diffuse level keep their meaning, and
//! `alpha_D = sum omega_i / 4 pi`, so that a diffuse transmitter gets 1 and a
//! lobe of a given size half what it gets on the hemisphere (its photons
//! spread over twice the directions). Smooth glass is a delta: `alpha_min`.
//! The table is made for light arriving from outside; the tracer reads it at
//! `|cos theta|` from inside too (alpha_D sets a photon count, never a
//! weight, so that only changes variance).
//!
//! Analyses run once per distinct function ([`AnalysisCache`]); BRDFs are
//! tabulated over theta_in ([`DirectionalityTable`]).
//!
//! [`alpha_min`]: AnalysisParams::alpha_min

pub mod cache;
pub mod cluster;
pub mod params;
pub mod sampling;
pub mod solid_angle;
pub mod table;

pub use cache::AnalysisCache;
pub use params::AnalysisParams;
pub use table::DirectionalityTable;

use crate::brdf::Brdf;
use crate::emitter::CosN;
use crate::error::{Error, Result};
use crate::sampling::luminance;
use glam::Vec3;
use sampling::{Placement, Target};
use std::time::{Duration, Instant};

/// Which `alpha_D` estimator to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Estimator {
    /// The paper's: variance test, clustering, peak solid angles, on
    /// stratified importance samples ([`sampling::Placement::Stratified`]).
    #[default]
    Paper,
    /// The paper's method on i.i.d. importance samples
    /// ([`sampling::Placement::Iid`]), for comparison only.
    PaperIid,
    /// `1 / (pi max p)`: keeps the peak photon density of a function equal
    /// to a diffuse one's by construction.
    PeakDensity,
}

impl Estimator {
    /// Every estimator, in the order the CLI lists them.
    pub const ALL: [Estimator; 3] = [
        Estimator::Paper,
        Estimator::PaperIid,
        Estimator::PeakDensity,
    ];

    /// How this estimator places its importance samples.
    pub fn placement(self) -> Placement {
        match self {
            Estimator::PaperIid => Placement::Iid,
            Estimator::Paper | Estimator::PeakDensity => Placement::Stratified,
        }
    }
}

impl std::str::FromStr for Estimator {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s {
            "paper" => Ok(Estimator::Paper),
            "paper-iid" => Ok(Estimator::PaperIid),
            "peak" | "peak-density" => Ok(Estimator::PeakDensity),
            _ => Err(Error::param(
                "directionality",
                format!("expected `paper`, `paper-iid` or `peak`, got `{s}`"),
            )),
        }
    }
}

impl std::fmt::Display for Estimator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Estimator::Paper => "paper",
            Estimator::PaperIid => "paper-iid",
            Estimator::PeakDensity => "peak",
        })
    }
}

/// One peak found by the clustering.
#[derive(Clone, Debug, PartialEq)]
pub struct Peak {
    /// Importance samples in the peak.
    pub samples: usize,
    /// Solid angle of its box of extreme spherical coordinates (sr).
    pub solid_angle: f32,
    /// Mean normalised value of its samples (sr^-1).
    pub mean_value: f32,
    /// Normalised mean direction of its samples (local frame).
    pub direction: Vec3,
}

/// The result of one analysis.
#[derive(Clone, Debug, PartialEq)]
pub struct Directionality {
    /// `alpha_D` in [`alpha_min`, 1](AnalysisParams::alpha_min).
    pub alpha_d: f32,
    /// Peaks kept (empty when the function is diffuse, or for the
    /// peak-density estimator).
    pub peaks: Vec<Peak>,
    /// Variance of the normalised function over the strata (sr^-2).
    pub variance: f32,
    /// Time of step 1 (sampling and strata).
    pub sample_time: Duration,
    /// Time of steps 3-4 (clustering and solid angles).
    pub cluster_time: Duration,
}

impl Directionality {
    fn diffuse(variance: f32, sample_time: Duration) -> Self {
        Directionality {
            alpha_d: 1.0,
            peaks: Vec::new(),
            variance,
            sample_time,
            cluster_time: Duration::ZERO,
        }
    }
}

/// Clusters a sample set and turns the kept groups into peaks (steps 3-4).
/// Public so that synthetic sample sets can be analysed directly.
///
/// Samples above and below the surface (`z >= 0`, `z < 0`) are clustered
/// apart: a glass's reflection and refraction lobes are two peaks however
/// close the clustering's linkage would put them (a hemisphere's samples are
/// all on one side, so it is unchanged). The diffuse level and the 10 % rule
/// stay those of the whole set.
pub fn find_peaks(dirs: &[Vec3], values: &[f32], drawn: usize, p: &AnalysisParams) -> Vec<Peak> {
    let phis: Vec<f32> = dirs.iter().map(|&w| crate::sampling::phi_of(w)).collect();
    Scratch::default().peaks_of(dirs, &phis, values, drawn, p)
}

/// The buffers of steps 3-4, kept from one sample set to the next (an
/// analysis has 24; their allocations were a twentieth of its work).
#[derive(Debug, Default)]
struct Scratch {
    live: cluster::Live,
    /// One side's samples, when a set has both.
    side_dirs: Vec<Vec3>,
    side_phis: Vec<f32>,
    side_values: Vec<f32>,
    /// One group's directions and azimuths.
    group_dirs: Vec<Vec3>,
    group_phis: Vec<f32>,
}

impl Scratch {
    /// [`find_peaks`] with each direction's azimuth `phis[i] =
    /// phi_of(dirs[i])` given (the sampling computed them for the strata
    /// already).
    fn peaks_of(
        &mut self,
        dirs: &[Vec3],
        phis: &[f32],
        values: &[f32],
        drawn: usize,
        p: &AnalysisParams,
    ) -> Vec<Peak> {
        let n = values.len().max(1) as f64;
        let mean = values.iter().map(|&v| v as f64).sum::<f64>() / n;
        let global = values
            .iter()
            .map(|&v| (v as f64 - mean).powi(2))
            .sum::<f64>()
            / n;
        let level = p.peak_variance_fraction as f64 * global;
        let min_samples = p.min_peak_fraction as f64 * drawn.max(values.len()) as f64;
        let mut peaks = Vec::new();
        if dirs.iter().all(|d| d.z >= 0.0) {
            // One side (every hemisphere's set): no copies.
            self.keep(dirs, phis, values, (level, min_samples), &mut peaks);
            return peaks;
        }
        for above in [true, false] {
            let (mut d, mut a, mut v) = (
                std::mem::take(&mut self.side_dirs),
                std::mem::take(&mut self.side_phis),
                std::mem::take(&mut self.side_values),
            );
            d.clear();
            a.clear();
            v.clear();
            for (i, w) in dirs.iter().enumerate() {
                if (w.z >= 0.0) == above {
                    d.push(*w);
                    a.push(phis[i]);
                    v.push(values[i]);
                }
            }
            if !d.is_empty() {
                self.keep(&d, &a, &v, (level, min_samples), &mut peaks);
            }
            (self.side_dirs, self.side_phis, self.side_values) = (d, a, v);
        }
        peaks
    }

    /// Clusters one side and appends its groups of at least `min_samples`
    /// as peaks; `level` is the clustering's variance limit.
    fn keep(
        &mut self,
        dirs: &[Vec3],
        phis: &[f32],
        values: &[f32],
        (level, min_samples): (f64, f64),
        peaks: &mut Vec<Peak>,
    ) {
        for g in cluster::cluster_in(&mut self.live, dirs, values, level) {
            if g.len() as f64 >= min_samples {
                peaks.push(self.peak(&g, dirs, phis, values));
            }
        }
    }

    /// A kept group's solid angle, mean value and mean direction.
    fn peak(&mut self, group: &[u32], dirs: &[Vec3], phis: &[f32], values: &[f32]) -> Peak {
        let (d, a) = (&mut self.group_dirs, &mut self.group_phis);
        d.clear();
        d.extend(group.iter().map(|&i| dirs[i as usize]));
        a.clear();
        a.extend(group.iter().map(|&i| phis[i as usize]));
        let mean_value = group
            .iter()
            .map(|&i| values[i as usize] as f64)
            .sum::<f64>()
            / group.len() as f64;
        Peak {
            samples: group.len(),
            solid_angle: solid_angle::solid_angle_at(d, a),
            mean_value: mean_value as f32,
            direction: d.iter().copied().sum::<Vec3>().normalize_or_zero(),
        }
    }
}

/// The paper's estimate on each of the `p.sets` sample sets, averaged;
/// the peaks listed are those of set 0.
fn paper(target: Target<'_>, est: Estimator, p: &AnalysisParams) -> Directionality {
    let t = Instant::now();
    let domain = sampling::Domain::of(&target);
    let set = sampling::sample(target, est.placement(), p);
    let sample_time = t.elapsed();
    if set.integral <= 0.0 || set.variance < p.variance_threshold {
        return Directionality::diffuse(set.variance, sample_time);
    }
    let t = Instant::now();
    let (mut sum, mut first, mut start) = (0.0f64, None, 0);
    let mut scratch = Scratch::default();
    for &end in &set.set_ends {
        let peaks = scratch.peaks_of(
            &set.dirs[start..end],
            &set.phis[start..end],
            &set.values[start..end],
            set.drawn,
            p,
        );
        start = end;
        let omega: f32 = peaks.iter().map(|pk| pk.solid_angle).sum();
        sum += (omega / domain.solid_angle()).clamp(p.alpha_min, 1.0) as f64;
        first.get_or_insert(peaks);
    }
    Directionality {
        alpha_d: ((sum / p.sets as f64) as f32).clamp(p.alpha_min, 1.0),
        peaks: first.unwrap_or_default(),
        variance: set.variance,
        sample_time,
        cluster_time: t.elapsed(),
    }
}

/// `alpha_D = 1 / (pi max p)` clamped to [`alpha_min`, 1].
fn peak_alpha(max_p: f64, p: &AnalysisParams) -> f32 {
    if max_p.is_nan() || max_p <= 0.0 {
        return 1.0;
    }
    ((1.0 / (std::f64::consts::PI * max_p)) as f32).clamp(p.alpha_min, 1.0)
}

/// Directionality of a `cos^n` emitter.
///
/// # Errors
/// [`Error::InvalidParameter`] when `p` does not validate.
pub fn analyze_emitter(e: &CosN, est: Estimator, p: &AnalysisParams) -> Result<Directionality> {
    p.validate()?;
    let n = e.exponent();
    match est {
        Estimator::PeakDensity => {
            // p = (n + 2) / (2 pi) cos^(n+1): max at the normal, closed form.
            let max_p = (n as f64 + 2.0) / (2.0 * std::f64::consts::PI);
            let mut d = Directionality::diffuse(variance_cosn(n), Duration::ZERO);
            d.alpha_d = peak_alpha(max_p, p);
            Ok(d)
        }
        Estimator::Paper | Estimator::PaperIid => Ok(paper(Target::CosN(n), est, p)),
    }
}

/// Variance of normalised `cos^n` over the hemisphere,
/// `n^2 / (4 pi^2 (2n + 1))` (docs/method.md, "The analysed function").
pub fn variance_cosn(n: f32) -> f32 {
    let n = n as f64;
    (n * n / (4.0 * std::f64::consts::PI.powi(2) * (2.0 * n + 1.0))) as f32
}

/// Directionality of a BRDF for one incident direction of cosine
/// `cos_theta_in` (isotropic: azimuth 0).
///
/// # Errors
/// [`Error::InvalidParameter`] when `cos_theta_in` is NaN or outside [0, 1],
/// or `p` does not validate.
pub fn analyze_brdf_at(
    b: &Brdf,
    cos_theta_in: f32,
    est: Estimator,
    p: &AnalysisParams,
) -> Result<Directionality> {
    p.validate()?;
    if !(0.0..=1.0).contains(&cos_theta_in) {
        return Err(Error::param(
            "cos_theta_in",
            format!("must be in [0, 1], got {cos_theta_in}"),
        ));
    }
    if matches!(b, Brdf::Lambert(_)) {
        // Constant over the hemisphere: variance 0, diffuse, by definition;
        // sampling it (3072 samples per incident angle) would only confirm it.
        return Ok(Directionality::diffuse(0.0, Duration::ZERO));
    }
    if b.is_delta() {
        let mut d = Directionality::diffuse(f32::INFINITY, Duration::ZERO);
        d.alpha_d = p.alpha_min;
        return Ok(d);
    }
    let sin = (1.0 - cos_theta_in * cos_theta_in).max(0.0).sqrt();
    let wi = Vec3::new(sin, 0.0, cos_theta_in);
    if est != Estimator::PeakDensity {
        return Ok(paper(Target::Brdf(b, wi), est, p));
    }
    let t = Instant::now();
    let set = sampling::sample(Target::Brdf(b, wi), est.placement(), p);
    let sample_time = t.elapsed();
    let albedo = luminance(b.albedo(wi)) as f64;
    let max_p = if albedo > 0.0 {
        set.max_projected as f64 / albedo
    } else {
        0.0
    };
    let mut d = Directionality::diffuse(set.variance, sample_time);
    d.alpha_d = peak_alpha(max_p, p);
    Ok(d)
}

/// Tabulates a BRDF's `alpha_D` over `p.theta_in_bins` incident angles.
/// A delta BRDF gets the floor everywhere without sampling.
///
/// # Errors
/// [`Error::InvalidParameter`] when `p` does not validate.
pub fn analyze_brdf(b: &Brdf, est: Estimator, p: &AnalysisParams) -> Result<DirectionalityTable> {
    p.validate()?;
    let bins = p.theta_in_bins;
    let (mut ts, mut tc) = (Duration::ZERO, Duration::ZERO);
    let mut alphas = Vec::with_capacity(bins);
    for k in 0..bins {
        let c = DirectionalityTable::node_theta(k, bins).cos();
        let d = analyze_brdf_at(b, c, est, p)?;
        ts += d.sample_time;
        tc += d.cluster_time;
        alphas.push(d.alpha_d);
    }
    Ok(DirectionalityTable::from_values(
        &alphas,
        p.alpha_min,
        ts,
        tc,
    ))
}
