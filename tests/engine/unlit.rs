//! KHR_materials_unlit: the surface shows its base colour (times texture and vertex colour) as radiance, whatever
//! lights it, and scatters nothing; its emissive factor plays no part (it is no light).

use crate::common::*;
use glam::{Vec3, Vec4};
use raykin::camera::CameraChoice;
use raykin::render::{Environment, RenderSettings};
use raykin::scene::{Material, MaterialExtensions, NodeTransform, procedural};
use std::sync::Arc;

#[test]
fn unlit_surfaces_show_their_base_colour_unlit() {
    let (ctx, _gpu) = gpu();
    let color = Vec3::new(0.2, 0.5, 0.8);
    let unlit = Material {
        name: "unlit".into(),
        base_color: color.extend(1.0),
        emissive: Vec3::ONE,
        extensions: MaterialExtensions {
            unlit: true,
            ..Default::default()
        },
        ..Default::default()
    };
    // A lit white quad beside it: the environment does light what is not unlit.
    let lit = Material {
        name: "lit".into(),
        base_color: Vec4::ONE,
        metallic: 0.0,
        ..Default::default()
    };
    let quad = |x0: f32, x1: f32, material| {
        quad_mesh(
            [
                Vec3::new(x0, -2.0, 0.0),
                Vec3::new(x1, -2.0, 0.0),
                Vec3::new(x1, 2.0, 0.0),
                Vec3::new(x0, 2.0, 0.0),
            ],
            material,
        )
    };
    let scene = Arc::new(procedural::scene_from_meshes(
        "unlit",
        vec![
            (quad(-2.0, 0.0, 0), NodeTransform::default()),
            (quad(0.0, 2.0, 1), NodeTransform::default()),
        ],
        vec![unlit, lit],
    ));
    let size = 16;
    let settings = RenderSettings {
        width: size,
        height: size,
        environment: Environment::Constant([3.0; 3]),
        seed: 4,
        ..Default::default()
    };
    let camera = CameraChoice::LookAt {
        eye: Vec3::new(0.0, 0.0, 3.0),
        target: Vec3::ZERO,
        yfov: 40f32.to_radians(),
    };
    let image = render(&ctx, &scene, settings, &camera, 4);
    assert_all_finite(&image, "unlit");
    // Columns 0..6 see only the unlit quad, 10..16 only the lit one.
    let mut lit_sum = 0.0;
    for y in 0..size {
        for x in 0..6 {
            let p = image[(y * size + x) as usize];
            for c in 0..3 {
                assert!(
                    (p[c] - color[c]).abs() < 1e-5,
                    "unlit pixel ({x}, {y}) is {p:?}, not its base colour {color}"
                );
            }
        }
        lit_sum += (10..size)
            .map(|x| image[(y * size + x) as usize][1] as f64)
            .sum::<f64>();
    }
    let lit_mean = lit_sum / (size * (size - 10)) as f64;
    assert!(
        lit_mean > 2.5,
        "the lit quad's mean is {lit_mean}, not about 3"
    );
}
