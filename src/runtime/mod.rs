//! plans → runs: executing a variant's plan with wgpu, headless, on any
//! backend (Mesa's lavapipe in CI).
//!
//! [`pipelines`] turns a plan and its pass shaders into wgpu render
//! pipelines exactly as the plan describes them (vertex layout, colour
//! targets and formats, depth compare and write). [`Runner`] executes the
//! plan frame after frame: it fills the shader's buffers and their
//! previous-frame twins, the `CacheParams` uniform (refresh phase kept as
//! c mod Δn), binds the double-buffered payload textures and depth buffers
//! as the plan's bindings say, runs the passes in order with the plan's
//! load operations, and swaps the cache. Scenes, timing and error
//! measurement build on it.

mod pipelines;
mod runner;

pub use pipelines::{pipelines, Gpu, PipelineOptions};
pub use runner::{read_texture, FrameInputs, Mesh, ObjectInputs, RunOptions, Runner};
