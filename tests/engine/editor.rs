//! The editor's engine side without a window: material edits re-upload and restart accumulation (emitters
//! included), picking agrees with a brute-force ray cast, and File > Save as writes the edits into a glTF that
//! loads back with everything else unchanged.

use crate::common::{gpu, repo_root, shared_assets};
use glam::{Vec3, Vec4};
use raykin::camera::CameraChoice;
use raykin::headless::HeadlessApp;
use raykin::render::{GpuScene, RenderSettings};
use raykin::scene::{LoadOptions, Materials, MeshInstance, SceneAsset, load_gltf};
use std::path::PathBuf;
use std::sync::Arc;

fn viewer_scene() -> Arc<SceneAsset> {
    Arc::new(
        load_gltf(
            repo_root().join("tests/fixtures/viewer/viewer_scene.gltf"),
            &LoadOptions::default(),
        )
        .expect("fixture loads"),
    )
}

const W: u32 = 48;
const H: u32 = 30;

fn app(scene: &Arc<SceneAsset>) -> (HeadlessApp, std::sync::MutexGuard<'static, ()>) {
    let (ctx, guard) = gpu();
    let settings = RenderSettings {
        width: W,
        height: H,
        spp_per_frame: 4,
        max_depth: 3,
        ..Default::default()
    };
    let app = HeadlessApp::new(ctx, scene.clone(), settings, &CameraChoice::Auto).expect("uploads");
    (app, guard)
}

fn red_pixels(img: &[[f32; 3]]) -> Vec<usize> {
    (0..img.len())
        .filter(|&i| img[i][0] > 2.0 * img[i][2] && img[i][0] > 2.0 * img[i][1])
        .collect()
}

#[test]
fn material_edits_reupload_and_restart_accumulation() {
    let scene = viewer_scene();
    let (mut app, _gpu) = app(&scene);
    app.accumulate(8, 4, |_| {});
    assert_eq!(app.samples(), 8);
    let before = app.radiance();
    let crate_pixels = red_pixels(&before);
    assert!(crate_pixels.len() > 20, "the red crate is in view");

    let paint = app
        .app
        .world()
        .resource::<Materials>()
        .find("Paint")
        .expect("material Paint");
    app.app.world_mut().resource_mut::<Materials>().0[paint].base_color =
        Vec4::new(0.05, 0.1, 0.9, 1.0);
    app.step();
    assert_eq!(app.samples(), 4, "the edit restarted accumulation");
    assert_eq!(
        app.gpu_scene().material_data[paint].base_color,
        [0.05, 0.1, 0.9, 1.0],
        "the GPU copy holds the edit"
    );
    app.accumulate(4, 4, |_| {});
    let after = app.radiance();
    let mean = |img: &[[f32; 3]], c: usize| {
        crate_pixels.iter().map(|&i| img[i][c] as f64).sum::<f64>() / crate_pixels.len() as f64
    };
    assert!(
        mean(&after, 2) > 3.0 * mean(&before, 2) && mean(&after, 0) < 0.5 * mean(&before, 0),
        "crate pixels did not turn blue: red {:.3} -> {:.3}, blue {:.3} -> {:.3}",
        mean(&before, 0),
        mean(&after, 0),
        mean(&before, 2),
        mean(&after, 2)
    );

    // A frame without edits keeps accumulating (only changed materials restart it).
    app.step();
    assert_eq!(app.samples(), 12);

    // Making the floor emissive turns it into a light: emitters appear (next-event estimation samples them).
    assert_eq!(app.gpu_scene().lights.triangle_count, 0);
    let floor = app
        .app
        .world()
        .resource::<Materials>()
        .find("Floor")
        .expect("material Floor");
    {
        let world = app.app.world_mut();
        let mut materials = world.resource_mut::<Materials>();
        materials.0[floor].emissive = Vec3::ONE;
        materials.0[floor].emissive_strength = 3.0;
    }
    app.step();
    assert_eq!(app.samples(), 4);
    assert_eq!(
        app.gpu_scene().lights.triangle_count,
        2,
        "the floor's two triangles"
    );
    assert!(app.gpu_scene().lights.triangle_power() > 0.0);
    // Revert to the file's values: no emitters again.
    let file = scene.materials[floor].clone();
    app.app.world_mut().resource_mut::<Materials>().0[floor] = file;
    app.step();
    assert_eq!(app.gpu_scene().lights.triangle_count, 0);
}

