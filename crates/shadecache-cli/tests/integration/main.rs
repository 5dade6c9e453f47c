//! End-to-end tests: the `shadecache` binary on the corpus and on bad
//! input, plus library-level checks of the cost model. One binary, one
//! module per area (as naga's own tests are laid out).

mod analyze;
mod app;
mod build_api;
mod composed;
mod corpus;
mod corpus_rewrites;
mod cost;
mod default_scene;
mod deferred;
mod drivers;
mod errors;
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
mod report_page;
mod rewrite;
mod skinned;
mod util;
#[cfg(feature = "wesl")]
mod wesl;
