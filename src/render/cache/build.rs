//! Building the cache: samples, their normals, one estimate per finest
//! cell, the coarse levels (see the parent module for the design and its
//! bias).

use super::guide::{self, GuideTable, Histogram, PowerPerBin};
use super::sample_estimate::{Sample, SampleEstimate, SampleEstimator};
use super::{
    point_key, to_rgbe, walls, CacheConfig, IrradianceCache, Slot, GUIDE_LEVEL, LEVELS,
    PLANE_TOLERANCE, SAMPLES_PER_CELL,
};
use crate::error::Result;
use crate::photon_map::{Neighbor, PhotonMap};
use crate::raycast::{Ray, RayCaster};
use crate::render::estimate::Estimate;
use crate::render::reads::{BuildReads, MapReads};
use crate::scene::{PreparedScene, Scene};
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;
use std::time::Instant;

impl IrradianceCache {
    /// Builds the cache of `full` (the map of all photons traced in
    /// `prepared`), on the current rayon pool. Each sample's surface normal
    /// comes from one ray of the caster of `prepared`.
    ///
    /// # Errors
    /// [`Error::InvalidParameter`](crate::Error::InvalidParameter) for a bad configuration.
    pub fn build<C: RayCaster>(
        full: &PhotonMap,
        prepared: &PreparedScene<C>,
        cfg: &CacheConfig,
    ) -> Result<Self> {
        Self::build_in(full, prepared.scene(), prepared.caster(), cfg, None)
    }

    pub(crate) fn build_in(
        full: &PhotonMap,
        scene: &Scene,
        rt: &dyn RayCaster,
        cfg: &CacheConfig,
        reads: Option<&MapReads>,
    ) -> Result<Self> {
        cfg.validate()?;
        let (lo, hi) = scene.bounds();
        let diagonal = (hi - lo).length();
        let t = Instant::now();
        let estimator = SampleEstimator::new(full, rt, cfg, diagonal);
        let quant = *full.quantizer();
        // Sample points, their surface normals (one ray each) and coins: the
        // photons whose coin comes up heads.
        let samples: Vec<Sample> = full
            .compact_photons()
            .par_iter()
            .filter_map(|c| {
                let coin = c.content_hash();
                if !estimator.heads(coin) {
                    return None;
                }
                let p = quant.decode(c);
                let n = surface_normal(rt, p.position, p.direction, diagonal)?;
                Some((p.position, n, coin))
            })
            .collect();
        let scratch = || Scratch {
            neighbors: Vec::with_capacity(cfg.lookup.k),
            marks: reads.map(BuildReads::new),
        };
        let estimate = |sc: &mut Scratch, sample: Sample| {
            let e = estimator.at(sample, &mut sc.neighbors);
            if let Some(marks) = sc.marks.as_mut() {
                marks.mark(full, &sc.neighbors);
            }
            e
        };
        let cell = cell_side(&samples, &scratch, &estimate, cfg, diagonal);
        // Cell faces off the round coordinates that walls sit on (a floor at
        // y = 0 on a face would split its samples and lookups by the sign of
        // rounding errors): every level's faces are >= 0.14 h from 0.
        let origin = Vec3::new(0.3127, 0.2718, 0.1414) * cell;
        let mut cache = IrradianceCache {
            slots: Vec::new(),
            origin,
            cell,
            inv_cell: 1.0 / cell,
            cells: 0,
            walled: 0,
            samples: samples.len(),
            lift: PLANE_TOLERANCE * diagonal,
            guides: GuideTable::default(),
            build_s: 0.0,
        };
        // Finest cells: one k-nearest estimate each, at the sample `pick`
        // chooses (a fixed choice whatever the thread count).
        let mut fine: Vec<(u64, u32)> = samples
            .iter()
            .enumerate()
            .map(|(i, s)| (cache.key(s.0, s.1, 0), i as u32))
            .collect();
        fine.par_sort_unstable();
        let groups: Vec<&[(u64, u32)]> = fine.chunk_by(|a, b| a.0 == b.0).collect();
        // Short runs of cells a task (an estimate casts some 40 rays): with
        // rayon's default runs, one thread finished its last run alone.
        let values: Vec<FineCell> = groups
            .par_iter()
            .with_max_len(MAX_PER_TASK)
            .map_init(&scratch, |sc, g| {
                let rep = Self::pick(&samples, g);
                let sample = samples[rep as usize];
                let e = estimate(sc, sample);
                let share = estimator.share(sample.0, &e);
                let guide = indirect_power(full, sample.1, &sc.neighbors);
                FineCell::new(e.estimate, share, cell, cfg.stride, rep, guide)
            })
            .collect();
        let fine_entries: Vec<Entry> = groups
            .par_iter()
            .with_max_len(MAX_PER_TASK)
            .zip(&values)
            .map(|(g, v)| cache.fine_entry(rt, &samples, g[0].0, v))
            .collect();
        let coarse = cache.coarse_entries(rt, &samples, &groups, &values);
        cache.fill(&fine_entries, &coarse);
        cache.guides = cache.guide_table(&samples, &groups, &values);
        cache.build_s = t.elapsed().as_secs_f64();
        Ok(cache)
    }

