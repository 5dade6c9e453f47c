//! Each caching view's variant on the host crate: made from Bevy's layouts
//! for the view, its cached meshes and their material, kept at the view's
//! size, and recorded after the main opaque pass.
//!
//! Each cache runs in its camera's [`CacheMode`]: every frame, never, or
//! governed by the host crate's `Governor`. A frame the governor gives to
//! the original draws the cache's meshes with the pipelines Bevy
//! specialised for them, in one pass at the same place in the frame (so
//! the frame is Bevy's own), and the `FrameTimer` times either kind; its
//! times, read a few frames later without a wait, feed the governor.

use std::ops::Range;
use std::sync::{Arc, Mutex};

use bevy::asset::UntypedAssetId;
use bevy::core_pipeline::core_3d::{main_opaque_pass_3d, main_transparent_pass_3d};
use bevy::core_pipeline::{schedule::Core3d, Core3dSystems};
use bevy::ecs::system::SystemParam;
use bevy::log::error;
use bevy::pbr::{
    MeshPipeline, MeshPipelineViewLayoutKey, PreparedMaterial, RenderMaterialInstances,
    ViewKeyCache,
};
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::erased_render_asset::ErasedRenderAssets;
use bevy::render::render_phase::{
    SortedPhaseItem, SortedRenderPhase, TrackedRenderPass, ViewSortedRenderPhases,
};
use bevy::render::render_resource::{BufferUsages, PipelineCache, ShaderType};
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::sync_world::MainEntity;
use bevy::render::view::{
    ExtractedView, ViewDepthStencilTexture, ViewTarget, ViewUniform, ViewUniformOffset,
    ViewUniforms,
};
use bevy::render::{Render, RenderSystems};
use shadecache_host::plan::ResourceKind;
use shadecache_host::{
    CacheMode, CachedShader, Choice, Coverage, DescribedPipelines, ErrorWatch, FrameLayout,
    FrameTimer, Governor, NoTimer, Options, PassTimer, Plan, SpeedEstimate, Targets, TwinSources,
    Twins, VertexBufferDescriptor, Viewport,
};

use crate::edits::EditedMaterials;
use crate::phase::{CacheId, CachedMesh3d, CachingViews, QueuedLayouts};
use crate::pipelines::{Compiled, Compiling, QueuedPipelines};
use crate::reload::ReloadedMaterials;
use crate::CacheCreation;
use crate::{CachedVariant, CachedVariants, ReprojectionCache};

/// Bevy's view uniform: group 0, binding 0 of the mesh view bind group.
const VIEW_BINDING: [u32; 2] = [0, 0];

/// What a view's cache was made for; a change makes it again.
#[derive(Clone, Debug, PartialEq)]
struct CacheKey {
    view_layout: MeshPipelineViewLayoutKey,
    /// The view's samples per pixel (`Msaa`): the host refuses more than
    /// one, as a cache holds one value per pixel.
    samples: u32,
    color_format: wgpu::TextureFormat,
    mesh_layout: bevy::mesh::MeshVertexBufferLayoutRef,
    /// The primitive state of Bevy's own pipeline for the meshes.
    primitive: wgpu::PrimitiveState,
    material_layout: Vec<wgpu::BindGroupLayoutEntry>,
    refresh_period: Option<u32>,
    /// The camera's viewport where it is part of the target (x, y,
    /// width, height): a cache is made for one.
    viewport: Option<[u32; 4]>,
}

/// One view's variant and what it draws with.
struct ViewCache {
    key: CacheKey,
    shader: CachedShader,
    /// This frame's view uniform, copied from Bevy's view buffer at the
    /// view's offset; the host keeps last frame's copy of it.
    view_now: wgpu::Buffer,
    twins: Twins,
    /// How it runs, as its camera says (made again when that changes).
    governed: Option<Governed>,
    /// The material asset each mesh it has drawn bound when last drawn.
    bound: HashMap<MainEntity, UntypedAssetId>,
}

impl ViewCache {
    /// Whether what the cache holds of its meshes is of other material
    /// values than this frame's: a mesh binds another asset than when it
    /// was last drawn (a material swapped on selection), or an asset whose
    /// values were edited this frame. Keeps this frame's bindings (in
    /// place: no map is made a frame).
    fn materials_changed(
        &mut self,
        bound: impl Iterator<Item = (MainEntity, UntypedAssetId)>,
        edited: &EditedMaterials,
    ) -> bool {
        let mut changed = false;
        for (mesh, asset) in bound {
            let swapped = self
                .bound
                .insert(mesh, asset)
                .is_some_and(|last| last != asset);
            changed |= swapped || edited.contains(asset);
        }
        changed
    }

    /// The bytes its targets and its watch's copies take.
    fn target_bytes(&self) -> u64 {
        let watch = self
            .governed
            .as_ref()
            .and_then(|governed| governed.watch.as_ref())
            .and_then(|watch| watch.as_ref().ok())
            .map_or(0, |watch| {
                [&watch.base, watch.watch.spare(), &watch.depth]
                    .into_iter()
                    .map(shadecache_host::texture_bytes)
                    .sum()
            });
        self.shader.target_bytes() + watch
    }
}

/// A cache's mode and what runs it: a governor for every mode (`Always`
/// and `Off` draw one way and decide nothing), and for `Auto` the timer
/// that measures it.
struct Governed {
    mode: CacheMode,
    governor: Governor,
    timer: Option<FrameTimer>,
    /// The frames of each kind, measured and watched (the rest of the
    /// readout is the governor's own state).
    counts: GovernorReadout,
    /// With an error budget: the watch, made at the first watched frame
    /// (`None` before), or why the view cannot be watched.
    watch: Option<Result<ViewWatch, String>>,
}

/// A view's error watch: the watch (its spare target is the original's
/// colour), and the base frame and the depth a watched frame copies the
/// view's into before the cached passes.
struct ViewWatch {
    watch: ErrorWatch,
    base: wgpu::Texture,
    depth_view: wgpu::TextureView,
    depth: wgpu::Texture,
}

