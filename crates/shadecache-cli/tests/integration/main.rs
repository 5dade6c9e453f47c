//! End-to-end tests: the `shadecache` binary as a user runs it, on the
//! corpus and on bad input, and the examples built as their users build
//! them. One binary, one module per area (as naga's own tests are laid
//! out). The library's own tests, which call it rather than run the
//! binary, are in `src/tests/`.

mod analyze;
mod app;
mod build_api;
mod composed;
mod corpus;
mod default_scene;
mod drivers;
mod errors;
mod interpolate_command;
mod lowres;
mod merge;
mod out_folders;
mod play_command;
mod profile_command;
mod real_shaders;
mod report_page;
mod rewrite;
mod util;
#[cfg(feature = "wesl")]
mod wesl;
