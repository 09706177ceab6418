//! [`Integrator::Auto`]: which form of the path integrator traces a frame. Both forms trace the same paths, so
//! the choice is one of speed alone, and the faster form depends on the GPU, the scene, the image size and the
//! samples per frame (an H100, 2026-12-05: the wavefront form takes 0.71-0.76x the megakernel's trace time on
//! the Cornell box at 1080p-1440p and 0.69x on the seed-like interior, but 1.25-1.63x on FlightHelmet; at 960x540
//! and 16 samples per frame 0.73-0.88x on every bench scene; docs/BENCHMARKS.md). So the first frames of each
//! workload time both forms with the trace pass's GPU timestamps, interleaved, and the faster traces the rest.
//!
//! CPU adapters (lavapipe) keep the megakernel without a trial: it is the faster form there on every scene
//! measured, their timestamps can miss compute work, and a trial would compile the wavefront's kernels, seconds
//! of the start-up, for nothing. So do adapters without timestamp queries.

use super::material_lobes::KernelNeeds;
use super::settings::Integrator;
use crate::gpu::GpuContext;
use Integrator::{Megakernel as M, Wavefront as W};
use bevy_ecs::prelude::Resource;

/// The forms a trial's frames run, in order. The first frame of each is not timed (it compiles its pipelines and
/// allocates its buffers); the timed ones come in an ABBA BAAB order, so that a drift of the GPU's clocks over
/// the trial (they rise during the first fraction of a second of work: docs/BENCHMARKS.md, "Clocks after
/// idle") favours neither form: the mean of each form's timed frames stands for it (a median would not cancel
/// the drift). GPU timestamps of a pass vary by well under 1% from frame to frame once the clocks are up.
const TRIAL: [Integrator; 10] = [M, W, M, W, W, M, W, M, M, W];
const WARM_UP_FRAMES: usize = 2;
/// The wavefront form must be at least this much faster to be chosen: on a tie the megakernel, which holds no
/// path state between kernels, traces.
const WAVES_MUST_SAVE: f64 = 0.02;

/// What a trial's outcome holds for: a change of any of these times both forms again.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Workload {
    pub width: u32,
    pub height: u32,
    pub spp_per_frame: u32,
    pub max_depth: u32,
    /// The kernels' specialisation: materials and the scene's shape.
    pub needs: KernelNeeds,
}

/// The outcome of a trial, for display and the bench's records.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decision {
    pub chosen: Integrator,
    /// Mean trace ms per frame of each form over its timed frames.
    pub megakernel_ms: f64,
    pub wavefront_ms: f64,
}

#[derive(Resource, Debug)]
pub struct IntegratorChoice {
    /// Whether `Auto` times the forms at all (a GPU adapter with timestamp queries).
    trials: bool,
    workload: Option<Workload>,
    /// Trace ms of the trial's frames so far, in [`TRIAL`]'s order, warm-up frames included.
    frames: Vec<f64>,
    decision: Option<Decision>,
    /// Whether the frame being traced is the trial's next (`TRIAL[frames.len()]`), its time still to record.
    timing: bool,
    /// The form that traced the last frame.
    last: Option<Integrator>,
    /// The last view size found too large for the waves, so that the user is told once.
    too_large: Option<(u32, u32)>,
}

impl IntegratorChoice {
    /// Trials where the adapter is a GPU with timestamp queries (module documentation).
    pub fn for_adapter(ctx: &GpuContext) -> Self {
        Self::new(ctx.info.device_type != wgpu::DeviceType::Cpu && ctx.supports_timestamps())
    }

    /// `trials`: whether `Auto` times both forms (tests run trials on CPU adapters too).
    pub fn new(trials: bool) -> Self {
        Self {
            trials,
            workload: None,
            frames: Vec::new(),
            decision: None,
            timing: false,
            last: None,
            too_large: None,
        }
    }

