//! GPU deformation against the CPU reference (lavapipe; tiny images): the vertex pool the deform pass
//! writes equals what the CPU path writes, the GPU refit's node boxes (and the wide trees' quantised boxes) equal a
//! CPU refit of the same trees from the same positions, the GPU SAH cost equals the CPU's, and the conservative top-level bounds hold
//! every deformed vertex. Assets: CesiumMan (also with tangents added), Fox, RobotExpressive,
//! AnimatedMorphCube and the synthetic two-influence-set skin + morph file of the fixture tests.

use crate::common::{gpu_context as gpu, repo_root, shared_assets};

use glam::{Vec3, Vec4};
use obvhs::cwbvh::node::CwBvhNode;
use raykin::bvh::GpuBvhNode;
use raykin::camera::CameraChoice;
use raykin::gpu_deform::DeformBackend;
use raykin::headless::HeadlessApp;
use raykin::render::{Environment, RenderSettings};
use raykin::scene::{LoadOptions, SceneAsset, load_gltf};
use std::sync::Arc;

fn settings(deform: DeformBackend) -> RenderSettings {
    RenderSettings {
        width: 4,
        height: 4,
        spp_per_frame: 1,
        max_depth: 1,
        environment: Environment::Sky,
        deform,
        ..Default::default()
    }
}

fn load(path: std::path::PathBuf) -> Arc<SceneAsset> {
    Arc::new(
        load_gltf(
            &path,
            &LoadOptions {
                skip_images: true,
                ..Default::default()
            },
        )
        .unwrap(),
    )
}

/// CesiumMan with a tangent per vertex (pseudo-random unit vectors, both handednesses), so that skinned
/// tangents are covered: none of the sample characters ships TANGENT.
fn cesium_with_tangents() -> Arc<SceneAsset> {
    let mut scene = (*load(shared_assets().join("CesiumMan/glTF-Binary/CesiumMan.glb"))).clone();
    for mesh in scene.meshes.iter_mut().filter(|m| m.skin_weights.is_some()) {
        mesh.tangents = Some(
            (0..mesh.positions.len())
                .map(|v| {
                    let a = v as f32 * 0.7;
                    let t = Vec3::new(a.cos(), (a * 1.3).sin(), 0.4).normalize();
                    t.extend(if v % 3 == 0 { -1.0 } else { 1.0 })
                })
                .collect::<Vec<Vec4>>(),
        );
    }
    Arc::new(scene)
}

fn app(scene: &Arc<SceneAsset>, backend: DeformBackend) -> HeadlessApp {
    HeadlessApp::new(gpu(), scene.clone(), settings(backend), &CameraChoice::Auto).unwrap()
}

/// CesiumMan with the bad skin data the CPU reference has fallbacks for: influences naming joints outside
/// the skin, vertices whose weights are all zero (they follow the node), and a morph target at weight 0.5
/// with NaN deltas on some vertices (those fall back to their rest position).
fn cesium_with_bad_data() -> Arc<SceneAsset> {
    let mut scene = (*load(shared_assets().join("CesiumMan/glTF-Binary/CesiumMan.glb"))).clone();
    for mesh in scene.meshes.iter_mut().filter(|m| m.skin_weights.is_some()) {
        let sw = mesh.skin_weights.as_mut().unwrap();
        for (v, (j, w)) in sw.joints.iter_mut().zip(&mut sw.weights).enumerate() {
            match v % 7 {
                0 => j[0] = 500,
                1 => *w = [0.0; 4],
                _ => {}
            }
        }
        let n = mesh.positions.len();
        mesh.morph_targets.push(raykin::scene::MorphTarget {
            positions: (0..n)
                .map(|v| {
                    if v % 11 == 0 {
                        Vec3::NAN
                    } else {
                        Vec3::new(0.0, 0.01 * (v % 5) as f32, 0.0)
                    }
                })
                .collect(),
            normals: None,
            tangents: None,
        });
        mesh.default_morph_weights = vec![0.5];
    }
    Arc::new(scene)
}

/// The scene posed at (clip, t) after one frame with `backend`.
fn posed(scene: &Arc<SceneAsset>, backend: DeformBackend, clip: usize, t: f32) -> HeadlessApp {
    let mut app = app(scene, backend);
    pose(&mut app, clip, t);
    app
}

fn pose(app: &mut HeadlessApp, clip: usize, t: f32) {
    app.set_time(clip, t).unwrap();
    app.step();
}

fn words(app: &HeadlessApp, buffer: &wgpu::Buffer) -> Vec<u32> {
    bytemuck::cast_slice(&app.ctx.read_buffer(buffer, buffer.size())).to_vec()
}

fn snorm16s(w: u32) -> [i32; 2] {
    [
        (w & 0xffff) as u16 as i16 as i32,
        (w >> 16) as u16 as i16 as i32,
    ]
}

