//! Traversal: static meshes traced through compressed 8-wide BVHs give the same image as through the
//! child-pair BVH2 (both trees hold the same triangles, so with the same seed every path takes the same hits;
//! scenes with deep trees, several meshes, textures and alpha-masked materials), and the shading-free
//! ray-casting pass casts exactly the rays it reports and counts the work they must do.

use crate::common::*;
use raykin::bvh::StaticLayout;
use raykin::camera::CameraChoice;
use raykin::gpu_deform::DeformBackend;
use raykin::render::RenderSettings;
use std::sync::Arc;

fn settings(size: u32, layout: StaticLayout, merge_static: bool) -> RenderSettings {
    RenderSettings {
        width: size,
        height: size,
        static_bvh: layout,
        merge_static,
        ..Default::default()
    }
}

/// Per-mesh wide trees (no merge) and per-mesh BVH2s.
fn render_both(file: &str, size: u32, spp: u32) -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
    let scene = shared_scene(file);
    let (ctx, _gpu) = gpu();
    let image = |layout| {
        render(
            &ctx,
            &scene,
            settings(size, layout, false),
            &CameraChoice::Auto,
            spp,
        )
    };
    (image(StaticLayout::Wide), image(StaticLayout::Binary))
}

/// How far two renders of one scene through different trees may differ: pixels further apart than
/// `tolerance` (relative; 0: any difference) at most one in `one_in`, channel means within `mean`.
struct Agreement {
    tolerance: f32,
    one_in: usize,
    mean: f64,
}

/// Two traversal orders over the same triangles: equal-distance hits on coplanar triangles may resolve
/// differently, a stray pixel, no more. Anything beyond is a traversal bug (a missed subtree shows as a hole).
const SAME_TRIANGLES: Agreement = Agreement {
    tolerance: 0.0,
    one_in: 200,
    mean: 1e-3,
};

/// A merged tree against per-mesh trees: the merged tree intersects world-space copies of the triangles, so
/// a hit's distance and barycentrics differ in their last bits, and so does everything shaded from them; a
/// path whose Russian roulette or a grazing bounce decides otherwise is rare. A missed member or a wrong
/// mapping back changes far more (a whole object's pixels).
const WORLD_SPACE_COPIES: Agreement = Agreement {
    tolerance: 1e-3,
    one_in: 100,
    mean: 2e-3,
};

fn assert_agree(file: &str, what: [&str; 2], a: &[[f32; 3]], b: &[[f32; 3]], agree: Agreement) {
    assert_all_finite(a, file);
    let far = a
        .iter()
        .zip(b)
        .filter(|(x, y)| {
            (0..3).any(|c| (x[c] - y[c]).abs() > agree.tolerance * y[c].abs().max(1e-2))
        })
        .count();
    assert!(
        far * agree.one_in <= a.len(),
        "{file}: {far} of {} pixels differ by more than {} between the {} and {} BVHs",
        a.len(),
        agree.tolerance,
        what[0],
        what[1]
    );
    let (ma, mb) = (mean_rgb(a), mean_rgb(b));
    for c in 0..3 {
        assert!(
            (ma[c] - mb[c]).abs() <= agree.mean * mb[c].max(1e-3),
            "{file}: channel {c} mean {} ({}) vs {} ({})",
            ma[c],
            what[0],
            mb[c],
            what[1]
        );
    }
}

fn assert_same_image(file: &str, size: u32, spp: u32) {
    let (wide, binary) = render_both(file, size, spp);
    assert_agree(file, ["wide", "binary"], &wide, &binary, SAME_TRIANGLES);
}

