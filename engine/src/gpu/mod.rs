//! The wgpu device: one adapter picked at start-up, shared by every plugin as a resource.

pub mod bind;
pub mod external_memory;
pub mod limits;
mod pipeline_cache;
pub mod readback;
pub mod specialize;
mod timestamps;

pub use pipeline_cache::PipelineCache;
pub use timestamps::PassTimestamps;

use bevy_ecs::prelude::Resource;
use std::sync::Arc;
pub use wgpu::DeviceType;

/// What a user with no usable GPU driver should do.
pub const NO_ADAPTER_HELP: &str = "no GPU adapter found (wgpu saw no Vulkan, Metal or DX12 device). \
On a machine without a GPU install Mesa's software Vulkan driver (lavapipe): \
`sudo apt-get install -y mesa-vulkan-drivers libvulkan1` on Debian/Ubuntu; \
with a GPU, install its vendor driver. WGPU_BACKEND=vulkan|metal|dx12 picks a backend.";

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error("{NO_ADAPTER_HELP}")]
    NoAdapter,
    #[error("the GPU adapter `{adapter}` refused a device: {source}")]
    Device {
        adapter: String,
        source: wgpu::RequestDeviceError,
    },
    #[error(
        "the GPU adapter `{adapter}` ({backend}) binds {available} storage buffers per shader stage; raykin's \
         kernels need {MIN_STORAGE_BUFFERS_PER_STAGE}. Install a Vulkan driver (Debian: mesa-vulkan-drivers) \
         or pick another adapter with WGPU_ADAPTER_NAME"
    )]
    TooFewStorageBuffers {
        adapter: String,
        backend: String,
        available: u32,
    },
}

/// The most storage buffers one of raykin's kernels binds in its stage (ReSTIR DI's: scene 14, its own 8 with
/// its two parameter buffers, motion 5; GPUs bind those two as uniforms). Below this (a GL driver offers 16, and
/// wgpu is built without GL for that reason) pipeline creation would panic deep in the first frame; refusing the
/// adapter here names the cause instead.
/// A test compiles every kernel and checks the figure.
pub const MIN_STORAGE_BUFFERS_PER_STAGE: u32 = 27;

