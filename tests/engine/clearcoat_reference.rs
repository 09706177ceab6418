//! raykin's clear coat against a reference it did not make: Mitsuba 3's `path` rendering a clear-coated red
//! dielectric sphere (KHR_materials_clearcoat 1, roughness 0.3, over roughness 0.6) on a diffuse floor under the
//! glass reference's sky map. The sphere is the glTF model under the coat's `fresnel_coat` layer as a Python BSDF
//! (tests/reference/clearcoat/gltf_clearcoat.py, checked by check_clearcoat.py: chi^2, eval against numpy,
//! albedo); tests/reference/clearcoat/make_reference.py wrote the scene and the two reference halves. See
//! tests/reference/clearcoat/README.md.

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
    sphere_matches_mitsuba(
        "clearcoated sphere",
        &dir(),
        &info,
        "clearcoat",
        (DEPTH, SPP),
        SPHERE_TOLERANCE,
    );
}
