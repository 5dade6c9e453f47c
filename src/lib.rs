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
//! * [`proc`]: facts about the IR that several stages share (operands,
//!   placement, reaching definitions), and copying IR between modules;
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
//! * `runtime`: the scene drawn through the host crate
//!   (`shadecache-host`), which runs a plan as applications do;
//! * `measure`: the measured run both GPU stages stand on: the scene's
//!   inputs, runners on one device, the clock, the read-back and the
//!   comparison with the reference;
//! * `profile`: measuring variants against the unmodified shader;
//! * `report`: the report's JSON, HTML and pictures;
//!
//! and the feature `interpolate` whole-frame reuse:
//!
//! * `interpolate`: I-frames rendered with their flows and the B-frames
//!   between them built by bidirectional reprojection (seeds 000 and 003),
//!   measured against rendering every frame.
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
// The toolchain's own internals, public for its end-to-end tests (in
// the command's crate) and hidden from the documentation: no stability
// promise.
#[cfg(feature = "profile")]
#[doc(hidden)]
pub mod measure;
pub mod plan;
#[doc(hidden)]
pub mod proc;
#[cfg(feature = "profile")]
pub mod profile;
#[cfg(feature = "profile")]
pub mod report;
pub mod rewrite;
#[cfg(feature = "profile")]
#[doc(hidden)]
pub mod runtime;
#[cfg(feature = "profile")]
pub mod scene;
