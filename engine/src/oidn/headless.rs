//! OIDN for renders that wait for their image (`raykin render`, `record`, benches, tests): the device is
//! opened on first use and kept, and the last result is kept per accumulation so that writing an EXR and a
//! PNG of the same image denoises once.

use super::device::{AdapterIdentity, DeviceRequest};
use super::{DenoiseOptions, Oidn, OidnError, Timings, read_inputs};
use crate::gpu::GpuContext;
use crate::render::{Accumulation, ViewTargets};
use bevy_ecs::prelude::Resource;
use std::sync::{Arc, Mutex};

/// A denoised accumulation and what it cost.
#[derive(Clone, Debug)]
pub struct OidnImage {
    pub color: Arc<Vec<[f32; 3]>>,
    pub timings: Timings,
    /// GPU-to-host copy of the accumulation and AOV buffers (0 with shared GPU memory: nothing is copied).
    pub readback_ms: f64,
    pub samples: u32,
    /// The OIDN device that ran it.
    pub device: String,
    /// OIDN read its inputs from GPU memory it shares with wgpu instead of host copies (`super::shared`).
    pub shared_memory: bool,
}

impl OidnImage {
    /// Everything from the GPU buffers to the denoised host image.
    pub fn total_ms(&self) -> f64 {
        self.readback_ms + self.timings.total_ms()
    }

    /// [`Self::total_ms`] without the one-time filter set-up: the cost of each further image of this size.
    pub fn steady_ms(&self) -> f64 {
        self.total_ms() - self.timings.setup_ms
    }
}

/// (view generation, accumulation, samples, options): what an image was denoised from.
type Key = (u64, u64, u32, DenoiseOptions);

#[derive(Default)]
struct State {
    oidn: Option<Result<Oidn, OidnError>>,
    last: Option<(Key, OidnImage)>,
    /// Denoising from shared GPU memory failed once (then the host path serves every later image).
    shared_failed: bool,
}

/// The app's OIDN device (a resource of every [`crate::headless::HeadlessApp`]).
#[derive(Resource, Default)]
pub struct HeadlessOidn {
    state: Mutex<State>,
    /// Which device to open; `None`: the one matching the app's adapter.
    pub request: Option<DeviceRequest>,
}

impl HeadlessOidn {
    /// OIDN on the requested device instead of the one matching the adapter.
    pub fn on(request: DeviceRequest) -> Self {
        Self {
            request: Some(request),
            ..Default::default()
        }
    }

    /// Opens the device if not yet done: its description, with notes (a GPU that failed over to the CPU), or
    /// why OIDN cannot run.
    pub fn open(&self, ctx: &GpuContext) -> Result<String, OidnError> {
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        let request = self
            .request
            .clone()
            .unwrap_or_else(|| DeviceRequest::MatchAdapter(AdapterIdentity::from_wgpu(&ctx.info)));
        match state.oidn.get_or_insert_with(|| Oidn::new(&request)) {
            Ok(o) => {
                let mut text = o.device_description();
                for note in &o.notes {
                    text.push_str(&format!(" ({note})"));
                }
                Ok(text)
            }
            Err(e) => Err(e.clone()),
        }
    }

    /// The view's current accumulation through OIDN with `options`. Blocks for the readback and the filter.
    pub fn denoise(
        &self,
        ctx: &GpuContext,
        view: &ViewTargets,
        accumulation: &Accumulation,
        options: DenoiseOptions,
    ) -> Result<OidnImage, OidnError> {
        self.open(ctx)?;
        let key = (
            view.generation,
            accumulation.epoch,
            accumulation.samples,
            options,
        );
        let mut state = self.state.lock().unwrap_or_else(|p| p.into_inner());
        if let Some((k, image)) = &state.last
            && *k == key
        {
            return Ok(image.clone());
        }
        let state = &mut *state;
        let Some(Ok(oidn)) = state.oidn.as_mut() else {
            unreachable!("opened above")
        };
        let shared = super::shared::attempt(oidn, ctx, &mut state.shared_failed, |o| {
            super::shared::denoise_view(o, ctx, &view.denoiser_sources(), &options)
        });
        let shared_memory = shared.is_some();
        let (denoised, readback_s, samples) = match shared {
            Some(d) => (d, 0.0, accumulation.samples),
            None => {
                let (inputs, readback_s) = read_inputs(ctx, view);
                (
                    oidn.denoise(&inputs.images(), &options)?,
                    readback_s,
                    inputs.samples,
                )
            }
        };
        if denoised.repaired > 0 {
            tracing::warn!(
                "Open Image Denoise returned {} non-finite pixels; they keep their noisy value",
                denoised.repaired
            );
        }
        let image = OidnImage {
            color: Arc::new(denoised.color),
            timings: denoised.timings,
            readback_ms: readback_s * 1e3,
            samples,
            device: oidn.device_description(),
            shared_memory,
        };
        state.last = Some((key, image.clone()));
        Ok(image)
    }
}
