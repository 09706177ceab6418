//! Lights: every KHR_lights_punctual light in the scene (click to select its node), the editable parameters
//! of the selected node's light (type, colour, intensity, cone angles, range), and what the environment is.
//! Edits change the node's `LightSource`; the renderer re-uploads the light list next frame.

use super::EditorState;
use super::scene_tree::{entity_name, select};
use crate::render::{Environment, RenderSettings};
use crate::scene::{LightSource, PunctualKind, PunctualLight};
use bevy_ecs::prelude::*;

pub fn show(ui: &mut egui::Ui, world: &mut World, state: &mut EditorState) {
    let mut lights: Vec<(Entity, PunctualLight)> = world
        .query::<(Entity, &LightSource)>()
        .iter(world)
        .map(|(e, l)| (e, l.0.clone()))
        .collect();
    lights.sort_by_key(|(e, _)| *e);
    if lights.is_empty() {
        ui.label("no punctual lights (KHR_lights_punctual) in the scene");
    }
    for (entity, light) in &lights {
        let label = format!("{}: {}", entity_name(world, *entity), kind_name(light.kind));
        if ui
            .selectable_label(state.selection.entity == Some(*entity), label)
            .clicked()
        {
            select(world, state, *entity);
        }
    }
    ui.label(format!(
        "environment: {}",
        describe_environment(&world.resource::<RenderSettings>().environment)
    ))
    .on_hover_text("edit it under Render");
}

fn kind_name(kind: PunctualKind) -> &'static str {
    match kind {
        PunctualKind::Point => "point",
        PunctualKind::Spot { .. } => "spot",
        PunctualKind::Directional => "directional",
    }
}

fn describe_environment(env: &Environment) -> String {
    match env {
        Environment::Sky => "sky gradient".into(),
        Environment::Constant(c) => format!("constant ({:.2}, {:.2}, {:.2})", c[0], c[1], c[2]),
        Environment::Map(m) => format!(
            "map {} (rotation {:.0} deg, strength {})",
            m.path.display(),
            m.rotation_degrees,
            m.strength
        ),
        Environment::SunSky(s) => format!(
            "sun and sky (sun at {:.0} deg elevation, {:.0} deg azimuth; turbidity {})",
            s.elevation_degrees, s.azimuth_degrees, s.turbidity
        ),
    }
}

/// The selected node's light, editable (in the inspector).
pub fn light_inspector(ui: &mut egui::Ui, world: &mut World, entity: Entity) {
    let Some(LightSource(mut light)) = world.get::<LightSource>(entity).cloned() else {
        return;
    };
    let before = light.clone();
    ui.label(egui::RichText::new("KHR_lights_punctual light").strong());
    egui::Grid::new("light").num_columns(2).show(ui, |ui| {
        ui.label("type");
        let mut kind = light.kind;
        egui::ComboBox::from_id_salt("light kind")
            .selected_text(kind_name(kind))
            .show_ui(ui, |ui| {
                let spot = match kind {
                    PunctualKind::Spot { .. } => kind,
                    _ => PunctualKind::Spot {
                        inner_cone_angle: 0.0,
                        outer_cone_angle: std::f32::consts::FRAC_PI_4,
                    },
                };
                for k in [PunctualKind::Point, spot, PunctualKind::Directional] {
                    ui.selectable_value(&mut kind, k, kind_name(k));
                }
            });
        light.kind = kind;
        ui.end_row();
        ui.label("colour");
        let mut c = light.color.to_array();
        ui.color_edit_button_rgb(&mut c);
        light.color = c.into();
        ui.end_row();
        ui.label(if kind == PunctualKind::Directional {
            "intensity (W/m^2)"
        } else {
            "intensity (W/sr)"
        });
        ui.add(
            egui::DragValue::new(&mut light.intensity)
                .speed(0.05)
                .range(0.0..=1.0e9),
        );
        ui.end_row();
        if let PunctualKind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } = &mut light.kind
        {
            let mut outer = outer_cone_angle.to_degrees();
            let mut inner = inner_cone_angle.to_degrees();
            ui.label("outer cone (deg)");
            ui.add(egui::Slider::new(&mut outer, 0.1..=90.0));
            ui.end_row();
            ui.label("inner cone (deg)");
            ui.add(egui::Slider::new(&mut inner, 0.0..=outer));
            ui.end_row();
            // The spec requires inner < outer.
            *outer_cone_angle = outer.to_radians();
            *inner_cone_angle = inner.min(outer * 0.999).to_radians();
        }
        if kind != PunctualKind::Directional {
            ui.label("range");
            let mut bounded = light.range.is_some();
            ui.horizontal(|ui| {
                ui.checkbox(&mut bounded, "");
                if bounded {
                    let mut r = light.range.unwrap_or(10.0);
                    ui.add(
                        egui::DragValue::new(&mut r)
                            .speed(0.05)
                            .range(1.0e-3..=1.0e9),
                    );
                    light.range = Some(r);
                } else {
                    light.range = None;
                }
            });
            ui.end_row();
        } else {
            light.range = None;
        }
    });
    if light != before
        && let Some(mut current) = world.get_mut::<LightSource>(entity)
    {
        current.0 = light;
    }
}
