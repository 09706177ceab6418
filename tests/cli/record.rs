//! `raykin record` end to end (the binary, on lavapipe): a 10-frame RiggedSimple recording at 32x32 whose
//! frames change with the pose, frame 7 re-rendered alone bit-identically, Ctrl-C then resume with no
//! truncated or duplicated frame, two `--range` halves + `--merge` equal to one run, motion vectors against
//! analytic values, and every bad input of issue 5 (unwritable folder, full disk, no animations, range outside
//! the clip, another recording in the folder, missing ffmpeg).

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::sync::{Mutex, MutexGuard, OnceLock};

/// The recording every test compares against: 10 frames of RiggedSimple's bend (one way, 0.05 to 0.95 s) at
/// 10 fps, 32x32, framed on the bending upper half.
const RECORDING: &[&str] = &[
    "--frames",
    "10",
    "--fps",
    "10",
    "--start",
    "0.05",
    "--width",
    "32",
    "--height",
    "32",
    "--spp",
    "8",
    "--look-from",
    "0,2.5,8",
    "--look-at",
    "0,2.5,0",
    "--fov",
    "40",
];

fn rigged_simple() -> PathBuf {
    crate::common::shared_assets().join("RiggedSimple/glTF/RiggedSimple.gltf")
}

/// The processes share 2 cores with lavapipe: one test at a time.
fn serial() -> MutexGuard<'static, ()> {
    static LOCK: Mutex<()> = Mutex::new(());
    LOCK.lock().unwrap_or_else(|p| p.into_inner())
}

fn raykin() -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_raykin"));
    c.env("XDG_RUNTIME_DIR", crate::common::xdg_runtime_dir());
    c
}

/// A fresh, empty folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir()
        .join(format!("raykin-record-tests-{}", std::process::id()))
        .join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.parent().unwrap()).unwrap();
    dir
}

fn record(scene: &Path, out: &Path, extra: &[&str]) -> Output {
    raykin()
        .arg("record")
        .arg(scene)
        .arg("--out")
        .arg(out)
        .args(extra)
        .output()
        .expect("raykin runs")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn assert_ok(o: &Output) {
    assert!(o.status.success(), "raykin failed: {}", stderr(o));
}

/// Frame files in `dir` by name, with their bytes.
fn frames(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .filter(|e| e.file_name().to_string_lossy().starts_with("frame_"))
        .map(|e| {
            (
                e.file_name().to_string_lossy().into_owned(),
                std::fs::read(e.path()).unwrap(),
            )
        })
        .collect()
}

fn expected_names(n: u32, ext: &str) -> Vec<String> {
    (0..n).map(|k| format!("frame_{k:05}.{ext}")).collect()
}

/// No temporary file of an interrupted write anywhere in `dir`.
fn assert_no_partials(dir: &Path) {
    let partials: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .filter(|n| n.ends_with(".partial"))
        .collect();
    assert!(
        partials.is_empty(),
        "leftover temporary files: {partials:?}"
    );
}

fn manifest(path: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap()
}

/// Every frame the manifest lists is on disk with its recorded size and SHA-256 and decodes as an image.
fn assert_manifest_matches_disk(dir: &Path, manifest_file: &str) -> usize {
    use sha2::Digest;
    let m = manifest(&dir.join(manifest_file));
    let listed = m["frames"].as_array().unwrap();
    for f in listed {
        for file in f["files"].as_array().unwrap() {
            let bytes = std::fs::read(dir.join(file["name"].as_str().unwrap())).unwrap();
            assert_eq!(bytes.len() as u64, file["bytes"].as_u64().unwrap());
            let hash: String = sha2::Sha256::digest(&bytes)
                .iter()
                .map(|b| format!("{b:02x}"))
                .collect();
            assert_eq!(hash, file["sha256"].as_str().unwrap());
            image::load_from_memory(&bytes).expect("a complete image");
        }
    }
    listed.len()
}

fn rgba(png: &[u8]) -> Vec<u8> {
    image::load_from_memory(png).unwrap().to_rgba8().into_raw()
}

fn mean_abs_diff(a: &[u8], b: &[u8]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x as f64 - *y as f64).abs())
        .sum::<f64>()
        / a.len() as f64
}

