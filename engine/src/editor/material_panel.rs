//! The material inspector: every parameter the renderer reads (`gpu_material`), edited on the
//! [`Materials`] resource; the render plugin re-uploads what changed and restarts accumulation.

use super::EditorState;
use crate::scene::{AlphaMode, Material, Materials, SceneAssets, TextureRef};
use bevy_ecs::prelude::*;

pub fn show(ui: &mut egui::Ui, world: &mut World, state: &mut EditorState) {
    let scene = world.resource::<SceneAssets>().0.clone();
    let materials = world.resource::<Materials>();
    if materials.0.is_empty() {
        ui.label("The scene has no materials (glTF's default material is used).");
        return;
    }
    let edited = materials.edited(&scene);
    let index = state
        .selection
        .material
        .filter(|&i| i < materials.0.len())
        .unwrap_or(0);
    let label = |i: usize, m: &Material| {
        let mark = if edited.contains(&i) { " *" } else { "" };
        if m.name.is_empty() {
            format!("{i}{mark}")
        } else {
            format!("{i}: {}{mark}", m.name)
        }
    };
    let mut chosen = index;
    egui::ComboBox::from_id_salt("material")
        .selected_text(label(index, &materials.0[index]))
        .width(220.0)
        .show_ui(ui, |ui| {
            for (i, m) in materials.0.iter().enumerate() {
                ui.selectable_value(&mut chosen, i, label(i, m));
            }
        });
    state.selection.material = Some(chosen);
    let original = scene.materials.get(chosen).cloned().unwrap_or_default();
    let mut m = materials.0[chosen].clone();
    edit(ui, &mut m, &original);
    ui.horizontal(|ui| {
        if ui
            .add_enabled(m != original, egui::Button::new("Revert to file"))
            .clicked()
        {
            m = original.clone();
        }
        if !edited.is_empty() {
            ui.label(format!("{} edited (*)", edited.len()));
        }
    });
    if m != world.resource::<Materials>().0[chosen] {
        world.resource_mut::<Materials>().0[chosen] = m;
    }
}

/// Picks one texture reference out of a material.
type TextureSlot = fn(&mut Material) -> &mut Option<TextureRef>;