/// Renders `file` with the static instances merged and without; returns the merge's members (node, mesh) and
/// how many leaf slots its tree has beyond the members' triangles (the spatial splits' repeats).
fn assert_merge_keeps_the_image(file: &str, size: u32, spp: u32) -> (Vec<(u32, u32)>, i64) {
    let scene = shared_scene(file);
    let (ctx, _gpu) = gpu();
    let mut merged = raykin::headless::HeadlessApp::new(
        ctx.clone(),
        scene.clone(),
        settings(size, StaticLayout::Wide, true),
        &CameraChoice::Auto,
    )
    .expect("scene uploads");
    merged.accumulate(spp, 64, |_| {});
    let merge = merged.gpu_scene().merge.as_ref();
    let members: Vec<(u32, u32)> = merge
        .map(|m| m.members.iter().map(|m| (m.node, m.mesh)).collect())
        .unwrap_or_default();
    let member_triangles: usize = members
        .iter()
        .map(|&(_, mesh)| scene.meshes[mesh as usize].triangles.len())
        .sum();
    let repeats = merge.map_or(0, |m| m.triangles as i64 - member_triangles as i64);
    let per_mesh = render(
        &ctx,
        &scene,
        settings(size, StaticLayout::Wide, false),
        &CameraChoice::Auto,
        spp,
    );
    assert_agree(
        file,
        ["merged", "per-mesh"],
        &merged.radiance(),
        &per_mesh,
        WORLD_SPACE_COPIES,
    );
    (members, repeats)
}

#[test]
fn flight_helmet_wide_equals_binary() {
    // Six meshes, deep trees, textures and an alpha-masked material.
    assert_same_image("FlightHelmet/glTF/FlightHelmet.gltf", 32, 4);
}

#[test]
fn alpha_blend_test_wide_equals_binary() {
    assert_same_image(
        "AlphaBlendModeTest/glTF-Binary/AlphaBlendModeTest.glb",
        32,
        4,
    );
}

/// FlightHelmet's six meshes overlap (shell, straps, lenses, stand): all six are merged, and the image is the
/// per-mesh trees' (same paths: the merge maps every hit back to the member's own triangle slot, so shading,
/// textures and the light list see what they saw). The merged tree's default preset cuts large triangles into
/// several leaves (spatial splits): a hit on any copy maps back to the same slot.
#[test]
fn merged_static_tree_gives_the_per_mesh_image() {
    let (members, repeats) =
        assert_merge_keeps_the_image("FlightHelmet/glTF/FlightHelmet.gltf", 32, 4);
    assert_eq!(members.len(), 6, "{members:?}");
    assert!(repeats > 0, "no triangle was split: {repeats}");
    // The Cornell box's light is a member: next-event estimation and MIS find it through the mapped hits.
    let (members, _) = assert_merge_keeps_the_image("CornellBox/CornellBox.glb", 32, 8);
    assert!(members.len() >= 2, "{members:?}");
}

/// The merged triangles skip the alpha test: meshes with an alpha-masked material stay outside the merge, and
/// their cut-outs render as before.
#[test]
fn alpha_masked_meshes_stay_out_of_the_merge() {
    let file = "AlphaBlendModeTest/glTF-Binary/AlphaBlendModeTest.glb";
    let (members, _) = assert_merge_keeps_the_image(file, 32, 4);
    let scene = shared_scene(file);
    let masked = |mesh: u32| {
        scene.meshes[mesh as usize]
            .triangle_materials
            .iter()
            .any(|&m| {
                scene
                    .materials
                    .get(m as usize)
                    .is_some_and(|m| matches!(m.alpha_mode, raykin::scene::AlphaMode::Mask(_)))
            })
    };
    let masked_nodes = scene
        .nodes
        .iter()
        .filter(|n| n.mesh.is_some_and(|m| masked(m as u32)))
        .count();
    assert!(masked_nodes > 0, "the test file has masked meshes");
    assert!(members.len() >= 2, "{members:?}");
    assert!(
        members.iter().all(|&(_, mesh)| !masked(mesh)),
        "{members:?}"
    );
}

