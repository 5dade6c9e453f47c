//! A variant made on the application's device, run frame after frame.

use std::cell::RefCell;
use std::collections::{BTreeMap, HashMap};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex, Weak};

use shadecache_plan::{DrawKind, LoadOp, Pass, Plan, ResourceKind, TargetKind, MAX_STENCIL_DRAWS};

use crate::formats::{cache_format, host_depth_format, texture_format};
use crate::frame::Viewport;
use crate::layouts::CacheResource;
use crate::pipelines::{
    by_group, describe, pipeline, pipeline_layout, HostFormats, PassPipelineDescriptor,
    PipelineInputs,
};
use crate::timing::{NoTimer, PassTimer};
use crate::twins::{Shared, TwinSources, Twins, TwinsInner};
use crate::vertex::{TwinSlot, VertexBufferDescriptor};
use crate::{frame, layouts, params, vertex, Error, FrameLayout, Targets};

/// What the host does beyond the plan's passes.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Options {
    /// Draw the plan's `classify` pass after each frame, into
    /// [`CachedShader::classes`]: the cache's decision at each pixel.
    pub classify: bool,
    /// A debugging view: the frame's colour outputs blend additively, so
    /// with a shader writing a constant a pixel counts its shadings.
    pub count_shading: bool,
    /// The variant's `less` and `greater` depth tests pass on equal depth
    /// too. For a shared depth ([`Targets::depth`]) that already holds the
    /// cached draws' own depth, as an engine's depth prepass does: with
    /// the plan's strict tests, they would hide themselves.
    pub depth_test_or_equal: bool,
}

struct Built {
    pass: Pass,
    pipeline: wgpu::RenderPipeline,
    /// The cache group's layout for this pass: the cache resources and
    /// twins it binds, and only those (a pass that renders into this
    /// frame's payload must not also bind it).
    cache_layout: Option<wgpu::BindGroupLayout>,
    /// Its place among the passes (the classification last).
    index: usize,
    /// Whether the pass reads the draw's ordinal (`cache_draw`): the cache
    /// group is then bound per draw, at the ordinal's offset.
    per_draw: bool,
}

/// The targets the host owns, double-buffered where last frame's is read.
struct CacheTargets {
    payload: [wgpu::Texture; 2],
    age: [wgpu::Texture; 2],
    depth: [wgpu::Texture; 2],
    classes: wgpu::Texture,
    /// This frame's G-buffer (the deferred variant), by index.
    gbuffer: Vec<wgpu::TextureView>,
    /// Lowres's samples, their geometry and depth (at 1/s × 1/s), and its
    /// double-buffered history.
    lowres: Option<LowresTargets>,
    payload_views: [wgpu::TextureView; 2],
    age_views: [wgpu::TextureView; 2],
    /// Attachment views.
    depth_views: [wgpu::TextureView; 2],
    /// Depth-aspect views, to bind.
    depth_sampled: [wgpu::TextureView; 2],
    classes_view: wgpu::TextureView,
    /// The bytes of all of the above, as their formats lay them out.
    bytes: u64,
}

/// The lowres variant's own targets.
struct LowresTargets {
    samples: wgpu::TextureView,
    geometry: wgpu::TextureView,
    depth: wgpu::TextureView,
    history: [wgpu::TextureView; 2],
}

/// A shader variant and its reprojection cache on the application's
/// device. Made once from a plan and the application's frame; each frame,
/// [`CachedShader::record`] records every pass into the application's
/// encoder, calling back for the draws.
pub struct CachedShader {
    device: wgpu::Device,
    plan: Plan,
    options: Options,
    passes: Vec<Built>,
    classify: Option<Built>,
    cache_group: Option<u32>,
    twin_slots: Vec<TwinSlot>,
    depth_format: wgpu::TextureFormat,
    formats: HostFormats,
    gbuffer_formats: Vec<wgpu::TextureFormat>,
    size: (u32, u32),
    /// The part of the target the passes draw into (x, y, width, height),
    /// where it is not the whole target (split screen).
    viewport: Option<[f32; 4]>,
    /// The camera's far − near, where the application gave its planes
    /// ([`CachedShader::set_depth_range`]).
    depth_range: Option<f32>,
    targets: CacheTargets,
    /// Bumped when the targets are made again: bind groups of older ones
    /// are stale.
    generation: u64,
    params: wgpu::Buffer,
    /// The draws' ordinals, one per `DRAW_ID_STRIDE` bytes.
    draw_ids: wgpu::Buffer,
    sampler: wgpu::Sampler,
    /// This shader's number among the process's, which its twins carry.
    id: u64,
    /// The application's vertex buffer slots (the host's twins follow).
    vertex_slots: u32,
    max_bind_groups: u32,
    current: usize,
    frame: u64,
    phase: u32,
    /// Whether the next frame has no previous one (first frame, resize,
    /// reset): last frame's depth is cleared to the far plane.
    fresh: bool,
    /// Twins made and not yet filled.
    pending: Vec<Weak<TwinsInner>>,
    next_twins: u64,
}

/// What a variant's pipelines and bind groups are made from, checked
/// against the application's frame: the host's formats, the application's
/// groups, and each pass described with its cache group's layout.
#[derive(Clone)]
struct Setup {
    plan: Plan,
    options: Options,
    /// The frame's viewport, where it is not the whole target.
    viewport: Option<[f32; 4]>,
    /// The application's vertex buffer slots.
    vertex_slots: u32,
    formats: HostFormats,
    depth_format: wgpu::TextureFormat,
    gbuffer_formats: Vec<wgpu::TextureFormat>,
    cache_group: Option<u32>,
    /// The application's groups but the cache's (where it shares it, its
    /// entries are in the cache group's layout).
    user_groups: BTreeMap<u32, Vec<wgpu::BindGroupLayoutEntry>>,
    twin_slots: Vec<TwinSlot>,
    /// The plan's passes, then the classification where it is drawn.
    passes: Vec<SetupPass>,
}

/// One pass of a [`Setup`].
#[derive(Clone)]
struct SetupPass {
    pass: Pass,
    index: usize,
    described: PassPipelineDescriptor,
    cache_layout: Option<wgpu::BindGroupLayout>,
    per_draw: bool,
}

