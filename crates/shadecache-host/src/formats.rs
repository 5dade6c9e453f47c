//! The plan's formats as wgpu's.

use shadecache_plan::{TextureFormat, VertexFormat};

/// The wgpu texture format a plan names.
pub fn texture_format(format: TextureFormat) -> wgpu::TextureFormat {
    use wgpu::TextureFormat as T;
    use TextureFormat as F;
    match format {
        F::Rgba8Unorm => T::Rgba8Unorm,
        F::Rgba8UnormSrgb => T::Rgba8UnormSrgb,
        F::Bgra8Unorm => T::Bgra8Unorm,
        F::Bgra8UnormSrgb => T::Bgra8UnormSrgb,
        F::R16Float => T::R16Float,
        F::Rg16Float => T::Rg16Float,
        F::Rgba16Float => T::Rgba16Float,
        F::R32Float => T::R32Float,
        F::Rg32Float => T::Rg32Float,
        F::Rgba32Float => T::Rgba32Float,
        F::R32Uint => T::R32Uint,
        F::Rg32Uint => T::Rg32Uint,
        F::Rgba32Uint => T::Rgba32Uint,
        F::R32Sint => T::R32Sint,
        F::Rg32Sint => T::Rg32Sint,
        F::Rgba32Sint => T::Rgba32Sint,
        F::Depth16Unorm => T::Depth16Unorm,
        F::Depth24Plus => T::Depth24Plus,
        F::Depth24PlusStencil8 => T::Depth24PlusStencil8,
        F::Depth32Float => T::Depth32Float,
    }
}

/// The wgpu vertex format a plan names.
pub fn vertex_format(format: VertexFormat) -> wgpu::VertexFormat {
    use wgpu::VertexFormat as W;
    use VertexFormat as F;
    match format {
        F::Float16 => W::Float16,
        F::Float16x2 => W::Float16x2,
        F::Float16x4 => W::Float16x4,
        F::Float32 => W::Float32,
        F::Float32x2 => W::Float32x2,
        F::Float32x3 => W::Float32x3,
        F::Float32x4 => W::Float32x4,
        F::Sint32 => W::Sint32,
        F::Sint32x2 => W::Sint32x2,
        F::Sint32x3 => W::Sint32x3,
        F::Sint32x4 => W::Sint32x4,
        F::Uint32 => W::Uint32,
        F::Uint32x2 => W::Uint32x2,
        F::Uint32x3 => W::Uint32x3,
        F::Uint32x4 => W::Uint32x4,
    }
}

/// The texture format of the payload cache.
pub fn cache_format(format: shadecache_plan::CacheFormat) -> wgpu::TextureFormat {
    match format {
        shadecache_plan::CacheFormat::Rgba16float => wgpu::TextureFormat::Rgba16Float,
        shadecache_plan::CacheFormat::Rgba32float => wgpu::TextureFormat::Rgba32Float,
    }
}

pub(crate) fn compare_function(compare: shadecache_plan::CompareFunction) -> wgpu::CompareFunction {
    use shadecache_plan::CompareFunction as C;
    match compare {
        C::Less => wgpu::CompareFunction::Less,
        C::LessEqual => wgpu::CompareFunction::LessEqual,
        C::Greater => wgpu::CompareFunction::Greater,
        C::GreaterEqual => wgpu::CompareFunction::GreaterEqual,
        C::Equal => wgpu::CompareFunction::Equal,
        C::Always => wgpu::CompareFunction::Always,
    }
}

/// The stencil state a plan's pass asks for, the same for both faces.
pub(crate) fn stencil_state(stencil: shadecache_plan::Stencil) -> wgpu::StencilState {
    let face = wgpu::StencilFaceState {
        compare: compare_function(stencil.compare),
        fail_op: wgpu::StencilOperation::Keep,
        depth_fail_op: wgpu::StencilOperation::Keep,
        pass_op: if stencil.replace {
            wgpu::StencilOperation::Replace
        } else {
            wgpu::StencilOperation::Keep
        },
    };
    wgpu::StencilState {
        front: face,
        back: face,
        read_mask: stencil.read_mask,
        write_mask: stencil.write_mask,
    }
}

/// The depth format of the host's depth buffers: the frame's, unless the
/// plan tests the stencil and the frame's format has none; then 32-bit
/// float depth with stencil where the device has it, else
/// `depth24plus-stencil8` (every WebGPU device has it).
pub(crate) fn host_depth_format(
    device: &wgpu::Device,
    frame: wgpu::TextureFormat,
    needs_stencil: bool,
) -> wgpu::TextureFormat {
    if !needs_stencil || frame.has_stencil_aspect() {
        frame
    } else if device
        .features()
        .contains(wgpu::Features::DEPTH32FLOAT_STENCIL8)
    {
        wgpu::TextureFormat::Depth32FloatStencil8
    } else {
        wgpu::TextureFormat::Depth24PlusStencil8
    }
}
