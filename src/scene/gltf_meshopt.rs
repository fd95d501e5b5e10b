//! `EXT_meshopt_compression`: buffer views stored compressed (what
//! `gltfpack -c` writes), decoded into their place in the parent buffer
//! before any accessor reads them, so the rest of the loader sees plain
//! data. The three bitstreams (attributes, triangles, indices) and the
//! four filters are the extension's appendices; every read is
//! bounds-checked and a malformed stream is an error naming its view.
//!
//! The uncompressed bytes go to the view's own buffer, which a compressing
//! writer leaves without data (`"fallback": true`, or no URI after the GLB
//! chunk): [`super::buffers`] gives such a buffer zeros of its declared
//! length, under the same limit as every other buffer.

use crate::error::{Error, Result};
use gltf::json::Root;
use serde_json::{Map, Value};

/// The extension's name.
pub(super) const EXT_MESHOPT_COMPRESSION: &str = "EXT_meshopt_compression";

/// Whether buffer `i` is a fallback the extension fills: marked so, or
/// without data of its own in a file that uses the extension.
pub(super) fn is_fallback(root: &Root, i: usize) -> bool {
    let Some(b) = root.buffers.get(i) else {
        return false;
    };
    let marked = b
        .extensions
        .as_ref()
        .and_then(|e| e.others.get(EXT_MESHOPT_COMPRESSION))
        .and_then(|e| e.get("fallback"))
        .and_then(Value::as_bool)
        .unwrap_or(false);
    let used = root
        .extensions_used
        .iter()
        .any(|e| e == EXT_MESHOPT_COMPRESSION);
    marked || (used && b.uri.is_none())
}

/// How a view was compressed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Mode {
    Attributes,
    Triangles,
    Indices,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
}

/// A view's extension object.
#[derive(Clone, Copy, Debug)]
struct Compressed {
    buffer: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: Mode,
    filter: Filter,
}

/// Decodes every compressed view of `root` into `buffers`.
pub(super) fn decode_views(root: &Root, buffers: &mut [Vec<u8>]) -> Result<()> {
    for (i, view) in root.buffer_views.iter().enumerate() {
        let Some(ext) = view
            .extensions
            .as_ref()
            .and_then(|e| e.others.get(EXT_MESHOPT_COMPRESSION))
        else {
            continue;
        };
        let what = |why: String| {
            Error::InvalidScene(format!("bufferView {i} ({EXT_MESHOPT_COMPRESSION}): {why}"))
        };
        let c = parse(ext).map_err(what)?;
        let length = view.byte_length.0 as usize;
        if c.stride.checked_mul(c.count) != Some(length) {
            return Err(what(format!(
                "byteStride {} times count {} is not the view's byteLength {length}",
                c.stride, c.count
            )));
        }
        if view.byte_stride.is_some_and(|s| s.0 != c.stride) {
            return Err(what("its byteStride differs from the view's".into()));
        }
        let source = buffers
            .get(c.buffer)
            .and_then(|b| b.get(c.offset..c.offset.checked_add(c.length)?))
            .ok_or_else(|| what("its compressed bytes lie outside their buffer".into()))?;
        let decoded = decode(&c, source).map_err(what)?;
        let start = view.byte_offset.map_or(0, |o| o.0 as usize);
        let target = buffers
            .get_mut(view.buffer.value())
            .and_then(|b| b.get_mut(start..start.checked_add(length)?))
            .ok_or_else(|| what("the view lies outside its buffer".into()))?;
        target.copy_from_slice(&decoded);
    }
    Ok(())
}

