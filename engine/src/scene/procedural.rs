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
    with_attributes(mesh, normals, uvs, material)
}

/// `mesh` (positions and triangles made) with its normals and UVs, one material, and one primitive over it all.
fn with_attributes(
    mut mesh: MeshData,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    material: u32,
) -> MeshData {
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
    let mesh = MeshData {
        name,
        positions: [(-h, -h), (h, -h), (h, h), (-h, h)]
            .map(|(x, z)| centre + Vec3::new(x, 0.0, z))
            .to_vec(),
        triangles: if up {
            vec![[0, 2, 1], [0, 3, 2]]
        } else {
            vec![[0, 1, 2], [0, 2, 3]]
        },
        ..Default::default()
    };
    with_attributes(mesh, vec![normal; 4], QUAD_UVS.to_vec(), material)
}

/// UVs of a four-corner mesh's corners, in the order its corners are made.
const QUAD_UVS: [Vec2; 4] = [Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y];

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

/// An axis-aligned box `size` across, centred at the origin: six faces, each with its own flat normal and wound
/// counter-clockwise seen from outside.
pub fn cuboid(size: Vec3, material: u32) -> MeshData {
    let mut mesh = MeshData {
        name: "box".into(),
        ..Default::default()
    };
    let (mut normals, mut uvs) = (Vec::new(), Vec::new());
    let half = size * 0.5;
    for axis in 0..3 {
        for sign in [1.0f32, -1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            // u x v = the axis, so (-u-v, +u-v, +u+v, -u+v) turns counter-clockwise about it; the face on the
            // negative side takes the corners in the opposite order.
            let (mut u, mut v) = (Vec3::ZERO, Vec3::ZERO);
            u[(axis + 1) % 3] = half[(axis + 1) % 3];
            v[(axis + 2) % 3] = half[(axis + 2) % 3];
            let centre = n * half[axis];
            let base = mesh.positions.len() as u32;
            for (a, b) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                mesh.positions.push(centre + u * a + v * b);
                normals.push(n);
                uvs.push(Vec2::new((a + 1.0) * 0.5, (b + 1.0) * 0.5));
            }
            let [p, q, r, s] = [base, base + 1, base + 2, base + 3];
            if sign > 0.0 {
                mesh.triangles.extend([[p, q, r], [p, r, s]]);
            } else {
                mesh.triangles.extend([[p, r, q], [p, s, r]]);
            }
        }
    }
    with_attributes(mesh, normals, uvs, material)
}

/// A parallelogram centred at the origin with corners at +-`u` +-`v`, facing `u x v`: its two triangles wound
/// counter-clockwise seen from that side.
pub fn quad(name: &str, u: Vec3, v: Vec3, material: u32) -> MeshData {
    let normal = u.cross(v).normalize();
    let mesh = MeshData {
        name: name.into(),
        positions: vec![-u - v, u - v, u + v, -u + v],
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        ..Default::default()
    };
    with_attributes(mesh, vec![normal; 4], QUAD_UVS.to_vec(), material)
}

fn placed(translation: Vec3) -> NodeTransform {
    NodeTransform {
        translation,
        ..Default::default()
    }
}

fn plain(name: &str, rgb: [f32; 3], metallic: f32, roughness: f32) -> Material {
    Material {
        name: name.into(),
        base_color: Vec3::from(rgb).extend(1.0),
        metallic,
        roughness,
        ..Default::default()
    }
}

/// The white furnace as a bench scene: three unit spheres of base colour 1 (a rough dielectric, a glossy metal,
/// a fully rough dielectric) side by side, to be lit by a constant environment of 1. Every path ends in the
/// environment; the light is all in the BSDF's sampling (and the spheres' small mutual reflections).
pub fn white_furnace() -> SceneAsset {
    let materials = vec![
        plain("rough dielectric", [1.0; 3], 0.0, 0.5),
        plain("glossy metal", [1.0; 3], 1.0, 0.3),
        plain("matte dielectric", [1.0; 3], 0.0, 1.0),
    ];
    let meshes = (0..3)
        .map(|i| {
            let x = (i as f32 - 1.0) * 2.2;
            (uv_sphere(1.0, 96, 48, i), placed(Vec3::new(x, 0.0, 0.0)))
        })
        .collect();
    scene_from_meshes("white furnace", meshes, materials)
}

/// Where [`grazing_light`] stands: every coordinate about 1e4, where a float's spacing is 2^-10, so offsets
/// that keep rays off their surfaces are a visible fraction of the scene's details.
pub const GRAZING_LIGHT_ORIGIN: Vec3 = Vec3::new(1.0e4, 1.0e4, -1.0e4);