/// The reference recording, made once per test binary.
fn reference() -> &'static Path {
    static DIR: OnceLock<PathBuf> = OnceLock::new();
    DIR.get_or_init(|| {
        let dir = scratch("reference");
        let o = record(&rigged_simple(), &dir, RECORDING);
        assert_ok(&o);
        dir
    })
}

#[test]
fn ten_frames_follow_the_pose_and_frame_7_rerenders_identically() {
    let _serial = serial();
    let full = reference();
    let files = frames(full);
    assert_eq!(
        files.keys().cloned().collect::<Vec<_>>(),
        expected_names(10, "png")
    );
    assert_eq!(assert_manifest_matches_disk(full, "manifest.json"), 10);
    let m = manifest(&full.join("manifest.json"));
    let times: Vec<f64> = m["frames"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f["time"].as_f64().unwrap())
        .collect();
    for (k, t) in times.iter().enumerate() {
        assert!(
            (t - (0.05 + k as f64 / 10.0)).abs() < 1e-5,
            "frame {k} at {t} s"
        );
    }

    // Noise floor: frame 0 with another seed (same pose).
    let other_seed = scratch("other-seed");
    let o = record(
        &rigged_simple(),
        &other_seed,
        &[RECORDING, &["--range", "0..1", "--seed", "1"]].concat(),
    );
    assert_ok(&o);
    // Pose changes move the silhouette: pixels flip between the figure and the sky (differences of more
    // than 80 of 255), which sampling noise alone never does.
    let seed_1 = rgba(&frames(&other_seed)["frame_00000.png"]);
    let images: Vec<Vec<u8>> = files.values().map(|png| rgba(png)).collect();
    let flipped = |a: &[u8], b: &[u8]| {
        a.iter()
            .zip(b)
            .filter(|(x, y)| (**x as i32 - **y as i32).abs() > 80)
            .count()
    };
    let noise = mean_abs_diff(&images[0], &seed_1);
    let noise_flips = flipped(&images[0], &seed_1);
    assert!(
        noise_flips <= 3,
        "{noise_flips} values flipped by noise alone"
    );
    for k in 0..9 {
        let change = mean_abs_diff(&images[k], &images[k + 1]);
        let flips = flipped(&images[k], &images[k + 1]);
        assert!(
            change > 1.5 * noise && flips >= 8,
            "frames {k} and {}: mean change {change:.3} (seed noise {noise:.3}), {flips} flipped values",
            k + 1
        );
    }

    // Frame 7 alone, in a new folder: the same file.
    let alone = scratch("frame-7");
    let o = record(
        &rigged_simple(),
        &alone,
        &[RECORDING, &["--range", "7..8"]].concat(),
    );
    assert_ok(&o);
    let single = frames(&alone);
    assert_eq!(single.len(), 1);
    assert!(
        single["frame_00007.png"] == files["frame_00007.png"],
        "frame 7 rendered alone differs from frame 7 of the full run"
    );
    assert!(alone.join("manifest.part-00007-00008.json").is_file());
}

