//! Whether the cache pays on the GPU the application runs on, decided
//! from that GPU's own frame times.
//!
//! `shadecache profile` answers on the developer's machine; the player's
//! GPU is another one, and the same variant wins on one and loses on
//! another by how heavy its payload is there. A [`Governor`] decides per
//! frame what the application draws, the original or the cached frame,
//! from the GPU times of the frames it has drawn:
//!
//! - **Measuring is interleaving.** While the cache is on, one frame in
//!   [`GovernorSettings::probe_every`] is the original: those frames are
//!   the measurement of what the cache saves. While it is off, a burst of
//!   cached frames runs every [`GovernorSettings::reprobe_every`] frames,
//!   because scenes change; the burst starts cold (the cache is new), and
//!   its first [`GovernorSettings::warmup`] frames are not counted, as the
//!   profiler leaves out its warm-up.
//! - **Deciding is an interval.** Each frame of the kind drawn rarely (the
//!   original while the cache is on, a warm cached frame while it is off)
//!   is paired with the latest frame of the other kind, so that both sides
//!   span the same stretch of time and a slow stretch of the machine weighs
//!   on both alike (the profiler interleaves frame by frame for the same
//!   reason). The speed-up is the median original frame over the median
//!   cached frame of the last [`GovernorSettings::window`] pairs, with the
//!   profiler's bootstrap interval (`shadecache_plan::speed`, the same
//!   code). The cache turns
//!   off when the whole interval lies below 1× and on when it lies above;
//!   in between, the decision holds (that is the hysteresis), and no
//!   decision changes within [`GovernorSettings::min_dwell`] frames of the
//!   last.
//! - **Times come late.** A GPU time is read when its timestamps are
//!   ready, frames after it was drawn, without a stall:
//!   [`Governor::next_frame`] numbers each frame, and
//!   [`Governor::measured`] takes the number back with the time.
//! - **A switch on starts a new cache.** The first cached frame after the
//!   cache was off carries `reset: true`: what the cache holds is from
//!   before, as after a camera cut.
//! - **Fast is not enough: the error watch.** With an error budget
//!   ([`GovernorSettings::min_psnr`]), one warm cached frame in
//!   [`GovernorSettings::watch_every`] is watched
//!   ([`GovernedFrame::watch`]): the application draws the original as well,
//!   into a spare target, and an [`crate::ErrorWatch`] compares the two on
//!   the GPU; its PSNR comes back through [`Governor::watched`]. Below the
//!   budget, the governor halves the refresh period Δn
//!   ([`GovernedFrame::period`], which the application sets with
//!   `CachedShader::set_refresh_period`); at the floor
//!   ([`GovernorSettings::min_period`]) it turns the cache off. Once the
//!   watched frames have stayed well within the budget
//!   ([`GovernorSettings::raise_after`] in a row,
//!   [`GovernorSettings::raise_margin`] dB above it), a lowered Δn doubles
//!   again, up to the variant's: the largest Δn within the budget is the
//!   cheapest refresh the budget allows. While off,
//!   each re-probe's burst watches its first warm frame, and the cache
//!   turns on again only when that frame was within the budget. A watched
//!   frame costs more (the original drawn too, the comparison): its time
//!   is kept apart, and the extra, spread over `watch_every` frames, is
//!   added to every cached frame the speed-up is weighed on, so the
//!   speed-up the governor reports is of the cache with its watch.
//!
//! - **Several variants: the fastest within the budget.** Where the
//!   application can draw several variants of the shader (a plan bundle's
//!   one-, two-, three-pass...; [`GovernorSettings::variants`]), the
//!   governor runs a trial at the start and every
//!   [`GovernorSettings::retrial_every`] frames while the cache is on: each
//!   variant in turn ([`GovernedFrame::variant`]) is started afresh, warmed
//!   up and measured against the original (one frame in
//!   [`GovernorSettings::trial_probe_every`], so that a turn is short),
//!   its first warm frame watched where there is a budget; the variant with
//!   the highest speed-up among those within the budget is then drawn, and
//!   the cache is off where even it loses. While the cache is off, each
//!   re-probe's burst tries the next variant.
//!
//! The governor itself draws nothing and reads no timestamps: it is the
//! decision, which an application (or the host's timing) feeds.

use std::collections::VecDeque;

use shadecache_plan::speed::{median, speedup_interval_resampled};

/// How the governor samples and decides.
#[derive(Clone, Debug, PartialEq)]
pub struct GovernorSettings {
    /// Pairs of frame times kept, each a frame of the kind drawn rarely
    /// (the original while the cache is on, a warm cached frame while it
    /// is off) and the latest of the other kind; the speed-up is of the
    /// last this many.
    pub window: usize,
    /// Pairs needed before a decision.
    pub min_samples: usize,
    /// While the cache is on, one frame in this many is the original.
    pub probe_every: u32,
    /// While the cache is off, a burst of cached frames starts this many
    /// frames after the last one began.
    pub reprobe_every: u32,
    /// Frames in a burst of cached frames while the cache is off.
    pub reprobe_frames: u32,
    /// Cached frames after a new start that are not measured: the cache
    /// fills (its refresh period Δn and one frame: after a cold start most
    /// values reach age Δn together).
    pub warmup: u32,
    /// Frames a decision holds at least.
    pub min_dwell: u32,
    /// Pairs between two decisions (each resamples the windows).
    pub decide_every: u32,
    /// Resamples of the bootstrap interval (the profiler takes 2000; a
    /// decision a game makes while it runs takes fewer, about 0.4 ms of
    /// CPU for 400 in a release build).
    pub resamples: usize,
    /// The error budget: the least PSNR (dB, over the cached pixels, as
    /// the profiler measures it) a watched cached frame may have against
    /// the original. `None`: no watch, the speed alone decides.
    pub min_psnr: Option<f64>,
    /// With a budget, one warm cached frame in this many is watched.
    pub watch_every: u32,
    /// The refresh period Δn the cache starts with: the variant's.
    pub period: u32,
    /// The least Δn the watch lowers to; below the budget there, the
    /// cache turns off. Δn = 1 recomputes every pixel every frame and
    /// saves nothing, so the floor is at least 2.
    pub min_period: u32,
    /// Watched frames in a row at least [`GovernorSettings::raise_margin`]
    /// dB above the budget before a lowered Δn is doubled again (up to
    /// [`GovernorSettings::period`]): a light that stopped moving gives
    /// back the cache's savings. Each raise the next watch finds below the
    /// budget doubles this, so a scene at the edge of the budget does not
    /// see-saw.
    pub raise_after: u32,
    /// How far above the budget, in dB, a watched frame counts towards a
    /// raise.
    pub raise_margin: f64,
    /// The variants the application can draw ([`GovernedFrame::variant`]
    /// indexes them); with more than one, the governor tries each and
    /// draws the fastest within the budget.
    pub variants: usize,
    /// During a trial, one frame in this many is the original.
    pub trial_probe_every: u32,
    /// While the cache is on, a trial of the variants runs again this many
    /// frames after the last ended.
    pub retrial_every: u32,
}

