//! Whole-frame reuse: render some frames (I-frames) and build the frames
//! between them (B-frames) from what the I-frames stored.
//!
//! The reprojection cache (the rest of this crate) keeps one value of a
//! shader from frame to frame; this stage keeps whole frames, after Yang
//! et al. 2011 (bidirectional reprojection), Andreev 2010 (half-velocity
//! up-conversion) and Didyk et al. 2010 (morph-and-blur extrapolation),
//! and interpolates a cached payload as none of them does. `n` displayed
//! frames make an I-frame interval: the frame at its start is rendered,
//! the n − 1 after it are built at α = 1/n … (n − 1)/n between it
//! (I-frame 0) and the next (I-frame 1), or extrapolated from I-frame 0
//! alone.
//!
//! How it is built, in the order a run uses it:
//!
//! - `setup`: the knobs checked, and what a run is before it touches
//!   the GPU (`RunPlan`: the size, the intervals, the scene's
//!   bindings, the reference's plan).
//! - [`iframe`]: the I-frame pass, the user's shader instrumented on naga
//!   IR: its position computed with the previous and the next I-frame's
//!   resources too (twins), and two flows added to its outputs. Every
//!   method reads only colour, depth and the flows.
//! - `frame_method`: what a method is to the schedule, one
//!   `FrameMethod` per family in
//!   `methods`, each owning its passes and runners: the fullscreen
//!   B-frame passes ([`bframe`], `shaders/bframe.wgsl`), the geometry
//!   drawn again at B-frame times (`shaders/bframe_scene.wgsl`), the
//!   morph ([`morph`], `shaders/morph.wgsl`) and the payload's passes
//!   ([`payload`]). `gpu` holds the pieces every fullscreen pass is
//!   made of.
//! - `run`: the schedule. Interval by interval, the reference at every
//!   displayed frame, the closing I-frame (with `--partition`, in parts
//!   of about equal measured cost: [`partition`]), then each method's
//!   frames. Two I-frame runners alternate, so I-frame 0 and I-frame 1
//!   stay alive side by side without copies. Frames are timed with GPU
//!   timestamps through the measured run's clock (`measure::clock`),
//!   drawn through the same runtime and host crate as the profiler's,
//!   fed by the same scene inputs.
//! - `frames`: how a frame is made and measured alike for every method:
//!   its twinned inputs, its B-frame parameters, what it shows (objects
//!   drawn every frame composited in through the Z-buffer bridge,
//!   [`thin`]), compared with the reference of its own time and kept
//!   (`measured`).
//! - `summary` and [`report`]: each method's time ratios, errors
//!   (SSIM, PSNR, the pursuit error of [`pursuit`], the motion-blurred
//!   composites of `blur`, image-based's correspondence errors of
//!   [`correspondence`]), its displayed frames' times and the latency it
//!   adds.
//!
//! The design of each method, what the papers leave open and how it was
//! decided is `docs/interpolation-design.md`; the measurements are
//! `docs/results-interpolation.md`.

#![warn(missing_docs)]

pub(crate) mod bframe;
mod blur;
pub mod correspondence;
pub mod edges;
mod frame_method;
mod frames;
mod gpu;
pub(crate) mod iframe;
mod measured;
mod methods;
pub(crate) mod morph;
pub mod partition;
pub mod payload;
pub mod pursuit;
pub mod report;
pub(crate) mod run;
#[cfg(test)]
mod search;
mod setup;
mod summary;
pub(crate) mod thin;

pub use bframe::Decision;
pub use morph::BlurOrder;

use std::path::Path;

use crate::diagnostic::Error;
use crate::front::Shader;
use crate::measure::Progress;
use crate::scene::Scene;

/// A way to show the frames between I-frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
#[non_exhaustive]
pub enum Method {
    /// Every frame rendered.
    Reference,
    /// The earlier I-frame shown again.
    SampleAndHold,
    /// The two I-frames cross-faded.
    LinearBlend,
    /// Seed 000 §5.
    ImageBased,
    /// Seed 003.
    HalfVelocity,
    /// Seed 000 §4, closest-on-miss (the paper's choice).
    SceneAssisted,
    /// Seed 000 §4, shade-on-miss.
    SceneAssistedShadeOnMiss,
    /// Single-direction reverse reprojection from the earlier I-frame, no
    /// reshading (a baseline).
    ReverseReprojection,
    /// The same, its misses shaded by the original fragment stage (seed
    /// 000's main baseline, Figs. 7–10).
    ReverseReprojectionReshade,
    /// Seed 004: the frames after an I-frame extrapolated by the snapped
    /// grid morph with the twin's exact motion, blurred, the I-frame
    /// compensated.
    Morph,
    /// The same with the motion extrapolated from the I-frame before
    /// (what a game that does not know the future has).
    MorphPast,
    /// The snapped grid morph alone: no blur, no compensation.
    MorphWarp,
    /// The cache's payload interpolated between the I-frames by
    /// image-based's search, and shaded at each B-frame's time
    /// ([`payload`]).
    Payload,
}

