//! The scene's textures on the GPU, and reading targets back.

use std::collections::HashMap;

use super::gpu::Gpu;
use crate::plan::{Plan, ResourceKind};

/// A texture's RGBA8 texels, row by row, as the runtime uploads them.
#[derive(Clone, Debug)]
pub struct Texels {
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
    /// A full mip chain is made from them (a colour texture's only).
    pub mipmaps: bool,
}

impl Texels {
    /// The mip levels below the texels, each the texels resized with a
    /// triangle filter (the box filter's smooth neighbour, what mip
    /// generation commonly uses) to half the one above, down to 1×1:
    /// (width, height, RGBA8).
    fn mip_levels(&self) -> Vec<(u32, u32, Vec<u8>)> {
        let Some(image) = image::RgbaImage::from_raw(self.width, self.height, self.rgba.clone())
        else {
            return Vec::new();
        };
        let mut levels = Vec::new();
        let (mut width, mut height) = (self.width, self.height);
        while width > 1 || height > 1 {
            (width, height) = ((width / 2).max(1), (height / 2).max(1));
            let level = image::imageops::resize(
                &image,
                width,
                height,
                image::imageops::FilterType::Triangle,
            );
            levels.push((width, height, level.into_raw()));
        }
        levels
    }
}

/// A depth texture's texels: `size`² 16-bit unorm depths, row-major (a
/// shadow map the scene renders from its light each frame).
#[derive(Clone, Debug, PartialEq)]
pub struct DepthTexels {
    pub size: u32,
    pub depth: Vec<u16>,
}

/// The side of the 2D depth textures the runtime makes: what a frame's
/// [`DepthTexels`] for them must have.
pub const DEPTH_MAP_SIZE: u32 = 512;

/// Writes `texels` into the 2D depth texture `texture` (made by
/// [`scene_textures`]).
pub(super) fn write_depth(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    texels: &DepthTexels,
) -> Result<(), String> {
    if texels.size != texture.width() || texels.depth.len() != (texels.size * texels.size) as usize
    {
        return Err(format!(
            "a depth map of {}² texels for a {}² depth texture",
            texels.size,
            texture.width()
        ));
    }
    let bytes: Vec<u8> = texels.depth.iter().flat_map(|d| d.to_le_bytes()).collect();
    gpu.queue.write_texture(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::DepthOnly,
        },
        &bytes,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(texels.size * 2),
            rows_per_image: Some(texels.size),
        },
        texture.size(),
    );
    Ok(())
}

/// The scene's textures and samplers for the plan's bindings: texels
/// uploaded, depth textures at the far plane (a 2D one in `depth16unorm`,
/// [`DEPTH_MAP_SIZE`]², so that a frame can write a shadow map into it),
/// and those 2D depth textures by binding.
#[allow(clippy::type_complexity)]
pub(super) fn scene_textures(
    gpu: &Gpu,
    plan: &Plan,
    textures: &HashMap<[u32; 2], Texels>,
    external_group: Option<u32>,
) -> Result<
    (
        HashMap<[u32; 2], wgpu::TextureView>,
        HashMap<[u32; 2], wgpu::Sampler>,
        HashMap<[u32; 2], wgpu::Texture>,
    ),
    String,
