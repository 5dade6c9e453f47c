//! The schedule: interval by interval, the reference at every displayed
//! frame, the closing I-frame (with `--partition`, in parts), then each
//! method's frames ([`super::frame_method::FrameMethod`]), every one
//! timed and compared with the reference of its own time.

use std::cell::{OnceCell, RefCell};
use std::collections::{BTreeMap, HashMap};
use std::path::Path;

use super::bframe::BFrames;
use super::frame_method::{FrameMethod, Setup};
use super::frames::{Cuts, Frames, InputsOf, IntervalAt, THRESHOLD};
use super::iframe::IFrameShader;
use super::measured::Measured;
use super::report::{KeptIFrame, Pictures, Report};
use super::setup::{check, flicker_note, RunPlan, WARMUP_INTERVALS};
use super::summary::Summary;
use super::thin::{FrameDepth, ThinObjects};
use super::{methods, pursuit, Method, Options};
use crate::diagnostic::Error;
use crate::front::Shader;
use crate::measure::bench::{self, Bench};
use crate::measure::clock::{read_linear, timed, timed_recording, Clock};
use crate::measure::inputs::SceneInputs;
use crate::measure::metrics::{self, LinearFrame};
use crate::measure::{fail, Progress};
use crate::runtime::{DrawShare, FrameInputs, FramePart, Gpu, Runner};
use crate::scene::Scene;

pub(super) fn run(
    shader: &Shader,
    scene: &Scene,
    scene_path: &Path,
    options: &Options,
    progress: &mut dyn Progress,
) -> Result<(Report, Pictures), Error> {
    check(options)?;
    let plan = RunPlan::new(shader, scene, options)?;
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
        plan.size,
    )?;
    let bench = Bench {
        gpu: &gpu,
        inputs: &inputs,
        size: plan.size,
        cull_back_faces: scene.cull_back_faces,
    };
    let scripted = Scripted {
        shader,
        scene,
        scene_path,
        options,
        plan: &plan,
        instrumented: &instrumented,
        bench: &bench,
    };
    scripted.measure(progress)
}

/// A run checked and its scene's inputs made: what the measurement
/// draws from.
struct Scripted<'a> {
    shader: &'a Shader,
    scene: &'a Scene,
    scene_path: &'a Path,
    options: &'a Options,
    plan: &'a RunPlan,
    instrumented: &'a IFrameShader,
    bench: &'a Bench<'a>,
}

impl Scripted<'_> {
    /// Makes the runners and the methods, measures every interval and
    /// sums the run up.
    fn measure(&self, progress: &mut dyn Progress) -> Result<(Report, Pictures), Error> {
        let (scene, options, plan, bench) = (self.scene, self.options, self.plan, self.bench);
        let (gpu, instrumented) = (bench.gpu, self.instrumented);
        let inputs_of = |frame: u32| bench.inputs.frame(scene, frame);
        let mut clock = Clock::new(gpu)?;
        let mut reference = bench::reference(bench, self.shader, &plan.reference)?;
        let sources = HashMap::from([("iframe.wgsl".to_string(), instrumented.text.clone())]);
        let iframe_runner = || {
            bench
                .runner(&instrumented.plan, &sources, false)
                .map_err(|err| fail(format!("the I-frame pass does not run: {err}")))
        };
        let mut slots = [iframe_runner()?, iframe_runner()?];
        let mut notes = scene_notes(scene);
        let moving: Vec<bool> = (0..scene.objects.len()).map(|i| scene.moves(i)).collect();
        let every_frame: Vec<bool> = scene.objects.iter().map(|o| o.every_frame).collect();
        let thin = ThinObjects::of_scene(bench, self.shader, plan, &every_frame, &mut notes)?;
        let bframes = bframe_passes(gpu, options, plan.size, thin.is_some())?;
        let morph = methods::morph_passes(gpu, options, plan.size)?;
        let setup = Setup {
            bench,
            shader: self.shader,
            plan,
            instrumented,
            sources: &sources,
            options,
            moving: &moving,
            bframes: &bframes,
            morph: morph.as_ref(),
        };
        let mut methods = methods::build(&setup, &mut notes)?;
        notes.extend(flicker_note(options));
        let mut schedule = Schedule {
            frames: Frames {
                gpu,
                instrumented,
                options,
                size: plan.size,
                far_depth: scene.camera.depth.far_depth(),
                moving: &moving,
                every_frame: &every_frame,
                thin: RefCell::new(thin),
            },
            bframes: &bframes,
            partition: None,
        };
        if options.partition {
            schedule.partition(&mut clock, &mut slots[0], &inputs_of, &mut notes)?;
        }
        let n = plan.n;
        let total = u64::from(WARMUP_INTERVALS + plan.intervals)
            * u64::from(n + 1 + methods.len() as u32 * (n - 1));
        progress.start(total);
        let mut measured = Measured::default();
        let mut measuring = Measuring {
            clock: &mut clock,
            measured: &mut measured,
            progress,
        };
        let runs = Runs {
            reference: &mut reference,
            slots: &mut slots,
            methods: &mut methods,
        };
        schedule.measure(&mut measuring, runs, &inputs_of, plan.intervals)?;
        measuring.progress.finish();
        let summary = Summary {
            frames: &schedule.frames,
            partitioned: schedule.partition.is_some(),
        };
        let scene_named = (self.scene_path, scene.description.as_str());
        Ok(summary.report(
            self.shader,
            scene_named,
            &clock,
            measured,
            plan.intervals,
            notes,
        ))
    }
}

