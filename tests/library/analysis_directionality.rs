//! Oracles for the directionality analysis (SPEC §2.3).
//!
//! The analysis is a pure function of its parameters, seed included (no
//! Embree, no threads: `src/analysis`), so a test at one fixed seed is
//! deterministic. The tests here that compare estimates with bounds run
//! several seeds (through `common::seed`, so a sweep draws fresh ones) and
//! measure their noise from the seed-to-seed spread; the exact ones (clamps,
//! closed forms, special cases, the cache) keep the default seed.

use adaptive_pm::analysis::{
    analyze_brdf, analyze_brdf_at, analyze_emitter, find_peaks, variance_cosn, AnalysisCache,
    AnalysisParams, Estimator,
};
use adaptive_pm::brdf::{Brdf, CookTorrance, Lambert, Mirror, Phong};
use adaptive_pm::emitter::CosN;
use adaptive_pm::rng::Rng;
use adaptive_pm::sampling::{spherical_direction, Frame};
use glam::Vec3;

use crate::common;

const BOTH: [Estimator; 2] = [Estimator::Paper, Estimator::PeakDensity];

/// Seeds a test's analyses run at: `SEEDS` of them through `common::seed`,
/// the first the default seed when no sweep is on.
const SEEDS: u64 = 8;

fn params(s: u64) -> AnalysisParams {
    let base = AnalysisParams::default().seed;
    AnalysisParams {
        seed: common::seed(base.wrapping_add(s)),
        ..Default::default()
    }
}

/// Non-increasing, from one estimate per seed at the wider (`wide`) and at
/// the sharper (`sharp`) function, paired by seed (a seed's sample points
/// are shared by every function). The mean rise, if any, must lie within 4
/// standard errors of the paired differences. When every seed gives the
/// same difference there is no noise: the difference itself must not be
/// positive. Returns the mean difference.
fn assert_no_rise(check: &str, wide: &[f32], sharp: &[f32]) -> f64 {
    let d = common::MeanVar::of(wide.iter().zip(sharp).map(|(&a, &b)| b as f64 - a as f64));
    if d.variance() == 0.0 {
        assert!(
            d.mean() <= 0.0,
            "{check}: rises by {} at every seed",
            d.mean()
        );
    } else {
        eprintln!(
            "{check}: mean change {:+.4e} = {:+.1} sigma",
            d.mean(),
            d.mean() / d.std_error()
        );
        common::assert_sigmas(check, d.mean().max(0.0), d.std_error(), 4.0);
    }
    d.mean()
}

/// The mean of `values` (one per seed) does not exceed `limit` by more than
/// 4 of its measured standard errors (no noise: it does not exceed it).
fn assert_at_most(check: &str, values: &[f32], limit: f64) {
    let m = common::MeanVar::of(values.iter().map(|&v| v as f64));
    if m.variance() == 0.0 {
        assert!(
            m.mean() <= limit,
            "{check}: {} > {limit} at every seed",
            m.mean()
        );
    } else {
        eprintln!(
            "{check}: {:.4e} +- {:.1e}, {:.1} sigma below {limit}",
            m.mean(),
            m.std_error(),
            (limit - m.mean()) / m.std_error()
        );
        common::assert_sigmas(check, (m.mean() - limit).max(0.0), m.std_error(), 4.0);
    }
}

#[test]
fn diffuse_functions_give_exactly_one() {
    let p = AnalysisParams::default();
    let e = analyze_emitter(&CosN::new(0.0).unwrap(), Estimator::Paper, &p).unwrap();
    assert_eq!(e.alpha_d, 1.0);
    assert!(e.peaks.is_empty() && e.variance == 0.0);
    let e = analyze_emitter(&CosN::new(0.0).unwrap(), Estimator::PeakDensity, &p).unwrap();
    assert_eq!(e.alpha_d, 1.0);
    let l: Brdf = Lambert::new(Vec3::new(0.7, 0.5, 0.3)).unwrap().into();
    for c in [1.0f32, 0.5, 0.05] {
        assert_eq!(
            analyze_brdf_at(&l, c, Estimator::Paper, &p)
                .unwrap()
                .alpha_d,
            1.0
        );
        // f32 rounding of luminance(albedo / pi) against luminance(albedo) / pi
        let a = analyze_brdf_at(&l, c, Estimator::PeakDensity, &p)
            .unwrap()
            .alpha_d;
        assert!((1.0 - a) < 1e-6, "{a}");
    }
    assert_eq!(
        analyze_brdf(&l, Estimator::Paper, &p).unwrap().alpha_d(0.3),
        1.0
    );
}

