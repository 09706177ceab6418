//! The wavefront trace pass (`RenderSettings::integrator` = [`Integrator::Wavefront`]): the path integrator cut
//! at its traversals into kernels over a queue of live paths (`wavefront.wgsl` says which and why). The same
//! estimator as the trace pass's megakernel, path for path; the frame runs the trace pass instead where the
//! denoisers' inputs or the primary-hit AOV are recorded, which this pass does not write.
//!
//! [`Integrator::Wavefront`]: crate::render::settings::Integrator::Wavefront

use crate::gpu::GpuContext;
use crate::gpu::PassTimestamps;
use crate::gpu::bind::{Binding, bind_group, compute_layout, storage_buffer};
use crate::render::layout::{
    BLAS_LAYOUT_WIDE, SORT_BLOCKS, SORT_WORDS, WAVE_CONTROL_RAYS, WAVE_CONTROL_WORDS,
};
use crate::render::material_lobes::{KernelNeeds, LobeKernels};
use crate::render::shaders::{ShaderModule, compose};
use crate::render::view::ViewTargets;
use bevy_ecs::prelude::Resource;

pub const KERNEL: ShaderModule = ShaderModule {
    name: "wavefront",
    source: include_str!("wavefront.wgsl"),
    requires: &[
        "constants",
        "sampler",
        "integrator/path",
        "traversal/refill",
    ],
};

/// The counters' and the sort's bytes at the start of the queues' buffer (`Queues::control`, `Queues::sort` in
/// the WGSL), zeroed before each dispatch.
const CONTROL_BYTES: u64 = (WAVE_CONTROL_WORDS + SORT_WORDS) as u64 * 4;
const QUEUE_ENTRY: u64 = 4;
/// Entries per path in the queues' buffer: the two queues, and where the rays are sorted the sort's keys and the
/// sorted queue (allocated only then: 8 bytes a path, 67 MB for the largest wave).
const fn queue_entries(sort: bool) -> u64 {
    if sort { 4 } else { 2 }
}
const STATE_ENTRY: u64 = 16;
/// `ShadowRay` in the WGSL: origin, direction, light.
const SHADOW_ENTRY: u64 = 48;
/// Bytes of state a path holds at most: the six per-path arrays and the hits, its queue entries with the rays
/// sorted, its shadow ray.
const PATH_BYTES: u64 = 7 * STATE_ENTRY + queue_entries(true) * QUEUE_ENTRY + SHADOW_ENTRY;
/// Paths a wave should hold when the view has fewer pixels: every bounce's dispatch waits for the one before it,
/// and once most paths have ended a bounce's few survivors cost that wait alone, so a wave's fixed cost is paid
/// per wave. At 960x540 and 16 samples per pixel a dispatch in one wave of 8.4 M paths took 0.54-0.95x the time
/// of four waves of 2.1 M on an H100 (FlightHelmet 0.54x, the spheres 0.63x, the Cornell box 0.95x;
/// docs/BENCHMARKS.md, "Sample lanes"), for [`PATH_BYTES`] of state a path (176: 1.5 GB at most, released when the
/// megakernel traces the view; smaller waves where the GPU's memory cannot hold it).
const WAVE_PATHS: u64 = 1 << 23;
/// The most samples of a pixel one wave holds.
const MAX_SAMPLES_PER_WAVE: u64 = 16;

/// Samples per pixel per wave for a view of `pixels` and a dispatch of `spp` samples per pixel, within the
/// paths the adapter's bindings hold (`max_paths`, at least `pixels`).
fn samples_per_wave(pixels: u64, spp: u32, max_paths: u64) -> u64 {
    (wave_paths().min(max_paths) / pixels.max(1))
        .clamp(1, MAX_SAMPLES_PER_WAVE)
        .min(spp.max(1) as u64)
}

/// The first `make(samples)` that succeeds, for `first` samples per wave and then half as many each time down to
/// one.
fn halving_until<T>(first: u64, mut make: impl FnMut(u64) -> Option<T>) -> Option<T> {
    let mut samples = first.max(1);
    loop {
        if let Some(made) = make(samples) {
            return Some(made);
        }
        if samples == 1 {
            return None;
        }
        samples /= 2;
    }
}

