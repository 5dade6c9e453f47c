//! Bind group layouts: the application's groups, checked against the
//! plan, and the cache's group, made from the plan.

use std::collections::BTreeMap;

use shadecache_plan::{CacheFormat, Plan, Resource, ResourceKind};

use crate::Error;

const VISIBLE: wgpu::ShaderStages = wgpu::ShaderStages::VERTEX_FRAGMENT;

/// The binding type WGSL declares as `kind`, and the stages it is
/// visible to (both; read-write storage the fragment stage only). A
/// sampled colour texture is taken as filterable float. `None` for what a
/// layout cannot state from the plan (storage textures and `other`).
fn binding_type(kind: ResourceKind) -> Option<(wgpu::BindingType, wgpu::ShaderStages)> {
    use wgpu::TextureViewDimension as D;
    use ResourceKind as K;
    let texture = |dimension, depth: bool| wgpu::BindingType::Texture {
        sample_type: if depth {
            wgpu::TextureSampleType::Depth
        } else {
            wgpu::TextureSampleType::Float { filterable: true }
        },
        view_dimension: dimension,
        multisampled: false,
    };
    let (ty, visibility) = match kind {
        K::Uniform => (buffer(wgpu::BufferBindingType::Uniform), VISIBLE),
        K::Storage => (
            buffer(wgpu::BufferBindingType::Storage { read_only: true }),
            VISIBLE,
        ),
        K::StorageReadWrite => (
            buffer(wgpu::BufferBindingType::Storage { read_only: false }),
            wgpu::ShaderStages::FRAGMENT,
        ),
        K::Texture => (texture(D::D2, false), VISIBLE),
        K::UintTexture => (
            wgpu::BindingType::Texture {
                sample_type: wgpu::TextureSampleType::Uint,
                view_dimension: D::D2,
                multisampled: false,
            },
            VISIBLE,
        ),
        K::TextureArray => (texture(D::D2Array, false), VISIBLE),
        K::CubeTexture => (texture(D::Cube, false), VISIBLE),
        K::CubeTextureArray => (texture(D::CubeArray, false), VISIBLE),
        K::DepthTexture => (texture(D::D2, true), VISIBLE),
        K::DepthTextureArray => (texture(D::D2Array, true), VISIBLE),
        K::DepthCubeTexture => (texture(D::Cube, true), VISIBLE),
        K::DepthCubeTextureArray => (texture(D::CubeArray, true), VISIBLE),
        K::Texture1d => (texture(D::D1, false), VISIBLE),
        K::Texture3d => (texture(D::D3, false), VISIBLE),
        K::Sampler => (
            wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
            VISIBLE,
        ),
        K::ComparisonSampler => (
            wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Comparison),
            VISIBLE,
        ),
        K::StorageTexture | K::Other => return None,
    };
    Some((ty, visibility))
}

fn buffer(ty: wgpu::BufferBindingType) -> wgpu::BindingType {
    wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset: false,
        min_binding_size: None,
    }
}

/// The layout entry a plan's resource implies (`binding_type`); `None`
/// for what a layout cannot state from the plan.
pub fn entry_for(resource: &Resource) -> Option<wgpu::BindGroupLayoutEntry> {
    let (ty, visibility) = binding_type(resource.kind)?;
    Some(wgpu::BindGroupLayoutEntry {
        binding: resource.binding,
        visibility,
        ty,
        count: None,
    })
}

/// The layout entries of the application's `group` as the plan implies
/// them, for an application without layouts of its own (and for the
/// profiler). Errors for a resource whose type the plan cannot state.
#[cfg(feature = "toolchain")]
pub fn plan_layout_entries(
    plan: &Plan,
    group: u32,
) -> Result<Vec<wgpu::BindGroupLayoutEntry>, Error> {
    plan.bindings
        .original
        .iter()
        .filter(|r| r.group == group)
        .map(|resource| {
            entry_for(resource).ok_or_else(|| {
                Error::Plan(format!(
                    "`{}` is a {} binding, whose layout the plan cannot state: give the layout",
                    resource.name, resource.kind
                ))
            })
        })
        .collect()
}

