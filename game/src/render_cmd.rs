//! `raykin render` and the no-argument default job.

use crate::adapter::open_gpu;
use crate::cli::{RenderArgs, SceneArgs};
use crate::outputs::Output;
use crate::scenes::{embedded_camera, embedded_scene, load_scene};
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use raykin::camera::CameraChoice;
use raykin::gpu::GpuContext;
use raykin::headless::HeadlessApp;
use raykin::record::CameraSpec;
use raykin::render::{DenoiserKind, Environment, RenderSettings};
use raykin::scene::SceneAsset;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

/// What can be checked before the GPU opens: the camera choice.
pub fn check_scene(scene: &SceneAsset, camera: &CameraChoice) -> Result<()> {
    raykin::camera::check_camera_choice(scene, camera)?;
    Ok(())
}

/// The image size against the adapter's limits, before the renderer creates any buffer.
pub fn check_size(ctx: &GpuContext, width: u32, height: u32) -> Result<()> {
    raykin::gpu::limits::check_image_size(&ctx.limits, width, height)
        .with_context(|| format!("on {}", ctx.info.name))
}

/// The render settings the arguments ask for; `scene` gives the field of view an f-number is converted with.
/// Errors on a lens or environment value that cannot be rendered.
pub fn settings_from(args: &SceneArgs, scene: &SceneAsset) -> Result<RenderSettings> {
    Ok(RenderSettings {
        width: args.width.max(1),
        height: args.height.max(1),
        spp_per_frame: args.spp_per_dispatch.max(1),
        max_depth: args.max_depth,
        environment: environment_from(args)?,
        lens: lens_from(args, scene)?,
        exposure: args.exposure,
        seed: args.seed,
        russian_roulette: !args.no_rr,
        rr_depth: args.rr_depth,
        nee: !args.no_nee,
        denoise: args.denoise.is_some(),
        denoiser: args
            .denoise
            .unwrap_or(crate::cli::DenoiseArg::Default)
            .into(),
        oidn: raykin::oidn::DenoiseOptions {
            quality: args.denoise_quality.into(),
            aux: args.denoise_aovs.into(),
            ..Default::default()
        },
        deform: args.deform.into(),
        static_bvh: args.static_bvh.layout(),
        merge_static: args.static_bvh.merged(),
        integrator: args.integrator.into(),
        ..Default::default()
    })
}

/// `--env`, `--sky`, `--env-map` (read here, so a bad file fails before the GPU opens) or `--sun-sky`.
fn environment_from(args: &SceneArgs) -> Result<Environment> {
    let strength = args.env_strength;
    if !(strength.is_finite() && strength >= 0.0) {
        anyhow::bail!("--env-strength {strength}: must be a finite number >= 0");
    }
    if let Some(path) = &args.env_map {
        raykin::environment::EnvironmentMap::load(path)?;
        return Ok(Environment::Map(raykin::environment::MapSettings {
            path: path.clone(),
            rotation_degrees: args.env_rotation,
            strength,
        }));
    }
    if let Some((elevation, azimuth)) = args.sun_sky {
        if !(1.7..=10.0).contains(&args.turbidity) {
            anyhow::bail!(
                "--turbidity {}: the sky model is fitted for 1.7 to 10",
                args.turbidity
            );
        }
        return Ok(Environment::SunSky(raykin::environment::SunSkySettings {
            elevation_degrees: elevation,
            azimuth_degrees: azimuth,
            turbidity: args.turbidity,
            strength,
        }));
    }
    Ok(match args.env {
        Some(c) => Environment::Constant((c * strength).to_array()),
        None => Environment::Sky,
    })
}