/// [`WAVE_PATHS`], or `RAYKIN_WAVE_PATHS` where set to a number (A/B runs).
fn wave_paths() -> u64 {
    static PATHS: std::sync::OnceLock<u64> = std::sync::OnceLock::new();
    *PATHS.get_or_init(|| crate::gpu::number_from_env("RAYKIN_WAVE_PATHS", WAVE_PATHS))
}

/// The paths one binding of each state array holds: the shadow rays' entries are the largest, and the queues
/// hold their entries per path with the rays sorted after the counters and the sort's bins (sorted or not, so
/// that the sort's trial never changes a wave's size).
fn max_paths(ctx: &GpuContext) -> u64 {
    let binding = crate::gpu::limits::max_binding_bytes(&ctx.limits);
    (binding / SHADOW_ENTRY)
        .min(binding.saturating_sub(CONTROL_BYTES) / (queue_entries(true) * QUEUE_ENTRY))
}

/// The kernels a wave runs, in order.
struct Kernels {
    begin_wave: LobeKernels,
    /// These three unsorted and sorted (`WAVE_SORT`); the first two also without and with the pass-throughs
    /// of alpha-blended surfaces (`WAVE_PASS_THROUGHS`): `[sort][pass-throughs]`.
    first_bounce: [[LobeKernels; 2]; 2],
    extend: [[LobeKernels; 2]; 2],
    /// Extend with refill (`GpuContext::wave_refill`), as `extend`: `[sort][pass-throughs]`.
    extend_refill: [[LobeKernels; 2]; 2],
    shade: [LobeKernels; 2],
    advance: LobeKernels,
    /// The ray sort's two kernels (`WAVE_SORT`), run after each `advance` where the rays are sorted.
    sort_prefix: LobeKernels,
    sort_scatter: LobeKernels,
    finish: LobeKernels,
}

/// The paths' state for one image size and wave: per path, the arrays of `wavefront.wgsl`'s group 1 (whose
/// length tells the kernels how many samples of each pixel a wave holds).
struct PathBuffers {
    pixels: u64,
    samples_per_wave: u64,
    /// The view's generation and the samples per wave asked for (more than `samples_per_wave` where the GPU's
    /// memory held fewer).
    made_for: (u64, u64),
    view_group: wgpu::BindGroup,
    /// The counters, then the queues: with the sort's entries where `sorted_queues`.
    queues: wgpu::Buffer,
    sorted_queues: bool,
    args_group: wgpu::BindGroup,
    args: wgpu::Buffer,
    /// The path arrays and the hits, then the shadow rays: bound beside the queues.
    state: Vec<wgpu::Buffer>,
}

/// A dispatch's size: workgroups, or the offset of its sizes in the dispatch-sizes buffer.
#[derive(Clone, Copy)]
enum Step {
    Direct(u32, u32, u32),
    Indirect(u64),
}

/// `RAYKIN_WAVE_PROFILE=on` (kernel development): the first wave of each dispatch runs one compute pass per
/// stage, each timed, and the times are logged (info level) when the pass is next prepared.
struct WaveProfile {
    timestamps: PassTimestamps,
    /// Set by a profiled dispatch: its depth and waves, for the log line.
    pending: std::sync::Mutex<Option<(u32, u32)>>,
}

impl WaveProfile {
    /// Stages of a wave: the first bounce, a trace and a shade stage per bounce, the last shadow rays, finish.
    const PAIRS: u32 = 1 + 2 * 32 + 2;

    fn new(ctx: &GpuContext) -> Option<Self> {
        if !crate::gpu::switch_on("RAYKIN_WAVE_PROFILE", false) {
            return None;
        }
        Some(Self {
            timestamps: PassTimestamps::new(ctx, "wavefront profile", Self::PAIRS)?,
            pending: Default::default(),
        })
    }

    /// Logs the last profiled dispatch's stage times (blocks until it finished).
    fn log(&self, ctx: &GpuContext) {
        let Some((depth, waves)) = self.pending.lock().ok().and_then(|mut p| p.take()) else {
            return;
        };
        let ms = self.timestamps.read_ms(ctx);
        let stages = 3 + 2 * depth as usize;
        let bounces: Vec<String> = (0..depth as usize)
            .map(|b| format!("{:.3}+{:.3}", ms[1 + 2 * b], ms[2 + 2 * b]))
            .collect();
        tracing::info!(
            "wavefront profile, first of {waves} waves, ms: first bounce {:.3}; bounces (trace+shade) {}; \
             last shadow rays {:.3}; finish {:.3}; total {:.3}",
            ms[0],
            bounces.join(" "),
            ms[stages - 2],
            ms[stages - 1],
            ms[..stages].iter().sum::<f64>()
        );
    }
}

