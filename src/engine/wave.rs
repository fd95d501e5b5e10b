//! One wave of the wavefront: a bounded chunk of photons of one bounce depth,
//! traced in parallel batches through the [`RayCaster`], then shaded: stored,
//! and split or ended.
//!
//! A stored photon is encoded once, as a 16-byte [`CompactPhoton`], straight
//! into the slot of the map buffer that its batch owns (a batch of `b`
//! photons stores at most `b`); the tracer then closes the gaps in place.
//! Density control, which redistributes power between stored photons, gets
//! full records instead. A photon's random numbers come from its key, so a
//! wave's result does not depend on the thread count or the batch size.

use super::albedo::AlbedoTable;
use super::counts::{expected_children, round_stochastic};
use crate::analysis::DirectionalityTable;
use crate::importance::ImportanceCounts;
use crate::photon_map::{CompactPhoton, PhotonRecord, Quantizer};
use crate::raycast::{BadHit, Hit, Ray, RayCaster};
use crate::rng::{hash2, Rng};
use crate::sampling::{luminance, Frame};
use crate::scene::{consistent_with_geometry, photon_shading_factor, Scene};
use glam::Vec3;
use std::sync::Arc;

/// A photon in flight.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PathState {
    /// Ray origin (already offset from the surface it leaves).
    pub origin: Vec3,
    /// Unit direction of travel.
    pub direction: Vec3,
    /// Power (flux) it carries.
    pub power: Vec3,
    /// Identity: seeds every random number this photon draws.
    pub key: u64,
    /// Every bounce since the light was on a specular surface (true at the
    /// light): a photon stored while this holds, after a bounce, is a
    /// caustic photon.
    pub specular_chain: bool,
}

/// What shading needs to know about the run.
pub(super) struct ShadeContext<'a, C> {
    pub scene: &'a Scene,
    pub caster: &'a C,
    /// alpha_D tables by material (adaptive mode); `None` for delta BRDFs.
    pub tables: &'a [Option<Arc<DirectionalityTable>>],
    /// Albedo tables by material (the survival probability).
    pub albedo: &'a [AlbedoTable],
    /// Floor of alpha_D (delta BRDFs).
    pub alpha_min: f32,
    /// Luminance of the most powerful light: the photon's alpha_E is its power over it.
    pub max_light_luminance: f32,
    /// `N_MAX_refl = N_MAX` when splitting; 0 turns splitting off (classic modes, budget).
    pub n_max_refl: f64,
    /// Per-hit cap on children.
    pub split_cap: u32,
    /// Whether photons at this depth may have children.
    pub continue_paths: bool,
    /// Density control: stored photons go to `BatchOut::records` with their
    /// shading normals, not into the map buffer.
    pub keep_records: bool,
    /// The caustic pass: a photon is stored only as a caustic photon (to
    /// `BatchOut::records`, without normals) and ends at its first
    /// non-specular hit, stored or not.
    pub caustic_only: bool,
    /// The frame photons are encoded in (the map's).
    pub frame: Quantizer,
    /// Offset of new ray origins from surfaces.
    pub epsilon: f32,
    pub depth: u8,
    /// Importance in the counts (`None`: the paper's counts, bit for bit).
    pub importance: Option<ImportanceCounts<'a>>,
}

/// The output of one batch.
#[derive(Default)]
pub(super) struct BatchOut {
    /// Photons written to the batch's slots of the map buffer.
    pub stored: usize,
    /// Density control only: the stored photons, uncompressed.
    pub records: Vec<PhotonRecord>,
    /// The shading normal (facing the photon's arrival side) of each stored photon.
    pub normals: Vec<Vec3>,
    pub children: Vec<PathState>,
    pub hits: u64,
    pub escaped: u64,
    pub capped: u64,
    /// Photons not stored because nothing reads them there (importance).
    pub unread: u64,
    /// The first hit of the batch that broke the caster contract.
    pub bad_hit: Option<BadHit>,
}

/// Per-worker buffers reused from batch to batch.
#[derive(Default)]
pub(crate) struct Scratch {
    rays: Vec<Ray>,
    hits: Vec<Option<Hit>>,
}

/// Traces and shades `batch`; stored photons go to `slots` (one per photon
/// of the batch, filled from the front) or, for density control, to the
/// output's records.
pub(super) fn shade_batch<C: RayCaster>(
    ctx: &ShadeContext<C>,
    batch: &[PathState],
    slots: &mut [CompactPhoton],
    scratch: &mut Scratch,
) -> BatchOut {
    scratch.rays.clear();
    scratch.rays.reserve(batch.len());
    for p in batch {
        // Field by field: copying the 12-byte vectors whole went through the
        // stack with overlapping stores and loads (a store-forwarding stall
        // per ray, 4 % of the trace under `perf annotate`).
        let (o, d) = (p.origin, p.direction);
        scratch.rays.push(Ray {
            origin: Vec3::new(o.x, o.y, o.z),
            dir: Vec3::new(d.x, d.y, d.z),
            tnear: 0.0,
            tfar: f32::INFINITY,
        });
    }
    scratch.hits.clear();
    scratch.hits.resize(batch.len(), None);
    ctx.caster.intersect_batch(&scratch.rays, &mut scratch.hits);
    let mut out = BatchOut {
        children: Vec::with_capacity(batch.len()),
        ..BatchOut::default()
    };
    for ((p, hit), ray) in batch.iter().zip(&scratch.hits).zip(&scratch.rays) {
        match hit {
            None => out.escaped += 1,
            // A caster of the user's may report anything: a hit that breaks
            // the contract ends the run with an error (see the tracer),
            // never a panic or a photon stored at a NaN.
            Some(h) => match h.check(ray, ctx.scene) {
                Ok(()) => shade_hit(ctx, p, h, slots, &mut out),
                Err(bad) => {
                    out.bad_hit.get_or_insert(bad);
                }
            },
        }
    }
    out
}

