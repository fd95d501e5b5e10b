//! The files a glTF scene names by URI (buffers, images), read only from
//! inside its asset root.
//!
//! - The asset root is a folder: the scene file's own by default, or the one
//!   [`LoadOptions::asset_root`](super::LoadOptions) names (the command
//!   line's `--asset-root`), which must hold the scene file's folder.
//! - A URI other than `data:` is a relative path, percent-decoded and
//!   resolved against the scene file's folder (as glTF 2.0 says), dot
//!   segments removed. It may climb (`../textures/wood.png`) anywhere inside
//!   the root but never out of it, also once symbolic links are resolved.
//!   Absolute paths, `file://` and other schemes are refused; so is anything
//!   that is not a regular file (`/dev/zero`, a FIFO, `/proc/...`), checked
//!   before opening and again on the open handle.
//! - Every read is bounded: a buffer's file is read up to its `byteLength`
//!   and no further ([`read_external_prefix`]); any other file is refused
//!   past its limit ([`read_external`]).
//!
//! Errors name the URI (shortened) and, when it escapes, the root; never the
//! file's contents, size or resolved path.

use crate::error::{Error, Result};
use std::ffi::OsString;
use std::fs::{File, Metadata};
use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// Where a scene's external files may be read from.
#[derive(Debug)]
pub(super) struct AssetRoot {
    /// The root as the caller named it (or the scene file's folder), for messages.
    shown: PathBuf,
    /// The root with its symbolic links resolved.
    canonical: PathBuf,
    /// The scene file's folder below `canonical`: where relative URIs start.
    scene_folder: Vec<OsString>,
    /// Whether no root was named, so the root is the scene file's folder.
    is_scene_folder: bool,
}

impl AssetRoot {
    /// The asset root of the scene file `scene`: `root`, or the scene's folder.
    ///
    /// # Errors
    /// [`Error::Io`] when the scene's folder or `root` cannot be resolved
    /// (missing, unreadable); [`Error::InvalidScene`] when `root` is not a
    /// folder, or does not hold the scene file's folder.
    pub(super) fn of_scene(scene: &Path, root: Option<&Path>) -> Result<Self> {
        let folder = match scene.parent() {
            Some(p) if !p.as_os_str().is_empty() => p,
            // `scene.gltf` in the working folder: its parent is "".
            _ => Path::new("."),
        };
        let io = |path: &Path| {
            let path = path.to_path_buf();
            move |source| Error::Io { path, source }
        };
        let real_folder = folder.canonicalize().map_err(io(scene))?;
        let (shown, canonical) = match root {
            None => (folder.to_path_buf(), real_folder.clone()),
            Some(r) => (r.to_path_buf(), r.canonicalize().map_err(io(r))?),
        };
        if !canonical.is_dir() {
            return Err(Error::InvalidScene(format!(
                "the asset root `{}` is not a folder",
                shown.display()
            )));
        }
        let Ok(below) = real_folder.strip_prefix(&canonical) else {
            return Err(Error::InvalidScene(format!(
                "the scene file `{}` is not inside the asset root `{}`",
                scene.display(),
                shown.display()
            )));
        };
        Ok(AssetRoot {
            scene_folder: below.iter().map(OsString::from).collect(),
            shown,
            canonical,
            is_scene_folder: root.is_none(),
        })
    }

    /// `the asset root `dir``, with what it is when the caller named none.
    fn describe(&self) -> String {
        let dir = self.shown.display();
        if self.is_scene_folder {
            format!("the asset root `{dir}` (the scene file's folder)")
        } else {
            format!("the asset root `{dir}`")
        }
    }
}

/// The URI as a message shows it: at most 80 characters.
fn shown(uri: &str) -> String {
    let mut s: String = uri.chars().take(80).collect();
    if s.len() < uri.len() {
        s.push('…');
    }
    format!("`{}`", s.escape_debug())
}

/// The error for resource `what` (`buffer 3`, `image 2`) at `uri`.
pub(super) fn refuse(what: &str, uri: &str, why: &str) -> Error {
    Error::InvalidScene(format!("{what} uri {}: {why}", shown(uri)))
}

/// Reads a resource a glTF file names by URI (an image): a `data:` URI, or
/// a file inside `root` ([`read_external`]), of at most `max_bytes`.
pub(super) fn read_resource(
    what: &str,
    uri: &str,
    max_bytes: u64,
    root: Option<&AssetRoot>,
) -> Result<Vec<u8>> {
    if !uri.starts_with("data:") {
        return read_external(what, uri, max_bytes, require_root(what, uri, root)?);
    }
    let data = decode_data_uri(what, uri)?;
    if data.len() as u64 > max_bytes {
        return Err(refuse(
            what,
            uri,
            &format!("larger than the limit of {max_bytes} bytes"),
        ));
    }
    Ok(data)
}

/// `root`, or the error for a scene loaded from memory (no folder to read in).
pub(super) fn require_root<'r>(
    what: &str,
    uri: &str,
    root: Option<&'r AssetRoot>,
) -> Result<&'r AssetRoot> {
    root.ok_or_else(|| refuse(what, uri, "external files need a scene file's folder"))
}

/// The bytes of a base64 `data:` URI.
pub(super) fn decode_data_uri(what: &str, uri: &str) -> Result<Vec<u8>> {
    let Some((_, payload)) = uri.split_once(";base64,") else {
        return Err(refuse(what, uri, "only base64 data URIs are supported"));
    };
    base64::decode(payload).map_err(|_| refuse(what, uri, "invalid base64"))
}

