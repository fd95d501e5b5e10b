//! One BRDF analysis (rough glass alpha 0.09 or 0.0025, or Cook–Torrance
//! 0.3, at theta_in = 30°) repeated N times, for instruction counts:
//! `valgrind --tool=callgrind --callgrind-out-file=/dev/null
//! target/release/examples/analysis_one glass 4` minus the same with 1,
//! divided by 3, is one analysis (docs/reproduction.md, "Cost").
use adaptive_pm::analysis::{analyze_brdf_at, AnalysisParams, Estimator};
use adaptive_pm::brdf::{Brdf, CookTorrance, RoughDielectric};
use glam::Vec3;
fn main() {
    let which = std::env::args().nth(1).unwrap_or("glass".into());
    let reps: usize = std::env::args()
        .nth(2)
        .map(|s| s.parse().unwrap())
        .unwrap_or(5);
    let p = AnalysisParams::default();
    let b: Brdf = match which.as_str() {
        "glass" => RoughDielectric::new(0.09, 1.5, Vec3::ONE, Vec3::ZERO, false)
            .unwrap()
            .into(),
        "glass05" => RoughDielectric::new(0.0025, 1.5, Vec3::ONE, Vec3::ZERO, false)
            .unwrap()
            .into(),
        _ => CookTorrance::new(0.3, Vec3::splat(0.9), Vec3::ZERO)
            .unwrap()
            .into(),
    };
    let t = std::time::Instant::now();
    let mut a = 0.0;
    let (mut ts, mut tc) = (std::time::Duration::ZERO, std::time::Duration::ZERO);
    for _ in 0..reps {
        let d = analyze_brdf_at(&b, 0.75f32.sqrt(), Estimator::Paper, &p).unwrap();
        a += d.alpha_d;
        ts += d.sample_time;
        tc += d.cluster_time;
    }
    println!(
        "sample {:?} cluster {:?}",
        ts / reps as u32,
        tc / reps as u32
    );
    println!(
        "{which} alpha {} {:?}/analysis",
        a / reps as f32,
        t.elapsed() / reps as u32
    );
}
