//! Render settings: sampling, environment, display transform, AOV view, resolution and frame pacing.

use super::EditorState;
use crate::environment::{MapSettings, SunSkySettings};
use crate::render::{
    AovView, DenoiserKind, Environment, FrameOidn, Integrator, RenderMode, RenderSettings,
    Tonemapper,
};
use bevy_ecs::prelude::*;

pub fn show(ui: &mut egui::Ui, world: &mut World, state: &mut EditorState) {
    let mut s = world.resource::<RenderSettings>().clone();
    let before = s.clone();
    egui::Grid::new("render settings")
        .num_columns(2)
        .show(ui, |ui| {
            ui.label("mode");
            ui.horizontal(|ui| {
                ui.selectable_value(&mut s.mode, RenderMode::Realtime, "real-time")
                    .on_hover_text(
                        "While anything moves: temporal reuse, ReSTIR DI and a spatial filter; a still \
                         hands over to plain accumulation",
                    );
                ui.selectable_value(&mut s.mode, RenderMode::Accumulate, "accumulate")
                    .on_hover_text("Restart accumulation whenever anything moves");
            });
            ui.end_row();
            if s.mode == RenderMode::Realtime {
                realtime_rows(ui, &mut s);
                if let Some(d) = world.get_resource::<crate::render::frame_denoiser::FrameDenoiser>()
                    && s.realtime.oidn != FrameOidn::Off
                    && s.denoiser == DenoiserKind::Oidn
                {
                    ui.label("");
                    ui.label(frame_oidn_status(d));
                    ui.end_row();
                }
            }
            ui.label("samples / frame");
            ui.add(egui::DragValue::new(&mut s.spp_per_frame).range(1..=256));
            ui.end_row();
            ui.label("max depth");
            ui.add(egui::DragValue::new(&mut s.max_depth).range(0..=64));
            ui.end_row();
            ui.label("integrator");
            egui::ComboBox::from_id_salt("integrator")
                .selected_text(format!("{:?}", s.integrator))
                .show_ui(ui, |ui| {
                    for i in [
                        Integrator::Auto,
                        Integrator::Megakernel,
                        Integrator::Wavefront,
                    ] {
                        ui.selectable_value(&mut s.integrator, i, format!("{i:?}"));
                    }
                })
                .response
                .on_hover_text(
                    "How paths are traced; the image is the same. Auto times both forms on the first \
                     frames and keeps the faster (the statistics panel says which).",
                );
            ui.end_row();
            ui.label("stop at spp");
            ui.add(egui::DragValue::new(&mut state.sample_limit).range(0..=1_000_000))
                .on_hover_text("0: keep accumulating");
            ui.end_row();
            environment_rows(ui, &mut s.environment);
            ui.label("exposure (stops)");
            ui.add(egui::Slider::new(&mut s.exposure, -10.0..=10.0));
            ui.end_row();
            ui.label("tone mapper");
            egui::ComboBox::from_id_salt("tonemapper")
                .selected_text(format!("{:?}", s.tonemapper))
                .show_ui(ui, |ui| {
                    for t in [
                        Tonemapper::AcesFitted,
                        Tonemapper::Reinhard,
                        Tonemapper::Clamp,
                    ] {
                        ui.selectable_value(&mut s.tonemapper, t, format!("{t:?}"));
                    }
                });
            ui.end_row();
            ui.label("show");
            egui::ComboBox::from_id_salt("aov")
                .selected_text(format!("{:?}", s.view))
                .show_ui(ui, |ui| {
                    for v in [
                        AovView::Color,
                        AovView::Albedo,
                        AovView::Normal,
                        AovView::Depth,
                    ] {
                        ui.selectable_value(&mut s.view, v, format!("{v:?}"));
                    }
                });
            ui.end_row();
            if s.view == AovView::Depth {
                ui.label("depth falloff");
                ui.add(
                    egui::DragValue::new(&mut s.depth_view_scale)
                        .speed(0.001)
                        .range(0.0..=100.0),
                );
                ui.end_row();
            }
            // Display-side: toggling it keeps the accumulated samples.
            ui.label("denoise");
            ui.horizontal(|ui| {
                ui.checkbox(&mut s.denoise, "");
                if s.denoise {
                    ui.selectable_value(&mut s.denoiser, DenoiserKind::Oidn, "OIDN")
                        .on_hover_text(
                            "Intel Open Image Denoise, once the image is still (svgf while it moves)",
                        );
                    ui.selectable_value(&mut s.denoiser, DenoiserKind::Svgf, "svgf")
                        .on_hover_text("the GPU a-trous filter, every frame");
                }
            });
            ui.end_row();
            if s.denoise && s.denoiser == DenoiserKind::Oidn {
                ui.label("  quality");
                ui.horizontal(|ui| {
                    for q in crate::oidn::Quality::ALL {
                        ui.selectable_value(&mut s.oidn.quality, q, q.name());
                    }
                });
                ui.end_row();
                ui.label("  AOVs");
                ui.horizontal(|ui| {
                    for a in crate::oidn::AuxMode::ALL {
                        ui.selectable_value(&mut s.oidn.aux, a, a.name());
                    }
                })
                .response
                .on_hover_text(
                    "prefilter: denoise albedo and normal first (OIDN's final-frame default); \
                     noisy: use them as they are; clean: trust them as converged",
                );
                ui.end_row();
                if let Some(v) = world.get_resource::<crate::oidn::ViewerOidn>() {
                    ui.label("");
                    ui.label(oidn_status(&v.status));
                    ui.end_row();
                }
            }
            if s.denoise {
                let p = &mut s.denoise_params;
                ui.label("  iterations");
                ui.add(egui::DragValue::new(&mut p.iterations).range(1..=8));
                ui.end_row();
                ui.label("  sigma luminance");
                ui.add(
                    egui::DragValue::new(&mut p.sigma_luminance)
                        .speed(0.05)
                        .range(0.0..=100.0),
                );
                ui.end_row();
            }
            ui.label("next-event estimation");
            ui.checkbox(&mut s.nee, "");
            ui.end_row();
            ui.label("Russian roulette");
            ui.checkbox(&mut s.russian_roulette, "");
            ui.end_row();
            ui.label("seed");
            ui.add(egui::DragValue::new(&mut s.seed));
            ui.end_row();
            ui.label("resolution");
            match state.fixed_render_size {
                Some((w, h)) => {
                    ui.label(format!("{w}x{h} (fixed)"));
                }
                None => {
                    ui.add(
                        egui::Slider::new(&mut state.render_scale, 0.1..=1.0).text("x image area"),
                    );
                }
            }
            ui.end_row();
            ui.label("vsync");
            ui.checkbox(&mut state.vsync, "");
            ui.end_row();
        });
    if s != before {
        world.insert_resource(s);
    }
}

