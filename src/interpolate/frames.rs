//! How the run makes and measures one displayed frame, for the schedule
//! and for every method alike: a frame's inputs (the instrumented
//! shader's twins filled from the I-frames around it), an interval's
//! B-frame parameters, what a frame shows (the objects drawn every frame
//! composited in), and a B-frame compared with the reference of its time
//! and kept.

use std::cell::{OnceCell, RefCell};

use super::bframe::{BFrameParams, IFrameTextures};
use super::frame_method::Reads;
use super::iframe::IFrameShader;
use super::measured::Measured;
use super::report::KeptFrame;
use super::thin::{FrameDepth, ThinObjects};
use super::{Method, Options};
use crate::diagnostic::Error;
use crate::measure::clock::{read_linear, timed_recording, Clock};
use crate::measure::fail;
use crate::measure::metrics::{self, LinearFrame};
use crate::runtime::{FrameInputs, Gpu, Runner};

/// The error threshold of [`metrics::compare`]'s share above it (unused
/// by the report; one 8-bit step).
pub(super) const THRESHOLD: f64 = 1.0 / 255.0;

/// A frame's inputs by displayed frame: the scene simulated at it.
pub(super) type InputsOf<'i> = dyn Fn(u32) -> Result<FrameInputs, Error> + 'i;

/// What every frame of the run shares.
pub(super) struct Frames<'a> {
    pub gpu: &'a Gpu,
    pub instrumented: &'a IFrameShader,
    pub options: &'a Options,
    pub size: [u32; 2],
    /// The depth buffer's value at the far plane (the scene's
    /// convention).
    pub far_depth: f32,
    /// Which of the scene's objects move ([`crate::scene::Scene::moves`]).
    pub moving: &'a [bool],
    /// Which of the scene's objects are drawn every displayed frame and
    /// left out of the I-frames (`every_frame`), and their drawing.
    pub every_frame: &'a [bool],
    pub thin: RefCell<Option<ThinObjects>>,
}

/// One interval as its methods see it: its first and closing I-frames'
/// times, whether it is recorded, the reference at each of its frames,
/// the two I-frames' textures and the slots they are in, and each
/// frame's inputs.
pub(super) struct IntervalAt<'a> {
    pub start: u32,
    pub end: u32,
    pub record: bool,
    /// The reference at each displayed frame after `start`, the closing
    /// I-frame's included.
    pub pictures: &'a [LinearFrame],
    pub textures: &'a (IFrameTextures<'a>, IFrameTextures<'a>),
    /// The I-frame slots (of the run's two) the opening and the closing
    /// I-frames are in.
    pub slots: (usize, usize),
    pub inputs_of: &'a InputsOf<'a>,
    /// I-frame 0's flow to I-frame 1 read back, once an interval, for
    /// what the CPU measures from it ([`IntervalAt::flow_next_0`]).
    pub flow_next_0: OnceCell<LinearFrame>,
    /// The pixels near a motion edge of I-frame 0's flow, made the first
    /// time they are asked for ([`IntervalAt::near_motion_edges`]).
    pub near_edges: OnceCell<Vec<bool>>,
    /// Where the scene's camera cuts fall against the interval.
    pub cuts: Cuts,
}

/// Where camera cuts fall against an interval: the shot changes between
/// the frames on either side of a cut, and nothing of one shot can be
/// made from the other's frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(super) struct Cuts {
    /// The first frame `k` (1 ..= n) of the interval that is of a new shot,
    /// if a cut falls after its I-frame 0 (at `k = n`: the closing I-frame
    /// starts the new shot).
    pub within: Option<u32>,
    /// A cut falls between the I-frame before and the interval's I-frame 0.
    pub before: bool,
}

impl Cuts {
    /// The cuts against an interval: `cut_at(k)` says whether a cut comes
    /// just before its frame `k`; `before` whether one fell in the
    /// interval before it.
    pub fn of(n: u32, cut_at: impl Fn(u32) -> bool, before: bool) -> Cuts {
        Cuts {
            within: (1..=n).find(|&k| cut_at(k)),
            before,
        }
    }

