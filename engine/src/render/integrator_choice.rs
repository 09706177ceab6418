//! [`Integrator::Auto`]: which form of the path integrator traces a frame. Both forms trace the same paths, so
//! the choice is one of speed alone, and the faster form depends on the GPU, the scene, the image size and the
//! samples per frame (an H100, 2026-12-05: the wavefront form takes 0.71-0.76x the megakernel's trace time on
//! the Cornell box at 1080p-1440p and 0.69x on the seed-like interior, but 1.25-1.63x on FlightHelmet; at 960x540
//! and 16 samples per frame 0.73-0.88x on every bench scene; docs/BENCHMARKS.md). So the first frames of each
//! workload time both forms with the trace pass's GPU timestamps, interleaved, and the faster traces the rest.
//!
//! Where the waves trace, a second trial then times them with each bounce's rays sorted before they are traced
//! and without (`wavefront.wgsl`, `WAVE_SORT`): the same paths again, faster only where the scene's trees are
//! too large for the caches (on an H100 the seed-like interior's trace 0.93x, the Cornell box's and the
//! environment-lit scene's 1.2x; docs/BENCHMARKS.md). Since the waves' extend refills its lanes (the default on
//! GPUs) no bench scene gains from the sort any more, the seed-like interior included; the trial stays for
//! scenes whose trees outgrow the caches further. `RAYKIN_WAVE_SORT=on|off` forces it, for any waves.
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
/// (Arms 0 and 1 of a trial: the megakernel and the waves, or the waves unsorted and sorted.)
const ORDER: [usize; 10] = [0, 1, 0, 1, 1, 0, 1, 0, 0, 1];
const FORMS: [Integrator; 2] = [M, W];
const WARM_UP_FRAMES: usize = 2;
/// The wavefront form must be at least this much faster to be chosen: on a tie the megakernel, which holds no
/// path state between kernels, traces.
const WAVES_MUST_SAVE: f64 = 0.02;
/// Likewise the sorted waves, whose sort is work of its own.
const SORT_MUST_SAVE: f64 = 0.02;
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

/// The outcome of the ray sort's trial, once the waves were chosen.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize)]
pub struct SortDecision {
    pub sorted: bool,
    /// The waves' fastest trace ms per frame unsorted and sorted among the deciding trial's timed frames.
    pub unsorted_ms: f64,
    pub sorted_ms: f64,
    pub trials: u32,
}

/// Which trial the frame being traced is part of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Timing {
    Forms,
    Sorting,
}

/// One trial between two arms: the frames so far in [`ORDER`], and how long the trials of this workload ran.
#[derive(Debug, Default)]
struct Trial {
    /// Trace ms of the trial's frames so far, warm-up frames included.
    frames: Vec<f64>,
    /// Trials of this workload so far (a trial timed while the clocks moved runs again).
    trials_run: u32,
    /// Trace ms of every trial frame of this workload so far.
    trial_ms: f64,
}

impl Trial {
    fn next_arm(&self) -> usize {
        ORDER[self.frames.len()]
    }

    /// Adds a frame's trace ms; once the trial decides, each arm's fastest timed frame.
    fn record(&mut self, ms: f64) -> Option<[f64; 2]> {
        self.frames.push(ms);
        if self.frames.len() < ORDER.len() {
            return None;
        }
        self.trials_run += 1;
        let timed = |arm: usize| -> Vec<f64> {
            (WARM_UP_FRAMES..ORDER.len())
                .filter(|&i| ORDER[i] == arm)
                .map(|i| self.frames[i])
                .collect()
        };
        let arms = [timed(0), timed(1)];
        let steady = arms.iter().all(|t| {
            let (lo, hi) = (min(t), t.iter().copied().fold(0.0, f64::max));
            hi <= lo * (1.0 + STEADY_SPREAD)
        });
        self.trial_ms += self.frames.iter().sum::<f64>();
        let ramp_passed = self.trial_ms >= CLOCK_RAMP_MS;
        let may_run_again = self.trials_run < LEAST_TRIALS || !ramp_passed;
        if !(steady && ramp_passed) && may_run_again && self.trials_run < MOST_TRIALS {
            self.frames.clear();
            return None;
        }
        Some([min(&arms[0]), min(&arms[1])])
    }
}

