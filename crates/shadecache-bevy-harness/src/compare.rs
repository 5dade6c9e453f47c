//! Each frame drawn through the cache and as Bevy draws it, compared.

use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

use bevy::app::AppExit;
use bevy::camera::visibility::RenderLayers;
use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use shadecache_bevy::{CacheMode, CachedMaterial, GovernorReadout, ReprojectionCache};

use crate::scene::{self, FrameCount};
use crate::{headless_app, run_to_exit, target_image, Deadline};

/// What a comparison run does.
#[derive(Clone, Debug)]
pub struct Headless {
    /// The images' side, in pixels.
    pub size: u32,
    /// Frames compared, after Bevy's pipelines are ready.
    pub frames: u32,
    /// The cache's refresh period, in place of the plan's.
    pub refresh_period: Option<u32>,
    /// Degrees the camera moves a frame.
    pub step_degrees: f32,
    /// After `resize.0` compared frames, both images change to `resize.1`
    /// pixels a side, and `frames` more are compared.
    pub resize: Option<(u32, u32)>,
    /// After this many compared frames, the caching camera marks a cut
    /// (it moves on smoothly: only the cut says to forget last frame), and
    /// `frames` more are compared.
    pub cut_after: Option<u32>,
    /// Both cameras with 4× MSAA, which a cache cannot do.
    pub msaa: bool,
    /// A box with Bevy's `StandardMaterial` marked for the cache too,
    /// which no variant was made from.
    pub foreign_material: bool,
    /// The stone meshes too, a second cached material with its own
    /// variant.
    pub stone: bool,
    /// A lit box in Bevy's own `StandardMaterial`, marked for the cache,
    /// and the plugin for it with Bevy PBR's variant.
    pub standard_material: bool,
    /// A lit sphere in `scene::RimMaterial` (Bevy's `ExtendedMaterial`),
    /// marked for the cache, and the plugin for it.
    pub rim: bool,
    /// The lava meshes left unmarked: Bevy draws them (the cache draws
    /// only the other cached meshes).
    pub lava_uncached: bool,
    /// The game's props in `StandardMaterial` (a floor, a pillar, a crate,
    /// a glass pane, a point light: `scene::spawn_props`), marked for the
    /// cache where `standard_material`.
    pub props: bool,
    /// One more lava mesh, with vertex colours: another vertex layout
    /// than the others' in the same view.
    pub coloured_mesh: bool,
    /// One more lava mesh, a quad turned away from the camera, its
    /// material double-sided through the material's `specialize`.
    pub double_sided: bool,
    /// Meshes Bevy draws itself beside the cached ones, in both views.
    pub other_meshes: OtherMeshes,
    /// Both cameras draw into the right half of their image (a split
    /// screen's viewport, away from the target's corner).
    pub half_viewport: bool,
    /// Both cameras with Bevy's depth prepass (`DepthPrepass`, which TAA
    /// and SSAO need): the view's depth holds the cached meshes' own
    /// before their passes run.
    pub depth_prepass: bool,
    /// Both cameras with Bevy's TAA (`TemporalAntiAliasing`, which jitters
    /// the projection every frame and adds the depth and motion-vector
    /// prepasses).
    pub taa: bool,
    /// One more lava mesh marked for the cache that the variant's passes
    /// cannot draw as Bevy does, which the plugin leaves to Bevy.
    pub left_to_bevy: Option<LeftToBevy>,
    /// After this many compared frames, the caching camera switches its
    /// cache off (Bevy draws the meshes again), and `frames` more are
    /// compared.
    pub switch_off_after: Option<u32>,
    /// After this many compared frames (more than `switch_off_after`),
    /// the cache is switched on again.
    pub switch_on_after: Option<u32>,
    /// After this many compared frames, the lava's shader asset changes
    /// (as a hot reload changes it), and `frames` more are compared.
    pub reload_shader_after: Option<u32>,
    /// After this many compared frames, the `StandardMaterial`s are edited
    /// as `material_edit` says (as a game recolours a mesh), and `frames`
    /// more are compared.
    pub edit_standard_material_after: Option<u32>,
    /// What the edit of `edit_standard_material_after` does.
    pub material_edit: MaterialEdit,
    /// Both cameras draw in linear HDR (`Hdr`, no tonemapping) into
    /// `rgba16float` images read back as they are, and the frames compare
    /// as `shadecache profile` compares them: PSNR over RGB in linear float,
    /// peak 1, the whole frame (its `psnr_frame`). Otherwise the images are
    /// `rgba8unorm-srgb`, as a game displays them, compared as stored.
    pub linear: bool,
    /// Caches made on Bevy's async compute pool, as in a game (Bevy draws
    /// the meshes until each is ready), instead of in the frame.
    pub async_cache: bool,
    /// The caching camera's `ReprojectionCache::mode`.
    pub mode: CacheMode,
    /// A third camera on the same path draws which material covers each
    /// pixel (`Masks`), and each frame's error is measured over each
    /// material's pixels too (`Compared::psnr_of`).
    pub masks: bool,
}

