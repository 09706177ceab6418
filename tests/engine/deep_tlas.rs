//! The top-level traversal never drops part of a deep tree: a top-level BVH 40 levels deep, every node with two
//! inner children and boxes that every camera ray enters, so the traversal stack holds an entry per level. With
//! the old WGSL stack of 32 entries the deepest pairs of instances vanished without a word; every one of the 80
//! emissive quads must show.

use crate::common::gpu;
use glam::{Mat4, Vec3};
use raykin::bvh::{FlatBvh, GpuBvhChild, GpuBvhNode};
use raykin::camera::CameraChoice;
use raykin::headless::HeadlessApp;
use raykin::render::{Environment, GpuScene, RenderSettings};
use raykin::scene::{Material, MeshData, NodeData, NodeTransform, SceneAsset, SceneAssets};
use std::sync::Arc;

const COLUMNS: usize = 10;
const ROWS: usize = 8;
const SPACING: f32 = 1.0;
const QUAD: f32 = 0.7;
const WIDTH: usize = 100;
const HEIGHT: usize = 80;

/// A square in the XY plane facing +Z.
fn quad() -> MeshData {
    let h = QUAD * 0.5;
    MeshData {
        normals: Some(vec![Vec3::Z; 4]),
        ..crate::common::quad_mesh(
            [
                Vec3::new(-h, -h, 0.0),
                Vec3::new(h, -h, 0.0),
                Vec3::new(h, h, 0.0),
                Vec3::new(-h, h, 0.0),
            ],
            0,
        )
    }
}

fn grid_scene() -> SceneAsset {
    let mut scene = SceneAsset {
        source: "quad grid".into(),
        materials: vec![Material {
            name: "light".into(),
            base_color: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
            emissive: Vec3::ONE,
            ..Default::default()
        }],
        meshes: vec![quad()],
        ..Default::default()
    };
    for i in 0..COLUMNS * ROWS {
        let (c, r) = (i % COLUMNS, i / COLUMNS);
        scene.nodes.push(NodeData {
            name: format!("quad {i}"),
            transform: NodeTransform {
                translation: Vec3::new(c as f32 * SPACING, r as f32 * SPACING, 0.0),
                ..Default::default()
            },
            mesh: Some(0),
            ..Default::default()
        });
        scene.roots.push(i);
    }
    scene
}

/// A caterpillar over `n` leaves (n even): chain node k has the next chain node and the pair node of leaves
/// 2k, 2k+1 as its two inner children; every box is the whole scene's, so every ray enters every node.
fn caterpillar(n: usize, lo: Vec3, hi: Vec3) -> FlatBvh {
    let pairs = n / 2;
    let inner = |index: usize| GpuBvhChild {
        min: lo.to_array(),
        index: index as u32,
        max: hi.to_array(),
        count: 0,
    };
    let leaf = |first: usize| GpuBvhChild {
        min: lo.to_array(),
        index: first as u32,
        max: hi.to_array(),
        count: 1,
    };
    // Chain nodes 0..pairs-1 (the last one's first child is the last pair), then the pair nodes.
    let chain = pairs - 1;
    let pair_node = |k: usize| chain + k;
    let mut nodes = Vec::new();
    for k in 0..chain {
        let next = if k + 1 < chain {
            inner(k + 1)
        } else {
            inner(pair_node(pairs - 1))
        };
        nodes.push(GpuBvhNode {
            children: [next, inner(pair_node(k))],
        });
    }
    for k in 0..pairs {
        nodes.push(GpuBvhNode {
            children: [leaf(2 * k), leaf(2 * k + 1)],
        });
    }
    FlatBvh {
        nodes,
        order: (0..n as u32).collect(),
        depth: chain as u32 + 1,
    }
}

#[test]
fn every_instance_of_a_deep_top_level_tree_is_traced() {
    let (ctx, _gpu) = gpu();
    let n = COLUMNS * ROWS;
    let centre = Vec3::new(
        (COLUMNS - 1) as f32 * SPACING * 0.5,
        (ROWS - 1) as f32 * SPACING * 0.5,
        0.0,
    );
    let settings = RenderSettings {
        width: WIDTH as u32,
        height: HEIGHT as u32,
        max_depth: 0,
        environment: Environment::Constant([0.0; 3]),
        ..Default::default()
    };
    let camera = CameraChoice::LookAt {
        eye: centre + Vec3::new(0.0, 0.0, 14.0),
        target: centre,
        yfov: 40f32.to_radians(),
    };
    let mut app =
        HeadlessApp::new(ctx.clone(), Arc::new(grid_scene()), settings, &camera).expect("uploads");
    app.step();
    let world = app.app.world_mut();
    let inputs = world
        .resource::<raykin::render::gpu_scene::InstanceMap>()
        .inputs()
        .to_vec();
    assert_eq!(inputs.len(), n);
    let tree = caterpillar(n, centre - Vec3::splat(10.0), centre + Vec3::splat(10.0));
    assert!(
        tree.depth > 32,
        "the tree must be deeper than the old 32-entry stack"
    );
    let scene = world.resource::<SceneAssets>().0.clone();
    world
        .resource_mut::<GpuScene>()
        .upload_instances(&ctx, &scene, &inputs, tree);
    app.restart_accumulation();
    app.accumulate(1, 1, |_| {});
    let image = app.radiance();

    // Project each quad's centre (its instance world matrix says where) and look at that pixel.
    let view = app.camera();
    let project = |p: Vec3| -> (usize, usize) {
        let camera_from_world: Mat4 = view.world_from_camera.inverse();
        let c = camera_from_world.transform_point3(p);
        let t = (view.yfov * 0.5).tan();
        let aspect = WIDTH as f32 / HEIGHT as f32;
        let ndc = (c.x / (-c.z * t * aspect), c.y / (-c.z * t));
        (
            ((ndc.0 * 0.5 + 0.5) * WIDTH as f32) as usize,
            ((0.5 - ndc.1 * 0.5) * HEIGHT as f32) as usize,
        )
    };
    let missing: Vec<usize> = inputs
        .iter()
        .enumerate()
        .filter(|(_, input)| {
            let (x, y) = project(input.world.transform_point3(Vec3::ZERO));
            image[y * WIDTH + x][0] < 0.5
        })
        .map(|(i, _)| i)
        .collect();
    assert!(
        missing.is_empty(),
        "{} of {n} instances missing from the image: {missing:?}",
        missing.len()
    );
}
