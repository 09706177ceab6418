//! Command-line interface.

use clap::{Args, Parser, Subcommand, ValueEnum};
use std::path::PathBuf;

#[derive(Parser, Debug)]
#[command(
    name = "raykin",
    version,
    about = "Path-trace animated glTF scenes on any GPU (wgpu compute, software BVH traversal)"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Option<Command>,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Render one image of a scene, headless.
    Render(RenderArgs),
    /// Record an animation as a frame sequence: deterministic, resumable, shardable (--range, --merge).
    Record(RecordArgs),
    /// Measure frame times, rays per second, BVH build time and GPU memory.
    Bench(BenchArgs),
    /// Open the interactive viewer and editor (or run its frame loop offscreen).
    View(ViewArgs),
}

#[derive(Args, Debug, Clone)]
pub struct ViewArgs {
    /// A .gltf or .glb file, or `crowd` (the animated bench crowd from --assets); default: the embedded
    /// Cornell box.
    pub scene: Option<PathBuf>,
    #[command(flatten)]
    pub load: LoadArgs,
    /// Run scripted steps (see docs/VIEWER.md): wait, edit materials, scrub, switch camera, screenshot, quit.
    #[arg(long)]
    pub script: Option<PathBuf>,
    /// Run the frame loop without a window (for timing on machines without a display).
    #[arg(long)]
    pub offscreen: bool,
    /// Frames to run offscreen.
    #[arg(long, default_value_t = 300, requires = "offscreen")]
    pub frames: u64,
    /// Offscreen: write per-pass frame times (median, p99) as JSON here.
    #[arg(long, requires = "offscreen")]
    pub report: Option<PathBuf>,
    /// Offscreen: also wait for the GPU after the frame schedule and after the UI pass and report those
    /// wall times (a cross-check of the timestamps; serialises CPU and GPU).
    #[arg(long, requires = "offscreen")]
    pub sync_passes: bool,
    /// Render at this fixed size WxH instead of the image area's size.
    #[arg(long, value_parser = parse_size)]
    pub image_size: Option<(u32, u32)>,
    /// Window size WxH (default: the last size used, else 1280x800).
    #[arg(long, value_parser = parse_size)]
    pub window_size: Option<(u32, u32)>,
    /// Present without waiting for vertical sync.
    #[arg(long)]
    pub no_vsync: bool,
    /// Animation time step in seconds per frame (default: wall-clock time; 1/60 with --script or --offscreen).
    #[arg(long, value_parser = parse_non_negative, allow_hyphen_values = true)]
    pub fixed_dt: Option<f32>,
    /// Samples per pixel per frame.
    #[arg(long, value_parser = at_least_one(), allow_negative_numbers = true)]
    pub spp_per_frame: Option<u32>,
    /// Surface interactions after the camera ray.
    #[arg(long)]
    pub max_depth: Option<u32>,
    /// Start with the scene's camera I.
    #[arg(long)]
    pub camera: Option<usize>,
    /// Play this animation clip (name or index).
    #[arg(long)]
    pub animation: Option<String>,
    /// Folder of the shared glTF assets (for `crowd`).
    #[arg(long, default_value = "../shared/assets")]
    pub assets: PathBuf,
    /// Neither read nor write the settings file.
    #[arg(long)]
    pub no_settings: bool,
    /// realtime: temporal reuse with gradients and a spatial filter while anything moves (ReSTIR DI is a
    /// switch of the Render panel), plain accumulation for stills (the default, or the settings file's mode);
    /// accumulate: restart accumulation whenever anything moves.
    #[arg(long, value_enum)]
    pub mode: Option<ModeArg>,
    /// Open Image Denoise over each real-time frame in place of the spatial filter (with OIDN the denoiser):
    /// shared (where OIDN's GPU device reads the GPU's memory: CUDA on NVIDIA), always (also through host
    /// copies: slow on the CPU), off. Default: the settings file's, else off (docs/BENCHMARKS.md, "OIDN per
    /// real-time frame").
    #[arg(long, value_enum)]
    pub frame_oidn: Option<FrameOidnArg>,
    /// The per-frame OIDN filter's quality (default: the settings file's, else balanced).
    #[arg(long, value_enum)]
    pub frame_oidn_quality: Option<DenoiseQuality>,
}