fn parse(ext: &Value) -> std::result::Result<Compressed, String> {
    let obj: &Map<String, Value> = ext.as_object().ok_or("not an object")?;
    let int = |key: &str, default: Option<u64>| -> std::result::Result<usize, String> {
        match obj.get(key) {
            Some(v) => v
                .as_u64()
                .and_then(|v| usize::try_from(v).ok())
                .ok_or(format!("`{key}` is not a non-negative integer")),
            None => default
                .map(|d| d as usize)
                .ok_or(format!("`{key}` is missing")),
        }
    };
    let text = |key: &str| {
        obj.get(key)
            .map(|v| v.as_str().ok_or(format!("`{key}` is not a string")))
    };
    let mode = match text("mode").ok_or("`mode` is missing")?? {
        "ATTRIBUTES" => Mode::Attributes,
        "TRIANGLES" => Mode::Triangles,
        "INDICES" => Mode::Indices,
        m => return Err(format!("unknown mode `{m}`")),
    };
    let filter = match text("filter").transpose()?.unwrap_or("NONE") {
        "NONE" => Filter::None,
        "OCTAHEDRAL" => Filter::Octahedral,
        "QUATERNION" => Filter::Quaternion,
        "EXPONENTIAL" => Filter::Exponential,
        f => return Err(format!("unknown filter `{f}`")),
    };
    let c = Compressed {
        buffer: int("buffer", None)?,
        offset: int("byteOffset", Some(0))?,
        length: int("byteLength", None)?,
        stride: int("byteStride", None)?,
        count: int("count", None)?,
        mode,
        filter,
    };
    let s = c.stride;
    let valid = match (c.mode, c.filter) {
        (Mode::Attributes, f) => {
            s > 0
                && s % 4 == 0
                && s <= 256
                && match f {
                    Filter::None | Filter::Exponential => true,
                    Filter::Octahedral => s == 4 || s == 8,
                    Filter::Quaternion => s == 8,
                }
        }
        (Mode::Triangles, Filter::None) => (s == 2 || s == 4) && c.count % 3 == 0,
        (Mode::Indices, Filter::None) => s == 2 || s == 4,
        _ => false,
    };
    if !valid {
        return Err(format!(
            "mode {:?} with filter {:?} and byteStride {s} (count {}) is not allowed",
            c.mode, c.filter, c.count
        ));
    }
    Ok(c)
}

fn decode(c: &Compressed, src: &[u8]) -> std::result::Result<Vec<u8>, String> {
    match c.mode {
        Mode::Attributes => {
            let mut out = decode_attributes(src, c.count, c.stride)?;
            apply_filter(c.filter, c.stride, &mut out);
            Ok(out)
        }
        Mode::Triangles => write_indices(&decode_triangles(src, c.count)?, c.stride),
        Mode::Indices => write_indices(&decode_indices(src, c.count)?, c.stride),
    }
}

/// A reader that fails, not panics, past the end.
struct Bytes<'a> {
    data: &'a [u8],
    at: usize,
}

impl<'a> Bytes<'a> {
    fn take(&mut self, n: usize) -> std::result::Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.data.len());
        let end = end.ok_or("the stream ends early")?;
        let s = &self.data[self.at..end];
        self.at = end;
        Ok(s)
    }

    fn byte(&mut self) -> std::result::Result<u8, String> {
        Ok(self.take(1)?[0])
    }

    /// Unsigned LEB128, at most 32 bits.
    fn varint(&mut self) -> std::result::Result<u32, String> {
        let mut v = 0u32;
        for shift in (0..35).step_by(7) {
            let b = self.byte()?;
            v |= u32::from(b & 0x7f).checked_shl(shift).unwrap_or(0);
            if b & 0x80 == 0 {
                return Ok(v);
            }
        }
        Err("a varint runs past 32 bits".into())
    }

    fn finished(&self) -> std::result::Result<(), String> {
        match self.at == self.data.len() {
            true => Ok(()),
            false => Err(format!("{} bytes left over", self.data.len() - self.at)),
        }
    }
}

fn unzigzag8(v: u8) -> u8 {
    if v & 1 != 0 {
        !(v >> 1)
    } else {
        v >> 1
    }
}

fn unzigzag32(v: u32) -> i32 {
    if v & 1 != 0 {
        !((v >> 1) as i32)
    } else {
        (v >> 1) as i32
    }
}

