//! The wave schedule: photons are traced in waves of at most [`WAVE`] paths
//! of one bounce depth, streamed depth by depth, so the live queue stays in
//! cache however many photons the run emits, and stored photons go once,
//! compact, into one map buffer reserved up front.
//!
//! Schedule (a pure function of the settings, never of the thread count or
//! the batch size, so budget decisions and the map are reproducible; the
//! queues are `PathQueue`s, whose chunks a wave takes without copying):
//! 1. if some depth has at least `WAVE` paths pending, trace `WAVE` of the
//!    deepest such depth (draining the deepest first bounds the queues);
//! 2. else, if photons remain to be emitted, emit the next `WAVE` of them
//!    (photon `i` of light `l` keyed by `(seed, l, i)`) and trace them;
//! 3. else trace up to `WAVE` of the shallowest depth with paths pending.
//!
//! Density control offers photons in order to a map that grows as it goes,
//! so its waves are whole depths as before ([`WAVE`] does not apply): its
//! result keeps its meaning (every depth-0 photon is offered before any
//! depth-1 photon).

use super::counts::{photon_power, LightPlan};
use super::queue::PathQueue;
use super::shard::Shard;
use super::wave::PathState;
use crate::rng::{hash2, Rng};
use crate::scene::Scene;
use rayon::prelude::*;

/// Largest wave: 16 Ki paths of 48 bytes (768 KiB) plus their rays and hits
/// stay in L2/L3 while they are traced and shaded.
pub const WAVE: usize = 1 << 14;

/// Pending paths per depth and the emission cursor.
pub(super) struct Schedule {
    /// `pending[d]`: paths waiting at depth `d`.
    pub(super) pending: Vec<PathQueue>,
    /// Next global emission index (lights in order).
    next: u64,
    emitted: u64,
    wave: usize,
    /// Which of each light's photon ids this run emits.
    shard: Shard,
}

impl Schedule {
    pub fn new(emitted: u64, max_depth: u32, whole_depths: bool, shard: Shard) -> Self {
        Schedule {
            shard,
            pending: vec![PathQueue::default(); max_depth as usize + 2],
            next: 0,
            emitted,
            wave: if whole_depths { usize::MAX } else { WAVE },
        }
    }

    /// Paths pending at every depth.
    pub fn pending_len(&self) -> usize {
        self.pending.iter().map(PathQueue::len).sum()
    }

    /// Photons emitted so far.
    pub fn emitted_so_far(&self) -> u64 {
        self.next
    }

    /// The next wave into `out` (cleared first), as chunks in queue order,
    /// and its depth; `None` when the run is done.
    pub fn next_wave(
        &mut self,
        scene: &Scene,
        plans: &[LightPlan],
        seed: u64,
        epsilon: f32,
        out: &mut Vec<Vec<PathState>>,
    ) -> Option<usize> {
        out.clear();
        let full = (0..self.pending.len())
            .rev()
            .find(|&d| self.pending[d].len() >= self.wave.min(WAVE));
        let depth = match full {
            Some(d) if self.wave != usize::MAX => d,
            _ if self.next < self.emitted => {
                let n = (self.emitted - self.next).min(self.wave as u64);
                let mut paths = Vec::new();
                emit(
                    scene, plans, self.shard, seed, epsilon, self.next, n, &mut paths,
                );
                out.push(paths);
                self.next += n;
                return Some(0);
            }
            _ => (0..self.pending.len()).find(|&d| !self.pending[d].is_empty())?,
        };
        self.pending[depth].take_last(self.wave, out);
        Some(depth)
    }
}

/// Photons `first .. first + n` of the run's emission order: every photon of
/// light 0 (of `shard`'s ids), then of light 1, and so on. A photon's key
/// is its id's, whichever shard emits it.
#[allow(clippy::too_many_arguments)]
fn emit(
    scene: &Scene,
    plans: &[LightPlan],
    shard: Shard,
    seed: u64,
    epsilon: f32,
    first: u64,
    n: u64,
    out: &mut Vec<PathState>,
) {
    let mut base = 0u64;
    let end = first + n;
    for (l, (light, plan)) in scene.lights.iter().zip(plans).enumerate() {
        let ids = shard.range(plan.photons);
        let count = ids.end - ids.start;
        let (lo, hi) = (first.max(base), end.min(base + count));
        if lo < hi {
            let power = photon_power(light, plan);
            let light_key = hash2(seed, l as u64);
            // Indexed: par_extend keeps the order of the ids.
            let (a, b) = (lo - base + ids.start, hi - base + ids.start);
            out.par_extend((a..b).into_par_iter().map(|i| {
                let key = hash2(light_key, i);
                let mut rng = Rng::new(key);
                let e = light.sample(rng.next_f32(), rng.next_2d(), rng.next_2d());
                PathState {
                    origin: e.origin + e.normal.unwrap_or_default() * epsilon,
                    direction: e.direction,
                    power: power * e.weight,
                    key,
                    specular_chain: true,
                }
            }));
        }
        base += count;
    }
}