#[cfg(unix)]
#[test]
fn interrupted_recording_resumes_without_truncated_or_duplicated_frames() {
    let _serial = serial();
    let full = reference();
    let dir = scratch("interrupted");
    let mut child = raykin()
        .arg("record")
        .arg(rigged_simple())
        .arg("--out")
        .arg(&dir)
        .args(RECORDING)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut lines = BufReader::new(child.stderr.take().unwrap()).lines();
    let mut done = 0;
    let mut log = String::new();
    for line in lines.by_ref() {
        let line = line.unwrap();
        log += &line;
        log += "\n";
        if line.contains(" done (") {
            done += 1;
            if done == 3 {
                // SAFETY: kill(2) on the child's pid; the child is alive until waited on below.
                let sent = unsafe { libc::kill(child.id() as libc::pid_t, libc::SIGINT) };
                assert_eq!(sent, 0, "SIGINT delivered");
                break;
            }
        }
    }
    for line in lines {
        log += &line.unwrap();
        log += "\n";
    }
    let status = child.wait().unwrap();
    assert_eq!(
        status.code(),
        Some(130),
        "exit status after SIGINT; log:\n{log}"
    );
    assert!(log.contains("interrupted:"), "{log}");
    let partial = frames(&dir);
    assert!(
        (3..10).contains(&partial.len()),
        "{} frames after the interrupt; log:\n{log}",
        partial.len()
    );
    assert_no_partials(&dir);
    // Every frame on disk is whole and listed; and equal to the uninterrupted run's.
    assert_eq!(
        assert_manifest_matches_disk(&dir, "manifest.json"),
        partial.len()
    );
    let reference_frames = frames(full);
    for (name, bytes) in &partial {
        assert!(reference_frames[name] == *bytes, "{name} differs");
    }

    let o = record(&rigged_simple(), &dir, RECORDING);
    assert_ok(&o);
    assert!(stderr(&o).contains("resuming"), "{}", stderr(&o));
    let resumed = frames(&dir);
    assert_eq!(
        resumed.keys().cloned().collect::<Vec<_>>(),
        expected_names(10, "png"),
        "each frame exactly once"
    );
    assert_eq!(resumed, reference_frames, "resumed set equals one full run");
    assert_eq!(assert_manifest_matches_disk(&dir, "manifest.json"), 10);
    assert_no_partials(&dir);

    // A frame deleted afterwards is the only one rendered again, identically.
    std::fs::remove_file(dir.join("frame_00004.png")).unwrap();
    let o = record(&rigged_simple(), &dir, RECORDING);
    assert_ok(&o);
    assert!(stderr(&o).contains("rendered 1 frame(s)"), "{}", stderr(&o));
    assert_eq!(frames(&dir), reference_frames);
}

#[test]
fn two_range_halves_merged_equal_one_full_run() {
    let _serial = serial();
    let full = reference();
    let dir = scratch("halves");
    // Both halves at once into one folder, as a Slurm array would.
    let spawn = |range: &str| {
        raykin()
            .arg("record")
            .arg(rigged_simple())
            .arg("--out")
            .arg(&dir)
            .args(RECORDING)
            .args(["--range", range])
            .stderr(Stdio::piped())
            .spawn()
            .unwrap()
    };
    let (a, b) = (spawn("0..5"), spawn("5..10"));
    for child in [a, b] {
        let o = child.wait_with_output().unwrap();
        assert_ok(&o);
    }
    assert_eq!(
        assert_manifest_matches_disk(&dir, "manifest.part-00000-00005.json"),
        5
    );
    assert_eq!(
        assert_manifest_matches_disk(&dir, "manifest.part-00005-00010.json"),
        5
    );
    let o = raykin()
        .args(["record", "--merge"])
        .arg(&dir)
        .output()
        .unwrap();
    assert_ok(&o);
    assert!(
        stderr(&o).contains("10 of 10 frames complete"),
        "{}",
        stderr(&o)
    );
    assert!(!dir.join("manifest.part-00000-00005.json").exists());
    assert_eq!(assert_manifest_matches_disk(&dir, "manifest.json"), 10);
    assert_eq!(frames(&dir), frames(full));
    let (merged, single) = (
        manifest(&dir.join("manifest.json")),
        manifest(&full.join("manifest.json")),
    );
    assert_eq!(merged["settings"], single["settings"]);
    assert_eq!(merged["scene_hash"], single["scene_hash"]);
    let hashes = |m: &serde_json::Value| -> Vec<serde_json::Value> {
        m["frames"]
            .as_array()
            .unwrap()
            .iter()
            .map(|f| f["files"].clone())
            .collect()
    };
    assert_eq!(hashes(&merged), hashes(&single));

    // A merge with a frame missing says which one, and fails.
    std::fs::remove_file(dir.join("frame_00006.png")).unwrap();
    let o = raykin()
        .args(["record", "--merge"])
        .arg(&dir)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("1 frame(s) missing (6)"),
        "{}",
        stderr(&o)
    );
}

