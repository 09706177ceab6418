//! `raykin record`: the command line around [`raykin::record::Recorder`]: arguments, a progress bar, Ctrl-C,
//! a summary, `--merge` and the optional ffmpeg encode.

use crate::adapter::open_gpu;
use crate::cli::RecordArgs;
use crate::outputs::Output;
use crate::render_cmd::{camera_spec, check_scene, check_size, settings_from};
use crate::scenes::load_scene;
use anyhow::{Context, Result, bail};
use indicatif::{ProgressBar, ProgressStyle};
use raykin::record::{
    FrameFormat, FrameOptions, RecordEvent, RecordJob, RecordRequest, RecordSummary, Recorder,
    Sampling,
};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// `--realtime`: the frames in sequence through the real-time path, then the optional video.
fn record_realtime(
    scene: Arc<raykin::scene::SceneAsset>,
    settings: &raykin::record::RecordSettings,
    out: &Path,
    video: Option<&Path>,
) -> Result<ExitCode> {
    let ctx = open_gpu()?;
    let cancel = Arc::new(AtomicBool::new(false));
    install_interrupt_handler(cancel.clone());
    let bar = progress_bar(settings.frames as u64);
    let recording =
        raykin::record::record_realtime(ctx, scene, settings, out, &cancel, &mut |done| {
            bar.set_position(done as u64)
        })?;
    bar.finish_and_clear();
    let mut ms = recording.frame_ms.clone();
    ms.sort_by(f64::total_cmp);
    eprintln!(
        "raykin: real-time recording: {} frames in {}, {:.1} ms per frame median (pose, frame, readback, write)",
        recording.files.len(),
        out.display(),
        ms.get(ms.len() / 2).copied().unwrap_or(0.0)
    );
    if recording.interrupted {
        eprintln!("raykin: interrupted: a real-time recording cannot resume; run it again whole");
        return Ok(ExitCode::from(EXIT_INTERRUPTED));
    }
    if let Some(video) = video {
        encode_video(out, settings.fps, video)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// Exit status of a run stopped by Ctrl-C (128 + SIGINT, as shells report it).
const EXIT_INTERRUPTED: u8 = 130;

pub fn main(args: &RecordArgs) -> ExitCode {
    match run(args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("raykin: error: {e:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(args: &RecordArgs) -> Result<ExitCode> {
    if let Some(dir) = &args.merge {
        return merge(dir, args.video.as_deref());
    }
    let (Some(scene_args), Some(out)) = (&args.scene, &args.out) else {
        bail!("record needs a scene file and --out DIR (or --merge DIR)");
    };
    if scene_args.time.is_some() {
        bail!(
            "--time poses a single image (raykin render); a recording is set by --start, --end or --frames, \
             and --fps"
        );
    }
    if let Some(video) = &args.video {
        check_video(video, args.format)?;
    }
    let scene = load_scene(&scene_args.scene, &args.load.options())?;
    crate::outputs::refuse_recording_over_inputs(out, &scene.files)?;
    if let Some(video) = &args.video {
        let video = Output {
            what: "--video",
            path: video.clone(),
        };
        crate::outputs::refuse_overwrites(&[video], &scene.files)?;
    }
    check_scene(&scene, &camera_spec(scene_args).choice())?;
    let request = RecordRequest {
        animation: scene_args.animation.clone(),
        fps: args.fps,
        start: args.start,
        end: args.end,
        frames: args.frames,
        frame: FrameOptions {
            sampling: match args.time_budget_ms {
                Some(ms) => Sampling::TimeBudgetMs(ms),
                None => Sampling::Spp(scene_args.spp),
            },
            spp_per_dispatch: scene_args.spp_per_dispatch,
            camera: camera_spec(scene_args),
            format: args.format,
            aovs: args.aovs.clone(),
            render: settings_from(scene_args, &scene)?,
        },
        scene: args.load.scene_index,
    };
    let settings = raykin::record::plan(&scene, &request)?;
    if settings.clip.is_none() {
        eprintln!(
            "raykin: note: {} has no animations: recording {} frames of the still scene, each with its own seed",
            scene.source, settings.frames
        );
    }
    if args.realtime {
        return record_realtime(scene, &settings, out, args.video.as_deref());
    }
    let slice = args
        .range
        .map(|r| raykin::record::resolve_range(&settings, r))
        .transpose()?;
    let job = RecordJob {
        scene,
        scene_label: scene_args.scene.display().to_string(),
        scene_hash: raykin::record::scene_hash(&scene_args.scene)?,
        settings: settings.clone(),
        dir: out.clone(),
        slice,
        force: args.force,
    };
    let recorder = Recorder::prepare(job)?;
    let range = recorder.range();
    let summary = if recorder.todo().is_empty() {
        eprintln!(
            "raykin: frames {}..{} in {} are already complete; nothing to render",
            range.start,
            range.end,
            out.display()
        );
        None
    } else {
        let ctx = open_gpu()?;
        check_size(
            &ctx,
            settings.frame.render.width,
            settings.frame.render.height,
        )?;
        let cancel = Arc::new(AtomicBool::new(false));
        install_interrupt_handler(cancel.clone());
        let bar = progress_bar(range.len() as u64);
        let summary = recorder.run(ctx, &cancel, &mut |event| show(&bar, event))?;
        bar.finish_and_clear();
        print_summary(&summary);
        if summary.interrupted {
            eprintln!(
                "raykin: interrupted: {} of {} frames complete; re-run the same command to resume",
                summary.complete, summary.frame_count
            );
            return Ok(ExitCode::from(EXIT_INTERRUPTED));
        }
        Some(summary)
    };
    if let Some(video) = &args.video {
        let complete = summary.as_ref().map_or_else(
            || {
                raykin::record::manifest::read_all(out)
                    .map(|m| raykin::record::manifest::verified_frames(out, &m).len())
                    .unwrap_or(0)
            },
            |s| s.complete,
        );
        if complete == settings.frames as usize {
            encode_video(out, settings.fps, video)?;
        } else {
            eprintln!(
                "raykin: --video: {complete} of {} frames are complete; encode after the other slices with \
                 `raykin record --merge {} --video {}`",
                settings.frames,
                out.display(),
                video.display()
            );
        }
    }
    Ok(ExitCode::SUCCESS)
}

fn install_interrupt_handler(cancel: Arc<AtomicBool>) {
    let result = ctrlc::set_handler(move || {
        if cancel.swap(true, Ordering::SeqCst) {
            eprintln!("\nraykin: interrupted again: quitting now");
            std::process::exit(EXIT_INTERRUPTED as i32);
        }
        eprintln!(
            "\nraykin: interrupt: stopping after the frame being written (a frame still sampling is abandoned); \
             interrupt again to quit at once"
        );
    });
    if let Err(e) = result {
        eprintln!("raykin: warning: cannot catch Ctrl-C ({e}); an interrupt stops at once");
    }
}

fn progress_bar(frames: u64) -> ProgressBar {
    let bar = ProgressBar::new(frames);
    bar.set_style(
        ProgressStyle::with_template(
            "recording [{bar:30}] frame {pos}/{len}, {elapsed} elapsed, ETA {eta}  {msg}",
        )
        .expect("static template")
        .progress_chars("=> "),
    );
    bar
}

fn show(bar: &ProgressBar, event: RecordEvent) {
    match event {
        RecordEvent::Started {
            range,
            todo,
            skipped,
        } => {
            if skipped > 0 {
                eprintln!(
                    "raykin: resuming: {skipped} of {} frames in {}..{} already complete, {todo} to render",
                    range.len(),
                    range.start,
                    range.end
                );
            }
            bar.set_position(skipped as u64);
            bar.reset_eta();
        }
        RecordEvent::Samples { frame, spp } => bar.set_message(format!("frame {frame}: {spp} spp")),
        RecordEvent::FrameDone { frame, done, todo } => {
            bar.inc(1);
            let line = format!(
                "frame {} done ({done}/{todo}): {:.0} ms, {} spp",
                frame.index, frame.render_ms, frame.spp
            );
            // Logs (a batch job's stderr) get one line per frame instead of a bar.
            if bar.is_hidden() {
                eprintln!("raykin: {line}");
            }
            bar.set_message(line);
        }
    }
}

fn print_summary(s: &RecordSummary) {
    for note in &s.notes {
        eprintln!("raykin: note: {note}");
    }
    if s.rendered == 0 {
        return;
    }
    let mean = s.frame_ms.iter().sum::<f64>() / s.rendered as f64;
    let (lo, hi) = s
        .frame_ms
        .iter()
        .fold((f64::MAX, 0f64), |(lo, hi), &v| (lo.min(v), hi.max(v)));
    let (spp_lo, spp_hi) = (
        s.spp.iter().min().copied().unwrap_or(0),
        s.spp.iter().max().copied().unwrap_or(0),
    );
    let spp = if spp_lo == spp_hi {
        format!("{spp_lo} spp")
    } else {
        format!("{spp_lo}-{spp_hi} spp")
    };
    eprintln!(
        "raykin: rendered {} frame(s) of {}..{} in {:.1} s ({} skipped): {mean:.0} ms per frame (min {lo:.0}, max \
         {hi:.0}), {spp}; {} of {} frames of the recording complete; manifest {}",
        s.rendered,
        s.range.start,
        s.range.end,
        s.wall_seconds,
        s.skipped,
        s.complete,
        s.frame_count,
        s.manifest.display()
    );
}

fn merge(dir: &Path, video: Option<&Path>) -> Result<ExitCode> {
    let summary = raykin::record::merge(dir)?;
    eprintln!(
        "raykin: merged {} part manifest(s) into {}: {} of {} frames complete{}{}",
        summary.parts_merged,
        summary.manifest.display(),
        summary.complete,
        summary.frame_count,
        if summary.partials_removed > 0 {
            format!(
                "; removed {} temporary file(s) of interrupted writes",
                summary.partials_removed
            )
        } else {
            String::new()
        },
        if summary.adapters.len() > 1 {
            format!(
                "; rendered on {} adapters: {}",
                summary.adapters.len(),
                summary.adapters.join(" | ")
            )
        } else {
            String::new()
        }
    );
    if !summary.missing.is_empty() {
        bail!(
            "{}: {} frame(s) missing ({}{}); re-run the slices that own them (or the whole command) to render them",
            dir.display(),
            summary.missing.len(),
            summary
                .missing
                .iter()
                .take(20)
                .map(u32::to_string)
                .collect::<Vec<_>>()
                .join(", "),
            if summary.missing.len() > 20 {
                ", ..."
            } else {
                ""
            }
        );
    }
    if let Some(video) = video {
        let manifest = raykin::record::manifest::read_all(dir)?
            .into_iter()
            .next()
            .context("the merged manifest disappeared")?
            .1;
        check_video(video, manifest.settings.frame.format)?;
        encode_video(dir, manifest.settings.fps, video)?;
    }
    Ok(ExitCode::SUCCESS)
}

/// `--video` prerequisites, checked before any rendering.
fn check_video(video: &Path, format: FrameFormat) -> Result<()> {
    if format != FrameFormat::Png {
        bail!(
            "--video {}: encodes PNG frames; record with --format png (EXR frames are linear radiance)",
            video.display()
        );
    }
    let found = Command::new("ffmpeg")
        .arg("-version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !found {
        bail!(
            "--video {}: ffmpeg is not on PATH (Debian/Ubuntu: apt-get install ffmpeg); nothing was rendered",
            video.display()
        );
    }
    Ok(())
}

/// Encodes DIR/frame_%05d.png at `fps` into `video` (written to a temporary name, then renamed).
fn encode_video(dir: &Path, fps: f32, video: &Path) -> Result<()> {
    let name = video
        .file_name()
        .context("--video needs a file name")?
        .to_string_lossy();
    let ext = video
        .extension()
        .map_or(String::new(), |e| format!(".{}", e.to_string_lossy()));
    let tmp: PathBuf = video.with_file_name(format!(".{name}.partial{ext}"));
    let output = Command::new("ffmpeg")
        .args(["-hide_banner", "-loglevel", "error", "-y", "-framerate"])
        .arg(fps.to_string())
        .arg("-i")
        .arg(dir.join("frame_%05d.png"))
        // yuv420p (what players expect) needs even sizes.
        .args([
            "-vf",
            "pad=ceil(iw/2)*2:ceil(ih/2)*2",
            "-pix_fmt",
            "yuv420p",
        ])
        .arg(&tmp)
        .output()
        .context("cannot run ffmpeg")?;
    if !output.status.success() {
        let _ = std::fs::remove_file(&tmp);
        bail!(
            "ffmpeg could not encode {}: {}",
            video.display(),
            String::from_utf8_lossy(&output.stderr).trim()
        );
    }
    std::fs::rename(&tmp, video)
        .with_context(|| format!("{}: cannot write it", video.display()))?;
    eprintln!("raykin: encoded {}", video.display());
    Ok(())
}
