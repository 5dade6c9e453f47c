//! The ways of showing the frames between I-frames, one family to a
//! file, each a [`FrameMethod`]:
//!
//! | file | methods | what it draws at a B-frame |
//! |---|---|---|
//! | [`hold_and_blend`] | sample-and-hold, linear blending | the earlier I-frame, or the two cross-faded |
//! | [`image_based`] | image-based | a search along both I-frames' flows (Yang et al. 2011 §5) |
//! | [`half_velocity`] | half-velocity | both I-frames fetched at half the motion (Andreev 2010) |
//! | [`scene_assisted`] | scene-assisted, reverse reprojection | the geometry at the frame's time, shading fetched from the I-frames |
//! | [`morph`] | morph, morph-past, morph-warp | the earlier I-frame extrapolated by a grid morph (Didyk et al. 2010) |
//! | [`payload`] | payload | a cached value interpolated by the search, shaded at the frame's time |
//!
//! [`build`] makes the ones a run asks for; a method the shader or the
//! adapter cannot have is left out with its reason in the report's
//! notes. Adding a method is its file and one arm here.

mod half_velocity;
mod hold_and_blend;
mod image_based;
mod morph;
mod payload;
mod scene_assisted;

pub(super) use hold_and_blend::drawn as bframe_drawn;
pub(super) use morph::passes as morph_passes;

use super::frame_method::{FrameMethod, Setup};
use super::Method;
use crate::diagnostic::Error;

/// The methods of `setup`'s options but the reference (which renders
/// every frame), in their order; what cannot be made is said in
/// `notes`.
pub(super) fn build<'a>(
    setup: &Setup<'a>,
    notes: &mut Vec<String>,
) -> Result<Vec<Box<dyn FrameMethod + 'a>>, Error> {
    let mut methods: Vec<Box<dyn FrameMethod + 'a>> = Vec::new();
    for &method in &setup.options.methods {
        match method {
            Method::Reference => {}
            Method::SampleAndHold | Method::LinearBlend => {
                methods.push(Box::new(hold_and_blend::HoldOrBlend {
                    method,
                    bframes: setup.bframes,
                }));
            }
            Method::ImageBased => {
                methods.push(Box::new(image_based::ImageBased::new(setup, notes)));
            }
            Method::HalfVelocity => {
                methods.push(Box::new(half_velocity::HalfVelocity::new(setup, notes)));
            }
            Method::SceneAssisted
            | Method::SceneAssistedShadeOnMiss
            | Method::ReverseReprojection
            | Method::ReverseReprojectionReshade => {
                let Some(mode) = method.scene_mode() else {
                    continue;
                };
                match scene_assisted::SceneRun::new(setup, method, mode) {
                    Ok(run) => methods.push(Box::new(scene_assisted::SceneAssisted { run })),
                    Err(reason) => notes.push(format!("{} refused: {reason}", method.name())),
                }
            }
            Method::Morph | Method::MorphPast | Method::MorphWarp => {
                let morph = setup.morph.ok_or_else(|| {
                    crate::measure::fail(format!(
                        "internal error: {} has no morph passes",
                        method.name()
                    ))
                })?;
                methods.push(Box::new(morph::Extrapolator { method, morph }));
            }
            Method::Payload => {
                if let Some(payload) = payload::Payload::new(setup, notes)? {
                    methods.push(Box::new(payload));
                }
            }
        }
    }
    Ok(methods)
}
