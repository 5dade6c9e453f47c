//! The cached meshes of each caching view, as a render phase of their own.
//!
//! Bevy draws a mesh through a render phase: the phase's items are queued
//! from the view's visible meshes, Bevy's mesh batching writes their mesh
//! uniforms (on the GPU, where it preprocesses) and indirect parameters,
//! and `DrawMesh` draws them. The variant's passes draw the same meshes
//! with Bevy's own bindings, so they are queued into a phase of their own
//! (a sorted phase, as Bevy's own custom-phase example does, batched by
//! Bevy's `MeshPipeline` batching), drawn once per pass. While a view
//! caches, its cached meshes are taken out of Bevy's opaque phase; when it
//! stops (switched off, or its cache failed), the view is marked for
//! respecialisation, so Bevy queues them again.

use std::ops::Range;

use bevy::core_pipeline::core_3d::Opaque3d;
use bevy::ecs::entity::EntityHash;
use bevy::ecs::system::SystemParam;
use bevy::mesh::{BaseMeshPipelineKey, MeshVertexBufferLayoutRef};
use bevy::pbr::{
    DrawMesh, MeshPipeline, PreparedMaterial, RenderMaterialInstances, RenderMeshInstances,
    SetMaterialBindGroup, SetMeshBindGroup, SetMeshViewBindGroup, SetMeshViewBindingArrayBindGroup,
    SpecializedMaterialPipelineCache, MATERIAL_BIND_GROUP_INDEX,
};
use bevy::platform::collections::{HashMap, HashSet};
use bevy::prelude::*;
use bevy::render::batching::gpu_preprocessing::batch_and_prepare_sorted_render_phase;
use bevy::render::camera::DirtySpecializations;
use bevy::render::erased_render_asset::ErasedRenderAssets;
use bevy::render::mesh::RenderMesh;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_phase::{
    sort_phase_system, AddRenderCommand, CachedRenderPipelinePhaseItem, DrawFunctionId,
    DrawFunctions, PhaseItem, PhaseItemExtraIndex, SortedPhaseItem, SortedRenderPhasePlugin,
    ViewBinnedRenderPhases, ViewSortedRenderPhases,
};
use bevy::render::render_resource::{CachedPipelineState, CachedRenderPipelineId, PipelineCache};
use bevy::render::renderer::RenderDevice;
use bevy::render::sync_world::MainEntity;
use bevy::render::view::{ExtractedView, RenderVisibleEntities, RetainedViewEntity};
use bevy::render::{Extract, ExtractSchedule, Render, RenderApp, RenderDebugFlags, RenderSystems};
use indexmap::IndexMap;

use crate::defs::{BevyDefs, LibraryDefs};
use crate::reload::ReloadedMaterials;
use crate::{CacheStats, CachedMaterial, CachedVariants, ReprojectionCache};

/// What each pass draws per cached mesh: Bevy's material draw, without its
/// pipeline (each pass's pipeline is the host's, set before).
pub(crate) type DrawCachedMesh = (
    SetMeshViewBindGroup<0>,
    SetMeshViewBindingArrayBindGroup<1>,
    SetMeshBindGroup<2>,
    SetMaterialBindGroup<MATERIAL_BIND_GROUP_INDEX>,
    DrawMesh,
);

/// One cached mesh in a view.
pub(crate) struct CachedMesh3d {
    entity: (Entity, MainEntity),
    /// Its material's variant ([`CachedVariants`]) and how Bevy draws it
    /// (an index into the view variant's [`QueuedLayouts`]: its vertex
    /// layout and primitive state): the phase keeps the meshes of each
    /// pair together, and each pair's cache draws its own.
    pub variant: u32,
    pub layout: u32,
    draw_function: DrawFunctionId,
    batch_range: Range<u32>,
    extra_index: PhaseItemExtraIndex,
    indexed: bool,
}

