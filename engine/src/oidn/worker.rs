//! A thread that owns an [`Oidn`] and denoises one job at a time, so an interactive frame loop only hands
//! over a job (host images, or the accumulation's GPU buffers and a buffer for the result) and later picks up
//! the result. The device is opened on the thread at its first job; every wait (for the GPU, for OIDN) happens
//! on the thread.

use super::device::DeviceRequest;
use super::{DenoiseOptions, Denoised, Oidn, OidnError, OidnInputs};
use crate::gpu::GpuContext;
use crate::render::passes::denoiser_planes::DenoiserSources;
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};

/// What to denoise; `tag` comes back with the result.
pub struct Job<T> {
    pub tag: T,
    pub source: Source,
    pub options: DenoiseOptions,
}

/// What a job denoises, and where its result goes.
pub enum Source {
    /// Host images; the result comes back as a host image ([`Denoised::color`]).
    Host(OidnInputs),
    /// The accumulation on the GPU; the result is written into `shown` (the display's layout,
    /// `render::HostDenoised::image_buffer`) and [`Denoised::color`] stays empty. In GPU memory shared with
    /// OIDN where its device allows (`super::shared`), else through host copies made on the thread.
    Gpu(Box<GpuJob>),
}

/// A [`Source::Gpu`] job's buffers (boxed: the device context is large beside a host image's handles).
pub struct GpuJob {
    pub ctx: GpuContext,
    pub sources: DenoiserSources,
    pub shown: wgpu::Buffer,
}

/// A finished job.
pub struct Done<T> {
    pub tag: T,
    pub result: Result<Denoised, OidnError>,
    /// The device that ran it ("CUDA NVIDIA H200"), and notes from opening it.
    pub device: String,
    pub notes: Vec<String>,
    /// A [`Source::Gpu`] job's buffer, holding the result when `result` is Ok.
    pub shown: Option<wgpu::Buffer>,
    /// The job ran in GPU memory shared with OIDN (nothing went through the host).
    pub shared_memory: bool,
    /// Milliseconds spent copying a [`Source::Gpu`] job's accumulation to the host (0 when shared).
    pub readback_ms: f64,
}

pub struct OidnWorker<T> {
    jobs: Option<Sender<Job<T>>>,
    /// Behind a lock only so that the worker can live in an ECS resource (which must be `Sync`).
    done: Mutex<Receiver<Done<T>>>,
    thread: Option<std::thread::JoinHandle<()>>,
    in_flight: usize,
}

impl<T: Send + 'static> OidnWorker<T> {
    pub fn spawn(request: DeviceRequest) -> Self {
        let (jobs, job_rx) = channel::<Job<T>>();
        let (done_tx, done) = channel();
        let thread = std::thread::Builder::new()
            .name("oidn".into())
            .spawn(move || {
                let mut oidn: Option<Result<Oidn, OidnError>> = None;
                let mut shared_failed = false;
                while let Ok(job) = job_rx.recv() {
                    let opened = oidn.get_or_insert_with(|| Oidn::new(&request));
                    let mut done = Done {
                        tag: job.tag,
                        result: Err(OidnError::Input("not run".into())),
                        device: String::new(),
                        notes: Vec::new(),
                        shown: None,
                        shared_memory: false,
                        readback_ms: 0.0,
                    };
                    match (opened, job.source) {
                        (Err(e), _) => done.result = Err(e.clone()),
                        (Ok(o), Source::Host(inputs)) => {
                            done.result = o.denoise(&inputs.images(), &job.options);
                        }
                        (Ok(o), Source::Gpu(gpu)) => {
                            let GpuJob {
                                ctx,
                                sources,
                                shown,
                            } = *gpu;
                            let into = super::shared::denoise_sources_into(
                                o,
                                &ctx,
                                &mut shared_failed,
                                (&sources, &shown),
                                &job.options,
                                true,
                            )
                            .expect("through the host where memory is not shared");
                            done.result = into.result;
                            done.shared_memory = into.shared_memory;
                            done.readback_ms = into.readback_ms;
                            done.shown = Some(shown);
                        }
                    }
                    if let Some(Ok(o)) = &mut oidn {
                        done.device = o.device_description();
                        done.notes = std::mem::take(&mut o.notes);
                    }
                    if done_tx.send(done).is_err() {
                        break;
                    }
                }
            })
            .ok();
        Self {
            jobs: Some(jobs),
            done: Mutex::new(done),
            thread,
            in_flight: 0,
        }
    }

    /// Queues a job; false when the thread is gone (it could not start).
    pub fn submit(&mut self, job: Job<T>) -> bool {
        let sent = self
            .jobs
            .as_ref()
            .is_some_and(|jobs| jobs.send(job).is_ok());
        self.in_flight += usize::from(sent);
        sent
    }

    /// Jobs submitted and not yet returned by [`Self::poll`].
    pub fn in_flight(&self) -> usize {
        self.in_flight
    }

    /// A finished job, without waiting.
    pub fn poll(&mut self) -> Option<Done<T>> {
        let done = self.done.get_mut().unwrap_or_else(|p| p.into_inner());
        match done.try_recv() {
            Ok(done) => {
                self.in_flight -= 1;
                Some(done)
            }
            Err(TryRecvError::Empty | TryRecvError::Disconnected) => None,
        }
    }

    /// Waits for the next finished job (tests, and callers that have nothing else to do).
    pub fn wait(&mut self) -> Option<Done<T>> {
        if self.in_flight == 0 {
            return None;
        }
        let done = self.done.get_mut().unwrap_or_else(|p| p.into_inner());
        let done = done.recv().ok()?;
        self.in_flight -= 1;
        Some(done)
    }
}

impl<T> Drop for OidnWorker<T> {
    fn drop(&mut self) {
        // Closing the channel ends the thread after its current job.
        self.jobs = None;
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