#[test]
fn cosn_variance_matches_closed_form_below_the_threshold() {
    // Below the threshold the strata hold the function's values at sample
    // points; the strata variance of cos^1 must match n^2/(4 pi^2 (2n+1))
    // = 0.00844 up to the grid's discretisation. Sigma: the spread of the
    // variance over 8 seeds (about 0.15 % of it), 4 standard errors of the
    // mean. Systematic: a stratum's value is the mean of importance samples
    // (pdf cos / pi) in it, so over a band of cos theta it is
    // E[cos | band] = (2/3)(b^3 - a^3)/(b^2 - a^2) rather than the band's
    // average; the variance of those values over the 16 bands, computed
    // below, is 1.45 % under the closed form (band midpoints: 0.39 %). The
    // strata hold a handful of samples each and the empty ones their centre
    // value, which puts the measured deficit (0.9 %) between the two.
    let want = variance_cosn(1.0) as f64;
    let k = AnalysisParams::default().grid_cos_theta;
    let bands: Vec<f64> = (0..k)
        .map(|i| {
            let (a, b) = (i as f64 / k as f64, (i + 1) as f64 / k as f64);
            2.0 / 3.0 * (b.powi(3) - a.powi(3)) / (b * b - a * a) / std::f64::consts::PI
        })
        .collect();
    let grid = common::MeanVar::of(bands.iter().copied());
    let grid_bias = want - grid.variance() * (k - 1) as f64 / k as f64;
    assert!(grid_bias > 0.0 && grid_bias < 0.02 * want, "{grid_bias}");
    let v = common::MeanVar::of((0..SEEDS).map(|s| {
        let d = analyze_emitter(&CosN::new(1.0).unwrap(), Estimator::Paper, &params(s)).unwrap();
        assert_eq!(d.alpha_d, 1.0, "cos^1 is below 0.015: diffuse");
        d.variance as f64
    }));
    common::assert_within_noise(
        "cos^1 strata variance",
        v.mean() - want,
        v.std_error(),
        4.0 * v.std_error() + grid_bias,
    );
}

#[test]
fn cosn_alpha_falls_with_n() {
    // Non-increasing over a grid of n: the estimates of 8 seeds at each n,
    // the steps paired by seed; a mean rise is allowed only within 4
    // standard errors of the paired steps.
    let ns = [
        0.0f32, 1.0, 2.0, 3.0, 5.0, 8.0, 12.0, 20.0, 35.0, 50.0, 80.0, 120.0, 160.0, 200.0,
    ];
    let alphas: Vec<Vec<f32>> = ns
        .iter()
        .map(|&n| {
            (0..SEEDS)
                .map(|s| {
                    analyze_emitter(&CosN::new(n).unwrap(), Estimator::Paper, &params(s))
                        .unwrap()
                        .alpha_d
                })
                .collect()
        })
        .collect();
    for i in 1..ns.len() {
        assert_no_rise(
            &format!("cos^n alpha from n={} to n={}", ns[i - 1], ns[i]),
            &alphas[i - 1],
            &alphas[i],
        );
    }
    assert_at_most("cos^200 alpha", &alphas[ns.len() - 1], 0.05);
    // The closed form, exact (no sampling).
    for n in ns {
        let b = analyze_emitter(
            &CosN::new(n).unwrap(),
            Estimator::PeakDensity,
            &AnalysisParams::default(),
        )
        .unwrap();
        assert!((b.alpha_d - 2.0 / (n + 2.0)).abs() < 1e-6);
    }
}

