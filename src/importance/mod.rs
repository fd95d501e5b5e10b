//! Visual importance over the scene's surfaces, from the camera (beyond the
//! paper; docs/method.md, "The importance pass").
//!
//! The adaptive counts see the lights and the BRDFs but not the camera: a
//! photon is split as readily where no pixel reads it as in the middle of
//! the image. Before the photons, this pass traces importance from the
//! camera, as Peter and Pietrek's importance map does ("Importance driven
//! construction of photon maps", EGWR 1998), with the renderer's own
//! estimator ([`crate::render`]'s camera rays, pixel sampler and gather),
//! so that the map says where *this* render reads photons.
//!
//! # What is deposited
//! Each camera sample (pixel `p`, sample `s`: the film's keys, so the walk
//! is the render's own) deposits the luminance of its path throughput `T`
//! at three kinds of point, kept apart:
//! - **first**: the camera ray's first non-specular hit, through mirrors and
//!   glass (`T` = the specular weights); the caustic map, and the indirect
//!   map without a gather, are read there;
//! - **gather**: the hits of the gather's `G` BRDF-sampled rays
//!   (`T = T_x f cos / pdf T_y / G`), where the cache or full map is read;
//! - **later**: [`ImportanceConfig::later_bounces`] further BRDF-sampled
//!   bounces from each gather hit. Nothing reads photons there; the
//!   deposits estimate the *adjoint*, what a photon there brings to the
//!   image through its later bounces (the estimate ADRRS, Vorba and
//!   Křivánek 2016, and EARS, Rath et al. 2022, drive splitting with).
//!
//! A cell's value is its deposits over the pass's camera samples and the
//! cell's face area `h^2`: importance per unit area and camera sample, a
//! density over the surfaces. For a camera facing a plane, the first-hit
//! density is 1 over the plane's area in view.
//!
//! # Cells
//! Cubes of side `h = cell_fraction * diagonal` of the scene's bounds
//! (default [`DEFAULT_CELL_FRACTION`] = 1/64: about 4000 cells over a box's
//! six walls, a few camera samples each at the default 128 x 128 x 4),
//! split six ways by the dominant axis and sign of the normal on the side
//! the ray arrived from, so the two faces of a wall, or a floor and a wall
//! in one cube, are different cells. A key packs the three cell
//! coordinates (19 bits each, wrapping) and the bucket.
//!
//! # Determinism and shards
//! Deposits are fixed-point integers (2^24 per unit of throughput) summed
//! per cell ([`ImportanceSums`]): integer sums do not depend on the order,
//! so the sums are bitwise the same whatever the thread count. Shard `I` of
//! `N` walks the camera samples `[floor(n I / N), floor(n (I + 1) / N))` of
//! the pass's `n`, as a trace's shard takes its photons ([`Shard`]), and
//! [`ImportanceSums::merge`] of the shards' sums is bitwise the whole pass's.
//!
//! # The lookup table ([`ImportanceGrid`])
//! Frozen from the sums: open addressing with linear probing, a table of
//! twice as many slots as cells (half full), **16 bytes per cell**. A slot
//! is 8 bytes:
//!
//! | bytes | field |
//! |---|---|
//! | 0-3 | tag: the high 32 bits of the key's hash, low bit set (0 = empty) |
//! | 4-5 | read importance (first + gather), bfloat16; in a reach cube's slot, its sign bit alone: photons there are stored |
//! | 6-7 | adjoint (first + gather + later), bfloat16 |
//!
//! The adjoint is read from **coarse cells** of side
//! [`ADJOINT_COARSENING`]` h` = 4 h, in the same table (a level bit in the
//! key; their read field is 0): later bounces spread their deposits thin,
//! and a room seen only through a door would otherwise be mostly cells
//! without a single deposit, each photon there rouletted to the floor.
//!
//! # What is stored
//! A photon is stored only where a kernel of the render may return it:
//! within the render's largest search radius ([`ImportanceConfig::reach`],
//! by default the renderer's tenth of the diagonal) of a read cell, on a
//! surface of any side (the k-nearest lookups accept any photon whose
//! surface turns less than 90 degrees from their own). The rule is kept
//! on the coarse cubes, as **reach cubes** (their own key, on no side):
//! each read cell flags the `(2 d + 1)^3` cubes around its own, `d` the
//! reach over the cube's side rounded up ([`CellGrid::reach_cells`]), so
//! every point within the reach of a read point lies in a flagged cube.
//! A reach wider than [`MAX_REACH_CELLS`] cubes stores everywhere. (Only
//! the 26 cells next to a read cell were flagged at first: the photons of
//! room A's floor of `door` that its sparse kernels reach from farther
//! went unstored, and the render read 7 % dark.)
//!
//! One probe per lookup ([`ImportanceGrid::read`], [`ImportanceGrid::adjoint`],
//! [`ImportanceGrid::within_reach`]); a tag collision, odds about cells /
//! 2^32 per lookup, reads a wrong cell.