impl PhaseItem for CachedMesh3d {
    fn entity(&self) -> Entity {
        self.entity.0
    }

    fn main_entity(&self) -> MainEntity {
        self.entity.1
    }

    fn draw_function(&self) -> DrawFunctionId {
        self.draw_function
    }

    fn batch_range(&self) -> &Range<u32> {
        &self.batch_range
    }

    fn batch_range_mut(&mut self) -> &mut Range<u32> {
        &mut self.batch_range
    }

    fn extra_index(&self) -> PhaseItemExtraIndex {
        self.extra_index.clone()
    }

    fn batch_range_and_extra_index_mut(&mut self) -> (&mut Range<u32>, &mut PhaseItemExtraIndex) {
        (&mut self.batch_range, &mut self.extra_index)
    }
}

impl SortedPhaseItem for CachedMesh3d {
    // The meshes of each variant and vertex layout in one run of the
    // phase, which that cache's passes draw; within a run the passes
    // depth-test, so the order changes no pixel and the items stay in the
    // order they were queued.
    type SortKey = (u32, u32);

    fn sort_key(&self) -> Self::SortKey {
        (self.variant, self.layout)
    }

    fn sort(items: &mut IndexMap<(Entity, MainEntity), CachedMesh3d, EntityHash>) {
        // Stable: the queued order within a run stays.
        items.sort_by(|_, a, _, b| a.sort_key().cmp(&b.sort_key()));
    }

    fn recalculate_sort_keys(
        _: &mut IndexMap<(Entity, MainEntity), Self, EntityHash>,
        _: &ExtractedView,
    ) {
    }

    fn indexed(&self) -> bool {
        self.indexed
    }
}

impl CachedRenderPipelinePhaseItem for CachedMesh3d {
    /// The pass's pipeline is the host's, not one of Bevy's pipeline cache:
    /// the draw function sets none, and nothing looks this id up. Bevy's
    /// batching keeps items of one id together, and two materials' bind
    /// groups can share an index (each material type has its own
    /// allocator): an id per variant and layout keeps a batch within one
    /// run.
    fn cached_pipeline(&self) -> CachedRenderPipelineId {
        let run = ((self.variant as usize) << 16) | self.layout as usize;
        CachedRenderPipelineId::new(usize::MAX - 1 - run)
    }
}

/// One material's variant in one view.
pub(crate) type ViewVariant = (RetainedViewEntity, u32);

/// How Bevy draws a mesh, as far as the variant's pipelines go: its
/// vertex layout, and the primitive state Bevy's specialisation gave its
/// pipeline (the mesh's topology, the material's culling and whatever
/// else its `specialize` set).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub(crate) struct DrawnAs {
    pub layout: MeshVertexBufferLayoutRef,
    pub primitive: wgpu::PrimitiveState,
    /// The build of the material's variant composed as Bevy composed the
    /// mesh's pipeline (an index into its `builds`).
    pub build: u32,
}

/// What one cache is made for: a material's variant in a view, for the
/// meshes drawn one way (the host's pipelines take one vertex layout and
/// primitive state; meshes drawn several ways have a cache each).
pub(crate) type CacheId = (RetainedViewEntity, u32, DrawnAs);

/// How each view's cached meshes of each variant are drawn, as queued
/// this frame: an item's `layout` is an index into its list.
#[derive(Resource, Default)]
pub(crate) struct QueuedLayouts(pub HashMap<ViewVariant, Vec<DrawnAs>>);

impl QueuedLayouts {
    /// The cache that draws `item` in `view`.
    pub fn cache_of(&self, view: RetainedViewEntity, item: &CachedMesh3d) -> Option<CacheId> {
        let layout = self
            .0
            .get(&(view, item.variant))?
            .get(item.layout as usize)?;
        Some((view, item.variant, layout.clone()))
    }
}