impl Default for GovernorSettings {
    fn default() -> Self {
        GovernorSettings {
            window: 24,
            min_samples: 12,
            probe_every: 16,
            reprobe_every: 600,
            reprobe_frames: 48,
            warmup: 33,
            min_dwell: 120,
            decide_every: 2,
            resamples: 400,
            min_psnr: None,
            watch_every: 64,
            period: 32,
            min_period: 2,
            raise_after: 4,
            raise_margin: 3.0,
            variants: 1,
            trial_probe_every: 4,
            retrial_every: 3000,
        }
    }
}

impl GovernorSettings {
    /// The defaults for a variant of `plan`: its cache warms up over its
    /// refresh period Δn and a frame, and a re-probe's burst is that warm-up
    /// and enough pairs for a decision. Its Δn is where the watch starts;
    /// a variant whose Δn is fixed by its passes (`lowres`'s lattice) has
    /// no lower one, and a watch that trips turns it off.
    pub fn for_plan(plan: &shadecache_plan::Plan) -> GovernorSettings {
        let defaults = GovernorSettings::default();
        let warmup = plan.refresh.period.max(1) + 1;
        let period = plan.refresh.period;
        GovernorSettings {
            warmup,
            reprobe_frames: warmup + defaults.min_samples as u32 + 4,
            period,
            min_period: if plan.upsampling.is_some() {
                period
            } else {
                defaults.min_period
            },
            ..defaults
        }
    }

    /// These settings with an error budget: the least PSNR, in dB, a
    /// watched frame may have.
    pub fn with_min_psnr(self, min_psnr: f64) -> GovernorSettings {
        GovernorSettings {
            min_psnr: Some(min_psnr),
            ..self
        }
    }

    /// Why these settings cannot govern: a window smaller than the samples
    /// a decision needs, a burst that is all warm-up, a zero cadence.
    pub fn check(&self) -> Result<(), String> {
        if self.min_samples < 4 || self.window < self.min_samples {
            return Err(format!(
                "the governor's window ({}) must hold its minimum samples ({}), at least 4",
                self.window, self.min_samples
            ));
        }
        if self.variants == 0 {
            return Err("the governor governs at least one variant".into());
        }
        if self.probe_every < 2
            || self.trial_probe_every < 2
            || self.decide_every == 0
            || self.resamples < 100
        {
            return Err("the governor probes one frame in 2 or more, decides every 1 or more measured frames, and resamples 100 times or more".into());
        }
        if let Some(min_psnr) = self.min_psnr {
            if !min_psnr.is_finite()
                || self.watch_every < 2
                || self.raise_after == 0
                || !self.raise_margin.is_finite()
            {
                return Err(format!(
                    "an error budget is a finite PSNR ({min_psnr} dB here), watched one frame in 2 or more ({} here), raised after 1 or more watches within a finite margin",
                    self.watch_every
                ));
            }
        }
        if self.reprobe_frames <= self.warmup || self.reprobe_every <= self.reprobe_frames {
            return Err(format!(
                "a burst of {} cached frames every {} frames leaves nothing after a warm-up of {}",
                self.reprobe_frames, self.reprobe_every, self.warmup
            ));
        }
        Ok(())
    }
}

/// How an application runs its cache: what a game's settings menu or a
/// build's configuration sets, and what a [`Governor`] made with
/// [`Governor::for_mode`] follows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CacheMode {
    /// The cached variant every frame: the developer measured it pays.
    Always,
    /// The original every frame.
    Off,
    /// The governor decides from this GPU's frame times; with
    /// `min_psnr`, the error watch keeps the cached frames within that
    /// PSNR (dB) of the original.
    Auto {
        /// The error budget ([`GovernorSettings::min_psnr`]).
        min_psnr: Option<f64>,
    },
}

impl Default for CacheMode {
    /// `Auto`, with no error budget.
    fn default() -> Self {
        CacheMode::Auto { min_psnr: None }
    }
}

/// What the application draws this frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Choice {
    /// The original shader.
    Original,
    /// The cached variant; with `reset`, the cache starts afresh first
    /// (`CachedShader::reset`).
    Cached {
        /// Whether the cache starts afresh this frame.
        reset: bool,
    },
}

/// One frame the governor asked for: its number, to give back with its
/// GPU time, and what to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GovernedFrame {
    /// The frame's number, for [`Governor::measured`].
    pub frame: u64,
    /// What to draw.
    pub choice: Choice,
    /// The refresh period Δn a cached frame runs with
    /// (`CachedShader::set_refresh_period` where it changed).
    pub period: u32,
    /// Whether this cached frame is watched: the original is drawn as
    /// well, into the watch's spare target, and the two compared
    /// ([`crate::ErrorWatch::compare`]); its PSNR goes to
    /// [`Governor::watched`].
    pub watch: bool,
    /// Which of the application's variants a cached frame draws (0 with
    /// one).
    pub variant: usize,
}

/// The speed-up the governor holds: the ratio of the medians and its 95%
/// interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpeedEstimate {
    /// Median original frame time over median cached frame time.
    pub speedup: f64,
    /// Its bootstrap interval.
    pub interval: [f64; 2],
}

/// A decision: the cache on or off, or its refresh period, from a frame
/// on, and why.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Decision {
    /// The frame it applies from.
    pub frame: u64,
    /// Whether the cache is on.
    pub on: bool,
    /// The refresh period Δn from then.
    pub period: u32,
    /// The variant drawn from then.
    pub variant: usize,
    /// The speed-up last weighed when it was made (`None` before there
    /// were enough frames to weigh).
    pub estimate: Option<SpeedEstimate>,
    /// Why.
    pub cause: Cause,
}

/// Why the governor decided.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Cause {
    /// The speed-up's interval lay wholly on the other side of 1×.
    Speed,
    /// A watched frame was below the error budget, at this PSNR (dB): Δn
    /// halved, or the cache off at the floor.
    Error {
        /// The watched frame's PSNR.
        psnr: f64,
    },
    /// The watched frames stayed well within the budget, the last at
    /// this PSNR (dB): a lowered Δn doubled again.
    Margin {
        /// The last watched frame's PSNR.
        psnr: f64,
    },
    /// A trial of the variants ended: the variant drawn is the fastest of
    /// those within the budget ([`Governor::trials`] has each one's
    /// figures).
    Trial,
}

/// One variant's turn in a trial.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrialTurn {
    /// The variant.
    pub variant: usize,
    /// Its speed-up against the original over its turn.
    pub estimate: SpeedEstimate,
    /// Its watched frame's PSNR (dB), with a budget.
    pub psnr: Option<f64>,
}

/// A trial in progress: the variant on turn, and the turns taken.
#[derive(Clone, Debug)]
struct Trial {
    variant: usize,
    turns: Vec<TrialTurn>,
    /// The watched PSNR of the variant on turn, once read.
    psnr: Option<f64>,
}

/// What a frame was, as far as measuring goes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Original,
    /// A cached frame, counted once the cache is warm.
    Cached {
        warm: bool,
    },
    /// A cached frame that was watched: it cost the original and the
    /// comparison too.
    Watched,
}