/// The pass, built the first time a frame runs in waves (its kernels and state cost nothing until then).
#[derive(Resource, Default)]
pub struct WavefrontSlot(pub Option<WavefrontPass>);

pub struct WavefrontPass {
    kernels: Kernels,
    needs: KernelNeeds,
    view_layout: wgpu::BindGroupLayout,
    args_layout: wgpu::BindGroupLayout,
    buffers: Option<PathBuffers>,
    /// The view generation and samples per wave for which no state fitted, so that it is not tried every frame.
    no_room: Option<(u64, u64)>,
    profile: Option<WaveProfile>,
    /// `GpuContext::wave_refill` was set: extend runs with refill where [`refill_traverses`] the scene.
    refill: bool,
}

/// Offset of extend_refill's dispatch size in the sizes buffer (`dispatch_args[8..11)`).
const REFILL_ARGS: u64 = 32;

/// Whether extend with refill traverses kernels compiled for `needs` (`refill_supported` in
/// `shaders/traversal/refill.wgsl`): a wide top level or one merged tree over wide meshes only.
fn refill_traverses(needs: KernelNeeds) -> bool {
    (needs.wide_top_level.is_some() || needs.sole_instance.is_some())
        && needs.blas_layouts == BLAS_LAYOUT_WIDE
}

impl WavefrontPass {
    /// Whether a view of `pixels` can be traced in waves on this adapter: one path per pixel must fit each of
    /// the state's bindings (the megakernel needs 16 bytes a pixel, the waves' shadow rays 48 a path).
    pub fn fits(ctx: &GpuContext, pixels: u64) -> bool {
        pixels <= max_paths(ctx)
    }