/// A member that moves after all (the inspector) leaves the merge for good, the rest is rebuilt in place, and
/// the image is that of a scene file with the node moved (traced without the merge).
#[test]
fn a_moved_member_leaves_the_merge_and_renders_where_it_went() {
    use raykin::scene::{SceneNode, Transform};
    let file = "CornellBox/CornellBox.glb";
    let scene = shared_scene(file);
    let (ctx, _gpu) = gpu();
    let mut app = raykin::headless::HeadlessApp::new(
        ctx.clone(),
        scene.clone(),
        settings(32, StaticLayout::Wide, true),
        &CameraChoice::Auto,
    )
    .expect("scene uploads");
    app.step();
    let before: Vec<u32> = app
        .gpu_scene()
        .merge
        .as_ref()
        .expect("merged")
        .members
        .iter()
        .map(|m| m.node)
        .collect();
    assert!(before.len() >= 3, "{before:?}");
    let moved = *before
        .iter()
        .find(|&&n| scene.nodes[n as usize].name == "small.box")
        .expect("the small box is a member");
    let offset = glam::Vec3::new(0.07, 0.0, 0.05) * scene_size(&scene);
    let world = app.app.world_mut();
    let entity = world
        .query::<(bevy_ecs::entity::Entity, &SceneNode)>()
        .iter(world)
        .find(|(_, n)| n.node == moved as usize)
        .map(|(e, _)| e)
        .expect("the member's entity");
    world
        .get_mut::<Transform>(entity)
        .expect("placed")
        .translation += offset;
    app.step();
    app.restart_accumulation();
    app.accumulate(8, 64, |_| {});
    let after: Vec<u32> = app
        .gpu_scene()
        .merge
        .as_ref()
        .expect("still merged")
        .members
        .iter()
        .map(|m| m.node)
        .collect();
    let expected: Vec<u32> = before.iter().copied().filter(|&n| n != moved).collect();
    assert_eq!(after, expected);

    let mut edited = (*scene).clone();
    edited.nodes[moved as usize].transform.translation += offset;
    let reference = render(
        &ctx,
        &Arc::new(edited),
        settings(32, StaticLayout::Wide, false),
        &CameraChoice::Auto,
        8,
    );
    let unmoved = render(
        &ctx,
        &scene,
        settings(32, StaticLayout::Wide, false),
        &CameraChoice::Auto,
        8,
    );
    let image = app.radiance();
    assert!(
        image.iter().zip(&unmoved).filter(|(a, b)| a != b).count() * 20 > image.len(),
        "the move shows"
    );
    assert_agree(
        file,
        ["moved member", "edited file"],
        &image,
        &reference,
        WORLD_SPACE_COPIES,
    );
}

fn scene_size(scene: &raykin::scene::SceneAsset) -> f32 {
    let (lo, hi) = scene.rest_bounds().expect("geometry");
    (hi - lo).max_element()
}

/// A 24x16 view of `scene` with its static meshes in `layout`.
fn ray_casting_app(
    ctx: &raykin::gpu::GpuContext,
    scene: &Arc<raykin::scene::SceneAsset>,
    layout: StaticLayout,
    camera: &CameraChoice,
) -> raykin::headless::HeadlessApp {
    let settings = RenderSettings {
        width: 24,
        height: 16,
        static_bvh: layout,
        ..Default::default()
    };
    raykin::headless::HeadlessApp::new(ctx.clone(), scene.clone(), settings, camera)
        .expect("scene uploads")
}

/// From inside the Cornell box every camera ray hits a wall.
fn inside_the_box() -> CameraChoice {
    CameraChoice::LookAt {
        eye: glam::Vec3::new(-278.0, 450.0, -60.0),
        target: glam::Vec3::new(-278.0, 300.0, -559.0),
        yfov: 60f32.to_radians(),
    }
}

#[test]
fn raycast_pass_casts_one_camera_ray_per_pixel_and_one_bounce_per_hit() {
    let scene = shared_scene("CornellBox/CornellBox.glb");
    let (ctx, _gpu) = gpu();
    if !ctx.supports_timestamps() {
        eprintln!("adapter has no timestamp queries: the ray-casting pass reports nothing");
        return;
    }
    for layout in [StaticLayout::Wide, StaticLayout::Binary] {
        let mut app = ray_casting_app(&ctx, &scene, layout, &inside_the_box());
        let primary = app.cast_rays(false).expect("timestamps");
        let bounce = app.cast_rays(true).expect("timestamps");
        assert_eq!(primary.rays, 24 * 16, "{layout:?}");
        assert_eq!(
            bounce.rays,
            2 * 24 * 16,
            "{layout:?}: every camera ray hits inside the box"
        );
        assert!(primary.gpu_ms.is_finite() && bounce.gpu_ms > 0.0);
    }
}

