//! The cache's hard cases, one test each: points behind the previous
//! camera, reprojections that leave the viewport, depth discontinuities and
//! contact points, and the frame counter's wrap.
//!
//! The lookups are tested on the GPU directly: a harness shader that
//! includes `shaders/cache.wgsl` as it is reads a prepared previous depth
//! buffer and payload through `cache_lookup`, `cache_lookup_loads` and
//! `cache_lookup_nearest` for a list of previous clip positions, and
//! writes each lookup's status and payload to a storage buffer. Every case
//! also runs through the CPU mirror (`crate::reprojection`), which
//! must take the same decisions. The frame counter test runs the real
//! `Runner`.

use std::borrow::Cow;
use std::collections::HashMap;

use crate::rewrite::reprojection::{self, PreviousDepth, Status};
use crate::rewrite::{self, Options, Variant};
use crate::runtime::{self, Gpu};
use glam::{DMat4, DVec2, DVec3, DVec4, IVec2, UVec2, Vec2, Vec4};
use wgpu::util::DeviceExt;

/// The harness around the cache helpers. Case `i` is evaluated in the
/// 2×2 pixel quad `i` (row-major, `columns` quads a row): the quad's other
/// three pixels carry the case's motion, so that at the top-left pixel,
/// where the outcome is written, `dpdx` and `dpdy` are what a rasteriser
/// would make of a surface with that depth slope seen through that
/// mapping: the previous texel position moves by J = s·R(θ) per pixel (a
/// zoom by 1/s and a roll by −θ of the camera; the identity by default),
/// and the previous depth by the slope per texel times J.
const HARNESS: &str = r#"
struct TestCase {
    clip: vec4<f32>,
    // x, y: the previous depth's slope, NDC depth per previous texel;
    // z, w: s − 1 and θ of the mapping J = s·R(θ) from this frame's pixels
    // to last frame's texels.
    slope: vec4<f32>,
}

struct Outcome {
    // Statuses of cache_lookup, cache_lookup_loads, cache_lookup_nearest
    // and cache_footprint.
    status: vec4<f32>,
    bilinear: vec4<f32>,
    loads: vec4<f32>,
    nearest: vec4<f32>,
    // The footprint's base texel and weights.
    footprint: vec4<f32>,
}

struct Harness {
    // Quads a row, and cases.
    columns: u32,
    count: u32,
    unused: vec2<u32>,
}

// Case i's clip position at texel (2 × (i mod columns), i / columns), its
// slope in the texel right of it, as f32 bits. (Read from a texture: on
// lavapipe, storage buffer loads leave some lanes of a quad at zero, which
// breaks the derivatives the lookups take.)
@group(0) @binding(0) var cases: texture_2d<u32>;
// One outcome per pixel of the target (row-major, 2 × columns pixels a
// row): every pixel writes its own, with no branch around the lookups.
@group(0) @binding(1) var<storage, read_write> outcomes: array<Outcome>;
@group(0) @binding(2) var<uniform> harness: Harness;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>((uv * 2.0) - vec2<f32>(1.0), 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    let pixel = vec2<u32>(position.xy);
    let quad = pixel / 2u;
    let corner = vec2<f32>(pixel % 2u);
    let index = (quad.y * harness.columns) + quad.x;
    let at = vec2<i32>(vec2<u32>(quad.x * 2u, quad.y));
    let test_case = TestCase(
        bitcast<vec4<f32>>(textureLoad(cases, at, 0)),
        bitcast<vec4<f32>>(textureLoad(cases, at + vec2<i32>(1, 0), 0)),
    );
    var clip = test_case.clip;
    let scale = 1.0 + test_case.slope.z;
    let along_x = vec2<f32>(cos(test_case.slope.w), sin(test_case.slope.w)) * scale;
    let along_y = vec2<f32>(-along_x.y, along_x.x);
    let moved = (along_x * corner.x) + (along_y * corner.y);
    let per_pixel = vec2<f32>(dot(test_case.slope.xy, along_x), dot(test_case.slope.xy, along_y));
    clip.x = clip.x + (((moved.x * 2.0) / cache_params.viewport.x) * clip.w);
    clip.y = clip.y - (((moved.y * 2.0) / cache_params.viewport.y) * clip.w);
    clip.z = clip.z + (((per_pixel.x * corner.x) + (per_pixel.y * corner.y)) * clip.w);
    let bilinear = cache_lookup(clip);
    let loads = cache_lookup_loads(clip);
    let nearest = cache_lookup_nearest(clip);
    let footprint = cache_footprint(clip);
    outcomes[(pixel.y * harness.columns * 2u) + pixel.x] = Outcome(
        vec4<f32>(f32(bilinear.status), f32(loads.status), f32(nearest.status), f32(footprint.status)),
        bilinear.payload,
        loads.payload,
        nearest.payload,
        vec4<f32>(footprint.base, footprint.weights),
    );
    return vec4<f32>(0.0);
}
"#;

/// Writes a depth buffer texel by texel.
const DEPTH_WRITER: &str = r#"
@group(0) @binding(0) var<storage, read> depths: array<f32>;
@group(0) @binding(1) var<uniform> width: vec4<u32>;

@vertex
fn vs_main(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((index << 1u) & 2u), f32(index & 2u));
    return vec4<f32>((uv * 2.0) - vec2<f32>(1.0), 0.0, 1.0);
}

@fragment
fn fs_main(@builtin(position) position: vec4<f32>) -> @builtin(frag_depth) f32 {
    let pixel = vec2<u32>(position.xy);
    return depths[(pixel.y * width.x) + pixel.x];
}
"#;

/// Last frame as the cache holds it: depth buffer and payload, row-major.
struct Cache {
    size: UVec2,
    depth: Vec<f32>,
    payload: Vec<Vec4>,
    epsilon: f32,
}

impl Cache {
    /// A cache whose depth and payload are functions of the texel.
    fn from_fn(size: UVec2, epsilon: f32, mut texel: impl FnMut(IVec2) -> (f32, Vec4)) -> Cache {
        let (mut depth, mut payload) = (Vec::new(), Vec::new());
        for y in 0..size.y as i32 {
            for x in 0..size.x as i32 {
                let (d, p) = texel(IVec2::new(x, y));
                depth.push(d);
                payload.push(p);
            }
        }
        Cache {
            size,
            depth,
            payload,
            epsilon,
        }
    }

    fn previous(&self) -> PreviousDepth<'_> {
        PreviousDepth {
            size: self.size,
            depth: &self.depth,
            epsilon: self.epsilon,
            // Standard Z: the far plane at depth 1.
            far_depth: 1.0,
        }
    }

    /// The clip position (with this `w`) of a point at cache texel
    /// coordinate `texel` and previous NDC depth `depth`.
    fn clip_at(&self, texel: Vec2, depth: f32, w: f32) -> Vec4 {
        let size = self.size.as_vec2();
        let ndc = Vec2::new(
            (texel.x + 0.5) / size.x * 2.0 - 1.0,
            1.0 - (texel.y + 0.5) / size.y * 2.0,
        );
        Vec4::new(ndc.x * w, ndc.y * w, depth * w, w)
    }
}

/// One lookup: a previous clip position, the previous depth's slope per
/// previous texel around it, and the mapping from this frame's pixels to
/// last frame's texels, J = (1 + `zoom`)·R(`roll`): the identity when both
/// are zero.
#[derive(Clone, Copy, Debug, Default)]
struct Case {
    clip: Vec4,
    slope: Vec2,
    zoom: f32,
    roll: f32,
}

impl Case {
    /// The columns of J: how the previous texel position moves per pixel
    /// along x and along y.
    fn jacobian(&self) -> (Vec2, Vec2) {
        let along_x = Vec2::new(self.roll.cos(), self.roll.sin()) * (1.0 + self.zoom);
        (along_x, along_x.perp())
    }

    /// The slope as the CPU mirror finds it from what the shader's
    /// derivatives give: the slope per pixel (per texel times J) taken
    /// back through J.
    fn mirrored_slope(&self) -> Vec2 {
        let (along_x, along_y) = self.jacobian();
        let per_pixel = Vec2::new(self.slope.dot(along_x), self.slope.dot(along_y));
        reprojection::previous_slope(per_pixel, along_x, along_y)
    }
}