/// Every instance's triangles in world space (current pose): (entity, triangle index, corners).
fn world_triangles(app: &mut HeadlessApp) -> Vec<(bevy_ecs::entity::Entity, usize, [Vec3; 3])> {
    let world = app.app.world_mut();
    let scene = world.resource::<raykin::scene::SceneAssets>().0.clone();
    let instances: Vec<_> = world
        .query::<(
            bevy_ecs::entity::Entity,
            &raykin::scene::GlobalTransform,
            &MeshInstance,
            Option<&raykin::scene::SkinnedMesh>,
        )>()
        .iter(world)
        .map(|(e, g, m, s)| {
            (
                e,
                if s.is_some() {
                    glam::Mat4::IDENTITY
                } else {
                    g.0
                },
                m.mesh,
            )
        })
        .collect();
    let gpu_scene = world.resource::<GpuScene>();
    let mut out = Vec::new();
    for (entity, m, mesh) in instances {
        let positions = gpu_scene.mesh_slots[mesh]
            .positions
            .clone()
            .unwrap_or_else(|| scene.meshes[mesh].positions.clone());
        for (i, t) in scene.meshes[mesh].triangles.iter().enumerate() {
            out.push((
                entity,
                i,
                t.map(|v| m.transform_point3(positions[v as usize])),
            ));
        }
    }
    out
}

/// Where the ray meets the triangle's plane inside the triangle (edges widened by `slack`), by edge signs:
/// a different method from the GPU's Moeller-Trumbore.
fn plane_hit(origin: Vec3, dir: Vec3, [a, b, c]: [Vec3; 3], slack: f32) -> Option<f32> {
    let n = (b - a).cross(c - a);
    let denom = n.dot(dir);
    if denom.abs() < 1e-12 {
        return None;
    }
    let dist = n.dot(a - origin) / denom;
    if dist <= 0.0 {
        return None;
    }
    let p = origin + dir * dist;
    let inside = [(a, b), (b, c), (c, a)]
        .iter()
        .all(|(u, v)| (*v - *u).cross(p - *u).dot(n) >= -slack * n.length_squared());
    inside.then_some(dist)
}

/// Picks every `step`-th pixel through the GPU pick pass and checks it against a brute-force cast of
/// the same ray over every triangle: same nearest surface (a different triangle only where two meet at the
/// same distance: shared edges), barycentrics that put the hit on the ray, the triangle's own material. At
/// least `min_hit_fraction` of the pixels must hit; at most 1% may disagree on hit vs miss (silhouette edges).
fn check_picking(scene: Arc<SceneAsset>, time: Option<f32>, step: usize, min_hit_fraction: f64) {
    let (mut app, _gpu) = app(&scene);
    if let Some(t) = time {
        app.set_time(0, t).expect("animated");
    }
    app.step();
    let view = *app.app.world().resource::<raykin::camera::CameraView>();
    let triangles = world_triangles(&mut app);
    let (mut hits, mut checked, mut edge_misses) = (0, 0, 0);
    for py in (0..H).step_by(step) {
        for px in (0..W).step_by(step) {
            let (origin, dir) = view.ray_through(px as f32 + 0.5, py as f32 + 0.5, W, H);
            let picked = raykin::render::picking::pick_pixel(app.app.world(), px, py);
            let nearest = triangles
                .iter()
                .filter_map(|(e, i, t)| plane_hit(origin, dir, *t, 0.0).map(|d| (*e, *i, d)))
                .min_by(|a, b| a.2.total_cmp(&b.2));
            checked += 1;
            match (picked, nearest) {
                (None, None) => {}
                (Some(p), Some((entity, triangle, dist))) => {
                    hits += 1;
                    let corners = triangles
                        .iter()
                        .find(|(e, i, _)| *e == p.entity && *i == p.triangle)
                        .expect("the picked triangle exists")
                        .2;
                    if (p.entity, p.triangle) != (entity, triangle) {
                        let d = plane_hit(origin, dir, corners, 1e-4);
                        assert!(
                            d.is_some_and(|d| (d - dist).abs() <= 1e-3 * dist),
                            "{}: pixel ({px}, {py}): picked triangle {} at {d:?}, nearest is {triangle} at {dist}",
                            scene.source,
                            p.triangle
                        );
                    }
                    let [u, v] = p.barycentrics;
                    let point = corners[0] * (1.0 - u - v) + corners[1] * u + corners[2] * v;
                    let off_ray = (point - origin).cross(dir).length();
                    assert!(
                        off_ray <= 1e-3 * dist.max(1.0),
                        "{}: pixel ({px}, {py}): the hit point is {off_ray} off the ray",
                        scene.source
                    );
                    let mesh = app
                        .app
                        .world()
                        .get::<MeshInstance>(p.entity)
                        .expect("mesh")
                        .mesh;
                    assert_eq!(p.mesh, mesh);
                    assert_eq!(
                        p.material,
                        Some(scene.meshes[mesh].triangle_materials[p.triangle] as usize)
                            .filter(|&m| m < scene.materials.len())
                    );
                }
                (p, e) => {
                    edge_misses += 1;
                    eprintln!(
                        "{}: pixel ({px}, {py}): picked {p:?}, brute force {e:?}",
                        scene.source
                    );
                }
            }
        }
    }
    assert!(
        edge_misses * 100 <= checked,
        "{}: {edge_misses} of {checked} pixels disagree on hit or miss",
        scene.source
    );
    assert!(
        hits as f64 > min_hit_fraction * checked as f64 && hits < checked,
        "{}: {hits} of {checked} rays hit",
        scene.source
    );
}