/// `--frame-oidn`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameOidnArg {
    Off,
    Shared,
    Always,
}

impl From<FrameOidnArg> for raykin::render::FrameOidn {
    fn from(a: FrameOidnArg) -> Self {
        match a {
            FrameOidnArg::Off => Self::Off,
            FrameOidnArg::Shared => Self::Shared,
            FrameOidnArg::Always => Self::Always,
        }
    }
}

/// `--mode`: how frames are made while anything moves.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum ModeArg {
    Realtime,
    Accumulate,
}

impl From<ModeArg> for raykin::render::RenderMode {
    fn from(m: ModeArg) -> Self {
        match m {
            ModeArg::Realtime => Self::Realtime,
            ModeArg::Accumulate => Self::Accumulate,
        }
    }
}

/// How a scene file is read: which of its glTF scenes, and whether it may read files outside its folder.
#[derive(Args, Debug, Clone, Default)]
pub struct LoadArgs {
    /// Show the file's glTF scene N (default: its default scene, else its first).
    #[arg(long = "scene", value_name = "N")]
    pub scene_index: Option<usize>,
    /// Let the scene's URIs name files outside its folder (absolute paths, `..`, symlinks out of it): only
    /// for trusted files.
    #[arg(long)]
    pub allow_external_files: bool,
    /// Show the file's KHR_materials_variants variant NAME instead of its own materials.
    #[arg(long, value_name = "NAME")]
    pub variant: Option<String>,
}

impl LoadArgs {
    pub fn options(&self) -> raykin::scene::LoadOptions {
        raykin::scene::LoadOptions {
            scene: self.scene_index,
            allow_external_files: self.allow_external_files,
            variant: self.variant.clone(),
            ..Default::default()
        }
    }
}

/// Russian roulette's start as the engine's settings have it (one place for the measured default).
pub fn default_rr_depth() -> u32 {
    raykin::render::RenderSettings::default().rr_depth
}

/// A u32 of at least 1 (sample counts, sizes).
pub fn at_least_one() -> clap::builder::RangedI64ValueParser<u32> {
    clap::value_parser!(u32).range(1..)
}

fn parse_number(s: &str) -> Result<f32, String> {
    s.trim()
        .parse::<f32>()
        .map_err(|_| format!("`{s}` is not a number"))
}

/// A finite number (negative allowed).
pub fn parse_finite(s: &str) -> Result<f32, String> {
    let v = parse_number(s)?;
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("`{s}` is not a finite number"))
    }
}

pub fn parse_non_negative(s: &str) -> Result<f32, String> {
    let v = parse_finite(s)?;
    if v >= 0.0 {
        Ok(v)
    } else {
        Err(format!("`{s}` is negative"))
    }
}

pub fn parse_positive(s: &str) -> Result<f32, String> {
    let v = parse_finite(s)?;
    if v > 0.0 {
        Ok(v)
    } else {
        Err(format!("`{s}` is not greater than 0"))
    }
}

/// A vertical field of view in degrees: a pinhole camera sees less than a half space.
pub fn parse_fov(s: &str) -> Result<f32, String> {
    let v = parse_finite(s)?;
    if v > 0.0 && v < 180.0 {
        Ok(v)
    } else {
        Err(format!(
            "`{s}`: a field of view is an angle in degrees between 0 and 180, both excluded"
        ))
    }
}

pub fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, got `{s}`"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|&n| (1..=16384).contains(&n))
            .ok_or_else(|| format!("`{v}` in `{s}` is not a size between 1 and 16384"))
    };
    Ok((parse(w)?, parse(h)?))
}