/// What one lookup gave.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Lookup {
    status: u32,
    payload: Vec4,
}

/// The three lookups of one case, and the footprint.
#[derive(Clone, Copy, Debug)]
struct Outcome {
    bilinear: Lookup,
    loads: Lookup,
    nearest: Lookup,
    footprint_status: u32,
    base: Vec2,
    fraction: Vec2,
}

fn status_of(code: f32) -> u32 {
    assert!(
        code == 0.0 || code == 1.0 || code == 2.0 || code == 3.0,
        "status {code}"
    );
    code as u32
}

/// Runs `cases` through the cache helpers on the GPU against `cache`.
fn lookups(gpu: &Gpu, cache: &Cache, cases: &[Case]) -> Vec<Outcome> {
    run_harness(gpu, cache, cases, false)
}

/// The same through the packed lookups (`cache_lookup_packed`,
/// `cache_lookup_loads_packed`, `cache_lookup_nearest_packed` in the
/// outcome's bilinear, loads and nearest), the payload texture holding
/// each texel's depth, from the far plane, in its fourth channel.
fn packed_lookups(gpu: &Gpu, cache: &Cache, cases: &[Case]) -> Vec<Outcome> {
    run_harness(gpu, cache, cases, true)
}

fn run_harness(gpu: &Gpu, cache: &Cache, cases: &[Case], packed: bool) -> Vec<Outcome> {
    let device = &gpu.device;
    let size = wgpu::Extent3d {
        width: cache.size.x,
        height: cache.size.y,
        depth_or_array_layers: 1,
    };
    let storage = |label: &str, bytes: &[u8], usage: wgpu::BufferUsages| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage,
        })
    };
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);

    // Last frame's depth buffer, drawn texel by texel.
    let depth = harness_texture(
        device,
        size,
        ("previous depth", wgpu::TextureFormat::Depth32Float),
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let (writer, writer_group) = depth_writer(device, cache);
    // Last frame's payload, rgba16float as the bilinear lookup needs.
    let payload = previous_payload(gpu, cache, size, packed);
    // The lookups, a case a 2×2 block of the target.
    let pipeline = lookup_pipeline(device, packed);
    let columns = 32u32.min(cases.len() as u32).max(1);
    let rows = (cases.len() as u32).div_ceil(columns).max(1);
    let target = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("harness target"),
        size: wgpu::Extent3d {
            width: columns * 2,
            height: rows * 2,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    });
    let case_texture = cases_texture(gpu, cases, (columns, rows));
    let case_view = case_texture.create_view(&wgpu::TextureViewDescriptor::default());
    let outcome_size = (columns * 2 * rows * 2 * 80) as u64;
    let outcomes = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("outcomes"),
        size: outcome_size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("outcomes readback"),
        size: outcome_size,
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    let harness: Vec<u8> = [columns, cases.len() as u32, 0, 0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let harness = storage("harness", &harness, wgpu::BufferUsages::UNIFORM);
    let params = storage(
        "cache params",
        &cache_params(cache),
        wgpu::BufferUsages::UNIFORM,
    );
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("cache sampler"),
        mag_filter: wgpu::FilterMode::Linear,
        min_filter: wgpu::FilterMode::Linear,
        ..wgpu::SamplerDescriptor::default()
    });
    // Every cached value fresh (age 0): refresh is off here, and ages are
    // tested through whole runs (`age_never_exceeds_refresh_period_under_motion`).
    let age = harness_texture(
        device,
        size,
        ("previous age", wgpu::TextureFormat::R16Float),
        wgpu::TextureUsages::empty(),
    );
    let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
    let (depth_view, payload_view, target_view) = (view(&depth), view(&payload), view(&target));
    let age_view = view(&age);
    let harness_group = harness_bind_group(device, &pipeline, &case_view, &outcomes, &harness);
    let cache_views = CacheViews {
        params: &params,
        payload: &payload_view,
        depth: &depth_view,
        sampler: &sampler,
        age: &age_view,
    };
    let cache_group = cache_bind_group(device, &pipeline, &cache_views);
    let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
    record_harness(
        &mut encoder,
        (&writer, &writer_group, &depth_view),
        (&pipeline, &harness_group, &cache_group, &target_view),
    );
    encoder.copy_buffer_to_buffer(&outcomes, 0, &readback, 0, outcome_size);
    gpu.queue.submit([encoder.finish()]);
    if let Some(err) = pollster::block_on(scope.pop()) {
        panic!("harness: {err}");
    }
    read_outcomes(gpu, &readback, cases.len(), columns)
}

/// The harness's own group: the cases, the outcomes, the harness
/// parameters.
fn harness_bind_group(
    device: &wgpu::Device,
    pipeline: &wgpu::RenderPipeline,
    case_view: &wgpu::TextureView,
    outcomes: &wgpu::Buffer,
    harness: &wgpu::Buffer,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("harness"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(case_view),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: outcomes.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: harness.as_entire_binding(),
            },
        ],
    })
}

/// What the cache group binds in the harness.
struct CacheViews<'a> {
    params: &'a wgpu::Buffer,
    payload: &'a wgpu::TextureView,
    depth: &'a wgpu::TextureView,
    sampler: &'a wgpu::Sampler,
    age: &'a wgpu::TextureView,
}

/// The cache group: bindings as cache.wgsl declares them (the current
/// payload, unused here, is not in the layout).
fn cache_bind_group(
    device: &wgpu::Device,
    pipeline: &wgpu::RenderPipeline,
    views: &CacheViews,
) -> wgpu::BindGroup {
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("cache"),
        layout: &pipeline.get_bind_group_layout(1),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: views.params.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: wgpu::BindingResource::TextureView(views.payload),
            },
            wgpu::BindGroupEntry {
                binding: 2,
                resource: wgpu::BindingResource::TextureView(views.depth),
            },
            wgpu::BindGroupEntry {
                binding: 4,
                resource: wgpu::BindingResource::Sampler(views.sampler),
            },
            wgpu::BindGroupEntry {
                binding: 5,
                resource: wgpu::BindingResource::TextureView(views.age),
            },
        ],
    })
}

/// Records the depth writer's pass, then the lookups'.
fn record_harness(
    encoder: &mut wgpu::CommandEncoder,
    (writer, writer_group, depth_view): (
        &wgpu::RenderPipeline,
        &wgpu::BindGroup,
        &wgpu::TextureView,
    ),
    (pipeline, harness_group, cache_group, target_view): (
        &wgpu::RenderPipeline,
        &wgpu::BindGroup,
        &wgpu::BindGroup,
        &wgpu::TextureView,
    ),
) {
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("write depth"),
            color_attachments: &[],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            ..wgpu::RenderPassDescriptor::default()
        });
        pass.set_pipeline(writer);
        pass.set_bind_group(0, writer_group, &[]);
        pass.draw(0..3, 0..1);
    }
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("lookups"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: target_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                    store: wgpu::StoreOp::Store,
                },
            })],
            ..wgpu::RenderPassDescriptor::default()
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, harness_group, &[]);
        pass.set_bind_group(1, cache_group, &[]);
        pass.draw(0..3, 0..1);
    }
}

/// A texture of the harness's cache, bound in the lookups.
fn harness_texture(
    device: &wgpu::Device,
    size: wgpu::Extent3d,
    (label, format): (&str, wgpu::TextureFormat),
    usage: wgpu::TextureUsages,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: usage | wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

/// The pass that writes the cache's depths into last frame's depth
/// buffer, and its bindings.
fn depth_writer(device: &wgpu::Device, cache: &Cache) -> (wgpu::RenderPipeline, wgpu::BindGroup) {
    let storage = |label: &str, bytes: &[u8], usage: wgpu::BufferUsages| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents: bytes,
            usage,
        })
    };
    let writer = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("depth writer"),
        source: wgpu::ShaderSource::Wgsl(Cow::Borrowed(DEPTH_WRITER)),
    });
    let writer = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("depth writer"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &writer,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: wgpu::TextureFormat::Depth32Float,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &writer,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[],
        }),
        multiview_mask: None,
        cache: None,
    });
    let depths: Vec<u8> = cache.depth.iter().flat_map(|d| d.to_le_bytes()).collect();
    let depths = storage("depths", &depths, wgpu::BufferUsages::STORAGE);
    let width: Vec<u8> = [cache.size.x, 0, 0, 0]
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let width = storage("width", &width, wgpu::BufferUsages::UNIFORM);
    let writer_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("depth writer"),
        layout: &writer.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: depths.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: width.as_entire_binding(),
            },
        ],
    });
    (writer, writer_group)
}

