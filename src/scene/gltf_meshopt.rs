//! `EXT_meshopt_compression` and `KHR_meshopt_compression`: buffer views
//! stored compressed (what `gltfpack -c` writes, `-ce khr` for the second),
//! decoded into their place in the parent buffer before any accessor reads
//! them, so the rest of the loader sees plain data. The bitstreams
//! (attributes in versions 0 and 1, triangles, indices) and the filters
//! (octahedral, quaternion, exponential, and the KHR extension's colour)
//! are the extensions' appendices; every read is bounds-checked and a
//! malformed stream is an error naming its view. The KHR extension's
//! version 0 is the EXT one's bitstream; its version 1 adds control modes
//! (bit widths per byte position) and channel modes (16-bit and rotated
//! XOR deltas).
//!
//! The uncompressed bytes go to the view's own buffer, which a compressing
//! writer leaves without data (`"fallback": true`, or no URI after the GLB
//! chunk): [`super::buffers`] gives such a buffer zeros of its declared
//! length, under the same limit as every other buffer.

use crate::error::{Error, Result};
use gltf::json::Root;
use serde_json::{Map, Value};

/// The vendor extension's name.
pub(super) const EXT_MESHOPT_COMPRESSION: &str = "EXT_meshopt_compression";
/// The Khronos extension's name.
pub(super) const KHR_MESHOPT_COMPRESSION: &str = "KHR_meshopt_compression";
const NAMES: [&str; 2] = [EXT_MESHOPT_COMPRESSION, KHR_MESHOPT_COMPRESSION];

/// Whether buffer `i` is a fallback an extension fills: marked so, or
/// without data of its own in a file that uses one.
pub(super) fn is_fallback(root: &Root, i: usize) -> bool {
    let Some(b) = root.buffers.get(i) else {
        return false;
    };
    let marked = NAMES.iter().any(|name| {
        b.extensions
            .as_ref()
            .and_then(|e| e.others.get(*name))
            .and_then(|e| e.get("fallback"))
            .and_then(Value::as_bool)
            .unwrap_or(false)
    });
    let used = root
        .extensions_used
        .iter()
        .any(|e| NAMES.contains(&e.as_str()));
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
    /// YCoCg colours (the KHR extension only).
    Color,
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
    /// The KHR extension: attributes may be in version 1, and colours filtered.
    khr: bool,
}

