//! KHR_lights_punctual end to end: files that use lights render lit by them (every such sample in
//! ../shared/assets and the test scenes), lights on animated nodes follow them (and the light list is
//! re-uploaded only when something moved), Save as writes edited lights back, bad light values are repaired
//! with a warning, and environment maps read from .hdr and .exr with clear errors for bad files.

use crate::common::*;
use glam::Vec3;
use raykin::camera::CameraChoice;
use raykin::headless::HeadlessApp;
use raykin::render::layout::{GpuLight, LIGHT_SPOT};
use raykin::render::{Environment, RenderSettings};
use raykin::scene::{LightSource, PunctualKind};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raykin-lights-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

fn black() -> Environment {
    Environment::Constant([0.0; 3])
}

fn small(environment: Environment) -> RenderSettings {
    RenderSettings {
        width: 16,
        height: 16,
        max_depth: 2,
        environment,
        ..Default::default()
    }
}

/// Whether a .gltf or .glb lists KHR_lights_punctual in extensionsUsed (its JSON, read directly).
fn uses_lights(path: &Path) -> bool {
    let bytes = std::fs::read(path).unwrap();
    let json = if bytes.starts_with(b"glTF") && bytes.len() >= 20 {
        let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
        bytes.get(20..20 + len).unwrap_or(&[]).to_vec()
    } else {
        bytes
    };
    serde_json::from_slice::<serde_json::Value>(&json).is_ok_and(|v| {
        v["extensionsUsed"]
            .as_array()
            .is_some_and(|a| a.iter().any(|e| e == "KHR_lights_punctual"))
    })
}

fn gltf_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for entry in entries.flatten() {
        let path = entry.path();
        if path.is_dir() {
            gltf_files(&path, out);
        } else if matches!(
            path.extension().and_then(|e| e.to_str()),
            Some("gltf" | "glb")
        ) {
            out.push(path);
        }
    }
}

/// Every file that uses KHR_lights_punctual, in the shared Khronos samples and the light test scenes, loads
/// its lights and renders lit by them alone (black environment, no emissive surfaces needed): never unlit.
#[test]
fn every_file_with_punctual_lights_renders_lit_by_them() {
    let (ctx, _gpu) = gpu();
    let mut files = Vec::new();
    gltf_files(&shared_assets(), &mut files);
    gltf_files(&repo_root().join("tests/reference/lights"), &mut files);
    files.sort();
    let lit: Vec<PathBuf> = files.into_iter().filter(|f| uses_lights(f)).collect();
    eprintln!("files using KHR_lights_punctual: {lit:?}");
    assert!(lit.len() >= 3, "the three light test scenes use lights");
    for path in lit {
        let scene = raykin::scene::load_gltf(&path, &Default::default()).expect("loads");
        assert!(
            !scene.lights.is_empty(),
            "{}: lights not read",
            path.display()
        );
        let scene = Arc::new(scene);
        let mut app = HeadlessApp::new(
            ctx.clone(),
            scene.clone(),
            small(black()),
            &camera_for(&path),
        )
        .unwrap();
        app.accumulate(4, 4, |_| {});
        let punctual = app.gpu_scene().lights.count - app.gpu_scene().lights.triangle_count;
        assert!(
            punctual as usize >= scene.lights.len(),
            "{}: lights not uploaded",
            path.display()
        );
        let img = app.radiance();
        assert_all_finite(&img, "lit render");
        let mean = mean_rgb(&img);
        eprintln!("{}: mean {mean:?}", path.display());
        assert!(
            mean.iter().sum::<f64>() > 1e-3,
            "{} renders unlit",
            path.display()
        );
    }
}

/// The light test scenes' camera (their floor is flat: the framing camera would see it edge-on), else the
/// framing camera.
fn camera_for(path: &Path) -> CameraChoice {
    if path.starts_with(repo_root().join("tests/reference/lights")) {
        return CameraChoice::LookAt {
            eye: Vec3::new(0.0, 2.2, 5.0),
            target: Vec3::new(0.0, 0.6, 0.0),
            yfov: 40f32.to_radians(),
        };
    }
    CameraChoice::Auto
}

