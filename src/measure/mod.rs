//! The measured run: what the profiler and whole-frame reuse share to
//! draw a shader over a scene and measure it against a reference.
//!
//! A measured comparison renders the user's shader as written (the
//! reference) and something built from it — a cache variant, a B-frame
//! method — over the same scene, frame by frame, and compares them. Both
//! stages stand on the same pieces, kept here so that they measure alike:
//!
//! * `setup`: the scene checked against what the shader binds (uniform
//!   and storage buffers, roles, names), the frame counts, instancing;
//! * `inputs`: what every run draws — the textures, the meshes laid
//!   out as the vertex inputs, each frame's buffers — and what was given
//!   a neutral value;
//! * `bench`: runners on one device and scene, the reference among
//!   them;
//! * `clock`: one frame timed (GPU timestamp queries through
//!   wgpu-profiler, from the first pass's start to the last one's end;
//!   wall time where the device has none) and a colour target read back
//!   in linear float;
//! * [`metrics`]: the comparison of a frame with the reference (PSNR,
//!   SSIM, flicker, the share above a threshold) and the cache's decisions.
//!
//! What is drawn in which order (the profiler interleaves every
//! configuration with the reference each frame; whole-frame reuse renders
//! I-frames and builds the frames between) belongs to each stage.

pub(crate) mod bench;
pub(crate) mod clock;
pub(crate) mod inputs;
pub mod metrics;
pub(crate) mod setup;
pub mod watch;

use crate::diagnostic::{Diagnostic, Error};
use crate::runtime::Gpu;

/// A plain error for what a measured run could not do (no position in a
/// file to point at).
pub(crate) fn fail(message: String) -> Error {
    Error::plain(Diagnostic::error(message))
}

/// The device the measured runs draw on, or the error saying how to get
/// one.
pub(crate) fn open_gpu() -> Result<Gpu, Error> {
    Gpu::new().map_err(fail)?.ok_or_else(|| {
        fail("no GPU adapter: install a Vulkan driver (mesa-vulkan-drivers gives lavapipe)".into())
    })
}

/// Progress reports while measuring.
pub trait Progress {
    /// `total` frame renders will be made.
    fn start(&mut self, total: u64);
    /// One more, of `what`.
    fn step(&mut self, what: &str);
    /// A configuration that could not be built, and why.
    fn refused(&mut self, what: &str, reason: &str);
    fn finish(&mut self);
}

/// Progress that says nothing.
#[derive(Debug, Default)]
pub struct Quiet;

impl Progress for Quiet {
    fn start(&mut self, _: u64) {}
    fn step(&mut self, _: &str) {}
    fn refused(&mut self, _: &str, _: &str) {}
    fn finish(&mut self) {}
}

/// The colour target of every measured frame, reference and variants
/// alike: linear float, values above 1 kept.
pub const MEASURED_COLOR_FORMAT: crate::plan::TextureFormat =
    crate::plan::TextureFormat::Rgba16Float;