/// A quad crossing the view at 1 unit/s (clip "slide") and a camera panning at 0.5 rad/s about +Y (clip
/// "pan"), as an embedded glTF.
fn motion_scene(dir: &Path) -> PathBuf {
    use base64::Engine as _;
    let mut bin: Vec<u8> = Vec::new();
    let f = |bin: &mut Vec<u8>, v: &[f32]| v.iter().for_each(|x| bin.extend(x.to_le_bytes()));
    f(
        &mut bin,
        &[
            -1.0, -1.0, 0.0, 1.0, -1.0, 0.0, 1.0, 1.0, 0.0, -1.0, 1.0, 0.0,
        ],
    ); // 0..48 positions
    [0u16, 1, 2, 0, 2, 3]
        .iter()
        .for_each(|i| bin.extend(i.to_le_bytes())); // 48..60 indices
    f(&mut bin, &[0.0, 1.0]); // 60..68 times
    f(&mut bin, &[-0.5, 0.0, 0.0, 0.5, 0.0, 0.0]); // 68..92 quad translations
    let half = |a: f32| (a * 0.5).sin();
    let quat = |a: f32| [0.0, half(a), 0.0, (a * 0.5).cos()];
    f(&mut bin, &[quat(0.0), quat(0.5)].concat()); // 92..124 camera rotations
    let uri = format!(
        "data:application/octet-stream;base64,{}",
        base64::engine::general_purpose::STANDARD.encode(&bin)
    );
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0,1]}}],
"nodes":[{{"mesh":0}},{{"camera":0,"translation":[0,0,5]}}],
"cameras":[{{"type":"perspective","perspective":{{"yfov":0.7853982,"znear":0.1,"aspectRatio":1.0}}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"animations":[
 {{"name":"slide","channels":[{{"sampler":0,"target":{{"node":0,"path":"translation"}}}}],"samplers":[{{"input":2,"output":3}}]}},
 {{"name":"pan","channels":[{{"sampler":0,"target":{{"node":1,"path":"rotation"}}}}],"samplers":[{{"input":2,"output":4}}]}}],
"buffers":[{{"byteLength":{len},"uri":"{uri}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":12}},
{{"buffer":0,"byteOffset":60,"byteLength":8}},{{"buffer":0,"byteOffset":68,"byteLength":24}},{{"buffer":0,"byteOffset":92,"byteLength":32}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[-1,-1,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5123,"count":6,"type":"SCALAR"}},
{{"bufferView":2,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[1]}},
{{"bufferView":3,"componentType":5126,"count":2,"type":"VEC3"}},
{{"bufferView":4,"componentType":5126,"count":2,"type":"VEC4"}}]}}"#,
        len = bin.len()
    );
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("motion.gltf");
    std::fs::write(&path, json).unwrap();
    path
}

fn read_motion(path: &Path) -> Vec<[f32; 3]> {
    raykin::image_io::read_exr(path).expect("motion EXR").2
}

