//! The tracer's share of raw Embree, measured in one process: each round
//! times raw `rtcIntersect1` calls on incoherent rays of the Cornell box
//! (as `adaptive-pm bench rays` does, best of 3 passes) and then one classic
//! trace, and prints the trace's rays per second over the raw rate.
//!
//! On a shared or virtual machine both rates drift by tens of percent from
//! minute to minute; a ratio taken within one round, and the median over the
//! rounds, drifts much less than two commands run apart.
//!
//! `cargo run --release --example trace_vs_raw -- [N_MAX] [THREADS] [ROUNDS] [SPLIT]`
//! (defaults 2000000, 1, 5, 0).
//! - SPLIT = L splits every triangle of the box into 4^L
//!   (`benches/common/subdivided.rs`): the same photons and paths, dearer
//!   rays. The light is left whole unless `SPLIT_LIGHTS=1`.
//! - Each round also prints the nanoseconds a ray costs on one core, raw and
//!   in the tracer; their difference is what the tracer adds to a ray.
//! - `NORAW=1` skips the raw passes (to profile the tracer alone, e.g. under
//!   `perf record`); `BATCH=B` sets the photons per parallel batch (default
//!   1024).

use adaptive_pm::embree::{measure_throughput, thread_pool, Device};
use adaptive_pm::engine::{Budget, Mode, TraceConfig, Tracer};
use adaptive_pm::scene::Scene;

#[path = "../benches/common/subdivided.rs"]
mod subdivided;

fn arg<T: std::str::FromStr>(i: usize, default: T) -> T {
    match std::env::args().nth(i) {
        None => default,
        Some(s) => s.parse().unwrap_or_else(|_| {
            eprintln!("argument {i}: {s:?} is not a number");
            std::process::exit(2)
        }),
    }
}

fn main() -> Result<(), adaptive_pm::Error> {
    let n_max: u64 = arg(1, 2_000_000);
    let threads: usize = arg(2, 1);
    let rounds: usize = arg(3, 5).max(1);
    let split: u32 = arg(4, 0);
    let skip_raw = std::env::var_os("NORAW").is_some();

    let split_lights = std::env::var_os("SPLIT_LIGHTS").is_some();
    let scene = subdivided::subdivided(&Scene::cornell()?, split, split_lights);
    let rays = if skip_raw {
        Vec::new()
    } else {
        scene
            .surface_sampler()
            .incoherent_rays(1_000_000, 1, scene.ray_epsilon())
    };
    let triangles = scene.triangle_count();
    let device = Device::new()?;
    let tracer = Tracer::new(scene.commit(&device)?);
    let pool = thread_pool(threads)?;
    let mut cfg = TraceConfig::new(Mode::Classic, Budget::NMax(n_max));
    if let Some(b) = std::env::var("BATCH").ok().and_then(|b| b.parse().ok()) {
        cfg.batch = b;
    }

    println!("{triangles} triangles, {threads} thread(s)");
    println!("round  raw Mrays/s  trace s  trace Mrays/s  of raw  raw ns  trace ns  added ns");
    let (mut ratios, mut rays_per_trace) = (Vec::new(), 0);
    for round in 0..rounds {
        let raw = if skip_raw {
            f64::NAN
        } else {
            measure_throughput(tracer.prepared().caster(), &rays, threads)?.raw_mrays_per_s
        };
        let run = pool.install(|| tracer.trace(&cfg))?;
        rays_per_trace = run.report.rays;
        let rate = rays_per_trace as f64 / run.report.trace_s / 1e6;
        ratios.push(rate / raw);
        // A thread's nanoseconds per ray: what a ray costs on one core.
        let (raw_ns, trace_ns) = (threads as f64 * 1e3 / raw, threads as f64 * 1e3 / rate);
        println!(
            "{round:>5}  {raw:>11.2}  {:>7.3}  {rate:>13.2}  {:>6.3}  {raw_ns:>6.0}  {trace_ns:>8.0}  {:>8.0}",
            run.report.trace_s,
            rate / raw,
            trace_ns - raw_ns
        );
    }
    if !skip_raw {
        ratios.sort_by(f64::total_cmp);
        println!(
            "{rays_per_trace} rays a trace on {threads} thread(s); of raw: median {:.3}, best {:.3}",
            ratios[ratios.len() / 2],
            ratios[ratios.len() - 1]
        );
    }
    Ok(())
}