/// `--aperture` or `--f-stop` with `--focus-distance` (a pinhole without them).
fn lens_from(args: &SceneArgs, scene: &SceneAsset) -> Result<raykin::render::ThinLens> {
    let Some(focus) = args.focus_distance else {
        return Ok(Default::default());
    };
    if !(focus.is_finite() && focus > 0.0) {
        anyhow::bail!("--focus-distance {focus}: must be a positive distance");
    }
    if let Some(n) = args.f_stop {
        if !(n.is_finite() && n > 0.0) {
            anyhow::bail!("--f-stop {n}: must be a positive f-number");
        }
        return Ok(raykin::render::ThinLens::from_f_number(
            n,
            camera_yfov(args, scene),
            focus,
        ));
    }
    let radius = args.aperture.unwrap_or(0.0);
    if !(radius.is_finite() && radius >= 0.0) {
        anyhow::bail!("--aperture {radius}: must be a radius >= 0");
    }
    Ok(raykin::render::ThinLens {
        aperture_radius: radius,
        focus_distance: focus,
    })
}

/// The vertical field of view the render will use: `--fov` with `--look-from`, else the chosen scene camera's,
/// else the framing camera's 45 degrees.
fn camera_yfov(args: &SceneArgs, scene: &SceneAsset) -> f32 {
    if args.look_from.is_some() {
        return args.fov.to_radians();
    }
    let cameras: Vec<usize> = scene.nodes.iter().filter_map(|n| n.camera).collect();
    cameras
        .get(args.camera.unwrap_or(0))
        .and_then(|&c| scene.cameras.get(c))
        .map_or(45f32.to_radians(), |c| c.yfov)
}

/// `--time T` / `--animation NAME|INDEX`: the clip and time to pose the scene at (clip 0, time 0 by default);
/// `None` when neither is given (the file's rest pose).
pub fn pose_from(scene: &SceneAsset, args: &SceneArgs) -> Result<Option<(usize, f32)>> {
    if args.time.is_none() && args.animation.is_none() {
        return Ok(None);
    }
    if scene.animations.is_empty() {
        anyhow::bail!(
            "{}: the scene has no animations, so --time/--animation cannot pose it",
            scene.source
        );
    }
    let clip = match &args.animation {
        Some(a) => raykin::animation::find_clip(scene, a).map_err(anyhow::Error::msg)?,
        None => 0,
    };
    Ok(Some((clip, args.time.unwrap_or(0.0))))
}

pub fn camera_from(args: &SceneArgs) -> CameraChoice {
    camera_spec(args).choice()
}

/// `--camera I` or `--look-from/--look-at/--fov`, in the form a recording's manifest stores.
pub fn camera_spec(args: &SceneArgs) -> CameraSpec {
    match (args.look_from, args.look_at, args.camera) {
        (Some(eye), Some(target), _) => CameraSpec::LookAt {
            eye: eye.to_array(),
            target: target.to_array(),
            yfov_degrees: args.fov,
        },
        (_, _, Some(i)) => CameraSpec::Index(i),
        _ => CameraSpec::Auto,
    }
}

