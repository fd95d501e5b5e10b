//! The importance pass: camera samples walked in parallel blocks, their
//! deposits summed per cell in fixed point, the shard's range of samples
//! only.

use super::grid::{to_fixed, Accumulator, CellGrid, ImportanceSums};
use super::ImportanceConfig;
use crate::error::{Error, Result};
use crate::raycast::{CheckedCaster, RayCaster};
use crate::render::importance_walk::{CameraWalk, WalkSettings};
use crate::render::MAX_GATHER;
use crate::scene::{PreparedScene, Scene};
use rayon::prelude::*;

/// Camera samples a parallel task walks: the blocks do not depend on the
/// thread count, and integer sums not on the order they merge in.
const BLOCK: u64 = 1024;

/// Most bounces after the gather hit accepted.
pub const MAX_LATER_BOUNCES: u32 = 64;

impl ImportanceConfig {
    /// Checks the settings.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`] naming the bad setting.
    pub fn validate(&self) -> Result<()> {
        crate::render::image::check_dimensions(self.width, self.height)?;
        if self.spp == 0 || self.spp > crate::render::MAX_SPP {
            return Err(Error::param(
                "importance spp",
                format!(
                    "must be in 1..={}, got {}",
                    crate::render::MAX_SPP,
                    self.spp
                ),
            ));
        }
        if self.gather > MAX_GATHER {
            return Err(Error::param(
                "importance gather",
                format!("must be at most {MAX_GATHER}, got {}", self.gather),
            ));
        }
        if self.later_bounces > MAX_LATER_BOUNCES {
            return Err(Error::param(
                "importance bounces",
                format!(
                    "must be at most {MAX_LATER_BOUNCES}, got {}",
                    self.later_bounces
                ),
            ));
        }
        if let Some(r) = self.reach {
            if !(r.is_finite() && r > 0.0) {
                return Err(Error::param(
                    "importance reach",
                    format!("the kernel radius must be a positive finite length, got {r}"),
                ));
            }
        }
        self.shard.validate()
    }
}

/// Runs the importance pass of `cfg` over `prepared`'s scene, on the
/// current rayon pool: the sums of the camera samples of `cfg.shard`
/// ([`ImportanceSums::merge`] of every shard's is the whole pass's).
///
/// # Errors
/// [`Error::InvalidParameter`] for bad settings, [`Error::InvalidScene`] for
/// a scene without a camera (and none given) or a caster that breaks its
/// contract.
pub fn importance_pass<C: RayCaster>(
    prepared: &PreparedScene<C>,
    cfg: &ImportanceConfig,
) -> Result<ImportanceSums> {
    run(prepared.scene(), prepared.caster(), cfg)
}

// One body for every caster, behind `dyn`, as the renderer's.
fn run(scene: &Scene, rt: &dyn RayCaster, cfg: &ImportanceConfig) -> Result<ImportanceSums> {
    cfg.validate()?;
    let camera = cfg.camera.or(scene.camera).ok_or_else(|| {
        Error::InvalidScene("the scene has no camera: give the importance pass one".into())
    })?;
    let (lo, hi) = scene.bounds();
    let grid = CellGrid::for_bounds(lo, hi, cfg.cell_fraction)?;
    let grid = match cfg.reach {
        Some(r) => grid.with_reach(r)?,
        None => grid,
    };
    let checked = CheckedCaster::new(scene, rt);
    let walk = CameraWalk::new(
        scene,
        &checked,
        &camera,
        WalkSettings {
            width: cfg.width,
            height: cfg.height,
            spp: cfg.spp,
            gather: cfg.gather,
            later_bounces: cfg.later_bounces,
            seed: cfg.seed,
        },
    );
    let samples = walk.samples();
    let range = cfg.shard.range(samples);
    let blocks = (range.end - range.start).div_ceil(BLOCK);
    let acc = (0..blocks)
        .into_par_iter()
        .map(|b| {
            let start = range.start + b * BLOCK;
            let mut acc = Accumulator::default();
            for i in start..(start + BLOCK).min(range.end) {
                walk.walk(i, &mut |reader, hit, w| {
                    acc.add(
                        grid.key(hit.position, hit.normal),
                        reader as usize,
                        to_fixed(w),
                    );
                });
            }
            acc
        })
        .reduce(Accumulator::default, Accumulator::merge);
    checked.result()?;
    Ok(acc.into_sums(grid, samples))
}