/// Mode 0: per-byte deltas from the previous element, in blocks of at most
/// 256 elements, groups of 16; the baseline element is the stream's tail.
fn decode_attributes(
    src: &[u8],
    count: usize,
    stride: usize,
) -> std::result::Result<Vec<u8>, String> {
    const TAIL_MIN: usize = 32;
    match src.first() {
        Some(0xa0) => {}
        Some(h) => return Err(format!("attribute header {h:#04x}, not 0xa0")),
        None => return Err("an empty stream".into()),
    }
    let tail = stride.max(TAIL_MIN);
    if src.len() < 1 + tail {
        return Err("the stream is shorter than its tail".into());
    }
    let mut last = src[src.len() - stride..].to_vec();
    let mut data = Bytes {
        data: &src[1..src.len() - tail],
        at: 0,
    };
    let mut out = vec![0u8; count * stride];
    let max_block = ((8192 / stride) & !15).min(256);
    let mut deltas = [0u8; 256];
    let mut first = 0;
    while first < count {
        let block = (count - first).min(max_block);
        let groups = block.div_ceil(16);
        for k in 0..stride {
            let header = data.take(groups.div_ceil(4))?;
            for g in 0..groups {
                let bits = (header[g / 4] >> ((g % 4) * 2)) & 3;
                decode_group(bits, &mut data, &mut deltas[g * 16..g * 16 + 16])?;
            }
            for (i, &d) in deltas[..block].iter().enumerate() {
                let v = last[k].wrapping_add(unzigzag8(d));
                out[(first + i) * stride + k] = v;
                last[k] = v;
            }
        }
        first += block;
    }
    data.finished()?;
    Ok(out)
}

/// One group of 16 zigzagged deltas: zeros, 2- or 4-bit codes with a
/// sentinel for a full byte, or 16 bytes.
fn decode_group(bits: u8, data: &mut Bytes, out: &mut [u8]) -> std::result::Result<(), String> {
    match bits {
        0 => out.fill(0),
        3 => out.copy_from_slice(data.take(16)?),
        _ => {
            let width = if bits == 1 { 2 } else { 4 };
            let per_byte = 8 / width;
            let sentinel = (1u8 << width) - 1;
            let packed = data.take(16 / per_byte)?;
            let mut codes = [0u8; 16];
            for (i, c) in codes.iter_mut().enumerate() {
                // The first element sits in the byte's most significant bits.
                let shift = 8 - width * (1 + i % per_byte);
                *c = (packed[i / per_byte] >> shift) & sentinel;
            }
            for (o, c) in out.iter_mut().zip(codes) {
                *o = if c == sentinel { data.byte()? } else { c };
            }
        }
    }
    Ok(())
}

/// Mode 1: triangle lists by edge and vertex FIFOs.
fn decode_triangles(src: &[u8], count: usize) -> std::result::Result<Vec<u32>, String> {
    const TAIL: usize = 16;
    let triangles = count / 3;
    match src.first() {
        Some(0xe1) => {}
        Some(h) => return Err(format!("triangle header {h:#04x}, not 0xe1")),
        None => return Err("an empty stream".into()),
    }
    if src.len() < 1 + triangles + TAIL {
        return Err("the stream is shorter than its codes and tail".into());
    }
    let codes = &src[1..1 + triangles];
    let aux = &src[src.len() - TAIL..];
    let mut data = Bytes {
        data: &src[1 + triangles..src.len() - TAIL],
        at: 0,
    };
    let mut fifo = Fifos::default();
    let (mut next, mut last) = (0u32, 0u32);
    let index = |data: &mut Bytes, last: &mut u32| -> std::result::Result<u32, String> {
        *last = last.wrapping_add_signed(unzigzag32(data.varint()?));
        Ok(*last)
    };
    let mut out = Vec::with_capacity(count);
    for &code in codes {
        let (hi, lo) = (code >> 4, code & 15);
        let tri = if hi < 15 {
            let (a, b) = fifo.edge(hi);
            let c = match lo {
                0 => {
                    next += 1;
                    fifo.push_vertex(next - 1);
                    next - 1
                }
                1..=12 => fifo.vertex(lo),
                13 | 14 => {
                    last = if lo == 13 {
                        last.wrapping_sub(1)
                    } else {
                        last.wrapping_add(1)
                    };
                    fifo.push_vertex(last);
                    last
                }
                _ => {
                    let c = index(&mut data, &mut last)?;
                    fifo.push_vertex(c);
                    c
                }
            };
            fifo.push_edge(c, b);
            fifo.push_edge(a, c);
            [a, b, c]
        } else {
            let explicit = lo >= 14;
            let zw = if explicit {
                data.byte()?
            } else {
                aux[usize::from(lo)]
            };
            if explicit && zw == 0 {
                next = 0;
            }
            let (z, w) = (zw >> 4, zw & 15);
            let a = if lo == 15 {
                index(&mut data, &mut last)?
            } else {
                next += 1;
                next - 1
            };
            let mut other = |x: u8, data: &mut Bytes| -> std::result::Result<(u32, bool), String> {
                Ok(match x {
                    0 => {
                        next += 1;
                        (next - 1, true)
                    }
                    15 if explicit => (index(data, &mut last)?, true),
                    _ => (fifo.vertex(x - 1), false),
                })
            };
            let (b, push_b) = other(z, &mut data)?;
            let (c, push_c) = other(w, &mut data)?;
            fifo.push_vertex(a);
            if push_b {
                fifo.push_vertex(b);
            }
            if push_c {
                fifo.push_vertex(c);
            }
            fifo.push_edge(b, a);
            fifo.push_edge(c, b);
            fifo.push_edge(a, c);
            [a, b, c]
        };
        out.extend_from_slice(&tri);
    }
    data.finished()?;
    Ok(out)
}