/// The ray-casting pass's counting run counts what the rays must do, in either static layout: from inside the
/// Cornell box every camera ray fetches the top-level root, at least one node of the layout's kind (none of the
/// other) and tests at least one triangle and at most all of them, and every hit casts a bounce ray that does the
/// same at the top level; looking away from the box, every ray stops at the top-level root's box.
#[test]
fn traversal_work_counts_what_the_rays_must_do() {
    let scene = shared_scene("CornellBox/CornellBox.glb");
    let triangles = scene.triangle_count() as u64;
    let (ctx, _gpu) = gpu();
    let inside = inside_the_box();
    let away = CameraChoice::LookAt {
        eye: glam::Vec3::new(-278.0, 273.0, 800.0),
        target: glam::Vec3::new(-278.0, 273.0, 1600.0),
        yfov: 40f32.to_radians(),
    };
    let pixels = 24 * 16;
    for layout in [StaticLayout::Wide, StaticLayout::Binary] {
        let run = |camera: &CameraChoice| {
            ray_casting_app(&ctx, &scene, layout, camera).count_traversal_work(true)
        };
        let (work, rays) = run(&inside);
        assert_eq!(rays, 2 * pixels, "{layout:?}: every camera ray hits");
        let [tlas, bvh2, wide, tested] = work.camera;
        let (own, other) = match layout {
            StaticLayout::Wide => (wide, bvh2),
            _ => (bvh2, wide),
        };
        assert!(tlas >= pixels, "{layout:?}: {work:?}");
        assert!(own >= pixels && other == 0, "{layout:?}: {work:?}");
        assert!(
            tested >= pixels && tested <= pixels * triangles,
            "{layout:?}: {work:?}"
        );
        assert!(work.bounce[0] >= pixels, "{layout:?}: {work:?}");
        let (work, rays) = run(&away);
        assert_eq!(rays, pixels, "{layout:?}: no camera ray hits");
        assert!(work.camera[0] >= pixels, "{layout:?}: {work:?}");
        assert_eq!(
            (work.camera[1], work.camera[2], work.camera[3], work.bounce),
            (0, 0, 0, [0; 4]),
            "{layout:?}"
        );
    }
}

/// Four samples per pixel of `scene` in the kernel form `ctx` (an animated scene 0.7 s into its first clip, the
/// walk of CesiumMan).
fn four_samples(
    ctx: raykin::gpu::GpuContext,
    scene: &Arc<raykin::scene::SceneAsset>,
    settings: RenderSettings,
) -> raykin::headless::HeadlessApp {
    let mut app =
        raykin::headless::HeadlessApp::new(ctx, scene.clone(), settings, &CameraChoice::Auto)
            .expect("scene uploads");
    if !scene.animations.is_empty() {
        // A frame in the rest pose first: the pose's writes then reach textures made before them.
        app.step();
        app.set_time(0, 0.7).expect("the walk clip");
    }
    app.accumulate(4, 4, |_| {});
    app
}

/// CPU adapters read the scene from textures (`gpu::scene_in_textures`), GPUs from storage buffers; CI has
/// only a CPU adapter, so both forms run here. Same kernels over the same bytes: the same image, bit for bit.
/// Between them the renders read every buffer of the scene: FlightHelmet under an environment map (textures,
/// the merged tree, the per-mesh wide trees of its alpha-masked lenses, the map's texels and distributions),
/// the Cornell box (emissive triangles: the light list, its CDF and tree), and CesiumMan posed mid-walk (the
/// skinned positions and the refit BVH2, rewritten after a first frame by either deformer: copied again before
/// the trace).
#[test]
fn the_scene_read_through_textures_renders_the_buffers_image() {
    let (ctx, _gpu) = gpu();
    let form = |textures: bool| {
        let mut form = ctx.clone();
        form.scene_in_textures = textures;
        form
    };
    let environment = raykin::render::Environment::Map(raykin::environment::MapSettings {
        path: repo_root().join("tests/reference/lights/sunny_64x33.exr"),
        rotation_degrees: 30.0,
        strength: 1.0,
    });
    let sky = raykin::render::Environment::Sky;
    let man = "CesiumMan/glTF-Binary/CesiumMan.glb";
    for (file, environment, deform) in [
        (
            "FlightHelmet/glTF/FlightHelmet.gltf",
            environment,
            DeformBackend::Auto,
        ),
        (
            "CornellBox/CornellBox.glb",
            sky.clone(),
            DeformBackend::Auto,
        ),
        (man, sky.clone(), DeformBackend::Cpu),
        (man, sky, DeformBackend::Gpu),
    ] {
        let scene = shared_scene(file);
        let image = |textures: bool| {
            let settings = RenderSettings {
                environment: environment.clone(),
                deform,
                ..settings(24, StaticLayout::Wide, true)
            };
            four_samples(form(textures), &scene, settings).radiance()
        };
        assert_forms_render_the_same_image(&image(true), &image(false), file);
    }
}

