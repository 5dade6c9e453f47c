//! What a run is before it touches the GPU: its knobs checked, the
//! interval length, the size and the intervals measured, the scene
//! checked against the shader, and the reference's plan.

use super::iframe::{self, IFrameShader};
use super::{Method, Options};
use crate::diagnostic::Error;
use crate::front::Shader;
use crate::measure::{fail, MEASURED_COLOR_FORMAT};
use crate::rewrite::Options as RewriteOptions;
use crate::runtime::Gpu;
use crate::scene::Scene;

/// Intervals drawn before the measured ones: the first I-frame has no
/// previous one, and the device warms up.
pub(super) const WARMUP_INTERVALS: u32 = 1;

/// The knobs checked, and what a run needs of them.
pub(super) fn check(options: &Options) -> Result<(), Error> {
    if options.frames_per_interval < 2 {
        return Err(fail(format!(
            "--frames-per-interval must be at least 2 (an I-frame and a B-frame), not {}",
            options.frames_per_interval
        )));
    }
    if options.iterations == 0 {
        return Err(fail(
            "--iterations must be at least 1: the search takes m ≥ 1 fixed-point steps".into(),
        ));
    }
    if options.methods.is_empty() {
        return Err(fail("no method to run".into()));
    }
    if !(-1.0..=1.0).contains(&options.min_cosine) {
        return Err(fail(format!(
            "the half-velocity direction test's cosine must be from -1 to 1, not {}",
            options.min_cosine
        )));
    }
    if options.latest_radius == 0 {
        return Err(fail(
            "--latest-radius must be at least 1: its taps are the pixel's diagonal neighbours that far away".into(),
        ));
    }
    if options.methods.iter().any(|m| m.extrapolates()) {
        check_morph(options)?;
    }
    if !(1..=MAX_PURSUIT_SUBSTEPS).contains(&options.pursuit_substeps) {
        return Err(fail(format!(
            "--pursuit-substeps must be from 1 to {MAX_PURSUIT_SUBSTEPS}, not {}: each sub-step samples every pixel of every displayed frame on the CPU",
            options.pursuit_substeps
        )));
    }
    if options.inpaint_passes == 0 || options.inpaint_delta == 0 {
        return Err(fail(format!(
            "--inpaint-passes and --inpaint-delta must be at least 1, not {} and {}",
            options.inpaint_passes, options.inpaint_delta
        )));
    }
    Ok(())
}

/// The display gammas `--gamma` takes: CRTs were about 2.2–2.5, sRGB is
/// 2.2, and a panel's transfer lies between 1.8 and 2.6. The bounds are
/// wider, but they keep a typo (1e30) from reading as a result.
pub const MIN_GAMMA: f32 = 1.0;
/// See [`MIN_GAMMA`].
pub const MAX_GAMMA: f32 = 3.0;

/// The most sub-steps of the pursuit's integration of one displayed
/// frame. The time is linear in it (×W×H×frames, on the CPU): 10 000 at
/// 32² and 4 frames took 4 s; 10⁶ ran for minutes.
pub const MAX_PURSUIT_SUBSTEPS: u32 = 1024;

/// The morph's knobs (the grid against the frame's size is checked by
/// [`check_grid`] once the size is known).
fn check_morph(options: &Options) -> Result<(), Error> {
    let ramp = |[a, b]: [f32; 2]| a.is_finite() && b.is_finite() && 0.0 <= a && a < b;
    // A display's: from a 1 Hz slide show to 1000 Hz; from a projector
    // across a hall (a pixel a degree) to a phone at arm's length (~100).
    let within = |flag: &str, value: f32, (low, high): (f32, f32)| {
        (!(low..=high).contains(&value))
            .then(|| format!("--{flag} must lie from {low} to {high}, not {value}"))
    };
    let problems = [
        (options.blur_level == 0 || options.blur_level > 6).then(|| {
            format!(
                "--blur-level must be from 1 to 6 (each level halves the frame), not {}",
                options.blur_level
            )
        }),
        (!(MIN_GAMMA..=MAX_GAMMA).contains(&options.gamma)).then(|| {
            format!(
                "--gamma is a display's, from {MIN_GAMMA} to {MAX_GAMMA} (sRGB is about 2.2), not {}",
                options.gamma
            )
        }),
        within("display-hz", options.display_hz, (1.0, 1000.0)),
        within("pixels-per-degree", options.pixels_per_degree, (1.0, 1000.0)),
        (!ramp(options.tracking)).then(|| {
            format!(
                "--tracking takes two speeds of 0 deg/s or more, the lower first, not {:?}",
                options.tracking
            )
        }),
        (!ramp(options.distortion_blur)).then(|| {
            format!(
                "--distortion-blur takes two distortions of 0 or more, the lower first, not {:?}",
                options.distortion_blur
            )
        }),
        options
            .blur_min_speed
            .filter(|v| !(*v >= 0.0 && v.is_finite()))
            .map(|v| format!("--blur-min-speed takes a speed of 0 deg/s or more, not {v}")),
        (!(options.snap_threshold >= 0.0 && options.snap_threshold.is_finite())).then(|| {
            format!(
                "--snap-threshold must be 0 or more, not {}",
                options.snap_threshold
            )
        }),
    ];
    match problems.into_iter().flatten().next() {
        Some(problem) => Err(fail(problem)),
        None => Ok(()),
    }
}

