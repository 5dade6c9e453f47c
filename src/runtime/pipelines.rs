use std::borrow::Cow;

use crate::plan::{CompareFunction, Pass, Plan, StepMode, TargetKind, VertexAttribute};

/// A headless wgpu device.
#[derive(Debug)]
pub struct Gpu {
    pub adapter: wgpu::AdapterInfo,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
}

impl Gpu {
    /// The first adapter any backend offers, with default limits. `None`
    /// when the machine has no GPU and no software driver.
    pub fn new() -> Result<Option<Gpu>, String> {
        let instance =
            wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle_from_env());
        let adapter = match pollster::block_on(
            instance.request_adapter(&wgpu::RequestAdapterOptions::default()),
        ) {
            Ok(adapter) => adapter,
            Err(_) => return Ok(None),
        };
        // Timestamp queries where the adapter has them (lavapipe does): the
        // profiler times each pass with them.
        let features = adapter.features() & wgpu_profiler::GpuProfiler::ALL_WGPU_TIMER_FEATURES;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("shadecache"),
            required_features: features,
            ..wgpu::DeviceDescriptor::default()
        }))
        .map_err(|err| format!("cannot open a device on {}: {err}", adapter.get_info().name))?;
        Ok(Some(Gpu {
            adapter: adapter.get_info(),
            device,
            queue,
        }))
    }
}

/// How to build the pipelines beyond what the plan says.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PipelineOptions {
    /// A debugging view: the frame's colour targets blend additively, so a
    /// pixel's value is the sum of every shading of it. With a shader that
    /// writes a constant, it counts how many times each pixel was shaded.
    pub count_shading: bool,
    /// Cull back faces (counter-clockwise triangles face front), as the
    /// scene says; the same for the reference and every variant.
    pub cull_back_faces: bool,
}

/// Builds one render pipeline per pass of `plan`; `shader` gives the WGSL
/// text of a pass's shader file by name. Validation errors from wgpu are
/// returned, naming the pass.
pub fn pipelines(
    gpu: &Gpu,
    plan: &Plan,
    shader: impl Fn(&str) -> Option<String>,
    options: PipelineOptions,
) -> Result<Vec<wgpu::RenderPipeline>, String> {
    // Slot 0 steps per vertex, slot 1 (when the shader has per-instance
    // inputs) per instance; each packs its inputs in the layout's order.
    let per_vertex = vertex_attributes(&plan.vertex_layout, StepMode::Vertex)?;
    let per_instance = vertex_attributes(&plan.vertex_layout, StepMode::Instance)?;
    let buffer = |attributes, step_mode| {
        Some(wgpu::VertexBufferLayout {
            array_stride: stride(attributes),
            step_mode,
            attributes,
        })
    };
    let mut buffers = vec![buffer(&per_vertex, wgpu::VertexStepMode::Vertex)];
    if !per_instance.is_empty() {
        buffers.push(buffer(&per_instance, wgpu::VertexStepMode::Instance));
    }
    plan.passes
        .iter()
        .map(|pass| {
            let source = shader(&pass.shader)
                .ok_or_else(|| format!("{}: no shader `{}`", pass.name, pass.shader))?;
            let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
            let pipeline = pipeline(gpu, pass, &source, &buffers, options)?;
            match pollster::block_on(scope.pop()) {
                None => Ok(pipeline),
                Some(err) => Err(format!("{}: {err}", pass.name)),
            }
        })
        .collect()
}