impl Setup {
    fn new(
        device: &wgpu::Device,
        plan: &Plan,
        frame: &FrameLayout<'_>,
        options: Options,
    ) -> Result<Setup, Error> {
        plan.check().map_err(Error::Plan)?;
        frame::check(plan, frame)?;
        let user_groups = layouts::user_groups(plan, frame.bind_group_layouts)?;
        let (user_buffers, twin_slots) = vertex::layouts(plan, frame.vertex_buffers)?;
        let formats = HostFormats {
            cache: cache_format(plan.cache.format),
            age: texture_format(shadecache_plan::AGE_FORMAT),
            classes: wgpu::TextureFormat::Rgba8Unorm,
            history: wgpu::TextureFormat::Rgba32Float,
        };
        let needs_stencil = plan.passes.iter().any(|p| p.stencil.is_some());
        let depth_format = host_depth_format(device, frame.depth_format, needs_stencil);
        let gbuffer_formats = gbuffer_formats(plan);
        let cache_group = layouts::cache_group(plan);
        let user: BTreeMap<u32, Vec<wgpu::BindGroupLayoutEntry>> = user_groups
            .iter()
            .filter(|(&group, _)| Some(group) != cache_group)
            .map(|(&group, entries)| (group, entries.to_vec()))
            .collect();
        // The cache's entries, and the application's when it shares the
        // cache's group.
        let mut cache_entries = layouts::cache_entries(plan)?;
        if let Some(shared) = cache_group.and_then(|group| user_groups.get(&group)) {
            cache_entries.extend(shared.iter().copied());
        }
        let buffers: Vec<Option<VertexBufferDescriptor>> = user_buffers
            .into_iter()
            .chain(twin_slots.iter().map(|t| Some(t.layout.clone())))
            .collect();
        let inputs = PipelineInputs {
            buffers: &buffers,
            frame,
            formats,
            depth_format,
            gbuffer: &gbuffer_formats,
            options,
        };
        let classify = plan.classify.as_ref().filter(|_| options.classify);
        let mut passes = Vec::with_capacity(plan.passes.len() + 1);
        for (index, pass) in plan.passes.iter().chain(classify).enumerate() {
            // The cache group's entries this pass binds, and only those.
            let cache = cache_group.map(|group| {
                let entries: Vec<wgpu::BindGroupLayoutEntry> = cache_entries
                    .iter()
                    .filter(|e| pass.bindings.contains(&[group, e.binding]))
                    .copied()
                    .collect();
                (group, entries)
            });
            let cache_layout = cache.as_ref().map(|(_, entries)| {
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("shadecache cache group"),
                    entries,
                })
            });
            let groups = by_group(user.clone(), cache, Vec::new());
            let device_groups = device.limits().max_bind_groups;
            if groups.len() as u32 > device_groups {
                let last = groups.len() - 1;
                return Err(Error::Mismatch(match cache_group {
                    Some(group) => format!(
                        "`{}` binds groups 0 to {last} (the cache's is group {group}), and the device has {device_groups}: rewrite the variant with `--max-bind-groups {device_groups}` (`Options::max_bind_groups`) or fewer, so that the cache shares a group of the application's",
                        pass.name
                    ),
                    None => format!(
                        "`{}` binds groups 0 to {last}, and the device has {device_groups}",
                        pass.name
                    ),
                }));
            }
            let per_draw = cache_group.is_some_and(|group| {
                plan.bindings
                    .cache
                    .iter()
                    .any(|r| r.name == "cache_draw" && pass.bindings.contains(&[group, r.binding]))
            });
            passes.push(SetupPass {
                pass: pass.clone(),
                index,
                described: describe(pass, &inputs, groups)?,
                cache_layout,
                per_draw,
            });
        }
        Ok(Setup {
            plan: plan.clone(),
            options,
            viewport: match frame.viewport {
                Viewport::Rect(rect) => Some(rect),
                Viewport::WholeTarget => None,
            },
            vertex_slots: frame.vertex_buffers.len() as u32,
            formats,
            depth_format,
            gbuffer_formats,
            cache_group,
            user_groups: user,
            twin_slots,
            passes,
        })
    }
}

/// A variant's pipelines described for an application that makes them
/// itself ([`CachedShader::describe_pipelines`]), and what the variant is
/// then made from with them ([`CachedShader::from_pipelines_async`]):
/// the plan, frame and options are checked once, here.
#[derive(Clone)]
pub struct DescribedPipelines(Setup);

impl DescribedPipelines {
    /// Each pass's pipeline: the plan's passes in order, then the
    /// classification where [`Options::classify`] asks for it.
    pub fn descriptors(&self) -> impl ExactSizeIterator<Item = &PassPipelineDescriptor> {
        self.0.passes.iter().map(|pass| &pass.described)
    }
}

impl std::fmt::Debug for DescribedPipelines {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DescribedPipelines")
            .field("variant", &self.0.plan.variant)
            .field("passes", &self.0.passes.len())
            .finish_non_exhaustive()
    }
}

impl std::fmt::Debug for CachedShader {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CachedShader")
            .field("variant", &self.plan.variant)
            .field("size", &self.size)
            .field("frame", &self.frame)
            .finish_non_exhaustive()
    }
}