/// Decodes every compressed view of `root` into `buffers`.
pub(super) fn decode_views(root: &Root, buffers: &mut [Vec<u8>]) -> Result<()> {
    for (i, view) in root.buffer_views.iter().enumerate() {
        let others = view.extensions.as_ref().map(|e| &e.others);
        let Some((name, ext)) = NAMES.iter().find_map(|&n| Some((n, others?.get(n)?))) else {
            continue;
        };
        let what = |why: String| Error::InvalidScene(format!("bufferView {i} ({name}): {why}"));
        let c = parse(ext, name == KHR_MESHOPT_COMPRESSION).map_err(what)?;
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

fn parse(ext: &Value, khr: bool) -> std::result::Result<Compressed, String> {
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
        "COLOR" if khr => Filter::Color,
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
        khr,
    };
    let s = c.stride;
    let valid = match (c.mode, c.filter) {
        (Mode::Attributes, f) => {
            s > 0
                && s % 4 == 0
                && s <= 256
                && match f {
                    Filter::None | Filter::Exponential => true,
                    Filter::Octahedral | Filter::Color => s == 4 || s == 8,
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
            let mut out = decode_attributes(src, c.count, c.stride, c.khr)?;
            apply_filter(c.filter, c.stride, &mut out);
            Ok(out)
        }
        Mode::Triangles => Ok(write_indices(&decode_triangles(src, c.count)?, c.stride)),
        Mode::Indices => Ok(write_indices(&decode_indices(src, c.count)?, c.stride)),
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

fn unzigzag16(v: u16) -> u16 {
    if v & 1 != 0 {
        !(v >> 1)
    } else {
        v >> 1
    }
}

/// Bit widths of a group's deltas by its 2 header bits: version 0, then
/// version 1 by the byte position's control mode 0 and 1.
const WIDTHS: [[u8; 4]; 3] = [[0, 2, 4, 8], [0, 1, 2, 4], [1, 2, 4, 8]];

/// Mode 0: deltas from the previous element, in blocks of at most 256
/// elements, groups of 16, stored byte position by byte position; the
/// baseline element is in the stream's tail (with, in version 1, a mode
/// per 4-byte channel: byte, 16-bit or rotated XOR deltas).
fn decode_attributes(
    src: &[u8],
    count: usize,
    stride: usize,
    v1_allowed: bool,
) -> std::result::Result<Vec<u8>, String> {
    let v1 = match src.first() {
        Some(0xa0) => false,
        Some(0xa1) if v1_allowed => true,
        Some(h) => {
            return Err(format!(
                "attribute header {h:#04x}, not a version this extension has"
            ))
        }
        None => return Err("an empty stream".into()),
    };
    let channels = stride / 4;
    let modes_len = if v1 { channels } else { 0 };
    let tail = (stride + modes_len).max(if v1 { 24 } else { 32 });
    if src.len() < 1 + tail {
        return Err("the stream is shorter than its tail".into());
    }
    let modes = &src[src.len() - modes_len..];
    let base_end = src.len() - modes_len;
    let mut last = src[base_end - stride..base_end].to_vec();
    for &m in modes {
        if m & 15 > 2 || (m & 15 < 2 && m >> 4 != 0) {
            return Err(format!("channel mode {m:#04x}"));
        }
    }
    let mut data = Bytes {
        data: &src[1..src.len() - tail],
        at: 0,
    };
    let mut out = vec![0u8; count * stride];
    let max_block = ((8192 / stride) & !15).min(256);
    let mut deltas = vec![0u8; stride * 256];
    let mut first = 0;
    while first < count {
        let block = (count - first).min(max_block);
        let groups = block.div_ceil(16);
        let control = data.take(if v1 { channels } else { 0 })?;
        for (k, d) in deltas.chunks_exact_mut(256).enumerate() {
            let d = &mut d[..groups * 16];
            let ctrl = control.get(k / 4).map_or(0, |c| (c >> ((k % 4) * 2)) & 3);
            match (v1, ctrl) {
                (true, 2) => d.fill(0),
                // Literal: the block's deltas, not rounded up to a group.
                (true, 3) => d[..block].copy_from_slice(data.take(block)?),
                _ => {
                    let widths = WIDTHS[if v1 { 1 + usize::from(ctrl) } else { 0 }];
                    let header = data.take(groups.div_ceil(4))?;
                    for (g, group) in d.chunks_exact_mut(16).enumerate() {
                        let bits = (header[g / 4] >> ((g % 4) * 2)) & 3;
                        decode_group(widths[usize::from(bits)], &mut data, group)?;
                    }
                }
            }
        }
        let rows = first * stride..(first + block) * stride;
        apply_deltas(&deltas, modes, &mut last, &mut out[rows], block);
        first += block;
    }
    data.finished()?;
    Ok(out)
}

/// Adds a block's deltas (`deltas[k * 256 + i]`: byte `k` of element `i`)
/// to `last` element by element into `out`, channel by channel.
fn apply_deltas(deltas: &[u8], modes: &[u8], last: &mut [u8], out: &mut [u8], block: usize) {
    let stride = last.len();
    let d = |k: usize, i: usize| deltas[k * 256 + i];
    for c in 0..stride.div_ceil(4) {
        let mode = modes.get(c).copied().unwrap_or(0);
        let bytes = 4 * c..(4 * c + 4).min(stride);
        for i in 0..block {
            let row = &mut out[i * stride..(i + 1) * stride];
            match mode & 15 {
                1 => {
                    for k in bytes.clone().step_by(2) {
                        let delta = unzigzag16(u16::from_le_bytes([d(k, i), d(k + 1, i)]));
                        let v = u16::from_le_bytes([last[k], last[k + 1]]).wrapping_add(delta);
                        last[k..k + 2].copy_from_slice(&v.to_le_bytes());
                    }
                }
                2 => {
                    let delta = u32::from_le_bytes([0, 1, 2, 3].map(|j| d(4 * c + j, i)));
                    let prev = u32::from_le_bytes([0, 1, 2, 3].map(|j| last[4 * c + j]));
                    // The encoder rotated left by the mode's high bits.
                    let v = prev ^ delta.rotate_right(u32::from(mode >> 4));
                    last[bytes.clone()].copy_from_slice(&v.to_le_bytes());
                }
                _ => {
                    for k in bytes.clone() {
                        last[k] = last[k].wrapping_add(unzigzag8(d(k, i)));
                    }
                }
            }
            row[bytes.clone()].copy_from_slice(&last[bytes.clone()]);
        }
    }
}

/// One group of 16 zigzagged deltas of `width` bits: zeros, 1-, 2- or
/// 4-bit codes with a sentinel (all ones) for a full byte after them, or 16
/// bytes.
fn decode_group(width: u8, data: &mut Bytes, out: &mut [u8]) -> std::result::Result<(), String> {
    match width {
        0 => out.fill(0),
        8 => out.copy_from_slice(data.take(16)?),
        _ => {
            let per_byte = usize::from(8 / width);
            let sentinel = (1u8 << width) - 1;
            let packed = data.take(16 / per_byte)?;
            let mut codes = [0u8; 16];
            for (i, c) in codes.iter_mut().enumerate() {
                let slot = (i % per_byte) as u8;
                // 1-bit codes fill a byte from its least significant bit,
                // 2- and 4-bit codes from its most significant bits.
                let shift = if width == 1 {
                    slot
                } else {
                    8 - width * (1 + slot)
                };
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
    // `next` counts up with 32-bit wraparound, as the extensions say.
    let bump = |next: &mut u32| {
        let v = *next;
        *next = v.wrapping_add(1);
        v
    };
    let index = |data: &mut Bytes, last: &mut u32| -> std::result::Result<u32, String> {
        *last = last.wrapping_add_signed(unzigzag32(data.varint()?));
        Ok(*last)
    };
    let mut out = Vec::with_capacity(count);
    for &code in codes {
        let (hi, lo) = (code >> 4, code & 15);
        let tri = if hi < 15 {
            let (a, b) = fifo.edge(hi)?;
            let c = match lo {
                0 => {
                    let c = bump(&mut next);
                    fifo.push_vertex(c);
                    c
                }
                1..=12 => fifo.vertex(lo)?,
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
                bump(&mut next)
            };
            let mut other = |x: u8, data: &mut Bytes| -> std::result::Result<(u32, bool), String> {
                Ok(match x {
                    0 => (bump(&mut next), true),
                    15 if explicit => (index(data, &mut last)?, true),
                    _ => (fifo.vertex(x - 1)?, false),
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

/// The triangle codec's recent edges and vertices (index 0: the newest),
/// with how many of each were pushed: a stream that reads an entry never
/// written is malformed.
#[derive(Default)]
struct Fifos {
    edges: [(u32, u32); 16],
    edges_pushed: usize,
    vertices: [u32; 16],
    vertices_pushed: usize,
}

impl Fifos {
    fn edge(&self, i: u8) -> std::result::Result<(u32, u32), String> {
        let i = usize::from(i);
        match i < self.edges_pushed {
            true => Ok(self.edges[(self.edges_pushed + 15 - i) & 15]),
            false => Err(format!("edge {i} read before it was written")),
        }
    }

    fn vertex(&self, i: u8) -> std::result::Result<u32, String> {
        let i = usize::from(i);
        match i < self.vertices_pushed {
            true => Ok(self.vertices[(self.vertices_pushed + 15 - i) & 15]),
            false => Err(format!("vertex {i} read before it was written")),
        }
    }

    fn push_edge(&mut self, a: u32, b: u32) {
        self.edges[self.edges_pushed & 15] = (a, b);
        self.edges_pushed += 1;
    }

    fn push_vertex(&mut self, v: u32) {
        self.vertices[self.vertices_pushed & 15] = v;
        self.vertices_pushed += 1;
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

fn write_indices(indices: &[u32], stride: usize) -> Vec<u8> {
    let mut out = Vec::with_capacity(indices.len() * stride);
    for &i in indices {
        if stride == 2 {
            // 16 bits with wraparound, as the extensions say.
            out.extend_from_slice(&(i as u16).to_le_bytes());
        } else {
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
    out
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
        Filter::Color if stride == 4 => data.chunks_exact_mut(4).for_each(|e| {
            let [y, co, cg, a] = [
                e[0] as i32,
                e[1] as i8 as i32,
                e[2] as i8 as i32,
                e[3] as i32,
            ];
            e.copy_from_slice(&ycocg(y, co, cg, a, 255.0).map(|v| v as u8));
        }),
        Filter::Color => data.chunks_exact_mut(8).for_each(|e| {
            let c = |k: usize| u16::from_le_bytes([e[2 * k], e[2 * k + 1]]);
            let [y, co, cg, a] = [
                c(0) as i32,
                c(1) as i16 as i32,
                c(2) as i16 as i32,
                c(3) as i32,
            ];
            let rgba = ycocg(y, co, cg, a, 65535.0).map(|v| v as u16);
            for (k, v) in rgba.into_iter().enumerate() {
                e[2 * k..2 * k + 2].copy_from_slice(&v.to_le_bytes());
            }
        }),
    }
}

/// The colour filter's RGBA in units of `max` (an `f32` whose cast to the
/// component type saturates) from Y, Co, Cg and the alpha that carries the
/// bit count in its highest set bit.
fn ycocg(y: i32, co: i32, cg: i32, a: i32, max: f32) -> [f32; 4] {
    if a <= 0 {
        return [0.0; 4];
    }
    let scale = (1i32 << (32 - a.leading_zeros())) - 1;
    let (r, g, b) = (y + co - cg, y + cg, y - co - cg);
    let a = a & (scale >> 1);
    let a = (a << 1) | (a & 1);
    let ss = max / scale as f32;
    [r, g, b, a].map(|v| (v as f32 * ss).round())
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
        decode_group(4, &mut data, &mut out).unwrap();
        let deltas = out.map(|d| unzigzag8(d) as i8);
        assert_eq!(
            deltas,
            [-1, -4, -3, 26, -91, 0, -6, 6, -4, -4, 5, -5, 1, -1, 0, 0]
        );
        assert!(data.finished().is_ok());
    }

    /// A version-1 stream written by hand: 20 elements of 8 bytes, one
    /// block; bytes 0-3 literal under a rotated-XOR channel, bytes 4-5 in
    /// 1-bit groups and bytes 6-7 zero under a 16-bit channel.
    #[test]
    fn version_one_control_and_channel_modes_decode() {
        let (count, stride) = (20usize, 8usize);
        let base: [u8; 8] = [1, 2, 3, 4, 10, 0, 0, 0];
        let xor: Vec<u32> = (0..count as u32)
            .map(|i| i.wrapping_mul(0x9E37_79B9))
            .collect();
        let mut src = vec![0xa1];
        // Control: bytes 0-3 literal (3), byte 4 and 5 mode 0, 6 and 7 zero (2).
        src.extend_from_slice(&[0xff, 0b1010_0000]);
        for k in 0..4 {
            src.extend(xor.iter().map(|x| x.to_le_bytes()[k]));
        }
        // Byte 4: deltas zigzag(1) = 2 in every element, a 1-bit group
        // can't hold 2: sentinel (1) then the byte, for both groups
        // (header bits 1: width 1 under control 0).
        src.push(0b0101);
        for _ in 0..2 {
            src.extend_from_slice(&[0xff, 0xff]);
            src.extend_from_slice(&[2; 16]);
        }
        // Byte 5: all zero deltas (header bits 0).
        src.push(0);
        // Tail: padding, the baseline, then the channel modes (XOR rotated
        // by 3, 16-bit deltas).
        let modes = [0x32, 0x01];
        let tail = stride + modes.len();
        src.extend(std::iter::repeat_n(0, 24 - tail));
        src.extend_from_slice(&base);
        src.extend_from_slice(&modes);
        let out = decode_attributes(&src, count, stride, true).unwrap();
        assert!(
            decode_attributes(&src, count, stride, false).is_err(),
            "EXT has no version 1"
        );
        let mut prev = u32::from_le_bytes([1, 2, 3, 4]);
        let mut low = u16::from_le_bytes([10, 0]);
        for (i, e) in out.chunks_exact(stride).enumerate() {
            // The reference decoder: rotate(v, (32 - r) & 31) ^ previous.
            prev ^= xor[i].rotate_left((32 - 3) & 31);
            assert_eq!(e[..4], prev.to_le_bytes(), "element {i}");
            // 16-bit channel: low byte delta zigzag 2 = +1, high byte 0.
            low = low.wrapping_add(1);
            assert_eq!(e[4..6], low.to_le_bytes(), "element {i}");
            assert_eq!(e[6..], [0, 0], "element {i}");
        }
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
            for head in [0xa0, 0xa1, 0xe1, 0xd1, 0x00] {
                let mut s = junk.clone();
                if let Some(b) = s.first_mut() {
                    *b = head;
                }
                for v1 in [false, true] {
                    let _ = decode_attributes(&s, 40, 12, v1);
                    let _ = decode_attributes(&s, 3, 256, v1);
                }
                let _ = decode_triangles(&s, 30);
                let _ = decode_indices(&s, 17);
            }
        }
    }
}
