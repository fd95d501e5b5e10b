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
fn debug_peaks() {
    let p = AnalysisParams::default();
    for n in [200.0f32, 1000.0] {
        let a = analyze_emitter(&CosN::new(n).unwrap(), Estimator::Paper, &p).unwrap();
        println!("{n}: {:?}", a.peaks);
        let set = adaptive_pm::analysis::sampling::sample(
            adaptive_pm::analysis::sampling::Target::CosN(n),
            &p,
        );
        let groups = adaptive_pm::analysis::cluster::cluster(&set.dirs, &set.values, 0.0);
        println!("dirs {} groups(limit 0) {}", set.dirs.len(), groups.len());
        let mut v = set.values.clone();
        v.sort_by(f32::total_cmp);
        println!(
            "min {} max {} above {}",
            v[0],
            v[v.len() - 1],
            v.iter()
                .filter(|&&x| x > 1.0 / (2.0 * std::f32::consts::PI))
                .count()
        );
    }
}