impl CachedShader {
    /// Makes every pass's pipeline on `device` from the plan, the pass
    /// shaders (`shader` gives a file's WGSL by the name the plan uses)
    /// and the application's frame, and the cache's targets at `size`,
    /// waiting for wgpu's verdict on each: see [`CachedShader::new_async`].
    /// Behind the default feature `blocking` (it blocks on pollster).
    #[cfg(feature = "blocking")]
    pub fn new<'s>(
        device: &wgpu::Device,
        plan: &Plan,
        shader: impl Fn(&str) -> Option<&'s str>,
        frame: &FrameLayout<'_>,
        size: (u32, u32),
        options: Options,
    ) -> Result<CachedShader, Error> {
        pollster::block_on(Self::new_async(device, plan, shader, frame, size, options))
    }

    /// Makes every pass's pipeline on `device` from the plan, the pass
    /// shaders (`shader` gives a file's WGSL by the name the plan uses)
    /// and the application's frame, and the cache's targets at `size`.
    /// Errors name what does not match, what the variant refuses, a size
    /// the device cannot hold, or what wgpu rejected (each pipeline is made
    /// in an error scope, so nothing reaches wgpu's panicking handler).
    pub async fn new_async<'s>(
        device: &wgpu::Device,
        plan: &Plan,
        shader: impl Fn(&str) -> Option<&'s str>,
        frame: &FrameLayout<'_>,
        size: (u32, u32),
        options: Options,
    ) -> Result<CachedShader, Error> {
        check_size(device, size)?;
        let setup = Setup::new(device, plan, frame, options)?;
        let user: BTreeMap<u32, wgpu::BindGroupLayout> = setup
            .user_groups
            .iter()
            .map(|(&group, entries)| {
                let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some("application group"),
                    entries,
                });
                (group, layout)
            })
            .collect();
        let mut pipelines = Vec::with_capacity(setup.passes.len());
        for pass in &setup.passes {
            let source = shader(&pass.described.shader).ok_or_else(|| {
                Error::Mismatch(format!(
                    "{}: no shader `{}` was given",
                    pass.described.label, pass.described.shader
                ))
            })?;
            let layout = pipeline_layout(
                device,
                &user,
                setup.cache_group.zip(pass.cache_layout.as_ref()),
            );
            pipelines.push(pipeline(device, &pass.described, source, &layout).await?);
        }
        Self::assemble(device, setup, size, pipelines).await
    }

    /// Every pass's render pipeline described, for an application that
    /// makes its pipelines itself, as an engine's pipeline cache does off
    /// the frame: make each with the pass's WGSL (`shader` names the
    /// plan's file) and give them, in order, to
    /// [`CachedShader::from_pipelines_async`]. Errors as
    /// [`CachedShader::new_async`]'s, but for what only wgpu can tell.
    pub fn describe_pipelines(
        device: &wgpu::Device,
        plan: &Plan,
        frame: &FrameLayout<'_>,
        options: Options,
    ) -> Result<DescribedPipelines, Error> {
        Setup::new(device, plan, frame, options).map(DescribedPipelines)
    }

    /// The variant with pipelines the application made from `described`
    /// (one per descriptor, in its order), and the cache's targets at
    /// `size`: what [`CachedShader::new_async`] makes when it makes the
    /// pipelines itself.
    pub async fn from_pipelines_async(
        device: &wgpu::Device,
        described: DescribedPipelines,
        size: (u32, u32),
        pipelines: Vec<wgpu::RenderPipeline>,
    ) -> Result<CachedShader, Error> {
        check_size(device, size)?;
        let DescribedPipelines(setup) = described;
        if pipelines.len() != setup.passes.len() {
            return Err(Error::Mismatch(format!(
                "{} pipelines were given for the {} passes described",
                pipelines.len(),
                setup.passes.len()
            )));
        }
        Self::assemble(device, setup, size, pipelines).await
    }

    /// The variant from its pipelines (one per pass of `setup`): the
    /// cache's uniform, sampler and targets.
    async fn assemble(
        device: &wgpu::Device,
        setup: Setup,
        size: (u32, u32),
        pipelines: Vec<wgpu::RenderPipeline>,
    ) -> Result<CachedShader, Error> {
        let Setup {
            plan,
            options,
            viewport,
            vertex_slots,
            formats,
            depth_format,
            gbuffer_formats,
            cache_group,
            twin_slots,
            passes: described,
            ..
        } = setup;
        let mut passes = Vec::with_capacity(described.len());
        let mut classify = None;
        for (pass, pipeline) in described.into_iter().zip(pipelines) {
            let built = Built {
                pipeline,
                pass: pass.pass,
                cache_layout: pass.cache_layout,
                index: pass.index,
                per_draw: pass.per_draw,
            };
            if built.index < plan.passes.len() {
                passes.push(built);
            } else {
                classify = Some(built);
            }
        }
        // In an error scope, as the pipelines: a plan's uniform the device
        // refuses is the plan's error, not wgpu's panic.
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let params = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("shadecache CacheParams"),
            size: params::size(&plan.cache.params)? as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        if let Some(err) = scope.pop().await {
            return Err(Error::Wgpu(format!("the CacheParams buffer: {err}")));
        }
        // rgba32float cannot be filtered: its variants load texels, and
        // the layout asks for a non-filtering sampler.
        let filter = if formats.cache == wgpu::TextureFormat::Rgba16Float {
            wgpu::FilterMode::Linear
        } else {
            wgpu::FilterMode::Nearest
        };
        let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
            label: Some("shadecache cache sampler"),
            mag_filter: filter,
            min_filter: filter,
            ..wgpu::SamplerDescriptor::default()
        });
        let draw_ids = draw_ids(device);
        let cached = CachedShader {
            device: device.clone(),
            targets: CacheTargets::new(
                device,
                size,
                formats,
                depth_format,
                (&gbuffer_formats, lowres_divisor(&plan)),
            ),
            draw_ids,
            plan,
            options,
            passes,
            classify,
            cache_group,
            twin_slots,
            depth_format,
            formats,
            gbuffer_formats,
            size,
            viewport,
            depth_range: None,
            generation: 0,
            params,
            sampler,
            id: NEXT_SHADER.fetch_add(1, Ordering::Relaxed),
            vertex_slots,
            max_bind_groups: device.limits().max_bind_groups,
            current: 0,
            frame: 0,
            phase: 0,
            fresh: true,
            pending: Vec::new(),
            next_twins: 0,
        };
        Ok(cached)
    }

    /// The twins of one draw's buffers (see [`Twins`]), waiting for
    /// wgpu's verdict on their bind groups: see [`CachedShader::twins_async`].
    /// Behind the default feature `blocking`.
    #[cfg(feature = "blocking")]
    pub fn twins(&mut self, sources: &TwinSources<'_>) -> Result<Twins, Error> {
        pollster::block_on(self.twins_async(sources))
    }

    /// The twins of one draw's buffers (see [`Twins`]): made once per
    /// draw, passed to every [`Draw::draw`] or [`Draw::draw_indexed`] of
    /// that draw. Every plan has them (a plan that keeps nothing of the
    /// draw's gives empty ones). Errors when a buffer the plan keeps last
    /// frame's copy of is not among `sources` or cannot be copied, or when
    /// wgpu rejects the bind groups made with them (in an error scope:
    /// the application's resources in the cache's group are checked here,
    /// once, not in the frame).
    pub async fn twins_async(&mut self, sources: &TwinSources<'_>) -> Result<Twins, Error> {
        let mut copies = Vec::new();
        let mut bound = Vec::new();
        for twin in &self.plan.bindings.previous {
            let key = [twin.shadows.group, twin.shadows.binding];
            let &(_, source) =
                sources
                    .buffers
                    .iter()
                    .find(|(k, _)| *k == key)
                    .ok_or_else(|| {
                        Error::Mismatch(format!(
                    "the variant reads last frame's `{}` (group {}, binding {}): give its buffer",
                    twin.shadows.name, key[0], key[1]
                ))
                    })?;
            let usage = match twin.shadows.kind {
                ResourceKind::Uniform => wgpu::BufferUsages::UNIFORM,
                _ => wgpu::BufferUsages::STORAGE,
            };
            let copy = self.twin_buffer(&twin.shadows.name, source, usage)?;
            bound.push((twin.binding, copy.clone()));
            copies.push((source.clone(), copy));
        }
        let shared = self.shared_resources(sources)?;
        let mut vertex = Vec::new();
        for slot in &self.twin_slots {
            let &(_, source) = sources
                .vertex_buffers
                .iter()
                .find(|(s, _)| *s == slot.source)
                .ok_or_else(|| {
                    Error::Mismatch(format!(
                        "the variant reads last frame's vertex buffer {}: give it",
                        slot.source
                    ))
                })?;
            let name = format!("vertex buffer {}", slot.source);
            let copy = self.twin_buffer(&name, source, wgpu::BufferUsages::VERTEX)?;
            vertex.push((slot.slot, copy.clone()));
            copies.push((source.clone(), copy));
        }
        let inner = Arc::new(TwinsInner {
            id: self.next_twins,
            owner: self.id,
            copies,
            bound,
            shared,
            vertex,
            bind_groups: Mutex::new(HashMap::new()),
        });
        self.check_bind_groups(&inner).await?;
        self.next_twins += 1;
        self.pending.push(Arc::downgrade(&inner));
        Ok(Twins { inner })
    }

    /// Makes the cache group's bind groups of every pass with `twins`, for
    /// both cache slots, in an error scope, and keeps them. After a resize
    /// they are made again from the same resources (the host's new targets
    /// have the old formats), so what wgpu accepted here it accepts then.
    async fn check_bind_groups(&self, twins: &TwinsInner) -> Result<(), Error> {
        let Some(group) = self.cache_group else {
            return Ok(());
        };
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut made = HashMap::new();
        for built in self.passes.iter().chain(&self.classify) {
            if let Some(layout) = &built.cache_layout {
                let make = |current| self.cache_bind_group(built, layout, twins, current);
                made.insert(built.index, (self.generation, [make(0)?, make(1)?]));
            }
        }
        if let Some(err) = scope.pop().await {
            return Err(Error::Wgpu(format!(
                "the cache group (group {group}): {err}"
            )));
        }
        *twins
            .bind_groups
            .lock()
            .map_err(|_| Error::Wgpu("a twins' bind groups were poisoned".into()))? = made;
        Ok(())
    }

    /// The application's resources in the cache's group, from `sources`.
    fn shared_resources(&self, sources: &TwinSources<'_>) -> Result<Vec<(u32, Shared)>, Error> {
        let Some(group) = self.cache_group else {
            return Ok(Vec::new());
        };
        let mut shared = Vec::new();
        for resource in self
            .plan
            .bindings
            .original
            .iter()
            .filter(|r| r.group == group)
        {
            let key = [group, resource.binding];
            let found = if let Some((_, b)) = sources.buffers.iter().find(|(k, _)| *k == key) {
                Shared::Buffer((*b).clone())
            } else if let Some((_, t)) = sources.textures.iter().find(|(k, _)| *k == key) {
                Shared::Texture((*t).clone())
            } else if let Some((_, s)) = sources.samplers.iter().find(|(k, _)| *k == key) {
                Shared::Sampler((*s).clone())
            } else {
                return Err(Error::Mismatch(format!(
                    "`{}` (group {group}, binding {}) shares its group with the cache, so the host binds it: give it among the draw's sources",
                    resource.name, resource.binding
                )));
            };
            shared.push((resource.binding, found));
        }
        Ok(shared)
    }

    fn twin_buffer(
        &self,
        name: &str,
        source: &wgpu::Buffer,
        usage: wgpu::BufferUsages,
    ) -> Result<wgpu::Buffer, Error> {
        if !source.usage().contains(wgpu::BufferUsages::COPY_SRC) {
            return Err(Error::Mismatch(format!(
                "the buffer of `{name}` lacks BufferUsages::COPY_SRC: the host copies it into last frame's each frame"
            )));
        }
        Ok(self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("last frame's {name}")),
            size: source.size().div_ceil(4) * 4,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        }))
    }

    /// Records one frame without timing: see [`CachedShader::record_timed`].
    pub fn record(
        &mut self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets<'_>,
        draw: impl FnMut(&mut Draw<'_, '_>),
    ) -> Result<(), Error> {
        self.record_timed(queue, encoder, targets, &mut NoTimer, draw)
    }

    /// Records one frame into `encoder`: the refresh uniform, every pass
    /// of the plan in order (and the classification when asked for), each
    /// timed by `timer`, calling `draw` once per pass for the application's
    /// draws, then the copies of this frame's buffers into their twins.
    /// Submit the encoder before recording the next frame.
    pub fn record_timed<T: PassTimer>(
        &mut self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets<'_>,
        timer: &mut T,
        mut draw: impl FnMut(&mut Draw<'_, '_>),
    ) -> Result<(), Error> {
        self.record_frame(
            queue,
            encoder,
            targets,
            timer,
            &mut |built, binder, mut render| draw_pass(built, binder, &mut render, &mut draw),
        )
    }

    /// Records one frame whose draws an engine's own render commands
    /// record (Bevy's render phases, which need the render pass itself),
    /// as [`CachedShader::record_timed`] does otherwise: the host begins
    /// each pass with its pipeline, and the cache's group and vertex twins
    /// of `twins` bound, and hands it to `draw` to record the pass's draws
    /// (the engine sets its own bind groups and buffers, and never the
    /// cache's group or the twins' slots). A screen-space pass is the
    /// host's own triangle and is not handed over. Every draw of the frame
    /// reads the same twins, so only a plan whose twins are per frame
    /// (a camera's view, not each object's transforms) is right here; the
    /// deferred variant, which tells draws apart in the stencil, is
    /// refused. An `Err` from `draw` ends the frame with [`Error::Draw`].
    pub fn record_engine_timed<T: PassTimer>(
        &mut self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets<'_>,
        timer: &mut T,
        twins: &Twins,
        mut draw: impl FnMut(&Pass, wgpu::RenderPass<'static>) -> Result<(), String>,
    ) -> Result<(), Error> {
        if let Some(pass) = self
            .passes
            .iter()
            .chain(&self.classify)
            .find(|built| built.per_draw || built.pass.stencil.is_some())
        {
            return Err(Error::Refused(format!(
                "pass `{}` tells each draw apart (its stencil reference or its draw ordinal), which an engine's own draw commands do not give",
                pass.pass.name
            )));
        }
        self.record_frame(
            queue,
            encoder,
            targets,
            timer,
            &mut |built, binder, mut render| {
                let mut draws = Draw::new(&mut render, built, binder);
                let own = draws.next_draw(twins);
                if let Some(err) = draws.error.take() {
                    return Err(err);
                }
                if own {
                    draw(&built.pass, render).map_err(Error::Draw)?;
                }
                Ok(())
            },
        )
    }

    /// One whole frame: the targets checked, the frame begun, every pass
    /// recorded by `record`, the frame ended.
    fn record_frame<T: PassTimer>(
        &mut self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets<'_>,
        timer: &mut T,
        record: &mut dyn FnMut(&Built, &Binder<'_>, wgpu::RenderPass<'static>) -> Result<(), Error>,
    ) -> Result<(), Error> {
        self.check_targets(targets)?;
        self.begin_frame(queue, encoder)?;
        let used = self.record_passes(encoder, targets, timer, Part::Whole, record)?;
        self.end_frame(encoder, used);
        Ok(())
    }

    /// The start of a frame: the refresh uniform, last frame's depth at the
    /// far plane when there is no last frame, and new twins filled.
    fn begin_frame(
        &mut self,
        queue: &wgpu::Queue,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(), Error> {
        let state = params::FrameState {
            size: self.size,
            viewport: self
                .viewport
                .unwrap_or([0.0, 0.0, self.size.0 as f32, self.size.1 as f32]),
            frame: self.frame,
            phase: self.phase,
            depth_range: self.depth_range.unwrap_or(0.0),
        };
        queue.write_buffer(&self.params, 0, &params::bytes(&self.plan, state)?);
        if self.fresh {
            // No previous frame: a depth at the far plane makes every
            // pixel miss (the depth test's tolerance, ε·|expected − far|,
            // is below the distance of anything in front of it).
            clear_depth(
                encoder,
                &self.targets.depth_views[1 - self.current],
                self.plan.clear.depth as f32,
            );
        }
        // Twins new this frame hold this frame's contents.
        for inner in self.pending.drain(..).filter_map(|weak| weak.upgrade()) {
            inner.copy(encoder);
        }
        Ok(())
    }

    /// The end of a frame: the twins drawn with copy this frame's
    /// contents, and the frame's state moves on.
    fn end_frame(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        used: BTreeMap<u64, Arc<TwinsInner>>,
    ) {
        // This frame's contents are next frame's last-frame contents.
        for inner in used.values() {
            inner.copy(encoder);
        }
        self.current = 1 - self.current;
        self.fresh = false;
        self.frame = self.frame.wrapping_add(1);
        let period = self.plan.refresh.period;
        self.phase = if period == 0 {
            0
        } else {
            (self.phase + 1) % period
        };
    }

    /// Records more draws into the last recorded frame: every pass of the
    /// plan again, each loading what the frame's colour and depth hold
    /// (`targets.clear` is ignored), calling `draw` once per pass. This
    /// draws a frame in parts, one part a submission (seed 000 §7's
    /// partitioned rendering: an I-frame spread over the displayed frames
    /// before it is shown); the parts together are the frame drawn at
    /// once, in the same order. Nothing of the frame's state moves on. A
    /// plan with a cache is refused: its passes read last frame's cache
    /// and write this frame's, which a part would mix.
    pub fn record_more_timed<T: PassTimer>(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets<'_>,
        timer: &mut T,
        mut draw: impl FnMut(&mut Draw<'_, '_>),
    ) -> Result<(), Error> {
        if self.cache_group.is_some() {
            return Err(Error::Refused(
                "a frame drawn in parts needs a plan without a cache: each pass reads last frame's cache and writes this frame's".into(),
            ));
        }
        if self.fresh {
            return Err(Error::Mismatch(
                "no frame recorded to draw more into: record its first part with `record_timed`"
                    .into(),
            ));
        }
        self.check_targets(targets)?;
        let targets = Targets {
            clear: None,
            ..targets.clone()
        };
        self.record_passes(
            encoder,
            &targets,
            timer,
            Part::More,
            &mut |built, binder, mut render| draw_pass(built, binder, &mut render, &mut draw),
        )?;
        Ok(())
    }

    /// Records every pass of the plan (and the classification), each
    /// timed by `timer`, handing each render pass, begun with its pipeline,
    /// to `record`; returns the twins drawn with, by id.
    fn record_passes<T: PassTimer>(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        targets: &Targets<'_>,
        timer: &mut T,
        part: Part,
        record: &mut dyn FnMut(&Built, &Binder<'_>, wgpu::RenderPass<'static>) -> Result<(), Error>,
    ) -> Result<BTreeMap<u64, Arc<TwinsInner>>, Error> {
        let binder = Binder {
            shader: self,
            used: RefCell::new(BTreeMap::new()),
        };
        let built = self.passes.iter().chain(&self.classify);
        for built in built {
            let attachments = self.attachments(&built.pass, targets);
            let query = timer.begin(encoder, &built.pass.name);
            let mut render = encoder
                .begin_render_pass(&wgpu::RenderPassDescriptor {
                    label: Some(&built.pass.name),
                    color_attachments: &attachments,
                    depth_stencil_attachment: Some(self.depth_attachment(
                        &built.pass,
                        part,
                        targets,
                    )),
                    timestamp_writes: timer.timestamp_writes(&query),
                    ..wgpu::RenderPassDescriptor::default()
                })
                // The pass ends (is dropped) inside `record`, before the
                // encoder is used again; wgpu checks that it is.
                .forget_lifetime();
            render.set_pipeline(&built.pipeline);
            if let (Some([x, y, width, height]), 1) = (self.viewport, built.pass.resolution_divisor)
            {
                render.set_viewport(x, y, width, height, 0.0, 1.0);
            }
            record(built, &binder, render)?;
            timer.end(encoder, query);
        }
        // What the passes left in the application's depth is the depth
        // the next frame reprojects against.
        if let (Some(view), Part::Whole) = (targets.depth, part) {
            encoder.copy_texture_to_texture(
                view.texture().as_image_copy(),
                self.targets.depth[self.current].as_image_copy(),
                view.texture().size(),
            );
        }
        Ok(binder.used.into_inner())
    }

    fn check_targets(&self, targets: &Targets<'_>) -> Result<(), Error> {
        if let Some(view) = targets.depth {
            let texture = view.texture();
            let size = (texture.width(), texture.height());
            if texture.format() != self.depth_format {
                return Err(Error::Mismatch(format!(
                    "the application's depth is {:?}, and the cache's is {:?} (the frame's depth format{})",
                    texture.format(),
                    self.depth_format,
                    if self.depth_format.has_stencil_aspect() { ", with the stencil the deferred variant needs" } else { "" }
                )));
            }
            // Depth24Plus's bits are the driver's: WebGPU does not copy it.
            use wgpu::TextureFormat as F;
            if matches!(
                self.depth_format,
                F::Depth24Plus | F::Depth24PlusStencil8 | F::Stencil8
            ) {
                return Err(Error::Refused(format!(
                    "the application's depth is {:?}, which cannot be copied into the cache for the next frame: share a depth32float, depth32float-stencil8 or depth16unorm depth",
                    self.depth_format
                )));
            }
            if size != self.size || texture.depth_or_array_layers() != 1 {
                return Err(Error::Mismatch(format!(
                    "the application's depth is {}×{}, the cache {}×{}",
                    size.0, size.1, self.size.0, self.size.1
                )));
            }
            if !texture.usage().contains(wgpu::TextureUsages::COPY_SRC) {
                return Err(Error::Mismatch(
                    "the application's depth lacks TextureUsages::COPY_SRC: the host copies it into the cache for the next frame's reprojection".into(),
                ));
            }
        }
        for pass in &self.plan.passes {
            for target in pass
                .color_targets
                .iter()
                .filter(|t| t.target == TargetKind::Color)
            {
                let location = target.location as usize;
                let view = targets
                    .color
                    .get(location)
                    .copied()
                    .flatten()
                    .ok_or_else(|| {
                        Error::Mismatch(format!("no colour view for @location({location})"))
                    })?;
                let texture = view.texture();
                let size = (texture.width(), texture.height());
                if size != self.size {
                    return Err(Error::Mismatch(format!(
                        "the colour target at @location({location}) is {}×{}, the cache {}×{}: call `resize` when the frame's size changes",
                        size.0, size.1, self.size.0, self.size.1
                    )));
                }
            }
        }
        Ok(())
    }

    fn attachments<'a>(
        &'a self,
        pass: &Pass,
        targets: &Targets<'a>,
    ) -> Vec<Option<wgpu::RenderPassColorAttachment<'a>>> {
        let t = &self.targets;
        let current = self.current;
        let mut attachments: Vec<Option<wgpu::RenderPassColorAttachment<'a>>> = Vec::new();
        for target in &pass.color_targets {
            let index = target.location as usize;
            if attachments.len() <= index {
                attachments.resize(index + 1, None);
            }
            let color = |c: [f64; 4]| wgpu::Color {
                r: c[0],
                g: c[1],
                b: c[2],
                a: c[3],
            };
            let (view, clear) = match target.target {
                TargetKind::Cache => (
                    &t.payload_views[current],
                    Some(color(self.plan.clear.cache)),
                ),
                TargetKind::Age => (&t.age_views[current], Some(wgpu::Color::TRANSPARENT)),
                TargetKind::Classes => (&t.classes_view, Some(wgpu::Color::TRANSPARENT)),
                TargetKind::GBuffer => match t.gbuffer.get(index) {
                    Some(view) => (view, Some(wgpu::Color::TRANSPARENT)),
                    None => continue,
                },
                TargetKind::Samples | TargetKind::SampleGeometry | TargetKind::History => {
                    let Some(lowres) = &t.lowres else { continue };
                    let view = match target.target {
                        TargetKind::Samples => &lowres.samples,
                        TargetKind::SampleGeometry => &lowres.geometry,
                        _ => &lowres.history[current],
                    };
                    (view, Some(wgpu::Color::TRANSPARENT))
                }
                // The application's own clear, on the pass that clears.
                TargetKind::Color => match targets.color.get(index).copied().flatten() {
                    Some(view) => (view, targets.clear),
                    None => continue,
                },
            };
            let load = match (target.load, clear) {
                (LoadOp::Clear, Some(clear)) => wgpu::LoadOp::Clear(clear),
                _ => wgpu::LoadOp::Load,
            };
            attachments[index] = Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load,
                    store: wgpu::StoreOp::Store,
                },
            });
        }
        attachments
    }

    /// The depth attachment of `pass`: this frame's depth buffer, or for
    /// [`Part::More`] the last recorded frame's, loaded.
    fn depth_attachment<'t>(
        &'t self,
        pass: &Pass,
        part: Part,
        targets: &Targets<'t>,
    ) -> wgpu::RenderPassDepthStencilAttachment<'t> {
        // The application's depth, where it shares its frame: loaded,
        // tested and written, never cleared (`Targets::depth`).
        if let (Some(view), true) = (targets.depth, pass.resolution_divisor <= 1) {
            return wgpu::RenderPassDepthStencilAttachment {
                view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                // The stencil is the deferred variant's own (its draw
                // ordinals and reuse marks): cleared where its plan clears.
                stencil_ops: self
                    .depth_format
                    .has_stencil_aspect()
                    .then_some(wgpu::Operations {
                        load: match (part, pass.depth.load) {
                            (Part::Whole, LoadOp::Clear) => wgpu::LoadOp::Clear(0),
                            _ => wgpu::LoadOp::Load,
                        },
                        store: wgpu::StoreOp::Store,
                    }),
            };
        }
        let (load, slot) = match (part, pass.depth.load) {
            (Part::More, _) => (wgpu::LoadOp::Load, 1 - self.current),
            (Part::Whole, LoadOp::Clear) => (
                wgpu::LoadOp::Clear(self.plan.clear.depth as f32),
                self.current,
            ),
            (Part::Whole, LoadOp::Load) => (wgpu::LoadOp::Load, self.current),
        };
        // The stencil holds the deferred variant's draw ordinals and reuse
        // marks from its geometry pass on; other plans do not use it.
        let stencil = self
            .depth_format
            .has_stencil_aspect()
            .then_some(wgpu::Operations {
                load: match load {
                    wgpu::LoadOp::Clear(_) => wgpu::LoadOp::Clear(0),
                    _ => wgpu::LoadOp::Load,
                },
                store: wgpu::StoreOp::Store,
            });
        // Lowres's samples have a depth buffer of their size.
        let view = match (&self.targets.lowres, pass.resolution_divisor) {
            (Some(lowres), d) if d > 1 => &lowres.depth,
            _ => &self.targets.depth_views[slot],
        };
        wgpu::RenderPassDepthStencilAttachment {
            view,
            depth_ops: Some(wgpu::Operations {
                load,
                store: wgpu::StoreOp::Store,
            }),
            stencil_ops: stencil,
        }
    }

    /// Makes the cache's targets at a new size: the cache starts over as
    /// after [`CachedShader::reset`], its next frame missing everywhere. A
    /// size of zero or past the device's largest 2D texture is an error,
    /// and the cache keeps its size.
    pub fn resize(&mut self, size: (u32, u32)) -> Result<(), Error> {
        if size == self.size {
            return Ok(());
        }
        check_size(&self.device, size)?;
        self.size = size;
        self.targets = CacheTargets::new(
            &self.device,
            size,
            self.formats,
            self.depth_format,
            (&self.gbuffer_formats, lowres_divisor(&self.plan)),
        );
        self.generation += 1;
        self.reset();
        Ok(())
    }

    /// The bytes of GPU memory the targets this cache owns take, as their
    /// formats lay them out (drivers may pad and align them further): the
    /// payload, age and depth twice (this frame's and last frame's), the
    /// classification, the deferred variant's G-buffer, lowres's samples
    /// and history. Three-pass with an `rgba16float` payload and 32-bit
    /// depth owns 32 bytes a pixel. Pipelines, bind groups and the
    /// application's own targets are not counted.
    pub fn target_bytes(&self) -> u64 {
        self.targets.bytes
    }

    /// Forgets last frame (a camera cut, a teleport): the cache starts
    /// over as one just made. The next frame misses everywhere, and the
    /// frame counter and refresh phase start again from 0, so the frames
    /// after a reset are those of a new cache (what a profile of a cold
    /// start measures). An application that keeps its own count calls
    /// [`CachedShader::set_frame_counter`] after it.
    pub fn reset(&mut self) {
        self.fresh = true;
        self.set_frame_counter(0);
    }

    /// The camera's near and far planes (view-space distances), from the
    /// next frame on: a lowres plan whose upsampling takes σz as a share of
    /// the depth range (the paper's, `depth_tolerance: of-range`) needs
    /// them. `None`, or a far plane that is not finite and beyond the near
    /// one (an infinite far plane), leaves σz a share of the depth itself,
    /// as it is for every plan until this is called. Other plans ignore it.
    pub fn set_depth_range(&mut self, planes: Option<(f32, f32)>) {
        self.depth_range = planes
            .filter(|(near, far)| near.is_finite() && far.is_finite() && far > near)
            .map(|(near, far)| far - near);
    }

    /// Sets the frame counter c, as if that many frames had been run, and
    /// the refresh phase to c mod Δn; the phase then advances by one modulo
    /// Δn per frame (so the period stays exact when the counter wraps).
    pub fn set_frame_counter(&mut self, frame: u64) {
        let period = u64::from(self.plan.refresh.period);
        self.frame = frame;
        self.phase = if period == 0 {
            0
        } else {
            (frame % period) as u32
        };
    }

    /// Sets the refresh period Δn from the next frame on: a pixel's value
    /// is then at most `period` frames old (what a governor lowers when
    /// the cached frames drift from the original). The cache keeps what it
    /// holds: a value older than the new period is refreshed within it,
    /// the pattern reaching every pixel once a period. The phase becomes
    /// c mod Δn. Refused for 0 (no refresh, which leaves wrong values
    /// forever) and past the largest period the refresh indicator takes,
    /// and for a variant whose refresh pattern is its sampling lattice
    /// (`lowres`: Δn is its s², fixed by its passes).
    pub fn set_refresh_period(&mut self, period: u32) -> Result<(), Error> {
        if self.plan.upsampling.is_some() {
            return Err(Error::Refused(format!(
                "this variant's refresh period is its lattice's s² = {}, fixed by its passes",
                self.plan.refresh.period
            )));
        }
        if period == 0 || period > shadecache_plan::MAX_REFRESH_PERIOD {
            return Err(Error::Refused(format!(
                "a refresh period of {period} frames: it is from 1 to {}",
                shadecache_plan::MAX_REFRESH_PERIOD
            )));
        }
        self.plan.refresh.period = period;
        self.set_frame_counter(self.frame);
        Ok(())
    }

    /// The refresh period Δn the next frame runs with.
    pub fn refresh_period(&self) -> u32 {
        self.plan.refresh.period
    }

    /// The frame counter c.
    pub fn frame_counter(&self) -> u64 {
        self.frame
    }

    /// The plan it runs.
    pub fn plan(&self) -> &Plan {
        &self.plan
    }

    /// The group the host binds: the cache's resources, the twins, and
    /// the application's resources when the shader uses all four groups.
    pub fn cache_group(&self) -> Option<u32> {
        self.cache_group
    }

    /// What it does beyond the plan's passes.
    pub fn options(&self) -> Options {
        self.options
    }

    /// The size of its targets, in pixels.
    pub fn size(&self) -> (u32, u32) {
        self.size
    }

    /// The last recorded frame's depth buffer.
    pub fn depth(&self) -> &wgpu::Texture {
        &self.targets.depth[1 - self.current]
    }

    /// The last recorded frame's payload texture.
    pub fn payload(&self) -> &wgpu::Texture {
        &self.targets.payload[1 - self.current]
    }

    /// The last recorded frame's age texture (r16float): at each pixel
    /// whose cache entry was written, frames since its value was computed.
    pub fn age(&self) -> &wgpu::Texture {
        &self.targets.age[1 - self.current]
    }

    /// The last frame's classes, when classification is on.
    pub fn classes(&self) -> &wgpu::Texture {
        &self.targets.classes
    }
}