#[derive(Resource, Debug)]
pub struct IntegratorChoice {
    /// Whether `Auto` times the forms at all (a GPU adapter with timestamp queries).
    trials: bool,
    workload: Option<Workload>,
    /// The megakernel against the waves.
    forms: Trial,
    decision: Option<Decision>,
    /// The waves unsorted against sorted, once the waves were chosen.
    sorting: Trial,
    sort_decision: Option<SortDecision>,
    /// `RAYKIN_WAVE_SORT`, or a test's choice: the waves sorted or not, without a trial.
    sort_forced: Option<bool>,
    /// The trial whose next frame is being traced, its time still to record.
    timing: Option<Timing>,
    /// The form that traced the last frame, and whether its rays were sorted.
    last: Option<Integrator>,
    sorted: bool,
    /// The last view size found too large for the waves, so that the user is told once.
    too_large: Option<(u32, u32)>,
}

impl IntegratorChoice {
    /// Trials where the adapter is a GPU with timestamp queries (module documentation).
    pub fn for_adapter(ctx: &GpuContext) -> Self {
        let mut choice =
            Self::new(ctx.info.device_type != wgpu::DeviceType::Cpu && ctx.supports_timestamps());
        if std::env::var_os("RAYKIN_WAVE_SORT").is_some() {
            choice.sort_forced = Some(crate::gpu::switch_on("RAYKIN_WAVE_SORT", false));
        }
        choice
    }

    /// `trials`: whether `Auto` times both forms (tests run trials on CPU adapters too).
    pub fn new(trials: bool) -> Self {
        Self {
            trials,
            workload: None,
            forms: Trial::default(),
            decision: None,
            sorting: Trial::default(),
            sort_decision: None,
            sort_forced: None,
            timing: None,
            last: None,
            sorted: false,
            too_large: None,
        }
    }

    /// Sorts the waves' rays (`Some(true)`), never (`Some(false)`), or as the trial decides (`None`).
    pub fn force_ray_sort(&mut self, sort: Option<bool>) {
        self.sort_forced = sort;
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
        self.timing = None;
        let form = match requested {
            _ if !waves_possible => Integrator::Megakernel,
            Integrator::Megakernel | Integrator::Wavefront => requested,
            Integrator::Auto if !self.trials => Integrator::Megakernel,
            Integrator::Auto => {
                if self.workload != Some(workload) {
                    self.workload = Some(workload);
                    self.forms = Trial::default();
                    self.decision = None;
                    self.sorting = Trial::default();
                    self.sort_decision = None;
                }
                match self.decision {
                    Some(d) => d.chosen,
                    None => {
                        self.timing = Some(Timing::Forms);
                        FORMS[self.forms.next_arm()]
                    }
                }
            }
        };
        self.sorted = form == Integrator::Wavefront && self.sort_rays(requested);
        self.last = Some(form);
        form
    }

    /// Whether this frame's waves sort their rays: forced, or under `Auto` once the waves were chosen, the sort's
    /// trial (the forms' trial times the waves unsorted).
    fn sort_rays(&mut self, requested: Integrator) -> bool {
        if let Some(forced) = self.sort_forced {
            return forced;
        }
        if requested != Integrator::Auto || self.timing.is_some() {
            return false;
        }
        match self.sort_decision {
            Some(d) => d.sorted,
            None => {
                self.timing = Some(Timing::Sorting);
                self.sorting.next_arm() == 1
            }
        }
    }

    /// Whether the frame [`Self::form`] chose traces waves with their rays sorted (never true of the megakernel).
    pub fn rays_sorted(&self) -> bool {
        self.sorted
    }

    /// Whether the frame [`Self::form`] chose is part of a trial: its trace time goes to [`Self::record`].
    pub fn timing(&self) -> bool {
        self.timing.is_some()
    }

