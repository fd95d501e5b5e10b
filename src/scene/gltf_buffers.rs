//! The bytes of a glTF file's buffers: the GLB binary chunk, `data:` URIs
//! (base64) and files beside the scene. The `gltf` crate's own loader
//! (`gltf::import_buffers`) comes with its `import` feature, which brings an
//! image decoder for textures that this crate ignores, so buffers are read here.

use crate::error::{Error, Result};
use std::path::Path;

/// One byte slice per buffer of `doc`, in buffer order, each at least as long
/// as the buffer's declared `byteLength`.
///
/// # Errors
/// [`Error::Load`] (path `base`, or empty for a slice) for a missing GLB chunk,
/// a malformed `data:` URI, an unsupported scheme, an external file when
/// there is no `base` folder, a buffer file that cannot be read, or a buffer
/// shorter than it says.
pub(super) fn load(
    doc: &gltf::Document,
    base: Option<&Path>,
    mut blob: Option<Vec<u8>>,
) -> Result<Vec<Vec<u8>>> {
    let fail = |msg: String| Error::Load {
        path: base.map(Path::to_path_buf).unwrap_or_default(),
        source: msg.into(),
    };
    let mut out = Vec::with_capacity(doc.buffers().len());
    for buffer in doc.buffers() {
        let i = buffer.index();
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| fail(format!("buffer {i} refers to a missing GLB binary chunk")))?,
            gltf::buffer::Source::Uri(uri) => {
                read_uri(uri, base).map_err(|e| fail(format!("buffer {i}: {e}")))?
            }
        };
        if data.len() < buffer.length() {
            return Err(fail(format!(
                "buffer {i} holds {} bytes but declares {}",
                data.len(),
                buffer.length()
            )));
        }
        out.push(data);
    }
    Ok(out)
}

fn read_uri(uri: &str, base: Option<&Path>) -> std::result::Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let Some((_, payload)) = rest.split_once(";base64,") else {
            return Err("a data URI that is not base64".into());
        };
        return decode_base64(payload);
    }
    let relative = if let Some(rest) = uri
        .strip_prefix("file://")
        .or_else(|| uri.strip_prefix("file:"))
    {
        rest
    } else if uri.contains(':') {
        return Err(format!("unsupported URI scheme in `{uri}`"));
    } else {
        uri
    };
    let Some(base) = base else {
        return Err(format!("external file `{uri}` with no folder to look in"));
    };
    let path = base.join(percent_decode(relative)?);
    std::fs::read(&path).map_err(|e| format!("cannot read {}: {e}", path.display()))
}

/// Standard base64 (RFC 4648), padding optional, no whitespace.
fn decode_base64(text: &str) -> std::result::Result<Vec<u8>, String> {
    fn value(c: u8) -> Option<u32> {
        match c {
            b'A'..=b'Z' => Some((c - b'A') as u32),
            b'a'..=b'z' => Some((c - b'a') as u32 + 26),
            b'0'..=b'9' => Some((c - b'0') as u32 + 52),
            b'+' => Some(62),
            b'/' => Some(63),
            _ => None,
        }
    }
    let bytes = text.trim_end_matches('=').as_bytes();
    if bytes.len() % 4 == 1 {
        return Err("base64 data of impossible length".into());
    }
    let mut out = Vec::with_capacity(bytes.len() * 3 / 4);
    for chunk in bytes.chunks(4) {
        let mut acc = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            let v = value(c).ok_or_else(|| format!("invalid base64 character {:?}", c as char))?;
            acc |= v << (18 - 6 * k);
        }
        let n = chunk.len() * 6 / 8; // 2 -> 1 byte, 3 -> 2, 4 -> 3
        out.extend_from_slice(&acc.to_be_bytes()[1..1 + n]);
    }
    Ok(out)
}

/// `%XX` escapes of a relative URI reference, decoded as UTF-8.
fn percent_decode(text: &str) -> std::result::Result<String, String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = bytes
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("malformed %-escape in `{text}`"))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| format!("`{text}` is not UTF-8 once %-decoded"))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_known_vectors() {
        // RFC 4648 §10 test vectors.
        for (plain, enc) in [
            ("", ""),
            ("f", "Zg=="),
            ("fo", "Zm8="),
            ("foo", "Zm9v"),
            ("foob", "Zm9vYg=="),
            ("fooba", "Zm9vYmE="),
            ("foobar", "Zm9vYmFy"),
        ] {
            assert_eq!(decode_base64(enc).unwrap(), plain.as_bytes(), "{enc}");
        }
        let all: Vec<u8> = (0..=255).collect();
        let enc = "AAECAwQFBgcICQoLDA0ODxAREhMUFRYXGBkaGxwdHh8gISIjJCUmJygpKissLS4vMDEyMzQ1Njc4OTo7PD0+P0BBQkNERUZHSElKS0xNTk9QUVJTVFVWV1hZWltcXV5fYGFiY2RlZmdoaWprbG1ub3BxcnN0dXZ3eHl6e3x9fn+AgYKDhIWGh4iJiouMjY6PkJGSk5SVlpeYmZqbnJ2en6ChoqOkpaanqKmqq6ytrq+wsbKztLW2t7i5uru8vb6/wMHCw8TFxsfIycrLzM3Oz9DR0tPU1dbX2Nna29zd3t/g4eLj5OXm5+jp6uvs7e7v8PHy8/T19vf4+fr7/P3+/w==";
        assert_eq!(decode_base64(enc).unwrap(), all);
    }

    #[test]
    fn bad_base64_and_escapes_are_errors() {
        assert!(decode_base64("Zm9v!").is_err());
        assert!(decode_base64("Z").is_err());
        assert!(percent_decode("a%2").is_err());
        assert!(percent_decode("a%zz").is_err());
        assert!(percent_decode("%ff").is_err());
        assert_eq!(percent_decode("my%20scene.bin").unwrap(), "my scene.bin");
    }

    #[test]
    fn uris_without_a_folder_or_with_other_schemes_are_errors() {
        assert!(read_uri("scene.bin", None).is_err());
        assert!(read_uri("https://example.com/scene.bin", Some(Path::new("."))).is_err());
        assert!(read_uri("data:application/octet-stream,abc", None).is_err());
        assert_eq!(
            read_uri("data:application/octet-stream;base64,Zm9v", None).unwrap(),
            b"foo"
        );
    }
}
