//! The interpolation run: interval by interval, the reference at every
//! displayed frame, the closing I-frame, then each method's B-frames,
//! every one timed and compared with the reference of its own time.

use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::bframe::{reborrow, BFrameParams, BFrames, Decision, IFrameTextures, MovingObjects};
use super::correspondence::{FrameErrors, Samples};
use super::iframe::{self, IFrameShader, SceneMode};
use super::morph::{Morph, MorphParams, MorphSetup, Source};
use super::report::{
    self, DisplayedFrame, FrameTimes, KeptFrame, KeptIFrame, MethodReport, Parameters, Pictures,
    Report,
};
use super::thin::{FrameDepth, ThinObjects};
use super::{pursuit, Method, Options};
use crate::diagnostic::Error;
use crate::front::Shader;
use crate::measure::bench::{self, Bench};
use crate::measure::clock::{read_linear, timed, timed_recording, Clock};
use crate::measure::inputs::SceneInputs;
use crate::measure::metrics::{self, FrameError, LinearFrame};
use crate::measure::{fail, Progress, MEASURED_COLOR_FORMAT};
use crate::rewrite::Options as RewriteOptions;
use crate::runtime::{DrawShare, FrameInputs, FramePart, Gpu, RunOptions, Runner};
use crate::scene::Scene;

/// Intervals drawn before the measured ones: the first I-frame has no
/// previous one, and the device warms up.
const WARMUP_INTERVALS: u32 = 1;

/// The error threshold of [`metrics::compare`]'s share above it (unused
/// by the report; one 8-bit step).
const THRESHOLD: f64 = 1.0 / 255.0;

/// One method's measured B-frames.
#[derive(Default)]
struct MethodRun {
    times: Vec<f64>,
    /// (displayed frame, α, error).
    frames: Vec<(u32, f64, FrameError)>,
    decisions: [u64; 5],
    /// The lowest-SSIM B-frame: (SSIM, frame, reference, result).
    worst: Option<(f64, u32, Vec<u8>, Vec<u8>)>,
    /// The extrapolators: what each interval's I-frame passes add (the
    /// morph's preparation), ms.
    prepare_times: Vec<f64>,
    /// The extrapolators that compensate: their displayed I-frames
    /// against the reference, by displayed frame.
    displayed_iframes: Vec<(u32, FrameError)>,
    /// Its pursuit error per interval.
    pursuit: Vec<f64>,
}

/// The knobs checked, and what a run needs of them.
fn check(options: &Options) -> Result<(), Error> {
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
    if options.inpaint_passes == 0 || options.inpaint_delta == 0 {
        return Err(fail(format!(
            "--inpaint-passes and --inpaint-delta must be at least 1, not {} and {}",
            options.inpaint_passes, options.inpaint_delta
        )));
    }
    Ok(())
}

/// The morph's knobs (the grid against the frame's size is checked by
/// [`check_grid`] once the size is known).
fn check_morph(options: &Options) -> Result<(), Error> {
    let ramp = |[a, b]: [f32; 2]| a.is_finite() && b.is_finite() && a < b;
    let positive = |flag: &str, value: f32| {
        (!(value > 0.0 && value.is_finite()))
            .then(|| format!("--{flag} must be positive, not {value}"))
    };
    let problems = [
        (options.blur_level == 0 || options.blur_level > 6).then(|| {
            format!(
                "--blur-level must be from 1 to 6 (each level halves the frame), not {}",
                options.blur_level
            )
        }),
        positive("gamma", options.gamma),
        positive("display-hz", options.display_hz),
        positive("pixels-per-degree", options.pixels_per_degree),
        (!ramp(options.tracking)).then(|| {
            format!(
                "--tracking takes two speeds, the lower first, not {:?}",
                options.tracking
            )
        }),
        (!ramp(options.distortion_blur)).then(|| {
            format!(
                "--distortion-blur takes two distortions, the lower first, not {:?}",
                options.distortion_blur
            )
        }),
        options
            .selective_blur
            .filter(|v| !(*v >= 0.0 && v.is_finite()))
            .map(|v| format!("--selective-blur takes a speed of 0 deg/s or more, not {v}")),
        (!(options.snap_threshold >= 0.0 && options.snap_threshold.is_finite())).then(|| {
            format!(
                "--snap-threshold must be 0 or more, not {}",
                options.snap_threshold
            )
        }),
        (options.pursuit_substeps == 0)
            .then(|| "--pursuit-substeps must be at least 1".to_string()),
    ];
    match problems.into_iter().flatten().next() {
        Some(problem) => Err(fail(problem)),
        None => Ok(()),
    }
}

