//! The variant's pipelines through Bevy's `PipelineCache`: the host
//! describes each pass's pipeline, Bevy compiles it off the frame (as it
//! compiles its own), and the view's cache is made once all are ready.
//! The variant's pass shaders are Bevy `Shader` assets, added when the
//! app is built.

use std::borrow::Cow;

use bevy::mesh::VertexBufferLayout;
use bevy::prelude::*;
use bevy::render::render_resource::{
    BindGroupLayoutDescriptor, CachedPipelineState, CachedRenderPipelineId, FragmentState,
    PipelineCache, RenderPipelineDescriptor, VertexState,
};
use bevy::shader::Shader;
use shadecache_host::PassPipelineDescriptor;

use crate::CachedVariant;

/// A build's pass shaders as Bevy assets, by the file name its plan uses.
#[derive(Clone, Default)]
pub(crate) struct ShaderHandles(Vec<(String, Handle<Shader>)>);

impl ShaderHandles {
    /// Adds `build`'s pass shaders to `shaders`, as `shadecache/<material>/<build>/<file>`
    /// (the path Bevy's messages name them by).
    pub fn add(
        shaders: &mut Assets<Shader>,
        material: &str,
        index: usize,
        build: &CachedVariant,
    ) -> ShaderHandles {
        ShaderHandles(
            build
                .0
                .shaders
                .iter()
                .map(|(file, source)| {
                    let path = format!("shadecache/{material}/{index}/{file}");
                    (
                        file.clone(),
                        shaders.add(Shader::from_wgsl(source.clone(), path)),
                    )
                })
                .collect(),
        )
    }

    fn get(&self, file: &str) -> Option<&Handle<Shader>> {
        self.0.iter().find(|(f, _)| f == file).map(|(_, h)| h)
    }
}

/// The variant pipelines queued in Bevy's pipeline cache, by their
/// descriptor: a cache made again for what it was made for before (a view
/// switched off and on, a refresh period set back) takes the pipelines
/// queued then, as Bevy's specialised pipelines do, rather than adding
/// more to Bevy's cache (which keeps every pipeline queued in it).
#[derive(Resource, Default)]
pub(crate) struct QueuedPipelines(Vec<(RenderPipelineDescriptor, CachedRenderPipelineId)>);

/// A view's pipelines, queued in Bevy's pipeline cache.
pub(crate) struct Compiling(Vec<CachedRenderPipelineId>);

/// Where a view's pipelines are.
pub(crate) enum Compiled {
    /// All made, in the order they were described.
    Ready(Vec<wgpu::RenderPipeline>),
    /// Some still compiling (or waiting for their shader to load).
    Waiting,
    /// Bevy could not make one: its error.
    Failed(String),
}

impl Compiling {
    /// Queues the described pipelines, with the build's shaders (those
    /// queued before are not queued again).
    pub fn queue<'d>(
        (cache, queued): (&PipelineCache, &mut QueuedPipelines),
        described: impl ExactSizeIterator<Item = &'d PassPipelineDescriptor>,
        shaders: &ShaderHandles,
    ) -> Result<Compiling, String> {
        let mut ids = Vec::with_capacity(described.len());
        for pass in described {
            let descriptor = bevy_descriptor(pass, shaders)?;
            let before = queued.0.iter().find(|(d, _)| *d == descriptor);
            let id = match before {
                Some(&(_, id)) => id,
                None => {
                    let id = cache.queue_render_pipeline(descriptor.clone());
                    queued.0.push((descriptor, id));
                    id
                }
            };
            ids.push(id);
        }
        Ok(Compiling(ids))
    }

    /// The pipelines, once all are made. With `block`, waits for those
    /// being compiled (as Bevy's `synchronous_pipeline_compilation`
    /// does); one whose shader has not reached the cache yet still waits.
    pub fn poll(&self, cache: &mut PipelineCache, block: bool) -> Compiled {
        let mut pipelines = Vec::with_capacity(self.0.len());
        for &id in &self.0 {
            if block {
                cache.block_on_render_pipeline(id);
            }
            if let CachedPipelineState::Err(err) = cache.get_render_pipeline_state(id) {
                return Compiled::Failed(err.to_string());
            }
            match cache.get_render_pipeline(id) {
                Some(pipeline) => pipelines.push((**pipeline).clone()),
                None => return Compiled::Waiting,
            }
        }
        Compiled::Ready(pipelines)
    }
}

/// The host's description of a pass's pipeline in Bevy's terms.
fn bevy_descriptor(
    pass: &PassPipelineDescriptor,
    shaders: &ShaderHandles,
) -> Result<RenderPipelineDescriptor, String> {
    let shader = shaders
        .get(&pass.shader)
        .ok_or_else(|| {
            format!(
                "{}: the variant has no shader `{}`",
                pass.label, pass.shader
            )
        })?
        .clone();
    let buffers = pass
        .vertex_buffers
        .iter()
        .enumerate()
        .map(|(slot, buffer)| {
            buffer
                .as_ref()
                .map(|b| VertexBufferLayout {
                    array_stride: b.array_stride,
                    step_mode: b.step_mode,
                    attributes: b.attributes.clone(),
                })
                .ok_or_else(|| {
                    format!(
                        "{}: vertex buffer slot {slot} holds nothing, which Bevy's pipeline descriptors cannot say",
                        pass.label
                    )
                })
        })
        .collect::<Result<Vec<_>, String>>()?;
    let label: Cow<'static, str> = format!("shadecache {}", pass.label).into();
    Ok(RenderPipelineDescriptor {
        label: Some(label.clone()),
        layout: pass
            .bind_group_layouts
            .iter()
            .map(|entries| BindGroupLayoutDescriptor::new(label.clone(), entries))
            .collect(),
        immediate_size: 0,
        vertex: VertexState {
            shader: shader.clone(),
            shader_defs: Vec::new(),
            entry_point: Some(pass.vertex_entry.clone().into()),
            buffers,
            constants: Vec::new(),
        },
        primitive: pass.primitive,
        depth_stencil: Some(pass.depth_stencil.clone()),
        multisample: pass.multisample,
        fragment: Some(FragmentState {
            shader,
            shader_defs: Vec::new(),
            entry_point: Some(pass.fragment_entry.clone().into()),
            targets: pass.targets.clone(),
            constants: Vec::new(),
        }),
        zero_initialize_workgroup_memory: false,
    })
}
