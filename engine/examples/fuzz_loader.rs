//! A mutation fuzzer for the glTF loader and the CPU side of the engine, on the stable toolchain and without
//! a GPU: each case mutates a seed file (structure-aware edits of the glTF JSON, byte edits of GLB chunks),
//! loads it, checks what the loader promises (no panic, every index in range, finite geometry and
//! materials), then builds every BVH and poses every animation on the CPU. docs/RELIABILITY.md says how to
//! run it and what it has found.
//!
//! ```sh
//! cargo build --workspace --examples
//! nice -n 19 target/debug/examples/fuzz_loader --seeds ../shared/assets --seeds tests/fixtures/malformed \
//!     --out fuzz-out --seconds 3600 --seed 1
//! target/debug/examples/fuzz_loader --replay fuzz-out/findings/panic-1234.gltf   # re-run one file
//! ```
//! A case is reproducible from its seed file and case number (`--case FILE:N`, printed with each finding);
//! `--case` also writes the mutated file into `--out`.

use raykin::bvh::{Blas, BvhQuality, StaticLayout, build_tlas};
use raykin::scene::{LoadOptions, SceneAsset, SceneError};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// A case using more CPU time than this is a hang (the slowest seed, FlightHelmet with its images, takes
/// about 11 s in a dev build). CPU time, not wall time: the fuzzer runs niced on a shared machine.
const HANG_CPU_SECONDS: f64 = 60.0;
/// Meshes above this many triangles skip the BVH build check (it is the slow part of a case).
const MAX_BVH_TRIANGLES: usize = 200_000;

struct Options {
    seeds: Vec<PathBuf>,
    out: PathBuf,
    seconds: u64,
    cases: u64,
    seed: u64,
    replay: Vec<PathBuf>,
    case: Option<(PathBuf, u64)>,
    /// The campaign's first case number: after a hang the fuzzer restarts itself here, one past the hang.
    first_case: u64,
}

fn parse_args() -> Result<Options, String> {
    let mut o = Options {
        seeds: Vec::new(),
        out: PathBuf::from("fuzz-out"),
        seconds: 60,
        cases: u64::MAX,
        seed: 1,
        replay: Vec::new(),
        case: None,
        first_case: 0,
    };
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        let mut value = || args.next().ok_or(format!("{a} needs a value"));
        match a.as_str() {
            "--seeds" => o.seeds.push(value()?.into()),
            "--out" => o.out = value()?.into(),
            "--seconds" => o.seconds = value()?.parse().map_err(|e| format!("--seconds: {e}"))?,
            "--cases" => o.cases = value()?.parse().map_err(|e| format!("--cases: {e}"))?,
            "--seed" => o.seed = value()?.parse().map_err(|e| format!("--seed: {e}"))?,
            "--replay" => o.replay.push(value()?.into()),
            "--first-case" => {
                o.first_case = value()?.parse().map_err(|e| format!("--first-case: {e}"))?
            }
            "--case" => {
                let v = value()?;
                let (file, n) = v.rsplit_once(':').ok_or("--case FILE:N")?;
                o.case = Some((file.into(), n.parse().map_err(|e| format!("--case: {e}"))?));
            }
            other => return Err(format!("unknown argument `{other}`")),
        }
    }
    Ok(o)
}

fn main() {
    let options = match parse_args() {
        Ok(o) => o,
        Err(e) => {
            eprintln!("fuzz_loader: {e}");
            std::process::exit(2);
        }
    };
    install_panic_recorder();
    if !options.replay.is_empty() {
        let mut failed = false;
        for file in &options.replay {
            let bytes = std::fs::read(file).unwrap_or_else(|e| panic!("{}: {e}", file.display()));
            let base = file.parent().unwrap_or(Path::new("."));
            let verdict = check_case(&bytes, base, file, true);
            println!("{}: {verdict}", file.display());
            failed |= verdict.is_finding();
        }
        std::process::exit(i32::from(failed));
    }
    let seeds = collect_seeds(&options.seeds);
    if seeds.is_empty() {
        eprintln!("fuzz_loader: no .gltf or .glb seeds found (--seeds DIR)");
        std::process::exit(2);
    }
    if let Some((file, n)) = &options.case {
        let seed = Seed::read(file).expect("seed file");
        let bytes = mutate(&seed, n_rng(options.seed, *n));
        // Written before the check, so a case that hangs can still be read and kept as a regression file.
        let ext = if bytes.starts_with(b"glTF") {
            "glb"
        } else {
            "gltf"
        };
        let saved = options.out.join(format!("case-{}-{n}.{ext}", options.seed));
        if std::fs::create_dir_all(&options.out)
            .and_then(|()| std::fs::write(&saved, &bytes))
            .is_ok()
        {
            eprintln!("fuzz_loader: case written to {}", saved.display());
        }
        let verdict = check_case(&bytes, &seed.base_dir, &seed.path, true);
        println!("case {}:{n}: {verdict}", file.display());
        std::process::exit(i32::from(verdict.is_finding()));
    }
    run_campaign(&options, &seeds);
}

