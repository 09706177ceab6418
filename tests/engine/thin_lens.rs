//! Thin-lens depth of field: the focus plane stays as sharp as a pinhole image, a point off the plane blurs
//! into the circle the thin-lens equation predicts (within a pixel), click-to-focus finds the surface's depth,
//! and a recording's settings carry the lens.

use crate::common::*;
use glam::Vec3;
use raykin::camera::CameraChoice;
use raykin::headless::HeadlessApp;
use raykin::render::{Environment, RenderSettings, ThinLens};
use raykin::scene::{Material, MeshData, NodeTransform, SceneAsset};
use std::sync::Arc;

const SIZE: u32 = 64;
const YFOV_DEGREES: f32 = 30.0;

/// A square facing +Z, `side` wide, centred at `center`.
fn square(center: Vec3, side: f32, material: u32) -> MeshData {
    let h = side * 0.5;
    quad_mesh(
        [
            center + Vec3::new(-h, -h, 0.0),
            center + Vec3::new(h, -h, 0.0),
            center + Vec3::new(h, h, 0.0),
            center + Vec3::new(-h, h, 0.0),
        ],
        material,
    )
}

fn emitter() -> Material {
    Material {
        name: "lamp".into(),
        base_color: glam::Vec4::new(0.0, 0.0, 0.0, 1.0),
        emissive: Vec3::ONE,
        emissive_strength: 100.0,
        ..Default::default()
    }
}

fn scene(meshes: Vec<MeshData>, materials: Vec<Material>) -> Arc<SceneAsset> {
    Arc::new(raykin::scene::procedural::scene_from_meshes(
        "lens test",
        meshes
            .into_iter()
            .map(|m| (m, NodeTransform::default()))
            .collect(),
        materials,
    ))
}

fn camera() -> CameraChoice {
    CameraChoice::LookAt {
        eye: Vec3::ZERO,
        target: Vec3::NEG_Z,
        yfov: YFOV_DEGREES.to_radians(),
    }
}

fn settings(lens: ThinLens) -> RenderSettings {
    RenderSettings {
        width: SIZE,
        height: SIZE,
        max_depth: 0,
        environment: Environment::Constant([0.0; 3]),
        lens,
        ..Default::default()
    }
}

/// Pixels per unit of the film at distance 1 (the image's vertical extent is 2 tan(fov/2)).
fn pixels_per_film_unit() -> f32 {
    SIZE as f32 / (2.0 * (0.5 * YFOV_DEGREES.to_radians()).tan())
}

/// Luminance-weighted centroid and second central moment (x variance + y variance, in pixels^2) of the image
/// part whose columns lie in `columns`.
fn moments(img: &[[f32; 3]], columns: std::ops::Range<u32>) -> (f64, f64, f64) {
    let (mut w, mut mx, mut my) = (0.0, 0.0, 0.0);
    for (i, p) in img.iter().enumerate() {
        let (x, y) = ((i as u32 % SIZE), (i as u32 / SIZE));
        if !columns.contains(&x) {
            continue;
        }
        let l = (p[0] + p[1] + p[2]) as f64;
        w += l;
        mx += l * (x as f64 + 0.5);
        my += l * (y as f64 + 0.5);
    }
    let (mx, my) = (mx / w, my / w);
    let mut var = 0.0;
    for (i, p) in img.iter().enumerate() {
        let (x, y) = ((i as u32 % SIZE), (i as u32 / SIZE));
        if !columns.contains(&x) {
            continue;
        }
        let l = (p[0] + p[1] + p[2]) as f64;
        var += l * ((x as f64 + 0.5 - mx).powi(2) + (y as f64 + 0.5 - my).powi(2));
    }
    (mx, my, var / w)
}