    /// Whether a view of this size is reported too large for the waves for the first time.
    pub fn first_too_large(&mut self, width: u32, height: u32) -> bool {
        let first = self.too_large != Some((width, height));
        self.too_large = Some((width, height));
        first
    }

    /// The form that traces this frame. `waves_possible` is false when the frame records what only the
    /// megakernel records (the denoisers' inputs, the primary-hit AOV): the megakernel then traces, untimed.
    pub fn form(
        &mut self,
        requested: Integrator,
        workload: Workload,
        waves_possible: bool,
    ) -> Integrator {
        self.timing = false;
        let form = match requested {
            _ if !waves_possible => Integrator::Megakernel,
            Integrator::Megakernel | Integrator::Wavefront => requested,
            Integrator::Auto if !self.trials => Integrator::Megakernel,
            Integrator::Auto => {
                if self.workload != Some(workload) {
                    self.workload = Some(workload);
                    self.frames.clear();
                    self.decision = None;
                }
                match self.decision {
                    Some(d) => d.chosen,
                    None => {
                        self.timing = true;
                        TRIAL[self.frames.len()]
                    }
                }
            }
        };
        self.last = Some(form);
        form
    }

    /// Whether the frame [`Self::form`] chose is part of a trial: its trace time goes to [`Self::record`].
    pub fn timing(&self) -> bool {
        self.timing
    }

    /// The trace pass's GPU time of the frame in trial; `None` (no timestamp could be read) ends the trial with
    /// the megakernel.
    pub fn record(&mut self, trace_ms: Option<f64>) {
        if !std::mem::take(&mut self.timing) {
            return;
        }
        let Some(ms) = trace_ms.filter(|ms| ms.is_finite()) else {
            self.trials = false;
            self.decision = None;
            return;
        };
        self.frames.push(ms);
        if self.frames.len() == TRIAL.len() {
            let [megakernel_ms, wavefront_ms] = [M, W].map(|form| {
                let timed: Vec<f64> = (WARM_UP_FRAMES..TRIAL.len())
                    .filter(|&i| TRIAL[i] == form)
                    .map(|i| self.frames[i])
                    .collect();
                timed.iter().sum::<f64>() / timed.len() as f64
            });
            let chosen = if wavefront_ms < megakernel_ms * (1.0 - WAVES_MUST_SAVE) {
                Integrator::Wavefront
            } else {
                Integrator::Megakernel
            };
            self.decision = Some(Decision {
                chosen,
                megakernel_ms,
                wavefront_ms,
            });
        }
    }

    /// Whether `Auto` times the forms on this adapter.
    pub fn trials(&self) -> bool {
        self.trials
    }

    /// The current workload's trial outcome, once both forms were timed.
    pub fn decision(&self) -> Option<Decision> {
        self.decision
    }

