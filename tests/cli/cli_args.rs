//! Issue 18, the command line: arguments that cannot render are refused with a clear message before any
//! work, negative numbers need no `=`, outputs never overwrite the scene's files, and the messages are one
//! line each, without colour codes or Mesa noise. Each case runs the `raykin` binary.

use crate::common::*;
use std::path::{Path, PathBuf};
use std::process::Output;

fn malformed(name: &str) -> PathBuf {
    repo_root().join("tests/fixtures/malformed").join(name)
}

fn cornell() -> PathBuf {
    shared_assets().join("CornellBox/CornellBox.glb")
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("raykin-cli-args-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Runs `raykin ARGS` from the repository root, as a newcomer would: no XDG_RUNTIME_DIR, no RUST_LOG.
fn raykin(args: &[&dyn AsRef<std::ffi::OsStr>]) -> Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_raykin"))
        .args(args.iter().map(|a| a.as_ref()))
        .current_dir(repo_root())
        .env_remove("XDG_RUNTIME_DIR")
        .env_remove("RUST_LOG")
        .output()
        .unwrap()
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// Failed with exit status 1 or 2 (never a panic's 101) and a message containing every word.
fn refused(out: &Output, words: &[&str]) -> String {
    let text = stderr(out);
    assert!(
        matches!(out.status.code(), Some(1 | 2)),
        "status {:?}: {text}",
        out.status
    );
    assert!(!text.contains("panicked"), "{text}");
    for w in words {
        assert!(text.contains(w), "no `{w}` in: {text}");
    }
    text
}

#[test]
fn arguments_that_cannot_render_are_refused_before_any_work() {
    let scene = cornell();
    let out = scratch("never.png");
    let cases: &[(&[&str], &str)] = &[
        (&["--width", "0"], "--width"),
        (&["--height", "0"], "--height"),
        (&["--spp", "0"], "--spp"),
        (&["--spp-per-dispatch", "0"], "--spp-per-dispatch"),
        (&["--exposure", "NaN"], "not a finite number"),
        (&["--exposure", "inf"], "not a finite number"),
        (&["--fov", "NaN"], "not a finite number"),
        (&["--fov", "0"], "between 0 and 180"),
        (&["--fov", "180"], "between 0 and 180"),
        (&["--fov", "-10"], "between 0 and 180"),
        (&["--env=-1,-1,-1"], "cannot be negative"),
        (&["--env", "-1,0,0"], "cannot be negative"),
        (&["--env", "1,nan,0"], "three finite numbers"),
        (&["--time", "inf"], "not a finite number"),
    ];
    for (extra, words) in cases {
        let mut args: Vec<&dyn AsRef<std::ffi::OsStr>> = vec![&"render", &scene, &"--out", &out];
        args.extend(extra.iter().map(|a| a as &dyn AsRef<std::ffi::OsStr>));
        let result = raykin(&args);
        let text = refused(&result, &[words]);
        assert!(
            !text.contains("adapter:"),
            "{extra:?}: the GPU was opened: {text}"
        );
    }
    assert!(!out.exists());
}

/// `--time -5` used to fail with "unexpected argument '-5'" unless written `--time=-5`.
#[test]
fn negative_numbers_need_no_equals_sign() {
    // The Cornell box has no animations: the run stops at that, after the arguments parsed.
    let out = raykin(&[
        &"render",
        &cornell(),
        &"--out",
        &scratch("never.png"),
        &"--time",
        &"-5",
        &"--exposure",
        &"-1.5",
        &"--look-from",
        &"-1,2,-3",
        &"--look-at",
        &"-0.5,0,0",
    ]);
    let text = refused(&out, &["has no animations"]);
    assert!(!text.contains("unexpected argument"), "{text}");
}

#[test]
fn a_missing_camera_names_the_file_and_its_cameras() {
    let out = raykin(&[
        &"render",
        &malformed("camera_type_mismatch.gltf"),
        &"--out",
        &scratch("never.png"),
        &"--camera",
        &"99",
    ]);
    refused(
        &out,
        &[
            "camera_type_mismatch.gltf",
            "camera 99 does not exist",
            "1 camera(s): 0 (node 1",
        ],
    );
}

#[test]
fn an_unknown_variant_names_the_file_and_its_variants() {
    let variants = repo_root().join("assets/conformance/Authored/MaterialVariants.gltf");
    let out = raykin(&[
        &"render",
        &variants,
        &"--out",
        &scratch("never-variant.png"),
        &"--variant",
        &"green",
    ]);
    refused(
        &out,
        &[
            "MaterialVariants.gltf",
            "no material variant is called `green`",
            "`red`, `blue`",
        ],
    );
}

#[test]
fn an_image_over_the_adapters_limits_is_a_clear_error() {
    let out = raykin(&[
        &"render",
        &cornell(),
        &"--out",
        &scratch("huge.png"),
        &"--width",
        &"100000",
        &"--height",
        &"100000",
        &"--spp",
        &"1",
    ]);
    refused(&out, &["image size 100000x100000", "at most"]);
}

/// An image the megakernel can trace but whose wavefront path state would not fit one binding (lavapipe's 128 MiB
/// hold 2.8 M paths of the shadow rays' 48 bytes; 2048x1536 is 3.1 M) is traced by the megakernel, with one line
/// saying so (it was a panic: wgpu's validation error on the bind group).
#[test]
fn an_image_too_large_for_the_waves_is_traced_by_the_megakernel() {
    let out = scratch("waves-too-large.png");
    let result = raykin(&[
        &"render",
        &cornell(),
        &"--width",
        &"2048",
        &"--height",
        &"1536",
        &"--spp",
        &"1",
        &"--integrator",
        &"wavefront",
        &"--out",
        &out,
    ]);
    let text = stderr(&result);
    assert!(result.status.success(), "{text}");
    assert!(out.exists(), "the image is written");
    let warnings: Vec<&str> = text
        .lines()
        .filter(|l| l.contains("too large for the wavefront"))
        .collect();
    assert_eq!(warnings.len(), 1, "{text}");
    assert!(
        warnings[0].contains("2048x1536") && warnings[0].contains("megakernel"),
        "{text}"
    );
}

/// A top-level tree obvhs builds deeper than the traversal stack (80 nested instances) is rebuilt balanced
/// and renders (it was refused; before that, instances vanished without a word).
#[test]
fn a_top_level_tree_deeper_than_the_stack_renders() {
    let out = scratch("deep.exr");
    let result = raykin(&[
        &"render",
        &malformed("tlas_deeper_than_64.gltf"),
        &"--width",
        &"32",
        &"--height",
        &"32",
        &"--spp",
        &"1",
        &"--out",
        &out,
    ]);
    assert!(result.status.success(), "{}", stderr(&result));
    assert!(out.exists(), "the image is written");
}

/// A copy of a small scene (.gltf + .bin) in its own folder, named `name`.
fn scene_copy(folder: &str, name: &str) -> PathBuf {
    let dir = scratch(folder);
    std::fs::create_dir_all(&dir).unwrap();
    let source = shared_assets().join("Box/glTF");
    std::fs::copy(source.join("Box0.bin"), dir.join("Box0.bin")).unwrap();
    let scene = dir.join(name);
    std::fs::copy(source.join("Box.gltf"), &scene).unwrap();
    scene
}

fn unchanged(file: &Path, before: &[u8]) {
    assert_eq!(
        std::fs::read(file).unwrap(),
        before,
        "{} was modified",
        file.display()
    );
}

#[test]
fn outputs_never_overwrite_the_scenes_files() {
    // --report at the scene used to overwrite it with JSON (exit 0).
    let scene = scene_copy("report", "Box.gltf");
    let before = std::fs::read(&scene).unwrap();
    let out = raykin(&[
        &"render",
        &scene,
        &"--out",
        &scratch("r.png"),
        &"--report",
        &scene,
    ]);
    refused(
        &out,
        &["--report", "refusing to overwrite", "nothing was rendered"],
    );
    unchanged(&scene, &before);
    // A scene named *.png rendered with --out at its own path.
    let scene = scene_copy("png", "scene.png");
    let before = std::fs::read(&scene).unwrap();
    let out = raykin(&[&"render", &scene, &"--out", &scene]);
    refused(&out, &["--out", "refusing to overwrite"]);
    unchanged(&scene, &before);
    // An AOV file at the scene's buffer.
    let scene = scene_copy("aov", "Box.gltf");
    let bin = scene.with_file_name("Box0.bin");
    let before = std::fs::read(&bin).unwrap();
    std::fs::rename(&bin, scene.with_file_name("Box0.albedo.exr")).unwrap();
    let text = std::fs::read_to_string(&scene)
        .unwrap()
        .replace("Box0.bin", "Box0.albedo.exr");
    std::fs::write(&scene, text).unwrap();
    let out = raykin(&[
        &"render",
        &scene,
        &"--out",
        &scene.with_file_name("Box0.exr"),
        &"--aovs",
    ]);
    refused(
        &out,
        &["--aovs output", "Box0.albedo.exr", "refusing to overwrite"],
    );
    unchanged(&scene.with_file_name("Box0.albedo.exr"), &before);
    // A recording folder holding the scene under a frame name.
    let scene = scene_copy("record", "frame_00000.png");
    let before = std::fs::read(&scene).unwrap();
    let out = raykin(&[
        &"record",
        &scene,
        &"--out",
        &scene.parent().unwrap(),
        &"--frames",
        &"1",
        &"--format",
        &"png",
    ]);
    refused(&out, &["would overwrite the scene's input file"]);
    unchanged(&scene, &before);
}

#[test]
fn an_unwritable_output_is_named_before_rendering() {
    // A "folder" that is a regular file: nothing can be created below it.
    let blocker = scratch("blocker");
    std::fs::write(&blocker, b"x").unwrap();
    let target = blocker.join("out.png");
    let out = raykin(&[&"render", &cornell(), &"--out", &target]);
    let text = refused(&out, &["--out", "out.png"]);
    assert!(
        !text.contains(".partial") && !text.contains("adapter:"),
        "{text}"
    );
}

/// Each warning once, as one line, without ANSI colour codes; no Mesa "XDG_RUNTIME_DIR" line.
#[test]
fn warnings_are_one_line_each_without_colour_or_mesa_noise() {
    let out = scratch("warned.png");
    let result = raykin(&[
        &"render",
        &malformed("negative_base_color.gltf"),
        &"--out",
        &out,
        &"--width",
        &"8",
        &"--height",
        &"8",
        &"--spp",
        &"1",
    ]);
    let text = stderr(&result);
    assert!(result.status.success(), "{text}");
    let warning_lines = text
        .lines()
        .filter(|l| l.contains("baseColorFactor"))
        .count();
    assert_eq!(warning_lines, 1, "{text}");
    assert!(
        text.lines()
            .any(|l| l.starts_with("raykin: warning: ") && l.contains("baseColorFactor"))
    );
    assert!(!text.contains('\u{1b}'), "ANSI codes in: {text:?}");
    assert!(!text.contains("XDG_RUNTIME_DIR"), "{text}");
}