/// The device and queue every GPU pass uses, plus what the adapter can do.
#[derive(Resource, Clone)]
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: Arc<wgpu::Adapter>,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    pub features: wgpu::Features,
    /// Kernels and bind-group layouts compiled on this device, shared by every renderer.
    pub pipelines: PipelineCache,
    /// Compute passes read their parameters (`var<uniform>` in the WGSL, [`bind::Binding::Params`]) from
    /// read-only storage buffers instead of uniforms: set on CPU adapters. lavapipe specialises a kernel on the
    /// values of uniforms that decide branches and loop counts and compiles it again (tens of seconds for the path
    /// tracer) for every new image size, depth or camera; storage buffers are never specialised. GPUs keep
    /// uniforms (the constant bank): storage parameters made the H200's trace kernel up to 13% slower.
    pub params_in_storage: bool,
    /// Kernels read the scene's buffers through read-only storage textures (`shaders/scene/bindings_texels.wgsl`,
    /// copied by `render::scene_texels`): set on CPU adapters, where lavapipe compiles every storage-buffer load
    /// into a loop over its SIMD lanes and a texel load into straight-line code. `RAYKIN_SCENE_READS=buffers|
    /// textures` overrides the choice (kernel development and A/B runs).
    pub scene_in_textures: bool,
    /// The trace pass runs a pixel's samples in one path loop, starting the next sample as soon as a path ends
    /// (`PATH_REGENERATION` in `shaders/integrator/path.wgsl`): set on CPU adapters, where lavapipe runs eight
    /// invocations as one masked vector and each lane otherwise waits for the longest path of the eight.
    /// `RAYKIN_PATH_REGENERATION=on|off` overrides (A/B runs).
    pub path_regeneration: bool,
    /// The trace pass spreads a dispatch's samples of a pixel over up to 16 invocations of one workgroup and adds
    /// their sums in workgroup memory (`passes::trace::sample_lanes`): set on GPUs. A pixel's samples looped in
    /// one invocation leave a small view's last warps running long after the rest have finished (FlightHelmet at
    /// 960x540 and 16 samples per dispatch took 2.3x the time per sample of 1080p at one). Never with
    /// `path_regeneration`, whose loop takes all of a pixel's samples. `RAYKIN_SAMPLE_LANES=on|off` overrides
    /// (A/B runs).
    pub sample_lanes: bool,
    /// The trace kernels are compiled for the scene's shape ([`crate::render::material_lobes::KernelNeeds`]):
    /// traversal starts in the top level's one leaf where it has one (`SOLE_INSTANCE`) and holds only the BLAS
    /// layouts the leaves use (`BLAS_LAYOUTS`, both in `shaders/traversal/tlas.wgsl`), and the environment's
    /// in-cell bilinear sampling only where a map uses it (`ENVIRONMENT_BILINEAR`). On by default;
    /// `RAYKIN_SCENE_SHAPE_KERNELS=off` keeps the general kernel (A/B runs).
    pub scene_shape_kernels: bool,
    /// The waves traverse a wide top-level tree built beside the BVH2 (`crate::bvh::tlas`) where the scene has
    /// more than one top-level leaf. On by default; `RAYKIN_WIDE_TOP_LEVEL=off` keeps the BVH2 (A/B runs).
    pub wide_top_level: bool,
    /// Deforming meshes get a wide tree collapsed from their BVH2 and refit with it (`crate::bvh::wide_refit`),
    /// which every kernel traverses instead of the BVH2. On by default; `RAYKIN_WIDE_DEFORMED=off` keeps the
    /// BVH2 (A/B runs).
    pub wide_deformed: bool,
    /// The waves' extend stage as a fixed grid of at most this many workgroups whose invocations start their
    /// next ray inside the traversal loop (`shaders/traversal/refill.wgsl`), where the scene's shape allows it;
    /// `None`: one ray an invocation. On by default on GPUs (measured faster under auto on every bench scene whose
    /// waves trace, docs/BENCHMARKS.md); CPU adapters, which trace waves only when asked, keep one ray an
    /// invocation (unmeasured there). `RAYKIN_WAVE_REFILL=on|off` and `RAYKIN_WAVE_REFILL_GROUPS=N` (A/B runs).
    pub wave_refill: Option<u32>,
    /// The staging buffer of the last readback, kept for the next: allocating (and on discrete GPUs pinning)
    /// host memory for every readback cost more than the copy.
    readback_staging: Arc<std::sync::Mutex<Option<wgpu::Buffer>>>,
}

/// wgpu's instance flags as a release build sets them, whatever the build, then `WGPU_DEBUG`, `WGPU_VALIDATION`
/// and the like from the environment. A debug build would otherwise turn on Vulkan's validation layer wherever it
/// is installed (the set-up installs it for the tests, which ask for it where they mean to) and write shader debug
/// information that Debian 12's layer misreads.
pub fn instance_flags() -> wgpu::InstanceFlags {
    wgpu::InstanceFlags::VALIDATION_INDIRECT_CALL.with_env()
}