/// A grazing-light scene far from the origin: boxes and spheres (tens of units) on an 800-unit floor, lit by
/// one emissive panel 700-1100 units to the side and 25-55 units above the floor (1.3-4.5 degrees of elevation at
/// the floor's centre), which faces along the floor's depth, so that its light leaves it 82-85 degrees from its
/// normal: the floor and the tops are lit at grazing incidence, the shadows run long across the view, the spheres'
/// shading normals meet the light at their terminators, and seen from the objects the panel's two triangles are
/// thin slivers (what solid-angle sampling finds hardest); a dim constant sky fills the shadows. All of it around
/// [`GRAZING_LIGHT_ORIGIN`].
pub fn grazing_light() -> SceneAsset {
    grazing_light_at(GRAZING_LIGHT_ORIGIN)
}

/// [`grazing_light`] around `o` instead (the same scene anywhere: tests compare the two).
pub fn grazing_light_at(o: Vec3) -> SceneAsset {
    let materials = vec![
        plain("floor", [0.6, 0.6, 0.6], 0.0, 0.8),
        plain("plaster", [0.75, 0.72, 0.68], 0.0, 0.9),
        plain("gold", [1.0, 0.78, 0.34], 1.0, 0.3),
        plain("blue", [0.2, 0.3, 0.7], 0.0, 0.4),
        Material {
            name: "panel".into(),
            base_color: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
            emissive: Vec3::new(1.0, 0.9, 0.8),
            emissive_strength: 4000.0,
            ..Default::default()
        },
    ];
    let tall = cuboid(Vec3::new(60.0, 120.0, 60.0), 1);
    let flat = cuboid(Vec3::new(80.0, 40.0, 80.0), 1);
    let turned = NodeTransform {
        rotation: glam::Quat::from_rotation_y(30f32.to_radians()),
        ..placed(o + Vec3::new(80.0, 20.0, 40.0))
    };
    // The panel: 400 wide (x), 30 tall (y), facing -z: towards the objects' side of z = 100, edge-on to them.
    let panel = quad(
        "panel",
        Vec3::new(-200.0, 0.0, 0.0),
        Vec3::new(0.0, 15.0, 0.0),
        4,
    );
    let meshes = vec![
        (ground_quad(800.0, 0), placed(o)),
        (tall, placed(o + Vec3::new(-100.0, 60.0, -50.0))),
        (flat, turned),
        (
            uv_sphere(40.0, 96, 48, 2),
            placed(o + Vec3::new(0.0, 40.0, -150.0)),
        ),
        (
            uv_sphere(25.0, 96, 48, 3),
            placed(o + Vec3::new(150.0, 25.0, -60.0)),
        ),
        (panel, placed(o + Vec3::new(-900.0, 40.0, 100.0))),
    ];
    scene_from_meshes("grazing light at 1e4", meshes, materials)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each face's winding agrees with its normal, and the normal points away from the centre.
    #[test]
    fn cuboid_faces_point_outwards() {
        let mesh = cuboid(Vec3::new(2.0, 4.0, 6.0), 0);
        assert_eq!(mesh.triangles.len(), 12);
        let normals = mesh.normals.as_ref().unwrap();
        for t in &mesh.triangles {
            let [a, b, c] = t.map(|i| mesh.positions[i as usize]);
            let geometric = (b - a).cross(c - a).normalize();
            let n = normals[t[0] as usize];
            assert!((geometric - n).length() < 1e-6, "{t:?}: {geometric} vs {n}");
            assert!(((a + b + c) / 3.0).dot(n) > 0.0, "{t:?} faces inwards");
        }
        let extent = mesh
            .positions
            .iter()
            .fold(Vec3::ZERO, |m, p| m.max(p.abs()));
        assert_eq!(extent, Vec3::new(1.0, 2.0, 3.0));
    }

    /// The grazing scene's light reaches the objects within a few degrees of the floor's plane, from the
    /// panel's front at 80-86 degrees from its normal, and every node sits near 1e4.
    #[test]
    fn grazing_light_grazes() {
        let scene = grazing_light();
        let panel = scene.nodes.iter().find(|n| n.name == "panel").unwrap();
        let mesh = &scene.meshes[panel.mesh.unwrap()];
        assert_eq!(mesh.triangles.len(), 2);
        let centre = panel.transform.translation;
        for p in &mesh.positions {
            let to_objects = GRAZING_LIGHT_ORIGIN - (centre + *p);
            let elevation = (to_objects.y.abs() / to_objects.length())
                .asin()
                .to_degrees();
            assert!(elevation > 1.0 && elevation < 5.0, "elevation {elevation}");
            let from_normal = (-to_objects.normalize().z).acos().to_degrees();
            assert!(
                from_normal > 80.0 && from_normal < 86.0,
                "{from_normal} degrees from the normal"
            );
        }
        let [a, b, c] = mesh.triangles[0].map(|i| mesh.positions[i as usize]);
        assert!((b - a).cross(c - a).z < 0.0, "the panel faces -z");
        for node in &scene.nodes {
            assert!((node.transform.translation - GRAZING_LIGHT_ORIGIN).length() < 1000.0);
        }
    }
}
