//! Reading a photon file as a stream of chunks, checking its header and size
//! up front and its checksums at the end.

use super::frame::{ByteHash, MapHash};
use super::header::{Header, HEADER_SIZE, TRAILER_MAGIC};
use super::{PHOTON_SIZE, TRAILER_SIZE};
use crate::error::{Error, Result};
use crate::photon_map::{CompactPhoton, PhotonMap};
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

/// Photons per chunk (1 MiB).
const CHUNK_PHOTONS: u64 = 1 << 16;

/// An open photon file, read chunk by chunk.
#[derive(Debug)]
pub struct PhotonReader {
    path: PathBuf,
    file: BufReader<File>,
    header: Header,
    left: u64,
    hash: ByteHash,
    photons_hash: MapHash,
    buf: Vec<u8>,
    verified: bool,
}

impl PhotonReader {
    /// Opens `path` and checks its header ([`Header::validate`]) and its
    /// length (a truncated or padded file is refused here, before any photon
    /// is read).
    ///
    /// # Errors
    /// [`Error::Io`] when it cannot be read or is not a regular file (a FIFO
    /// is refused without blocking: [`crate::input::open_regular_file`]);
    /// [`Error::InvalidParameter`] (`photon file`) for a bad header or a
    /// wrong length.
    pub fn open(path: &Path) -> Result<Self> {
        let io = |source| Error::Io {
            path: path.to_path_buf(),
            source,
        };
        let (file, meta) = crate::input::open_regular_file(path)?;
        let bad = |why: String| Error::param("photon file", format!("{}: {why}", path.display()));
        let len = meta.len();
        if len < HEADER_SIZE as u64 + TRAILER_SIZE {
            return Err(bad(format!("truncated ({len} bytes, less than a header)")));
        }
        let mut file = BufReader::with_capacity(1 << 20, file);
        let mut hb = vec![0u8; HEADER_SIZE];
        file.read_exact(&mut hb).map_err(io)?;
        let header = Header::from_bytes(&hb)
            .and_then(|h| h.validate().map(|()| h))
            .map_err(|e| match e {
                // Named once, with the file: not "photon file: photon file: ...".
                Error::InvalidParameter { reason, .. } => bad(reason),
                other => other,
            })?;
        let expected = header
            .photons
            .checked_mul(PHOTON_SIZE)
            .and_then(|b| b.checked_add(HEADER_SIZE as u64 + TRAILER_SIZE));
        if expected != Some(len) {
            return Err(bad(format!(
                "{len} bytes, but its header announces {} photons ({} bytes): truncated or corrupt",
                header.photons,
                expected.map_or("too many".into(), |e| e.to_string())
            )));
        }
        let mut hash = ByteHash::default();
        hash.update(&hb);
        Ok(PhotonReader {
            path: path.to_path_buf(),
            file,
            left: header.photons,
            header,
            hash,
            photons_hash: MapHash::default(),
            buf: Vec::new(),
            verified: false,
        })
    }

    /// The header.
    pub fn header(&self) -> &Header {
        &self.header
    }

    /// The next chunk of raw photon bytes (16 per photon, little-endian), or
    /// `None` once every photon has been read and the checksum matched.
    ///
    /// # Errors
    /// [`Error::Io`] on a read failure; [`Error::InvalidParameter`] when the
    /// checksum or the trailer does not match (a corrupt file).
    pub fn next_bytes(&mut self) -> Result<Option<&[u8]>> {
        let io = |source| Error::Io {
            path: self.path.clone(),
            source,
        };
        if self.left == 0 {
            if !self.verified {
                self.verify_trailer()?;
            }
            return Ok(None);
        }
        let n = self.left.min(CHUNK_PHOTONS);
        self.buf.resize((n * PHOTON_SIZE) as usize, 0);
        self.file.read_exact(&mut self.buf).map_err(io)?;
        self.hash.update(&self.buf);
        photons_of(&self.buf).for_each(|p| self.photons_hash.add(&p));
        self.left -= n;
        Ok(Some(&self.buf))
    }

