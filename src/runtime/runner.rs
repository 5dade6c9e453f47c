//! Running a variant frame after frame exactly as its plan says, through
//! the host crate an application uses: this runner is the application.
//! It owns the scene's meshes, buffers and textures, describes its frame
//! from the plan ([`frame_layout`]), and draws every object in each pass.

use std::collections::{BTreeMap, HashMap};

use shadecache_host::toolchain::render_target;
use shadecache_host::{CachedShader, Draw, NoTimer, PassTimer, Targets, TwinSources, Twins};

use super::frame::{cached_shader, RunOptions};
use super::gpu::Gpu;
use super::textures::scene_textures;
use super::textures::Texels;
use crate::plan::{Plan, ResourceKind};

/// A share of an object's draw: the triangles of `indices` (a range of its
/// index buffer) of the instances of `instances`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DrawShare {
    /// The object, by its place in [`FrameInputs::objects`].
    pub object: usize,
    pub indices: std::ops::Range<u32>,
    pub instances: std::ops::Range<u32>,
}

impl DrawShare {
    /// Every object's draw whole, in order: a frame drawn at once.
    /// `index_count` gives a mesh's count of indices.
    pub fn whole(objects: &[ObjectInputs], index_count: impl Fn(usize) -> u32) -> Vec<DrawShare> {
        objects
            .iter()
            .enumerate()
            .map(|(object, draw)| DrawShare {
                object,
                indices: 0..index_count(draw.mesh),
                instances: 0..draw.instances,
            })
            .collect()
    }
}

/// A part of a frame ([`Runner::frame_part`]): its shares of the draws,
/// and whether it adds to the last frame drawn (else it begins one).
#[derive(Clone, Debug, Default)]
pub struct FramePart {
    pub draws: Vec<DrawShare>,
    pub more: bool,
}

/// An indexed triangle mesh whose vertices are laid out as the plan's
/// per-vertex inputs, packed in order.
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
    /// the layout's order. The host keeps last frame's copy for the twins.
    /// Empty when the shader has no per-instance inputs.
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
    /// This frame's contents of 2D depth textures by `[group, binding]`
    /// (a shadow map rendered from the light), written before its passes;
    /// a depth texture not listed keeps what it had (at first the far
    /// plane).
    pub depth_maps: HashMap<[u32; 2], std::sync::Arc<super::DepthTexels>>,
    /// A camera cut comes before this frame (the first of a new shot):
    /// the cache starts afresh ([`Runner::reset`]) before it is drawn.
    pub cut: bool,
    /// The camera's near and far planes where the far one is finite (what
    /// a lowres plan with σz of the depth range reads).
    pub depth_range: Option<(f32, f32)>,
}

struct GpuMesh {
    vertices: wgpu::Buffer,
    indices: wgpu::Buffer,
    count: u32,
}

/// One object's resources: its buffers, its bind groups and their twins.
struct Object {
    buffers: HashMap<[u32; 2], wgpu::Buffer>,
    instances: Option<wgpu::Buffer>,
    bind_groups: Vec<(u32, wgpu::BindGroup)>,
    twins: Twins,
}

/// The scene on the GPU, drawn through the host crate: meshes, textures,
/// per-object buffers, and the variant.
pub struct Runner {
    cached: CachedShader,
    /// Every colour target, by output location.
    colors: Vec<Option<wgpu::Texture>>,
    /// The frame's colour targets by output location, each in the plan's
    /// format for it.
    color_views: Vec<Option<wgpu::TextureView>>,
    meshes: Vec<GpuMesh>,
    objects: Vec<Object>,
    /// The application's group layouts, as the plan implies them.
    layouts: BTreeMap<u32, wgpu::BindGroupLayout>,
    views: HashMap<[u32; 2], wgpu::TextureView>,
    samplers: HashMap<[u32; 2], wgpu::Sampler>,
    /// The 2D depth textures a frame can write a shadow map into.
    depth_maps: HashMap<[u32; 2], wgpu::Texture>,
    /// The group the caller binds, and what it bound.
    external: Option<(u32, Option<wgpu::BindGroup>)>,
}

