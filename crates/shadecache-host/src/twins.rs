//! Last frame's copies of an application's buffers, one set per draw.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// The application's buffers whose last-frame contents the variant reads:
/// the uniform and storage buffers by the `[group, binding]` they are
/// bound at, and the vertex buffers by slot. Give every buffer of one draw
/// (those the plan has no twin for are ignored); each needs
/// `BufferUsages::COPY_SRC`.
#[derive(Clone, Debug, Default)]
pub struct TwinSources<'a> {
    /// The uniform and storage buffers, by `[group, binding]`.
    pub buffers: &'a [([u32; 2], &'a wgpu::Buffer)],
    /// The vertex buffers, by slot.
    pub vertex_buffers: &'a [(u32, &'a wgpu::Buffer)],
    /// Only for a shader that uses all four bind groups, whose last the
    /// cache shares: that group's textures and samplers (its buffers are
    /// in `buffers`), which the host binds with the cache's.
    pub textures: &'a [([u32; 2], &'a wgpu::TextureView)],
    /// That group's samplers, by `[group, binding]`.
    pub samplers: &'a [([u32; 2], &'a wgpu::Sampler)],
}

/// The twins of one draw's buffers: buffers the host fills with last
/// frame's contents of the application's. Every draw takes them
/// ([`crate::Draw::draw`], [`crate::Draw::draw_indexed`]), so a draw cannot
/// be recorded without them.
///
/// When they are first used, in a frame, they are filled with that frame's
/// contents (there is no last frame): before its passes. After each frame's
/// passes, in the same encoder, the host copies the application's buffers
/// into them: the frame's contents, which are last frame's for the next one
/// whatever the application writes after the submission.
#[derive(Clone, Debug)]
pub struct Twins {
    pub(crate) inner: Arc<TwinsInner>,
}

#[derive(Debug)]
pub(crate) struct TwinsInner {
    pub id: u64,
    /// The id of the shader that made them.
    pub owner: u64,
    /// (the application's buffer, its twin) pairs, copied each frame.
    pub copies: Vec<(wgpu::Buffer, wgpu::Buffer)>,
    /// The cache group's twin entries: binding and buffer.
    pub bound: Vec<(u32, wgpu::Buffer)>,
    /// The application's resources in the cache's group, by binding.
    pub shared: Vec<(u32, Shared)>,
    /// The vertex twins: host slot and buffer.
    pub vertex: Vec<(u32, wgpu::Buffer)>,
    /// The cache group's bind groups by pass, for each cache slot, made
    /// for a generation of the cache's textures (resizes make new ones).
    pub bind_groups: Mutex<HashMap<usize, (u64, [wgpu::BindGroup; 2])>>,
}

impl TwinsInner {
    pub fn copy(&self, encoder: &mut wgpu::CommandEncoder) {
        for (source, twin) in &self.copies {
            // Copies move whole words.
            let size = source.size().min(twin.size()) & !(wgpu::COPY_BUFFER_ALIGNMENT - 1);
            encoder.copy_buffer_to_buffer(source, 0, twin, 0, size);
        }
    }
}

/// One of the application's resources bound in the cache's group.
#[derive(Clone, Debug)]
pub(crate) enum Shared {
    Buffer(wgpu::Buffer),
    Texture(wgpu::TextureView),
    Sampler(wgpu::Sampler),
}

impl Shared {
    pub fn resource(&self) -> wgpu::BindingResource<'_> {
        match self {
            Shared::Buffer(buffer) => buffer.as_entire_binding(),
            Shared::Texture(view) => wgpu::BindingResource::TextureView(view),
            Shared::Sampler(sampler) => wgpu::BindingResource::Sampler(sampler),
        }
    }
}
