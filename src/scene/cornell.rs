//! The built-in Cornell box: `assets/cornell_box.gltf` compiled into the binary,
//! so a newcomer needs no file (`adaptive-pm scene cornell`).

use super::Scene;
use crate::error::Result;

/// The asset's bytes (written by `tools/make_cornell.py`).
pub const CORNELL_GLTF: &[u8] = include_bytes!("../../assets/cornell_box.gltf");

pub(super) fn load() -> Result<Scene> {
    super::gltf_load::load_slice(CORNELL_GLTF, None)
}