fn progress_bar(total: u64, what: &str) -> ProgressBar {
    let bar = ProgressBar::new(total);
    bar.set_style(
        ProgressStyle::with_template(
            "{prefix} [{bar:40}] {pos}/{len} spp, {elapsed} elapsed, ETA {eta}",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    bar.set_prefix(what.to_string());
    bar
}

#[derive(serde::Serialize)]
struct RenderReport {
    scene: String,
    adapter: String,
    backend: String,
    width: u32,
    height: u32,
    spp: u32,
    max_depth: u32,
    denoise: bool,
    /// "oidn" or "svgf" when denoised (svgf also where OIDN was asked for but could not run).
    denoiser: Option<String>,
    /// OIDN: the device, and milliseconds from the GPU buffers to the denoised host image.
    oidn_device: Option<String>,
    oidn_ms: Option<f64>,
    /// The part of `oidn_ms` that reads the accumulation and AOVs back to the host and makes them means (0
    /// with shared GPU memory).
    oidn_readback_ms: Option<f64>,
    /// OIDN read its inputs from GPU memory shared with wgpu, not from host copies.
    oidn_shared_memory: Option<bool>,
    triangles: usize,
    bvh_build_and_upload_s: f64,
    gpu_memory_geometry_bvh_bytes: u64,
    gpu_memory_total_bytes: u64,
    /// Instances traced through the merged static tree (0: none), its triangles, and the bytes it adds
    /// (counted in `gpu_memory_geometry_bvh_bytes`).
    merged_static_instances: usize,
    merged_static_triangles: u32,
    merged_static_bytes: u64,
    /// The scene's buffers copied into textures, which kernels on CPU adapters read (0 on GPUs; not counted in
    /// `gpu_memory_total_bytes`).
    scene_texture_bytes: u64,
    render_wall_s: f64,
    samples_per_second: f64,
}

pub fn run(args: &RenderArgs) -> Result<()> {
    let scene = load_scene(&args.scene.scene, &args.load.options())?;
    let outputs = Outputs {
        image: &args.out,
        aovs: args.aovs,
        report: args.report.as_deref(),
        noisy_beside: None,
    };
    check_outputs(&scene, &outputs)?;
    // Pose and camera arguments are checked before the GPU opens: a typo fails at once.
    let pose = pose_from(&scene, &args.scene)?;
    let camera = camera_from(&args.scene);
    check_scene(&scene, &camera)?;
    let ctx = open_gpu()?;
    check_size(&ctx, args.scene.width, args.scene.height)?;
    render_to_file(ctx, scene, &args.scene, camera, pose, outputs)?;
    Ok(())
}

/// What [`render_to_file`] writes.
struct Outputs<'a> {
    image: &'a Path,
    /// First-hit AOVs as EXRs beside the image.
    aovs: bool,
    report: Option<&'a Path>,
    /// With denoising on: the image before denoising, here as well.
    noisy_beside: Option<&'a Path>,
}

/// With `--denoise`, opens the chosen denoiser before rendering: OIDN's device is named, or its failure
/// reported and svgf used instead. Returns the denoiser that will run.
pub fn announce_denoiser(app: &mut HeadlessApp) -> Option<&'static str> {
    match app.resolve_denoiser() {
        Some(Ok(device)) => eprintln!("raykin: denoiser: Open Image Denoise on {device}"),
        Some(Err(e)) => eprintln!("raykin: warning: {e}; denoising with svgf instead"),
        None => {}
    }
    let s = app.app.world().resource::<RenderSettings>();
    s.denoise.then_some(match s.denoiser {
        DenoiserKind::Oidn => "oidn",
        DenoiserKind::Svgf => "svgf",
    })
}

/// `NAME.albedo.exr`, `NAME.normal.exr`, `NAME.depth.exr` beside the image.
fn aov_paths(out: &Path) -> [(&'static str, PathBuf); 3] {
    let stem = out.with_extension("");
    ["albedo", "normal", "depth"].map(|name| {
        (
            name,
            PathBuf::from(format!("{}.{name}.exr", stem.display())),
        )
    })
}

/// Every file the render writes: a known format, never one of the scene's files or another output, in
/// writable folders; all before any rendering.
fn check_outputs(scene: &SceneAsset, outputs: &Outputs) -> Result<()> {
    let out = outputs.image;
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("exr") | Some("png")) {
        anyhow::bail!(
            "{}: the output must end in .exr (linear radiance) or .png (tone-mapped sRGB)",
            out.display()
        );
    }
    let mut files = vec![Output {
        what: "--out",
        path: out.to_path_buf(),
    }];
    if outputs.aovs {
        files.extend(aov_paths(out).map(|(_, path)| Output {
            what: "--aovs output",
            path,
        }));
    }
    if let Some(report) = outputs.report {
        files.push(Output {
            what: "--report",
            path: report.to_path_buf(),
        });
    }
    if let Some(noisy) = outputs.noisy_beside {
        files.push(Output {
            what: "the noisy image",
            path: noisy.to_path_buf(),
        });
    }
    crate::outputs::refuse_overwrites(&files, &scene.files)?;
    for o in &files {
        crate::outputs::check_writable(o.what, &o.path)?;
    }
    Ok(())
}