> {
    let mut views = HashMap::new();
    let mut samplers = HashMap::new();
    let mut depth_maps = HashMap::new();
    for resource in &plan.bindings.original {
        if Some(resource.group) == external_group {
            continue;
        }
        let key = [resource.group, resource.binding];
        if let Some((depth, shape)) = sampled_shape(resource.kind) {
            let view = if depth
                && shape.layers == 1
                && shape.dimension == wgpu::TextureViewDimension::D2
            {
                let (texture, view) = far_depth(
                    gpu,
                    &resource.name,
                    wgpu::TextureFormat::Depth16Unorm,
                    shape,
                    DEPTH_MAP_SIZE,
                );
                depth_maps.insert(key, texture);
                view
            } else if depth {
                far_depth(
                    gpu,
                    &resource.name,
                    wgpu::TextureFormat::Depth32Float,
                    shape,
                    64,
                )
                .1
            } else {
                let texels = textures
                    .get(&key)
                    .ok_or_else(|| format!("no texels for texture `{}`", resource.name))?;
                upload(gpu, texels, shape, wgpu::TextureFormat::Rgba8Unorm)
            };
            views.insert(key, view);
            continue;
        }
        match resource.kind {
            ResourceKind::Sampler | ResourceKind::ComparisonSampler => {
                let compare = resource.kind == ResourceKind::ComparisonSampler;
                samplers.insert(
                    key,
                    gpu.device.create_sampler(&wgpu::SamplerDescriptor {
                        label: Some(&resource.name),
                        address_mode_u: wgpu::AddressMode::Repeat,
                        address_mode_v: wgpu::AddressMode::Repeat,
                        address_mode_w: wgpu::AddressMode::Repeat,
                        mag_filter: wgpu::FilterMode::Linear,
                        min_filter: wgpu::FilterMode::Linear,
                        mipmap_filter: wgpu::MipmapFilterMode::Linear,
                        compare: compare.then_some(wgpu::CompareFunction::LessEqual),
                        ..wgpu::SamplerDescriptor::default()
                    }),
                );
            }
            // A `texture_2d<u32>` (an iteration count, a material id)
            // read with `textureLoad`: the scene's texels as whole numbers
            // 0 to 255 per channel.
            ResourceKind::UintTexture => {
                let texels = textures
                    .get(&key)
                    .ok_or_else(|| format!("no texels for texture `{}`", resource.name))?;
                let shape = SampledShape {
                    dimension: wgpu::TextureViewDimension::D2,
                    layers: 1,
                };
                views.insert(
                    key,
                    upload(gpu, texels, shape, wgpu::TextureFormat::Rgba8Uint),
                );
            }
            ResourceKind::Uniform | ResourceKind::Storage | ResourceKind::StorageReadWrite => {}
            other => {
                return Err(format!(
                    "cannot bind `{}`: {other} bindings are not supported",
                    resource.name
                ))
            }
        }
    }
    Ok((views, samplers, depth_maps))
}

/// How a texture the shader samples is made: its view's dimension and how
/// many layers it has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct SampledShape {
    dimension: wgpu::TextureViewDimension,
    layers: u32,
}

/// Layers of the arrays the runtime makes (a shadow map array indexed by
/// light, say): the same texels, or the far plane, in each.
const ARRAY_LAYERS: u32 = 8;
/// Cubes of the cube arrays it makes.
const CUBE_ARRAY_CUBES: u32 = 2;

/// Whether a plan's texture kind is a depth texture, and its shape; `None`
/// for what is not a sampled texture.
fn sampled_shape(kind: ResourceKind) -> Option<(bool, SampledShape)> {
    use wgpu::TextureViewDimension as D;
    let texture = kind.sampled()?;
    let (dimension, layers) = match (texture.cube, texture.arrayed) {
        (false, false) => (D::D2, 1),
        (false, true) => (D::D2Array, ARRAY_LAYERS),
        (true, false) => (D::Cube, 6),
        (true, true) => (D::CubeArray, 6 * CUBE_ARRAY_CUBES),
    };
    Some((texture.depth, SampledShape { dimension, layers }))
}

