//! Runs a shadecache variant inside an application's own wgpu render loop.
//!
//! shadecache rewrites a shader into reprojection-cache variants (seed
//! 002's one-, two- and three-pass) and writes, next to each variant's
//! pass shaders, a [`Plan`]: the passes in order, their targets and depth
//! state, the vertex inputs, and every binding the host supplies. Running
//! a plan by hand means double-buffered cache textures, last frame's copies
//! of the buffers the position reads, the refresh uniform, one pipeline per
//! pass with the right clears and depth state, the first frame and
//! resizes. This crate does that, on the application's device and in the
//! application's encoder; shadecache's profiler measures variants through
//! it, so what an application runs is what was measured.
//!
//! An application describes its original pass once, as a [`FrameLayout`]
//! (its vertex buffer layouts, bind group layout entries, colour target
//! states, depth format), and makes a [`CachedShader`] from the plan and
//! the pass shaders. What a cache cannot do correctly — blending into a
//! cached output, multisampling, a viewport smaller than the target,
//! multiview — is refused there, with the reason, as is a frame that does
//! not match what the shaders read ([`Error`]). Per draw it makes
//! [`Twins`] from the draw's buffers. Per frame it writes its buffers as
//! before and calls [`CachedShader::record`], which records every pass and
//! calls back once per pass for the draws: the same draws as the original
//! pass, their bind groups and buffers set on the [`Draw`] and each drawn
//! with its twins through [`Draw::draw_indexed`] or [`Draw::draw`] (the
//! deferred variant's screen-space passes turn each into one triangle over
//! the screen). There is no raw render pass and no draw without twins, so
//! a draw the variant needs cannot be skipped; the host copies the frame's
//! buffers into their twins after the passes, so they hold last frame's
//! contents whatever the application writes next. The first frame, a
//! [`CachedShader::resize`] and a [`CachedShader::reset`] (a camera cut)
//! miss everywhere. A lowres plan whose σz is a share of the depth range
//! needs the camera's planes ([`CachedShader::set_depth_range`]).
//! [`Timestamps`] times each pass with plain timestamp
//! queries; [`PassTimer`] lets another timer do it.
//!
//! Whether the cache pays is the player's GPU's to say: a [`Governor`]
//! decides per frame whether to draw the original or the cached frame
//! from the frames' GPU times, which [`FrameTimer`] reads when they are
//! ready; an [`ErrorWatch`] compares a cached frame with the original on
//! the GPU once in a while, so the governor keeps the cache within an
//! error budget by its refresh period; [`CacheMode`] gives one render loop
//! for caching always, never, or as the governor says.
//!
//! Every misuse is an [`Error`], never a panic in the application: a size
//! the device cannot hold (in `new` and `resize`), a draw with another
//! shader's twins, the cache's bind group set by the application; what
//! wgpu could reject (pipelines, bind groups) is made in error scopes.
//!
//! The API is async at its core ([`CachedShader::new_async`],
//! [`CachedShader::twins_async`]: wgpu's error scopes resolve as futures),
//! and the default feature `blocking` adds [`CachedShader::new`] and
//! [`CachedShader::twins`], which wait on them with pollster. Without it
//! the crate has no blocking dependency, as the web needs. What was
//! checked: the crate builds without default features, and the tests run
//! natively (Vulkan); the `wasm32-unknown-unknown` target itself was not
//! built.
//!
//! An engine that compiles its pipelines itself (off the frame, in its
//! own pipeline cache) makes them from
//! [`CachedShader::describe_pipelines`] and gives them to
//! [`CachedShader::from_pipelines_async`]: each pass's pipeline
//! described, its layout as each bind group's entries.
//!
//! The crate depends on wgpu, serde and the plan schema only: an
//! application links neither naga's front ends nor the toolchain.
//!
//! ```no_run
//! use shadecache_host::{CachedShader, FrameLayout, Options, Plan, Targets, TwinSources};
//!
//! # fn run(
//! #     device: &wgpu::Device,
//! #     queue: &wgpu::Queue,
//! #     plan_json: &str,
//! #     pass_source: impl Fn(&str) -> Option<&'static str>,
//! #     vertex_layout: wgpu::VertexBufferLayout<'_>,
//! #     uniform_entries: &[wgpu::BindGroupLayoutEntry],
//! #     globals: &wgpu::Buffer,
//! #     globals_group: &wgpu::BindGroup,
//! #     vertices: &wgpu::Buffer,
//! #     view: &wgpu::TextureView,
//! # ) -> Result<(), Box<dyn std::error::Error>> {
//! let plan: Plan = serde_json::from_str(plan_json)?;
//! let colors = [Some(wgpu::ColorTargetState::from(wgpu::TextureFormat::Rgba8Unorm))];
//! let buffers = [Some(vertex_layout)];
//! let groups = [(0, uniform_entries)];
//! let frame = FrameLayout::new(&buffers, &groups, &colors);
//! let mut cached = CachedShader::new(device, &plan, pass_source, &frame, (1280, 720), Options::default())?;
//! // The draw's buffers (made with COPY_SRC): the host keeps last frame's copies.
//! let twins = cached.twins(&TwinSources { buffers: &[([0, 0], globals)], ..Default::default() })?;
//!
//! // Each frame: write `globals` as before, then
//! let mut encoder = device.create_command_encoder(&Default::default());
//! // `depth: Some(&depth_view)` shares the application's depth with the
//! // cached draws, when the frame has other draws (see `Targets::depth`).
//! let targets = Targets { color: &[Some(view)], clear: Some(wgpu::Color::BLACK), depth: None };
//! cached.record(queue, &mut encoder, &targets, |draw| {
//!     draw.set_bind_group(0, globals_group, &[]);
//!     draw.set_vertex_buffer(0, vertices.slice(..));
//!     draw.draw(&twins, 0..3, 0..1);
//! })?;
//! queue.submit([encoder.finish()]);
//! # Ok(())
//! # }
//! ```

