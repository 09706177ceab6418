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
/// allocates its buffers); the timed ones come in adjacent pairs, one of each form, in an ABBA BAAB order, so
/// that a drift of the GPU's clocks over the trial (they rise during the first fraction of a second of work:
/// docs/BENCHMARKS.md, "Clocks after idle") leaves each form's fastest frame beside the other's. Each form's
/// fastest frame decides: the clocks only ever make a frame slower than the steady state, so a frame that follows
/// an idle GPU (the bench reads images back between frames) cannot decide it. The median of the pairs' ratios,
/// used before, could, where such frames fell on one form in two of the four pairs.
const TRIAL: [Integrator; 10] = [M, W, M, W, W, M, W, M, M, W];
const WARM_UP_FRAMES: usize = 2;
/// The wavefront form must be at least this much faster to be chosen: on a tie the megakernel, which holds no
/// path state between kernels, traces.
const WAVES_MUST_SAVE: f64 = 0.02;
/// GPU timestamps of a pass vary by well under 1% from frame to frame once the clocks are up; a form whose timed
/// frames spread wider than this (slowest / fastest - 1) was timed while they were still rising, and the trial
/// runs again (the bench's first 10 frames after an idle GPU: FlightHelmet's trial chose the wavefront at 4.6 ms
/// per frame over the megakernel's 4.0 ms on an H100, 2026-12-05).
const STEADY_SPREAD: f64 = 0.10;
/// Unsteady trials run again until [`LEAST_TRIALS`] trials and [`CLOCK_RAMP_MS`] of trace time have passed, or
/// [`MOST_TRIALS`]: a count alone ended small frames' trials inside the clocks' ramp (40 frames of the Cornell
/// box at 960x540 and one sample are 20-25 ms of a ramp that lasts about 0.3 s on the H200): the likely reason
/// why the bench's error curves chose the wavefront at 1.22x the megakernel's time (H100, 2026-12-05; the trial's
/// frame times were not recorded). No trial decides before [`CLOCK_RAMP_MS`] of trace time, steady or not: clocks
/// can also hold low and steady for a while, and a trial inside that decides by times the steady state does not
/// have (the grazing scene's 16-spp frames on an H100, 2026-12-06: 14.1 ms for the megakernel and 11.3 ms for the
/// wavefront in a steady second trial, 3.9 and 4.4 ms once the clocks were up, so the slower form traced).
const LEAST_TRIALS: u32 = 4;
const CLOCK_RAMP_MS: f64 = 500.0;
const MOST_TRIALS: u32 = 100;

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
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct Decision {
    pub chosen: Integrator,
    /// Each form's fastest trace ms per frame among the deciding trial's timed frames.
    pub megakernel_ms: f64,
    pub wavefront_ms: f64,
    /// Trials run before this one decided (more than one where the first were timed while the clocks moved).
    pub trials: u32,
}

