//! Bad input: each case gets a clear error naming the file and the problem, or a warning and a skipped piece
//! while the rest renders; never a panic, a hang, or a non-finite/black image.

use crate::common::*;
use base64::Engine as _;
use raykin::camera::CameraChoice;
use raykin::render::{Environment, RenderSettings};
use raykin::scene::{LoadOptions, SceneError, load_gltf};
use serde_json::json;
use std::path::{Path, PathBuf};
use std::sync::Arc;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raykin-bad-input-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// A glTF with one triangle primitive per entry of `prims` (positions, indices), buffers as a data URI.
fn gltf_json(prims: &[(Vec<[f32; 3]>, Vec<u32>)]) -> serde_json::Value {
    let mut bin = Vec::new();
    let (mut views, mut accessors, mut primitives) = (vec![], vec![], vec![]);
    for (positions, indices) in prims {
        let pos_offset = bin.len();
        for p in positions {
            for c in p {
                bin.extend_from_slice(&c.to_le_bytes());
            }
        }
        let idx_offset = bin.len();
        for i in indices {
            bin.extend_from_slice(&i.to_le_bytes());
        }
        let finite: Vec<&[f32; 3]> = positions
            .iter()
            .filter(|p| p.iter().all(|c| c.is_finite()))
            .collect();
        let lo: Vec<f32> = (0..3)
            .map(|c| finite.iter().map(|p| p[c]).fold(f32::MAX, f32::min))
            .collect();
        let hi: Vec<f32> = (0..3)
            .map(|c| finite.iter().map(|p| p[c]).fold(f32::MIN, f32::max))
            .collect();
        views.push(
            json!({"buffer": 0, "byteOffset": pos_offset, "byteLength": idx_offset - pos_offset}),
        );
        accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5126, "count": positions.len(), "type": "VEC3", "min": lo, "max": hi}));
        views.push(
            json!({"buffer": 0, "byteOffset": idx_offset, "byteLength": bin.len() - idx_offset}),
        );
        accessors.push(json!({"bufferView": views.len() - 1, "componentType": 5125, "count": indices.len(), "type": "SCALAR"}));
        primitives.push(json!({"attributes": {"POSITION": accessors.len() - 2}, "indices": accessors.len() - 1}));
    }
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": primitives}],
        "buffers": [{"byteLength": bin.len(), "uri": uri}],
        "bufferViews": views, "accessors": accessors,
    })
}

fn quad() -> (Vec<[f32; 3]>, Vec<u32>) {
    (
        vec![
            [-1.0, -1.0, 0.0],
            [1.0, -1.0, 0.0],
            [1.0, 1.0, 0.0],
            [-1.0, 1.0, 0.0],
        ],
        vec![0, 1, 2, 0, 2, 3],
    )
}

fn write(name: &str, value: &serde_json::Value) -> PathBuf {
    let path = scratch(name);
    std::fs::write(&path, serde_json::to_vec(value).unwrap()).unwrap();
    path
}

fn load(path: &Path) -> Result<raykin::scene::SceneAsset, SceneError> {
    load_gltf(path, &LoadOptions::default())
}

/// Renders a loaded scene tiny and checks the image is finite and not black.
fn renders_visibly(scene: raykin::scene::SceneAsset) {
    let (ctx, _gpu) = gpu();
    let settings = RenderSettings {
        width: 16,
        height: 16,
        environment: Environment::Sky,
        max_depth: 2,
        ..Default::default()
    };
    let img = render(&ctx, &Arc::new(scene), settings, &CameraChoice::Auto, 2);
    assert_all_finite(&img, "bad-input render");
    assert!(mean_rgb(&img).iter().all(|c| *c > 0.01), "image is black");
}

fn assert_names(err: &dyn std::fmt::Display, path: &Path, words: &[&str]) {
    let msg = err.to_string();
    let file = path.file_name().unwrap().to_string_lossy();
    assert!(
        msg.contains(file.as_ref()),
        "error does not name the file: {msg}"
    );
    for w in words {
        assert!(
            msg.to_lowercase().contains(&w.to_lowercase()),
            "error does not mention `{w}`: {msg}"
        );
    }
}