/// Seed 004's blurred and sharpened frames fuse only within Bloch's
/// critical duration (about 40 ms): a longer group may be seen to flicker.
pub(super) fn flicker_note(options: &Options) -> Option<String> {
    let blurs = options
        .methods
        .iter()
        .any(|m| matches!(m, Method::Morph | Method::MorphPast));
    let group_ms = 1000.0 * options.frames_per_interval as f32 / options.display_hz;
    (blurs && group_ms > 40.0).then(|| {
        format!(
            "the morph's groups of {} frames at {} Hz last {group_ms:.0} ms, past the ~40 ms over which the eye fuses a sharpened frame with blurred ones (Bloch's law): the alternation may be seen to flicker",
            options.frames_per_interval, options.display_hz
        )
    })
}

/// The morph's grid against the frame: a power of two from 2 to 128 that
/// divides both sides (each vertex searches a grid × grid neighbourhood
/// through a pyramid of halvings).
pub(super) fn check_grid(grid: u32, [width, height]: [u32; 2]) -> Result<(), Error> {
    if !grid.is_power_of_two() || !(2..=128).contains(&grid) {
        return Err(fail(format!(
            "--grid must be a power of two from 2 to 128 (its neighbourhoods are searched by halving), not {grid}"
        )));
    }
    if width % grid != 0 || height % grid != 0 {
        return Err(fail(format!(
            "--grid {grid} does not divide the {width}×{height} frame: the morph's tiles must cover it exactly"
        )));
    }
    // The argmax pyramid pads the frame by one tile on each axis
    // (`morph::argmax_sizes`): its first level must fit a texture.
    let largest = crate::scene::bounds::MAX_SIZE - grid;
    if width > largest || height > largest {
        return Err(fail(format!(
            "the morph at --grid {grid} takes frames up to {largest} pixels a side, not {width}×{height}: its search pyramid pads the frame by one tile, and a texture is at most {} pixels a side",
            crate::scene::bounds::MAX_SIZE
        )));
    }
    Ok(())
}

/// What a run is, before it touches the GPU: the interval length, the
/// size, the intervals measured, the scene checked against the shader,
/// and the reference's plan.
pub(super) struct RunPlan {
    /// Displayed frames per interval.
    pub n: u32,
    pub size: [u32; 2],
    pub intervals: u32,
    pub bindings: crate::measure::setup::SceneBindings,
    pub rewrite_options: RewriteOptions,
    pub reference: crate::plan::Plan,
}

impl RunPlan {
    pub fn new(shader: &Shader, scene: &Scene, options: &Options) -> Result<RunPlan, Error> {
        let n = options.frames_per_interval;
        let size = options.size.unwrap_or(scene.size);
        let frames = options.frames.unwrap_or(scene.frames);
        crate::measure::setup::check_counts(size, frames, 0)?;
        if options.methods.iter().any(|m| m.extrapolates()) {
            check_grid(options.grid, size)?;
        }
        let intervals = frames.div_ceil(n);
        let last_frame = (WARMUP_INTERVALS + intervals + 1) * n;
        let bindings = crate::measure::setup::scene_bindings(
            shader,
            scene,
            (options.entry.as_deref(), options.vertex_entry.as_deref()),
            size,
            last_frame,
        )?;
        let rewrite_options = RewriteOptions {
            depth: scene.camera.depth,
            vertex_entry: options.vertex_entry.clone(),
            color_format: MEASURED_COLOR_FORMAT,
            ..RewriteOptions::default()
        };
        let reference =
            crate::rewrite::plan::reference(shader, &bindings.analysis, &rewrite_options)
                .map_err(fail)?;
        Ok(RunPlan {
            n,
            size,
            intervals,
            bindings,
            rewrite_options,
            reference,
        })
    }

    /// The I-frame pass: the shader instrumented with the flows. The twins
    /// of per-instance inputs take vertex attributes beside the shader's,
    /// as many as the device grants.
    pub fn instrument(&self, shader: &Shader, gpu: &Gpu) -> Result<IFrameShader, Error> {
        let max_vertex_attributes = gpu.device.limits().max_vertex_attributes;
        iframe::instrument(
            shader,
            &self.bindings.analysis,
            &self.rewrite_options,
            max_vertex_attributes,
        )
        .map_err(|refusal| {
            fail(format!(
                "the I-frame pass cannot be made: {}",
                refusal.reason
            ))
        })
    }
}
