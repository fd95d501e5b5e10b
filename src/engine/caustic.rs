//! The caustic pass (docs/method.md, "The caustic pass"): photons emitted
//! only toward the specular objects ([`CausticAim`], Jensen's projection
//! map), traced through mirrors and glass exactly as the main trace traces
//! them (the same shading code: scattering, Russian roulette, the flux
//! transport mode, Beer–Lambert), and stored only at their first
//! non-specular hit after an all-specular path (`L S+ D`, the caustic
//! flag). A path that meets a non-specular surface first, or after its
//! first bounce, ends there unstored.
//!
//! The map it makes has the main trace's expected caustic power per area
//! (`caustic_emit`), from photons that nearly all reach a specular object:
//! the renderer takes its caustic map from here instead of the main
//! trace's caustic photons ([`super::Maps::with_caustic_pass`]; never both).
//!
//! Determinism: photon `i` of light `l` is keyed by `(seed, stream, l, i)`
//! with [`CAUSTIC_STREAM`] apart from the main trace's keys, and every
//! bounce of its path by that key, as in the main trace; waves are fixed
//! slices of the emission order, so the photons do not depend on the
//! thread count or the batch size. A [`super::Shard`] takes its share of
//! every light's ids, as the main trace's; the shards' photons together
//! are the whole pass's, but each shard encodes in its own power frame.
//!
//! ```no_run
//! # #[cfg(all(feature = "embree", feature = "gltf"))] {
//! use adaptive_pm::embree::Device;
//! use adaptive_pm::engine::{default_caustic_photons, Budget, Maps, Mode, TraceConfig, Tracer};
//! use adaptive_pm::scene::{Scene, BUILTIN_CORNELL_GLASS};
//!
//! let tracer = Tracer::new(Scene::open(BUILTIN_CORNELL_GLASS)?.commit(&Device::new()?)?);
//! let cfg = TraceConfig::new(Mode::Adaptive, Budget::NMax(1_000_000));
//! let main = tracer.trace(&cfg)?;
//! let pass = tracer.trace_caustic(&cfg, default_caustic_photons(tracer.scene(), 1_000_000))?;
//! // The renderer's maps, their caustic map the pass's.
//! let maps = Maps::full_only(main.photons, main.frame).with_caustic_pass(pass);
//! # }
//! # Ok::<(), adaptive_pm::Error>(())
//! ```
//!
//! No splitting: the pass follows few bounces, and every photon it emits
//! is already aimed; Russian roulette alone decides survival, so a pass
//! stores at most one photon per photon emitted. The memory budget counts
//! [`BYTES_PER_CAUSTIC_PHOTON`] per emitted photon: the stored ones are
//! held as full records until the pass encodes them in its frame, which
//! needs their largest power.

use super::albedo::AlbedoTable;
use super::buffer::trace_wave;
use super::caustic_aim::CausticAim;
pub use super::caustic_budget::{default_caustic_photons, CausticBudget, DEFAULT_CAUSTIC_SHARE};
use super::caustic_emit::aimed_photon;
use super::config::{CheckedConfig, TraceConfig};
use super::stream::WAVE;
use super::tracer::Tracer;
use super::wave::{PathState, ShadeContext};
use crate::error::{Error, Result};
use crate::photon_map::{CompactPhoton, PhotonMap, PhotonRecord, Quantizer};
use crate::raycast::RayCaster;
use crate::rng::{hash2, Rng};
use crate::sampling::luminance;
use crate::scene::Scene;
use rayon::prelude::*;
use std::time::Instant;

/// Keys the caustic pass's photons apart from the main trace's: light
/// `l`'s photons are keyed by `hash2(hash2(seed, CAUSTIC_STREAM), l)`.
pub const CAUSTIC_STREAM: u64 = 0xCA05_71C0_0000_0001;

/// Bytes the memory budget counts per emitted caustic photon: at most one
/// stored photon each, held as a full record until the pass encodes it,
/// then compact.
pub const BYTES_PER_CAUSTIC_PHOTON: u64 =
    (std::mem::size_of::<PhotonRecord>() + std::mem::size_of::<CompactPhoton>()) as u64;

