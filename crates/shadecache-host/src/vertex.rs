//! The vertex buffers: the application's, checked against the inputs the
//! plan's shaders read, and the host's copies of last frame's.

use shadecache_plan::{Plan, StepMode};

use crate::formats::vertex_format;
use crate::Error;

/// A vertex buffer's layout, owned: the application's as the host keeps
/// it, a twin slot's, and each buffer of a
/// [`PassPipelineDescriptor`](crate::PassPipelineDescriptor).
#[derive(Clone, Debug, PartialEq)]
pub struct VertexBufferDescriptor {
    /// Bytes between elements.
    pub array_stride: wgpu::BufferAddress,
    /// Per vertex or per instance.
    pub step_mode: wgpu::VertexStepMode,
    /// What each element holds, at which shader location.
    pub attributes: Vec<wgpu::VertexAttribute>,
}

impl VertexBufferDescriptor {
    /// The layout as wgpu takes it.
    pub fn borrowed(&self) -> wgpu::VertexBufferLayout<'_> {
        wgpu::VertexBufferLayout {
            array_stride: self.array_stride,
            step_mode: self.step_mode,
            attributes: &self.attributes,
        }
    }
}

impl From<&wgpu::VertexBufferLayout<'_>> for VertexBufferDescriptor {
    fn from(layout: &wgpu::VertexBufferLayout<'_>) -> VertexBufferDescriptor {
        VertexBufferDescriptor {
            array_stride: layout.array_stride,
            step_mode: layout.step_mode,
            attributes: layout.attributes.to_vec(),
        }
    }
}

/// Last frame's copy of one of the application's vertex buffers: the
/// plan's twin inputs read it at the offsets of the inputs they shadow.
#[derive(Clone, Debug)]
pub(crate) struct TwinSlot {
    /// The application's slot it copies.
    pub source: u32,
    /// The slot the host binds the copy at.
    pub slot: u32,
    pub layout: VertexBufferDescriptor,
}

/// The vertex buffers of the variant's pipelines: the application's, as
/// given, then one twin slot per buffer whose inputs have twins. Checks
/// that every input the plan reads is in a buffer, in the plan's format
/// and step mode.
pub(crate) fn layouts(
    plan: &Plan,
    given: &[Option<wgpu::VertexBufferLayout<'_>>],
) -> Result<(Vec<Option<VertexBufferDescriptor>>, Vec<TwinSlot>), Error> {
    let user: Vec<Option<VertexBufferDescriptor>> = given
        .iter()
        .map(|l| l.as_ref().map(VertexBufferDescriptor::from))
        .collect();
    let find = |location: u32| {
        user.iter().enumerate().find_map(|(slot, layout)| {
            let layout = layout.as_ref()?;
            layout
                .attributes
                .iter()
                .find(|a| a.shader_location == location)
                .map(|a| (slot as u32, layout, a))
        })
    };
    let mut twins: Vec<TwinSlot> = Vec::new();
    for input in &plan.vertex_layout {
        let format = vertex_format(input.format);
        let step = match input.step {
            StepMode::Vertex => wgpu::VertexStepMode::Vertex,
            StepMode::Instance => wgpu::VertexStepMode::Instance,
        };
        let Some(of) = input.previous_of else {
            let (_, layout, attribute) = find(input.location).ok_or_else(|| {
                Error::Mismatch(format!(
                    "the shader reads vertex input @location({}) `{}`, which none of the frame's vertex buffers holds",
                    input.location, input.name
                ))
            })?;
            if attribute.format != format || layout.step_mode != step {
                return Err(Error::Mismatch(format!(
                    "vertex input @location({}) `{}` is {} stepping per {:?} in the shader, {:?} stepping per {:?} in the frame",
                    input.location, input.name, input.format, input.step, attribute.format, layout.step_mode
                )));
            }
            continue;
        };
        // A twin reads last frame's copy of the buffer holding what it
        // shadows, at the same offset.
        let (source, layout, shadowed) = find(of).ok_or_else(|| {
            Error::Mismatch(format!(
                "vertex input @location({}) `{}` is last frame's @location({of}), which none of the frame's vertex buffers holds",
                input.location, input.name
            ))
        })?;
        if shadowed.format != format {
            return Err(Error::Mismatch(format!(
                "vertex input @location({}) `{}` is {}, and @location({of}) it shadows is {:?} in the frame",
                input.location, input.name, input.format, shadowed.format
            )));
        }
        let attribute = wgpu::VertexAttribute {
            shader_location: input.location,
            ..*shadowed
        };
        match twins.iter_mut().find(|t| t.source == source) {
            Some(twin) => twin.layout.attributes.push(attribute),
            None => twins.push(TwinSlot {
                source,
                slot: (user.len() + twins.len()) as u32,
                layout: VertexBufferDescriptor {
                    array_stride: layout.array_stride,
                    step_mode: layout.step_mode,
                    attributes: vec![attribute],
                },
            }),
        }
    }
    Ok((user, twins))
}