/// Which part of a frame a recording is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    /// A frame (or its first part): its passes start as the plan says.
    Whole,
    /// More draws into the last recorded frame: every target loads.
    More,
}

/// Numbers the shaders of a process, so that a draw can tell its own
/// shader's twins from another's.
static NEXT_SHADER: AtomicU64 = AtomicU64::new(0);

/// Whether the device can hold the cache's targets at `size`.
fn check_size(device: &wgpu::Device, size: (u32, u32)) -> Result<(), Error> {
    let most = device.limits().max_texture_dimension_2d;
    if size.0 == 0 || size.1 == 0 || size.0 > most || size.1 > most {
        return Err(Error::Limits(format!(
            "the cache's targets cannot be {}×{}: this device's 2D textures are 1 to {most} texels a side",
            size.0, size.1
        )));
    }
    Ok(())
}

/// The formats of the G-buffer textures the plan's passes render into,
/// by index (the target's location).
fn gbuffer_formats(plan: &Plan) -> Vec<wgpu::TextureFormat> {
    let mut formats = Vec::new();
    for target in plan
        .passes
        .iter()
        .flat_map(|p| &p.color_targets)
        .filter(|t| t.target == TargetKind::GBuffer)
    {
        let index = target.location as usize;
        if formats.len() <= index {
            formats.resize(index + 1, wgpu::TextureFormat::R32Uint);
        }
        formats[index] = texture_format(target.format);
    }
    formats
}