/// How a run edits the `StandardMaterial`s.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum MaterialEdit {
    /// Every `StandardMaterial`'s base colour changes.
    #[default]
    EveryColour,
    /// The base colour changes of the `StandardMaterial`s no mesh marked
    /// for the cache binds.
    UncachedColours,
    /// Each marked mesh with a `StandardMaterial` is given a new asset, of
    /// another colour (as a game highlights a selected mesh).
    SwapMarked,
}

/// Meshes Bevy draws with its own `StandardMaterial` (unlit) beside the
/// cached lava, for the tests of the depth they share.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum OtherMeshes {
    /// The lava alone.
    #[default]
    None,
    /// An opaque box between the camera and the lava sphere.
    OpaqueInFront,
    /// A translucent pane behind the lava sphere: the transparent pass,
    /// after the cached one, must find the sphere's depth.
    TranslucentBehind,
    /// A translucent pane before the lava sphere, blended over it.
    TranslucentInFront,
    /// All three, and a floor the sphere sinks into.
    All,
}

/// What makes a lava mesh one the plugin leaves to Bevy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LeftToBevy {
    /// Its material blends (`AlphaMode::Blend`).
    AlphaBlend,
    /// It has a lightmap.
    Lightmapped,
    /// It has vertex colours, and the lava's cache lacks its build for
    /// them: Bevy composes its pipeline with `VERTEX_COLORS`, and the
    /// variant was composed without.
    ComposedOtherwise,
}

/// One compared frame: the cached image against Bevy's.
#[derive(Clone, Debug)]
pub struct Compared {
    /// The images' side.
    pub size: u32,
    /// PSNR of the cached image against Bevy's over RGB, the whole frame,
    /// in dB (∞ when equal): of the stored sRGB values, or with `linear`
    /// of the linear ones.
    pub psnr: f64,
    /// The largest difference of a channel, out of 1.
    pub max_error: f64,
    /// Pixels of lava in Bevy's image (red above green and blue).
    pub lava_pixels: usize,
    /// The frame (of the camera's path) the images came back in.
    pub frame: u32,
    /// With `masks`, the PSNR over the pixels each material covers in
    /// Bevy's frame, in the order of `Masked::ALL`: `None` where it covers
    /// none (or without `masks`).
    pub psnr_of: [Option<f64>; Masked::ALL.len()],
}

impl Compared {
    /// The PSNR over the pixels `material` covers, if it covers any.
    pub fn psnr_over(&self, material: Masked) -> Option<f64> {
        self.psnr_of[material as usize]
    }
}

/// The materials whose pixels a run with `masks` tells apart, each drawn
/// in its own colour by the mask camera (every other opaque mesh in black,
/// so that it hides them as in Bevy's frame; blended ones not at all, so
/// a material seen through the glass pane counts as seen).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Masked {
    /// `scene::LavaMaterial`'s meshes: red.
    Lava,
    /// Opaque `StandardMaterial` meshes: green.
    StandardMaterial,
}

impl Masked {
    pub const ALL: [Masked; 2] = [Masked::Lava, Masked::StandardMaterial];

    fn colour(self) -> Color {
        match self {
            Masked::Lava => Color::srgb(1.0, 0.0, 0.0),
            Masked::StandardMaterial => Color::srgb(0.0, 1.0, 0.0),
        }
    }

    /// Whether a pixel of the mask (RGBA out of 1) is this material's.
    fn covers(self, pixel: &[f32]) -> bool {
        let channel = match self {
            Masked::Lava => 0,
            Masked::StandardMaterial => 1,
        };
        pixel[channel] > 0.5
    }

    pub fn name(self) -> &'static str {
        match self {
            Masked::Lava => "the lava",
            Masked::StandardMaterial => "StandardMaterial",
        }
    }
}

/// A short run of the lava alone, cached every frame: 24 frames compared
/// at 128², the camera 0.5° a frame, the plan's Δn, nothing else drawn or
/// done.
impl Default for Headless {
    fn default() -> Headless {
        Headless {
            size: 128,
            frames: 24,
            refresh_period: None,
            step_degrees: 0.5,
            resize: None,
            cut_after: None,
            msaa: false,
            foreign_material: false,
            stone: false,
            standard_material: false,
            lava_uncached: false,
            rim: false,
            props: false,
            coloured_mesh: false,
            double_sided: false,
            other_meshes: OtherMeshes::None,
            left_to_bevy: None,
            half_viewport: false,
            depth_prepass: false,
            taa: false,
            switch_off_after: None,
            switch_on_after: None,
            reload_shader_after: None,
            edit_standard_material_after: None,
            material_edit: MaterialEdit::EveryColour,
            async_cache: false,
            masks: false,
            linear: false,
            mode: CacheMode::Always,
        }
    }
}