fn edit(ui: &mut egui::Ui, m: &mut Material, original: &Material) {
    egui::Grid::new("material params")
        .num_columns(2)
        .show(ui, |ui| {
            ui.label("base colour");
            let mut c = m.base_color.to_array();
            if ui.color_edit_button_rgba_unmultiplied(&mut c).changed() {
                m.base_color = c.into();
            }
            ui.end_row();
            ui.label("metallic");
            ui.add(egui::Slider::new(&mut m.metallic, 0.0..=1.0));
            ui.end_row();
            ui.label("roughness");
            ui.add(egui::Slider::new(&mut m.roughness, 0.0..=1.0));
            ui.end_row();
            ui.label("emissive colour");
            let mut e = m.emissive.to_array();
            if ui.color_edit_button_rgb(&mut e).changed() {
                m.emissive = e.into();
            }
            ui.end_row();
            ui.label("emissive strength");
            ui.add(
                egui::DragValue::new(&mut m.emissive_strength)
                    .speed(0.05)
                    .range(0.0..=1.0e4),
            );
            ui.end_row();
            ui.label("unlit");
            ui.checkbox(&mut m.extensions.unlit, "").on_hover_text(
                "KHR_materials_unlit: the base colour is shown as is, with no lighting",
            );
            ui.end_row();
            ui.label("alpha mode");
            let mut mode = match m.alpha_mode {
                AlphaMode::Opaque => 0,
                AlphaMode::Mask(_) => 1,
                AlphaMode::Blend => 2,
            };
            let mut cutoff = match (m.alpha_mode, original.alpha_mode) {
                (AlphaMode::Mask(c), _) | (_, AlphaMode::Mask(c)) => c,
                _ => 0.5,
            };
            egui::ComboBox::from_id_salt("alpha mode")
                .selected_text(["opaque", "mask", "blend"][mode])
                .show_ui(ui, |ui| {
                    for (i, name) in ["opaque", "mask", "blend"].iter().enumerate() {
                        ui.selectable_value(&mut mode, i, *name);
                    }
                });
            ui.end_row();
            if mode == 1 {
                ui.label("alpha cutoff");
                ui.add(egui::Slider::new(&mut cutoff, 0.0..=1.0));
                ui.end_row();
            }
            m.alpha_mode = match mode {
                0 => AlphaMode::Opaque,
                1 => AlphaMode::Mask(cutoff),
                _ => AlphaMode::Blend,
            };
            ui.label("double-sided");
            ui.checkbox(&mut m.double_sided, "");
            ui.end_row();
            if original.normal_texture.is_some() {
                ui.label("normal scale");
                ui.add(
                    egui::DragValue::new(&mut m.normal_scale)
                        .speed(0.01)
                        .range(-10.0..=10.0),
                );
                ui.end_row();
            }
        });
    edit_dielectric(ui, m);
    edit_layers(ui, m);
    // Textures can be switched off (and back on) where the file has them.
    let slots: [(&str, TextureSlot, Option<TextureRef>); 4] = [
        (
            "base colour texture",
            |m| &mut m.base_color_texture,
            original.base_color_texture,
        ),
        (
            "metallic-roughness texture",
            |m| &mut m.metallic_roughness_texture,
            original.metallic_roughness_texture,
        ),
        (
            "normal texture",
            |m| &mut m.normal_texture,
            original.normal_texture,
        ),
        (
            "emissive texture",
            |m| &mut m.emissive_texture,
            original.emissive_texture,
        ),
    ];
    for (name, slot, file_value) in slots {
        let Some(file_value) = file_value else {
            continue;
        };
        let field = slot(m);
        let mut on = field.is_some();
        if ui.checkbox(&mut on, name).changed() {
            *field = on.then_some(file_value);
        }
    }
}

/// KHR_materials_ior, _transmission, _volume and _specular: the dielectric layer and what lies behind it.
/// Setting a value on a material without the extension adds it (Save as writes it).
fn edit_dielectric(ui: &mut egui::Ui, m: &mut Material) {
    use crate::scene::material_extensions::{Specular, Transmission, Volume};
    use glam::Vec3;
    let e = &mut m.extensions;
    egui::CollapsingHeader::new("transmission, IOR, specular")
        .default_open(e.transmission.is_some())
        .show(ui, |ui| {
            egui::Grid::new("dielectric params")
                .num_columns(2)
                .show(ui, |ui| {
                    ui.label("IOR");
                    // 0 is the schema's "f0 = 1" value: shown, not clamped away.
                    ui.add(
                        egui::DragValue::new(&mut e.ior)
                            .speed(0.01)
                            .range(1.0..=5.0)
                            .clamp_existing_to_range(false),
                    );
                    ui.end_row();
                    ui.label("transmission");
                    let mut t = e.transmission.as_ref().map_or(0.0, |t| t.factor);
                    if ui.add(egui::Slider::new(&mut t, 0.0..=1.0)).changed() {
                        e.transmission
                            .get_or_insert(Transmission {
                                factor: 0.0,
                                texture: None,
                            })
                            .factor = t;
                    }
                    ui.end_row();
                    ui.label("volume behind (refracts)");
                    let mut volume = e.volume.as_ref().is_some_and(|v| v.thickness > 0.0);
                    if ui.checkbox(&mut volume, "").changed() {
                        let v = e.volume.get_or_insert(Volume {
                            thickness: 0.0,
                            thickness_texture: None,
                            attenuation_distance: f32::INFINITY,
                            attenuation_color: Vec3::ONE,
                        });
                        v.thickness = if volume { v.thickness.max(1.0) } else { 0.0 };
                    }
                    ui.end_row();
                    if let Some(v) = e.volume.as_mut().filter(|v| v.thickness > 0.0) {
                        ui.label("attenuation colour");
                        let mut c = v.attenuation_color.to_array();
                        if ui.color_edit_button_rgb(&mut c).changed() {
                            v.attenuation_color = c.into();
                        }
                        ui.end_row();
                        ui.label("attenuation distance");
                        ui.horizontal(|ui| {
                            let mut absorbs = v.attenuation_distance.is_finite();
                            if ui.checkbox(&mut absorbs, "").changed() {
                                v.attenuation_distance = if absorbs { 1.0 } else { f32::INFINITY };
                            }
                            if absorbs {
                                ui.add(
                                    egui::DragValue::new(&mut v.attenuation_distance)
                                        .speed(0.01)
                                        .range(1.0e-4..=1.0e6),
                                );
                            }
                        });
                        ui.end_row();
                    }
                    let had_specular = e.specular.is_some();
                    let specular = e.specular.get_or_insert(Specular {
                        factor: 1.0,
                        texture: None,
                        color: Vec3::ONE,
                        color_texture: None,
                    });
                    let before = specular.clone();
                    ui.label("specular");
                    ui.add(egui::Slider::new(&mut specular.factor, 0.0..=1.0));
                    ui.end_row();
                    ui.label("specular colour");
                    let mut c = specular.color.to_array();
                    if ui.color_edit_button_rgb(&mut c).changed() {
                        specular.color = c.into();
                    }
                    ui.end_row();
                    // Only an edit adds the extension (its defaults are the core specification's).
                    if !had_specular && *specular == before {
                        e.specular = None;
                    }
                });
        });
}