#[derive(Args, Debug)]
pub struct BenchArgs {
    /// Named bench scenes (cornell, flight-helmet, spheres, crowd, env-lit, many-lights, furnace, grazing: fixed
    /// cameras) or glTF files (automatic camera); repeatable. Default: the suite's scenes.
    #[arg(long)]
    pub scene: Vec<String>,
    /// quick (tiny sizes, CI) or full (1920x1080 and 2560x1440 on a GPU; scaled down on a CPU adapter).
    #[arg(long, default_value = "quick")]
    pub suite: String,
    /// Folder of the shared glTF assets the named scenes come from.
    #[arg(long, default_value = "../shared/assets")]
    pub assets: PathBuf,
    /// Output folder: results.json, results.csv, curves.csv, summary.md, charts/*.png.
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
    /// Folder of cached high-spp reference images (keyed by a hash of scene, camera, settings, size, spp
    /// and kernel source).
    #[arg(long, default_value = "bench-cache")]
    pub cache: PathBuf,
    /// Run only these parts: frames, errors, bvh, refit, scaling, oidn (repeatable; default all).
    #[arg(long)]
    pub parts: Vec<String>,
    /// Override the suite's measured frame count (frame loop).
    #[arg(long)]
    pub frames: Option<usize>,
    #[arg(long, default_value_t = 6)]
    pub max_depth: u32,
    /// Path depth from which Russian roulette may end a path (see `render --help`).
    #[arg(long, default_value_t = default_rr_depth(), value_parser = at_least_one())]
    pub rr_depth: u32,
    /// Samples per pixel per frame of the frame loop and of the error part's default curve (an offline
    /// render's dispatch: `render --spp-per-dispatch`).
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u32).range(1..=1024))]
    pub spp_per_frame: u32,
    /// Shorthand for --scene crowd (64 CesiumMan + 32 Fox, animated, through the frame loop).
    #[arg(long)]
    pub crowd: bool,
    /// BVH layout of static meshes (see `render --help`).
    #[arg(long, value_enum, default_value_t = StaticBvh::Merged)]
    pub static_bvh: StaticBvh,
    /// How paths are traced (see `render --help`).
    #[arg(long, value_enum, default_value_t = IntegratorArg::Auto)]
    pub integrator: IntegratorArg,
    /// Override the suite's frame-loop sizes with one size.
    #[arg(long, value_parser = at_least_one(), allow_negative_numbers = true)]
    pub width: Option<u32>,
    #[arg(long, value_parser = at_least_one(), allow_negative_numbers = true)]
    pub height: Option<u32>,
    /// Where skinning, morphing and BVH refit run (see `render --help`).
    #[arg(long, value_enum, default_value_t = DeformArg::Auto)]
    pub deform: DeformArg,
    /// Error-vs-time part: measure only the curves whose name contains one of these (repeatable; the default
    /// curve is always measured). Default: every curve.
    #[arg(long)]
    pub curve: Vec<String>,
    /// Error-vs-time part: the largest spp of each curve (a power of two), instead of the suite's.
    #[arg(long, value_parser = at_least_one())]
    pub error_max_spp: Option<u32>,
    /// Write the static scenes for Mitsuba 3 into this folder (one subfolder per scene: geometry, textures,
    /// environment, camera, the error part's size and sample counts), then stop. Render them with
    /// `scripts/mitsuba-side-by-side.py DIR`, then compare with `--mitsuba DIR`.
    #[arg(long, value_name = "DIR")]
    pub export_mitsuba: Option<PathBuf>,
    /// Error-vs-time part: add the Mitsuba renders that `scripts/mitsuba-side-by-side.py` left in this folder
    /// (a curve per scene, and the side-by-side table: samples/s, variance, time to equal error).
    #[arg(long, value_name = "DIR")]
    pub mitsuba: Option<PathBuf>,
}

/// `--deform`: where deformable meshes are skinned, morphed and refit.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeformArg {
    /// GPU compute passes on a real GPU; the CPU on a software adapter (lavapipe), where it measured faster.
    Auto,
    Cpu,
    Gpu,
}