#[test]
fn motion_vectors_match_analytic_motion() {
    let _serial = serial();
    let base = scratch("motion");
    let scene = motion_scene(&base);
    let (w, fps) = (32.0f32, 10.0f32);
    let tan = (std::f32::consts::FRAC_PI_4 * 0.5).tan();

    // Frame 4 of clip `clip` at 10 fps, 32x32, 1 spp.
    let frame_4 = |clip: &str, out: &Path, extra: &[&str]| {
        let common = [
            "--animation",
            clip,
            "--fps",
            "10",
            "--frames",
            "10",
            "--range",
            "4..5",
            "--width",
            "32",
            "--height",
            "32",
            "--spp",
            "1",
        ];
        record(&scene, out, &[&common[..], extra].concat())
    };
    // The quad slides +0.1 per frame at depth 5 under a still camera: every quad pixel moved
    // -0.1 / (5 tan(fov/2)) * w/2 pixels since the previous frame; the background did not move.
    let out = base.join("slide");
    let o = frame_4("slide", &out, &["--aovs", "motion,depth"]);
    assert_ok(&o);
    let motion = read_motion(&out.join("frame_00004.motion.exr"));
    let expected_dx = -(1.0 / fps) / (5.0 * tan) * (w / 2.0);
    let (mut surface, mut background) = (0, 0);
    for (i, m) in motion.iter().enumerate() {
        match m[2] {
            1.0 => {
                surface += 1;
                assert!(
                    (m[0] - expected_dx).abs() < 1e-3 && m[1].abs() < 1e-3,
                    "pixel {i}: motion {m:?}, expected ({expected_dx}, 0)"
                );
            }
            0.0 => {
                background += 1;
                assert_eq!(
                    [m[0], m[1]],
                    [0.0, 0.0],
                    "pixel {i}: still background moved"
                );
            }
            s => panic!("pixel {i}: status {s}"),
        }
    }
    // The 2x2 quad at depth 5 covers (2 / (2 * 5 tan(22.5 deg)))^2 = 23% of the view.
    assert!(
        (200..300).contains(&surface) && background > 600,
        "{surface} surface, {background} background pixels"
    );

    // The camera pans 0.05 rad per frame about +Y: a pixel's direction at infinity was, one frame earlier, at
    // the screen position of the same world direction seen by the camera rotated back.
    let out = base.join("pan");
    let o = frame_4(
        "pan",
        &out,
        &["--camera", "0", "--aovs", "motion", "--format", "exr"],
    );
    assert_ok(&o);
    let (_, _, radiance) = raykin::image_io::read_exr(&out.join("frame_00004.exr")).unwrap();
    assert!(
        radiance
            .iter()
            .flatten()
            .all(|v| v.is_finite() && *v >= 0.0)
            && radiance.len() == 1024,
        "linear EXR frame"
    );
    let motion = read_motion(&out.join("frame_00004.motion.exr"));
    let angle_now = 0.5 * 0.4f32;
    let angle_before = 0.5 * 0.3f32;
    let project = |camera_angle: f32, d: glam::Vec3| -> glam::Vec2 {
        let q = glam::Quat::from_rotation_y(-camera_angle) * d;
        glam::Vec2::new(
            (q.x / (-q.z * tan) + 1.0) * 0.5 * w,
            (1.0 - q.y / (-q.z * tan)) * 0.5 * w,
        )
    };
    // The camera turns about its own position, so a still surface point moves on screen exactly like its
    // direction: one formula for the quad's pixels (status 1) and the environment's (status 0).
    let mut statuses = [0; 2];
    for (i, m) in motion.iter().enumerate() {
        let (x, y) = ((i % 32) as f32 + 0.5, (i / 32) as f32 + 0.5);
        let ndc = glam::Vec2::new(x / w * 2.0 - 1.0, 1.0 - y / w * 2.0);
        let d = glam::Quat::from_rotation_y(angle_now)
            * glam::Vec3::new(ndc.x * tan, ndc.y * tan, -1.0).normalize();
        let expected = project(angle_before, d) - glam::Vec2::new(x, y);
        assert!(m[2] == 0.0 || m[2] == 1.0, "pixel {i}: status {}", m[2]);
        statuses[m[2] as usize] += 1;
        assert!(
            (m[0] - expected.x).abs() < 2e-3 && (m[1] - expected.y).abs() < 2e-3,
            "pixel {i}: motion {m:?}, expected {expected}"
        );
    }
    assert!(
        statuses[0] > 500 && statuses[1] > 100,
        "{statuses:?} environment/surface pixels"
    );
    assert!(base.join("slide/frame_00004.depth.exr").is_file());
}