/// A seed file, read once.
struct Seed {
    path: PathBuf,
    base_dir: PathBuf,
    bytes: Vec<u8>,
}

impl Seed {
    fn read(path: &Path) -> std::io::Result<Self> {
        Ok(Self {
            path: path.to_path_buf(),
            base_dir: path.parent().unwrap_or(Path::new(".")).to_path_buf(),
            bytes: std::fs::read(path)?,
        })
    }
}

fn collect_seeds(dirs: &[PathBuf]) -> Vec<Seed> {
    let mut files = Vec::new();
    let mut stack: Vec<PathBuf> = dirs.to_vec();
    while let Some(p) = stack.pop() {
        if p.is_dir() {
            if let Ok(entries) = std::fs::read_dir(&p) {
                stack.extend(entries.flatten().map(|e| e.path()));
            }
        } else if matches!(
            p.extension().and_then(|e| e.to_str()),
            Some("gltf") | Some("glb")
        ) {
            files.push(p);
        }
    }
    files.sort();
    files.iter().filter_map(|f| Seed::read(f).ok()).collect()
}

/// The random stream of case `n` of a campaign seeded with `seed`.
fn n_rng(seed: u64, n: u64) -> fastrand::Rng {
    fastrand::Rng::with_seed(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ n)
}

fn run_campaign(options: &Options, seeds: &[Seed]) {
    let findings = options.out.join("findings");
    std::fs::create_dir_all(&findings).expect("create the output folder");
    // Small seeds mutate and load fastest: pick a seed with probability ~ 1/sqrt(size).
    let weights: Vec<f64> = seeds
        .iter()
        .map(|s| 1.0 / (s.bytes.len() as f64).sqrt())
        .collect();
    let total: f64 = weights.iter().sum();
    let current = Arc::new(Mutex::new(String::new()));
    // CPU time (ms) at the start of the running case; u64::MAX between cases.
    let started_case = Arc::new(AtomicU64::new(u64::MAX));
    let current_case = Arc::new(AtomicU64::new(options.first_case));
    let start = Instant::now();
    let deadline = std::time::SystemTime::now() + Duration::from_secs(options.seconds);
    spawn_watchdog(Watch {
        label: current.clone(),
        started: started_case.clone(),
        case: current_case.clone(),
        out: options.out.clone(),
        deadline,
    });
    let cpu_start = cpu_seconds();
    let mut seen = std::collections::HashSet::new();
    // Why cases were refused (digits dropped): shows which mutations never get past the parser.
    let mut reasons: std::collections::HashMap<String, u64> = Default::default();
    let (mut cases, mut loaded, mut finds) = (options.first_case, 0u64, 0u64);
    let mut last_report = Instant::now();
    let mut picker = fastrand::Rng::with_seed(options.seed);
    // Resuming after a hang: the same seed choices as an uninterrupted campaign.
    for _ in 0..options.first_case {
        picker.f64();
    }
    let first_case = options.first_case;
    while cases < options.cases && start.elapsed() < Duration::from_secs(options.seconds) {
        let n = cases;
        let mut pick = picker.f64() * total;
        let seed = seeds
            .iter()
            .zip(&weights)
            .find(|(_, w)| {
                pick -= **w;
                pick <= 0.0
            })
            .map_or(&seeds[0], |(s, _)| s);
        let label = format!("{}:{n}", seed.path.display());
        *current.lock().unwrap() = label.clone();
        current_case.store(n, Ordering::SeqCst);
        started_case.store((cpu_seconds() * 1000.0) as u64, Ordering::SeqCst);
        let bytes = mutate(seed, n_rng(options.seed, n));
        let decode_images = n % 16 == 0;
        let save = (n % 8 == 3).then_some(options.out.as_path());
        let verdict = check_case_saving(&bytes, &seed.base_dir, &seed.path, decode_images, save);
        started_case.store(u64::MAX, Ordering::SeqCst);
        cases += 1;
        loaded += u64::from(matches!(verdict, Verdict::Loaded));
        if let Verdict::Refused(m) = &verdict {
            let why = m.split_once(": ").map_or(m.as_str(), |(_, r)| r);
            let key: String = why
                .chars()
                .filter(|c| !c.is_ascii_digit())
                .take(70)
                .collect();
            *reasons.entry(key).or_default() += 1;
        }
        if let Some(key) = verdict.finding_key()
            && seen.insert(key.clone())
        {
            finds += 1;
            let ext = if bytes.starts_with(b"glTF") {
                "glb"
            } else {
                "gltf"
            };
            let stem = format!("{}-{:08x}", verdict.kind(), fxhash(key.as_bytes()));
            let _ = std::fs::write(findings.join(format!("{stem}.{ext}")), &bytes);
            let _ = std::fs::write(
                findings.join(format!("{stem}.txt")),
                format!("case {label} (--seed {})\n{verdict}\n", options.seed),
            );
            eprintln!("fuzz_loader: finding {stem}: {verdict}");
        }
        if last_report.elapsed() > Duration::from_secs(60) {
            last_report = Instant::now();
            report(options, cases - first_case, loaded, finds, start, cpu_start);
        }
    }
    report(options, cases - first_case, loaded, finds, start, cpu_start);
    let mut top: Vec<_> = reasons.into_iter().collect();
    top.sort_by_key(|(_, n)| std::cmp::Reverse(*n));
    for (why, n) in top.iter().take(12) {
        eprintln!("fuzz_loader: refused {n:>8}: {why}");
    }
}