impl GpuContext {
    /// Picks the highest-performance adapter (WGPU_BACKEND and WGPU_ADAPTER_NAME are honoured) and opens a
    /// device with the adapter's own limits: the path tracer binds more storage buffers than wgpu's defaults.
    /// wgpu is built without its GL backend: a GL adapter binds 16 storage buffers per stage, too few for the
    /// trace kernel ([`MIN_STORAGE_BUFFERS_PER_STAGE`]).
    pub fn new_headless() -> Result<Self, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            flags: instance_flags(),
            ..wgpu::InstanceDescriptor::new_without_display_handle_from_env()
        });
        Self::from_instance(&instance, None)
    }

    pub fn from_instance(
        instance: &wgpu::Instance,
        surface: Option<&wgpu::Surface<'_>>,
    ) -> Result<Self, GpuError> {
        let adapter = pollster::block_on(wgpu::util::initialize_adapter_from_env_or_default(
            instance, surface,
        ))
        .map_err(|_| GpuError::NoAdapter)?;
        let info = adapter.get_info();
        let wanted = wgpu::Features::TIMESTAMP_QUERY
            | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS
            | wgpu::Features::SUBGROUP
            // OIDN's GPU device reads the accumulation from memory it imports (external_memory.rs).
            | wgpu::Features::VULKAN_EXTERNAL_MEMORY_FD;
        let features = adapter.features() & wanted;
        let limits = adapter.limits();
        if limits.max_storage_buffers_per_shader_stage < MIN_STORAGE_BUFFERS_PER_STAGE {
            return Err(GpuError::TooFewStorageBuffers {
                adapter: info.name.clone(),
                backend: format!("{:?}", info.backend),
                available: limits.max_storage_buffers_per_shader_stage,
            });
        }
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("raykin"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        }))
        .map_err(|source| GpuError::Device {
            adapter: info.name.clone(),
            source,
        })?;
        Ok(Self {
            pipelines: PipelineCache::new(device.clone()),
            params_in_storage: info.device_type == wgpu::DeviceType::Cpu,
            scene_in_textures: scene_in_textures_on(&info, &limits),
            path_regeneration: path_regeneration_on(&info),
            sample_lanes: switch_on(
                "RAYKIN_SAMPLE_LANES",
                info.device_type != wgpu::DeviceType::Cpu,
            ),
            scene_shape_kernels: switch_on("RAYKIN_SCENE_SHAPE_KERNELS", true),
            wide_top_level: switch_on("RAYKIN_WIDE_TOP_LEVEL", true),
            wide_deformed: switch_on("RAYKIN_WIDE_DEFORMED", true),
            wave_refill: switch_on(
                "RAYKIN_WAVE_REFILL",
                info.device_type != wgpu::DeviceType::Cpu,
            )
            .then(|| {
                number_from_env("RAYKIN_WAVE_REFILL_GROUPS", WAVE_REFILL_GROUPS).clamp(1, 32768)
                    as u32
            }),
            readback_staging: Arc::default(),
            device,
            queue,
            adapter: Arc::new(adapter),
            info,
            limits,
            features,
        })
    }

    /// One line for logs and the start-up banner: name, backend, device type, driver.
    pub fn describe(&self) -> String {
        format!(
            "{} ({:?}, {:?}, driver {} {})",
            self.info.name,
            self.info.backend,
            self.info.device_type,
            self.info.driver,
            self.info.driver_info
        )
    }

    /// How a [`bind::Binding::Params`] buffer is bound on this adapter.
    pub fn params_binding_type(&self) -> wgpu::BufferBindingType {
        if self.params_in_storage {
            wgpu::BufferBindingType::Storage { read_only: true }
        } else {
            wgpu::BufferBindingType::Uniform
        }
    }

    /// The offset alignment of parameter records bound with dynamic offsets (either binding type).
    pub fn params_offset_alignment(&self) -> u64 {
        self.limits
            .min_uniform_buffer_offset_alignment
            .max(self.limits.min_storage_buffer_offset_alignment) as u64
    }

    pub fn supports_timestamps(&self) -> bool {
        self.features.contains(wgpu::Features::TIMESTAMP_QUERY)
    }

    /// Blocks until the GPU has finished all submitted work.
    pub fn wait_idle(&self) {
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }

    /// Copies `size` bytes of `src` to the CPU (blocking).
    pub fn read_buffer(&self, src: &wgpu::Buffer, size: u64) -> Vec<u8> {
        self.read_buffer_range(src, 0, size)
    }

    /// Copies the whole of each buffer, back to back, into one staging buffer (one submission, one wait) and
    /// hands the mapped bytes to `read`, which sees them in place (no copy; wgpu maps at 8-byte alignment at
    /// least, so `[f32; 4]` sums cast without one).
    pub fn read_buffers_with<R>(
        &self,
        sources: &[&wgpu::Buffer],
        read: impl FnOnce(&[u8]) -> R,
    ) -> R {
        let ranges: Vec<_> = sources.iter().map(|b| (*b, 0, b.size())).collect();
        self.read_ranges_with(&ranges, read)
    }

    /// Copies `size` bytes of `src` from `offset` to the CPU (blocking).
    pub fn read_buffer_range(&self, src: &wgpu::Buffer, offset: u64, size: u64) -> Vec<u8> {
        self.read_ranges_with(&[(src, offset, size)], <[u8]>::to_vec)
    }

    fn kept_staging(&self) -> std::sync::MutexGuard<'_, Option<wgpu::Buffer>> {
        self.readback_staging
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
    }

    /// The readback behind the two above: each (buffer, offset, size) range copied, back to back, into one
    /// staging buffer, one submission, one wait, and `read` called on the mapped bytes.
    fn read_ranges_with<R>(
        &self,
        ranges: &[(&wgpu::Buffer, u64, u64)],
        read: impl FnOnce(&[u8]) -> R,
    ) -> R {
        let start = std::time::Instant::now();
        let size: u64 = ranges.iter().map(|r| r.2).sum();
        // A mapped slice may not be empty.
        let staging_size = size.max(wgpu::COPY_BUFFER_ALIGNMENT);
        // Taken out of the cache (not locked across the wait): a concurrent readback makes its own.
        let kept = self.kept_staging().take();
        let staging = match kept {
            Some(b) if b.size() >= staging_size => b,
            _ => self.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("readback"),
                size: staging_size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        };
        let mut encoder = self.device.create_command_encoder(&Default::default());
        let mut at = 0;
        for &(src, offset, size) in ranges {
            encoder.copy_buffer_to_buffer(src, offset, &staging, at, size);
            at += size;
        }
        let created = start.elapsed();
        self.queue.submit([encoder.finish()]);
        let slice = staging.slice(..staging_size);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        self.wait_idle();
        let mapped_at = start.elapsed();
        let result = {
            let mapped = slice
                .get_mapped_range()
                .expect("readback buffer was mapped above");
            read(&mapped[..size as usize])
        };
        staging.unmap();
        // Kept unless a concurrent readback put back a larger one.
        let mut kept = self.kept_staging();
        if kept.as_ref().is_none_or(|b| b.size() < staging.size()) {
            *kept = Some(staging);
        }
        drop(kept);
        tracing::debug!(
            "readback of {:.1} MiB: staging buffer {:.2} ms, copy and map {:.2} ms, read {:.2} ms",
            size as f64 / 1048576.0,
            created.as_secs_f64() * 1e3,
            (mapped_at - created).as_secs_f64() * 1e3,
            (start.elapsed() - mapped_at).as_secs_f64() * 1e3
        );
        result
    }
}

