//! Scenes whose rays cost more but whose photons do not change: every
//! triangle split by midpoint subdivision. Shared by `benches/rays.rs` and
//! `examples/trace_vs_raw.rs`.

use adaptive_pm::scene::Scene;
use glam::Vec3;

/// `scene`'s meshes with every triangle split into 4^`levels` (midpoint
/// subdivision): the same surfaces, materials and area lights, and rays
/// that cost more. Punctual lights, the camera and vertex normals are not
/// copied (the Cornell box, which the benches split, has none of them).
/// Emitting meshes are split too only with `split_lights`: left whole,
/// sampling a light (finding a photon's triangle) costs what it cost before.
pub fn subdivided(scene: &Scene, levels: u32, split_lights: bool) -> Scene {
    let mut out = Scene::new();
    for m in scene.materials() {
        out.add_material(m.clone());
    }
    for mesh in scene.meshes() {
        let mut tris: Vec<[Vec3; 3]> = (0..mesh.indices.len()).map(|i| mesh.triangle(i)).collect();
        let emits = scene.materials()[mesh.material].emission.is_some();
        let levels = if emits && !split_lights { 0 } else { levels };
        for _ in 0..levels {
            tris = tris
                .iter()
                .flat_map(|&[a, b, c]| {
                    let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
                    [[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]
                })
                .collect();
        }
        let positions = tris.iter().flatten().copied().collect();
        let indices = (0..tris.len() as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        out.add_mesh(mesh.name.clone(), positions, indices, mesh.material)
            .expect("a subdivided mesh is as valid as its source");
    }
    out
}