/// The triangle codec's recent edges and vertices (index 0: the newest).
#[derive(Default)]
struct Fifos {
    edges: [(u32, u32); 16],
    edge_at: usize,
    vertices: [u32; 16],
    vertex_at: usize,
}

impl Fifos {
    fn edge(&self, i: u8) -> (u32, u32) {
        self.edges[(self.edge_at + 15 - usize::from(i)) & 15]
    }

    fn vertex(&self, i: u8) -> u32 {
        self.vertices[(self.vertex_at + 15 - usize::from(i)) & 15]
    }

    fn push_edge(&mut self, a: u32, b: u32) {
        self.edges[self.edge_at] = (a, b);
        self.edge_at = (self.edge_at + 1) & 15;
    }

    fn push_vertex(&mut self, v: u32) {
        self.vertices[self.vertex_at] = v;
        self.vertex_at = (self.vertex_at + 1) & 15;
    }
}

/// Mode 2: zigzagged deltas from one of two baselines.
fn decode_indices(src: &[u8], count: usize) -> std::result::Result<Vec<u32>, String> {
    const TAIL: usize = 4;
    match src.first() {
        Some(0xd1) => {}
        Some(h) => return Err(format!("index header {h:#04x}, not 0xd1")),
        None => return Err("an empty stream".into()),
    }
    if src.len() < 1 + TAIL {
        return Err("the stream is shorter than its tail".into());
    }
    let mut data = Bytes {
        data: &src[1..src.len() - TAIL],
        at: 0,
    };
    let mut last = [0u32; 2];
    let mut out = Vec::with_capacity(count.min(src.len()));
    for _ in 0..count {
        let v = data.varint()?;
        let base = (v & 1) as usize;
        last[base] = last[base].wrapping_add_signed(unzigzag32(v >> 1));
        out.push(last[base]);
    }
    data.finished()?;
    Ok(out)
}