/// A `side`² depth texture of `shape` with every texel at the far plane
/// (a shadow map that shadows nothing), and its view.
fn far_depth(
    gpu: &Gpu,
    label: &str,
    format: wgpu::TextureFormat,
    shape: SampledShape,
    side: u32,
) -> (wgpu::Texture, wgpu::TextureView) {
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: side,
            height: side,
            depth_or_array_layers: shape.layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    for layer in 0..shape.layers {
        let view = texture.create_view(&wgpu::TextureViewDescriptor {
            dimension: Some(wgpu::TextureViewDimension::D2),
            base_array_layer: layer,
            array_layer_count: Some(1),
            ..wgpu::TextureViewDescriptor::default()
        });
        shadecache_host::toolchain::clear_depth(&mut encoder, &view, 1.0);
    }
    gpu.queue.submit([encoder.finish()]);
    let view = texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(shape.dimension),
        ..wgpu::TextureViewDescriptor::default()
    });
    (texture, view)
}

/// Uploads RGBA8 texels into every layer of a texture of `shape` (a 2D
/// texture, the six faces of a cube, an array of either) of `format`, one
/// with four 8-bit channels (normalised, or whole numbers).
fn upload(
    gpu: &Gpu,
    texels: &Texels,
    shape: SampledShape,
    format: wgpu::TextureFormat,
) -> wgpu::TextureView {
    let layers = shape.layers;
    let size = wgpu::Extent3d {
        width: texels.width,
        height: texels.height,
        depth_or_array_layers: layers,
    };
    // Whole numbers are not filtered: an integer texture keeps one level.
    let integer = format.sample_type(None, None) == Some(wgpu::TextureSampleType::Uint);
    let mips = if texels.mipmaps && !integer {
        texels.mip_levels()
    } else {
        Vec::new()
    };
    let levels: Vec<(u32, u32, &[u8])> =
        std::iter::once((texels.width, texels.height, texels.rgba.as_slice()))
            .chain(mips.iter().map(|(w, h, rgba)| (*w, *h, rgba.as_slice())))
            .collect();
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("scene texture"),
        size,
        mip_level_count: levels.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for layer in 0..layers {
        for (mip_level, &(width, height, rgba)) in levels.iter().enumerate() {
            gpu.queue.write_texture(
                wgpu::TexelCopyTextureInfo {
                    texture: &texture,
                    mip_level: mip_level as u32,
                    origin: wgpu::Origin3d {
                        x: 0,
                        y: 0,
                        z: layer,
                    },
                    aspect: wgpu::TextureAspect::All,
                },
                rgba,
                wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(width * 4),
                    rows_per_image: Some(height),
                },
                wgpu::Extent3d {
                    width,
                    height,
                    depth_or_array_layers: 1,
                },
            );
        }
    }
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(shape.dimension),
        ..wgpu::TextureViewDescriptor::default()
    })
}

/// Reads a texture back as raw rows of `bytes_per_texel × width` bytes.
pub fn read_texture(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
) -> Result<Vec<u8>, String> {
    read_aspect(gpu, texture, bytes_per_texel, wgpu::TextureAspect::All)
}

/// The depth of every texel of a depth texture (`depth32float`, or the
/// depth of `depth32float-stencil8`), row-major.
pub fn read_depth(gpu: &Gpu, texture: &wgpu::Texture) -> Result<Vec<f32>, String> {
    Ok(
        read_aspect(gpu, texture, 4, wgpu::TextureAspect::DepthOnly)?
            .chunks_exact(4)
            .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .collect(),
    )
}

/// Reads `aspect` of a texture back, `bytes_per_texel` a texel.
fn read_aspect(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
    aspect: wgpu::TextureAspect,
) -> Result<Vec<u8>, String> {
    let (width, height) = (texture.width(), texture.height());
    let row = width * bytes_per_texel;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: (padded * height) as u64,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let mut encoder = gpu
        .device
        .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        texture.size(),
    );
    gpu.queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|err| err.to_string())?;
    let data = slice.get_mapped_range().map_err(|err| format!("{err:?}"))?;
    let mut out = Vec::with_capacity((row * height) as usize);
    for y in 0..height {
        let start = (y * padded) as usize;
        out.extend_from_slice(&data[start..start + row as usize]);
    }
    Ok(out)
}