/// Decides per frame whether the application draws the original or the
/// cached frame, from the GPU times of the frames drawn (module docs).
#[derive(Clone, Debug)]
pub struct Governor {
    settings: GovernorSettings,
    on: bool,
    /// The next frame's number.
    frame: u64,
    /// The frame the last decision applies from.
    since: u64,
    /// Cached frames drawn since the cache last started afresh.
    warm_frames: u32,
    /// Whether the next cached frame starts the cache afresh.
    reset_next: bool,
    /// The refresh period Δn cached frames run with.
    period: u32,
    /// The watched frame whose error is awaited, with its epoch.
    watching: Option<(u64, u32)>,
    /// Whether the last watch since the pairs started afresh was within
    /// the budget (while off: whether the burst's frame was).
    watch_ok: bool,
    /// Times of watched frames (the original and the comparison on top
    /// of a cached frame), the latest few, and whether the first one was
    /// measured (it is not counted).
    watch_times: VecDeque<f64>,
    watch_used: bool,
    /// Watched frames in a row well within the budget, and how many a
    /// raise of Δn needs now (doubled by a raise that tripped).
    within: u32,
    raise_after: u32,
    /// Whether the last change of Δn was a raise.
    raised_last: bool,
    /// The variant cached frames draw, the trial in progress, the frame
    /// the last one ended, and every trial's turns.
    variant: usize,
    trial: Option<Trial>,
    trial_ended: u64,
    trials: Vec<Vec<TrialTurn>>,
    /// Frames asked for and not yet measured, by number, with the epoch
    /// of pairs they were drawn in.
    pending: VecDeque<(u64, Kind, u32)>,
    /// Counts the times the pairs started afresh: a time that arrives
    /// after that, of a frame drawn before, is of a cache that is gone.
    epoch: u32,
    /// The latest time of each kind, and the windows of paired times.
    last_original: Option<f64>,
    last_cached: Option<f64>,
    originals: VecDeque<f64>,
    cached: VecDeque<f64>,
    /// Measured frames since the last decision was weighed.
    undecided: u32,
    estimate: Option<SpeedEstimate>,
    decisions: Vec<Decision>,
    /// `Some` for [`CacheMode::Always`] (true) and [`CacheMode::Off`]:
    /// nothing is measured or decided.
    fixed: Option<bool>,
}

/// Frames asked for and never measured that the governor forgets: a time
/// that never comes (a frame the application dropped) does not grow it.
const MAX_PENDING: usize = 256;

/// Watched frames' times kept for the watch's cost.
const WATCH_TIMES: usize = 8;

impl Governor {
    /// A governor with the cache on (the developer chose it); the first
    /// original frames measure it.
    pub fn new(settings: GovernorSettings) -> Result<Governor, String> {
        settings.check()?;
        Ok(Governor {
            on: true,
            frame: 0,
            since: 0,
            warm_frames: 0,
            reset_next: true,
            period: settings.period,
            watching: None,
            watch_ok: false,
            watch_times: VecDeque::new(),
            watch_used: false,
            within: 0,
            raise_after: settings.raise_after,
            raised_last: false,
            variant: 0,
            trial: None,
            trial_ended: 0,
            trials: Vec::new(),
            pending: VecDeque::new(),
            epoch: 0,
            last_original: None,
            last_cached: None,
            originals: VecDeque::new(),
            cached: VecDeque::new(),
            undecided: 0,
            estimate: None,
            decisions: Vec::new(),
            fixed: None,
            settings,
        })
    }

    /// A governor for a variant of `plan` in `mode`: `Auto` governs with
    /// [`GovernorSettings::for_plan`] (and its budget); `Always` and `Off`
    /// draw the one way every frame (the cache starting afresh on its
    /// first), and measure and decide nothing, so that an application has
    /// one render loop for every mode.
    pub fn for_mode(mode: CacheMode, plan: &shadecache_plan::Plan) -> Result<Governor, String> {
        let settings = GovernorSettings::for_plan(plan);
        let (settings, fixed) = match mode {
            CacheMode::Always => (settings, Some(true)),
            CacheMode::Off => (settings, Some(false)),
            CacheMode::Auto { min_psnr: None } => (settings, None),
            CacheMode::Auto {
                min_psnr: Some(min_psnr),
            } => (settings.with_min_psnr(min_psnr), None),
        };
        let mut governor = Governor::new(settings)?;
        governor.fixed = fixed;
        governor.on = fixed != Some(false);
        Ok(governor)
    }

    /// Every trial of the variants, each the turns it took, in order.
    pub fn trials(&self) -> &[Vec<TrialTurn>] {
        &self.trials
    }

    /// The variant cached frames draw now.
    pub fn variant(&self) -> usize {
        self.variant
    }

    /// Whether the cache is on.
    pub fn is_on(&self) -> bool {
        self.on
    }

    /// The refresh period Δn cached frames run with now.
    pub fn period(&self) -> u32 {
        self.period
    }

    /// The speed-up last weighed, if there were enough frames of each kind.
    pub fn estimate(&self) -> Option<SpeedEstimate> {
        self.estimate
    }

    /// Every switch, in order.
    pub fn decisions(&self) -> &[Decision] {
        &self.decisions
    }

    /// What to draw for the next frame, and its number.
    pub fn next_frame(&mut self) -> GovernedFrame {
        let frame = self.frame;
        self.frame += 1;
        if let Some(on) = self.fixed {
            return GovernedFrame {
                frame,
                choice: if on {
                    self.cached_frame()
                } else {
                    Choice::Original
                },
                period: self.period,
                watch: false,
                variant: self.variant,
            };
        }
        if self.settings.variants > 1 && self.trial.is_none() && self.on {
            let due = frame == 0
                || frame.saturating_sub(self.trial_ended) >= u64::from(self.settings.retrial_every);
            if due {
                self.trial = Some(Trial {
                    variant: 0,
                    turns: Vec::new(),
                    psnr: None,
                });
                self.start_pairs_afresh(true);
            }
        }
        let draw = if self.on {
            let since = frame - self.since;
            let every = u64::from(match self.trial {
                Some(_) => self.settings.trial_probe_every,
                None => self.settings.probe_every,
            });
            if since % every == every - 1 {
                Choice::Original
            } else {
                self.cached_frame()
            }
        } else {
            // The first burst a re-probe period after the switch off.
            let every = u64::from(self.settings.reprobe_every);
            let elapsed = frame - self.since;
            let into = elapsed % every;
            if elapsed >= every && into < u64::from(self.settings.reprobe_frames) {
                if into == 0 {
                    // A new burst: the cached frames of the last one are
                    // of another scene; it tries the next variant.
                    self.start_pairs_afresh(true);
                    self.variant = (self.variant + 1) % self.settings.variants;
                }
                self.cached_frame()
            } else {
                Choice::Original
            }
        };
        let warm = self.warm_frames > self.settings.warmup;
        let watch = matches!(draw, Choice::Cached { .. }) && warm && self.watch_due();
        let kind = match draw {
            Choice::Original => Kind::Original,
            Choice::Cached { .. } if watch => Kind::Watched,
            Choice::Cached { .. } => Kind::Cached { warm },
        };
        if watch {
            self.watching = Some((frame, self.epoch));
        }
        if self.pending.len() == MAX_PENDING {
            self.pending.pop_front();
        }
        self.pending.push_back((frame, kind, self.epoch));
        GovernedFrame {
            frame,
            choice: draw,
            period: self.period,
            watch,
            variant: self.trial.as_ref().map_or(self.variant, |t| t.variant),
        }
    }