#[test]
fn bad_input_gives_clear_errors_and_loses_nothing() {
    let _serial = serial();
    let base = scratch("bad");
    std::fs::create_dir_all(&base).unwrap();

    // An output "folder" under a regular file.
    let file = base.join("a-file");
    std::fs::write(&file, b"x").unwrap();
    let o = record(&rigged_simple(), &file.join("out"), RECORDING);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("cannot create it") && stderr(&o).contains("a-file"),
        "{}",
        stderr(&o)
    );

    // --range outside the recording: refused before anything is written.
    let out = base.join("range");
    let o = record(
        &rigged_simple(),
        &out,
        &[RECORDING, &["--range", "8..12"]].concat(),
    );
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("--range 8..12 is outside the recording: it has 10 frames (0..10)"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
    // Frames past the clip's end (2.083 s).
    let o = record(
        &rigged_simple(),
        &out,
        &[
            "--frames", "100", "--fps", "10", "--width", "8", "--height", "8",
        ],
    );
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("past the end of clip 0"),
        "{}",
        stderr(&o)
    );

    // A scene without animations: an error naming the way out, then a still recording when asked.
    let cornell = crate::common::shared_assets().join("CornellBox/CornellBox.glb");
    let o = record(
        &cornell,
        &out,
        &["--width", "16", "--height", "16", "--spp", "1"],
    );
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("has no animations") && stderr(&o).contains("--frames N"),
        "{}",
        stderr(&o)
    );
    let still = base.join("still");
    let o = record(
        &cornell,
        &still,
        &[
            "--frames",
            "2",
            "--width",
            "16",
            "--height",
            "16",
            "--time-budget-ms",
            "50",
        ],
    );
    assert_ok(&o);
    assert_eq!(frames(&still).len(), 2);
    let m = manifest(&still.join("manifest.json"));
    assert_eq!(m["settings"]["clip"], serde_json::Value::Null);
    for f in m["frames"].as_array().unwrap() {
        assert!(
            f["spp"].as_u64().unwrap() >= 1,
            "time budget: spp reached per frame"
        );
    }

    // A folder holding another recording (other settings): refused, with the difference and --force named;
    // nothing in it changes.
    let before = frames(&still);
    let o = record(
        &cornell,
        &still,
        &[
            "--frames", "2", "--width", "16", "--height", "16", "--spp", "2",
        ],
    );
    assert!(!o.status.success());
    let e = stderr(&o);
    assert!(
        e.contains("another scene or with other settings")
            && e.contains("settings.sampling")
            && e.contains("--force"),
        "{e}"
    );
    assert_eq!(frames(&still), before);
    // --force starts over; the old manifest is kept aside.
    let o = record(
        &cornell,
        &still,
        &[
            "--frames", "2", "--width", "16", "--height", "16", "--spp", "2", "--range", "0..1",
            "--force",
        ],
    );
    assert_ok(&o);
    let names: Vec<String> = std::fs::read_dir(&still)
        .unwrap()
        .flatten()
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(
        names
            .iter()
            .any(|n| n.starts_with("manifest.json.replaced-")),
        "{names:?}"
    );

    // Frame files without a manifest are not overwritten.
    let foreign = base.join("foreign");
    std::fs::create_dir_all(&foreign).unwrap();
    std::fs::write(foreign.join("frame_00000.png"), b"someone else's").unwrap();
    let o = record(&rigged_simple(), &foreign, RECORDING);
    assert!(!o.status.success());
    assert!(stderr(&o).contains("no raykin manifest"), "{}", stderr(&o));
    assert_eq!(
        std::fs::read(foreign.join("frame_00000.png")).unwrap(),
        b"someone else's"
    );

    // A damaged manifest is named, not replaced.
    let damaged = base.join("damaged");
    std::fs::create_dir_all(&damaged).unwrap();
    std::fs::write(damaged.join("manifest.json"), b"{ not json").unwrap();
    let o = record(&rigged_simple(), &damaged, RECORDING);
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("manifest.json: not a raykin manifest"),
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read(damaged.join("manifest.json")).unwrap(),
        b"{ not json"
    );

    // --video without ffmpeg on PATH: said before any rendering.
    let out = base.join("video");
    let o = raykin()
        .env("PATH", base.join("no-such-bin"))
        .arg("record")
        .arg(rigged_simple())
        .arg("--out")
        .arg(&out)
        .args(RECORDING)
        .args(["--video"])
        .arg(base.join("out.mp4"))
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(
        stderr(&o).contains("ffmpeg is not on PATH"),
        "{}",
        stderr(&o)
    );
    assert!(!out.exists());
}

/// Runs `script` with `$RAYKIN` and `$MNT` (an empty folder) in a private mount namespace where it may
/// mount a tmpfs; `None` where this machine allows no such namespace.
fn in_mount_namespace(script: &str, mnt: &Path) -> Option<Output> {
    std::fs::create_dir_all(mnt).unwrap();
    let probe = Command::new("unshare")
        .args([
            "-rm",
            "sh",
            "-c",
            "mount -t tmpfs -o size=64k tmpfs \"$0\"",
            &mnt.to_string_lossy(),
        ])
        .output()
        .ok()?;
    if !probe.status.success() {
        return None;
    }
    let xdg = crate::common::xdg_runtime_dir();
    Command::new("unshare")
        .args(["-rm", "sh", "-c", script])
        .env("RAYKIN", env!("CARGO_BIN_EXE_raykin"))
        .env("MNT", mnt)
        .env("SCENE", rigged_simple())
        .env("XDG_RUNTIME_DIR", xdg)
        .output()
        .ok()
}

