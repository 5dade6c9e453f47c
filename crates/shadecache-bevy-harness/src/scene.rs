//! The scene: the lava and stone materials, their meshes, the camera's
//! path.

use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::{DebandDither, Tonemapping};
use bevy::prelude::*;
use bevy::render::render_resource::{AsBindGroup, ShaderType};
use bevy::shader::ShaderRef;
use shadecache_bevy::{CachedMaterial, CachedVariant, ShadecachePlugin};

/// Every variant the build script wrote, by shader, node and variant.
mod built {
    shadecache_bevy::include_variants!();
}

/// The one-pass variant of `assets/lava.wesl`, as the build script made
/// it (of the node the build chose: no id is typed here).
pub fn lava_variant() -> CachedVariant {
    variant(built::lava::one_pass::PLAN, built::lava::one_pass::SHADERS)
}

/// The same variant, built with the defs Bevy composes the lava with for
/// meshes with vertex colours.
pub fn lava_vertex_colors_variant() -> CachedVariant {
    variant(
        built::lava_vertex_colors::one_pass::PLAN,
        built::lava_vertex_colors::one_pass::SHADERS,
    )
}

/// The one-pass variant of `assets/stone.wesl`, of the node its analysis
/// ranks first.
pub fn stone_variant() -> CachedVariant {
    variant(
        built::stone::one_pass::PLAN,
        built::stone::one_pass::SHADERS,
    )
}

fn variant(plan: &str, shaders: &[(&str, &str)]) -> CachedVariant {
    CachedVariant::new(plan, shaders.iter().copied())
        .unwrap_or_else(|err| panic!("the build script's variant does not load: {err}"))
}

/// The two-pass variant of Bevy's own `StandardMaterial` shader
/// (bevy_pbr's `render/pbr.wesl`), of the node its analysis ranks first.
pub fn standard_material_variant() -> CachedVariant {
    variant(
        built::standard_material::two_pass::PLAN,
        built::standard_material::two_pass::SHADERS,
    )
}

/// The two-pass variant of `assets/rim.wesl`, the extension of
/// [`RimMaterial`].
pub fn rim_variant() -> CachedVariant {
    variant(built::rim::two_pass::PLAN, built::rim::two_pass::SHADERS)
}

/// Bevy's `StandardMaterial` extended with a rim light of its own.
pub type RimMaterial = bevy::pbr::ExtendedMaterial<StandardMaterial, RimExtension>;

/// The rim light `assets/rim.wesl` adds to Bevy's PBR.
#[derive(Asset, TypePath, AsBindGroup, Clone, Debug)]
pub struct RimExtension {
    /// `rim` in the shader: its colour, and its exponent in `shape.x`.
    #[uniform(100)]
    pub rim: RimParams,
}

/// The rim's uniform.
#[derive(Clone, Copy, Debug, ShaderType)]
pub struct RimParams {
    pub color: Vec4,
    pub shape: Vec4,
}

impl bevy::pbr::MaterialExtension for RimExtension {
    fn fragment_shader() -> ShaderRef {
        "rim.wesl".into()
    }
}

/// Bevy's materials of the game and a cache for each: the lava (its
/// variant built for Bevy's primitive shapes and for meshes with vertex
/// colours) and the stone, each with its variant.
pub struct MaterialsPlugin {
    /// Whether the lava's cache has its build for meshes with vertex
    /// colours (a test leaves it out to see such a mesh left to Bevy).
    pub lava_vertex_colors: bool,
    /// Whether Bevy's `StandardMaterial` is cached too.
    pub standard_material: bool,
    /// Whether [`RimMaterial`], an `ExtendedMaterial` of Bevy's, is drawn
    /// and cached.
    pub rim: bool,
}

impl Default for MaterialsPlugin {
    fn default() -> Self {
        MaterialsPlugin {
            lava_vertex_colors: true,
            standard_material: true,
            rim: false,
        }
    }
}

impl Plugin for MaterialsPlugin {
    fn build(&self, app: &mut App) {
        let mut lava = ShadecachePlugin::<LavaMaterial>::new(lava_variant());
        if self.lava_vertex_colors {
            lava = lava.and(lava_vertex_colors_variant());
        }
        app.add_plugins((
            MaterialPlugin::<LavaMaterial>::default(),
            MaterialPlugin::<StoneMaterial>::default(),
            lava,
            ShadecachePlugin::<StoneMaterial>::new(stone_variant()),
        ));
        if self.standard_material {
            app.add_plugins(ShadecachePlugin::<StandardMaterial>::new(
                standard_material_variant(),
            ));
        }
        if self.rim {
            app.add_plugins((
                MaterialPlugin::<RimMaterial>::default(),
                ShadecachePlugin::<RimMaterial>::new(rim_variant()),
            ));
        }
    }
}

