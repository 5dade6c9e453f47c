//! Running a variant frame after frame exactly as its plan says.

use std::collections::HashMap;

use super::pipelines::{attribute_size, pipelines, texture_format, Gpu, PipelineOptions};
use crate::plan::{
    CacheFormat, Field, LoadOp, Pass, Plan, ResourceKind, StepMode, TargetKind, VertexAttribute,
};
use crate::scene::textures::Texels;

/// An indexed triangle mesh whose vertices are laid out as the plan's
/// `vertex_layout`, attributes packed in order.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub vertices: Vec<u8>,
    pub indices: Vec<u32>,
}

/// One draw of one frame: which mesh, how many instances of it, and the
/// contents of the shader's uniform and storage buffers for it by
/// `[group, binding]`.
#[derive(Clone, Debug)]
pub struct ObjectInputs {
    pub mesh: usize,
    pub buffers: HashMap<[u32; 2], Vec<u8>>,
    /// New vertex data for the mesh this frame (a deforming mesh), laid
    /// out as at creation.
    pub vertices: Option<Vec<u8>>,
    /// Instances drawn, in one instanced draw call (1 by default), by
    /// every pass alike: `@builtin(instance_index)` runs from 0 to this.
    pub instances: u32,
    /// This frame's per-instance vertex inputs: one record per instance,
    /// each the plan's per-instance inputs that are not twins, packed in
    /// the layout's order. The runner fills the twins with last frame's
    /// records (this frame's on the first frame). Empty when the shader
    /// has no per-instance inputs.
    pub instance_inputs: Vec<u8>,
}

impl Default for ObjectInputs {
    fn default() -> Self {
        ObjectInputs {
            mesh: 0,
            buffers: HashMap::new(),
            vertices: None,
            instances: 1,
            instance_inputs: Vec::new(),
        }
    }
}

/// What one frame draws.
#[derive(Clone, Debug, Default)]
pub struct FrameInputs {
    pub objects: Vec<ObjectInputs>,
}

/// How to run beyond what the plan says.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RunOptions {
    pub pipelines: PipelineOptions,
    /// Draw the plan's `classify` pass after each frame (see
    /// [`Runner::classes`]).
    pub classify: bool,
}

/// Bytes of the `CacheParams` uniform the plan lays out: its fields' end
/// rounded up to 16 (WGSL's uniform layout), at least 16.
fn params_size(fields: &[Field]) -> Result<usize, String> {
    let mut end = 0;
    for field in fields {
        let width = match field.ty.as_str() {
            "f32" | "u32" | "i32" => 4,
            "vec2<f32>" | "vec2<u32>" => 8,
            "vec4<f32>" | "vec4<u32>" => 16,
            other => {
                return Err(format!(
                    "CacheParams field `{}` has a type this runtime cannot write: {other}",
                    field.name
                ))
            }
        };
        end = end.max(field.offset as usize + width);
    }
    Ok(end.div_ceil(16).max(1) * 16)
}

struct GpuMesh {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    count: u32,
}

/// What the GPU holds for a plan: pipelines, the double-buffered cache,
/// the buffers and their previous-frame twins, textures and samplers.
pub struct Runner {
    plan: Plan,
    pipelines: Vec<wgpu::RenderPipeline>,
    classify: Option<(Pass, wgpu::RenderPipeline)>,
    size: (u32, u32),
    color: wgpu::Texture,
    classes: wgpu::Texture,
    payload: [wgpu::Texture; 2],
    /// Frames since each cached value was computed.
    age: [wgpu::Texture; 2],
    depth: [wgpu::Texture; 2],
    params: wgpu::Buffer,
    meshes: Vec<GpuMesh>,
    /// Buffers by (object, [group, binding]), twins included.
    buffers: HashMap<(usize, [u32; 2]), wgpu::Buffer>,
    /// Last frame's contents of each buffer a twin shadows, by object.
    previous: HashMap<(usize, [u32; 2]), Vec<u8>>,
    /// Per-instance vertex buffers by object (slot 1), twins filled.
    instance_buffers: HashMap<usize, wgpu::Buffer>,
    /// Last frame's per-instance inputs by object, as given.
    previous_instances: HashMap<usize, Vec<u8>>,
    views: HashMap<[u32; 2], wgpu::TextureView>,
    samplers: HashMap<[u32; 2], wgpu::Sampler>,
    cache_sampler: wgpu::Sampler,
    /// Which of the two cache slots is this frame's.
    current: usize,
    /// c, the frame counter, and c mod Δn, advanced together.
    frame: u64,
    phase: u32,
    /// Whether a frame has been rendered: until then the cache holds no
    /// previous frame (whatever the counter says).
    rendered: bool,
}