fn animated_spot_gltf() -> serde_json::Value {
    use base64::Engine as _;
    // A floor quad, and a spot on a node that moves from x = -1 to x = 1 over one second.
    let positions: [[f32; 3]; 4] = [
        [-3.0, 0.0, -3.0],
        [-3.0, 0.0, 3.0],
        [3.0, 0.0, 3.0],
        [3.0, 0.0, -3.0],
    ];
    let indices: [u32; 6] = [0, 1, 2, 0, 2, 3];
    let times: [f32; 2] = [0.0, 1.0];
    let translations: [[f32; 3]; 2] = [[-1.0, 2.0, 0.0], [1.0, 2.0, 0.0]];
    let mut bin = Vec::new();
    for v in positions
        .iter()
        .flatten()
        .chain(translations.iter().flatten())
    {
        bin.extend_from_slice(&v.to_le_bytes());
    }
    for t in times {
        bin.extend_from_slice(&t.to_le_bytes());
    }
    for i in indices {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    // -Z turned to -Y: a quarter turn about +X.
    let s = std::f32::consts::FRAC_1_SQRT_2;
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "spot", "color": [1.0, 0.8, 0.6], "intensity": 5.0, "range": 10.0,
             "spot": {"innerConeAngle": 0.3, "outerConeAngle": 0.6}}]}},
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"name": "lamp", "translation": [-1.0, 2.0, 0.0], "rotation": [-s, 0.0, 0.0, s],
                   "extensions": {"KHR_lights_punctual": {"light": 0}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 3}]}],
        "animations": [{"channels": [{"sampler": 0, "target": {"node": 1, "path": "translation"}}],
                        "samplers": [{"input": 2, "output": 1, "interpolation": "LINEAR"}]}],
        "buffers": [{"byteLength": bin.len(), "uri": uri}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 24},
            {"buffer": 0, "byteOffset": 72, "byteLength": 8},
            {"buffer": 0, "byteOffset": 80, "byteLength": 24}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-3.0, 0.0, -3.0], "max": [3.0, 0.0, 3.0]},
            {"bufferView": 1, "componentType": 5126, "count": 2, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR", "min": [0.0], "max": [1.0]},
            {"bufferView": 3, "componentType": 5125, "count": 6, "type": "SCALAR"}],
    })
}

fn uploaded_lights(app: &HeadlessApp) -> Vec<GpuLight> {
    let scene = app.gpu_scene();
    let bytes = app
        .ctx
        .read_buffer(&scene.light_buffer, scene.light_buffer.size());
    bytemuck::cast_slice::<u8, GpuLight>(&bytes)[..scene.lights.count as usize].to_vec()
}