    /// Whether this warm cached frame is watched: with a budget, the
    /// first warm frame since the pairs started afresh (a burst's one
    /// watch) and every `watch_every` after it, while no other watch is
    /// awaited.
    fn watch_due(&self) -> bool {
        if self.settings.min_psnr.is_none() || self.watching.is_some() {
            return false;
        }
        let into = self.warm_frames - self.settings.warmup - 1;
        into.is_multiple_of(self.settings.watch_every)
    }

    /// Forgets the pairs and the latest cached time, and warms the cache
    /// up again (started afresh at its next frame with `reset`): what was
    /// measured is of a cache that is gone, or of another Δn.
    fn start_pairs_afresh(&mut self, reset: bool) {
        self.originals.clear();
        self.cached.clear();
        self.last_cached = None;
        self.warm_frames = 0;
        self.reset_next |= reset;
        self.watching = None;
        self.watch_ok = false;
        self.epoch = self.epoch.wrapping_add(1);
    }

    /// A cached frame: the first after a switch on or a burst's start
    /// starts afresh.
    fn cached_frame(&mut self) -> Choice {
        let reset = std::mem::take(&mut self.reset_next);
        self.warm_frames = self.warm_frames.saturating_add(1);
        Choice::Cached { reset }
    }

    /// The GPU time of frame `frame`, in milliseconds, once read; a frame
    /// not asked for (or forgotten) is ignored. May switch the cache for
    /// the frames after.
    pub fn measured(&mut self, frame: u64, gpu_ms: f64) {
        if self.fixed.is_some() {
            return;
        }
        let at = self.pending.iter().position(|(f, _, _)| *f == frame);
        let Some((_, kind, epoch)) = at.and_then(|at| self.pending.remove(at)) else {
            return;
        };
        if epoch != self.epoch {
            return;
        }
        if !gpu_ms.is_finite() || gpu_ms <= 0.0 {
            return;
        }
        match kind {
            Kind::Original => self.last_original = Some(gpu_ms),
            Kind::Cached { warm: true } => self.last_cached = Some(gpu_ms),
            Kind::Cached { warm: false } => return,
            Kind::Watched => {
                // The first watched frame pays the watch's first use, and
                // one slow frame weighs in full in a trial's one-watch turn
                // (Bevy's PBR on lavapipe: 12.7 ms against 5.0–8.6 for the
                // next, 236 ms against 8 on a busy machine): it is not
                // counted, as a cache's warm-up is not.
                if !std::mem::replace(&mut self.watch_used, true) {
                    return;
                }
                if self.watch_times.len() == WATCH_TIMES {
                    self.watch_times.pop_front();
                }
                self.watch_times.push_back(gpu_ms);
                return;
            }
        }
        // Each frame of the kind drawn rarely is paired with the latest
        // of the other: both windows span the same frames, so a slow
        // stretch of the machine weighs on both alike.
        let rare = kind
            == if self.on {
                Kind::Original
            } else {
                Kind::Cached { warm: true }
            };
        let (Some(original), Some(cached), true) = (self.last_original, self.last_cached, rare)
        else {
            return;
        };
        for (window, ms) in [(&mut self.originals, original), (&mut self.cached, cached)] {
            if window.len() == self.settings.window {
                window.pop_front();
            }
            window.push_back(ms);
        }
        if self.trial.is_some() {
            if self.originals.len() >= self.settings.min_samples {
                self.end_turn();
            }
            return;
        }
        self.undecided += 1;
        if self.undecided >= self.settings.decide_every {
            self.undecided = 0;
            self.weigh();
        }
    }

    /// Ends the turn of the variant on trial with its figures, and starts
    /// the next variant's, or ends the trial.
    fn end_turn(&mut self) {
        let Some(estimate) = self.estimate_now() else {
            return;
        };
        self.estimate = Some(estimate);
        let Some(trial) = self.trial.as_mut() else {
            return;
        };
        // A budget needs the turn's watched frame: its answer is a few
        // frames late (a turn that never gets one, after a whole window of
        // pairs, ends without it and is not within the budget).
        let awaited = self.settings.min_psnr.is_some() && trial.psnr.is_none();
        if awaited && self.watching.is_some() && self.originals.len() < self.settings.window {
            return;
        }
        trial.turns.push(TrialTurn {
            variant: trial.variant,
            estimate,
            psnr: trial.psnr.take(),
        });
        trial.variant += 1;
        if trial.variant < self.settings.variants {
            self.start_pairs_afresh(true);
            return;
        }
        let Some(trial) = self.trial.take() else {
            return;
        };
        self.end_trial(trial.turns);
    }

    /// Draws the fastest variant of the trial's turns within the budget
    /// (the fastest of all where none is), and turns the cache off where
    /// even it loses.
    fn end_trial(&mut self, turns: Vec<TrialTurn>) {
        let within = |turn: &&TrialTurn| match (self.settings.min_psnr, turn.psnr) {
            (Some(min_psnr), Some(psnr)) => psnr >= min_psnr,
            (Some(_), None) => false,
            (None, _) => true,
        };
        let fastest = |turns: &mut dyn Iterator<Item = &TrialTurn>| {
            turns
                .max_by(|a, b| a.estimate.speedup.total_cmp(&b.estimate.speedup))
                .copied()
        };
        let best = fastest(&mut turns.iter().filter(within)).or_else(|| fastest(&mut turns.iter()));
        self.trials.push(turns);
        self.trial_ended = self.frame;
        let Some(best) = best else {
            return;
        };
        self.variant = best.variant;
        self.estimate = Some(best.estimate);
        self.switch(best.estimate.interval[1] >= 1.0, Cause::Trial);
    }

    /// Weighs the windows, and switches where the interval lies wholly on
    /// the other side of 1× and the last decision has held long enough.
    fn weigh(&mut self) {
        let Some(estimate) = self.estimate_now() else {
            return;
        };
        self.estimate = Some(estimate);
        if self.frame - self.since < u64::from(self.settings.min_dwell) {
            return;
        }
        let switch = if self.on {
            estimate.interval[1] < 1.0
        } else {
            // On again only where the burst's watched frame was within
            // the budget.
            estimate.interval[0] > 1.0 && (self.settings.min_psnr.is_none() || self.watch_ok)
        };
        if switch {
            self.switch(!self.on, Cause::Speed);
        }
    }

