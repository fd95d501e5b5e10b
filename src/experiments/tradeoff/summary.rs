//! The study's summaries: bias and variance per mode and budget, the
//! equal-time and equal-memory comparisons, and how the reference-free
//! error estimate tracks the true error.
//!
//! **Equal time / memory.** Level `i` is the geometric mean over the modes of
//! their mean time (or map bytes) at budget `i`. Each mode's mean indirect
//! error (and points error) is interpolated log-log along its own curve at
//! that level. The curve is the mode's frontier ([`frontier`]): a budget
//! that took longer than a larger one and erred more (timing noise at the
//! smallest budgets) is left out. Up to a factor [`MAX_EXTRAPOLATION`]
//! beyond its measured range the curve is extended with the slope from its
//! end to the first point at least twice as far along; further out the
//! mode has no value there. Both guard against two budgets close in time:
//! on `door`, whose density control measured 3.9 and 15.8 there, extending
//! the segment between them read 0.18 in one run and 646 in the next.

// `!(x > 0.0)` is deliberate here: it rejects NaN with the non-positive values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use super::measure::RunOutput;
use super::reference::Reference;
use super::{Contender, Run, TradeoffConfig};
use serde::Serialize;
use std::collections::BTreeMap;

/// How far (as a ratio) a curve is extended beyond its measured range.
pub const MAX_EXTRAPOLATION: f64 = 2.0;

/// One error over the seeds of a mode and budget.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Stat {
    /// Mean over the seeds of each seed's error.
    pub mean: f64,
    /// Error of the seeds' mean result, the spread's share and the
    /// reference's own noise removed (in quadrature).
    pub bias: f64,
    /// rms deviation of one seed's result from the seeds' mean (relative).
    pub spread: f64,
}

/// One mode and budget over its seeds.
#[derive(Clone, Debug, Serialize)]
pub struct Group {
    /// The contender.
    pub mode: Contender,
    /// The budget.
    pub n_max: u64,
    /// Its quality Q.
    pub quality: f64,
    /// Mean seconds.
    pub time_s: f64,
    /// Mean bytes of the kept maps.
    pub map_bytes: f64,
    /// (a) indirect image.
    pub indirect: Stat,
    /// (b) full image.
    pub image: Stat,
    /// (c) points.
    pub points: Stat,
    /// Mean share of the stored photons that the render read.
    pub read_share: f64,
    /// Mean share read by pixels and gather rays (the cache's build left out).
    pub read_share_pixels: f64,
}

/// Bias/spread of samples (one vector per seed) against `r`, relative to `mean(r)`.
fn stat(samples: &[Vec<f64>], r: &[f64], errs: &[f64], ref_noise: f64) -> Stat {
    let s = samples.len().max(1) as f64;
    let n = r.len().max(1) as f64;
    let rm = r.iter().sum::<f64>() / n;
    if rm <= 0.0 {
        return Stat::default();
    }
    let mean: Vec<f64> = (0..r.len())
        .map(|i| samples.iter().map(|v| v[i]).sum::<f64>() / s)
        .collect();
    let var = samples
        .iter()
        .map(|v| {
            v.iter()
                .zip(&mean)
                .map(|(a, b)| (a - b) * (a - b))
                .sum::<f64>()
                / n
        })
        .sum::<f64>()
        / s
        * if s > 1.0 { s / (s - 1.0) } else { 0.0 };
    let err2 = mean
        .iter()
        .zip(r)
        .map(|(a, b)| (a - b) * (a - b))
        .sum::<f64>()
        / n;
    Stat {
        mean: errs.iter().sum::<f64>() / errs.len().max(1) as f64,
        bias: (err2 / (rm * rm) - var / s / (rm * rm) - ref_noise * ref_noise)
            .max(0.0)
            .sqrt(),
        spread: var.sqrt() / rm,
    }
}

/// Kept pixels and channels of an image, flattened.
fn flat(img: &crate::render::Image, keep: &[bool]) -> Vec<f64> {
    img.pixels
        .iter()
        .zip(keep)
        .filter(|(_, k)| **k)
        .flat_map(|(p, _)| [p.x as f64, p.y as f64, p.z as f64])
        .collect()
}