/// Octahedral words agree within one snorm16 step per component (the pool stores 16-bit normals; the two
/// paths round the same f32 vector, which may differ in the last bit).
fn oct_close(a: u32, b: u32) -> bool {
    let (a, b) = (snorm16s(a), snorm16s(b));
    (a[0] - b[0]).abs() <= 1 && (a[1] - b[1]).abs() <= 1
}

fn positions_of(pool: &[u32], offset: u32, n: usize) -> Vec<Vec3> {
    let words = raykin::render::layout::POSITION_WORDS as usize;
    pool[offset as usize..offset as usize + words * n]
        .chunks_exact(words)
        .map(|c| {
            Vec3::new(
                f32::from_bits(c[0]),
                f32::from_bits(c[1]),
                f32::from_bits(c[2]),
            )
        })
        .collect()
}

struct Checked {
    meshes: usize,
    /// Meshes away from their rest pose (a morph mesh at zero weights is not).
    moved: usize,
    worst_position: f64,
    loose_area: f64,
    /// Wide nodes compared.
    wide_nodes: usize,
}

/// Compares the current frame of the GPU path with the CPU path, mesh by mesh.
fn compare(scene: &Arc<SceneAsset>, cpu: &HeadlessApp, gpu_app: &HeadlessApp, t: f32) -> Checked {
    let scene_g = gpu_app.gpu_scene();
    let deformer = gpu_app
        .deformation()
        .deformer
        .as_ref()
        .expect("the GPU backend deforms this scene");
    let owned = deformer.owned();
    let (pool_c, pool_g) = (
        words(cpu, &cpu.gpu_scene().vertex_pool),
        words(gpu_app, &scene_g.vertex_pool),
    );
    let nodes_g: Vec<GpuBvhNode> =
        bytemuck::cast_slice(&words(gpu_app, &scene_g.blas_nodes)).to_vec();
    let wide_g: Vec<CwBvhNode> =
        bytemuck::cast_slice(&words(gpu_app, &scene_g.wide_nodes)).to_vec();
    let cpu_deformed = gpu_app
        .app
        .world()
        .resource::<raykin::animation::DeformedMeshes>();
    let mut out = Checked {
        meshes: 0,
        moved: 0,
        worst_position: 0.0,
        loose_area: 0.0,
        wide_nodes: 0,
    };
    for (m, _) in owned.iter().enumerate().filter(|(_, o)| **o) {
        let mesh = &scene.meshes[m];
        let n = mesh.positions.len();
        let slot = &scene_g.mesh_slots[m];
        let g = slot.gpu;
        assert!(
            cpu_deformed.meshes.get(m).is_none_or(Option::is_none),
            "{t}: mesh {m} was deformed on the CPU too"
        );
        // Positions: 1e-5 of the mesh's largest coordinate.
        let pc = positions_of(&pool_c, g.position_offset, n);
        let pg = positions_of(&pool_g, g.position_offset, n);
        let scale = pc
            .iter()
            .map(|p| p.abs().max_element())
            .fold(1e-3f32, f32::max) as f64;
        let worst = pc
            .iter()
            .zip(&pg)
            .map(|(a, b)| (*a - *b).abs().max_element() as f64)
            .fold(0.0, f64::max);
        assert!(
            worst <= 1e-5 * scale,
            "{} t={t} mesh {m}: position differs by {worst:e} (scale {scale})",
            scene.source
        );
        out.worst_position = out.worst_position.max(worst / scale);
        out.moved += pg
            .iter()
            .zip(&mesh.positions)
            .any(|(a, b)| (*a - *b).length() > 1e-4 * scale as f32) as usize;
        if g.normal_offset != raykin::render::layout::NONE {
            let o = g.normal_offset as usize;
            for v in 0..n {
                assert!(
                    oct_close(pool_c[o + v], pool_g[o + v]),
                    "{} t={t} mesh {m} vertex {v}: normal {:08x} vs {:08x}",
                    scene.source,
                    pool_c[o + v],
                    pool_g[o + v]
                );
            }
        }
        if g.tangent_offset != raykin::render::layout::NONE {
            let o = g.tangent_offset as usize;
            for v in 0..n {
                assert!(oct_close(pool_c[o + 2 * v], pool_g[o + 2 * v]));
                assert_eq!(pool_c[o + 2 * v + 1], pool_g[o + 2 * v + 1], "handedness");
            }
        }
        // Refit: the GPU's boxes are exactly a CPU refit of the same tree from the GPU's positions, and so
        // are the wide tree's quantised boxes, which the kernels traverse.
        let tree = slot.blas.binary().expect("a deformable mesh has a BVH2");
        let count = tree.flat.nodes.len();
        let root = slot.blas_node_offset as usize;
        let gpu_nodes = &nodes_g[root..root + count];
        let mut cpu_tree = tree.clone();
        cpu_tree.refit(&pg, &slot.gpu_triangles);
        assert_eq!(
            cpu_tree.flat.nodes, gpu_nodes,
            "{} t={t} mesh {m}: GPU refit boxes",
            scene.source
        );
        let wide = cpu_tree
            .wide
            .as_ref()
            .expect("deforming meshes have a wide tree");
        let root = slot.wide_node_offset as usize;
        assert_eq!(
            g.blas_root,
            slot.wide_node_offset | raykin::render::layout::WIDE_BLAS
        );
        assert_eq!(
            wide.nodes,
            &wide_g[root..root + wide.nodes.len()],
            "{} t={t} mesh {m}: GPU wide refit",
            scene.source
        );
        out.wide_nodes += wide.nodes.len();
        // The top-level bounds hold every deformed vertex.
        let (lo, hi) = slot.deformed_bounds.expect("bounds of a posed mesh");
        for p in &pg {
            assert!(
                p.cmpge(lo).all() && p.cmple(hi).all(),
                "{} t={t} mesh {m}: {p} outside the conservative bounds {lo}..{hi}",
                scene.source
            );
        }
        let (rlo, rhi) = cpu_tree.flat.root_bounds();
        let area = |d: Vec3| (d.x * d.y + d.y * d.z + d.z * d.x) as f64;
        out.loose_area = out
            .loose_area
            .max(area(hi - lo) / area(rhi - rlo).max(1e-12));
        out.meshes += 1;
    }
    out
}