fn write_indices(indices: &[u32], stride: usize) -> std::result::Result<Vec<u8>, String> {
    let mut out = Vec::with_capacity(indices.len() * stride);
    for &i in indices {
        if stride == 2 {
            let i = u16::try_from(i).map_err(|_| format!("index {i} does not fit 16 bits"))?;
            out.extend_from_slice(&i.to_le_bytes());
        } else {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    Ok(out)
}

fn apply_filter(filter: Filter, stride: usize, data: &mut [u8]) {
    match filter {
        Filter::None => {}
        Filter::Octahedral if stride == 4 => data.chunks_exact_mut(4).for_each(|e| {
            let v = [0, 1, 2].map(|k| f32::from(e[k] as i8));
            let n = octahedral(v, 127.0);
            e[..3].copy_from_slice(&n.map(|x| x as i8 as u8));
        }),
        Filter::Octahedral => data.chunks_exact_mut(8).for_each(|e| {
            let v = [0, 1, 2].map(|k| f32::from(i16::from_le_bytes([e[2 * k], e[2 * k + 1]])));
            let n = octahedral(v, 32767.0);
            for (k, x) in n.into_iter().enumerate() {
                e[2 * k..2 * k + 2].copy_from_slice(&(x as i16).to_le_bytes());
            }
        }),
        Filter::Quaternion => data.chunks_exact_mut(8).for_each(|e| {
            let c = |k: usize| i16::from_le_bytes([e[2 * k], e[2 * k + 1]]);
            let one = f32::from(c(3) | 3);
            let range = std::f32::consts::FRAC_1_SQRT_2;
            let [x, y, z] = [0, 1, 2].map(|k| f32::from(c(k)) / one * range);
            let w = (1.0 - x * x - y * y - z * z).max(0.0).sqrt();
            let max = (c(3) & 3) as usize;
            let mut q = [0i16; 4];
            for (k, v) in [(1, x), (2, y), (3, z), (0, w)] {
                q[(max + k) % 4] = (v * 32767.0).round() as i16;
            }
            for (k, v) in q.into_iter().enumerate() {
                e[2 * k..2 * k + 2].copy_from_slice(&v.to_le_bytes());
            }
        }),
        Filter::Exponential => data.chunks_exact_mut(4).for_each(|e| {
            let v = i32::from_le_bytes([e[0], e[1], e[2], e[3]]);
            let (exp, mantissa) = (v >> 24, (v << 8) >> 8);
            // Exact in f64 for every exponent the format may hold.
            let x = (f64::from(mantissa) * 2f64.powi(exp)) as f32;
            e.copy_from_slice(&x.to_le_bytes());
        }),
    }
}

/// The octahedral filter's unit vector, in units of `max`.
fn octahedral([x, y, one]: [f32; 3], max: f32) -> [f32; 3] {
    if one == 0.0 {
        return [0.0; 3];
    }
    let (mut x, mut y) = (x / one, y / one);
    let z = 1.0 - x.abs() - y.abs();
    let t = z.min(0.0);
    x -= t.copysign(x);
    y -= t.copysign(y);
    let len = (x * x + y * y + z * z).sqrt();
    [x, y, z].map(|c| (c / len * max).round())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_specifications_four_bit_example_decodes() {
        // Appendix A: 16 deltas in 4-bit sentinel coding, two spilled.
        let bytes = [0x17, 0x5f, 0xf0, 0xbc, 0x77, 0xa9, 0x21, 0x00, 0x34, 0xb5];
        let mut data = Bytes {
            data: &bytes,
            at: 0,
        };
        let mut out = [0u8; 16];
        decode_group(2, &mut data, &mut out).unwrap();
        let deltas = out.map(|d| unzigzag8(d) as i8);
        assert_eq!(
            deltas,
            [-1, -4, -3, 26, -91, 0, -6, 6, -4, -4, 5, -5, 1, -1, 0, 0]
        );
        assert!(data.finished().is_ok());
    }

    #[test]
    fn index_deltas_follow_two_baselines() {
        // 5, 6 on baseline 0, then 100 on baseline 1, then 7 on baseline 0.
        let enc = |delta: i32, base: u32| ((((delta << 1) ^ (delta >> 31)) as u32) << 1) | base;
        let mut src = vec![0xd1];
        for (d, b) in [(5, 0), (1, 0), (100, 1), (1, 0), (-50, 1)] {
            let mut v = enc(d, b);
            loop {
                let byte = (v & 0x7f) as u8;
                v >>= 7;
                src.push(if v == 0 { byte } else { byte | 0x80 });
                if v == 0 {
                    break;
                }
            }
        }
        src.extend_from_slice(&[0; 4]);
        assert_eq!(decode_indices(&src, 5).unwrap(), [5, 6, 100, 7, 50]);
        assert!(decode_indices(&src, 6).is_err(), "past the data");
        assert!(decode_indices(&src, 4).is_err(), "bytes left over");
    }

    #[test]
    fn malformed_streams_are_errors_not_panics() {
        for len in 0..80 {
            let junk: Vec<u8> = (0..len).map(|i| (i * 37 + 11) as u8).collect();
            for head in [0xa0, 0xe1, 0xd1, 0x00] {
                let mut s = junk.clone();
                if let Some(b) = s.first_mut() {
                    *b = head;
                }
                let _ = decode_attributes(&s, 40, 12);
                let _ = decode_attributes(&s, 3, 256);
                let _ = decode_triangles(&s, 30);
                let _ = decode_indices(&s, 17);
            }
        }
    }
}
