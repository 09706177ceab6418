//! `raykin render --denoise`: OIDN's image is what the command writes, and without the library a message and
//! the fallback to svgf (the denoiser itself is tested in tests/engine/oidn.rs).

use crate::common::cornell::{self, EPS};
use crate::common::{gpu, rel_mse, shared_assets};

/// `raykin render --denoise` (OIDN, the default denoiser) writes the image `HeadlessApp::oidn_denoised` makes
/// from the same samples, bit for bit (OIDN's CPU device on lavapipe is deterministic), names the device in its
/// report, and differs from svgf's image.
#[test]
fn render_command_writes_the_oidn_image() {
    let dir = crate::common::fresh_dir("oidn-cli");
    let run = |out: &std::path::Path, denoiser: &str| {
        let report = out.with_extension("json");
        let output = std::process::Command::new(env!("CARGO_BIN_EXE_raykin"))
            .arg("render")
            .arg(shared_assets().join("CornellBox/CornellBox.glb"))
            .args([
                "--width", "16", "--height", "16", "--spp", "4", "--seed", "61",
            ])
            .args(["--env", "0,0,0", "--max-depth", "8", "--fov", "39.3077"])
            .args(["--look-from=-278,273,800", "--look-at=-278,273,0"])
            .args(["--denoise", denoiser, "--out"])
            .arg(out)
            .arg("--report")
            .arg(&report)
            .output()
            .expect("raykin runs");
        let log = String::from_utf8_lossy(&output.stderr);
        assert!(output.status.success(), "raykin render failed:\n{log}");
        let r: serde_json::Value =
            serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
        (
            raykin::image_io::read_exr(out).expect("EXR").2,
            r,
            log.to_string(),
        )
    };
    let (from_cli, report, log) = run(&dir.join("oidn.exr"), "oidn");
    let (svgf, _, _) = run(&dir.join("svgf.exr"), "svgf");
    assert_eq!(report["denoiser"], "oidn", "{report}");
    let device = report["oidn_device"].as_str().unwrap_or_default();
    assert!(
        !device.is_empty() && log.contains(device),
        "the device is named in the report and the log: {report}\n{log}"
    );

    let (ctx, _gpu) = gpu();
    let mut app = cornell::app(ctx, true, 16, 61);
    app.accumulate(4, 16, |_| {});
    let expected = app.oidn_denoised().expect("OIDN runs");
    let bits = |v: &[[f32; 3]]| -> Vec<u32> { v.iter().flatten().map(|x| x.to_bits()).collect() };
    assert!(
        bits(&from_cli) == bits(&expected.color),
        "`--denoise oidn` EXR differs from HeadlessApp::oidn_denoised"
    );
    assert!(
        rel_mse(&from_cli, &svgf, EPS) > 1e-4,
        "OIDN's and svgf's images are the same"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A missing library: `raykin render --denoise oidn` says what is missing and where it looked, falls back to
/// svgf, and still writes the image; the report names the denoiser that ran.
#[test]
fn missing_library_falls_back_to_svgf_with_a_message() {
    let dir = std::env::temp_dir().join(format!("raykin-oidn-missing-{}", std::process::id()));
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let out = dir.join("box.png");
    let report = dir.join("report.json");
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_raykin"))
        .arg("render")
        .arg(shared_assets().join("CornellBox/CornellBox.glb"))
        .args(["--width", "16", "--height", "16", "--spp", "2"])
        .args(["--denoise", "oidn", "--out"])
        .arg(&out)
        .arg("--report")
        .arg(&report)
        .env(raykin::oidn::library::DIR_VARIABLE, &empty)
        .env("XDG_RUNTIME_DIR", crate::common::xdg_runtime_dir())
        .output()
        .expect("raykin runs");
    let log = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "raykin render failed:\n{log}");
    for needle in [
        "Open Image Denoise is not installed",
        raykin::oidn::library::LIBRARY_FILE,
        &empty.display().to_string(),
        "scripts/setup.sh",
        "denoising with svgf instead",
    ] {
        assert!(log.contains(needle), "stderr lacks `{needle}`:\n{log}");
    }
    assert!(out.exists(), "no image written");
    let r: serde_json::Value = serde_json::from_slice(&std::fs::read(&report).unwrap()).unwrap();
    assert_eq!(r["denoiser"], "svgf");
    let _ = std::fs::remove_dir_all(&dir);
}
