//! The commands' GPU work under Vulkan's validation layer (Debian: vulkan-validationlayers, installed by
//! scripts/setup.sh): no error and no warning, synchronisation validation included. Lavapipe runs invalid command
//! buffers as if they were valid (it reads whatever descriptor set was bound last and runs dispatches in order), so
//! a fault that only a real GPU shows needs the layer to be seen here: the wavefront integrator's sizing kernels
//! once had a pipeline layout incompatible with the view's group, which lavapipe rendered correctly and NVIDIA
//! rendered as camera rays only (VUID-vkCmdDispatch-None-02697; docs/BENCHMARKS.md, "The sixteenth session's
//! CPU-path changes on the GPU").

use crate::common::{fresh_dir, repo_root, shared_assets, xdg_runtime_dir};
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, MutexGuard};

const LAYER_MANIFEST: &str = "/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json";

/// The processes share 2 cores with lavapipe: one test of this module at a time.
fn serial() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|p| p.into_inner())
}

/// Runs `raykin ARGS` with the validation layer reporting errors, warnings and information (the information
/// proves the layer ran) and asserts that it succeeded and the layer reported no error or warning.
fn assert_runs_valid(what: &str, dir: &Path, args: &[&dyn AsRef<std::ffi::OsStr>]) {
    assert!(
        Path::new(LAYER_MANIFEST).exists(),
        "Vulkan's validation layer is not installed ({LAYER_MANIFEST}): run scripts/setup.sh \
         (apt-get install vulkan-validationlayers)"
    );
    let settings = dir.join("vk_layer_settings.txt");
    std::fs::write(
        &settings,
        "khronos_validation.report_flags = error,warn,info\n\
         khronos_validation.debug_action = VK_DBG_LAYER_ACTION_LOG_MSG\n\
         khronos_validation.enables = VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT\n",
    )
    .unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_raykin"))
        .args(args.iter().map(|a| a.as_ref()))
        .current_dir(repo_root())
        .env("XDG_RUNTIME_DIR", xdg_runtime_dir())
        .env("VK_INSTANCE_LAYERS", "VK_LAYER_KHRONOS_validation")
        .env("VK_LAYER_SETTINGS_PATH", dir)
        // Debug builds write shader debug information naming WGSL as the source language (10), which Debian 12's
        // layer (1.3.239) does not know yet and reports as invalid SPIR-V; release builds write none.
        .env("WGPU_DEBUG", "0")
        .output()
        .unwrap();
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "raykin failed: {text}");
    assert!(
        text.contains("khronos-validation-createinstance-status-message"),
        "the validation layer did not run: {text}"
    );
    let found = complaints(&text);
    assert!(
        found.is_empty(),
        "{what}: {} validation messages, the first: {}",
        found.len(),
        found[0]
    );
}

/// The messages the layer reported as errors or warnings (performance warnings included), one line each.
fn complaints(text: &str) -> Vec<&str> {
    text.lines()
        .filter(|l| l.contains("Validation Error") || l.contains("Validation Warning"))
        .filter(|l| !l.contains("createinstance-status-message"))
        .collect()
}

fn cornell() -> PathBuf {
    shared_assets().join("CornellBox/CornellBox.glb")
}

#[test]
fn both_integrators_and_the_denoiser_record_valid_commands() {
    let _serial = serial();
    let dir = fresh_dir("validation-render");
    // The Cornell box at 16x16 with each form's own options.
    let forms: [(&str, &[&str]); 3] = [
        ("megakernel", &["--spp", "2", "--integrator", "megakernel"]),
        ("wavefront", &["--spp", "2", "--integrator", "wavefront"]),
        ("denoised", &["--spp", "4", "--denoise"]),
    ];
    for (name, options) in forms {
        let scene = cornell();
        let out = dir.join(format!("{name}.exr"));
        let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![
            &"render",
            &scene,
            &"--width",
            &"16",
            &"--height",
            &"16",
            &"--out",
            &out,
        ];
        args.extend(options.iter().map(|o| o as &dyn AsRef<std::ffi::OsStr>));
        assert_runs_valid(name, &dir, &args);
    }
}

#[test]
fn real_time_recording_of_a_skinned_scene_records_valid_commands() {
    let _serial = serial();
    let dir = fresh_dir("validation-record");
    let scene = shared_assets().join("CesiumMan/glTF-Binary/CesiumMan.glb");
    assert_runs_valid(
        "real-time recording",
        &dir,
        &[
            &"record",
            &scene,
            &"--frames",
            &"3",
            &"--fps",
            &"10",
            &"--width",
            &"16",
            &"--height",
            &"16",
            &"--spp",
            &"2",
            &"--deform",
            &"gpu",
            &"--realtime",
            &"--out",
            &dir.join("frames"),
        ],
    );
}

#[test]
fn bench_frame_loop_records_valid_commands() {
    let _serial = serial();
    let dir = fresh_dir("validation-bench");
    assert_runs_valid(
        "bench frame loop",
        &dir,
        &[
            &"bench",
            &"--suite",
            &"quick",
            &"--parts",
            &"frames",
            &"--frames",
            &"3",
            &"--scene",
            &"cornell",
            &"--assets",
            &shared_assets(),
            &"--out",
            &dir.join("out"),
            &"--cache",
            &dir.join("cache"),
        ],
    );
}

#[test]
fn offscreen_viewer_records_valid_commands() {
    let _serial = serial();
    let dir = fresh_dir("validation-viewer");
    // The viewer's frame: the real-time mode while the skinned figure walks, and the editor's panels drawn by egui.
    let scene = shared_assets().join("CesiumMan/glTF-Binary/CesiumMan.glb");
    assert_runs_valid(
        "offscreen viewer",
        &dir,
        &[
            &"view",
            &scene,
            &"--offscreen",
            &"--no-settings",
            &"--frames",
            &"4",
            &"--image-size",
            &"32x32",
        ],
    );
}
