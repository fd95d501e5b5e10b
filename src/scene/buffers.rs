//! Loading a glTF file's buffers without reading anything outside its asset root.
//!
//! - The GLB binary chunk and `data:` URIs (base64) are already in memory:
//!   their size is bounded by the file's.
//! - Any other URI is a file inside the scene's asset root, read by
//!   [`super::assets`] (which says what may be read), never past the
//!   buffer's declared `byteLength`.
//! - The declared lengths together are bounded by [`MAX_BUFFER_BYTES`]
//!   before any byte is read.

use super::assets::{decode_data_uri, read_external_prefix, require_root, AssetRoot};
use crate::error::{Error, Result};
use gltf::json::Root;

/// Bytes all buffers of one scene may declare together (1 GiB).
pub const MAX_BUFFER_BYTES: u64 = 1 << 30;

/// Loads every buffer of `root`; `blob` is the GLB binary chunk, `assets`
/// the scene's asset root (`None` when loading from memory: no external files).
pub(super) fn load_buffers(
    root: &Root,
    blob: Option<Vec<u8>>,
    assets: Option<&AssetRoot>,
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
            // A compressing writer's fallback: the views decoded into it are
            // all it holds (the GLB chunk is buffer 0's, never a fallback's).
            None if (i > 0 || blob.is_none()) && super::gltf_meshopt::is_fallback(root, i) => {
                vec![0; want as usize]
            }
            None => blob.take().ok_or_else(|| {
                Error::InvalidScene(format!(
                    "buffer {i} has no uri and there is no GLB binary chunk"
                ))
            })?,
            Some(uri) if uri.starts_with("data:") => decode_data_uri(&format!("buffer {i}"), uri)?,
            Some(uri) => {
                let what = format!("buffer {i}");
                read_external_prefix(&what, uri, want, require_root(&what, uri, assets)?)?
            }
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
