//! Payload interpolation ([`crate::interpolate::payload`]): the cache's
//! payload drawn at each I-frame (two runners, alternating as the I-frame
//! slots do), interpolated between the two I-frames by image-based's
//! search, and shaded at each B-frame's time by a pass that reads what
//! the search wrote. The payload pass counts in its I-frame time.

use crate::diagnostic::Error;
use crate::interpolate::bframe::{BFrameParams, BFrames, IFrameTextures};
use crate::interpolate::frame_method::{FrameMethod, Setup};
use crate::interpolate::frames::{Drawn, Frames, InputsOf, IntervalAt};
use crate::interpolate::gpu::reborrow;
use crate::interpolate::measured::Measured;
use crate::interpolate::thin::FrameDepth;
use crate::interpolate::Method;
use crate::measure::clock::{timed, timed_recording, Clock};
use crate::measure::fail;
use crate::runtime::{RunOptions, Runner};

/// [`Method::Payload`]: its runners.
pub(super) struct Payload {
    slots: [Runner; 2],
    search: BFrames,
    shade: Runner,
}

impl Payload {
    /// The payload of the I-frame in `slot` as the search reads it: the
    /// I-frame's depth and flows with the payload in place of its colour.
    fn iframe<'r>(&'r self, slot: usize, iframe: &IFrameTextures<'r>) -> IFrameTextures<'r> {
        IFrameTextures {
            color: self.slots[slot].payload(),
            ..*iframe
        }
    }

    /// The method's passes and runners, with a note naming its node;
    /// `None` with the reason in `notes` where the shader cannot have
    /// them. A node named on the command line that is not a candidate is
    /// an error.
    pub fn new(setup: &Setup, notes: &mut Vec<String>) -> Result<Option<Payload>, Error> {
        let (bench, options) = (setup.bench, setup.options);
        let analysis = &setup.plan.bindings.analysis;
        let candidate = match &options.payload_node {
            Some(id) => analysis.select(
                &setup.shader.file,
                &crate::analysis::Nodes::Ids(vec![id.clone()]),
            )?[0],
            None => match crate::interpolate::payload::choose(analysis) {
                Ok(candidate) => candidate,
                Err(reason) => {
                    notes.push(format!("payload refused: {reason}"));
                    return Ok(None);
                }
            },
        };
        let made = crate::interpolate::payload::passes(
            setup.shader,
            analysis,
            candidate,
            &setup.plan.rewrite_options,
            &setup.plan.reference,
        )
        .map_err(|refusal| refusal.reason)
        .and_then(|passes| {
            let slot = || bench.runner(&passes.iframe, &passes.sources, false);
            let slots = [slot()?, slot()?];
            let search = BFrames::new(
                bench.gpu,
                (bench.size[0], bench.size[1]),
                &[Method::ImageBased],
                setup.search(),
            )?;
            let mut shade = bench.runner_with(
                &passes.shade,
                &passes.sources,
                RunOptions {
                    external_group: Some(passes.payload_group),
                    ..RunOptions::default()
                },
            )?;
            let view = crate::interpolate::gpu::view(search.color());
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
                Payload {
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
}

impl FrameMethod for Payload {
    fn method(&self) -> Method {
        Method::Payload
    }

    fn reads_flows(&self) -> bool {
        true
    }

    fn reads_later_frame(&self) -> bool {
        true
    }

    /// The first I-frame's payload, into slot 0.
    fn open(
        &mut self,
        frames: &Frames,
        clock: &mut Clock,
        inputs_of: &InputsOf,
    ) -> Result<(), Error> {
        let inputs = frames.interpolated(inputs_of(0)?);
        timed(clock, &mut self.slots[0], &inputs, "payload").map_err(fail)?;
        Ok(())
    }

    /// The closing I-frame's payload, into its slot, timed.
    fn prepare(
        &mut self,
        frames: &Frames,
        clock: &mut Clock,
        at: &IntervalAt,
        _measured: &mut Measured,
    ) -> Result<Option<f64>, Error> {
        let inputs = frames.interpolated((at.inputs_of)(at.end)?);
        let (time, _, _) =
            timed(clock, &mut self.slots[at.slots.1], &inputs, "payload").map_err(fail)?;
        Ok(Some(time))
    }

    /// The two I-frames' payloads interpolated by the search and shaded
    /// at the frame's time, timed together.
    fn draw<'s>(
        &'s mut self,
        frames: &Frames,
        clock: &mut Clock,
        at: &'s IntervalAt,
        k: u32,
        params: &BFrameParams,
    ) -> Result<Drawn<'s>, Error> {
        let inputs = frames.interpolated((at.inputs_of)(at.start + k)?);
        let (earlier, later) = at.slots;
        let (time, _, _) = timed_recording(clock, "bframe", |mut profiler| {
            let payloads = (
                self.iframe(earlier, &at.textures.0),
                self.iframe(later, &at.textures.1),
            );
            self.search.render(
                frames.gpu,
                Method::ImageBased,
                (&payloads.0, &payloads.1),
                params,
                None,
                reborrow(&mut profiler),
            )?;
            self.shade.frame(frames.gpu, &inputs, profiler)
        })
        .map_err(fail)?;
        let color = self
            .shade
            .color()
            .ok_or_else(|| fail("the payload's shade pass draws no colour".into()))?;
        Ok(Drawn {
            time,
            color,
            depth: FrameDepth::Buffer(self.shade.depth()),
            decisions: Some(self.search.decisions()),
        })
    }
}
