//! plans → runs: executing a variant's plan with wgpu, headless, on any
//! backend (Mesa's lavapipe in CI).
//!
//! So far this stage turns a plan and its pass shaders into wgpu render
//! pipelines, exactly as the plan describes them (vertex layout, colour
//! targets and formats, depth compare and write). The test suite builds a
//! pipeline for every pass of every variant of the corpus with it.

mod pipelines;

pub use pipelines::{pipelines, Gpu};
