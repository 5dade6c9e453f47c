//! Draws a Bevy 0.20 material through a shadecache reprojection-cache
//! variant, in Bevy's own render graph, with Bevy's own bindings.
//!
//! shadecache rewrites a material's fragment shader (composed with Bevy's
//! WESL packages, by a build script) into cache variants: passes that
//! reuse last frame's payload where the surface point was visible, and
//! compute it afresh elsewhere and on a refresh pattern. Each variant comes
//! with a plan (`plan.json`). This crate runs one in a Bevy app:
//!
//! - **What the user writes.** A [`ShadecachePlugin::<M>`](ShadecachePlugin)
//!   for each cached material `M`, with the variant made from `M`'s shader
//!   ([`CachedVariant`], from the files the build script wrote); a
//!   [`CachedMaterial`] on each mesh entity to cache (the entity keeps its
//!   `MeshMaterial3d<M>`, whose type picks the variant); and a
//!   [`ReprojectionCache`] on each camera that caches.
//! - **Where it draws.** Each caching view has a render phase of its
//!   cached meshes (`phase.rs`), queued from Bevy's visibility and batched
//!   by Bevy's mesh batching, and removed from Bevy's opaque phase so Bevy
//!   does not draw them too; each material's meshes are one run of the
//!   phase. After the main opaque pass, the host crate
//!   ([`shadecache_host`]) records each material's variant into the view's
//!   target, one after the other, each with its own cache; each pass draws
//!   the material's run of the phase with Bevy's own render commands:
//!   the view bind group, the mesh bind group, the material's bind group,
//!   `DrawMesh` (so GPU preprocessing, indirect draws and Bevy's mesh
//!   slabs are Bevy's own).
//! - **Last frame.** The variant reads last frame's transforms. The mesh's
//!   are Bevy's own `previous_world_from_local` (the rewrite reads the
//!   sibling member, `plan.json`'s `previous_members`, so the mesh array
//!   needs no copy). The view's are a copy of the view's uniform kept by
//!   the host: each frame the plugin copies the view's slice of Bevy's view
//!   buffer into a buffer of its own, whose copy the host keeps for the
//!   next frame.
//! - **The cache's targets** (payload, age, depth, double-buffered) are
//!   the host's, per view, sized as the view's target: a resize makes them
//!   again and the next frame misses everywhere, as does a camera cut
//!   ([`ReprojectionCache::cut`]) and the first frame.
//! - **Failures** are Bevy errors in the log (and in [`CacheStats`]),
//!   never a panic in the game:
//!   a plan that does not match the view's layouts, meshes with other
//!   vertex attributes than the plan reads or of another material, what
//!   the host refuses (MSAA: the cache holds one value per pixel; a
//!   lowres variant in a camera viewport smaller than its target). The
//!   view then leaves the meshes to Bevy's own material, and says why
//!   once. A mesh the variant's passes cannot draw as Bevy does is left
//!   to Bevy on its own, with its reason logged once, while the view
//!   caches the others: skinned and morphed meshes, lightmapped ones,
//!   meshes whose material blends or masks (`AlphaMode` other than
//!   `Opaque`: Bevy draws them in its own phase) or is drawn deferred,
//!   and meshes of a material no plugin was added for.
//!
//! - **One depth with Bevy.** The variant's passes run between Bevy's
//!   opaque and transparent passes in the view's own depth: they test
//!   against what the opaque pass left and write into it, so Bevy's opaque
//!   meshes hide and are hidden by the cached ones, and the transparent
//!   pass blends over them in depth order. The host copies that depth into
//!   the cache for the next frame's reprojection (a point another mesh hid
//!   last frame misses), so a caching camera's depth texture is made a copy
//!   source. The variant's `less`/`greater` tests pass on equal depth, as
//!   a depth prepass (TAA's, SSAO's) already holds the cached meshes' own.
//!
//! - **Drawn as Bevy draws them.** The host makes a variant's pipelines
//!   for one vertex layout and primitive state, and the primitive state is
//!   that of the pipeline Bevy specialised for the mesh: the mesh's
//!   topology, the material's culling, whatever the material's own
//!   `specialize` set. A view's meshes of one material drawn several ways
//!   (one with vertex colours, one double-sided) have a cache each, drawn
//!   in turn, each its own run of the phase; a mesh is cached from the
//!   frame after Bevy's pipeline for it is made.
//!
//! - **Composed as Bevy composes it.** Bevy composes a material's shader
//!   per mesh layout and view; the variant was composed once, with the
//!   build script's defs, and its plan names those that change its code.
//!   A mesh is drawn through the first of its material's builds
//!   ([`ShadecachePlugin::and`]) whose defs are those of the pipeline Bevy
//!   specialised for it (`defs.rs`), else left to Bevy with the defs that
//!   differ in its reason.
//!
//! - **Bevy's own materials.** `StandardMaterial` is a material like any
//!   other: its variant is made from bevy_pbr's `render/pbr.wesl`
//!   (`Build::crate_shader`) with Bevy's defs for the mesh layout and
//!   `BINDLESS` (Bevy binds it bindless where the device can), and its
//!   meshes are drawn through it with Bevy's bindless material bind group.
//!   An `ExtendedMaterial<StandardMaterial, _>` is built from its
//!   extension's shader the same way (bindless only if the extension is).
//! - **Multi-pass variants and prepasses.** Without a prepass, the view's
//!   depth holds only Bevy's other meshes and the plan's strict depth
//!   tests stand, so a later pass (two-pass's second, three-pass's third)
//!   draws only the pixels the earlier ones left. After a prepass the
//!   depth already holds the cached meshes' own: the tests pass on equal
//!   depth, and a variant whose later passes are told apart by depth is
//!   refused for the view (one-pass is not).
//!
//! What it does not do (yet): skinned, morphed, lightmapped, blended or
//! deferred meshes (left to Bevy, above).
//!
//! - **Bevy's pipeline model, no stall.** The variant's pass shaders are
//!   Bevy `Shader` assets, and a view's pipelines are queued in Bevy's
//!   `PipelineCache` from the host's descriptions of them
//!   (`CachedShader::describe_pipelines`), which compiles them off the
//!   frame as it compiles its own; Bevy draws the meshes until all are
//!   ready, then the host takes them (`from_pipelines_async`). With
//!   `RenderPlugin { synchronous_pipeline_compilation: true }` or
//!   [`CacheCreation`] they are made in the frame instead.
//! - **Hot reload.** The variant is rewritten at build time; a material
//!   whose fragment shader changes while the game runs (Bevy's file
//!   watcher) is handed back to Bevy from then on, said once
//!   (`reload.rs`), until the game is built again.
//! - **Split screen.** A camera drawing into part of its target has the
//!   variant's passes draw into its viewport, and the cache's lookups map
//!   last frame's positions into that rectangle of the target (the plan's
//!   `viewport_origin`); a viewport that changes makes the cache again.