/// Two tiny lamps at depths 4 and 6 with the lens focused at 2 (both blurred), then at 4 (the first sharp).
/// The blur's second moment is R^2 / 2 for a uniform disc of radius R, plus the lamp's own footprint and the
/// pixel grid's (1/12 per axis, subtracted since moments are taken at pixel centres); the diameter 2R must
/// match the thin-lens equation within a pixel.
#[test]
fn circle_of_confusion_matches_the_thin_lens_equation() {
    let (ctx, _gpu) = gpu();
    let ppu = pixels_per_film_unit();
    let side = 0.02;
    // 14 pixels left and right of the centre line at their depths.
    let left = Vec3::new(-14.0 / ppu * 4.0, 0.0, -4.0);
    let right = Vec3::new(14.0 / ppu * 6.0, 0.0, -6.0);
    let s = scene(
        vec![square(left, side, 0), square(right, side * 1.5, 0)],
        vec![emitter()],
    );
    let render_with = |lens: ThinLens, spp| render(&ctx, &s, settings(lens), &camera(), spp);

    let aperture_radius = 0.12;
    let focus = 2.0;
    let img = render_with(
        ThinLens {
            aperture_radius,
            focus_distance: focus,
        },
        1024,
    );
    assert_all_finite(&img, "defocused");
    for (depth, columns, lamp_side) in [
        (4.0f32, 0..SIZE / 2, side),
        (6.0, SIZE / 2..SIZE, side * 1.5),
    ] {
        // The thin-lens equation, independently of raykin's camera model: a lens of focal length f focused
        // at z_f puts its sensor at s' = f z_f / (z_f - f); a point at depth z focuses at s_z = f z / (z - f),
        // and the aperture's cone (diameter D) crosses the sensor in a circle of diameter
        // c = D |s_z - s'| / s_z. The sensor's height for this field of view is 2 s' tan(fov / 2).
        let f = 0.05f64;
        let (z, zf, d) = (depth as f64, focus as f64, 2.0 * aperture_radius as f64);
        let s_sensor = f * zf / (zf - f);
        let s_z = f * z / (z - f);
        let c = d * (s_z - s_sensor).abs() / s_z;
        let sensor_height = 2.0 * s_sensor * (0.5 * YFOV_DEGREES.to_radians() as f64).tan();
        let expected = c / sensor_height * SIZE as f64;
        let (_, _, var) = moments(&img, columns);
        let lamp_px = lamp_side as f64 / depth as f64 * ppu as f64;
        let radius2 = 2.0 * (var + 2.0 / 12.0 - lamp_px * lamp_px / 6.0);
        let measured = 2.0 * radius2.max(0.0).sqrt();
        eprintln!(
            "depth {depth}: circle of confusion {measured:.2} px, thin-lens equation {expected:.2} px"
        );
        assert!(
            (measured - expected).abs() < 1.0,
            "depth {depth}: blur diameter {measured:.2} px, the thin-lens equation gives {expected:.2} px"
        );
        let from_model = ThinLens {
            aperture_radius,
            focus_distance: focus,
        }
        .circle_of_confusion_pixels(depth, YFOV_DEGREES.to_radians(), SIZE);
        assert!((from_model as f64 - expected).abs() < 1e-3 * expected);
    }

    // Focused on the first lamp: as sharp as a pinhole image of it.
    let sharp = render_with(
        ThinLens {
            aperture_radius,
            focus_distance: 4.0,
        },
        256,
    );
    let pinhole = render_with(ThinLens::default(), 256);
    let (sx, sy, sharp_var) = moments(&sharp, 0..SIZE / 2);
    let (px, py, pinhole_var) = moments(&pinhole, 0..SIZE / 2);
    eprintln!("in focus: second moment {sharp_var:.3} px^2 vs pinhole {pinhole_var:.3}");
    assert!(
        (sx - px).abs() < 0.05 && (sy - py).abs() < 0.05,
        "the in-focus lamp moved"
    );
    assert!(
        (sharp_var - pinhole_var).abs() < 0.05,
        "the focus plane is not sharp"
    );
    // ... while the lamp at 6 blurs into a disc whose diameter the thin-lens equation gives: its second moment
    // is R^2 / 2 plus the lamp's own square (side^2 / 6) plus the pixel grid's binning (1/12 per axis). The
    // pinhole's moment is no baseline: its point-like lamp straddles a pixel corner (a moment of 0.5 from
    // binning alone).
    let (_, _, far_var) = moments(&sharp, SIZE / 2..SIZE);
    let lens = ThinLens {
        aperture_radius,
        focus_distance: 4.0,
    };
    let coc_radius =
        0.5 * lens.circle_of_confusion_pixels(6.0, YFOV_DEGREES.to_radians(), SIZE) as f64;
    let lamp_px = (side * 1.5 / 6.0 * ppu) as f64;
    let predicted = 0.5 * coc_radius * coc_radius + lamp_px * lamp_px / 6.0 + 2.0 / 12.0;
    eprintln!("off the focus plane: second moment {far_var:.3} px^2, predicted {predicted:.3}");
    assert!(
        (far_var - predicted).abs() < 0.15 && far_var > 0.8,
        "off the focus plane the lamp must blur as the thin lens predicts ({far_var:.3} vs {predicted:.3} px^2)"
    );
}