    /// A finest cell's entry: its estimate, walled where its sample sees a
    /// face inside its cube ([`walls`]).
    fn fine_entry(&self, rt: &dyn RayCaster, samples: &[Sample], key: u64, v: &FineCell) -> Entry {
        let (p, n, _) = samples[v.rep as usize];
        let (lo, side) = self.cube(p, 0);
        let walled = walls::crossed(rt, (p, n), self.lift, lo, side);
        Entry {
            key,
            rgbe: to_rgbe(v.value),
            point: walled.then(|| walls::encode(p, lo, side)),
        }
    }

    /// The coarser levels' entries. A coarse cell holds the mean over the
    /// finest cells inside it, each counted once (a mean over samples
    /// would weight a cell's bright part by its extra photons: a mean of E
    /// weighted by E, too bright by Var E / E), and only over its sparsest.
    ///
    /// A lookup reads a coarse cell for want of finer ones, that is where
    /// photons are sparse; a wall with the light on its far side has dense,
    /// bright cells there, and a coarse cell across it that averaged them
    /// read the near side at the far side's light (x 4.8 on `door`'s camera
    /// room, measured). So a finest cell is averaged into levels up to one
    /// above its [`FineCell::natural`] (a blur of at most about twice its own
    /// kernel), and a coarse cell averages only its sparsest cells (of its
    /// highest natural level), of those only the ones its representative
    /// (the one with the least coin) sees ([`walls`]).
    fn coarse_entries(
        &self,
        rt: &dyn RayCaster,
        samples: &[Sample],
        groups: &[&[(u64, u32)]],
        values: &[FineCell],
    ) -> Vec<Entry> {
        let mut keyed: Vec<(u64, u32, u32)> = (1..LEVELS)
            .flat_map(|level| {
                groups
                    .iter()
                    .zip(values)
                    .enumerate()
                    .filter(move |(_, (_, v))| level <= v.natural + 1)
                    .map(move |(gi, (g, _))| {
                        let s = samples[g[0].1 as usize];
                        (self.key(s.0, s.1, level), gi as u32, level)
                    })
            })
            .collect();
        keyed.par_sort_unstable();
        let cells: Vec<&[(u64, u32, u32)]> = keyed.chunk_by(|a, b| a.0 == b.0).collect();
        cells
            .par_iter()
            .with_max_len(MAX_PER_TASK)
            .map(|group| {
                let sparsest = group
                    .iter()
                    .map(|&(_, gi, _)| values[gi as usize].natural)
                    .max()
                    .unwrap_or(0);
                let members: Vec<&FineCell> = group
                    .iter()
                    .map(|&(_, gi, _)| &values[gi as usize])
                    .filter(|v| v.natural >= sparsest)
                    .collect();
                let rep = members
                    .iter()
                    .min_by_key(|v| samples[v.rep as usize].2)
                    .copied()
                    .unwrap_or(members[0]);
                let (p, n, _) = samples[rep.rep as usize];
                let (lo, side) = self.cube(p, group[0].2);
                let seen: Vec<&FineCell> = members
                    .iter()
                    .copied()
                    .filter(|v| {
                        v.rep == rep.rep
                            || walls::sees(rt, p, n, samples[v.rep as usize].0, self.lift)
                    })
                    .collect();
                let (sum, weight) = seen.iter().fold((Vec3::ZERO, 0.0f32), |(s, w), v| {
                    (s + v.value * v.weight, w + v.weight)
                });
                let hidden = seen.len() < members.len();
                let walled = hidden || walls::crossed(rt, (p, n), self.lift, lo, side);
                Entry {
                    key: group[0].0,
                    rgbe: to_rgbe(sum / weight.max(f32::MIN_POSITIVE)),
                    point: walled.then(|| walls::encode(p, lo, side)),
                }
            })
            .collect()
    }

