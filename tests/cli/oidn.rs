//! `raykin render --denoise oidn` without the library: the message and the fallback to svgf (the denoiser
//! itself is tested in tests/engine/oidn.rs).

use crate::common::shared_assets;

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
        .env("XDG_RUNTIME_DIR", std::env::temp_dir().join("raykin-xdg"))
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
