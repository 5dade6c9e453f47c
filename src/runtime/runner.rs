//! Running a variant frame after frame exactly as its plan says.

use std::collections::HashMap;

use super::pipelines::{pipelines, texture_format, Gpu, PipelineOptions};
use crate::plan::Plan;

/// An indexed triangle mesh whose vertices are laid out as the plan's
/// `vertex_layout`, attributes packed in order.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub vertices: Vec<u8>,
    pub indices: Vec<u32>,
}

/// What one frame reads: the contents of the shader's uniform and storage
/// buffers by `[group, binding]`, as they are this frame.
#[derive(Clone, Debug, Default)]
pub struct FrameInputs {
    pub buffers: HashMap<[u32; 2], Vec<u8>>,
}

/// What the GPU holds for a plan: pipelines, the double-buffered cache,
/// the buffers and their previous-frame twins.
#[derive(Debug)]
pub struct Runner {
    plan: Plan,
    pipelines: Vec<wgpu::RenderPipeline>,
    size: (u32, u32),
    color: wgpu::Texture,
    payload: [wgpu::Texture; 2],
    depth: [wgpu::Texture; 2],
    params: wgpu::Buffer,
    buffers: HashMap<[u32; 2], wgpu::Buffer>,
    /// Last frame's contents of each buffer a twin shadows.
    previous: HashMap<[u32; 2], Vec<u8>>,
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    index_count: u32,
    /// Which of the two cache slots is this frame's.
    current: usize,
    frame: u64,
    phase: u32,
}

