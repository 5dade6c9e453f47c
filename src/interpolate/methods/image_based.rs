//! Image-based B-frames (Yang et al. 2011 §5): each pixel's point in the
//! two I-frames found by a fixed-point search along their flows, and the
//! two looked up and blended; one fullscreen pass
//! ([`crate::interpolate::bframe`]).
//!
//! Where the scene can draw the geometry at B-frame times, its search is
//! also measured against the exact correspondences (the paper's Fig. 11,
//! drawn untimed): [`Correspondence`].

use crate::diagnostic::Error;
use crate::interpolate::bframe::{BFrameParams, BFrames, IFrameTextures};
use crate::interpolate::correspondence::FrameErrors;
use crate::interpolate::frame_method::{FrameMethod, Setup};
use crate::interpolate::frames::{Drawn, Frames, IntervalAt};
use crate::interpolate::iframe::SceneMode;
use crate::interpolate::measured::Measured;
use crate::interpolate::thin::FrameDepth;
use crate::interpolate::Method;
use crate::measure::clock::{read_linear, Clock};
use crate::measure::fail;
use crate::measure::metrics::LinearFrame;
use crate::runtime::FrameInputs;

use super::hold_and_blend::render_timed;
use super::scene_assisted::SceneRun;

/// [`Method::ImageBased`].
pub(super) struct ImageBased<'a> {
    pub bframes: &'a BFrames,
    /// Its search against the exact correspondences, when they can be
    /// drawn.
    pub correspondence: Option<Correspondence>,
}

impl<'a> ImageBased<'a> {
    /// The method, drawn with `setup`'s B-frame passes; what keeps its
    /// correspondences from being measured is said in `notes`.
    pub fn new(setup: &Setup<'a>, notes: &mut Vec<String>) -> ImageBased<'a> {
        let made =
            SceneRun::new(setup, Method::ImageBased, SceneMode::Correspondence).and_then(|exact| {
                // The method's own search, writing what it found and the
                // direction it took.
                let search = BFrames::writing_depth(
                    setup.bench.gpu,
                    (setup.bench.size[0], setup.bench.size[1]),
                    &[Method::ImageBased],
                    setup.search(),
                    true,
                )?;
                Ok(Correspondence { exact, search })
            });
        let correspondence = match made {
            Ok(made) => Some(made),
            Err(reason) => {
                notes.push(format!(
                    "image-based's correspondence error is not measured: {reason}"
                ));
                None
            }
        };
        ImageBased {
            bframes: setup.bframes,
            correspondence,
        }
    }
}

impl FrameMethod for ImageBased<'_> {
    fn method(&self) -> Method {
        Method::ImageBased
    }

    fn reads_flows(&self) -> bool {
        true
    }

    fn reads_later_frame(&self) -> bool {
        true
    }

    fn draw<'s>(
        &'s mut self,
        frames: &Frames,
        clock: &mut Clock,
        at: &'s IntervalAt,
        _k: u32,
        params: &BFrameParams,
    ) -> Result<Drawn<'s>, Error> {
        let method = Method::ImageBased;
        let time = render_timed(self.bframes, method, frames, clock, at, params)?;
        Ok(Drawn {
            time,
            color: self.bframes.color(),
            depth: FrameDepth::Chosen(self.bframes.chosen_depth()),
            decisions: Some(self.bframes.decisions()),
        })
    }

    /// Its correspondence errors at the interval's interior frames.
    fn measure(
        &mut self,
        frames: &Frames,
        at: &IntervalAt,
        k: u32,
        params: &BFrameParams,
        measured: &mut Measured,
    ) -> Result<(), Error> {
        let n = frames.options.frames_per_interval;
        let Some(correspondence) = self.correspondence.as_mut().filter(|_| k >= 1 && k < n) else {
            return Ok(());
        };
        let (start, end) = (at.start, at.end);
        let inputs = frames.twinned_inputs(at.inputs_of, [start + k, start, end])?;
        let swapped = frames.twinned_inputs(at.inputs_of, [start + k, end, start])?;
        let errors = correspondence.measure(frames, at, params, (&inputs, &swapped))?;
        let ours = &mut measured.correspondence;
        ours.means
            .push((errors.total.mean(), errors.total_hit.mean()));
        ours.total.extend(errors.total);
        ours.used.extend(errors.used);
        ours.linear.extend(errors.linear);
        Ok(())
    }
}

/// Image-based's correspondences against the exact ones: the
/// scene-assisted pass in [`SceneMode::Correspondence`] and a second
/// image-based pass that writes what its search found.
pub(super) struct Correspondence {
    exact: SceneRun,
    search: BFrames,
}

impl Correspondence {
    /// Fig. 11's errors of one B-frame ([`crate::interpolate::correspondence`]): where
    /// image-based's forward search found each covered pixel's point in
    /// I-frame 0 against where it is (E_total), and where linear motion
    /// along I-frame 0's exact flow puts it (E_lin).
    fn measure(
        &mut self,
        frames: &Frames,
        at: &IntervalAt,
        params: &BFrameParams,
        (inputs, swapped): (&FrameInputs, &FrameInputs),
    ) -> Result<FrameErrors, Error> {
        let textures = at.textures;
        let gpu = frames.gpu;
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
                .color_at(frames.instrumented.scene_locations[0])
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
        Ok(crate::interpolate::correspondence::frame_errors(
            &exact,
            &found,
            at.flow_next_0(gpu)?,
            (&exact_later, &directions),
            frames.size,
            params.alpha,
        ))
    }
}