    /// Whether a method that `reads` so repeats the earlier I-frame at
    /// frame `k` instead of making its own: where what it reads is of
    /// two shots (its two I-frames across a cut, or, for motion from the
    /// past, the I-frame before and this one), and at every frame of a new
    /// shot that no I-frame has shown yet.
    pub fn repeats(&self, reads: Reads, k: u32) -> bool {
        let new_shot = self.within.is_some_and(|cut| k >= cut);
        match reads {
            Reads::EarlierIFrame => false,
            Reads::BothIFrames => self.within.is_some(),
            Reads::PastIFrames => self.before || new_shot,
        }
    }
}

impl IntervalAt<'_> {
    /// I-frame 0's flow to I-frame 1, read back the first time it is
    /// asked for in the interval.
    pub fn flow_next_0(&self, gpu: &Gpu) -> Result<&LinearFrame, Error> {
        if let Some(flow) = self.flow_next_0.get() {
            return Ok(flow);
        }
        let flow = read_linear(gpu, self.textures.0.flow_next).map_err(fail)?;
        Ok(self.flow_next_0.get_or_init(|| flow))
    }

    /// The pixels within [`super::edges::EDGE_RADIUS_PX`] of a motion edge
    /// of I-frame 0's flow to I-frame 1, where every method's error is
    /// also measured.
    pub fn near_motion_edges(&self, frames: &Frames) -> Result<&[bool], Error> {
        if let Some(near) = self.near_edges.get() {
            return Ok(near);
        }
        let flow = self.flow_next_0(frames.gpu)?;
        let size = [frames.size[0] as usize, frames.size[1] as usize];
        let near = super::edges::near_motion_edges(flow, size, super::edges::EDGE_RADIUS_PX);
        Ok(self.near_edges.get_or_init(|| near))
    }
}

/// A B-frame read back: when it is, its time (ms), its colour and its
/// decisions.
pub(super) struct BFrameSample {
    pub displayed: u32,
    pub alpha: f64,
    pub time: f64,
    pub frame: LinearFrame,
    /// Each pixel's [`super::Decision`] code.
    pub decisions: Vec<u32>,
}

/// A frame a method drew, timed: its colour, its depth, and each
/// pixel's decision when it makes some.
pub(super) struct Drawn<'t> {
    /// Its passes' time, ms.
    pub time: f64,
    pub color: &'t wgpu::Texture,
    pub depth: FrameDepth<'t>,
    pub decisions: Option<&'t wgpu::Texture>,
}

/// Object `index`'s per-instance input records in `inputs`.
fn instance_records(inputs: &FrameInputs, index: usize) -> &[u8] {
    inputs
        .objects
        .get(index)
        .map_or(&[][..], |o| o.instance_inputs.as_slice())
}