/// Last frame's payload texture, rgba16float, each texel's depth in its
/// fourth channel when `packed`.
fn previous_payload(gpu: &Gpu, cache: &Cache, size: wgpu::Extent3d, packed: bool) -> wgpu::Texture {
    let payload = harness_texture(
        &gpu.device,
        size,
        ("previous payload", wgpu::TextureFormat::Rgba16Float),
        wgpu::TextureUsages::COPY_DST,
    );
    let texels: Vec<u8> = cache
        .payload
        .iter()
        .zip(&cache.depth)
        // Standard Z: the far plane at depth 1 (`CacheParams.far_depth`).
        .map(|(p, d)| {
            if packed {
                p.truncate().extend(d - 1.0)
            } else {
                *p
            }
        })
        .flat_map(|p| p.to_array())
        .flat_map(|v| half::f16::from_f32(v).to_le_bytes())
        .collect();
    gpu.queue.write_texture(
        payload.as_image_copy(),
        &texels,
        wgpu::TexelCopyBufferLayout {
            offset: 0,
            bytes_per_row: Some(cache.size.x * 8),
            rows_per_image: Some(cache.size.y),
        },
        size,
    );
    payload
}

/// The lookups' pipeline: the cache helpers and the harness, the packed
/// lookups in place of the others when `packed`.
fn lookup_pipeline(device: &wgpu::Device, packed: bool) -> wgpu::RenderPipeline {
    let helpers = std::fs::read_to_string(super::util::root().join("shaders/cache.wgsl")).unwrap();
    let harness = if packed {
        HARNESS
            .replace("cache_lookup(clip)", "cache_lookup_packed(clip)")
            .replace(
                "cache_lookup_loads(clip)",
                "cache_lookup_loads_packed(clip)",
            )
            .replace(
                "cache_lookup_nearest(clip)",
                "cache_lookup_nearest_packed(clip)",
            )
    } else {
        HARNESS.to_string()
    };
    let lookup_module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("harness"),
        source: wgpu::ShaderSource::Wgsl(Cow::Owned(format!("{helpers}\n{harness}"))),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("harness"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &lookup_module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: None,
        multisample: wgpu::MultisampleState::default(),
        fragment: Some(wgpu::FragmentState {
            module: &lookup_module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::TextureFormat::Rgba8Unorm.into())],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The cases, two rgba32uint texels each (clip position; slope, zoom,
/// roll), `columns` to a row.
fn cases_texture(gpu: &Gpu, cases: &[Case], (columns, rows): (u32, u32)) -> wgpu::Texture {
    let case_bytes: Vec<u8> = cases
        .iter()
        .flat_map(|c| {
            [c.clip.to_array(), [c.slope.x, c.slope.y, c.zoom, c.roll]]
                .into_iter()
                .flatten()
        })
        .flat_map(|v: f32| v.to_le_bytes())
        .collect();
    let mut case_bytes = case_bytes;
    case_bytes.resize((columns * rows * 32) as usize, 0);
    gpu.device.create_texture_with_data(
        &gpu.queue,
        &wgpu::TextureDescriptor {
            label: Some("cases"),
            size: wgpu::Extent3d {
                width: columns * 2,
                height: rows,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format: wgpu::TextureFormat::Rgba32Uint,
            usage: wgpu::TextureUsages::TEXTURE_BINDING,
            view_formats: &[],
        },
        wgpu::util::TextureDataOrder::LayerMajor,
        &case_bytes,
    )
}

/// `CacheParams` as the runner fills it for the harness's cache.
fn cache_params(cache: &Cache) -> Vec<u8> {
    let mut params = Vec::new();
    params.extend((cache.size.x as f32).to_le_bytes());
    params.extend((cache.size.y as f32).to_le_bytes());
    params.extend(cache.epsilon.to_le_bytes());
    for value in [0u32, 0, 1, 0] {
        // refresh phase, period (off), quad, frame
        params.extend(value.to_le_bytes());
    }
    params.extend(65504.0f32.to_le_bytes());
    // far depth (standard Z); lowres's knobs and depth range (unused
    // here), up to the vec2 alignment of the viewport's origin.
    params.extend(1.0f32.to_le_bytes());
    params.resize(56, 0);
    // The viewport is the whole target: its origin, the target's size.
    params.extend([0.0f32, 0.0].iter().flat_map(|v| v.to_le_bytes()));
    params.extend((cache.size.x as f32).to_le_bytes());
    params.extend((cache.size.y as f32).to_le_bytes());
    params
}

/// The outcome of each case, read back from the lookups' buffer.
fn read_outcomes(gpu: &Gpu, readback: &wgpu::Buffer, cases: usize, columns: u32) -> Vec<Outcome> {
    let slice = readback.slice(..);
    slice.map_async(wgpu::MapMode::Read, |_| {});
    gpu.device
        .poll(wgpu::PollType::wait_indefinitely())
        .unwrap();
    let data = slice.get_mapped_range().unwrap();
    let floats: Vec<f32> = data
        .chunks_exact(4)
        .map(|b| f32::from_le_bytes(b.try_into().unwrap()))
        .collect();
    let outcomes: Vec<&[f32]> = floats.chunks_exact(20).collect();
    (0..cases)
        .map(|i| {
            let (x, y) = (i as u32 % columns * 2, i as u32 / columns * 2);
            let o = outcomes[(y * columns * 2 + x) as usize];
            let v = |i: usize| Vec4::from_slice(&o[i * 4..i * 4 + 4]);
            let status = v(0);
            Outcome {
                bilinear: Lookup {
                    status: status_of(status.x),
                    payload: v(1),
                },
                loads: Lookup {
                    status: status_of(status.y),
                    payload: v(2),
                },
                nearest: Lookup {
                    status: status_of(status.z),
                    payload: v(3),
                },
                footprint_status: status_of(status.w),
                base: v(4).truncate().truncate(),
                fraction: Vec2::new(v(4).z, v(4).w),
            }
        })
        .collect()
}

/// The CPU mirror's decisions for a case: footprint, nearest.
fn cpu(cache: &Cache, case: &Case) -> (Status, Status) {
    let previous = cache.previous();
    (
        reprojection::footprint(case.clip, case.mirrored_slope(), &previous).status,
        reprojection::nearest(case.clip, case.mirrored_slope(), &previous).0,
    )
}

/// Every lookup of every case decided as the CPU mirror decides: the
/// bilinear and loads lookups as `footprint`, nearest as `nearest`; and,
/// on screen, the same footprint.
fn assert_cpu_agrees(cache: &Cache, cases: &[Case], outcomes: &[Outcome]) {
    for (case, outcome) in cases.iter().zip(outcomes) {
        let (footprint, nearest) = cpu(cache, case);
        if footprint != Status::Offscreen {
            let mirror =
                reprojection::footprint(case.clip, case.mirrored_slope(), &cache.previous());
            assert_eq!(outcome.base, mirror.base, "{case:?}: {outcome:?}");
            assert!(
                (outcome.fraction - mirror.fraction).abs().max_element() < 1e-4,
                "{case:?}: {outcome:?}"
            );
        }
        assert_eq!(
            [
                outcome.footprint_status,
                outcome.bilinear.status,
                outcome.loads.status,
                outcome.nearest.status
            ],
            [
                footprint.code(),
                footprint.code(),
                footprint.code(),
                nearest.code()
            ],
            "GPU and CPU disagree on {case:?}: {outcome:?}"
        );
    }
}

/// A flat 16×16 cache at depth 0.5 holding one payload everywhere.
fn flat_cache() -> Cache {
    Cache::from_fn(UVec2::new(16, 16), 1e-3, |_| {
        (0.5, Vec4::new(0.25, 0.5, 0.75, 1.0))
    })
}

/// Previous clip w ≤ 0 (w = 0, -0.0, negative) or NaN: off-screen (status
/// 1) for all three lookups, never the wrapped-around hit a negative w gives.
#[test]
fn behind_previous_camera() {
    // Dividing by a negative w lands the point on a texel whose depth
    // agrees: without the `w > 0` test that is a false hit.
    let Some(gpu) = super::gpu::gpu() else { return };
    let cache = flat_cache();
    let behind = |x: f32, y: f32, w: f32| Case {
        clip: cache.clip_at(Vec2::new(x, y), 0.5, w),
        slope: Vec2::ZERO,
        ..Case::default()
    };
    let clip = |x: f32, y: f32, z: f32, w: f32| Case {
        clip: Vec4::new(x, y, z, w),
        slope: Vec2::ZERO,
        ..Case::default()
    };
    let nan = f32::NAN;
    let cases = [
        // Negative w whose NDC lands on texel centres, between texels, on
        // the edges: the mirrored point would hit.
        behind(5.0, 7.0, -1.0),
        behind(5.5, 7.25, -1.0),
        behind(8.3, 2.9, -2.5),
        behind(0.0, 0.0, -1.0),
        behind(15.0, 15.0, -4.0),
        behind(3.0, 3.0, -1e-3),
        behind(12.0, 4.0, -1e-30),
        // On the camera's plane: w = 0 and w = -0.0, any xyz.
        clip(0.3, -0.2, 0.5, 0.0),
        clip(0.0, 0.0, 0.0, 0.0),
        clip(0.0, 0.0, 0.5, 0.0),
        clip(-0.3, 0.2, -0.5, -0.0),
        clip(0.0, 0.0, 0.0, -0.0),
        // NaN anywhere.
        clip(nan, nan, nan, nan),
        clip(0.1, 0.1, 0.5, nan),
        clip(nan, 0.1, 0.5, 1.0),
        clip(0.1, nan, 0.5, 1.0),
    ];
    let outcomes = lookups(&gpu, &cache, &cases);
    for (case, outcome) in cases.iter().zip(&outcomes) {
        for lookup in [outcome.bilinear, outcome.loads, outcome.nearest] {
            assert_eq!(lookup.status, 1, "{case:?}: {outcome:?}");
        }
    }
    assert_cpu_agrees(&cache, &cases, &outcomes);

    // A NaN depth alone, in front of the camera and inside the viewport,
    // cannot be compared: disoccluded (status 2), a miss too.
    let unknown_depth = [clip(0.1, 0.1, nan, 1.0)];
    let outcomes = lookups(&gpu, &cache, &unknown_depth);
    for lookup in [outcomes[0].bilinear, outcomes[0].loads, outcomes[0].nearest] {
        assert_eq!(lookup.status, 2, "{:?}", outcomes[0]);
    }
    assert_cpu_agrees(&cache, &unknown_depth, &outcomes);

    // The same points in front of the camera (w > 0) hit: only the sign
    // of w tells them apart.
    let mirrored: Vec<Case> = cases[..7]
        .iter()
        .map(|c| Case {
            clip: -c.clip,
            ..*c
        })
        .collect();
    let outcomes = lookups(&gpu, &cache, &mirrored);
    for (case, outcome) in mirrored.iter().zip(&outcomes) {
        for lookup in [outcome.bilinear, outcome.loads, outcome.nearest] {
            assert_eq!(lookup.status, 0, "{case:?}: {outcome:?}");
            assert!(
                (lookup.payload - cache.payload[0]).abs().max_element() < 1e-3,
                "{case:?}: {outcome:?}"
            );
        }
    }
    assert_cpu_agrees(&cache, &mirrored, &outcomes);
}

/// A sloped 16×16 cache: depth rises by 0.01 a texel along x and 0.005
/// along y (a surface at an angle), and the payload holds the texel's own
/// coordinates, so a lookup's payload tells where it read.
fn sloped_cache() -> Cache {
    Cache::from_fn(UVec2::new(16, 16), 1e-3, |t| {
        let t = t.as_vec2();
        (sloped_depth(t), Vec4::new(t.x, t.y, 0.0, 1.0))
    })
}

fn sloped_depth(texel: Vec2) -> f32 {
    0.4 + 0.01 * texel.x + 0.005 * texel.y
}

/// The slope of a sloped surface under a zoom and a roll, in the harness:
/// a point of the sloped cache's plane, seen through a mapping from this
/// frame's pixels to last frame's texels that scales by 0.7–1.6 and turns
/// by up to 60°, hits for every lookup, and the CPU mirror takes the slope
/// back through the mapping to the same decisions. With the slope per
/// pixel applied to the offsets in texels (`cache_previous_slope`
/// returning its fallback), the steepest of these miss as disoccluded.
#[test]
fn sloped_surface_under_zoom_and_roll() {
    let Some(gpu) = super::gpu::gpu() else { return };
    let mut cache = sloped_cache();
    // A steeper plane, so that a wrongly turned slope shows.
    cache.depth = (0..256)
        .map(|i| {
            let t = Vec2::new((i % 16) as f32, (i / 16) as f32);
            0.3 + 0.03 * t.x + 0.01 * t.y
        })
        .collect();
    let mut cases = Vec::new();
    for (zoom, roll) in [
        (0.0, 0.0),
        (-0.3, 0.4),
        (0.6, -1.0),
        (0.3, 1.05),
        (-0.2, -0.6),
    ] {
        for texel in [
            Vec2::new(4.3, 5.6),
            Vec2::new(9.5, 7.25),
            Vec2::new(11.0, 10.0),
        ] {
            let depth = 0.3 + 0.03 * texel.x + 0.01 * texel.y;
            cases.push(Case {
                clip: cache.clip_at(texel, depth, 1.0),
                slope: Vec2::new(0.03, 0.01),
                zoom,
                roll,
            });
        }
    }
    let outcomes = lookups(&gpu, &cache, &cases);
    for (case, outcome) in cases.iter().zip(&outcomes) {
        assert_eq!(
            [
                outcome.bilinear.status,
                outcome.loads.status,
                outcome.nearest.status
            ],
            [0, 0, 0],
            "{case:?}: {outcome:?}"
        );
    }
    assert_cpu_agrees(&cache, &cases, &outcomes);
}

/// What a case must give: the footprint lookups' status, nearest's.
struct Expected {
    texel: Vec2,
    footprint: u32,
    nearest: u32,
}

/// Point or bilinear footprint outside the viewport (taps outside weighing
/// ≥ 0.001): off-screen; exactly on an edge texel's centre: a hit on it.
#[test]
fn offscreen_reprojection() {
    // Points just outside each edge miss for every lookup; a point inside
    // the viewport whose footprint has taps outside it weighing ≥ 0.001
    // misses for the bilinear lookups (nearest reads its own texel and
    // hits); a point exactly on an edge texel's centre, or within 0.0005
    // texel of it, hits: its outside taps weigh < 0.001 and are ignored,
    // and it reads the edge texel itself.
    let Some(gpu) = super::gpu::gpu() else { return };
    let last = 15.0;
    let expect = |x: f32, y: f32, footprint: u32, nearest: u32| Expected {
        texel: Vec2::new(x, y),
        footprint,
        nearest,
    };
    let expected = [
        // Just outside each edge and corner (0.1 px beyond it).
        expect(-0.6, 8.0, 1, 1),
        expect(last + 0.6, 8.0, 1, 1),
        expect(8.0, -0.6, 1, 1),
        expect(8.0, last + 0.6, 1, 1),
        expect(-0.6, -0.6, 1, 1),
        expect(last + 0.6, last + 0.6, 1, 1),
        // Far outside.
        expect(-40.0, 8.0, 1, 1),
        expect(8.0, 1e6, 1, 1),
        // Inside the viewport, but the footprint's outside taps weigh 0.3
        // or 0.002: the bilinear lookups miss, nearest hits.
        expect(-0.3, 8.0, 1, 0),
        expect(last + 0.3, 8.0, 1, 0),
        expect(8.0, -0.3, 1, 0),
        expect(8.0, last + 0.3, 1, 0),
        expect(-0.002, 8.0, 1, 0),
        expect(last + 0.002, 8.0, 1, 0),
        expect(8.0, last + 0.002, 1, 0),
        // The outside taps weigh 0.0005 (within the 0.001 slack): hit.
        expect(-0.0005, 8.0, 0, 0),
        expect(last + 0.0005, 8.0, 0, 0),
        expect(8.0, last + 0.0005, 0, 0),
        // Exactly on edge and corner texel centres: hit.
        expect(0.0, 8.0, 0, 0),
        expect(last, 8.0, 0, 0),
        expect(8.0, 0.0, 0, 0),
        expect(8.0, last, 0, 0),
        expect(0.0, 0.0, 0, 0),
        expect(last, last, 0, 0),
        expect(last, 0.0, 0, 0),
        // Inside, for comparison.
        expect(8.4, 7.7, 0, 0),
        expect(1.0, 14.5, 0, 0),
    ];
    // On a flat cache every tap agrees, so only the viewport test makes
    // the off-screen points miss; on the sloped one an edge texel read in
    // place of an outside tap disagrees with that tap's expected depth, so
    // only the weight test lets the edge texel centres hit.
    for (name, cache, depth) in [
        ("flat", flat_cache(), (|_| 0.5) as fn(Vec2) -> f32),
        ("sloped", sloped_cache(), sloped_depth),
    ] {
        let slope = if name == "flat" {
            Vec2::ZERO
        } else {
            Vec2::new(0.01, 0.005)
        };
        let cases: Vec<Case> = expected
            .iter()
            .flat_map(|e| {
                // w = 1 and w = 2: exact divisions, edge positions exact.
                [1.0, 2.0].map(|w| Case {
                    clip: cache.clip_at(e.texel, depth(e.texel), w),
                    slope,
                    ..Case::default()
                })
            })
            .collect();
        let outcomes = lookups(&gpu, &cache, &cases);
        for ((e, case), outcome) in expected
            .iter()
            .flat_map(|e| [e, e])
            .zip(&cases)
            .zip(&outcomes)
        {
            let what = format!(
                "{name} cache, texel {} (w = {}): {outcome:?}",
                e.texel, case.clip.w
            );
            assert_eq!(outcome.bilinear.status, e.footprint, "bilinear, {what}");
            assert_eq!(outcome.loads.status, e.footprint, "loads, {what}");
            assert_eq!(outcome.nearest.status, e.nearest, "nearest, {what}");
            // A hit reads where the point is: the edge texel itself on an
            // edge (the sloped cache's payload is the texel coordinate).
            let clamped = e.texel.clamp(Vec2::ZERO, Vec2::splat(last));
            if name == "sloped" && e.footprint == 0 {
                for lookup in [outcome.bilinear, outcome.loads] {
                    let read = lookup.payload.truncate().truncate();
                    assert!((read - clamped).abs().max_element() < 0.01, "{what}");
                }
            }
            if name == "sloped" && e.nearest == 0 {
                let read = outcome.nearest.payload.truncate().truncate();
                assert_eq!(read, (e.texel + Vec2::splat(0.5)).floor(), "{what}");
            }
        }
        assert_cpu_agrees(&cache, &cases, &outcomes);
    }
}

/// A 16×16 cache with a silhouette down the middle: a foreground surface
/// (depth 0.3, sloping by 0.004 a texel along x) left of x = 8 and a flat
/// background at 0.9 right of it. Payload x is the material: 0 foreground,
/// 1 background.
fn silhouette_cache() -> Cache {
    Cache::from_fn(UVec2::new(16, 16), 1e-3, |t| {
        let (depth, material) = silhouette(t.as_vec2());
        (depth, Vec4::new(material, 0.0, 0.0, 1.0))
    })
}

/// The surface at a texel coordinate of the silhouette cache: depth and
/// material; a point belongs to the foreground when its nearest texel does.
fn silhouette(texel: Vec2) -> (f32, f32) {
    if texel.x < 7.5 {
        (0.3 + 0.004 * texel.x, 0.0)
    } else {
        (0.9, 1.0)
    }
}

/// Lookups of points of the silhouette cache's scene, each at a texel
/// coordinate on a surface: material 0 the sloped foreground, 1 the
/// background, anything else a surface at depth 0.6 that was not there.
fn silhouette_cases(cache: &Cache, points: impl Iterator<Item = (Vec2, f32)>) -> Vec<Case> {
    points
        .map(|(texel, material)| {
            let (depth, slope) = match material {
                0.0 => (0.3 + 0.004 * texel.x, 0.004),
                1.0 => (0.9, 0.0),
                _ => (0.6, 0.0),
            };
            Case {
                clip: cache.clip_at(texel, depth, 1.0),
                slope: Vec2::new(slope, 0.0),
                ..Case::default()
            }
        })
        .collect()
}

/// A bilinear footprint straddling a depth step (0.3 against 0.9) misses:
/// nothing blends across it; nearest hits where its own texel agrees.
#[test]
fn depth_discontinuity() {
    // At a contact, two surfaces meeting with no depth step, the depth
    // test cannot tell them apart: see
    // `depth_discontinuity_at_contact_points` for the measured bound.
    let Some(gpu) = super::gpu::gpu() else { return };
    let cache = silhouette_cache();
    // (texel, the point's material: 0 foreground, 1 background,
    // footprint status, nearest status)
    let expected = [
        // Well inside either side: everything hits.
        (Vec2::new(3.5, 4.5), 0.0, 0, 0),
        (Vec2::new(12.2, 9.9), 1.0, 0, 0),
        // Foreground points whose footprint reaches the background with
        // weight 0.3, 0.5, 0.002: bilinear misses; nearest's own texel (7)
        // is foreground and hits.
        (Vec2::new(7.3, 4.0), 0.0, 2, 0),
        (Vec2::new(7.3, 4.6), 0.0, 2, 0),
        (Vec2::new(7.002, 4.0), 0.0, 2, 0),
        // The background tap weighs 0.0005: ignored, a hit.
        (Vec2::new(7.0005, 4.0), 0.0, 0, 0),
        // A foreground point (one that moved) whose nearest texel is
        // background: both miss.
        (Vec2::new(7.6, 4.0), 0.0, 2, 2),
        // Background points reaching the foreground: bilinear misses,
        // nearest (texel 8) hits, unless its texel is foreground.
        (Vec2::new(7.7, 4.0), 1.0, 2, 0),
        (Vec2::new(7.5, 11.25), 1.0, 2, 0),
        (Vec2::new(7.998, 4.0), 1.0, 2, 0),
        (Vec2::new(7.9995, 4.0), 1.0, 0, 0),
        (Vec2::new(7.3, 4.0), 1.0, 2, 2),
        // A point at neither depth misses everywhere.
        (Vec2::new(3.5, 4.5), 0.5, 2, 2),
    ];
    let cases = silhouette_cases(&cache, expected.iter().map(|e| (e.0, e.1)));
    let outcomes = lookups(&gpu, &cache, &cases);
    for ((&(texel, material, footprint, nearest), case), outcome) in
        expected.iter().zip(&cases).zip(&outcomes)
    {
        let what = format!("texel {texel}, material {material}: {case:?} {outcome:?}");
        assert_eq!(outcome.bilinear.status, footprint, "bilinear, {what}");
        assert_eq!(outcome.loads.status, footprint, "loads, {what}");
        assert_eq!(outcome.nearest.status, nearest, "nearest, {what}");
        // A hit's material is the point's own: nothing blended across.
        for lookup in [outcome.bilinear, outcome.loads, outcome.nearest] {
            if lookup.status == 0 {
                assert!((lookup.payload.x - material).abs() < 0.002, "{what}");
            }
        }
    }
    assert_cpu_agrees(&cache, &cases, &outcomes);
}

/// The packed lookups keep the depth in the payload's fourth channel.
/// They share the off-screen test with the separate ones (behind the
/// previous camera, outside the viewport), nearest-packed decides exactly
/// as nearest, and bilinear-packed tests the depth filtered at the point:
/// a footprint straddling a silhouette misses unless the far side weighs
/// under ε·|e − far|/|Δd| — which, unlike the separate test's fixed 0.001
/// weight, is tighter next to a surface near the far plane.
#[test]
fn packed_lookups_behind_offscreen_and_at_silhouettes() {
    let Some(gpu) = super::gpu::gpu() else { return };
    let statuses = |o: &Outcome| [o.bilinear.status, o.loads.status, o.nearest.status];

    // Behind the previous camera or NaN: off-screen; the mirrored points
    // in front hit and read the payload.
    let flat = flat_cache();
    let mut cases = Vec::new();
    for (x, y, w) in [(5.0, 7.0, -1.0), (8.3, 2.9, -2.5), (3.0, 3.0, -1e-3)] {
        cases.push(Case {
            clip: flat.clip_at(Vec2::new(x, y), 0.5, w),
            slope: Vec2::ZERO,
            ..Case::default()
        });
    }
    for clip in [
        Vec4::new(0.0, 0.0, 0.5, 0.0),
        Vec4::new(0.0, 0.0, 0.5, -0.0),
        Vec4::new(0.1, 0.1, 0.5, f32::NAN),
        Vec4::new(f32::NAN, 0.1, 0.5, 1.0),
    ] {
        cases.push(Case {
            clip,
            slope: Vec2::ZERO,
            ..Case::default()
        });
    }
    for outcome in packed_lookups(&gpu, &flat, &cases) {
        assert_eq!(statuses(&outcome), [1, 1, 1], "{outcome:?}");
    }
    let mirrored: Vec<Case> = cases[..3]
        .iter()
        .map(|c| Case {
            clip: -c.clip,
            ..*c
        })
        .collect();
    for outcome in packed_lookups(&gpu, &flat, &mirrored) {
        assert_eq!(statuses(&outcome), [0, 0, 0], "{outcome:?}");
        for lookup in [outcome.bilinear, outcome.loads, outcome.nearest] {
            let read = lookup.payload.truncate();
            assert!((read - flat.payload[0].truncate()).abs().max_element() < 1e-3);
        }
    }

    // Leaving the viewport, on the sloped cache: bilinear-packed is
    // off-screen exactly where the separate footprint is, and hits on the
    // edge texel centres; nearest-packed decides as nearest.
    let sloped = sloped_cache();
    let cases: Vec<Case> = [
        (-0.6, 8.0),
        (15.6, 8.0),
        (8.0, -0.3),
        (8.0, 15.3),
        (-0.002, 8.0),
        (-0.0005, 8.0),
        (0.0, 8.0),
        (15.0, 15.0),
        (8.0, 0.0),
        (8.4, 7.7),
    ]
    .iter()
    .map(|&(x, y)| {
        let texel = Vec2::new(x, y);
        Case {
            clip: sloped.clip_at(texel, sloped_depth(texel), 1.0),
            slope: Vec2::new(0.01, 0.005),
            ..Case::default()
        }
    })
    .collect();
    let separate = lookups(&gpu, &sloped, &cases);
    let packed = packed_lookups(&gpu, &sloped, &cases);
    for ((case, separate), packed) in cases.iter().zip(&separate).zip(&packed) {
        let what = format!("{case:?}: separate {separate:?}, packed {packed:?}");
        let offscreen = u32::from(separate.footprint_status == 1);
        assert_eq!(packed.bilinear.status, offscreen, "{what}");
        assert_eq!(packed.loads.status, offscreen, "{what}");
        assert_eq!(packed.nearest.status, separate.nearest.status, "{what}");
    }

    // At the silhouette (foreground 0.3 + 0.004 x left of x = 8, background
    // 0.9 right of it): (texel, material, bilinear-packed status).
    let cache = silhouette_cache();
    let expected = [
        (Vec2::new(3.5, 4.5), 0.0, 0),
        (Vec2::new(12.2, 9.9), 1.0, 0),
        // The background weighs 0.3, 0.3, 0.002: the filtered depth is off
        // by 0.17, 0.17, 0.0011 against a tolerance of 0.00067.
        (Vec2::new(7.3, 4.0), 0.0, 2),
        (Vec2::new(7.3, 4.6), 0.0, 2),
        (Vec2::new(7.002, 4.0), 0.0, 2),
        // 0.0005: off by 0.0003, a hit reading 0.0005 of the background.
        (Vec2::new(7.0005, 4.0), 0.0, 0),
        (Vec2::new(7.6, 4.0), 0.0, 2),
        (Vec2::new(7.7, 4.0), 1.0, 2),
        (Vec2::new(7.5, 11.25), 1.0, 2),
        (Vec2::new(7.998, 4.0), 1.0, 2),
        // The foreground weighs 0.0005: off by 0.0003, but the background
        // is 0.1 from the far plane, so the tolerance is 0.0001: a miss
        // (the separate test ignores the tap and hits).
        (Vec2::new(7.9995, 4.0), 1.0, 2),
        (Vec2::new(7.3, 4.0), 1.0, 2),
        (Vec2::new(3.5, 4.5), 0.5, 2),
    ];
    let cases = silhouette_cases(&cache, expected.iter().map(|e| (e.0, e.1)));
    let separate = lookups(&gpu, &cache, &cases);
    let packed = packed_lookups(&gpu, &cache, &cases);
    for (((&(texel, material, status), case), separate), packed) in
        expected.iter().zip(&cases).zip(&separate).zip(&packed)
    {
        let what = format!("texel {texel}, material {material}: {case:?} {packed:?}");
        assert_eq!(packed.bilinear.status, status, "bilinear-packed, {what}");
        assert_eq!(packed.loads.status, status, "loads-packed, {what}");
        assert_eq!(
            packed.nearest.status, separate.nearest.status,
            "nearest-packed, {what}"
        );
        for lookup in [packed.bilinear, packed.loads, packed.nearest] {
            if lookup.status == 0 {
                assert!((lookup.payload.x - material).abs() < 0.002, "{what}");
            }
        }
    }
}

/// A floor (y = 0) and a unit box resting on it, ray cast at pixel
/// centres: the scene of a contact. The camera is still; the box slides
/// back and sideways between the frames.
struct ContactScene {
    size: u32,
    clip_from_world: DMat4,
    eye: DVec3,
    /// The box's minimum corner last frame and this frame.
    previous_box: DVec3,
    current_box: DVec3,
}

/// What a ray hits: the floor, or a face of the box (axis, side), and
/// where.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Surface {
    Floor,
    Face(usize, bool),
}

impl Surface {
    fn material(self) -> f32 {
        match self {
            Surface::Floor => 0.0,
            Surface::Face(..) => 1.0,
        }
    }
}

impl ContactScene {
    fn new() -> ContactScene {
        let eye = DVec3::new(0.6, 2.4, 3.4);
        let clip_from_world = DMat4::perspective_rh(45f64.to_radians(), 1.0, 0.5, 20.0)
            * DMat4::look_at_rh(eye, DVec3::new(0.0, 0.3, 0.0), DVec3::Y);
        let previous_box = DVec3::new(-0.5, 0.0, -0.5);
        ContactScene {
            size: 64,
            clip_from_world,
            eye,
            previous_box,
            current_box: previous_box + DVec3::new(0.12, 0.0, -0.2),
        }
    }

    /// The direction of the ray through a framebuffer position.
    fn ray(&self, position: DVec2) -> DVec3 {
        let s = self.size as f64;
        let ndc = DVec4::new(
            position.x / s * 2.0 - 1.0,
            1.0 - position.y / s * 2.0,
            1.0,
            1.0,
        );
        let far = self.clip_from_world.inverse() * ndc;
        far.truncate() / far.w - self.eye
    }

    /// The nearest surface along a ray (t > 0), with the box at `corner`.
    fn cast(&self, direction: DVec3, corner: DVec3) -> Option<(f64, Surface)> {
        let mut best: Option<(f64, Surface)> = None;
        if direction.y < 0.0 {
            best = Some((-self.eye.y / direction.y, Surface::Floor));
        }
        let (mut enter, mut exit, mut face) = (f64::NEG_INFINITY, f64::INFINITY, Surface::Floor);
        for axis in 0..3 {
            let (o, d) = (self.eye[axis], direction[axis]);
            let (low, high) = (corner[axis], corner[axis] + 1.0);
            if d.abs() < 1e-12 {
                if o < low || o > high {
                    return best;
                }
                continue;
            }
            let (t0, t1) = ((low - o) / d, (high - o) / d);
            let near = t0.min(t1);
            if near > enter {
                enter = near;
                face = Surface::Face(axis, t0 > t1);
            }
            exit = exit.min(t0.max(t1));
        }
        if enter <= exit && enter > 0.0 && best.is_none_or(|(t, _)| enter < t) {
            best = Some((enter, face));
        }
        best
    }

    /// Where a ray meets a surface's plane, the box at `corner`.
    fn on_plane(&self, direction: DVec3, surface: Surface, corner: DVec3) -> DVec3 {
        let (axis, value) = match surface {
            Surface::Floor => (1, 0.0),
            Surface::Face(axis, high) => (axis, corner[axis] + if high { 1.0 } else { 0.0 }),
        };
        self.eye + direction * ((value - self.eye[axis]) / direction[axis])
    }

    fn ndc(&self, point: DVec3) -> DVec3 {
        let clip = self.clip_from_world * point.extend(1.0);
        clip.truncate() / clip.w
    }

    /// Last frame's world position of a point on `surface` now.
    fn previous_of(&self, point: DVec3, surface: Surface) -> DVec3 {
        match surface {
            Surface::Floor => point,
            Surface::Face(..) => point - (self.current_box - self.previous_box),
        }
    }

    /// Last frame's frame as the cache holds it (depth 1 and material 2
    /// where no surface is), with each texel's surface point.
    fn previous_frame(&self) -> (Cache, Vec<Option<DVec3>>) {
        let mut points = Vec::new();
        // ε relative, as the shader's: ε·|e − 1| at the box's distance is
        // about the absolute 1e-3 this case was first measured with.
        let cache = Cache::from_fn(UVec2::splat(self.size), 1e-2, |t| {
            let direction = self.ray(t.as_dvec2() + 0.5);
            match self.cast(direction, self.previous_box) {
                Some((t, surface)) => {
                    let point = self.eye + direction * t;
                    points.push(Some(point));
                    let depth = self.ndc(point).z as f32;
                    (depth, Vec4::new(surface.material(), 0.0, 0.0, 1.0))
                }
                None => {
                    points.push(None);
                    (1.0, Vec4::new(2.0, 0.0, 0.0, 1.0))
                }
            }
        });
        (cache, points)
    }
}

/// How the lookups fared on the pixels of the contact scene that were
/// hidden last frame (uncovered this frame, so they must miss).
#[derive(Debug, Default)]
struct ContactStats {
    /// Pixels seen in both frames, and those of them that hit.
    visible: usize,
    visible_hits: usize,
    /// Pixels hidden last frame, and those of them that hit anyway.
    uncovered: usize,
    false_hits: usize,
    /// The largest world distance, over false hits, between the point and
    /// a surface point the lookup read (a weighty tap's).
    farthest: f64,
    /// The largest error of the material read, over false hits.
    material_error: f32,
}

/// Contact points (seed 001, fig. 3): floor uncovered next to a sliding box
/// may falsely hit, but only ≤ 10% of it, reading points ≤ 0.03 units away.
#[test]
fn depth_discontinuity_at_contact_points() {
    // A box resting on the floor slides away from the camera (and
    // sideways), uncovering floor along its bottom edge and beside it.
    // Where the box's face met the floor there is no depth step, so the
    // depth test cannot tell them apart: uncovered floor pixels next to
    // last frame's contact line falsely hit and read the box's payload (a
    // wrong material: the full payload difference). The bound, measured at
    // 64×64 with a relative ε = 1e-2 and the box 3.8 units from the eye
    // (near 0.5, far 20): every false hit reads surface points within 0.03
    // world units of its own point, the depth-test limit ε·z·(f − z)/f at
    // that distance, so it happens only where surfaces touch, never across a
    // depth step, and a payload continuous across the contact is off by at
    // most its world-space gradient × 0.03; false hits are at most 10% of
    // the uncovered pixels (measured: 6 of 135, for both reconstructions);
    // and there are some (the depth test alone cannot see contacts:
    // material ids would, as in the seed). Pixels seen in both frames hit
    // (≥ 95%).
    let Some(gpu) = super::gpu::gpu() else { return };
    let scene = ContactScene::new();
    let (cache, previous_points) = scene.previous_frame();
    let size = scene.size as usize;
    let mut cases = Vec::new();
    let mut truth = Vec::new();
    for y in 0..size {
        for x in 0..size {
            let pixel = DVec2::new(x as f64 + 0.5, y as f64 + 0.5);
            let direction = scene.ray(pixel);
            let Some((t, surface)) = scene.cast(direction, scene.current_box) else {
                continue;
            };
            let point = scene.eye + direction * t;
            let previous = scene.previous_of(point, surface);
            let depth = scene.ndc(previous).z;
            // The slope of the previous depth across this frame's pixels,
            // on the surface's plane, as the rasteriser's derivatives.
            let slope = |step: DVec2| {
                let next = scene.on_plane(scene.ray(pixel + step), surface, scene.current_box);
                (scene.ndc(scene.previous_of(next, surface)).z - depth) as f32
            };
            // Hidden last frame when the ray to its previous position
            // meets something else first.
            let seen = scene
                .cast(previous - scene.eye, scene.previous_box)
                .is_some_and(|(t, _)| t > 1.0 - 1e-9);
            cases.push(Case {
                clip: (scene.clip_from_world * previous.extend(1.0)).as_vec4(),
                slope: Vec2::new(slope(DVec2::X), slope(DVec2::Y)),
                ..Case::default()
            });
            truth.push((surface, previous, seen));
        }
    }
    let outcomes = lookups(&gpu, &cache, &cases);
    let footprint_stats = |nearest: bool| {
        let mut stats = ContactStats::default();
        for ((case, &(surface, previous, seen)), outcome) in cases.iter().zip(&truth).zip(&outcomes)
        {
            let lookup = if nearest {
                outcome.nearest
            } else {
                outcome.bilinear
            };
            let hit = lookup.status == 0;
            if seen {
                stats.visible += 1;
                stats.visible_hits += usize::from(hit);
                continue;
            }
            stats.uncovered += 1;
            if !hit {
                continue;
            }
            stats.false_hits += 1;
            let taps: Vec<IVec2> = if nearest {
                vec![reprojection::nearest(case.clip, case.mirrored_slope(), &cache.previous()).1]
            } else {
                reprojection::footprint(case.clip, case.mirrored_slope(), &cache.previous())
                    .taps()
                    .iter()
                    .filter(|(_, weight)| *weight >= reprojection::NEGLIGIBLE_WEIGHT)
                    .map(|(t, _)| *t)
                    .collect()
            };
            for tap in taps {
                let read = previous_points[(tap.y as usize) * size + tap.x as usize]
                    .expect("a false hit reads a surface");
                stats.farthest = stats.farthest.max((read - previous).length());
            }
            stats.material_error = stats
                .material_error
                .max((lookup.payload.x - surface.material()).abs());
        }
        stats
    };
    let bilinear = footprint_stats(false);
    let nearest = footprint_stats(true);
    for (name, stats) in [("bilinear", &bilinear), ("nearest", &nearest)] {
        assert!(stats.uncovered > 100, "{name}: {stats:?}");
        assert!(
            stats.false_hits > 0,
            "{name}: no false hit at the contact; if the cache now tells surfaces apart \
             (material ids), this test's bound should say so: {stats:?}"
        );
        assert!(stats.farthest < 0.03, "{name}: {stats:?}");
        assert!(
            stats.false_hits * 10 <= stats.uncovered,
            "{name}: {stats:?}"
        );
        assert!(
            stats.visible_hits * 100 >= stats.visible * 95,
            "{name}: {stats:?}"
        );
    }
    assert_cpu_agrees(&cache, &cases, &outcomes);
}

/// A full-viewport quad whose payload is a pattern of its position.
const QUAD_SHADER: &str = r#"
struct Frame {
    clip_from_local: mat4x4<f32>,
}
@group(0) @binding(0) var<uniform> frame: Frame;

struct VertexOutput {
    @builtin(position) clip_position: vec4<f32>,
    @location(0) local: vec3<f32>,
}

@vertex
fn vs_main(@location(0) position: vec3<f32>) -> VertexOutput {
    var out: VertexOutput;
    out.clip_position = frame.clip_from_local * vec4<f32>(position, 1.0);
    out.local = position;
    return out;
}

@fragment
fn fs_main(in: VertexOutput) -> @location(0) vec4<f32> {
    let pattern = sin(in.local * 10.0);
    return vec4<f32>((pattern * 0.5) + vec3<f32>(0.5), 1.0);
}
"#;

/// Runs the one-pass variant of `QUAD_SHADER` on a still 32×32 quad for
/// `frames` frames, the counter started at `start`, and returns each
/// frame's refresh map (per pixel: recomputed by the refresh indicator)
/// after checking that every pixel of the first frame misses and every
/// later one hits or refreshes.
fn refresh_maps(gpu: &Gpu, period: u32, quad: u32, start: u64, frames: usize) -> Vec<Vec<bool>> {
    let (shader, analysis) = super::util::analyzed("quad.wgsl", QUAD_SHADER);
    let candidate = super::util::candidate(&analysis, "sin(in.local * 10.0)");
    let options = Options {
        refresh_period: period,
        refresh_quad: quad,
        ..Options::default()
    };
    let rewritten =
        rewrite::rewrite(&shader, &analysis, candidate, Variant::OnePass, &options).unwrap();
    let sources: HashMap<String, String> =
        crate::back::render_variant(&rewritten, crate::back::Language::Wgsl)
            .unwrap()
            .into_iter()
            .map(|(name, bytes)| (name, String::from_utf8(bytes).unwrap()))
            .collect();
    // At depth 0.0005: within ε of 0, the depth of a never-written (zeroed)
    // buffer, so a first frame that read one would hit.
    let z = 0.0005f32;
    let mut vertices = Vec::new();
    for [x, y] in [[-1.0f32, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]] {
        for v in [x, y, z] {
            vertices.extend(v.to_le_bytes());
        }
    }
    let mesh = runtime::Mesh {
        vertices,
        indices: vec![0, 1, 2, 0, 2, 3],
    };
    let size = 32u32;
    let mut runner = runtime::Runner::new(
        gpu,
        &rewritten.plan,
        |name| sources.get(name).cloned(),
        &[mesh],
        &HashMap::new(),
        (size, size),
        runtime::RunOptions {
            classify: true,
            ..runtime::RunOptions::default()
        },
    )
    .unwrap();
    runner.set_frame_counter(start);
    let identity: Vec<u8> = glam::Mat4::IDENTITY
        .to_cols_array()
        .iter()
        .flat_map(|v| v.to_le_bytes())
        .collect();
    let inputs = runtime::FrameInputs {
        objects: vec![runtime::ObjectInputs {
            mesh: 0,
            buffers: HashMap::from([([0, 0], identity)]),
            ..runtime::ObjectInputs::default()
        }],
        ..runtime::FrameInputs::default()
    };
    let mut maps = Vec::new();
    for frame in 0..frames {
        runner.frame(gpu, &inputs, None).unwrap();
        let classes = runtime::read_texture(gpu, runner.classes(), 4).unwrap();
        let decisions = crate::measure::metrics::decisions(&classes);
        assert_eq!(decisions.covered, (size * size) as usize);
        if frame == 0 {
            assert_eq!(
                decisions.disoccluded, 1.0,
                "the first frame after setting the counter has no previous frame: {decisions:?}"
            );
            continue;
        }
        assert_eq!(
            decisions.hit + decisions.refresh,
            1.0,
            "frame {frame}: {decisions:?}"
        );
        maps.push(
            classes
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2]] == crate::measure::metrics::REFRESH)
                .collect(),
        );
    }
    assert_eq!(runner.frame_counter(), start.wrapping_add(frames as u64));
    maps
}