    pub fn new(ctx: &GpuContext, scene_layout: &wgpu::BindGroupLayout) -> Self {
        use Binding::*;
        // frame, accum, 6 path arrays, hits, counters and queues, shadow rays
        let mut bindings = vec![Params];
        bindings.extend([ReadWrite; 10]);
        let view_layout = compute_layout(ctx, "wavefront view", &bindings);
        let args_layout = compute_layout(ctx, "wavefront dispatch sizes", &[ReadWrite]);
        let source = compose(&KERNEL);
        let queue = [Some(scene_layout), Some(&view_layout)];
        // The sizing kernels' layout is the queue kernels' plus the sizes, never a gap where the scene's group is
        // (although they read no scene): Vulkan's layouts are compatible for a group only when every group before
        // it matches, and wgpu 30 does not bind the view's group again when a pass switches to a layout that
        // differs only below it. With a gap, `advance` wrote through a stale group on NVIDIA and sized nothing.
        let [scene, view] = queue;
        let sizing = [scene, view, Some(&args_layout)];
        let constants: &[(&'static str, f64)] = &[("PATH_AOVS", 0.0)];
        let kernel_with = |entry: &'static str,
                           layouts: &[Option<&wgpu::BindGroupLayout>],
                           constants: &[(&'static str, f64)]| {
            LobeKernels::new(ctx, "wavefront", source.clone(), layouts, entry)
                .with_constants(constants)
        };
        let kernel = |entry, layouts: &[_]| kernel_with(entry, layouts, constants);
        let refill_groups = ctx.wave_refill.unwrap_or(0);
        let sorted = |entry, sort: f64| {
            kernel_with(entry, &queue, &[("PATH_AOVS", 0.0), ("WAVE_SORT", sort)])
        };
        let passing = |entry, sort: f64| {
            [0.0, 1.0].map(|passes| {
                kernel_with(
                    entry,
                    &queue,
                    &[
                        ("PATH_AOVS", 0.0),
                        ("WAVE_PASS_THROUGHS", passes),
                        ("WAVE_SORT", sort),
                    ],
                )
            })
        };
        Self {
            kernels: Kernels {
                begin_wave: kernel("begin_wave", &sizing),
                first_bounce: [0.0, 1.0].map(|sort| passing("first_bounce", sort)),
                extend: [0.0, 1.0].map(|sort| passing("extend", sort)),
                extend_refill: [0.0, 1.0].map(|sort| passing("extend_refill", sort)),
                shade: [0.0, 1.0].map(|sort| sorted("shade", sort)),
                advance: kernel_with(
                    "advance",
                    &sizing,
                    &[
                        ("PATH_AOVS", 0.0),
                        ("WAVE_REFILL_GROUPS", f64::from(refill_groups)),
                    ],
                ),
                sort_prefix: kernel("sort_prefix", &queue),
                sort_scatter: kernel("sort_scatter", &queue),
                finish: kernel("finish", &queue),
            },
            needs: KernelNeeds::default(),
            view_layout,
            args_layout,
            buffers: None,
            no_room: None,
            profile: WaveProfile::new(ctx),
            refill: refill_groups > 0,
        }
    }

    /// Whether the kernels of the last [`Self::prepare`] extend with refill (`GpuContext::wave_refill`, where the
    /// scene's shape allows it).
    pub fn refilling(&self) -> bool {
        self.refill && refill_traverses(self.needs)
    }

    /// Compiles the kernels for `needs` (the first time; with the pass-throughs of alpha-blended surfaces where
    /// some material blends, and sorting the rays where `sort`) and makes the paths' state for the view's size
    /// and dispatches of `spp` samples per pixel (again only when the view's targets were replaced or a wave's
    /// samples per pixel change; the queues alone when `sort` changes). Where the GPU's memory cannot hold the
    /// state, waves of half as many samples are tried, down to one; returns false where even that does not fit
    /// (the megakernel must trace the frame).
    pub fn prepare(
        &mut self,
        ctx: &GpuContext,
        view: &ViewTargets,
        needs: KernelNeeds,
        spp: u32,
        sort: bool,
    ) -> bool {
        let (passing, sorted) = (needs.materials.alpha_blend as usize, sort as usize);
        let refill = self.refill && refill_traverses(needs);
        let k = &mut self.kernels;
        let extend = if refill {
            &mut k.extend_refill[sorted][passing]
        } else {
            &mut k.extend[sorted][passing]
        };
        for kernels in [
            &mut k.begin_wave,
            &mut k.first_bounce[sorted][passing],
            extend,
            &mut k.shade[sorted],
            &mut k.advance,
            &mut k.finish,
        ] {
            kernels.get(needs);
        }
        if sort {
            k.sort_prefix.get(needs);
            k.sort_scatter.get(needs);
        }
        self.needs = needs;
        if let Some(profile) = &self.profile {
            profile.log(ctx);
        }
        let pixels = view.pixels();
        let wanted = samples_per_wave(pixels, spp, max_paths(ctx));
        let key = (view.generation, wanted);
        if let Some(buffers) = self.buffers.as_mut().filter(|b| b.made_for == key) {
            if buffers.sorted_queues == sort {
                return true;
            }
            // The sort's trial or decision changed what the queues hold: only they are made again.
            let Some(queues) = make_queues(ctx, buffers.pixels * buffers.samples_per_wave, sort)
            else {
                tracing::warn!("the wavefront's queues do not fit the GPU's memory");
                return false;
            };
            buffers.view_group = view_group(ctx, &self.view_layout, view, &buffers.state, &queues);
            buffers.queues = queues;
            buffers.sorted_queues = sort;
            return true;
        }
        if self.no_room == Some(key) {
            return false;
        }
        // Release the old state before making the new one.
        self.buffers = None;
        self.buffers = halving_until(wanted, |samples| {
            let made = self.make_buffers(ctx, view, samples, key, sort);
            if made.is_none() {
                tracing::warn!(
                    "the wavefront's path state for {samples} samples of {pixels} pixels a wave ({} MB) does not \
                     fit the GPU's memory",
                    (pixels * samples * PATH_BYTES) >> 20
                );
            }
            made
        });
        self.no_room = self.buffers.is_none().then_some(key);
        self.buffers.is_some()
    }

    /// The paths' state for waves of `samples` samples of each pixel, or `None` where the GPU's memory cannot
    /// hold it.
    fn make_buffers(
        &self,
        ctx: &GpuContext,
        view: &ViewTargets,
        samples_per_wave: u64,
        made_for: (u64, u64),
        sort: bool,
    ) -> Option<PathBuffers> {
        let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let pixels = view.pixels();
        let paths = pixels * samples_per_wave;
        let arrays = |labels: &[&str]| -> Vec<wgpu::Buffer> {
            labels
                .iter()
                .map(|label| storage_buffer(ctx, label, paths * STATE_ENTRY))
                .collect()
        };
        let states = arrays(&[
            "wavefront path origin",
            "wavefront path direction",
            "wavefront path throughput",
            "wavefront path vertex",
            "wavefront path normal",
            "wavefront path radiance",
            "wavefront hits",
        ]);
        let queues = queues_buffer(ctx, paths, sort);
        let shadows = storage_buffer(ctx, "wavefront shadow rays", paths * SHADOW_ENTRY);
        let args = ctx.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("wavefront dispatch sizes"),
            size: 48,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT,
            mapped_at_creation: false,
        });
        // Before the bind groups, which would raise a validation error for a buffer that could not be made.
        if pollster::block_on(scope.pop()).is_some() {
            return None;
        }
        let state: Vec<wgpu::Buffer> = states.into_iter().chain([shadows]).collect();
        let view_group = view_group(ctx, &self.view_layout, view, &state, &queues);
        let args_group = bind_group(ctx, "wavefront dispatch sizes", &self.args_layout, &[&args]);
        Some(PathBuffers {
            pixels,
            samples_per_wave,
            made_for,
            view_group,
            queues,
            sorted_queues: sort,
            args_group,
            args,
            state,
        })
    }

    /// Records the pass (after [`Self::prepare`] for this view, `spp` and `sort`): `spp` samples per pixel in
    /// waves of the prepared samples per pixel, each `max_depth + 1` bounces, in one compute pass, each bounce's
    /// rays sorted where `sort`. The view's frame uniform must hold this dispatch's constants; its ray counter
    /// gets the rays traced.
    pub fn encode(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        scene: &wgpu::BindGroup,
        view: &ViewTargets,
        (spp, max_depth): (u32, u32),
        sort: bool,
        timestamp_writes: Option<wgpu::ComputePassTimestampWrites>,
    ) {
        let buffers = self
            .buffers
            .as_ref()
            .expect("WavefrontPass::prepare ran for this view");
        debug_assert_eq!(buffers.pixels, view.pixels());
        let needs = self.needs;
        fn compiled(k: &LobeKernels, needs: KernelNeeds) -> &wgpu::ComputePipeline {
            k.compiled(needs)
                .expect("WavefrontPass::prepare compiled this kernel")
        }
        let pipeline = |k| compiled(k, needs);
        let k = &self.kernels;
        encoder.clear_buffer(&buffers.queues, 0, Some(CONTROL_BYTES));
        // The kernels with or without the pass-throughs of alpha-blended surfaces, sorting or not.
        let (passing, sorted) = (self.needs.materials.alpha_blend as usize, sort as usize);
        let extend = if self.refilling() {
            (
                pipeline(&k.extend_refill[sorted][passing]),
                Step::Indirect(REFILL_ARGS),
            )
        } else {
            (pipeline(&k.extend[sorted][passing]), Step::Indirect(0))
        };
        let (x, y) = view.workgroups();
        let samples_per_wave = buffers.samples_per_wave as u32;
        // After a shading kernel: the next bounce's counts, and where the rays are sorted, the sort (its
        // scatter sized like the shading kernel, by the paths queued).
        let mut advance = vec![(pipeline(&k.advance), Step::Direct(1, 1, 1))];
        if sort {
            advance.push((pipeline(&k.sort_prefix), Step::Direct(SORT_BLOCKS, 1, 1)));
            advance.push((pipeline(&k.sort_scatter), Step::Indirect(12)));
        }
        // A wave's dispatches by stage (the stages `RAYKIN_WAVE_PROFILE` times apart).
        let mut first = vec![
            (pipeline(&k.begin_wave), Step::Direct(1, 1, 1)),
            (
                pipeline(&k.first_bounce[sorted][passing]),
                Step::Direct(x, y, samples_per_wave),
            ),
        ];
        first.extend(advance.iter().copied());
        let mut stages = vec![first];
        for _ in 1..=max_depth {
            stages.push(vec![extend]);
            let mut shade = vec![(pipeline(&k.shade[sorted]), Step::Indirect(12))];
            shade.extend(advance.iter().copied());
            stages.push(shade);
        }
        // The last bounce's shadow rays, then the wave's radiance into the accumulation.
        stages.push(vec![extend]);
        stages.push(vec![(pipeline(&k.finish), Step::Direct(x, y, 1))]);
        let waves = spp.div_ceil(samples_per_wave);
        let profile = self
            .profile
            .as_ref()
            .filter(|_| stages.len() as u32 <= WaveProfile::PAIRS);
        // One compute pass running `stages` `waves` times over.
        let mut run = |stages: &[Vec<(&wgpu::ComputePipeline, Step)>], waves: u32, writes| {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("wavefront trace"),
                timestamp_writes: writes,
            });
            pass.set_bind_group(0, scene, &[]);
            pass.set_bind_group(1, &buffers.view_group, &[]);
            pass.set_bind_group(2, &buffers.args_group, &[]);
            for &(kernel, step) in (0..waves).flat_map(|_| stages.iter().flatten()) {
                pass.set_pipeline(kernel);
                match step {
                    Step::Direct(x, y, z) => pass.dispatch_workgroups(x, y, z),
                    Step::Indirect(offset) => {
                        pass.dispatch_workgroups_indirect(&buffers.args, offset)
                    }
                }
            }
        };
        match profile {
            // The first wave one pass per stage, each timed; the trace pass's own timestamps are left out.
            Some(p) => {
                for (i, stage) in stages.iter().enumerate() {
                    run(
                        std::slice::from_ref(stage),
                        1,
                        Some(p.timestamps.pass_writes(i as u32)),
                    );
                }
                if waves > 1 {
                    run(&stages, waves - 1, None);
                }
                p.timestamps.resolve(encoder, stages.len() as u32);
                if let Ok(mut pending) = p.pending.lock() {
                    *pending = Some((max_depth, waves));
                }
            }
            None => run(&stages, waves, timestamp_writes),
        }
        encoder.clear_buffer(&view.ray_counter, 0, None);
        encoder.copy_buffer_to_buffer(
            &buffers.queues,
            WAVE_CONTROL_RAYS as u64 * 4,
            &view.ray_counter,
            0,
            4,
        );
    }
}