fn report(options: &Options, cases: u64, loaded: u64, finds: u64, start: Instant, cpu0: f64) {
    let wall = start.elapsed().as_secs_f64();
    let cpu = cpu_seconds() - cpu0;
    let line = format!(
        "seed {} cases {cases} loaded {loaded} findings {finds} wall_s {wall:.0} cpu_s {cpu:.0} cases_per_cpu_s {:.1}",
        options.seed,
        cases as f64 / cpu.max(1e-9)
    );
    eprintln!("fuzz_loader: {line}");
    // One line per campaign (per restart after a hang), rewritten as it runs: the hours are summed from
    // these files.
    let _ = std::fs::write(
        options
            .out
            .join(format!("stats-{}-{}.txt", options.seed, options.first_case)),
        line + "\n",
    );
}

/// User + system CPU seconds of this process (Linux /proc; 0 elsewhere).
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the command name (which is in parentheses and may hold spaces).
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|v| v.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    // utime and stime are fields 14 and 15 of stat(5); `rest` starts at field 3.
    (ticks(11) + ticks(12)) / 100.0
}

/// What the watchdog needs to name a hung case and restart the campaign after it.
struct Watch {
    label: Arc<Mutex<String>>,
    /// CPU time (ms) at the start of the running case; u64::MAX between cases.
    started: Arc<AtomicU64>,
    case: Arc<AtomicU64>,
    out: PathBuf,
    deadline: std::time::SystemTime,
}

/// A case over the CPU limit is recorded as a hang; the process then replaces itself with the same campaign
/// from the next case (a hung thread cannot be stopped), so one hang does not end the campaign.
fn spawn_watchdog(watch: Watch) {
    std::thread::spawn(move || {
        loop {
            std::thread::sleep(Duration::from_secs(1));
            let s = watch.started.load(Ordering::SeqCst);
            if s != u64::MAX && cpu_seconds() - s as f64 / 1000.0 > HANG_CPU_SECONDS {
                let label = watch.label.lock().map(|l| l.clone()).unwrap_or_default();
                let note = format!("hang: case {label} used over {HANG_CPU_SECONDS} CPU seconds\n");
                let name = format!("hang-{:08x}.txt", fxhash(label.as_bytes()));
                let _ = std::fs::write(watch.out.join("findings").join(name), &note);
                eprintln!("fuzz_loader: {note}");
                let left = watch
                    .deadline
                    .duration_since(std::time::SystemTime::now())
                    .unwrap_or_default();
                if left.as_secs() > 0 {
                    restart(watch.case.load(Ordering::SeqCst) + 1, left.as_secs());
                }
                std::process::exit(3);
            }
        }
    });
}

/// Replaces this process with the same command line, resumed at `first_case` for `seconds`.
fn restart(first_case: u64, seconds: u64) {
    use std::os::unix::process::CommandExt;
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    for (flag, value) in [("--first-case", first_case), ("--seconds", seconds)] {
        match args.iter().position(|a| a == flag) {
            Some(i) if i + 1 < args.len() => args[i + 1] = value.to_string(),
            _ => args.extend([flag.to_string(), value.to_string()]),
        }
    }
    let Ok(exe) = std::env::current_exe() else {
        return;
    };
    let error = std::process::Command::new(exe).args(args).exec();
    eprintln!("fuzz_loader: cannot restart after the hang: {error}");
}

fn fxhash(bytes: &[u8]) -> u32 {
    bytes.iter().fold(0x811C_9DC5u32, |h, &b| {
        (h ^ b as u32).wrapping_mul(0x0100_0193)
    })
}

// ---------------------------------------------------------------------------------------------------------
// Checking one case

enum Verdict {
    Loaded,
    Refused(String),
    /// A panic anywhere (also one the loader caught): message and location.
    Panic(String),
    /// Loaded, but breaks a promise of the loader.
    Broken(String),
    /// The refusal does not name the file.
    Unnamed(String),
}

impl Verdict {
    fn is_finding(&self) -> bool {
        self.finding_key().is_some()
    }
    fn kind(&self) -> &'static str {
        match self {
            Self::Loaded => "loaded",
            Self::Refused(_) => "refused",
            Self::Panic(_) => "panic",
            Self::Broken(_) => "broken",
            Self::Unnamed(_) => "unnamed",
        }
    }
    /// Findings are deduplicated by kind and the message without numbers (one file per distinct bug).
    fn finding_key(&self) -> Option<String> {
        let text = match self {
            Self::Loaded | Self::Refused(_) => return None,
            Self::Panic(m) | Self::Broken(m) | Self::Unnamed(m) => m,
        };
        let digitless: String = text.chars().filter(|c| !c.is_ascii_digit()).collect();
        Some(format!("{}:{digitless}", self.kind()))
    }
}