#[test]
fn lights_on_animated_nodes_follow_them() {
    let (ctx, _gpu) = gpu();
    let path = scratch("animated_spot.gltf");
    std::fs::write(&path, serde_json::to_vec(&animated_spot_gltf()).unwrap()).unwrap();
    let scene = Arc::new(raykin::scene::load_gltf(&path, &Default::default()).expect("loads"));
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let mut settings = small(black());
    settings.spp_per_frame = 2;
    let camera = CameraChoice::LookAt {
        eye: Vec3::new(0.0, 5.0, 4.0),
        target: Vec3::ZERO,
        yfov: 0.8,
    };
    let mut app = HeadlessApp::new(ctx.clone(), scene, settings, &camera).unwrap();
    let spot_at = |app: &HeadlessApp| {
        let lights = uploaded_lights(app);
        let spot = lights
            .iter()
            .find(|l| l.kind == LIGHT_SPOT)
            .expect("the spot is uploaded");
        (Vec3::from(spot.position), Vec3::from(spot.direction))
    };
    app.set_time(0, 0.25).unwrap();
    app.step();
    let (p, d) = spot_at(&app);
    assert!(
        (p - Vec3::new(-0.5, 2.0, 0.0)).length() < 1e-5,
        "spot at {p}"
    );
    assert!((d - Vec3::NEG_Y).length() < 1e-5, "spot shines along {d}");
    let left = app.radiance();
    // Nothing moves: accumulation goes on (the light list is not re-uploaded).
    app.step();
    assert_eq!(app.samples(), 4);
    app.set_time(0, 0.75).unwrap();
    app.step();
    assert_eq!(app.samples(), 2, "a moved light restarts accumulation");
    let (p, _) = spot_at(&app);
    assert!(
        (p - Vec3::new(0.5, 2.0, 0.0)).length() < 1e-5,
        "spot at {p}"
    );
    // The lit spot on the floor moved right: compare the two image halves.
    let right = app.radiance();
    let half = |img: &[[f32; 3]], left_half: bool| {
        img.iter()
            .enumerate()
            .filter(|(i, _)| ((i % 16) < 8) == left_half)
            .map(|(_, p)| p[0] as f64)
            .sum::<f64>()
    };
    assert!(half(&left, true) > half(&left, false));
    assert!(half(&right, false) > half(&right, true));
}

#[test]
fn edited_lights_save_back_as_khr_lights_punctual() {
    let source = repo_root().join("tests/reference/lights/point.gltf");
    let scene = raykin::scene::load_gltf(&source, &Default::default()).unwrap();
    let node = scene.nodes.iter().position(|n| n.light.is_some()).unwrap();
    let mut light = scene.lights[0].clone();
    light.intensity = 12.5;
    light.color = Vec3::new(0.2, 0.4, 0.6);
    light.kind = PunctualKind::Spot {
        inner_cone_angle: 0.2,
        outer_cone_angle: 0.5,
    };
    light.range = Some(7.0);
    for out in ["saved.gltf", "saved.glb"] {
        let out = scratch(out);
        raykin::scene::save_edited(
            &std::fs::read(&source).unwrap(),
            source.parent().unwrap(),
            "point.gltf",
            Default::default(),
            &scene.materials,
            Some(&[(node, light.clone())]),
            &out,
        )
        .unwrap();
        let back = raykin::scene::load_gltf(&out, &Default::default()).unwrap();
        assert_eq!(back.lights.len(), 1);
        assert_eq!(back.nodes[node].light, Some(0));
        assert_eq!(back.lights[0], light, "{}", out.display());
    }
    // The editor's copy is the ECS component the renderer reads.
    let (ctx, _gpu) = gpu();
    let mut app =
        HeadlessApp::new(ctx, Arc::new(scene), small(black()), &CameraChoice::Auto).unwrap();
    app.step();
    let before = uploaded_lights(&app);
    let world = app.app.world_mut();
    let mut q = world.query::<&mut LightSource>();
    q.single_mut(world).unwrap().0.intensity *= 2.0;
    app.step();
    assert_eq!(app.samples(), 1, "an edited light restarts accumulation");
    let after = uploaded_lights(&app);
    let point = |l: &[GpuLight]| {
        l.iter()
            .find(|l| l.kind == raykin::render::layout::LIGHT_POINT)
            .unwrap()
            .radiance[0]
    };
    assert!((point(&after) / point(&before) - 2.0).abs() < 1e-5);
}

