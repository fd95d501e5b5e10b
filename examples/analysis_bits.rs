//! The bits of alpha_D, the variance and every peak of the analyses of 15
//! BRDFs (rough glass of five alphas, thin or not, included) at 8 incident
//! angles and 7 `cos^n` emitters, for all three estimators: run before and
//! after a change to the analysis and `cmp` the outputs to show that it
//! changed no result (docs/reproduction.md, "Cost").
use adaptive_pm::analysis::{analyze_brdf_at, analyze_emitter, AnalysisParams, Estimator};
use adaptive_pm::brdf::{Brdf, CookTorrance, GltfPbr, Phong, RoughDielectric};
use adaptive_pm::emitter::CosN;
use glam::Vec3;
fn main() {
    let p = AnalysisParams::default();
    let mut fs: Vec<(String, Brdf)> = vec![
        (
            "phong100".into(),
            Phong::new(Vec3::ZERO, Vec3::splat(0.9), 100.0)
                .unwrap()
                .into(),
        ),
        (
            "ct0.3".into(),
            CookTorrance::new(0.3, Vec3::splat(0.9), Vec3::ZERO)
                .unwrap()
                .into(),
        ),
        (
            "ct0.05".into(),
            CookTorrance::new(0.05, Vec3::splat(0.9), Vec3::ZERO)
                .unwrap()
                .into(),
        ),
        (
            "gm0.3".into(),
            GltfPbr::new(Vec3::splat(0.9), 1.0, 0.09, 0.04)
                .unwrap()
                .into(),
        ),
        (
            "gp".into(),
            GltfPbr::new(Vec3::new(0.8, 0.3, 0.2), 0.0, 0.25, 0.04)
                .unwrap()
                .into(),
        ),
    ];
    for a in [0.0025f32, 0.01, 0.09, 0.3, 1.0] {
        for thin in [false, true] {
            fs.push((
                format!("glass{a}{thin}"),
                RoughDielectric::new(a, 1.5, Vec3::new(0.9, 0.8, 1.0), Vec3::ZERO, thin)
                    .unwrap()
                    .into(),
            ));
        }
    }
    for est in Estimator::ALL {
        for (name, b) in &fs {
            for k in 0..8 {
                let c = (k as f32 + 0.5) / 8.0;
                let d = analyze_brdf_at(b, c, est, &p).unwrap();
                let pk: Vec<String> = d
                    .peaks
                    .iter()
                    .map(|q| {
                        format!(
                            "{}:{:08x}:{:08x}",
                            q.samples,
                            q.solid_angle.to_bits(),
                            q.mean_value.to_bits()
                        )
                    })
                    .collect();
                println!(
                    "{est} {name} {k} {:08x} {:08x} {}",
                    d.alpha_d.to_bits(),
                    d.variance.to_bits(),
                    pk.join(",")
                );
            }
        }
        for n in [1.0f32, 3.0, 10.0, 50.0, 100.0, 1000.0, 1e5] {
            let d = analyze_emitter(&CosN::new(n).unwrap(), est, &p).unwrap();
            println!(
                "{est} cos{n} {:08x} {:08x} {}",
                d.alpha_d.to_bits(),
                d.variance.to_bits(),
                d.peaks.len()
            );
        }
    }
}