impl std::fmt::Display for Verdict {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Loaded => write!(f, "loaded"),
            Self::Refused(m) => write!(f, "refused: {m}"),
            Self::Panic(m) => write!(f, "PANIC: {m}"),
            Self::Broken(m) => write!(f, "BROKEN: {m}"),
            Self::Unnamed(m) => write!(f, "UNNAMED ERROR: {m}"),
        }
    }
}

std::thread_local! {
    static PANICS: std::cell::RefCell<Vec<String>> = const { std::cell::RefCell::new(Vec::new()) };
    static IN_CASE: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Records every panic (with its location) instead of printing it: the loader catches panics of the
/// decoders it calls, and the fuzzer must still see them.
fn install_panic_recorder() {
    std::panic::set_hook(Box::new(|info| {
        let message = info
            .payload()
            .downcast_ref::<String>()
            .cloned()
            .or_else(|| info.payload().downcast_ref::<&str>().map(|s| s.to_string()))
            .unwrap_or_default();
        let at = info
            .location()
            .map(|l| format!("{}:{}", l.file(), l.line()))
            .unwrap_or_default();
        if !IN_CASE.get() {
            // A bug in the fuzzer itself: say so before the process ends.
            eprintln!("fuzz_loader: internal panic: {message} at {at}");
        }
        PANICS.with(|p| p.borrow_mut().push(format!("{message} at {at}")));
    }));
}

fn take_panics() -> Vec<String> {
    PANICS.with(|p| std::mem::take(&mut *p.borrow_mut()))
}

fn check_case(bytes: &[u8], base_dir: &Path, name: &Path, decode_images: bool) -> Verdict {
    check_case_saving(bytes, base_dir, name, decode_images, None)
}

/// Like [`check_case`]; with `save_dir`, a loaded case is also saved through File > Save as (GLB, the
/// edited-materials writer) and the result reloaded.
fn check_case_saving(
    bytes: &[u8],
    base_dir: &Path,
    name: &Path,
    decode_images: bool,
    save_dir: Option<&Path>,
) -> Verdict {
    take_panics();
    IN_CASE.set(true);
    let options = LoadOptions {
        skip_images: !decode_images,
        ..Default::default()
    };
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let loaded = raykin::scene::load_gltf_slice(bytes, base_dir, name, &options);
        match loaded {
            Ok(scene) => match invariants(&scene)
                .and_then(|()| save_and_reload(bytes, base_dir, name, &scene, save_dir))
                .and_then(|()| exercise_cpu(scene))
            {
                Ok(()) => Verdict::Loaded,
                Err(e) => Verdict::Broken(e),
            },
            Err(e) => refusal(&e, name),
        }
    }));
    IN_CASE.set(false);
    let panics = take_panics();
    match result {
        _ if !panics.is_empty() => Verdict::Panic(panics.join(" | ")),
        Ok(v) => v,
        Err(_) => Verdict::Panic("panic without a message".into()),
    }
}

fn refusal(e: &SceneError, name: &Path) -> Verdict {
    let message = e.to_string();
    // The loader turns a decoder's panic into this error; for the fuzzer it is a panic.
    if let SceneError::Internal { message, .. } = e {
        return Verdict::Panic(message.clone());
    }
    let file = name
        .file_name()
        .map_or(String::new(), |f| f.to_string_lossy().into_owned());
    if message.contains(&file) {
        Verdict::Refused(message)
    } else {
        Verdict::Unnamed(message)
    }
}

/// Saves `scene`'s source with its materials as a GLB in `dir` and reloads it: the writer must not panic,
/// and what it writes must load with the same triangles.
fn save_and_reload(
    bytes: &[u8],
    base_dir: &Path,
    name: &Path,
    scene: &SceneAsset,
    dir: Option<&Path>,
) -> Result<(), String> {
    let Some(dir) = dir else {
        return Ok(());
    };
    let out = dir.join("saved.glb");
    let label = name.display().to_string();
    let access = LoadOptions::default().access();
    if raykin::scene::save_with_materials(bytes, base_dir, &label, access, &scene.materials, &out)
        .is_err()
    {
        // A texture the load skipped cannot be embedded: a clear refusal is fine.
        return Ok(());
    }
    let again = raykin::scene::load_gltf(
        &out,
        &LoadOptions {
            skip_images: true,
            ..Default::default()
        },
    )
    .map_err(|e| format!("Save as wrote a file that does not load: {e}"))?;
    if again.triangle_count() != scene.triangle_count() {
        return Err(format!(
            "Save as changed the triangle count: {} -> {}",
            scene.triangle_count(),
            again.triangle_count()
        ));
    }
    Ok(())
}

