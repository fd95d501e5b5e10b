//! Writing a file so that nothing is left under its name unless it is complete:
//! a temporary created with `create_new` in the destination's folder (so an
//! existing file or a symlink planted there is never followed or truncated),
//! renamed over the destination only once written and flushed; dropped
//! unfinished, the temporary is removed.
//!
//! A local helper until the project's shared safe-output module lands.

use crate::error::{Error, Result};
use std::fs::{File, OpenOptions};
use std::path::{Path, PathBuf};

/// An output file being written under a temporary name.
#[derive(Debug)]
pub struct AtomicOutput {
    dest: PathBuf,
    tmp: PathBuf,
    file: Option<File>,
}

impl AtomicOutput {
    /// Creates the temporary next to `dest`.
    ///
    /// # Errors
    /// [`Error::Io`] when the folder is missing or not writable, or `dest` is a
    /// directory.
    pub fn create(dest: &Path) -> Result<Self> {
        let io = |source| Error::Io {
            path: dest.to_path_buf(),
            source,
        };
        if dest.is_dir() {
            return Err(io(std::io::Error::other("is a directory")));
        }
        let name = dest
            .file_name()
            .ok_or_else(|| io(std::io::Error::other("has no file name")))?;
        let dir = match dest.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        let mut n = 0u32;
        loop {
            let mut tmp_name = std::ffi::OsString::from(".");
            tmp_name.push(name);
            tmp_name.push(format!(".{}.{n}.tmp", std::process::id()));
            let tmp = dir.join(tmp_name);
            match OpenOptions::new().write(true).create_new(true).open(&tmp) {
                Ok(file) => {
                    return Ok(AtomicOutput {
                        dest: dest.to_path_buf(),
                        tmp,
                        file: Some(file),
                    })
                }
                Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists && n < 100 => n += 1,
                Err(e) => return Err(io(e)),
            }
        }
    }

    /// The open temporary file.
    pub fn file(&mut self) -> &mut File {
        self.file.as_mut().expect("open until finished")
    }

    /// Flushes the temporary to disk and renames it to the destination.
    ///
    /// # Errors
    /// [`Error::Io`] when syncing or renaming fails (the temporary is removed).
    pub fn finish(mut self) -> Result<()> {
        let file = self.file.take().expect("open until finished");
        let io = |source| Error::Io {
            path: self.dest.clone(),
            source,
        };
        file.sync_all().map_err(io)?;
        drop(file);
        std::fs::rename(&self.tmp, &self.dest).map_err(io)?;
        self.tmp = PathBuf::new();
        Ok(())
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
