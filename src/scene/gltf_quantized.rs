//! Vertex attributes read as `f32` vectors, whatever their storage: `FLOAT`,
//! or the integers `KHR_mesh_quantization` allows (glTF 2.0 itself allows
//! normalized `UNSIGNED_BYTE` and `UNSIGNED_SHORT` texture coordinates).
//!
//! - A normalized integer `c` is dequantized as the extension says:
//!   `max(c / 127, -1)` (`BYTE`), `c / 255` (`UNSIGNED_BYTE`),
//!   `max(c / 32767, -1)` (`SHORT`), `c / 65535` (`UNSIGNED_SHORT`).
//! - A non-normalized integer is its value: the dequantization scale and
//!   offset are in the node's transform, as gltfpack writes them.
//! - Which storage each attribute may use ([`check_attribute`]: POSITION,
//!   NORMAL, TANGENT, TEXCOORD_n) is checked with the document, before any
//!   byte is read: the extension's types only when the file declares it, and
//!   elements aligned to 4 bytes (a `BYTE` VEC3 needs a `byteStride` of 4).
//!
//! The gltf crate's readers read `FLOAT` positions and normals only, and its
//! texture coordinate reader reaches `unreachable!()` on `BYTE` or `SHORT`
//! and always normalizes; [`read_f32_vectors`] replaces them. It checks every
//! range again, so it never panics whatever `gltf_data` let through.

use super::gltf_checks::{component_size, label, multiplicity};
use crate::error::{Error, Result};
use gltf::json::accessor::{ComponentType, Type};
use gltf::json::mesh::Semantic;
use gltf::json::validation::Checked;
use gltf::json::{self, Root};

/// The extension's name, as `extensionsUsed` and `extensionsRequired` list it.
pub(super) const KHR_MESH_QUANTIZATION: &str = "KHR_mesh_quantization";

/// Reads every element of `accessor` as `N` floats, dequantized, with its
/// sparse substitutions; an accessor without a `bufferView` starts as zeros.
/// `buffers` are the scene's loaded buffers, indexed as the file's.
///
/// # Errors
/// [`Error::InvalidScene`] naming the accessor when it is not a SCALAR,
/// VECn or (`N` = 16) MAT4 of `N` components, when it stores `UNSIGNED_INT` or normalized
/// `FLOAT` (no vertex attribute does), or when an element, a sparse index or
/// a sparse value lies outside its buffer view; [`Error::OutOfMemory`] when
/// the floats cannot be allocated.
pub(super) fn read_f32_vectors<const N: usize>(
    accessor: &gltf::Accessor<'_>,
    buffers: &[Vec<u8>],
) -> Result<Vec<[f32; N]>> {
    let name = label("accessor", accessor.index(), accessor.name());
    let bad = |why: &str| Error::InvalidScene(format!("{name} {why}"));
    let storage = Storage::of(accessor, N).map_err(|why| bad(&why))?;
    let count = accessor.count();
    let mut out = Vec::new();
    out.try_reserve_exact(count)
        .map_err(|_| Error::OutOfMemory {
            what: "a vertex attribute",
            bytes: (count as u64).saturating_mul(4 * N as u64),
            budget_bytes: super::MAX_BUFFER_BYTES,
        })?;
    match accessor.view() {
        Some(view) => {
            let bytes = view_bytes(&view, buffers).ok_or_else(|| bad("lies past its buffer"))?;
            let stride = view.stride().unwrap_or(storage.element_size(N));
            for i in 0..count {
                let start = i
                    .checked_mul(stride)
                    .and_then(|s| s.checked_add(accessor.offset()));
                let element = start.and_then(|s| storage.element(bytes.get(s..)?));
                out.push(
                    element.ok_or_else(|| bad(&format!("element {i} lies past its bufferView")))?,
                );
            }
        }
        None => out.resize(count, [0.0; N]),
    }
    if let Some(sparse) = accessor.sparse() {
        substitute_sparse(&mut out, &sparse, storage, buffers).map_err(|why| bad(&why))?;
    }
    Ok(out)
}