impl ViewWatch {
    /// A watch of the view whose colour and depth are `color` and
    /// `depth`; why not where they cannot be copied or read (a copy of the
    /// colour and the depth starts the original's frame).
    fn new(
        device: &wgpu::Device,
        color: &wgpu::Texture,
        depth: &wgpu::Texture,
    ) -> Result<ViewWatch, String> {
        let usage = wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::TEXTURE_BINDING;
        if !color.usage().contains(usage) {
            return Err("the view's main texture is not a copy source bound as a texture (CameraMainTextureUsages)".into());
        }
        if !matches!(
            depth.format(),
            wgpu::TextureFormat::Depth32Float | wgpu::TextureFormat::Depth16Unorm
        ) || !depth.usage().contains(wgpu::TextureUsages::COPY_SRC)
        {
            return Err(format!(
                "the view's depth, {:?}, cannot be copied",
                depth.format()
            ));
        }
        let size = (color.width(), color.height());
        let watch = ErrorWatch::new(device, size, color.format()).map_err(|err| err.to_string())?;
        let texture = |label, format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: color.size(),
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let base = texture(
            "shadecache error watch's base",
            color.format(),
            wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let depth = texture(
            "shadecache error watch's depth",
            depth.format(),
            wgpu::TextureUsages::COPY_DST | wgpu::TextureUsages::RENDER_ATTACHMENT,
        );
        Ok(ViewWatch {
            watch,
            base,
            depth_view: depth.create_view(&Default::default()),
            depth,
        })
    }

    /// Copies the view's colour (into the base and the spare) and depth,
    /// as the opaque pass left them, before the cached passes.
    fn copy_view(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        color: &wgpu::Texture,
        depth: &wgpu::Texture,
    ) {
        for into in [&self.base, self.watch.spare()] {
            encoder.copy_texture_to_texture(
                color.as_image_copy(),
                into.as_image_copy(),
                color.size(),
            );
        }
        encoder.copy_texture_to_texture(
            depth.as_image_copy(),
            self.depth.as_image_copy(),
            depth.size(),
        );
    }
}

/// What a cached material's governor holds, for a game's readout and
/// Bevy's diagnostics (of the view that drew it last).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct GovernorReadout {
    /// Whether the cache is on.
    pub on: bool,
    /// The speed-up last weighed and its interval, once there were enough
    /// frames.
    pub estimate: Option<SpeedEstimate>,
    /// The refresh period Δn.
    pub period: u32,
    /// Frames the view drew the meshes Bevy's way (the governor's probes,
    /// or all while the cache is off).
    pub original_frames: u64,
    /// Frames drawn through the cache.
    pub cached_frames: u64,
    /// Frames whose GPU time reached the governor.
    pub measured_frames: u64,
    /// With an error budget, the last watched frame's PSNR against Bevy's
    /// own frame (dB, over the pixels the cached meshes drew in either).
    pub psnr: Option<f64>,
}

/// A view's cache, or why it has none.
enum Slot {
    Ready(Box<ViewCache>),
    /// Its pipelines being compiled by Bevy's pipeline cache (off the
    /// frame unless [`CacheCreation`] says otherwise); the view leaves its
    /// meshes to Bevy meanwhile.
    Compiling(CacheKey, Box<Pending>),
    /// The error, logged once; the view leaves its meshes to Bevy until
    /// what the cache was made for changes.
    Failed(CacheKey),
}

/// Every caching view's cache of each cached material's variant.
#[derive(Resource, Default)]
struct ViewCaches(HashMap<CacheId, Mutex<Slot>>);

/// What the plugin did, shared by the main world and the render world
/// (both hold a clone): frames drawn through the cache, and every error
/// logged (a cache that cannot be made, a frame that failed), for a game's
/// readout or its tests.
#[derive(Resource, Clone, Default, Debug)]
pub struct CacheStats(Arc<Mutex<StatsInner>>);

#[derive(Default, Debug)]
struct StatsInner {
    frames: u64,
    /// Frames drawn through each material's variant, by its name.
    by_material: Vec<(String, u64)>,
    errors: Vec<String>,
    /// Each governed material's governor, by its name.
    governors: Vec<(String, GovernorReadout)>,
    /// The bytes of GPU memory every view's caches own.
    target_bytes: u64,
}

impl CacheStats {
    /// Frames drawn through the cache, over every view and material (a
    /// view drawing two cached materials counts two a frame).
    pub fn frames_drawn(&self) -> u64 {
        self.lock().frames
    }