/// The material: Bevy draws it with `assets/lava.wesl`.
#[derive(Asset, TypePath, AsBindGroup, Clone, Debug)]
#[bind_group_data(LavaKey)]
pub struct LavaMaterial {
    /// Its uniform, `material` in the shader.
    #[uniform(0)]
    pub params: LavaParams,
    /// Opaque in the game; the tests blend one mesh to see it left to
    /// Bevy.
    pub alpha_mode: AlphaMode,
    /// Both faces drawn: the material's `specialize` turns culling off.
    pub double_sided: bool,
}

/// What the lava's pipeline is specialised on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LavaKey {
    double_sided: bool,
}

impl From<&LavaMaterial> for LavaKey {
    fn from(material: &LavaMaterial) -> Self {
        LavaKey {
            double_sided: material.double_sided,
        }
    }
}

/// `LavaMaterial` in the shader.
#[derive(ShaderType, Clone, Debug)]
pub struct LavaParams {
    /// The crust's colour.
    pub cool_color: Vec4,
    /// The glow's colour.
    pub hot_color: Vec4,
    /// x: how fast the glow flows; y: how far the light wraps around.
    pub flow: Vec4,
}

impl Material for LavaMaterial {
    fn fragment_shader() -> ShaderRef {
        "lava.wesl".into()
    }

    fn alpha_mode(&self) -> AlphaMode {
        self.alpha_mode
    }

    fn specialize(
        _pipeline: &bevy::pbr::MaterialPipeline,
        descriptor: &mut bevy::render::render_resource::RenderPipelineDescriptor,
        _layout: &bevy::mesh::MeshVertexBufferLayoutRef,
        key: bevy::pbr::MaterialPipelineKey<Self>,
    ) -> Result<(), bevy::render::render_resource::SpecializedMeshPipelineError> {
        if key.bind_group_data.double_sided {
            descriptor.primitive.cull_mode = None;
        }
        Ok(())
    }
}

impl LavaMaterial {
    /// The game's lava, drawn with `alpha_mode`.
    pub fn new(alpha_mode: AlphaMode) -> Self {
        LavaMaterial {
            params: LavaParams {
                cool_color: Vec4::new(0.25, 0.12, 0.08, 1.0),
                hot_color: Vec4::new(1.0, 0.35, 0.05, 1.0),
                flow: Vec4::new(0.6, 0.3, 0.0, 0.0),
            },
            alpha_mode,
            double_sided: false,
        }
    }
}

/// The second cached material: veined stone, drawn with
/// `assets/stone.wesl`.
#[derive(Asset, TypePath, AsBindGroup, Clone, Debug)]
pub struct StoneMaterial {
    /// Its uniform, `material` in the shader.
    #[uniform(0)]
    pub params: StoneParams,
}

/// `StoneMaterial` in the shader.
#[derive(ShaderType, Clone, Debug)]
pub struct StoneParams {
    /// The stone's dark colour.
    pub dark: Vec4,
    /// Its veins' colour.
    pub pale: Vec4,
    /// x: the veins' frequency; y: how far they are stirred.
    pub veins: Vec4,
}

impl Material for StoneMaterial {
    fn fragment_shader() -> ShaderRef {
        "stone.wesl".into()
    }
}

impl Default for StoneMaterial {
    fn default() -> Self {
        StoneMaterial {
            params: StoneParams {
                dark: Vec4::new(0.18, 0.2, 0.22, 1.0),
                pale: Vec4::new(0.85, 0.84, 0.8, 1.0),
                veins: Vec4::new(1.5, 2.5, 0.0, 0.0),
            },
        }
    }
}

/// Places the stone meshes, marked for the cache: a plinth under the
/// lava sphere and a column behind the torus.
pub fn spawn_stone(
    commands: &mut Commands,
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<StoneMaterial>,
) {
    let stone = materials.add(StoneMaterial::default());
    let shapes = [
        (
            meshes.add(Cuboid::new(1.4, 0.5, 1.4)),
            Vec3::new(-1.2, -1.0, 0.0),
        ),
        (
            meshes.add(Cylinder::new(0.3, 2.2)),
            Vec3::new(1.6, 0.2, -1.2),
        ),
    ];
    for (mesh, at) in shapes {
        commands.spawn((
            Mesh3d(mesh),
            MeshMaterial3d(stone.clone()),
            Transform::from_translation(at),
            CachedMaterial,
        ));
    }
}

