//! One render pipeline per pass, from the plan and the application's frame.

use std::borrow::Cow;
use std::collections::BTreeMap;

use shadecache_plan::{DrawKind, Pass, TargetKind};

use crate::formats::{compare_function, stencil_state};
use crate::{Error, FrameLayout, Options, VertexBufferDescriptor};

/// The formats of the targets the host owns.
#[derive(Clone, Copy, Debug)]
pub(crate) struct HostFormats {
    pub cache: wgpu::TextureFormat,
    pub age: wgpu::TextureFormat,
    pub classes: wgpu::TextureFormat,
    /// Lowres's history and its samples' geometry.
    pub history: wgpu::TextureFormat,
}

/// The pipeline layout of every pass: the application's groups, the
/// cache's group, and empty groups between them.
pub(crate) fn pipeline_layout(
    device: &wgpu::Device,
    user: &BTreeMap<u32, wgpu::BindGroupLayout>,
    cache: Option<(u32, &wgpu::BindGroupLayout)>,
) -> wgpu::PipelineLayout {
    let empty = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadecache empty group"),
        entries: &[],
    });
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> =
        by_group(user.iter().map(|(g, l)| (*g, l)), cache, &empty)
            .into_iter()
            .map(Some)
            .collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadecache pass layout"),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    })
}

/// The groups of a pass's pipeline layout, in order: the application's
/// (`user`), the cache's, and `empty` between them, up to the last.
pub(crate) fn by_group<T: Clone>(
    user: impl IntoIterator<Item = (u32, T)>,
    cache: Option<(u32, T)>,
    empty: T,
) -> Vec<T> {
    let groups: BTreeMap<u32, T> = user.into_iter().chain(cache).collect();
    let Some(&last) = groups.keys().next_back() else {
        return Vec::new();
    };
    (0..=last)
        .map(|group| groups.get(&group).cloned().unwrap_or_else(|| empty.clone()))
        .collect()
}

/// What every pass's pipeline is made with.
pub(crate) struct PipelineInputs<'a> {
    pub buffers: &'a [Option<VertexBufferDescriptor>],
    pub frame: &'a FrameLayout<'a>,
    pub formats: HostFormats,
    /// The format of the host's depth buffers: the frame's, or one with a
    /// stencil aspect when the plan's passes test the stencil.
    pub depth_format: wgpu::TextureFormat,
    /// The G-buffer textures' formats, by index.
    pub gbuffer: &'a [wgpu::TextureFormat],
    pub options: Options,
}

/// One pass's render pipeline, described for an application that makes
/// its pipelines itself (an engine's pipeline cache, which compiles them
/// off the frame): everything `wgpu::RenderPipelineDescriptor` takes,
/// owned, with the shader by the plan's file name and the pipeline layout
/// as each group's entries. [`CachedShader::describe_pipelines`] gives
/// them, [`CachedShader::from_pipelines_async`] takes the pipelines made
/// from them.
///
/// [`CachedShader::describe_pipelines`]: crate::CachedShader::describe_pipelines
/// [`CachedShader::from_pipelines_async`]: crate::CachedShader::from_pipelines_async
#[derive(Clone, Debug)]
pub struct PassPipelineDescriptor {
    /// The pass's name, the pipeline's label.
    pub label: String,
    /// The file the pass is drawn with, as the plan names it.
    pub shader: String,
    /// The vertex stage's entry point.
    pub vertex_entry: String,
    /// The fragment stage's entry point.
    pub fragment_entry: String,
    /// The vertex buffers by slot: the application's, then the host's
    /// copies of last frame's; `None` where a slot holds nothing.
    pub vertex_buffers: Vec<Option<VertexBufferDescriptor>>,
    /// The frame's primitive state for a pass over the application's
    /// geometry; the default for a screen-space pass.
    pub primitive: wgpu::PrimitiveState,
    /// The depth and stencil state, in the host's depth format.
    pub depth_stencil: wgpu::DepthStencilState,
    /// One sample: the variants refuse multisampled frames.
    pub multisample: wgpu::MultisampleState,
    /// The colour targets by location.
    pub targets: Vec<Option<wgpu::ColorTargetState>>,
    /// The pipeline layout: each bind group's entries, by group (empty
    /// where the pass binds nothing). A bind group made with a layout of
    /// equal entries binds (wgpu pools equal layouts), so the host's own
    /// bind groups bind to pipelines made with layouts of these.
    pub bind_group_layouts: Vec<Vec<wgpu::BindGroupLayoutEntry>>,
}

