//! The application's frame as it is, and what a variant cannot do in it.

use std::num::NonZeroU32;

use shadecache_plan::{Plan, TargetKind};

use crate::Error;

/// How the application's original pass draws: what its pipeline was made
/// with. The variant's pipelines are made from it, and it is checked
/// against the plan.
#[derive(Clone, Debug)]
pub struct FrameLayout<'a> {
    /// The vertex buffers of the original pipeline, by slot. The host adds
    /// slots after them for last frame's copies of those the position
    /// reads per instance.
    pub vertex_buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    /// The bind group layouts of the original pipeline, by group: their
    /// entries, as given to `create_bind_group_layout`. Bind groups made
    /// from a layout with the same entries bind to the variant's passes
    /// (wgpu pools equal layouts). The plan's cache group is the host's.
    pub bind_group_layouts: &'a [(u32, &'a [wgpu::BindGroupLayoutEntry])],
    /// The colour targets, by the fragment output's `@location`.
    pub color_targets: &'a [Option<wgpu::ColorTargetState>],
    /// The depth buffer's format. The host renders depth itself, double
    /// buffered (last frame's depth is part of the cache), in this format.
    pub depth_format: wgpu::TextureFormat,
    /// The original pipeline's primitive state (topology, culling, winding).
    pub primitive: wgpu::PrimitiveState,
    /// Samples per pixel; the cache holds one value per pixel: 1 only.
    pub sample_count: u32,
    /// The viewport the original pass draws into.
    pub viewport: Viewport,
    /// Multiview rendering (one draw into several layers).
    pub multiview: Option<NonZeroU32>,
}

impl<'a> FrameLayout<'a> {
    /// A single-sampled frame over the whole target with `depth32float`
    /// depth and wgpu's default primitive state.
    pub fn new(
        vertex_buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
        bind_group_layouts: &'a [(u32, &'a [wgpu::BindGroupLayoutEntry])],
        color_targets: &'a [Option<wgpu::ColorTargetState>],
    ) -> Self {
        FrameLayout {
            vertex_buffers,
            bind_group_layouts,
            color_targets,
            depth_format: wgpu::TextureFormat::Depth32Float,
            primitive: wgpu::PrimitiveState::default(),
            sample_count: 1,
            viewport: Viewport::WholeTarget,
            multiview: None,
        }
    }
}

/// Where the original pass draws in its targets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Viewport {
    /// The whole target.
    WholeTarget,
    /// A rectangle of the target, in pixels: x, y, width, height (split
    /// screen). The passes draw into it and the cache's lookups map last
    /// frame's positions into it (the plan's `viewport_origin`); the
    /// cache's textures stay the target's size. Plans that assume the
    /// whole target (lowres, older plans) are refused. It is the cache's
    /// for its life: make the cache again for another.
    Rect([f32; 4]),
}

/// The frame's colour views, by the fragment output's `@location`, and
/// how the first pass that writes each starts.
#[derive(Clone, Debug)]
pub struct Targets<'a> {
    /// The frame's colour views, by `@location`.
    pub color: &'a [Option<&'a wgpu::TextureView>],
    /// The clear colour of the original pass; `None` keeps what the
    /// targets hold (the original pass loads).
    pub clear: Option<wgpu::Color>,
    /// The application's depth target, for cached draws that share a
    /// frame with the application's other draws: the variant's passes at
    /// full resolution load it (never clear it), test against it with the
    /// plan's comparisons and write into it, so that what the application
    /// drew before hides the cached draws and what it draws after is
    /// hidden by them. What the passes leave in it is copied into the
    /// cache's own depth, which the next frame reprojects against (so a
    /// point that another draw hid last frame misses, as it should). Its
    /// format is the frame's depth format, its size the cache's, and its
    /// texture has `COPY_SRC`; a stencil in it is the deferred variant's,
    /// cleared by its first pass. `None`: the cache's own depth, cleared
    /// each frame, which only the cached draws see.
    pub depth: Option<&'a wgpu::TextureView>,
}

/// Refuses what a cache cannot do correctly, and checks that the frame
/// has a target for every output the plan writes.
pub(crate) fn check(plan: &Plan, frame: &FrameLayout<'_>) -> Result<(), Error> {
    let assumes = &plan.assumes;
    if frame.sample_count != assumes.sample_count {
        return Err(Error::Refused(format!(
            "{} samples per pixel where the plan assumes {}: the cache holds one value and one depth per pixel, and a sample's reprojection would read its pixel's",
            frame.sample_count, assumes.sample_count
        )));
    }
    if let (Viewport::Rect(rect), false) = (frame.viewport, assumes.partial_viewport) {
        return Err(Error::Refused(format!(
            "a viewport of {rect:?}, not the whole target, and the plan assumes the whole target (lowres's samples are a lattice over it; a plan written before viewports has no `viewport_origin`)"
        )));
    }
    if let (Some(views), false) = (frame.multiview, assumes.multiview) {
        return Err(Error::Refused(format!(
            "multiview ({views} views): the plan has one cache, and each view would reproject into the others' values"
        )));
    }
    for pass in &plan.passes {
        for target in &pass.color_targets {
            if target.target != TargetKind::Color {
                continue;
            }
            let location = target.location;
            let Some(Some(state)) = frame.color_targets.get(location as usize) else {
                return Err(Error::Mismatch(format!(
                    "pass `{}` writes the fragment output @location({location}), and the frame has no colour target there",
                    pass.name
                )));
            };
            if state.blend.is_some() && !assumes.blending {
                return Err(Error::Refused(format!(
                    "blending into @location({location}): the cache keeps one surface per pixel, and a blended draw shows several; a cached value would be blended again with stale contents"
                )));
            }
        }
    }
    if !frame.depth_format.has_depth_aspect() {
        return Err(Error::Mismatch(format!(
            "the depth format {:?} has no depth: the cache's depth test needs one",
            frame.depth_format
        )));
    }
    Ok(())
}