#[test]
fn malformed_json_is_a_clear_error() {
    let path = scratch("malformed.gltf");
    std::fs::write(
        &path,
        b"{ \"asset\": { \"version\": \"2.0\" }, \"meshes\": [ {",
    )
    .unwrap();
    let err = load(&path).unwrap_err();
    assert!(matches!(err, SceneError::Invalid { .. }), "{err}");
    assert_names(&err, &path, &["not a valid glTF"]);
}

#[test]
fn truncated_glb_is_a_clear_error() {
    let bytes = std::fs::read(shared_assets().join("CornellBox/CornellBox.glb")).unwrap();
    for keep in [10, bytes.len() / 2, bytes.len() - 100] {
        let path = scratch(&format!("truncated_{keep}.glb"));
        std::fs::write(&path, &bytes[..keep]).unwrap();
        let err = load(&path).expect_err("a truncated file must not load");
        assert_names(&err, &path, &[]);
    }
}

#[test]
fn missing_buffer_names_the_uri() {
    let mut doc = gltf_json(&[quad()]);
    doc["buffers"][0]["uri"] = json!("does_not_exist.bin");
    let path = write("missing_buffer.gltf", &doc);
    let err = load(&path).unwrap_err();
    assert!(matches!(err, SceneError::Buffer { .. }), "{err}");
    assert_names(&err, &path, &["does_not_exist.bin"]);
}

#[test]
fn missing_texture_warns_and_renders_without_it() {
    let mut doc = gltf_json(&[quad()]);
    doc["images"] = json!([{"uri": "no_such_texture.png"}]);
    doc["textures"] = json!([{"source": 0}]);
    doc["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0}}]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let path = write("missing_texture.gltf", &doc);
    let scene = load(&path).expect("a missing texture is not fatal");
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("no_such_texture.png") || w.contains("image 0")),
        "{:?}",
        scene.warnings
    );
    assert!(scene.materials[0].base_color_texture.is_none());
    renders_visibly(scene);
}

#[test]
fn out_of_range_indices_skip_the_primitive() {
    let (p, _) = quad();
    let doc = gltf_json(&[quad(), (p, vec![0, 1, 7])]);
    let path = write("bad_indices.gltf", &doc);
    let scene = load(&path).expect("the good primitive still loads");
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("index 7 is out of range")),
        "{:?}",
        scene.warnings
    );
    assert_eq!(scene.triangle_count(), 2);
    renders_visibly(scene);

    // With nothing left to render, the error says why.
    let (p, _) = quad();
    let path = write("only_bad_indices.gltf", &gltf_json(&[(p, vec![0, 1, 9])]));
    let err = load(&path).unwrap_err();
    assert_names(&err, &path, &["out of range"]);
}

#[test]
fn nan_vertices_drop_their_triangles() {
    let (mut p, i) = quad();
    p.push([f32::NAN, 0.0, 0.0]);
    p.push([0.0, f32::INFINITY, 0.0]);
    let mut idx = i.clone();
    idx.extend([4, 0, 1, 5, 1, 2]);
    let path = write("nan_vertices.gltf", &gltf_json(&[(p, idx)]));
    let scene = load(&path).expect("finite triangles still load");
    assert!(
        scene.warnings.iter().any(|w| w.contains("NaN or infinite")),
        "{:?}",
        scene.warnings
    );
    assert_eq!(scene.triangle_count(), 2);
    assert!(scene.meshes[0].positions.iter().all(|v| v.is_finite()));
    renders_visibly(scene);
}

#[test]
fn zero_area_triangles_are_dropped() {
    let (mut p, mut i) = quad();
    p.push([0.5, 0.5, 0.0]);
    i.extend([0, 0, 1, 0, 2, 4]); // repeated vertex; collinear (0, 2 and 4 on the diagonal)
    let path = write("zero_area.gltf", &gltf_json(&[(p, i)]));
    let scene = load(&path).expect("loads");
    assert!(
        scene
            .warnings
            .iter()
            .any(|w| w.contains("2 zero-area triangles dropped")),
        "{:?}",
        scene.warnings
    );
    assert_eq!(scene.triangle_count(), 2);
    renders_visibly(scene);
}