/// The groups the application binds, by the plan.
#[cfg(feature = "toolchain")]
pub fn plan_groups(plan: &Plan) -> Vec<u32> {
    let mut groups: Vec<u32> = plan.bindings.original.iter().map(|r| r.group).collect();
    groups.sort_unstable();
    groups.dedup();
    groups
}

/// The group the cache's resources and the twins are bound at, if the
/// plan has any.
pub(crate) fn cache_group(plan: &Plan) -> Option<u32> {
    plan.bindings
        .cache
        .iter()
        .map(|r| r.group)
        .chain(plan.bindings.previous.iter().map(|t| t.group))
        .next()
}

/// Checks the application's layouts against every resource the plan
/// says its shaders bind; returns them by group. (A shader that uses all
/// four groups shares its last with the cache: that group's layout is
/// given too, and the host binds it.)
pub(crate) fn user_groups<'a>(
    plan: &Plan,
    given: &'a [(u32, &'a [wgpu::BindGroupLayoutEntry])],
) -> Result<BTreeMap<u32, &'a [wgpu::BindGroupLayoutEntry]>, Error> {
    let mut groups = BTreeMap::new();
    for &(group, entries) in given {
        if groups.insert(group, entries).is_some() {
            return Err(Error::Mismatch(format!(
                "the frame gives group {group}'s layout twice"
            )));
        }
    }
    for resource in &plan.bindings.original {
        let where_ = format!(
            "`{}` (group {}, binding {})",
            resource.name, resource.group, resource.binding
        );
        let entry = groups
            .get(&resource.group)
            .and_then(|entries| entries.iter().find(|e| e.binding == resource.binding))
            .ok_or_else(|| {
                Error::Mismatch(format!(
                    "the shader binds {where_}, and the frame's layouts have no such entry"
                ))
            })?;
        if !compatible(resource.kind, &entry.ty) {
            return Err(Error::Mismatch(format!(
                "the shader binds {where_} as a {} binding; the frame's layout has {:?}",
                resource.kind, entry.ty
            )));
        }
    }
    Ok(groups)
}

/// Whether a layout entry's type can hold what WGSL declares as `kind`:
/// the same binding type, up to what WGSL does not say (a texture's float
/// filterability, a sampler's filtering, a buffer's dynamic offset and
/// least size).
fn compatible(kind: ResourceKind, ty: &wgpu::BindingType) -> bool {
    use wgpu::BindingType as B;
    use ResourceKind as K;
    let is_depth = |t: &wgpu::TextureSampleType| *t == wgpu::TextureSampleType::Depth;
    match (kind, ty) {
        (K::Other, _) => true,
        (K::StorageTexture, B::StorageTexture { .. }) => true,
        (K::Sampler, B::Sampler(s)) => *s != wgpu::SamplerBindingType::Comparison,
        (
            kind,
            B::Texture {
                sample_type,
                view_dimension,
                ..
            },
        ) => matches!(
            binding_type(kind),
            Some((B::Texture { sample_type: want, view_dimension: dimension, .. }, _))
                if dimension == *view_dimension && is_depth(&want) == is_depth(sample_type)
        ),
        (kind, B::Buffer { ty, .. }) => matches!(
            binding_type(kind),
            Some((B::Buffer { ty: want, .. }, _)) if want == *ty
        ),
        (kind, ty) => binding_type(kind).is_some_and(|(want, _)| want == *ty),
    }
}

/// How the G-buffer's textures are named in the plan: `gbuffer_a`,
/// `gbuffer_b`... for the first, the second...
pub(crate) const GBUFFER_PREFIX: &str = "gbuffer_";

/// The cache's own resources, as `shaders/cache.wgsl` names them (and the
/// deferred variant's G-buffer): what a host binds for each.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum CacheResource {
    /// The refresh uniform, `CacheParams`.
    Params,
    PreviousPayload,
    CurrentPayload,
    PreviousAge,
    PreviousDepth,
    Sampler,
    /// This frame's G-buffer texture of that index (the deferred
    /// variant's), read with `textureLoad`.
    GBuffer(usize),
    /// Lowres: this frame's samples, their geometry, last frame's
    /// upsampling history (all read with `textureLoad`).
    Samples,
    SampleGeometry,
    PreviousHistory,
    /// The draw's ordinal, a uniform bound per draw at a dynamic offset.
    Draw,
}