/// The real-time path's stages and their main tuning.
fn realtime_rows(ui: &mut egui::Ui, s: &mut RenderSettings) {
    let r = &mut s.realtime;
    ui.label("  temporal");
    ui.horizontal(|ui| {
        ui.checkbox(&mut r.temporal, "reprojection");
        ui.checkbox(&mut r.gradients, "gradients");
        ui.checkbox(&mut r.spatial, "spatial filter");
    });
    ui.end_row();
    ui.label("  OIDN per frame");
    ui.horizontal(|ui| {
        for o in FrameOidn::ALL {
            ui.selectable_value(&mut r.oidn, o, o.name());
        }
        ui.separator();
        for q in crate::oidn::Quality::ALL {
            ui.selectable_value(&mut r.oidn_quality, q, q.name());
        }
    })
    .response
    .on_hover_text(
        "Open Image Denoise over the temporal history instead of the spatial filter, while anything \
         moves (with OIDN as the denoiser). shared: only where OIDN's GPU device reads the GPU's memory \
         (a few ms per frame); always: also through host copies (OIDN's CPU device: slow)",
    );
    ui.end_row();
    ui.label("  history length");
    ui.add(egui::DragValue::new(&mut r.history_cap).range(1..=1024))
        .on_hover_text(
            "Frames of history at most; beyond, an exponential average of weight 1 / length",
        );
    ui.end_row();
    ui.label("  ReSTIR DI");
    ui.horizontal(|ui| {
        ui.checkbox(&mut r.restir.enabled, "on");
        ui.checkbox(&mut r.restir.temporal, "temporal");
        ui.checkbox(&mut r.restir.spatial, "spatial");
        ui.checkbox(&mut r.restir.unbiased, "unbiased")
            .on_hover_text(
                "Visibility in the reuse weights: unbiased, two shadow rays per neighbour",
            );
    });
    ui.end_row();
    ui.label("  candidates / neighbours");
    ui.horizontal(|ui| {
        ui.add(egui::DragValue::new(&mut r.restir.candidates).range(1..=64));
        ui.add(egui::DragValue::new(&mut r.restir.neighbours).range(0..=8));
    });
    ui.end_row();
    ui.label("  hand-over");
    ui.horizontal(|ui| {
        ui.checkbox(&mut r.handover, "");
        ui.add(
            egui::DragValue::new(&mut r.handover_spp)
                .range(0..=4096)
                .suffix(" spp"),
        )
        .on_hover_text(
            "Samples of plain accumulation over which a still fades out the real-time image",
        );
    });
    ui.end_row();
}

/// One line on the real-time path's per-frame OIDN.
fn frame_oidn_status(d: &crate::render::frame_denoiser::FrameDenoiser) -> String {
    match (&d.failed, &d.last) {
        (Some(why), _) => format!("OIDN per frame failed, spatial filter instead: {why}"),
        (None, Some(r)) => format!(
            "last moving frame denoised on {} in {:.1} ms{}",
            r.device,
            r.ms,
            data_path(r.shared_memory)
        ),
        (None, None) => "moving frames use the spatial filter (OIDN per frame not run here)".into(),
    }
}

