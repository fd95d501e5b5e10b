//! Photon files (`.apm`): the photons of one shard of a run, or of a merged map,
//! in a form that can be memory-mapped and read back without the scene.
//! The format is specified in `docs/photon-file.md`; in short:
//!
//! | bytes | content |
//! |-------|---------|
//! | `0..4096` | [`Header`]: magic, version, scene hash, settings, shard I/N, counts, per-depth power |
//! | `4096..4096 + 16 n` | `n` compact photons ([`crate::photon_map::CompactPhoton`]), little-endian |
//! | last 16 | trailer: `"APMPEND\0"`, then the file checksum ([`ByteHash`]) of the header and photons |
//!
//! Every shard quantises its photons in the run's **canonical frame**
//! ([`canonical_frame`]): the scene's bounds and a power scale fixed by the
//! emission plan, both known before tracing. A shard's compact photons are
//! then bitwise those the whole run makes, and the merged map is the whole
//! run's map. The run's checksum ([`MapHash`]) is order-independent (a sum of
//! per-photon hashes), so a merge that concatenates shards reproduces it.

mod frame;
mod header;
mod merge;
mod reader;
mod writer;

pub use crate::output::AtomicOutput;
pub use frame::{
    canonical_frame, photons_checksum, scene_hash, settings_hash, ByteHash, CanonicalFrame, MapHash,
};
pub use header::{
    Header, Settings, DEPTHS, FLAG_BUDGET_BOUND, FLAG_MERGED, HEADER_SIZE, MAGIC, MAX_POWER_SCALE,
    TRAILER_MAGIC, VERSION,
};
pub use merge::{merge, MergeSummary};
pub use reader::{read_map, read_render_maps, PhotonReader};
pub use writer::{write_photons, ShardInfo};

/// Bytes per stored photon.
pub const PHOTON_SIZE: u64 = 16;
/// Bytes of the trailer (magic + checksum).
pub const TRAILER_SIZE: u64 = 16;
