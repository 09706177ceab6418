//! Measurements behind docs/ANIMATION.md (ignored by default; they print tables):
//!   cargo test --release --workspace --test engine -- --ignored --nocapture animation_bench::

use crate::common::shared_assets;
use raykin::animation::{AnimationPlayer, DeformedMeshes, cpu_app};
use raykin::bvh::{BvhQuality, MeshBvh};
use raykin::scene::{LoadOptions, SceneAsset, SceneRoot, load_gltf};

use std::sync::Arc;

/// CPU seconds of this process (all threads) or of the calling thread: unlike wall time, not inflated when
/// other jobs share the machine's two cores.
fn cpu_seconds(clock: libc::clockid_t) -> f64 {
    let mut t = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: clock_gettime writes the timespec it is given.
    unsafe { libc::clock_gettime(clock, &mut t) };
    t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9
}

fn process_cpu() -> f64 {
    cpu_seconds(libc::CLOCK_PROCESS_CPUTIME_ID)
}

fn thread_cpu() -> f64 {
    cpu_seconds(libc::CLOCK_THREAD_CPUTIME_ID)
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
        let scene = Arc::new(
            load_gltf(
                shared_assets().join(path),
                &LoadOptions {
                    skip_images: true,
                    ..Default::default()
                },
            )
            .unwrap(),
        );
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

/// CPU skinning and refit time per frame of the crowd (96 skinned meshes, every one moving), per 100k
/// vertices and per 100k triangles, and refit/rebuild times per mesh.
#[test]
#[ignore]
fn cpu_skinning_time() {
    let crowd = raykin::animation::crowd_scene(shared_assets()).unwrap();
    let scene: Arc<SceneAsset> = Arc::new(crowd.scene);
    let mut app = cpu_app(scene.clone());
    let r = root(&mut app);
    raykin::animation::attach_players(app.world_mut(), r, &crowd.players);
    app.update();
    // One BVH per deformable mesh, built at the first pose, refit every frame as the renderer does.
    let mut trees: Vec<(usize, MeshBvh, Vec<[u32; 3]>)> = {
        let d = app.world().resource::<DeformedMeshes>();
        (0..scene.meshes.len())
            .filter(|&m| scene.meshes[m].is_deformable())
            .map(|m| {
                let tris = &scene.meshes[m].triangles;
                let b = MeshBvh::build(
                    &d.meshes[m].as_ref().unwrap().positions,
                    tris,
                    BvhQuality::Medium,
                )
                .unwrap();
                let order = b.ordered_triangles(tris);
                (m, b, order)
            })
            .collect()
    };
    let deformed_triangles: usize = trees
        .iter()
        .map(|t| scene.meshes[t.0].triangles.len())
        .sum();
    let (mut wall, mut cpu, mut verts, mut refit_wall, mut refit_cpu) =
        (0.0, 0.0, 0usize, 0.0, 0.0);
    let frames = 40;
    // RAYON_NUM_THREADS=1 measures the work itself: rayon's idle workers spin, which inflates the
    // process CPU time of a parallel run.
    for _ in 0..frames {
        // The frame's animation and transform systems run too; the deform system times itself.
        let c0 = process_cpu();
        app.update();
        let d = app.world().resource::<DeformedMeshes>();
        wall += d.last_seconds;
        verts += d.last_vertices;
        let (t0, c1) = (std::time::Instant::now(), process_cpu());
        {
            use rayon::prelude::*;
            trees.par_iter_mut().for_each(|(m, b, order)| {
                b.refit(&d.meshes[*m].as_ref().unwrap().positions, order);
            });
        }
        refit_wall += t0.elapsed().as_secs_f64();
        let c2 = process_cpu();
        cpu += c1 - c0;
        refit_cpu += c2 - c1;
    }
    let per_frame = |s: f64| s / frames as f64 * 1e3;
    let per_100k_tris = |s: f64| per_frame(s) / (deformed_triangles as f64 / 1e5);
    println!(
        "crowd: {} meshes, {} triangles ({deformed_triangles} deformed); rayon threads {}; wall times are inflated when other jobs share the cores, CPU times are not",
        scene.meshes.len(),
        scene.triangle_count(),
        rayon::current_num_threads()
    );
    println!(
        "deform (skin + morph, positions/normals/tangents) of {} vertices: {:.2} ms/frame wall, {:.2} ms/frame CPU (whole frame update, all threads): {:.2} CPU-ms per 100k triangles ({:.2} per 100k vertices)",
        verts / frames,
        per_frame(wall),
        per_frame(cpu),
        per_100k_tris(cpu),
        per_frame(cpu) / (verts as f64 / frames as f64 / 1e5)
    );
    println!(
        "refit + SAH of every deformed BLAS: {:.2} ms/frame wall, {:.2} ms/frame CPU: {:.2} CPU-ms per 100k triangles ({:.1} ns per triangle)",
        per_frame(refit_wall),
        per_frame(refit_cpu),
        per_100k_tris(refit_cpu),
        refit_cpu / frames as f64 / deformed_triangles as f64 * 1e9
    );
    for (name, m) in [("CesiumMan", 1usize), ("Fox", scene.meshes.len() - 1)] {
        let d = app.world().resource::<DeformedMeshes>().meshes[m]
            .clone()
            .unwrap();
        let tris = &scene.meshes[m].triangles;
        let t0 = thread_cpu();
        let mut b = MeshBvh::build(&d.positions, tris, BvhQuality::Medium).unwrap();
        let build = thread_cpu() - t0;
        let order = b.ordered_triangles(tris);
        let t0 = thread_cpu();
        let n = 2000;
        for _ in 0..n {
            b.refit(&d.positions, &order);
        }
        let refit = (thread_cpu() - t0) / n as f64;
        println!(
            "{name}: {} triangles: rebuild {:.2} ms, refit + SAH {:.3} ms ({:.1} ns per triangle), thread CPU time",
            tris.len(),
            build * 1e3,
            refit * 1e3,
            refit / tris.len() as f64 * 1e9
        );
    }
}