/// The bytes of `view` in its buffer.
fn view_bytes<'b>(view: &gltf::buffer::View<'_>, buffers: &'b [Vec<u8>]) -> Option<&'b [u8]> {
    let end = view.offset().checked_add(view.length())?;
    buffers.get(view.buffer().index())?.get(view.offset()..end)
}

/// Writes a sparse accessor's values over `out`, at its indices. Sparse
/// indices and values are tightly packed (the glTF 2.0 schema says so), as
/// `gltf_data` checked them.
fn substitute_sparse<const N: usize>(
    out: &mut [[f32; N]],
    sparse: &gltf::accessor::sparse::Sparse<'_>,
    storage: Storage,
    buffers: &[Vec<u8>],
) -> std::result::Result<(), String> {
    use gltf::accessor::sparse::IndexType;
    let (indices, values) = (sparse.indices(), sparse.values());
    let past = || "has sparse data past its bufferView".to_string();
    let index_bytes = view_bytes(&indices.view(), buffers)
        .and_then(|b| b.get(indices.offset()..))
        .ok_or_else(past)?;
    let value_bytes = view_bytes(&values.view(), buffers)
        .and_then(|b| b.get(values.offset()..))
        .ok_or_else(past)?;
    let index_size = match indices.index_type() {
        IndexType::U8 => 1,
        IndexType::U16 => 2,
        IndexType::U32 => 4,
    };
    let element_size = storage.element_size(N);
    for k in 0..sparse.count() {
        let index = index_bytes
            .get(k * index_size..(k + 1) * index_size)
            .map(little_endian_index)
            .ok_or_else(past)?;
        let value = value_bytes
            .get(k * element_size..)
            .and_then(|b| storage.element(b))
            .ok_or_else(past)?;
        let slot = usize::try_from(index).ok().and_then(|i| out.get_mut(i));
        *slot.ok_or_else(|| format!("has sparse index {index}, past its count"))? = value;
    }
    Ok(())
}

/// An unsigned index of 1, 2 or 4 little-endian bytes.
fn little_endian_index(bytes: &[u8]) -> u64 {
    bytes
        .iter()
        .rev()
        .fold(0u64, |acc, &b| (acc << 8) | u64::from(b))
}

/// How one component is stored: its type and whether it is normalized.
#[derive(Clone, Copy, Debug)]
struct Storage {
    component: ComponentType,
    normalized: bool,
}

impl Storage {
    /// The storage of `accessor`, if it holds vectors of `n` components that
    /// an attribute may store (or 4x4 matrices, 16 components whose columns
    /// need no padding); `Err` says why not.
    fn of(accessor: &gltf::Accessor<'_>, n: usize) -> std::result::Result<Self, String> {
        let dimensions = accessor.dimensions();
        let vector = matches!(
            dimensions,
            Type::Scalar | Type::Vec2 | Type::Vec3 | Type::Vec4 | Type::Mat4
        );
        if !vector || multiplicity(dimensions) != n as u64 {
            return Err(format!("is {dimensions:?}, not a vector of {n} components"));
        }
        let storage = Storage {
            component: accessor.data_type(),
            normalized: accessor.normalized(),
        };
        match (storage.component, storage.normalized) {
            (ComponentType::U32, _) | (ComponentType::F32, true) => Err(format!(
                "stores {}, which no vertex attribute may",
                storage.describe()
            )),
            _ => Ok(storage),
        }
    }

    fn element_size(self, n: usize) -> usize {
        component_size(self.component) as usize * n
    }