#[test]
fn picking_matches_a_brute_force_ray_cast() {
    check_picking(viewer_scene(), None, 3, 0.25);
    let cornell = Arc::new(
        load_gltf(
            shared_assets().join("CornellBox/CornellBox.glb"),
            &LoadOptions::default(),
        )
        .expect("Cornell box loads"),
    );
    check_picking(cornell, None, 3, 0.25);
    // Skinned: picking sees the deformed pose the GPU traces.
    let man = Arc::new(
        load_gltf(
            shared_assets().join("CesiumMan/glTF/CesiumMan.gltf"),
            &LoadOptions {
                skip_images: true,
                ..Default::default()
            },
        )
        .expect("CesiumMan loads"),
    );
    check_picking(man, Some(0.7), 1, 0.03);
}

fn temp_dir(name: &str) -> PathBuf {
    crate::common::fresh_dir(&format!("editor-{name}"))
}

/// Saves `source` with one material edited, to .gltf and .glb in a different folder, and reloads both.
fn check_save(source: PathBuf) {
    let original = load_gltf(&source, &LoadOptions::default()).expect("source loads");
    let mut materials = original.materials.clone();
    materials[0].base_color = Vec4::new(0.1, 0.7, 0.2, 1.0);
    materials[0].roughness = 0.33;
    materials[0].emissive = Vec3::new(1.0, 0.5, 0.25);
    materials[0].emissive_strength = 4.0;
    materials[0].double_sided = !materials[0].double_sided;
    let had_texture = materials[0].base_color_texture.is_some();
    materials[0].base_color_texture = None;
    // The extensions the inspector edits: added where the file has none, written back as edited.
    for (i, m) in materials.iter_mut().enumerate().take(2) {
        use raykin::scene::material_extensions::{
            Clearcoat, Sheen, Specular, Transmission, Volume,
        };
        m.extensions.ior = 1.7;
        m.extensions.transmission = Some(Transmission {
            factor: 0.8,
            texture: None,
        });
        // An infinite attenuation distance ("none") must not come back as JSON null.
        m.extensions.volume = Some(Volume {
            thickness: 0.5,
            thickness_texture: None,
            attenuation_distance: if i == 0 { 2.5 } else { f32::INFINITY },
            attenuation_color: Vec3::new(0.9, 0.6, 0.3),
        });
        m.extensions.specular = Some(Specular {
            factor: 0.6,
            texture: None,
            color: Vec3::new(1.0, 0.5, 0.25),
            color_texture: None,
        });
        // The layers: a file's texture entries the edit turned off (None) must go.
        m.extensions.clearcoat = Some(Clearcoat {
            factor: 0.75,
            texture: None,
            roughness: 0.25,
            roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
        });
        m.extensions.sheen = Some(Sheen {
            color: Vec3::new(0.5, 0.25, 0.125),
            color_texture: None,
            roughness: 0.375,
            roughness_texture: None,
        });
    }
    // Unlit switched on (the inspector's checkbox) on the last material.
    if let Some(m) = materials.last_mut() {
        m.extensions.unlit = !m.extensions.unlit;
    }
    // The file's own coats: a texture turned off, a coat normal map's scale changed.
    for m in materials.iter_mut().skip(2) {
        if let Some(c) = &mut m.extensions.clearcoat {
            if c.normal_texture.is_some() {
                c.normal_scale = 0.5;
            }
            c.texture = None;
        }
    }
    let bytes = std::fs::read(&source).expect("read");
    let dir = temp_dir(&source.file_stem().unwrap().to_string_lossy());
    for ext in ["gltf", "glb"] {
        let out = dir.join(format!("edited/out.{ext}"));
        raykin::scene::save_with_materials(
            &bytes,
            source.parent().unwrap(),
            &source.display().to_string(),
            Default::default(),
            &materials,
            &out,
        )
        .unwrap_or_else(|e| panic!("{}: {e}", out.display()));
        let saved = load_gltf(&out, &LoadOptions::default())
            .unwrap_or_else(|e| panic!("{}: reload: {e}", out.display()));
        assert_eq!(saved.materials, materials, "{}: materials", out.display());
        assert_eq!(saved.meshes.len(), original.meshes.len());
        for (a, b) in saved.meshes.iter().zip(&original.meshes) {
            assert_eq!(
                a.positions,
                b.positions,
                "{}: mesh `{}`",
                out.display(),
                b.name
            );
            assert_eq!(a.triangles, b.triangles);
        }
        assert_eq!(saved.images.len(), original.images.len());
        for (a, b) in saved.images.iter().zip(&original.images) {
            assert_eq!((a.width, a.height), (b.width, b.height));
            assert!(
                a.rgba8 == b.rgba8,
                "{}: image `{}` changed",
                out.display(),
                b.name
            );
        }
        assert_eq!(saved.animations.len(), original.animations.len());
        assert_eq!(saved.nodes.len(), original.nodes.len());
        assert!(had_texture || saved.materials[0].base_color_texture.is_none());
    }
}