/// KHR_materials_clearcoat and _sheen: the layers over the material. Setting a value on a material without the
/// extension adds it (Save as writes it); a layer at 0 stays in the file but renders as none.
fn edit_layers(ui: &mut egui::Ui, m: &mut Material) {
    use crate::scene::material_extensions::{Clearcoat, Sheen};
    let e = &mut m.extensions;
    egui::CollapsingHeader::new("clearcoat, sheen")
        .default_open(e.clearcoat.is_some() || e.sheen.is_some())
        .show(ui, |ui| {
            egui::Grid::new("layer params")
                .num_columns(2)
                .show(ui, |ui| {
                    let had_coat = e.clearcoat.is_some();
                    let coat = e.clearcoat.get_or_insert(Clearcoat {
                        factor: 0.0,
                        texture: None,
                        roughness: 0.0,
                        roughness_texture: None,
                        normal_texture: None,
                        normal_scale: 1.0,
                    });
                    let before = coat.clone();
                    ui.label("clearcoat");
                    ui.add(egui::Slider::new(&mut coat.factor, 0.0..=1.0));
                    ui.end_row();
                    ui.label("clearcoat roughness");
                    ui.add(egui::Slider::new(&mut coat.roughness, 0.0..=1.0));
                    ui.end_row();
                    if coat.normal_texture.is_some() {
                        ui.label("clearcoat normal scale");
                        ui.add(
                            egui::DragValue::new(&mut coat.normal_scale)
                                .speed(0.01)
                                .range(-10.0..=10.0),
                        );
                        ui.end_row();
                    }
                    // Only an edit adds the extension.
                    if !had_coat && *coat == before {
                        e.clearcoat = None;
                    }
                    let had_sheen = e.sheen.is_some();
                    let sheen = e.sheen.get_or_insert(Sheen {
                        color: glam::Vec3::ZERO,
                        color_texture: None,
                        roughness: 0.0,
                        roughness_texture: None,
                    });
                    let before = sheen.clone();
                    ui.label("sheen colour");
                    let mut c = sheen.color.to_array();
                    if ui.color_edit_button_rgb(&mut c).changed() {
                        sheen.color = c.into();
                    }
                    ui.end_row();
                    ui.label("sheen roughness");
                    ui.add(egui::Slider::new(&mut sheen.roughness, 0.0..=1.0));
                    ui.end_row();
                    if !had_sheen && *sheen == before {
                        e.sheen = None;
                    }
                });
        });
}
