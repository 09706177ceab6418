//! Kernels compiled once per device and shared by every renderer on it. Building a pipeline is the costly step
//! of creating a renderer (on lavapipe 0.09 s for the path tracer once specialised, `gpu::specialize`, 0.5 s
//! without, and 0.7 s more of LLVM where Mesa's disk cache has not seen it); a viewer that opens another scene, a
//! bench that renders several, or a test binary with hundreds of renderers reuses what an earlier renderer
//! compiled.
//!
//! Bind-group layouts are shared as well, so that a pipeline built against one renderer's layouts is keyed by
//! layouts that later renderers receive again (wgpu compares a pipeline's layouts with a bind group's by
//! identity). Everything is keyed by its full description, source text included: a different kernel or layout is
//! never mistaken for a cached one. Entries live as long as the device; their number is bounded by the kernels
//! and pipeline constants the engine has (a few dozen).

use super::specialize;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, PoisonError};

#[derive(Clone)]
pub struct PipelineCache {
    device: wgpu::Device,
    entries: Arc<Mutex<Entries>>,
    /// Whether pipelines are specialised before wgpu sees them (`gpu::specialize`; `RAYKIN_SPECIALIZE=off`
    /// hands wgpu the WGSL and the constants, for A/B runs).
    specialize: bool,
}

#[derive(Default)]
struct Entries {
    bind_group_layouts: HashMap<(String, Vec<wgpu::BindGroupLayoutEntry>), wgpu::BindGroupLayout>,
    modules: HashMap<ModuleKey, CompiledModule>,
    pipelines: HashMap<PipelineKey, wgpu::ComputePipeline>,
    compiled: usize,
    /// Storage buffers in each layout made here, and the most any compiled pipeline binds in its stage.
    storage_buffers: HashMap<wgpu::BindGroupLayout, u32>,
    most_storage_buffers: u32,
}

/// One WGSL source over one set of bind-group layouts.
#[derive(Clone, PartialEq, Eq, Hash)]
struct ModuleKey {
    source: Arc<str>,
    layouts: Vec<Option<wgpu::BindGroupLayout>>,
}

#[derive(PartialEq, Eq, Hash)]
struct PipelineKey {
    module: ModuleKey,
    entry: String,
    /// Pipeline-overridable constants by name, values as f64 bits.
    constants: Vec<(String, u64)>,
}

struct CompiledModule {
    /// The WGSL as wgpu compiles it, made where a pipeline is not specialised.
    module: Option<wgpu::ShaderModule>,
    layout: wgpu::PipelineLayout,
    /// The WGSL parsed for specialisation (`None`: off, or it did not parse).
    parsed: Option<specialize::ParsedModule>,
}

/// The runtime checks naga writes into the engine's kernels: bounds checks stay (an index read from a buffer is
/// clamped or left to the driver's robust access, as wgpu does by default); the loop bounding and the integer
/// division guards go. Loop bounding wraps every loop in a 64-bit iteration counter that cannot end a real hang,
/// only keeps the driver from assuming termination, at a counter update per iteration of the traversal loops;
/// the division guards select around each integer `/` and `%`.
///
/// # Safety
/// Every loop of the engine's WGSL terminates (traversals over trees the engine built, binary searches, loops
/// with a constant bound) and no integer division has a zero divisor or overflows (divisors are image sizes,
/// counts checked beforehand, or constants): the two conditions `wgpu::ShaderRuntimeChecks` states for these
/// fields. For measurements, `RAYKIN_SHADER_CHECKS=all` compiles with every check (wgpu's default) and
/// `RAYKIN_SHADER_CHECKS=none` without bounds checks too (not safe: a probe of what they cost).
fn engine_shader_checks() -> wgpu::ShaderRuntimeChecks {
    match std::env::var("RAYKIN_SHADER_CHECKS").as_deref() {
        Ok("all") => wgpu::ShaderRuntimeChecks::checked(),
        Ok("none") => wgpu::ShaderRuntimeChecks::unchecked(),
        _ => wgpu::ShaderRuntimeChecks {
            force_loop_bounding: false,
            int_div_checks: false,
            ..wgpu::ShaderRuntimeChecks::checked()
        },
    }
}

