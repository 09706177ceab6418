//! The ray-casting benchmark pass: one camera ray per pixel centre and, with `max_depth` 1 in the frame
//! constants, one cosine-distributed bounce per hit, without shading: the traversal throughput the speed targets
//! count. A second pipeline of the same kernel counts the traversal work per ray (nodes fetched by kind,
//! triangles tested: `shaders/traversal/stats.wgsl`), for the bytes-per-ray side of the throughput figures.

use crate::gpu::GpuContext;
use crate::gpu::bind::{Binding, bind_group, compute_layout};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;

pub const KERNEL: ShaderModule = ShaderModule {
    name: "raycast",
    source: include_str!("raycast.wgsl"),
    requires: &[
        "constants",
        "camera",
        "sampler",
        "sampling",
        "math",
        "traversal/tlas",
    ],
};

/// Counters of [`TraversalWork`]: 4 for camera rays, 4 for bounce rays, each 64 bits.
const WORK_COUNTERS: u64 = 8;

/// Traversal work summed over one pass: top-level nodes, deformable meshes' BVH2 nodes, wide (CWBVH) nodes and
/// triangle tests, for the camera rays and for the bounce rays.
#[derive(Clone, Copy, Debug, Default, PartialEq, serde::Serialize)]
pub struct TraversalWork {
    pub camera: [u64; 4],
    pub bounce: [u64; 4],
}

pub struct RaycastPass {
    pipeline: wgpu::ComputePipeline,
    /// The same kernel with TRAVERSAL_STATS on (compiled on first use).
    counting: std::sync::OnceLock<wgpu::ComputePipeline>,
    module: crate::gpu::ComputeModule,
    work_counts: wgpu::Buffer,
    view_layout: wgpu::BindGroupLayout,
}

impl RaycastPass {
    pub fn new(ctx: &GpuContext, scene_layout: &wgpu::BindGroupLayout) -> Self {
        use Binding::*;
        // frame, hit distances, ray counter, traversal work counters
        let view_layout =
            compute_layout(ctx, "raycast", &[Params, ReadWrite, ReadWrite, ReadWrite]);
        let module = crate::gpu::ComputeModule::new(
            ctx,
            compose(&KERNEL),
            &[Some(scene_layout), Some(&view_layout)],
        );
        Self {
            pipeline: module.pipeline("raycast", "cast_rays", &[]),
            counting: std::sync::OnceLock::new(),
            module,
            work_counts: crate::gpu::bind::storage_buffer(
                ctx,
                "raycast work counts",
                WORK_COUNTERS * 8,
            ),
            view_layout,
        }
    }

    /// The traversal work of the last [`Self::encode`] with `count_work` (blocks for the GPU).
    pub fn read_work(&self, ctx: &GpuContext) -> TraversalWork {
        let bytes = ctx.read_buffer(&self.work_counts, WORK_COUNTERS * 8);
        let counter = |k: usize| {
            let word = |i: usize| u32::from_le_bytes(bytes[4 * i..4 * i + 4].try_into().unwrap());
            u64::from(word(2 * k)) | (u64::from(word(2 * k + 1)) << 32)
        };
        TraversalWork {
            camera: [0, 1, 2, 3].map(counter),
            bounce: [4, 5, 6, 7].map(counter),
        }
    }

    /// Records the pass over the view (its frame uniform already written); rays cast land in the view's ray
    /// counter, which is reset first. With `count_work` the counting kernel runs instead (slower: time the
    /// other), its counters reset first ([`Self::read_work`]).
    pub fn encode(
        &self,
        ctx: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &wgpu::BindGroup,
        view: &ViewTargets,
        count_work: bool,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        // The summed hit distances are written out so that no work can be optimised away.
        let distances = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("raycast distances"),
            size: view.pixels().max(1) * 4,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let group = bind_group(
            ctx,
            "raycast",
            &self.view_layout,
            &[
                &view.frame,
                &distances,
                &view.ray_counter,
                &self.work_counts,
            ],
        );
        encoder.clear_buffer(&view.ray_counter, 0, None);
        let pipeline = if count_work {
            encoder.clear_buffer(&self.work_counts, 0, None);
            self.counting.get_or_init(|| {
                self.module
                    .pipeline("raycast counting", "cast_rays", &[("TRAVERSAL_STATS", 1.0)])
            })
        } else {
            &self.pipeline
        };
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("raycast"),
            timestamp_writes,
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, scene, &[]);
        pass.set_bind_group(1, &group, &[]);
        let (x, y) = view.workgroups();
        pass.dispatch_workgroups(x, y, 1);
    }
}