/// The draws whose ordinals the `Draw` uniform tells apart; later draws
/// take the ordinals again from 1.
pub(crate) const DRAW_IDS: u32 = 128;
/// Bytes between two ordinals in the `Draw` uniform: WebGPU's largest
/// `minUniformBufferOffsetAlignment`.
pub(crate) const DRAW_ID_STRIDE: u32 = 256;

impl CacheResource {
    pub fn named(name: &str) -> Result<CacheResource, Error> {
        if let Some(&[letter @ b'a'..=b'z']) = name.strip_prefix(GBUFFER_PREFIX).map(str::as_bytes)
        {
            return Ok(CacheResource::GBuffer((letter - b'a') as usize));
        }
        Ok(match name {
            "cache_params" => CacheResource::Params,
            "cache_previous_payload" => CacheResource::PreviousPayload,
            "cache_current_payload" => CacheResource::CurrentPayload,
            "cache_previous_age" => CacheResource::PreviousAge,
            "cache_previous_depth" => CacheResource::PreviousDepth,
            "cache_sampler" => CacheResource::Sampler,
            "cache_samples" => CacheResource::Samples,
            "cache_sample_geometry" => CacheResource::SampleGeometry,
            "cache_previous_history" => CacheResource::PreviousHistory,
            "cache_draw" => CacheResource::Draw,
            other => {
                return Err(Error::Plan(format!(
                    "the cache binds `{other}`, which this host does not know (a newer plan?)"
                )))
            }
        })
    }

    /// Its binding type. rgba32float is not filterable without an
    /// optional feature: its variants reconstruct from texel loads, with a
    /// non-filtering sampler.
    fn binding_type(self, payload_filterable: bool) -> wgpu::BindingType {
        let texture = |sample_type| wgpu::BindingType::Texture {
            sample_type,
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        };
        match self {
            CacheResource::Params => buffer(wgpu::BufferBindingType::Uniform),
            CacheResource::PreviousPayload | CacheResource::CurrentPayload => {
                texture(wgpu::TextureSampleType::Float {
                    filterable: payload_filterable,
                })
            }
            CacheResource::PreviousAge => {
                texture(wgpu::TextureSampleType::Float { filterable: true })
            }
            CacheResource::PreviousDepth => texture(wgpu::TextureSampleType::Depth),
            CacheResource::GBuffer(_) => texture(wgpu::TextureSampleType::Uint),
            CacheResource::Samples
            | CacheResource::SampleGeometry
            | CacheResource::PreviousHistory => {
                texture(wgpu::TextureSampleType::Float { filterable: false })
            }
            CacheResource::Draw => wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: true,
                min_binding_size: wgpu::BufferSize::new(16),
            },
            CacheResource::Sampler => wgpu::BindingType::Sampler(if payload_filterable {
                wgpu::SamplerBindingType::Filtering
            } else {
                wgpu::SamplerBindingType::NonFiltering
            }),
        }
    }
}

/// The cache group's entries: the cache's own resources, and each twin as
/// the resource it shadows.
pub(crate) fn cache_entries(plan: &Plan) -> Result<Vec<wgpu::BindGroupLayoutEntry>, Error> {
    let payload_filterable = plan.cache.format == CacheFormat::Rgba16float;
    let mut entries = Vec::new();
    for resource in &plan.bindings.cache {
        entries.push(wgpu::BindGroupLayoutEntry {
            binding: resource.binding,
            visibility: VISIBLE,
            ty: CacheResource::named(&resource.name)?.binding_type(payload_filterable),
            count: None,
        });
    }
    for twin in &plan.bindings.previous {
        let mut entry = entry_for(&twin.shadows).ok_or_else(|| {
            Error::Plan(format!(
                "`{}` shadows a {} binding, which cannot have a twin",
                twin.name, twin.shadows.kind
            ))
        })?;
        entry.binding = twin.binding;
        entries.push(entry);
    }
    Ok(entries)
}