/// Seed 004's blurred and sharpened frames fuse only within Bloch's
/// critical duration (about 40 ms): a longer group may be seen to flicker.
fn flicker_note(options: &Options) -> Option<String> {
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
fn check_grid(grid: u32, [width, height]: [u32; 2]) -> Result<(), Error> {
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
    Ok(())
}

pub(super) fn run(
    shader: &Shader,
    scene: &Scene,
    scene_path: &Path,
    options: &Options,
    progress: &mut dyn Progress,
) -> Result<(Report, Pictures), Error> {
    check(options)?;
    let plan = RunPlan::new(shader, scene, options)?;
    let (n, size) = (plan.n, plan.size);
    let gpu = crate::measure::open_gpu()?;
    let instrumented = plan.instrument(shader, &gpu)?;
    crate::scene::storage::check(&plan.bindings.storage, scene)?;
    crate::measure::setup::check_instancing(shader, scene, &plan.reference.vertex_layout)?;
    let inputs = SceneInputs::new(
        shader,
        scene,
        scene_path,
        &plan.reference,
        &plan.bindings.used,
        (&plan.bindings.uniforms, &plan.bindings.storage),
        size,
    )?;
    let mut clock = Clock::new(&gpu)?;
    let bench = Bench {
        gpu: &gpu,
        inputs: &inputs,
        size,
        cull_back_faces: scene.cull_back_faces,
    };
    let mut reference = bench::reference(&bench, shader, &plan.reference)?;
    let sources = HashMap::from([("iframe.wgsl".to_string(), instrumented.text.clone())]);
    let iframe_runner = || {
        bench
            .runner(&instrumented.plan, &sources, false)
            .map_err(|err| fail(format!("the I-frame pass does not run: {err}")))
    };
    let mut slots = [iframe_runner()?, iframe_runner()?];
    let mut notes = Vec::new();
    if scene.effects.is_empty() {
        notes.push(
            "the scene declares no motion (`effects` is empty): every B-frame should equal its I-frames"
                .to_string(),
        );
    }
    let moving: Vec<bool> = (0..scene.objects.len()).map(|i| scene.moves(i)).collect();
    let GeometryRuns {
        scene: mut scene_runs,
        mut correspondence,
        moving: mut moving_runs,
    } = geometry_runs(
        &bench,
        &instrumented,
        &sources,
        options,
        moving.contains(&true),
        &mut notes,
    );
    if moving_runs.is_some() {
        let count = moving.iter().filter(|m| **m).count();
        notes.push(format!(
            "half-velocity draws the {count} moving object(s) at each B-frame's time and wipes them out of the earlier I-frame (Andreev 2010 slides 33–47): both count in its B-frame time (--no-moving-objects leaves them to the velocity)"
        ));
    }
    let every_frame: Vec<bool> = scene.objects.iter().map(|o| o.every_frame).collect();
    let thin = if every_frame.contains(&true) {
        let runner = bench::reference(&bench, shader, &plan.reference)?;
        let count = every_frame.iter().filter(|t| **t).count();
        notes.push(format!(
            "{count} object(s) drawn at every displayed frame (`every_frame`) and left out of the I-frames, depth-tested into each method's frames through the Z-buffer bridge (Yang et al. 2011 Fig. 4(d)): against the depth the frame was drawn with (image-based: the depth its search chose), or I-frame 0's for the methods that keep none (sample-and-hold, linear blending, half-velocity, the morphs); the bridge and the draw count in every displayed frame's time"
        ));
        Some(ThinObjects::new(&gpu, runner).map_err(fail)?)
    } else {
        None
    };
    let mut payload_run = if options.methods.contains(&Method::Payload) {
        payload_run(&bench, shader, &plan, options, &mut notes)?
    } else {
        None
    };
    let bframes = BFrames::writing_depth(
        &gpu,
        (size[0], size[1]),
        &options.methods,
        (
            options.iterations,
            options.latest_frame_init.then_some(options.latest_radius),
        ),
        thin.is_some(),
    )
    .map_err(fail)?;
    let morph = if options.methods.iter().any(|m| m.extrapolates()) {
        check_grid(options.grid, size)?;
        let setup = MorphSetup {
            size,
            grid: options.grid,
            blur_level: options.blur_level,
            selective_blur: options.selective_blur.is_some(),
        };
        Some(Morph::new(&gpu, setup).map_err(fail)?)
    } else {
        None
    };
    if let Some(note) = flicker_note(options) {
        notes.push(note);
    }
    let morph_methods: Vec<Method> = options
        .methods
        .iter()
        .copied()
        .filter(|m| m.extrapolates())
        .collect();
    let b_methods: Vec<Method> = options
        .methods
        .iter()
        .copied()
        .filter(|m| m.fragment_entry().is_some())
        .collect();
    let run = Schedule {
        gpu: &gpu,
        instrumented: &instrumented,
        bframes: &bframes,
        methods: &b_methods,
        morph: morph.as_ref().map(|m| (m, &morph_methods[..])),
        options,
        size,
        far_depth: scene.camera.depth.far_depth(),
        moving: &moving,
        partition: None,
        every_frame: &every_frame,
        thin: std::cell::RefCell::new(thin),
    };
    let run = if options.partition {
        let first = run.twinned_inputs(&|frame| inputs.frame(scene, frame), [0, 0, n])?;
        let costs = run.draw_costs(&mut clock, &mut slots[0], &first)?;
        let whole = slots[0].whole_draws(&first);
        notes.push(format!(
            "--partition: each I-frame is drawn in {n} parts, one per displayed frame, cut from the draws in order by each object's measured cost alone ({}) (Yang et al. 2011 §7); its I-frame time is the parts' total, and the partitioning adds n − 1 displayed frames of latency to every method",
            costs
                .iter()
                .map(|c| format!("{c:.3} ms"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        Schedule {
            partition: Some(super::partition::split(&whole, &costs, n)),
            ..run
        }
    } else {
        run
    };
    let geometry_methods = scene_runs.len() + usize::from(payload_run.is_some());
    let total = u64::from(WARMUP_INTERVALS + plan.intervals)
        * u64::from(
            n + 1 + (b_methods.len() + geometry_methods + morph_methods.len()) as u32 * (n - 1),
        );
    progress.start(total);
    let measured = run.measure(
        &mut clock,
        Runs {
            reference: &mut reference,
            slots: &mut slots,
            scene: &mut scene_runs,
            correspondence: correspondence.as_mut(),
            moving: moving_runs.as_mut(),
            payload: payload_run.as_mut(),
        },
        &|frame: u32| inputs.frame(scene, frame),
        plan.intervals,
        progress,
    )?;
    progress.finish();
    Ok(run.report(
        shader,
        (scene_path, &scene.description),
        &clock,
        measured,
        plan.intervals,
        notes,
    ))
}

/// What a run is, before it touches the GPU: the interval length, the
/// size, the intervals measured, the scene checked against the shader,
/// and the reference's plan.
struct RunPlan {
    n: u32,
    size: [u32; 2],
    intervals: u32,
    bindings: crate::measure::setup::SceneBindings,
    rewrite_options: RewriteOptions,
    reference: crate::plan::Plan,
}

impl RunPlan {
    fn new(shader: &Shader, scene: &Scene, options: &Options) -> Result<RunPlan, Error> {
        let n = options.frames_per_interval;
        let size = options.size.unwrap_or(scene.size);
        let frames = options.frames.unwrap_or(scene.frames);
        crate::measure::setup::check_counts(size, frames, 0)?;
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
    fn instrument(&self, shader: &Shader, gpu: &Gpu) -> Result<IFrameShader, Error> {
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

/// The runs that rasterise the geometry at B-frame times.
struct GeometryRuns {
    /// One per scene-assisted method.
    scene: Vec<SceneRun>,
    /// With image-based, the exact correspondences its search is measured
    /// against.
    correspondence: Option<Correspondence>,
    /// With half-velocity, its moving objects (003 slides 33–47): the
    /// scene-assisted pass in its moving-objects mode, drawing only the
    /// objects that move at each B-frame's time (their exact offsets and
    /// mask). Where I-frame 0 shows one, its flows say so (w = 2), which
    /// character removal reads.
    moving: Option<SceneRun>,
}

/// The runs that rasterise the geometry at each B-frame's time, through
/// the host, binding the I-frames in the group after the twins': one per
/// scene-assisted method, with image-based the exact correspondences its
/// search is measured against (000 Fig. 11, drawn untimed), and with
/// half-velocity its moving objects, when the scene has `any_moving`.
/// What cannot be made is said in `notes`.
fn geometry_runs(
    bench: &Bench,
    instrumented: &IFrameShader,
    sources: &HashMap<String, String>,
    options: &Options,
    any_moving: bool,
    notes: &mut Vec<String>,
) -> GeometryRuns {
    let gpu = bench.gpu;
    let scene_run = |method: Method, mode: SceneMode| -> Result<SceneRun, String> {
        let group = instrumented.scene_group;
        let granted = gpu.device.limits().max_bind_groups;
        if group >= granted {
            return Err(format!(
                "its I-frame textures take bind group {group} (the shader and the twins use the groups before), and the adapter grants {granted}"
            ));
        }
        let plan = instrumented.scene_plan(mode)?;
        let runner = bench.runner_with(
            &plan,
            sources,
            RunOptions {
                external_group: Some(group),
                ..RunOptions::default()
            },
        )?;
        Ok(SceneRun::new(gpu, method, mode, runner))
    };
    let mut scene_runs = Vec::new();
    for &method in &options.methods {
        let Some(mode) = method.scene_mode() else {
            continue;
        };
        match scene_run(method, mode) {
            Ok(run) => scene_runs.push(run),
            Err(reason) => notes.push(format!("{} refused: {reason}", method.name())),
        }
    }
    let mut correspondence = None;
    if options.methods.contains(&Method::ImageBased) {
        let made = scene_run(Method::ImageBased, SceneMode::Correspondence).and_then(|exact| {
            // The method's own search, writing what it found and the
            // direction it took.
            let search = BFrames::writing_depth(
                gpu,
                (bench.size[0], bench.size[1]),
                &[Method::ImageBased],
                (
                    options.iterations,
                    options.latest_frame_init.then_some(options.latest_radius),
                ),
                true,
            )?;
            Ok(Correspondence { exact, search })
        });
        match made {
            Ok(made) => correspondence = Some(made),
            Err(reason) => notes.push(format!(
                "image-based's correspondence error is not measured: {reason}"
            )),
        }
    }
    let mut moving_runs = None;
    let half_velocity = options.methods.contains(&Method::HalfVelocity);
    if half_velocity && options.moving_objects && any_moving {
        match scene_run(Method::HalfVelocity, SceneMode::MovingObjects) {
            Ok(run) => moving_runs = Some(run),
            Err(reason) => notes.push(format!(
                "half-velocity treats moving objects as the rest (no exact offsets, no removal): {reason}"
            )),
        }
    }
    GeometryRuns {
        scene: scene_runs,
        correspondence,
        moving: moving_runs,
    }
}

/// Payload interpolation's runners ([`super::payload`]): the payload pass
/// at each I-frame (two, alternating as the I-frame slots do), the
/// image-based search over the two I-frames' payloads, and the shade
/// pass at each B-frame's time, which reads what the search wrote.
struct PayloadRun {
    slots: [Runner; 2],
    search: BFrames,
    shade: Runner,
}

impl PayloadRun {
    /// The payload of the I-frame in `slot` as the search reads it: the
    /// I-frame's depth and flows with the payload in place of its colour.
    fn iframe<'r>(&'r self, slot: usize, iframe: &IFrameTextures<'r>) -> IFrameTextures<'r> {
        IFrameTextures {
            color: self.slots[slot].payload(),
            ..*iframe
        }
    }
}

/// Payload interpolation's passes and runners, with a note naming its
/// node; `None` with the reason in `notes` where the shader cannot have
/// them. A node named on the command line that is not a candidate is an
/// error.
fn payload_run(
    bench: &Bench,
    shader: &Shader,
    plan: &RunPlan,
    options: &Options,
    notes: &mut Vec<String>,
) -> Result<Option<PayloadRun>, Error> {
    let analysis = &plan.bindings.analysis;
    let candidate = match &options.payload_node {
        Some(id) => {
            analysis.select(&shader.file, &crate::analysis::Nodes::Ids(vec![id.clone()]))?[0]
        }
        None => match super::payload::choose(analysis) {
            Ok(candidate) => candidate,
            Err(reason) => {
                notes.push(format!("payload refused: {reason}"));
                return Ok(None);
            }
        },
    };
    let made = super::payload::passes(
        shader,
        analysis,
        candidate,
        &plan.rewrite_options,
        &plan.reference,
    )
    .map_err(|refusal| refusal.reason)
    .and_then(|passes| {
        let slot = || bench.runner(&passes.iframe, &passes.sources, false);
        let slots = [slot()?, slot()?];
        let search = BFrames::new(
            bench.gpu,
            (bench.size[0], bench.size[1]),
            &[Method::ImageBased],
            (
                options.iterations,
                options.latest_frame_init.then_some(options.latest_radius),
            ),
        )?;
        let mut shade = bench.runner_with(
            &passes.shade,
            &passes.sources,
            RunOptions {
                external_group: Some(passes.payload_group),
                ..RunOptions::default()
            },
        )?;
        let view = super::bframe::view(search.color());
        shade.bind_external(
            bench.gpu,
            "interpolated payload",
            &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&view),
            }],
        )?;
        Ok((
            passes.node,
            PayloadRun {
                slots,
                search,
                shade,
            },
        ))
    });
    match made {
        Ok(((id, text), run)) => {
            notes.push(format!(
                "payload interpolates node {id} (`{text}`) between the I-frames with image-based's search and shades each B-frame at its own time; its payload pass counts in its I-frame time"
            ));
            Ok(Some(run))
        }
        Err(reason) => {
            notes.push(format!("payload refused: {reason}"));
            Ok(None)
        }
    }
}

/// Object `index`'s per-instance input records in `inputs`.
fn instance_records(inputs: &FrameInputs, index: usize) -> &[u8] {
    inputs
        .objects
        .get(index)
        .map_or(&[][..], |o| o.instance_inputs.as_slice())
}

/// A B-frame read back: when it is, its time (ms), its colour and its
/// decisions.
struct BFrameSample {
    displayed: u32,
    alpha: f64,
    time: f64,
    frame: LinearFrame,
    /// Each pixel's [`Decision`] code.
    decisions: Vec<u32>,
}

/// A scene-assisted method: its runner (the geometry at each B-frame's
/// time, through the host) and what it binds of the I-frames.
struct SceneRun {
    method: Method,
    mode: SceneMode,
    runner: Runner,
    params: wgpu::Buffer,
    sampler: wgpu::Sampler,
}

impl SceneRun {
    fn new(gpu: &Gpu, method: Method, mode: SceneMode, runner: Runner) -> SceneRun {
        SceneRun {
            method,
            mode,
            runner,
            params: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("scene-assisted parameters"),
                size: 32,
                usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            sampler: super::bframe::linear_clamp(&gpu.device),
        }
    }

    /// Its pass's target at output `location`.
    fn output(&self, location: u32) -> Result<&wgpu::Texture, String> {
        self.runner.color_at(location).ok_or_else(|| {
            format!("internal error: the scene-assisted pass has no target at {location}")
        })
    }

    /// Binds the two I-frames and this B-frame's parameters
    /// (`SceneParams` of `shaders/bframe_scene.wgsl`).
    fn bind(
        &mut self,
        gpu: &Gpu,
        (earlier, later): &(IFrameTextures, IFrameTextures),
        params: &BFrameParams,
    ) -> Result<(), Error> {
        let mode = self.mode as u32;
        let words = [
            params.viewport[0].to_bits(),
            params.viewport[1].to_bits(),
            params.alpha.to_bits(),
            params.depth_epsilon.to_bits(),
            params.far_depth.to_bits(),
            mode,
            0,
            0,
        ];
        let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
        gpu.queue.write_buffer(&self.params, 0, &bytes);
        let (color, depth) = (super::bframe::view, super::bframe::depth_view);
        let views = [
            color(earlier.color),
            depth(earlier.depth),
            color(later.color),
            depth(later.depth),
        ];
        let mut entries = vec![wgpu::BindGroupEntry {
            binding: 0,
            resource: self.params.as_entire_binding(),
        }];
        entries.extend(
            views
                .iter()
                .zip(1..)
                .map(|(view, binding)| wgpu::BindGroupEntry {
                    binding,
                    resource: wgpu::BindingResource::TextureView(view),
                }),
        );
        entries.push(wgpu::BindGroupEntry {
            binding: 5,
            resource: wgpu::BindingResource::Sampler(&self.sampler),
        });
        self.runner
            .bind_external(gpu, "I-frames", &entries)
            .map_err(fail)?;
        Ok(())
    }
}

/// Image-based's correspondences against the exact ones: the
/// scene-assisted pass in [`SceneMode::Correspondence`] and a second
/// image-based pass that writes what its search found.
struct Correspondence {
    exact: SceneRun,
    search: BFrames,
}

impl Correspondence {
    /// Fig. 11's errors of one B-frame ([`super::correspondence`]): where
    /// image-based's forward search found each covered pixel's point in
    /// I-frame 0 against where it is (E_total), and where linear motion
    /// along I-frame 0's exact flow puts it (E_lin).
    fn measure(
        &mut self,
        schedule: &Schedule,
        at: &IntervalAt,
        params: &BFrameParams,
        (inputs, swapped): (&FrameInputs, &FrameInputs),
    ) -> Result<FrameErrors, Error> {
        let textures = at.textures;
        let gpu = schedule.gpu;
        self.search
            .render(
                gpu,
                Method::ImageBased,
                (&textures.0, &textures.1),
                params,
                None,
                None,
            )
            .map_err(fail)?;
        let found = read_linear(gpu, self.search.written_offsets()).map_err(fail)?;
        // The chosen depths' second channel: the direction taken.
        let directions: Vec<f32> = crate::runtime::read_texture(gpu, self.search.chosen_depth(), 8)
            .map_err(fail)?
            .chunks_exact(8)
            .map(|t| f32::from_le_bytes([t[4], t[5], t[6], t[7]]))
            .collect();
        let mut exact_into = |textures: (&IFrameTextures, &IFrameTextures),
                              params: &BFrameParams,
                              inputs: &FrameInputs|
         -> Result<LinearFrame, Error> {
            self.exact.bind(gpu, &(*textures.0, *textures.1), params)?;
            self.exact.runner.frame(gpu, inputs, None).map_err(fail)?;
            let target = self
                .exact
                .runner
                .color_at(schedule.instrumented.scene_locations[0])
                .ok_or_else(|| {
                    fail("internal error: the correspondence pass has no colour".into())
                })?;
            read_linear(gpu, target).map_err(fail)
        };
        let exact = exact_into((&textures.0, &textures.1), params, inputs)?;
        // With the I-frames swapped: the exact points in I-frame 1.
        let later = BFrameParams {
            alpha: 1.0 - params.alpha,
            ..*params
        };
        let exact_later = exact_into((&textures.1, &textures.0), &later, swapped)?;
        Ok(super::correspondence::frame_errors(
            &exact,
            &found,
            at.flow_next_0(gpu)?,
            (&exact_later, &directions),
            schedule.size,
            params.alpha,
        ))
    }
}

/// Image-based's correspondence errors over the measured B-frames.
#[derive(Default)]
struct CorrespondenceErrors {
    /// Per B-frame, the mean E_total over every covered pixel and over
    /// those I-frame 0 shows.
    means: Vec<(f64, f64)>,
    total: Samples,
    used: Samples,
    linear: Samples,
}

/// What the run keeps of the measured intervals.
#[derive(Default)]
struct Measured {
    /// Image-based's correspondence errors.
    correspondence: CorrespondenceErrors,
    /// With `motion_blur`, the composites around each I-frame.
    blur: Option<super::blur::MotionBlur>,
    /// The reference at the last interval's end: the next one's start.
    previous_end: Option<LinearFrame>,
    /// B-frames kept whole ([`Options::keep_frames`], and the end points
    /// of [`Options::endpoints`]).
    kept: Vec<KeptFrame>,
    iframes: Vec<KeptIFrame>,
    reference_times: Vec<f64>,
    /// Per recorded interval, its closing I-frame's time (with
    /// `--partition`, its parts' total).
    iframe_times: Vec<f64>,
    /// With `--partition`, per recorded interval, the time of each part of
    /// its closing I-frame, instrumented and original.
    iframe_parts: Vec<Vec<f64>>,
    reference_parts: Vec<Vec<f64>>,
    /// The I-frames against the reference at the same time.
    iframe_errors: Vec<(u32, FrameError)>,
    methods: BTreeMap<Method, MethodRun>,
    /// The interval's displayed frames per method, for the pursuit error:
    /// the I-frame as the method shows it (`None`: as rendered) and its
    /// B-frames.
    groups: BTreeMap<Method, Vec<Option<LinearFrame>>>,
}

/// The runners a measured run draws with: the reference, the two
/// I-frame slots (an interval's opening and closing I-frames alternate
/// between them), the scene-assisted methods', and image-based's
/// correspondences and half-velocity's moving objects when asked for.
struct Runs<'r> {
    reference: &'r mut Runner,
    slots: &'r mut [Runner; 2],
    scene: &'r mut [SceneRun],
    correspondence: Option<&'r mut Correspondence>,
    moving: Option<&'r mut SceneRun>,
    payload: Option<&'r mut PayloadRun>,
}

/// One interval as its B-frame methods see it: its first and closing
/// I-frames' times, whether it is recorded, the reference at each of its
/// frames and the two I-frames' textures.
struct IntervalAt<'a> {
    start: u32,
    end: u32,
    record: bool,
    pictures: &'a [LinearFrame],
    textures: &'a (IFrameTextures<'a>, IFrameTextures<'a>),
    /// I-frame 0's flow to I-frame 1 read back, once an interval, for
    /// what the CPU measures from it ([`IntervalAt::flow_next_0`]).
    flow_next_0: std::cell::OnceCell<LinearFrame>,
}

impl IntervalAt<'_> {
    /// I-frame 0's flow to I-frame 1, read back the first time it is
    /// asked for in the interval.
    fn flow_next_0(&self, gpu: &Gpu) -> Result<&LinearFrame, Error> {
        if let Some(flow) = self.flow_next_0.get() {
            return Ok(flow);
        }
        let flow = read_linear(gpu, self.textures.0.flow_next).map_err(fail)?;
        Ok(self.flow_next_0.get_or_init(|| flow))
    }
}

/// What every interval of the run shares.
struct Schedule<'a> {
    gpu: &'a Gpu,
    instrumented: &'a IFrameShader,
    bframes: &'a BFrames,
    /// The methods with B-frame passes.
    methods: &'a [Method],
    /// The morph's passes and the methods that extrapolate with them.
    morph: Option<(&'a Morph, &'a [Method])>,
    options: &'a Options,
    size: [u32; 2],
    far_depth: f32,
    /// Which of the scene's objects move ([`Scene::moves`]).
    moving: &'a [bool],
    /// With `--partition`, the parts each I-frame is drawn in
    /// ([`super::partition`]).
    partition: Option<Vec<FramePart>>,
    /// Which of the scene's objects are drawn every displayed frame and
    /// left out of the I-frames (`every_frame`), and their drawing.
    every_frame: &'a [bool],
    thin: std::cell::RefCell<Option<ThinObjects>>,
}

impl Schedule<'_> {
    /// The inputs of the instrumented module at `frames[0]`: the scene's,
    /// with the previous twins filled with frame `frames[1]`'s buffers,
    /// the next twins with `frames[2]`'s, and the flow parameters. An
    /// I-frame's are its neighbours' (the first I-frame's previous is
    /// itself); a scene-assisted B-frame's the I-frames around it.
    fn twinned_inputs(
        &self,
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        [frame, previous, next]: [u32; 3],
    ) -> Result<FrameInputs, Error> {
        let mut now = inputs_of(frame)?;
        let before = inputs_of(previous)?;
        let after = inputs_of(next)?;
        for (index, object) in now.objects.iter_mut().enumerate() {
            let moving = self.moving.get(index).copied().unwrap_or(false);
            let params: Vec<u8> = [
                self.size[0] as f32,
                self.size[1] as f32,
                f32::from(u8::from(moving)),
                0.0,
            ]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
            for (twins, other) in [
                (&self.instrumented.previous, &before),
                (&self.instrumented.next, &after),
            ] {
                for (original, twin) in twins {
                    let bytes = other
                        .objects
                        .get(index)
                        .and_then(|o| o.buffers.get(original))
                        .ok_or_else(|| {
                            fail(format!(
                                "internal error: object {index} has no buffer at group {} binding {} to twin",
                                original[0], original[1]
                            ))
                        })?;
                    object.buffers.insert(*twin, bytes.clone());
                }
            }
            object.buffers.insert(self.instrumented.params, params);
            if !self.instrumented.instance_twins.is_empty() {
                object.instance_inputs = self
                    .instrumented
                    .instance_records([
                        &object.instance_inputs,
                        instance_records(&before, index),
                        instance_records(&after, index),
                    ])
                    .map_err(fail)?;
            }
        }
        Ok(self.interpolated(now))
    }

    /// `inputs` without the objects drawn every displayed frame: what the
    /// I-frames and the passes at B-frame times draw.
    fn interpolated(&self, mut inputs: FrameInputs) -> FrameInputs {
        for (object, thin) in inputs.objects.iter_mut().zip(self.every_frame) {
            if *thin {
                object.instances = 0;
            }
        }
        inputs
    }

    /// `inputs` with only the moving objects drawn.
    fn only_moving(&self, mut inputs: FrameInputs) -> FrameInputs {
        for (object, moves) in inputs.objects.iter_mut().zip(self.moving) {
            if !moves {
                object.instances = 0;
            }
        }
        inputs
    }

    /// Each object's cost in `runner`'s frame of `inputs`, ms: its draw
    /// alone over a frame that draws nothing, the median of three, for
    /// [`super::partition::split`]. Untimed by the report.
    fn draw_costs(
        &self,
        clock: &mut Clock,
        runner: &mut Runner,
        inputs: &FrameInputs,
    ) -> Result<Vec<f64>, Error> {
        let whole = runner.whole_draws(inputs);
        let mut time_of = |draws: Vec<DrawShare>| -> Result<f64, Error> {
            let part = FramePart { draws, more: false };
            let times = (0..3)
                .map(|_| self.time_part(clock, runner, inputs, &part, "partition"))
                .collect::<Result<Vec<f64>, Error>>()?;
            Ok(metrics::median(&times))
        };
        let empty = time_of(Vec::new())?;
        whole
            .into_iter()
            .map(|draw| Ok((time_of(vec![draw])? - empty).max(0.0)))
            .collect()
    }

    /// Draws `inputs` with `runner`, timed: at once, or with `--partition`
    /// part by part (each timed alone). Returns the total and the parts'
    /// times.
    fn draw_iframe(
        &self,
        clock: &mut Clock,
        runner: &mut Runner,
        inputs: &FrameInputs,
        label: &str,
    ) -> Result<(f64, Vec<f64>), Error> {
        let Some(parts) = &self.partition else {
            let (time, _, _) = timed(clock, runner, inputs, label).map_err(fail)?;
            return Ok((time, Vec::new()));
        };
        let times = parts
            .iter()
            .map(|part| self.time_part(clock, runner, inputs, part, label))
            .collect::<Result<Vec<f64>, Error>>()?;
        Ok((times.iter().sum(), times))
    }

    /// One part of `runner`'s frame of `inputs`, timed (ms).
    fn time_part(
        &self,
        clock: &mut Clock,
        runner: &mut Runner,
        inputs: &FrameInputs,
        part: &FramePart,
        label: &str,
    ) -> Result<f64, Error> {
        timed_recording(clock, label, |profiler| {
            runner.frame_part(self.gpu, inputs, Some(part), profiler)
        })
        .map(|(time, _, _)| time)
        .map_err(fail)
    }

    fn textures<'r>(&self, runner: &'r Runner) -> Result<IFrameTextures<'r>, Error> {
        let [previous, next] = self.instrumented.flow_locations;
        let missing =
            |what: &str| fail(format!("internal error: the I-frame has no {what} target"));
        Ok(IFrameTextures {
            color: runner.color().ok_or_else(|| missing("colour"))?,
            depth: runner.depth(),
            flow_previous: runner
                .color_at(previous)
                .ok_or_else(|| missing("flow_previous"))?,
            flow_next: runner.color_at(next).ok_or_else(|| missing("flow_next"))?,
        })
    }

    /// Every interval in turn (the warm-up's unrecorded), after the first
    /// I-frame: what the run measured.
    fn measure(
        &self,
        clock: &mut Clock,
        mut runs: Runs,
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        intervals: u32,
        progress: &mut dyn Progress,
    ) -> Result<Measured, Error> {
        let n = self.options.frames_per_interval;
        let mut measured = Measured {
            blur: self
                .options
                .motion_blur
                .then(|| super::blur::MotionBlur::new(n, self.size)),
            ..Measured::default()
        };
        // The first I-frame: the one the first interval opens with.
        timed(
            clock,
            &mut runs.slots[0],
            &self.twinned_inputs(inputs_of, [0, 0, n])?,
            "iframe",
        )
        .map_err(fail)?;
        if let Some(payload) = runs.payload.as_deref_mut() {
            let inputs = self.interpolated(inputs_of(0)?);
            timed(clock, &mut payload.slots[0], &inputs, "payload").map_err(fail)?;
        }
        // The Z-buffer bridge's first frames, from either kind of depth,
        // untimed: a software rasteriser compiles a pipeline on its first
        // draw.
        if self.thin.borrow().is_some() {
            let first = &runs.slots[0];
            let color = first
                .color()
                .ok_or_else(|| fail("the I-frame draws no colour".into()))?;
            for depth in [
                FrameDepth::Buffer(first.depth()),
                FrameDepth::Chosen(self.bframes.chosen_depth()),
            ] {
                self.shown(clock, inputs_of, 0, (color, depth))?;
            }
        }
        for interval in 0..WARMUP_INTERVALS + intervals {
            let record = interval >= WARMUP_INTERVALS;
            self.interval(
                clock,
                &mut runs,
                inputs_of,
                (interval, record),
                &mut measured,
                progress,
            )?;
        }
        Ok(measured)
    }

    /// Draws interval `interval`: the reference at each of its displayed
    /// frames, its closing I-frame, every method's B-frames; keeps the
    /// measurements when `record`.
    fn interval(
        &self,
        clock: &mut Clock,
        runs: &mut Runs,
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        (interval, record): (u32, bool),
        measured: &mut Measured,
        progress: &mut dyn Progress,
    ) -> Result<(), Error> {
        let Runs {
            reference,
            slots,
            scene: scene_runs,
            correspondence,
            moving,
            payload,
        } = runs;
        let n = self.options.frames_per_interval;
        let start = interval * n;
        let end = start + n;
        // Every frame the interval draws or twins (its own, and the next
        // I-frame's for the closing I-frame's twins), simulated once.
        let frames: BTreeMap<u32, FrameInputs> = (start..=end + n)
            .map(|frame| Ok((frame, inputs_of(frame)?)))
            .collect::<Result<_, Error>>()?;
        let inputs_of = |frame: u32| {
            frames.get(&frame).cloned().ok_or_else(|| {
                fail(format!(
                    "internal error: frame {frame} is outside interval {interval}"
                ))
            })
        };
        let inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error> = &inputs_of;

        // The reference at every displayed frame of the interval, the
        // closing I-frame's time included.
        let mut pictures = self.references(
            clock,
            reference,
            inputs_of,
            (start, record),
            measured,
            progress,
        )?;

        // With --partition, the original drawn in parts too at the
        // closing I-frame's time: the I-frame of the methods that draw
        // no flows.
        if self.partition.is_some() {
            let (_, parts) = self.draw_iframe(clock, reference, &inputs_of(end)?, "reference")?;
            if record {
                measured.reference_parts.push(parts);
            }
        }

        // The closing I-frame, into the slot the opening one is not in.
        let (earlier, later) = ((interval % 2) as usize, ((interval + 1) % 2) as usize);
        let scene_methods: Vec<Method> = scene_runs
            .iter()
            .map(|r| r.method)
            .chain(payload.is_some().then_some(Method::Payload))
            .collect();
        self.closing_iframe(
            clock,
            &mut slots[later],
            inputs_of,
            (start, record, &pictures[n as usize - 1]),
            &scene_methods,
            measured,
            progress,
        )?;

        if let Some(payload) = payload.as_deref_mut() {
            let inputs = self.interpolated(inputs_of(end)?);
            let (time, _, _) =
                timed(clock, &mut payload.slots[later], &inputs, "payload").map_err(fail)?;
            if record {
                let run = measured.methods.entry(Method::Payload).or_default();
                run.prepare_times.push(time);
            }
        }

        let textures = (
            self.textures(&slots[earlier])?,
            self.textures(&slots[later])?,
        );
        let at = IntervalAt {
            start,
            end,
            record,
            pictures: &pictures,
            textures: &textures,
            flow_next_0: std::cell::OnceCell::new(),
        };
        for &method in self.methods {
            // Half-velocity's moving objects: wiped out of I-frame 0 once
            // an interval, timed with its first B-frame.
            let moving = moving
                .as_deref_mut()
                .filter(|_| method == Method::HalfVelocity);
            self.image_method(
                clock,
                method,
                (moving, correspondence.as_deref_mut()),
                inputs_of,
                &at,
                measured,
                progress,
            )?;
        }
        for scene_run in scene_runs.iter_mut() {
            self.scene_method(clock, scene_run, inputs_of, &at, measured, progress)?;
        }
        if let Some(payload) = payload.as_deref_mut() {
            let slots = (earlier, later);
            self.payload_method(clock, (payload, slots), inputs_of, &at, measured, progress)?;
        }
        if let Some((morph, methods)) = self.morph {
            for &method in methods {
                self.morph_method(clock, (morph, method), inputs_of, &at, measured, progress)?;
            }
        }
        if record {
            self.pursue(&at, measured)?;
        }
        measured.previous_end = pictures.pop();
        Ok(())
    }

    /// One image-space method's B-frames of the interval, timed, and
    /// compared with the reference when recorded (image-based's searches
    /// with the exact correspondences too).
    #[allow(clippy::too_many_arguments)]
    fn image_method(
        &self,
        clock: &mut Clock,
        method: Method,
        (mut moving, mut correspondence): (Option<&mut SceneRun>, Option<&mut Correspondence>),
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        at: &IntervalAt,
        measured: &mut Measured,
        progress: &mut dyn Progress,
    ) -> Result<(), Error> {
        let (start, end, record, textures, pictures) =
            (at.start, at.end, at.record, at.textures, at.pictures);
        let n = self.options.frames_per_interval;
        let mut removal = moving.is_some();
        for k in self.frames_of_interval(record, measured) {
            let params = self.params(k);
            let mut moving_now = match moving.as_deref_mut() {
                Some(run) => {
                    run.bind(self.gpu, textures, &params)?;
                    let inputs = self.twinned_inputs(inputs_of, [start + k, start, end])?;
                    Some((run, self.only_moving(inputs)))
                }
                None => None,
            };
            let (time, _, _) = timed_recording(clock, "bframe", |mut profiler| {
                let mut objects = None;
                if let Some((run, inputs)) = moving_now.as_mut() {
                    if std::mem::take(&mut removal) {
                        self.bframes.remove_moving_objects(
                            self.gpu,
                            (textures.0.color, textures.0.flow_next),
                            &params,
                            self.options.inpaint_passes,
                            reborrow(&mut profiler),
                        );
                    }
                    run.runner
                        .frame(self.gpu, inputs, reborrow(&mut profiler))?;
                    objects = Some(MovingObjects {
                        now: run.output(self.instrumented.scene_locations[0])?,
                        removed: self.bframes.removed(),
                    });
                }
                self.bframes.render(
                    self.gpu,
                    method,
                    (&textures.0, &textures.1),
                    &params,
                    objects,
                    profiler,
                )
            })
            .map_err(fail)?;
            progress.step(method.name());
            if record {
                let depth = match method {
                    Method::ImageBased => FrameDepth::Chosen(self.bframes.chosen_depth()),
                    _ => FrameDepth::Buffer(textures.0.depth),
                };
                let sample = self.sample(
                    clock,
                    inputs_of,
                    (start + k, params.alpha, time),
                    (self.bframes.color(), depth),
                    Some(self.bframes.decisions()),
                )?;
                let reference = self.reference_at(k, pictures, measured)?;
                self.keep(measured, method, sample, &reference);
                let interior = k >= 1 && k < n;
                if let (Method::ImageBased, Some(c), true) =
                    (method, correspondence.as_deref_mut(), interior)
                {
                    let inputs = self.twinned_inputs(inputs_of, [start + k, start, end])?;
                    let swapped = self.twinned_inputs(inputs_of, [start + k, end, start])?;
                    let errors = c.measure(self, at, &params, (&inputs, &swapped))?;
                    let ours = &mut measured.correspondence;
                    ours.means
                        .push((errors.total.mean(), errors.total_hit.mean()));
                    ours.total.extend(errors.total);
                    ours.used.extend(errors.used);
                    ours.linear.extend(errors.linear);
                }
            }
        }
        Ok(())
    }

    /// One scene-assisted method's B-frames of the interval, rasterised
    /// at their times, timed, and compared when recorded.
    fn scene_method(
        &self,
        clock: &mut Clock,
        scene_run: &mut SceneRun,
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        at: &IntervalAt,
        measured: &mut Measured,
        progress: &mut dyn Progress,
    ) -> Result<(), Error> {
        let (start, end, record, textures, pictures) =
            (at.start, at.end, at.record, at.textures, at.pictures);
        for k in self.frames_of_interval(record, measured) {
            let params = self.params(k);
            scene_run.bind(self.gpu, textures, &params)?;
            let inputs = self.twinned_inputs(inputs_of, [start + k, start, end])?;
            let (time, _, _) =
                timed(clock, &mut scene_run.runner, &inputs, "bframe").map_err(fail)?;
            progress.step(scene_run.method.name());
            if record {
                let [color, decision] = self.instrumented.scene_locations;
                let sample = self.sample(
                    clock,
                    inputs_of,
                    (start + k, params.alpha, time),
                    (
                        scene_run.output(color).map_err(fail)?,
                        FrameDepth::Buffer(scene_run.runner.depth()),
                    ),
                    Some(scene_run.output(decision).map_err(fail)?),
                )?;
                self.keep(
                    measured,
                    scene_run.method,
                    sample,
                    &self.reference_at(k, pictures, measured)?,
                );
            }
        }
        Ok(())
    }

    /// Payload interpolation's B-frames of the interval: the two
    /// I-frames' payloads (in `slots`, earlier and later) interpolated by
    /// image-based's search, shaded at each B-frame's time; timed
    /// together, compared when recorded.
    fn payload_method(
        &self,
        clock: &mut Clock,
        (run, (earlier, later)): (&mut PayloadRun, (usize, usize)),
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        at: &IntervalAt,
        measured: &mut Measured,
        progress: &mut dyn Progress,
    ) -> Result<(), Error> {
        let (start, record, pictures) = (at.start, at.record, at.pictures);
        for k in self.frames_of_interval(record, measured) {
            let params = self.params(k);
            let inputs = self.interpolated(inputs_of(start + k)?);
            let (time, _, _) = timed_recording(clock, "bframe", |mut profiler| {
                let payloads = (
                    run.iframe(earlier, &at.textures.0),
                    run.iframe(later, &at.textures.1),
                );
                run.search.render(
                    self.gpu,
                    Method::ImageBased,
                    (&payloads.0, &payloads.1),
                    &params,
                    None,
                    reborrow(&mut profiler),
                )?;
                run.shade.frame(self.gpu, &inputs, profiler)
            })
            .map_err(fail)?;
            progress.step(Method::Payload.name());
            if record {
                let color = run
                    .shade
                    .color()
                    .ok_or_else(|| fail("the payload's shade pass draws no colour".into()))?;
                let sample = self.sample(
                    clock,
                    inputs_of,
                    (start + k, params.alpha, time),
                    (color, FrameDepth::Buffer(run.shade.depth())),
                    Some(run.search.decisions()),
                )?;
                let reference = self.reference_at(k, pictures, measured)?;
                self.keep(measured, Method::Payload, sample, &reference);
            }
        }
        Ok(())
    }

    /// One extrapolator's frames of the interval, from I-frame 0 alone:
    /// the morph's preparation (timed with the I-frame), then each
    /// in-between frame, timed and compared when recorded. The
    /// compensating ones display I-frame 0 as the preparation left it.
    fn morph_method(
        &self,
        clock: &mut Clock,
        (morph, method): (&Morph, Method),
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        at: &IntervalAt,
        measured: &mut Measured,
        progress: &mut dyn Progress,
    ) -> Result<(), Error> {
        let (start, record, pictures) = (at.start, at.record, at.pictures);
        let n = self.options.frames_per_interval;
        let earlier = &at.textures.0;
        let mut params = self.morph_params(method);
        let source = Source {
            color: earlier.color,
            depth: earlier.depth,
            flow: if params.exact_motion {
                earlier.flow_next
            } else {
                earlier.flow_previous
            },
        };
        let (prepare_ms, _, _) = timed_recording(clock, "morph", |profiler| {
            morph.prepare(self.gpu, &source, &params, profiler);
            Ok(())
        })
        .map_err(fail)?;
        if record {
            measured
                .methods
                .entry(method)
                .or_default()
                .prepare_times
                .push(prepare_ms);
            self.displayed_iframe((morph, method, params.blur), at, measured)?;
        }
        // Extrapolated from I-frame 0 alone: α = 1 is no end point of it.
        for k in self.frames_of_interval(record, measured) {
            if k == n {
                continue;
            }
            params.step = k as f32 / n as f32;
            let (time, _, _) = timed_recording(clock, "bframe", |profiler| {
                morph.render(self.gpu, &source, &params, profiler);
                Ok(())
            })
            .map_err(fail)?;
            progress.step(method.name());
            if record {
                let sample = self.sample(
                    clock,
                    inputs_of,
                    (start + k, params.step, time),
                    (morph.color(), FrameDepth::Buffer(earlier.depth)),
                    None,
                )?;
                let reference = self.reference_at(k, pictures, measured)?;
                self.keep(measured, method, sample, &reference);
            }
        }
        Ok(())
    }

    /// What an extrapolator shows at its interval's I-frame: compensated
    /// (with blur: [`Morph::displayed`]) or the I-frame itself. The
    /// compensated one is compared with the reference, kept with
    /// `keep_frames` and put in the pursuit group (the I-frame itself is
    /// there by default); either joins the motion-blur composites.
    fn displayed_iframe(
        &self,
        (morph, method, blur): (&Morph, Method, bool),
        at: &IntervalAt,
        measured: &mut Measured,
    ) -> Result<(), Error> {
        let start = at.start;
        if !blur {
            if let Some(composites) = measured.blur.as_mut() {
                let shown = read_linear(self.gpu, at.textures.0.color).map_err(fail)?;
                composites.add(Some(method), start, &shown);
            }
            return Ok(());
        }
        if measured.previous_end.is_none() {
            return Ok(());
        }
        let shown = read_linear(self.gpu, morph.displayed()).map_err(fail)?;
        let reference = self.reference_at(0, at.pictures, measured)?;
        let [width, height] = self.size;
        let error = metrics::compare_frames(&reference, &shown, width, height, THRESHOLD);
        let run = measured.methods.entry(method).or_default();
        run.displayed_iframes.push((start, error));
        if let Some(composites) = measured.blur.as_mut() {
            composites.add(Some(method), start, &shown);
        }
        if self.options.keep_frames {
            measured.kept.push(KeptFrame {
                method,
                frame: start,
                alpha: 0.0,
                error,
                reference,
                result: shown.clone(),
                decisions: Vec::new(),
            });
        }
        let n = self.options.frames_per_interval as usize;
        measured
            .groups
            .entry(method)
            .or_insert_with(|| vec![None; n])[0] = Some(shown);
        Ok(())
    }

    /// The morph's knobs for `method` (its step set per frame).
    fn morph_params(&self, method: Method) -> MorphParams {
        let o = self.options;
        let n = o.frames_per_interval as f32;
        MorphParams {
            step: 0.0,
            frames: n,
            gamma: o.gamma,
            exact_motion: method != Method::MorphPast,
            speed_scale: self.speed_scale(),
            tracking: o.tracking,
            blur_min_speed: o.selective_blur,
            distortion: o.distortion_blur,
            snap_threshold: o.snap_threshold,
            far_depth: self.far_depth,
            blur: method != Method::MorphWarp,
            snap: o.snap,
        }
    }

    /// Degrees per second on the retina per pixel of flow over an
    /// interval: the rendered rate R_d / n over the pixels per degree.
    fn speed_scale(&self) -> f32 {
        let o = self.options;
        o.display_hz / o.frames_per_interval as f32 / o.pixels_per_degree
    }

    /// Each method's pursuit error over the interval just built: the
    /// interval's displayed frames integrated along I-frame 0's exact
    /// motion (damped where the eye cannot track), against the same of
    /// the reference ([`super::pursuit`]).
    fn pursue(&self, at: &IntervalAt, measured: &mut Measured) -> Result<(), Error> {
        let groups = std::mem::take(&mut measured.groups);
        let n = self.options.frames_per_interval as usize;
        let Some(first) = measured.previous_end.as_ref() else {
            return Ok(());
        };
        let rendered = read_linear(self.gpu, at.textures.0.color).map_err(fail)?;
        let motion = pursuit::tracked_motion(
            at.flow_next_0(self.gpu)?,
            self.speed_scale(),
            self.options.tracking,
        );
        let integrate = |frames: &[&[f32]]| {
            pursuit::integrate(
                frames,
                &motion,
                self.size,
                self.options.gamma,
                self.options.pursuit_substeps,
            )
        };
        let reference: Vec<&[f32]> = std::iter::once(first.as_slice())
            .chain(at.pictures.iter().take(n - 1).map(Vec::as_slice))
            .collect();
        let seen = integrate(&reference);
        let mut errors = Vec::new();
        for (method, group) in &groups {
            let frames: Option<Vec<&[f32]>> = group
                .iter()
                .enumerate()
                .map(|(k, frame)| match (k, frame) {
                    (_, Some(frame)) => Some(frame.as_slice()),
                    (0, None) => Some(rendered.as_slice()),
                    _ => None,
                })
                .collect();
            if let Some(frames) = frames {
                errors.push((*method, pursuit::error(&integrate(&frames), &seen)));
            }
        }
        for (method, error) in errors {
            measured
                .methods
                .entry(method)
                .or_default()
                .pursuit
                .push(error);
        }
        Ok(())
    }

    /// The reference at each displayed frame after `start` up to the next
    /// I-frame's, timed and read back (kept when `record`).
    fn references(
        &self,
        clock: &mut Clock,
        reference: &mut Runner,
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        (start, record): (u32, bool),
        measured: &mut Measured,
        progress: &mut dyn Progress,
    ) -> Result<Vec<LinearFrame>, Error> {
        let mut pictures: Vec<LinearFrame> = Vec::new();
        for k in 1..=self.options.frames_per_interval {
            let (time, _, _) =
                timed(clock, reference, &inputs_of(start + k)?, "reference").map_err(fail)?;
            progress.step("reference");
            let color = reference
                .color()
                .ok_or_else(|| fail("the reference draws no colour".into()))?;
            pictures.push(read_linear(self.gpu, color).map_err(fail)?);
            if record {
                measured.reference_times.push(time);
                if let (Some(blur), Some(picture)) = (measured.blur.as_mut(), pictures.last()) {
                    blur.add(None, start + k, picture);
                }
            }
        }
        Ok(pictures)
    }

    /// The I-frame closing the interval from `start`, into `slot`; when
    /// `record`, compared with the reference of its time (`reference`),
    /// added to the motion-blur composites of every method (the fullscreen
    /// ones and `scene_methods`), and kept whole with `keep_frames`.
    #[allow(clippy::too_many_arguments)]
    fn closing_iframe(
        &self,
        clock: &mut Clock,
        slot: &mut Runner,
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        (start, record, reference): (u32, bool, &[f32]),
        scene_methods: &[Method],
        measured: &mut Measured,
        progress: &mut dyn Progress,
    ) -> Result<(), Error> {
        let n = self.options.frames_per_interval;
        let end = start + n;
        let [width, height] = self.size;
        let (time, parts) = self.draw_iframe(
            clock,
            slot,
            &self.twinned_inputs(inputs_of, [end, start, end + n])?,
            "iframe",
        )?;
        progress.step("iframe");
        if record {
            let color = slot
                .color()
                .ok_or_else(|| fail("the I-frame draws no colour".into()))?;
            // As displayed: with the objects drawn every frame.
            let (frame, added) = self.shown(
                clock,
                inputs_of,
                end,
                (color, FrameDepth::Buffer(slot.depth())),
            )?;
            measured.iframe_times.push(time + added);
            if !parts.is_empty() {
                measured.iframe_parts.push(parts);
            }
            let error = metrics::compare_frames(reference, &frame, width, height, THRESHOLD);
            measured.iframe_errors.push((end, error));
            if let Some(blur) = measured.blur.as_mut() {
                // Every method shows the I-frame.
                let shown = self.methods.iter().chain(scene_methods);
                for &method in shown {
                    blur.add(Some(method), end, &frame);
                }
            }
            if self.options.keep_frames {
                let textures = self.textures(slot)?;
                let depth = crate::runtime::read_depth(self.gpu, textures.depth).map_err(fail)?;
                measured.iframes.push(KeptIFrame {
                    frame: end,
                    color: frame,
                    depth,
                    flow_previous: read_linear(self.gpu, textures.flow_previous).map_err(fail)?,
                    flow_next: read_linear(self.gpu, textures.flow_next).map_err(fail)?,
                });
            }
        }
        Ok(())
    }

    /// What a method shows at `displayed` (α `alpha`, its pass taking
    /// `time` ms), read back: its frame `color`, and with objects drawn
    /// every frame, them composited into it by `depth` at that frame's
    /// time ([`ThinObjects::composite`], its time added); and its
    /// `decisions`, when it makes some.
    fn sample(
        &self,
        clock: &mut Clock,
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        (displayed, alpha, time): (u32, f32, f64),
        (color, depth): (&wgpu::Texture, FrameDepth),
        decisions: Option<&wgpu::Texture>,
    ) -> Result<BFrameSample, Error> {
        let decisions = match decisions {
            Some(texture) => crate::runtime::read_texture(self.gpu, texture, 4)
                .map_err(fail)?
                .chunks_exact(4)
                .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
                .collect(),
            None => Vec::new(),
        };
        let (frame, added) = self.shown(clock, inputs_of, displayed, (color, depth))?;
        Ok(BFrameSample {
            displayed,
            alpha: f64::from(alpha),
            time: time + added,
            frame,
            decisions,
        })
    }

    /// The frame `color` (depth `depth`) as displayed at `displayed`, read
    /// back, and what showing it added (ms): with objects drawn every
    /// frame, them composited into it at that frame's time.
    fn shown(
        &self,
        clock: &mut Clock,
        inputs_of: &dyn Fn(u32) -> Result<FrameInputs, Error>,
        displayed: u32,
        (color, depth): (&wgpu::Texture, FrameDepth),
    ) -> Result<(LinearFrame, f64), Error> {
        let mut thin = self.thin.borrow_mut();
        let Some(thin) = thin.as_mut() else {
            return Ok((read_linear(self.gpu, color).map_err(fail)?, 0.0));
        };
        let inputs = inputs_of(displayed)?;
        let (time, _, _) = timed_recording(clock, "every frame", |profiler| {
            thin.composite(
                self.gpu,
                (&inputs, self.every_frame),
                (color, depth),
                profiler,
            )
        })
        .map_err(fail)?;
        let frame = read_linear(self.gpu, thin.color().map_err(fail)?).map_err(fail)?;
        Ok((frame, time))
    }

    /// The frames of an interval each method builds: 1 to n − 1; with
    /// [`Options::endpoints`], in a recorded interval, also 0 and n (the
    /// I-frames' own times: a differential check).
    fn frames_of_interval(&self, record: bool, measured: &Measured) -> Vec<u32> {
        let n = self.options.frames_per_interval;
        if self.options.endpoints && record && measured.previous_end.is_some() {
            (0..=n).collect()
        } else {
            (1..n).collect()
        }
    }

    /// The reference picture at the `k`-th frame of the interval whose
    /// later frames are `pictures`.
    fn reference_at(
        &self,
        k: u32,
        pictures: &[LinearFrame],
        measured: &Measured,
    ) -> Result<LinearFrame, Error> {
        let picture = match k {
            0 => measured.previous_end.as_ref(),
            k => pictures.get(k as usize - 1),
        };
        picture.cloned().ok_or_else(|| {
            fail(format!(
                "internal error: no reference picture at frame {k} of the interval"
            ))
        })
    }

    /// The B-frame parameters of the `k`-th frame of an interval.
    fn params(&self, k: u32) -> BFrameParams {
        BFrameParams {
            viewport: [self.size[0] as f32, self.size[1] as f32],
            alpha: k as f32 / self.options.frames_per_interval as f32,
            screen_epsilon: self.options.screen_epsilon,
            depth_epsilon: self.options.depth_epsilon,
            far_depth: self.far_depth,
            dual_init: self.options.dual_init,
            smaller_residual: self.options.smaller_residual,
            velocity_merge: self.options.velocity_merge,
            moving_objects: false,
            min_cosine: self.options.min_cosine,
            // The B-frame before in the same interval (k − 1 ≥ 1: the
            // first B-frame of an interval does not read the last
            // interval's offsets, which belong to other I-frames).
            previous_alpha: (self.options.latest_frame_init && k >= 2)
                .then(|| (k - 1) as f32 / self.options.frames_per_interval as f32),
            inpaint_delta: self.options.inpaint_delta,
        }
    }

    /// Keeps a measured B-frame of `method`, compared with the reference
    /// picture of its time.
    fn keep(
        &self,
        measured: &mut Measured,
        method: Method,
        sample: BFrameSample,
        reference: &[f32],
    ) {
        let [width, height] = self.size;
        let error = metrics::compare_frames(reference, &sample.frame, width, height, THRESHOLD);
        let endpoint = sample.alpha == 0.0 || sample.alpha == 1.0;
        if endpoint || self.options.keep_frames {
            measured.kept.push(KeptFrame {
                method,
                frame: sample.displayed,
                alpha: sample.alpha,
                error,
                reference: reference.to_vec(),
                result: sample.frame.clone(),
                decisions: sample.decisions.clone(),
            });
        }
        if endpoint {
            return;
        }
        let n = self.options.frames_per_interval;
        let group = measured
            .groups
            .entry(method)
            .or_insert_with(|| vec![None; n as usize]);
        if let Some(slot) = group.get_mut((sample.displayed % n) as usize) {
            *slot = Some(sample.frame.clone());
        }
        if let Some(blur) = measured.blur.as_mut() {
            blur.add(Some(method), sample.displayed, &sample.frame);
        }
        let entry = measured.methods.entry(method).or_default();
        entry.times.push(sample.time);
        for &code in &sample.decisions {
            if let Some(count) = entry.decisions.get_mut(code as usize) {
                *count += 1;
            }
        }
        if entry.worst.as_ref().is_none_or(|w| error.ssim < w.0) {
            entry.worst = Some((
                error.ssim,
                sample.displayed,
                metrics::rgba8(reference),
                metrics::rgba8(&sample.frame),
            ));
        }
        entry.frames.push((sample.displayed, sample.alpha, error));
    }

    /// The time of each displayed frame `method` showed over the measured
    /// intervals: its B-frames' passes and its I-frames' (the original's
    /// for the methods that read no flows), with `--partition` the
    /// I-frames' parts spread over the frames.
    fn displayed_frame_times(&self, method: Method, measured: &Measured) -> Vec<f64> {
        let n = self.options.frames_per_interval as usize;
        if method == Method::Reference {
            return measured.reference_times.clone();
        }
        let run = measured.methods.get(&method);
        let bframes = run.map_or(&[][..], |r| &r.times[..]);
        let mut times = Vec::new();
        for (i, chunk) in bframes.chunks(n - 1).enumerate() {
            let (iframe, parts) = if method.reads_flows() {
                (measured.iframe_times.get(i), measured.iframe_parts.get(i))
            } else {
                (
                    measured.reference_times.get(i * n + n - 1),
                    measured.reference_parts.get(i),
                )
            };
            let work = super::partition::IntervalWork {
                bframes: chunk,
                iframe: iframe.copied().unwrap_or(0.0),
                parts: parts.map(|p| &p[..]),
                added: run
                    .filter(|_| method.adds_iframe_passes())
                    .and_then(|r| r.prepare_times.get(i))
                    .copied()
                    .unwrap_or(0.0),
            };
            times.extend(work.frame_times());
        }
        times
    }

    /// What `method` measured, as the report says it.
    fn method_report(
        &self,
        method: Method,
        measured: &Measured,
        (reference_ms, iframe_ms): (f64, f64),
    ) -> MethodReport {
        let n = self.options.frames_per_interval;
        let run = measured.methods.get(&method);
        let blur = measured.blur.as_ref().and_then(|b| match method {
            Method::Reference => Some((1.0, metrics::PSNR_CAP)),
            _ => b.of(method),
        });
        let b_ms = run.map_or(0.0, |r| metrics::median(&r.times));
        let i_ms = if method.adds_iframe_passes() {
            iframe_ms + run.map_or(0.0, |r| metrics::median(&r.prepare_times))
        } else if method.reads_flows() {
            iframe_ms
        } else {
            reference_ms
        };
        let (i_ratio, b_ratio, amortized) = if method == Method::Reference {
            (1.0, 1.0, 1.0)
        } else {
            (
                i_ms / reference_ms,
                b_ms / reference_ms,
                (i_ms + f64::from(n - 1) * b_ms) / (f64::from(n) * reference_ms),
            )
        };
        let errors: Vec<&FrameError> = run
            .map(|r| r.frames.iter().map(|(_, _, e)| e).collect())
            .unwrap_or_default();
        let ssims: Vec<f64> = errors.iter().map(|e| e.ssim).collect();
        let psnrs: Vec<f64> = errors.iter().map(|e| e.psnr_frame).collect();
        let double_miss_rate = (method == Method::ImageBased).then(|| {
            let d = run.map_or([0; 5], |r| r.decisions);
            let with_geometry: u64 = d.iter().sum::<u64>() - d[Decision::Background as usize];
            if with_geometry == 0 {
                0.0
            } else {
                d[Decision::DoubleMiss as usize] as f64 / with_geometry as f64
            }
        });
        MethodReport {
            method,
            frames_per_interval: n,
            i_frame_time_ratio: i_ratio,
            b_frame_time_ratio: b_ratio,
            amortized_time_ratio: amortized,
            b_frame_ms: b_ms,
            ssim_mean: if method == Method::Reference {
                1.0
            } else {
                metrics::mean(&ssims)
            },
            ssim_min: ssims.iter().copied().fold(1.0, f64::min),
            psnr_mean: if method == Method::Reference {
                metrics::PSNR_CAP
            } else {
                metrics::mean(&psnrs)
            },
            double_miss_rate,
            correspondence_error_px: (method == Method::ImageBased
                && !measured.correspondence.means.is_empty())
            .then(|| {
                let c = &measured.correspondence;
                let all: Vec<f64> = c.means.iter().map(|m| m.0).collect();
                let hit: Vec<f64> = c.means.iter().map(|m| m.1).collect();
                report::CorrespondenceError {
                    all: metrics::mean(&all),
                    hit: metrics::mean(&hit),
                    total: c.total.spread(),
                    used: c.used.spread(),
                    linear: c.linear.spread(),
                }
            }),
            added_latency_frames: if method.reads_later_frame() || self.partition.is_some() {
                f64::from(n - 1)
            } else {
                0.0
            },
            displayed_frame_ms: FrameTimes::of(
                &self.displayed_frame_times(method, measured),
                self.partition.is_some(),
            ),
            worst_frame: run.and_then(|r| r.worst.as_ref().map(|w| w.1)),
            motion_blur_ssim: blur.map(|b| b.0),
            motion_blur_psnr: blur.map(|b| b.1),
            pursuit_error: if method == Method::Reference {
                Some(0.0)
            } else {
                run.filter(|r| !r.pursuit.is_empty())
                    .map(|r| metrics::mean(&r.pursuit))
            },
            displayed_i_frame_psnr: run.filter(|r| !r.displayed_iframes.is_empty()).map(|r| {
                let psnr: Vec<f64> = r
                    .displayed_iframes
                    .iter()
                    .map(|(_, e)| e.psnr_frame)
                    .collect();
                metrics::mean(&psnr)
            }),
        }
    }

    fn report(
        &self,
        shader: &Shader,
        (scene_path, scene_description): (&Path, &str),
        clock: &Clock,
        measured: Measured,
        intervals: u32,
        mut notes: Vec<String>,
    ) -> (Report, Pictures) {
        let n = self.options.frames_per_interval;
        let reference_ms = metrics::median(&measured.reference_times);
        let iframe_ms = metrics::median(&measured.iframe_times);
        let mut methods = Vec::new();
        let mut pictures = Pictures::default();
        // The methods that ran: the refused ones are in the notes.
        let shown: Vec<Method> = self
            .options
            .methods
            .iter()
            .copied()
            .filter(|m| *m == Method::Reference || measured.methods.contains_key(m))
            .collect();
        for &method in &shown {
            let run = measured.methods.get(&method);
            if let Some((_, _, reference, result)) = run.and_then(|r| r.worst.clone()) {
                pictures.worst.push((method, reference, result));
            }
            methods.push(self.method_report(method, &measured, (reference_ms, iframe_ms)));
        }
        let frames = displayed_frames(&shown, &measured);
        notes.push("one I-frame pass writes both flows: the paper renders the forward flow in a geometry pass of its own, so its I-frames cost more than these".to_string());
        if !self.options.methods.contains(&Method::Reference) {
            notes.push("the reference is rendered every frame all the same: the errors and ratios are against it".into());
        }
        notes.extend(report::motion_difference(&methods));
        let answer = report::answer(&methods, n);
        let report = Report {
            format: report::FORMAT,
            shader: shader.file.path.clone(),
            scene: scene_path.display().to_string(),
            scene_description: scene_description.to_string(),
            adapter: format!("{} ({:?})", self.gpu.adapter.name, self.gpu.adapter.backend),
            driver: crate::runtime::driver_line(&self.gpu.adapter),
            timing: if clock.timestamps {
                "gpu-timestamps"
            } else {
                "cpu"
            }
            .into(),
            size: self.size,
            frames_per_interval: n,
            intervals,
            parameters: Parameters {
                options: self.options.clone(),
                flow_format: "rgba16float".into(),
                flows: "both flows from the I-frame pass (next- and previous-I-frame twins)".into(),
            },
            reference_ms,
            i_frame_ms: iframe_ms,
            i_frame_psnr_min: measured
                .iframe_errors
                .iter()
                .map(|(_, e)| e.psnr_frame)
                .fold(metrics::PSNR_CAP, f64::min),
            methods,
            frames,
            notes,
            answer,
        };
        pictures.kept = measured.kept;
        pictures.iframes = measured.iframes;
        (report, pictures)
    }
}