    /// The gather guides: the finest cells' power per bin summed over each
    /// cell of [`GUIDE_LEVEL`] (a finest cell's hundred photons are too few
    /// for a histogram that helps), each quantised.
    fn guide_table(
        &self,
        samples: &[Sample],
        groups: &[&[(u64, u32)]],
        values: &[FineCell],
    ) -> GuideTable {
        let mut keyed: Vec<(u64, u32)> = groups
            .iter()
            .enumerate()
            .map(|(gi, g)| {
                let (p, n, _) = samples[g[0].1 as usize];
                (self.key(p, n, GUIDE_LEVEL), gi as u32)
            })
            .collect();
        keyed.sort_unstable();
        let entries: Vec<(u64, Histogram)> = keyed
            .chunk_by(|a, b| a.0 == b.0)
            .filter_map(|cell| {
                let mut power = [0.0f32; guide::SIDE * guide::SIDE];
                for &(_, gi) in cell {
                    for (p, q) in power.iter_mut().zip(&values[gi as usize].guide) {
                        *p += q;
                    }
                }
                Some((cell[0].0, Histogram::of(&power)?))
            })
            .collect();
        GuideTable::new(&entries)
    }

    /// Sizes the table and inserts the entries, a walled one's point in a
    /// second slot: two slots a cell (16 bytes), so at most 0.67 full while
    /// at most a third of the cells are walled (a tenth on the Cornell box);
    /// beyond that the table grows to stay 2/3 full at most, so that a
    /// probe chain stays short.
    fn fill(&mut self, fine: &[Entry], coarse: &[Entry]) {
        let entries = || fine.iter().chain(coarse);
        self.cells = fine.len() + coarse.len();
        self.walled = entries().filter(|e| e.point.is_some()).count();
        let used = self.cells + self.walled;
        let slots = (2 * self.cells).max(used + used.div_ceil(2)).max(2);
        self.slots = vec![Slot::default(); slots];
        for e in entries() {
            self.insert(e.key, e.rgbe, e.point.is_some());
            if let Some(code) = e.point {
                self.insert(point_key(e.key), code, false);
            }
        }
    }

    /// The sample whose estimate a finest cell holds: the one of `group`
    /// with the least coin hash, a choice that depends on the samples alone.
    fn pick(samples: &[Sample], group: &[(u64, u32)]) -> u32 {
        group
            .iter()
            .map(|&(_, i)| i)
            .min_by_key(|&i| samples[i as usize].2)
            .unwrap_or(group[0].1)
    }
}

/// Cells (or samples) a parallel task of the build takes at most.
const MAX_PER_TASK: usize = 32;