    /// The trace pass's GPU time of the frame in trial; `None` (no timestamp could be read) ends the trial with
    /// the megakernel.
    pub fn record(&mut self, trace_ms: Option<f64>) {
        let Some(timing) = self.timing.take() else {
            return;
        };
        let Some(ms) = trace_ms.filter(|ms| ms.is_finite()) else {
            self.trials = false;
            self.decision = None;
            return;
        };
        match timing {
            Timing::Forms => {
                if let Some([megakernel, wavefront]) = self.forms.record(ms) {
                    let chosen = if wavefront / megakernel < 1.0 - WAVES_MUST_SAVE {
                        Integrator::Wavefront
                    } else {
                        Integrator::Megakernel
                    };
                    self.decision = Some(Decision {
                        chosen,
                        megakernel_ms: megakernel,
                        wavefront_ms: wavefront,
                        trials: self.forms.trials_run,
                    });
                }
            }
            Timing::Sorting => {
                if let Some([unsorted, sorted]) = self.sorting.record(ms) {
                    self.sort_decision = Some(SortDecision {
                        sorted: sorted / unsorted < 1.0 - SORT_MUST_SAVE,
                        unsorted_ms: unsorted,
                        sorted_ms: sorted,
                        trials: self.sorting.trials_run,
                    });
                }
            }
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

    /// The ray sort's trial outcome, once the waves were chosen and timed both ways.
    pub fn sort_decision(&self) -> Option<SortDecision> {
        self.sort_decision
    }

    /// Whether `Auto` has nothing left to time for the current workload: no trials on this adapter, or the
    /// megakernel chosen, or the waves chosen and their sort decided (or forced).
    pub fn settled(&self) -> bool {
        !self.trials
            || self.decision.is_some_and(|d| {
                d.chosen == Integrator::Megakernel
                    || self.sort_forced.is_some()
                    || self.sort_decision.is_some()
            })
    }

    /// The form that traced the last frame (`None` before the first).
    pub fn last_form(&self) -> Option<Integrator> {
        self.last
    }

    /// The last frame's form by name, "wavefront (rays sorted)" where the waves sorted their rays.
    pub fn last_form_name(&self) -> Option<String> {
        let form = self.last?;
        Some(if self.sorted {
            format!("{} (rays sorted)", form.name())
        } else {
            form.name().to_string()
        })
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
            assert_eq!(frames, ORDER.len());
            assert_eq!(forms.into_inner(), ORDER.map(|arm| FORMS[arm]));
            let decision = choice.decision().expect("decided");
            assert_eq!(decision.chosen, expected, "wavefront at {waves_ms} ms");
            assert_eq!(
                (decision.megakernel_ms, decision.wavefront_ms),
                (60.0, waves_ms)
            );
            // The frames after the trial are the chosen form's, untimed (the waves' then time their ray sort).
            assert_eq!(choice.form(Integrator::Auto, workload(8), true), expected);
            assert_eq!(choice.timing(), expected == Integrator::Wavefront);
            assert_eq!(choice.last_form(), Some(expected));
        }
    }

    /// Clocks rising steadily over the trial (each frame 0.5 ms faster than the one before) do not favour the
    /// form timed later: equal forms stay a tie, so the megakernel.
    #[test]
    fn a_drift_over_the_trial_favours_neither_form() {
        let mut choice = IntegratorChoice::new(true);
        let frames = trial(&mut choice, |_, frame| 100.0 - 0.5 * frame as f64, 100);
        assert_eq!(frames, ORDER.len(), "one trial");
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
        assert_eq!(frames, 2 * ORDER.len(), "a second trial");
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
        assert!(frames > 2 * ORDER.len());
        let d = choice.decision().unwrap();
        assert_eq!(d.chosen, Integrator::Megakernel);
        assert_eq!((d.megakernel_ms, d.wavefront_ms), (3.9, 4.4));
        assert!(choice.forms.trial_ms >= CLOCK_RAMP_MS);
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
                speeds(form, (4.6, 4.0)) * if frame % ORDER.len() == 4 { 3.0 } else { 1.0 }
            },
            10_000,
        );
        assert_ramp_passed(&choice, frames);
        assert_eq!(choice.decision().unwrap().chosen, Integrator::Wavefront);
    }

    /// Trials that never settle end with the first trial after [`LEAST_TRIALS`] and [`CLOCK_RAMP_MS`].
    fn assert_ramp_passed(choice: &IntegratorChoice, frames: usize) {
        assert_eq!(frames % ORDER.len(), 0, "whole trials");
        assert_eq!(
            choice.decision().map(|d| d.trials as usize),
            Some(frames / ORDER.len())
        );
        assert!(choice.forms.trials_run >= LEAST_TRIALS);
        let per_trial = choice.forms.trial_ms / choice.forms.trials_run as f64;
        assert!(
            choice.forms.trial_ms >= CLOCK_RAMP_MS
                && choice.forms.trial_ms < CLOCK_RAMP_MS + per_trial,
            "{} ms of trials",
            choice.forms.trial_ms
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
        assert!(elapsed.get() > 300.0 && frames > LEAST_TRIALS as usize * ORDER.len());
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
                let after_gap = [2, 3, 5, 9].contains(&(1 + (frame - 1) % ORDER.len()));
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
        assert!(choice.forms.frames.is_empty());
        let mut cpu = IntegratorChoice::new(false);
        assert_eq!(
            cpu.form(Integrator::Auto, workload(8), true),
            Integrator::Megakernel
        );
        assert!(!cpu.timing());
    }

    /// Once `Auto` chose the waves, it times them unsorted and sorted (the same frame order, arm 1 sorted) and
    /// keeps the sort only where it saves more than [`SORT_MUST_SAVE`]; then nothing is timed.
    #[test]
    fn the_waves_sort_their_rays_where_a_trial_finds_it_faster() {
        for (sorted_ms, expected) in [(80.0, true), (99.0, false), (120.0, false)] {
            let mut choice = IntegratorChoice::new(true);
            trial(&mut choice, |form, _| speeds(form, (200.0, 100.0)), 100);
            assert_eq!(choice.decision().unwrap().chosen, Integrator::Wavefront);
            assert!(!choice.settled());
            let mut sorted_frames = Vec::new();
            while choice.sort_decision().is_none() {
                assert_eq!(
                    choice.form(Integrator::Auto, workload(8), true),
                    Integrator::Wavefront
                );
                assert!(choice.timing());
                sorted_frames.push(choice.rays_sorted());
                choice.record(Some(if choice.rays_sorted() {
                    sorted_ms
                } else {
                    100.0
                }));
                assert!(sorted_frames.len() <= 100);
            }
            assert_eq!(sorted_frames, ORDER.map(|arm| arm == 1), "one trial");
            let d = choice.sort_decision().unwrap();
            assert_eq!(
                (d.sorted, d.unsorted_ms, d.sorted_ms),
                (expected, 100.0, sorted_ms)
            );
            assert!(choice.settled());
            assert_eq!(
                choice.form(Integrator::Auto, workload(8), true),
                Integrator::Wavefront
            );
            assert!(!choice.timing());
            assert_eq!(choice.rays_sorted(), expected);
            // A new workload times the forms, and then the sort, again.
            choice.form(Integrator::Auto, workload(16), true);
            assert!(choice.timing() && !choice.rays_sorted());
            assert_eq!((choice.decision(), choice.sort_decision()), (None, None));
        }
    }

    /// The megakernel chosen, nothing more is timed; a forced sort takes no trial and applies to any waves,
    /// explicit ones included; the megakernel never sorts.
    #[test]
    fn a_forced_sort_or_the_megakernel_takes_no_sort_trial() {
        let mut choice = IntegratorChoice::new(true);
        trial(&mut choice, |form, _| speeds(form, (50.0, 100.0)), 100);
        assert!(choice.settled());
        assert_eq!(
            choice.form(Integrator::Auto, workload(8), true),
            Integrator::Megakernel
        );
        assert!(!choice.timing() && !choice.rays_sorted());
        for forced in [true, false] {
            let mut choice = IntegratorChoice::new(true);
            choice.force_ray_sort(Some(forced));
            trial(&mut choice, |form, _| speeds(form, (100.0, 50.0)), 100);
            assert!(choice.settled());
            assert_eq!(
                choice.form(Integrator::Auto, workload(8), true),
                Integrator::Wavefront
            );
            assert!(!choice.timing());
            assert_eq!(choice.rays_sorted(), forced);
            choice.form(Integrator::Wavefront, workload(8), true);
            assert_eq!(choice.rays_sorted(), forced);
            choice.form(Integrator::Megakernel, workload(8), true);
            assert!(!choice.rays_sorted());
        }
        // Explicit waves are not sorted unless forced, and not timed.
        let mut choice = IntegratorChoice::new(true);
        choice.form(Integrator::Wavefront, workload(8), true);
        assert!(!choice.timing() && !choice.rays_sorted());
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
