//! KHR_materials_variants: which of the file's material sets is shown, as the [`ActiveVariant`] resource (the
//! render plugin rewrites only the triangles' materials). Shown only for files that have variants.

use crate::scene::{ActiveVariant, SceneAssets};
use bevy_ecs::prelude::*;

const FILE_MATERIALS: &str = "(file's materials)";

pub fn show(ui: &mut egui::Ui, world: &mut World) {
    let scene = world.resource::<SceneAssets>().0.clone();
    if scene.variants.is_empty() {
        return;
    }
    let current = world.resource::<ActiveVariant>().0;
    let name = |v: Option<usize>| {
        v.and_then(|v| scene.variants.get(v))
            .map_or(FILE_MATERIALS, String::as_str)
            .to_string()
    };
    let mut chosen = current;
    ui.horizontal(|ui| {
        ui.label("variant");
        egui::ComboBox::from_id_salt("material variant")
            .selected_text(name(current))
            .width(180.0)
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut chosen, None, FILE_MATERIALS);
                for v in 0..scene.variants.len() {
                    ui.selectable_value(&mut chosen, Some(v), name(Some(v)));
                }
            });
    })
    .response
    .on_hover_text(
        "KHR_materials_variants; Save as keeps every variant and the file's own materials",
    );
    if chosen != current {
        world.resource_mut::<ActiveVariant>().0 = chosen;
    }
}