    /// Frames drawn through the variant of the material `M`, over every
    /// view.
    pub fn frames_drawn_of<M: 'static>(&self) -> u64 {
        let name = bevy::utils::prelude::ShortName::of::<M>().to_string();
        self.lock()
            .by_material
            .iter()
            .find(|(n, _)| *n == name)
            .map_or(0, |(_, frames)| *frames)
    }

    /// The bytes of GPU memory the caches of every caching view own, as
    /// of the last frame prepared: each cache's targets
    /// ([`CachedShader::target_bytes`]: 32 bytes a pixel for a one- or
    /// three-pass variant with an `rgba16float` payload, more for a wider
    /// payload, the deferred variant's G-buffer or lowres's history) and,
    /// with an error budget, the watch's copies of the view's colour and
    /// depth. A view caching two materials owns two caches.
    pub fn target_bytes(&self) -> u64 {
        self.lock().target_bytes
    }

    /// Every error logged, in order.
    pub fn errors(&self) -> Vec<String> {
        self.lock().errors.clone()
    }

    /// The governor of the material `M`'s cache (of the view that drew it
    /// last), once one has drawn.
    pub fn governor_of<M: 'static>(&self) -> Option<GovernorReadout> {
        self.governor(&bevy::utils::prelude::ShortName::of::<M>().to_string())
    }

    /// [`CacheStats::governor_of`] by the material's name.
    pub(crate) fn governor(&self, material: &str) -> Option<GovernorReadout> {
        self.lock()
            .governors
            .iter()
            .find(|(n, _)| n == material)
            .map(|(_, readout)| *readout)
    }

    fn governed(&self, material: &str, readout: GovernorReadout) {
        let mut inner = self.lock();
        match inner.governors.iter_mut().find(|(n, _)| n == material) {
            Some((_, kept)) => *kept = readout,
            None => inner.governors.push((material.to_string(), readout)),
        }
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, StatsInner> {
        self.0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    fn drew(&self, material: &str) {
        let mut inner = self.lock();
        inner.frames += 1;
        match inner.by_material.iter_mut().find(|(n, _)| n == material) {
            Some((_, frames)) => *frames += 1,
            None => inner.by_material.push((material.to_string(), 1)),
        }
    }

    /// Logs `err` and keeps it.
    pub(crate) fn error(&self, err: String) {
        error!("shadecache: {err}");
        self.lock().errors.push(err);
    }
}

pub(crate) fn build(render_app: &mut SubApp, stats: CacheStats) {
    render_app
        .insert_resource(stats)
        .init_resource::<ViewCaches>()
        .add_systems(
            Render,
            copyable_view_uniforms
                .in_set(RenderSystems::PrepareResources)
                .before(bevy::render::view::prepare_view_uniforms),
        )
        .add_systems(
            Render,
            prepare_view_caches
                .in_set(RenderSystems::QueueMeshes)
                .after(crate::phase::queue_cached_meshes)
                .before(crate::phase::take_from_opaque_phase),
        )
        .add_systems(
            Core3d,
            // Between Bevy's opaque and transparent passes, in the view's
            // depth: the cached meshes hide and are hidden by the opaque
            // ones, and the transparent ones blend over them.
            draw_cached_passes
                .after(main_opaque_pass_3d)
                .before(main_transparent_pass_3d)
                .in_set(Core3dSystems::MainPass),
        );
}

/// The plugin copies the view's uniform out of Bevy's view buffer each
/// frame, which needs the buffer to be a copy source. Asked for whenever
/// the buffer is not one (it is made again with the usage when next
/// written): at the first frame, and after the render world is made
/// again.
fn copyable_view_uniforms(mut uniforms: ResMut<ViewUniforms>) {
    let copyable = uniforms
        .uniforms
        .buffer()
        .is_some_and(|buffer| buffer.usage().contains(BufferUsages::COPY_SRC));
    if !copyable {
        uniforms.uniforms.add_usages(BufferUsages::COPY_SRC);
    }
}

/// What a view's cache is made from: the variant, the device, and Bevy's
/// mesh pipeline, view keys, the cached meshes' vertex layouts and their
/// materials.
#[derive(SystemParam)]
struct CacheSources<'w> {
    variants: Res<'w, CachedVariants>,
    creation: Res<'w, CacheCreation>,
    /// The materials whose shader changed since the game started: Bevy's.
    reloaded: Res<'w, ReloadedMaterials>,
    device: Res<'w, RenderDevice>,
    mesh_pipeline: Res<'w, MeshPipeline>,
    view_keys: Res<'w, ViewKeyCache>,
    layouts: Res<'w, QueuedLayouts>,
    material_instances: Res<'w, RenderMaterialInstances>,
    materials: Res<'w, ErasedRenderAssets<PreparedMaterial>>,
}

/// Bevy's pipeline cache, and the variant pipelines queued in it.
#[derive(SystemParam)]
struct Pipelines<'w> {
    cache: ResMut<'w, PipelineCache>,
    queued: ResMut<'w, QueuedPipelines>,
}

/// Makes, keeps or drops each caching view's caches: one per variant and
/// vertex layout its visible cached meshes have, before the cached meshes
/// are taken from Bevy's opaque phase (only meshes with a cache are).
fn prepare_view_caches(
    sources: CacheSources,
    phases: Res<ViewSortedRenderPhases<CachedMesh3d>>,
    views: Query<(&ExtractedView, &ExtractedCamera, &ReprojectionCache)>,
    // The caches, and Bevy's pipeline cache that compiles their pipelines
    // (with those queued in it).
    (mut caches, mut pipelines): (ResMut<ViewCaches>, Pipelines),
    mut caching: ResMut<CachingViews>,
    stats: Res<CacheStats>,
    mut refusals: Local<HashMap<CacheId, String>>,
) {
    let was_caching = std::mem::take(&mut caching.0);
    // A material whose shader changed is Bevy's from then on: its caches
    // go, and its meshes back to Bevy's opaque pass.
    let current = |variant: u32| {
        sources
            .variants
            .get(variant)
            .is_some_and(|m| !sources.reloaded.contains(m.material))
    };
    caches
        .0
        .retain(|(view, variant, _), _| phases.contains_key(view) && current(*variant));
    let mut seen: HashSet<CacheId> = HashSet::default();
    for (view, camera, settings) in &views {
        let Some(phase) = phases.get(&view.retained_view_entity) else {
            continue;
        };
        for variant in (0..sources.variants.len()).filter(|&v| current(v)) {
            let queued = sources.layouts.0.get(&(view.retained_view_entity, variant));
            for (index, layout) in queued.into_iter().flatten().enumerate() {
                let id: CacheId = (view.retained_view_entity, variant, layout.clone());
                seen.insert(id.clone());
                let items: Vec<&CachedMesh3d> = phase
                    .items
                    .values()
                    .filter(|item| item.variant == variant && item.layout == index as u32)
                    .collect();
                let key = match cache_key(&id, &items, settings, camera, &sources) {
                    Ok(Some(key)) => key,
                    // The material or the view is not prepared yet (or
                    // again, after a change): a view that cached goes on
                    // with the cache it has, as its meshes are out of
                    // Bevy's opaque phase.
                    Ok(None) => {
                        if was_caching.contains(&id) {
                            caching.0.insert(id);
                        }
                        continue;
                    }
                    Err(err) => {
                        // Said once while it lasts; the meshes go back to
                        // Bevy (`phase::take_from_opaque_phase`).
                        if refusals.insert(id, err.clone()).as_ref() != Some(&err) {
                            stats.error(format!(
                                "the view does not cache {}, so Bevy draws it: {err}",
                                sources.variants.name(variant)
                            ));
                        }
                        continue;
                    }
                };
                refusals.remove(&id);
                let size = camera
                    .physical_target_size
                    .map(|s| (s.x, s.y))
                    .unwrap_or((1, 1));
                let made = prepare_cache(
                    (&mut caches, &mut pipelines),
                    &id,
                    key,
                    size,
                    &sources,
                    &stats,
                );
                if made {
                    caching.0.insert(id);
                }
            }
        }
    }
    // A cache with nothing of its own visible this frame goes on with what
    // it has.
    caching.0.extend(
        was_caching
            .into_iter()
            .filter(|id| !seen.contains(id) && phases.contains_key(&id.0) && current(id.1)),
    );
    stats.lock().target_bytes = caches
        .0
        .values_mut()
        .map(|slot| match slot.get_mut() {
            Ok(Slot::Ready(cache)) => cache.target_bytes(),
            _ => 0,
        })
        .sum();
}

