//! Scaling: trace time against triangle count (instanced copies of one asset under one top-level BVH) and
//! against resolution (one scene at several sizes).

use super::scenes::{BenchScene, instanced_grid};
use crate::stats::Spread;
use anyhow::Result;
use raykin::gpu::GpuContext;
use raykin::render::RenderSettings;
use raykin::scene::SceneAsset;
use std::sync::Arc;

#[derive(Clone, Debug, serde::Serialize)]
pub struct TriangleScalingRow {
    pub copies: usize,
    /// Triangles the rays can hit (copies x the asset's), and those stored once.
    pub instanced_triangles: usize,
    pub unique_triangles: usize,
    pub width: u32,
    pub height: u32,
    pub trace_ms: Spread,
    pub all_rays_per_s: f64,
}

#[derive(Clone, Debug, serde::Serialize)]
pub struct ResolutionScalingRow {
    pub scene: String,
    pub width: u32,
    pub height: u32,
    pub trace_ms: Spread,
    pub ns_per_pixel: f64,
}

pub fn triangles(
    ctx: &GpuContext,
    asset: &Arc<SceneAsset>,
    copies: &[usize],
    base: &RenderSettings,
    frames: usize,
) -> Result<Vec<TriangleScalingRow>> {
    let mut rows = Vec::new();
    for &n in copies {
        let (scene, camera) = instanced_grid(asset, n);
        let name = format!("{n} x {}", asset.source);
        let bench = BenchScene::still(name, Arc::new(scene), camera, base.environment.clone());
        let row = super::frame_loop::measure(ctx, &bench, base.clone(), 1, frames)?;
        rows.push(TriangleScalingRow {
            copies: n,
            instanced_triangles: n * asset.triangle_count(),
            unique_triangles: asset.triangle_count(),
            width: base.width,
            height: base.height,
            trace_ms: row.trace_ms,
            all_rays_per_s: row.all_rays_per_s,
        });
    }
    Ok(rows)
}

pub fn resolution(
    ctx: &GpuContext,
    scene: &BenchScene,
    sizes: &[(u32, u32)],
    base: &RenderSettings,
    frames: usize,
) -> Result<Vec<ResolutionScalingRow>> {
    let mut rows = Vec::new();
    for &(width, height) in sizes {
        let settings = super::at_size(base, (width, height));
        let row = super::frame_loop::measure(ctx, scene, settings, 1, frames)?;
        rows.push(ResolutionScalingRow {
            scene: scene.name.clone(),
            width,
            height,
            ns_per_pixel: row.trace_ms.median * 1e6 / (width as f64 * height as f64),
            trace_ms: row.trace_ms,
        });
    }
    Ok(rows)
}
