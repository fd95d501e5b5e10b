//! Merging shards into one map file: checks that they are the shards of one
//! run, all of them and each once, then streams their photons into the output
//! (one chunk in memory at a time), checking every shard's checksum.

use super::frame::{ByteHash, MapHash};
use super::header::{Header, DEPTHS, FLAG_BUDGET_BOUND, FLAG_MERGED, TRAILER_MAGIC};
use super::reader::{photons_of, PhotonReader};
use crate::error::{Error, Result};
use crate::output::AtomicOutput;
use std::io::Write;
use std::path::{Path, PathBuf};

/// What a merge produced.
#[derive(Clone, Debug)]
pub struct MergeSummary {
    /// The merged map's header.
    pub header: Header,
    /// The merged map's checksum (as `trace --json` prints it).
    pub checksum: u64,
}

fn refuse(why: String) -> Error {
    Error::param("merge", why)
}

/// Opens every shard and checks they form one whole run; returns them in shard order.
fn check_shards(inputs: &[PathBuf]) -> Result<Vec<PhotonReader>> {
    let Some(first) = inputs.first() else {
        return Err(refuse("no shard given".into()));
    };
    let mut readers: Vec<PhotonReader> = Vec::with_capacity(inputs.len());
    let h0 = PhotonReader::open(first)?.header().clone();
    if h0.flags & FLAG_MERGED != 0 {
        return Err(refuse(format!(
            "{} is already a merged map",
            first.display()
        )));
    }
    let n = h0.shard_count;
    let mut seen: Vec<Option<&Path>> = vec![None; n as usize];
    for path in inputs {
        let r = PhotonReader::open(path)?;
        let h = r.header();
        let other = |what: &str| {
            refuse(format!(
                "{} and {} are shards of different {what}",
                first.display(),
                path.display()
            ))
        };
        if h.scene_hash != h0.scene_hash {
            return Err(other("scenes"));
        }
        if h.settings != h0.settings {
            return Err(other(
                "settings (mode, seed, N_MAX, depth, split cap or analysis)",
            ));
        }
        if (h.frame_min, h.frame_max, h.power_scale) != (h0.frame_min, h0.frame_max, h0.power_scale)
            || h.emitted_total != h0.emitted_total
        {
            return Err(other("runs (their emission differs)"));
        }
        if h.shard_count != n {
            return Err(refuse(format!(
                "{} is shard {}/{} but {} is shard {}/{}",
                first.display(),
                h0.shard_index,
                n,
                path.display(),
                h.shard_index,
                h.shard_count
            )));
        }
        let i = h.shard_index as usize;
        if i >= seen.len() {
            return Err(refuse(format!(
                "{}: shard index {i} out of 0..{n}",
                path.display()
            )));
        }
        if let Some(p) = seen[i] {
            return Err(refuse(format!(
                "shard {i}/{n} given twice: {} and {}",
                p.display(),
                path.display()
            )));
        }
        seen[i] = Some(path);
        readers.push(r);
    }
    let missing: Vec<String> = (0..n as usize)
        .filter(|&i| seen[i].is_none())
        .map(|i| i.to_string())
        .collect();
    if !missing.is_empty() {
        return Err(refuse(format!(
            "missing shard(s) {} of {n}",
            missing.join(", ")
        )));
    }
    readers.sort_by_key(|r| r.header().shard_index);
    Ok(readers)
}

/// The merged header, from the shards' headers.
fn merged_header(readers: &[PhotonReader]) -> Header {
    let mut h = readers[0].header().clone();
    h.flags = FLAG_MERGED;
    h.shard_index = 0;
    h.shard_count = 1;
    h.merged_from = readers.len() as u32;
    let (mut photons, mut emitted, mut clamped, mut skipped) = (0u64, 0u64, 0u64, 0u64);
    let mut sum = MapHash::default();
    h.depth_photons = [0; DEPTHS];
    h.depth_power = [[0.0; 3]; DEPTHS];
    for r in readers {
        let s = r.header();
        h.flags |= s.flags & FLAG_BUDGET_BOUND;
        photons += s.photons;
        emitted += s.emitted;
        clamped += s.clamped;
        skipped += s.skipped;
        sum.combine(&MapHash {
            count: s.photons,
            sum: s.photon_sum,
        });
        for (a, b) in h.depth_photons.iter_mut().zip(&s.depth_photons) {
            *a += b;
        }
        for (a, b) in h
            .depth_power
            .iter_mut()
            .flatten()
            .zip(s.depth_power.iter().flatten())
        {
            *a += b;
        }
    }
    h.photons = photons;
    h.emitted = emitted;
    h.clamped = clamped;
    h.skipped = skipped;
    h.photon_sum = sum.sum;
    h.map_checksum = sum.checksum(&h.frame());
    h
}

/// Merges `inputs` (every shard of one run, in any order) into `out`.
/// Nothing is left at `out` on any error.
///
/// # Errors
/// [`Error::InvalidParameter`] (`merge` or `photon file`) for shards of
/// different scenes or settings, a missing or duplicate shard, a truncated or
/// corrupt file (including photons that do not hash to what their header
/// says); [`Error::Io`] when a file cannot be read or written.
pub fn merge(inputs: &[PathBuf], out: &Path) -> Result<MergeSummary> {
    let mut readers = check_shards(inputs)?;
    let header = merged_header(&readers);
    let mut output = AtomicOutput::create(out)?;
    let io = |source| Error::Io {
        path: out.to_path_buf(),
        source,
    };
    let mut w = std::io::BufWriter::with_capacity(1 << 20, output.file());
    let mut file_hash = ByteHash::default();
    let hb = header.to_bytes();
    file_hash.update(&hb);
    w.write_all(&hb).map_err(io)?;
    let mut total = MapHash::default();
    for r in &mut readers {
        let announced = MapHash {
            count: r.header().photons,
            sum: r.header().photon_sum,
        };
        let index = r.header().shard_index;
        let mut got = MapHash::default();
        while let Some(bytes) = r.next_bytes()? {
            photons_of(bytes).for_each(|p| got.add(&p));
            file_hash.update(bytes);
            w.write_all(bytes).map_err(io)?;
        }
        if got != announced {
            return Err(refuse(format!(
                "shard {index}: its photons do not match its header (corrupt)"
            )));
        }
        total.combine(&got);
    }
    w.write_all(&TRAILER_MAGIC).map_err(io)?;
    w.write_all(&file_hash.value().to_le_bytes()).map_err(io)?;
    w.flush().map_err(io)?;
    drop(w);
    output.finish()?;
    let checksum = total.checksum(&header.frame());
    Ok(MergeSummary { header, checksum })
}