/// What every loaded scene must satisfy for the renderer and the animation code to use it blindly.
fn invariants(s: &SceneAsset) -> Result<(), String> {
    let check = |ok: bool, what: String| if ok { Ok(()) } else { Err(what) };
    for (i, m) in s.meshes.iter().enumerate() {
        let n = m.positions.len();
        check(
            m.positions.iter().all(|p| p.is_finite()),
            format!("mesh {i}: non-finite position"),
        )?;
        check(
            m.triangles.iter().flatten().all(|&v| (v as usize) < n),
            format!("mesh {i}: triangle index out of range"),
        )?;
        check(
            m.triangle_materials.len() == m.triangles.len(),
            format!("mesh {i}: triangle_materials length"),
        )?;
        check(
            m.triangle_materials
                .iter()
                .all(|&t| (t as usize) <= s.materials.len()),
            format!("mesh {i}: material index out of range"),
        )?;
        for (what, len) in [
            ("normals", m.normals.as_ref().map(Vec::len)),
            ("tangents", m.tangents.as_ref().map(Vec::len)),
            ("uv0", m.uv0.as_ref().map(Vec::len)),
            ("uv1", m.uv1.as_ref().map(Vec::len)),
            ("colors", m.colors.as_ref().map(Vec::len)),
        ] {
            check(
                len.is_none_or(|l| l == n),
                format!("mesh {i}: {what} length differs from positions"),
            )?;
        }
        if let Some(w) = &m.skin_weights {
            check(
                w.joints.len() == n * w.sets as usize && w.weights.len() == w.joints.len(),
                format!("mesh {i}: skin weight count"),
            )?;
            check(
                w.weights
                    .iter()
                    .flatten()
                    .all(|x| x.is_finite() && *x >= 0.0),
                format!("mesh {i}: skin weight not finite or negative"),
            )?;
        }
        for (t, target) in m.morph_targets.iter().enumerate() {
            check(
                target.positions.len() == n && target.positions.iter().all(|p| p.is_finite()),
                format!("mesh {i}: morph target {t} positions"),
            )?;
        }
    }
    for (i, m) in s.materials.iter().enumerate() {
        let texture_ok = |t: &Option<raykin::scene::TextureRef>| {
            t.is_none_or(|t| (t.texture as usize) < s.textures.len())
        };
        check(
            m.base_color.is_finite()
                && m.base_color.min_element() >= 0.0
                && m.base_color.max_element() <= 1.0,
            format!("material {i}: base colour {} outside [0, 1]", m.base_color),
        )?;
        check(
            m.emitted_radiance().is_finite() && m.emitted_radiance().min_element() >= 0.0,
            format!(
                "material {i}: emission {} not finite and non-negative",
                m.emitted_radiance()
            ),
        )?;
        check(
            (0.0..=1.0).contains(&m.metallic) && (0.0..=1.0).contains(&m.roughness),
            format!("material {i}: metallic/roughness outside [0, 1]"),
        )?;
        check(
            m.normal_scale.is_finite(),
            format!("material {i}: normal scale not finite"),
        )?;
        check(
            texture_ok(&m.base_color_texture)
                && texture_ok(&m.metallic_roughness_texture)
                && texture_ok(&m.normal_texture)
                && texture_ok(&m.emissive_texture),
            format!("material {i}: texture index out of range"),
        )?;
    }
    for (i, t) in s.textures.iter().enumerate() {
        check(
            t.image == u32::MAX || (t.image as usize) < s.images.len(),
            format!("texture {i}: image out of range"),
        )?;
    }
    for (i, img) in s.images.iter().enumerate() {
        check(
            img.rgba8.len() == img.width as usize * img.height as usize * 4,
            format!("image {i}: pixel count"),
        )?;
    }
    for (i, c) in s.cameras.iter().enumerate() {
        check(
            c.yfov.is_finite() && c.yfov > 0.0 && c.yfov < std::f32::consts::PI,
            format!("camera {i}: yfov {}", c.yfov),
        )?;
    }
    let nodes = s.nodes.len();
    for (i, n) in s.nodes.iter().enumerate() {
        check(
            n.mesh.is_none_or(|m| m < s.meshes.len())
                && n.camera.is_none_or(|c| c < s.cameras.len())
                && n.skin.is_none_or(|k| k < s.skins.len())
                && n.children.iter().all(|&c| c < nodes)
                && n.parent.is_none_or(|p| p < nodes),
            format!("node {i}: an index out of range"),
        )?;
        let t = &n.transform;
        check(
            t.translation.is_finite() && t.rotation.is_finite() && t.scale.is_finite(),
            format!("node {i}: non-finite transform"),
        )?;
    }
    check(
        s.roots.iter().all(|&r| r < nodes),
        "a root out of range".into(),
    )?;
    for (i, skin) in s.skins.iter().enumerate() {
        check(
            skin.joints.iter().all(|&j| j < nodes)
                && skin.inverse_bind_matrices.len() == skin.joints.len()
                && skin.inverse_bind_matrices.iter().all(|m| m.is_finite()),
            format!("skin {i}: joints or inverse bind matrices"),
        )?;
    }
    for (a, clip) in s.animations.iter().enumerate() {
        check(
            clip.duration.is_finite(),
            format!("animation {a}: duration"),
        )?;
        for (c, ch) in clip.channels.iter().enumerate() {
            check(
                ch.node < nodes && ch.validate().is_ok(),
                format!("animation {a} channel {c}: invalid after loading"),
            )?;
        }
    }
    Ok(())
}