impl CacheTargets {
    fn new(
        device: &wgpu::Device,
        size: (u32, u32),
        formats: HostFormats,
        depth_format: wgpu::TextureFormat,
        (gbuffer_formats, lowres_divisor): (&[wgpu::TextureFormat], Option<u32>),
    ) -> CacheTargets {
        let bytes = std::cell::Cell::new(0u64);
        let target = |label: &str, size: (u32, u32), format| {
            let texture = render_target(device, label, size, format);
            bytes.set(bytes.get() + texture_bytes(&texture));
            texture
        };
        let make = |label: &str, format| target(label, size, format);
        let pair = |label: &str, format| [make(label, format), make(label, format)];
        let payload = pair("shadecache payload", formats.cache);
        let age = pair("shadecache age", formats.age);
        let depth = pair("shadecache depth", depth_format);
        let classes = make("shadecache classes", formats.classes);
        let view = |t: &wgpu::Texture| t.create_view(&wgpu::TextureViewDescriptor::default());
        let depth_only = |t: &wgpu::Texture| {
            t.create_view(&wgpu::TextureViewDescriptor {
                aspect: wgpu::TextureAspect::DepthOnly,
                ..wgpu::TextureViewDescriptor::default()
            })
        };
        let gbuffer = gbuffer_formats
            .iter()
            .map(|&format| view(&make("shadecache G-buffer", format)))
            .collect();
        let lowres = lowres_divisor.map(|d| {
            let low = (size.0.div_ceil(d), size.1.div_ceil(d));
            let small = |label: &str, format| view(&target(label, low, format));
            LowresTargets {
                samples: small("shadecache samples", formats.cache),
                geometry: small("shadecache sample geometry", formats.history),
                depth: depth_only_attachment(&target(
                    "shadecache samples' depth",
                    low,
                    depth_format,
                )),
                history: [
                    view(&make("shadecache history", formats.history)),
                    view(&make("shadecache history", formats.history)),
                ],
            }
        });
        CacheTargets {
            gbuffer,
            lowres,
            payload_views: [view(&payload[0]), view(&payload[1])],
            age_views: [view(&age[0]), view(&age[1])],
            depth_views: [view(&depth[0]), view(&depth[1])],
            depth_sampled: [depth_only(&depth[0]), depth_only(&depth[1])],
            classes_view: view(&classes),
            bytes: bytes.get(),
            payload,
            age,
            depth,
            classes,
        }
    }
}