/// Makes the cache `id` for `key`, or again if it was made for another
/// key; whether it is ready.
fn prepare_cache(
    (caches, pipelines): (&mut ViewCaches, &mut Pipelines),
    id: &CacheId,
    key: CacheKey,
    size: (u32, u32),
    sources: &CacheSources,
    stats: &CacheStats,
) -> bool {
    let slot = caches.0.entry(id.clone()).or_insert_with(|| {
        Mutex::new(make_cache(sources, pipelines, id, key.clone(), size, stats))
    });
    let slot = slot
        .get_mut()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    let current = match slot {
        Slot::Ready(cache) => &cache.key,
        Slot::Compiling(key, _) | Slot::Failed(key) => key,
    };
    if *current != key {
        // A cache still being made for the old key is dropped (Bevy's
        // cache keeps its pipelines, unused).
        *slot = make_cache(sources, pipelines, id, key, size, stats);
    }
    if let Slot::Compiling(key, pending) = slot {
        let key = key.clone();
        let compiled = pending
            .compiling
            .poll(&mut pipelines.cache, sources.creation.synchronous);
        let made = match compiled {
            Compiled::Waiting => None,
            Compiled::Failed(err) => Some(Err(err)),
            Compiled::Ready(made) => Some(build_cache(
                sources.device.wgpu_device(),
                key.clone(),
                pending,
                made,
            )),
        };
        if let Some(made) = made {
            *slot = settle(made, key, sources.variants.name(id.1), stats);
        }
    }
    matches!(slot, Slot::Ready(_))
}

/// The part of its target a camera draws into (x, y, width, height),
/// where it is not the whole target (split screen): the variant's passes
/// draw into it, and map last frame's positions into it.
fn partial_viewport(camera: &ExtractedCamera) -> Option<[u32; 4]> {
    let viewport = camera.viewport.as_ref()?;
    let whole = camera.physical_target_size?;
    let (at, size) = (viewport.physical_position, viewport.physical_size);
    (at != UVec2::ZERO || size != whole).then_some([at.x, at.y, size.x, size.y])
}

/// What the view's cache is made for, from Bevy's prepared view, mesh and
/// material; `None` while one of them is not prepared yet.
fn cache_key(
    (view, _, drawn): &CacheId,
    items: &[&CachedMesh3d],
    settings: &ReprojectionCache,
    camera: &ExtractedCamera,
    sources: &CacheSources,
) -> Result<Option<CacheKey>, String> {
    let view_keys = &sources.view_keys;
    let (material_instances, materials) = (&sources.material_instances, &sources.materials);
    use bevy::render::render_phase::PhaseItem;
    let Some(view_key) = view_keys.get(view).copied() else {
        return Ok(None);
    };
    // The material group's layout, which every cached mesh's material
    // must have: each pass binds each mesh's own material.
    let mut material_layout: Option<Vec<wgpu::BindGroupLayoutEntry>> = None;
    for item in items {
        let Some(instance) = material_instances.instances.get(&item.main_entity()) else {
            return Ok(None);
        };
        let Some(material) = materials.get(instance.asset_id) else {
            return Ok(None);
        };
        let layout = material
            .properties
            .material_layout
            .as_ref()
            .map(|layout| layout.entries.clone())
            .unwrap_or_default();
        match &material_layout {
            Some(first) if *first != layout => {
                return Err(
                    "the view's cached meshes have materials of different bind group layouts; mark only meshes with the material the variant was made from"
                        .into(),
                )
            }
            Some(_) => {}
            None => material_layout = Some(layout),
        }
    }
    let Some(material_layout) = material_layout else {
        return Ok(None);
    };
    let color_format = view_key.target_format();
    Ok(Some(CacheKey {
        view_layout: MeshPipelineViewLayoutKey::from(view_key),
        samples: view_key.msaa_samples(),
        color_format,
        mesh_layout: drawn.layout.clone(),
        primitive: drawn.primitive,
        material_layout,
        refresh_period: settings.refresh_period,
        viewport: partial_viewport(camera),
    }))
}

/// Starts making a view's cache: its pipelines are queued in Bevy's
/// pipeline cache. A failure is logged once.
fn make_cache(
    sources: &CacheSources,
    pipelines: &mut Pipelines,
    (_, variant, drawn): &CacheId,
    key: CacheKey,
    size: (u32, u32),
    stats: &CacheStats,
) -> Slot {
    let Some(material) = sources.variants.get(*variant) else {
        return Slot::Failed(key);
    };
    let Some(build) = material.builds.get(drawn.build as usize) else {
        return Slot::Failed(key);
    };
    let Some(shaders) = material.shaders.get(drawn.build as usize) else {
        let err = "the variant's shaders are not Bevy assets: they are added as the app is finished (`Plugin::finish`), which this app did not reach";
        return settle(Err(err.into()), key, &material.name, stats);
    };
    let queued = cache_inputs(build, &sources.mesh_pipeline, &key)
        .and_then(|inputs| describe_pipelines(&inputs, sources.device.wgpu_device()))
        .and_then(|described| {
            let queue = (&*pipelines.cache, &mut *pipelines.queued);
            let compiling = Compiling::queue(queue, described.descriptors(), shaders)?;
            Ok(Pending {
                described,
                compiling,
                size,
            })
        });
    match queued {
        Ok(pending) => Slot::Compiling(key, Box::new(pending)),
        Err(err) => settle(Err(err), key, &material.name, stats),
    }
}

/// The slot a made (or failed) cache takes; a failure is logged.
fn settle(
    made: Result<ViewCache, String>,
    key: CacheKey,
    material: &str,
    stats: &CacheStats,
) -> Slot {
    match made {
        Ok(cache) => Slot::Ready(Box::new(cache)),
        Err(err) => {
            stats.error(format!(
                "the view's cache of {material} cannot be made, so Bevy draws it: {err}"
            ));
            Slot::Failed(key)
        }
    }
}