/// What a caustic pass did.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize)]
pub struct CausticReport {
    /// Bounding spheres aimed at (specular meshes).
    pub targets: usize,
    /// Photons emitted per light (this shard's).
    pub per_light: Vec<u64>,
    /// Photons emitted in all.
    pub emitted: u64,
    /// Emitted photons that left toward a sphere (the rest had no sphere in
    /// view or no emission that way).
    pub aimed: u64,
    /// Caustic photons stored.
    pub stored: u64,
    /// Seconds the pass took (tracing and encoding; no kd-tree).
    pub trace_s: f64,
}

/// The caustic photons of a pass.
#[derive(Clone, Debug)]
pub struct CausticOutput {
    /// Every stored photon (each flagged caustic), compact.
    pub photons: Vec<CompactPhoton>,
    /// The frame they are encoded in (the scene's bounds, and the largest
    /// stored channel as the power scale).
    pub frame: Quantizer,
    /// Counts and time.
    pub report: CausticReport,
}

impl CausticOutput {
    /// The stored photons, decoded.
    pub fn records(&self) -> Vec<PhotonRecord> {
        self.photons.iter().map(|p| self.frame.decode(p)).collect()
    }

    /// Their kd-tree, built in place.
    pub fn into_map(self) -> PhotonMap {
        PhotonMap::from_compact(self.photons, self.frame)
    }
}

/// The per-light photon counts: `photons` shared by the lights' luminance,
/// at least one for a light with power (none at all when `photons` is 0).
fn caustic_counts(scene: &Scene, photons: u64) -> Vec<u64> {
    let lums: Vec<f64> = scene
        .lights()
        .iter()
        .map(|l| luminance(l.power()).max(0.0) as f64)
        .collect();
    let total: f64 = lums.iter().sum();
    lums.iter()
        .map(|&lum| {
            if photons == 0 || lum <= 0.0 {
                0
            } else {
                ((photons as f64 * lum / total).round() as u64).max(1)
            }
        })
        .collect()
}

impl<C: RayCaster> Tracer<C> {
    /// A caustic pass of `photons` photons with `cfg`'s seed, bounce
    /// limit, batch, shard and memory budget (its mode and `N_MAX` do not
    /// apply: the pass never splits). A scene without a specular mesh
    /// gives an empty pass.
    ///
    /// # Errors
    /// As [`Tracer::trace`] for bad settings and a caster's bad hit;
    /// [`Error::Budget`] when `photons` caustic photons would not fit in
    /// the memory budget ([`BYTES_PER_CAUSTIC_PHOTON`] each).
    pub fn trace_caustic(&self, cfg: &TraceConfig, photons: u64) -> Result<CausticOutput> {
        self.trace_caustic_checked(&cfg.check()?, photons)
    }

    /// [`Tracer::trace_caustic`] with settings checked beforehand.
    ///
    /// # Errors
    /// As [`Tracer::trace_caustic`].
    pub fn trace_caustic_checked(
        &self,
        cfg: &CheckedConfig,
        photons: u64,
    ) -> Result<CausticOutput> {
        let start = Instant::now();
        let scene = self.scene();
        let aim = CausticAim::new(scene);
        let shard = cfg.settings().shard;
        let counts = caustic_counts(scene, if aim.is_empty() { 0 } else { photons });
        let per_light: Vec<u64> = counts.iter().map(|&n| shard.len_of(n)).collect();
        let emitted: u64 = per_light.iter().sum();
        let budget = cfg.memory_budget();
        if emitted > budget / BYTES_PER_CAUSTIC_PHOTON {
            return Err(Error::Budget {
                photons: emitted,
                needed_bytes: emitted.saturating_mul(BYTES_PER_CAUSTIC_PHOTON),
                budget_bytes: budget,
            });
        }
        let mut report = CausticReport {
            targets: aim.targets().len(),
            per_light,
            emitted,
            ..CausticReport::default()
        };
        let emission = Emission {
            scene,
            aim: &aim,
            counts: &counts,
            shard,
            key: hash2(cfg.seed(), CAUSTIC_STREAM),
            epsilon: scene.ray_epsilon(),
        };
        let albedo: Vec<AlbedoTable> = scene
            .materials()
            .iter()
            .map(|m| AlbedoTable::new(&m.brdf))
            .collect();
        let mut records = Vec::new();
        let mut first = 0;
        while first < emitted {
            let n = (emitted - first).min(WAVE as u64);
            let wave = emission.wave(first, n);
            report.aimed += wave.len() as u64;
            self.trace_caustic_wave(cfg, &albedo, wave, &mut records)?;
            first += n;
        }
        let frame = caustic_frame(scene, &records);
        let photons: Vec<CompactPhoton> = records
            .par_iter()
            .with_min_len(4096)
            .map(|r| frame.encode(r))
            .collect();
        report.stored = photons.len() as u64;
        report.trace_s = start.elapsed().as_secs_f64();
        Ok(CausticOutput {
            photons,
            frame,
            report,
        })
    }