/// The caches whose meshes were taken out of Bevy's opaque phase this
/// frame, and the views of those taken before and no longer: Bevy queues
/// the meshes of those views again.
#[derive(Resource, Default)]
pub(crate) struct TakenViews {
    taken: HashSet<CacheId>,
    handed_back: HashSet<RetainedViewEntity>,
}

impl TakenViews {
    /// Hands back the views of the caches that took meshes and that
    /// `keeps` does not keep, once: they leave the taken set, so the queue
    /// does not find them again.
    fn hand_back_unless(&mut self, keeps: impl Fn(&CacheId) -> bool) {
        let TakenViews { taken, handed_back } = self;
        taken.retain(|id| {
            let kept = keeps(id);
            if !kept {
                handed_back.insert(id.0);
            }
            kept
        });
    }
}

/// The caches that draw this frame: their view caches, and they were made
/// (a view whose cache failed leaves those meshes to Bevy).
#[derive(Resource, Default)]
pub(crate) struct CachingViews(pub HashSet<CacheId>);

pub(crate) struct CachedPhasePlugin;

impl Plugin for CachedPhasePlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins(SortedRenderPhasePlugin::<CachedMesh3d, MeshPipeline>::new(
            RenderDebugFlags::default(),
        ));
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_resource::<DrawFunctions<CachedMesh3d>>()
            .add_render_command::<CachedMesh3d, DrawCachedMesh>()
            .init_resource::<ViewSortedRenderPhases<CachedMesh3d>>()
            .init_resource::<QueuedLayouts>()
            .init_resource::<TakenViews>()
            .init_resource::<CachingViews>()
            .add_systems(ExtractSchedule, extract_cached_phases)
            .add_systems(
                Render,
                (
                    respecialize_handed_back_views.in_set(RenderSystems::PrepareAssets),
                    (queue_cached_meshes, take_from_opaque_phase)
                        .chain()
                        .in_set(RenderSystems::QueueMeshes)
                        .after(bevy::pbr::queue_material_meshes),
                    sort_phase_system::<CachedMesh3d>.in_set(RenderSystems::PhaseSort),
                    batch_and_prepare_sorted_render_phase::<CachedMesh3d, MeshPipeline>
                        .in_set(RenderSystems::PrepareResources),
                ),
            );
    }
}

/// The 3D cameras with a cache.
type CachingCameras<'w, 's> =
    Query<'w, 's, (Entity, &'static Camera, &'static ReprojectionCache), With<Camera3d>>;

/// Gives each caching camera's view its phase, and drops the phases of
/// views that went away. A view whose meshes were taken from Bevy's
/// opaque phase and that caches no more (switched off, gone inactive) is
/// handed back now, so that Bevy queues its meshes again in this very
/// frame: found in the next frame's queue, it would be a frame drawn by
/// neither.
fn extract_cached_phases(
    mut phases: ResMut<ViewSortedRenderPhases<CachedMesh3d>>,
    cameras: Extract<CachingCameras>,
    mut taken: ResMut<TakenViews>,
    mut live: Local<HashSet<RetainedViewEntity>>,
) {
    live.clear();
    for (main_entity, camera, cache) in &cameras {
        if !camera.is_active || !cache.enabled {
            continue;
        }
        let view = RetainedViewEntity::new(main_entity.into(), None, 0);
        phases.prepare_for_new_frame(view);
        live.insert(view);
    }
    phases.retain(|view, _| live.contains(view));
    taken.hand_back_unless(|(view, _, _)| live.contains(view));
}

/// A view that stopped caching (switched off, its cache failed) has its
/// meshes specialised and queued again by Bevy, so that they return to its
/// opaque phase. Bevy clears its dirty views as each frame is extracted,
/// so they are marked here, after that, for the frame that queues them. A
/// view that took the meshes of a material whose shader changed this frame
/// (`reload`) is marked at once too: its caches stop in this frame's queue.
fn respecialize_handed_back_views(
    mut taken: ResMut<TakenViews>,
    mut dirty: ResMut<DirtySpecializations>,
    variants: Res<CachedVariants>,
    reloaded: Res<ReloadedMaterials>,
) {
    taken.hand_back_unless(|(_, variant, _)| {
        variants
            .get(*variant)
            .is_none_or(|m| !reloaded.contains(m.material))
    });
    dirty.views.extend(taken.handed_back.drain());
}