impl std::fmt::Debug for Runner {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Runner")
            .field("cached", &self.cached)
            .finish_non_exhaustive()
    }
}

/// The wgpu-profiler, timing each pass as `<label>/<pass>`.
struct Profiled<'p> {
    profiler: &'p mut wgpu_profiler::GpuProfiler,
    label: &'p str,
}

impl PassTimer for Profiled<'_> {
    type Query = wgpu_profiler::GpuProfilerQuery;

    fn begin(&mut self, encoder: &mut wgpu::CommandEncoder, pass: &str) -> Self::Query {
        self.profiler
            .begin_pass_query(format!("{}/{pass}", self.label), encoder)
    }

    fn timestamp_writes<'a>(
        &'a self,
        query: &'a Self::Query,
    ) -> Option<wgpu::RenderPassTimestampWrites<'a>> {
        query.render_pass_timestamp_writes()
    }

    fn compute_timestamp_writes<'a>(
        &'a self,
        query: &'a Self::Query,
    ) -> Option<wgpu::ComputePassTimestampWrites<'a>> {
        query.compute_pass_timestamp_writes()
    }

    fn end(&mut self, encoder: &mut wgpu::CommandEncoder, query: Self::Query) {
        self.profiler.end_query(encoder, query);
    }
}

impl Runner {
    /// Makes the variant, uploads the meshes and textures, and allocates
    /// the targets for a `size` frame. `textures` holds the texels of
    /// every texture binding of the plan by `[group, binding]`.
    pub fn new(
        gpu: &Gpu,
        plan: &Plan,
        shader: impl Fn(&str) -> Option<String>,
        meshes: &[Mesh],
        textures: &HashMap<[u32; 2], Texels>,
        size: (u32, u32),
        options: RunOptions,
    ) -> Result<Runner, String> {
        let (cached, frame) = cached_shader(gpu, plan, shader, size, options)?;
        let device = &gpu.device;
        let colors: Vec<Option<wgpu::Texture>> = frame
            .color_formats()
            .map(|format| format.map(|format| render_target(device, "color", size, format)))
            .collect();
        let color_views = colors
            .iter()
            .map(|texture| {
                texture
                    .as_ref()
                    .map(|t| t.create_view(&wgpu::TextureViewDescriptor::default()))
            })
            .collect();
        let meshes = meshes
            .iter()
            .map(|mesh| {
                let index_bytes: Vec<u8> =
                    mesh.indices.iter().flat_map(|i| i.to_le_bytes()).collect();
                GpuMesh {
                    // Copied into a twin when the plan reads last frame's
                    // deformed vertices.
                    vertices: filled(
                        gpu,
                        "vertices",
                        &mesh.vertices,
                        wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_SRC,
                    ),
                    indices: filled(gpu, "indices", &index_bytes, wgpu::BufferUsages::INDEX),
                    count: mesh.indices.len() as u32,
                }
            })
            .collect();
        let layouts = frame
            .groups
            .iter()
            .map(|(group, entries)| {
                let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("scene group"),
                    entries,
                });
                (*group, layout)
            })
            .collect();
        let (views, samplers, depth_maps) =
            scene_textures(gpu, plan, textures, options.external_group)?;
        Ok(Runner {
            cached,
            colors,
            color_views,
            meshes,
            objects: Vec::new(),
            layouts,
            views,
            samplers,
            depth_maps,
            external: options.external_group.map(|group| (group, None)),
        })
    }

    /// Binds `entries` at the caller's group (`RunOptions::external_group`)
    /// in every pass from the next frame on, as a bind group of the layout
    /// the plan implies for it; `label` names it in errors.
    #[cfg(feature = "interpolate")]
    pub fn bind_external(
        &mut self,
        gpu: &Gpu,
        label: &str,
        entries: &[wgpu::BindGroupEntry],
    ) -> Result<(), String> {
        let (group, bound) = self.external.as_mut().ok_or_else(|| {
            format!("internal error: {label}: the runner binds no group of the caller's")
        })?;
        let layout = self.layouts.get(group).ok_or_else(|| {
            format!("internal error: {label}: the plan puts nothing in group {group}")
        })?;
        let bind_group = super::validated(&gpu.device, || {
            gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(label),
                layout,
                entries,
            })
        })
        .map_err(|err| format!("the {label} cannot be bound: {err}"))?;
        *bound = Some(bind_group);
        Ok(())
    }

    /// Starts the cache afresh, as after a camera cut: the next frame
    /// misses everywhere.
    pub fn reset(&mut self) {
        self.cached.reset();
    }

    /// Sets the frame counter c (see [`CachedShader::set_frame_counter`]).
    #[cfg(all(test, feature = "interpolate"))]
    pub fn set_frame_counter(&mut self, frame: u64) {
        self.cached.set_frame_counter(frame);
    }

    /// The frame counter c: frames run, plus where it was set to.
    #[cfg(all(test, feature = "interpolate"))]
    pub fn frame_counter(&self) -> u64 {
        self.cached.frame_counter()
    }

    pub fn plan(&self) -> &Plan {
        self.cached.plan()
    }

    /// The frame's first colour target, which the profile reads back;
    /// `None` for a plan that writes only the cache (a payload pass alone).
    pub fn color(&self) -> Option<&wgpu::Texture> {
        self.colors.iter().flatten().next()
    }

    /// The frame's colour target at output `location`, if it has one.
    #[cfg(feature = "interpolate")]
    pub fn color_at(&self, location: u32) -> Option<&wgpu::Texture> {
        self.colors.get(location as usize)?.as_ref()
    }

    /// The last frame's classes, when classification is on.
    pub fn classes(&self) -> &wgpu::Texture {
        self.cached.classes()
    }

    /// The last frame's depth buffer.
    pub fn depth(&self) -> &wgpu::Texture {
        self.cached.depth()
    }

    /// The last frame's payload texture.
    #[cfg(feature = "interpolate")]
    pub fn payload(&self) -> &wgpu::Texture {
        self.cached.payload()
    }

    /// The last frame's age texture (r16float): at each pixel whose cache
    /// entry was written, how many frames ago its value was computed.
    pub fn age(&self) -> &wgpu::Texture {
        self.cached.age()
    }

    /// Sets the refresh period Δn from the next frame on
    /// (`CachedShader::set_refresh_period`).
    pub fn set_refresh_period(&mut self, period: u32) -> Result<(), String> {
        self.cached
            .set_refresh_period(period)
            .map_err(|err| err.to_string())
    }

    /// The refresh period Δn the next frame runs with.
    pub fn refresh_period(&self) -> u32 {
        self.cached.refresh_period()
    }

    /// Records and submits the error watch's comparison of this runner's
    /// last frame with `original`'s last frame (the same inputs drawn by
    /// the original), over the pixels this frame covered; timed as
    /// `<label>/watch` when a profiler is given. `false` when the watch
    /// still waits for its last answer (nothing was recorded).
    pub fn watch(
        &self,
        gpu: &Gpu,
        (watch, frame): (&mut shadecache_host::ErrorWatch, u64),
        original: &Runner,
        profiler: Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) -> Result<bool, String> {
        let (Some(cached), Some(original)) = (self.color(), original.color()) else {
            return Err("the error watch compares colour frames; one of these draws none".into());
        };
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let frames = [original, cached];
        let recorded = match profiler {
            Some((profiler, label)) => {
                let mut timer = Profiled { profiler, label };
                let recorded = watch.compare_frames(
                    &gpu.device,
                    (&gpu.queue, &mut encoder),
                    &mut timer,
                    frame,
                    frames,
                    shadecache_host::Coverage::Cache(&self.cached),
                );
                timer.profiler.resolve_queries(&mut encoder);
                recorded
            }
            None => watch.compare_frames(
                &gpu.device,
                (&gpu.queue, &mut encoder),
                &mut NoTimer,
                frame,
                frames,
                shadecache_host::Coverage::Cache(&self.cached),
            ),
        }
        .map_err(|err| err.to_string())?;
        gpu.queue.submit([encoder.finish()]);
        Ok(recorded)
    }

    /// Renders one frame: every pass of the plan in order (each timed when
    /// a profiler is given, as `<label>/<pass>`), the classification when
    /// asked for; the host swaps the cache.
    pub fn frame(
        &mut self,
        gpu: &Gpu,
        inputs: &FrameInputs,
        profiler: Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) -> Result<(), String> {
        if inputs.cut {
            self.reset();
        }
        self.cached.set_depth_range(inputs.depth_range);
        self.frame_part(gpu, inputs, None, profiler)
    }

    /// Every object's draw of `inputs` whole, in order: what
    /// [`Runner::frame`] draws.
    pub fn whole_draws(&self, inputs: &FrameInputs) -> Vec<DrawShare> {
        DrawShare::whole(&inputs.objects, |mesh| {
            self.meshes.get(mesh).map_or(0, |m| m.count)
        })
    }

    /// Checks that `part` and `inputs` name objects and meshes there are,
    /// and writes the frame's buffers and depth maps.
    fn upload(
        &mut self,
        gpu: &Gpu,
        inputs: &FrameInputs,
        part: Option<&FramePart>,
    ) -> Result<(), String> {
        if let Some(share) = part
            .into_iter()
            .flat_map(|p| &p.draws)
            .find(|d| d.object >= inputs.objects.len())
        {
            return Err(format!("no object {} to draw a share of", share.object));
        }
        if let Some(draw) = inputs.objects.iter().find(|d| d.mesh >= self.meshes.len()) {
            return Err(format!("no mesh {}", draw.mesh));
        }
        for (index, draw) in inputs.objects.iter().enumerate() {
            self.write_object(gpu, index, draw)?;
        }
        // A plan whose passes do not read a depth texture (a payload
        // pass alone) has none to write.
        for (key, texels) in &inputs.depth_maps {
            if let Some(texture) = self.depth_maps.get(key) {
                super::textures::write_depth(gpu, texture, texels)?;
            }
        }
        Ok(())
    }

    /// Draws a part of a frame: only `part`'s shares of the objects' draws
    /// (in its order), as a frame of its own or, with `part.more`, into
    /// the last frame drawn ([`CachedShader::record_more_timed`]: its
    /// colour and depth loaded). `None` draws every object whole.
    pub fn frame_part(
        &mut self,
        gpu: &Gpu,
        inputs: &FrameInputs,
        part: Option<&FramePart>,
        profiler: Option<(&mut wgpu_profiler::GpuProfiler, &str)>,
    ) -> Result<(), String> {
        self.upload(gpu, inputs, part)?;
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor::default());
        let color: Vec<Option<&wgpu::TextureView>> =
            self.color_views.iter().map(Option::as_ref).collect();
        let clear = self.plan().clear.color;
        let targets = Targets {
            color: &color,
            clear: Some(wgpu::Color {
                r: clear[0],
                g: clear[1],
                b: clear[2],
                a: clear[3],
            }),
            depth: None,
        };
        if let Some((group, None)) = &self.external {
            return Err(format!(
                "nothing bound at group {group}, which the caller binds"
            ));
        }
        let (objects, meshes) = (&self.objects, &self.meshes);
        let external = self
            .external
            .as_ref()
            .and_then(|(group, bound)| Some((*group, bound.as_ref()?)));
        let whole: Vec<DrawShare>;
        let shares = match part {
            Some(part) => &part.draws,
            None => {
                whole = self.whole_draws(inputs);
                &whole
            }
        };
        let draw = |pass: &mut Draw<'_, '_>| {
            for share in shares {
                let object = &objects[share.object];
                let mesh = &meshes[inputs.objects[share.object].mesh];
                for (group, bind_group) in &object.bind_groups {
                    pass.set_bind_group(*group, bind_group, &[]);
                }
                if let Some((group, bind_group)) = external {
                    pass.set_bind_group(group, bind_group, &[]);
                }
                pass.set_vertex_buffer(0, mesh.vertices.slice(..));
                if let Some(instances) = &object.instances {
                    pass.set_vertex_buffer(1, instances.slice(..));
                }
                pass.set_index_buffer(mesh.indices.slice(..), wgpu::IndexFormat::Uint32);
                pass.draw_indexed(
                    &object.twins,
                    share.indices.clone(),
                    0,
                    share.instances.clone(),
                );
            }
        };
        let more = part.is_some_and(|p| p.more);
        let recorded = match (profiler, more) {
            (Some((profiler, label)), more) => {
                let mut timer = Profiled { profiler, label };
                let recorded = if more {
                    self.cached
                        .record_more_timed(&mut encoder, &targets, &mut timer, draw)
                } else {
                    self.cached
                        .record_timed(&gpu.queue, &mut encoder, &targets, &mut timer, draw)
                };
                timer.profiler.resolve_queries(&mut encoder);
                recorded
            }
            (None, true) => {
                self.cached
                    .record_more_timed(&mut encoder, &targets, &mut NoTimer, draw)
            }
            (None, false) => self.cached.record(&gpu.queue, &mut encoder, &targets, draw),
        };
        recorded.map_err(|err| err.to_string())?;
        gpu.queue.submit([encoder.finish()]);
        Ok(())
    }

    /// Writes an object's buffers, instance records and deformed vertices,
    /// making its resources first (again, when a buffer outgrew its own).
    fn write_object(&mut self, gpu: &Gpu, index: usize, draw: &ObjectInputs) -> Result<(), String> {
        if let (Some(vertices), Some(mesh)) = (&draw.vertices, self.meshes.get(draw.mesh)) {
            if vertices.len() as u64 <= mesh.vertices.size() {
                gpu.queue.write_buffer(&mesh.vertices, 0, vertices);
            }
        }
        let fits = self.objects.get(index).is_some_and(|object| {
            draw.buffers.iter().all(|(key, bytes)| {
                object
                    .buffers
                    .get(key)
                    .is_none_or(|b| b.size() >= padded(bytes.len()))
            }) && object
                .instances
                .as_ref()
                .is_none_or(|b| b.size() >= padded(draw.instance_inputs.len()))
        });
        if !fits {
            let object = self.make_object(gpu, draw)?;
            if index < self.objects.len() {
                self.objects[index] = object;
            } else {
                self.objects.push(object);
            }
        }
        let object = &self.objects[index];
        for (key, bytes) in &draw.buffers {
            if let Some(buffer) = object.buffers.get(key) {
                gpu.queue.write_buffer(buffer, 0, bytes);
            }
        }
        if let Some(instances) = &object.instances {
            gpu.queue.write_buffer(instances, 0, &draw.instance_inputs);
        }
        Ok(())
    }

    /// An object's uniform and storage buffers, sized for this frame's
    /// contents, by (group, binding); the group the caller binds has none.
    fn object_buffers(
        &self,
        gpu: &Gpu,
        draw: &ObjectInputs,
    ) -> Result<HashMap<[u32; 2], wgpu::Buffer>, String> {
        let plan = self.cached.plan();
        let mut buffers = HashMap::new();
        let external_group = self.external.as_ref().map(|(group, _)| *group);
        for resource in &plan.bindings.original {
            if Some(resource.group) == external_group {
                continue;
            }
            let key = [resource.group, resource.binding];
            let usage = match resource.kind {
                ResourceKind::Uniform => wgpu::BufferUsages::UNIFORM,
                ResourceKind::Storage | ResourceKind::StorageReadWrite => {
                    wgpu::BufferUsages::STORAGE
                }
                _ => continue,
            };
            let bytes = draw.buffers.get(&key).ok_or_else(|| {
                format!(
                    "nothing to bind at group {} binding {} (`{}`)",
                    key[0], key[1], resource.name
                )
            })?;
            let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(&resource.name),
                size: padded(bytes.len()),
                usage: usage | wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            });
            buffers.insert(key, buffer);
        }
        Ok(buffers)
    }

    /// An object's buffers (sized for this frame's contents), its bind
    /// groups and its twins.
    fn make_object(&mut self, gpu: &Gpu, draw: &ObjectInputs) -> Result<Object, String> {
        let plan = self.cached.plan();
        let external_group = self.external.as_ref().map(|(group, _)| *group);
        let buffers = self.object_buffers(gpu, draw)?;
        let instances = (!draw.instance_inputs.is_empty()).then(|| {
            gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("per-instance vertex inputs"),
                size: padded(draw.instance_inputs.len()),
                usage: wgpu::BufferUsages::VERTEX
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            })
        });
        let mut bind_groups = Vec::new();
        let cache_group = self.cached.cache_group();
        for (&group, layout) in self
            .layouts
            .iter()
            .filter(|(g, _)| Some(**g) != cache_group && Some(**g) != external_group)
        {
            let mut entries = Vec::new();
            for resource in plan.bindings.original.iter().filter(|r| r.group == group) {
                let key = [group, resource.binding];
                let bound = if let Some(buffer) = buffers.get(&key) {
                    buffer.as_entire_binding()
                } else if let Some(view) = self.views.get(&key) {
                    wgpu::BindingResource::TextureView(view)
                } else if let Some(sampler) = self.samplers.get(&key) {
                    wgpu::BindingResource::Sampler(sampler)
                } else {
                    return Err(format!(
                        "nothing to bind at group {group} binding {} (`{}`)",
                        resource.binding, resource.name
                    ));
                };
                entries.push(wgpu::BindGroupEntry {
                    binding: resource.binding,
                    resource: bound,
                });
            }
            let bind_group = super::gpu::validated(&gpu.device, || {
                gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
                    label: Some("scene group"),
                    layout,
                    entries: &entries,
                })
            })
            .map_err(|err| format!("group {group}: {err}"))?;
            bind_groups.push((group, bind_group));
        }
        let sources: Vec<([u32; 2], &wgpu::Buffer)> =
            buffers.iter().map(|(key, buffer)| (*key, buffer)).collect();
        // Slot 0 holds the mesh's vertices, slot 1 the instance records:
        // the host twins those the plan reads last frame's values of.
        let mesh = self
            .meshes
            .get(draw.mesh)
            .ok_or_else(|| format!("no mesh {}", draw.mesh))?;
        let vertex: Vec<(u32, &wgpu::Buffer)> = std::iter::once((0, &mesh.vertices))
            .chain(instances.iter().map(|b| (1, b)))
            .collect();
        let textures: Vec<([u32; 2], &wgpu::TextureView)> =
            self.views.iter().map(|(key, view)| (*key, view)).collect();
        let samplers: Vec<([u32; 2], &wgpu::Sampler)> =
            self.samplers.iter().map(|(key, s)| (*key, s)).collect();
        let twins = self
            .cached
            .twins(&TwinSources {
                buffers: &sources,
                vertex_buffers: &vertex,
                textures: &textures,
                samplers: &samplers,
            })
            .map_err(|err| err.to_string())?;
        Ok(Object {
            buffers,
            instances,
            bind_groups,
            twins,
        })
    }
}

/// A buffer's size for `len` bytes: whole 16-byte rows, at least one.
fn padded(len: usize) -> u64 {
    (len as u64).max(16).div_ceil(16) * 16
}

/// A buffer holding `bytes`.
fn filled(gpu: &Gpu, label: &str, bytes: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
    let buffer = gpu.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(label),
        size: (bytes.len() as u64).max(16).div_ceil(4) * 4,
        usage: usage | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    gpu.queue.write_buffer(&buffer, 0, bytes);
    buffer
}
