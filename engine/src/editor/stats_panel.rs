//! Frame statistics: rate, CPU phase and GPU pass times, rays per second, accumulation, BVH refit/rebuild
//! counters and GPU memory.

use super::ViewerStats;
use crate::bvh::refit::BvhStats;
use crate::frame_timing::FrameTimings;
use crate::gpu::GpuContext;
use crate::render::integrator_choice::IntegratorChoice;
use crate::render::{Accumulation, GpuScene, Integrator, RenderSettings, ViewTargets};
use bevy_ecs::prelude::*;

fn mib(bytes: u64) -> String {
    format!("{:.1} MiB", bytes as f64 / 1048576.0)
}

/// The form that traces the frames and, under `Auto`, why.
fn integrator_line(world: &World) -> String {
    let Some(choice) = world.get_resource::<IntegratorChoice>() else {
        return "-".into();
    };
    let requested = world.resource::<RenderSettings>().integrator;
    let form = choice.last_form_name().unwrap_or_else(|| "-".into());
    match (requested, choice.decision()) {
        (Integrator::Auto, Some(d)) => format!(
            "{form} (auto: megakernel {:.2} ms, wavefront {:.2} ms per frame{})",
            d.megakernel_ms,
            d.wavefront_ms,
            choice.sort_decision().map_or(String::new(), |s| format!(
                "; rays unsorted {:.2} ms, sorted {:.2} ms",
                s.unsorted_ms, s.sorted_ms
            ))
        ),
        (Integrator::Auto, None) if choice.trials() => format!("{form} (auto: timing both forms)"),
        (Integrator::Auto, None) => {
            format!("{form} (auto: untimed on this adapter)")
        }
        _ => form.to_string(),
    }
}

pub fn show(ui: &mut egui::Ui, world: &mut World) {
    let stats = world.resource::<ViewerStats>().clone();
    let phases = world.resource::<FrameTimings>().last;
    let ctx = world.resource::<GpuContext>();
    let (adapter, timestamps) = (ctx.info.name.clone(), ctx.supports_timestamps());
    let cpu_adapter = ctx.info.device_type == wgpu::DeviceType::Cpu;
    let view = world.resource::<ViewTargets>();
    let samples = world.resource::<Accumulation>().samples;
    let bvh = world.resource::<BvhStats>();
    egui::Grid::new("stats").num_columns(2).show(ui, |ui| {
        ui.label("frame");
        ui.label(format!("{:.1} fps, {:.1} ms", stats.fps, stats.frame_ms));
        ui.end_row();
        ui.label("samples");
        ui.label(format!(
            "{} spp at {}x{}",
            samples, view.width, view.height
        ));
        ui.end_row();
        ui.label("CPU ms");
        ui.add(
            egui::Label::new(format!(
                "animate {:.2}, transform {:.2}, deform {:.2}, BVH {:.2}, upload {:.2}, submit {:.2}, UI {:.2}",
                phases.animate_ms,
                phases.transform_ms,
                phases.deform_ms,
                phases.bvh_ms,
                phases.upload_ms,
                phases.render_ms,
                stats.ui_ms
            ))
            .wrap(),
        );
        ui.end_row();
        ui.label("GPU ms");
        match stats.last_gpu.and_then(|g| g.passes) {
            Some(p) => ui.add(
                egui::Label::new(format!(
                    "{}trace {:.2}, tonemap {:.3}{}{}{}",
                    if p.gbuffer_ms > 0.0 {
                        format!(
                            "G-buffer {:.3}, ReSTIR {:.3}, gradients {:.3}, temporal {:.3}, ",
                            p.gbuffer_ms, p.restir_ms, p.gradient_ms, p.temporal_ms
                        )
                    } else {
                        String::new()
                    },
                    p.trace_ms,
                    p.tonemap_ms,
                    if p.denoise_ms > 0.0 {
                        format!(", denoise {:.3}", p.denoise_ms)
                    } else {
                        String::new()
                    },
                    stats
                        .ui_gpu_ms
                        .map_or(String::new(), |u| format!(", UI {u:.3}")),
                    if cpu_adapter {
                        " (CPU adapter: its timestamps can miss compute work)"
                    } else {
                        ""
                    }
                ))
                .wrap(),
            ),
            None if timestamps => ui.label("waiting for the first frame"),
            None => ui.label("n/a: the adapter has no timestamp queries"),
        };
        ui.end_row();
        ui.label("integrator");
        ui.add(egui::Label::new(integrator_line(world)).wrap());
        ui.end_row();
        ui.label("rays/s");
        ui.label(stats.rays_per_second.map_or("-".into(), |r| {
            format!("{:.2} M", r / 1e6)
        }));
        ui.end_row();
        ui.label("BVH");
        let worst = bvh.sah_ratio.iter().copied().fold(1.0f32, f32::max);
        ui.add(
            egui::Label::new(format!(
                "{} refits, {} rebuilds, worst SAH ratio {:.2}",
                bvh.refits, bvh.rebuilds, worst
            ))
            .wrap(),
        );
        ui.end_row();
        let memory = world.resource::<GpuScene>().memory;
        let realtime = world
            .get_resource::<crate::render::realtime::Realtime>()
            .map_or(0, |r| {
                r.targets.as_ref().map_or(0, |t| t.memory_bytes())
                    + r.spatial_filter.as_ref().map_or(0, |f| f.memory_bytes())
                    + r.external_image.as_ref().map_or(0, wgpu::Buffer::size)
            });
        ui.label("GPU memory");
        ui.add(
            egui::Label::new(format!(
                "{} geometry+BVH, {} textures, {} total{}",
                mib(memory.geometry_and_bvh()),
                mib(memory.texels),
                mib(memory.total()),
                if realtime + memory.motion > 0 {
                    format!(", real-time path {}", mib(realtime + memory.motion))
                } else {
                    String::new()
                }
            ))
            .wrap(),
        );
        ui.end_row();
        ui.label("adapter");
        ui.add(egui::Label::new(adapter).wrap());
        ui.end_row();
    });
}