#[test]
fn phong_alpha_falls_with_the_exponent_and_mirror_is_the_floor() {
    // Falls over exponents a decade apart, at 8 seeds, paired by seed: the
    // mean step must be a fall, beyond 4 of its standard errors (the
    // peak-density estimator at normal incidence finds its maximum at the
    // mirror direction whatever the samples: the same at every seed).
    let p = AnalysisParams::default();
    let es = [0.0f32, 10.0, 100.0, 1000.0];
    for est in BOTH {
        let alphas: Vec<Vec<f32>> = es
            .iter()
            .map(|&e| {
                let b: Brdf = Phong::new(Vec3::ZERO, Vec3::splat(0.9), e).unwrap().into();
                (0..SEEDS)
                    .map(|s| analyze_brdf_at(&b, 1.0, est, &params(s)).unwrap().alpha_d)
                    .collect()
            })
            .collect();
        for i in 1..es.len() {
            let check = format!("{est}: Phong alpha from e={} to e={}", es[i - 1], es[i]);
            assert_no_rise(&check, &alphas[i - 1], &alphas[i]);
            // Strictly: the mean fall is significant (or exact).
            let d = common::MeanVar::of(
                alphas[i - 1]
                    .iter()
                    .zip(&alphas[i])
                    .map(|(&a, &b)| b as f64 - a as f64),
            );
            assert!(
                d.mean() < 0.0 && d.mean() + 4.0 * d.std_error() < 0.0,
                "{check}: {} +- {}",
                d.mean(),
                d.std_error()
            );
        }
        assert_at_most(&format!("{est}: Phong e=1000 alpha"), &alphas[3], 0.01);
        // Delta BRDF: the floor, without sampling.
        let m: Brdf = Mirror::new(Vec3::ONE).unwrap().into();
        assert_eq!(
            analyze_brdf_at(&m, 0.5, est, &p).unwrap().alpha_d,
            p.alpha_min
        );
        let t = analyze_brdf(&m, est, &p).unwrap();
        assert_eq!(t.alpha_d(0.5), p.alpha_min);
        assert_eq!(t.alpha_d(1.0), p.alpha_min);
    }
}

/// `count` importance samples of a flat-topped lobe around `axis`: value 30
/// within `t1` radians of the axis, falling linearly to 0 at `t2` (sampled
/// by rejection from the cap of half-angle `t2`, so directions follow the
/// function).
fn plateau(axis: Vec3, t1: f32, t2: f32, count: usize, r: &mut Rng) -> (Vec<Vec3>, Vec<f32>) {
    let f = Frame::from_normal(axis.normalize());
    let (mut d, mut v) = (Vec::new(), Vec::new());
    while d.len() < count {
        let [a, b] = r.next_2d();
        let c = 1.0 - a * (1.0 - t2.cos());
        let th = c.clamp(-1.0, 1.0).acos();
        let val = if th < t1 {
            30.0
        } else {
            30.0 * (t2 - th) / (t2 - t1)
        };
        if r.next_f32() * 30.0 < val {
            let w = f.world_from_local(spherical_direction(c, std::f32::consts::TAU * b));
            if w.z > 0.0 {
                d.push(w);
                v.push(val);
            }
        }
    }
    (d, v)
}

fn has_peak_around(peaks: &[adaptive_pm::analysis::Peak], axis: Vec3) -> bool {
    let axis = axis.normalize();
    peaks.iter().any(|pk| pk.direction.dot(axis) > 0.2f32.cos())
}

/// A rate measured over `n` independent sample sets and its standard error
/// (Agresti–Coull: `(x + 2) / (n + 4)` in the binomial variance, so that a
/// rate of 0 or 1 still has a positive sigma).
fn rate(x: u32, n: u32) -> (f64, f64) {
    let p = (x as f64 + 2.0) / (n as f64 + 4.0);
    (
        x as f64 / n as f64,
        (p * (1.0 - p) / (n as f64 + 4.0)).sqrt(),
    )
}

