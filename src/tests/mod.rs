//! The library's tests that span stages or draw on a GPU: rewrites of the
//! whole corpus and every pipeline they build, the hard cases of each
//! variant, the profiler's and the interpolation's measured runs on
//! lavapipe with small frames. They call the library, its internals
//! included; the command's tests (`crates/shadecache-cli/tests/`) run the
//! binary.
//!
//! They take the features the workspace builds the library with (the
//! command turns on `interpolate`), so `cargo test --workspace` runs them
//! and a build script's `cargo test -p shadecache` does not need a GPU.
//! Without a GPU adapter a test that needs one fails, unless
//! `SHADECACHE_SKIP_GPU_TESTS=1` asks to skip it.

#![allow(clippy::panic, clippy::print_stdout, clippy::print_stderr)]

mod analyze;
mod build_api;
mod composed;
mod corpus;
mod corpus_rewrites;
mod cost;
mod deferred;
mod every_frame;
mod extrapolate;
mod gpu;
mod hard_cases;
mod hard_runs;
mod instanced;
mod interpolate;
mod lowres;
mod merge;
mod partition;
mod payload;
mod previous_members;
mod profile;
mod real_shaders;
mod rewrite;
mod skinned;
mod util;
#[cfg(feature = "wesl")]
mod wesl;