    /// The speed-up of the windows, with the watch's cost; `None` with
    /// fewer pairs than a decision needs.
    fn estimate_now(&self) -> Option<SpeedEstimate> {
        let min = self.settings.min_samples;
        if self.originals.len() < min || self.cached.len() < min {
            return None;
        }
        let originals: Vec<f64> = self.originals.iter().copied().collect();
        let mut cached: Vec<f64> = self.cached.iter().copied().collect();
        // The watch's extra, spread over the frames between two watches,
        // is part of what a cached frame costs.
        let overhead = self.watch_overhead(&cached);
        for ms in &mut cached {
            *ms += overhead;
        }
        Some(SpeedEstimate {
            speedup: median(&originals) / median(&cached),
            interval: speedup_interval_resampled(&originals, &cached, self.settings.resamples),
        })
    }

    /// The watch's extra cost per frame: a watched frame's median time
    /// over a cached frame's, spread over `watch_every` frames; 0 without
    /// a budget or a watched time.
    fn watch_overhead(&self, cached: &[f64]) -> f64 {
        if self.settings.min_psnr.is_none() || self.watch_times.is_empty() || cached.is_empty() {
            return 0.0;
        }
        let watched: Vec<f64> = self.watch_times.iter().copied().collect();
        (median(&watched) - median(cached)).max(0.0) / f64::from(self.settings.watch_every)
    }

    /// Turns the cache on or off (or keeps it, at the end of a trial)
    /// from the next frame, and says why.
    fn switch(&mut self, on: bool, cause: Cause) {
        self.on = on;
        self.since = self.frame;
        // The new state's pairs are its own: a cache that starts afresh,
        // or bursts of it among original frames.
        self.start_pairs_afresh(true);
        self.decided(cause);
    }

    /// Keeps the decision just made, of the state the governor is in now.
    fn decided(&mut self, cause: Cause) {
        self.decisions.push(Decision {
            frame: self.frame,
            on: self.on,
            period: self.period,
            variant: self.variant,
            estimate: self.estimate,
            cause,
        });
    }

    /// The error of watched frame `frame` (PSNR in dB, as the
    /// [`crate::ErrorWatch`] gives it), once read. Below the budget the
    /// refresh period halves, down to the floor; below it at the floor,
    /// the cache turns off. A frame not watched, or watched before the
    /// pairs last started afresh, is ignored.
    pub fn watched(&mut self, frame: u64, psnr: f64) {
        let (Some(min_psnr), Some((watched, epoch))) = (self.settings.min_psnr, self.watching)
        else {
            return;
        };
        if watched != frame {
            return;
        }
        self.watching = None;
        if epoch != self.epoch {
            return;
        }
        // A NaN is no measurement of being within the budget.
        self.watch_ok = psnr >= min_psnr;
        if let Some(trial) = self.trial.as_mut() {
            // The turn's variant's figure; the trial decides.
            trial.psnr = Some(psnr);
            return;
        }
        if !self.on {
            // Off, a burst's frame below the budget keeps the cache off.
            return;
        }
        if self.watch_ok {
            self.within_budget(psnr, min_psnr);
            return;
        }
        self.within = 0;
        if std::mem::take(&mut self.raised_last) {
            // The raise was one too many: the next needs twice the watches.
            self.raise_after = self.raise_after.saturating_mul(2);
        }
        let cause = Cause::Error { psnr };
        if self.period > self.settings.min_period || self.period == 0 {
            // Δn = 0 refreshes nothing: its first step down is to 32.
            let period = match self.period {
                0 => 32,
                period => (period / 2).max(self.settings.min_period),
            };
            self.change_period(period, cause);
        } else {
            self.switch(false, cause);
        }
    }

    /// Frame `frame` was to be watched and was not (the application's
    /// watch still waited for its last answer, or cannot run): it is an
    /// ordinary cached frame, and the next watch is the next due. Without
    /// this, the governor would wait for its answer and watch nothing
    /// more.
    pub fn unwatched(&mut self, frame: u64) {
        if self.watching.is_some_and(|(watched, _)| watched == frame) {
            self.watching = None;
        }
        if let Some(pending) = self.pending.iter_mut().find(|(f, _, _)| *f == frame) {
            if pending.1 == Kind::Watched {
                pending.1 = Kind::Cached { warm: true };
            }
        }
    }

    /// The application cannot watch at all (its frames cannot be read
    /// as the watch needs): the speed alone decides from now on, as
    /// without a budget, instead of waiting for watches that never come
    /// (a cache the budget turned off could not turn on again).
    pub fn drop_budget(&mut self) {
        self.settings.min_psnr = None;
        self.watching = None;
    }

    /// A watched frame within the budget: after `raise_after` in a row
    /// well within it, a lowered Δn doubles again, up to the variant's.
    fn within_budget(&mut self, psnr: f64, min_psnr: f64) {
        let highest = self.settings.period;
        let lowered = match highest {
            // No refresh: lowered to 32 and below, raised back to none.
            0 => self.period != 0,
            highest => self.period < highest,
        };
        if psnr < min_psnr + self.settings.raise_margin || !lowered {
            self.within = 0;
            return;
        }
        self.within += 1;
        if self.within < self.raise_after {
            return;
        }
        self.within = 0;
        let period = match highest {
            0 if self.period >= 32 => 0,
            0 => self.period * 2,
            highest => self.period.saturating_mul(2).min(highest),
        };
        self.change_period(period, Cause::Margin { psnr });
        self.raised_last = true;
    }