/// What a view's cache is described from: the plan (Δn set), Bevy's
/// layouts, the meshes' vertex buffer, the frame's formats.
struct CacheInputs {
    plan: Plan,
    groups: [(u32, Vec<wgpu::BindGroupLayoutEntry>); 4],
    vertex: VertexBufferDescriptor,
    key: CacheKey,
    prepass: bool,
}

/// A view's cache while Bevy compiles its pipelines: the host's
/// description of them, those queued, and the size to make it at.
struct Pending {
    described: DescribedPipelines,
    compiling: Compiling,
    size: (u32, u32),
}

/// Checks what the view's cache is made for and gathers what making it
/// takes; the errors a view is refused for.
fn cache_inputs(
    variant: &CachedVariant,
    mesh_pipeline: &MeshPipeline,
    key: &CacheKey,
) -> Result<CacheInputs, String> {
    let mut plan: Plan = variant.plan().clone();
    if let Some(period) = key.refresh_period {
        if period == 0 {
            return Err("a refresh period of 0 never refreshes: give 1 or more".into());
        }
        plan.refresh.period = period;
    }
    check_twins(&plan)?;
    let prepass = key.view_layout.intersects(
        MeshPipelineViewLayoutKey::DEPTH_PREPASS
            | MeshPipelineViewLayoutKey::NORMAL_PREPASS
            | MeshPipelineViewLayoutKey::MOTION_VECTOR_PREPASS
            | MeshPipelineViewLayoutKey::DEFERRED_PREPASS,
    );
    if prepass {
        if let Some(pass) = depth_tells_passes_apart(&plan) {
            return Err(format!(
                "the view has a prepass, which writes the cached meshes' depth before the variant's passes, and {}'s `{}` draws only the pixels earlier passes left, told by the depth they wrote: give the view no prepass, or cache the material with the one-pass variant",
                plan.variant.as_str(),
                pass.name
            ));
        }
    }
    let view_layout = mesh_pipeline.get_view_layout(key.view_layout);
    let mesh_layout = &mesh_pipeline.mesh_layouts.model_only;
    let groups = [
        (0, view_layout.main_layout.entries.clone()),
        (1, view_layout.binding_array_layout.entries.clone()),
        (2, mesh_layout.entries.clone()),
        (3, key.material_layout.clone()),
    ];
    let attributes = vertex_attributes(&plan)?;
    let buffer = key
        .mesh_layout
        .0
        .get_layout(&attributes)
        .map_err(|err| format!("the cached meshes lack what the variant reads: {err}"))?;
    Ok(CacheInputs {
        plan,
        groups,
        vertex: VertexBufferDescriptor {
            array_stride: buffer.array_stride,
            step_mode: buffer.step_mode,
            attributes: buffer.attributes.clone(),
        },
        key: key.clone(),
        prepass,
    })
}

/// The view's pipelines described by the host, from the application's
/// frame as Bevy's pipeline for the cached meshes has it and the host's
/// options for the view.
fn describe_pipelines(
    inputs: &CacheInputs,
    device: &wgpu::Device,
) -> Result<DescribedPipelines, String> {
    let groups: Vec<(u32, &[wgpu::BindGroupLayoutEntry])> = inputs
        .groups
        .iter()
        .map(|(group, entries)| (*group, entries.as_slice()))
        .collect();
    let vertex = [Some(inputs.vertex.borrowed())];
    let key = &inputs.key;
    let colors = [Some(wgpu::ColorTargetState::from(key.color_format))];
    let mut frame = FrameLayout::new(&vertex, &groups, &colors);
    frame.sample_count = key.samples;
    if let Some([x, y, width, height]) = key.viewport {
        frame.viewport = Viewport::Rect([x as f32, y as f32, width as f32, height as f32]);
    }
    // As Bevy's own pipeline for these meshes: the mesh's topology, the
    // material's culling, whatever its `specialize` set.
    frame.primitive = key.primitive;
    // The view's depth is shared. After a prepass (which TAA, SSAO and
    // motion blur need) it already holds the cached meshes' depth: their
    // own tests must pass on it. Without one it holds only Bevy's other
    // meshes, and the plan's strict tests stand (a later pass tells the
    // pixels an earlier one left by them).
    let options = Options {
        depth_test_or_equal: inputs.prepass,
        ..Options::default()
    };
    CachedShader::describe_pipelines(device, &inputs.plan, &frame, options)
        .map_err(|err| err.to_string())
}

/// Makes a view's cache from the pipelines Bevy compiled for it: the
/// host's targets, the view's copy and its twin. Quick (the pipelines
/// are the slow part): it waits on wgpu's error scopes, which a native
/// device has answered by then.
fn build_cache(
    device: &wgpu::Device,
    key: CacheKey,
    pending: &Pending,
    pipelines: Vec<wgpu::RenderPipeline>,
) -> Result<ViewCache, String> {
    let mut shader = bevy::tasks::block_on(CachedShader::from_pipelines_async(
        device,
        pending.described.clone(),
        pending.size,
        pipelines,
    ))
    .map_err(|err| err.to_string())?;
    let view_size = ViewUniform::min_size().get().next_multiple_of(16);
    let view_now = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("shadecache view uniform, this frame"),
        size: view_size,
        usage: wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::UNIFORM,
        mapped_at_creation: false,
    });
    let twins = shader
        .twins(&TwinSources {
            buffers: &[(VIEW_BINDING, &view_now)],
            ..Default::default()
        })
        .map_err(|err| err.to_string())?;
    Ok(ViewCache {
        key,
        shader,
        view_now,
        twins,
        governed: None,
        bound: HashMap::default(),
    })
}

impl ViewCache {
    /// The cache's governor for `mode`, made again where the mode changed
    /// (a new governor: what the old one measured was of another mode).
    /// `Auto` without timestamp queries caches every frame; an error
    /// budget is not watched here. Both are said once, as warnings.
    fn governed(
        &mut self,
        mode: CacheMode,
        device: &RenderDevice,
        queue: &RenderQueue,
    ) -> Result<&mut Governed, String> {
        if self.governed.as_ref().is_none_or(|g| g.mode != mode) {
            let timer = match mode {
                CacheMode::Auto { .. } => {
                    // The variant's passes, or the one pass of Bevy's way.
                    let passes = self.shader.plan().passes.len() as u32;
                    let timer = FrameTimer::new(device.wgpu_device(), queue, passes, 4);
                    if timer.is_none() {
                        warn!("shadecache: the device has no timestamp queries, which CacheMode::Auto decides from: the view caches every frame");
                    }
                    timer
                }
                _ => None,
            };
            let run = match (mode, &timer) {
                (CacheMode::Auto { .. }, None) => CacheMode::Always,
                (mode, _) => mode,
            };
            let governor = Governor::for_mode(run, self.shader.plan())?;
            self.governed = Some(Governed {
                mode,
                counts: GovernorReadout::default(),
                governor,
                timer,
                watch: None,
            });
        }
        self.governed
            .as_mut()
            .ok_or_else(|| "no governor".to_string())
    }
}

