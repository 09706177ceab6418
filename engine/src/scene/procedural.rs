//! Meshes and scenes made in code: test scenes (furnace spheres), ground planes for benches.

use super::*;

/// A UV sphere with analytic normals and UVs.
pub fn uv_sphere(radius: f32, segments: u32, rings: u32, material: u32) -> MeshData {
    let mut mesh = MeshData {
        name: "sphere".into(),
        ..Default::default()
    };
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    for r in 0..=rings {
        let v = r as f32 / rings as f32;
        let theta = v * std::f32::consts::PI;
        for s in 0..=segments {
            let u = s as f32 / segments as f32;
            let phi = u * std::f32::consts::TAU;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                -theta.sin() * phi.sin(),
            );
            mesh.positions.push(n * radius);
            normals.push(n);
            uvs.push(Vec2::new(u, v));
        }
    }
    let row = segments + 1;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (
                r * row + s,
                r * row + s + 1,
                (r + 1) * row + s,
                (r + 1) * row + s + 1,
            );
            // Skip the triangles that collapse at the poles.
            if r != 0 {
                mesh.triangles.push([a, c, b]);
            }
            if r != rings - 1 {
                mesh.triangles.push([b, c, d]);
            }
        }
    }
    mesh.triangle_materials = vec![material; mesh.triangles.len()];
    mesh.primitives.push(PrimitiveRange {
        vertex_offset: 0,
        vertex_count: mesh.positions.len() as u32,
        material,
    });
    mesh.normals = Some(normals);
    mesh.uv0 = Some(uvs);
    mesh
}

/// A square in the XZ plane facing +Y, `size` on a side, centred at the origin.
pub fn ground_quad(size: f32, material: u32) -> MeshData {
    let h = size * 0.5;
    MeshData {
        name: "ground".into(),
        positions: vec![
            Vec3::new(-h, 0.0, -h),
            Vec3::new(h, 0.0, -h),
            Vec3::new(h, 0.0, h),
            Vec3::new(-h, 0.0, h),
        ],
        normals: Some(vec![Vec3::Y; 4]),
        uv0: Some(vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]),
        triangles: vec![[0, 2, 1], [0, 3, 2]],
        triangle_materials: vec![material; 2],
        primitives: vec![PrimitiveRange {
            vertex_offset: 0,
            vertex_count: 4,
            material,
        }],
        ..Default::default()
    }
}

/// A scene of one node per mesh, each placed by its transform, no camera.
pub fn scene_from_meshes(
    name: &str,
    meshes: Vec<(MeshData, NodeTransform)>,
    materials: Vec<Material>,
) -> SceneAsset {
    let mut scene = SceneAsset {
        source: name.into(),
        materials,
        ..Default::default()
    };
    for (i, (mesh, transform)) in meshes.into_iter().enumerate() {
        scene.nodes.push(NodeData {
            name: mesh.name.clone(),
            transform,
            mesh: Some(i),
            ..Default::default()
        });
        scene.roots.push(i);
        scene.meshes.push(mesh);
    }
    scene
}