/// Reads the whole file that the relative `uri` names inside `root`, a
/// regular file of at most `max_bytes`. `what` names the resource in errors
/// (`image 2`).
///
/// # Errors
/// [`Error::InvalidScene`] naming `what` and the URI for a URI that is not a
/// relative path, one that leaves the root (lexically or through a symbolic
/// link; the message names the root), a missing or non-regular file, or a
/// file over `max_bytes`.
pub(super) fn read_external(
    what: &str,
    uri: &str,
    max_bytes: u64,
    root: &AssetRoot,
) -> Result<Vec<u8>> {
    let (file, meta) = open_external(what, uri, root)?;
    let too_big = || {
        refuse(
            what,
            uri,
            &format!("the file is larger than the limit of {max_bytes} bytes"),
        )
    };
    if meta.len() > max_bytes {
        return Err(too_big());
    }
    // One byte past the limit: a file that grows while it is read is refused.
    let data = read_at_most(what, uri, file, meta.len(), max_bytes.saturating_add(1))?;
    if data.len() as u64 > max_bytes {
        return Err(too_big());
    }
    Ok(data)
}

/// Reads the first `len` bytes of the file that `uri` names inside `root`
/// (a buffer's `byteLength`: a longer file is fine, nothing past `len` is
/// read). Errors as [`read_external`]'s, and for a file shorter than `len`.
pub(super) fn read_external_prefix(
    what: &str,
    uri: &str,
    len: u64,
    root: &AssetRoot,
) -> Result<Vec<u8>> {
    let (file, meta) = open_external(what, uri, root)?;
    if meta.len() < len {
        return Err(refuse(
            what,
            uri,
            "the file is shorter than the buffer's byteLength",
        ));
    }
    read_at_most(what, uri, file, len, len)
}

fn read_at_most(what: &str, uri: &str, file: File, expect: u64, limit: u64) -> Result<Vec<u8>> {
    let mut data = Vec::with_capacity(expect as usize);
    file.take(limit)
        .read_to_end(&mut data)
        .map_err(|_| refuse(what, uri, "read failed"))?;
    Ok(data)
}

/// Opens the regular file that `uri` names inside `root`.
fn open_external(what: &str, uri: &str, root: &AssetRoot) -> Result<(File, Metadata)> {
    let escapes = |why: &str| refuse(what, uri, &format!("{why} {}", root.describe()));
    let path = resolve(uri, &root.scene_folder, &root.canonical).map_err(|why| match why {
        Unresolved::Escapes => escapes("the path leaves"),
        Unresolved::Other(why) => refuse(what, uri, why),
    })?;
    let not_found = || refuse(what, uri, "cannot be opened");
    // Symbolic links may point anywhere: the resolved file must still be inside.
    let real = path.canonicalize().map_err(|_| not_found())?;
    if !real.starts_with(&root.canonical) {
        return Err(escapes("it resolves outside"));
    }
    // The error names the URI, never the resolved path.
    crate::input::open_regular_file(&real).map_err(|e| {
        if crate::input::is_not_regular(&e) {
            refuse(what, uri, "not a regular file")
        } else {
            not_found()
        }
    })
}

/// Percent-decodes a URI path; `None` on a malformed escape, a NUL or bad UTF-8.
pub fn percent_decode(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut k = 0;
    while k < b.len() {
        if b[k] == b'%' {
            let hex = std::str::from_utf8(b.get(k + 1..k + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            k += 3;
        } else {
            out.push(b[k]);
            k += 1;
        }
    }
    if out.contains(&0) {
        return None;
    }
    String::from_utf8(out).ok()
}

/// Why a URI names no path inside the root.
enum Unresolved {
    /// Its `..` climb above the root.
    Escapes,
    Other(&'static str),
}

/// The path of a relative URI inside `base` (its root), normalised; `Err`
/// names why not.
pub fn resolve_inside(uri: &str, base: &Path) -> std::result::Result<PathBuf, &'static str> {
    resolve(uri, &[], base).map_err(|why| match why {
        Unresolved::Escapes => "the path leaves the asset root",
        Unresolved::Other(why) => why,
    })
}

/// The path of a relative URI that starts in `root`'s subfolder `start`,
/// its dot segments removed (RFC 3986 §5.2.4) without touching the file
/// system, so `..` may climb to `root` but not above it.
fn resolve(uri: &str, start: &[OsString], root: &Path) -> std::result::Result<PathBuf, Unresolved> {
    let scheme = uri.split_once(':').is_some_and(|(s, _)| {
        !s.is_empty()
            && !s.contains(['/', '\\'])
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    if scheme {
        return Err(Unresolved::Other(
            "URI schemes (file://, http://, ...) are not read; use a relative path",
        ));
    }
    let path = percent_decode(uri).ok_or(Unresolved::Other("malformed percent-encoding"))?;
    if path.starts_with(['/', '\\']) || Path::new(&path).has_root() {
        return Err(Unresolved::Other(
            "absolute paths are not read; use a path relative to the scene file",
        ));
    }
    let mut parts: Vec<OsString> = start.to_vec();
    for part in path.split(['/', '\\']) {
        match part {
            "" | "." => {}
            ".." => {
                parts.pop().ok_or(Unresolved::Escapes)?;
            }
            p => {
                // `C:` and the like are no normal component on every system.
                if Path::new(p)
                    .components()
                    .any(|c| !matches!(c, Component::Normal(_)))
                {
                    return Err(Unresolved::Escapes);
                }
                parts.push(p.into());
            }
        }
    }
    if parts.is_empty() {
        return Err(Unresolved::Other("the path names no file"));
    }
    let mut out = root.to_path_buf();
    out.extend(parts);
    Ok(out)
}