/// What queueing a mesh into the phase reads: the phase's draw
/// functions, and Bevy's prepared meshes and their instances.
#[derive(SystemParam)]
pub(crate) struct MeshQueueing<'w> {
    draw_functions: Res<'w, DrawFunctions<CachedMesh3d>>,
    render_meshes: Res<'w, RenderAssets<RenderMesh>>,
    render_mesh_instances: Res<'w, RenderMeshInstances>,
    material_instances: Res<'w, RenderMaterialInstances>,
    materials: Res<'w, ErasedRenderAssets<PreparedMaterial>>,
    variants: Res<'w, CachedVariants>,
    specialized: Res<'w, SpecializedMaterialPipelineCache>,
    pipeline_cache: Res<'w, PipelineCache>,
    device: Res<'w, RenderDevice>,
    library_defs: Res<'w, LibraryDefs>,
}

impl MeshQueueing<'_> {
    /// The pipeline Bevy specialised for the mesh of `entity` in `view`
    /// (the material's `specialize` included), and its primitive state;
    /// `None` until that pipeline is made. `made` holds the pipelines seen
    /// made before: one being made again (its shader changed, a hot
    /// reload) still draws the mesh through the cache meanwhile, as Bevy's
    /// retained phase items wait for it; dropped from the cache's phase in
    /// that frame, the mesh was drawn by neither (it is out of Bevy's).
    fn drawn_by_bevy(
        &self,
        view: &RetainedViewEntity,
        entity: MainEntity,
        made: &mut HashSet<CachedRenderPipelineId>,
    ) -> Option<(CachedRenderPipelineId, wgpu::PrimitiveState)> {
        let id = *self.specialized.get(view)?.get(&entity)?;
        // Only a pipeline the cache has processed has its descriptor.
        match self.pipeline_cache.get_render_pipeline_state(id) {
            CachedPipelineState::Ok(_) => {
                made.insert(id);
            }
            CachedPipelineState::Queued | CachedPipelineState::Creating(_)
                if made.contains(&id) => {}
            _ => return None,
        }
        let primitive = self
            .pipeline_cache
            .get_render_pipeline_descriptor(id)
            .primitive;
        Some((id, primitive))
    }

    /// The first build of the material `variant`'s variant composed as
    /// Bevy composed `pipeline`; why a mesh drawn with it is left to Bevy
    /// where none is: the first build's defs that differ.
    fn build(&self, variant: u32, pipeline: CachedRenderPipelineId) -> Result<u32, String> {
        let descriptor = self.pipeline_cache.get_render_pipeline_descriptor(pipeline);
        let stages = descriptor
            .vertex
            .shader_defs
            .iter()
            .chain(descriptor.fragment.iter().flat_map(|f| &f.shader_defs));
        let defs = BevyDefs::new(stages, &self.device, &self.library_defs);
        let builds = self.variants.get(variant).map_or(&[][..], |m| &m.builds);
        let differences: Vec<Vec<String>> = builds
            .iter()
            .map(|build| defs.differences(&build.plan().shader_defs))
            .collect();
        match differences.iter().position(Vec::is_empty) {
            Some(build) => Ok(build as u32),
            None => Err(format!(
                "composed by Bevy with other defs than {}'s variant was ({}): build the variant with Bevy's defs for this mesh as well and add it with `ShadecachePlugin::and`",
                self.variants.name(variant),
                differences.first().map_or(String::new(), |d| d.join("; "))
            )),
        }
    }

    /// The variant that draws the mesh of `entity`: its material's; why it
    /// is left to Bevy where its material has none. `None` while its
    /// material is not extracted yet.
    fn variant(&self, entity: MainEntity) -> Option<Result<u32, String>> {
        let instance = self.material_instances.instances.get(&entity)?;
        let material = instance.asset_id.type_id();
        Some(self.variants.index_of(material).ok_or_else(|| {
            format!(
                "of a material no ShadecachePlugin was added for (the cached materials: {}; add `ShadecachePlugin::<M>` with its variant to cache it)",
                self.variants.names()
            )
        }))
    }

    /// Why the mesh of `entity` is left to Bevy, for what the variant's
    /// passes cannot draw as Bevy would: a skinned or morphed mesh, a
    /// lightmapped one (its mesh bind group has the lightmap's layout), one
    /// whose material blends or masks (Bevy draws it in its own phase, in
    /// depth order) or is drawn deferred.
    fn left_to_bevy(
        &self,
        entity: MainEntity,
        mesh: &RenderMesh,
        lightmapped: bool,
    ) -> Option<String> {
        // Their mesh bind group has another layout (joints, morph
        // weights), and their previous positions need last frame's joints
        // and weights.
        if mesh.layout.0.contains(Mesh::ATTRIBUTE_JOINT_INDEX) {
            return Some("skinned, which the plugin does not draw through the cache yet".into());
        }
        if mesh.key_bits.contains(BaseMeshPipelineKey::MORPH_TARGETS) {
            return Some("morphed, which the plugin does not draw through the cache yet".into());
        }
        if lightmapped {
            return Some("lightmapped: its mesh bind group holds the lightmap, which the variant's pipelines were not made for".into());
        }
        let instance = self.material_instances.instances.get(&entity)?;
        let material = self.materials.get(instance.asset_id)?;
        let properties = &material.properties;
        if properties.alpha_mode != AlphaMode::Opaque {
            return Some(format!(
                "drawn with alpha mode {:?}: the cache keeps one opaque value per pixel, and Bevy draws such a mesh in its own phase",
                properties.alpha_mode
            ));
        }
        if properties.render_method == bevy::material::OpaqueRendererMethod::Deferred {
            return Some(
                "drawn deferred: its material writes Bevy's G-buffer, which the variant's passes do not".into(),
            );
        }
        None
    }
}