fn render_to_file(
    ctx: GpuContext,
    scene: Arc<SceneAsset>,
    args: &SceneArgs,
    camera: CameraChoice,
    pose: Option<(usize, f32)>,
    outputs: Outputs,
) -> Result<()> {
    let out = outputs.image;
    let ext = out
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let settings = settings_from(args, &scene)?;
    let mut app = HeadlessApp::new(ctx, scene.clone(), settings.clone(), &camera)?;
    // The denoiser is on or off for the whole render: its inputs (moments, first-hit AOVs) accumulate only when
    // it runs, or when the AOVs are written.
    app.set_keep_denoiser_inputs(outputs.aovs);
    for n in &app.notes {
        eprintln!("raykin: warning: {}: {n}", scene.source);
    }
    if let Some((clip, time)) = pose {
        app.set_time(clip, time).map_err(anyhow::Error::msg)?;
    }
    let denoiser = announce_denoiser(&mut app);
    let start = Instant::now();
    let bar = progress_bar(args.spp as u64, "rendering");
    app.accumulate(args.spp, args.spp_per_dispatch, |done| {
        bar.set_position(done as u64)
    });
    bar.finish_and_clear();
    let wall = start.elapsed().as_secs_f64();
    let (w, h) = (settings.width, settings.height);
    let denoise_start = Instant::now();
    let radiance = app.output_radiance();
    let denoise_s = denoise_start.elapsed().as_secs_f64();
    if let Some(bad) = radiance.iter().flatten().find(|v| !v.is_finite()) {
        anyhow::bail!("internal error: the render has a non-finite pixel value ({bad})");
    }
    if ext.as_deref() == Some("exr") {
        raykin::image_io::write_atomically(out, |p| {
            raykin::image_io::write_exr(p, w, h, &radiance)
        })?;
    } else {
        let rgba = app.display_rgba8();
        raykin::image_io::write_atomically(out, |p| raykin::image_io::write_png(p, w, h, &rgba))?;
    }
    let noisy = outputs.noisy_beside.filter(|_| denoiser.is_some());
    if let Some(noisy) = noisy {
        app.settings_mut().denoise = false;
        let rgba = app.display_rgba8();
        raykin::image_io::write_atomically(noisy, |p| raykin::image_io::write_png(p, w, h, &rgba))?;
        app.settings_mut().denoise = true;
    }
    if outputs.aovs {
        let a = app.aovs();
        let depth: Vec<[f32; 3]> = a.depth.iter().map(|d| [*d; 3]).collect();
        for ((_, path), data) in aov_paths(out)
            .into_iter()
            .zip([&a.albedo, &a.normal, &depth])
        {
            raykin::image_io::write_atomically(&path, |p| {
                raykin::image_io::write_exr(p, w, h, data)
            })?;
        }
    }
    let oidn = (denoiser == Some("oidn"))
        .then(|| app.oidn_denoised().ok())
        .flatten();
    let gpu_scene = app.gpu_scene();
    let denoised = match (denoiser, &oidn) {
        (Some("oidn"), Some(o)) => format!(
            ", denoised by Open Image Denoise on {}{} in {:.2} s",
            o.device,
            if o.shared_memory {
                " (GPU memory shared with wgpu)"
            } else {
                ""
            },
            denoise_s
        ),
        (Some(d), _) => format!(", denoised by {d} in {denoise_s:.2} s"),
        (None, _) => String::new(),
    };
    eprintln!(
        "raykin: wrote {} ({w}x{h}, {} spp{denoised}, {:.2} s, {:.2} M samples/s)",
        out.display(),
        args.spp,
        wall,
        (w as f64 * h as f64 * args.spp as f64) / wall / 1e6
    );
    if let Some(noisy) = noisy {
        eprintln!(
            "raykin: wrote {} (the same {} spp before denoising)",
            noisy.display(),
            args.spp
        );
    }
    if let Some(path) = outputs.report {
        let r = RenderReport {
            scene: scene.source.clone(),
            adapter: app.ctx.info.name.clone(),
            backend: format!("{:?}", app.ctx.info.backend),
            width: w,
            height: h,
            spp: args.spp,
            max_depth: args.max_depth,
            denoise: settings.denoise,
            denoiser: denoiser.map(str::to_string),
            oidn_device: oidn.as_ref().map(|o| o.device.clone()),
            oidn_ms: oidn.as_ref().map(|o| o.total_ms()),
            oidn_readback_ms: oidn.as_ref().map(|o| o.readback_ms),
            oidn_shared_memory: oidn.as_ref().map(|o| o.shared_memory),
            triangles: scene.triangle_count(),
            bvh_build_and_upload_s: gpu_scene.build_seconds,
            gpu_memory_geometry_bvh_bytes: gpu_scene.memory.geometry_and_bvh(),
            gpu_memory_total_bytes: gpu_scene.memory.total(),
            merged_static_instances: gpu_scene.merge.as_ref().map_or(0, |m| m.members.len()),
            merged_static_triangles: gpu_scene.merge.as_ref().map_or(0, |m| m.triangles),
            merged_static_bytes: gpu_scene.merge.as_ref().map_or(0, |m| m.bytes),
            scene_texture_bytes: app
                .app
                .world()
                .resource::<raykin::render::scene_bindings::SceneBindings>()
                .texture_bytes(),
            render_wall_s: wall,
            samples_per_second: (w as f64 * h as f64 * args.spp as f64) / wall,
        };
        raykin::image_io::write_bytes_atomically(
            path,
            serde_json::to_string_pretty(&r)?.as_bytes(),
        )
        .with_context(|| format!("--report {}: cannot write the report", path.display()))?;
    }
    Ok(())
}

