//! Meshes and scenes made in code: test scenes (furnace spheres), ground planes and a field of lights for
//! benches.

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
    horizontal_square("ground".into(), Vec3::ZERO, size, true, material)
}

/// A square in a horizontal plane, `size` on a side, centred at `centre`, facing +Y (`up`) or -Y: its
/// triangles wound counter-clockwise seen from that side.
fn horizontal_square(name: String, centre: Vec3, size: f32, up: bool, material: u32) -> MeshData {
    let h = size * 0.5;
    let normal = if up { Vec3::Y } else { Vec3::NEG_Y };
    MeshData {
        name,
        positions: [(-h, -h), (h, -h), (h, h), (-h, h)]
            .map(|(x, z)| centre + Vec3::new(x, 0.0, z))
            .to_vec(),
        normals: Some(vec![normal; 4]),
        uv0: Some(vec![Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y]),
        triangles: if up {
            vec![[0, 2, 1], [0, 3, 2]]
        } else {
            vec![[0, 1, 2], [0, 2, 3]]
        },
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

/// The many-lights scene: a 40 x 40 floor under `n x n` small emissive squares (0.3 wide, facing down, 1.5
/// apart, at heights 1.5 to 3.3), their radiance spread over two orders of magnitude and three tints. Light
/// sampling benches and tests use it: most squares light only the floor beneath them.
pub fn light_field(n: usize) -> SceneAsset {
    let mut meshes = vec![(ground_quad(40.0, 0), NodeTransform::default())];
    let mut materials = vec![Material {
        name: "floor".into(),
        base_color: glam::Vec4::new(0.7, 0.7, 0.7, 1.0),
        metallic: 0.0,
        roughness: 0.7,
        ..Default::default()
    }];
    for k in 0..n * n {
        let (i, j) = ((k % n) as f32, (k / n) as f32);
        let centre = Vec3::new(
            i - n as f32 / 2.0,
            1.0 + 0.3 * ((k * 7) % 5) as f32,
            j - n as f32 / 2.0,
        ) * 1.5;
        let h = 0.15;
        let material = k as u32 + 1;
        materials.push(Material {
            name: format!("lamp {k}"),
            base_color: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
            emissive: Vec3::new(1.0, 0.5 + 0.25 * (k % 3) as f32, 0.3),
            emissive_strength: 10f32.powf(((k * 37) % 100) as f32 / 50.0),
            ..Default::default()
        });
        meshes.push((
            // Facing -Y, towards the floor.
            horizontal_square(format!("lamp {k}"), centre, 2.0 * h, false, material),
            NodeTransform::default(),
        ));
    }
    scene_from_meshes("light field", meshes, materials)
}