    /// The first element of `bytes`, dequantized; `None` when `bytes` is short.
    fn element<const N: usize>(self, bytes: &[u8]) -> Option<[f32; N]> {
        let size = component_size(self.component) as usize;
        let mut out = [0.0; N];
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.component_value(bytes.get(k * size..(k + 1) * size)?)?;
        }
        Some(out)
    }

    /// One component from exactly its bytes.
    fn component_value(self, b: &[u8]) -> Option<f32> {
        use ComponentType::*;
        let (value, scale, signed) = match self.component {
            F32 => return Some(f32::from_le_bytes(b.try_into().ok()?)),
            I8 => (
                f32::from(i8::from_le_bytes(b.try_into().ok()?)),
                127.0,
                true,
            ),
            U8 => (
                f32::from(u8::from_le_bytes(b.try_into().ok()?)),
                255.0,
                false,
            ),
            I16 => (
                f32::from(i16::from_le_bytes(b.try_into().ok()?)),
                32767.0,
                true,
            ),
            U16 => (
                f32::from(u16::from_le_bytes(b.try_into().ok()?)),
                65535.0,
                false,
            ),
            U32 => return None,
        };
        Some(match (self.normalized, signed) {
            (false, _) => value,
            // The most negative integer (-128, -32768) is -1, like the one above it.
            (true, true) => (value / scale).max(-1.0),
            (true, false) => value / scale,
        })
    }

    /// `normalized SHORT`, `FLOAT`: the storage as the specification names it.
    fn describe(self) -> String {
        let name = match self.component {
            ComponentType::I8 => "BYTE",
            ComponentType::U8 => "UNSIGNED_BYTE",
            ComponentType::I16 => "SHORT",
            ComponentType::U16 => "UNSIGNED_SHORT",
            ComponentType::U32 => "UNSIGNED_INT",
            ComponentType::F32 => "FLOAT",
        };
        if self.normalized {
            format!("normalized {name}")
        } else {
            name.to_string()
        }
    }
}

/// Whether glTF 2.0 allows a storage for an attribute by itself, or only
/// with `KHR_mesh_quantization`.
#[derive(Clone, Copy, PartialEq, Debug)]
enum Allowed {
    Core,
    WithQuantization,
    Never,
}

/// What an attribute this module reads must be: its accessor type, which
/// storage it may have, and that rule in words for messages.
struct Rule {
    accessor_type: Type,
    allowed: fn(Storage) -> Allowed,
    in_words: &'static str,
}

/// The rule of `semantic` (the extension's table); `None` for attributes
/// this module does not read.
fn rule_of(semantic: &Semantic) -> Option<Rule> {
    const ANY_INTEGER: &str = "FLOAT (not normalized), or with KHR_mesh_quantization BYTE, \
        UNSIGNED_BYTE, SHORT or UNSIGNED_SHORT (normalized or not)";
    const UNIT: &str =
        "FLOAT (not normalized), or with KHR_mesh_quantization normalized BYTE or SHORT";
    let (accessor_type, allowed, in_words): (_, fn(Storage) -> Allowed, _) = match semantic {
        Semantic::Positions => (Type::Vec3, position_or_texcoord, ANY_INTEGER),
        Semantic::TexCoords(_) => (Type::Vec2, position_or_texcoord, ANY_INTEGER),
        Semantic::Normals => (Type::Vec3, unit_vector, UNIT),
        Semantic::Tangents => (Type::Vec4, unit_vector, UNIT),
        _ => return None,
    };
    Some(Rule {
        accessor_type,
        allowed,
        in_words,
    })
}

fn position_or_texcoord(s: Storage) -> Allowed {
    use ComponentType::*;
    match (s.component, s.normalized) {
        (F32, false) | (U8 | U16, true) => Allowed::Core,
        (I8 | U8 | I16 | U16, _) => Allowed::WithQuantization,
        _ => Allowed::Never,
    }
}

fn unit_vector(s: Storage) -> Allowed {
    use ComponentType::*;
    match (s.component, s.normalized) {
        (F32, false) => Allowed::Core,
        (I8 | I16, true) => Allowed::WithQuantization,
        _ => Allowed::Never,
    }
}