impl std::fmt::Debug for Runner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Runner")
            .field("variant", &self.plan.variant)
            .field("size", &self.size)
            .field("frame", &self.frame)
            .finish_non_exhaustive()
    }
}

fn target(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
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
}

impl Runner {
    /// Builds the pipelines, uploads the meshes and textures, and
    /// allocates the targets for a `size` frame. `textures` holds the
    /// texels of every texture binding of the plan by `[group, binding]`.
    pub fn new(
        gpu: &Gpu,
        plan: &Plan,
        shader: impl Fn(&str) -> Option<String>,
        meshes: &[Mesh],
        textures: &HashMap<[u32; 2], Texels>,
        size: (u32, u32),
        options: RunOptions,
    ) -> Result<Runner, String> {
        // Checked once, here, before anything is made from it.
        plan.check()?;
        let pipelines = pipelines(gpu, plan, &shader, options.pipelines)?;
        let classify = match (&plan.classify, options.classify) {
            (Some(pass), true) => {
                let single = Plan {
                    passes: vec![pass.clone()],
                    ..plan.clone()
                };
                // The same culling as the passes it classifies; never
                // additive, its colours are codes.
                let classify_options = PipelineOptions {
                    count_shading: false,
                    ..options.pipelines
                };
                let mut built =
                    super::pipelines::pipelines(gpu, &single, &shader, classify_options)?;
                built.pop().map(|p| (pass.clone(), p))
            }
            _ => None,
        };
        let device = &gpu.device;
        let color_format = plan
            .passes
            .iter()
            .flat_map(|p| &p.color_targets)
            .find(|t| t.target == TargetKind::Color)
            .map(|t| texture_format(&t.format))
            .transpose()?
            .unwrap_or(wgpu::TextureFormat::Rgba8Unorm);
        let cache_format = texture_format(plan.cache.format.as_str())?;
        let age_format = texture_format(crate::plan::AGE_FORMAT)?;
        let depth_format = wgpu::TextureFormat::Depth32Float;
        let buffer = |label: &str, bytes: &[u8], usage: wgpu::BufferUsages| {
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: (bytes.len() as u64).max(16).div_ceil(4) * 4,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            });
            gpu.queue.write_buffer(&buffer, 0, bytes);
            buffer
        };
        let meshes = meshes
            .iter()
            .map(|mesh| {
                let index_bytes: Vec<u8> =
                    mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
                GpuMesh {
                    vertices: buffer("vertices", &mesh.vertices, wgpu::BufferUsages::VERTEX),
                    indices: buffer("indices", &index_bytes, wgpu::BufferUsages::INDEX),
                    count: mesh.indices.len() as u32,
                }
            })
            .collect();

        // The user's textures and samplers.
        let mut views = HashMap::new();
        let mut samplers = HashMap::new();
        for resource in &plan.bindings.original {
            let key = [resource.group, resource.binding];
            if let Some((depth, shape)) = sampled_shape(resource.kind) {
                let view = if depth {
                    far_depth(gpu, &resource.name, depth_format, shape)
                } else {
                    let texels = textures
                        .get(&key)
                        .ok_or_else(|| format!("no texels for texture `{}`", resource.name))?;
                    upload(gpu, texels, shape)
                };
                views.insert(key, view);
                continue;
            }
            match resource.kind {
                ResourceKind::Sampler | ResourceKind::ComparisonSampler => {
                    let compare = resource.kind == ResourceKind::ComparisonSampler;
                    samplers.insert(
                        key,
                        device.create_sampler(&wgpu::SamplerDescriptor {
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
                ResourceKind::Uniform | ResourceKind::Storage => {}
                other => {
                    return Err(format!(
                        "cannot bind `{}`: {other} bindings are not supported",
                        resource.name
                    ))
                }
            }
        }

        Ok(Runner {
            plan: plan.clone(),
            pipelines,
            classify,
            size,
            color: target(device, "color", size, color_format),
            classes: target(device, "classes", size, wgpu::TextureFormat::Rgba8Unorm),
            payload: [
                target(device, "payload 0", size, cache_format),
                target(device, "payload 1", size, cache_format),
            ],
            age: [
                target(device, "age 0", size, age_format),
                target(device, "age 1", size, age_format),
            ],
            depth: [
                target(device, "depth 0", size, depth_format),
                target(device, "depth 1", size, depth_format),
            ],
            params: buffer(
                "cache params",
                &vec![0; params_size(&plan.cache.params)?],
                wgpu::BufferUsages::UNIFORM,
            ),
            meshes,
            buffers: HashMap::new(),
            previous: HashMap::new(),
            instance_buffers: HashMap::new(),
            previous_instances: HashMap::new(),
            views,
            samplers,
            cache_sampler: device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("cache sampler"),
                mag_filter: wgpu::FilterMode::Linear,
                min_filter: wgpu::FilterMode::Linear,
                ..wgpu::SamplerDescriptor::default()
            }),
            current: 0,
            frame: 0,
            phase: 0,
            rendered: false,
        })
    }

    /// Sets the frame counter c to `frame`, as if that many frames had
    /// been run, and the refresh phase to c mod Δn (the phase then advances
    /// by one modulo Δn per frame, never from the counter itself: so the
    /// refresh period stays exact when the counter's u32 copy in
    /// `CacheParams`, or the counter, wraps). The cache is left as it is:
    /// before the first frame, that frame still has no previous one. For
    /// tests of long runs, and to resume a sequence.
    pub fn set_frame_counter(&mut self, frame: u64) {
        let period = u64::from(self.plan.refresh.period);
        self.frame = frame;
        self.phase = if period == 0 {
            0
        } else {
            (frame % period) as u32
        };
    }

    /// The frame counter c: frames run, plus where it was set to.
    pub fn frame_counter(&self) -> u64 {
        self.frame
    }

    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// The frame's colour target.
    pub fn color(&self) -> &wgpu::Texture {
        &self.color
    }

    /// The last frame's classes, when classification is on.
    pub fn classes(&self) -> &wgpu::Texture {
        &self.classes
    }

    /// The last frame's depth buffer.
    pub fn depth(&self) -> &wgpu::Texture {
        &self.depth[1 - self.current]
    }

    /// The last frame's payload texture.
    pub fn payload(&self) -> &wgpu::Texture {
        &self.payload[1 - self.current]
    }

    /// The last frame's age texture (r16float): at each pixel whose cache
    /// entry was written, how many frames ago its value was computed.
    pub fn age(&self) -> &wgpu::Texture {
        &self.age[1 - self.current]
    }

    /// Renders one frame: every pass of the plan in order (each timed when
    /// a profiler is given, as `<label>/<pass>`), the classification when
    /// asked for, then swaps the cache.
    pub fn frame(
        &mut self,
        gpu: &Gpu,
        inputs: &FrameInputs,
        mut profiler: Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) -> Result<(), String> {
        let device = &gpu.device;
        // The buffers, and their twins with last frame's contents (this
        // frame's on the first frame).
        for (object, draw) in inputs.objects.iter().enumerate() {
            if let (Some(vertices), Some(mesh)) = (&draw.vertices, self.meshes.get(draw.mesh)) {
                if vertices.len() as u64 <= mesh.vertices.size() {
                    gpu.queue.write_buffer(&mesh.vertices, 0, vertices);
                }
            }
            for (&key, bytes) in &draw.buffers {
                self.write_buffer(gpu, (object, key), bytes);
            }
            if !draw.instance_inputs.is_empty() {
                let previous = self
                    .previous_instances
                    .get(&object)
                    .unwrap_or(&draw.instance_inputs);
                let records = instance_records(
                    &self.plan.vertex_layout,
                    &draw.instance_inputs,
                    previous,
                    draw.instances,
                )?;
                self.write_instance_buffer(gpu, object, &records);
            }
            let twins = self.plan.bindings.previous.clone();
            for twin in &twins {
                let shadowed = (object, [twin.shadows.group, twin.shadows.binding]);
                let bytes = self
                    .previous
                    .get(&shadowed)
                    .or_else(|| draw.buffers.get(&shadowed.1))
                    .ok_or_else(|| format!("no contents for `{}`", twin.shadows.name))?
                    .clone();
                self.write_buffer(gpu, (object, [twin.group, twin.binding]), &bytes);
            }
        }

        // CacheParams, laid out as the plan's `cache.params`.
        let params = self.cache_params()?;
        gpu.queue.write_buffer(&self.params, 0, &params);

        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        let current = self.current;
        let previous = 1 - current;
        let color_view = view(&self.color);
        let classes_view = view(&self.classes);
        let payload_views = [view(&self.payload[0]), view(&self.payload[1])];
        let age_views = [view(&self.age[0]), view(&self.age[1])];
        let depth_views = [view(&self.depth[0]), view(&self.depth[1])];
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        if !self.rendered {
            // No previous frame: a depth at the far plane (1.0, or 0.0 with
            // reversed Z) makes every pixel miss: the depth test's
            // tolerance, ε·|expected − far depth|, is below the distance of
            // anything in front of the far plane from it.
            clear_depth_in(
                &mut encoder,
                &depth_views[previous],
                self.plan.clear.depth as f32,
            );
        }
        let classify = self
            .classify
            .as_ref()
            .map(|(pass, pipeline)| (pass, pipeline));
        let passes: Vec<(&Pass, &wgpu::RenderPipeline)> = self
            .plan
            .passes
            .iter()
            .zip(&self.pipelines)
            .chain(classify)
            .collect();
        for (pass, pipeline) in passes {
            // Bind groups per object: the objects' buffers differ.
            let mut groups: Vec<u32> = pass.bindings.iter().map(|b| b[0]).collect();
            groups.dedup();
            let mut per_object = Vec::new();
            for object in 0..inputs.objects.len() {
                let mut bind_groups = Vec::new();
                for &group in &groups {
                    let layout = pipeline.get_bind_group_layout(group);
                    let mut entries = Vec::new();
                    for &[g, binding] in pass.bindings.iter().filter(|b| b[0] == group) {
                        let resource = self.resource(
                            object,
                            [g, binding],
                            current,
                            [&payload_views, &age_views, &depth_views],
                        )?;
                        entries.push(wgpu::BindGroupEntry { binding, resource });
                    }
                    // A plan that binds what the pipeline does not declare
                    // is an error of the plan, reported, not a panic. The
                    // first frame finds it: every later one binds the same
                    // kinds of resource to the same layouts.
                    let scope = (!self.rendered)
                        .then(|| device.push_error_scope(wgpu::ErrorFilter::Validation));
                    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                        label: Some(&pass.name),
                        layout: &layout,
                        entries: &entries,
                    });
                    if let Some(err) = scope.and_then(|scope| pollster::block_on(scope.pop())) {
                        return Err(format!("{}: group {group}: {err}", pass.name));
                    }
                    bind_groups.push((group, bind_group));
                }
                per_object.push(bind_groups);
            }
            let mut attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = Vec::new();
            for target in &pass.color_targets {
                let index = target.location as usize;
                if attachments.len() <= index {
                    attachments.resize(index + 1, None);
                }
                let (view, clear) = match target.target {
                    TargetKind::Cache => (&payload_views[current], self.plan.clear.cache),
                    TargetKind::Age => (&age_views[current], [0.0; 4]),
                    TargetKind::Classes => (&classes_view, [0.0, 0.0, 0.0, 0.0]),
                    TargetKind::Color => (&color_view, self.plan.clear.color),
                };
                attachments[index] = Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: if target.load == LoadOp::Clear {
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
                    },
                });
            }
            let query = profiler.as_mut().map(|(p, label)| {
                p.begin_pass_query(format!("{label}/{}", pass.name), &mut encoder)
            });
            {
                let mut render = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(&pass.name),
                    color_attachments: &attachments,
                    depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                        view: &depth_views[current],
                        depth_ops: Some(wgpu::Operations {
                            load: if pass.depth.load == LoadOp::Clear {
                                wgpu::LoadOp::Clear(self.plan.clear.depth as f32)
                            } else {
                                wgpu::LoadOp::Load
                            },
                            store: wgpu::StoreOp::Store,
                        }),
                        stencil_ops: None,
                    }),
                    timestamp_writes: query
                        .as_ref()
                        .and_then(|q| q.render_pass_timestamp_writes()),
                    ..wgpu::RenderPassDescriptor::default()
                });
                render.set_pipeline(pipeline);
                for (object, (draw, bind_groups)) in
                    inputs.objects.iter().zip(&per_object).enumerate()
                {
                    let Some(mesh) = self.meshes.get(draw.mesh) else {
                        return Err(format!("no mesh {}", draw.mesh));
                    };
                    for (group, bind_group) in bind_groups {
                        render.set_bind_group(*group, bind_group, &[]);
                    }
                    render.set_vertex_buffer(0, mesh.vertices.slice(..));
                    if let Some(instances) = self.instance_buffers.get(&object) {
                        render.set_vertex_buffer(1, instances.slice(..));
                    }
                    render.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
                    render.draw_indexed(0..mesh.count, 0, 0..draw.instances);
                }
            }
            if let (Some((p, _)), Some(query)) = (profiler.as_mut(), query) {
                p.end_query(&mut encoder, query);
            }
        }
        if let Some((p, _)) = profiler.as_mut() {
            p.resolve_queries(&mut encoder);
        }
        gpu.queue.submit([encoder.finish()]);

        // This frame's contents are next frame's previous.
        for (object, draw) in inputs.objects.iter().enumerate() {
            if !draw.instance_inputs.is_empty() {
                self.previous_instances
                    .insert(object, draw.instance_inputs.clone());
            }
            for twin in &self.plan.bindings.previous {
                let shadowed = [twin.shadows.group, twin.shadows.binding];
                if let Some(bytes) = draw.buffers.get(&shadowed) {
                    self.previous.insert((object, shadowed), bytes.clone());
                }
            }
        }
        self.current = previous;
        self.rendered = true;
        self.frame = self.frame.wrapping_add(1);
        let period = self.plan.refresh.period;
        self.phase = if period == 0 {
            0
        } else {
            (self.phase + 1) % period
        };
        Ok(())
    }

    /// Writes `bytes` to the buffer bound at `key` for an object, creating
    /// it (or a larger one) as needed: a storage buffer when the plan binds
    /// storage there (or a twin of it), a uniform buffer otherwise.
    fn write_buffer(&mut self, gpu: &Gpu, key: (usize, [u32; 2]), bytes: &[u8]) {
        let size = (bytes.len() as u64).max(16).div_ceil(16) * 16;
        let [group, binding] = key.1;
        let bindings = &self.plan.bindings;
        // A twin is of the kind it shadows.
        let storage = bindings
            .original
            .iter()
            .find(|r| r.group == group && r.binding == binding)
            .or_else(|| {
                bindings
                    .previous
                    .iter()
                    .find(|t| t.group == group && t.binding == binding)
                    .map(|t| &t.shadows)
            })
            .is_some_and(|resource| resource.kind == ResourceKind::Storage);
        let usage = if storage {
            wgpu::BufferUsages::STORAGE
        } else {
            wgpu::BufferUsages::UNIFORM
        };
        let stale = self.buffers.get(&key).is_some_and(|b| b.size() < size);
        if stale {
            self.buffers.remove(&key);
        }
        let buffer = self.buffers.entry(key).or_insert_with(|| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(if storage {
                    "shader storage buffer"
                } else {
                    "shader uniform buffer"
                }),
                size,
                usage: usage | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        gpu.queue.write_buffer(buffer, 0, bytes);
    }

    /// The `CacheParams` uniform's bytes for this frame: each field of the
    /// plan's `cache.params` at its offset, by its name.
    fn cache_params(&self) -> Result<Vec<u8>, String> {
        let refresh = &self.plan.refresh;
        let mut bytes = vec![0u8; params_size(&self.plan.cache.params)?];
        for field in &self.plan.cache.params {
            let value: Vec<u8> = match field.name.as_str() {
                "viewport" => [self.size.0 as f32, self.size.1 as f32]
                    .iter()
                    .flat_map(|v| v.to_le_bytes())
                    .collect(),
                "depth_epsilon" => refresh.depth_epsilon.to_le_bytes().to_vec(),
                "refresh_phase" => self.phase.to_le_bytes().to_vec(),
                "refresh_period" => refresh.period.to_le_bytes().to_vec(),
                "refresh_quad" => refresh.quad.to_le_bytes().to_vec(),
                "frame" => (self.frame as u32).to_le_bytes().to_vec(),
                // The largest value the payload texture holds: what is
                // above it is "no value".
                "payload_limit" => match self.plan.cache.format {
                    CacheFormat::Rgba16float => 65504.0f32,
                    CacheFormat::Rgba32float => f32::MAX,
                }
                .to_le_bytes()
                .to_vec(),
                // The depth test's tolerance is relative to it.
                "far_depth" => (self.plan.clear.depth as f32).to_le_bytes().to_vec(),
                other => {
                    return Err(format!(
                        "the plan's CacheParams has a field `{other}` this runtime does not fill"
                    ))
                }
            };
            let at = field.offset as usize;
            bytes
                .get_mut(at..at + value.len())
                .ok_or_else(|| format!("CacheParams field `{}` lies outside it", field.name))?
                .copy_from_slice(&value);
        }
        Ok(bytes)
    }

    /// Writes an object's per-instance vertex records, creating (or
    /// growing) its buffer as needed.
    fn write_instance_buffer(&mut self, gpu: &Gpu, object: usize, records: &[u8]) {
        let size = (records.len() as u64).max(16).div_ceil(4) * 4;
        if self
            .instance_buffers
            .get(&object)
            .is_some_and(|b| b.size() < size)
        {
            self.instance_buffers.remove(&object);
        }
        let buffer = self.instance_buffers.entry(object).or_insert_with(|| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("per-instance vertex inputs"),
                size,
                usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        });
        gpu.queue.write_buffer(buffer, 0, records);
    }

    fn resource<'a>(
        &'a self,
        object: usize,
        key: [u32; 2],
        current: usize,
        [payload_views, age_views, depth_views]: [&'a [wgpu::TextureView; 2]; 3],
    ) -> Result<wgpu::BindingResource<'a>, String> {
        let [group, binding] = key;
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
                "cache_previous_age" => wgpu::BindingResource::TextureView(&age_views[1 - current]),
                "cache_sampler" => wgpu::BindingResource::Sampler(&self.cache_sampler),
                other => return Err(format!("unknown cache resource `{other}`")),
            });
        }
        if let Some(view) = self.views.get(&key) {
            return Ok(wgpu::BindingResource::TextureView(view));
        }
        if let Some(sampler) = self.samplers.get(&key) {
            return Ok(wgpu::BindingResource::Sampler(sampler));
        }
        self.buffers
            .get(&(object, key))
            .map(|b| b.as_entire_binding())
            .ok_or_else(|| format!("nothing to bind at group {group} binding {binding}"))
    }
}

