//! Loading a glTF file's buffers without reading anything outside the scene.
//!
//! - The GLB binary chunk and `data:` URIs (base64) are already in memory:
//!   their size is bounded by the file's.
//! - Any other URI is a relative path, percent-decoded and normalised, that
//!   must stay inside the scene file's folder, also once symbolic links are
//!   resolved. Absolute paths, `..` escapes, `file://` and other schemes are
//!   refused; so is anything that is not a regular file (`/dev/zero`, a FIFO,
//!   `/proc/...`), checked before opening and again on the open handle.
//! - A file is never read past the buffer's declared `byteLength`, and the
//!   declared lengths together are bounded by [`MAX_BUFFER_BYTES`] before any
//!   byte is read.
//!
//! Errors name the URI (shortened), never the file's contents or size.

use crate::error::{Error, Result};
use gltf::json::Root;
use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// Bytes all buffers of one scene may declare together (1 GiB).
pub const MAX_BUFFER_BYTES: u64 = 1 << 30;

/// The URI as a message shows it: at most 80 characters.
fn shown(uri: &str) -> String {
    let mut s: String = uri.chars().take(80).collect();
    if s.len() < uri.len() {
        s.push('…');
    }
    format!("`{}`", s.escape_debug())
}

fn refuse_resource(what: &str, uri: &str, why: &str) -> Error {
    Error::InvalidScene(format!("{what} uri {}: {why}", shown(uri)))
}

/// Loads every buffer of `root`; `blob` is the GLB binary chunk, `base` the
/// scene file's folder (`None` when loading from memory: no external files).
pub(super) fn load_buffers(
    root: &Root,
    blob: Option<Vec<u8>>,
    base: Option<&Path>,
) -> Result<Vec<Vec<u8>>> {
    let total = root
        .buffers
        .iter()
        .fold(0u64, |acc, b| acc.saturating_add(b.byte_length.0));
    if total > MAX_BUFFER_BYTES {
        return Err(Error::InvalidScene(format!(
            "the buffers declare {total} bytes, over the limit of {MAX_BUFFER_BYTES}"
        )));
    }
    let mut blob = blob;
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, b) in root.buffers.iter().enumerate() {
        let want = b.byte_length.0;
        let data = match b.uri.as_deref() {
            None => blob.take().ok_or_else(|| {
                Error::InvalidScene(format!(
                    "buffer {i} has no uri and there is no GLB binary chunk"
                ))
            })?,
            Some(uri) if uri.starts_with("data:") => decode_data_uri(&format!("buffer {i}"), uri)?,
            Some(uri) => read_file(&format!("buffer {i}"), uri, Bytes::AtLeast(want), base)?,
        };
        if (data.len() as u64) < want {
            return Err(Error::InvalidScene(format!(
                "buffer {i} holds fewer bytes than its byteLength"
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// Reads another resource a glTF file names by URI (an image): a `data:`
/// URI, or a file inside `base` under the same rules as buffers, of at most
/// `max_bytes`. `what` names it in errors (`image 2`).
pub(super) fn read_resource(
    what: &str,
    uri: &str,
    max_bytes: u64,
    base: Option<&Path>,
) -> Result<Vec<u8>> {
    let data = if uri.starts_with("data:") {
        decode_data_uri(what, uri)?
    } else {
        read_file(what, uri, Bytes::AtMost(max_bytes), base)?
    };
    if data.len() as u64 > max_bytes {
        return Err(refuse_resource(
            what,
            uri,
            "larger than the limit for one resource",
        ));
    }
    Ok(data)
}

/// How many bytes a file read takes.
#[derive(Clone, Copy)]
enum Bytes {
    /// A buffer's `byteLength`: the file must hold that many; no more is read.
    AtLeast(u64),
    /// A whole file of at most this many bytes.
    AtMost(u64),
}

fn decode_data_uri(what: &str, uri: &str) -> Result<Vec<u8>> {
    let Some((_, payload)) = uri.split_once(";base64,") else {
        return Err(refuse_resource(
            what,
            uri,
            "only base64 data URIs are supported",
        ));
    };
    base64::decode(payload).map_err(|_| refuse_resource(what, uri, "invalid base64"))
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

/// The path of a relative URI inside `base`, normalised; `Err` names why not.
pub fn resolve_inside(uri: &str, base: &Path) -> std::result::Result<PathBuf, &'static str> {
    let scheme = uri.split_once(':').is_some_and(|(s, _)| {
        !s.is_empty()
            && !s.contains(['/', '\\'])
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
    });
    if scheme {
        return Err("URI schemes (file://, http://, ...) are not read; use a relative path");
    }
    let path = percent_decode(uri).ok_or("malformed percent-encoding")?;
    if path.starts_with(['/', '\\']) || Path::new(&path).has_root() {
        return Err("absolute paths are not read; use a path relative to the scene file");
    }
    let mut parts: Vec<&str> = Vec::new();
    for part in path.split(['/', '\\']) {
        match part {
            "" | "." => {}
            ".." => {
                parts
                    .pop()
                    .ok_or("the path leaves the scene file's folder")?;
            }
            p => parts.push(p),
        }
    }
    if parts.is_empty() {
        return Err("the path names no file");
    }
    let mut out = base.to_path_buf();
    for p in parts {
        if Path::new(p)
            .components()
            .any(|c| !matches!(c, Component::Normal(_)))
        {
            return Err("the path leaves the scene file's folder");
        }
        out.push(p);
    }
    Ok(out)
}

fn read_file(what: &str, uri: &str, bytes: Bytes, base: Option<&Path>) -> Result<Vec<u8>> {
    let refuse = |why: &str| refuse_resource(what, uri, why);
    let base = base.ok_or_else(|| refuse("external files need a scene file's folder"))?;
    let path = resolve_inside(uri, base).map_err(refuse)?;
    let not_found = || refuse("cannot be opened");
    // Symbolic links may point anywhere: the resolved file must still be inside.
    let real = path.canonicalize().map_err(|_| not_found())?;
    let real_base = base.canonicalize().map_err(|_| not_found())?;
    if !real.starts_with(&real_base) {
        return Err(refuse("it resolves outside the scene file's folder"));
    }
    // The error names the URI, never the resolved path.
    let (file, meta) = crate::input::open_regular_file(&real).map_err(|e| {
        if crate::input::is_not_regular(&e) {
            refuse("not a regular file")
        } else {
            not_found()
        }
    })?;
    let take = match bytes {
        Bytes::AtLeast(want) if meta.len() < want => {
            return Err(refuse("the file is shorter than the buffer's byteLength"));
        }
        Bytes::AtMost(max) if meta.len() > max => {
            return Err(refuse("larger than the limit for one resource"));
        }
        Bytes::AtLeast(n) => n,
        Bytes::AtMost(_) => meta.len(),
    };
    let mut data = Vec::with_capacity(take as usize);
    file.take(take)
        .read_to_end(&mut data)
        .map_err(|_| refuse("read failed"))?;
    Ok(data)
}