/// Builds every BVH the renderer would (CPU only) and poses each clip at a few times through the CPU frame
/// schedule, checking the deformed vertices stay finite.
fn exercise_cpu(scene: SceneAsset) -> Result<(), String> {
    let mut boxes = Vec::new();
    for (i, m) in scene.meshes.iter().enumerate() {
        if m.triangles.len() > MAX_BVH_TRIANGLES {
            continue;
        }
        let blas = Blas::build(
            &m.positions,
            &m.triangles,
            BvhQuality::Fast,
            StaticLayout::Wide,
            m.is_deformable(),
            true,
        );
        if let Ok(b) = blas {
            let (lo, hi) = b.root_bounds();
            let finite = lo.is_finite() && hi.is_finite();
            if !finite && !m.triangles.is_empty() {
                return Err(format!("mesh {i}: BVH bounds not finite"));
            }
            boxes.push((lo, hi));
        }
    }
    let _ = build_tlas(&boxes);
    let clips: Vec<f32> = scene.animations.iter().map(|c| c.duration).collect();
    let scene = Arc::new(scene);
    let mut app = raykin::animation::cpu_app(scene);
    app.update();
    for (clip, duration) in clips.iter().enumerate().take(3) {
        for t in [0.0, duration * 0.37, *duration] {
            raykin::animation::hold_at(app.world_mut(), clip, t);
            app.update();
            let deformed = app.world().resource::<raykin::animation::DeformedMeshes>();
            for (m, d) in deformed.meshes.iter().enumerate() {
                if let Some(d) = d
                    && !d.positions.iter().all(|p| p.is_finite())
                {
                    return Err(format!(
                        "mesh {m}: non-finite deformed position (clip {clip}, t {t})"
                    ));
                }
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------------------------------------
// Mutation

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// A GLB split into its JSON and BIN chunks (None when the bytes are not a well-formed GLB).
fn split_glb(bytes: &[u8]) -> Option<(Vec<u8>, Option<Vec<u8>>)> {
    let u32_at = |o: usize| -> Option<u32> {
        Some(u32::from_le_bytes(bytes.get(o..o + 4)?.try_into().ok()?))
    };
    if !bytes.starts_with(GLB_MAGIC) {
        return None;
    }
    let (mut json, mut bin) = (None, None);
    let mut offset = 12;
    while offset + 8 <= bytes.len() {
        let len = u32_at(offset)? as usize;
        let kind = u32_at(offset + 4)?;
        let data = bytes.get(offset + 8..offset + 8 + len)?.to_vec();
        match kind {
            CHUNK_JSON if json.is_none() => json = Some(data),
            CHUNK_BIN if bin.is_none() => bin = Some(data),
            _ => {}
        }
        offset += 8 + len;
    }
    Some((json?, bin))
}

fn join_glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let pad = |n: usize| (4 - n % 4) % 4;
    let mut out = Vec::new();
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&0u32.to_le_bytes());
    let mut chunk = |kind: u32, data: &[u8], fill: u8| {
        out.extend_from_slice(&((data.len() + pad(data.len())) as u32).to_le_bytes());
        out.extend_from_slice(&kind.to_le_bytes());
        out.extend_from_slice(data);
        out.extend(std::iter::repeat_n(fill, pad(data.len())));
    };
    chunk(CHUNK_JSON, json, b' ');
    if let Some(bin) = bin {
        chunk(CHUNK_BIN, bin, 0);
    }
    let total = out.len() as u32;
    out[8..12].copy_from_slice(&total.to_le_bytes());
    out
}

/// One mutated case from a seed.
fn mutate(seed: &Seed, mut rng: fastrand::Rng) -> Vec<u8> {
    let glb = split_glb(&seed.bytes);
    let json_bytes = glb.as_ref().map_or(&seed.bytes[..], |(j, _)| &j[..]);
    let mut json = serde_json::from_slice::<Value>(json_bytes).ok();
    if let Some(doc) = json.as_mut() {
        // Mostly one edit: every extra edit is another chance to fail the parser before the code under test.
        let edits = [1, 1, 1, 1, 1, 2, 2, 3][rng.usize(..8)];
        for _ in 0..edits {
            mutate_json(doc, &mut rng);
        }
    }
    let json_out = json
        .map(|v| serde_json::to_vec(&v).expect("a Value serialises"))
        .unwrap_or_else(|| json_bytes.to_vec());
    let mut out = match glb {
        Some((_, bin)) => {
            let mut bin = bin;
            if let Some(b) = bin.as_mut()
                && rng.u8(..) < 64
            {
                mutate_bytes(b, &mut rng, true);
            }
            join_glb(&json_out, bin.as_deref())
        }
        None => json_out,
    };
    // Now and then damage the container itself (lengths, magic, truncation, stray bytes).
    if rng.u8(..32) == 0 {
        mutate_bytes(&mut out, &mut rng, false);
    }
    out
}

/// Interesting numbers: boundaries of glTF's integer fields, component-type codes, huge and tiny floats.
fn interesting_number(rng: &mut fastrand::Rng) -> Value {
    const INTS: &[i64] = &[
        0, 1, 2, 3, 4, 5, 7, 8, 9, 12, 16, 63, 64, 65, 255, 256, 65535, 65536, -1, -2, 2147483647,
        2147483648, 4294967295, 4294967296, 5120, 5121, 5122, 5123, 5125, 5126, 5130, 9728, 9729,
        10497, 33071, 33648, 34962, 34963,
    ];
    const FLOATS: &[f64] = &[
        0.0, -0.0, 0.5, -1.0, 1e-40, 1e-20, 1e18, 1e19, -1e19, 1e30, 3.4e38, 1e39, -1e39, 1e300,
        0.01, 3.2, 180.0,
    ];
    if rng.bool() {
        Value::from(INTS[rng.usize(..INTS.len())])
    } else {
        Value::from(FLOATS[rng.usize(..FLOATS.len())])
    }
}

const KEYS: &[&str] = &[
    "byteStride",
    "byteOffset",
    "byteLength",
    "count",
    "componentType",
    "type",
    "normalized",
    "sparse",
    "indices",
    "values",
    "bufferView",
    "buffer",
    "uri",
    "mimeType",
    "source",
    "sampler",
    "samplers",
    "channels",
    "target",
    "node",
    "path",
    "input",
    "output",
    "interpolation",
    "joints",
    "skin",
    "skeleton",
    "inverseBindMatrices",
    "mesh",
    "camera",
    "children",
    "scene",
    "scenes",
    "nodes",
    "matrix",
    "scale",
    "rotation",
    "translation",
    "weights",
    "targets",
    "mode",
    "material",
    "attributes",
    "POSITION",
    "NORMAL",
    "TANGENT",
    "TEXCOORD_0",
    "TEXCOORD_1",
    "COLOR_0",
    "JOINTS_0",
    "WEIGHTS_0",
    "emissiveFactor",
    "baseColorFactor",
    "metallicFactor",
    "roughnessFactor",
    "alphaCutoff",
    "alphaMode",
    "perspective",
    "orthographic",
    "yfov",
    "znear",
    "zfar",
    "aspectRatio",
    "version",
    "minVersion",
    "extensionsRequired",
    "extensionsUsed",
    "KHR_materials_emissive_strength",
    "emissiveStrength",
    "min",
    "max",
];

const STRINGS: &[&str] = &[
    "SCALAR",
    "VEC2",
    "VEC3",
    "VEC4",
    "MAT2",
    "MAT3",
    "MAT4",
    "VEC5",
    "translation",
    "rotation",
    "scale",
    "weights",
    "pointer",
    "LINEAR",
    "STEP",
    "CUBICSPLINE",
    "SLERP",
    "OPAQUE",
    "MASK",
    "BLEND",
    "perspective",
    "orthographic",
    "2.0",
    "2.1",
    "3.0",
    "1.0",
    "",
    "image/png",
    "image/jpeg",
    "/dev/zero",
    "/etc/passwd",
    "../../../etc/passwd",
    "nonexistent.bin",
    "data:,",
    "data:application/octet-stream;base64,AAAA",
    "data:application/octet-stream;base64,!!!",
    "file:///etc/passwd",
    "http://example.com/x.bin",
    ".",
    "%2e%2e/%2e%2e/x",
];

fn random_leaf(rng: &mut fastrand::Rng) -> Value {
    match rng.u8(..8) {
        0..=3 => interesting_number(rng),
        4 | 5 => Value::from(STRINGS[rng.usize(..STRINGS.len())]),
        6 => Value::Null,
        _ => Value::Array(
            (0..rng.usize(0..5))
                .map(|_| interesting_number(rng))
                .collect(),
        ),
    }
}

/// Every path (list of keys/indices) to a value in the document, up to a size limit.
fn paths(v: &Value, prefix: &mut Vec<PathStep>, out: &mut Vec<Vec<PathStep>>) {
    if out.len() > 20_000 {
        return;
    }
    out.push(prefix.clone());
    match v {
        Value::Object(map) => {
            for (k, child) in map {
                prefix.push(PathStep::Key(k.clone()));
                paths(child, prefix, out);
                prefix.pop();
            }
        }
        Value::Array(items) => {
            // Large arrays (min/max, weights) add nothing but cost: sample a few entries.
            for (i, child) in items.iter().enumerate().take(16) {
                prefix.push(PathStep::Index(i));
                paths(child, prefix, out);
                prefix.pop();
            }
        }
        _ => {}
    }
}

#[derive(Clone)]
enum PathStep {
    Key(String),
    Index(usize),
}

fn at_mut<'a>(v: &'a mut Value, path: &[PathStep]) -> Option<&'a mut Value> {
    path.iter().try_fold(v, |v, step| match step {
        PathStep::Key(k) => v.get_mut(k.as_str()),
        PathStep::Index(i) => v.get_mut(*i),
    })
}