/// A cell's entry in the table: its key, its irradiance (RGBE) and, for a
/// walled cell, its representative's position ([`walls::encode`]).
struct Entry {
    key: u64,
    rgbe: u32,
    point: Option<u32>,
}

/// A finest cell's estimate, with what its kernel says of the sample
/// density around it.
#[derive(Clone, Copy)]
struct FineCell {
    value: Vec3,
    /// The sample whose estimate it holds.
    rep: u32,
    /// `ceil(log2(s))` for samples `s^2` times sparser than
    /// [`SAMPLES_PER_CELL`] a cell (0 where they are at least that dense),
    /// within the levels: the level whose side matches the kernel's.
    natural: u32,
    /// `1 / P(the cell holds a sample)`, the sample count Poisson: in a
    /// coarse cell's mean it undoes the weight that a cell's existence
    /// gives its part of the surface, since a sparse cell exists in
    /// proportion to its photons, more likely in the bright part.
    weight: f32,
    /// The gather guide's power per bin: where its indirect photons came
    /// from.
    guide: PowerPerBin,
}

impl FineCell {
    /// The cell of side `cell` whose estimate is `e`, from the photons that
    /// are not samples (one in `stride` is one), over a kernel whose disc
    /// the sample sees on a surface by `share` ([`super::support::kernel_share`]).
    fn new(e: Estimate, share: f32, cell: f32, stride: u32, rep: u32, guide: PowerPerBin) -> Self {
        // Expected samples in the cell: the non-samples' density from the
        // kernel (`found` in `pi r^2`), over `stride - 1`, times the area.
        // The whole disc, not its share, as before the share: an edge cell
        // counted as denser joined fewer coarse levels, and the cache missed
        // more (0.07 % to 0.1 % of the lookups on the Cornell box at N_MAX
        // 1e5), each miss read by the whole-disc k-nearest estimate.
        let per_cell =
            e.found as f32 * cell * cell / (PI * e.radius * e.radius * (stride - 1) as f32);
        let sparser = SAMPLES_PER_CELL / per_cell.max(1e-12);
        let level = if sparser > 1.0 {
            (0.5 * sparser.log2()).ceil()
        } else {
            0.0
        };
        let exists = -(-per_cell).exp_m1();
        FineCell {
            value: e.value / share,
            rep,
            natural: level.min((LEVELS - 1) as f32) as u32,
            weight: 1.0 / exists.max(1e-6),
            guide,
        }
    }
}

/// The ratio of a cell's side to the kernel radius of its estimate, where a
/// cell holds [`SAMPLES_PER_CELL`] samples: `sqrt(SAMPLES_PER_CELL pi stride / k)`.
fn kernel_fraction(cfg: &CacheConfig) -> f32 {
    (SAMPLES_PER_CELL * PI * cfg.stride as f32 / cfg.lookup.k as f32).sqrt()
}

/// A build task's lookup scratch and, when the render marks its reads, its
/// marks ([`BuildReads`], merged when the task ends).
struct Scratch<'r, 'a> {
    neighbors: Vec<Neighbor>,
    marks: Option<BuildReads<'r, 'a>>,
}

/// The finest cell's side: from the median kernel radius over a spread
/// subset of the samples, sized so that a cell holds about
/// [`SAMPLES_PER_CELL`] samples.
fn cell_side<S, G, F>(
    samples: &[Sample],
    scratch: &G,
    estimate: &F,
    cfg: &CacheConfig,
    diagonal: f32,
) -> f32
where
    G: Fn() -> S + Sync,
    F: Fn(&mut S, Sample) -> SampleEstimate + Sync,
{
    let probe_step = (samples.len() / 1024).max(1);
    let mut radii: Vec<f32> = samples
        .par_iter()
        .step_by(probe_step)
        .with_max_len(MAX_PER_TASK)
        .map_init(scratch, |sc, &s| estimate(sc, s).estimate.radius)
        .collect();
    let mid = radii.len() / 2;
    let median = if radii.is_empty() {
        cfg.lookup.max_radius
    } else {
        *radii.select_nth_unstable_by(mid, f32::total_cmp).1
    };
    (kernel_fraction(cfg) * median)
        .max(1e-6 * diagonal)
        .max(f32::MIN_POSITIVE)
}