use crate::engine::Shard;
use crate::render::importance_walk::Reader;
use crate::scene::Camera;

pub mod counts;
mod grid;
mod pass;
mod table;

pub use counts::{ImportanceCounts, ALPHA_I_FLOOR, ALPHA_I_MAX, PILOT_PHOTONS};
pub use grid::{
    CellGrid, ImportanceSums, ADJOINT_COARSENING, FIXED_ONE, MAX_DEPOSIT, MAX_REACH_CELLS, READERS,
};
pub use pass::{importance_pass, MAX_LATER_BOUNCES};
pub use table::ImportanceGrid;

/// Default cell side as a fraction of the scene's bounding-box diagonal.
pub const DEFAULT_CELL_FRACTION: f32 = 1.0 / 64.0;

/// Index of the first-hit reader in [`ImportanceSums::cells`].
pub const FIRST: usize = Reader::First as usize;
/// Index of the gather reader.
pub const GATHER: usize = Reader::Gather as usize;
/// Index of the later bounces (the adjoint's remainder).
pub const LATER: usize = Reader::Later as usize;

/// How to run the importance pass: the render it stands for (image size,
/// samples, gather rays, seed, camera), how far the adjoint looks, the
/// cells, and which camera samples this run walks.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImportanceConfig {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Camera samples per pixel.
    pub spp: u32,
    /// Gather rays per camera sample (0: the render reads the map at the
    /// first hit, and there are no gather or later deposits).
    pub gather: u32,
    /// BRDF-sampled bounces after each gather hit (the adjoint's reach).
    pub later_bounces: u32,
    /// Seed of the camera samples (the render's seed walks its own samples).
    pub seed: u64,
    /// The camera; `None` is the scene's.
    pub camera: Option<Camera>,
    /// Cell side over the scene's diagonal, in `(0, 1]`.
    pub cell_fraction: f32,
    /// The render's largest kernel radius (world units): photons within it
    /// of a read cell are stored. `None` is the renderer's default,
    /// [`crate::render::DEFAULT_MAX_RADIUS_FRACTION`] of the diagonal.
    pub reach: Option<f32>,
    /// Which camera samples to walk (the whole pass by default).
    pub shard: Shard,
}

impl ImportanceConfig {
    /// Matches the pass to a render: its camera, aspect, gather and kernel
    /// radius, about
    /// 128 x 128 pixels at [`ImportanceConfig::spp`] (a render's full sample
    /// count would cost as much as the render).
    pub fn match_render(&mut self, rc: &crate::render::RenderConfig) {
        let aspect = rc.width as f64 / rc.height.max(1) as f64;
        self.height = ((128.0 / aspect.sqrt()).round() as u32).clamp(1, rc.height.max(1));
        self.width = ((self.height as f64 * aspect).round() as u32).max(1);
        self.gather = rc.final_gather;
        self.camera = rc.camera;
        self.reach = rc.max_radius;
    }
}

impl Default for ImportanceConfig {
    /// 128 x 128 pixels at 4 samples, the render's default gather rays
    /// per sample, 4 later bounces, cells of 1/64 of the diagonal, the
    /// scene's camera.
    fn default() -> Self {
        ImportanceConfig {
            width: 128,
            height: 128,
            spp: 4,
            gather: crate::render::DEFAULT_GATHER,
            later_bounces: 4,
            seed: 1,
            camera: None,
            cell_fraction: DEFAULT_CELL_FRACTION,
            reach: None,
            shard: Shard::WHOLE,
        }
    }
}
