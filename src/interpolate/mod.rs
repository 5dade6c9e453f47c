//! Whole-frame reuse: render some frames (I-frames) and build the frames
//! between them (B-frames) from what the I-frames stored.
//!
//! The reprojection cache (the rest of this crate) keeps one value of a
//! shader from frame to frame. This stage keeps whole frames: seeds 000
//! (Yang et al., "Image-based bidirectional scene reprojection") and 003
//! (Andreev, "How to get from 30 to 60 frames per second in video games
//! for free"), as `../shared/design/seeds-000-003.md` turns them into
//! passes. `n` displayed frames make an I-frame interval: the frame at
//! its start is rendered, the n − 1 after it are B-frames at
//! α = 1/n … (n − 1)/n between it (I-frame 0, time t) and the next
//! (I-frame 1, time t + 1).
//!
//! # The I-frame pass ([`iframe`])
//!
//! The user's shader, instrumented on naga IR: its vertex stage computes
//! the position with the previous and the next I-frame's resources too
//! (twins, as the cache's previous-frame twin), and its fragment stage
//! adds two flows to its outputs, Vb (to the previous I-frame) and Vf (to
//! the next): Δx, Δy in pixels and Δz in depth, `rgba16float`. That is
//! everything the B-frame methods read: colour, depth, Vb, Vf. Nothing
//! about the user's matrices is assumed. Per-instance vertex inputs the
//! position reads (the wgpu tutorial's model-matrix columns) get a twin
//! input per other I-frame, which the run fills with that I-frame's
//! instance transforms; they take as many vertex attributes as the device
//! grants (the tutorial's 11 inputs and 8 twins need 19, past WebGPU's
//! default 16). A shader whose position cannot be twinned (no vertex
//! stage, too many inputs) is refused with the reason.
//!
//! # The B-frame methods ([`bframe`], `shaders/bframe.wgsl`)
//!
//! Most are a fullscreen pass over the two I-frames' textures:
//! - `image-based` (000 §5): for each B-frame pixel p a fixed-point search
//!   q ← p − α·Vf(q) into I-frame 0 and q ← p − (1 − α)·Vb(q) into I-frame
//!   1, m iterations each (eqs. 3–12); with dual initialisation each also
//!   starts from the other frame's velocity at p (eqs. 16–17). The flows
//!   are read per texel, unfiltered: a filtered flow mixes an object's
//!   motion with the floor's along its silhouette and sends the search to
//!   a point on neither, where unfiltered it converges onto one of the two
//!   surfaces and the decisions choose (measured on the walking scene: the
//!   pass a third cheaper, SSIM the same). Per-texel flows also make the
//!   paper's "no early exit" free to drop: a step that stays in its texel
//!   reads the same flow again and lands on the same point for every step
//!   after, so the search stops there with the result of all m steps
//!   (`search.rs` states it as a property). Of the two starts of one
//!   direction, where both converge (under ε1) on different surfaces the
//!   nearer is kept: both are fixed points, and the farther is what the
//!   nearer hides at the B-frame's time (the floor behind a moving
//!   sphere's rim, which the start at p converges onto; the smaller
//!   residual, the paper's rule for the starts, picked it and shrank every
//!   moving object by a pixel: walking scene SSIM 0.967 against 0.980);
//!   else the smaller residual. The second start is skipped where it lies
//!   within ε1 of where the first ended, which it would converge to. m is
//!   a pipeline constant, so the loop unrolls. §5.2 decides between the
//!   directions: both residuals under ε1 and depths agreeing, the smaller
//!   residual; depths disagreeing, the nearer surface; only one under ε1,
//!   that one; neither (a double miss), the smaller residual. The point
//!   found is carried to the other I-frame by its exact flow and the two
//!   colours blended by α where it is visible there (eqs. 14–15), else
//!   its own colour is shown. What the paper leaves open is decided as the
//!   design note proposes: ε1 = 1 px; ε2 and the visibility test are the
//!   cache's relative depth test; "exactly one under ε1" is treated as
//!   case 2; case 3 uses eqs. 14–15. With latest-frame initialisation
//!   (eqs. 18–19), every B-frame of an interval but the first also starts
//!   each search from the offsets the B-frame before found, rescaled to
//!   its α, taken from the nearest-depth tap of a 5-tap neighbourhood (the
//!   centre and its diagonals `--latest-radius` pixels away, 1 by default;
//!   the paper leaves the size open), and the
//!   pass writes its own offsets and chosen depth for the next. It is off
//!   by default (`--latest-init`): measured on the bundled scenes it
//!   lowered SSIM and made the pass half as costly again.
//! - `half-velocity` (003): I-frame 0 sampled back along the velocity, α
//!   of the way (half-way at n = 2): p + α·Vb₁(p), Vb₁ being I-frame 1's
//!   flow to I-frame 0 (the current velocity, negated). Velocity merging:
//!   where I-frame 0's surface is nearer than I-frame 1's at p (the tail a
//!   moving object leaves behind), I-frame 0's own velocity Vb₀ is used
//!   instead, extrapolated, unless its direction differs from the current
//!   one's by more than `min_cosine`, where the pixel is held ("no worse
//!   than 30 fps"). It reads no colour of I-frame 1: no extra latency.
//!   Moving objects (003's dynamic objects, slides 33–47; on unless
//!   `--no-moving-objects`): the objects the scene moves in the world
//!   ([`Scene::moves`]) are drawn alone at the B-frame's time by the
//!   scene-assisted pass in its moving-objects mode, which writes each
//!   pixel's exact offset from I-frame 0 and so the mask; a still surface
//!   hides a fragment where both I-frames show a nearer one at its pixel.
//!   Those pixels take I-frame 0's colour where their point is. The
//!   I-frame pass marks moving objects in its flows (w = 2, from a
//!   per-object flag the host sets), and character removal wipes them out
//!   of I-frame 0 once an interval: `--inpaint-passes` passes (3) at
//!   quarter resolution, as the paper's, each filling a masked pixel with
//!   the mean of its unmasked neighbours `--inpaint-delta` pixels away (2)
//!   and unmasking it for the next (the paper's horizontal/vertical and
//!   blur refinements are left out). Where the point sampled showed a
//!   moving object that is not at the pixel now, the removed frame is
//!   shown (slide 47). These passes count in half-velocity's B-frame time.
//! - Baselines, in the same run: `reference` (every frame rendered),
//!   `sample-and-hold` (I-frame 0 shown again) and `linear-blend` (the two
//!   I-frames cross-faded at the same pixel).
//!
//! The scene-assisted ones (000 §4, `shaders/bframe_scene.wgsl`, imported
//! into the I-frame module as `fs_scene_assisted`) rasterise the geometry
//! at the B-frame's time with its position at both I-frames (the same
//! twins, bound to the I-frames' times) and take each fragment's colour
//! from the I-frames where its point is visible there, blended by α where
//! it is in both: `scene-assisted` fills a double miss with the I-frame
//! whose depth at the reprojected point is the nearer (closest-on-miss,
//! the paper's choice); `scene-assisted-shade-on-miss` discards it and a
//! second pass of the original fragment stage shades it (its depth test
//! keeps it to those pixels); `reverse-reprojection` reads I-frame 0 alone
//! and never reshades (a baseline), and `reverse-reprojection-reshade`
//! shades what I-frame 0 does not show in the same second pass (the
//! paper's main baseline, Figs. 7–10: no added latency, as it reads I-frame
//! 0 alone). The I-frames' textures are bound in
//! the group after the twins', which the runner leaves to its caller
//! (`RunOptions::external_group`).
//!
//! # Extrapolation (seed 004: [`morph`], `shaders/morph.wgsl`)
//!
//! Didyk et al. build the n − 1 frames *after* a rendered frame from it
//! alone, so nothing waits for the next one (no added latency), and hide
//! what the warp gets wrong perceptually: on a display fast enough that
//! the eye fuses the frames, blurred in-between frames alternating with a
//! sharpened rendered frame look like the rendered frame moving.
//! `design/seeds-001-004.md` Part B turns the paper into the passes this
//! follows; what it leaves open is an option recorded in the report.
//! - Motion: `morph` takes I-frame 0's flow to I-frame 1, the twin's exact
//!   motion (the paper renders both clip positions: "perfect motion
//!   flow"). A game does not know its next frame; `morph-past` takes the
//!   flow to the I-frame before, negated: the motion of the last interval
//!   carried on (the paper's warning: hard for fast and complex motion).
//!   The report gives both, and their difference is the cost of not
//!   knowing the future. Frame k of the interval moves k/n of it
//!   ("a linear assumption proved sufficient"), damped by the eye-tracking
//!   factor f(v) = 1 − smoothstep(70, 90 deg/s) where the eye could not
//!   follow (speed from `--display-hz`, n and `--pixels-per-degree`).
//! - Snapping: one vertex per `--grid` (8) pixels; vertex i searches the
//!   non-overlapping neighbourhood [g·i − g/2, g·i + g/2) for the largest
//!   motion gradient (the larger forward difference of the flow) through
//!   the paper's argmax pyramid: a texel packs the gradient (16 bits) above
//!   its place (8 + 8 bits), so an integer maximum of four is the argmax
//!   with its place, log2(g) halvings give one texel per vertex (ties to
//!   the larger y, then x; a brute-force CPU search agrees). A vertex
//!   snaps only to a gradient of at least `--snap-threshold` (1 px per px),
//!   so a smooth flow keeps the regular grid; it lands on the corner after
//!   the pixel, on the discontinuity; border vertices stay put. Of the
//!   four pixels around it, the nearest surface's motion and depth move
//!   it: an occluding edge moves with the occluder, and the surface it
//!   uncovers stretches behind it (no hole: the grid is connected).
//! - The grid is drawn through an index buffer, two triangles per tile,
//!   depth-tested with the I-frame's depth (nearer wins, either depth
//!   convention), no culling (fold-overs flip the winding).
//! - Blur and compensation: the I-frame's low-pass L is a pyramid of the
//!   binomial [1 3 3 1]/8 (the paper's 3-tap binomial sits half a texel
//!   off when it decimates) read at `--blur-level` (2) with a cubic
//!   B-spline. The displayed I-frame is O = (n·I^γ − (n − 1)·L^γ)^(1/γ)
//!   (γ = `--gamma`, 2.2), so the n frames integrate to I in light; an
//!   in-between frame shows L warped, and where O^γ leaves [0, 1] it
//!   clamps and the in-between frames take the rest, (n − 1) shares of
//!   it (the paper's Fig. 5: the excess goes into the blurred frames,
//!   and a shortfall likewise). Where I is darker than L (by luminance)
//!   the original is kept in every frame: black stays black. The paper
//!   blurs each morphed frame; here L is warped by the same grid as the
//!   colour, which agrees wherever the grid moves as a translation, and
//!   a tile that stretches or folds shows smoothstep(`--distortion-blur`)
//!   of L by its distortion (the larger |s − 1| of the warp's singular
//!   values): one pass per extrapolated frame. `--selective-blur`
//!   blurs only where the motion is at least that fast (0.15 deg/s, the
//!   drift limit below which the eye does not pursue): a still picture
//!   stays sharp. `morph-warp` is the snapped morph alone.
//! - The morph's preparation (the pyramids and the compensation) runs
//!   once per I-frame and counts in its I-frame time; each extrapolated
//!   frame is one pass.
//!
//! # Payload interpolation ([`payload`])
//!
//! What none of the papers does: the reprojection cache's three-pass
//! split of the fragment stage at a node (one that reads no per-frame
//! input: the marble's albedo) gives a payload pass, drawn at each
//! I-frame, and a shade pass. `payload` interpolates the two I-frames'
//! payloads with image-based's search and decisions and shades every
//! B-frame at its own time, with its own uniforms: a moving light or
//! highlight stays where it is, which every method that warps colours
//! drags along the flow (000 §6's limitation).
//!
//! # The frames each displayed frame costs ([`partition`])
//!
//! The amortised ratio spreads an I-frame's cost over its interval for
//! free. With `--partition` the run draws each I-frame in n parts of about
//! equal measured cost, one per displayed frame (000 §7), each loading the
//! colour and depth the part before left (the host's `record_more_timed`),
//! so the parts together are the I-frame drawn at once. Either way each
//! method reports its displayed frames' median and slowest time.
//!
//! # Objects drawn every frame ([`thin`])
//!
//! A scene object marked `every_frame` (thin, fast geometry: the
//! windmill's blades) is left out of the I-frames and drawn with the
//! original shader at every displayed frame, depth-tested into what each
//! method shows through a Z-buffer bridge (000 §6, Fig. 4(d)).
//!
//! Every method is also measured by its pursuit error ([`pursuit`]): the
//! stand-in for the paper's user study, what an eye tracking the motion
//! integrates over each interval's n displayed frames on a hold-type
//! display, against the same for the reference.
//!
//! # The run (`run.rs`)
//!
//! Displayed frame by displayed frame the reference is rendered and read
//! back; at each interval's end the I-frame, then every method's B-frames
//! of the interval, each compared with the reference of its own time. The
//! frames are timed with GPU timestamps through the profiler's clock
//! (`measure::clock::timed`), drawn through the same runtime and
//! host crate, fed by the same scene inputs, and compared by the same
//! metrics. Two I-frame runners alternate, so I-frame 0 and I-frame 1
//! stay alive side by side without copies.
//!
//! With `--motion-blur`, each method's displayed frames within n/2 of an
//! I-frame are also averaged into a motion-blurred frame (000 §9: ten
//! B-frames per I-frame at n = 10) and compared with the same composite
//! of the reference frames (`blur.rs`).
//!
//! # What is measured ([`report`])
//!
//! Per method: the I-frame's time over a reference frame (1 for the
//! methods that need no flows: their I-frame is the original; the morph's
//! preparation added for the extrapolators), one B-frame's, the amortised (T_I + (n − 1)·T_B) / (n·T_ref) (ours: the
//! I-frame's cost spread over its interval for free, where 000's Table 3
//! times each displayed frame with a partition of the I-frame, which
//! `--partition` measures as `displayed_frame_ms`), and SSIM and PSNR of the B-frames against the reference
//! rendered at the same time, the pursuit error, the latency added; for
//! image-based the share of pixels that were double misses.
//!
//! The paper renders the forward flow in a geometry pass of its own (an
//! interactive application knows t + 1's parameters only after drawing
//! t); a scripted scene knows them, so one pass writes both flows here,
//! which the report says.