impl Frames<'_> {
    /// The inputs of the instrumented module at `frames[0]`: the scene's,
    /// with the previous twins filled with frame `frames[1]`'s buffers,
    /// the next twins with `frames[2]`'s, and the flow parameters. An
    /// I-frame's are its neighbours' (the first I-frame's previous is
    /// itself); a scene-assisted B-frame's the I-frames around it.
    pub fn twinned_inputs(
        &self,
        inputs_of: &InputsOf,
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
    pub fn interpolated(&self, mut inputs: FrameInputs) -> FrameInputs {
        for (object, thin) in inputs.objects.iter_mut().zip(self.every_frame) {
            if *thin {
                object.instances = 0;
            }
        }
        inputs
    }

    /// `inputs` with only the moving objects drawn.
    pub fn only_moving(&self, mut inputs: FrameInputs) -> FrameInputs {
        for (object, moves) in inputs.objects.iter_mut().zip(self.moving) {
            if !moves {
                object.instances = 0;
            }
        }
        inputs
    }

    pub fn textures<'r>(&self, runner: &'r Runner) -> Result<IFrameTextures<'r>, Error> {
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

    /// What a method shows at `displayed` (α `alpha`), read back: the
    /// frame it drew, and with objects drawn every frame, them
    /// composited into it by its depth at that frame's time
    /// ([`ThinObjects::composite`], its time added to the drawing's); and
    /// its decisions, when it makes some.
    pub fn sample(
        &self,
        clock: &mut Clock,
        inputs_of: &InputsOf,
        (displayed, alpha): (u32, f32),
        drawn: &Drawn,
    ) -> Result<BFrameSample, Error> {
        let decisions = match drawn.decisions {
            Some(texture) => crate::runtime::read_texture(self.gpu, texture, 4)
                .map_err(fail)?
                .chunks_exact(4)
                .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
                .collect(),
            None => Vec::new(),
        };
        let (frame, added) = self.shown(clock, inputs_of, displayed, (drawn.color, drawn.depth))?;
        Ok(BFrameSample {
            displayed,
            alpha: f64::from(alpha),
            time: drawn.time + added,
            frame,
            decisions,
        })
    }

    /// The frame `color` (depth `depth`) as displayed at `displayed`, read
    /// back, and what showing it added (ms): with objects drawn every
    /// frame, them composited into it at that frame's time.
    pub fn shown(
        &self,
        clock: &mut Clock,
        inputs_of: &InputsOf,
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
    pub fn frames_of_interval(&self, record: bool, measured: &Measured) -> Vec<u32> {
        let n = self.options.frames_per_interval;
        if self.options.endpoints && record && measured.previous_end.is_some() {
            (0..=n).collect()
        } else {
            (1..n).collect()
        }
    }

    /// The reference picture at the `k`-th frame of the interval whose
    /// later frames are `pictures`.
    pub fn reference_at(
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
    pub fn params(&self, k: u32) -> BFrameParams {
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
    pub fn keep(
        &self,
        measured: &mut Measured,
        method: Method,
        sample: BFrameSample,
        reference: &[f32],
        near_edges: &[bool],
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
        entry
            .edge_psnr
            .extend(metrics::psnr_where(reference, &sample.frame, near_edges));
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

    /// Degrees per second on the retina per pixel of flow over an
    /// interval: the rendered rate R_d / n over the pixels per degree.
    pub fn speed_scale(&self) -> f32 {
        let o = self.options;
        o.display_hz / o.frames_per_interval as f32 / o.pixels_per_degree
    }
}

#[cfg(test)]
mod tests {
    use super::{Cuts, Reads};

    /// Which frames of an interval of 4 repeat the earlier I-frame, for
    /// each way a method reads, with a cut at frame 2 of it, at its
    /// closing I-frame, in the interval before, and none.
    #[test]
    fn a_cut_repeats_what_would_be_made_from_two_shots() {
        let frames = |cuts: Cuts, reads: Reads| -> Vec<u32> {
            (1..4).filter(|&k| cuts.repeats(reads, k)).collect()
        };
        let at = |cut: u32| Cuts::of(4, |k| k == cut, false);
        let before = Cuts::of(4, |_| false, true);
        let none = Cuts::of(4, |_| false, false);
        assert_eq!(at(2).within, Some(2));
        for cuts in [at(2), at(4), before, none] {
            assert!(frames(cuts, Reads::EarlierIFrame).is_empty());
        }
        assert_eq!(frames(at(2), Reads::BothIFrames), [1, 2, 3]);
        assert_eq!(frames(at(4), Reads::BothIFrames), [1, 2, 3]);
        assert!(frames(before, Reads::BothIFrames).is_empty());
        assert_eq!(frames(at(2), Reads::PastIFrames), [2, 3]);
        assert!(frames(at(4), Reads::PastIFrames).is_empty());
        assert_eq!(frames(before, Reads::PastIFrames), [1, 2, 3]);
        assert!(frames(none, Reads::BothIFrames).is_empty());
        assert!(frames(none, Reads::PastIFrames).is_empty());
    }
}