/// Across the frame counter's wrap (u32 and u64), for Δn = 7, 12 and 8,
/// every block is refreshed exactly once every Δn frames: fraction 1/Δn.
#[test]
fn frame_counter_wrap() {
    // Periods that do not divide 2^32 (7, 12) and one that does (8). Each
    // frame's refreshes are also eq. 1's with the unwrapped counter:
    // b = (h(block) + c) mod Δn = 0.
    let Some(gpu) = super::gpu::gpu() else { return };
    let near_u32 = u64::from(u32::MAX) - 20;
    for (period, quad, start) in [
        (7, 2, near_u32),
        (12, 4, near_u32),
        (8, 2, near_u32),
        (7, 2, u64::MAX - 20),
    ] {
        let maps = refresh_maps(&gpu, period, quad, start, 41);
        let what = format!("Δn = {period}, k = {quad}, from {start}");
        let pixels = maps[0].len();
        // Every pixel is refreshed exactly once in every window of Δn
        // frames: the gaps between its refreshes are exactly Δn.
        for pixel in 0..pixels {
            let refreshed: Vec<usize> = (0..maps.len()).filter(|&f| maps[f][pixel]).collect();
            assert!(
                refreshed[0] < period as usize,
                "{what}: pixel {pixel} {refreshed:?}"
            );
            assert!(
                refreshed.windows(2).all(|w| w[1] - w[0] == period as usize),
                "{what}: pixel {pixel} refreshed at {refreshed:?}"
            );
            assert!(
                maps.len() - refreshed[refreshed.len() - 1] <= period as usize,
                "{what}: pixel {pixel} {refreshed:?}"
            );
        }
        for window in maps.windows(period as usize) {
            let refreshes: usize = window
                .iter()
                .map(|m| m.iter().filter(|&&r| r).count())
                .sum();
            assert_eq!(
                refreshes, pixels,
                "{what}: 1/Δn of the pixels a frame on average"
            );
        }
        // The refresh indicator with the unwrapped counter c (frame i of
        // the maps is the counter's start + 1 + i).
        for (i, map) in maps.iter().enumerate() {
            let c = u128::from(start) + 1 + i as u128;
            let phase = (c % u128::from(period)) as u32;
            for (pixel, &refreshed) in map.iter().enumerate() {
                let centre = Vec2::new((pixel % 32) as f32 + 0.5, (pixel / 32) as f32 + 0.5);
                assert_eq!(
                    refreshed,
                    reprojection::refresh(centre, phase, period, quad),
                    "{what}: frame {i}, pixel {pixel}"
                );
            }
        }
    }
}

/// naga writes `discard` as OpKill, which ends the invocation: a
/// derivative after the reuse-or-discard of two-pass pass 1 (and of
/// three-pass pass 1) would be undefined in every quad a missed lane
/// leaves. Every pass of every corpus node × variant is walked on the IR:
/// nothing that takes a derivative runs after a `discard` of the pass's
/// own entry point.
#[test]
fn no_derivative_after_kill_in_any_emitted_pass() {
    let mut passes = 0;
    let mut deferred = 0;
    for rewrite in super::corpus_rewrites::corpus_rewrites() {
        let Ok(emitted) = &rewrite.outcome else {
            continue;
        };
        for (pass, found) in &emitted.kills {
            if let Err(err) = found {
                panic!("{} {pass}: {err}", rewrite.label());
            }
            passes += 1;
        }
        deferred += emitted.deferred_kills;
    }
    assert!(passes > 3000, "{passes} passes");
    assert!(deferred > 0, "no pass defers its kill");
}