/// Groups the runs (in the study's order) by mode and budget.
pub(crate) fn groups(
    runs: &[Run],
    outs: &[RunOutput],
    r: &Reference,
    cfg: &TradeoffConfig,
) -> Vec<Group> {
    let s = cfg.seeds as usize;
    let (ri, rf) = (flat(&r.indirect, &r.keep), flat(&r.full, &r.keep));
    runs.chunks(s)
        .zip(outs.chunks(s))
        .map(|(rs, os)| {
            let avg = |f: fn(&Run) -> f64| rs.iter().map(f).sum::<f64>() / rs.len() as f64;
            let ind: Vec<Vec<f64>> = os.iter().map(|o| flat(&o.indirect, &r.keep)).collect();
            let full: Vec<Vec<f64>> = os.iter().map(|o| flat(&o.full, &r.keep)).collect();
            let pts: Vec<Vec<f64>> = os.iter().map(|o| o.points.clone()).collect();
            let errs = |f: fn(&Run) -> f64| rs.iter().map(f).collect::<Vec<f64>>();
            Group {
                mode: rs[0].mode,
                n_max: rs[0].n_max,
                quality: rs[0].quality,
                time_s: avg(|r| r.time_s),
                map_bytes: avg(|r| r.map_bytes as f64),
                indirect: stat(&ind, &ri, &errs(|r| r.indirect_rel_rmse), r.info.noise),
                image: stat(&full, &rf, &errs(|r| r.image_rel_rmse), r.info.image_noise),
                points: stat(
                    &pts,
                    &r.irradiance,
                    &errs(|r| r.points_rel_err),
                    r.info.points_noise,
                ),
                read_share: avg(|r| r.read_share),
                read_share_pixels: avg(|r| r.read_share_pixels),
            }
        })
        .collect()
}

/// The axis of a comparison.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Axis {
    /// Seconds.
    Time,
    /// Bytes of the kept maps.
    Memory,
}

/// One level of an equal-time or equal-memory comparison.
#[derive(Clone, Debug, Serialize)]
pub struct Level {
    /// Budget level (0 = the smallest budget).
    pub level: usize,
    /// Seconds or bytes of the level.
    pub at: f64,
    /// The mode with the lowest indirect error there.
    pub best: Option<Contender>,
    /// Each mode's mean indirect error there.
    pub errors: BTreeMap<String, f64>,
    /// The mode with the lowest points error there.
    pub best_points: Option<Contender>,
    /// Each mode's mean points error there.
    pub points_errors: BTreeMap<String, f64>,
}

/// The points of `c` (x ascending) whose `y` is below that of every point
/// before them: the least error reached within each time or memory.
pub fn frontier(c: Vec<(f64, f64)>) -> Vec<(f64, f64)> {
    let mut least = f64::INFINITY;
    c.into_iter()
        .filter(|&(_, y)| {
            let keep = y < least;
            least = least.min(y);
            keep
        })
        .collect()
}

/// log-log interpolation of `(x, y)` points (x ascending) at `x`.
pub fn interpolate(c: &[(f64, f64)], x: f64) -> Option<f64> {
    let c: Vec<(f64, f64)> = c
        .iter()
        .copied()
        .filter(|p| p.0 > 0.0 && p.1 > 0.0)
        .collect();
    let (first, last) = (c.first()?, c.last()?);
    if x < first.0 / MAX_EXTRAPOLATION || x > last.0 * MAX_EXTRAPOLATION || !(x > 0.0) {
        return None;
    }
    if c.len() == 1 {
        return (x == first.0).then_some(first.1);
    }
    let ((x0, y0), (x1, y1)) = if x < first.0 {
        // Below the range: the slope from the first point to the first one
        // at least twice as far along (the last if none), so that two
        // budgets whose times timing noise brought together do not set it.
        let far = c.iter().find(|p| p.0 >= 2.0 * first.0).unwrap_or(last);
        (*first, *far)
    } else if x > last.0 {
        let near = c
            .iter()
            .rev()
            .find(|p| p.0 <= 0.5 * last.0)
            .unwrap_or(first);
        (*near, *last)
    } else {
        let i = c
            .windows(2)
            .position(|w| x <= w[1].0)
            .unwrap_or(c.len() - 2);
        (c[i], c[i + 1])
    };
    let f = if x1 > x0 {
        (x.ln() - x0.ln()) / (x1.ln() - x0.ln())
    } else {
        0.0
    };
    Some((y0.ln() + f * (y1.ln() - y0.ln())).exp())
}