/// What a comparison run saw.
#[derive(Clone, Debug)]
pub struct HeadlessRun {
    /// The frames compared, in order.
    pub compared: Vec<Compared>,
    /// Frames the plugin drew through the cache (a view drawing two
    /// cached materials counts two a frame).
    pub frames_drawn: u64,
    /// Of those, the frames drawn through the stone's variant.
    pub stone_frames_drawn: u64,
    /// Of those, the frames drawn through Bevy PBR's variant.
    pub standard_frames_drawn: u64,
    /// Of those, the frames drawn through the rim material's variant.
    pub rim_frames_drawn: u64,
    /// Errors the plugin logged.
    pub errors: Vec<String>,
    /// The bytes of GPU memory the caches owned as the run ended.
    pub target_bytes: u64,
    /// The frame the cut was marked in, if one was.
    pub cut_frame: Option<u32>,
    /// The frame the cache was switched off in, if it was.
    pub switch_off_frame: Option<u32>,
    /// The frame the lava's shader changed in, if it did.
    pub reload_frame: Option<u32>,
    /// The frame the `StandardMaterial`s' colour changed in, if it did.
    pub edit_frame: Option<u32>,
    /// The lava's governor, where the mode is `Auto`.
    pub governor: Option<GovernorReadout>,
    /// The plugin's diagnostics (`render/shadecache/...`) with their
    /// latest values, as the run ended.
    pub diagnostics: Vec<(String, f64)>,
    /// The pipelines Bevy's `PipelineCache` made for the variants'
    /// passes (labelled `shadecache …`), as the run ended.
    pub variant_pipelines_in_bevys_cache: usize,
}

/// Which image a camera draws.
#[derive(Component, Clone, Copy, PartialEq, Eq)]
enum Role {
    Cached,
    Reference,
    /// Draws the mask twins (`MASK_LAYER`) only.
    Mask,
}

/// The render layer of the mask twins and the mask camera.
const MASK_LAYER: usize = 1;

/// The images read back, by the frame they arrived in.
#[derive(Resource, Default)]
struct Capture {
    cached: Vec<(u32, Vec<u8>)>,
    reference: Vec<(u32, Vec<u8>)>,
    mask: Vec<(u32, Vec<u8>)>,
    compared: Vec<Compared>,
    cut_frame: Option<u32>,
    switch_off_frame: Option<u32>,
    switch_on_frame: Option<u32>,
    reload_frame: Option<u32>,
    edit_frame: Option<u32>,
}

/// What comes back from the app (its runner takes it).
#[derive(Default)]
struct Outcome {
    compared: Vec<Compared>,
    cut_frame: Option<u32>,
    switch_off_frame: Option<u32>,
    reload_frame: Option<u32>,
    edit_frame: Option<u32>,
    diagnostics: Vec<(String, f64)>,
}

#[derive(Resource, Clone)]
struct Run(Headless, Arc<Mutex<Outcome>>);

/// Runs the game headless with two cameras on the same path, one caching
/// and one drawing as Bevy does, each into an image read back every frame;
/// returns the comparisons of the frames Bevy's own image has lava in (its
/// pipelines compile asynchronously, for the first frames).
pub fn run_headless(settings: Headless) -> HeadlessRun {
    // The runner takes the app: the comparisons come back through this.
    let results = Arc::new(Mutex::new(Outcome::default()));
    let materials = crate::scene::MaterialsPlugin {
        lava_vertex_colors: settings.left_to_bevy != Some(LeftToBevy::ComposedOtherwise),
        standard_material: settings.standard_material,
        rim: settings.rim,
    };
    let mut app = headless_app(false, settings.step_degrees, true, materials);
    // Bevy compiles its pipelines before the frame that needs them here;
    // the caches are made the same way, unless the run asks otherwise.
    app.insert_resource(shadecache_bevy::CacheCreation {
        synchronous: !settings.async_cache,
    })
    .insert_resource(Run(settings.clone(), results.clone()))
    .init_resource::<Capture>()
    .add_systems(Startup, setup)
    .add_systems(PostStartup, spawn_mask_twins)
    .add_systems(
        Update,
        (
            scene::move_cameras,
            compare,
            resize,
            cut_or_switch_off,
            finish,
        )
            .chain(),
    );
    let in_bevys_cache = VariantPipelines::default();
    if let Some(render_app) = app.get_sub_app_mut(bevy::render::RenderApp) {
        render_app
            .insert_resource(in_bevys_cache.clone())
            .add_systems(bevy::render::Render, count_variant_pipelines);
    }
    let (outcome, stats) = run_to_exit(app, &results);
    HeadlessRun {
        compared: outcome.compared,
        frames_drawn: stats.frames_drawn(),
        stone_frames_drawn: stats.frames_drawn_of::<scene::StoneMaterial>(),
        standard_frames_drawn: stats.frames_drawn_of::<StandardMaterial>(),
        rim_frames_drawn: stats.frames_drawn_of::<scene::RimMaterial>(),
        errors: stats.errors(),
        target_bytes: stats.target_bytes(),
        cut_frame: outcome.cut_frame,
        switch_off_frame: outcome.switch_off_frame,
        reload_frame: outcome.reload_frame,
        edit_frame: outcome.edit_frame,
        governor: stats.governor_of::<scene::LavaMaterial>(),
        diagnostics: outcome.diagnostics,
        variant_pipelines_in_bevys_cache: in_bevys_cache.0.load(Ordering::Relaxed),
    }
}