impl Method {
    /// Every method, in the report's order.
    pub const ALL: [Method; 13] = [
        Method::Reference,
        Method::SampleAndHold,
        Method::LinearBlend,
        Method::ImageBased,
        Method::HalfVelocity,
        Method::SceneAssisted,
        Method::SceneAssistedShadeOnMiss,
        Method::ReverseReprojection,
        Method::ReverseReprojectionReshade,
        Method::Morph,
        Method::MorphPast,
        Method::MorphWarp,
        Method::Payload,
    ];

    /// The method's name on the command line and in reports.
    pub fn name(self) -> &'static str {
        match self {
            Method::Reference => "reference",
            Method::SampleAndHold => "sample-and-hold",
            Method::LinearBlend => "linear-blend",
            Method::ImageBased => "image-based",
            Method::HalfVelocity => "half-velocity",
            Method::SceneAssisted => "scene-assisted",
            Method::SceneAssistedShadeOnMiss => "scene-assisted-shade-on-miss",
            Method::ReverseReprojection => "reverse-reprojection",
            Method::ReverseReprojectionReshade => "reverse-reprojection-reshade",
            Method::Morph => "morph",
            Method::MorphPast => "morph-past",
            Method::MorphWarp => "morph-warp",
            Method::Payload => "payload",
        }
    }

    /// Its scene-assisted pass's mode, for the methods that rasterise the
    /// geometry at each B-frame.
    pub(crate) fn scene_mode(self) -> Option<iframe::SceneMode> {
        match self {
            Method::SceneAssisted => Some(iframe::SceneMode::ClosestOnMiss),
            Method::SceneAssistedShadeOnMiss => Some(iframe::SceneMode::ShadeOnMiss),
            Method::ReverseReprojection => Some(iframe::SceneMode::ReverseReprojection),
            Method::ReverseReprojectionReshade => {
                Some(iframe::SceneMode::ReverseReprojectionReshade)
            }
            _ => None,
        }
    }

    /// Its B-frame pass's entry point in `shaders/bframe.wgsl`; `None`
    /// for the reference, which renders every frame.
    pub fn fragment_entry(self) -> Option<&'static str> {
        match self {
            Method::SampleAndHold => Some("fs_sample_and_hold"),
            Method::LinearBlend => Some("fs_linear_blend"),
            Method::ImageBased => Some("fs_image_based"),
            Method::HalfVelocity => Some("fs_half_velocity"),
            _ => None,
        }
    }

    /// Whether it extrapolates from the earlier I-frame alone by the grid
    /// morph (seed 004), its I-frame followed by the morph's preparation.
    pub fn extrapolates(self) -> bool {
        matches!(self, Method::Morph | Method::MorphPast | Method::MorphWarp)
    }
}