    /// The form that traced the last frame (`None` before the first).
    pub fn last_form(&self) -> Option<Integrator> {
        self.last
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn workload(width: u32) -> Workload {
        Workload {
            width,
            height: 8,
            spp_per_frame: 1,
            max_depth: 6,
            needs: KernelNeeds::default(),
        }
    }

    /// Runs `Auto` frames with `ms(form)` as each frame's trace time until a decision or `limit` frames.
    fn trial(choice: &mut IntegratorChoice, ms: impl Fn(Integrator) -> f64, limit: usize) -> usize {
        for frame in 0..limit {
            if choice.decision().is_some() {
                return frame;
            }
            let form = choice.form(Integrator::Auto, workload(8), true);
            assert!(choice.timing());
            choice.record(Some(ms(form)));
        }
        limit
    }

    #[test]
    fn the_faster_form_is_kept_after_both_were_timed() {
        for (waves_ms, expected) in [
            (0.7, Integrator::Wavefront),
            (1.3, Integrator::Megakernel),
            // Within 2%: the megakernel, which holds no path state.
            (0.99, Integrator::Megakernel),
        ] {
            let mut choice = IntegratorChoice::new(true);
            let forms = std::cell::RefCell::new(Vec::new());
            let frames = trial(
                &mut choice,
                |form| {
                    forms.borrow_mut().push(form);
                    // The warm-up frame of each form is slow and must not count.
                    let warm_up = forms.borrow().iter().filter(|f| **f == form).count() == 1;
                    let ms = if form == Integrator::Wavefront {
                        waves_ms
                    } else {
                        1.0
                    };
                    if warm_up { 50.0 } else { ms }
                },
                100,
            );
            assert_eq!(frames, TRIAL.len());
            assert_eq!(forms.into_inner(), TRIAL);
            let decision = choice.decision().expect("decided");
            assert_eq!(decision.chosen, expected, "wavefront at {waves_ms} ms");
            assert_eq!(
                (decision.megakernel_ms, decision.wavefront_ms),
                (1.0, waves_ms)
            );
            // The frames after the trial are the chosen form's, untimed.
            assert_eq!(choice.form(Integrator::Auto, workload(8), true), expected);
            assert!(!choice.timing());
            assert_eq!(choice.last_form(), Some(expected));
        }
    }

    /// Clocks rising linearly over the trial (each frame 0.5 ms faster than the one before) do not favour the
    /// form timed later: equal forms stay a tie, so the megakernel.
    #[test]
    fn a_drift_over_the_trial_favours_neither_form() {
        let mut choice = IntegratorChoice::new(true);
        let frame = std::cell::Cell::new(0);
        trial(
            &mut choice,
            |_| {
                frame.set(frame.get() + 1);
                10.0 - 0.5 * frame.get() as f64
            },
            100,
        );
        let d = choice.decision().expect("decided");
        assert_eq!((d.megakernel_ms, d.wavefront_ms), (6.75, 6.75));
        // The order alone decides this: alternating forms would have timed the wavefront 0.5 ms faster.
        assert_eq!(d.chosen, Integrator::Megakernel);
    }

    #[test]
    fn a_new_workload_times_both_forms_again() {
        let mut choice = IntegratorChoice::new(true);
        trial(
            &mut choice,
            |f| if f == Integrator::Wavefront { 0.5 } else { 1.0 },
            100,
        );
        assert_eq!(
            choice.decision().map(|d| d.chosen),
            Some(Integrator::Wavefront)
        );
        assert_eq!(
            choice.form(Integrator::Auto, workload(16), true),
            Integrator::Megakernel
        );
        assert!(choice.timing());
        assert_eq!(choice.decision(), None);
    }

    #[test]
    fn explicit_forms_cpu_adapters_and_megakernel_only_frames_are_not_timed() {
        let mut choice = IntegratorChoice::new(true);
        for requested in [Integrator::Megakernel, Integrator::Wavefront] {
            assert_eq!(choice.form(requested, workload(8), true), requested);
            assert!(!choice.timing());
        }
        // Frames recording the denoisers' inputs: the megakernel, whatever was asked for.
        for requested in [Integrator::Auto, Integrator::Wavefront] {
            assert_eq!(
                choice.form(requested, workload(8), false),
                Integrator::Megakernel
            );
            assert!(!choice.timing());
        }
        // A record with no frame in trial changes nothing.
        choice.record(Some(1.0));
        assert!(choice.frames.is_empty());
        let mut cpu = IntegratorChoice::new(false);
        assert_eq!(
            cpu.form(Integrator::Auto, workload(8), true),
            Integrator::Megakernel
        );
        assert!(!cpu.timing());
    }

    #[test]
    fn an_unreadable_time_ends_the_trial_with_the_megakernel() {
        let mut choice = IntegratorChoice::new(true);
        choice.form(Integrator::Auto, workload(8), true);
        choice.record(None);
        for _ in 0..10 {
            assert_eq!(
                choice.form(Integrator::Auto, workload(8), true),
                Integrator::Megakernel
            );
            assert!(!choice.timing());
        }
    }
}
