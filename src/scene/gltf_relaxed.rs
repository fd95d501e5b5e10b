//! Valid glTF that the gltf crate's schema refuses, rewritten so that it
//! reads. The crate deserializes the JSON into fixed Rust types, stricter
//! than the glTF schema in three places that real files reach:
//!
//! - an integer written as a float (`"buffer": 1.0`, `"count": 3e0`): JSON
//!   has one number type, and the Khronos validator accepts it;
//! - an animation channel's `target` without a `node` (with
//!   `KHR_animation_pointer`), and any other animation: animations are
//!   not read here, so they are dropped unread;
//! - a scene without `nodes` (an empty scene);
//!
//! and a UTF-8 byte order mark before the JSON, which the glTF
//! specification asks writers to leave out but JSON readers commonly skip.
//!
//! The rewrite runs only after the file failed to parse as it is; a file
//! it cannot mend keeps the crate's first error.

use serde_json::{Number, Value};

const BOM: &[u8] = b"\xEF\xBB\xBF";

/// `bytes` (a `.gltf` or a GLB checked by the loader's header check)
/// rewritten as described in the module docs; `None` when its JSON does
/// not parse even as plain JSON, or the result would not fit a GLB.
pub(super) fn relaxed(bytes: &[u8]) -> Option<Vec<u8>> {
    match glb_json(bytes) {
        Some((json, rest)) => {
            let json = relaxed_json(json)?;
            glb_with_json(&json, rest)
        }
        None => relaxed_json(bytes),
    }
}

/// A GLB's JSON chunk and the bytes after it; `None` for a `.gltf`.
fn glb_json(bytes: &[u8]) -> Option<(&[u8], &[u8])> {
    if !bytes.starts_with(b"glTF") {
        return None;
    }
    let len = u32::from_le_bytes(bytes.get(12..16)?.try_into().ok()?) as usize;
    let end = 20usize.checked_add(len)?;
    Some((bytes.get(20..end)?, bytes.get(end..)?))
}

/// A GLB of version 2 holding `json` (padded with spaces, as the format
/// asks) and then the original chunks `rest`.
fn glb_with_json(json: &[u8], rest: &[u8]) -> Option<Vec<u8>> {
    let padded = json.len().div_ceil(4) * 4;
    let total = u32::try_from(12 + 8 + padded + rest.len()).ok()?;
    let mut out = Vec::with_capacity(total as usize);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total.to_le_bytes());
    out.extend_from_slice(&(padded as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(json);
    out.resize(20 + padded, b' ');
    out.extend_from_slice(rest);
    Some(out)
}

fn relaxed_json(json: &[u8]) -> Option<Vec<u8>> {
    let json = json.strip_prefix(BOM).unwrap_or(json);
    let mut root: Value = serde_json::from_slice(json).ok()?;
    let object = root.as_object_mut()?;
    object.remove("animations");
    if let Some(Value::Array(scenes)) = object.get_mut("scenes") {
        for scene in scenes.iter_mut().filter_map(Value::as_object_mut) {
            scene
                .entry("nodes")
                .or_insert_with(|| Value::Array(Vec::new()));
        }
    }
    integers_as_integers(&mut root);
    serde_json::to_vec(&root).ok()
}

/// Every float with an integral value that an f64 holds exactly (below
/// 2^53 in magnitude) becomes an integer: the crate's integer fields take
/// it, and its float fields take integers.
fn integers_as_integers(v: &mut Value) {
    const EXACT: f64 = 9_007_199_254_740_992.0;
    match v {
        Value::Number(n) if !n.is_i64() && !n.is_u64() => {
            if let Some(f) = n.as_f64().filter(|f| f.fract() == 0.0 && f.abs() < EXACT) {
                *n = Number::from(f as i64);
            }
        }
        Value::Array(items) => items.iter_mut().for_each(integers_as_integers),
        Value::Object(map) => map.values_mut().for_each(integers_as_integers),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(bytes: &[u8]) -> Value {
        serde_json::from_slice(bytes).unwrap()
    }

    #[test]
    fn integral_floats_become_integers_and_others_stay() {
        let out = relaxed(br#"{"a": 1.0, "b": [3e0, 0.5, -2.0], "c": {"d": 1e300}}"#).unwrap();
        let v = parse(&out);
        assert!(v["a"].is_u64() && v["b"][0].is_u64() && v["b"][2].is_i64());
        assert_eq!(v["b"][1].as_f64(), Some(0.5));
        assert!(v["c"]["d"].is_f64(), "too large to be exact: left a float");
    }

    #[test]
    fn animations_go_scenes_get_nodes_and_a_bom_is_skipped() {
        let mut text = BOM.to_vec();
        text.extend_from_slice(br#"{"animations": [{}], "scenes": [{}, {"nodes": [0]}]}"#);
        let v = parse(&relaxed(&text).unwrap());
        assert!(v.get("animations").is_none());
        assert_eq!(v["scenes"][0]["nodes"], Value::Array(vec![]));
        assert_eq!(v["scenes"][1]["nodes"][0], 0);
        assert!(relaxed(b"{not json").is_none());
    }

    #[test]
    fn a_glb_keeps_its_other_chunks_and_a_consistent_header() {
        let json = br#"{"n": 2.0}"#;
        let bin = [8u8, 0, 0, 0, b'B', b'I', b'N', 0, 1, 2, 3, 4, 5, 6, 7, 8];
        let mut glb = b"glTF".to_vec();
        glb.extend_from_slice(&2u32.to_le_bytes());
        let total = 12 + 8 + 12 + bin.len();
        glb.extend_from_slice(&(total as u32).to_le_bytes());
        glb.extend_from_slice(&12u32.to_le_bytes());
        glb.extend_from_slice(b"JSON");
        glb.extend_from_slice(json);
        glb.extend_from_slice(b"  ");
        glb.extend_from_slice(&bin);
        let out = relaxed(&glb).unwrap();
        let len = u32::from_le_bytes(out[8..12].try_into().unwrap()) as usize;
        assert_eq!(len, out.len());
        let (json, rest) = glb_json(&out).unwrap();
        assert_eq!(json.len() % 4, 0);
        assert!(parse(json)["n"].is_u64());
        assert_eq!(rest, bin);
    }
}