/// A compute pipeline from one WGSL module and its bind group layouts; `label` names the module, layout and
/// pipeline. Public for kernels outside the renderer's passes (tests probing the WGSL library).
pub fn compute_pipeline(
    ctx: &GpuContext,
    label: &str,
    source: String,
    layouts: &[Option<&wgpu::BindGroupLayout>],
    entry: &str,
) -> wgpu::ComputePipeline {
    let [pipeline] = compute_pipelines(ctx, label, source, layouts, [entry]);
    pipeline
}

/// One pipeline per entry point of one module, over the same layouts.
pub(crate) fn compute_pipelines<const N: usize>(
    ctx: &GpuContext,
    label: &str,
    source: String,
    layouts: &[Option<&wgpu::BindGroupLayout>],
    entries: [&str; N],
) -> [wgpu::ComputePipeline; N] {
    let module = ComputeModule::new(ctx, source, layouts);
    entries.map(|entry| module.pipeline(if N == 1 { label } else { entry }, entry, &[]))
}

/// `source` with its parameters (`var<uniform>`) read from storage buffers, as kernels run on CPU adapters
/// ([`GpuContext::params_in_storage`]); the naga test validates both forms of every kernel.
pub fn params_in_storage(source: &str) -> String {
    source.replace("var<uniform>", "var<storage, read>")
}

/// Storage textures a kernel binds when it reads the scene through textures (one per scene buffer).
pub const SCENE_TEXTURES: u32 = 14;

/// Whether kernels on this adapter read the scene through textures ([`GpuContext::scene_in_textures`]): CPU
/// adapters that bind enough storage textures.
fn scene_in_textures_on(info: &wgpu::AdapterInfo, limits: &wgpu::Limits) -> bool {
    let fits = limits.max_storage_textures_per_shader_stage >= SCENE_TEXTURES;
    let cpu = info.device_type == wgpu::DeviceType::Cpu;
    match std::env::var("RAYKIN_SCENE_READS").as_deref() {
        Ok("textures") => fits,
        Ok("buffers") => false,
        Ok(other) => {
            tracing::warn!(
                "RAYKIN_SCENE_READS={other} is neither `buffers` nor `textures`; ignored"
            );
            fits && cpu
        }
        Err(_) => fits && cpu,
    }
}

/// Whether the trace pass regenerates paths on this adapter ([`GpuContext::path_regeneration`]).
fn path_regeneration_on(info: &wgpu::AdapterInfo) -> bool {
    switch_on(
        "RAYKIN_PATH_REGENERATION",
        info.device_type == wgpu::DeviceType::Cpu,
    )
}

