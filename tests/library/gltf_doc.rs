//! Small glTF documents written by tests: JSON with the geometry (and
//! images) in one `data:` buffer.

use serde_json::{json, Value};
use std::path::PathBuf;

/// One primitive: positions, indices, mode, material.
pub(crate) type Primitive<'a> = (&'a [[f32; 3]], &'a [u32], u32, Option<usize>);

/// A glTF document under construction: one buffer of f32 positions and u32
/// indices, meshes of one primitive each.
#[derive(Default)]
pub(crate) struct Doc {
    pub(crate) bin: Vec<u8>,
    pub(crate) accessors: Vec<Value>,
    pub(crate) views: Vec<Value>,
    pub(crate) meshes: Vec<Value>,
    pub(crate) nodes: Vec<Value>,
    pub(crate) materials: Vec<Value>,
    pub(crate) images: Vec<Value>,
    pub(crate) textures: Vec<Value>,
    pub(crate) samplers: Vec<Value>,
    pub(crate) skins: Vec<Value>,
    /// The scene's root nodes; `None`: every node is a root.
    pub(crate) roots: Option<Vec<usize>>,
    pub(crate) extensions_used: Vec<&'static str>,
}

impl Doc {
    pub(crate) fn view(&mut self, bytes: &[u8]) -> usize {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        while self.bin.len() % 4 != 0 {
            self.bin.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": offset, "byteLength": bytes.len()}));
        self.views.len() - 1
    }

    /// Adds a mesh of one primitive in `mode` (4 = triangles, 5 = strip,
    /// 6 = fan, 1 = lines) and returns its index.
    pub(crate) fn mesh(
        &mut self,
        positions: &[[f32; 3]],
        indices: &[u32],
        mode: u32,
        material: Option<usize>,
    ) -> usize {
        self.primitives(&[(positions, indices, mode, material)])
    }

    pub(crate) fn primitives(&mut self, prims: &[Primitive]) -> usize {
        let mut list = Vec::new();
        for &(positions, indices, mode, material) in prims {
            let bytes: Vec<u8> = positions
                .iter()
                .flatten()
                .flat_map(|c| c.to_le_bytes())
                .collect();
            let v = self.view(&bytes);
            let lo = (0..3).map(|k| positions.iter().map(|p| p[k]).fold(f32::INFINITY, f32::min));
            let hi = (0..3).map(|k| {
                positions
                    .iter()
                    .map(|p| p[k])
                    .fold(f32::NEG_INFINITY, f32::max)
            });
            self.accessors.push(json!({"bufferView": v, "componentType": 5126, "count": positions.len(), "type": "VEC3",
                "min": lo.collect::<Vec<_>>(), "max": hi.collect::<Vec<_>>()}));
            let pos = self.accessors.len() - 1;
            let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
            let v = self.view(&bytes);
            self.accessors
                .push(json!({"bufferView": v, "componentType": 5125, "count": indices.len(), "type": "SCALAR"}));
            let mut p = json!({"attributes": {"POSITION": pos}, "indices": self.accessors.len() - 1, "mode": mode});
            if let Some(m) = material {
                p["material"] = json!(m);
            }
            list.push(p);
        }
        self.meshes.push(json!({ "primitives": list }));
        self.meshes.len() - 1
    }

    /// Adds float attribute `name` (`VECn`, `n = N`) to primitive 0 of
    /// mesh `mesh`.
    fn float_attribute<const N: usize>(&mut self, mesh: usize, name: &str, values: &[[f32; N]]) {
        let bytes: Vec<u8> = values
            .iter()
            .flatten()
            .flat_map(|c| c.to_le_bytes())
            .collect();
        let v = self.view(&bytes);
        self.accessors
            .push(json!({"bufferView": v, "componentType": 5126,
            "count": values.len(), "type": format!("VEC{N}")}));
        self.meshes[mesh]["primitives"][0]["attributes"][name] = json!(self.accessors.len() - 1);
    }

    /// Adds `TEXCOORD_0` values to primitive 0 of mesh `mesh`.
    pub(crate) fn texcoords(&mut self, mesh: usize, uvs: &[[f32; 2]]) {
        self.float_attribute(mesh, "TEXCOORD_0", uvs);
    }

    /// Adds `COLOR_0` to primitive 0 of mesh `mesh`: normalized
    /// UNSIGNED_BYTE RGBA.
    pub(crate) fn colors(&mut self, mesh: usize, rgba: &[[u8; 4]]) {
        let bytes: Vec<u8> = rgba.iter().flatten().copied().collect();
        let v = self.view(&bytes);
        self.accessors.push(
            json!({"bufferView": v, "componentType": 5121, "normalized": true,
            "count": rgba.len(), "type": "VEC4"}),
        );
        self.meshes[mesh]["primitives"][0]["attributes"]["COLOR_0"] =
            json!(self.accessors.len() - 1);
    }

    /// Adds `NORMAL` values to primitive 0 of mesh `mesh` (what the
    /// validator asks of a primitive whose material has a normal texture).
    pub(crate) fn normals(&mut self, mesh: usize, n: &[[f32; 3]]) {
        self.float_attribute(mesh, "NORMAL", n);
    }

    /// Adds `TANGENT` values to primitive 0 of mesh `mesh`.
    pub(crate) fn tangents(&mut self, mesh: usize, t: &[[f32; 4]]) {
        self.float_attribute(mesh, "TANGENT", t);
    }

    /// Adds a texture of the PNG `png` read through sampler `sampler` (a
    /// sampler's JSON) and returns its index.
    pub(crate) fn texture(&mut self, png: &[u8], sampler: Value) -> usize {
        let v = self.view(png);
        self.images
            .push(json!({"bufferView": v, "mimeType": "image/png"}));
        self.samplers.push(sampler);
        self.textures
            .push(json!({"source": self.images.len() - 1, "sampler": self.samplers.len() - 1}));
        self.textures.len() - 1
    }

    /// Adds a texture whose image is the WebP `webp`, named by
    /// `EXT_texture_webp` (which the document then requires), with the PNG
    /// `fallback` as its `source` when given; returns its index.
    pub(crate) fn webp_texture(
        &mut self,
        webp: &[u8],
        sampler: Value,
        fallback: Option<&[u8]>,
    ) -> usize {
        let v = self.view(webp);
        self.images
            .push(json!({"bufferView": v, "mimeType": "image/webp"}));
        let webp_image = self.images.len() - 1;
        self.samplers.push(sampler);
        let mut texture = json!({"sampler": self.samplers.len() - 1,
            "extensions": {"EXT_texture_webp": {"source": webp_image}}});
        if let Some(png) = fallback {
            let v = self.view(png);
            self.images
                .push(json!({"bufferView": v, "mimeType": "image/png"}));
            texture["source"] = json!(self.images.len() - 1);
        }
        self.textures.push(texture);
        if !self.extensions_used.contains(&"EXT_texture_webp") {
            self.extensions_used.push("EXT_texture_webp");
        }
        self.textures.len() - 1
    }

    pub(crate) fn material(&mut self, m: Value) -> usize {
        self.materials.push(m);
        self.materials.len() - 1
    }

    pub(crate) fn node(&mut self, n: Value) {
        self.nodes.push(n);
    }

    pub(crate) fn write(&self, dir: &std::path::Path) -> PathBuf {
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::encode(&self.bin)
        );
        let mut doc = json!({
            "asset": {"version": "2.0"}, "scene": 0,
            "scenes": [{"nodes": self.roots.clone().unwrap_or_else(|| (0..self.nodes.len()).collect())}],
            "nodes": self.nodes, "meshes": self.meshes, "materials": self.materials,
            "accessors": self.accessors, "bufferViews": self.views,
            "buffers": [{"byteLength": self.bin.len(), "uri": uri}],
        });
        for (key, list) in [
            ("images", &self.images),
            ("textures", &self.textures),
            ("samplers", &self.samplers),
            ("skins", &self.skins),
        ] {
            if !list.is_empty() {
                doc[key] = json!(list);
            }
        }
        if !self.extensions_used.is_empty() {
            doc["extensionsUsed"] = json!(self.extensions_used);
        }
        // KHR_mesh_quantization changes what accessors may hold: a file that
        // uses it must require it (the Khronos validator: NON_REQUIRED_EXTENSION).
        // So does one whose textures may have their image only in WebP.
        let required: Vec<&str> = ["KHR_mesh_quantization", "EXT_texture_webp"]
            .into_iter()
            .filter(|e| self.extensions_used.contains(e))
            .collect();
        if !required.is_empty() {
            doc["extensionsRequired"] = json!(required);
        }
        let path = dir.join("scene.gltf");
        std::fs::write(&path, doc.to_string()).unwrap();
        dump_for_the_validator(&doc);
        path
    }
}