/// The pipelines Bevy's pipeline cache holds for the variants' passes,
/// counted in the render world each frame.
#[derive(Resource, Clone, Default)]
struct VariantPipelines(Arc<AtomicUsize>);

fn count_variant_pipelines(
    cache: Res<bevy::render::render_resource::PipelineCache>,
    count: Res<VariantPipelines>,
) {
    use bevy::render::render_resource::{CachedPipelineState, PipelineDescriptor};
    let made = cache
        .pipelines()
        .filter(|pipeline| matches!(pipeline.state, CachedPipelineState::Ok(_)))
        .filter(|pipeline| match &pipeline.descriptor {
            PipelineDescriptor::RenderPipelineDescriptor(descriptor) => descriptor
                .label
                .as_deref()
                .is_some_and(|label| label.starts_with("shadecache ")),
            _ => false,
        })
        .count();
    count.0.store(made, Ordering::Relaxed);
}

/// The assets of the materials only some runs draw.
#[derive(bevy::ecs::system::SystemParam)]
struct SomeRunsMaterials<'w> {
    stone: ResMut<'w, Assets<scene::StoneMaterial>>,
    /// Only where the rim material's plugin was added.
    rim: Option<ResMut<'w, Assets<scene::RimMaterial>>>,
}

fn setup(
    mut commands: Commands,
    run: Res<Run>,
    mut images: ResMut<Assets<Image>>,
    mut meshes: ResMut<Assets<Mesh>>,
    mut materials: ResMut<Assets<scene::LavaMaterial>>,
    mut standard: ResMut<Assets<StandardMaterial>>,
    mut some_runs: SomeRunsMaterials,
) {
    let settings = &run.0;
    scene::spawn_meshes(
        &mut commands,
        &mut meshes,
        &mut materials,
        !settings.lava_uncached,
    );
    if settings.stone {
        scene::spawn_stone(&mut commands, &mut meshes, &mut some_runs.stone);
    }
    if settings.double_sided {
        let lava = scene::LavaMaterial {
            double_sided: true,
            ..scene::LavaMaterial::new(AlphaMode::Opaque)
        };
        // The quad faces −z, away from the camera's start at +z: only its
        // back is seen.
        commands.spawn((
            Mesh3d(meshes.add(Rectangle::new(1.2, 0.8))),
            MeshMaterial3d(materials.add(lava)),
            Transform::from_xyz(0.1, 0.9, 0.9)
                .with_rotation(Quat::from_rotation_y(std::f32::consts::PI)),
            CachedMaterial,
        ));
    }
    if settings.coloured_mesh {
        let mut mesh = Mesh::from(Cuboid::new(0.5, 0.5, 0.5));
        let vertices = mesh.count_vertices();
        mesh.insert_attribute(
            Mesh::ATTRIBUTE_COLOR,
            vec![[1.0f32, 1.0, 1.0, 1.0]; vertices],
        );
        commands.spawn((
            Mesh3d(meshes.add(mesh)),
            MeshMaterial3d(materials.add(scene::LavaMaterial::new(AlphaMode::Opaque))),
            Transform::from_xyz(-0.3, 0.9, 0.8),
            CachedMaterial,
        ));
    }
    if settings.props {
        scene::spawn_props(
            &mut commands,
            &mut meshes,
            &mut standard,
            settings.standard_material,
        );
    }
    if let (true, Some(rim_materials)) = (settings.rim, some_runs.rim.as_mut()) {
        let rim = scene::RimMaterial {
            base: StandardMaterial {
                base_color: Color::srgb(0.3, 0.3, 0.35),
                perceptual_roughness: 0.5,
                ..default()
            },
            extension: scene::RimExtension {
                rim: scene::RimParams {
                    color: Vec4::new(0.2, 0.6, 1.0, 1.0),
                    shape: Vec4::new(3.0, 0.0, 0.0, 0.0),
                },
            },
        };
        commands.spawn((
            Mesh3d(meshes.add(Sphere::new(0.45).mesh().uv(32, 18))),
            MeshMaterial3d(rim_materials.add(rim)),
            Transform::from_xyz(0.3, 0.3, 1.1),
            CachedMaterial,
        ));
        commands.spawn(scene::point_light(400_000.0, Vec3::new(-0.6, 1.8, 2.4)));
    }
    // The lit box of the StandardMaterial test (the props have their own).
    if settings.standard_material && !settings.props {
        commands.spawn((
            Mesh3d(meshes.add(Cuboid::new(0.6, 0.6, 0.6))),
            MeshMaterial3d(standard.add(StandardMaterial {
                base_color: Color::srgb(0.2, 0.5, 0.9),
                perceptual_roughness: 0.4,
                ..default()
            })),
            Transform::from_xyz(-0.2, 0.2, 1.0).with_rotation(Quat::from_rotation_y(0.6)),
            CachedMaterial,
        ));
        // A light on it: its specular highlight moves with the camera.
        commands.spawn(scene::point_light(400_000.0, Vec3::new(0.6, 1.6, 2.2)));
    }
    if settings.foreign_material {
        commands.spawn((
            Mesh3d(meshes.add(Cuboid::new(0.6, 0.6, 0.6))),
            MeshMaterial3d(standard.add(StandardMaterial::from(Color::srgb(0.2, 0.5, 0.9)))),
            Transform::from_xyz(0.0, 1.0, 0.6),
            CachedMaterial,
        ));
    }
    if let Some(which) = settings.left_to_bevy {
        let alpha_mode = match which {
            LeftToBevy::AlphaBlend => AlphaMode::Blend,
            LeftToBevy::Lightmapped | LeftToBevy::ComposedOtherwise => AlphaMode::Opaque,
        };
        let mut sphere = Sphere::new(0.4).mesh().uv(24, 16);
        if which == LeftToBevy::ComposedOtherwise {
            let vertices = sphere.count_vertices();
            sphere.insert_attribute(
                Mesh::ATTRIBUTE_COLOR,
                vec![[1.0f32, 1.0, 1.0, 1.0]; vertices],
            );
        }
        let mut mesh = commands.spawn((
            Mesh3d(meshes.add(sphere)),
            MeshMaterial3d(materials.add(scene::LavaMaterial::new(alpha_mode))),
            Transform::from_xyz(0.2, 0.9, 0.8),
            CachedMaterial,
        ));
        if which == LeftToBevy::Lightmapped {
            let image = Image::new_fill(
                bevy::render::render_resource::Extent3d {
                    width: 4,
                    height: 4,
                    depth_or_array_layers: 1,
                },
                bevy::render::render_resource::TextureDimension::D2,
                &[128, 128, 128, 255],
                bevy::render::render_resource::TextureFormat::Rgba8UnormSrgb,
                bevy::asset::RenderAssetUsages::RENDER_WORLD,
            );
            mesh.insert(bevy::pbr::Lightmap {
                image: images.add(image),
                ..default()
            });
        }
    }
    spawn_other_meshes(
        settings.other_meshes,
        &mut commands,
        &mut meshes,
        &mut standard,
    );
    let mask = settings.masks.then_some(Role::Mask);
    for role in [Role::Cached, Role::Reference].into_iter().chain(mask) {
        let target = target_image(&mut images, settings.size, settings.linear);
        let mut camera =
            commands.spawn((scene::camera(target.clone(), settings.step_degrees), role));
        if role == Role::Mask {
            camera.insert(RenderLayers::layer(MASK_LAYER));
        }
        if settings.msaa {
            camera.insert(Msaa::Sample4);
        }
        if settings.depth_prepass {
            camera.insert(bevy::core_pipeline::prepass::DepthPrepass);
        }
        if settings.taa {
            camera.insert((
                bevy::anti_alias::taa::TemporalAntiAliasing::default(),
                Msaa::Off,
            ));
        }
        if settings.half_viewport {
            camera.insert(Camera {
                clear_color: ClearColorConfig::Custom(Color::BLACK),
                viewport: Some(bevy::camera::Viewport {
                    physical_position: UVec2::new(settings.size / 2, 0),
                    physical_size: UVec2::new(settings.size / 2, settings.size),
                    ..default()
                }),
                ..default()
            });
        }
        if settings.linear {
            camera.insert(bevy::camera::Hdr);
        }
        if role == Role::Cached {
            camera.insert(ReprojectionCache {
                refresh_period: settings.refresh_period,
                mode: settings.mode,
                ..default()
            });
        }
        spawn_readback(&mut commands, target, role);
    }
}