#[derive(Resource, Debug)]
pub struct IntegratorChoice {
    /// Whether `Auto` times the forms at all (a GPU adapter with timestamp queries).
    trials: bool,
    workload: Option<Workload>,
    /// Trace ms of the trial's frames so far, in [`TRIAL`]'s order, warm-up frames included.
    frames: Vec<f64>,
    /// Trials of this workload so far (a trial timed while the clocks moved runs again).
    trials_run: u32,
    /// Trace ms of every trial frame of this workload so far.
    trial_ms: f64,
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
            trials_run: 0,
            trial_ms: 0.0,
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
                    self.trials_run = 0;
                    self.trial_ms = 0.0;
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
        if self.frames.len() < TRIAL.len() {
            return;
        }
        self.trials_run += 1;
        let timed = |form: Integrator| -> Vec<f64> {
            (WARM_UP_FRAMES..TRIAL.len())
                .filter(|&i| TRIAL[i] == form)
                .map(|i| self.frames[i])
                .collect()
        };
        let (megakernel, wavefront) = (timed(M), timed(W));
        let steady = [&megakernel, &wavefront].iter().all(|t| {
            let (lo, hi) = (min(t), t.iter().copied().fold(0.0, f64::max));
            hi <= lo * (1.0 + STEADY_SPREAD)
        });
        self.trial_ms += self.frames.iter().sum::<f64>();
        let ramp_passed = self.trial_ms >= CLOCK_RAMP_MS;
        let may_run_again = self.trials_run < LEAST_TRIALS || !ramp_passed;
        if !(steady && ramp_passed) && may_run_again && self.trials_run < MOST_TRIALS {
            self.frames.clear();
            return;
        }
        let ratio = min(&wavefront) / min(&megakernel);
        let chosen = if ratio < 1.0 - WAVES_MUST_SAVE {
            Integrator::Wavefront
        } else {
            Integrator::Megakernel
        };
        self.decision = Some(Decision {
            chosen,
            megakernel_ms: min(&megakernel),
            wavefront_ms: min(&wavefront),
            trials: self.trials_run,
        });
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

fn min(values: &[f64]) -> f64 {
    values.iter().copied().fold(f64::INFINITY, f64::min)
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

    /// Runs `Auto` frames with `ms(form, frame)` as each frame's trace time (frames counted from 1) until a
    /// decision or `limit` frames.
    fn trial(
        choice: &mut IntegratorChoice,
        ms: impl Fn(Integrator, usize) -> f64,
        limit: usize,
    ) -> usize {
        for frame in 0..limit {
            if choice.decision().is_some() {
                return frame;
            }
            let form = choice.form(Integrator::Auto, workload(8), true);
            assert!(choice.timing());
            choice.record(Some(ms(form, frame + 1)));
        }
        limit
    }

    /// The megakernel's and the wavefront's ms per frame of `(megakernel, wavefront)`.
    fn speeds(form: Integrator, (megakernel, wavefront): (f64, f64)) -> f64 {
        if form == Integrator::Wavefront {
            wavefront
        } else {
            megakernel
        }
    }

    /// Frames of 60 ms: one trial is past the clocks' ramp and decides.
    #[test]
    fn the_faster_form_is_kept_after_both_were_timed() {
        for (waves_ms, expected) in [
            (42.0, Integrator::Wavefront),
            (78.0, Integrator::Megakernel),
            // Within 2%: the megakernel, which holds no path state.
            (59.4, Integrator::Megakernel),
        ] {
            let mut choice = IntegratorChoice::new(true);
            let forms = std::cell::RefCell::new(Vec::new());
            let frames = trial(
                &mut choice,
                |form, frame| {
                    forms.borrow_mut().push(form);
                    // The warm-up frame of each form is slow and must not count.
                    let ms = speeds(form, (60.0, waves_ms));
                    if frame <= WARM_UP_FRAMES { 500.0 } else { ms }
                },
                100,
            );
            assert_eq!(frames, TRIAL.len());
            assert_eq!(forms.into_inner(), TRIAL);
            let decision = choice.decision().expect("decided");
            assert_eq!(decision.chosen, expected, "wavefront at {waves_ms} ms");
            assert_eq!(
                (decision.megakernel_ms, decision.wavefront_ms),
                (60.0, waves_ms)
            );
            // The frames after the trial are the chosen form's, untimed.
            assert_eq!(choice.form(Integrator::Auto, workload(8), true), expected);
            assert!(!choice.timing());
            assert_eq!(choice.last_form(), Some(expected));
        }
    }

    /// Clocks rising steadily over the trial (each frame 0.5 ms faster than the one before) do not favour the
    /// form timed later: equal forms stay a tie, so the megakernel.
    #[test]
    fn a_drift_over_the_trial_favours_neither_form() {
        let mut choice = IntegratorChoice::new(true);
        let frames = trial(&mut choice, |_, frame| 100.0 - 0.5 * frame as f64, 100);
        assert_eq!(frames, TRIAL.len(), "one trial");
        // The order alone decides this: alternating forms would have timed the wavefront 0.5 ms faster, and
        // each form's fastest frame is the wavefront's last.
        assert_eq!(choice.decision().unwrap().chosen, Integrator::Megakernel);
    }

    /// Clocks that jump up during the trial (the bench's first frames after an idle GPU: three times slower,
    /// then steady) time it again; the steady trial decides. The megakernel is the faster form here, but its
    /// slow frames would have made it the slower by its mean.
    #[test]
    fn a_trial_timed_while_the_clocks_rose_runs_again() {
        let mut choice = IntegratorChoice::new(true);
        let frames = trial(
            &mut choice,
            |form, frame| speeds(form, (40.0, 46.0)) * if frame <= 3 { 3.0 } else { 1.0 },
            100,
        );
        assert_eq!(frames, 2 * TRIAL.len(), "a second trial");
        let d = choice.decision().unwrap();
        assert_eq!(d.trials, 2);
        assert_eq!(d.chosen, Integrator::Megakernel);
        assert_eq!((d.megakernel_ms, d.wavefront_ms), (40.0, 46.0));
    }

    /// Clocks that hold low and steady at first, where the forms' order is not the steady state's (the grazing
    /// scene's 16-spp frames on an H100: 14.1 and 11.3 ms, then 3.9 and 4.4 ms), do not decide: trials run on
    /// until the ramp's time has passed, and the last chooses the megakernel.
    #[test]
    fn a_steady_trial_inside_the_clocks_ramp_does_not_decide() {
        let mut choice = IntegratorChoice::new(true);
        let elapsed = std::cell::Cell::new(0.0);
        let frames = trial(
            &mut choice,
            |form, _| {
                let ms = if elapsed.get() < 300.0 {
                    speeds(form, (14.1, 11.3))
                } else {
                    speeds(form, (3.9, 4.4))
                };
                elapsed.set(elapsed.get() + ms);
                ms
            },
            10_000,
        );
        assert!(frames > 2 * TRIAL.len());
        let d = choice.decision().unwrap();
        assert_eq!(d.chosen, Integrator::Megakernel);
        assert_eq!((d.megakernel_ms, d.wavefront_ms), (3.9, 4.4));
        assert!(choice.trial_ms >= CLOCK_RAMP_MS);
    }

    /// Where the times never settle, the last trial decides by each form's fastest frame: one frame timed across
    /// a jump cannot tip it.
    #[test]
    fn an_unsteady_gpu_is_decided_by_the_fastest_frames() {
        let mut choice = IntegratorChoice::new(true);
        // The fourth frame of every trial (the wavefront's in its first pair) three times slower: by their means
        // the megakernel would be the faster form.
        let frames = trial(
            &mut choice,
            |form, frame| {
                speeds(form, (4.6, 4.0)) * if frame % TRIAL.len() == 4 { 3.0 } else { 1.0 }
            },
            10_000,
        );
        assert_ramp_passed(&choice, frames);
        assert_eq!(choice.decision().unwrap().chosen, Integrator::Wavefront);
    }

    /// Trials that never settle end with the first trial after [`LEAST_TRIALS`] and [`CLOCK_RAMP_MS`].
    fn assert_ramp_passed(choice: &IntegratorChoice, frames: usize) {
        assert_eq!(frames % TRIAL.len(), 0, "whole trials");
        assert_eq!(
            choice.decision().map(|d| d.trials as usize),
            Some(frames / TRIAL.len())
        );
        assert!(choice.trials_run >= LEAST_TRIALS);
        let per_trial = choice.trial_ms / choice.trials_run as f64;
        assert!(
            choice.trial_ms >= CLOCK_RAMP_MS && choice.trial_ms < CLOCK_RAMP_MS + per_trial,
            "{} ms of trials",
            choice.trial_ms
        );
    }

    /// Frames of half a millisecond: 40 of them (four trials) fit in the clocks' 300 ms ramp, where here every
    /// frame runs slower by a factor that jumps from frame to frame, the megakernel's more than the wavefront's.
    /// The trials go on past the ramp and choose the megakernel, the faster form on steady clocks.
    #[test]
    fn small_frames_are_timed_past_the_clocks_ramp() {
        let mut choice = IntegratorChoice::new(true);
        let elapsed = std::cell::Cell::new(0.0);
        let frames = trial(
            &mut choice,
            |form, frame| {
                let slower = match (form, frame % 2) {
                    (Integrator::Megakernel, 0) => 1.6,
                    (Integrator::Megakernel, _) => 3.0,
                    (_, 0) => 1.0,
                    _ => 1.2,
                };
                let ramp = elapsed.get() < 300.0;
                let ms = speeds(form, (0.5, 0.6)) * if ramp { slower } else { 1.0 };
                elapsed.set(elapsed.get() + ms);
                ms
            },
            10_000,
        );
        assert!(elapsed.get() > 300.0 && frames > LEAST_TRIALS as usize * TRIAL.len());
        let d = choice.decision().unwrap();
        assert_eq!(d.chosen, Integrator::Megakernel);
        assert_eq!((d.megakernel_ms, d.wavefront_ms), (0.5, 0.6));
    }

    /// The bench's error curves read the image back after frames 1, 2, 4 and 8 of a trial: the frames after
    /// those gaps run on clocks that dropped while the GPU idled (here 1.5x slower). They fall on megakernel
    /// frames in two of the four pairs, which made the median of the pairs' ratios choose the wavefront though
    /// it is 1.15x slower.
    #[test]
    fn frames_after_an_idle_gpu_do_not_decide() {
        let mut choice = IntegratorChoice::new(true);
        let frames = trial(
            &mut choice,
            |form, frame| {
                let after_gap = [2, 3, 5, 9].contains(&(1 + (frame - 1) % TRIAL.len()));
                speeds(form, (4.0, 4.6)) * if after_gap { 1.5 } else { 1.0 }
            },
            10_000,
        );
        assert_ramp_passed(&choice, frames);
        let d = choice.decision().unwrap();
        assert_eq!(d.chosen, Integrator::Megakernel);
        assert_eq!((d.megakernel_ms, d.wavefront_ms), (4.0, 4.6));
    }

    #[test]
    fn a_new_workload_times_both_forms_again() {
        let mut choice = IntegratorChoice::new(true);
        trial(&mut choice, |form, _| speeds(form, (1.0, 0.5)), 10_000);
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