impl From<DeformArg> for raykin::gpu_deform::DeformBackend {
    fn from(a: DeformArg) -> Self {
        match a {
            DeformArg::Auto => Self::Auto,
            DeformArg::Cpu => Self::Cpu,
            DeformArg::Gpu => Self::Gpu,
        }
    }
}

/// Scene, camera and sampling options shared by the commands that render.
#[derive(Args, Debug, Clone)]
pub struct SceneArgs {
    /// A .gltf or .glb file.
    pub scene: PathBuf,
    /// Samples per pixel.
    #[arg(long, default_value_t = 64, value_parser = at_least_one(), allow_negative_numbers = true)]
    pub spp: u32,
    /// Surface interactions after the camera ray.
    #[arg(long, default_value_t = 6)]
    pub max_depth: u32,
    #[arg(long, default_value_t = 640, value_parser = at_least_one(), allow_negative_numbers = true)]
    pub width: u32,
    #[arg(long, default_value_t = 360, value_parser = at_least_one(), allow_negative_numbers = true)]
    pub height: u32,
    /// Index of the scene's camera to use (default: the first, else a framing of the scene).
    #[arg(long, conflicts_with = "look_from")]
    pub camera: Option<usize>,
    /// Camera position X,Y,Z (with --look-at; overrides the scene's cameras).
    #[arg(long, value_parser = parse_vec3, requires = "look_at", allow_hyphen_values = true)]
    pub look_from: Option<glam::Vec3>,
    /// Point the camera looks at, X,Y,Z.
    #[arg(long, value_parser = parse_vec3, requires = "look_from", allow_hyphen_values = true)]
    pub look_at: Option<glam::Vec3>,
    /// Vertical field of view in degrees (0 < FOV < 180), with --look-from.
    #[arg(long, default_value_t = 45.0, value_parser = parse_fov, allow_hyphen_values = true)]
    pub fov: f32,
    /// Constant environment radiance R,G,B (non-negative).
    #[arg(long, value_parser = parse_radiance, conflicts_with_all = ["sky", "env_map", "sun_sky"], allow_hyphen_values = true)]
    pub env: Option<glam::Vec3>,
    /// Sky-gradient environment (the default when no other environment is given).
    #[arg(long, conflicts_with_all = ["env_map", "sun_sky"])]
    pub sky: bool,
    /// Equirectangular HDR environment map (.hdr or .exr; Mitsuba 3's `envmap` orientation, +Y up), importance
    /// sampled.
    #[arg(long, conflicts_with = "sun_sky")]
    pub env_map: Option<PathBuf>,
    /// Turn the environment map about +Y by this many degrees (Mitsuba's `rotate([0, 1, 0], DEG)`).
    #[arg(
        long,
        default_value_t = 0.0,
        allow_negative_numbers = true,
        requires = "env_map"
    )]
    pub env_rotation: f32,
    /// Scale of the environment's radiance (map or sun and sky).
    #[arg(long, default_value_t = 1.0)]
    pub env_strength: f32,
    /// Physically based daylight: the Preetham sky and the sun at ELEVATION,AZIMUTH degrees (azimuth 0
    /// towards -Z, 90 towards +X). Physical units: a sunlit white surface is about 30; try --exposure -5.
    #[arg(long, value_parser = parse_pair)]
    pub sun_sky: Option<(f32, f32)>,
    /// Atmospheric turbidity of --sun-sky, 1.7 (very clear) to 10 (hazy).
    #[arg(long, default_value_t = 3.0, requires = "sun_sky")]
    pub turbidity: f32,
    /// Thin-lens aperture radius in scene units (glTF: metres); needs --focus-distance.
    #[arg(long, conflicts_with = "f_stop", requires = "focus_distance")]
    pub aperture: Option<f32>,
    /// Thin-lens f-number, converted to an aperture with a 35 mm full-frame sensor (24 mm tall) behind the
    /// camera's field of view, in a scene measured in metres; needs --focus-distance.
    #[arg(long, requires = "focus_distance")]
    pub f_stop: Option<f32>,
    /// Distance of the sharp plane along the view axis (with --aperture or --f-stop).
    #[arg(long)]
    pub focus_distance: Option<f32>,
    #[arg(long, default_value_t = 0)]
    pub seed: u32,
    /// Exposure in stops for PNG output (EXR is never exposed or tone-mapped).
    #[arg(long, default_value_t = 0.0, value_parser = parse_finite, allow_hyphen_values = true)]
    pub exposure: f32,
    /// Disable next-event estimation (BRDF sampling only).
    #[arg(long)]
    pub no_nee: bool,
    /// Disable Russian roulette.
    #[arg(long)]
    pub no_rr: bool,
    /// Path depth from which Russian roulette may end a path (Mitsuba's `rr_depth`; 1: from the first bounce).
    #[arg(long, default_value_t = default_rr_depth(), value_parser = at_least_one(), allow_negative_numbers = true)]
    pub rr_depth: u32,
    /// Pose time in seconds (clip 0 unless --animation); the same time always gives the same image.
    #[arg(long, value_parser = parse_finite, allow_hyphen_values = true)]
    pub time: Option<f32>,
    /// Animation clip by name or index.
    #[arg(long)]
    pub animation: Option<String>,
    /// Samples per pixel per GPU submission.
    #[arg(long, default_value_t = 16, value_parser = at_least_one(), allow_negative_numbers = true)]
    pub spp_per_dispatch: u32,
    /// Denoise the image: `oidn` (Intel Open Image Denoise on the albedo and normal AOVs; the default when
    /// the flag has no value) or `svgf` (the GPU a-trous filter guided by normal, depth and albedo). Where
    /// OIDN cannot run, svgf stands in with a warning.
    #[arg(long, value_enum, num_args = 0..=1, default_missing_value = "default", value_name = "DENOISER")]
    pub denoise: Option<DenoiseArg>,
    /// OIDN's quality: high (final frames), balanced or fast (previews).
    #[arg(long, value_enum, default_value_t = DenoiseQuality::High, value_name = "QUALITY")]
    pub denoise_quality: DenoiseQuality,
    /// How OIDN uses the albedo and normal AOVs: prefilter (denoise them first; OIDN's final-frame
    /// recommendation), noisy (as they are, possibly noisy) or clean (as they are, trusted as converged).
    #[arg(long, value_enum, default_value_t = DenoiseAovs::Prefilter, value_name = "MODE")]
    pub denoise_aovs: DenoiseAovs,
    /// Where skinning, morphing and BVH refit run: GPU compute passes or the CPU (the reference); auto
    /// picks the GPU on real GPUs and the CPU on a software adapter (lavapipe). The image is the same
    /// up to float rounding.
    #[arg(long, value_enum, default_value_t = DeformArg::Auto)]
    pub deform: DeformArg,
    /// BVH layout of static meshes: compressed 8-wide trees with the instances that never move merged into
    /// one (fastest: overlapping meshes stop costing a descent each), the same without the merge, or the
    /// refittable BVH2 deformable meshes refit (with `binary` they are traced through it too, not through the
    /// wide trees collapsed from it). The image is the same up to float rounding.
    #[arg(long, value_enum, default_value_t = StaticBvh::Merged)]
    pub static_bvh: StaticBvh,
    /// How paths are traced: one kernel per pixel's paths, or kernels per stage over a queue of the paths
    /// still alive (only where nothing but radiance is recorded: not with --denoise or --aovs), or by default
    /// whichever of the two the first frames time faster on this GPU (the megakernel on CPU adapters). The
    /// image is the same.
    #[arg(long, value_enum, default_value_t = IntegratorArg::Auto)]
    pub integrator: IntegratorArg,
}