mod defs;
mod edits;
mod phase;
mod pipelines;
mod reload;
mod view_cache;

use std::any::TypeId;
use std::marker::PhantomData;
use std::sync::Arc;

use bevy::prelude::*;
use bevy::render::extract_component::{ExtractComponent, ExtractComponentPlugin};
use bevy::render::RenderApp;
use bevy::shader::Shader;
use shadecache_host::Plan;

pub use shadecache_host;
pub use shadecache_host::{include_variants, CacheMode};
pub use view_cache::{CacheStats, GovernorReadout};

/// A variant's plan and its pass shaders, as the build script wrote them
/// (`plan.json` and the WGSL files it names).
#[derive(Clone)]
pub struct CachedVariant(Arc<VariantFiles>);

struct VariantFiles {
    plan: Plan,
    shaders: Vec<(String, String)>,
}

impl CachedVariant {
    /// Reads a plan and its pass shaders (each by the file name the plan
    /// uses). A plan that does not parse, is inconsistent or names a
    /// shader not given is an error here, before the app starts.
    pub fn new<N: Into<String>, S: Into<String>>(
        plan_json: &str,
        shaders: impl IntoIterator<Item = (N, S)>,
    ) -> Result<CachedVariant, shadecache_host::Error> {
        let plan: Plan = serde_json::from_str(plan_json)
            .map_err(|err| shadecache_host::Error::Plan(format!("plan.json: {err}")))?;
        plan.check().map_err(shadecache_host::Error::Plan)?;
        let shaders: Vec<(String, String)> = shaders
            .into_iter()
            .map(|(name, source)| (name.into(), source.into()))
            .collect();
        for pass in plan.passes.iter().chain(&plan.classify) {
            if !shaders.iter().any(|(name, _)| *name == pass.shader) {
                return Err(shadecache_host::Error::Mismatch(format!(
                    "pass `{}` is drawn with `{}`, which was not given",
                    pass.name, pass.shader
                )));
            }
        }
        Ok(CachedVariant(Arc::new(VariantFiles { plan, shaders })))
    }

