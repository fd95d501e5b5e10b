//! The map buffer a run writes into: one wave's photons encoded straight
//! into per-batch slots at its end, the gaps closed in place, and the frame
//! every photon of a run is encoded in.

use super::counts::{photon_power, LightPlan};
use super::wave::{shade_batch, BatchOut, PathState, Scratch, ShadeContext};
use crate::photon_map::{CompactPhoton, Quantizer};
use crate::raycast::RayCaster;
use crate::scene::Scene;
use rayon::prelude::*;

/// Traces one wave (chunks of paths, each cut into batches of at most
/// `batch`): batches in parallel, each writing its stored photons to its own
/// slots at the end of `photons`; the gaps (escaped photons, delta surfaces)
/// are then closed in place, in batch order.
pub(super) fn trace_wave<C: RayCaster>(
    ctx: &ShadeContext<C>,
    wave: &[Vec<PathState>],
    photons: &mut Vec<CompactPhoton>,
    batch: usize,
    records_only: bool,
) -> Vec<BatchOut> {
    let batches: Vec<&[PathState]> = wave.iter().flat_map(|c| c.chunks(batch)).collect();
    if records_only {
        return batches
            .par_iter()
            .map_init(Scratch::default, |s, b| shade_batch(ctx, b, &mut [], s))
            .collect();
    }
    let base = photons.len();
    let paths: usize = batches.iter().map(|b| b.len()).sum();
    // In parallel: these writes are the first touch of fresh pages (a
    // page fault and the kernel's zeroing each), serial otherwise.
    photons.par_extend(rayon::iter::repeat_n(CompactPhoton::default(), paths));
    let mut slots: Vec<&mut [CompactPhoton]> = Vec::with_capacity(batches.len());
    let mut rest = &mut photons[base..];
    for b in &batches {
        let (mine, others) = rest.split_at_mut(b.len());
        slots.push(mine);
        rest = others;
    }
    let outs: Vec<BatchOut> = batches
        .par_iter()
        .zip(slots)
        .map_init(Scratch::default, |s, (b, slots)| {
            shade_batch(ctx, b, slots, s)
        })
        .collect();
    let (mut write, mut from) = (base, base);
    for (b, o) in batches.iter().zip(&outs) {
        photons.copy_within(from..from + o.stored, write);
        write += o.stored;
        from += b.len();
    }
    photons.truncate(write);
    outs
}

/// The frame every photon of a run is encoded in, fixed before tracing so
/// that photons are written once: positions on a grid over the scene's
/// bounds (hits lie on its triangles), powers relative to the largest
/// emitted photon's largest channel times [`POWER_HEADROOM`]. It depends only
/// on the scene and the emission plan, so every shard of a run (and every
/// thread count and batch size) encodes in the same frame, and the map's
/// checksum (compact photons in tree order, and this frame) is the same.
pub fn map_frame(scene: &Scene, plans: &[LightPlan]) -> Quantizer {
    let (lo, hi, power_scale) = frame_inputs(scene, plans);
    Quantizer::new(lo, hi, power_scale)
}

/// The inputs of [`map_frame`]: the scene's bounds and the power scale,
/// [`POWER_HEADROOM`] times the largest channel of the brightest emitted
/// photon. Photon files store these (`photon_file::canonical_frame`).
pub fn frame_inputs(scene: &Scene, plans: &[LightPlan]) -> (glam::Vec3, glam::Vec3, f32) {
    let (lo, hi) = scene.bounds();
    let largest = scene
        .lights
        .iter()
        .zip(plans)
        .map(|(l, p)| photon_power(l, p).max_element())
        .filter(|p| p.is_finite())
        .fold(0.0f32, f32::max);
    (lo, hi, largest * POWER_HEADROOM)
}

/// How far above the largest emitted photon a stored photon's channel may go
/// before it is clamped: a bounce multiplies power by the BRDF weight over the
/// survival probability, at most 1 for Lambert, rarely above a few for
/// glossy models. Stored powers keep 9 significant bits down to
/// `2^-31 / POWER_HEADROOM` of the largest emitted photon.
pub const POWER_HEADROOM: f32 = 256.0;