/// `--integrator`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum IntegratorArg {
    /// The faster form on this GPU, scene and size, timed on the first frames; the megakernel on CPU adapters.
    Auto,
    Megakernel,
    Wavefront,
}

impl From<IntegratorArg> for raykin::render::Integrator {
    fn from(a: IntegratorArg) -> Self {
        match a {
            IntegratorArg::Auto => Self::Auto,
            IntegratorArg::Megakernel => Self::Megakernel,
            IntegratorArg::Wavefront => Self::Wavefront,
        }
    }
}

/// `--denoise [DENOISER]`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum DenoiseArg {
    /// The flag alone: the default denoiser.
    #[value(hide = true)]
    Default,
    Oidn,
    Svgf,
}

impl From<DenoiseArg> for raykin::render::DenoiserKind {
    fn from(a: DenoiseArg) -> Self {
        match a {
            DenoiseArg::Default => Self::default(),
            DenoiseArg::Oidn => Self::Oidn,
            DenoiseArg::Svgf => Self::Svgf,
        }
    }
}

/// `--denoise-quality`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum DenoiseQuality {
    High,
    Balanced,
    Fast,
}

impl From<DenoiseQuality> for raykin::oidn::Quality {
    fn from(q: DenoiseQuality) -> Self {
        match q {
            DenoiseQuality::High => Self::High,
            DenoiseQuality::Balanced => Self::Balanced,
            DenoiseQuality::Fast => Self::Fast,
        }
    }
}