fn best(errors: &BTreeMap<String, f64>, modes: &[Contender]) -> Option<Contender> {
    modes
        .iter()
        .filter_map(|m| errors.get(m.name()).map(|e| (*m, *e)))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .map(|p| p.0)
}

/// The equal-time or equal-memory comparison, one level per budget.
pub fn equal(groups: &[Group], modes: &[Contender], levels: usize, axis: Axis) -> Vec<Level> {
    let x = |g: &Group| match axis {
        Axis::Time => g.time_s,
        Axis::Memory => g.map_bytes,
    };
    let curve = |m: Contender, f: fn(&Group) -> f64| {
        let mut c: Vec<(f64, f64)> = groups
            .iter()
            .filter(|g| g.mode == m)
            .map(|g| (x(g), f(g)))
            .collect();
        c.sort_by(|a, b| a.0.total_cmp(&b.0));
        frontier(c)
    };
    (0..levels)
        .map(|i| {
            let xs: Vec<f64> = modes
                .iter()
                .filter_map(|m| groups.iter().filter(|g| g.mode == *m).nth(i).map(x))
                .filter(|v| *v > 0.0)
                .collect();
            let at = (xs.iter().map(|v| v.ln()).sum::<f64>() / xs.len().max(1) as f64).exp();
            let at_mode = |f: fn(&Group) -> f64| -> BTreeMap<String, f64> {
                modes
                    .iter()
                    .filter_map(|m| {
                        interpolate(&curve(*m, f), at).map(|e| (m.name().to_string(), e))
                    })
                    .collect()
            };
            let errors = at_mode(|g| g.indirect.mean);
            let points_errors = at_mode(|g| g.points.mean);
            Level {
                level: i,
                at,
                best: best(&errors, modes),
                errors,
                best_points: best(&points_errors, modes),
                points_errors,
            }
        })
        .collect()
}

/// How `estimated_rel_err` tracks `points_rel_err`.
#[derive(Clone, Copy, Debug, Default, Serialize)]
pub struct Tracking {
    /// Runs with a positive estimate.
    pub runs: usize,
    /// Median of `points_rel_err / estimated_rel_err`.
    pub median_ratio: f64,
    /// Smallest ratio.
    pub min_ratio: f64,
    /// Largest ratio.
    pub max_ratio: f64,
}

/// The ratio true / estimated error over `runs`.
pub fn tracking(runs: &[Run]) -> Tracking {
    let mut r: Vec<f64> = runs
        .iter()
        .filter(|r| r.estimated_rel_err > 0.0)
        .map(|r| r.points_rel_err / r.estimated_rel_err)
        .collect();
    r.sort_by(f64::total_cmp);
    if r.is_empty() {
        return Tracking::default();
    }
    Tracking {
        runs: r.len(),
        median_ratio: r[r.len() / 2],
        min_ratio: r[0],
        max_ratio: r[r.len() - 1],
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smallest budget that took longer than the next and erred more is
    /// left out of the curve, and an extension below the curve follows its
    /// first kept segment, not the steep one between the two.
    #[test]
    fn a_slower_and_worse_budget_leaves_the_curve() {
        let c = vec![(0.242, 3.88), (0.257, 15.84), (0.493, 1.66), (1.7, 0.77)];
        let f = frontier(c.clone());
        assert_eq!(f, vec![(0.242, 3.88), (0.493, 1.66), (1.7, 0.77)]);
        let below = interpolate(&f, 0.211).unwrap();
        assert!(below > 3.88 && below < 5.0, "{below}");
        // Two budgets close in time at the curve's start: the extension
        // takes the slope to the first point twice as far along.
        let close = vec![(0.314, 15.84), (0.339, 3.88), (0.574, 1.66), (2.224, 0.77)];
        let before = interpolate(&close, 0.257).unwrap();
        assert!(before > 15.84 && before < 25.0, "{before}");
        // The same above the range.
        let after = interpolate(&close, 4.0).unwrap();
        assert!(after < 0.77 && after > 0.3, "{after}");
        // Equal errors: the later one adds nothing.
        assert_eq!(frontier(vec![(1.0, 2.0), (2.0, 2.0)]), vec![(1.0, 2.0)]);
    }
}
