//! Shared by both integration-test binaries (tests/engine/, tests/cli/): one GPU context per binary, asset
//! paths, scratch folders, image statistics, and the Mitsuba reference set-up (`cornell`).
#![allow(dead_code)]

pub mod cornell;
pub mod denoising;
pub mod sphere_reference;

use raykin::camera::CameraChoice;
use raykin::gpu::GpuContext;
use raykin::headless::HeadlessApp;
use raykin::render::RenderSettings;
use raykin::scene::SceneAsset;
use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

/// The repository root (each test binary runs in its package's folder, engine/ or game/).
pub fn repo_root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// `../shared/assets`, beside the repository, as in CI.
pub fn shared_assets() -> PathBuf {
    repo_root().join("../shared/assets")
}

/// A fresh, empty folder under the temporary directory, unique to this process.
pub fn fresh_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raykin-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("temp dir");
    dir
}

/// Every .gltf and .glb file under `dir`, sorted.
pub fn gltf_files_under(dir: &std::path::Path) -> Vec<PathBuf> {
    let mut files = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(dir) = stack.pop() {
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else if matches!(
                path.extension().and_then(|e| e.to_str()),
                Some("gltf" | "glb")
            ) {
                files.push(path);
            }
        }
    }
    files.sort();
    files
}

/// One device per test binary; a lock serialises GPU tests (lavapipe has 2 cores to share).
pub fn gpu() -> (GpuContext, std::sync::MutexGuard<'static, ()>) {
    static LOCK: Mutex<()> = Mutex::new(());
    let guard = LOCK.lock().unwrap_or_else(|p| p.into_inner());
    (gpu_context(), guard)
}

/// The `XDG_RUNTIME_DIR` the tests give the device and the `raykin` processes: one private (0700) folder under
/// the temporary directory, made if missing.
pub fn xdg_runtime_dir() -> PathBuf {
    let dir = std::env::temp_dir().join("raykin-xdg");
    let _ = std::fs::create_dir_all(&dir);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(&dir, std::fs::Permissions::from_mode(0o700));
    }
    dir
}

/// The test binary's device, without serialising (for tests that run one at a time anyway).
pub fn gpu_context() -> GpuContext {
    static CTX: OnceLock<GpuContext> = OnceLock::new();
    CTX.get_or_init(|| {
        let dir = xdg_runtime_dir();
        // SAFETY: set before any GPU thread starts, once per process.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        GpuContext::new_headless()
            .expect("a GPU adapter (install mesa-vulkan-drivers for lavapipe)")
    })
    .clone()
}

/// Renders `spp` samples per pixel and returns mean linear radiance per pixel.
pub fn render(
    ctx: &GpuContext,
    scene: &Arc<SceneAsset>,
    settings: RenderSettings,
    camera: &CameraChoice,
    spp: u32,
) -> Vec<[f32; 3]> {
    let mut app =
        HeadlessApp::new(ctx.clone(), scene.clone(), settings, camera).expect("scene uploads");
    app.accumulate(spp, 64, |_| {});
    app.radiance()
}

/// Relative MSE over pixels and channels: (a - b)^2 / (b^2 + eps).
pub fn rel_mse(a: &[[f32; 3]], reference: &[[f32; 3]], eps: f64) -> f64 {
    let mut sum = 0.0;
    for (p, r) in a.iter().zip(reference) {
        for c in 0..3 {
            let d = p[c] as f64 - r[c] as f64;
            sum += d * d / (r[c] as f64 * r[c] as f64 + eps);
        }
    }
    sum / (3 * a.len()) as f64
}

pub fn assert_all_finite(img: &[[f32; 3]], what: &str) {
    let bad = img.iter().flatten().filter(|v| !v.is_finite()).count();
    assert_eq!(bad, 0, "{what}: {bad} non-finite pixel values");
}

/// Two forms of one kernel rendered the same image: `a` finite, `b` not black, and every pixel equal bit for bit.
pub fn assert_forms_render_the_same_image(a: &[[f32; 3]], b: &[[f32; 3]], what: &str) {
    assert_all_finite(a, what);
    assert!(
        mean_rgb(b).iter().all(|&m| m > 1e-3),
        "{what}: a black image"
    );
    let differ = a.iter().zip(b).filter(|(a, b)| a != b).count();
    assert_eq!(
        differ, 0,
        "{what}: {differ} pixels differ between the two forms"
    );
}

/// The asset at `file` under ../shared/assets, loaded (a failure names the file).
pub fn shared_scene(file: &str) -> Arc<SceneAsset> {
    let path = shared_assets().join(file);
    Arc::new(
        raykin::scene::load_gltf(&path, &Default::default())
            .unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    )
}

/// The largest difference of a channel of `a` from `b`'s, relative to `b`'s (at least 1e-3): two forms of a
/// kernel that add the same samples in another order differ by rounding only.
pub fn worst_relative_difference(a: &[[f32; 3]], b: &[[f32; 3]]) -> f32 {
    a.iter()
        .zip(b)
        .flat_map(|(a, b)| (0..3).map(move |c| (a[c] - b[c]).abs() / b[c].abs().max(1e-3)))
        .fold(0.0f32, f32::max)
}

pub fn mean_rgb(img: &[[f32; 3]]) -> [f64; 3] {
    let mut m = [0.0; 3];
    for p in img {
        for c in 0..3 {
            m[c] += p[c] as f64;
        }
    }
    m.map(|v| v / img.len() as f64)
}

/// Each channel of `got` within `tolerance` (relative) of `want`; `what` names the comparison.
pub fn assert_channel_means_within(what: &str, got: [f64; 3], want: [f64; 3], tolerance: f64) {
    for c in 0..3 {
        assert!(
            (got[c] / want[c] - 1.0).abs() < tolerance,
            "{what}: mean channel {c}: {} vs {} (tolerance {tolerance})",
            got[c],
            want[c]
        );
    }
}

/// A quad from four corners, counter-clockwise seen from its front, as two triangles of one material.
pub fn quad_mesh(corners: [glam::Vec3; 4], material: u32) -> raykin::scene::MeshData {
    raykin::scene::MeshData {
        name: "quad".into(),
        positions: corners.to_vec(),
        triangles: vec![[0, 1, 2], [0, 2, 3]],
        triangle_materials: vec![material; 2],
        primitives: vec![raykin::scene::PrimitiveRange {
            vertex_offset: 0,
            vertex_count: 4,
            material,
        }],
        ..Default::default()
    }
}

/// Least-squares slope of log(y) against log(x).
pub fn log_log_slope(points: &[(f64, f64)]) -> f64 {
    let n = points.len() as f64;
    let (lx, ly): (Vec<f64>, Vec<f64>) = points.iter().map(|(x, y)| (x.ln(), y.ln())).unzip();
    let mx = lx.iter().sum::<f64>() / n;
    let my = ly.iter().sum::<f64>() / n;
    let cov: f64 = lx.iter().zip(&ly).map(|(x, y)| (x - mx) * (y - my)).sum();
    let var: f64 = lx.iter().map(|x| (x - mx) * (x - mx)).sum();
    cov / var
}
