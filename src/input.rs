//! Safe input files: every file a command reads is a regular file of bounded
//! size, so a hostile path cannot hang or exhaust the process.
//!
//! - A FIFO, a character device (`/dev/zero`, `/dev/urandom`), a socket or a
//!   folder is refused **before** it is opened: opening a FIFO for reading
//!   blocks until a writer appears, possibly forever. The check is repeated on
//!   the open handle, so a path swapped for something else in between is
//!   still refused before any byte is read.
//! - [`read_regular_file`] reads at most the given number of bytes; a file
//!   that is larger (or grows while being read) is refused, never read to the
//!   end.
//!
//! glTF buffer URIs follow the same rules in `scene::buffers`; every other
//! reader of the crate and of the CLI (scenes, photon files, EXR images and
//! tiles, the trade study's cache) goes through [`open_regular_file`] or
//! [`read_regular_file`].

use crate::error::{Error, Result};
use std::fs::{File, Metadata};
use std::io::Read;
use std::path::Path;

fn io_err(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn invalid(path: &Path, msg: String) -> Error {
    io_err(
        path,
        std::io::Error::new(std::io::ErrorKind::InvalidInput, msg),
    )
}

/// What a non-regular file is, for the error message.
fn kind_of(meta: &Metadata) -> &'static str {
    use std::os::unix::fs::FileTypeExt;
    let t = meta.file_type();
    if t.is_dir() {
        "a folder"
    } else if t.is_fifo() {
        "a FIFO (named pipe)"
    } else if t.is_char_device() || t.is_block_device() {
        "a device"
    } else if t.is_socket() {
        "a socket"
    } else {
        "not a regular file"
    }
}

/// Whether `e`, from [`open_regular_file`] or [`read_regular_file`], says
/// the path is not a regular file (rather than missing or unreadable).
pub fn is_not_regular(e: &Error) -> bool {
    matches!(e, Error::Io { source, .. } if source.kind() == std::io::ErrorKind::InvalidInput
        && source.to_string().contains(NOT_REGULAR))
}

/// The words every not-a-regular-file error carries.
const NOT_REGULAR: &str = "only regular files are read";

fn require_regular(path: &Path, meta: &Metadata) -> Result<()> {
    if meta.file_type().is_file() {
        Ok(())
    } else {
        Err(invalid(path, format!("{}: {NOT_REGULAR}", kind_of(meta))))
    }
}

/// Opens `path` for reading if it is a regular file (symbolic links are
/// followed), and returns the handle with its metadata (taken from the
/// handle, so its length is that of the file actually opened).
///
/// The type is checked before opening (opening a FIFO would block) and again
/// on the open handle (the path may have been replaced in between).
///
/// # Errors
/// [`Error::Io`] naming `path` when it is missing, unreadable, or not a
/// regular file (a FIFO, a device, a socket, a folder).
pub fn open_regular_file(path: &Path) -> Result<(File, Metadata)> {
    let before = std::fs::metadata(path).map_err(|e| io_err(path, e))?;
    require_regular(path, &before)?;
    let file = File::open(path).map_err(|e| io_err(path, e))?;
    let meta = file.metadata().map_err(|e| io_err(path, e))?;
    require_regular(path, &meta)?;
    Ok((file, meta))
}

/// Reads the whole of `path`, a regular file of at most `max_bytes` bytes.
///
/// The size is checked from the metadata before anything is allocated, the
/// buffer is reserved fallibly, and the read stops one byte past `max_bytes`
/// (a file that grows while being read, or a `/proc` file that reports size
/// 0, is refused rather than read without end).
///
/// # Errors
/// As [`open_regular_file`]; [`Error::Io`] naming `path` when it is larger
/// than `max_bytes`, when the memory cannot be reserved, or when reading fails.
pub fn read_regular_file(path: &Path, max_bytes: u64) -> Result<Vec<u8>> {
    let (file, meta) = open_regular_file(path)?;
    let too_big = || {
        invalid(
            path,
            format!("the file is larger than the limit of {max_bytes} bytes"),
        )
    };
    if meta.len() > max_bytes {
        return Err(too_big());
    }
    let mut bytes = Vec::new();
    let want = usize::try_from(meta.len()).map_err(|_| too_big())?;
    bytes
        .try_reserve_exact(want)
        .map_err(|_| Error::OutOfMemory {
            what: "reading a file",
            bytes: want as u64,
            budget_bytes: max_bytes,
        })?;
    file.take(max_bytes.saturating_add(1))
        .read_to_end(&mut bytes)
        .map_err(|e| io_err(path, e))?;
    if bytes.len() as u64 > max_bytes {
        return Err(too_big());
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn regular_files_are_read_and_others_refused() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("a.bin");
        std::fs::write(&p, b"12345678").unwrap();
        assert_eq!(read_regular_file(&p, 8).unwrap(), b"12345678");
        let e = read_regular_file(&p, 7).unwrap_err();
        assert!(anyhow_like(&e).contains("larger than"));
        for other in [Path::new("/dev/zero"), dir.path()] {
            let e = open_regular_file(other).unwrap_err();
            assert!(anyhow_like(&e).contains("only regular files"), "{e}");
        }
        assert!(open_regular_file(&dir.path().join("missing")).is_err());
    }

    /// The error with its source, as the CLI prints it.
    fn anyhow_like(e: &Error) -> String {
        use std::error::Error as _;
        match e.source() {
            Some(s) => format!("{e}: {s}"),
            None => e.to_string(),
        }
    }
}