/// The gather guide's power per bin of `neighbors` (a finest cell's
/// estimate's photons, at a sample of normal `n`): the photons that bounced
/// at least once and are not caustic ones (the light's own emission and
/// light through mirrors and glass are not the gather's).
fn indirect_power(full: &PhotonMap, n: Vec3, neighbors: &[Neighbor]) -> PowerPerBin {
    let frame = guide::frame(n, n);
    let indirect = neighbors.iter().filter_map(|nb| {
        let c = full.compact(nb.index);
        (c.depth() >= 1 && !c.is_caustic()).then(|| {
            let p = full.photon(nb.index);
            (p.direction, p.power)
        })
    });
    guide::power_per_bin(&frame, indirect)
}

/// The normal of the surface a photon travelling along `dir` landed on at
/// `p`, facing the photon (against `dir`); `None` when no surface is there.
fn surface_normal(rt: &dyn RayCaster, p: Vec3, dir: Vec3, diagonal: f32) -> Option<Vec3> {
    let back = 1e-4 * diagonal;
    let ray = Ray {
        tfar: 2.0 * back,
        ..Ray::new(p - dir * back, dir)
    };
    let h = rt.intersect(&ray)?;
    let ng = h.ng.normalize_or_zero();
    let n = if ng.dot(dir) > 0.0 { -ng } else { ng };
    (n != Vec3::ZERO).then_some(n)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::mix64;

    /// An empty cache of cell side 1 to fill.
    fn empty() -> IrradianceCache {
        IrradianceCache {
            slots: Vec::new(),
            origin: Vec3::ZERO,
            cell: 1.0,
            inv_cell: 1.0,
            cells: 0,
            walled: 0,
            samples: 0,
            lift: 1e-3,
            guides: GuideTable::default(),
            build_s: 0.0,
        }
    }

    /// The table keeps two slots a cell while at most a third are walled,
    /// grows past that to stay at most 2/3 full, and every entry, its point
    /// included, reads back; a key it does not hold misses (the probe
    /// chain ends at an empty slot).
    #[test]
    fn the_table_stays_two_thirds_full_and_reads_back() {
        for (cells, walled_every) in [(3000usize, 0usize), (3000, 3), (3000, 1), (1, 1)] {
            let entries: Vec<Entry> = (0..cells)
                .map(|i| Entry {
                    key: mix64(i as u64 + 1),
                    rgbe: i as u32 + 1,
                    point: (walled_every > 0 && i % walled_every == 0).then_some(i as u32 * 7),
                })
                .collect();
            let mut cache = empty();
            cache.fill(&entries, &[]);
            let used = cache.cells + cache.walled;
            assert!(
                3 * used <= 2 * cache.slots.len(),
                "{used} in {}",
                cache.slots.len()
            );
            if 3 * cache.walled <= cache.cells {
                assert_eq!(
                    cache.bytes_per_entry(),
                    16,
                    "{cells} cells, {}",
                    cache.walled
                );
            }
            for e in &entries {
                let slot = cache.probe(e.key).unwrap();
                assert_eq!(slot.payload, e.rgbe);
                assert_eq!(slot.tag & super::super::WALLED != 0, e.point.is_some());
                if let Some(code) = e.point {
                    assert_eq!(cache.probe(point_key(e.key)).unwrap().payload, code);
                }
            }
            for i in 0..1000u64 {
                assert!(cache.probe(mix64((i + 2) << 40)).is_none());
            }
        }
    }
}