fn clear_depth_in(encoder: &mut wgpu::CommandEncoder, view: &wgpu::TextureView, depth: f32) {
    let _pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("clear depth"),
        color_attachments: &[],
        depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations {
                load: wgpu::LoadOp::Clear(depth),
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: None,
        }),
        ..wgpu::RenderPassDescriptor::default()
    });
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

/// Whether a plan's resource kind is a texture the shader samples (which
/// the runtime makes: a scene's texels, or the far plane for depth).
/// The per-instance vertex buffer's records for `count` instances: for
/// each, the layout's per-instance inputs in order, an input's bytes from
/// `current` and a twin's from `previous` (the bytes of the input it
/// shadows), where `current` and `previous` hold the non-twin inputs
/// packed per instance.
fn instance_records(
    layout: &[VertexAttribute],
    current: &[u8],
    previous: &[u8],
    count: u32,
) -> Result<Vec<u8>, String> {
    // Each non-twin input's (location, offset, size) in a given record.
    let mut given = Vec::new();
    let mut offset = 0;
    for attribute in layout
        .iter()
        .filter(|a| a.step == StepMode::Instance && a.previous_of.is_none())
    {
        let size = attribute_size(attribute)? as usize;
        given.push((attribute.location, offset, size));
        offset += size;
    }
    let stride = offset;
    let count = count as usize;
    for (bytes, what) in [(current, "this frame's"), (previous, "last frame's")] {
        if bytes.len() != stride * count {
            return Err(format!(
                "{what} per-instance vertex inputs are {} bytes, not {count} records of {stride}",
                bytes.len()
            ));
        }
    }
    let mut out = Vec::new();
    for instance in 0..count {
        for attribute in layout.iter().filter(|a| a.step == StepMode::Instance) {
            let (bytes, of) = match attribute.previous_of {
                Some(of) => (previous, of),
                None => (current, attribute.location),
            };
            let Some(&(_, offset, size)) = given.iter().find(|g| g.0 == of) else {
                return Err(format!(
                    "vertex input @location({}) is the twin of @location({of}), which is not a per-instance input",
                    attribute.location
                ));
            };
            let at = instance * stride + offset;
            out.extend_from_slice(&bytes[at..at + size]);
        }
    }
    Ok(out)
}

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

