//! raykin's glass against a reference it did not make: Mitsuba 3's `volpath` rendering a smooth glass sphere
//! (KHR_materials_transmission 1, KHR_materials_ior 1.5) whose interior absorbs (KHR_materials_volume,
//! Beer-Lambert with sigma_a = -ln(attenuationColor) / attenuationDistance) on a diffuse floor beside a blue
//! panel, lit by a smooth environment map. The glass is the glTF model as a Python BSDF
//! (tests/reference/glass/gltf_glass.py, checked by check_glass.py); tests/reference/glass/make_reference.py
//! wrote the scene, the map and the two reference halves. See tests/reference/glass/README.md.

use crate::common::sphere_reference::*;
use crate::common::*;
use std::path::PathBuf;

/// raykin depth = Mitsuba max_depth - 1 (reference.json records 9).
const DEPTH: u32 = 8;
/// Samples per pixel in each of our two halves.
const SPP: u32 = 128;
/// The sphere's mean may differ from Mitsuba's by this much (relative, per channel) plus 4 standard errors.
const SPHERE_TOLERANCE: f64 = 0.03;

fn dir() -> PathBuf {
    repo_root().join("tests/reference/glass")
}

/// The scene file is what reference.json says Mitsuba rendered: the glass's extensions and values.
fn check_scene_file(info: &serde_json::Value) {
    let gltf: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir().join("glass.gltf")).unwrap()).unwrap();
    let glass = gltf["materials"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["name"] == "glass")
        .expect("a material named glass");
    let (ext, want) = (&glass["extensions"], &info["glass"]);
    assert_eq!(
        ext["KHR_materials_transmission"]["transmissionFactor"],
        want["transmission"]
    );
    assert_eq!(ext["KHR_materials_ior"]["ior"], want["ior"]);
    let volume = &ext["KHR_materials_volume"];
    assert_eq!(volume["attenuationColor"], want["attenuation_color"]);
    assert_eq!(volume["attenuationDistance"], want["attenuation_distance"]);
    assert_eq!(volume["thicknessFactor"], want["thickness"]);
    assert_eq!(glass["pbrMetallicRoughness"]["roughnessFactor"], 0.0);
    assert_eq!(glass["pbrMetallicRoughness"]["metallicFactor"], 0.0);
}

#[test]
fn glass_sphere_with_absorption_matches_mitsuba() {
    let info = reference_info(&dir());
    assert_eq!(
        info["integrator"]["max_depth"].as_u64(),
        Some(DEPTH as u64 + 1)
    );
    check_scene_file(&info);
    sphere_matches_mitsuba(
        "glass sphere",
        &dir(),
        &info,
        "glass",
        (DEPTH, SPP),
        SPHERE_TOLERANCE,
    );
}
