//! OIDN in the viewer: once the image has settled (the accumulation outlived a frame and reached
//! [`SETTLE_SPP`], or the sample limit), a worker thread denoises it, in GPU memory shared with OIDN where its
//! device allows (nothing crosses to the host; `super::shared`), else from host copies it makes itself, and
//! writes the result into a GPU buffer the display shows in place of the svgf image until the accumulation
//! restarts. It runs again each time the sample count doubles, and once more at the sample limit. While the
//! camera or an animation moves, the display shows svgf's image: OIDN is never waited for by the frame loop.

use super::Timings;
use super::device::{AdapterIdentity, DeviceRequest};
use super::worker::{GpuJob, Job, OidnWorker, Source};
use crate::FrameSet;
use crate::gpu::GpuContext;
use crate::render::{
    Accumulation, AovView, DenoiserKind, HostDenoised, RenderSettings, ViewTargets,
};
use bevy_app::{App, Plugin, Update};
use bevy_ecs::prelude::*;

/// Samples per pixel at which a still image is first denoised by OIDN.
pub const SETTLE_SPP: u32 = 16;

/// (view generation, accumulation, samples): which image a copy or a result belongs to.
type Key = (u64, u64, u32);

/// What the Render panel shows about OIDN.
#[derive(Clone, Debug, Default, PartialEq)]
pub enum OidnStatus {
    #[default]
    Idle,
    /// Copying or denoising the image of this many samples per pixel.
    Denoising(u32),
    /// Showing the image of `samples` spp, denoised on `device` in `timings` (plus `readback_ms` of host
    /// copies, 0 when OIDN shared the GPU's memory).
    Shown {
        samples: u32,
        device: String,
        timings: Timings,
        shared_memory: bool,
        readback_ms: f64,
    },
    /// OIDN cannot run here; the svgf image is shown.
    Unavailable(String),
}

/// The viewer's OIDN state (a resource, with [`OidnViewerPlugin`]).
#[derive(Resource, Default)]
pub struct ViewerOidn {
    worker: Option<OidnWorker<Key>>,
    shown: Option<Key>,
    /// A result was handed to the display this frame: one more frame must run to show it.
    fresh: bool,
    pub status: OidnStatus,
}

impl ViewerOidn {
    /// A copy or a denoise is under way: the frame loop should keep running to show its result.
    pub fn busy(&self) -> bool {
        self.fresh || self.worker.as_ref().is_some_and(|w| w.in_flight() > 0)
    }

    /// Whether to denoise now: the image is still (it outlived this frame's samples) and has reached
    /// [`SETTLE_SPP`] or the sample limit, and no result for this accumulation is shown at half its samples
    /// or more (or, at the limit, at fewer samples).
    fn due(&self, key: Key, spp_per_frame: u32, limit: Option<u32>) -> bool {
        let samples = key.2;
        let at_limit = limit.is_some_and(|l| samples >= l);
        if samples <= spp_per_frame && !at_limit {
            return false;
        }
        if samples < SETTLE_SPP.min(limit.unwrap_or(u32::MAX)) {
            return false;
        }
        match self.shown {
            Some(s) if (s.0, s.1) == (key.0, key.1) => {
                samples >= 2 * s.2 || (at_limit && s.2 < samples)
            }
            _ => true,
        }
    }
}

/// Adds [`ViewerOidn`] and its per-frame system (after the trace and display passes).
pub struct OidnViewerPlugin;

impl Plugin for OidnViewerPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ViewerOidn>().add_systems(
            Update,
            denoise_still_image
                .in_set(FrameSet::Render)
                .after(crate::render::frame::render_frame),
        );
    }
}

/// The viewer's OIDN step: hand arrived results to the display, and hand the worker the accumulation when due.
pub fn denoise_still_image(
    ctx: Res<GpuContext>,
    settings: Res<RenderSettings>,
    view: Res<ViewTargets>,
    accumulation: Res<Accumulation>,
    host: Res<HostDenoised>,
    mut oidn: ResMut<ViewerOidn>,
) {
    oidn.fresh = false;
    let wanted = settings.denoise
        && settings.denoiser == DenoiserKind::Oidn
        && settings.view == AovView::Color;
    if !wanted || matches!(oidn.status, OidnStatus::Unavailable(_)) {
        return;
    }
    let oidn = &mut *oidn;
    let current = (view.generation, accumulation.epoch);
    let worker = oidn.worker.get_or_insert_with(|| {
        OidnWorker::spawn(DeviceRequest::MatchAdapter(AdapterIdentity::from_wgpu(
            &ctx.info,
        )))
    });
    while let Some(done) = worker.poll() {
        for note in &done.notes {
            tracing::warn!("{note}");
        }
        match done.result {
            Ok(image) if (done.tag.0, done.tag.1) == current => {
                // The next frame's display transform shows it, also when the viewer then goes idle.
                oidn.fresh = done
                    .shown
                    .is_some_and(|b| host.show_buffer(&view, &accumulation, b));
                oidn.shown = Some(done.tag);
                oidn.status = OidnStatus::Shown {
                    samples: done.tag.2,
                    device: done.device,
                    timings: image.timings,
                    shared_memory: done.shared_memory,
                    readback_ms: done.readback_ms,
                };
            }
            // The accumulation restarted while it was denoised.
            Ok(_) => oidn.status = OidnStatus::Idle,
            Err(e) => {
                tracing::warn!("{e}; the viewer shows the svgf denoiser's image instead");
                oidn.status = OidnStatus::Unavailable(e.to_string());
                return;
            }
        }
    }
    let key = (current.0, current.1, accumulation.samples);
    let busy = worker.in_flight() > 0;
    if busy || !oidn.due(key, settings.spp_per_frame, accumulation.sample_limit) {
        return;
    }
    let job = Job {
        tag: key,
        source: Source::Gpu(Box::new(GpuJob {
            ctx: ctx.clone(),
            sources: view.denoiser_sources(),
            shown: HostDenoised::image_buffer(&ctx, &view),
        })),
        options: settings.oidn,
    };
    let worker = oidn.worker.as_mut().expect("spawned above");
    if worker.submit(job) {
        oidn.status = OidnStatus::Denoising(key.2);
    } else {
        oidn.status = OidnStatus::Unavailable("the denoising thread could not start".into());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_still_image_is_denoised_at_the_threshold_then_at_each_doubling_and_at_the_limit() {
        let mut v = ViewerOidn::default();
        let key = |samples| (1, 7, samples);
        // Restarted this frame (samples = samples per frame): moving.
        assert!(!v.due(key(SETTLE_SPP), SETTLE_SPP, None));
        assert!(!v.due(key(SETTLE_SPP - 1), 1, None));
        assert!(v.due(key(SETTLE_SPP), 1, None));
        v.shown = Some(key(SETTLE_SPP));
        assert!(!v.due(key(2 * SETTLE_SPP - 1), 1, None));
        assert!(v.due(key(2 * SETTLE_SPP), 1, None));
        // At the sample limit it runs once more for the final count, then stops.
        assert!(v.due(key(SETTLE_SPP + 4), 1, Some(SETTLE_SPP + 4)));
        v.shown = Some(key(SETTLE_SPP + 4));
        assert!(!v.due(key(SETTLE_SPP + 4), 1, Some(SETTLE_SPP + 4)));
        // A limit below the threshold is the threshold; a new accumulation starts over.
        assert!(v.due((1, 8, 4), 4, Some(4)));
        assert!(v.due((1, 8, SETTLE_SPP), 1, None));
    }
}
