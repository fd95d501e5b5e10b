//! The library's integration tests: physics oracles, determinism, hostile
//! input. One binary of modules, so the suite compiles and links once; a
//! module is a former test file. Run one with its path as the filter:
//! `cargo test --test library render_cache::` (or one test:
//! `cargo test --test library render_cache::cache_is_unbiased`).

#[path = "../common/mod.rs"]
mod common;

mod analysis_btdf;
mod analysis_directionality;
mod analysis_monotone;
mod bench_cornell;
mod big_run;
mod brdf_models;
mod caustic_aim;
mod caustic_pass;
mod caustic_render;
mod caustic_runs;
mod cornell_empty;
mod cornell_rays;
mod dielectric;
mod directional_light;
mod door_scene;
mod embree_wrapper;
mod engine;
mod fixtures;
mod gather_guide;
mod gather_plan;
mod glass_transport;
mod gltf_alpha_mask;
mod gltf_alpha_mask_rays;
mod gltf_alpha_mask_refusals;
mod gltf_asset_root;
mod gltf_conformance;
mod gltf_doc;
mod gltf_emissive_texture;
mod gltf_glass;
mod gltf_layers;
mod gltf_meshopt;
mod gltf_normal_texture;
mod gltf_quantized;
mod gltf_sheen;
mod gltf_textures;
mod gltf_validator;
mod hostile;
mod hostile_values;
mod image_checksums;
mod importance_counts;
mod importance_pass;
mod isa_pinning;
mod kdtree;
mod kdtree_memory;
mod partial_transmission;
mod path_tracer;
mod photon_density;
mod raycast;
mod render;
mod render_cache;
mod render_cache_sight;
mod render_progressive;
mod render_reads;
mod scene_load;
mod shards;
mod sweep;
mod tradeoff;