#[test]
fn gpu_deformation_matches_cpu_reference() {
    // The device's lock: these tests compile pipelines, which other tests count.
    let _device = crate::common::gpu().1;
    let assets = shared_assets();
    let cases: Vec<(&str, Arc<SceneAsset>, usize, [f32; 3])> = vec![
        (
            "CesiumMan",
            load(assets.join("CesiumMan/glTF-Binary/CesiumMan.glb")),
            0,
            [0.3, 1.3, 1.9],
        ),
        (
            "CesiumMan+tangents",
            cesium_with_tangents(),
            0,
            [0.7, 1.3, 2.0],
        ),
        (
            "CesiumMan+bad data",
            cesium_with_bad_data(),
            0,
            [0.5, 1.0, 1.5],
        ),
        (
            "Fox",
            load(assets.join("Fox/glTF-Binary/Fox.glb")),
            2,
            [0.1, 0.4, 0.9],
        ),
        (
            "RobotExpressive",
            load(assets.join("RobotExpressive/RobotExpressive.glb")),
            0,
            [0.5, 1.5, 2.5],
        ),
        (
            "AnimatedMorphCube",
            load(assets.join("AnimatedMorphCube/glTF/AnimatedMorphCube.gltf")),
            0,
            [0.4, 1.2, 2.8],
        ),
        (
            "synthetic skin + morph",
            load(repo_root().join("tests/reference/skinning/synthetic_skin_morph.gltf")),
            0,
            [0.25, 0.5, 0.9],
        ),
    ];
    for (name, scene, clip, times) in cases {
        // One app per backend, posed at each time in turn (later poses also exercise rebuilt trees).
        let (mut cpu, mut gpu_app) = (
            app(&scene, DeformBackend::Cpu),
            app(&scene, DeformBackend::Gpu),
        );
        for t in times {
            pose(&mut cpu, clip, t);
            pose(&mut gpu_app, clip, t);
            let c = compare(&scene, &cpu, &gpu_app, t);
            eprintln!(
                "{name} t={t}: {} GPU-deformed meshes ({} away from rest); worst position difference {:.2e} of the largest coordinate; conservative TLAS box area / refit root area <= {:.2}",
                c.meshes, c.moved, c.worst_position, c.loose_area
            );
            assert!(c.moved > 0, "{name}: nothing deformed on the GPU");
            assert!(c.wide_nodes > 0, "{name}: no wide tree refit");
        }
    }
}

