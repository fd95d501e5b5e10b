//! Prints the measurements the SPEC asks for (run with `--ignored --nocapture`):
//! `alpha_D(n) (n + 2) / 2` over n for both estimators, and a few BRDFs.
//! Not an oracle: the oracles are in the other `analysis_*` files.

use adaptive_pm::analysis::{analyze_brdf_at, analyze_emitter, AnalysisParams, Estimator};
use adaptive_pm::brdf::{Brdf, CookTorrance, Phong};
use adaptive_pm::emitter::CosN;
use glam::Vec3;

#[test]
#[ignore]
fn report_cosn_sweep() {
    let p = AnalysisParams::default();
    println!("n | paper alpha | paper ratio | peaks | peak alpha | peak ratio");
    for n in [
        0.0f32, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0, 100.0, 200.0, 1e3, 1e6,
    ] {
        let e = CosN::new(n).unwrap();
        let a = analyze_emitter(&e, Estimator::Paper, &p).unwrap();
        let b = analyze_emitter(&e, Estimator::PeakDensity, &p).unwrap();
        println!(
            "{n} | {:.4} | {:.3} | {} | {:.4} | {:.3} | var {:.4} | {:?} {:?}",
            a.alpha_d,
            a.alpha_d * (n + 2.0) / 2.0,
            a.peaks.len(),
            b.alpha_d,
            b.alpha_d * (n + 2.0) / 2.0,
            a.variance,
            a.sample_time,
            a.cluster_time
        );
    }
    for e in [1.0f32, 10.0, 100.0, 1000.0, 1e6] {
        let b: Brdf = Phong::new(Vec3::ZERO, Vec3::splat(0.9), e).unwrap().into();
        for c in [1.0f32, 0.5, 0.1] {
            let a = analyze_brdf_at(&b, c, Estimator::Paper, &p).unwrap();
            let q = analyze_brdf_at(&b, c, Estimator::PeakDensity, &p).unwrap();
            println!(
                "phong {e} cos {c}: paper {:.4} ({} peaks) peak {:.4} {:?} {:?}",
                a.alpha_d,
                a.peaks.len(),
                q.alpha_d,
                a.sample_time,
                a.cluster_time
            );
        }
    }
    for m in [1e-4f32, 0.05, 0.3, 1.0] {
        let b: Brdf = CookTorrance::new(m, Vec3::splat(0.9), Vec3::ZERO)
            .unwrap()
            .into();
        for c in [1.0f32, 0.5, 0.1] {
            let a = analyze_brdf_at(&b, c, Estimator::Paper, &p).unwrap();
            let q = analyze_brdf_at(&b, c, Estimator::PeakDensity, &p).unwrap();
            println!(
                "ct {m} cos {c}: paper {:.4} ({} peaks) peak {:.4} {:?} {:?}",
                a.alpha_d,
                a.peaks.len(),
                q.alpha_d,
                a.sample_time,
                a.cluster_time
            );
        }
    }
}

#[test]
#[ignore]
fn report_convergence() {
    // alpha_D mean and seed spread (8 seeds) when samples and strata double.
    let fns: Vec<(&str, Option<Brdf>, f32)> = vec![
        ("cosn 10", None, 10.0),
        ("cosn 100", None, 100.0),
        (
            "phong 100",
            Some(
                Phong::new(Vec3::ZERO, Vec3::splat(0.9), 100.0)
                    .unwrap()
                    .into(),
            ),
            0.0,
        ),
        (
            "ct 0.3",
            Some(
                CookTorrance::new(0.3, Vec3::splat(0.9), Vec3::ZERO)
                    .unwrap()
                    .into(),
            ),
            0.0,
        ),
    ];
    for (name, b, n) in fns {
        for (s, gc, gp) in [
            (256usize, 16usize, 16usize),
            (512, 16, 32),
            (1024, 32, 32),
            (2048, 32, 64),
        ] {
            let a: Vec<f32> = (0..8u64)
                .map(|seed| {
                    let p = AnalysisParams {
                        samples: s,
                        grid_cos_theta: gc,
                        grid_phi: gp,
                        seed,
                        ..Default::default()
                    };
                    match &b {
                        Some(b) => {
                            analyze_brdf_at(b, 0.75f32.sqrt(), Estimator::Paper, &p)
                                .unwrap()
                                .alpha_d
                        }
                        None => {
                            analyze_emitter(&CosN::new(n).unwrap(), Estimator::Paper, &p)
                                .unwrap()
                                .alpha_d
                        }
                    }
                })
                .collect();
            let m = a.iter().sum::<f32>() / 8.0;
            let sd = (a.iter().map(|x| (x - m).powi(2)).sum::<f32>() / 7.0).sqrt();
            println!("{name} N={s} grid={gc}x{gp}: mean {m:.4} sd {sd:.4}");
        }
    }
}

/// The largest relative step up of `alpha_D` over the ranges of
/// `analysis_monotone.rs` at 16 seeds (`FAMILY=cos|phong|ct`, default all),
/// the measurement behind its slack: the step's size depends on the seed.
#[test]
#[ignore]
fn report_step_ups_over_seeds() {
    fn largest_step_up(a: &[f32]) -> (f32, usize) {
        (1..a.len())
            .map(|i| ((a[i] / a[i - 1] - 1.0).max(0.0), i))
            .fold((0.0, 0), |m, x| if x.0 > m.0 { x } else { m })
    }
    let only = std::env::var("FAMILY").ok();
    for fam in ["cos", "phong", "ct"] {
        if only.as_deref().is_some_and(|f| f != fam) {
            continue;
        }
        let mut all = Vec::new();
        for s in 0..16u64 {
            let p = AnalysisParams {
                seed: AnalysisParams::default().seed.wrapping_add(s),
                ..Default::default()
            };
            let a: Vec<f32> = match fam {
                "cos" => (0..=1000)
                    .map(|n| {
                        analyze_emitter(&CosN::new(n as f32).unwrap(), Estimator::Paper, &p)
                            .unwrap()
                            .alpha_d
                    })
                    .collect(),
                "phong" => (0..=190)
                    .map(|i| {
                        let e = 1.05f32.powi(i) - 1.0;
                        let b: Brdf = Phong::new(Vec3::ZERO, Vec3::splat(0.9), e).unwrap().into();
                        analyze_brdf_at(&b, 1.0, Estimator::Paper, &p)
                            .unwrap()
                            .alpha_d
                    })
                    .collect(),
                _ => (0..=100)
                    .map(|i| 1.0 - i as f32 * 0.0099)
                    .chain([5e-3, 1e-3, CookTorrance::MIN_ROUGHNESS])
                    .map(|m| {
                        let b: Brdf = CookTorrance::new(m, Vec3::splat(0.9), Vec3::ZERO)
                            .unwrap()
                            .into();
                        analyze_brdf_at(&b, 1.0, Estimator::Paper, &p)
                            .unwrap()
                            .alpha_d
                    })
                    .collect(),
            };
            let (m, i) = largest_step_up(&a);
            println!(
                "{fam} seed {s}: largest step up {:.2} % at index {i}",
                m * 100.0
            );
            all.push(m as f64);
        }
        let mean = all.iter().sum::<f64>() / all.len() as f64;
        let sd =
            (all.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (all.len() - 1) as f64).sqrt();
        println!("{fam}: mean {:.2} % sd {:.2} %", 100.0 * mean, 100.0 * sd);
    }
}