#![warn(missing_docs)]

#[doc(hidden)]
pub mod bframe;
mod blur;
pub mod correspondence;
#[doc(hidden)]
pub mod iframe;
#[doc(hidden)]
pub mod morph;
pub mod partition;
pub mod payload;
pub mod pursuit;
pub mod report;
pub(crate) mod run;
#[cfg(test)]
mod search;
#[doc(hidden)]
pub mod thin;

pub use bframe::Decision;

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
    pub fn scene_mode(self) -> Option<iframe::SceneMode> {
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

    /// Whether its B-frames read the I-frames' flows (its I-frames are
    /// the instrumented pass; else the original shader).
    pub fn reads_flows(self) -> bool {
        matches!(
            self,
            Method::ImageBased | Method::HalfVelocity | Method::Payload
        ) || self.extrapolates()
    }

    /// Whether each I-frame of it adds passes of its own to the
    /// instrumented one (the morph's preparation, the payload's pass),
    /// which count in its I-frame time.
    pub fn adds_iframe_passes(self) -> bool {
        self.extrapolates() || self == Method::Payload
    }

    /// Whether it extrapolates from the earlier I-frame alone by the grid
    /// morph (seed 004), its I-frame followed by the morph's preparation.
    pub fn extrapolates(self) -> bool {
        matches!(self, Method::Morph | Method::MorphPast | Method::MorphWarp)
    }

    /// Whether its B-frames read the later I-frame's colour, which must
    /// then be rendered before they are shown: n − 1 displayed frames of
    /// added latency. Half-velocity reads only the later frame's depth and
    /// velocity, which an engine renders first (003's one-frame mode: the
    /// middle frame is shown while the rest of the frame renders).
    pub fn reads_later_frame(self) -> bool {
        matches!(
            self,
            Method::LinearBlend
                | Method::ImageBased
                | Method::SceneAssisted
                | Method::SceneAssistedShadeOnMiss
                | Method::Payload
        )
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
    /// Selective blur: blur (and compensate) only where the motion is at
    /// least this fast, deg/s (the drift limit below which the eye does
    /// not track: 0.15); `None` blurs everywhere, as the paper.
    pub selective_blur: Option<f32>,
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
            selective_blur: None,
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