/// The SAH cost measured on the GPU and read back a frame late equals the CPU's cost of the same tree.
#[test]
fn gpu_sah_ratio_matches_cpu() {
    let _device = crate::common::gpu().1;
    let scene = load(shared_assets().join("CesiumMan/glTF-Binary/CesiumMan.glb"));
    let mut app = posed(&scene, DeformBackend::Gpu, 0, 1.3);
    app.app
        .world_mut()
        .resource_mut::<raykin::bvh::refit::BvhStats>()
        .max_rebuilds_per_frame = 0;
    // The pose holds: later frames deform nothing, and the first frame's cost arrives.
    for _ in 0..3 {
        app.step();
        app.ctx.wait_idle();
    }
    let gpu_scene = app.gpu_scene();
    let pool = words(&app, &gpu_scene.vertex_pool);
    let stats = app.bvh_stats();
    let mut checked = 0;
    for (m, owned) in app
        .deformation()
        .deformer
        .as_ref()
        .unwrap()
        .owned()
        .iter()
        .enumerate()
    {
        if !owned {
            continue;
        }
        let slot = &gpu_scene.mesh_slots[m];
        let positions = positions_of(
            &pool,
            slot.gpu.position_offset,
            scene.meshes[m].positions.len(),
        );
        let mut tree = slot.blas.binary().unwrap().clone();
        tree.refit(&positions, &slot.gpu_triangles);
        let (want, got) = (tree.sah_ratio(), stats.sah_ratio[m]);
        eprintln!("mesh {m}: SAH ratio GPU {got:.5}, CPU {want:.5}");
        assert!(want > 1.05, "the pose degrades the rest-pose tree ({want})");
        assert!((got - want).abs() <= 1e-4 * want, "GPU {got} vs CPU {want}");
        checked += 1;
    }
    assert!(checked > 0);
    assert_eq!(stats.rebuilds, 0);
}

/// Switching `RenderSettings::deform` mid-run (the viewer's toggle) re-deforms every mesh on the new
/// backend in the same frame: CPU after GPU writes exactly the CPU's vertices, GPU after CPU the GPU's.
#[test]
fn switching_backend_mid_run_redeforms_everything() {
    let _device = crate::common::gpu().1;
    let scene = load(shared_assets().join("CesiumMan/glTF-Binary/CesiumMan.glb"));
    let reference = posed(&scene, DeformBackend::Cpu, 0, 0.8);
    let want = words(&reference, &reference.gpu_scene().vertex_pool);
    let mut app = posed(&scene, DeformBackend::Gpu, 0, 0.8);
    assert!(app.deformation().deformer.is_some());
    let gpu_pool = words(&app, &app.gpu_scene().vertex_pool);

    app.settings_mut().deform = DeformBackend::Cpu;
    app.step();
    assert_eq!(app.deformation().backend, DeformBackend::Cpu);
    assert!(app.deformation().deformer.is_none());
    assert!(
        app.gpu_scene()
            .mesh_slots
            .iter()
            .all(|s| s.deformed_bounds.is_none())
    );
    assert_eq!(words(&app, &app.gpu_scene().vertex_pool), want);

    app.settings_mut().deform = DeformBackend::Gpu;
    app.step();
    assert_eq!(app.deformation().backend, DeformBackend::Gpu);
    assert_eq!(words(&app, &app.gpu_scene().vertex_pool), gpu_pool);
}

/// Deformable meshes' trees take `gpu_deformed_bvh_quality` where the GPU deforms them (their rebuilds run on a
/// worker thread) and `bvh_quality` where the CPU does (its rebuilds run inside the frame), at upload as at every
/// rebuild, so that a rebuild from the upload pose gives the upload's tree.
#[test]
fn deformable_trees_take_their_backends_preset() {
    use raykin::bvh::{BvhQuality, MeshBvh};
    let _device = crate::common::gpu().1;
    let scene = load(shared_assets().join("CesiumMan/glTF-Binary/CesiumMan.glb"));
    let defaults = RenderSettings::default();
    let (gpu_preset, cpu_preset) = (defaults.gpu_deformed_bvh_quality, defaults.bvh_quality);
    assert_eq!(
        (gpu_preset, cpu_preset),
        (BvhQuality::VerySlow, BvhQuality::Medium)
    );
    let mut checked = 0;
    for (backend, preset, other) in [
        (DeformBackend::Gpu, gpu_preset, cpu_preset),
        (DeformBackend::Cpu, cpu_preset, gpu_preset),
    ] {
        let app = app(&scene, backend);
        let gpu_scene = app.gpu_scene();
        assert_eq!(gpu_scene.deformable_quality(), preset, "{backend:?}");
        for (m, mesh) in scene.meshes.iter().enumerate() {
            if !mesh.is_deformable() {
                continue;
            }
            let build = |quality| {
                MeshBvh::build_refittable(&mesh.positions, &mesh.triangles, quality, true).unwrap()
            };
            let (want, not) = (build(preset), build(other));
            // The two presets give this mesh different trees, so the check below tells them apart.
            assert_ne!(want.flat.order, not.flat.order);
            let got = gpu_scene.mesh_slots[m].blas.binary().unwrap();
            assert_eq!(got.flat.order, want.flat.order, "{backend:?}, mesh {m}");
            assert_eq!(got.build_sah, want.build_sah, "{backend:?}, mesh {m}");
            checked += 1;
        }
    }
    assert_eq!(checked, 2);
}
