//! The seed-like workload (issue 17): a hall of about 1.6M triangles lit only by emitters, with the crowd walking
//! in it, for the seed's setting (2560x1440, 1 spp, depth 6).

use super::AnimationPlayer;
use super::crowd::crowd_scene;
use crate::scene::compose::compose;
use crate::scene::{
    LoadOptions, Material, NodeTransform, SceneAsset, SceneError, load_gltf, procedural,
};
use glam::{Quat, Vec3, Vec4};
use std::path::Path;
use std::sync::Arc;

/// The hall's scene and the players that animate its crowd.
pub struct SeedInterior {
    pub scene: SceneAsset,
    pub players: Vec<(usize, AnimationPlayer)>,
}

/// Hall: 24 m wide (x -12..12), 7 m high, from the back wall at z = -12 to the front wall at z = 18 behind
/// the camera, lit by six ceiling panels (2 x 2 m, radiance 12) and nothing else. Inside: the crowd (64
/// CesiumMan and 32 Fox walking, 317k triangles, its ground as the floor), MetalRoughSpheresNoTextures (1.04M
/// triangles) as a 6 m panel on the back wall, and three FlightHelmets (1.8 m tall) by the side walls.
/// `shared_assets` holds `CesiumMan/`, `Fox/`, `FlightHelmet/` and `MetalRoughSpheresNoTextures/`.
pub fn seed_interior_scene(shared_assets: impl AsRef<Path>) -> Result<SeedInterior, SceneError> {
    let dir = shared_assets.as_ref();
    let options = LoadOptions::default();
    let crowd = crowd_scene(dir)?;
    let spheres = Arc::new(load_gltf(
        dir.join("MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb"),
        &options,
    )?);
    let helmet = Arc::new(load_gltf(
        dir.join("FlightHelmet/glTF/FlightHelmet.gltf"),
        &options,
    )?);
    let mut parts = vec![
        (Arc::new(crowd.scene), NodeTransform::default()),
        (Arc::new(hall()), NodeTransform::default()),
        (
            spheres.clone(),
            fit(&spheres, 6.0, Vec3::new(0.0, 3.6, -11.8), Quat::IDENTITY),
        ),
    ];
    // Three helmets by the side walls, turned towards the hall's middle: with them the hall holds 1.64M
    // triangle instances (1.45M distinct triangles: the helmets share theirs).
    for (x, z, turn) in [(-9.5, -8.0, 0.9), (9.5, -8.0, -0.9), (9.5, 2.0, -1.2)] {
        let placement = fit(
            &helmet,
            1.8,
            Vec3::new(x, 0.9, z),
            Quat::from_rotation_y(turn),
        );
        parts.push((helmet.clone(), placement));
    }
    let (scene, copies) = compose("seed-like hall (crowd, spheres, FlightHelmets)", &parts);
    // The crowd's players name nodes and clips of the crowd scene: shift them to its copy.
    let node_offset = copies[0].group_node + 1;
    let players = crowd
        .players
        .into_iter()
        .map(|(node, mut player)| {
            player.clip += copies[0].first_clip;
            (node + node_offset, player)
        })
        .collect();
    Ok(SeedInterior { scene, players })
}

/// The placement that scales `asset`'s rest bounds to `height` (its largest side) and centres them at `centre`.
fn fit(asset: &SceneAsset, height: f32, centre: Vec3, rotation: Quat) -> NodeTransform {
    let (lo, hi) = asset.rest_bounds().unwrap_or((Vec3::ZERO, Vec3::ONE));
    let scale = height / (hi - lo).max_element().max(1e-6);
    NodeTransform {
        translation: centre - rotation * ((lo + hi) * 0.5 * scale),
        rotation,
        scale: Vec3::splat(scale),
    }
}

/// Walls, ceiling and the ceiling's emissive panels (the crowd brings the floor).
fn hall() -> SceneAsset {
    let wall = Material {
        name: "wall".into(),
        base_color: Vec4::new(0.7, 0.68, 0.62, 1.0),
        metallic: 0.0,
        roughness: 0.7,
        double_sided: true,
        ..Default::default()
    };
    let panel = Material {
        name: "ceiling panel".into(),
        base_color: Vec4::new(0.8, 0.8, 0.8, 1.0),
        metallic: 0.0,
        roughness: 0.9,
        emissive: Vec3::ONE,
        emissive_strength: 12.0,
        ..Default::default()
    };
    // A quad of side `size` facing `normal`, centred at `centre` (the ground quad turned).
    let quad = |size: f32, material: u32, centre: Vec3, normal: Vec3| {
        (
            procedural::ground_quad(size, material),
            NodeTransform {
                translation: centre,
                rotation: Quat::from_rotation_arc(Vec3::Y, normal),
                scale: Vec3::ONE,
            },
        )
    };
    let mut meshes = vec![
        quad(40.0, 0, Vec3::new(0.0, 7.0, 3.0), Vec3::NEG_Y),
        quad(40.0, 0, Vec3::new(0.0, 3.5, -12.0), Vec3::Z),
        quad(40.0, 0, Vec3::new(0.0, 3.5, 18.0), Vec3::NEG_Z),
        quad(40.0, 0, Vec3::new(-12.0, 3.5, 3.0), Vec3::X),
        quad(40.0, 0, Vec3::new(12.0, 3.5, 3.0), Vec3::NEG_X),
    ];
    for x in [-6.0, 0.0, 6.0] {
        for z in [-6.0, 4.0] {
            meshes.push(quad(2.0, 1, Vec3::new(x, 6.98, z), Vec3::NEG_Y));
        }
    }
    procedural::scene_from_meshes("hall", meshes, vec![wall, panel])
}