#[test]
fn kernels_compiled_for_the_scene_shape_render_the_general_kernels_image() {
    use raykin::render::layout::{BLAS_LAYOUT_BINARY, BLAS_LAYOUT_WIDE};
    let (ctx, _gpu) = gpu();
    let form = |shaped: bool| {
        let mut form = ctx.clone();
        form.scene_shape_kernels = shaped;
        form
    };
    // The Cornell box merged into one wide tree (one leaf); CesiumMan, one skinned instance walking, traced
    // through the wide tree refit with its BVH2, or through the BVH2.
    let man = "CesiumMan/glTF-Binary/CesiumMan.glb";
    for (file, wide_deformed, layouts) in [
        ("CornellBox/CornellBox.glb", true, BLAS_LAYOUT_WIDE),
        (man, true, BLAS_LAYOUT_WIDE),
        (man, false, BLAS_LAYOUT_BINARY),
    ] {
        let scene = shared_scene(file);
        let image = |shaped: bool| {
            let mut ctx = form(shaped);
            ctx.wide_deformed = wide_deformed;
            let app = four_samples(ctx, &scene, settings(24, StaticLayout::Wide, true));
            let shape = app.gpu_scene();
            assert!(
                shape.sole_instance.is_some(),
                "{file}: the top level holds one leaf"
            );
            assert_eq!(shape.blas_layouts, layouts, "{file}: BLAS layouts");
            // The sky gradient's cells are sampled uniformly: the bilinear code is compiled out.
            assert!(
                shape.lights.environment_cells_uniform(),
                "{file}: the sky samples its cells uniformly"
            );
            app.radiance()
        };
        assert_forms_render_the_same_image(&image(true), &image(false), file);
    }
    // A map with a sun samples inside its cells bilinearly: the kernels keep that code (spheres under it, lit by
    // little else).
    let mut sunny = settings(16, StaticLayout::Wide, true);
    sunny.environment = raykin::render::Environment::Map(raykin::environment::MapSettings {
        path: repo_root().join("tests/reference/lights/sunny_64x33.exr"),
        rotation_degrees: 30.0,
        strength: 1.0,
    });
    let spheres =
        shared_scene("MetalRoughSpheresNoTextures/glTF-Binary/MetalRoughSpheresNoTextures.glb");
    let image = |shaped: bool| {
        let app = four_samples(form(shaped), &spheres, sunny.clone());
        assert!(
            !app.gpu_scene().lights.environment_cells_uniform(),
            "a sunny map is sampled bilinearly inside its cells"
        );
        app.radiance()
    };
    assert_forms_render_the_same_image(&image(true), &image(false), "spheres under a sunny map");
    // Not merged, the box's four meshes are four leaves: no shortcut; as BVH2s, the other layout.
    for (layout, layouts) in [
        (StaticLayout::Wide, BLAS_LAYOUT_WIDE),
        (StaticLayout::Binary, BLAS_LAYOUT_BINARY),
    ] {
        let mut app = raykin::headless::HeadlessApp::new(
            form(true),
            shared_scene("CornellBox/CornellBox.glb"),
            settings(8, layout, false),
            &CameraChoice::Auto,
        )
        .expect("scene uploads");
        app.accumulate(1, 1, |_| {});
        assert_eq!(app.gpu_scene().sole_instance, None, "four leaves");
        assert_eq!(app.gpu_scene().blas_layouts, layouts, "{layout:?}");
    }
}