/// The paper's clustering is a property of the sample set, so it is tested
/// over 400 independent sample sets (seeded through `common::seed`), as
/// rates whose standard errors are measured from the same sets.
///
/// - Two flat-topped lobes, 90° apart, 300 samples each: a peak around each
///   in 17 943 of 20 000 sets as measured (89.7 %; the former 45 of 50
///   required sat at that rate, and failed one seed in three); we require
///   85 %, with a shortfall of at most 4 sigma (1.5 % at 400 sets).
/// - A third lobe of 5 % of the samples (< 10 %) is never a peak: kept in 0
///   of 20 000 sets; we require at most 1 %, again within 4 sigma.
///
/// What this does *not* claim: for two sharply peaked `cos^200` lobes the
/// method finds both in only ~22 of 50 sets (the core of a lobe holds ~13 % of
/// all samples, so the 10 % rule often drops one of them), a limitation of the
/// paper's constants that the README reports.
#[test]
fn two_separated_lobes_give_two_peaks_and_a_small_one_is_dropped() {
    const SETS: u32 = 400;
    let p = AnalysisParams::default();
    let (x, y) = (Vec3::new(0.7, 0.0, 0.7), Vec3::new(-0.7, 0.0, 0.7));
    let (mut both, mut small_dropped) = (0, 0);
    for seed in 0..SETS as u64 {
        let mut r = Rng::new(common::seed(seed));
        let (mut d, mut v) = plateau(x, 0.1, 0.2, 300, &mut r);
        let (d2, v2) = plateau(y, 0.1, 0.2, 300, &mut r);
        d.extend(d2);
        v.extend(v2);
        let peaks = find_peaks(&d, &v, d.len(), &p);
        both += u32::from(has_peak_around(&peaks, x) && has_peak_around(&peaks, y));

        let (mut d, mut v) = plateau(x, 0.1, 0.2, 570, &mut r);
        let (d3, v3) = plateau(Vec3::new(0.0, 0.7, 0.7), 0.1, 0.2, 30, &mut r);
        d.extend(d3);
        v.extend(v3);
        let peaks = find_peaks(&d, &v, d.len(), &p);
        let ok = !peaks.is_empty()
            && peaks
                .iter()
                .all(|pk| pk.direction.y.abs() < 0.3 && pk.samples as f32 >= 0.1 * d.len() as f32);
        small_dropped += u32::from(ok);
    }
    for (check, x, least) in [
        ("two lobes found", both, 0.85),
        ("small lobe dropped", small_dropped, 0.99),
    ] {
        let (r, se) = rate(x, SETS);
        eprintln!("{check}: {x}/{SETS} sample sets");
        common::assert_sigmas(check, (least - r).max(0.0), se, 4.0);
    }
}

#[test]
fn extremes_are_finite_and_documented() {
    let p = AnalysisParams::default();
    let models: Vec<Brdf> = vec![
        Phong::new(Vec3::ZERO, Vec3::ONE, 1e6).unwrap().into(),
        Phong::new(Vec3::splat(0.5), Vec3::splat(0.5), 0.0)
            .unwrap()
            .into(),
        CookTorrance::new(1e-4, Vec3::ONE, Vec3::ZERO)
            .unwrap()
            .into(),
        CookTorrance::new(1.0, Vec3::splat(0.04), Vec3::ONE)
            .unwrap()
            .into(),
    ];
    for est in BOTH {
        for b in &models {
            for c in [1.0f32, 0.5, 1e-3, 1e-6] {
                let a = analyze_brdf_at(b, c, est, &p).unwrap().alpha_d;
                assert!((p.alpha_min..=1.0).contains(&a), "{b:?} {c}: {a}");
            }
        }
        // all-zero function (albedo 0) and the horizon: diffuse, by the docs
        let black: Brdf = Phong::new(Vec3::ZERO, Vec3::ZERO, 10.0).unwrap().into();
        assert_eq!(analyze_brdf_at(&black, 0.5, est, &p).unwrap().alpha_d, 1.0);
        assert_eq!(
            analyze_brdf_at(&models[0], 0.0, est, &p).unwrap().alpha_d,
            1.0
        );
        let e = analyze_emitter(&CosN::new(1e6).unwrap(), est, &p).unwrap();
        assert_eq!(e.alpha_d, p.alpha_min);
    }
    for bad in [f32::NAN, -0.1, 1.5] {
        assert!(analyze_brdf_at(&models[0], bad, Estimator::Paper, &p).is_err());
    }
    assert!(CosN::new(f32::NAN).is_err() && CosN::new(-1.0).is_err());
    for bad in [
        AnalysisParams { samples: 0, ..p },
        AnalysisParams {
            alpha_min: 0.0,
            ..p
        },
        AnalysisParams {
            variance_threshold: f32::NAN,
            ..p
        },
        AnalysisParams {
            min_peak_fraction: 1.5,
            ..p
        },
        AnalysisParams { grid_phi: 0, ..p },
        AnalysisParams {
            theta_in_bins: 1,
            ..p
        },
    ] {
        assert!(analyze_emitter(&CosN::new(5.0).unwrap(), Estimator::Paper, &bad).is_err());
    }
}