fn mutate_json(doc: &mut Value, rng: &mut fastrand::Rng) {
    let mut all = Vec::new();
    paths(doc, &mut Vec::new(), &mut all);
    // The asset header only decides acceptance: mutate it rarely.
    let mut target = all[rng.usize(..all.len())].clone();
    if matches!(target.first(), Some(PathStep::Key(k)) if k == "asset") && rng.u8(..8) != 0 {
        target = all[rng.usize(..all.len())].clone();
    }
    let donor_path = all[rng.usize(..all.len())].clone();
    let donor = at_mut(doc, &donor_path).map(|v| v.clone());
    let Some(node) = at_mut(doc, &target) else {
        return;
    };
    // Mostly type-preserving edits: a value of the wrong JSON type only exercises the parser's refusal.
    if rng.u8(..8) == 0 {
        *node = match donor {
            Some(d) if rng.bool() => d,
            _ => random_leaf(rng),
        };
        return;
    }
    match node {
        Value::Number(n) => {
            let integer = n.is_i64() || n.is_u64();
            let n = n.as_f64().unwrap_or(0.0);
            *node = match rng.u8(..6) {
                0 => Value::from((n as i64).saturating_add(1)),
                1 => Value::from((n as i64).saturating_sub(1)),
                2 if integer => Value::from((n as i64).saturating_neg()),
                2 => Value::from(-n),
                3 => Value::from(
                    [1u64 << 31, 1 << 32, 1 << 40, u32::MAX as u64, 1 << 62][rng.usize(..5)],
                ),
                _ => interesting_number(rng),
            };
        }
        Value::String(_) => *node = Value::from(STRINGS[rng.usize(..STRINGS.len())]),
        Value::Bool(b) => *b = !*b,
        Value::Array(items) => match rng.u8(..5) {
            0 if !items.is_empty() => {
                items.remove(rng.usize(..items.len()));
            }
            1 if !items.is_empty() => {
                let copy = items[rng.usize(..items.len())].clone();
                items.insert(rng.usize(..=items.len()), copy);
            }
            2 => rng.shuffle(items),
            3 => items.truncate(rng.usize(..=items.len())),
            _ => items.push(interesting_number(rng)),
        },
        Value::Object(map) => match rng.u8(..4) {
            0 if !map.is_empty() => {
                let key = map
                    .keys()
                    .nth(rng.usize(..map.len()))
                    .cloned()
                    .expect("non-empty");
                map.remove(&key);
            }
            1 => {
                let key = KEYS[rng.usize(..KEYS.len())];
                let value = match donor {
                    Some(d) if rng.bool() => d,
                    _ => interesting_number(rng),
                };
                map.insert(key.to_string(), value);
            }
            _ => {
                // Splice an object of the same kind when the donor is one (another accessor, node ...).
                if let Some(d @ Value::Object(_)) = donor {
                    *node = d;
                } else if !map.is_empty() {
                    let key = map
                        .keys()
                        .nth(rng.usize(..map.len()))
                        .cloned()
                        .expect("non-empty");
                    map.insert(key, interesting_number(rng));
                }
            }
        },
        Value::Null => *node = interesting_number(rng),
    }
}