/// Spawns the meshes `which` asks for, seen from the start of the
/// camera's path (before the lava sphere at x = −1.2).
fn spawn_other_meshes(
    which: OtherMeshes,
    commands: &mut Commands,
    meshes: &mut Assets<Mesh>,
    standard: &mut Assets<StandardMaterial>,
) {
    let unlit = |color: Color, alpha_mode: AlphaMode| StandardMaterial {
        base_color: color,
        unlit: true,
        alpha_mode,
        ..default()
    };
    let all = which == OtherMeshes::All;
    let mut spawn = |mesh: Mesh, material: StandardMaterial, at: Vec3| {
        commands.spawn((
            Mesh3d(meshes.add(mesh)),
            MeshMaterial3d(standard.add(material)),
            Transform::from_translation(at),
        ));
    };
    if all || which == OtherMeshes::OpaqueInFront {
        spawn(
            Cuboid::new(0.6, 0.6, 0.6).into(),
            unlit(Color::srgb(0.2, 0.3, 0.9), AlphaMode::Opaque),
            Vec3::new(-0.9, 0.3, 1.6),
        );
    }
    let pane = |z: f32| (Cuboid::new(1.6, 1.4, 0.05).into(), Vec3::new(-1.2, 0.1, z));
    let glass = unlit(Color::srgba(0.6, 0.8, 1.0, 0.4), AlphaMode::Blend);
    if all || which == OtherMeshes::TranslucentBehind {
        let (mesh, at) = pane(-1.0);
        spawn(mesh, glass.clone(), at);
    }
    if all || which == OtherMeshes::TranslucentInFront {
        let (mesh, at) = pane(1.1);
        spawn(mesh, glass, at);
    }
    if all {
        spawn(
            Plane3d::default().mesh().size(8.0, 8.0).into(),
            unlit(Color::srgb(0.3, 0.6, 0.3), AlphaMode::Opaque),
            Vec3::new(0.0, -0.4, 0.0),
        );
    }
}

