//! One render pipeline per pass, from the plan and the application's frame.

use std::borrow::Cow;
use std::collections::BTreeMap;

use shadecache_plan::{DrawKind, Pass, TargetKind};

use crate::formats::{compare_function, stencil_state};
use crate::{Error, FrameLayout, Options};

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
    let last = user
        .keys()
        .copied()
        .chain(cache.map(|(group, _)| group))
        .max();
    let empty = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("shadecache empty group"),
        entries: &[],
    });
    let layouts: Vec<Option<&wgpu::BindGroupLayout>> = match last {
        None => Vec::new(),
        Some(last) => (0..=last)
            .map(|group| {
                Some(
                    user.get(&group)
                        .or(cache.filter(|(g, _)| *g == group).map(|(_, l)| l))
                        .unwrap_or(&empty),
                )
            })
            .collect(),
    };
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("shadecache pass layout"),
        bind_group_layouts: &layouts,
        immediate_size: 0,
    })
}

/// What every pass's pipeline is made with.
pub(crate) struct PipelineInputs<'a> {
    pub layout: &'a wgpu::PipelineLayout,
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub frame: &'a FrameLayout<'a>,
    pub formats: HostFormats,
    /// The format of the host's depth buffers: the frame's, or one with a
    /// stencil aspect when the plan's passes test the stencil.
    pub depth_format: wgpu::TextureFormat,
    /// The G-buffer textures' formats, by index.
    pub gbuffer: &'a [wgpu::TextureFormat],
    pub options: Options,
}

/// The pass's pipeline; wgpu's validation errors name the pass.
pub(crate) async fn pipeline(
    device: &wgpu::Device,
    pass: &Pass,
    source: &str,
    inputs: &PipelineInputs<'_>,
) -> Result<wgpu::RenderPipeline, Error> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(&pass.shader),
        source: wgpu::ShaderSource::Wgsl(Cow::Borrowed(source)),
    });
    let targets = color_targets(pass, inputs)?;
    // A screen-space pass draws one triangle over the screen, from the
    // vertex index alone, whatever the application's geometry.
    let (buffers, primitive) = match pass.draw {
        DrawKind::Geometry => (inputs.buffers, inputs.frame.primitive),
        DrawKind::Fullscreen => (&[][..], wgpu::PrimitiveState::default()),
    };
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(&pass.name),
        layout: Some(inputs.layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(&pass.vertex_entry),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            buffers,
        },
        primitive,
        depth_stencil: Some(wgpu::DepthStencilState {
            format: inputs.depth_format,
            depth_write_enabled: Some(pass.depth.write),
            depth_compare: Some({
                let compare = compare_function(pass.depth.compare);
                match (inputs.options.depth_test_or_equal, compare) {
                    (true, wgpu::CompareFunction::Less) => wgpu::CompareFunction::LessEqual,
                    (true, wgpu::CompareFunction::Greater) => wgpu::CompareFunction::GreaterEqual,
                    _ => compare,
                }
            }),
            stencil: pass.stencil.map(stencil_state).unwrap_or_default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some(&pass.fragment_entry),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            targets: &targets,
        }),
        multiview_mask: None,
        cache: None,
    });
    match scope.pop().await {
        None => Ok(pipeline),
        Some(err) => Err(Error::Wgpu(format!("{}: {err}", pass.name))),
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