    fn verify_trailer(&mut self) -> Result<()> {
        let mut t = [0u8; TRAILER_SIZE as usize];
        self.file.read_exact(&mut t).map_err(|source| Error::Io {
            path: self.path.clone(),
            source,
        })?;
        self.buf = Vec::new();
        let stored = u64::from_le_bytes([t[8], t[9], t[10], t[11], t[12], t[13], t[14], t[15]]);
        let corrupt = |what: &str| {
            Error::param(
                "photon file",
                format!(
                    "{}: {what} checksum mismatch (the file is corrupt)",
                    self.path.display()
                ),
            )
        };
        if t[..8] != TRAILER_MAGIC || stored != self.hash.value() {
            return Err(corrupt("file"));
        }
        // The photons must also be those the header's map checksum describes
        // (a file resealed after editing its photons or its header).
        let announced = MapHash {
            count: self.header.photons,
            sum: self.header.photon_sum,
        };
        if self.photons_hash != announced {
            return Err(corrupt("photon"));
        }
        self.verified = true;
        Ok(())
    }
}

/// Splits raw photon bytes into compact photons.
pub(crate) fn photons_of(bytes: &[u8]) -> impl Iterator<Item = CompactPhoton> + '_ {
    bytes.chunks_exact(16).map(|c| {
        let w = |i: usize| {
            let mut a = [0u8; 8];
            a.copy_from_slice(&c[i..i + 8]);
            u64::from_le_bytes(a)
        };
        CompactPhoton::from_bits(w(0), w(8))
    })
}

/// Reads a whole photon file into a kd-tree photon map, keeping the photons
/// that `keep` accepts, checking the checksums.
///
/// # Errors
/// As [`PhotonReader::open`] and [`PhotonReader::next_bytes`];
/// [`Error::InvalidParameter`] for a map over `u32::MAX` photons or one whose
/// memory cannot be reserved.
pub fn read_map(path: &Path, keep: impl Fn(&CompactPhoton) -> bool) -> Result<(Header, PhotonMap)> {
    read_open_map(PhotonReader::open(path)?, keep)
}

/// [`read_map`] from an open reader.
fn read_open_map(
    mut r: PhotonReader,
    keep: impl Fn(&CompactPhoton) -> bool,
) -> Result<(Header, PhotonMap)> {
    let header = r.header().clone();
    let bad = |why: String| Error::param("photon file", format!("{}: {why}", r.path.display()));
    if header.photons > u32::MAX as u64 {
        return Err(bad(format!(
            "{} photons: a map holds at most u32::MAX",
            header.photons
        )));
    }
    let mut photons = Vec::new();
    // The count is bounded by the file's length, not by memory: reserve
    // fallibly so that a map too large for this machine is an error.
    photons
        .try_reserve_exact(header.photons as usize)
        .map_err(|_| Error::OutOfMemory {
            what: "a photon file's photons",
            bytes: header.photons.saturating_mul(16),
            budget_bytes: crate::engine::config::available_memory(),
        })?;
    while let Some(bytes) = r.next_bytes()? {
        photons.extend(photons_of(bytes).filter(|p| keep(p)));
    }
    let frame = header.frame();
    Ok((header, PhotonMap::from_compact(photons, frame)))
}

/// The three maps a render reads, from a map file of `scene`: a merged map,
/// or the photon file of a whole (unsharded) run.
///
/// # Errors
/// As [`read_map`]; [`Error::InvalidParameter`] when the file was traced in
/// another scene, or is one shard of a sharded run (its photons carry their
/// share of the whole run's power: alone they would give a fraction of the
/// light, so every shard must be merged first).
pub fn read_render_maps(
    path: &Path,
    scene: &crate::scene::Scene,
) -> Result<(Header, crate::render::RenderMaps)> {
    let reader = PhotonReader::open(path)?;
    let header = reader.header();
    if header.shard_count != 1 {
        return Err(Error::param(
            "photon file",
            format!(
                "{} is shard {}/{} of a run, not a whole map: merge every shard first \
                 (adaptive-pm merge SHARD.apm... --out MAP.apm)",
                path.display(),
                header.shard_index,
                header.shard_count
            ),
        ));
    }
    if header.scene_hash != super::scene_hash(scene) {
        return Err(Error::param(
            "photon file",
            // The hash covers everything this build knows of a scene, so a
            // release that reads more of a file (a material's new field) sees
            // the same file as another scene: say so rather than blame it.
            format!(
                "{} was traced in another scene (or by a release of adaptive-pm \
                 that read this scene's file differently: trace it again)",
                path.display()
            ),
        ));
    }
    let (header, full) = read_open_map(reader, |_| true)?;
    let (photons, frame) = full.into_compact();
    let photons = photons
        .into_iter()
        .map(|p| CompactPhoton::from_bits(p.bits().0, p.bits().1))
        .collect();
    let maps = crate::render::RenderMaps::from_photons(photons, frame);
    Ok((header, maps))
}
