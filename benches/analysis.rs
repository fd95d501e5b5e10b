//! Directionality analysis timings: step 1 (sampling) and steps 3-4
//! (clustering + solid angles, one per sample set, as the estimator runs
//! them) separately, the whole analysis of one function (`whole/`, what a
//! scene pays per emitter or per BRDF incident angle), plus whole BRDF
//! tables, rough glass included. Targets: one analysis < 1 ms, one table
//! < 20 ms, on one core.

use adaptive_pm::analysis::sampling::{sample, Placement, Target};
use adaptive_pm::analysis::{
    analyze_brdf, analyze_brdf_at, analyze_emitter, find_peaks, AnalysisParams, Estimator,
};
use adaptive_pm::brdf::{Brdf, CookTorrance, GltfPbr, Phong, RoughDielectric};
use adaptive_pm::emitter::CosN;
use criterion::{black_box, criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;

type Named = (&'static str, Option<Brdf>, f32);

fn functions() -> Vec<Named> {
    let phong = Phong::new(Vec3::ZERO, Vec3::splat(0.9), 100.0).unwrap();
    let ct = |m| CookTorrance::new(m, Vec3::splat(0.9), Vec3::ZERO).unwrap();
    let gltf = |r: f32| GltfPbr::new(Vec3::splat(0.9), 1.0, r * r, 0.04).unwrap();
    let plastic = GltfPbr::new(Vec3::new(0.8, 0.3, 0.2), 0.0, 0.25, 0.04).unwrap();
    let glass = |alpha| RoughDielectric::new(alpha, 1.5, Vec3::ONE, Vec3::ZERO, false).unwrap();
    vec![
        ("cosn10", None, 10.0),
        ("cosn100", None, 100.0),
        ("phong100", Some(phong.into()), 0.0),
        ("ct0.3", Some(ct(0.3).into()), 0.0),
        ("ct0.05", Some(ct(0.05).into()), 0.0),
        ("gltf-metal0.3", Some(gltf(0.3).into()), 0.0),
        ("gltf-plastic0.5", Some(plastic.into()), 0.0),
        // The plastic under a clear coat of roughness 0.1 (KHR_materials_clearcoat).
        (
            "gltf-coated0.1",
            Some(plastic.with_clearcoat(1.0, 0.01).unwrap().into()),
            0.0,
        ),
        // The plastic under a sheen of roughness 0.3 (KHR_materials_sheen).
        (
            "gltf-sheen0.3",
            Some(plastic.with_sheen(Vec3::splat(0.8), 0.3).unwrap().into()),
            0.0,
        ),
        // Rough glass: the analysis over the whole sphere (reflection and
        // transmission).
        ("rough-glass0.3", Some(glass(0.09).into()), 0.0),
        ("rough-glass0.05", Some(glass(0.0025).into()), 0.0),
    ]
}

fn bench(c: &mut Criterion) {
    let p = AnalysisParams::default();
    let wi = Vec3::new(0.5, 0.0, 0.75f32.sqrt());
    let mut g = c.benchmark_group("analysis");
    g.throughput(Throughput::Elements(p.samples as u64));
    for (name, b, n) in functions() {
        fn target(b: &Option<Brdf>, wi: Vec3, n: f32) -> Target<'_> {
            match b {
                Some(b) => Target::Brdf(b, wi),
                None => Target::CosN(n),
            }
        }
        g.bench_function(format!("sample/{name}"), |bn| {
            bn.iter(|| sample(black_box(target(&b, wi, n)), Placement::Stratified, &p))
        });
        let set = sample(target(&b, wi, n), Placement::Stratified, &p);
        g.bench_function(format!("cluster/{name}"), |bn| {
            bn.iter(|| {
                let mut start = 0;
                for &end in &set.set_ends {
                    let d = &set.dirs[start..end];
                    black_box(find_peaks(
                        black_box(d),
                        &set.values[start..end],
                        set.drawn,
                        &p,
                    ));
                    start = end;
                }
            })
        });
        g.bench_function(format!("whole/{name}"), |bn| match &b {
            Some(b) => bn.iter(|| analyze_brdf_at(black_box(b), wi.z, Estimator::Paper, &p)),
            None => {
                let e = CosN::new(n).unwrap();
                bn.iter(|| analyze_emitter(black_box(&e), Estimator::Paper, &p))
            }
        });
    }
    g.finish();
    let mut g = c.benchmark_group("table");
    g.sample_size(10);
    for (name, b, _) in functions() {
        if let Some(b) = b {
            g.bench_function(format!("paper/{name}"), |bn| {
                bn.iter(|| analyze_brdf(black_box(&b), Estimator::Paper, &p))
            });
        }
    }
    g.finish();
}

// No plots: criterion's plotters backend needs a system font, which these
// machines lack (it panicked after the first measurement); the numbers are
// in the terminal and in target/criterion.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = bench
}
criterion_main!(benches);