/// The counters and queues for `paths` paths, with the sort's entries where `sort`.
fn queues_buffer(ctx: &GpuContext, paths: u64, sort: bool) -> wgpu::Buffer {
    let bytes = CONTROL_BYTES + queue_entries(sort) * paths * QUEUE_ENTRY;
    storage_buffer(ctx, "wavefront queues", bytes)
}

/// [`queues_buffer`], or `None` where the GPU's memory cannot hold it.
fn make_queues(ctx: &GpuContext, paths: u64, sort: bool) -> Option<wgpu::Buffer> {
    let scope = ctx.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
    let queues = queues_buffer(ctx, paths, sort);
    pollster::block_on(scope.pop()).is_none().then_some(queues)
}

/// Group 1 of the wave kernels: the view's frame and accumulation, `state` (the path arrays and hits, then the
/// shadow rays) with `queues` before the shadow rays.
fn view_group(
    ctx: &GpuContext,
    layout: &wgpu::BindGroupLayout,
    view: &ViewTargets,
    state: &[wgpu::Buffer],
    queues: &wgpu::Buffer,
) -> wgpu::BindGroup {
    let (shadows, arrays) = state.split_last().expect("path state and shadow rays");
    let mut group: Vec<&wgpu::Buffer> = vec![&view.frame, &view.accum];
    group.extend(arrays);
    group.push(queues);
    group.push(shadows);
    bind_group(ctx, "wavefront view", layout, &group)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn waves_shrink_by_halves_until_their_state_fits() {
        let mut tried = Vec::new();
        let made = halving_until(16, |samples| {
            tried.push(samples);
            (samples <= 3).then_some(samples)
        });
        assert_eq!((made, tried), (Some(2), vec![16, 8, 4, 2]));
        let mut tried = Vec::new();
        let none: Option<u64> = halving_until(5, |samples| {
            tried.push(samples);
            None
        });
        assert_eq!((none, tried), (None, vec![5, 2, 1]));
        assert_eq!(halving_until(0, Some), Some(1));
    }
}
