//! What the Mitsuba references of a sphere under the sky map (tests/reference/glass, tests/reference/clearcoat)
//! share: reference.json's camera and map, the render settings, the sphere's own pixels and their mean.

use super::cornell::assert_agree_within_noise;
use super::{assert_all_finite, gpu, render};
use glam::Vec3;
use raykin::camera::{CameraChoice, CameraView};
use raykin::render::{Environment, RenderSettings};
use std::path::Path;

/// Both references are SIZE x SIZE.
pub const SIZE: u32 = 64;

pub fn reference_info(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("reference.json")).unwrap()).unwrap()
}

pub fn f32s(v: &serde_json::Value) -> Vec<f32> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap() as f32)
        .collect()
}

pub fn vec3(v: &serde_json::Value) -> Vec3 {
    Vec3::from_slice(&f32s(v))
}

/// The reference's camera, read from reference.json.
pub fn camera(info: &serde_json::Value) -> CameraChoice {
    let c = &info["camera"];
    assert_eq!(c["up"], serde_json::json!([0.0, 1.0, 0.0]));
    CameraChoice::LookAt {
        eye: vec3(&c["eye"]),
        target: vec3(&c["target"]),
        yfov: (c["yfov_deg"].as_f64().unwrap() as f32).to_radians(),
    }
}

pub fn settings(dir: &Path, info: &serde_json::Value, depth: u32, seed: u32) -> RenderSettings {
    let env = &info["envmap"];
    RenderSettings {
        width: SIZE,
        height: SIZE,
        max_depth: depth,
        environment: Environment::Map(raykin::environment::MapSettings {
            path: dir.join(env["file"].as_str().unwrap()),
            rotation_degrees: env["rotation_degrees"].as_f64().unwrap() as f32,
            strength: 1.0,
        }),
        seed,
        ..Default::default()
    }
}

/// Indices of the pixels whose four corner rays all hit the exact sphere (the sphere's own pixels, no edge).
pub fn sphere_pixels(view: &CameraView, centre: Vec3, radius: f32) -> Vec<usize> {
    let hits = |x: u32, y: u32| {
        let (o, d) = view.ray_through(x as f32, y as f32, SIZE, SIZE);
        let oc = o - centre;
        let b = oc.dot(d);
        b * b - (oc.length_squared() - radius * radius) > 0.0
    };
    (0..SIZE * SIZE)
        .filter(|&i| {
            let (x, y) = (i % SIZE, i / SIZE);
            hits(x, y) && hits(x + 1, y) && hits(x, y + 1) && hits(x + 1, y + 1)
        })
        .map(|i| i as usize)
        .collect()
}

/// Per-channel mean over `pixels` of the average of two halves, and its standard error estimated from the
/// halves' per-pixel differences (pixels independent: Var(mean) = sum (a - b)^2 / 4 / n^2).
pub fn masked_mean(a: &[[f32; 3]], b: &[[f32; 3]], pixels: &[usize]) -> ([f64; 3], [f64; 3]) {
    let n = pixels.len() as f64;
    let mut mean = [0.0; 3];
    let mut var = [0.0; 3];
    for &p in pixels {
        for c in 0..3 {
            let (x, y) = (a[p][c] as f64, b[p][c] as f64);
            mean[c] += 0.5 * (x + y) / n;
            var[c] += (x - y) * (x - y) / 4.0 / (n * n);
        }
    }
    (mean, var.map(f64::sqrt))
}

/// Renders `dir/{stem}.gltf` as two independent halves of `spp` samples at `depth` and checks them against
/// Mitsuba's halves `{stem}_a.exr` and `{stem}_b.exr`: the whole image within both renderers' noise, and the
/// mean of the sphere's own pixels (found through raykin's camera; the script found as many through its own)
/// per channel within `tolerance` plus 4 standard errors. `what` names the sphere in messages.
pub fn sphere_matches_mitsuba(
    what: &str,
    dir: &Path,
    info: &serde_json::Value,
    stem: &str,
    (depth, spp): (u32, u32),
    tolerance: f64,
) {
    let scene = std::sync::Arc::new(
        raykin::scene::load_gltf(dir.join(format!("{stem}.gltf")), &Default::default())
            .unwrap_or_else(|e| panic!("{stem}.gltf: {e}")),
    );
    let (ctx, _gpu) = gpu();
    let choice = camera(info);
    let start = std::time::Instant::now();
    let a = render(&ctx, &scene, settings(dir, info, depth, 1), &choice, spp);
    let b = render(&ctx, &scene, settings(dir, info, depth, 2), &choice, spp);
    eprintln!(
        "{what}: 2 x {spp} spp, depth {depth}, in {:.1} s",
        start.elapsed().as_secs_f64()
    );
    assert_all_finite(&a, &format!("{what} half a"));
    assert_all_finite(&b, &format!("{what} half b"));
    let read = |half: &str| {
        let (w, h, img) = raykin::image_io::read_exr(&dir.join(format!("{stem}_{half}.exr")))
            .expect("reference image");
        assert_eq!((w, h), (SIZE, SIZE));
        img
    };
    let (ra, rb) = (read("a"), read("b"));

    let view = raykin::headless::HeadlessApp::new(
        ctx.clone(),
        scene.clone(),
        settings(dir, info, depth, 0),
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
        "{what} ({} px): mean ours {ours:?} (se {ours_se:?}), Mitsuba {theirs:?} (se {theirs_se:?}), ratio {:?}",
        pixels.len(),
        [0, 1, 2].map(|c| ours[c] / theirs[c])
    );

    assert_agree_within_noise(&format!("{what} vs Mitsuba"), (&a, &b), (&ra, &rb));
    for c in 0..3 {
        let tolerance = tolerance + 4.0 * (ours_se[c].hypot(theirs_se[c])) / theirs[c];
        assert!(
            (ours[c] / theirs[c] - 1.0).abs() < tolerance,
            "{what}'s pixels, channel {c}: mean {} vs Mitsuba {} (tolerance {tolerance:.3})",
            ours[c],
            theirs[c]
        );
    }
}
