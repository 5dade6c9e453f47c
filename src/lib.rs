//! shadecache makes real-time shaders cheaper by reusing work across frames.
//!
//! It reads a WGSL shader, finds the intermediate values of its fragment
//! entry point that are worth keeping from one frame to the next (the
//! *payload* of a reverse-reprojection cache, after Sitthi-amorn et al.,
//! "An Improved Shading Cache for Modern GPUs", 2008), and estimates what
//! each would save.
//!
//! The modules follow the pipeline, WGSL → IR → candidates → variants →
//! plans → runs → reports:
//!
//! * [`front`]: read, parse and validate a shader (naga's WGSL front end),
//!   compose it from naga_oil modules, give a fragment-only module its
//!   vertex stage;
//! * `proc`: facts about the IR that several stages share (operands,
//!   placement, reaching definitions), and copying IR between modules
//!   (internal);
//! * [`cost`]: the static cost model;
//! * [`analysis`]: the expression graph, the candidates and why the others
//!   are rejected;
//! * [`rewrite`]: one candidate and one variant into cache passes, on IR,
//!   and the plan that says how to run them; `rewrite::reprojection` is the
//!   cache shader's reprojection arithmetic on the CPU, for tests and
//!   reasoning (kept in step with `shaders/cache.wgsl`);
//! * [`plan`]: `plan.json`, how a host runs a variant's passes: the
//!   `shadecache-plan` crate's definition (serde only), re-exported;
//! * [`back`]: writing the passes with naga's back ends;
//! * [`build`]: the same from a build script;
//! * [`diagnostic`]: the error type and its codespan rendering.
//!
//! Those are the default features, all a build script needs: naga and
//! naga_oil, nothing that runs a GPU. The feature `profile` adds the
//! stages that measure on a GPU through wgpu:
//!
//! * `scene`: what a profile renders, the default scene, roles;
//! * `runtime` (internal): the scene drawn through the host crate
//!   (`shadecache-host`), which runs a plan as applications do;
//! * `measure` (internal): the measured run both GPU stages stand on: the
//!   scene's inputs, runners on one device, the clock, the read-back and
//!   the comparison with the reference; its [`watch`] is public, for a
//!   supervisor that reports what the GPU was doing when a driver fails;
//! * `profile`: measuring variants against the unmodified shader;
//! * `report`: the report's JSON, HTML and pictures;
//!
//! and the feature `interpolate` whole-frame reuse:
//!
//! * `interpolate`: I-frames rendered with their flows and the frames
//!   between them built from them (bidirectional reprojection,
//!   half-velocity up-conversion, morph-and-blur extrapolation, payload
//!   interpolation), measured against rendering every frame.
//!
//! The `shadecache` command (the `shadecache-cli` crate) turns both on.

#![forbid(unsafe_code)]
#![warn(
    clippy::print_stdout,
    clippy::print_stderr,
    clippy::todo,
    clippy::unimplemented,
    clippy::panic,
    missing_debug_implementations
)]

pub mod analysis;
pub mod back;
pub mod build;
pub mod cost;
pub mod diagnostic;
pub mod front;
#[cfg(feature = "interpolate")]
pub mod interpolate;
#[cfg(feature = "profile")]
pub(crate) mod measure;
pub mod plan;
pub(crate) mod proc;
#[cfg(feature = "profile")]
pub mod profile;
#[cfg(feature = "profile")]
pub mod report;
pub mod rewrite;
#[cfg(feature = "profile")]
pub(crate) mod runtime;
#[cfg(feature = "profile")]
pub mod scene;
#[cfg(all(test, feature = "interpolate"))]
mod tests;
#[cfg(feature = "profile")]
pub use measure::watch;