/// Click-to-focus: the depth under a pixel (the viewer's Ctrl+click and the script's `focus X Y`) is the
/// surface's distance along the view axis, so focusing there makes it sharp.
#[test]
fn focus_on_a_picked_surface_uses_its_camera_depth() {
    let (ctx, _gpu) = gpu();
    let wall = {
        let mut m = square(Vec3::new(0.0, 0.0, -3.0), 10.0, 0);
        // Tilted: depth varies across the image, so the pixel matters.
        for p in &mut m.positions {
            p.z -= 0.2 * p.x;
        }
        m
    };
    let s = scene(vec![wall], vec![Material::default()]);
    let mut app =
        HeadlessApp::new(ctx.clone(), s, settings(ThinLens::default()), &camera()).unwrap();
    app.step();
    ctx.wait_idle();
    for (x, y) in [(32, 32), (10, 40), (60, 5)] {
        let depth =
            raykin::render::picking::depth_at(app.app.world(), x, y).expect("the wall is hit");
        // The wall plane z = -3 - 0.2 x; the pixel centre's pinhole ray meets it at this depth.
        let (o, d) = app
            .camera()
            .ray_through(x as f32 + 0.5, y as f32 + 0.5, SIZE, SIZE);
        let t = (-3.0 - o.z) / (d.z + 0.2 * d.x);
        let expected = t * d.dot(Vec3::NEG_Z);
        assert!(
            (depth - expected).abs() < 1e-3 * expected,
            "pixel ({x}, {y}): depth {depth} vs {expected}"
        );
    }
}

/// A recording's manifest holds the render settings as JSON: the lens is among them, so a frame re-renders
/// with the same depth of field.
#[test]
fn recorded_settings_carry_the_lens() {
    let lens = ThinLens::from_f_number(2.8, 0.6, 3.5);
    let settings = RenderSettings {
        lens,
        ..Default::default()
    };
    let json = serde_json::to_value(&settings).unwrap();
    assert_eq!(json["lens"]["focus_distance"].as_f64().unwrap() as f32, 3.5);
    let back: RenderSettings = serde_json::from_value(json).unwrap();
    assert_eq!(back.lens, lens);
    // f/2.8 behind a 0.6 rad field of view on a 24 mm tall sensor: f = 12 mm / tan(0.3).
    let focal = 0.012 / 0.3f32.tan();
    assert!((lens.aperture_radius - focal / 2.8 / 2.0).abs() < 1e-6);
    // Settings written before the lens existed still read (a pinhole).
    let mut old = serde_json::to_value(RenderSettings::default()).unwrap();
    old.as_object_mut().unwrap().remove("lens");
    let old: RenderSettings = serde_json::from_value(old).unwrap();
    assert_eq!(old.lens.aperture_radius, 0.0);
}
