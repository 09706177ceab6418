//! A thread that owns an [`Oidn`] and denoises one job at a time, so an interactive frame loop only hands
//! over host images and later picks up the result. The device is opened on the thread at its first job.

use super::device::DeviceRequest;
use super::{DenoiseOptions, Denoised, Oidn, OidnError, OidnInputs};
use std::sync::Mutex;
use std::sync::mpsc::{Receiver, Sender, TryRecvError, channel};

/// What to denoise; `tag` comes back with the result.
pub struct Job<T> {
    pub tag: T,
    pub inputs: OidnInputs,
    pub options: DenoiseOptions,
}

/// A finished job.
pub struct Done<T> {
    pub tag: T,
    pub result: Result<Denoised, OidnError>,
    /// The device that ran it ("CUDA NVIDIA H200"), and notes from opening it.
    pub device: String,
    pub notes: Vec<String>,
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
                while let Ok(job) = job_rx.recv() {
                    let opened = oidn.get_or_insert_with(|| Oidn::new(&request));
                    let (result, device, notes) = match opened {
                        Ok(o) => (
                            o.denoise(&job.inputs.images(), &job.options),
                            o.device_description(),
                            std::mem::take(&mut o.notes),
                        ),
                        Err(e) => (Err(e.clone()), String::new(), Vec::new()),
                    };
                    let done = Done {
                        tag: job.tag,
                        result,
                        device,
                        notes,
                    };
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