#[test]
fn save_as_writes_the_edited_materials() {
    // External .bin and .png, referenced from another folder.
    check_save(shared_assets().join("TextureCoordinateTest/glTF/TextureCoordinateTest.gltf"));
    // A .glb: its binary chunk becomes out.bin beside the .gltf, and is repacked into the .glb.
    check_save(shared_assets().join("CornellBox/CornellBox.glb"));
    // Clearcoat textures (and coat normal maps with their scale) on the materials left as they were.
    check_save(shared_assets().join("ClearCoatTest/glTF/ClearCoatTest.gltf"));
}

#[test]
fn saving_refuses_bad_requests_clearly() {
    let source = shared_assets().join("CornellBox/CornellBox.glb");
    let bytes = std::fs::read(&source).expect("read");
    let original = load_gltf(&source, &LoadOptions::default()).expect("loads");
    let dir = temp_dir("refuse");
    let err = raykin::scene::save_with_materials(
        &bytes,
        source.parent().unwrap(),
        "CornellBox.glb",
        Default::default(),
        &original.materials,
        &dir.join("out.obj"),
    )
    .expect_err("extension");
    assert!(
        err.to_string().contains("must end in .gltf or .glb"),
        "{err}"
    );
    let err = raykin::scene::save_with_materials(
        &bytes,
        source.parent().unwrap(),
        "CornellBox.glb",
        Default::default(),
        &original.materials[..1],
        &dir.join("out.glb"),
    )
    .expect_err("count");
    assert!(err.to_string().contains("materials"), "{err}");
}

fn material_variants_file() -> PathBuf {
    repo_root().join("assets/conformance/Authored/MaterialVariants.gltf")
}

