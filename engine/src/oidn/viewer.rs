//! OIDN in the viewer: once the image has settled (the accumulation outlived a frame and reached
//! [`SETTLE_SPP`], or the sample limit), its buffers are copied to the host without waiting for the GPU,
//! denoised on a worker thread, and shown in place of the svgf image until the accumulation restarts. It runs
//! again each time the sample count doubles, and once more at the sample limit. While the camera or an
//! animation moves, the display shows svgf's image: OIDN is never waited for by the frame loop.

use super::Timings;
use super::device::{AdapterIdentity, DeviceRequest};
use super::worker::{Job, OidnWorker};
use crate::FrameSet;
use crate::gpu::GpuContext;
use crate::gpu::readback::AsyncReadback;
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
    /// Showing the image of `samples` spp, denoised on `device` in `timings`.
    Shown {
        samples: u32,
        device: String,
        timings: Timings,
    },
    /// OIDN cannot run here; the svgf image is shown.
    Unavailable(String),
}

/// The viewer's OIDN state (a resource, with [`OidnViewerPlugin`]).
#[derive(Resource, Default)]
pub struct ViewerOidn {
    worker: Option<OidnWorker<Key>>,
    /// A copy of the accumulation on its way to the host.
    readback: Option<(Key, AsyncReadback)>,
    /// The last copy's staging buffer, kept for the next copy of the same size: allocating it (170 MB of
    /// host-visible memory at 2560x1440) took about 40 ms of the frame on the H200.
    spare_readback: Option<AsyncReadback>,
    shown: Option<Key>,
    /// A result was handed to the display this frame: one more frame must run to show it.
    fresh: bool,
    pub status: OidnStatus,
}

impl ViewerOidn {
    /// A copy or a denoise is under way: the frame loop should keep running to show its result.
    pub fn busy(&self) -> bool {
        self.fresh
            || self.readback.is_some()
            || self.worker.as_ref().is_some_and(|w| w.in_flight() > 0)
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

/// The viewer's OIDN step: hand arrived results to the display, arrived copies to the worker, and start a
/// copy when due.
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
                oidn.fresh = host.show(&ctx, &view, &accumulation, &image.color);
                oidn.shown = Some(done.tag);
                oidn.status = OidnStatus::Shown {
                    samples: done.tag.2,
                    device: done.device,
                    timings: image.timings,
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
    if let Some((key, readback)) = &mut oidn.readback {
        if let Some((_, bytes)) = readback.poll(&ctx).pop() {
            let key = *key;
            oidn.spare_readback = oidn.readback.take().map(|(_, r)| r);
            if (key.0, key.1) == current {
                let job = Job {
                    tag: key,
                    inputs: super::inputs::inputs_from_planes(view.width, view.height, &bytes),
                    options: settings.oidn,
                };
                if !worker.submit(job) {
                    oidn.status =
                        OidnStatus::Unavailable("the denoising thread could not start".into());
                }
            }
        }
        return;
    }
    let key = (current.0, current.1, accumulation.samples);
    if worker.in_flight() > 0 || !oidn.due(key, settings.spp_per_frame, accumulation.sample_limit) {
        return;
    }
    let plane = view.accum.size();
    let mut readback = match oidn.spare_readback.take() {
        Some(r) if r.size() == 3 * plane => r,
        _ => AsyncReadback::new(&ctx, "oidn inputs", 3 * plane, 1),
    };
    let mut encoder = ctx.device.create_command_encoder(&Default::default());
    let sources = [
        (&view.accum, 0, plane),
        (&view.albedo_depth, plane, plane),
        (&view.normal_hits, 2 * plane, plane),
    ];
    if readback.encode(&mut encoder, &sources, 0) {
        ctx.queue.submit([encoder.finish()]);
        readback.after_submit();
        oidn.readback = Some((key, readback));
        oidn.status = OidnStatus::Denoising(key.2);
    } else {
        oidn.spare_readback = Some(readback);
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
