//! The quality knob chosen for the user: a time or error target picks Q.
//!
//! Two pilot runs at [`PILOTS`] `N_MAX` measure, each, the time (trace +
//! kd-trees + a render of the requested size) and the error estimated
//! without a reference from two half-maps (see [`super`]). Time is modelled
//! as `a + b N` and error as `c N^-p` through the two pilots (`p` clamped to
//! `0.1..=1`; the k-NN estimate with `k ~ sqrt(N)` gives `p ~ 1/4` for
//! noise); the model is solved for the target and clamped to
//! `1..=INT_MAX`. The estimate sees noise, not kernel bias: the trade study
//! reports how far the true error sits above it (`estimate_tracking`).

use super::measure::{estimated_error, k_for};
use super::reference::study_points;
use super::TradeoffConfig;
use crate::embree::EmbreeScene;
use crate::engine::config::INT_MAX;
use crate::engine::{Budget, Mode, TraceConfig, Tracer};
use crate::error::{Error, Result};
use crate::render::{render, RenderConfig, RenderMaps};
use serde::Serialize;
use std::sync::Arc;
use std::time::Instant;

/// `N_MAX` of the two pilot runs.
pub const PILOTS: [u64; 2] = [10_000, 40_000];

/// Points the pilots' error estimate reads.
const PILOT_POINTS: usize = 128;

/// What the user asks for.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Target {
    /// Seconds of trace + kd-trees + render.
    Time(f64),
    /// Relative error of the map's irradiance (the half-map estimate).
    Error(f64),
}

/// The chosen budget and what the models predict.
#[derive(Clone, Debug, Serialize)]
pub struct Choice {
    /// The quality Q.
    pub quality: f64,
    /// Its `N_MAX`.
    pub n_max: u64,
    /// Predicted seconds.
    pub predicted_time_s: f64,
    /// Predicted relative error (half-map estimate).
    pub predicted_error: f64,
    /// The pilots: `(N_MAX, seconds, estimated error)`.
    pub pilots: Vec<(u64, f64, f64)>,
}

/// Picks Q for `target` with `mode`, renders of `rc`'s size (see the module docs).
///
/// # Errors
/// A target that is not a positive number; trace or render errors.
pub fn choose_quality(
    prepared: &Arc<EmbreeScene>,
    mode: Mode,
    target: Target,
    rc: &RenderConfig,
) -> Result<Choice> {
    let v = match target {
        Target::Time(v) | Target::Error(v) => v,
    };
    if !(v.is_finite() && v > 0.0) {
        return Err(Error::param(
            "target",
            format!("must be a positive number, got {v}"),
        ));
    }
    let pts = study_points(prepared.scene(), PILOT_POINTS);
    let study = TradeoffConfig {
        width: rc.width,
        height: rc.height,
        spp: rc.spp,
        ..TradeoffConfig::default()
    };
    let mut pilots = Vec::new();
    for n in PILOTS {
        let t = Instant::now();
        let tracer = Tracer::new(Arc::clone(prepared));
        let out = tracer.trace(&TraceConfig::new(mode, Budget::NMax(n)))?;
        let maps = RenderMaps::build(&out.records());
        let mut c = rc.clone();
        c.k = k_for(n);
        render(prepared, Some(&maps), &c)?;
        let secs = t.elapsed().as_secs_f64();
        pilots.push((
            n,
            secs,
            estimated_error(prepared, &study, mode.into(), n, 1, &pts)?,
        ));
    }
    let [(n0, t0, e0), (n1, t1, e1)] = [pilots[0], pilots[1]];
    let (n0, n1) = (n0 as f64, n1 as f64);
    let b = ((t1 - t0) / (n1 - n0)).max(t1 / n1 * 0.1);
    let a = (t1 - b * n1).max(0.0);
    let p = if e0 > 0.0 && e1 > 0.0 {
        ((e0 / e1).ln() / (n1 / n0).ln()).clamp(0.1, 1.0)
    } else {
        0.25
    };
    let c = e1.max(1e-12) * n1.powf(p);
    let n = match target {
        Target::Time(s) => (s - a) / b,
        Target::Error(e) => (c / e).powf(1.0 / p),
    };
    let n_max = if n.is_finite() {
        n.clamp(1.0, INT_MAX as f64).round() as u64
    } else {
        INT_MAX
    };
    let nf = n_max as f64;
    Ok(Choice {
        quality: (nf / INT_MAX as f64).sqrt(),
        n_max,
        predicted_time_s: a + b * nf,
        predicted_error: c * nf.powf(-p),
        pilots,
    })
}