/// What queueing keeps from frame to frame: the meshes already refused
/// (said once), which build of a variant each of Bevy's pipelines
/// matches (its defs compared once, not per mesh and frame), and the
/// pipelines seen made.
#[derive(Default)]
pub(crate) struct QueueMemory {
    refused: HashSet<MainEntity>,
    matches: HashMap<(u32, CachedRenderPipelineId), Result<u32, String>>,
    made: HashSet<CachedRenderPipelineId>,
}

/// Queues the view's visible cached meshes into its phase, every frame
/// (the phase is small: the meshes of the cached materials), each with
/// its material's variant, and notes their vertex layouts.
pub(crate) fn queue_cached_meshes(
    queueing: MeshQueueing,
    mut phases: ResMut<ViewSortedRenderPhases<CachedMesh3d>>,
    views: Query<(&ExtractedView, &RenderVisibleEntities)>,
    cached: Query<(), With<CachedMaterial>>,
    mut layouts: ResMut<QueuedLayouts>,
    stats: Res<CacheStats>,
    mut memory: Local<QueueMemory>,
) {
    let QueueMemory {
        refused,
        matches,
        made,
    } = &mut *memory;
    if queueing.library_defs.is_changed() {
        matches.clear();
    }
    let draw = queueing.draw_functions.read().id::<DrawCachedMesh>();
    let (render_meshes, render_mesh_instances) =
        (&queueing.render_meshes, &queueing.render_mesh_instances);
    layouts.0.clear();
    for (view, visible) in &views {
        // Extraction emptied it of last frame's (transient) items.
        let Some(phase) = phases.get_mut(&view.retained_view_entity) else {
            continue;
        };
        let Some(meshes) = visible.get::<Mesh3d>() else {
            continue;
        };
        let gpu_culled = meshes
            .entities_gpu_culling
            .iter()
            .map(|(main, render)| (render, main));
        let cpu_culled = meshes.entities_cpu_culling.iter().map(|(r, m)| (r, m));
        for (render_entity, main_entity) in cpu_culled.chain(gpu_culled) {
            if cached.get(*render_entity).is_err() {
                continue;
            }
            let Some(instance) = render_mesh_instances.render_mesh_queue_data(*main_entity) else {
                continue;
            };
            let Some(mesh) = render_meshes.get(instance.mesh_asset_id()) else {
                continue;
            };
            let lightmapped = instance.lightmap_slab_index().is_some();
            let Some(variant) = queueing.variant(*main_entity) else {
                continue;
            };
            let left = match &variant {
                Ok(_) => queueing.left_to_bevy(*main_entity, mesh, lightmapped),
                Err(reason) => Some(reason.clone()),
            };
            if let Some(reason) = left {
                if refused.insert(*main_entity) {
                    stats.error(format!(
                        "mesh entity {main_entity:?} is {reason}: Bevy draws it with its material"
                    ));
                }
                continue;
            }
            let Ok(variant) = variant else { continue };
            // Not drawn by Bevy yet either: its pipeline is on the way.
            let Some((pipeline, primitive)) =
                queueing.drawn_by_bevy(&view.retained_view_entity, *main_entity, made)
            else {
                continue;
            };
            // Meshes drawn with one pipeline share its defs: matched once.
            let build = matches
                .entry((variant, pipeline))
                .or_insert_with(|| queueing.build(variant, pipeline))
                .clone();
            let build = match build {
                Ok(build) => build,
                Err(reason) => {
                    if refused.insert(*main_entity) {
                        stats.error(format!(
                            "mesh entity {main_entity:?} is {reason}: Bevy draws it with its material"
                        ));
                    }
                    continue;
                }
            };
            let drawn = DrawnAs {
                layout: mesh.layout.clone(),
                primitive,
                build,
            };
            let view_layouts = layouts
                .0
                .entry((view.retained_view_entity, variant))
                .or_default();
            let layout = match view_layouts.iter().position(|d| *d == drawn) {
                Some(index) => index,
                None => {
                    view_layouts.push(drawn);
                    view_layouts.len() - 1
                }
            };
            phase.add_transient(CachedMesh3d {
                entity: (*render_entity, *main_entity),
                variant,
                layout: layout as u32,
                draw_function: draw,
                batch_range: 0..1,
                extra_index: PhaseItemExtraIndex::None,
                indexed: mesh.indexed(),
            });
        }
    }
}

/// Takes the meshes of each cache that draws out of Bevy's opaque phase:
/// the variant draws them. A view that took a cache's meshes before and
/// does not now hands them back.
pub(crate) fn take_from_opaque_phase(
    phases: Res<ViewSortedRenderPhases<CachedMesh3d>>,
    caching: Res<CachingViews>,
    layouts: Res<QueuedLayouts>,
    mut opaque: ResMut<ViewBinnedRenderPhases<Opaque3d>>,
    mut taken: ResMut<TakenViews>,
) {
    for (view, phase) in phases.iter() {
        let Some(opaque) = opaque.get_mut(view) else {
            continue;
        };
        for ((_, main_entity), item) in &phase.items {
            let cache = layouts.cache_of(*view, item);
            if cache.is_some_and(|cache| caching.0.contains(&cache)) {
                opaque.remove(*main_entity);
            }
        }
    }
    let now: HashSet<CacheId> = caching
        .0
        .iter()
        .filter(|(view, _, _)| opaque.contains_key(view))
        .cloned()
        .collect();
    taken.hand_back_unless(|id| now.contains(id));
    taken.taken = now;
}