    /// The plan.
    pub fn plan(&self) -> &Plan {
        &self.0.plan
    }

    /// A pass shader's WGSL, by the file name the plan uses.
    pub fn shader(&self, name: &str) -> Option<&str> {
        self.0
            .shaders
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, source)| source.as_str())
    }
}

/// How a view's cache is made. By default its pipelines compile in
/// Bevy's `PipelineCache`, off the frame: compiling them takes long
/// (hundreds of milliseconds for a material composed with Bevy's PBR on a
/// CPU rasteriser), and Bevy draws the meshes itself until the cache is
/// ready, so the frame does not stall. `synchronous: true` waits for them
/// in the frame that needs them, as Bevy's `RenderPlugin {
/// synchronous_pipeline_compilation }` does for its own pipelines (for
/// tests that compare frames from the first).
/// Insert it in the app before the first frame.
#[derive(
    Resource, Clone, Copy, Debug, Default, bevy::render::extract_resource::ExtractResource,
)]
#[extract_app(RenderApp)]
pub struct CacheCreation {
    /// Make each cache in the frame that needs it.
    pub synchronous: bool,
}

/// Marks a mesh entity to draw through its material's variant (the
/// [`ShadecachePlugin`] of its `MeshMaterial3d`'s type). The entity keeps
/// its `MeshMaterial3d`: the variant's passes bind that material's bind
/// group, and with the cache off Bevy draws it as before.
#[derive(Component, Clone, Copy, Debug, Default, ExtractComponent)]
#[extract_app(RenderApp)]
pub struct CachedMaterial;