/// Many primitives with a few slivers each (the spheres of MetalRoughSpheresNoTextures) give one warning for the
/// file, with the total, the primitives' count and the first few named, not a warning per primitive.
#[test]
fn zero_area_triangles_of_many_primitives_are_reported_once() {
    let (mut p, mut i) = quad();
    p.push([0.5, 0.5, 0.0]);
    i.extend([0, 0, 1, 0, 2, 4]);
    let slivered = (p, i);
    let path = write(
        "zero_area_many.gltf",
        &gltf_json(&[
            slivered.clone(),
            quad(),
            slivered.clone(),
            slivered.clone(),
            slivered,
        ]),
    );
    let scene = load(&path).expect("loads");
    let dropped: Vec<&String> = scene
        .warnings
        .iter()
        .filter(|w| w.contains("zero-area"))
        .collect();
    assert_eq!(dropped.len(), 1, "{:?}", scene.warnings);
    for part in [
        "8 zero-area triangles dropped from 4 primitives",
        "mesh 0 `` primitive 0: 2; mesh 0 `` primitive 2: 2; mesh 0 `` primitive 3: 2; and 1 more",
    ] {
        assert!(dropped[0].contains(part), "{part:?} in {dropped:?}");
    }
    assert_eq!(scene.triangle_count(), 5 * 2);
}

#[test]
fn unsupported_required_extension_is_refused() {
    let mut doc = gltf_json(&[quad()]);
    // Draco, quantization and meshopt are supported now (tests/gltf_conformance.rs); the archived
    // specular-glossiness model is not.
    doc["extensionsUsed"] = json!(["KHR_materials_pbrSpecularGlossiness"]);
    doc["extensionsRequired"] = json!(["KHR_materials_pbrSpecularGlossiness"]);
    let path = write("specgloss.gltf", &doc);
    let err = load(&path).unwrap_err();
    assert!(
        matches!(err, SceneError::UnsupportedExtension { .. }),
        "{err}"
    );
    assert_names(&err, &path, &["KHR_materials_pbrSpecularGlossiness"]);
}

#[test]
fn cyclic_nodes_are_refused() {
    let mut doc = gltf_json(&[quad()]);
    doc["nodes"] = json!([{"mesh": 0, "children": [1]}, {"children": [0]}]);
    let path = write("cycle.gltf", &doc);
    let err = load(&path).unwrap_err();
    assert_names(&err, &path, &[]);
}

#[test]
fn accessor_outside_its_buffer_skips_the_primitive() {
    let mut doc = gltf_json(&[quad(), quad()]);
    // The second primitive's positions claim 400 vertices in a 48-byte view.
    doc["accessors"][2]["count"] = json!(400);
    let path = write("accessor_overflow.gltf", &doc);
    match load(&path) {
        Ok(scene) => {
            assert!(!scene.warnings.is_empty());
            assert_eq!(scene.triangle_count(), 2);
        }
        Err(e) => assert_names(&e, &path, &[]),
    }
}

#[test]
fn scene_over_gpu_limits_is_a_clear_error() {
    let (ctx, _gpu) = gpu();
    let scene = Arc::new(load(&shared_assets().join("CornellBox/CornellBox.glb")).unwrap());
    let settings = RenderSettings {
        width: 8,
        height: 8,
        ..Default::default()
    };
    let err = raykin::headless::HeadlessApp::with_binding_limit(
        ctx,
        scene,
        settings,
        &CameraChoice::Auto,
        Some(256),
    )
    .err()
    .expect("a 256-byte limit cannot hold the Cornell box");
    let msg = err.to_string();
    assert!(
        msg.contains("CornellBox.glb")
            && msg.contains("over this GPU's limits")
            && msg.contains("MiB"),
        "{msg}"
    );
}