/// What the scene says of the run before it is measured.
fn scene_notes(scene: &Scene) -> Vec<String> {
    let mut notes = Vec::new();
    if scene.effects.is_empty() {
        notes.push(
            "the scene declares no motion (`effects` is empty): every B-frame should equal its I-frames"
                .to_string(),
        );
    }
    if !scene.camera.cuts.is_empty() {
        let frames: Vec<String> = scene
            .camera
            .cuts
            .iter()
            .map(|c| c.frame.to_string())
            .collect();
        let plural = if frames.len() == 1 { "" } else { "s" };
        notes.push(format!(
            "camera cut{plural} at motion frame{plural} {}: where a method's frames would be made from two shots (both I-frames across a cut, or the motion from the I-frame before it), they repeat the earlier I-frame, as do every method's frames of a new shot that no I-frame has shown yet; an interval with a cut in it is left out of the pursuit error and flicker",
            frames.join(", ")
        ));
    }
    notes
}

/// The image-space methods' B-frame passes: every method's asked for,
/// image-based's writing the depth it chose where objects drawn every
/// frame are bridged in (`thin`).
fn bframe_passes(
    gpu: &Gpu,
    options: &Options,
    size: [u32; 2],
    thin: bool,
) -> Result<BFrames, Error> {
    let latest = options.latest_frame_init.then_some(options.latest_radius);
    // Sample-and-hold's pass always: every method repeats the frame with
    // it where a camera cut leaves nothing to reuse.
    let mut methods = options.methods.clone();
    if !methods.contains(&Method::SampleAndHold) {
        methods.push(Method::SampleAndHold);
    }
    BFrames::writing_depth(
        gpu,
        (size[0], size[1]),
        &methods,
        (options.iterations, latest),
        thin,
    )
    .map_err(fail)
}

/// What each step of the schedule writes to: the clock it is timed by,
/// what the run keeps, and the progress shown.
struct Measuring<'m, 'g> {
    clock: &'m mut Clock<'g>,
    measured: &'m mut Measured,
    progress: &'m mut dyn Progress,
}

/// The runners a measured run draws with: the reference, the two I-frame
/// slots (an interval's opening and closing I-frames alternate between
/// them), and the methods.
struct Runs<'r, 'a> {
    reference: &'r mut Runner,
    slots: &'r mut [Runner; 2],
    methods: &'r mut [Box<dyn FrameMethod + 'a>],
}

/// One interval before its I-frames are drawn: where it starts and ends,
/// whether it is recorded, and its frames' inputs.
struct Interval<'a> {
    index: u32,
    start: u32,
    end: u32,
    record: bool,
    inputs_of: &'a InputsOf<'a>,
    /// A camera cut fell in the interval before.
    cut_before: bool,
}