    /// Traces one wave of aimed photons through every bounce (no
    /// splitting: a wave never grows), its caustic photons into `records`
    /// in path order.
    fn trace_caustic_wave(
        &self,
        cfg: &CheckedConfig,
        albedo: &[AlbedoTable],
        wave: Vec<PathState>,
        records: &mut Vec<PhotonRecord>,
    ) -> Result<()> {
        let scene = self.scene();
        let tables = vec![None; scene.materials().len()];
        let mut wave = vec![wave];
        let mut depth = 0usize;
        while wave.iter().any(|c| !c.is_empty()) {
            let ctx = ShadeContext {
                scene,
                caster: self.prepared().caster(),
                tables: &tables,
                albedo,
                alpha_min: cfg.analysis().alpha_min,
                max_light_luminance: 1.0,
                n_max_refl: 0.0,
                split_cap: cfg.split_cap(),
                continue_paths: depth < cfg.max_depth() as usize,
                keep_records: true,
                caustic_only: true,
                frame: Quantizer::new(glam::Vec3::ZERO, glam::Vec3::ONE, 1.0),
                epsilon: scene.ray_epsilon(),
                depth: depth as u8,
                importance: None,
            };
            let outs = trace_wave(&ctx, &wave, &mut Vec::new(), cfg.batch(), true);
            if let Some(bad) = outs.iter().find_map(|o| o.bad_hit) {
                return Err(bad.into_error(scene));
            }
            let mut next = Vec::new();
            for out in outs {
                records.extend(out.records);
                next.extend(out.children);
            }
            wave = vec![next];
            depth += 1;
        }
        Ok(())
    }
}

/// What emitting a wave of caustic photons needs.
struct Emission<'a> {
    scene: &'a Scene,
    aim: &'a CausticAim,
    /// Every light's photon count (the whole pass's, before sharding).
    counts: &'a [u64],
    shard: super::Shard,
    /// The pass's stream key.
    key: u64,
    epsilon: f32,
}

impl Emission<'_> {
    /// Photons `first .. first + n` of the pass's emission order (light 0's
    /// ids of this shard, then light 1's, ...), those aimed at a sphere.
    fn wave(&self, first: u64, n: u64) -> Vec<PathState> {
        let mut out = Vec::new();
        let (mut base, end) = (0u64, first + n);
        for (l, (light, &count)) in self.scene.lights().iter().zip(self.counts).enumerate() {
            let ids = self.shard.range(count);
            let len = ids.end - ids.start;
            let (lo, hi) = (first.max(base), end.min(base + len));
            if lo < hi {
                let power = light.power() / count as f32;
                let light_key = hash2(self.key, l as u64);
                let (a, b) = (lo - base + ids.start, hi - base + ids.start);
                out.par_extend((a..b).into_par_iter().filter_map(|i| {
                    let key = hash2(light_key, i);
                    let e = aimed_photon(light, self.aim, &mut Rng::new(key))?;
                    Some(PathState {
                        origin: e.origin + e.normal.unwrap_or_default() * self.epsilon,
                        direction: e.direction,
                        power: power * e.weight,
                        key,
                        specular_chain: true,
                    })
                }));
            }
            base += len;
        }
        out
    }
}

/// The frame of a pass's photons: the scene's bounds (as the main map's)
/// and the largest stored channel, so no photon is clamped.
fn caustic_frame(scene: &Scene, records: &[PhotonRecord]) -> Quantizer {
    let (lo, hi) = scene.bounds();
    let largest = records
        .iter()
        .map(|r| r.power.max_element())
        .fold(0.0f32, f32::max);
    Quantizer::new(lo, hi, if largest > 0.0 { largest } else { 1.0 })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_budget_per_photon_is_the_one_the_docs_quote() {
        // docs/rendering.md and docs/method.md give 56 bytes.
        assert_eq!(BYTES_PER_CAUSTIC_PHOTON, 56);
    }
}