/// The folder that `scripts/ci-gltf-validator-generated.sh` has the tests
/// copy every document they write into, for the Khronos validator.
pub(crate) const DUMP_ENV: &str = "ADAPTIVE_PM_GLTF_DUMP";

/// With [`DUMP_ENV`] set, keeps a copy of `doc` named after the test that
/// wrote it and its rank among that test's documents (tests run one per
/// thread, so the names are the same from run to run).
fn dump_for_the_validator(doc: &Value) {
    let Ok(dir) = std::env::var(DUMP_ENV) else {
        return;
    };
    thread_local! {
        static WRITTEN: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
    }
    let rank = WRITTEN.with(|w| {
        w.set(w.get() + 1);
        w.get()
    });
    let test = std::thread::current()
        .name()
        .unwrap_or("unnamed")
        .replace("::", "__");
    let dir = PathBuf::from(dir);
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::write(dir.join(format!("{test}-{rank}.gltf")), doc.to_string()).unwrap();
}

/// A unit square in the plane y = 0, wound to face +y (`up`) or -y.
pub(crate) fn square(half: f32, up: bool) -> ([[f32; 3]; 4], [u32; 6]) {
    let p = [
        [-half, 0.0, -half],
        [half, 0.0, -half],
        [half, 0.0, half],
        [-half, 0.0, half],
    ];
    // (p1 - p0) x (p3 - p0) = (+x) x (+z) = -y: [0, 1, 2] faces down.
    let idx = if up {
        [0, 2, 1, 0, 3, 2]
    } else {
        [0, 1, 2, 0, 2, 3]
    };
    (p, idx)
}
