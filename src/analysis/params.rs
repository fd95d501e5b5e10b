//! The constants of the directionality analysis, each a named, documented
//! field. Defaults are the paper's values where the paper gives one.

use crate::error::{Error, Result};

/// Every constant of the analysis (docs/method.md, "Directionality analysis").
///
/// Sample count and grid. Before stratification (one i.i.d. set, 8 seeds,
/// theta_in = 30° for BRDFs; mean ± sd of `alpha_D` as N and the grid
/// doubled; measured on that analysis, which the code no longer has):
///
/// | function  | N=256, 16x16 | N=512, 16x32 | N=1024, 32x32 | N=2048, 32x64 |
/// |-----------|--------------|--------------|---------------|---------------|
/// | cos^10    | 0.170 ± .014 | 0.179 ± .011 | 0.197 ± .011  | 0.192 ± .019  |
/// | cos^100   | 0.035 ± .003 | 0.039 ± .002 | 0.042 ± .001  | 0.041 ± .001  |
/// | Phong 100 | 0.048 ± .005 | 0.049 ± .011 | 0.056 ± .003  | 0.061 ± .002  |
/// | CT m=0.3  | 0.65 ± 0.45  | 0.99 ± 0.02  | 0.77 ± 0.41   | 0.55 ± 0.48   |
///
/// The seed-to-seed spread, and the bimodality on rough Cook–Torrance (a
/// wide peak's box of extreme coordinates sometimes surrounds the normal),
/// are why the default is now 24 interleaved stratified sets of 128 samples
/// whose estimates are averaged ([`AnalysisParams::sets`]): a set of 128 is
/// smaller than the paper's clustering would like (its values sit ~15 %
/// below the 512-sample ones for cos^n), but the average is stable: over 64
/// seeds its relative sd is 1.0-1.4 % on the first three rows' functions and
/// 5.2 % on Cook–Torrance (`analysis_directionality::default_analysis_is_stable_across_seeds`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AnalysisParams {
    /// Variance of the normalised function (sr^-2) below which it is diffuse
    /// and `alpha_D = 1` (paper: 0.015; for `cos^n` it passes near n = 1.56).
    pub variance_threshold: f32,
    /// A growing peak stops before the merge that would lift the variance of
    /// its values above this fraction of the global variance (paper: 0.15).
    pub peak_variance_fraction: f32,
    /// Peaks holding fewer than this fraction of all importance samples are
    /// dropped (paper: 0.10).
    pub min_peak_fraction: f32,
    /// Floor of `alpha_D` (default 1e-3): a mirror or a near-delta lobe still
    /// gets `alpha_min * N_MAX` photons, never zero.
    pub alpha_min: f32,
    /// Importance samples per sample set (default 128).
    pub samples: usize,
    /// Independent analyses per function, each on its own stratified sample
    /// set (the sets interleave into one stratified set of `sets * samples`
    /// points), whose `alpha_D` are averaged (default 24). Why: a peak's box
    /// ends at its outermost sample above the diffuse level, and as a lobe
    /// sharpens the samples cross that level one at a time, each crossing a
    /// step up of alpha_D of about `(n + 1) / (samples ln(n + 1))` for
    /// `cos^n`; averaging K sets of N splits each step into K steps K times
    /// smaller at the clustering cost of K N^2 (against (K N)^2 for one set).
    /// Measured (`tests/library/analysis_monotone.rs`): with 24 x 128 the largest
    /// step up over cos^n, n = 0..1000, is 1.57-1.76 % over 16 seeds (mean
    /// 1.68 %); over Phong exponents 0.34-3.53 % (mean 1.65 %; `cargo test
    /// --test library analysis_monotone::step_ups_over_16_seeds -- --ignored
    /// --nocapture`). With 16 x 128 it was 2.5 % at the default seed, with
    /// one set of 512, 10 % (and 48 % for Phong).
    pub sets: usize,
    /// Strata along `cos theta` of the equal-solid-angle grid (default 16).
    pub grid_cos_theta: usize,
    /// Strata along `phi` of the grid (default 32; 16 x 32 = 512 strata of
    /// 2 pi / 512 sr each).
    pub grid_phi: usize,
    /// Incident-angle nodes of a BRDF table, uniform in theta_in over
    /// [0, 90°] at cell centres (default 32: 2 bytes each, 64 bytes; the
    /// convergence test checks linear interpolation between them).
    pub theta_in_bins: usize,
    /// Seed of the importance samples (counter-based: the same function gives
    /// the same answer whatever else was analysed before).
    pub seed: u64,
}

impl Default for AnalysisParams {
    fn default() -> Self {
        AnalysisParams {
            variance_threshold: 0.015,
            peak_variance_fraction: 0.15,
            min_peak_fraction: 0.10,
            alpha_min: 1e-3,
            samples: 128,
            sets: 24,
            grid_cos_theta: 16,
            grid_phi: 32,
            theta_in_bins: 32,
            seed: 0x5EED_A11A,
        }
    }
}

/// Largest sample count or stratum count accepted (memory stays a few MB).
pub const MAX_SAMPLES: usize = 1 << 20;

impl AnalysisParams {
    /// Checks every field.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the first field out of its domain:
    /// thresholds must be finite and > 0, fractions in (0, 1], `alpha_min` in
    /// (0, 1], `samples` and the strata count in [16, 2^20], each grid side
    /// >= 1, `theta_in_bins` in [2, 4096].
    pub fn validate(&self) -> Result<()> {
        let pos = |name: &'static str, v: f32| {
            if v.is_finite() && v > 0.0 {
                Ok(())
            } else {
                Err(Error::param(
                    name,
                    format!("must be finite and > 0, got {v}"),
                ))
            }
        };
        let unit = |name: &'static str, v: f32| {
            if v > 0.0 && v <= 1.0 {
                Ok(())
            } else {
                Err(Error::param(name, format!("must be in (0, 1], got {v}")))
            }
        };
        pos("variance_threshold", self.variance_threshold)?;
        unit("peak_variance_fraction", self.peak_variance_fraction)?;
        unit("min_peak_fraction", self.min_peak_fraction)?;
        unit("alpha_min", self.alpha_min)?;
        let count = |name: &'static str, v: usize, lo: usize, hi: usize| {
            if (lo..=hi).contains(&v) {
                Ok(())
            } else {
                Err(Error::param(
                    name,
                    format!("must be in [{lo}, {hi}], got {v}"),
                ))
            }
        };
        count("samples", self.samples, 16, MAX_SAMPLES)?;
        count("grid_cos_theta", self.grid_cos_theta, 1, MAX_SAMPLES)?;
        count("grid_phi", self.grid_phi, 1, MAX_SAMPLES)?;
        count(
            "grid strata",
            self.grid_cos_theta.saturating_mul(self.grid_phi),
            16,
            MAX_SAMPLES,
        )?;
        count("theta_in_bins", self.theta_in_bins, 2, 4096)?;
        count("sets", self.sets, 1, 1024)?;
        Ok(())
    }
}