/// `--denoise-aovs`.
#[derive(ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum DenoiseAovs {
    Prefilter,
    Noisy,
    Clean,
}

impl From<DenoiseAovs> for raykin::oidn::AuxMode {
    fn from(a: DenoiseAovs) -> Self {
        match a {
            DenoiseAovs::Prefilter => Self::Prefilter,
            DenoiseAovs::Noisy => Self::Noisy,
            DenoiseAovs::Clean => Self::Clean,
        }
    }
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq)]
pub enum StaticBvh {
    /// One compressed 8-wide tree per mesh, and the instances that never move merged into one more.
    Merged,
    /// One compressed 8-wide tree per mesh, every instance through the top level.
    Wide,
    /// The refittable BVH2 deformable meshes refit, per mesh (deformable meshes traced through theirs too).
    Binary,
}

impl StaticBvh {
    pub fn layout(self) -> raykin::bvh::StaticLayout {
        match self {
            StaticBvh::Merged | StaticBvh::Wide => raykin::bvh::StaticLayout::Wide,
            StaticBvh::Binary => raykin::bvh::StaticLayout::Binary,
        }
    }

    pub fn merged(self) -> bool {
        self == StaticBvh::Merged
    }
}

#[derive(Args, Debug)]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    // Beside, not inside, SceneArgs: clap never fills an optional flattened struct (record's) that
    // flattens another.
    #[command(flatten)]
    pub load: LoadArgs,
    /// Output image: .exr (linear radiance) or .png (tone-mapped sRGB).
    #[arg(long)]
    pub out: PathBuf,
    /// Also write first-hit AOVs next to the image: NAME.albedo.exr, NAME.normal.exr, NAME.depth.exr.
    #[arg(long)]
    pub aovs: bool,
    /// Write a JSON report (adapter, timings, memory) to this file.
    #[arg(long)]
    pub report: Option<PathBuf>,
}