fn pipeline(
    gpu: &Gpu,
    pass: &Pass,
    source: &str,
    buffers: &[Option<wgpu::VertexBufferLayout<'_>>],
    options: PipelineOptions,
) -> Result<wgpu::RenderPipeline, String> {
    let module = gpu
        .device
        .create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(&pass.shader),
            source: wgpu::ShaderSource::Wgsl(Cow::Borrowed(source)),
        });
    let mut targets: Vec<Option<wgpu::ColorTargetState>> = Vec::new();
    for target in &pass.color_targets {
        let index = target.location as usize;
        if targets.len() <= index {
            targets.resize(index + 1, None);
        }
        let additive = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::One,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        targets[index] = Some(wgpu::ColorTargetState {
            format: texture_format(&target.format)?,
            blend: (options.count_shading && target.target == TargetKind::Color).then_some(
                wgpu::BlendState {
                    color: additive,
                    alpha: additive,
                },
            ),
            write_mask: wgpu::ColorWrites::ALL,
        });
    }
    let depth_compare = match pass.depth.compare {
        CompareFunction::Less => wgpu::CompareFunction::Less,
        CompareFunction::LessEqual => wgpu::CompareFunction::LessEqual,
        CompareFunction::Greater => wgpu::CompareFunction::Greater,
        CompareFunction::GreaterEqual => wgpu::CompareFunction::GreaterEqual,
        CompareFunction::Equal => wgpu::CompareFunction::Equal,
        CompareFunction::Always => wgpu::CompareFunction::Always,
    };
    Ok(gpu
        .device
        .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some(&pass.name),
            layout: None,
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some(&pass.vertex_entry),
                compilation_options: wgpu::PipelineCompilationOptions::default(),
                buffers,
            },
            primitive: wgpu::PrimitiveState {
                cull_mode: options.cull_back_faces.then_some(wgpu::Face::Back),
                ..wgpu::PrimitiveState::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: texture_format(&pass.depth.format)?,
                depth_write_enabled: Some(pass.depth.write),
                depth_compare: Some(depth_compare),
                stencil: wgpu::StencilState::default(),
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
        }))
}

/// The plan's attributes packed one after another in one buffer.
/// Bytes of one element of a buffer holding `attributes`, packed.
fn stride(attributes: &[wgpu::VertexAttribute]) -> u64 {
    attributes
        .iter()
        .map(|a| a.offset + a.format.size())
        .max()
        .unwrap_or(0)
}

/// The byte size of one vertex input of the plan.
pub fn attribute_size(attribute: &VertexAttribute) -> Result<u64, String> {
    Ok(vertex_format(&attribute.format)?.size())
}

/// The attributes of `layout` that step as `step`, packed in order.
fn vertex_attributes(
    layout: &[VertexAttribute],
    step: StepMode,
) -> Result<Vec<wgpu::VertexAttribute>, String> {
    let mut offset = 0;
    layout
        .iter()
        .filter(|attribute| attribute.step == step)
        .map(|attribute| {
            let format = vertex_format(&attribute.format)?;
            let out = wgpu::VertexAttribute {
                format,
                offset,
                shader_location: attribute.location,
            };
            offset += format.size();
            Ok(out)
        })
        .collect()
}

fn vertex_format(name: &str) -> Result<wgpu::VertexFormat, String> {
    use wgpu::VertexFormat as F;
    Ok(match name {
        "float32" => F::Float32,
        "float32x2" => F::Float32x2,
        "float32x3" => F::Float32x3,
        "float32x4" => F::Float32x4,
        "sint32" => F::Sint32,
        "sint32x2" => F::Sint32x2,
        "sint32x3" => F::Sint32x3,
        "sint32x4" => F::Sint32x4,
        "uint32" => F::Uint32,
        "uint32x2" => F::Uint32x2,
        "uint32x3" => F::Uint32x3,
        "uint32x4" => F::Uint32x4,
        other => return Err(format!("unsupported vertex format `{other}`")),
    })
}

pub(super) fn texture_format(name: &str) -> Result<wgpu::TextureFormat, String> {
    use wgpu::TextureFormat as T;
    Ok(match name {
        "rgba8unorm" => T::Rgba8Unorm,
        "rgba8unorm-srgb" => T::Rgba8UnormSrgb,
        "bgra8unorm" => T::Bgra8Unorm,
        "r16float" => T::R16Float,
        "rgba16float" => T::Rgba16Float,
        "rgba32float" => T::Rgba32Float,
        "depth32float" => T::Depth32Float,
        other => return Err(format!("unsupported texture format `{other}`")),
    })
}
