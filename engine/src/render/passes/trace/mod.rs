//! The trace pass: `spp` paths per pixel through the path integrator (`shaders/integrator/path.wgsl`), added to
//! the view's accumulation targets with the first-hit AOVs and the denoiser's moments. On GPUs a pixel's samples
//! are spread over several invocations of a workgroup ([`sample_lanes`]). Where
//! `RenderSettings::integrator` asks for waves and nothing but radiance is recorded, the frame runs the wavefront
//! pass (`passes::wavefront`) in its place.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, CachedGroup, bind_group, compute_layout};
use crate::render::material_lobes::{KernelNeeds, LobeKernels};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;
use bevy_ecs::prelude::Resource;

pub const KERNEL: ShaderModule = ShaderModule {
    name: "trace",
    source: include_str!("trace.wgsl"),
    requires: &[
        "constants",
        "camera",
        "color",
        "math",
        "sampler",
        "integrator/path",
    ],
};

#[derive(Resource)]
pub struct TracePass {
    /// Per lobe choice, indexed by [`kernel_index`]: with or without the denoisers' inputs (`PATH_AOVS`) and
    /// the primary-hit AOV (`PATH_HIT_AOV`), regenerating paths where the adapter does; each compiled when a view
    /// first needs it.
    kernels: [LobeKernels; 4],
    needs: KernelNeeds,
    aovs: bool,
    hit_aov: bool,
    view_layout: wgpu::BindGroupLayout,
    view_group: CachedGroup<u64>,
}

impl TracePass {
    pub fn new(ctx: &GpuContext, scene_layout: &wgpu::BindGroupLayout) -> Self {
        use Binding::*;
        // frame, accum, albedo + depth, normal + hits, ray counter, primary hit, moments
        let view_layout = compute_layout(
            ctx,
            "trace view",
            &[
                Params, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite, ReadWrite,
            ],
        );
        let kernels = |index: usize| {
            let (aovs, hit_aov) = kernel_flags(index);
            let mut constants = vec![
                ("PATH_AOVS", f64::from(u8::from(aovs))),
                ("PATH_HIT_AOV", f64::from(u8::from(hit_aov))),
            ];
            if ctx.path_regeneration {
                constants.push(("PATH_REGENERATION", 1.0));
            }
            LobeKernels::new(
                ctx,
                "path trace",
                compose(&KERNEL),
                &[Some(scene_layout), Some(&view_layout)],
                "trace_pixels",
            )
            .with_constants(&constants)
        };
        Self {
            kernels: std::array::from_fn(kernels),
            needs: KernelNeeds::default(),
            aovs: true,
            hit_aov: false,
            view_layout,
            view_group: CachedGroup::default(),
        }
    }

    /// Binds the view's targets (again only when they were replaced) and picks the kernel for the lobes the
    /// scene's materials use, with the denoisers' inputs (first-hit AOVs, moments) when `aovs` (compiling it the
    /// first time). Without them the view's AOV targets keep what they held.
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        view: &ViewTargets,
        needs: KernelNeeds,
        aovs: bool,
    ) {
        self.kernels[kernel_index(aovs, view.hit_aov)].get(needs);
        self.needs = needs;
        self.aovs = aovs;
        self.hit_aov = view.hit_aov;
        let layout = &self.view_layout;
        self.view_group.get_or_make(view.generation, || {
            bind_group(
                ctx,
                "trace view",
                layout,
                &[
                    &view.frame,
                    &view.accum,
                    &view.albedo_depth,
                    &view.normal_hits,
                    &view.ray_counter,
                    &view.hit,
                    &view.moments,
                ],
            )
        });
    }

    /// Records the pass (after [`Self::prepare`] for this view); the view's frame uniform must hold this
    /// dispatch's constants, `sample_lanes` among them, and its ray counter is reset first.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &wgpu::BindGroup,
        view: &ViewTargets,
        sample_lanes: u32,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let group = self
            .view_group
            .get(&view.generation)
            .expect("TracePass::prepare ran for this view");
        encoder.clear_buffer(&view.ray_counter, 0, None);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("path trace"),
            timestamp_writes,
        });
        pass.set_pipeline(
            self.kernels[kernel_index(self.aovs, self.hit_aov)]
                .compiled(self.needs)
                .expect("TracePass::prepare compiled this kernel"),
        );
        pass.set_bind_group(0, scene, &[]);
        pass.set_bind_group(1, group, &[]);
        let tile = pixel_tile(sample_lanes);
        pass.dispatch_workgroups(view.width.div_ceil(tile.0), view.height.div_ceil(tile.1), 1);
    }
}