impl PipelineCache {
    pub fn new(device: wgpu::Device) -> Self {
        Self {
            device,
            entries: Arc::default(),
            specialize: super::switch_on("RAYKIN_SPECIALIZE", true),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Entries> {
        // A panic while compiling leaves the maps consistent (entries are inserted whole).
        self.entries.lock().unwrap_or_else(PoisonError::into_inner)
    }

    /// The bind-group layout with these entries, created on first request.
    pub fn bind_group_layout(
        &self,
        label: &str,
        entries: &[wgpu::BindGroupLayoutEntry],
    ) -> wgpu::BindGroupLayout {
        let mut cache = self.lock();
        if let Some(layout) = cache
            .bind_group_layouts
            .get(&(label.to_owned(), entries.to_vec()))
        {
            return layout.clone();
        }
        let layout = self
            .device
            .create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries,
            });
        // Storage textures count too: on CPU adapters the scene's read-only storage textures stand in one for
        // one for the storage buffers GPUs bind (`render::scene_texels`), so both forms give one figure.
        let storage = entries
            .iter()
            .filter(|e| {
                matches!(
                    e.ty,
                    wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Storage { .. },
                        ..
                    } | wgpu::BindingType::StorageTexture { .. }
                )
            })
            .count() as u32;
        cache.storage_buffers.insert(layout.clone(), storage);
        cache
            .bind_group_layouts
            .insert((label.to_owned(), entries.to_vec()), layout.clone());
        layout
    }

    /// The compute pipeline for `entry` of `source` over `layouts` with `constants`, compiled on first request.
    /// `label` names the module, layout and pipeline where they are created.
    pub fn compute_pipeline(
        &self,
        label: &str,
        source: &Arc<str>,
        layouts: &[Option<&wgpu::BindGroupLayout>],
        entry: &str,
        constants: &[(&str, f64)],
    ) -> wgpu::ComputePipeline {
        let module_key = ModuleKey {
            source: source.clone(),
            layouts: layouts.iter().map(|l| l.cloned()).collect(),
        };
        let key = PipelineKey {
            module: module_key.clone(),
            entry: entry.to_owned(),
            constants: constants
                .iter()
                .map(|(name, value)| ((*name).to_owned(), value.to_bits()))
                .collect(),
        };
        let mut entries = self.lock();
        if let Some(pipeline) = entries.pipelines.get(&key) {
            return pipeline.clone();
        }
        let module = entries
            .modules
            .entry(module_key)
            .or_insert_with(|| CompiledModule {
                module: None,
                layout: self
                    .device
                    .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                        label: Some(label),
                        bind_group_layouts: layouts,
                        immediate_size: 0,
                    }),
                parsed: self.specialize.then(|| specialize::parse(source)).flatten(),
            });
        let start = std::time::Instant::now();
        let specialized = module.parsed.as_ref().and_then(|parsed| {
            let specialized = specialize::specialize(parsed, entry, constants);
            if specialized.is_none() {
                // The kernel still compiles, with every branch its constants switch off (a bug to report).
                tracing::warn!("pipeline {label} `{entry}` not specialised: compiled from WGSL");
            }
            specialized
        });
        let layout = module.layout.clone();
        let (shader, constants) = match specialized {
            // SAFETY: see `engine_shader_checks`.
            Some(naga_module) => (
                unsafe {
                    self.device.create_shader_module_trusted(
                        wgpu::ShaderModuleDescriptor {
                            label: Some(label),
                            source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(naga_module)),
                        },
                        engine_shader_checks(),
                    )
                },
                &[][..],
            ),
            None => (
                module
                    .module
                    .get_or_insert_with(|| {
                        let descriptor = wgpu::ShaderModuleDescriptor {
                            label: Some(label),
                            source: wgpu::ShaderSource::Wgsl(source.as_ref().into()),
                        };
                        // SAFETY: see `engine_shader_checks`.
                        unsafe {
                            self.device
                                .create_shader_module_trusted(descriptor, engine_shader_checks())
                        }
                    })
                    .clone(),
                constants,
            ),
        };
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(label),
                layout: Some(&layout),
                module: &shader,
                entry_point: Some(entry),
                compilation_options: wgpu::PipelineCompilationOptions {
                    constants,
                    ..Default::default()
                },
                cache: None,
            });
        tracing::debug!(
            "pipeline {label} `{entry}` compiled in {:.1} ms",
            start.elapsed().as_secs_f64() * 1e3
        );
        entries.compiled += 1;
        let storage = layouts
            .iter()
            .flatten()
            .map(|l| entries.storage_buffers.get(*l).copied().unwrap_or(0))
            .sum();
        entries.most_storage_buffers = entries.most_storage_buffers.max(storage);
        entries.pipelines.insert(key, pipeline.clone());
        pipeline
    }

    /// How many pipelines this cache has compiled (each at most once).
    pub fn compiled(&self) -> usize {
        self.lock().compiled
    }

    /// The most storage buffers one compiled pipeline binds (in its one stage), counting the layouts made here;
    /// storage textures count as the buffers they stand in for.
    pub fn most_storage_buffers_per_stage(&self) -> u32 {
        self.lock().most_storage_buffers
    }
}
