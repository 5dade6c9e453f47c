//! plans → runs: executing a variant's plan with wgpu, headless, on any
//! backend (Mesa's lavapipe in CI), through the host crate
//! (`shadecache-host`) that applications run variants with: what the
//! profiler measures is what an application runs.
//!
//! `frame` describes the frame the profiler draws as an application
//! describes its own: the plan's vertex inputs packed per step, the bind
//! group layouts the plan implies, its colour outputs. [`Runner`] is the
//! application: it owns the scene's meshes, per-object buffers and
//! textures, writes each frame's contents, and draws every object in each
//! pass the host records; the host keeps the cache, the twins and the
//! refresh uniform. `textures` uploads the scene's textures and reads
//! targets back.

mod frame;
mod gpu;
mod runner;
mod textures;

#[cfg(all(test, feature = "interpolate"))]
pub use frame::build_passes;
pub use frame::{PipelineOptions, RunOptions};
#[cfg(feature = "interpolate")]
pub use gpu::validated;
pub use gpu::{describe_adapter, driver_line, Gpu};
#[cfg(feature = "interpolate")]
pub use runner::{DrawShare, FramePart};
pub use runner::{FrameInputs, Mesh, ObjectInputs, Runner};
pub use textures::{read_depth, read_texture, DepthTexels, Texels, DEPTH_MAP_SIZE};