impl Runner {
    /// Builds the pipelines and allocates the targets for a `size` frame.
    pub fn new(
        gpu: &Gpu,
        plan: &Plan,
        shader: impl Fn(&str) -> Option<String>,
        mesh: &Mesh,
        size: (u32, u32),
        options: PipelineOptions,
    ) -> Result<Runner, String> {
        let pipelines = pipelines(gpu, plan, shader, options)?;
        let device = &gpu.device;
        let color_format = plan
            .passes
            .iter()
            .flat_map(|p| &p.color_targets)
            .find(|t| t.target == "color")
            .map(|t| texture_format(&t.format))
            .transpose()?
            .unwrap_or(wgpu::TextureFormat::Rgba8Unorm);
        let texture = |label: &str, format: wgpu::TextureFormat| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d {
                    width: size.0,
                    height: size.1,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT
                    | wgpu::TextureUsages::TEXTURE_BINDING
                    | wgpu::TextureUsages::COPY_SRC,
                view_formats: &[],
            })
        };
        let cache_format = texture_format(&plan.cache.format)?;
        let depth_format = wgpu::TextureFormat::Depth32Float;
        let buffer = |label: &str, size: u64, usage: wgpu::BufferUsages| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4),
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let vertices = buffer(
            "vertices",
            mesh.vertices.len() as u64,
            wgpu::BufferUsages::VERTEX,
        );
        gpu.queue.write_buffer(&vertices, 0, &mesh.vertices);
        let index_bytes: Vec<u8> = mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let indices = buffer(
            "indices",
            index_bytes.len() as u64,
            wgpu::BufferUsages::INDEX,
        );
        gpu.queue.write_buffer(&indices, 0, &index_bytes);
        Ok(Runner {
            plan: plan.clone(),
            pipelines,
            size,
            color: texture("color", color_format),
            payload: [
                texture("payload 0", cache_format),
                texture("payload 1", cache_format),
            ],
            depth: [
                texture("depth 0", depth_format),
                texture("depth 1", depth_format),
            ],
            params: buffer("cache params", 32, wgpu::BufferUsages::UNIFORM),
            buffers: HashMap::new(),
            previous: HashMap::new(),
            vertices,
            indices,
            index_count: mesh.indices.len() as u32,
            current: 0,
            frame: 0,
            phase: 0,
        })
    }

    /// The frame's colour target.
    pub fn color(&self) -> &wgpu::Texture {
        &self.color
    }

    /// This frame's depth buffer (after [`Runner::frame`]: the last frame's).
    pub fn depth(&self) -> &wgpu::Texture {
        &self.depth[1 - self.current]
    }

    /// Renders one frame: every pass of the plan in order, then swaps the
    /// cache.
    pub fn frame(&mut self, gpu: &Gpu, inputs: &FrameInputs) -> Result<(), String> {
        let device = &gpu.device;
        // The buffers, and their twins with last frame's contents (this
        // frame's on the first frame).
        for (&key, bytes) in &inputs.buffers {
            let buffer = self.buffers.entry(key).or_insert_with(|| {
                device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("shader buffer"),
                    size: (bytes.len() as u64).max(16),
                    usage: wgpu::BufferUsages::UNIFORM
                        | wgpu::BufferUsages::STORAGE
                        | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            });
            gpu.queue.write_buffer(buffer, 0, bytes);
        }
        for twin in &self.plan.bindings.previous {
            let shadowed = [twin.shadows.group, twin.shadows.binding];
            let bytes = self
                .previous
                .get(&shadowed)
                .or_else(|| inputs.buffers.get(&shadowed))
                .ok_or_else(|| format!("no contents for `{}`", twin.shadows.name))?
                .clone();
            let buffer = self
                .buffers
                .entry([twin.group, twin.binding])
                .or_insert_with(|| {
                    device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(&twin.name),
                        size: (bytes.len() as u64).max(16),
                        usage: wgpu::BufferUsages::UNIFORM
                            | wgpu::BufferUsages::STORAGE
                            | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    })
                });
            gpu.queue.write_buffer(buffer, 0, &bytes);
        }

        // CacheParams, laid out as the plan's `cache.params`.
        let refresh = &self.plan.refresh;
        let mut params = Vec::with_capacity(32);
        params.extend((self.size.0 as f32).to_le_bytes());
        params.extend((self.size.1 as f32).to_le_bytes());
        params.extend(refresh.depth_epsilon.to_le_bytes());
        params.extend(self.phase.to_le_bytes());
        params.extend(refresh.period.to_le_bytes());
        params.extend(refresh.quad.to_le_bytes());
        params.extend((self.frame as u32).to_le_bytes());
        params.extend(0u32.to_le_bytes());
        gpu.queue.write_buffer(&self.params, 0, &params);

        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        let current = self.current;
        let previous = 1 - current;
        let color_view = view(&self.color);
        let payload_views = [view(&self.payload[0]), view(&self.payload[1])];
        let depth_views = [view(&self.depth[0]), view(&self.depth[1])];
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        if self.frame == 0 {
            // No previous frame: a cleared depth makes every pixel miss.
            let _clear = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("clear previous depth"),
                color_attachments: &[],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_views[previous],
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(self.plan.clear.depth as f32),
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                ..wgpu::RenderPassDescriptor::default()
            });
        }
        for (pass, pipeline) in self.plan.passes.iter().zip(&self.pipelines) {
            let mut groups: Vec<u32> = pass.bindings.iter().map(|b| b[0]).collect();
            groups.dedup();
            let mut bind_groups = Vec::new();
            for &group in &groups {
                let layout = pipeline.get_bind_group_layout(group);
                let mut entries = Vec::new();
                for &[g, binding] in pass.bindings.iter().filter(|b| b[0] == group) {
                    let resource =
                        self.resource(g, binding, current, &payload_views, &depth_views)?;
                    entries.push(wgpu::BindGroupEntry { binding, resource });
                }
                bind_groups.push((
                    group,
                    device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some(&pass.name),
                        layout: &layout,
                        entries: &entries,
                    }),
                ));
            }
            let load_color = |load: &str, clear: [f64; 4]| wgpu::Operations {
                load: if load == "clear" {
                    wgpu::LoadOp::Clear(wgpu::Color {
                        r: clear[0],
                        g: clear[1],
                        b: clear[2],
                        a: clear[3],
                    })
                } else {
                    wgpu::LoadOp::Load
                },
                store: wgpu::StoreOp::Store,
            };
            let mut attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = Vec::new();
            for target in &pass.color_targets {
                let index = target.location as usize;
                if attachments.len() <= index {
                    attachments.resize(index + 1, None);
                }
                let (view, clear) = if target.target == "cache" {
                    (&payload_views[current], self.plan.clear.cache)
                } else {
                    (&color_view, self.plan.clear.color)
                };
                attachments[index] = Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: load_color(&target.load, clear),
                });
            }
            let mut render = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(&pass.name),
                color_attachments: &attachments,
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth_views[current],
                    depth_ops: Some(wgpu::Operations {
                        load: if pass.depth.load == "clear" {
                            wgpu::LoadOp::Clear(self.plan.clear.depth as f32)
                        } else {
                            wgpu::LoadOp::Load
                        },
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                ..wgpu::RenderPassDescriptor::default()
            });
            render.set_pipeline(pipeline);
            for (group, bind_group) in &bind_groups {
                render.set_bind_group(*group, bind_group, &[]);
            }
            render.set_vertex_buffer(0, self.vertices.slice(..));
            render.set_index_buffer(self.indices.slice(..), wgpu::IndexFormat::Uint32);
            render.draw_indexed(0..self.index_count, 0, 0..1);
        }
        gpu.queue.submit([encoder.finish()]);

        // This frame's contents are next frame's previous.
        for twin in &self.plan.bindings.previous {
            let shadowed = [twin.shadows.group, twin.shadows.binding];
            if let Some(bytes) = inputs.buffers.get(&shadowed) {
                self.previous.insert(shadowed, bytes.clone());
            }
        }
        self.current = previous;
        self.frame += 1;
        self.phase = (self.phase + 1) % self.plan.refresh.period.max(1);
        Ok(())
    }

    fn resource<'a>(
        &'a self,
        group: u32,
        binding: u32,
        current: usize,
        payload_views: &'a [wgpu::TextureView; 2],
        depth_views: &'a [wgpu::TextureView; 2],
    ) -> Result<wgpu::BindingResource<'a>, String> {
        let cache = &self.plan.bindings.cache;
        if let Some(resource) = cache
            .iter()
            .find(|r| r.group == group && r.binding == binding)
        {
            return Ok(match resource.name.as_str() {
                "cache_params" => self.params.as_entire_binding(),
                "cache_previous_payload" => {
                    wgpu::BindingResource::TextureView(&payload_views[1 - current])
                }
                "cache_previous_depth" => {
                    wgpu::BindingResource::TextureView(&depth_views[1 - current])
                }
                "cache_current_payload" => {
                    wgpu::BindingResource::TextureView(&payload_views[current])
                }
                other => return Err(format!("unknown cache resource `{other}`")),
            });
        }
        self.buffers
            .get(&[group, binding])
            .map(|b| b.as_entire_binding())
            .ok_or_else(|| format!("nothing to bind at group {group} binding {binding}"))
    }
}

/// Reads a texture back as raw rows of `bytes_per_texel × width` bytes.
pub fn read_texture(
    gpu: &Gpu,
    texture: &wgpu::Texture,
    bytes_per_texel: u32,
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
            aspect: wgpu::TextureAspect::All,
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
