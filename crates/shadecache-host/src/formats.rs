//! The plan names formats as WebGPU spells them; these are wgpu's.

use crate::Error;

/// The wgpu texture format a plan names (`rgba16float`, `depth32float`).
pub fn texture_format(name: &str) -> Result<wgpu::TextureFormat, Error> {
    use wgpu::TextureFormat as T;
    Ok(match name {
        "rgba8unorm" => T::Rgba8Unorm,
        "rgba8unorm-srgb" => T::Rgba8UnormSrgb,
        "bgra8unorm" => T::Bgra8Unorm,
        "bgra8unorm-srgb" => T::Bgra8UnormSrgb,
        "r16float" => T::R16Float,
        "rg16float" => T::Rg16Float,
        "rgba16float" => T::Rgba16Float,
        "r32float" => T::R32Float,
        "rgba32float" => T::Rgba32Float,
        "r32uint" => T::R32Uint,
        "rg32uint" => T::Rg32Uint,
        "rgba32uint" => T::Rgba32Uint,
        "r32sint" => T::R32Sint,
        "rg32sint" => T::Rg32Sint,
        "rgba32sint" => T::Rgba32Sint,
        "depth16unorm" => T::Depth16Unorm,
        "depth24plus" => T::Depth24Plus,
        "depth24plus-stencil8" => T::Depth24PlusStencil8,
        "depth32float" => T::Depth32Float,
        other => return Err(Error::Plan(format!("unknown texture format `{other}`"))),
    })
}

/// The wgpu vertex format a plan names (`float32x3`).
pub fn vertex_format(name: &str) -> Result<wgpu::VertexFormat, Error> {
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
        other => return Err(Error::Plan(format!("unknown vertex format `{other}`"))),
    })
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
