//! WGSL sources, assembled from the files in `shaders/` (WGSL has no includes). Tests validate exactly these
//! strings with naga, so what CI checks is what runs.

pub const COMMON: &str = include_str!("../../../shaders/common.wgsl");
pub const BVH: &str = include_str!("../../../shaders/bvh.wgsl");
pub const BRDF: &str = include_str!("../../../shaders/brdf.wgsl");
pub const PATH_TRACE: &str = include_str!("../../../shaders/path_trace.wgsl");
pub const TONEMAP: &str = include_str!("../../../shaders/tonemap.wgsl");
pub const DISPLAY: &str = include_str!("../../../shaders/display.wgsl");
pub const DENOISE: &str = include_str!("../../../shaders/denoise.wgsl");
pub const RAYCAST: &str = include_str!("../../../shaders/raycast.wgsl");
pub const PICK: &str = include_str!("../../../shaders/pick.wgsl");
/// GPU skinning + morphing and the GPU BLAS refit (`crate::gpu_deform`); standalone modules.
pub const DEFORM: &str = include_str!("../../../shaders/deform.wgsl");
pub const REFIT: &str = include_str!("../../../shaders/refit.wgsl");

/// The path tracer module: shared declarations, traversal, BRDF, then the kernel.
pub fn path_trace_source() -> String {
    scene_kernel_source("path_trace.wgsl", PATH_TRACE)
}

/// The shading-free ray-casting benchmark kernel: the path tracer's scene bindings and traversal.
pub fn raycast_source() -> String {
    scene_kernel_source("raycast.wgsl", RAYCAST)
}

/// The viewer's picking pass: one ray through a pixel centre, the path tracer's bindings and traversal.
pub fn pick_source() -> String {
    scene_kernel_source("pick.wgsl", PICK)
}

/// A kernel over the scene bindings: shared declarations, traversal and BRDF, then `kernel` (WGSL has no
/// includes).
fn scene_kernel_source(name: &str, kernel: &str) -> String {
    [
        file("common.wgsl", COMMON),
        file("bvh.wgsl", BVH),
        file("brdf.wgsl", BRDF),
        file(name, kernel),
    ]
    .join("\n")
}

pub fn tonemap_source() -> String {
    file("tonemap.wgsl", TONEMAP)
}

pub fn deform_source() -> String {
    file("deform.wgsl", DEFORM)
}

pub fn refit_source() -> String {
    file("refit.wgsl", REFIT)
}

/// Kernel development: with `RAYKIN_SHADER_DIR` set, WGSL files found in that folder replace the built-in
/// copies (edit a kernel and rerun without rebuilding; A/B variants in one GPU session). Unset in normal use.
fn file(name: &str, built_in: &str) -> String {
    let Some(dir) = std::env::var_os("RAYKIN_SHADER_DIR") else {
        return built_in.to_string();
    };
    let path = std::path::Path::new(&dir).join(name);
    match std::fs::read_to_string(&path) {
        Ok(text) => {
            tracing::warn!("shader {name} read from {}", path.display());
            text
        }
        Err(_) => built_in.to_string(),
    }
}

pub fn denoise_source() -> String {
    file("denoise.wgsl", DENOISE)
}

/// The viewer's display pass (a render pipeline: the tone-mapped image drawn into the window).
pub fn display_source() -> String {
    file("display.wgsl", DISPLAY)
}

/// Every module the renderer builds, by name, for validation.
pub fn all_modules() -> Vec<(&'static str, String)> {
    vec![
        ("path_trace", path_trace_source()),
        ("tonemap", tonemap_source()),
        ("display", display_source()),
        ("denoise", denoise_source()),
        ("raycast", raycast_source()),
        ("pick", pick_source()),
        ("deform", deform_source()),
        ("refit", refit_source()),
    ]
}