/// Workgroups of 128 invocations the waves' extend with refill runs at most: on an H100 4096 was the fastest of
/// 1024-32768 on the seed-like interior, the crowd and the static scenes the waves trace, or within 0.2% of it
/// (docs/BENCHMARKS.md, "The waves' extend with refill"); a GPU that holds fewer at once runs the rest as
/// further rounds of whole strides.
const WAVE_REFILL_GROUPS: u64 = 4096;

/// A number from the environment variable `name` (A/B runs of a tuning constant), else `default`.
pub(crate) fn number_from_env(name: &str, default: u64) -> u64 {
    match std::env::var(name) {
        Ok(v) => v.parse().unwrap_or_else(|_| {
            tracing::warn!("{name}={v} is not a number; ignored");
            default
        }),
        Err(_) => default,
    }
}

/// An `on|off` environment switch of a kernel form (A/B runs), else `default`.
pub(crate) fn switch_on(name: &str, default: bool) -> bool {
    match std::env::var(name).as_deref() {
        Ok("on") => true,
        Ok("off") => false,
        Ok(other) => {
            tracing::warn!("{name}={other} is neither `on` nor `off`; ignored");
            default
        }
        Err(_) => default,
    }
}

/// The scene module of composed kernels (`render::shaders::compose` heads each module with this line).
const SCENE_BINDINGS_HEADER: &str = "// ---- scene/bindings.wgsl ----\n";
/// The scene module as CPU adapters read it.
const SCENE_BINDINGS_TEXELS: &str = include_str!("../../../shaders/scene/bindings_texels.wgsl");

/// `source` with the scene read from textures ([`GpuContext::scene_in_textures`]): the composed
/// `scene/bindings.wgsl` module is replaced by `scene/bindings_texels.wgsl`, which declares the same bindings as
/// textures and defines the same `read_*` functions. Kernels without the scene module are returned unchanged.
/// The naga test validates this form of every kernel.
pub fn scene_in_textures(source: &str) -> String {
    let Some(start) = source.find(SCENE_BINDINGS_HEADER) else {
        return source.to_string();
    };
    let body = start + SCENE_BINDINGS_HEADER.len();
    let end = source[body..]
        .find("\n// ---- ")
        .map_or(source.len(), |i| body + i + 1);
    // Kernel development, as for the library's modules: `$RAYKIN_SHADER_DIR/scene/bindings_texels.wgsl`.
    let texels = std::env::var_os("RAYKIN_SHADER_DIR")
        .and_then(|dir| {
            std::fs::read_to_string(std::path::Path::new(&dir).join("scene/bindings_texels.wgsl"))
                .ok()
        })
        .unwrap_or_else(|| SCENE_BINDINGS_TEXELS.to_string());
    format!(
        "{}{SCENE_BINDINGS_HEADER}{texels}\n{}",
        &source[..start],
        &source[end..]
    )
}

/// One WGSL module over its bind group layouts, from which pipelines are compiled: per entry point, and per
/// set of values of its pipeline-overridable constants. Compiled pipelines come from (and go to) the device's
/// [`PipelineCache`].
pub(crate) struct ComputeModule {
    cache: PipelineCache,
    source: Arc<str>,
    layouts: Vec<Option<wgpu::BindGroupLayout>>,
}

impl ComputeModule {
    pub fn new(
        ctx: &GpuContext,
        source: String,
        layouts: &[Option<&wgpu::BindGroupLayout>],
    ) -> Self {
        let source = if ctx.params_in_storage {
            params_in_storage(&source)
        } else {
            source
        };
        let source = if ctx.scene_in_textures {
            scene_in_textures(&source)
        } else {
            source
        };
        Self {
            cache: ctx.pipelines.clone(),
            source: source.into(),
            layouts: layouts.iter().map(|l| l.cloned()).collect(),
        }
    }

    pub fn pipeline(
        &self,
        label: &str,
        entry: &str,
        constants: &[(&str, f64)],
    ) -> wgpu::ComputePipeline {
        let layouts: Vec<_> = self.layouts.iter().map(Option::as_ref).collect();
        self.cache
            .compute_pipeline(label, &self.source, &layouts, entry, constants)
    }
}