/// The bytes a texture holds, as its format lays its texels out: every
/// layer and sample of its first mip level. A depth format without a
/// defined layout counts 4 bytes for 24-bit depth and 4 for a stencil
/// beside 32-bit depth, as most drivers store them; drivers may pad rows
/// and align allocations, so this is what it needs at least. How
/// [`CachedShader::target_bytes`] counts the cache's, for an application
/// that adds its own copies (a watch's) to them.
pub fn texture_bytes(texture: &wgpu::Texture) -> u64 {
    let format = texture.format();
    let texel = format.block_copy_size(None).unwrap_or(match format {
        wgpu::TextureFormat::Depth32FloatStencil8 => 8,
        _ => 4,
    });
    let size = texture.size();
    [
        size.width,
        size.height,
        size.depth_or_array_layers,
        texture.sample_count(),
        texel,
    ]
    .into_iter()
    .map(u64::from)
    .product()
}

/// The divisor of the plan's reduced-resolution pass (lowres's samples),
/// if it has one.
fn lowres_divisor(plan: &Plan) -> Option<u32> {
    plan.passes
        .iter()
        .map(|p| p.resolution_divisor)
        .find(|&d| d > 1)
}

/// An attachment view of a depth texture.
fn depth_only_attachment(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor::default())
}