/// With `masks`, a twin of each opaque mesh on the mask camera's layer, in
/// its material's mask colour (`Masked`) or black, unlit: the mask camera
/// sees the scene's geometry as the other two do, and which material each
/// pixel shows. Twins cast no shadow, and the scene's meshes do not move,
/// so one twin each, made once, follows them.
#[allow(clippy::type_complexity)]
fn spawn_mask_twins(
    mut commands: Commands,
    run: Res<Run>,
    meshes: Query<(
        &Mesh3d,
        &Transform,
        Option<&MeshMaterial3d<scene::LavaMaterial>>,
        Option<&MeshMaterial3d<StandardMaterial>>,
    )>,
    mut standard: ResMut<Assets<StandardMaterial>>,
) {
    if !run.0.masks {
        return;
    }
    let unlit = |colour: Color| StandardMaterial {
        base_color: colour,
        unlit: true,
        cull_mode: None,
        double_sided: true,
        ..default()
    };
    let mut twins = Vec::new();
    for (mesh, transform, lava, pbr) in &meshes {
        let colour = if lava.is_some() {
            Masked::Lava.colour()
        } else if let Some(pbr) = pbr {
            match standard.get(&pbr.0).map(|m| m.alpha_mode) {
                Some(AlphaMode::Opaque) => Masked::StandardMaterial.colour(),
                // Blended: the material behind shows through.
                Some(_) | None => continue,
            }
        } else {
            Color::BLACK
        };
        twins.push((mesh.clone(), *transform, colour));
    }
    for (mesh, transform, colour) in twins {
        commands.spawn((
            mesh,
            MeshMaterial3d(standard.add(unlit(colour))),
            transform,
            RenderLayers::layer(MASK_LAYER),
            bevy::light::NotShadowCaster,
        ));
    }
}

/// Reads `target` back every frame into the capture of `role`.
fn spawn_readback(commands: &mut Commands, target: Handle<Image>, role: Role) {
    commands.spawn(Readback::texture(target)).observe(
        move |event: On<ReadbackComplete>, mut capture: ResMut<Capture>, frame: Res<FrameCount>| {
            let list = match role {
                Role::Cached => &mut capture.cached,
                Role::Reference => &mut capture.reference,
                Role::Mask => &mut capture.mask,
            };
            list.push((frame.0, event.data.clone()));
        },
    );
}