/// The pass's pipeline, described: see [`PassPipelineDescriptor`].
/// `bind_group_layouts` are the entries of the layout [`pipeline_layout`]
/// makes.
pub(crate) fn describe(
    pass: &Pass,
    inputs: &PipelineInputs<'_>,
    bind_group_layouts: Vec<Vec<wgpu::BindGroupLayoutEntry>>,
) -> Result<PassPipelineDescriptor, Error> {
    let targets = color_targets(pass, inputs)?;
    // A screen-space pass draws one triangle over the screen, from the
    // vertex index alone, whatever the application's geometry.
    let (buffers, primitive) = match pass.draw {
        DrawKind::Geometry => (inputs.buffers, inputs.frame.primitive),
        DrawKind::Fullscreen => (&[][..], wgpu::PrimitiveState::default()),
    };
    let depth_compare = {
        let compare = compare_function(pass.depth.compare);
        match (inputs.options.depth_test_or_equal, compare) {
            (true, wgpu::CompareFunction::Less) => wgpu::CompareFunction::LessEqual,
            (true, wgpu::CompareFunction::Greater) => wgpu::CompareFunction::GreaterEqual,
            _ => compare,
        }
    };
    Ok(PassPipelineDescriptor {
        label: pass.name.clone(),
        shader: pass.shader.clone(),
        vertex_entry: pass.vertex_entry.clone(),
        fragment_entry: pass.fragment_entry.clone(),
        vertex_buffers: buffers.to_vec(),
        primitive,
        depth_stencil: wgpu::DepthStencilState {
            format: inputs.depth_format,
            depth_write_enabled: Some(pass.depth.write),
            depth_compare: Some(depth_compare),
            stencil: pass.stencil.map(stencil_state).unwrap_or_default(),
            bias: wgpu::DepthBiasState::default(),
        },
        multisample: wgpu::MultisampleState::default(),
        targets,
        bind_group_layouts,
    })
}

/// The described pipeline, made on `device` with `layout` from the pass's
/// WGSL; wgpu's validation errors name the pass.
pub(crate) async fn pipeline(
    device: &wgpu::Device,
    described: &PassPipelineDescriptor,
    source: &str,
    layout: &wgpu::PipelineLayout,
) -> Result<wgpu::RenderPipeline, Error> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(&described.shader),
        source: wgpu::ShaderSource::Wgsl(Cow::Borrowed(source)),
    });
    let buffers: Vec<Option<wgpu::VertexBufferLayout<'_>>> = described
        .vertex_buffers
        .iter()
        .map(|buffer| buffer.as_ref().map(VertexBufferDescriptor::borrowed))
        .collect();
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(&described.label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(&described.vertex_entry),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            buffers: &buffers,
        },
        primitive: described.primitive,
        depth_stencil: Some(described.depth_stencil.clone()),
        multisample: described.multisample,
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(&described.fragment_entry),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            targets: &described.targets,
        }),
        multiview_mask: None,
        cache: None,
    });
    match scope.pop().await {
        None => Ok(pipeline),
        Some(err) => Err(Error::Wgpu(format!("{}: {err}", described.label))),
    }
}

/// The pass's colour targets by location: the frame's for its outputs,
/// the host's for the cache, the age and the classes.
fn color_targets(
    pass: &Pass,
    inputs: &PipelineInputs<'_>,
) -> Result<Vec<Option<wgpu::ColorTargetState>>, Error> {
    let additive = wgpu::BlendComponent {
        src_factor: wgpu::BlendFactor::One,
        dst_factor: wgpu::BlendFactor::One,
        operation: wgpu::BlendOperation::Add,
    };
    let host = |format| wgpu::ColorTargetState {
        format,
        blend: None,
        write_mask: wgpu::ColorWrites::ALL,
    };
    let mut targets: Vec<Option<wgpu::ColorTargetState>> = Vec::new();
    for target in &pass.color_targets {
        let index = target.location as usize;
        if targets.len() <= index {
            targets.resize(index + 1, None);
        }
        targets[index] = Some(match target.target {
            TargetKind::Cache => host(inputs.formats.cache),
            TargetKind::Age => host(inputs.formats.age),
            TargetKind::Classes => host(inputs.formats.classes),
            TargetKind::Samples => host(inputs.formats.cache),
            TargetKind::SampleGeometry | TargetKind::History => host(inputs.formats.history),
            TargetKind::GBuffer => host(inputs.gbuffer.get(index).copied().ok_or_else(|| {
                Error::Plan(format!(
                    "pass `{}` writes G-buffer texture {index}, which the plan's G-buffer pass does not make",
                    pass.name
                ))
            })?),
            TargetKind::Color => {
                let mut state = inputs
                    .frame
                    .color_targets
                    .get(index)
                    .cloned()
                    .flatten()
                    .ok_or_else(|| {
                        Error::Mismatch(format!(
                            "pass `{}` writes @location({index}), and the frame has no colour target there",
                            pass.name
                        ))
                    })?;
                if inputs.options.count_shading {
                    state.blend = Some(wgpu::BlendState {
                        color: additive,
                        alpha: additive,
                    });
                }
                state
            }
        });
    }
    Ok(targets)
}