fn shade_hit<C>(
    ctx: &ShadeContext<C>,
    p: &PathState,
    h: &Hit,
    slots: &mut [CompactPhoton],
    out: &mut BatchOut,
) {
    out.hits += 1;
    let position = p.origin + p.direction * h.t;
    // Checked by `Hit::check`; `None` keeps a missed case a stop, not a
    // panic. A textured material scatters by its texels at this point.
    let Some(surface) = ctx.scene.surface_brdf(h) else {
        return;
    };
    let brdf = &surface;
    let from_inside = h.ng.dot(p.direction) > 0.0;
    let mut power = p.power;
    if from_inside {
        // The segment just travelled lay inside this (closed) object.
        if let Some(sigma) = ctx.scene.interior_attenuation(h.material) {
            power *= (-sigma * h.t).exp();
        }
    }
    // Surfaces are two-sided: the normal on the side the photon arrives from.
    let arrival_side = h.facing(p.direction);
    if !brdf.is_specular() {
        let read = ctx.importance.is_none_or(|i| i.stores(position));
        let record = PhotonRecord {
            position,
            power,
            direction: p.direction,
            depth: ctx.depth,
            caustic: p.specular_chain && ctx.depth > 0,
        };
        if ctx.caustic_only {
            if record.caustic && position.is_finite() && power.is_finite() {
                out.records.push(record);
            }
        } else if !read {
            out.unread += 1;
        } else if ctx.keep_records {
            out.records.push(record);
            out.normals.push(arrival_side);
        } else if position.is_finite() && power.is_finite() {
            // At most one store per photon of the batch: a slot is free.
            slots[out.stored] = ctx.frame.encode(&record);
            out.stored += 1;
        }
    }
    if !ctx.continue_paths {
        return;
    }
    // A partly transmitting surface scatters by one of its parts (stored
    // above whichever it is), drawn from a stream of its own so that other
    // scenes draw the numbers they always drew.
    let material = ctx.scene.scattering_material(h.material, || {
        Rng::new(p.key ^ 0x1_0BE5_0000_0000).next_f32()
    });
    let glass;
    let brdf = if material == h.material {
        brdf
    } else {
        glass = ctx.scene.materials[material as usize].brdf;
        &glass
    };
    // The caustic pass ends at its first non-specular scattering.
    if ctx.caustic_only && !brdf.is_specular() {
        return;
    }
    let material = material as usize;
    let side = ctx.scene.scattering_normal(brdf, h, from_inside);
    let n = match brdf.is_specular() {
        true => side,
        false => ctx.scene.shading_side(h, side, -p.direction),
    };
    // Flux through a shading normal takes the adjoint's factor (none on
    // the geometric normal, where it is 1).
    let shading_normal = n != side;
    let frame = Frame::from_normal(n);
    let wi = frame.local_from_world(-p.direction);
    // The classic survival probability: the largest channel of the albedo
    // (tabulated from the outside for glass: any value in (0, 1] is unbiased).
    let r = ctx.albedo[material].at(wi.z.abs()).max_element().min(1.0) as f64;
    if r <= 0.0 {
        return;
    }
    let s = if ctx.n_max_refl > 0.0 {
        let alpha_e = luminance(power) / ctx.max_light_luminance;
        let alpha_d = match &ctx.tables[material] {
            Some(t) => t.alpha_d(wi.z.abs()),
            None => ctx.alpha_min,
        };
        alpha_e as f64 * alpha_d as f64 * ctx.n_max_refl
    } else {
        0.0
    };
    // alpha_I takes the split count and, up to 1, the survival: splitting
    // stays with `s`, which the wave's budget scales (alpha_I is 1, exactly,
    // without importance or at a specular hit: the paper's m bit for bit).
    let alpha_i = match ctx.importance {
        Some(i) if !brdf.is_specular() => f64::from(i.alpha_i(position, arrival_side)),
        _ => 1.0,
    };
    let (m, capped) = expected_children(s * alpha_i, r * alpha_i.min(1.0), ctx.split_cap);
    out.capped += u64::from(capped);
    // One stream per hit: the rounding, then each child's direction in turn.
    let mut rng = Rng::new(p.key ^ 0x5E1E_C7ED_0000_0000);
    let k = round_stochastic(m, rng.next_f32());
    let scale = (1.0 / m) as f32;
    let specular = brdf.is_specular();
    let specular_chain = p.specular_chain && specular;
    for c in 0..k {
        let key = hash2(p.key, c as u64 + 1);
        let Some(bs) = brdf.sample(wi, rng.next_2d()) else {
            continue;
        };
        let direction = frame.world_from_local(bs.wo).normalize();
        let mut child_power = power * bs.weight * scale;
        if shading_normal {
            // A sample under the surface is dropped, as camera paths drop theirs.
            if direction.dot(side) <= 0.0 {
                continue;
            }
            child_power *= photon_shading_factor(h.ng, n, -p.direction, direction);
        }
        if !child_power.is_finite() || child_power.max_element() <= 0.0 {
            continue;
        }
        if specular
            && !consistent_with_geometry(h.ng, -p.direction, direction, bs.wo.z * wi.z < 0.0)
        {
            continue;
        }
        // Off the surface on the side the child leaves by (the geometric
        // side: a shading normal may disagree with it).
        let side = h.facing(-direction);
        out.children.push(PathState {
            origin: position + side * ctx.epsilon,
            direction,
            power: child_power,
            key,
            specular_chain,
        });
    }
}