/// Byte-level damage. `floats`: the BIN chunk, where aligned NaN/infinite/huge floats are the interesting
/// values.
fn mutate_bytes(bytes: &mut Vec<u8>, rng: &mut fastrand::Rng, floats: bool) {
    if bytes.is_empty() {
        return;
    }
    for _ in 0..rng.usize(1..=8) {
        let len = bytes.len();
        match rng.u8(..6) {
            0 => {
                let i = rng.usize(..len);
                bytes[i] ^= 1 << rng.u8(..8);
            }
            1 => {
                let i = rng.usize(..len);
                bytes[i] = [0, 1, 0x7f, 0x80, 0xff][rng.usize(..5)];
            }
            2 if floats && len >= 4 => {
                let i = rng.usize(..len / 4) * 4;
                let v: f32 = [
                    f32::NAN,
                    f32::INFINITY,
                    -f32::INFINITY,
                    1e19,
                    -1e30,
                    0.0,
                    f32::MAX,
                ][rng.usize(..7)];
                bytes[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
            3 if len >= 4 => {
                // A length or offset field: a u32 somewhere set to a boundary value.
                let i = rng.usize(..len / 4) * 4;
                let v: u32 = [0, 1, 0xffff_ffff, 0x8000_0000, len as u32 + 1][rng.usize(..5)];
                bytes[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
            4 => bytes.truncate(rng.usize(..len)),
            _ => {
                let i = rng.usize(..=len);
                let extra: Vec<u8> = (0..rng.usize(1..16)).map(|_| rng.u8(..)).collect();
                bytes.splice(i..i, extra);
            }
        }
        if bytes.is_empty() {
            return;
        }
    }
}