/// A depth texture of `shape` with every texel at the far plane (a shadow
/// map that shadows nothing).
fn far_depth(
    gpu: &Gpu,
    label: &str,
    format: wgpu::TextureFormat,
    shape: SampledShape,
) -> wgpu::TextureView {
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: 64,
            height: 64,
            depth_or_array_layers: shape.layers,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
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
        clear_depth_in(&mut encoder, &view, 1.0);
    }
    gpu.queue.submit([encoder.finish()]);
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(shape.dimension),
        ..wgpu::TextureViewDescriptor::default()
    })
}

/// Uploads RGBA8 texels into every layer of a texture of `shape` (a 2D
/// texture, the six faces of a cube, an array of either).
fn upload(gpu: &Gpu, texels: &Texels, shape: SampledShape) -> wgpu::TextureView {
    let layers = shape.layers;
    let size = wgpu::Extent3d {
        width: texels.width,
        height: texels.height,
        depth_or_array_layers: layers,
    };
    let texture = gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("scene texture"),
        size,
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::Rgba8Unorm,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for layer in 0..layers {
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: 0,
                origin: wgpu::Origin3d {
                    x: 0,
                    y: 0,
                    z: layer,
                },
                aspect: wgpu::TextureAspect::All,
            },
            &texels.rgba,
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(texels.width * 4),
                rows_per_image: Some(texels.height),
            },
            wgpu::Extent3d {
                depth_or_array_layers: 1,
                ..size
            },
        );
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
