//! Merging shards into one map file: checks that they are the shards of one
//! run, all of them and each once, then streams their photons into the output
//! (one chunk in memory at a time), checking every shard's checksum.

use super::frame::{ByteHash, MapHash};
use super::header::{Header, Settings, DEPTHS, FLAG_BUDGET_BOUND, FLAG_MERGED, TRAILER_MAGIC};
use super::reader::PhotonReader;
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

/// One shard to merge: its path and its (validated) header.
struct ShardFile<'a> {
    path: &'a Path,
    header: Header,
}

/// The header fields every shard of one run shares, bit for bit (a frame
/// compared as floats would call two NaN frames different runs).
fn run_identity(h: &Header) -> (u64, [u32; 7], u64) {
    let f = |v: f32| v.to_bits();
    let (lo, hi) = (h.frame_min, h.frame_max);
    let frame = [
        f(lo.x),
        f(lo.y),
        f(lo.z),
        f(hi.x),
        f(hi.y),
        f(hi.z),
        f(h.power_scale),
    ];
    (h.scene_hash, frame, h.emitted_total)
}

/// How two shards' kernels differ, if they do (`docs/determinism.md`).
fn kernel_mismatch(a: &Settings, b: &Settings) -> Option<String> {
    use crate::isa::{version_name, Isa, MathVariant};
    let or_unrecorded = |name: Option<&str>| name.unwrap_or("an unrecorded one").to_string();
    if a.embree_isa != b.embree_isa {
        let name = |c| or_unrecorded(Isa::from_code(c).map(Isa::name));
        return Some(format!(
            "Embree kernel set {} against {}",
            name(a.embree_isa),
            name(b.embree_isa)
        ));
    }
    if a.embree_version != b.embree_version {
        let name = |c| {
            if c == 0 {
                or_unrecorded(None)
            } else {
                version_name(c)
            }
        };
        return Some(format!(
            "Embree {} against {}",
            name(a.embree_version),
            name(b.embree_version)
        ));
    }
    if a.math_variant != b.math_variant {
        let name = |c| or_unrecorded(MathVariant::from_code(c).map(MathVariant::name));
        return Some(format!(
            "maths library variant {} against {}",
            name(a.math_variant),
            name(b.math_variant)
        ));
    }
    None
}

/// Reads every shard's header (each file is closed again: a merge of many
/// shards holds one open file at a time) and checks they form one whole run:
/// the same scene, settings and frame, the shard count equal to the number of
/// files given, every index once. Returns them in shard order.
fn check_shards(inputs: &[PathBuf]) -> Result<Vec<ShardFile<'_>>> {
    let Some(first) = inputs.first() else {
        return Err(refuse("no shard given".into()));
    };
    let mut shards = Vec::with_capacity(inputs.len());
    for path in inputs {
        let header = PhotonReader::open(path)?.header().clone();
        if header.flags & FLAG_MERGED != 0 {
            return Err(refuse(format!(
                "{} is already a merged map",
                path.display()
            )));
        }
        shards.push(ShardFile { path, header });
    }
    let h0 = &shards[0].header;
    for s in &shards[1..] {
        let h = &s.header;
        let other = |what: &str| {
            refuse(format!(
                "{} and {} are shards of different {what}",
                first.display(),
                s.path.display()
            ))
        };
        if h.scene_hash != h0.scene_hash {
            return Err(other("scenes"));
        }
        if let Some(why) = kernel_mismatch(&h0.settings, &h.settings) {
            return Err(refuse(format!(
                "{} and {} were traced by different code: {why}; it draws different \
                 photons from the same seed, so the merge would not be the single run's \
                 map. Pin one Embree kernel set for every shard (the {} variable, or the \
                 trace's kernel-set option) and trace them with one Embree on hosts of one \
                 maths variant",
                first.display(),
                s.path.display(),
                crate::isa::ISA_ENV,
            )));
        }
        if h.settings != h0.settings {
            return Err(other(
                "settings (mode, seed, N_MAX, depth, split cap or analysis)",
            ));
        }
        if run_identity(h) != run_identity(h0) {
            return Err(other("runs (their frame or total emission differs)"));
        }
        if h.shard_count != h0.shard_count {
            return Err(refuse(format!(
                "{} is shard {}/{} but {} is shard {}/{}",
                first.display(),
                h0.shard_index,
                h0.shard_count,
                s.path.display(),
                h.shard_index,
                h.shard_count
            )));
        }
    }
    let n = h0.shard_count;
    shards.sort_by_key(|s| s.header.shard_index);
    check_each_index_once(&shards, n)?;
    Ok(shards)
}

/// Checks that `sorted` (by index, every index below `n`: the headers are
/// validated) holds each of `0..n` once. Never allocates from `n`, which
/// comes from a file.
fn check_each_index_once(sorted: &[ShardFile], n: u32) -> Result<()> {
    for w in sorted.windows(2) {
        if w[0].header.shard_index == w[1].header.shard_index {
            return Err(refuse(format!(
                "shard {}/{n} given twice: {} and {}",
                w[0].header.shard_index,
                w[0].path.display(),
                w[1].path.display()
            )));
        }
    }
    if sorted.len() as u64 == n as u64 {
        return Ok(());
    }
    // Distinct indices below n, fewer than n of them: list the first gaps.
    const SHOWN: usize = 10;
    let mut given = sorted.iter().map(|s| s.header.shard_index).peekable();
    let mut missing = Vec::new();
    for i in 0..n {
        if given.peek() == Some(&i) {
            given.next();
        } else {
            missing.push(i.to_string());
            if missing.len() == SHOWN {
                break;
            }
        }
    }
    let absent = n as u64 - sorted.len() as u64;
    let more = if absent > SHOWN as u64 {
        format!(" and {} more", absent - SHOWN as u64)
    } else {
        String::new()
    };
    Err(refuse(format!(
        "missing shard(s) {}{more} of {n}",
        missing.join(", ")
    )))
}