/// Which of the pass's kernels a view with (or without) the denoisers' inputs and the hit AOV runs.
fn kernel_index(aovs: bool, hit_aov: bool) -> usize {
    aovs as usize | (hit_aov as usize) << 1
}

/// The denoisers' inputs and the hit AOV of kernel `index` ([`kernel_index`]'s inverse).
fn kernel_flags(index: usize) -> (bool, bool) {
    (index & 1 != 0, index & 2 != 0)
}

/// The most invocations that share a pixel's samples: a workgroup of 64 then holds 2x2 pixels.
const MOST_SAMPLE_LANES: u32 = 16;
/// Invocations a dispatch should have where its pixels' samples allow: enough for every thread slot of a large
/// GPU many times over (an H100 holds 270 k; 2^22 is 15 times that), so that no warp still running long paths
/// leaves the rest idle at the end. At 960x540 and 16 samples per pixel, sixteen lanes took 0.34x (FlightHelmet)
/// and 0.58x (the spheres) of the loop's time on an H100 (docs/BENCHMARKS.md, "Sample lanes").
const LANE_INVOCATIONS: u64 = 1 << 22;

/// How many invocations share each pixel's `spp` samples of a dispatch of `pixels` (written to the frame
/// constants, read by `trace.wgsl`): where the adapter spreads samples ([`GpuContext::sample_lanes`]), the fewest
/// lanes (a power of two, at most `spp` and [`MOST_SAMPLE_LANES`]) that give the dispatch [`LANE_INVOCATIONS`],
/// else 1 (one invocation loops over them all).
pub fn sample_lanes(ctx: &GpuContext, pixels: u64, spp: u32) -> u32 {
    if !ctx.sample_lanes || ctx.path_regeneration {
        return 1;
    }
    lanes_for(pixels, spp, lane_invocations())
}

/// The fewest lanes that give `invocations` for `pixels`, at most `spp` (a power of two) and 16.
fn lanes_for(pixels: u64, spp: u32, invocations: u64) -> u32 {
    let wanted = invocations.div_ceil(pixels.max(1)).next_power_of_two();
    let below_spp = 1 << (u32::BITS - 1 - spp.max(1).leading_zeros());
    (wanted.min(MOST_SAMPLE_LANES as u64) as u32).min(below_spp)
}

/// [`LANE_INVOCATIONS`], or `RAYKIN_LANE_INVOCATIONS` where set to a number (A/B runs).
fn lane_invocations() -> u64 {
    static INVOCATIONS: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    *INVOCATIONS
        .get_or_init(|| crate::gpu::number_from_env("RAYKIN_LANE_INVOCATIONS", LANE_INVOCATIONS))
}

/// The pixels of one workgroup of 64 invocations with `lanes` to a pixel, as `trace.wgsl`'s `pixel_tile` (8x8
/// for one lane, 4x8 for two, 4x4, 2x4, 2x2 for sixteen).
fn pixel_tile(lanes: u32) -> (u32, u32) {
    let log2 = lanes.trailing_zeros();
    (8 >> log2.div_ceil(2), 8 >> (log2 / 2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lanes_fill_small_views_within_the_samples() {
        // 960x540 (518 k pixels) wants 16 lanes, 1080p 4, 1440p 2, 4K one.
        assert_eq!(lanes_for(960 * 540, 16, LANE_INVOCATIONS), 16);
        assert_eq!(lanes_for(1920 * 1080, 16, LANE_INVOCATIONS), 4);
        assert_eq!(lanes_for(2560 * 1440, 16, LANE_INVOCATIONS), 2);
        assert_eq!(lanes_for(3840 * 2160, 16, LANE_INVOCATIONS), 1);
        // Never more lanes than samples (a power of two at most), nor more than sixteen.
        assert_eq!(lanes_for(960 * 540, 7, LANE_INVOCATIONS), 4);
        assert_eq!(lanes_for(960 * 540, 1, LANE_INVOCATIONS), 1);
        assert_eq!(lanes_for(16, 64, LANE_INVOCATIONS), 16);
        assert_eq!(lanes_for(0, 0, LANE_INVOCATIONS), 1);
    }

    #[test]
    fn each_kernel_index_names_one_kernel() {
        for aovs in [false, true] {
            for hit_aov in [false, true] {
                assert_eq!(kernel_flags(kernel_index(aovs, hit_aov)), (aovs, hit_aov));
                assert!(kernel_index(aovs, hit_aov) < 4);
            }
        }
    }

    #[test]
    fn a_workgroup_holds_64_invocations_whatever_the_lanes() {
        for lanes in [1, 2, 4, 8, 16] {
            let (x, y) = pixel_tile(lanes);
            assert_eq!(x * y * lanes, 64, "{lanes} lanes: {x}x{y} pixels");
        }
    }
}