#[test]
fn table_interpolates_direct_analyses_and_cache_runs_each_once() {
    let p = AnalysisParams::default();
    let b: Brdf = Phong::new(Vec3::splat(0.1), Vec3::splat(0.8), 30.0)
        .unwrap()
        .into();
    let t = analyze_brdf(&b, Estimator::PeakDensity, &p).unwrap();
    assert_eq!(t.len(), p.theta_in_bins);
    assert!(t.size_bytes() <= 256);
    // At a node the table returns the direct analysis up to quantisation
    // (relative step ln(1/alpha_min)/65535 ~ 1.1e-4).
    for k in [0usize, 7, 20] {
        let th = adaptive_pm::analysis::DirectionalityTable::node_theta(k, p.theta_in_bins);
        let direct = analyze_brdf_at(&b, th.cos(), Estimator::PeakDensity, &p)
            .unwrap()
            .alpha_d;
        assert!((t.alpha_d(th.cos()) - direct).abs() <= 2e-4 * direct, "{k}");
    }
    for c in [f32::NAN, -1.0, 2.0, 0.0, 1.0] {
        assert!(t.alpha_d(c).is_finite());
    }
    let mut cache = AnalysisCache::new(p, Estimator::Paper).unwrap();
    let same: Brdf = Phong::new(Vec3::splat(0.1), Vec3::splat(0.8), 30.0)
        .unwrap()
        .into();
    let t1 = cache.brdf(&b).unwrap();
    let t2 = cache.brdf(&same).unwrap();
    assert!(std::sync::Arc::ptr_eq(&t1, &t2));
    let a = cache.emitter(&CosN::new(10.0).unwrap()).unwrap();
    assert_eq!(a, cache.emitter(&CosN::new(10.0).unwrap()).unwrap());
    cache.emitter(&CosN::new(11.0).unwrap()).unwrap();
    assert_eq!(cache.analyses(), 3);
    // keyed by the exact bits: the next float up is another function, -0.0
    // and 0.0 are one
    let next: Brdf = Phong::new(
        Vec3::splat(0.1),
        Vec3::splat(0.8),
        f32::from_bits(30.0f32.to_bits() + 1),
    )
    .unwrap()
    .into();
    assert_ne!(next.param_bits(), b.param_bits());
    cache.brdf(&next).unwrap();
    assert_eq!(cache.analyses(), 4);
    cache.emitter(&CosN::new(0.0).unwrap()).unwrap();
    cache.emitter(&CosN::new(-0.0).unwrap()).unwrap();
    assert_eq!(cache.analyses(), 5);
    assert_eq!(cache.len(), 5);
}

/// The default analysis (24 averaged stratified sets of 128 samples) is
/// stable from seed to seed: over 64 seeds the relative standard deviation
/// of `alpha_D` is below 10 % for a `cos^n` emitter, Phong and rough
/// Cook–Torrance at theta_in = 30° (measured at the default seeds: 1.0 % to
/// 1.4 % for cos^10, cos^100 and Phong 100, 5.2 % for Cook–Torrance
/// m = 0.3). The single i.i.d. set it replaced spread far more (the table
/// in `AnalysisParams`' docs: 22 % on Phong 100 at 512 samples, 70 % and
/// bimodal on Cook–Torrance): a bound of 10 % lies between the two, and a
/// spread estimated from 64 seeds has a standard error of 9 % of itself.
#[test]
fn default_analysis_is_stable_across_seeds() {
    let theta_in = 0.75f32.sqrt();
    let functions: [(&str, Option<Brdf>, f32); 4] = [
        ("cos^10", None, 10.0),
        ("cos^100", None, 100.0),
        (
            "Phong 100",
            Some(
                Phong::new(Vec3::ZERO, Vec3::splat(0.9), 100.0)
                    .unwrap()
                    .into(),
            ),
            0.0,
        ),
        (
            "Cook-Torrance 0.3",
            Some(
                CookTorrance::new(0.3, Vec3::splat(0.9), Vec3::ZERO)
                    .unwrap()
                    .into(),
            ),
            0.0,
        ),
    ];
    for (name, brdf, n) in functions {
        let alphas = (0..64).map(|s| {
            let p = params(s);
            let a = match &brdf {
                Some(b) => analyze_brdf_at(b, theta_in, Estimator::Paper, &p),
                None => analyze_emitter(&CosN::new(n).unwrap(), Estimator::Paper, &p),
            };
            a.unwrap().alpha_d as f64
        });
        let m = common::MeanVar::of(alphas);
        let rel = m.variance().sqrt() / m.mean();
        eprintln!("{name}: alpha_D {:.4}, relative sd {:.3}", m.mean(), rel);
        assert!(rel < 0.1, "{name}: relative sd {rel} over 64 seeds");
    }
}