/// Places the game's props in Bevy's own `StandardMaterial`, each marked
/// for the cache where `cached`: a floor the lava sphere rests on, a
/// pillar before the sphere and a crate before the torus (each hides part
/// of the lava as the camera turns), a point light over them, and a glass
/// pane before the torus, which blends and which Bevy draws in its
/// transparent pass over the cached meshes.
pub fn spawn_props(
    commands: &mut Commands,
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<StandardMaterial>,
    cached: bool,
) {
    let lit = |color: Color, roughness: f32| StandardMaterial {
        base_color: color,
        perceptual_roughness: roughness,
        ..default()
    };
    let props = [
        (
            meshes.add(Plane3d::default().mesh().size(9.0, 9.0)),
            lit(Color::srgb(0.35, 0.4, 0.3), 0.9),
            Transform::from_xyz(0.0, -0.8, 0.0),
        ),
        (
            meshes.add(Cylinder::new(0.22, 2.0)),
            lit(Color::srgb(0.6, 0.62, 0.66), 0.5),
            Transform::from_xyz(-0.5, 0.2, 1.3),
        ),
        (
            meshes.add(Cuboid::new(0.6, 0.6, 0.6)),
            lit(Color::srgb(0.2, 0.35, 0.8), 0.35),
            Transform::from_xyz(0.9, -0.5, 1.2).with_rotation(Quat::from_rotation_y(0.5)),
        ),
    ];
    for (mesh, material, transform) in props {
        let mut entity = commands.spawn((
            Mesh3d(mesh),
            MeshMaterial3d(materials.add(material)),
            transform,
        ));
        if cached {
            entity.insert(CachedMaterial);
        }
    }
    commands.spawn((
        Mesh3d(meshes.add(Cuboid::new(1.4, 1.0, 0.04))),
        MeshMaterial3d(materials.add(StandardMaterial {
            base_color: Color::srgba(0.6, 0.8, 1.0, 0.35),
            alpha_mode: AlphaMode::Blend,
            perceptual_roughness: 0.1,
            ..default()
        })),
        Transform::from_xyz(1.3, 0.0, 1.1),
    ));
    commands.spawn(point_light(600_000.0, Vec3::new(1.5, 2.5, 2.5)));
}

/// A point light of `intensity` lumens at `at`, reaching 12 units, with
/// no shadows (as Bevy's default).
pub fn point_light(intensity: f32, at: Vec3) -> impl Bundle {
    (
        PointLight {
            intensity,
            range: 12.0,
            ..default()
        },
        Transform::from_translation(at),
    )
}

/// Places the lava meshes: a sphere, a torus and a box, each marked for
/// the cache where `cached`.
pub fn spawn_meshes(
    commands: &mut Commands,
    meshes: &mut Assets<Mesh>,
    materials: &mut Assets<LavaMaterial>,
    cached: bool,
) {
    let lava = materials.add(LavaMaterial::new(AlphaMode::Opaque));
    let shapes = [
        (
            meshes.add(Sphere::new(0.8).mesh().uv(48, 32)),
            Vec3::new(-1.2, 0.0, 0.0),
        ),
        (meshes.add(Torus::new(0.35, 0.75)), Vec3::new(1.2, 0.0, 0.0)),
        (
            meshes.add(Cuboid::new(0.9, 0.9, 0.9)),
            Vec3::new(0.0, 0.0, -1.6),
        ),
    ];
    for (mesh, at) in shapes {
        let mut entity = commands.spawn((
            Mesh3d(mesh),
            MeshMaterial3d(lava.clone()),
            Transform::from_translation(at),
        ));
        if cached {
            entity.insert(CachedMaterial);
        }
    }
}

/// Where the camera is at frame `n`: on a circle around the meshes, a
/// fixed step a frame, so that runs are alike whatever their speed.
pub fn orbit(n: u32, step_degrees: f32) -> Transform {
    orbit_at(n as f32 * step_degrees)
}

/// The camera `degrees` along its circle around the meshes.
pub fn orbit_at(degrees: f32) -> Transform {
    let angle = degrees.to_radians();
    Transform::from_xyz(4.5 * angle.sin(), 1.6, 4.5 * angle.cos()).looking_at(Vec3::ZERO, Vec3::Y)
}

/// A camera on the path, drawing into `target`: single-sampled and
/// without post-processing, so its image is the material's own output (a
/// cache holds one value per pixel).
pub fn camera(target: Handle<Image>, step_degrees: f32) -> impl Bundle {
    (
        Camera3d::default(),
        Camera {
            clear_color: ClearColorConfig::Custom(Color::BLACK),
            ..default()
        },
        RenderTarget::Image(target.into()),
        Msaa::Off,
        Tonemapping::None,
        DebandDither::Disabled,
        orbit(0, step_degrees),
    )
}

/// The frame counter the camera's path follows.
#[derive(Resource, Default)]
pub struct FrameCount(pub u32);

/// Moves every 3D camera one step along the path.
pub fn move_cameras(
    mut frame: ResMut<FrameCount>,
    step: Res<Step>,
    mut cameras: Query<&mut Transform, With<Camera3d>>,
) {
    frame.0 += 1;
    for mut transform in &mut cameras {
        *transform = orbit(frame.0, step.0);
    }
}

/// Degrees the camera moves a frame.
#[derive(Resource, Clone, Copy)]
pub struct Step(pub f32);
