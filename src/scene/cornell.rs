//! The built-in scenes, compiled into the binary so a newcomer needs no file:
//! - `cornell`: `assets/cornell_box.gltf`, the measured Cornell box with both
//!   blocks;
//! - `cornell-empty`: `assets/cornell_empty.gltf`, the same five walls, light,
//!   albedos and camera without the blocks (12 triangles): the paper's test
//!   scene (§3.2, "une source lumineuse et des parois idéalement diffuses").
//!
//! Both are written by `tools/make_cornell.py` (`--empty` for the second).

use super::Scene;
use crate::error::Result;

/// The box with both blocks (written by `tools/make_cornell.py`).
pub const CORNELL_GLTF: &[u8] = include_bytes!("../../assets/cornell_box.gltf");

/// The empty box (written by `tools/make_cornell.py --empty`).
pub const CORNELL_EMPTY_GLTF: &[u8] = include_bytes!("../../assets/cornell_empty.gltf");

/// Every built-in scene: its command-line name and its glTF bytes.
pub const BUILTINS: [(&str, &[u8]); 2] = [
    (super::BUILTIN_CORNELL, CORNELL_GLTF),
    (super::BUILTIN_CORNELL_EMPTY, CORNELL_EMPTY_GLTF),
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