/// What every interval of the run shares.
struct Schedule<'a> {
    frames: Frames<'a>,
    /// The image-space methods' B-frame passes (the Z-buffer bridge's
    /// first frames read their chosen depth).
    bframes: &'a BFrames,
    /// With `--partition`, the parts each I-frame is drawn in
    /// ([`super::partition`]).
    partition: Option<Vec<FramePart>>,
}

impl Schedule<'_> {
    /// Cuts each I-frame into parts for `--partition`, from the draws'
    /// costs measured in `slot`'s first I-frame, and says so in `notes`.
    fn partition(
        &mut self,
        clock: &mut Clock,
        slot: &mut Runner,
        inputs_of: &InputsOf,
        notes: &mut Vec<String>,
    ) -> Result<(), Error> {
        let n = self.frames.options.frames_per_interval;
        let first = self.frames.twinned_inputs(inputs_of, [0, 0, n])?;
        let costs = self.draw_costs(clock, slot, &first)?;
        let whole = slot.whole_draws(&first);
        notes.push(format!(
            "--partition: each I-frame is drawn in {n} parts, one per displayed frame, cut from the draws in order by each object's measured cost alone ({}) (Yang et al. 2011 §7); its I-frame time is the parts' total, and the partitioning adds n − 1 displayed frames of latency to every method",
            costs
                .iter()
                .map(|c| format!("{c:.3} ms"))
                .collect::<Vec<_>>()
                .join(", ")
        ));
        self.partition = Some(super::partition::split(&whole, &costs, n));
        Ok(())
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
            runner.frame_part(self.frames.gpu, inputs, Some(part), profiler)
        })
        .map(|(time, _, _)| time)
        .map_err(fail)
    }

    /// Every interval in turn (the warm-up's unrecorded), after the first
    /// I-frame, into `m`.
    fn measure(
        &self,
        m: &mut Measuring,
        mut runs: Runs,
        inputs_of: &InputsOf,
        intervals: u32,
    ) -> Result<(), Error> {
        let frames = &self.frames;
        let n = frames.options.frames_per_interval;
        m.measured.blur = frames
            .options
            .motion_blur
            .then(|| super::blur::MotionBlur::new(n, frames.size));
        // The first I-frame: the one the first interval opens with.
        let first = frames.twinned_inputs(inputs_of, [0, 0, n])?;
        timed(m.clock, &mut runs.slots[0], &first, "iframe").map_err(fail)?;
        for method in runs.methods.iter_mut() {
            let run = m.measured.methods.entry(method.method()).or_default();
            run.reads_flows = method.reads_flows();
            run.reads_later_frame = method.reads_later_frame();
            method.open(frames, m.clock, inputs_of)?;
        }
        // The Z-buffer bridge's first frames, from either kind of depth,
        // untimed: a software rasteriser compiles a pipeline on its first
        // draw.
        if frames.thin.borrow().is_some() {
            let first = &runs.slots[0];
            let color = first
                .color()
                .ok_or_else(|| fail("the I-frame draws no colour".into()))?;
            for depth in [
                FrameDepth::Buffer(first.depth()),
                FrameDepth::Chosen(self.bframes.chosen_depth()),
            ] {
                frames.shown(m.clock, inputs_of, 0, (color, depth))?;
            }
        }
        let mut cut_before = false;
        for index in 0..WARMUP_INTERVALS + intervals {
            let start = index * n;
            let interval = Interval {
                index,
                start,
                end: start + n,
                record: index >= WARMUP_INTERVALS,
                inputs_of,
                cut_before,
            };
            cut_before = self.interval(m, &mut runs, &interval)?;
        }
        Ok(())
    }

    /// Draws `interval`: the reference at each of its displayed frames,
    /// its closing I-frame, every method's frames; keeps the measurements
    /// when it is recorded. Whether a camera cut fell in it.
    fn interval(
        &self,
        m: &mut Measuring,
        runs: &mut Runs,
        interval: &Interval,
    ) -> Result<bool, Error> {
        let Runs {
            reference,
            slots,
            methods,
        } = runs;
        let frames = &self.frames;
        let n = frames.options.frames_per_interval;
        let (index, start, end) = (interval.index, interval.start, interval.end);
        // Every frame the interval draws or twins (its own, and the next
        // I-frame's for the closing I-frame's twins), simulated once.
        let simulated: BTreeMap<u32, FrameInputs> = (start..=end + n)
            .map(|frame| Ok((frame, (interval.inputs_of)(frame)?)))
            .collect::<Result<_, Error>>()?;
        let inputs_of = |frame: u32| {
            simulated.get(&frame).cloned().ok_or_else(|| {
                fail(format!(
                    "internal error: frame {frame} is outside interval {index}"
                ))
            })
        };
        let interval = Interval {
            inputs_of: &inputs_of,
            ..*interval
        };
        let cut_at = |k: u32| simulated.get(&(start + k)).is_some_and(|frame| frame.cut);
        let cuts = Cuts::of(n, cut_at, interval.cut_before);

        // The reference at every displayed frame of the interval, the
        // closing I-frame's time included.
        let mut pictures = self.references(m, reference, &interval)?;

        // With --partition, the original drawn in parts too at the
        // closing I-frame's time: the I-frame of the methods that draw
        // no flows.
        if self.partition.is_some() {
            let (_, parts) = self.draw_iframe(m.clock, reference, &inputs_of(end)?, "reference")?;
            if interval.record {
                m.measured.reference_parts.push(parts);
            }
        }

        // The closing I-frame, into the slot the opening one is not in.
        let (earlier, later) = ((index % 2) as usize, ((index + 1) % 2) as usize);
        let shown: Vec<Method> = methods
            .iter()
            .filter(|method| method.shows_rendered_iframe())
            .map(|method| method.method())
            .collect();
        let closing = &pictures[n as usize - 1];
        self.closing_iframe(m, &mut slots[later], &interval, closing, &shown)?;

        let textures = (
            frames.textures(&slots[earlier])?,
            frames.textures(&slots[later])?,
        );
        let at = IntervalAt {
            start,
            end,
            record: interval.record,
            pictures: &pictures,
            textures: &textures,
            slots: (earlier, later),
            inputs_of: &inputs_of,
            flow_next_0: OnceCell::new(),
            near_edges: OnceCell::new(),
            cuts,
        };
        for method in methods.iter_mut() {
            self.method_frames(m, method.as_mut(), &at)?;
        }
        if interval.record && cuts.within.is_none() {
            pursuit::interval_errors(&self.frames, &at, m.measured)?;
        } else {
            // No eye tracks the motion across a cut: the interval's
            // frames are left out of the pursuit error and flicker.
            m.measured.groups.clear();
        }
        m.measured.previous_end = pictures.pop();
        Ok(cuts.within.is_some())
    }

    /// One method's frames of the interval: its I-frame passes, then each
    /// frame it builds, drawn and timed; in a recorded interval compared
    /// with the reference of its time and kept.
    fn method_frames(
        &self,
        m: &mut Measuring,
        method: &mut dyn FrameMethod,
        at: &IntervalAt,
    ) -> Result<(), Error> {
        let frames = &self.frames;
        let n = frames.options.frames_per_interval;
        let name = method.method();
        // Where a camera cut leaves it nothing to reuse, the frame before
        // is shown again: no morph, no blend, no blur (and no preparation
        // where no frame of the interval is its own).
        let reads = method.reads();
        let repeats = |k: u32| at.cuts.repeats(reads, k);
        let prepared = if (1..n).filter(|&k| method.builds(k, n)).all(repeats) {
            method.prepare_held(frames, at, m.measured)?;
            None
        } else {
            method.prepare(frames, m.clock, at, m.measured)?
        };
        if let (Some(time), true) = (prepared, at.record) {
            let run = m.measured.methods.entry(name).or_default();
            run.prepare_times.push(time);
        }
        for k in frames.frames_of_interval(at.record, m.measured) {
            if !method.builds(k, n) {
                continue;
            }
            let params = frames.params(k);
            let repeated = repeats(k);
            let drawn = if repeated {
                let hold = Method::SampleAndHold;
                methods::bframe_drawn(self.bframes, hold, frames, m.clock, at, &params)?
            } else {
                method.draw(frames, m.clock, at, k, &params)?
            };
            m.progress.step(name.name());
            if !at.record {
                continue;
            }
            let displayed = (at.start + k, params.alpha);
            let sample = frames.sample(m.clock, at.inputs_of, displayed, &drawn)?;
            let reference = frames.reference_at(k, at.pictures, m.measured)?;
            let near_edges = at.near_motion_edges(frames)?;
            frames.keep(m.measured, name, sample, &reference, near_edges);
            if !repeated {
                method.measure(frames, at, k, &params, m.measured)?;
            }
        }
        Ok(())
    }

    /// The reference at each displayed frame after the interval's start
    /// up to the next I-frame's, timed and read back (kept when
    /// recorded).
    fn references(
        &self,
        m: &mut Measuring,
        reference: &mut Runner,
        interval: &Interval,
    ) -> Result<Vec<LinearFrame>, Error> {
        let start = interval.start;
        let mut pictures: Vec<LinearFrame> = Vec::new();
        for k in 1..=self.frames.options.frames_per_interval {
            let inputs = (interval.inputs_of)(start + k)?;
            let (time, _, _) = timed(m.clock, reference, &inputs, "reference").map_err(fail)?;
            m.progress.step("reference");
            let color = reference
                .color()
                .ok_or_else(|| fail("the reference draws no colour".into()))?;
            pictures.push(read_linear(self.frames.gpu, color).map_err(fail)?);
            if interval.record {
                m.measured.reference_times.push(time);
                if let (Some(blur), Some(picture)) = (m.measured.blur.as_mut(), pictures.last()) {
                    blur.add(None, start + k, picture);
                }
            }
        }
        Ok(pictures)
    }

    /// The I-frame closing `interval`, into `slot`; when recorded,
    /// compared with the reference of its time (`reference`), added to
    /// the motion-blur composites of the methods that show it (`shown`),
    /// and kept whole with `keep_frames`.
    fn closing_iframe(
        &self,
        m: &mut Measuring,
        slot: &mut Runner,
        interval: &Interval,
        reference: &[f32],
        shown: &[Method],
    ) -> Result<(), Error> {
        let frames = &self.frames;
        let n = frames.options.frames_per_interval;
        let (start, end) = (interval.start, interval.end);
        let [width, height] = frames.size;
        let inputs = frames.twinned_inputs(interval.inputs_of, [end, start, end + n])?;
        let (time, parts) = self.draw_iframe(m.clock, slot, &inputs, "iframe")?;
        m.progress.step("iframe");
        if !interval.record {
            return Ok(());
        }
        let color = slot
            .color()
            .ok_or_else(|| fail("the I-frame draws no colour".into()))?;
        // As displayed: with the objects drawn every frame.
        let depth = FrameDepth::Buffer(slot.depth());
        let (frame, added) = frames.shown(m.clock, interval.inputs_of, end, (color, depth))?;
        let measured = &mut *m.measured;
        measured.iframe_times.push(time + added);
        if !parts.is_empty() {
            measured.iframe_parts.push(parts);
        }
        let error = metrics::compare_frames(reference, &frame, width, height, THRESHOLD);
        measured.iframe_errors.push((end, error));
        if let Some(blur) = measured.blur.as_mut() {
            for &method in shown {
                blur.add(Some(method), end, &frame);
            }
        }
        if frames.options.keep_frames {
            let gpu = frames.gpu;
            let textures = frames.textures(slot)?;
            let depth = crate::runtime::read_depth(gpu, textures.depth).map_err(fail)?;
            measured.iframes.push(KeptIFrame {
                frame: end,
                color: frame,
                depth,
                flow_previous: read_linear(gpu, textures.flow_previous).map_err(fail)?,
                flow_next: read_linear(gpu, textures.flow_next).map_err(fail)?,
            });
        }
        Ok(())
    }
}
