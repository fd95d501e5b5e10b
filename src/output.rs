//! Safe output files: every file a command writes appears whole or not at all,
//! and never replaces something that is not a regular file.
//!
//! - The target must be absent or a regular file (also through a symbolic
//!   link): a character device (`--out /dev/null`), a FIFO, a socket or a
//!   folder is refused, so running as root cannot destroy `/dev/null`.
//! - The bytes go to a temporary file in the target's folder, created with
//!   `create_new` (`O_CREAT | O_EXCL`: never opens an existing file, never
//!   follows a planted symbolic link), flushed with `fsync`, then renamed over
//!   the target (atomic within a file system). On any failure the temporary
//!   file is removed and the target is left as it was.
//!
//! - An output is never one of the command's inputs, however spelled
//!   ([`refuse_overwrite`]: same device and inode, or same resolved path).
//!
//! Every writer of the crate and of the CLI goes through [`write_bytes`],
//! [`write_with`], [`write_via_path`] or [`AtomicOutput`].

use crate::error::{Error, Result};
use std::fs::{File, OpenOptions};
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};

fn io_err(path: &Path, source: std::io::Error) -> Error {
    Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn invalid(path: &Path, msg: &str) -> Error {
    io_err(
        path,
        std::io::Error::new(std::io::ErrorKind::InvalidInput, msg.to_string()),
    )
}

fn parent_of(path: &Path) -> PathBuf {
    match path.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Checks that `path` may receive an output file: its folder exists, and it
/// is absent or a regular file (symbolic links are followed for this check).
///
/// # Errors
/// [`Error::Io`] naming the path and why.
pub fn check_target(path: &Path) -> Result<()> {
    if path.file_name().is_none() {
        return Err(invalid(path, "the output path names no file"));
    }
    let parent = parent_of(path);
    if !parent.is_dir() {
        return Err(invalid(path, "the output folder does not exist"));
    }
    match std::fs::metadata(path) {
        Ok(m) if m.file_type().is_file() => Ok(()),
        Ok(m) if m.is_dir() => Err(invalid(path, "the output path is a folder")),
        Ok(_) => Err(invalid(
            path,
            "the output path exists and is not a regular file (a device, FIFO or socket)",
        )),
        // A dangling symbolic link: rename replaces the link itself.
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(io_err(path, e)),
    }
}

/// The most bytes of the target's file name that a temporary name repeats:
/// a legal name of 255 bytes, with the suffix, would pass the file
/// system's limit ("File name too long" on a 254-byte `--out`).
const TEMP_NAME_PREFIX_BYTES: usize = 64;

/// Creates something new beside `path`, under the first free name of
/// `.{file name}.{kind}-{pid}-{n}` (the file name cut to
/// [`TEMP_NAME_PREFIX_BYTES`]): `create` must fail with `AlreadyExists`
/// when the name is taken (`create_new`, `mkdir`), so nothing that exists,
/// or a link planted at that name, is ever opened.
fn create_beside<T>(
    path: &Path,
    kind: &str,
    create: impl Fn(&Path) -> std::io::Result<T>,
) -> Result<(PathBuf, T)> {
    static COUNTER: AtomicU64 = AtomicU64::new(0);
    let mut name = path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "out".into());
    let mut cut = name.len().min(TEMP_NAME_PREFIX_BYTES);
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    name.truncate(cut);
    let parent = parent_of(path);
    for _ in 0..64 {
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let candidate = parent.join(format!(".{name}.{kind}-{}-{n}", std::process::id()));
        match create(&candidate) {
            Ok(made) => return Ok((candidate, made)),
            Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(io_err(path, e)),
        }
    }
    Err(invalid(path, "cannot create a temporary file beside it"))
}

/// Creates a fresh temporary file beside `path` (exclusively).
fn create_temp(path: &Path) -> Result<(PathBuf, File)> {
    create_beside(path, "tmp", |p| {
        OpenOptions::new().write(true).create_new(true).open(p)
    })
}

/// Creates a fresh folder beside `path` that only we can enter.
fn create_private_dir(path: &Path) -> Result<PathBuf> {
    let (dir, ()) = create_beside(path, "tmpdir", |p| {
        let mut builder = std::fs::DirBuilder::new();
        #[cfg(unix)]
        std::os::unix::fs::DirBuilderExt::mode(&mut builder, 0o700);
        builder.create(p)
    })?;
    Ok(dir)
}

/// Renames `tmp` (written and synced: `synced`) over `path`, or removes it
/// on failure.
fn finish(path: &Path, tmp: &Path, synced: std::io::Result<()>) -> Result<()> {
    let done = synced.and_then(|()| {
        // The target may have been replaced meanwhile: check again.
        check_target(path).map_err(|e| std::io::Error::other(e.to_string()))?;
        std::fs::rename(tmp, path)
    });
    if let Err(e) = done {
        let _ = std::fs::remove_file(tmp);
        return Err(io_err(path, e));
    }
    // Best effort: make the rename itself durable.
    if let Ok(dir) = File::open(parent_of(path)) {
        let _ = dir.sync_all();
    }
    Ok(())
}

/// Writes `bytes` to `path` atomically.
///
/// # Errors
/// [`Error::Io`] for a refused target or a failed write; `path` is untouched then.
pub fn write_bytes(path: impl AsRef<Path>, bytes: &[u8]) -> Result<()> {
    write_with(path, |w| w.write_all(bytes))
}

/// Writes to `path` atomically through `write`, given a buffered writer.
///
/// # Errors
/// As [`write_bytes`], and whatever `write` returns.
pub fn write_with(
    path: impl AsRef<Path>,
    write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>,
) -> Result<()> {
    let path = path.as_ref();
    let mut out = AtomicOutput::create(path)?;
    let mut w = BufWriter::new(out.file());
    let written = write(&mut w).and_then(|()| w.flush());
    drop(w);
    // On failure `out` is dropped unfinished: its temporary is removed.
    written.map_err(|e| io_err(path, e))?;
    out.finish()
}

/// An output file written in pieces under a temporary name beside its
/// target (for writers that stream, such as the photon files): created with
/// [`check_target`]'s checks and `create_new`, renamed over the target by
/// [`AtomicOutput::finish`] as [`write_bytes`] does; dropped unfinished, the
/// temporary is removed and the target left as it was.
#[derive(Debug)]
pub struct AtomicOutput {
    path: PathBuf,
    tmp: PathBuf,
    file: Option<File>,
}

impl AtomicOutput {
    /// Creates the temporary beside `path`.
    ///
    /// # Errors
    /// As [`check_target`], or when the folder is not writable.
    pub fn create(path: impl AsRef<Path>) -> Result<Self> {
        let path = path.as_ref();
        check_target(path)?;
        let (tmp, file) = create_temp(path)?;
        Ok(AtomicOutput {
            path: path.to_path_buf(),
            tmp,
            file: Some(file),
        })
    }

    /// The open temporary file.
    pub fn file(&mut self) -> &mut File {
        self.file.as_mut().expect("open until finished")
    }

    /// Syncs the temporary and renames it over the target.
    ///
    /// # Errors
    /// [`Error::Io`] when syncing or renaming fails (the temporary is removed).
    pub fn finish(mut self) -> Result<()> {
        let synced = self.file().sync_all();
        self.file.take();
        let tmp = std::mem::take(&mut self.tmp);
        finish(&self.path, &tmp, synced)
    }
}

impl Drop for AtomicOutput {
    fn drop(&mut self) {
        if !self.tmp.as_os_str().is_empty() {
            self.file.take();
            let _ = std::fs::remove_file(&self.tmp);
        }
    }
}

/// Writes to `path` atomically through `write`, given the path of a fresh
/// file to create: for encoders that open a path themselves (EXR, plotters).
/// That file lies in a private folder (`0700`, created exclusively beside
/// the target), so nobody else can plant a link at its name between our
/// creating it and the encoder's opening it.
///
/// # Errors
/// As [`write_bytes`], and whatever `write` returns.
pub fn write_via_path(
    path: impl AsRef<Path>,
    write: impl FnOnce(&Path) -> std::io::Result<()>,
) -> Result<()> {
    let path = path.as_ref();
    check_target(path)?;
    let dir = create_private_dir(path)?;
    let inner = dir.join(path.file_name().unwrap_or_else(|| "out".as_ref()));
    // Reopened by name to sync: safe inside the private folder.
    let synced = write(&inner).and_then(|()| File::open(&inner)?.sync_all());
    let done = finish(path, &inner, synced);
    let _ = std::fs::remove_dir(&dir);
    done
}

/// Checks, before a long run, that `path` will be writable: [`check_target`],
/// then a temporary file is created beside it (exclusively) and removed.
///
/// # Errors
/// As [`check_target`], or when the folder is not writable.
pub fn probe(path: impl AsRef<Path>) -> Result<()> {
    let path = path.as_ref();
    check_target(path)?;
    let (tmp, file) = create_temp(path)?;
    drop(file);
    let _ = std::fs::remove_file(tmp);
    Ok(())
}

/// The identity of an existing file: its device and inode.
#[cfg(unix)]
fn identity(path: &Path) -> Option<(u64, u64)> {
    use std::os::unix::fs::MetadataExt;
    std::fs::metadata(path).ok().map(|m| (m.dev(), m.ino()))
}

/// Elsewhere: no identity, files are compared by resolved path.
#[cfg(not(unix))]
fn identity(_: &Path) -> Option<(u64, u64)> {
    None
}

/// `path` with its folder resolved (symbolic links, `.`, `..`): how a path
/// that does not exist yet is compared.
fn resolved(path: &Path) -> PathBuf {
    if let Ok(p) = path.canonicalize() {
        return p;
    }
    match (parent_of(path).canonicalize(), path.file_name()) {
        (Ok(dir), Some(name)) => dir.join(name),
        _ => path.to_path_buf(),
    }
}

/// Whether `a` and `b` name the same file: the same device and inode when
/// both exist (this sees through `./`, `..`, absolute spellings, symbolic
/// and hard links), else the same path once resolved.
fn same_file(a: &Path, b: &Path) -> bool {
    match (identity(a), identity(b)) {
        (Some(x), Some(y)) => x == y,
        _ => resolved(a) == resolved(b),
    }
}

/// Refuses an output path that names one of the command's input files,
/// however it is spelled: `out.apm`, `./out.apm`, `$PWD/out.apm`,
/// `dir/../dir/out.apm`, a symbolic or hard link to it. Writing the output
/// would replace that input (and a reader still streaming it would read the
/// new file). Call it before any work, with every file the command reads.
///
/// Files are compared by device and inode when both exist, by their
/// resolved paths otherwise.
///
/// # Errors
/// [`Error::Io`] naming `out` and the input it would overwrite.
pub fn refuse_overwrite(out: &Path, inputs: &[&Path]) -> Result<()> {
    match inputs.iter().find(|input| same_file(out, input)) {
        Some(input) => Err(invalid(
            out,
            &format!(
                "the output is also the input {}: it would be overwritten",
                input.display()
            ),
        )),
        None => Ok(()),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::io::Write;

    /// Every legal file name works, the longest (255 bytes) and multi-byte
    /// ones included, and no temporary is left beside it.
    #[test]
    fn the_longest_legal_names_are_written() {
        let dir = tempfile::tempdir().unwrap();
        for name in ["a".repeat(254), "b".repeat(255), "é".repeat(127)] {
            let path = dir.path().join(&name);
            let mut out = AtomicOutput::create(&path).unwrap();
            out.file().write_all(b"x").unwrap();
            out.finish().unwrap();
            assert_eq!(std::fs::read(&path).unwrap(), b"x");
        }
        assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 3);
    }
}