#![warn(missing_docs)]

mod cached;
mod error;
mod formats;
mod frame;
mod governor;
mod layouts;
mod params;
mod pipelines;
mod readback;
mod timing;
mod twins;
mod vertex;
mod watch;

pub use cached::{texture_bytes, CachedShader, DescribedPipelines, Draw, Options};
pub use error::Error;
pub use frame::{FrameLayout, Targets, Viewport};
pub use governor::{
    CacheMode, Cause, Choice, Decision, GovernedFrame, Governor, GovernorSettings, SpeedEstimate,
    TrialTurn,
};
pub use pipelines::PassPipelineDescriptor;
pub use vertex::VertexBufferDescriptor;

/// Brings in the Rust module a build script's `shadecache::build::Build`
/// writes (`$OUT_DIR/shadecache/variants.rs`), naming every variant it
/// wrote: after `include_variants!();` in a module, the one-pass variant
/// of `lava.wesl` is `lava::one_pass::PLAN` (its `plan.json`) and
/// `lava::one_pass::SHADERS` (its pass shaders by file name), of the node
/// the build chose, with no node id or path typed; `lava::NODE` names the
/// node, and every node's variants are under `lava::<node id>::`.
#[macro_export]
macro_rules! include_variants {
    () => {
        include!(concat!(env!("OUT_DIR"), "/shadecache/variants.rs"));
    };
}
pub use shadecache_plan as plan;
pub use shadecache_plan::Plan;
pub use timing::{FrameTimer, NoTimer, PassTime, PassTimer, Timestamps};
pub use twins::{TwinSources, Twins};
pub use watch::{Coverage, ErrorWatch, WatchedError};

/// What the shadecache toolchain shares with the host to draw its scenes
/// (feature `toolchain`, which the toolchain turns on): the plan's formats
/// and layouts in wgpu's terms, the host's render targets. An application
/// has its own and does not need it.
#[cfg(feature = "toolchain")]
pub mod toolchain {
    pub use crate::cached::{clear_depth, render_target};
    pub use crate::formats::{cache_format, texture_format, vertex_format};
    pub use crate::layouts::{entry_for, plan_groups, plan_layout_entries};
}
