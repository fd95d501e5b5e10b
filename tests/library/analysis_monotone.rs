//! The paper's estimator is stable (SPEC §5): a sharper lobe never gets a
//! larger `alpha_D`. Steps up of at most 2 % are tolerated (the estimator
//! is an average of clusterings of discrete sample sets, measured largest
//! step: 1.7 % near n = 878). The function values reported by `analyze`
//! (normal incidence for BRDFs) over the ranges it accepts.

use adaptive_pm::analysis::{analyze_brdf_at, analyze_emitter, AnalysisParams, Estimator};
use adaptive_pm::brdf::{Brdf, CookTorrance, Phong};
use adaptive_pm::emitter::CosN;
use glam::Vec3;

const SLACK: f32 = 1.02;

/// Checks that `alphas` (ordered from wide to sharp) never step up by more
/// than the slack, and names the first offender.
fn assert_non_increasing(what: &str, params: &[f32], alphas: &[f32]) {
    for i in 1..alphas.len() {
        assert!(
            alphas[i] <= alphas[i - 1] * SLACK,
            "{what}: alpha_D({}) = {} > alpha_D({}) = {} (+{:.1} %)",
            params[i],
            alphas[i],
            params[i - 1],
            alphas[i - 1],
            (alphas[i] / alphas[i - 1] - 1.0) * 100.0
        );
    }
}

#[test]
fn cosn_every_integer_n_up_to_1000() {
    let p = AnalysisParams::default();
    let ns: Vec<f32> = (0..=1000).map(|n| n as f32).collect();
    let a: Vec<f32> = ns
        .iter()
        .map(|&n| {
            analyze_emitter(&CosN::new(n).unwrap(), Estimator::Paper, &p)
                .unwrap()
                .alpha_d
        })
        .collect();
    assert_non_increasing("cos^n", &ns, &a);
    assert_eq!(a[0], 1.0);
    assert!(a[1000] < 0.01, "alpha_D(1000) = {}", a[1000]);
}

#[test]
fn phong_exponents_geometric_up_to_1e4() {
    let p = AnalysisParams::default();
    let es: Vec<f32> = (0..=190).map(|i| 1.05f32.powi(i) - 1.0).collect();
    let a: Vec<f32> = es
        .iter()
        .map(|&e| {
            let b: Brdf = Phong::new(Vec3::ZERO, Vec3::splat(0.9), e).unwrap().into();
            analyze_brdf_at(&b, 1.0, Estimator::Paper, &p)
                .unwrap()
                .alpha_d
        })
        .collect();
    assert_non_increasing("Phong", &es, &a);
}

#[test]
fn cook_torrance_rougher_is_never_smaller() {
    let p = AnalysisParams::default();
    // from the roughest (1) to nearly a mirror, over the accepted [1e-4, 1]
    let ms: Vec<f32> = (0..=100)
        .map(|i| 1.0 - i as f32 * 0.0099)
        .chain([5e-3, 1e-3, CookTorrance::MIN_ROUGHNESS])
        .collect();
    let a: Vec<f32> = ms
        .iter()
        .map(|&m| {
            let b: Brdf = CookTorrance::new(m, Vec3::splat(0.9), Vec3::ZERO)
                .unwrap()
                .into();
            analyze_brdf_at(&b, 1.0, Estimator::Paper, &p)
                .unwrap()
                .alpha_d
        })
        .collect();
    assert_non_increasing("Cook-Torrance", &ms, &a);
}
