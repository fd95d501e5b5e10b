//! Byte ranges of a glTF document against its loaded buffers.
//!
//! Every count read from the file must be backed by the bytes that hold it:
//! buffer views lie inside their buffer, accessors inside their view (with
//! their stride), sparse indices and values inside theirs, and sparse indices
//! are strictly increasing and below the accessor's count. After this, the
//! gltf crate's readers never slice out of range nor allocate more than the
//! file holds.

use super::gltf_checks::{component_size, label, multiplicity};
use crate::error::{Error, Result};
use gltf::json::accessor::ComponentType;
use gltf::json::validation::Checked;
use gltf::json::Root;

fn bad(msg: String) -> Error {
    Error::InvalidScene(msg)
}

/// `a + b` and `a * b` that name what overflowed instead of wrapping.
fn add(a: u64, b: u64, what: &str) -> Result<u64> {
    a.checked_add(b)
        .ok_or_else(|| bad(format!("{what}: byte range overflows")))
}
fn mul(a: u64, b: u64, what: &str) -> Result<u64> {
    a.checked_mul(b)
        .ok_or_else(|| bad(format!("{what}: byte range overflows")))
}

/// Checks views, accessors and sparse data against `buffers` (already loaded,
/// each at least as long as its declared `byteLength`).
pub(super) fn check_data(root: &Root, buffers: &[Vec<u8>]) -> Result<()> {
    let mut views = Vec::with_capacity(root.buffer_views.len());
    for (i, v) in root.buffer_views.iter().enumerate() {
        let name = label("bufferView", i, v.name.as_deref());
        let b = v.buffer.value();
        let offset = v.byte_offset.map_or(0, |o| o.0);
        let end = add(offset, v.byte_length.0, &name)?;
        let have = buffers.get(b).map_or(0, |d| d.len() as u64);
        if end > have {
            return Err(bad(format!(
                "{name} ends at byte {end}, past the end of buffer {b} ({have} bytes)"
            )));
        }
        views.push((offset, v.byte_length.0, v.byte_stride.map(|s| s.0 as u64)));
    }
    for (i, a) in root.accessors.iter().enumerate() {
        let name = label("accessor", i, a.name.as_deref());
        let (Checked::Valid(ct), Checked::Valid(ty)) = (a.component_type, a.type_) else {
            return Err(bad(format!("{name} has an unknown componentType or type")));
        };
        let elem = component_size(ct.0) * multiplicity(ty);
        let count = a.count.0;
        // glTF 2.0 requires count >= 1; the gltf crate's reader computes
        // `count - 1` and overflows on 0 (found by the fuzzer).
        if count == 0 {
            return Err(bad(format!("{name} has count 0 (glTF 2.0: at least 1)")));
        }
        if let Some(v) = a.buffer_view {
            let (_, len, stride) = views[v.value()];
            let stride = stride.unwrap_or(elem);
            if stride < elem {
                return Err(bad(format!(
                    "{name} has {elem}-byte elements but its view's byteStride is {stride}"
                )));
            }
            let offset = a.byte_offset.map_or(0, |o| o.0);
            let end = add(
                add(offset, mul(stride, count - 1, &name)?, &name)?,
                elem,
                &name,
            )?;
            if end > len {
                return Err(bad(format!(
                    "{name}: {count} elements need {end} bytes, its bufferView has {len}"
                )));
            }
        }
        if let Some(s) = &a.sparse {
            let n = s.count.0;
            let Checked::Valid(ict) = s.indices.component_type else {
                return Err(bad(format!("{name} has sparse indices of an unknown type")));
            };
            let isize = component_size(ict.0);
            let (ioff, ilen, _) = views[s.indices.buffer_view.value()];
            let istart = add(ioff, s.indices.byte_offset.0, &name)?;
            let iend = add(istart, mul(n, isize, &name)?, &name)?;
            if iend > add(ioff, ilen, &name)? {
                return Err(bad(format!(
                    "{name}: its {n} sparse indices run past their bufferView"
                )));
            }
            let (voff, vlen, _) = views[s.values.buffer_view.value()];
            let vend = add(
                add(voff, s.values.byte_offset.0, &name)?,
                mul(n, elem, &name)?,
                &name,
            )?;
            if vend > add(voff, vlen, &name)? {
                return Err(bad(format!(
                    "{name}: its {n} sparse values run past their bufferView"
                )));
            }
            let buffer = &buffers[root.buffer_views[s.indices.buffer_view.value()]
                .buffer
                .value()];
            check_sparse_indices(&name, &buffer[istart as usize..iend as usize], ict.0, count)?;
        }
    }
    Ok(())
}

/// Sparse indices must be strictly increasing and below the accessor's count.
fn check_sparse_indices(name: &str, bytes: &[u8], ct: ComponentType, count: u64) -> Result<()> {
    let size = component_size(ct) as usize;
    let mut prev: Option<u64> = None;
    for chunk in bytes.chunks_exact(size) {
        let i = match size {
            1 => chunk[0] as u64,
            2 => u16::from_le_bytes([chunk[0], chunk[1]]) as u64,
            _ => u32::from_le_bytes([chunk[0], chunk[1], chunk[2], chunk[3]]) as u64,
        };
        if i >= count || prev.is_some_and(|p| i <= p) {
            return Err(bad(format!(
                "{name}: its sparse indices are not strictly increasing below its count {count}"
            )));
        }
        prev = Some(i);
    }
    Ok(())
}
