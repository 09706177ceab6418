//! Animation players: clip, play/pause, speed, loop mode and a timeline scrubber for each.

use super::scene_tree::entity_name;
use crate::animation::{AnimationPlayer, PlayMode};
use crate::scene::SceneAssets;
use bevy_ecs::prelude::*;

/// Players listed one by one up to this many (a crowd has one per character); the rest share the buttons.
const MAX_LISTED: usize = 16;

pub fn show(ui: &mut egui::Ui, world: &mut World) {
    let scene = world.resource::<SceneAssets>().0.clone();
    if scene.animations.is_empty() {
        ui.label("The scene has no animations.");
        return;
    }
    let mut players: Vec<(Entity, AnimationPlayer)> = world
        .query::<(Entity, &AnimationPlayer)>()
        .iter(world)
        .map(|(e, p)| (e, *p))
        .collect();
    players.sort_by_key(|(e, _)| *e);
    if players.is_empty() {
        ui.label("No animation player.");
        return;
    }
    if players.len() > 1 {
        ui.horizontal(|ui| {
            ui.label(format!("{} players", players.len()));
            let all = if ui.button("Play all").clicked() {
                Some(true)
            } else if ui.button("Pause all").clicked() {
                Some(false)
            } else {
                None
            };
            if let Some(playing) = all {
                for (e, _) in &players {
                    if let Some(mut p) = world.get_mut::<AnimationPlayer>(*e) {
                        p.playing = playing;
                    }
                }
            }
        });
    }
    for (entity, player) in players.iter().take(MAX_LISTED) {
        let mut p = *player;
        ui.push_id(entity, |ui| {
            ui.separator();
            ui.label(entity_name(world, *entity));
            let clip_name = |i: usize| {
                let a = &scene.animations[i];
                if a.name.is_empty() {
                    format!("clip {i} ({:.2} s)", a.duration)
                } else {
                    format!("{i}: {} ({:.2} s)", a.name, a.duration)
                }
            };
            egui::ComboBox::from_id_salt("clip")
                .selected_text(clip_name(p.clip.min(scene.animations.len() - 1)))
                .show_ui(ui, |ui| {
                    for i in 0..scene.animations.len() {
                        ui.selectable_value(&mut p.clip, i, clip_name(i));
                    }
                });
            let duration = scene
                .animations
                .get(p.clip)
                .map_or(0.0, |a| a.duration)
                .max(1e-3);
            ui.horizontal(|ui| {
                if ui
                    .button(if p.playing { "Pause" } else { "Play" })
                    .clicked()
                {
                    p.playing = !p.playing;
                    // A finished one-shot clip restarts from the beginning.
                    if p.playing && p.mode == PlayMode::Once && p.time >= duration {
                        p.time = 0.0;
                    }
                }
                ui.add(
                    egui::DragValue::new(&mut p.speed)
                        .speed(0.01)
                        .range(-8.0..=8.0)
                        .prefix("speed "),
                );
                egui::ComboBox::from_id_salt("mode")
                    .selected_text(format!("{:?}", p.mode))
                    .show_ui(ui, |ui| {
                        for mode in [PlayMode::Loop, PlayMode::Once, PlayMode::PingPong] {
                            ui.selectable_value(&mut p.mode, mode, format!("{mode:?}"));
                        }
                    });
            });
            let mut t = p.local_time(duration);
            let scrub = ui.add(egui::Slider::new(&mut t, 0.0..=duration).text("s"));
            // Only the user's hand counts: the widget may round the shown value on its own.
            if scrub.changed() && (scrub.dragged() || scrub.clicked() || scrub.has_focus()) {
                // Scrubbing holds the pose where the handle is.
                p.time = t;
                p.playing = false;
            }
        });
        if p != *player
            && let Some(mut current) = world.get_mut::<AnimationPlayer>(*entity)
        {
            *current = p;
        }
    }
    if players.len() > MAX_LISTED {
        ui.label(format!(
            "... and {} more players (Play all / Pause all apply to them)",
            players.len() - MAX_LISTED
        ));
    }
}