/// A camera whose view draws its [`CachedMaterial`] meshes through the
/// variant. With `enabled` false Bevy draws them with their material, as
/// without the plugin.
#[derive(Component, Clone, Copy, Debug, ExtractComponent)]
#[extract_app(RenderApp)]
pub struct ReprojectionCache {
    /// Whether the view draws through the cache.
    pub enabled: bool,
    /// The refresh pattern's period Δn, in place of the plan's: every
    /// pixel is computed afresh at least every Δn frames. `None` keeps the
    /// plan's; 1 computes every pixel every frame (the cache is then the
    /// uncached frame, up to its format's rounding).
    pub refresh_period: Option<u32>,
    /// Set for one frame when the camera cuts ([`ReprojectionCache::cut`]):
    /// that frame misses everywhere. The plugin clears it as the next
    /// frame begins.
    pub cut: bool,
    /// Whether the view caches every frame (`Always`, the default: the
    /// developer measured that it pays) or lets the host crate's governor
    /// decide from this GPU's frame times (`Auto`): one frame in 16 the
    /// view draws the cached meshes with Bevy's own pipelines instead, in
    /// the same place of the frame, and the two kinds of frame's GPU times
    /// decide whether the cache pays here; a cache that loses is turned
    /// off (Bevy's pipelines draw the meshes) and probed again every 600
    /// frames. `Off` draws Bevy's way every frame, the meshes still in
    /// the plugin's pass. `Auto` needs timestamp queries (without them the
    /// view caches every frame, and says why). With an error budget
    /// (`min_psnr`), one cached frame in 64 is watched: the plugin copies
    /// the view's colour and depth as Bevy's opaque pass left them, draws
    /// the cached meshes Bevy's way into the copy, and the host crate's
    /// `ErrorWatch` compares the two frames over the pixels either
    /// changed; below the budget the governor lowers Δn, and at its floor
    /// turns the cache off. The watch needs the view's main texture to be
    /// a copy source bound as a texture (Bevy's default
    /// `CameraMainTextureUsages`) and a copyable depth (`Depth32Float`);
    /// otherwise it warns once and the speed alone decides. The
    /// governor's state is in [`CacheStats`] and in Bevy's diagnostics
    /// (`render/shadecache/<material>/...`).
    pub mode: CacheMode,
}

impl Default for ReprojectionCache {
    fn default() -> Self {
        ReprojectionCache {
            enabled: true,
            refresh_period: None,
            cut: false,
            mode: CacheMode::Always,
        }
    }
}

impl ReprojectionCache {
    /// Marks this frame as a camera cut (a teleport, a new shot): nothing
    /// of last frame is reused.
    pub fn cut(&mut self) {
        self.cut = true;
    }

    /// Whether this frame is marked as a cut.
    pub fn is_cut(&self) -> bool {
        self.cut
    }
}

/// Draws the [`CachedMaterial`] meshes of the material `M` through a
/// [`CachedVariant`] made from `M`'s shader, in the views of cameras with a
/// [`ReprojectionCache`]. Add one per cached material, each with its own
/// variant (`ShadecachePlugin::<LavaMaterial>::new(lava)` beside
/// `ShadecachePlugin::<StoneMaterial>::new(stone)`); Bevy's
/// `MaterialPlugin::<M>` draws `M` as before wherever the cache does not.
pub struct ShadecachePlugin<M> {
    builds: Vec<CachedVariant>,
    material: PhantomData<fn() -> M>,
}

impl<M: bevy::pbr::Material> ShadecachePlugin<M> {
    /// The plugin for `M`'s variant.
    pub fn new(variant: CachedVariant) -> Self {
        ShadecachePlugin {
            builds: vec![variant],
            material: PhantomData,
        }
    }

    /// Another build of `M`'s variant, composed with other defs (for
    /// meshes with vertex colours, say: Bevy composes `M`'s shader once
    /// per mesh layout and view). Each mesh is drawn through the first
    /// build composed as Bevy composes its pipeline (the plan's
    /// `shader_defs` against the defs of the pipeline Bevy specialised
    /// for it); a mesh no build matches is left to Bevy, with the defs
    /// that differ in its reason.
    pub fn and(mut self, variant: CachedVariant) -> Self {
        self.builds.push(variant);
        self
    }
}

impl<M: bevy::pbr::Material> Plugin for ShadecachePlugin<M> {
    fn build(&self, app: &mut App) {
        // What every cached material shares (the phase, the cameras'
        // components, the stats) is added with the first.
        if !app.is_plugin_added::<SharedPlugin>() {
            app.add_plugins(SharedPlugin);
        }
        let name = bevy::utils::prelude::ShortName::of::<M>().to_string();
        for diagnostic in diagnostics::of(&name) {
            bevy::diagnostic::RegisterDiagnostic::register_diagnostic(
                app,
                bevy::diagnostic::Diagnostic::new(diagnostic),
            );
        }
        app.add_systems(
            PostUpdate,
            move |stats: Res<CacheStats>, diagnostics: bevy::diagnostic::Diagnostics| {
                diagnostics::publish(&name, &stats, diagnostics)
            },
        )
        .add_systems(Update, reload::watch::<M>)
        .add_systems(
            PostUpdate,
            edits::watch::<M>.after(bevy::asset::AssetEventSystems),
        );
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .world_mut()
            .resource_mut::<CachedVariants>()
            .add::<M>(self.builds.clone());
    }