/// Checks accessor `index`, the attribute `semantic` of a primitive, against
/// the table of glTF 2.0 and `KHR_mesh_quantization`: its type, its
/// storage, the extension declared when its storage needs it, and elements
/// aligned to 4 bytes. `Err` names the attribute and the accessor and says
/// what is wrong. Attributes not in the table (COLOR_n, JOINTS_n, ...) pass.
pub(super) fn check_attribute(
    root: &Root,
    semantic: &Semantic,
    index: usize,
) -> std::result::Result<(), String> {
    let Some(rule) = rule_of(semantic) else {
        return Ok(());
    };
    let attribute = semantic.to_string();
    let Some(acc) = root.accessors.get(index) else {
        return Err(format!("its {attribute} accessor {index} does not exist"));
    };
    let name = format!(
        "its {attribute} {}",
        label("accessor", index, acc.name.as_deref())
    );
    let (Checked::Valid(ct), Checked::Valid(ty)) = (acc.component_type, acc.type_) else {
        return Err(format!("{name} has an unknown componentType or type"));
    };
    if ty != rule.accessor_type {
        return Err(format!("{name} is {ty:?}, not {:?}", rule.accessor_type));
    }
    let storage = Storage {
        component: ct.0,
        normalized: acc.normalized,
    };
    match (rule.allowed)(storage) {
        Allowed::Never => Err(format!(
            "{name} stores {}; {attribute} may be {}",
            storage.describe(),
            rule.in_words
        )),
        Allowed::WithQuantization if !declares_quantization(root) => Err(format!(
            "{name} stores {}, which needs the extension {KHR_MESH_QUANTIZATION} \
             (the file lists it in neither extensionsUsed nor extensionsRequired)",
            storage.describe()
        )),
        _ => check_alignment(root, acc, &name),
    }
}

/// glTF 2.0 §3.6.2.4: a vertex attribute's elements start on 4-byte
/// boundaries. Without a `byteStride` they are packed, so 3-byte elements
/// (a `BYTE` VEC3) would not be: the writer most likely meant a stride of 4,
/// and reading them packed would scramble the mesh.
fn check_alignment(
    root: &Root,
    acc: &json::Accessor,
    name: &str,
) -> std::result::Result<(), String> {
    let Some(view) = acc
        .buffer_view
        .and_then(|v| root.buffer_views.get(v.value()))
    else {
        return Ok(());
    };
    let (Checked::Valid(ct), Checked::Valid(ty)) = (acc.component_type, acc.type_) else {
        return Ok(());
    };
    let element = component_size(ct.0) * multiplicity(ty);
    if view.byte_stride.is_none() && element % 4 != 0 {
        return Err(format!(
            "{name} has {element}-byte elements and its bufferView no byteStride: \
             vertex attributes must be aligned to 4 bytes (a byteStride of {})",
            element.next_multiple_of(4)
        ));
    }
    Ok(())
}