/// The buffer of draw ordinals: ordinal i + 1 at byte i·`DRAW_ID_STRIDE`.
fn draw_ids(device: &wgpu::Device) -> wgpu::Buffer {
    let stride = layouts::DRAW_ID_STRIDE as usize;
    let mut bytes = vec![0u8; stride * layouts::DRAW_IDS as usize];
    for i in 0..layouts::DRAW_IDS as usize {
        bytes[i * stride..i * stride + 4].copy_from_slice(&(i as u32 + 1).to_le_bytes());
    }
    wgpu::util::DeviceExt::create_buffer_init(
        device,
        &wgpu::util::BufferInitDescriptor {
            label: Some("shadecache draw ordinals"),
            contents: &bytes,
            usage: wgpu::BufferUsages::UNIFORM,
        },
    )
}

/// A 2D texture of `size` that passes render into, that later passes
/// sample, and that can be copied out (to read it back).
pub fn render_target(
    device: &wgpu::Device,
    label: &str,
    size: (u32, u32),
    format: wgpu::TextureFormat,
) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: size.0.max(1),
            height: size.1.max(1),
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    })
}

/// Clears a depth view to `depth` (a render pass with no colour): how the
/// host marks last frame's depth as the far plane, and how a shadow map
/// that shadows nothing is made.
pub fn clear_depth(encoder: &mut wgpu::CommandEncoder, view: &wgpu::TextureView, depth: f32) {
    let _pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
        label: Some("shadecache: no last frame"),
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

/// Makes and finds the cache group's bind groups during a frame, and
/// notes the twins drawn with, by id.
struct Binder<'s> {
    shader: &'s CachedShader,
    used: RefCell<BTreeMap<u64, Arc<TwinsInner>>>,
}

impl Binder<'_> {
    /// The cache group's bind group for `twins` in a pass this frame.
    fn bind_group(
        &self,
        built: &Built,
        twins: &TwinsInner,
    ) -> Result<Option<(u32, wgpu::BindGroup)>, Error> {
        let shader = self.shader;
        let (Some(group), Some(layout)) = (shader.cache_group, &built.cache_layout) else {
            return Ok(None);
        };
        let mut cached = twins
            .bind_groups
            .lock()
            .map_err(|_| Error::Wgpu("a twins' bind groups were poisoned".into()))?;
        let stale = cached
            .get(&built.index)
            .is_none_or(|(generation, _)| *generation != shader.generation);
        if stale {
            let make = |current| shader.cache_bind_group(built, layout, twins, current);
            let groups = [make(0)?, make(1)?];
            cached.insert(built.index, (shader.generation, groups));
        }
        Ok(cached
            .get(&built.index)
            .map(|(_, groups)| (group, groups[shader.current].clone())))
    }
}

impl CachedShader {
    /// The cache group's bind group when `current` is this frame's slot.
    fn cache_bind_group(
        &self,
        built: &Built,
        layout: &wgpu::BindGroupLayout,
        twins: &TwinsInner,
        current: usize,
    ) -> Result<wgpu::BindGroup, Error> {
        let shader = self;
        let t = &shader.targets;
        let previous = 1 - current;
        let bound = |binding: u32| {
            shader
                .cache_group
                .is_some_and(|group| built.pass.bindings.contains(&[group, binding]))
        };
        let mut entries = Vec::new();
        for resource in shader
            .plan
            .bindings
            .cache
            .iter()
            .filter(|r| bound(r.binding))
        {
            let view = wgpu::BindingResource::TextureView;
            let lowres = || {
                t.lowres.as_ref().ok_or_else(|| {
                    Error::Plan(format!(
                        "`{}` is lowres's, and the plan has no pass at a reduced resolution",
                        resource.name
                    ))
                })
            };
            let resource_of = match CacheResource::named(&resource.name)? {
                CacheResource::Samples => view(&lowres()?.samples),
                CacheResource::SampleGeometry => view(&lowres()?.geometry),
                CacheResource::PreviousHistory => view(&lowres()?.history[previous]),
                CacheResource::Draw => wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &shader.draw_ids,
                    offset: 0,
                    size: wgpu::BufferSize::new(16),
                }),
                CacheResource::Params => shader.params.as_entire_binding(),
                CacheResource::PreviousPayload => view(&t.payload_views[previous]),
                CacheResource::CurrentPayload => view(&t.payload_views[current]),
                CacheResource::PreviousAge => view(&t.age_views[previous]),
                CacheResource::PreviousDepth => view(&t.depth_sampled[previous]),
                CacheResource::Sampler => wgpu::BindingResource::Sampler(&shader.sampler),
                CacheResource::GBuffer(index) => {
                    view(t.gbuffer.get(index).ok_or_else(|| {
                        Error::Plan(format!(
                            "`{}` names G-buffer texture {index}, which the plan's G-buffer pass does not make",
                            resource.name
                        ))
                    })?)
                }
            };
            entries.push(wgpu::BindGroupEntry {
                binding: resource.binding,
                resource: resource_of,
            });
        }
        for (binding, buffer) in twins.bound.iter().filter(|(b, _)| bound(*b)) {
            entries.push(wgpu::BindGroupEntry {
                binding: *binding,
                resource: buffer.as_entire_binding(),
            });
        }
        for (binding, resource) in twins.shared.iter().filter(|(b, _)| bound(*b)) {
            entries.push(wgpu::BindGroupEntry {
                binding: *binding,
                resource: resource.resource(),
            });
        }
        Ok(shader.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("shadecache cache group"),
            layout,
            entries: &entries,
        }))
    }
}