/// Adds a shard's counter to the merged one; a sum past `u64::MAX` cannot
/// come from real shards.
fn add_count(total: &mut u64, add: u64, what: &str, path: &Path) -> Result<()> {
    *total = total.checked_add(add).ok_or_else(|| {
        refuse(format!(
            "the shards' {what} overflow 64 bits at {} (corrupt headers)",
            path.display()
        ))
    })?;
    Ok(())
}

/// The merged header, from the shards' headers, with checked sums.
fn merged_header(shards: &[ShardFile]) -> Result<Header> {
    let mut h = shards[0].header.clone();
    h.flags = FLAG_MERGED;
    h.shard_index = 0;
    h.shard_count = 1;
    h.merged_from = u32::try_from(shards.len())
        .map_err(|_| refuse(format!("{} shards: at most u32::MAX", shards.len())))?;
    let (mut photons, mut emitted, mut clamped, mut skipped) = (0u64, 0u64, 0u64, 0u64);
    let mut sum = MapHash::default();
    h.depth_photons = [0; DEPTHS];
    h.depth_power = [[0.0; 3]; DEPTHS];
    for shard in shards {
        let (s, path) = (&shard.header, shard.path);
        h.flags |= s.flags & FLAG_BUDGET_BOUND;
        add_count(&mut photons, s.photons, "photon counts", path)?;
        add_count(&mut emitted, s.emitted, "emitted counts", path)?;
        add_count(&mut clamped, s.clamped, "clamped counts", path)?;
        add_count(&mut skipped, s.skipped, "skipped counts", path)?;
        sum.combine(&MapHash {
            count: s.photons,
            sum: s.photon_sum,
        });
        for (a, b) in h.depth_photons.iter_mut().zip(&s.depth_photons) {
            add_count(a, *b, "per-depth counts", path)?;
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
    // The shards of one run emit its total between them, exactly.
    if emitted != h.emitted_total {
        return Err(refuse(format!(
            "the shards emitted {emitted} photons together, but their run emits {}",
            h.emitted_total
        )));
    }
    h.photons = photons;
    h.emitted = emitted;
    h.clamped = clamped;
    h.skipped = skipped;
    h.photon_sum = sum.sum;
    h.map_checksum = sum.checksum(&h.frame());
    // Sums of finite powers may still overflow f64: check the result as a reader would.
    h.validate()
        .map_err(|e| refuse(format!("the merged header is invalid: {e}")))?;
    Ok(h)
}

/// Merges `inputs` (every shard of one run, in any order) into `out`.
/// Nothing is left at `out` on any error.
///
/// # Errors
/// [`Error::InvalidParameter`] (`merge` or `photon file`) for shards of
/// different scenes or settings, a missing or duplicate shard, a truncated or
/// corrupt file (including photons that do not hash to what their header
/// says, and any header field out of range: [`Header::validate`]), counters
/// whose sum overflows, or emitted counts that do not add up to the run's
/// total; [`Error::Io`] when a file cannot be read or written, or is not a
/// regular file.
pub fn merge(inputs: &[PathBuf], out: &Path) -> Result<MergeSummary> {
    let shards = check_shards(inputs)?;
    let header = merged_header(&shards)?;
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
    for shard in &shards {
        // Reopened one at a time; the reader checks the photons against the
        // header (both checksums) once the last chunk is read.
        let mut r = PhotonReader::open(shard.path)?;
        if r.header() != &shard.header {
            return Err(refuse(format!(
                "{} changed during the merge",
                shard.path.display()
            )));
        }
        while let Some(bytes) = r.next_bytes()? {
            file_hash.update(bytes);
            w.write_all(bytes).map_err(io)?;
        }
    }
    w.write_all(&TRAILER_MAGIC).map_err(io)?;
    w.write_all(&file_hash.value().to_le_bytes()).map_err(io)?;
    w.flush().map_err(io)?;
    drop(w);
    output.finish()?;
    // Each reader checked its photons against its header's hash, and the
    // merged header combines those hashes: its checksum is the map's.
    let checksum = header.map_checksum;
    Ok(MergeSummary { header, checksum })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(isa: u8, version: u32, math: u8) -> Settings {
        Settings {
            mode: 2,
            estimator: 0,
            seed: 1,
            n_max: 1000,
            max_depth: 15,
            split_cap: 4096,
            analysis_hash: 2,
            embree_isa: isa,
            embree_version: version,
            math_variant: math,
        }
    }

    #[test]
    fn shards_of_other_kernels_name_what_differs() {
        let a = settings(4, 31305, 3);
        assert_eq!(kernel_mismatch(&a, &a), None);
        let why = |b| kernel_mismatch(&a, &b).unwrap();
        assert_eq!(
            why(settings(5, 31305, 3)),
            "Embree kernel set avx2 against avx512"
        );
        assert_eq!(
            why(settings(0, 31305, 3)),
            "Embree kernel set avx2 against an unrecorded one"
        );
        assert_eq!(why(settings(4, 40303, 3)), "Embree 3.13.5 against 4.3.3");
        assert_eq!(
            why(settings(4, 31305, 1)),
            "maths library variant fma against sse2"
        );
    }
}