    /// Runs the cache at Δn = `period` from the next frame, and says why.
    fn change_period(&mut self, period: u32, cause: Cause) {
        self.period = period;
        self.raised_last = false;
        // The cache keeps what it holds; the times are of another Δn.
        self.start_pairs_afresh(false);
        self.decided(cause);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Frame times with ±`spread` relative noise, seeded.
    struct Noise(u64);

    impl Noise {
        fn around(&mut self, ms: f64, spread: f64) -> f64 {
            self.0 ^= self.0 << 13;
            self.0 ^= self.0 >> 7;
            self.0 ^= self.0 << 17;
            let unit = (self.0 >> 11) as f64 / (1u64 << 53) as f64;
            ms * (1.0 + spread * (2.0 * unit - 1.0))
        }
    }

    /// Runs `frames` frames, each measured `lag` frames later, the
    /// original costing `original(frame)` and a warm cached frame
    /// `cached(frame)` (a cold one costs the original's and more). The
    /// frame times drawn, in order.
    fn play(
        governor: &mut Governor,
        frames: u64,
        lag: usize,
        original: impl Fn(u64) -> f64,
        cached: impl Fn(u64) -> f64,
    ) -> Vec<(Choice, f64)> {
        play_watched(governor, frames, lag, (original, cached), |_, _| 100.0)
    }

    /// [`play`], a watched frame costing the cached frame and the
    /// original, its PSNR `psnr(frame, Δn)` given back with its time.
    fn play_watched(
        governor: &mut Governor,
        frames: u64,
        lag: usize,
        (original, cached): (impl Fn(u64) -> f64, impl Fn(u64) -> f64),
        psnr: impl Fn(u64, u32) -> f64,
    ) -> Vec<(Choice, f64)> {
        play_variants(
            governor,
            (frames, lag),
            (original, |frame, _| cached(frame)),
            |frame, period, _| psnr(frame, period),
        )
    }

    /// [`play_watched`] with several variants: a warm cached frame of
    /// variant v costs `cached(frame, v)`, a watched one's PSNR is
    /// `psnr(frame, Δn, v)`.
    fn play_variants(
        governor: &mut Governor,
        (frames, lag): (u64, usize),
        (original, cached): (impl Fn(u64) -> f64, impl Fn(u64, usize) -> f64),
        psnr: impl Fn(u64, u32, usize) -> f64,
    ) -> Vec<(Choice, f64)> {
        let mut noise = Noise(0x2545_F491_4F6C_DD1D);
        let mut drawn = Vec::new();
        let mut in_flight: VecDeque<(GovernedFrame, f64)> = VecDeque::new();
        let mut warm = 0u32;
        for _ in 0..frames {
            let next = governor.next_frame();
            let mut ms = match next.choice {
                Choice::Original => noise.around(original(next.frame), 0.05),
                Choice::Cached { reset } => {
                    warm = if reset { 0 } else { warm + 1 };
                    let cold = warm < 8;
                    let base = if cold {
                        original(next.frame) * 1.1
                    } else {
                        cached(next.frame, next.variant)
                    };
                    noise.around(base, 0.05)
                }
            };
            if next.watch {
                ms += original(next.frame) * 1.05;
            }
            drawn.push((next.choice, ms));
            in_flight.push_back((next, ms));
            if in_flight.len() > lag {
                let (frame, ms) = in_flight.pop_front().unwrap();
                governor.measured(frame.frame, ms);
                if frame.watch {
                    let db = psnr(frame.frame, frame.period, frame.variant);
                    governor.watched(frame.frame, db);
                }
            }
        }
        drawn
    }

    fn mean_ms(drawn: &[(Choice, f64)]) -> f64 {
        drawn.iter().map(|(_, ms)| ms).sum::<f64>() / drawn.len() as f64
    }

    fn governor() -> Governor {
        Governor::new(GovernorSettings::default()).unwrap()
    }

    #[test]
    fn a_losing_cache_is_turned_off_and_costs_little_after() {
        let mut g = governor();
        let drawn = play(&mut g, 3000, 3, |_| 1.0, |_| 1.25);
        assert!(!g.is_on(), "{:?}", g.decisions());
        assert_eq!(g.decisions().len(), 1, "{:?}", g.decisions());
        let off_at = g.decisions()[0].frame as usize;
        assert!(off_at <= 400, "turned off at frame {off_at}");
        // No cached frame for a re-probe period after the switch, then
        // bursts that cost a few percent over the original.
        assert!(
            drawn[off_at..off_at + 600]
                .iter()
                .all(|(choice, _)| *choice == Choice::Original),
            "a cached frame within 600 frames of the switch off"
        );
        let after = mean_ms(&drawn[off_at..]);
        assert!(after < 1.05, "mean {after} ms after switching off");
    }

    #[test]
    fn a_winning_cache_is_kept_with_most_of_its_gain() {
        let mut g = governor();
        let drawn = play(&mut g, 3000, 3, |_| 1.0, |_| 0.5);
        assert!(g.is_on());
        assert!(g.decisions().is_empty(), "{:?}", g.decisions());
        let estimate = g.estimate().unwrap();
        assert!(estimate.interval[0] > 1.5, "{estimate:?}");
        // The fixed cache saves 0.5 ms a frame; the probes keep ≥ 90% of it.
        let kept = (1.0 - mean_ms(&drawn[100..])) / 0.5;
        assert!(kept >= 0.9, "kept {kept:.3} of the gain");
    }

    #[test]
    fn a_scene_that_changes_weight_is_followed_both_ways() {
        let mut g = governor();
        // The cache wins for 1500 frames, then loses, then wins again.
        let cached = |frame: u64| {
            if (1500..3500).contains(&frame) {
                1.4
            } else {
                0.5
            }
        };
        play(&mut g, 6000, 3, |_| 1.0, cached);
        let switches: Vec<(u64, bool)> = g.decisions().iter().map(|d| (d.frame, d.on)).collect();
        assert_eq!(switches.len(), 2, "{switches:?}");
        let (off, on) = (switches[0], switches[1]);
        // Off within 400 frames of the change: the pairs come one in 16
        // frames, and the window's median turns after half of it is new.
        assert!(!off.1 && (1500..1900).contains(&off.0), "{switches:?}");
        // Back on at a burst after 3500: within a re-probe period and a burst.
        assert!(
            on.1 && (3500..3500 + 600 + 48 + 120).contains(&on.0),
            "{switches:?}"
        );
    }

    /// The machine slows down for a while (another tenant, a clock
    /// change): every frame takes 1.8 times as long. The original frames
    /// are rare while the cache is on; compared with cached frames of
    /// another stretch of time, the cache would look like a loss.
    #[test]
    fn a_slow_stretch_of_the_machine_does_not_switch_a_winning_cache_off() {
        let mut g = governor();
        let slow = |frame: u64| {
            if (500..650).contains(&frame) {
                1.8
            } else {
                1.0
            }
        };
        play(&mut g, 2000, 3, slow, move |frame| 0.8 * slow(frame));
        assert!(g.decisions().is_empty(), "{:?}", g.decisions());
    }

    #[test]
    fn a_cache_at_one_to_one_does_not_flap() {
        let mut g = governor();
        play(&mut g, 1000, 3, |_| 1.0, |_| 1.0);
        assert!(g.decisions().len() <= 1, "{:?}", g.decisions());
    }

    #[test]
    fn switching_on_starts_the_cache_afresh() {
        let mut g = governor();
        let cached = |frame: u64| if frame < 1000 { 1.4 } else { 0.5 };
        let drawn = play(&mut g, 3000, 2, |_| 1.0, cached);
        let on = g
            .decisions()
            .iter()
            .find(|d| d.on)
            .expect("switched back on");
        let first = drawn[on.frame as usize..]
            .iter()
            .find(|(draw, _)| matches!(draw, Choice::Cached { .. }))
            .unwrap();
        assert_eq!(first.0, Choice::Cached { reset: true });
    }

    /// A frame drawn before a switch whose time arrives after it is of
    /// the cache as it was: it does not enter the new state's pairs.
    #[test]
    fn a_time_from_before_a_switch_is_not_paired_after_it() {
        let mut g = governor();
        let mut held = None;
        // A losing cache, each time given back at once but one cached
        // frame's, held until the governor has switched off.
        while g.is_on() {
            let next = g.next_frame();
            let ms = match next.choice {
                Choice::Original => 1.0,
                Choice::Cached { .. } => 1.5,
            };
            if held.is_none() && next.frame > 100 && ms > 1.0 {
                held = Some((next.frame, ms));
                continue;
            }
            g.measured(next.frame, ms);
            assert!(next.frame < 5000, "never switched off");
        }
        let (frame, ms) = held.expect("a cached frame was held back");
        // Off, before its first re-probe: no cached time is paired.
        for _ in 0..500 {
            let next = g.next_frame();
            g.measured(next.frame, 1.0);
        }
        assert!(g.last_cached.is_none() && g.cached.is_empty());
        g.measured(frame, ms);
        assert!(g.last_cached.is_none() && g.cached.is_empty());
    }

    /// `Always` and `Off` draw one way every frame, whatever the times.
    #[test]
    fn fixed_modes_draw_one_way_and_decide_nothing() {
        let plan: shadecache_plan::Plan = serde_json::from_str(include_str!(
            "../tests/fixtures/square/three-pass/plan.json"
        ))
        .unwrap();
        for (mode, cached) in [(CacheMode::Always, true), (CacheMode::Off, false)] {
            let mut g = Governor::for_mode(mode, &plan).unwrap();
            let drawn = play(&mut g, 2000, 3, |_| 1.0, |_| 2.0);
            assert!(g.decisions().is_empty());
            assert_eq!(g.is_on(), cached);
            assert!(drawn
                .iter()
                .all(|(choice, _)| matches!(choice, Choice::Cached { .. }) == cached));
            assert_eq!(drawn[0].0 == Choice::Cached { reset: true }, cached);
        }
        let auto = Governor::for_mode(
            CacheMode::Auto {
                min_psnr: Some(30.0),
            },
            &plan,
        )
        .unwrap();
        assert_eq!(auto.settings.min_psnr, Some(30.0));
        assert_eq!(auto.period(), plan.refresh.period);
    }

    #[test]
    fn times_of_frames_not_asked_for_are_ignored() {
        let mut g = governor();
        for _ in 0..10 {
            g.next_frame();
        }
        g.measured(12345, 1.0);
        g.measured(3, f64::NAN);
        assert_eq!(g.pending.len(), 9);
        assert!(GovernorSettings {
            window: 8,
            min_samples: 12,
            ..Default::default()
        }
        .check()
        .is_err());
    }

    fn watched_governor() -> Governor {
        Governor::new(GovernorSettings::default().with_min_psnr(30.0)).unwrap()
    }

    /// The light starts to move at frame 1000: the cached shading lags
    /// it, the more the longer Δn (3 dB a halving, within the budget of 30
    /// dB from Δn = 8). The watch halves Δn from 32 to 8 and the cache
    /// stays on.
    #[test]
    fn the_watch_lowers_delta_n_until_the_error_is_within_budget() {
        let mut g = watched_governor();
        let psnr = |frame: u64, period: u32| {
            if frame < 1000 {
                45.0
            } else {
                24.0 + 3.0 * (5.0 - f64::from(period).log2())
            }
        };
        play_watched(&mut g, 3000, 3, (|_| 1.0, |_| 0.5), psnr);
        assert!(g.is_on(), "{:?}", g.decisions());
        assert_eq!(g.period(), 8, "{:?}", g.decisions());
        let steps: Vec<(u64, u32)> = g.decisions().iter().map(|d| (d.frame, d.period)).collect();
        assert_eq!(steps.len(), 2, "{steps:?}");
        assert!(steps.iter().all(|&(frame, _)| frame >= 1000), "{steps:?}");
        assert!(g
            .decisions()
            .iter()
            .all(|d| d.on && matches!(d.cause, Cause::Error { psnr } if psnr < 30.0)));
        // Each step within a watch period and a warm-up of the change.
        assert!(steps[1].0 < 1000 + 2 * (64 + 40) + 10, "{steps:?}");
    }

    /// Below the budget at every Δn, the watch lowers Δn to the floor and
    /// then turns the cache off, and the re-probes' watches keep it off
    /// while the error stays: a cache that pays and looks wrong is off.
    #[test]
    fn the_watch_turns_the_cache_off_at_the_floor_and_keeps_it_off() {
        let mut g = watched_governor();
        let psnr = |frame: u64, _| if frame < 500 { 45.0 } else { 20.0 };
        let drawn = play_watched(&mut g, 4000, 3, (|_| 1.0, |_| 0.5), psnr);
        let last = *g.decisions().last().expect("decided");
        assert!(!last.on && last.period == 2, "{:?}", g.decisions());
        assert!(!g.is_on());
        assert_eq!(
            g.decisions().iter().filter(|d| !d.on).count(),
            1,
            "{:?}",
            g.decisions()
        );
        // The re-probes' bursts only, after the switch off.
        let cached = drawn[last.frame as usize..]
            .iter()
            .filter(|(choice, _)| *choice != Choice::Original)
            .count() as u64;
        let settings = GovernorSettings::default();
        let bursts = (4000 - last.frame) / u64::from(settings.reprobe_every);
        assert!(
            cached <= bursts * u64::from(settings.reprobe_frames),
            "{cached} cached frames after the switch off"
        );
    }

    /// A cache just worth it without the watch (0.97 of the original's
    /// time) loses once the watch's cost is counted (the original drawn
    /// again one frame in 8): the governor turns it off.
    #[test]
    fn the_watchs_cost_is_counted_in_the_speedup() {
        let settings = GovernorSettings {
            watch_every: 8,
            ..GovernorSettings::default()
        };
        let mut unwatched = Governor::new(settings.clone()).unwrap();
        play(&mut unwatched, 2000, 3, |_| 1.0, |_| 0.9);
        assert!(unwatched.is_on(), "{:?}", unwatched.decisions());
        let mut watched = Governor::new(settings.with_min_psnr(30.0)).unwrap();
        play_watched(&mut watched, 2000, 3, (|_| 1.0, |_| 0.9), |_, _| 45.0);
        assert!(!watched.is_on(), "{:?}", watched.decisions());
        assert_eq!(watched.decisions()[0].cause, Cause::Speed);
    }

    /// The light moves from frame 1000 to 2000 and then stops: the watch
    /// lowers Δn while it moves and, once the watched frames have stayed
    /// well within the budget, doubles it back to the variant's 32.
    #[test]
    fn the_watch_raises_delta_n_again_once_the_error_stays_within_budget() {
        let mut g = watched_governor();
        let psnr = |frame: u64, period: u32| {
            if (1000..2000).contains(&frame) {
                24.0 + 3.0 * (5.0 - f64::from(period).log2())
            } else {
                45.0
            }
        };
        play_watched(&mut g, 4000, 3, (|_| 1.0, |_| 0.5), psnr);
        let steps: Vec<(u64, u32)> = g.decisions().iter().map(|d| (d.frame, d.period)).collect();
        assert_eq!(g.period(), 32, "{steps:?}");
        assert!(g.is_on());
        let lowest = steps.iter().map(|&(_, p)| p).min().unwrap();
        assert_eq!(lowest, 8, "{steps:?}");
        let raised: Vec<&Decision> = g
            .decisions()
            .iter()
            .filter(|d| matches!(d.cause, Cause::Margin { .. }))
            .collect();
        assert_eq!(raised.len(), 2, "{steps:?}");
        assert!(raised.iter().all(|d| d.frame >= 2000), "{steps:?}");
    }

    /// At the edge of the budget (well within it at Δn = 8, below it at
    /// 16), a raise trips at the next watch;
    /// each such raise doubles the watches the next one needs, so the
    /// governor does not see-saw between the two.
    #[test]
    fn a_raise_that_trips_waits_twice_as_long_for_the_next() {
        let mut g = watched_governor();
        let psnr = |_: u64, period: u32| if period <= 8 { 40.0 } else { 28.0 };
        play_watched(&mut g, 8000, 3, (|_| 1.0, |_| 0.5), psnr);
        let raises: Vec<u64> = g
            .decisions()
            .iter()
            .filter(|d| matches!(d.cause, Cause::Margin { .. }))
            .map(|d| d.frame)
            .collect();
        assert!(
            !raises.is_empty() && raises.len() <= 4,
            "{:?}",
            g.decisions()
        );
        // The gaps between raises grow.
        assert!(
            raises.windows(3).all(|w| w[2] - w[1] > w[1] - w[0]),
            "{raises:?}"
        );
        assert!(g.is_on());
    }

    fn governor_of(variants: usize, min_psnr: Option<f64>) -> Governor {
        Governor::new(GovernorSettings {
            variants,
            min_psnr,
            ..GovernorSettings::default()
        })
        .unwrap()
    }

    /// Three variants: the fastest (0.4 ms) is below the budget, the
    /// next (0.5 ms) within it: the trial at the start tries each and the
    /// governor draws the second, on.
    #[test]
    fn the_fastest_variant_within_the_budget_is_drawn() {
        let mut g = governor_of(3, Some(30.0));
        let costs = [0.8, 0.5, 0.4];
        let psnrs = [45.0, 40.0, 25.0];
        let drawn = play_variants(&mut g, (1500, 3), (|_| 1.0, |_, v| costs[v]), |_, _, v| {
            psnrs[v]
        });
        assert_eq!(g.trials().len(), 1, "{:?}", g.decisions());
        let turns = &g.trials()[0];
        assert_eq!(
            turns.iter().map(|t| t.variant).collect::<Vec<_>>(),
            [0, 1, 2]
        );
        assert!(turns.iter().all(|t| t.psnr.is_some()), "{turns:?}");
        assert!(
            turns[2].estimate.speedup > turns[1].estimate.speedup,
            "{turns:?}"
        );
        assert_eq!(g.variant(), 1);
        assert!(g.is_on());
        assert_eq!(g.decisions()[0].cause, Cause::Trial);
        // The trial is short: it ends within 400 frames.
        assert!(g.decisions()[0].frame < 400, "{:?}", g.decisions());
        assert!(mean_ms(&drawn[500..]) < 0.6, "{}", mean_ms(&drawn[500..]));
    }

    /// Without a budget the fastest variant is drawn; where every variant
    /// loses, the trial turns the cache off, and each re-probe's burst
    /// tries the next variant.
    #[test]
    fn a_trial_where_every_variant_loses_turns_the_cache_off() {
        let mut g = governor_of(2, None);
        let drawn = play_variants(
            &mut g,
            (2000, 3),
            (|_| 1.0, |_, v| [1.4, 1.6][v]),
            |_, _, _| 100.0,
        );
        assert!(!g.is_on(), "{:?}", g.decisions());
        assert_eq!(g.decisions()[0].cause, Cause::Trial);
        assert!(!g.decisions()[0].on);
        let after = g.decisions()[0].frame as usize;
        assert!(
            mean_ms(&drawn[after..]) < 1.05,
            "{}",
            mean_ms(&drawn[after..])
        );
        let mut fastest = governor_of(2, None);
        play_variants(
            &mut fastest,
            (1000, 3),
            (|_| 1.0, |_, v| [0.7, 0.5][v]),
            |_, _, _| 100.0,
        );
        assert_eq!(fastest.variant(), 1);
    }

    /// The variants' costs swap at frame 2000: the trial every 3000 frames
    /// finds it and draws the other.
    #[test]
    fn a_retrial_finds_a_variant_that_became_faster() {
        let mut g = governor_of(2, None);
        let cost = |frame: u64, v: usize| match (frame < 2000, v) {
            (true, 0) | (false, 1) => 0.4,
            _ => 0.7,
        };
        play_variants(&mut g, (4000, 3), (|_| 1.0, cost), |_, _, _| 100.0);
        assert_eq!(g.trials().len(), 2, "{:?}", g.decisions());
        assert_eq!(g.variant(), 1, "{:?}", g.decisions());
        let trials: Vec<usize> = g
            .decisions()
            .iter()
            .filter(|d| d.cause == Cause::Trial)
            .map(|d| d.variant)
            .collect();
        assert_eq!(trials, [0, 1]);
    }

    /// The application skips a watch (its watch still busy, say): told
    /// so, the governor watches the next frame due, and a light that
    /// starts moving later still lowers Δn. Had it waited for the skipped
    /// frame's answer, it would never watch again.
    #[test]
    fn a_watch_the_application_skips_does_not_stop_the_watching() {
        let mut g = watched_governor();
        let mut skipped = 0;
        for _ in 0..3000 {
            let next = g.next_frame();
            let ms = match next.choice {
                Choice::Original => 1.0,
                Choice::Cached { .. } => 0.5,
            };
            g.measured(next.frame, ms);
            if next.watch {
                if skipped < 2 {
                    skipped += 1;
                    g.unwatched(next.frame);
                } else {
                    let psnr = if next.frame < 1500 { 45.0 } else { 25.0 };
                    g.watched(next.frame, psnr);
                }
            }
        }
        assert_eq!(skipped, 2);
        assert!(g.period() < 32, "{:?}", g.decisions());
        assert!(g
            .decisions()
            .iter()
            .all(|d| d.frame >= 1500 && matches!(d.cause, Cause::Error { .. })));
    }

    /// The first watched frame pays the watch's first use (on lavapipe,
    /// Bevy's PBR: 12.7 ms against 5.0–8.6 for the next; 236 ms against 8
    /// on a busy machine): it is left out of the watch's cost.
    /// A trial's turns each have one watch, so with it counted the first
    /// turns would weigh it in full.
    #[test]
    fn the_first_watched_frame_is_not_counted_in_the_watchs_cost() {
        let trial_with = |first_watch_ms: f64| {
            let mut g = governor_of(2, Some(30.0));
            let mut watches = 0;
            for _ in 0..400 {
                let next = g.next_frame();
                let mut ms = match next.choice {
                    Choice::Original => 1.0,
                    Choice::Cached { .. } => 0.5,
                };
                if next.watch {
                    ms += if watches == 0 { first_watch_ms } else { 1.0 };
                    watches += 1;
                }
                g.measured(next.frame, ms);
                if next.watch {
                    g.watched(next.frame, 45.0);
                }
            }
            let turns: Vec<f64> = g.trials()[0].iter().map(|t| t.estimate.speedup).collect();
            turns
        };
        let (ordinary, slow_first) = (trial_with(1.0), trial_with(236.0));
        assert_eq!(ordinary, slow_first);
        assert!(slow_first.iter().all(|&s| s > 1.5), "{slow_first:?}");
    }
}
