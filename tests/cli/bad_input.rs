//! Bad input to the binary: without a GPU adapter, `raykin` says how to install one (the loader-level bad
//! inputs are the library's tests, tests/engine/bad_input.rs).

use crate::common::repo_root;

#[test]
fn no_gpu_adapter_says_how_to_install_one() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_raykin"))
        .args([
            "render",
            "../shared/assets/CornellBox/CornellBox.glb",
            "--spp",
            "1",
            "--width",
            "8",
            "--height",
            "8",
            "--out",
        ])
        .arg(std::env::temp_dir().join(format!("raykin-no-adapter-{}.png", std::process::id())))
        .current_dir(repo_root())
        .env("WGPU_BACKEND", "vulkan")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        stderr.contains("no GPU adapter") && stderr.contains("mesa-vulkan-drivers"),
        "{stderr}"
    );
}
