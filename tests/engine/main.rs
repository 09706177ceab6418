//! Tests of the engine library (`raykin`): one integration-test binary, one module per subject. The GPU
//! tests share one device and serialise through `common::gpu()`.
//!   cargo test --workspace --test engine -- furnace::      (one module)

#[path = "../common/mod.rs"]
mod common;

mod animation_bench;
mod animation_fixtures;
mod architecture;
mod assets;
mod bad_input;
mod clearcoat_reference;
mod cornell_reference;
mod deep_tlas;
mod denoise;
mod editor;
mod furnace;
mod glass_reference;
mod gltf_conformance;
mod gpu_deform;
mod layered_materials;
mod light_sampling;
mod lights_reference;
mod near_emitter;
mod oidn;
mod path_regeneration;
mod punctual_lights;
mod realtime;
mod record;
mod refit_stability;
mod reliability;
mod sample_lanes;
mod sampler;
mod shaders;
mod skinned_image;
mod thin_lens;
mod transmission;
mod traversal;
mod unlit;
mod wavefront;