    /// The variant's pass shaders become Bevy `Shader` assets (Bevy's
    /// pipeline cache compiles from those), once every plugin is built.
    fn finish(&self, app: &mut App) {
        let name = bevy::utils::prelude::ShortName::of::<M>().to_string();
        let Some(mut shaders) = app.world_mut().get_resource_mut::<Assets<Shader>>() else {
            return;
        };
        let handles: Vec<pipelines::ShaderHandles> = self
            .builds
            .iter()
            .enumerate()
            .map(|(index, build)| pipelines::ShaderHandles::add(&mut shaders, &name, index, build))
            .collect();
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        let mut variants = render_app.world_mut().resource_mut::<CachedVariants>();
        if let Some(index) = variants.index_of(TypeId::of::<M>()) {
            variants.0[index as usize].shaders = handles;
        }
    }
}

/// The governor's state in Bevy's diagnostics, per cached material:
/// `render/shadecache/<material>/speedup` and its interval's bounds
/// (`speedup_low`, `speedup_high`), `cached` (1 while the cache is on, 0
/// while the governor has it off), `delta_n` (the refresh period) and,
/// with an error budget, `psnr` (the last watched frame's), as
/// `RenderDiagnosticsPlugin` puts Bevy's passes' times under `render/`.
mod diagnostics {
    use bevy::diagnostic::{DiagnosticPath, Diagnostics};

    use crate::CacheStats;

    const MEASURES: [&str; 6] = [
        "speedup",
        "speedup_low",
        "speedup_high",
        "cached",
        "delta_n",
        "psnr",
    ];

    /// The paths of `material`'s diagnostics.
    pub fn of(material: &str) -> Vec<DiagnosticPath> {
        MEASURES
            .iter()
            .map(|measure| DiagnosticPath::new(format!("render/shadecache/{material}/{measure}")))
            .collect()
    }

    /// Adds this frame's measurements of `material`'s governor, once it
    /// has one.
    pub fn publish(material: &str, stats: &CacheStats, mut diagnostics: Diagnostics) {
        let Some(readout) = stats.governor(material) else {
            return;
        };
        let paths = of(material);
        let mut add = |at: usize, value: f64| diagnostics.add_measurement(&paths[at], || value);
        if let Some(estimate) = readout.estimate {
            add(0, estimate.speedup);
            add(1, estimate.interval[0]);
            add(2, estimate.interval[1]);
        }
        add(3, f64::from(u8::from(readout.on)));
        add(4, f64::from(readout.period));
        if let Some(psnr) = readout.psnr {
            add(5, psnr);
        }
    }
}

/// The variant of each cached material, in the order their plugins were
/// added: a phase item's `variant` is its index here.
#[derive(Resource, Default)]
pub(crate) struct CachedVariants(Vec<MaterialVariant>);

pub(crate) struct MaterialVariant {
    /// The material asset's type.
    pub material: TypeId,
    /// Its name, for messages.
    pub name: String,
    /// Its variant's builds, each composed with its own defs
    /// ([`ShadecachePlugin::and`]); a mesh is drawn through the first
    /// composed as Bevy composes its pipeline.
    pub builds: Vec<CachedVariant>,
    /// Each build's pass shaders as Bevy assets, which Bevy's pipeline
    /// cache compiles the variant's pipelines from (added as the app is
    /// finished: empty before).
    pub shaders: Vec<pipelines::ShaderHandles>,
}