/// The inspector's variant switch (it writes [`ActiveVariant`]) on MaterialVariants.gltf: a grey quad whose
/// variants `red` and `blue` map it to red and blue materials, under a white sky. Each switch restarts the
/// accumulation once and recolours the quad's pixels towards the variant's base colour while the sky's stay
/// bit-identical; switching back gives the first image bit for bit (same seed and samples). Neither a mesh BVH
/// nor the top-level one is rebuilt and no GPU buffer is recreated: only triangle material words change.
#[test]
fn variant_switch_recolours_without_rebuilding_bvhs() {
    use raykin::render::Environment;
    use raykin::scene::ActiveVariant;
    const SIZE: u32 = 16;
    const SPP: u32 = 8;
    let scene = Arc::new(load_gltf(material_variants_file(), &LoadOptions::default()).unwrap());
    let (ctx, _gpu) = gpu();
    let settings = RenderSettings {
        width: SIZE,
        height: SIZE,
        max_depth: 1,
        environment: Environment::Constant([1.0; 3]),
        ..Default::default()
    };
    // The unit quad at z = 0 covers the middle 58% of a 60-degree view from 1.5 away.
    let camera = CameraChoice::LookAt {
        eye: Vec3::new(0.0, 0.0, 1.5),
        target: Vec3::ZERO,
        yfov: 60f32.to_radians(),
    };
    let mut app = HeadlessApp::new(ctx, scene.clone(), settings, &camera).expect("uploads");
    app.accumulate(SPP, SPP, |_| {});
    let file_image = app.radiance();
    let quad: Vec<usize> = (5..11)
        .flat_map(|y| (5..11).map(move |x| (y * SIZE + x) as usize))
        .collect();
    let sky = [0usize, (SIZE - 1) as usize, (SIZE * SIZE - 1) as usize];
    let chroma = |c: [f64; 3]| {
        let sum = c.iter().sum::<f64>().max(1e-9);
        c.map(|x| x / sum)
    };
    let quad_chroma = |img: &[[f32; 3]]| {
        let mut sum = [0.0f64; 3];
        for &i in &quad {
            for c in 0..3 {
                sum[c] += img[i][c] as f64;
            }
        }
        chroma(sum)
    };
    let distance =
        |a: [f64; 3], b: [f64; 3]| (0..3).map(|c| (a[c] - b[c]).powi(2)).sum::<f64>().sqrt();
    let gpu_scene = app.gpu_scene();
    let (built, generation) = (gpu_scene.build_seconds, gpu_scene.generation);
    let order = gpu_scene.mesh_slots[0].blas.order().to_vec();
    let rebuilds = app.bvh_stats().rebuilds;

    let show = |app: &mut HeadlessApp, variant: Option<usize>| -> Vec<[f32; 3]> {
        let epoch = app.accumulation_mut().epoch;
        app.app.world_mut().resource_mut::<ActiveVariant>().0 = variant;
        app.accumulate(SPP, SPP, |_| {});
        assert_eq!(
            app.accumulation_mut().epoch,
            epoch + 1,
            "{variant:?}: one restart"
        );
        assert_eq!(app.samples(), SPP, "{variant:?}: a fresh accumulation");
        assert_eq!(app.gpu_scene().variant, variant);
        assert_eq!(
            app.bvh_stats().last_tlas_seconds,
            0.0,
            "{variant:?}: top-level BVH rebuilt"
        );
        app.radiance()
    };
    for (variant, name) in scene.variants.iter().enumerate() {
        let material = scene
            .materials
            .iter()
            .find(|m| &m.name == name)
            .expect("each variant maps the quad to the material of its name");
        let target = chroma(material.base_color.truncate().as_dvec3().to_array());
        let image = show(&mut app, Some(variant));
        let (before, after) = (
            distance(quad_chroma(&file_image), target),
            distance(quad_chroma(&image), target),
        );
        eprintln!(
            "variant `{name}`: quad chromaticity {before:.3} -> {after:.3} from the material's"
        );
        assert!(
            before > 0.3 && after < 0.1,
            "variant `{name}`: the quad's chromaticity is {after:.3} from its material's (was {before:.3})"
        );
        for &i in &sky {
            assert_eq!(
                image[i], file_image[i],
                "variant `{name}`: sky pixel {i} changed"
            );
        }
    }
    let back = show(&mut app, None);
    assert!(
        back == file_image,
        "the file's materials again: the image differs"
    );

    let gpu_scene = app.gpu_scene();
    assert_eq!(
        gpu_scene.build_seconds, built,
        "the scene was uploaded again"
    );
    assert_eq!(
        gpu_scene.generation, generation,
        "GPU buffers were recreated"
    );
    assert_eq!(gpu_scene.mesh_slots[0].blas.order(), &order[..]);
    assert_eq!(app.bvh_stats().rebuilds, rebuilds, "a mesh BVH was rebuilt");
    // Nothing changed: the accumulation goes on.
    app.step();
    assert_eq!(app.samples(), 2 * SPP);
}

/// File > Save as keeps KHR_materials_variants: the saved file offers every variant with the same mappings,
/// and its primitives keep the file's own materials (the variant shown is a view setting, not written).
#[test]
fn save_as_keeps_every_variant() {
    let source = material_variants_file();
    let original = load_gltf(&source, &LoadOptions::default()).unwrap();
    let bytes = std::fs::read(&source).unwrap();
    let out = temp_dir("variants").join("saved.gltf");
    raykin::scene::save_with_materials(
        &bytes,
        source.parent().unwrap(),
        &source.display().to_string(),
        Default::default(),
        &original.materials,
        &out,
    )
    .unwrap();
    let saved = load_gltf(&out, &LoadOptions::default()).unwrap();
    assert_eq!(saved.variants, original.variants);
    assert_eq!(saved.active_variant, None);
    for (a, b) in saved.meshes.iter().zip(&original.meshes) {
        assert_eq!(a.primitive_variants, b.primitive_variants);
        for variant in [None, Some(0), Some(1)] {
            assert_eq!(
                a.triangle_materials_under(variant),
                b.triangle_materials_under(variant),
                "{variant:?}"
            );
        }
    }
}