/// How OIDN's images travelled, for the status lines.
fn data_path(shared_memory: bool) -> &'static str {
    if shared_memory {
        " (GPU memory shared with wgpu)"
    } else {
        " (through host copies)"
    }
}

/// One line on OIDN's state for the panel.
fn oidn_status(status: &crate::oidn::OidnStatus) -> String {
    use crate::oidn::OidnStatus;
    match status {
        OidnStatus::Idle => format!(
            "runs once the image is still ({} spp)",
            crate::oidn::viewer::SETTLE_SPP
        ),
        OidnStatus::Denoising(spp) => format!("denoising {spp} spp..."),
        OidnStatus::Shown {
            samples,
            device,
            timings,
            shared_memory,
            readback_ms,
        } => format!(
            "{samples} spp denoised on {device} in {:.0} ms{}",
            timings.total_ms() + readback_ms,
            data_path(*shared_memory)
        ),
        OidnStatus::Unavailable(why) => format!("unavailable, showing svgf: {why}"),
    }
}

/// The environment's kind and its parameters (grid rows). A map's path applies when the field loses focus.
fn environment_rows(ui: &mut egui::Ui, env: &mut Environment) {
    ui.label("environment");
    let kind = |e: &Environment| match e {
        Environment::Sky => 0,
        Environment::Constant(_) => 1,
        Environment::Map(_) => 2,
        Environment::SunSky(_) => 3,
    };
    let names = ["sky gradient", "constant", "HDR map", "sun and sky"];
    let mut selected = kind(env);
    egui::ComboBox::from_id_salt("environment")
        .selected_text(names[selected])
        .show_ui(ui, |ui| {
            for (i, name) in names.iter().enumerate() {
                ui.selectable_value(&mut selected, i, *name);
            }
        });
    ui.end_row();
    if selected != kind(env) {
        *env = match selected {
            0 => Environment::Sky,
            1 => Environment::Constant([1.0; 3]),
            2 => Environment::Map(MapSettings {
                path: Default::default(),
                rotation_degrees: 0.0,
                strength: 1.0,
            }),
            _ => Environment::SunSky(SunSkySettings::default()),
        };
    }
    match env {
        Environment::Sky => {}
        Environment::Constant(c) => {
            ui.label("radiance");
            // Colour and a strength, so bright (> 1) environments stay editable.
            let strength = c.iter().copied().fold(0.0f32, f32::max).max(1.0);
            let mut colour = c.map(|v| v / strength);
            let mut new_strength = strength;
            ui.horizontal(|ui| {
                ui.color_edit_button_rgb(&mut colour);
                ui.add(
                    egui::DragValue::new(&mut new_strength)
                        .speed(0.05)
                        .range(1.0..=1.0e4)
                        .prefix("x"),
                );
            });
            *c = colour.map(|v| v * new_strength);
            ui.end_row();
        }
        Environment::Map(m) => {
            ui.label("  file (.hdr, .exr)");
            let id = ui.make_persistent_id("environment map path");
            let mut text = ui
                .data_mut(|d| d.get_temp::<String>(id))
                .unwrap_or_else(|| m.path.display().to_string());
            let response = ui.text_edit_singleline(&mut text);
            if response.lost_focus() {
                m.path = text.trim().into();
                ui.data_mut(|d| d.remove::<String>(id));
            } else {
                ui.data_mut(|d| d.insert_temp(id, text));
            }
            ui.end_row();
            ui.label("  rotation (deg)");
            ui.add(egui::Slider::new(&mut m.rotation_degrees, -180.0..=180.0));
            ui.end_row();
            ui.label("  strength");
            ui.add(
                egui::DragValue::new(&mut m.strength)
                    .speed(0.01)
                    .range(0.0..=1.0e6),
            );
            ui.end_row();
        }
        Environment::SunSky(sky) => {
            ui.label("  sun elevation (deg)");
            ui.add(egui::Slider::new(&mut sky.elevation_degrees, -10.0..=90.0));
            ui.end_row();
            ui.label("  sun azimuth (deg)");
            ui.add(egui::Slider::new(&mut sky.azimuth_degrees, 0.0..=360.0));
            ui.end_row();
            ui.label("  turbidity");
            ui.add(egui::Slider::new(&mut sky.turbidity, 1.7..=10.0));
            ui.end_row();
            ui.label("  strength");
            ui.add(
                egui::DragValue::new(&mut sky.strength)
                    .speed(0.001)
                    .range(0.0..=100.0),
            )
            .on_hover_text("1: physical units (W/m^2/sr); try exposure -5");
            ui.end_row();
        }
    }
}