/// `raykin` with no arguments: the embedded Cornell box, rendered to out/default.png.
pub fn run_default() -> Result<()> {
    let scene = embedded_scene()?;
    let ctx = open_gpu()?;
    // A software rasteriser (lavapipe) traces a few hundred thousand paths a second: keep its job under a minute.
    let cpu = ctx.info.device_type == raykin::gpu::DeviceType::Cpu;
    let (size, spp) = if cpu { (256, 32) } else { (1024, 1024) };
    eprintln!(
        "raykin: rendering the embedded Cornell box, {size}x{size} at {spp} spp (`raykin render --help` for more)"
    );
    let args = SceneArgs {
        scene: PathBuf::from("<embedded>"),
        spp,
        max_depth: 6,
        width: size,
        height: size,
        camera: None,
        look_from: None,
        look_at: None,
        fov: 39.3077,
        env: Some(glam::Vec3::ZERO),
        sky: false,
        env_map: None,
        env_rotation: 0.0,
        env_strength: 1.0,
        sun_sky: None,
        turbidity: 3.0,
        aperture: None,
        f_stop: None,
        focus_distance: None,
        seed: 0,
        exposure: 0.0,
        no_nee: false,
        no_rr: false,
        rr_depth: crate::cli::default_rr_depth(),
        time: None,
        animation: None,
        spp_per_dispatch: 16,
        // A newcomer's first picture: denoised (OIDN, else svgf), with the noisy one beside it.
        denoise: Some(crate::cli::DenoiseArg::Default),
        denoise_quality: crate::cli::DenoiseQuality::High,
        denoise_aovs: crate::cli::DenoiseAovs::Prefilter,
        deform: crate::cli::DeformArg::Auto,
        static_bvh: crate::cli::StaticBvh::Merged,
        integrator: crate::cli::IntegratorArg::Auto,
    };
    let camera = embedded_camera();
    let out = Path::new("out/default.png");
    let outputs = Outputs {
        image: out,
        aovs: false,
        report: None,
        noisy_beside: Some(Path::new("out/default-noisy.png")),
    };
    check_outputs(&scene, &outputs)?;
    render_to_file(ctx, Arc::new(scene), &args, camera, None, outputs)
}
