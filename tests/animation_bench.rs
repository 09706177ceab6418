//! Measurements behind docs/ANIMATION.md (ignored by default; they print tables):
//!   cargo test -p raykin --test animation_bench -- --ignored --nocapture
//! Figures come from the dev profile (engine opt-level 1, dependencies opt-level 2), as the brief builds.

use raykin::animation::{AnimationPlayer, DeformedMeshes, cpu_app};
use raykin::bvh::{BvhQuality, MeshBvh};
use raykin::scene::{LoadOptions, SceneAsset, SceneRoot, load_gltf};
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/assets")
}

fn root(app: &mut bevy_app::App) -> bevy_ecs::entity::Entity {
    let world = app.world_mut();
    world
        .query_filtered::<bevy_ecs::entity::Entity, bevy_ecs::query::With<SceneRoot>>()
        .single(world)
        .unwrap()
}

/// SAH ratio of each skinned mesh's BVH, refit every frame (never rebuilt) from a build at the rest pose,
/// over one pass of the clip at 30 frames per second: CSV on stdout.
#[test]
#[ignore]
fn sah_ratio_curves() {
    for (name, path, clip) in [
        ("CesiumMan", "CesiumMan/glTF-Binary/CesiumMan.glb", 0usize),
        ("Fox-Survey", "Fox/glTF-Binary/Fox.glb", 0),
        ("Fox-Walk", "Fox/glTF-Binary/Fox.glb", 1),
        ("Fox-Run", "Fox/glTF-Binary/Fox.glb", 2),
        (
            "RobotExpressive-Dance",
            "RobotExpressive/RobotExpressive.glb",
            0,
        ),
    ] {
        let scene =
            Arc::new(load_gltf(assets().join(path), &LoadOptions { skip_images: true }).unwrap());
        let mut app = cpu_app(scene.clone());
        let r = root(&mut app);
        let duration = scene.animations[clip].duration;
        let meshes: Vec<usize> = (0..scene.meshes.len())
            .filter(|&m| scene.meshes[m].skin_weights.is_some())
            .collect();
        let mut bvhs: Vec<(MeshBvh, Vec<[u32; 3]>)> = Vec::new();
        let frames = (duration * 30.0).ceil() as usize;
        println!("# {name} (clip {clip}, {duration:.2} s), SAH ratio per skinned mesh");
        println!(
            "asset,time_s,{}",
            meshes
                .iter()
                .map(|m| format!("mesh{m}"))
                .collect::<Vec<_>>()
                .join(",")
        );
        for f in 0..=frames {
            let t = f as f32 / 30.0;
            app.world_mut()
                .entity_mut(r)
                .insert(AnimationPlayer::paused_at(clip, t));
            app.update();
            let d = app.world().resource::<DeformedMeshes>();
            if bvhs.is_empty() {
                // Build at the first posed frame, as the renderer does after upload + first refit.
                for &m in &meshes {
                    let p = &d.meshes[m].as_ref().unwrap().positions;
                    let b =
                        MeshBvh::build(p, &scene.meshes[m].triangles, BvhQuality::Medium).unwrap();
                    let tris = b
                        .flat
                        .order
                        .iter()
                        .map(|&t| scene.meshes[m].triangles[t as usize])
                        .collect();
                    bvhs.push((b, tris));
                }
            }
            let mut row = vec![format!("{name},{t:.3}")];
            for (k, &m) in meshes.iter().enumerate() {
                let p = &d.meshes[m].as_ref().unwrap().positions;
                let (b, tris) = &mut bvhs[k];
                b.refit(p, tris);
                row.push(format!("{:.3}", bvhs[k].0.sah_ratio()));
            }
            if f % 3 == 0 || f == frames {
                println!("{}", row.join(","));
            }
        }
    }
}

/// CPU skinning time per 100k vertices (the crowd: 96 skinned meshes) and refit/rebuild times per mesh.
#[test]
#[ignore]
fn cpu_skinning_time() {
    let crowd = raykin::scene::crowd_scene(assets()).unwrap();
    let scene: Arc<SceneAsset> = Arc::new(crowd.scene);
    let mut app = cpu_app(scene.clone());
    let r = root(&mut app);
    raykin::animation::attach_players(app.world_mut(), r, &crowd.players);
    app.update();
    let (mut secs, mut verts) = (0.0, 0usize);
    let frames = 20;
    for _ in 0..frames {
        app.update();
        let d = app.world().resource::<DeformedMeshes>();
        secs += d.last_seconds;
        verts += d.last_vertices;
    }
    println!(
        "crowd: {} meshes, {} triangles; deform {:.1} ms/frame for {} vertices: {:.2} ms per 100k vertices",
        scene.meshes.len(),
        scene.triangle_count(),
        secs / frames as f64 * 1e3,
        verts / frames,
        secs / verts as f64 * 1e5 * 1e3
    );
    for (name, m) in [("CesiumMan", 1usize), ("Fox", scene.meshes.len() - 1)] {
        let d = app.world().resource::<DeformedMeshes>().meshes[m]
            .clone()
            .unwrap();
        let tris = &scene.meshes[m].triangles;
        let t0 = std::time::Instant::now();
        let mut b = MeshBvh::build(&d.positions, tris, BvhQuality::Medium).unwrap();
        let build = t0.elapsed().as_secs_f64();
        let order = b.ordered_triangles(tris);
        let t0 = std::time::Instant::now();
        for _ in 0..100 {
            b.refit(&d.positions, &order);
        }
        let refit = t0.elapsed().as_secs_f64() / 100.0;
        println!(
            "{name}: {} triangles: rebuild {:.2} ms, refit {:.3} ms",
            tris.len(),
            build * 1e3,
            refit * 1e3
        );
    }
}