/// Records one pass's draws through the application's callback.
fn draw_pass(
    built: &Built,
    binder: &Binder<'_>,
    render: &mut wgpu::RenderPass<'static>,
    draw: &mut impl FnMut(&mut Draw<'_, '_>),
) -> Result<(), Error> {
    let mut draws = Draw::new(render, built, binder);
    draw(&mut draws);
    if let Some(err) = draws.error.take() {
        return Err(err);
    }
    if built.pass.stencil.is_some() && draws.drawn == 0 {
        return Err(Error::Mismatch(format!(
            "pass `{}` marks each draw's pixels in the stencil, and the callback drew nothing in it",
            built.pass.name
        )));
    }
    Ok(())
}

/// One pass being recorded: the application sets its bind groups and
/// buffers as in its original pass, and draws with [`Draw::draw_indexed`]
/// or [`Draw::draw`], each with the draw's [`Twins`]. There is no raw
/// render pass: in a pass that marks each draw's pixels in the stencil the
/// host sets the reference per draw, and a screen-space pass draws one
/// triangle over the screen instead of the geometry, so every draw goes
/// through the host. A misuse (twins of another shader, the cache's bind
/// group or a twin's vertex slot) is returned from `record` as an
/// [`Error::Draw`], and the draw is skipped.
///
/// A draw without its twins does not compile:
///
/// ```compile_fail
/// fn draw_without_twins(draw: &mut shadecache_host::Draw<'_, '_>) {
///     draw.draw_indexed(0..6, 0, 0..1);
/// }
/// ```
///
/// nor does reaching past the host to the render pass:
///
/// ```compile_fail
/// fn draw_past_the_host(draw: &mut shadecache_host::Draw<'_, '_>) {
///     draw.render_pass().draw(0..3, 0..1);
/// }
/// ```
pub struct Draw<'r, 'e> {
    render: &'r mut wgpu::RenderPass<'e>,
    built: &'r Built,
    binder: &'r Binder<'r>,
    error: Option<Error>,
    /// Draws so far in this pass: the next one's stencil ordinal.
    drawn: u32,
    /// The twins whose cache group is bound now.
    bound: Option<u64>,
    /// The cache group's bind group of those twins, for a pass that binds
    /// it again at each draw's ordinal (`Built::per_draw`).
    per_draw: Option<(u32, wgpu::BindGroup)>,
}

impl<'r, 'e> Draw<'r, 'e> {
    fn new(render: &'r mut wgpu::RenderPass<'e>, built: &'r Built, binder: &'r Binder<'r>) -> Self {
        Draw {
            render,
            built,
            binder,
            error: None,
            drawn: 0,
            bound: None,
            per_draw: None,
        }
    }

    /// The plan's pass being recorded (its name and role).
    pub fn pass(&self) -> &Pass {
        &self.built.pass
    }

    /// Sets one of the application's bind groups, as
    /// `RenderPass::set_bind_group`. The cache's group is the host's.
    pub fn set_bind_group(&mut self, index: u32, bind_group: &wgpu::BindGroup, offsets: &[u32]) {
        let shader = self.binder.shader;
        if Some(index) == shader.cache_group {
            self.fail(format!(
                "group {index} is the cache's, which the host binds: give the resources the application keeps there among the draw's `TwinSources`"
            ));
        } else if index >= shader.max_bind_groups {
            self.fail(format!(
                "group {index} is past the device's {} bind groups",
                shader.max_bind_groups
            ));
        } else {
            self.render.set_bind_group(index, bind_group, offsets);
        }
    }

    /// Sets one of the application's vertex buffers, as
    /// `RenderPass::set_vertex_buffer`, at a slot of its frame layout.
    pub fn set_vertex_buffer(&mut self, slot: u32, buffer: wgpu::BufferSlice<'_>) {
        let slots = self.binder.shader.vertex_slots;
        if slot >= slots {
            self.fail(format!(
                "vertex buffer slot {slot} is not among the frame layout's {slots}: the slots after them hold the host's copies of last frame's"
            ));
        } else {
            self.render.set_vertex_buffer(slot, buffer);
        }
    }

    /// Sets the index buffer, as `RenderPass::set_index_buffer`.
    pub fn set_index_buffer(&mut self, buffer: wgpu::BufferSlice<'_>, format: wgpu::IndexFormat) {
        self.render.set_index_buffer(buffer, format);
    }

    /// Draws indexed geometry with `twins` (last frame's copies of this
    /// draw's buffers), as `RenderPass::draw_indexed`. In a pass that
    /// marks or tests each draw's pixels in the stencil (the deferred
    /// variant's), the draw's ordinal is the stencil reference, and a
    /// screen-space pass draws one triangle over the screen instead, with
    /// the bind groups set for this draw.
    pub fn draw_indexed(
        &mut self,
        twins: &Twins,
        indices: std::ops::Range<u32>,
        base_vertex: i32,
        instances: std::ops::Range<u32>,
    ) {
        if self.next_draw(twins) {
            self.render.draw_indexed(indices, base_vertex, instances);
        }
    }

    /// Draws non-indexed geometry with `twins`, as `RenderPass::draw`; see
    /// [`Draw::draw_indexed`].
    pub fn draw(
        &mut self,
        twins: &Twins,
        vertices: std::ops::Range<u32>,
        instances: std::ops::Range<u32>,
    ) {
        if self.next_draw(twins) {
            self.render.draw(vertices, instances);
        }
    }

    /// Keeps the first misuse, for `record` to return.
    fn fail(&mut self, text: String) {
        self.error.get_or_insert(Error::Draw(text));
    }

    /// Binds `twins`, sets the stencil reference of the next draw and
    /// draws the screen's triangle for a screen-space pass; whether the
    /// application's own geometry is to be drawn.
    fn next_draw(&mut self, twins: &Twins) -> bool {
        if !self.bind(twins) {
            return false;
        }
        self.drawn += 1;
        let pass = &self.built.pass;
        if let Some(stencil) = pass.stencil {
            if self.drawn > MAX_STENCIL_DRAWS {
                self.error.get_or_insert(Error::Mismatch(format!(
                    "pass `{}` has more than {MAX_STENCIL_DRAWS} draws, the most the stencil tells apart",
                    pass.name
                )));
                return false;
            }
            self.render
                .set_stencil_reference(self.drawn | stencil.reference_bits);
        }
        if let Some((group, bind_group)) = &self.per_draw {
            let slot = (self.drawn - 1) % layouts::DRAW_IDS;
            self.render
                .set_bind_group(*group, bind_group, &[slot * layouts::DRAW_ID_STRIDE]);
        }
        match pass.draw {
            DrawKind::Geometry => true,
            DrawKind::Fullscreen => {
                self.render.draw(0..3, 0..1);
                false
            }
        }
    }

    /// Binds the cache group with `twins` and the vertex twins, unless they
    /// are bound already; whether the draw may go on.
    fn bind(&mut self, twins: &Twins) -> bool {
        let inner = &twins.inner;
        if inner.owner != self.binder.shader.id {
            self.fail(
                "these twins were made by another CachedShader: make each draw's with `twins` of the shader that records it"
                    .into(),
            );
            return false;
        }
        if self.bound == Some(inner.id) {
            return true;
        }
        match self.binder.bind_group(self.built, inner) {
            Ok(Some((group, bind_group))) if self.built.per_draw => {
                self.per_draw = Some((group, bind_group));
            }
            Ok(Some((group, bind_group))) => self.render.set_bind_group(group, &bind_group, &[]),
            Ok(None) => {}
            Err(err) => {
                self.error.get_or_insert(err);
                return false;
            }
        }
        for (slot, buffer) in &inner.vertex {
            self.render.set_vertex_buffer(*slot, buffer.slice(..));
        }
        self.bound = Some(inner.id);
        self.binder
            .used
            .borrow_mut()
            .entry(inner.id)
            .or_insert_with(|| inner.clone());
        true
    }
}
