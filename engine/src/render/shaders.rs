//! WGSL sources, assembled from the files in `shaders/` (WGSL has no includes). Tests validate exactly these
//! strings with naga, so what CI checks is what runs.

pub const COMMON: &str = include_str!("../../../shaders/common.wgsl");
pub const BVH: &str = include_str!("../../../shaders/bvh.wgsl");
pub const BRDF: &str = include_str!("../../../shaders/brdf.wgsl");
pub const PATH_TRACE: &str = include_str!("../../../shaders/path_trace.wgsl");
pub const TONEMAP: &str = include_str!("../../../shaders/tonemap.wgsl");
pub const DENOISE: &str = include_str!("../../../shaders/denoise.wgsl");

/// The path tracer module: shared declarations, traversal, BRDF, then the kernel.
pub fn path_trace_source() -> String {
    [COMMON, BVH, BRDF, PATH_TRACE].join("\n")
}

pub fn tonemap_source() -> String {
    TONEMAP.to_string()
}

pub fn denoise_source() -> String {
    DENOISE.to_string()
}

/// Every compute module the renderer builds, by name, for validation.
pub fn all_modules() -> Vec<(&'static str, String)> {
    vec![
        ("path_trace", path_trace_source()),
        ("tonemap", tonemap_source()),
        ("denoise", denoise_source()),
    ]
}
