//! Writing a shard: a run's compact photons, in the canonical frame.

use super::frame::{ByteHash, CanonicalFrame, MapHash};
use super::header::{Header, Settings, DEPTHS, FLAG_BUDGET_BOUND, TRAILER_MAGIC};
use crate::engine::{Mode, Shard, TraceConfig};
use crate::error::{Error, Result};
use crate::output::AtomicOutput;
use crate::photon_map::CompactPhoton;
use std::io::Write;
use std::path::Path;

/// What a shard file says about its run besides the photons.
#[derive(Clone, Debug)]
pub struct ShardInfo {
    /// [`super::scene_hash`] of the scene.
    pub scene_hash: u64,
    /// The run's canonical frame ([`super::canonical_frame`]).
    pub frame: CanonicalFrame,
    /// Photons this shard emitted.
    pub emitted: u64,
    /// Photons the whole run emits.
    pub emitted_total: u64,
    /// Whether the memory budget bound.
    pub budget_bound: bool,
    /// The kernels that traced the shard ([`TraceReport::kernels`](crate::engine::TraceReport::kernels)).
    pub kernels: Option<crate::isa::Kernels>,
    /// The tracing host's maths variant ([`TraceReport::math`](crate::engine::TraceReport::math)).
    pub math: Option<crate::isa::MathVariant>,
}

/// The header fields that come from the settings.
pub(crate) fn settings_of(cfg: &TraceConfig, info: &ShardInfo) -> Settings {
    Settings {
        mode: match cfg.mode {
            Mode::Classic => 0,
            Mode::Density => 1,
            Mode::Adaptive => 2,
        },
        estimator: match cfg.estimator {
            crate::analysis::Estimator::Paper => 0,
            crate::analysis::Estimator::PeakDensity => 1,
            crate::analysis::Estimator::PaperIid => 2,
        },
        seed: cfg.seed,
        n_max: cfg.budget.n_max().unwrap_or(0),
        max_depth: cfg.max_depth,
        split_cap: cfg.split_cap,
        analysis_hash: super::settings_hash(cfg),
        embree_isa: info.kernels.map_or(0, |k| k.isa.code()),
        embree_version: info.kernels.map_or(0, |k| k.version_code()),
        math_variant: info.math.map_or(0, crate::isa::MathVariant::code),
    }
}

/// Writes the compact `photons` of shard `cfg.shard` of a run, encoded in
/// `info.frame` (the tracer writes them so), to `path` through a temporary
/// renamed at the end. Returns the header written.
///
/// # Errors
/// [`Error::Io`] when the file cannot be written (nothing is left at `path`).
pub fn write_photons(
    path: &Path,
    cfg: &TraceConfig,
    info: &ShardInfo,
    photons: &[CompactPhoton],
) -> Result<Header> {
    let shard: Shard = cfg.shard;
    let frame = &info.frame.quantizer();
    let mut hash = MapHash::default();
    let mut header = Header {
        flags: if info.budget_bound {
            FLAG_BUDGET_BOUND
        } else {
            0
        },
        scene_hash: info.scene_hash,
        settings: settings_of(cfg, info),
        shard_index: shard.index,
        shard_count: shard.count,
        merged_from: 0,
        photons: 0,
        emitted: info.emitted,
        emitted_total: info.emitted_total,
        frame_min: info.frame.min,
        frame_max: info.frame.max,
        power_scale: info.frame.power_scale,
        photon_sum: 0,
        map_checksum: 0,
        clamped: 0,
        skipped: 0,
        depth_photons: [0; DEPTHS],
        depth_power: [[0.0; 3]; DEPTHS],
    };
    for p in photons {
        hash.add(p);
    }
    for (d, (n, power)) in frame.power_sums(photons).into_iter().enumerate() {
        let d = d.min(DEPTHS - 1);
        header.depth_photons[d] += n;
        for (a, p) in header.depth_power[d].iter_mut().zip(power) {
            *a += p;
        }
    }
    header.photons = hash.count;
    header.photon_sum = hash.sum;
    header.map_checksum = hash.checksum(frame);

    let mut out = AtomicOutput::create(path)?;
    let io = |source| Error::Io {
        path: path.to_path_buf(),
        source,
    };
    let mut file_hash = ByteHash::default();
    let mut w = std::io::BufWriter::with_capacity(1 << 20, out.file());
    let hb = header.to_bytes();
    file_hash.update(&hb);
    w.write_all(&hb).map_err(io)?;
    let mut buf = Vec::with_capacity(1 << 16);
    for chunk in photons.chunks(4096) {
        buf.clear();
        for p in chunk {
            // Without the kd-tree's split axis: files hold the photons only.
            let (a, b) = p.bits();
            let (a, b) = CompactPhoton::from_bits(a, b).bits();
            buf.extend_from_slice(&a.to_le_bytes());
            buf.extend_from_slice(&b.to_le_bytes());
        }
        file_hash.update(&buf);
        w.write_all(&buf).map_err(io)?;
    }
    w.write_all(&TRAILER_MAGIC).map_err(io)?;
    w.write_all(&file_hash.value().to_le_bytes()).map_err(io)?;
    w.flush().map_err(io)?;
    drop(w);
    out.finish()?;
    Ok(header)
}