#[test]
fn invalid_light_values_are_repaired_with_a_warning() {
    let mut doc = animated_spot_gltf();
    doc["extensions"]["KHR_lights_punctual"]["lights"] = json!([
        {"type": "spot", "intensity": -3.0, "range": 0.0, "spot": {"innerConeAngle": 0.9, "outerConeAngle": 0.4}}]);
    doc["extensionsRequired"] = json!(["KHR_lights_punctual"]);
    let path = scratch("bad_light.gltf");
    std::fs::write(&path, serde_json::to_vec(&doc).unwrap()).unwrap();
    let scene = raykin::scene::load_gltf(&path, &Default::default())
        .expect("a required KHR_lights_punctual loads");
    let warnings = scene.warnings.join("\n");
    for word in ["intensity", "range", "cone"] {
        assert!(
            warnings.contains(word),
            "no warning about {word}: {warnings}"
        );
    }
    let light = &scene.lights[0];
    assert_eq!(light.intensity, 0.0);
    assert_eq!(light.range, None);
    let PunctualKind::Spot {
        inner_cone_angle,
        outer_cone_angle,
    } = light.kind
    else {
        panic!()
    };
    assert!(inner_cone_angle < outer_cone_angle);
}

/// A radiance map with a gradient and a hot spot, in linear f32.
fn test_map() -> (u32, u32, Vec<[f32; 3]>) {
    let (w, h) = (16u32, 9u32);
    let texels = (0..w * h)
        .map(|i| {
            let (x, y) = (i % w, i / w);
            if (x, y) == (5, 3) {
                [250.0, 200.0, 150.0]
            } else {
                [0.1 + 0.05 * x as f32, 0.2, 0.3 + 0.1 * y as f32]
            }
        })
        .collect();
    (w, h, texels)
}

#[test]
fn environment_maps_read_from_hdr_and_exr() {
    let (w, h, texels) = test_map();
    let exr = scratch("map.exr");
    raykin::image_io::write_exr(&exr, w, h, &texels).unwrap();
    let hdr = scratch("map.hdr");
    {
        let file = std::io::BufWriter::new(std::fs::File::create(&hdr).unwrap());
        let pixels: Vec<image::Rgb<f32>> = texels.iter().map(|t| image::Rgb(*t)).collect();
        image::codecs::hdr::HdrEncoder::new(file)
            .encode(&pixels, w as usize, h as usize)
            .unwrap();
    }
    // RGBE keeps 8 mantissa bits under an exponent shared by the texel's channels: a channel is exact to
    // 1/128 of the texel's largest.
    for (path, tolerance) in [(&exr, 1e-6), (&hdr, 1.0 / 128.0)] {
        let (map, notes) = raykin::environment::EnvironmentMap::load(path).unwrap();
        assert!(notes.is_empty(), "{notes:?}");
        assert_eq!((map.width, map.height), (w, h));
        for (a, b) in map.texels.iter().zip(&texels) {
            for c in 0..3 {
                assert!(
                    (a[c] - b[c]).abs() <= tolerance * b.iter().copied().fold(0.0, f32::max),
                    "{}: {a:?} vs {b:?}",
                    path.display()
                );
            }
        }
    }
}

#[test]
fn bad_environment_maps_are_clear_errors() {
    let missing = scratch("missing.hdr");
    let err = raykin::environment::EnvironmentMap::load(&missing)
        .unwrap_err()
        .to_string();
    assert!(
        err.contains("missing.hdr") && err.contains("cannot read"),
        "{err}"
    );
    let garbage = scratch("garbage.exr");
    std::fs::write(&garbage, b"this is not an image at all").unwrap();
    let err = raykin::environment::EnvironmentMap::load(&garbage)
        .unwrap_err()
        .to_string();
    assert!(err.contains("garbage.exr") && err.contains(".hdr"), "{err}");
    // An app asked for a map it cannot read fails with the same message, before rendering.
    let (ctx, _gpu) = gpu();
    let scene = Arc::new(
        raykin::scene::load_gltf(
            repo_root().join("tests/reference/lights/envmap.gltf"),
            &Default::default(),
        )
        .unwrap(),
    );
    let settings = small(Environment::Map(raykin::environment::MapSettings {
        path: garbage.clone(),
        rotation_degrees: 0.0,
        strength: 1.0,
    }));
    let err = HeadlessApp::new(ctx, scene, settings, &CameraChoice::Auto)
        .err()
        .expect("refused")
        .to_string();
    assert!(err.contains("garbage.exr"), "{err}");
}