#[derive(Args, Debug)]
#[command(mut_arg("scene", |a| a.required(false).required_unless_present("merge")))]
#[command(
    after_help = "Frame k is the pose at START + k/FPS with its own seed from (--seed, k); re-running the \
same command resumes. docs/RECORDING.md: files, manifest, motion vectors, Slurm arrays."
)]
pub struct RecordArgs {
    #[command(flatten)]
    pub scene: Option<SceneArgs>,
    #[command(flatten)]
    pub load: LoadArgs,
    /// Output folder: frame_00000.png|exr, AOVs (frame_00000.NAME.exr), manifest.json.
    #[arg(long, required_unless_present = "merge")]
    pub out: Option<PathBuf>,
    /// Frames per second of the recording (frame k is the pose at START + k/FPS).
    #[arg(long, default_value_t = 30.0, value_parser = parse_positive, allow_hyphen_values = true)]
    pub fps: f32,
    /// T0: seconds into the clip of frame 0.
    #[arg(long, default_value_t = 0.0, value_parser = parse_finite, allow_hyphen_values = true)]
    pub start: f32,
    /// T1: the frames cover [START, END) (default: the clip's end).
    #[arg(long, conflicts_with = "frames", value_parser = parse_finite, allow_hyphen_values = true)]
    pub end: Option<f32>,
    /// Number of frames instead of --end (required for a scene without animations).
    #[arg(long, value_parser = at_least_one(), allow_negative_numbers = true)]
    pub frames: Option<u32>,
    /// Render only frames A..B (A to B-1; also A..=B, A.., ..B), e.g. one task of a Slurm array.
    #[arg(long, value_parser = raykin::record::parse_range)]
    pub range: Option<(Option<u32>, Option<u32>)>,
    /// Sample each frame for this long instead of a fixed --spp (frames are then not bit-reproducible).
    #[arg(long, conflicts_with = "spp", value_parser = parse_positive_ms, allow_hyphen_values = true)]
    pub time_budget_ms: Option<f64>,
    /// png (tone-mapped sRGB) or exr (linear radiance).
    #[arg(long, default_value = "png")]
    pub format: raykin::record::FrameFormat,
    /// Extra linear EXR images per frame, comma-separated: albedo,normal,depth,motion.
    #[arg(long, value_delimiter = ',')]
    pub aovs: Vec<raykin::record::Aov>,
    /// Start a new recording in a folder that holds another one (its manifests are set aside, frames
    /// overwritten).
    #[arg(long)]
    pub force: bool,
    /// Encode the PNG frames into this video with ffmpeg once every frame is complete.
    #[arg(long)]
    pub video: Option<PathBuf>,
    /// Record what the viewer shows: the frames in sequence through the real-time path (one path per pixel
    /// per frame, history carried from frame to frame), instead of each frame converged on its own. Not
    /// resumable; writes DIR/realtime.json.
    #[arg(long, conflicts_with_all = ["range", "time_budget_ms", "merge", "aovs"])]
    pub realtime: bool,
    /// Fold the part manifests of --range runs in this folder into manifest.json and report missing frames.
    #[arg(long, conflicts_with_all = ["out", "range", "force"])]
    pub merge: Option<PathBuf>,
}

/// A constant environment radiance: three finite, non-negative numbers.
pub fn parse_radiance(s: &str) -> Result<glam::Vec3, String> {
    let v = parse_vec3(s)?;
    if v.min_element() < 0.0 {
        return Err(format!("`{s}`: radiance cannot be negative"));
    }
    Ok(v)
}

fn parse_positive_ms(s: &str) -> Result<f64, String> {
    parse_positive(s).map(f64::from)
}

pub fn parse_vec3(s: &str) -> Result<glam::Vec3, String> {
    let parts: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("`{p}`: {e}")))
        .collect::<Result<_, _>>()?;
    match parts[..] {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => {
            Ok(glam::Vec3::new(x, y, z))
        }
        _ => Err(format!("expected three finite numbers X,Y,Z, got `{s}`")),
    }
}

/// `A,B`: two finite numbers.
pub fn parse_pair(s: &str) -> Result<(f32, f32), String> {
    let parts: Vec<f32> = s
        .split(',')
        .map(|p| p.trim().parse::<f32>().map_err(|e| format!("`{p}`: {e}")))
        .collect::<Result<_, _>>()?;
    match parts[..] {
        [a, b] if a.is_finite() && b.is_finite() => Ok((a, b)),
        _ => Err(format!("expected two finite numbers A,B, got `{s}`")),
    }
}