/// Pairs the images both cameras drew and compares them. The two
/// readbacks of a frame arrive in the same update: they are paired by it
/// (and by size, across a resize); one without its pair (one of the old
/// images', after a resize) is dropped.
fn compare(mut capture: ResMut<Capture>, frame: Res<FrameCount>, run: Res<Run>) {
    let mut pairs = Vec::new();
    for (frame, cached) in std::mem::take(&mut capture.cached) {
        let Some(at) = capture
            .reference
            .iter()
            .position(|(f, r)| *f == frame && r.len() == cached.len())
        else {
            continue;
        };
        let reference = capture.reference.remove(at).1;
        let mask = capture
            .mask
            .iter()
            .position(|(f, m)| *f == frame && m.len() == cached.len())
            .map(|at| capture.mask.remove(at).1);
        if run.0.masks && mask.is_none() {
            continue;
        }
        pairs.push((cached, reference, mask));
    }
    capture.reference.clear();
    capture.mask.clear();
    for (cached, reference, mask) in pairs {
        let linear = run.0.linear;
        let (cached, reference) = (channels(&cached, linear), channels(&reference, linear));
        // Frames count from the first with lava in it: Bevy compiles each
        // material's pipelines when it first meets it, and a frame drawn
        // before the lava's holds only the other meshes.
        let lava_pixels = lava_pixels(&reference);
        if lava_pixels == 0 {
            continue;
        }
        let (psnr, max_error) = image_error(&cached, &reference);
        let mask = mask.map(|mask| channels(&mask, linear));
        let psnr_of = Masked::ALL.map(|material| {
            let mask = mask.as_ref()?;
            image_error_where(&cached, &reference, |pixel| {
                material.covers(&mask[pixel * 4..pixel * 4 + 4])
            })
        });
        capture.compared.push(Compared {
            size: ((cached.len() / 4) as f64).sqrt() as u32,
            psnr,
            max_error,
            lava_pixels,
            frame: frame.0,
            psnr_of,
        });
    }
}

/// The `StandardMaterial`s of meshes marked for the cache.
type MarkedStandard<'w, 's> =
    Query<'w, 's, &'static mut MeshMaterial3d<StandardMaterial>, With<CachedMaterial>>;

/// Once `cut_after` frames are compared, marks a cut on the caching
/// camera, once; once `switch_off_after` are, switches its cache off;
/// once `reload_shader_after` are, changes the lava's shader asset (its
/// source as it was: Bevy sees a change, as from a hot reload); once
/// `edit_standard_material_after` are, edits the `StandardMaterial`s as
/// `material_edit` says.
fn cut_or_switch_off(
    run: Res<Run>,
    frame: Res<FrameCount>,
    mut capture: ResMut<Capture>,
    mut caches: Query<&mut ReprojectionCache>,
    server: Res<AssetServer>,
    mut shaders: ResMut<Assets<bevy::shader::Shader>>,
    // The materials to edit, and those of meshes marked for the cache.
    (mut standard, mut marked): (ResMut<Assets<StandardMaterial>>, MarkedStandard),
) {
    let compared = capture.compared.len() as u32;
    let due = |after: Option<u32>, done: Option<u32>| {
        done.is_none() && after.is_some_and(|after| compared >= after)
    };
    if due(run.0.cut_after, capture.cut_frame) {
        for mut cache in &mut caches {
            cache.cut();
        }
        capture.cut_frame = Some(frame.0);
    }
    let switched_off = capture.switch_off_frame.is_some();
    if switched_off && due(run.0.switch_on_after, capture.switch_on_frame) {
        for mut cache in &mut caches {
            cache.enabled = true;
        }
        capture.switch_on_frame = Some(frame.0);
    }
    if due(run.0.switch_off_after, capture.switch_off_frame) {
        for mut cache in &mut caches {
            cache.enabled = false;
        }
        capture.switch_off_frame = Some(frame.0);
    }
    if due(run.0.reload_shader_after, capture.reload_frame) {
        let lava = server.load::<bevy::shader::Shader>("lava.wesl");
        // Borrowed mutably, the asset is marked modified.
        if let Some(mut shader) = shaders.get_mut(&lava) {
            let _changed: &mut bevy::shader::Shader = &mut shader;
            capture.reload_frame = Some(frame.0);
        }
    }
    if due(run.0.edit_standard_material_after, capture.edit_frame) {
        let colour = Color::srgb(0.2, 0.35, 0.9);
        match run.0.material_edit {
            MaterialEdit::EveryColour | MaterialEdit::UncachedColours => {
                let kept: Vec<AssetId<StandardMaterial>> =
                    if run.0.material_edit == MaterialEdit::UncachedColours {
                        marked.iter().map(|m| m.id()).collect()
                    } else {
                        Vec::new()
                    };
                let ids: Vec<AssetId<StandardMaterial>> =
                    standard.ids().filter(|id| !kept.contains(id)).collect();
                for id in ids {
                    if let Some(mut material) = standard.get_mut(id) {
                        material.base_color = colour;
                    }
                }
            }
            MaterialEdit::SwapMarked => {
                for mut material in &mut marked {
                    if let Some(old) = standard.get(&material.0).cloned() {
                        material.0 = standard.add(StandardMaterial {
                            base_color: colour,
                            ..old
                        });
                    }
                }
            }
        }
        capture.edit_frame = Some(frame.0);
    }
}