/// The plugin keeps last frame's copy of the view only; the mesh's
/// previous transforms are Bevy's own members.
fn check_twins(plan: &Plan) -> Result<(), String> {
    for twin in &plan.bindings.previous {
        let original = &twin.shadows;
        if [original.group, original.binding] != VIEW_BINDING
            || original.kind != ResourceKind::Uniform
        {
            return Err(format!(
                "the variant reads last frame's `{}` (group {}, binding {}), and the plugin keeps last frame's view only (group 0, binding 0): Bevy's mesh transforms are read through their `previous_` members, so compose the material with Bevy's own mesh bindings",
                original.name, original.group, original.binding
            ));
        }
    }
    if plan.vertex_layout.iter().any(|a| a.previous_of.is_some()) {
        return Err("the variant reads last frame's vertex buffers (a deforming mesh), which the plugin does not keep".into());
    }
    Ok(())
}

/// A pass that draws the meshes after another did in the same frame and
/// keeps the depth it wrote, with a strict test: it draws only the pixels
/// the earlier passes left (two-pass's second pass, three-pass's third),
/// which a depth already holding the meshes' own cannot tell.
fn depth_tells_passes_apart(plan: &Plan) -> Option<&shadecache_host::plan::Pass> {
    use shadecache_host::plan::{CompareFunction, DrawKind, LoadOp};
    let mut drawn = false;
    for pass in &plan.passes {
        if pass.draw != DrawKind::Geometry || pass.resolution_divisor != 1 {
            continue;
        }
        let strict = matches!(
            pass.depth.compare,
            CompareFunction::Less | CompareFunction::Greater
        );
        if drawn && pass.depth.load == LoadOp::Load && strict {
            return Some(pass);
        }
        drawn = true;
    }
    None
}

/// The mesh attributes at the variant's vertex input locations, by Bevy's
/// mesh pipeline's convention.
fn vertex_attributes(plan: &Plan) -> Result<Vec<bevy::mesh::VertexAttributeDescriptor>, String> {
    plan.vertex_layout
        .iter()
        .filter(|input| input.previous_of.is_none())
        .map(|input| {
            let attribute = match input.location {
                0 => Mesh::ATTRIBUTE_POSITION,
                1 => Mesh::ATTRIBUTE_NORMAL,
                2 => Mesh::ATTRIBUTE_UV_0,
                3 => Mesh::ATTRIBUTE_UV_1,
                4 => Mesh::ATTRIBUTE_TANGENT,
                5 => Mesh::ATTRIBUTE_COLOR,
                other => {
                    return Err(format!(
                        "vertex input `{}` at @location({other}) is not one of Bevy's mesh attributes (0 to 5: position, normal, uv, uv_b, tangent, colour)",
                        input.name
                    ))
                }
            };
            Ok(attribute.at_shader_location(input.location))
        })
        .collect()
}

/// What the views' passes draw: the phase of cached meshes, each view's
/// cache, the views that cache this frame, and Bevy's view uniforms (the
/// twin's source).
#[derive(SystemParam)]
struct CachedDraws<'w> {
    phases: Res<'w, ViewSortedRenderPhases<CachedMesh3d>>,
    caches: Res<'w, ViewCaches>,
    caching: Res<'w, CachingViews>,
    layouts: Res<'w, QueuedLayouts>,
    variants: Res<'w, CachedVariants>,
    view_uniforms: Res<'w, ViewUniforms>,
    edited: Res<'w, EditedMaterials>,
    material_instances: Res<'w, RenderMaterialInstances>,
}

/// Records the view's variants after Bevy's opaque pass, one cached
/// material after another: for each, the view's uniform copied for next
/// frame's twin, then each pass drawing the material's cached meshes (its
/// run of the phase) with Bevy's render commands.
fn draw_cached_passes(
    world: &World,
    view: ViewQuery<(
        &ExtractedView,
        &ViewTarget,
        &ViewDepthStencilTexture,
        &ViewUniformOffset,
        &ReprojectionCache,
    )>,
    drawn: CachedDraws,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    stats: Res<CacheStats>,
    mut ctx: RenderContext,
) {
    let CachedDraws {
        phases,
        caches,
        caching,
        layouts,
        variants,
        view_uniforms,
        edited,
        material_instances,
    } = drawn;
    let view_entity = view.entity();
    let (extracted, target, depth, offset, settings) = view.into_inner();
    let id = extracted.retained_view_entity;
    let (Some(phase), Some(uniforms)) = (
        phases.get(&id),
        view_uniforms
            .uniforms
            .buffer()
            .filter(|buffer| buffer.usage().contains(BufferUsages::COPY_SRC)),
    ) else {
        return;
    };
    let drawing: Vec<(CacheId, Range<usize>)> = cache_runs(phase)
        .into_iter()
        .filter_map(|(first, items)| {
            let cache = layouts.cache_of(id, first)?;
            caching.0.contains(&cache).then_some((cache, items))
        })
        .collect();
    if drawing.is_empty() {
        return;
    }
    // The passes' GPU time, as Bevy's own passes record theirs
    // (`render/shadecache/elapsed_gpu` with `RenderDiagnosticsPlugin`):
    // every cached material of the view.
    let diagnostics = ctx.diagnostic_recorder();
    let encoder = ctx.command_encoder();
    let span = diagnostics
        .as_ref()
        .map(|diagnostics| diagnostics.time_span(encoder, "shadecache"));
    let color = [Some(&**target.main_texture_view())];
    let targets = Targets {
        color: &color,
        clear: None,
        // The view's depth, which the opaque pass filled and the
        // transparent pass tests against.
        depth: Some(&depth.attachment.texture.default_view),
    };
    for (cache_id, items) in drawing {
        let variant = cache_id.1;
        let Some(slot) = caches.0.get(&cache_id) else {
            continue;
        };
        let mut slot = slot.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        let Slot::Ready(cache) = &mut *slot else {
            continue;
        };
        let texture = target.main_texture();
        if let Err(err) = cache.shader.resize((texture.width(), texture.height())) {
            stats.error(err.to_string());
            continue;
        }
        // A cut, or its meshes' material values changed this frame (an
        // asset swapped or edited): what the cache holds is of another
        // shot or other values.
        use bevy::render::render_phase::PhaseItem;
        let bound = phase
            .items
            .values()
            .skip(items.start)
            .take(items.len())
            .filter_map(|item| {
                let instance = material_instances.instances.get(&item.main_entity())?;
                Some((item.main_entity(), instance.asset_id))
            });
        let materials_changed = cache.materials_changed(bound, &edited);
        if settings.is_cut() || materials_changed {
            cache.shader.reset();
        }
        let frame = CacheFrame {
            world,
            phase,
            view: (view_entity, id),
            items,
            targets: &targets,
            textures: (target.main_texture(), &depth.attachment.texture.texture),
            device: &device,
            queue: &queue,
            uniforms: (uniforms, offset.offset as u64),
            viewport: cache.key.viewport,
        };
        let name = variants.name(variant);
        match frame.draw(cache, settings.mode, encoder) {
            Ok((cached, readout)) => {
                if cached {
                    stats.drew(name);
                }
                if let Some(readout) = readout {
                    stats.governed(name, readout);
                }
            }
            Err(err) => stats.error(err),
        }
    }
    if let Some(span) = span {
        span.end(encoder);
    }
}

