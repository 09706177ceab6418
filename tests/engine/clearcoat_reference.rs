//! raykin's clear coat against a reference it did not make: Mitsuba 3's `path` rendering a clear-coated red
//! dielectric sphere (KHR_materials_clearcoat 1, roughness 0.3, over roughness 0.6) on a diffuse floor under the
//! glass reference's sky map. The sphere is the glTF model under the coat's `fresnel_coat` layer as a Python BSDF
//! (tests/reference/clearcoat/gltf_clearcoat.py, checked by check_clearcoat.py: chi^2, eval against numpy,
//! albedo); tests/reference/clearcoat/make_reference.py wrote the scene and the two reference halves. See
//! tests/reference/clearcoat/README.md.

use crate::common::cornell::assert_agree_within_noise;
use crate::common::sphere_reference::*;
use crate::common::*;
use std::path::PathBuf;

/// raykin depth = Mitsuba max_depth - 1 (reference.json records 5).
const DEPTH: u32 = 4;
/// Samples per pixel in each of our two halves.
const SPP: u32 = 64;
/// The sphere's mean may differ from Mitsuba's by this much (relative, per channel) plus 4 standard errors.
const SPHERE_TOLERANCE: f64 = 0.02;

fn dir() -> PathBuf {
    repo_root().join("tests/reference/clearcoat")
}

/// The scene file is what reference.json says Mitsuba rendered: the coat's and the base's values.
fn check_scene_file(info: &serde_json::Value) {
    let gltf: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir().join("clearcoat.gltf")).unwrap())
            .unwrap();
    let coated = gltf["materials"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "coated")
        .expect("a material named coated");
    let (coat, want) = (
        &coated["extensions"]["KHR_materials_clearcoat"],
        &info["coated"],
    );
    assert_eq!(coat["clearcoatFactor"], want["clearcoat"]);
    assert_eq!(
        coat["clearcoatRoughnessFactor"],
        want["clearcoat_roughness"]
    );
    let pbr = &coated["pbrMetallicRoughness"];
    assert_eq!(pbr["roughnessFactor"], want["roughness"]);
    assert_eq!(pbr["metallicFactor"], want["metallic"]);
}

#[test]
fn clearcoated_sphere_matches_mitsuba() {
    let info = reference_info(&dir());
    assert_eq!(
        info["integrator"]["max_depth"].as_u64(),
        Some(DEPTH as u64 + 1)
    );
    check_scene_file(&info);
    let scene = std::sync::Arc::new(
        raykin::scene::load_gltf(dir().join("clearcoat.gltf"), &Default::default())
            .expect("clearcoat.gltf loads"),
    );
    let (ctx, _gpu) = gpu();
    let choice = camera(&info);
    let start = std::time::Instant::now();
    let a = render(
        &ctx,
        &scene,
        settings(&dir(), &info, DEPTH, 1),
        &choice,
        SPP,
    );
    let b = render(
        &ctx,
        &scene,
        settings(&dir(), &info, DEPTH, 2),
        &choice,
        SPP,
    );
    eprintln!(
        "clearcoat: 2 x {SPP} spp, depth {DEPTH}, in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert_all_finite(&a, "clearcoat half a");
    assert_all_finite(&b, "clearcoat half b");
    let read = |name: &str| {
        let (w, h, img) = raykin::image_io::read_exr(&dir().join(name)).expect("reference image");
        assert_eq!((w, h), (SIZE, SIZE));
        img
    };
    let (ra, rb) = (read("clearcoat_a.exr"), read("clearcoat_b.exr"));

    let view = raykin::headless::HeadlessApp::new(
        ctx.clone(),
        scene.clone(),
        settings(&dir(), &info, DEPTH, 0),
        &choice,
    )
    .unwrap()
    .camera();
    let sphere = &info["sphere"];
    let pixels = sphere_pixels(
        &view,
        vec3(&sphere["center"]),
        sphere["radius"].as_f64().unwrap() as f32,
    );
    assert_eq!(
        pixels.len() as u64,
        info["sphere_pixels"]["count"].as_u64().unwrap(),
        "sphere pixel count: raykin's camera and the script's disagree"
    );
    let (ours, ours_se) = masked_mean(&a, &b, &pixels);
    let (theirs, theirs_se) = masked_mean(&ra, &rb, &pixels);
    eprintln!(
        "clearcoated sphere ({} px): mean ours {ours:?} (se {ours_se:?}), Mitsuba {theirs:?} (se {theirs_se:?}), ratio {:?}",
        pixels.len(),
        [0, 1, 2].map(|c| ours[c] / theirs[c])
    );

    assert_agree_within_noise("clearcoated sphere vs Mitsuba", (&a, &b), (&ra, &rb));
    for c in 0..3 {
        let tolerance = SPHERE_TOLERANCE + 4.0 * (ours_se[c].hypot(theirs_se[c])) / theirs[c];
        assert!(
            (ours[c] / theirs[c] - 1.0).abs() < tolerance,
            "clearcoated sphere's pixels, channel {c}: mean {} vs Mitsuba {} (tolerance {tolerance:.3})",
            ours[c],
            theirs[c]
        );
    }
}