/// What to run and with which knobs; `None` takes the scene's. The knobs
/// the B-frame passes use are what the report records as its
/// `parameters` (serialised here; what the report states elsewhere, or
/// says nothing of the passes, is skipped).
#[derive(Clone, Debug, serde::Serialize)]
pub struct Options {
    /// The methods to run.
    #[serde(skip)]
    pub methods: Vec<Method>,
    /// n: displayed frames per I-frame interval (at least 2).
    #[serde(skip)]
    pub frames_per_interval: u32,
    /// m: search iterations (at least 1).
    pub iterations: u32,
    /// ε1, in pixels.
    pub screen_epsilon: f32,
    /// ε2 and the visibility test's relative depth tolerance.
    pub depth_epsilon: f32,
    /// Dual initialisation (000 eqs. 16–17) besides the default start.
    pub dual_init: bool,
    /// Of two converged starts on different surfaces the smaller residual
    /// wins, as seed 000 states it; else (the default) the nearer surface,
    /// which the farther is hidden behind at the B-frame's time.
    pub smaller_residual: bool,
    /// Latest-frame initialisation (000 eqs. 18–19): every image-based
    /// B-frame but an interval's first also starts from the offsets of
    /// the B-frame before it.
    pub latest_frame_init: bool,
    /// How far, in pixels, latest-frame initialisation's diagonal taps are
    /// from the pixel (the neighbourhood: the centre and four taps).
    pub latest_radius: u32,
    /// Half-velocity's velocity merging (003 slide 31): the earlier
    /// frame's velocity for the tails; else the later frame's alone.
    pub velocity_merge: bool,
    /// Half-velocity's direction test.
    pub min_cosine: f32,
    /// Half-velocity's moving objects (003 slides 33–47): drawn at each
    /// B-frame's time for their exact offsets and mask, and wiped out of
    /// the earlier I-frame where they have left. Else every pixel follows
    /// the merged velocity.
    pub moving_objects: bool,
    /// Character removal's passes over the earlier I-frame.
    pub inpaint_passes: u32,
    /// Character removal's neighbour distance, in pixels.
    pub inpaint_delta: u32,
    /// The morph's grid spacing in pixels (seed 004: 8): a power of two
    /// that divides the frame; each vertex searches its grid × grid
    /// neighbourhood.
    pub grid: u32,
    /// Snap the grid's vertices to the motion's discontinuities (off: the
    /// regular grid, to measure what snapping gives).
    pub snap: bool,
    /// The least motion gradient (pixels of flow per pixel) a vertex snaps
    /// to: below it the grid stays regular.
    pub snap_threshold: f32,
    /// The low-pass's pyramid level (each halves the frame with the
    /// binomial [1 3 3 1]/8), read with a cubic B-spline.
    pub blur_level: u32,
    /// The display's gamma (light = value^γ) the compensation conserves
    /// light under.
    pub gamma: f32,
    /// The display's refresh rate R_d; the rendered rate is R_d / n.
    pub display_hz: f32,
    /// The display's pixels per degree of visual angle (a 22" 1680×1050
    /// panel seen from 60 cm: 37).
    pub pixels_per_degree: f32,
    /// Eye-tracking damping f(v) = 1 − smoothstep(a, b, v), deg/s (seed
    /// 004 §6: 70 and 90).
    pub tracking: [f32; 2],
    /// A gate by speed: blur (and compensate) only where the motion is at
    /// least this fast, deg/s (0.15: below it, seed 004 §2 says, drift eye
    /// movement interferes with smooth pursuit); `None` blurs everywhere.
    /// Not the paper's selective blur, which gates by luminance and range
    /// (and which the morph always applies).
    pub blur_min_speed: Option<f32>,
    /// Where an in-between frame's blur comes from: the rendered frame's
    /// low-pass warped with it (ours, the default), or each morphed frame
    /// blurred (the paper's order).
    pub blur_order: BlurOrder,
    /// The grid distortion mapped to full blur: smoothstep(a, b, D), D the
    /// largest |s − 1| over the warp's singular values.
    pub distortion_blur: [f32; 2],
    /// Sub-steps per displayed frame of the pursuit integral.
    pub pursuit_substeps: u32,
    /// The frame's size; `None` takes the scene's.
    #[serde(skip)]
    pub size: Option<[u32; 2]>,
    /// Displayed frames measured (rounded up to whole intervals).
    #[serde(skip)]
    pub frames: Option<u32>,
    /// The fragment entry point; `None` for the module's only one.
    #[serde(skip)]
    pub entry: Option<String>,
    /// The vertex entry point drawing with it; `None` infers it.
    #[serde(skip)]
    pub vertex_entry: Option<String>,
    /// The node `payload` interpolates (an id from `shadecache
    /// analyze`); `None` takes the highest-ranked candidate that reads no
    /// per-frame input ([`payload::choose`]). The report's notes name it.
    #[serde(skip)]
    pub payload_node: Option<String>,
    /// Partitioned rendering (000 §7): each I-frame drawn in n parts of
    /// about equal measured cost, one per displayed frame
    /// ([`partition`]); the report gives each method's displayed frames'
    /// times either way.
    pub partition: bool,
    /// Keep every measured B-frame whole ([`report::Pictures::kept`]).
    #[serde(skip)]
    pub keep_frames: bool,
    /// Also composite each method's frames around every I-frame into a
    /// motion-blurred frame (000 §9) and compare it with the reference's.
    #[serde(skip)]
    pub motion_blur: bool,
    /// A differential check: in each measured interval, also build each
    /// method's B-frames at α = 0 and α = 1 (the I-frames' own times),
    /// kept whole and not counted in the report's figures.
    #[serde(skip)]
    pub endpoints: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options {
            methods: Method::ALL.to_vec(),
            frames_per_interval: 4,
            iterations: 3,
            screen_epsilon: 1.0,
            depth_epsilon: crate::rewrite::DEFAULT_DEPTH_EPSILON,
            dual_init: true,
            smaller_residual: false,
            latest_frame_init: false,
            latest_radius: 1,
            velocity_merge: true,
            min_cosine: 0.5,
            moving_objects: true,
            inpaint_passes: 3,
            inpaint_delta: 2,
            grid: 8,
            snap: true,
            snap_threshold: 1.0,
            blur_level: 2,
            gamma: 2.2,
            display_hz: 120.0,
            pixels_per_degree: 37.0,
            tracking: [70.0, 90.0],
            blur_min_speed: None,
            blur_order: BlurOrder::WarpBlurred,
            distortion_blur: [0.25, 1.0],
            pursuit_substeps: 8,
            size: None,
            frames: None,
            entry: None,
            vertex_entry: None,
            payload_node: None,
            partition: false,
            keep_frames: false,
            motion_blur: false,
            endpoints: false,
        }
    }
}

/// Renders `scene` with every method of `options` and with the reference,
/// and measures them. `scene_path` names the scene file (its folder
/// resolves relative files).
pub fn interpolate(
    shader: &Shader,
    scene: &Scene,
    scene_path: &Path,
    options: &Options,
    progress: &mut dyn Progress,
) -> Result<(report::Report, report::Pictures), Error> {
    run::run(shader, scene, scene_path, options, progress)
}