/// SSIM of every displayed frame measured, per method: an I-frame's is
/// the I-frame's against the reference (every method shows it, but the
/// extrapolators that compensate, which show their own), a B-frame's the
/// method's; the reference's is 1.
fn displayed_frames(methods: &[Method], measured: &Measured) -> Vec<DisplayedFrame> {
    let mut frames: BTreeMap<u32, DisplayedFrame> = BTreeMap::new();
    for &(frame, ref error) in &measured.iframe_errors {
        frames.insert(
            frame,
            DisplayedFrame {
                frame,
                alpha: 0.0,
                ssim: methods
                    .iter()
                    .map(|&m| {
                        if m == Method::Reference {
                            1.0
                        } else {
                            error.ssim
                        }
                    })
                    .collect(),
            },
        );
    }
    for (i, &method) in methods.iter().enumerate() {
        let Some(run) = measured.methods.get(&method) else {
            continue;
        };
        // The extrapolators that compensate show their own I-frames.
        for &(frame, ref error) in &run.displayed_iframes {
            if let Some(entry) = frames.get_mut(&frame) {
                entry.ssim[i] = error.ssim;
            }
        }
        for &(frame, alpha, ref error) in &run.frames {
            let entry = frames.entry(frame).or_insert_with(|| DisplayedFrame {
                frame,
                alpha,
                ssim: vec![1.0; methods.len()],
            });
            entry.ssim[i] = error.ssim;
        }
    }
    frames.into_values().collect()
}
