//! One run of the trade study: trace, build, render, and the three errors.

use super::reference::Reference;
use super::{Contender, Run, TradeoffConfig};
use crate::embree::EmbreeScene;
use crate::engine::config::INT_MAX;
use crate::engine::{TraceOutput, Tracer};
use crate::error::Result;
use crate::photon_map::PhotonMap;
use crate::render::{
    irradiance_estimate, relative_rmse_masked, render, render_reading, Image, Lookup, MapReads,
    RenderMaps, View,
};
use crate::rng::hash2;
use crate::scene::SurfacePoint;
use std::sync::Arc;
use std::time::Instant;

/// What a run leaves for the bias/variance split: its indirect and full
/// images and its points' irradiance.
pub(crate) struct RunOutput {
    pub indirect: Image,
    pub full: Image,
    pub points: Vec<f64>,
}

/// k of the estimates for a budget: `sqrt(N_MAX) / 2` in 20..=1000.
pub fn k_for(n_max: u64) -> usize {
    ((n_max as f64).sqrt() / 2.0).round().clamp(20.0, 1000.0) as usize
}

/// `sqrt(mean (a - r)^2) / mean(r)` (0 when `mean(r)` is not positive).
pub fn rel_rmse(a: &[f64], r: &[f64]) -> f64 {
    let n = a.len().min(r.len()).max(1) as f64;
    let mse = a.iter().zip(r).map(|(x, y)| (x - y) * (x - y)).sum::<f64>() / n;
    let mean = r.iter().sum::<f64>() / n;
    if mean > 0.0 {
        mse.sqrt() / mean
    } else {
        0.0
    }
}

// A tracer of its own per run, as a user starting a run would have: its
// time includes the directionality analysis (and the importance pass).
fn trace(
    prepared: &Arc<EmbreeScene>,
    cfg: &TradeoffConfig,
    who: Contender,
    n_max: u64,
    seed: u64,
) -> Result<TraceOutput> {
    let rc = cfg.render_config(cfg.spp, seed);
    Tracer::new(Arc::clone(prepared)).trace(&who.trace_config(n_max, seed, &rc))
}

/// Irradiance (mean over RGB) at each point from `map` alone.
pub(crate) fn points_irradiance(map: &PhotonMap, pts: &[SurfacePoint], k: usize) -> Vec<f64> {
    let mut scratch = Vec::with_capacity(k);
    let lk = Lookup {
        k,
        max_radius: f32::INFINITY,
    };
    pts.iter()
        .map(|p| {
            let e = irradiance_estimate(map, p.position, p.normal, lk, &mut scratch).value;
            (e.x as f64 + e.y as f64 + e.z as f64) / 3.0
        })
        .collect()
}

/// The reference-free error estimate of a budget from two half-budget maps
/// (see [`super`]): `rms(E_A - E_B) / sqrt(2) / mean`.
pub(crate) fn estimated_error(
    prepared: &Arc<EmbreeScene>,
    cfg: &TradeoffConfig,
    who: Contender,
    n_max: u64,
    seed: u64,
    pts: &[SurfacePoint],
) -> Result<f64> {
    let k = k_for(n_max);
    let half = (n_max / 2).max(1);
    let mut e = Vec::new();
    for s in [hash2(seed, 0xA), hash2(seed, 0xB)] {
        let map = PhotonMap::build(&trace(prepared, cfg, who, half, s)?.records());
        e.push(points_irradiance(&map, pts, k));
    }
    let mean: f64 = e.iter().flatten().sum::<f64>() / (2 * pts.len()).max(1) as f64;
    let ms = e[0]
        .iter()
        .zip(&e[1])
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / pts.len().max(1) as f64;
    Ok(if mean > 0.0 {
        (ms / 2.0).sqrt() / mean
    } else {
        0.0
    })
}

/// Measures one run.
pub(crate) fn measure_run(
    prepared: &Arc<EmbreeScene>,
    cfg: &TradeoffConfig,
    reference: &Reference,
    who: Contender,
    n_max: u64,
    seed: u64,
) -> Result<(Run, RunOutput)> {
    let k = k_for(n_max);
    let t = Instant::now();
    let out = trace(prepared, cfg, who, n_max, seed)?;
    let trace_s = t.elapsed().as_secs_f64();
    let importance_s = out.report.importance.as_ref().map_or(0.0, |i| i.pass_s);
    let records = out.records();
    let t = Instant::now();
    let maps = RenderMaps::build(&records);
    let build_s = t.elapsed().as_secs_f64();
    let mut rc = cfg.render_config(cfg.spp, seed);
    rc.k = k;
    let reads = MapReads::new(&maps);
    let t = Instant::now();
    let (full, _) = render_reading(prepared, &reads, &rc)?;
    let render_s = t.elapsed().as_secs_f64();
    let read_share = reads.share(&records)?;
    let read_share_pixels = reads.share_without_cache_build(&records)?;
    rc.view = View::DirectOnly;
    let direct = render(prepared, Some(&maps), &rc)?;
    let mut indirect = full.clone();
    for (p, d) in indirect.pixels.iter_mut().zip(&direct.pixels) {
        *p = (*p - *d).max(glam::Vec3::ZERO);
    }
    let points = points_irradiance(&maps.full, &reference.points, k);
    let run = Run {
        mode: who,
        quality: (n_max as f64 / INT_MAX as f64).sqrt(),
        n_max,
        seed,
        photons: records.len(),
        k,
        trace_s,
        importance_s,
        build_s,
        render_s,
        time_s: trace_s + build_s + render_s,
        map_bytes: maps.full.memory_bytes() + maps.indirect.memory_bytes(),
        indirect_rel_rmse: relative_rmse_masked(&indirect, &reference.indirect, &reference.keep)?,
        image_rel_rmse: relative_rmse_masked(&full, &reference.full, &reference.keep)?,
        points_rel_err: rel_rmse(&points, &reference.irradiance),
        estimated_rel_err: estimated_error(prepared, cfg, who, n_max, seed, &reference.points)?,
        read_share,
        read_share_pixels,
    };
    Ok((
        run,
        RunOutput {
            indirect,
            full,
            points,
        },
    ))
}