/// Once `resize.0` frames are compared, gives both cameras new images of
/// the new size, read back in place of the old.
fn resize(
    mut commands: Commands,
    run: Res<Run>,
    capture: Res<Capture>,
    mut images: ResMut<Assets<Image>>,
    cameras: Query<(Entity, &Role)>,
    readbacks: Query<Entity, With<Readback>>,
    mut done: Local<bool>,
) {
    let Some((after, size)) = run.0.resize else {
        return;
    };
    if *done || (capture.compared.len() as u32) < after {
        return;
    }
    *done = true;
    for readback in &readbacks {
        commands.entity(readback).despawn();
    }
    for (camera, role) in &cameras {
        let target = target_image(&mut images, size, run.0.linear);
        commands
            .entity(camera)
            .insert(RenderTarget::Image(target.clone().into()));
        spawn_readback(&mut commands, target, *role);
    }
}

/// Ends the run once enough frames are compared (or at the deadline).
fn finish(
    run: Res<Run>,
    capture: Res<Capture>,
    deadline: Res<Deadline>,
    store: Option<Res<bevy::diagnostic::DiagnosticsStore>>,
    mut exit: MessageWriter<AppExit>,
) {
    let settings = &run.0;
    let wanted = settings.frames
        + settings.resize.map_or(0, |(after, _)| after)
        + settings.cut_after.unwrap_or(0)
        + settings.switch_off_after.unwrap_or(0)
        + settings.switch_on_after.unwrap_or(0)
        + settings.reload_shader_after.unwrap_or(0)
        + settings.edit_standard_material_after.unwrap_or(0);
    if capture.compared.len() as u32 >= wanted || deadline.passed() {
        *run.1.lock().unwrap_or_else(|p| p.into_inner()) = Outcome {
            compared: capture.compared.clone(),
            cut_frame: capture.cut_frame,
            switch_off_frame: capture.switch_off_frame,
            reload_frame: capture.reload_frame,
            edit_frame: capture.edit_frame,
            diagnostics: store
                .iter()
                .flat_map(|store| store.iter())
                .filter(|d| d.path().as_str().starts_with("render/shadecache/"))
                .filter_map(|d| Some((d.path().to_string(), d.value()?)))
                .collect(),
        };
        exit.write(AppExit::Success);
    }
}

/// Pixels of lava in an RGBA image: red above green and blue (its crust
/// and glow are; the clear colour and the other meshes of these scenes,
/// green, blue and a pale pane, are not).
pub(crate) fn lava_pixels(data: &[f32]) -> usize {
    data.chunks(4)
        .filter(|p| p[0] > p[1] && p[0] > p[2])
        .count()
}

/// The channels of an image read back, RGBA, out of 1: an `rgba16float`
/// image's (`linear`) decoded, an RGBA8 one's as stored.
pub(crate) fn channels(data: &[u8], linear: bool) -> Vec<f32> {
    if linear {
        data.chunks_exact(2)
            .map(|b| half::f16::from_le_bytes([b[0], b[1]]).to_f32())
            .collect()
    } else {
        data.iter().map(|&v| f32::from(v) / 255.0).collect()
    }
}

/// PSNR (dB, peak 1) and largest channel difference (out of 1) of two RGBA
/// images, over their colour channels.
pub fn image_error(a: &[f32], b: &[f32]) -> (f64, f64) {
    let (squared, count, max) = squared_error(a, b, |_| true);
    (psnr(squared, count), max)
}

/// The PSNR (dB, peak 1) of two RGBA images over the colour channels of
/// the pixels (by index) `within` keeps; `None` where it keeps none.
pub fn image_error_where(a: &[f32], b: &[f32], within: impl Fn(usize) -> bool) -> Option<f64> {
    let (squared, count, _) = squared_error(a, b, within);
    (count > 0).then(|| psnr(squared, count))
}

/// The summed squared difference over the colour channels of the pixels
/// `within` keeps, how many channels that is, and the largest difference.
fn squared_error(a: &[f32], b: &[f32], within: impl Fn(usize) -> bool) -> (f64, usize, f64) {
    let mut squared = 0.0f64;
    let mut max = 0.0f64;
    let mut count = 0usize;
    for (pixel, (pa, pb)) in a.chunks(4).zip(b.chunks(4)).enumerate() {
        if !within(pixel) {
            continue;
        }
        for c in 0..3 {
            let d = f64::from((pa[c] - pb[c]).abs());
            max = max.max(d);
            squared += d * d;
            count += 1;
        }
    }
    (squared, count, max)
}

fn psnr(squared: f64, count: usize) -> f64 {
    let mse = squared / count.max(1) as f64;
    if mse == 0.0 {
        f64::INFINITY
    } else {
        10.0 * (1.0 / mse).log10()
    }
}