/// What one cache's frame draws with: the view, its run of the phase, its
/// targets, and Bevy's view uniforms (the twin's source, at the view's
/// offset).
struct CacheFrame<'a> {
    world: &'a World,
    phase: &'a SortedRenderPhase<CachedMesh3d>,
    view: (Entity, bevy::render::view::RetainedViewEntity),
    items: Range<usize>,
    targets: &'a Targets<'a>,
    /// The view's colour and depth textures (the error watch copies them).
    textures: (&'a wgpu::Texture, &'a wgpu::Texture),
    device: &'a RenderDevice,
    queue: &'a RenderQueue,
    uniforms: (&'a wgpu::Buffer, u64),
    /// The camera's viewport, where it is part of the target.
    viewport: Option<[u32; 4]>,
}

impl CacheFrame<'_> {
    /// Draws the frame of `cache` as its mode and governor say: through
    /// the variant or Bevy's way, timed where it is governed, the times
    /// that have arrived given to the governor. Whether it drew through
    /// the cache, and the governor's state where it is governed.
    fn draw(
        &self,
        cache: &mut ViewCache,
        mode: CacheMode,
        encoder: &mut wgpu::CommandEncoder,
    ) -> Result<(bool, Option<GovernorReadout>), String> {
        let governed = cache.governed(mode, self.device, self.queue)?;
        let device = self.device.wgpu_device();
        if let Some(timer) = &mut governed.timer {
            let times = timer.ready(device).map_err(|err| err.to_string())?;
            for (frame, ms) in times {
                governed.governor.measured(frame, ms);
                governed.counts.measured_frames += 1;
            }
        }
        if let Some(Ok(view_watch)) = &mut governed.watch {
            if let Some(answer) = view_watch
                .watch
                .ready(device)
                .map_err(|err| err.to_string())?
            {
                governed.governor.watched(answer.frame, answer.psnr);
                governed.counts.psnr = Some(answer.psnr);
            }
        }
        let next = governed.governor.next_frame();
        let timed = governed
            .timer
            .as_mut()
            .is_some_and(|timer| timer.begin_frame(next.frame));
        let cached = matches!(next.choice, Choice::Cached { .. });
        if let Choice::Cached { reset: true } = next.choice {
            cache.shader.reset();
        }
        if cached && cache.shader.refresh_period() != next.period {
            cache
                .shader
                .set_refresh_period(next.period)
                .map_err(|err| err.to_string())?;
        }
        let ViewCache {
            shader,
            view_now,
            twins,
            governed,
            ..
        } = cache;
        let governed = governed.as_mut().ok_or("no governor")?;
        self.prepare_watch(governed.mode, &mut governed.watch);
        if let Some(Err(_)) = governed.watch {
            // No watch can run here: the speed alone decides.
            governed.governor.drop_budget();
        }
        let free = match &governed.watch {
            Some(Ok(watch)) => watch.watch.is_free(),
            _ => false,
        };
        if next.watch && !free {
            // Its last answer is still on the way: an ordinary cached
            // frame, the next watch the next due.
            governed.governor.unwatched(next.frame);
        }
        let watch = match &mut governed.watch {
            Some(Ok(watch)) if cached && next.watch && free => Some(watch),
            _ => None,
        };
        let timer = governed.timer.as_mut().filter(|_| timed);
        let result = match (timer, cached) {
            (Some(timer), true) => self.cached(
                encoder,
                (shader, view_now, twins),
                (timer, watch),
                next.frame,
            ),
            (None, true) => self.cached(
                encoder,
                (shader, view_now, twins),
                (&mut NoTimer, watch),
                next.frame,
            ),
            (Some(timer), false) => self.bevys_way(encoder, timer, self.view_targets()),
            (None, false) => self.bevys_way(encoder, &mut NoTimer, self.view_targets()),
        };
        if let Some(timer) = governed.timer.as_mut().filter(|_| timed) {
            timer.resolve(encoder);
        }
        result?;
        let counts = &mut governed.counts;
        if cached {
            counts.cached_frames += 1;
        } else {
            counts.original_frames += 1;
        }
        let governor = &governed.governor;
        let governs = matches!(governed.mode, CacheMode::Auto { .. });
        Ok((
            cached,
            governs.then_some(GovernorReadout {
                on: governor.is_on(),
                estimate: governor.estimate(),
                period: governor.period(),
                ..*counts
            }),
        ))
    }

    /// The variant's passes over the run: the view's uniform copied for
    /// next frame's twin, then each pass drawing the run with Bevy's
    /// render commands.
    ///
    /// On a watched frame, the view's colour and depth are copied first,
    /// Bevy's way draws the run into the copies after, and the watch
    /// compares the two frames over the pixels either changed.
    fn cached<T: PassTimer>(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        (shader, view_now, twins): (&mut CachedShader, &wgpu::Buffer, &Twins),
        (timer, watch): (&mut T, Option<&mut ViewWatch>),
        frame: u64,
    ) -> Result<(), String> {
        let (color, depth) = self.textures;
        if let Some(watch) = &watch {
            watch.copy_view(encoder, color, depth);
        }
        let (uniforms, offset) = self.uniforms;
        encoder.copy_buffer_to_buffer(uniforms, offset, view_now, 0, view_now.size());
        shader
            .record_engine_timed(
                self.queue,
                encoder,
                self.targets,
                timer,
                twins,
                |_, pass| {
                    let mut pass = TrackedRenderPass::new(self.device, pass);
                    self.phase
                        .render_range(&mut pass, self.world, self.view.0, self.items.clone())
                        .map_err(|err| format!("{err:?}"))
                },
            )
            .map_err(|err| err.to_string())?;
        let Some(watch) = watch else {
            return Ok(());
        };
        let spare = watch.watch.spare_view().clone();
        self.bevys_way(encoder, timer, (&spare, &watch.depth_view))?;
        watch
            .watch
            .compare(
                self.device.wgpu_device(),
                (self.queue, encoder),
                timer,
                frame,
                color,
                Coverage::ChangedFrom(&watch.base),
            )
            .map(|_| ())
            .map_err(|err| err.to_string())
    }

    /// The view's colour and depth attachments, which `draw_cached_passes`
    /// always gives.
    fn view_targets(&self) -> (&wgpu::TextureView, &wgpu::TextureView) {
        let color = self.targets.color.first().copied().flatten();
        match (color, self.targets.depth) {
            (Some(color), Some(depth)) => (color, depth),
            _ => unreachable!("the view's targets are made with a colour and a depth"),
        }
    }

    /// Makes the view's watch at its first frame with a budget, and again
    /// when the view's size changes; where the view cannot be watched,
    /// says why once and keeps the reason.
    fn prepare_watch(&self, mode: CacheMode, watch: &mut Option<Result<ViewWatch, String>>) {
        if !matches!(mode, CacheMode::Auto { min_psnr: Some(_) }) {
            return;
        }
        let (color, depth) = self.textures;
        let stale = match &*watch {
            Some(Ok(watch)) => watch.base.size() != color.size(),
            Some(Err(_)) => false,
            None => true,
        };
        if stale {
            let made = ViewWatch::new(self.device.wgpu_device(), color, depth);
            if let Err(why) = &made {
                warn!("shadecache: the view's error watch cannot run, so the speed alone decides: {why}");
            }
            *watch = Some(made);
        }
    }

    /// The run drawn as Bevy draws it: one pass into the view's colour and
    /// depth, each mesh with the pipeline Bevy specialised for it and the
    /// same render commands. The frame is Bevy's own; the cache is not
    /// recorded (its next frame reuses from the last one that was).
    fn bevys_way<T: PassTimer>(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        timer: &mut T,
        (color, depth): (&wgpu::TextureView, &wgpu::TextureView),
    ) -> Result<(), String> {
        use bevy::pbr::SpecializedMaterialPipelineCache;
        use bevy::render::render_resource::PipelineCache;
        let specialized = self
            .world
            .resource::<SpecializedMaterialPipelineCache>()
            .get(&self.view.1)
            .ok_or("the view has no pipelines Bevy specialised")?;
        let pipelines = self.world.resource::<PipelineCache>();
        let query = timer.begin(encoder, "original");
        let raw = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("shadecache: the cached meshes as Bevy draws them"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: color,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: depth,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Load,
                    store: wgpu::StoreOp::Store,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: timer.timestamp_writes(&query),
            ..Default::default()
        });
        let mut pass = TrackedRenderPass::new(self.device, raw);
        if let Some([x, y, width, height]) = self.viewport {
            pass.set_viewport(x as f32, y as f32, width as f32, height as f32, 0.0, 1.0);
        }
        // Batch by batch, as `render_range` draws them (a batch's first
        // item draws every instance of it, each with its own mesh from
        // the indirect parameters), each batch with the pipeline Bevy
        // specialised for its meshes.
        use bevy::render::render_phase::PhaseItem;
        let pipeline_of = |index: usize| {
            let (_, item) = self.phase.items.get_index(index)?;
            specialized.get(&item.main_entity()).copied()
        };
        let mut drawn = Ok(());
        let mut index = self.items.start;
        while index < self.items.end && drawn.is_ok() {
            let Some((_, item)) = self.phase.items.get_index(index) else {
                break;
            };
            let batch = item.batch_range().len().max(1);
            let end = (index + batch).min(self.items.end);
            let first = pipeline_of(index);
            drawn = match (
                first,
                first.and_then(|id| pipelines.get_render_pipeline(id)),
            ) {
                (Some(id), Some(pipeline)) if (index..end).all(|i| pipeline_of(i) == Some(id)) => {
                    pass.set_render_pipeline(pipeline);
                    self.phase
                        .render_range(&mut pass, self.world, self.view.0, index..end)
                        .map_err(|err| format!("{err:?}"))
                }
                (Some(_), Some(_)) => Err(
                    "a batch of cached meshes has meshes Bevy draws with different pipelines"
                        .into(),
                ),
                _ => Err("Bevy's pipeline for a cached mesh is not ready".into()),
            };
            index = end;
        }
        drop(pass);
        timer.end(encoder, query);
        drawn
    }
}

/// Each cache's run of the phase's items (sorted by variant and layout),
/// with its first item.
fn cache_runs(phase: &SortedRenderPhase<CachedMesh3d>) -> Vec<(&CachedMesh3d, Range<usize>)> {
    let mut runs: Vec<(&CachedMesh3d, Range<usize>)> = Vec::new();
    for (index, item) in phase.items.values().enumerate() {
        match runs.last_mut() {
            Some((first, range)) if first.sort_key() == item.sort_key() => range.end = index + 1,
            _ => runs.push((item, index..index + 1)),
        }
    }
    runs
}