impl CachedVariants {
    /// `M`'s variant. Once per material: Bevy refuses a second
    /// `ShadecachePlugin::<M>` as it refuses any plugin added twice.
    fn add<M: Asset>(&mut self, builds: Vec<CachedVariant>) {
        self.0.push(MaterialVariant {
            material: TypeId::of::<M>(),
            name: bevy::utils::prelude::ShortName::of::<M>().to_string(),
            builds,
            shaders: Vec::new(),
        });
    }

    /// The index of the variant of the material asset type `material`.
    pub fn index_of(&self, material: TypeId) -> Option<u32> {
        self.0
            .iter()
            .position(|v| v.material == material)
            .map(|i| i as u32)
    }

    pub fn get(&self, index: u32) -> Option<&MaterialVariant> {
        self.0.get(index as usize)
    }

    /// How many cached materials there are.
    pub fn len(&self) -> u32 {
        self.0.len() as u32
    }

    /// The name of the material of the variant `index`.
    pub fn name(&self, index: u32) -> &str {
        self.get(index)
            .map_or("a cached material", |v| v.name.as_str())
    }

    /// The names of the cached materials, for a message.
    pub fn names(&self) -> String {
        let names: Vec<&str> = self.0.iter().map(|v| v.name.as_str()).collect();
        names.join(", ")
    }
}

/// What every cached material shares, added once.
struct SharedPlugin;

impl Plugin for SharedPlugin {
    fn build(&self, app: &mut App) {
        app
            .add_plugins(
                (
                    ExtractComponentPlugin::<CachedMaterial>::default(),
                    ExtractComponentPlugin::<ReprojectionCache>::default(),
                    bevy::render::extract_resource::ExtractResourcePlugin::<CacheCreation>::default(
                    ),
                    bevy::render::extract_resource::ExtractResourcePlugin::<
                        reload::ReloadedMaterials,
                    >::default(),
                    bevy::render::extract_resource::ExtractResourcePlugin::<
                        edits::EditedMaterials,
                    >::default(),
                    phase::CachedPhasePlugin,
                ),
            )
            .add_systems(First, (clear_cuts, edits::clear, copyable_depth));
        let stats = CacheStats::default();
        app.insert_resource(stats.clone())
            .init_resource::<reload::ReloadedMaterials>()
            .init_resource::<edits::EditedMaterials>()
            .init_resource::<CacheCreation>();
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
            return;
        };
        render_app
            .init_resource::<reload::ReloadedMaterials>()
            .init_resource::<edits::EditedMaterials>()
            .init_resource::<CacheCreation>()
            .init_resource::<CachedVariants>()
            .init_resource::<pipelines::QueuedPipelines>()
            .init_resource::<defs::LibraryDefs>()
            .add_systems(bevy::render::ExtractSchedule, defs::extract_library_defs);
        view_cache::build(render_app, stats);
    }
}

/// The cached draws share the view's depth (so Bevy's other meshes hide
/// and are hidden by them), and the host copies what they leave in it into
/// the cache for the next frame's reprojection: the depth texture of a
/// caching camera is a copy source.
fn copyable_depth(mut cameras: Query<&mut Camera3d, With<ReprojectionCache>>) {
    use bevy::render::render_resource::TextureUsages;
    for mut camera in &mut cameras {
        let usages = TextureUsages::from(camera.depth_texture_usages);
        if !usages.contains(TextureUsages::COPY_SRC) {
            camera.depth_texture_usages = (usages | TextureUsages::COPY_SRC).into();
        }
    }
}

/// A cut is one frame's: it was extracted at the end of the frame it
/// was set in, and is cleared as the next begins.
fn clear_cuts(mut caches: Query<&mut ReprojectionCache>) {
    for mut cache in &mut caches {
        if cache.cut {
            cache.cut = false;
        }
    }
}