fn declares_quantization(root: &Root) -> bool {
    root.extensions_used
        .iter()
        .chain(&root.extensions_required)
        .any(|e| e == KHR_MESH_QUANTIZATION)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The accessor 0 of a document of one buffer, `buffers`' first.
    fn read<const N: usize>(
        accessor: serde_json::Value,
        views: serde_json::Value,
        bin: &[u8],
    ) -> Result<Vec<[f32; N]>> {
        let doc = serde_json::json!({
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": bin.len()}],
            "bufferViews": views,
            "accessors": [accessor],
        });
        let gltf = gltf::Gltf::from_slice_without_validation(doc.to_string().as_bytes()).unwrap();
        let accessor = gltf.document.accessors().next().unwrap();
        read_f32_vectors::<N>(&accessor, &[bin.to_vec()])
    }

    fn storage(component: ComponentType, normalized: bool) -> Storage {
        Storage {
            component,
            normalized,
        }
    }

    #[test]
    fn normalized_integers_dequantize_as_the_extension_says() {
        use ComponentType::*;
        let value = |s: Storage, b: &[u8]| s.component_value(b).unwrap();
        assert_eq!(value(storage(I8, true), &[127]), 1.0);
        assert_eq!(value(storage(I8, true), &[(-127i8) as u8]), -1.0);
        assert_eq!(value(storage(I8, true), &[(-128i8) as u8]), -1.0);
        assert_eq!(value(storage(I8, true), &[64]), 64.0 / 127.0);
        assert_eq!(value(storage(U8, true), &[255]), 1.0);
        assert_eq!(value(storage(U8, true), &[51]), 0.2);
        assert_eq!(value(storage(I16, true), &(-32768i16).to_le_bytes()), -1.0);
        assert_eq!(value(storage(I16, true), &32767i16.to_le_bytes()), 1.0);
        assert_eq!(value(storage(U16, true), &65535u16.to_le_bytes()), 1.0);
        // Not normalized: the integer itself.
        assert_eq!(value(storage(I8, false), &[(-128i8) as u8]), -128.0);
        assert_eq!(value(storage(U16, false), &65535u16.to_le_bytes()), 65535.0);
        assert_eq!(value(storage(F32, false), &1.5f32.to_le_bytes()), 1.5);
        // Only exactly one component's bytes are read.
        assert_eq!(storage(I16, false).component_value(&[1]), None);
    }

    #[test]
    fn strided_bytes_and_sparse_values_are_read() {
        // Two BYTE VEC3 in a stride of 4 (the fourth byte is padding), then
        // a sparse value for element 1 right after them.
        let bin = [1, 2, 3, 99, (-128i8) as u8, 127, 0, 99, 1, 7, 8, 9];
        let views = serde_json::json!([
            {"buffer": 0, "byteLength": 8, "byteStride": 4},
            {"buffer": 0, "byteOffset": 8, "byteLength": 4},
        ]);
        let plain = serde_json::json!({"bufferView": 0, "componentType": 5120, "normalized": true, "count": 2, "type": "VEC3"});
        let v = read::<3>(plain.clone(), views.clone(), &bin).unwrap();
        assert_eq!(v[0], [1.0 / 127.0, 2.0 / 127.0, 3.0 / 127.0]);
        assert_eq!(v[1], [-1.0, 1.0, 0.0]);
        let mut sparse = plain;
        sparse["sparse"] = serde_json::json!({"count": 1,
            "indices": {"bufferView": 1, "componentType": 5121},
            "values": {"bufferView": 1, "byteOffset": 1}});
        let v = read::<3>(sparse, views, &bin).unwrap();
        assert_eq!(v[1], [7.0 / 127.0, 8.0 / 127.0, 9.0 / 127.0]);
    }

    #[test]
    fn what_the_data_check_would_refuse_is_an_error_here_too() {
        let views = serde_json::json!([{"buffer": 0, "byteLength": 4, "byteStride": 4}]);
        let too_many = serde_json::json!({"bufferView": 0, "componentType": 5122, "count": 2, "type": "VEC2", "name": "uv"});
        let e = read::<2>(too_many, views.clone(), &[0; 4])
            .unwrap_err()
            .to_string();
        assert!(e.contains("accessor 0 (`uv`) element 1 lies past"), "{e}");
        let wide = serde_json::json!({"bufferView": 0, "componentType": 5125, "count": 1, "type": "SCALAR"});
        let e = read::<1>(wide, views.clone(), &[0; 4])
            .unwrap_err()
            .to_string();
        assert!(e.contains("UNSIGNED_INT"), "{e}");
        let vec2 =
            serde_json::json!({"bufferView": 0, "componentType": 5122, "count": 1, "type": "VEC2"});
        let e = read::<3>(vec2, views, &[0; 4]).unwrap_err().to_string();
        assert!(e.contains("is Vec2, not a vector of 3"), "{e}");
    }
}
