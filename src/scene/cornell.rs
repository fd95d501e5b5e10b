//! The built-in scenes, compiled into the binary so a newcomer needs no file:
//! - `cornell`: `assets/cornell_box.gltf`, the measured Cornell box with both
//!   blocks;
//! - `cornell-empty`: `assets/cornell_empty.gltf`, the same five walls, light,
//!   albedos and camera without the blocks (12 triangles): the paper's test
//!   scene (§3.2, "une source lumineuse et des parois idéalement diffuses");
//! - `cornell-glass`: `assets/cornell_glass.gltf`, the empty box with two
//!   spheres of radius 100 on the floor, a mirror and a smooth glass ball
//!   (IOR 1.5, a refracting volume), 20480 smooth-shaded triangles each;
//! - `door`: `assets/door.gltf`, Veach's two rooms joined by a door left
//!   ajar (a 10 cm gap, units centimetres), the only light in the room the
//!   camera does not see.
//!
//! The boxes are written by `tools/make_cornell.py` (`--empty` for the
//! second, `--glass` for the third), the door by `tools/make_door.py`.

use super::Scene;
use crate::error::Result;

/// The box with both blocks (written by `tools/make_cornell.py`).
pub const CORNELL_GLTF: &[u8] = include_bytes!("../../assets/cornell_box.gltf");

/// The empty box (written by `tools/make_cornell.py --empty`).
pub const CORNELL_EMPTY_GLTF: &[u8] = include_bytes!("../../assets/cornell_empty.gltf");

/// The empty box with a mirror and a glass sphere (written by
/// `tools/make_cornell.py --glass`).
pub const CORNELL_GLASS_GLTF: &[u8] = include_bytes!("../../assets/cornell_glass.gltf");

/// Two rooms and a door ajar (written by `tools/make_door.py`).
pub const DOOR_GLTF: &[u8] = include_bytes!("../../assets/door.gltf");

/// Every built-in scene: its command-line name and its glTF bytes.
pub const BUILTINS: [(&str, &[u8]); 4] = [
    (super::BUILTIN_CORNELL, CORNELL_GLTF),
    (super::BUILTIN_CORNELL_EMPTY, CORNELL_EMPTY_GLTF),
    (super::BUILTIN_CORNELL_GLASS, CORNELL_GLASS_GLTF),
    (super::BUILTIN_DOOR, DOOR_GLTF),
];

pub(super) fn load() -> Result<Scene> {
    super::gltf_load::load_slice(CORNELL_GLTF, None)
}

/// The built-in scene called `name`, if there is one.
pub(super) fn builtin(name: &str) -> Option<Result<Scene>> {
    BUILTINS
        .iter()
        .find(|(n, _)| *n == name)
        .map(|(_, bytes)| super::gltf_load::load_slice(bytes, None))
}