#[cfg(unix)]
#[test]
fn full_disk_and_read_only_folder_keep_finished_frames() {
    let _serial = serial();
    let mnt = scratch("tmpfs");
    let args = RECORDING.join(" ");
    let kept = scratch("tmpfs-result");
    // 32 KiB (8 tmpfs pages) fills after a few 32x32 frames (one page each) beside the manifest and its
    // temporary copy; then the disk grows and the same command finishes the set, which is copied out.
    let script = format!(
        r#"set -u
mount -t tmpfs -o size=32k tmpfs "$MNT" || exit 90
"$RAYKIN" record "$SCENE" --out "$MNT/rec" {args} 2>&1; echo "first-exit=$?"
ls -a "$MNT/rec"; echo "listing-done"
mount -o remount,size=4m "$MNT"
"$RAYKIN" record "$SCENE" --out "$MNT/rec" {args} 2>&1; echo "second-exit=$?"
cp -r "$MNT/rec" "{kept}"
mkdir -p "$MNT/ro" && mount -t tmpfs -o ro tmpfs "$MNT/ro"
"$RAYKIN" record "$SCENE" --out "$MNT/ro" {args} 2>&1; echo "ro-exit=$?"
"#,
        kept = kept.display()
    );
    let Some(o) = in_mount_namespace(&script, &mnt) else {
        eprintln!(
            "no private mount namespace (unshare -rm): a file-size limit makes the writes fail instead"
        );
        write_failure_under_file_size_limit();
        return;
    };
    let log = String::from_utf8_lossy(&o.stdout).into_owned() + &stderr(&o);
    assert!(
        log.contains("first-exit=1"),
        "the full disk must fail the run:\n{log}"
    );
    assert!(
        log.contains("No space left on device") && log.contains("/rec/"),
        "the error names the file and the cause:\n{log}"
    );
    assert!(
        log.contains("frames of the recording are complete and listed in"),
        "{log}"
    );
    let first_listing = log.split("listing-done").next().unwrap();
    assert!(
        !first_listing.contains(".partial"),
        "a temporary file survived the failed write:\n{log}"
    );
    assert!(
        log.contains("second-exit=0"),
        "the resumed run finishes:\n{log}"
    );
    assert!(
        log.contains("resuming:"),
        "finished frames were kept:\n{log}"
    );
    assert!(
        log.contains("ro-exit=1") && log.contains("it is not writable: Read-only file system"),
        "{log}"
    );
    // Nothing written before the failure was lost or damaged: the set equals one uninterrupted run.
    assert_eq!(frames(&kept), frames(reference()));
    assert_eq!(assert_manifest_matches_disk(&kept, "manifest.json"), 10);
}

/// The same guarantees without a tmpfs: `ulimit -f` (SIGXFSZ ignored) makes writes past 4 KiB fail with
/// "File too large" once the manifest outgrows it; finished frames stay whole, a re-run completes the set.
#[cfg(unix)]
fn write_failure_under_file_size_limit() {
    let dir = scratch("file-size-limit");
    let o = Command::new("sh")
        .args([
            "-c",
            r#"ulimit -f 8; trap '' XFSZ; exec "$RAYKIN" record "$SCENE" --out "$OUT" "$@""#,
            "sh",
        ])
        .args(RECORDING)
        .env("RAYKIN", env!("CARGO_BIN_EXE_raykin"))
        .env("SCENE", rigged_simple())
        .env("OUT", &dir)
        .env("XDG_RUNTIME_DIR", crate::common::xdg_runtime_dir())
        .output()
        .unwrap();
    let log = stderr(&o);
    assert!(
        !o.status.success(),
        "the size limit must fail the run:\n{log}"
    );
    assert!(
        log.contains("File too large") && log.contains("frames of the recording are complete"),
        "{log}"
    );
    assert_no_partials(&dir);
    let kept = assert_manifest_matches_disk(&dir, "manifest.json");
    assert!((1..10).contains(&kept), "{kept} frames before the failure");
    let o = record(&rigged_simple(), &dir, RECORDING);
    assert_ok(&o);
    assert_eq!(frames(&dir), frames(reference()));
}
