//! Scenes: what a profile renders — meshes, a camera path, object
//! animation, a light, values for the shader's uniforms, and the effects
//! the scene exercises. Scenes are TOML files (`corpus/scenes/`, schema in
//! `docs/scene-toml.md`).
//!
//! Only the **declared effects** are simulated: a scene that does not list
//! `light-motion` keeps its light where it is, whatever motion it
//! describes. So a profile's misses and refreshes come from the effects the
//! scene says it has.
//!
//! [`Scene::frame`] gives the state of frame n (camera, light, time, each
//! object's transform); `uniforms` turns it into the bytes of the
//! shader's uniform buffers, filling the well-known members
//! (`clip_from_world`, `world_from_local`, `camera_position`,
//! `light_position`, `time`, ...) from the simulation and every other member
//! from the scene's `[uniforms]`. A member the scene does not provide is an
//! error naming it: nothing is silently zero.
//!
//! An object may be drawn as `instances` in one instanced draw call
//! (`instances`); the shader's read-only storage buffers then hold one
//! element per instance, filled by `storage` from each instance's
//! transform and the scene's `[storage.<binding>]` tables. `layout`
//! writes values at naga's offsets for both kinds of buffer.

#![warn(missing_docs)]

pub mod bounds;
pub mod init;
pub(crate) mod instance_inputs;
pub(crate) mod instances;
pub(crate) mod layout;
pub(crate) mod mesh;
pub(crate) mod roles;
pub(crate) mod shadow;
pub(crate) mod skin;
pub(crate) mod storage;
pub(crate) mod textures;
pub(crate) mod uniforms;

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::Path;
use std::sync::Arc;

use glam::{Mat4, Vec3};
use serde::Deserialize;

use crate::diagnostic::{Diagnostic, Error, SourceFile};
pub use crate::plan::DepthConvention;
pub use instances::Instances;
pub use mesh::{Mesh, MeshSource};

/// A `[storage.<binding>]` table: values of the elements' members by name.
pub type StorageTable = BTreeMap<String, toml::Spanned<toml::Value>>;

/// What moves in a scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Effect {
    /// The camera orbits, pans, zooms or rolls.
    CameraMotion,
    /// Objects turn and move (and instances orbit and spin).
    ObjectMotion,
    /// The light orbits.
    LightMotion,
    /// Time-varying parameters: the `time` uniform advances.
    Time,
    /// Objects moving past each other uncover what was hidden (declared by
    /// scenes built for it; simulated through `object-motion`).
    Disocclusion,
    /// Vertices move in the object's own space (a ripple along the
    /// normals): a motion the previous-frame uniforms cannot describe.
    Deformation,
}

/// Uniform values from a frame on (`[[uniform_changes]]`).
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct UniformChange {
    /// The first run frame (warm-up included) with these values.
    pub frame: u32,
    /// Values of uniform members by name, each set in `[uniforms]` too.
    pub uniforms: BTreeMap<String, toml::Value>,
}

/// A scene file.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// What the scene is and how it moves, in words.
    #[serde(default)]
    pub description: String,
    /// Frame size in pixels.
    #[serde(default = "default_size")]
    pub size: [u32; 2],
    /// Frames measured.
    #[serde(default = "default_frames")]
    pub frames: u32,
    /// Frames rendered first and not measured.
    #[serde(default = "default_warmup")]
    pub warmup: u32,
    /// The frame of the scene's motion a run starts at: its first frame
    /// (warm-up included) shows the camera, objects, light and time as
    /// they are `start_frame` frames into the motion, with a cold cache.
    /// What an application's cache sees when it starts (or is reset)
    /// partway through its motion.
    #[serde(default)]
    pub start_frame: u32,
    /// What moves: only the effects declared are simulated.
    #[serde(default)]
    pub effects: Vec<Effect>,
    /// The camera.
    #[serde(default)]
    pub camera: Camera,
    /// The light.
    #[serde(default)]
    pub light: Light,
    /// What is drawn, each object one draw.
    #[serde(default)]
    pub objects: Vec<Object>,
    /// The shader's own names for what the simulation animates:
    /// `"buffer.member"` (or a plain uniform's name) to a role of
    /// `layout::ROLES`, e.g. `"camera.view_proj" = "clip_from_world"`.
    /// Members named like a role (`clip_from_world`, ...) take it without
    /// one.
    #[serde(default)]
    pub roles: BTreeMap<String, toml::Spanned<String>>,
    /// Values of uniform members by name.
    #[serde(default)]
    pub uniforms: BTreeMap<String, toml::Value>,
    /// Uniform values that change partway through the run, in frame order:
    /// from its `frame` on (frames of the motion: run frames, warm-up
    /// included, after `start_frame`), each change's values replace
    /// `[uniforms]`' (a payload whose weight changes, as a governor must
    /// follow).
    #[serde(default)]
    pub uniform_changes: Vec<UniformChange>,
    /// Textures by binding name.
    #[serde(default)]
    pub textures: BTreeMap<String, textures::TextureSource>,
    /// Read-only storage buffers by binding name: values of their
    /// elements' members, for every object (an object's own `storage`
    /// table sets members for it alone).
    #[serde(default)]
    pub storage: BTreeMap<String, toml::Spanned<StorageTable>>,
    /// Constants for float vertex inputs the mesh has nothing for (a text
    /// renderer's per-glyph `depth`), by the input's name: one value, or
    /// one per component.
    #[serde(default)]
    pub vertex_inputs: BTreeMap<String, VertexConstant>,
    /// Seconds per frame for the `time` uniform.
    #[serde(default = "default_frame_time")]
    pub seconds_per_frame: f32,
    /// Cull back faces (the procedural meshes face outwards,
    /// counter-clockwise). Off for open or two-sided geometry.
    #[serde(default = "default_true")]
    pub cull_back_faces: bool,
    /// The file the scene was read from, for errors found later (values
    /// checked against the shader).
    #[serde(skip)]
    pub file: Option<Arc<SourceFile>>,
    /// What the scene sets to a neutral value because the shader binds it
    /// and nothing says what it is (the default scene's, [`init`]).
    #[serde(skip)]
    pub defaulted: Vec<String>,
}

fn default_true() -> bool {
    true
}

fn default_size() -> [u32; 2] {
    [256, 256]
}
fn default_frames() -> u32 {
    32
}
fn default_warmup() -> u32 {
    4
}
fn default_frame_time() -> f32 {
    1.0 / 60.0
}

#[derive(Clone, Debug, Deserialize)]
/// The camera: where it is, where it looks, how it projects and moves.
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Where it is.
    #[serde(default = "default_eye")]
    pub eye: [f32; 3],
    /// What it looks at.
    #[serde(default)]
    pub target: [f32; 3],
    /// The vertical field of view.
    #[serde(default = "default_fov")]
    pub fov_degrees: f32,
    /// The near plane's distance.
    #[serde(default = "default_near")]
    pub near: f32,
    /// A distance, or `"infinity"` for an infinite far plane.
    #[serde(default = "default_far")]
    pub far: Far,
    /// `standard` (near at depth 0, far at 1) or `reversed` (near at 1,
    /// far at 0). The plans follow it: depth compares, clear value, and
    /// the far-plane depth the cache's depth test is relative to.
    #[serde(default)]
    pub depth: DepthConvention,
    /// With `camera-motion`: orbit about the target's vertical axis.
    #[serde(default)]
    pub orbit_degrees_per_frame: f32,
    /// With `camera-motion`: translate the eye (and target) every frame.
    #[serde(default)]
    pub pan_per_frame: [f32; 3],
    /// With `camera-motion`: roll about the line of sight, counter-clockwise
    /// as seen by the camera.
    #[serde(default)]
    pub roll_degrees_per_frame: f32,
    /// With `camera-motion`: magnify by this factor every frame (the tangent
    /// of half the field of view divided by it); 1 keeps the field of view,
    /// above 1 zooms in, below 1 out.
    #[serde(default = "no_zoom")]
    pub zoom_per_frame: f32,
    /// Camera cuts, in frame order: from each cut's `frame` on (frames of
    /// the motion, as `[[uniform_changes]]`'), the camera is in a new shot,
    /// with the cut's eye and target, its motion starting afresh from
    /// there. What reused frames across a cut would show is the old shot:
    /// every stage that reuses starts again ([`FrameState::shot`]).
    #[serde(default)]
    pub cuts: Vec<Cut>,
}

/// A camera cut: a new shot from `frame` on.
#[derive(Clone, Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cut {
    /// The motion frame the new shot starts at.
    pub frame: u32,
    /// The eye in the new shot; the camera's own `eye` when not given.
    pub eye: Option<[f32; 3]>,
    /// What it looks at; the camera's own `target` when not given.
    pub target: Option<[f32; 3]>,
}

impl Default for Camera {
    fn default() -> Self {
        Camera {
            eye: default_eye(),
            target: [0.0; 3],
            fov_degrees: default_fov(),
            near: default_near(),
            far: default_far(),
            depth: DepthConvention::Standard,
            orbit_degrees_per_frame: 0.0,
            pan_per_frame: [0.0; 3],
            roll_degrees_per_frame: 0.0,
            zoom_per_frame: no_zoom(),
            cuts: Vec::new(),
        }
    }
}

fn no_zoom() -> f32 {
    1.0
}

fn default_eye() -> [f32; 3] {
    [0.0, 0.5, 3.0]
}
fn default_fov() -> f32 {
    45.0
}
fn default_near() -> f32 {
    0.1
}
fn default_far() -> Far {
    Far::Distance(20.0)
}

/// Where the camera's far plane is.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Far {
    /// The far plane at this distance.
    Distance(f32),
    /// No far plane: depth tends to the far value as distance grows.
    Infinity,
}

impl<'de> Deserialize<'de> for Far {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Far, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Far;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a distance or \"infinity\"")
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> Result<Far, E> {
                Ok(Far::Distance(v as f32))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> Result<Far, E> {
                Ok(Far::Distance(v as f32))
            }
            fn visit_u64<E: serde::de::Error>(self, v: u64) -> Result<Far, E> {
                Ok(Far::Distance(v as f32))
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> Result<Far, E> {
                match v {
                    "infinity" => Ok(Far::Infinity),
                    _ => Err(E::invalid_value(serde::de::Unexpected::Str(v), &self)),
                }
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

impl Camera {
    /// The projection (right-handed, depth in [0, 1]) for the camera's
    /// near and far planes and depth convention.
    pub fn projection(&self, aspect: f32) -> Mat4 {
        self.projection_with_fov(self.fov_degrees.to_radians(), aspect)
    }

    /// The field of view (radians) after `frames` frames of zoom.
    pub fn fov_after(&self, frames: f32) -> f32 {
        let half = (self.fov_degrees.to_radians() * 0.5).tan() / self.zoom_per_frame.powf(frames);
        2.0 * half.atan()
    }

    fn projection_with_fov(&self, fov: f32, aspect: f32) -> Mat4 {
        match (self.depth, self.far) {
            (DepthConvention::Standard, Far::Distance(far)) => {
                Mat4::perspective_rh(fov, aspect, self.near, far)
            }
            (DepthConvention::Standard, Far::Infinity) => {
                Mat4::perspective_infinite_rh(fov, aspect, self.near)
            }
            // Swapping the planes maps near to 1 and far to 0: depth is
            // exactly 1 minus the standard one.
            (DepthConvention::Reversed, Far::Distance(far)) => {
                Mat4::perspective_rh(fov, aspect, far, self.near)
            }
            (DepthConvention::Reversed, Far::Infinity) => {
                Mat4::perspective_infinite_reverse_rh(fov, aspect, self.near)
            }
        }
    }
}

#[derive(Clone, Debug, Deserialize)]
/// The light: a point, which may orbit.
#[serde(deny_unknown_fields)]
pub struct Light {
    /// Where it is at frame 0.
    #[serde(default = "default_light")]
    pub position: [f32; 3],
    /// With `light-motion`: orbit about the vertical axis.
    #[serde(default)]
    pub orbit_degrees_per_frame: f32,
    /// With `light-motion`: frames the light stands still before it
    /// starts to orbit (a light switched on to move partway through, as
    /// a governor's error watch must notice).
    #[serde(default)]
    pub still_frames: u32,
}

impl Default for Light {
    fn default() -> Self {
        Light {
            position: default_light(),
            orbit_degrees_per_frame: 0.0,
            still_frames: 0,
        }
    }
}

fn default_light() -> [f32; 3] {
    [4.0, 5.0, 3.0]
}

#[derive(Clone, Debug, Deserialize)]
/// One object: a mesh, where it is and how it moves.
#[serde(deny_unknown_fields)]
pub struct Object {
    /// Its mesh.
    pub mesh: MeshSource,
    /// Where it is at frame 0.
    #[serde(default)]
    pub position: [f32; 3],
    /// Initial rotation, degrees about x, y, z.
    #[serde(default)]
    pub rotation_degrees: [f32; 3],
    /// Its uniform scale.
    #[serde(default = "default_scale")]
    pub scale: f32,
    /// With `object-motion`: degrees per frame about x, y, z.
    #[serde(default)]
    pub rotation_degrees_per_frame: [f32; 3],
    /// With `object-motion`: world units per frame.
    #[serde(default)]
    pub translation_per_frame: [f32; 3],
    /// With `deformation`: a ripple along the normals.
    #[serde(default)]
    pub deformation: Option<Deformation>,
    /// A chain of joints that bends the mesh on the GPU, as engines skin
    /// characters (bending with `deformation`).
    #[serde(default)]
    pub skin: Option<skin::Skin>,
    /// Draw the mesh this many times in one instanced draw call, placed
    /// and moved per instance.
    #[serde(default)]
    pub instances: Option<Instances>,
    /// This object's values of storage members by binding name, over the
    /// scene's `[storage]`.
    #[serde(default)]
    pub storage: BTreeMap<String, toml::Spanned<StorageTable>>,
    /// Whole-frame reuse (`interpolate`): draw this object at every
    /// displayed frame, depth-tested into the interpolated frames, and
    /// leave it out of the I-frames (seed 000 Fig. 4(d): thin, fast
    /// geometry no interpolation follows). The cache's runs draw it as
    /// any other.
    #[serde(default)]
    pub every_frame: bool,
}

impl Object {
    /// How many instances the object's draw call draws.
    pub fn instance_count(&self) -> u32 {
        self.instances.as_ref().map_or(1, |i| i.count)
    }
}

/// A ripple along the normals: each vertex moves by
/// `amplitude · sin(frequency · y + speed · frame)` along its normal.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Deformation {
    /// How far vertices move along their normals.
    pub amplitude: f32,
    /// The ripple's frequency along y.
    #[serde(default = "default_ripple_frequency")]
    pub frequency: f32,
    /// Radians per frame.
    #[serde(default = "default_ripple_speed")]
    pub speed: f32,
}

fn default_ripple_frequency() -> f32 {
    6.0
}
fn default_ripple_speed() -> f32 {
    0.1
}

fn default_scale() -> f32 {
    1.0
}

/// The simulated state of one frame.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameState {
    /// The camera's view-projection.
    pub clip_from_world: Mat4,
    /// The camera's projection and view, whose product is
    /// `clip_from_world`, for shaders that take them apart.
    pub clip_from_view: Mat4,
    /// The camera's view.
    pub view_from_world: Mat4,
    /// The eye.
    pub camera_position: Vec3,
    /// The light.
    pub light_position: Vec3,
    /// The light's view-projection, looking at the origin.
    pub light_clip_from_world: Mat4,
    /// Seconds since the first frame (with `time`).
    pub time: f32,
    /// The frame's size in pixels (the scene's, or the run's with
    /// [`Scene::frame_sized`]).
    pub resolution: glam::Vec2,
    /// Each object's `world_from_local`.
    pub objects: Vec<Mat4>,
    /// Each object's instances' transforms in the object's space (one
    /// identity for an object that is not instanced).
    pub instances: Vec<Vec<Mat4>>,
    /// Each object's joints' poses in its mesh's space (one identity for
    /// an object without a skin): a skinning matrix is the object's
    /// `world_from_local` times its joint's pose.
    pub joints: Vec<Vec<Mat4>>,
    /// The frame of the scene's motion it shows: the run frame (0-based,
    /// warm-up included) plus `start_frame`. `[[uniform_changes]]` are on
    /// this timeline, as the motion is.
    pub frame: u32,
    /// The camera's shot: how many of `[[camera.cuts]]` the motion has
    /// passed. Two frames of different shots have nothing to reuse
    /// between them ([`FrameState::cut`]).
    pub shot: u32,
    /// The frame before (`None` on the first frame, and within that state
    /// itself): what a `previous_` member holds, as engines keep last
    /// frame's transforms beside this frame's (Bevy's
    /// `previous_world_from_local`).
    pub previous: Option<Box<FrameState>>,
}

impl FrameState {
    /// The frame before, or this one on the first frame (as a twin holds
    /// this frame's contents on the first frame).
    pub fn before(&self) -> &FrameState {
        self.previous.as_deref().unwrap_or(self)
    }

    /// Whether a camera cut comes between the frame before and this one:
    /// the first frame of a new shot.
    pub fn cut(&self) -> bool {
        self.before().shot != self.shot
    }

    /// Object `object`'s instances' whole world transforms: its placement
    /// times each instance's within it.
    pub fn instance_worlds(&self, object: usize) -> Vec<Mat4> {
        self.instances[object]
            .iter()
            .map(|&instance| self.objects[object] * instance)
            .collect()
    }
}

/// A vertex input's constant: one value for every component, or one per
/// component.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum VertexConstant {
    /// One value for every component.
    Scalar(f32),
    /// One value per component.
    Vector(Vec<f32>),
}

impl VertexConstant {
    /// Four components: a scalar in each, a vector padded (w = 1).
    pub fn components(&self) -> [f32; 4] {
        match self {
            VertexConstant::Scalar(value) => [*value; 4],
            VertexConstant::Vector(values) => {
                let mut out = [0.0, 0.0, 0.0, 1.0];
                for (slot, value) in out.iter_mut().zip(values) {
                    *slot = *value;
                }
                out
            }
        }
    }
}

impl Scene {
    /// Reads and checks a scene file. Errors point into the file.
    pub fn load(path: &Path) -> Result<Scene, Error> {
        let file = Arc::new(crate::front::read_text(
            path,
            crate::front::TextKind::Scene,
        )?);
        Scene::parse(file)
    }

    /// The default scene for `shader` ([`init`]), drawn with the vertex
    /// entry point that pairs with fragment entry point `entry`.
    pub fn default_for(
        shader: &crate::front::Shader,
        entry: Option<&str>,
        vertex_entry: Option<&str>,
    ) -> Result<Scene, Error> {
        let init = init::for_shader(shader, entry, vertex_entry)?;
        let file = Arc::new(SourceFile::new(
            format!("default scene for {}", shader.file.path),
            init.text,
        ));
        let mut scene = Scene::parse(file)?;
        scene.defaulted = init.defaulted;
        Ok(scene)
    }

    /// This scene with the motion a game has, for whole-frame reuse with
    /// no scene given: the camera orbits at 1° a frame (60°/s at 60 Hz, a
    /// third-person camera turning) and a small sphere crosses in front of
    /// the turning one at 1.5 units/s, so that what is interpolated moves
    /// on screen as in a game (the profile's default barely moves: a cache
    /// wants few misses, an interpolation test wants motion).
    pub fn with_game_motion(mut self) -> Scene {
        self.camera.orbit_degrees_per_frame = 1.0;
        for effect in [Effect::CameraMotion, Effect::ObjectMotion] {
            if !self.has(effect) {
                self.effects.push(effect);
            }
        }
        self.objects.push(Object {
            mesh: MeshSource::Sphere {
                radius: 0.3,
                rings: 24,
                segments: 48,
            },
            position: [-1.1, -0.2, 1.3],
            rotation_degrees: [0.0; 3],
            scale: 1.0,
            rotation_degrees_per_frame: [0.0, 2.0, 0.0],
            translation_per_frame: [0.025, 0.0, 0.0],
            deformation: None,
            skin: None,
            instances: None,
            storage: BTreeMap::new(),
            every_frame: false,
        });
        self.description = "default scene with a game's motion: the camera orbits at 1° a frame (60°/s at 60 Hz) around a turning sphere, and a small sphere crosses in front of it at 0.025 units a frame (1.5 units/s)".into();
        self
    }

    /// Parses and checks a scene's text; errors point into it.
    pub fn parse(file: Arc<SourceFile>) -> Result<Scene, Error> {
        let mut scene: Scene = toml::from_str(&file.text).map_err(|err| {
            let range = err.span().unwrap_or(0..0);
            Error::in_file(
                file.clone(),
                Diagnostic::error(format!("invalid scene: {}", err.message()))
                    .with_label(range, "here"),
            )
        })?;
        bounds::check(&scene, &file)?;
        scene.file = Some(file);
        Ok(scene)
    }

    /// Where the value at `path` (table keys, and decimal indices into
    /// arrays: `["objects", "0", "mesh"]`) sits in the scene's file.
    pub fn span(&self, path: &[&str]) -> Option<Range<usize>> {
        bounds::span_in(&self.file.as_ref()?.text, path)
    }

    /// Checks that every `[uniforms]` key names a uniform member of
    /// `module` and every `[textures]` key a texture it declares: a
    /// misspelt name would otherwise leave the shader's own value to a
    /// default and the scene's unused, without a word.
    pub fn check_names(&self, module: &naga::Module) -> Result<(), Error> {
        let buffers = uniforms::buffers(module);
        for name in self.uniforms.keys() {
            if !uniforms::has_member(&buffers, name) {
                let mut known: Vec<String> = buffers
                    .iter()
                    .flat_map(|b| b.members.iter())
                    .filter(|m| !layout::is_padding(&m.name))
                    .map(|m| format!("`{}`", m.name))
                    .collect();
                known.sort();
                known.dedup();
                let listing = if known.is_empty() {
                    "it has no uniform buffer".to_string()
                } else {
                    format!("its uniform members are {}", known.join(", "))
                };
                return Err(self.error(
                    format!("[uniforms] sets `{name}`, which the shader does not have: {listing}"),
                    self.span(&["uniforms", name]),
                ));
            }
        }
        for (index, change) in self.uniform_changes.iter().enumerate() {
            if let Some(name) = change
                .uniforms
                .keys()
                .find(|n| !self.uniforms.contains_key(*n))
            {
                let at = index.to_string();
                return Err(self.error(
                    format!(
                        "[[uniform_changes]] at frame {} sets `{name}`, which [uniforms] does not: set its value from the first frame there",
                        change.frame
                    ),
                    self.span(&["uniform_changes", &at, "uniforms", name]),
                ));
            }
        }
        let textures: Vec<String> = module
            .global_variables
            .iter()
            .filter(|(_, g)| matches!(module.types[g.ty].inner, naga::TypeInner::Image { .. }))
            .filter_map(|(_, g)| g.name.clone())
            .collect();
        for name in self.textures.keys() {
            if !textures.contains(name) {
                let listing = if textures.is_empty() {
                    "it binds no texture".to_string()
                } else {
                    let names: Vec<String> = textures.iter().map(|t| format!("`{t}`")).collect();
                    format!("its textures are {}", names.join(", "))
                };
                return Err(self.error(
                    format!(
                        "[textures.{name}] names a texture the shader does not bind: {listing}"
                    ),
                    self.span(&["textures", name]),
                ));
            }
        }
        Ok(())
    }

    /// An error about the scene, pointing at `span` of its file when the
    /// scene was read from one.
    pub fn error(&self, message: String, span: Option<Range<usize>>) -> Error {
        let diagnostic = Diagnostic::error(message);
        match (&self.file, span) {
            (Some(file), Some(span)) => {
                Error::in_file(file.clone(), diagnostic.with_label(span, "here"))
            }
            (Some(file), None) => Error::in_file(file.clone(), diagnostic),
            (None, _) => Error::plain(diagnostic),
        }
    }

    /// The role the simulation fills member `member` of binding `binding`
    /// with: the one `[roles]` gives it, else its own name when that is a
    /// role's; `None` when the scene gives its value.
    pub fn role(&self, binding: &str, member: &str) -> Option<&str> {
        match self.roles.get(&roles::key(binding, member)) {
            Some(role) => Some(role.get_ref().as_str()),
            None => layout::implicit_role(&roles::key(binding, member)),
        }
    }

    /// Whether the scene declares `effect`.
    pub fn has(&self, effect: Effect) -> bool {
        self.effects.contains(&effect)
    }

    /// Whether object `index` moves in the world: it turns, travels or
    /// deforms (its instances spin or orbit) under the declared effects. A
    /// still object still moves on screen when the camera does; this is
    /// the "dynamic" of seed 003, whose motion the camera's does not give.
    pub fn moves(&self, index: usize) -> bool {
        let Some(object) = self.objects.get(index) else {
            return false;
        };
        let bends = object
            .skin
            .as_ref()
            .is_some_and(|skin| skin.bend_degrees_per_frame != 0.0);
        let deforms = (object.deformation.is_some() || bends) && self.has(Effect::Deformation);
        let nonzero = |v: &[f32]| v.iter().any(|x| *x != 0.0);
        let travels = nonzero(&object.rotation_degrees_per_frame)
            || nonzero(&object.translation_per_frame)
            || object.instances.as_ref().is_some_and(|i| {
                i.spin_degrees_per_frame
                    .iter()
                    .any(|s| *s != glam::Vec3::ZERO)
                    || nonzero(&i.orbit_degrees_per_frame)
            });
        deforms || (travels && self.has(Effect::ObjectMotion))
    }

    /// Object `index`'s mesh as frame `n` deforms it, when the scene
    /// declares `deformation` and the object has one; `None` when its mesh
    /// does not change.
    pub fn deformed(&self, index: usize, mesh: &Mesh, n: u32) -> Option<Mesh> {
        let ripple = self.objects.get(index)?.deformation?;
        if !self.has(Effect::Deformation) {
            return None;
        }
        let phase = ripple.speed * self.motion_frame(n);
        let mut out = mesh.clone();
        for (p, normal) in out.positions.iter_mut().zip(&mesh.normals) {
            *p += *normal * (ripple.amplitude * (ripple.frequency * p.y + phase).sin());
        }
        Some(out)
    }

    /// The state of frame `n` of a run at `size` pixels (which may not be
    /// the scene's own).
    pub fn frame_sized(&self, n: u32, size: [u32; 2]) -> FrameState {
        let mut state = self.frame(n, size[0] as f32 / size[1].max(1) as f32);
        let resolution = glam::Vec2::new(size[0] as f32, size[1] as f32);
        state.resolution = resolution;
        if let Some(previous) = state.previous.as_mut() {
            previous.resolution = resolution;
        }
        state
    }

    /// The state of frame `n` (0-based, warm-up included), simulating only
    /// the declared effects, with the frame before it.
    pub fn frame(&self, n: u32, aspect: f32) -> FrameState {
        let mut state = self.frame_alone(n, aspect);
        if n > 0 {
            state.previous = Some(Box::new(self.frame_alone(n - 1, aspect)));
        }
        state
    }

    /// The frame of the motion run frame `n` shows.
    fn motion_frame(&self, n: u32) -> f32 {
        (u64::from(n) + u64::from(self.start_frame)) as f32
    }

    /// Frame `n`'s state without the frame before.
    fn frame_alone(&self, n: u32, aspect: f32) -> FrameState {
        let t = self.motion_frame(n);
        let camera = &self.camera;
        let (shot, cut) = self.shot_at(t);
        let (mut eye, mut target) = (Vec3::from(camera.eye), Vec3::from(camera.target));
        // The camera's own motion from the start of its shot.
        let camera_t = match cut {
            Some(cut) => {
                eye = Vec3::from(cut.eye.unwrap_or(camera.eye));
                target = Vec3::from(cut.target.unwrap_or(camera.target));
                t - cut.frame as f32
            }
            None => t,
        };
        if self.has(Effect::CameraMotion) {
            let orbit =
                Mat4::from_rotation_y((camera.orbit_degrees_per_frame * camera_t).to_radians());
            eye = target + orbit.transform_vector3(eye - target);
            let pan = Vec3::from(camera.pan_per_frame) * camera_t;
            eye += pan;
            target += pan;
        }
        let (fov, roll) = if self.has(Effect::CameraMotion) {
            (
                camera.fov_after(camera_t),
                (camera.roll_degrees_per_frame * camera_t).to_radians(),
            )
        } else {
            (camera.fov_degrees.to_radians(), 0.0)
        };
        let clip_from_view = camera.projection_with_fov(fov, aspect);
        // Rolling the camera counter-clockwise turns the view the other way.
        let view_from_world = Mat4::from_rotation_z(-roll) * Mat4::look_at_rh(eye, target, Vec3::Y);
        let clip_from_world = clip_from_view * view_from_world;

        let mut light = Vec3::from(self.light.position);
        if self.has(Effect::LightMotion) {
            let moving = (t - self.light.still_frames as f32).max(0.0);
            light =
                Mat4::from_rotation_y((self.light.orbit_degrees_per_frame * moving).to_radians())
                    .transform_point3(light);
        }
        let light_clip_from_world = Mat4::perspective_rh(50f32.to_radians(), 1.0, 0.5, 30.0)
            * Mat4::look_at_rh(light, Vec3::ZERO, Vec3::Y);

        let moving = self.has(Effect::ObjectMotion);
        let objects = self
            .objects
            .iter()
            .map(|object| {
                let motion = if moving { t } else { 0.0 };
                let degrees = Vec3::from(object.rotation_degrees)
                    + Vec3::from(object.rotation_degrees_per_frame) * motion;
                let rotation = Mat4::from_euler(
                    glam::EulerRot::XYZ,
                    degrees.x.to_radians(),
                    degrees.y.to_radians(),
                    degrees.z.to_radians(),
                );
                let position =
                    Vec3::from(object.position) + Vec3::from(object.translation_per_frame) * motion;
                Mat4::from_translation(position)
                    * rotation
                    * Mat4::from_scale(Vec3::splat(object.scale))
            })
            .collect();
        let instances = self
            .objects
            .iter()
            .map(|object| match &object.instances {
                None => vec![Mat4::IDENTITY],
                Some(instances) => {
                    let motion = if moving { t } else { 0.0 };
                    (0..instances.count)
                        .map(|i| instances.transform(i, motion))
                        .collect()
                }
            })
            .collect();
        FrameState {
            clip_from_world,
            clip_from_view,
            view_from_world,
            camera_position: eye,
            light_position: light,
            light_clip_from_world,
            time: if self.has(Effect::Time) {
                t * self.seconds_per_frame
            } else {
                0.0
            },
            resolution: glam::Vec2::new(self.size[0] as f32, self.size[1] as f32),
            objects,
            instances,
            joints: self.joint_poses(t),
            frame: n.saturating_add(self.start_frame),
            shot,
            previous: None,
        }
    }

    /// The camera's shot at motion frame `t`, and the cut that began it
    /// (none for the first shot).
    fn shot_at(&self, t: f32) -> (u32, Option<&Cut>) {
        let passed = self
            .camera
            .cuts
            .iter()
            .take_while(|cut| cut.frame as f32 <= t)
            .count();
        (
            passed as u32,
            passed.checked_sub(1).map(|last| &self.camera.cuts[last]),
        )
    }

    /// The value of uniform member `name` in motion frame `frame`: the last
    /// `[[uniform_changes]]` from that frame or before that sets it, else
    /// `[uniforms]`'.
    pub fn uniform_at(&self, name: &str, frame: u32) -> Option<&toml::Value> {
        self.uniform_changes
            .iter()
            .rev()
            .filter(|change| change.frame <= frame)
            .find_map(|change| change.uniforms.get(name))
            .or_else(|| self.uniforms.get(name))
    }

    /// Each object's joints' poses at frame `t` (bending only with
    /// `deformation`).
    fn joint_poses(&self, t: f32) -> Vec<Vec<Mat4>> {
        let bending = if self.has(Effect::Deformation) {
            t
        } else {
            0.0
        };
        self.objects
            .iter()
            .map(|object| match &object.skin {
                Some(skin) => skin.poses(bending),
                None => vec![Mat4::IDENTITY],
            })
            .collect()
    }

    /// Object `index`'s mesh in the pose of `state`, for what the CPU
    /// needs of it (shadow casters, silhouettes); `None` without a skin.
    pub fn posed(&self, index: usize, mesh: &Mesh, state: &FrameState) -> Option<Mesh> {
        self.objects.get(index)?.skin.as_ref()?;
        Some(skin::pose(mesh, state.joints.get(index)?))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene(effects: &str) -> Scene {
        let text = format!(
            "effects = [{effects}]\n[camera]\norbit_degrees_per_frame = 2.0\n[light]\norbit_degrees_per_frame = 5.0\n[[objects]]\nmesh = {{ kind = \"cube\" }}\nrotation_degrees_per_frame = [0.0, 3.0, 0.0]\ndeformation = {{ amplitude = 0.1 }}\n"
        );
        Scene::parse(Arc::new(SourceFile::new("scene.toml", text))).unwrap()
    }

    /// A frame's state as the motion has it, whatever frame it is (the
    /// states of a still scene's frames differ in their number alone).
    fn posed(mut state: FrameState) -> FrameState {
        state.frame = 0;
        state
    }

    #[test]
    fn only_declared_effects_move() {
        let still = scene("");
        assert_eq!(
            posed(still.frame_alone(0, 1.0)),
            posed(still.frame_alone(10, 1.0))
        );
        let mesh = still.objects[0].mesh.build(Path::new(".")).unwrap();
        assert!(still.deformed(0, &mesh, 10).is_none());

        let light = scene("\"light-motion\"");
        let (a, b) = (light.frame(0, 1.0), light.frame(10, 1.0));
        assert_ne!(a.light_position, b.light_position);
        assert_eq!(a.clip_from_world, b.clip_from_world);
        assert_eq!(a.objects, b.objects);

        let camera = scene("\"camera-motion\"");
        let (a, b) = (camera.frame(0, 1.0), camera.frame(10, 1.0));
        assert_ne!(a.clip_from_world, b.clip_from_world);
        assert_eq!(a.light_position, b.light_position);

        let deforming = scene("\"deformation\"");
        let moved = deforming.deformed(0, &mesh, 3).unwrap();
        assert_ne!(moved.positions, mesh.positions);
        assert_eq!(
            posed(deforming.frame_alone(0, 1.0)),
            posed(deforming.frame_alone(3, 1.0))
        );
    }

    /// A scene started `start_frame` frames into its motion shows at run
    /// frame n what the scene from its start shows at n + start_frame:
    /// camera, light, objects, time and deformation alike. Its first
    /// frame has no frame before it (the cache starts cold there).
    #[test]
    fn a_scene_started_later_shows_that_frame_of_its_motion() {
        let all =
            "\"camera-motion\", \"object-motion\", \"light-motion\", \"time\", \"deformation\"";
        let from_start = scene(all);
        let mut later = scene(all);
        later.start_frame = 7;
        assert_eq!(later.frame_alone(0, 1.0), from_start.frame_alone(7, 1.0));
        assert_eq!(later.frame(3, 1.0), from_start.frame(10, 1.0));
        assert!(later.frame(0, 1.0).previous.is_none());
        assert_ne!(
            posed(later.frame_alone(0, 1.0)),
            posed(from_start.frame_alone(0, 1.0))
        );
        let mesh = later.objects[0].mesh.build(Path::new(".")).unwrap();
        assert_eq!(
            later.deformed(0, &mesh, 2).unwrap().positions,
            from_start.deformed(0, &mesh, 9).unwrap().positions
        );
    }

    /// A camera cut starts a new shot at its frame: the cut's eye, the
    /// orbit starting afresh there, the shot counted, and only the cut's
    /// frame says a cut came before it. Cuts out of frame order, or to an
    /// eye at its target, are errors at their line.
    #[test]
    fn camera_cut_starts_a_new_shot() {
        let cuts = "[camera]\neye = [0.0, 0.5, 3.0]\norbit_degrees_per_frame = 2.0\n[[camera.cuts]]\nframe = 6\neye = [3.0, 0.5, 0.0]\n[[camera.cuts]]\nframe = 9\n";
        let text = format!(
            "effects = [\"camera-motion\"]\n{cuts}[[objects]]\nmesh = {{ kind = \"cube\" }}\n"
        );
        let scene = Scene::parse(Arc::new(SourceFile::new("s.toml", text))).unwrap();
        let shots: Vec<u32> = (0..12).map(|n| scene.frame(n, 1.0).shot).collect();
        assert_eq!(shots, [0, 0, 0, 0, 0, 0, 1, 1, 1, 2, 2, 2]);
        let cut: Vec<u32> = (0..12).filter(|&n| scene.frame(n, 1.0).cut()).collect();
        assert_eq!(cut, [6, 9]);
        assert!((scene.frame(6, 1.0).camera_position - Vec3::new(3.0, 0.5, 0.0)).length() < 1e-5);
        // The second cut names no eye: the camera's own, its orbit afresh.
        let (first, second) = (scene.frame(0, 1.0), scene.frame(9, 1.0));
        assert!((first.camera_position - second.camera_position).length() < 1e-5);
        assert_ne!(scene.frame(10, 1.0).camera_position, second.camera_position);

        for (cuts, message) in [
            (
                "[[camera.cuts]]\nframe = 9\n[[camera.cuts]]\nframe = 6\n",
                "frame order",
            ),
            (
                "[[camera.cuts]]\nframe = 4\neye = [0.0, 0.0, 0.0]\n",
                "looks nowhere",
            ),
        ] {
            let text = format!("[[objects]]\nmesh = {{ kind = \"cube\" }}\n{cuts}");
            let err = Scene::parse(Arc::new(SourceFile::new("s.toml", text)))
                .map(|_| ())
                .expect_err(message);
            let rendered = err.render();
            assert!(rendered.contains(message), "{rendered}");
            assert!(rendered.contains("s.toml:"), "{rendered}");
        }
    }

    /// `[[uniform_changes]]` replace `[uniforms]`' values from their
    /// frame on, the latest change that sets a member winning; a change
    /// of a member `[uniforms]` does not set is an error at its line.
    #[test]
    fn uniform_changes_take_over_from_their_frame() {
        let text = "[[objects]]\nmesh = { kind = \"cube\" }\n[uniforms]\ntaps = 64\nsaturation = 1.0\n[[uniform_changes]]\nframe = 10\nuniforms = { taps = 8 }\n[[uniform_changes]]\nframe = 20\nuniforms = { taps = 1, saturation = 0.5 }\n";
        let scene = Scene::parse(Arc::new(SourceFile::new("s.toml", text))).unwrap();
        let at = |name: &str, frame| {
            scene
                .uniform_at(name, frame)
                .and_then(|v| v.as_float().or(v.as_integer().map(|i| i as f64)))
        };
        assert_eq!(at("taps", 0), Some(64.0));
        assert_eq!(at("taps", 9), Some(64.0));
        assert_eq!(at("taps", 10), Some(8.0));
        assert_eq!(at("taps", 25), Some(1.0));
        assert_eq!(at("saturation", 15), Some(1.0));
        assert_eq!(at("saturation", 20), Some(0.5));
        assert_eq!(scene.frame(12, 1.0).frame, 12);

        let module = naga::front::wgsl::parse_str(
            "struct P { taps: u32, saturation: f32 }\n@group(0) @binding(0) var<uniform> p: P;\n@fragment fn f() -> @location(0) vec4<f32> { return vec4<f32>(f32(p.taps) * p.saturation); }\n",
        )
        .unwrap();
        assert!(scene.check_names(&module).is_ok());
        let unset = text.replace("taps = 1, saturation", "taps = 1, brightness");
        let scene = Scene::parse(Arc::new(SourceFile::new("s.toml", unset))).unwrap();
        let err = scene.check_names(&module).unwrap_err().render();
        assert!(
            err.contains("brightness") && err.contains("s.toml:11:"),
            "{err}"
        );
    }

    /// Depth of a point `distance` in front of the camera.
    fn depth_at(camera: &Camera, distance: f32) -> f32 {
        let clip = camera.projection(1.0) * glam::Vec4::new(0.0, 0.0, -distance, 1.0);
        clip.z / clip.w
    }

    #[test]
    fn depth_conventions_put_near_and_far_where_they_say() {
        let camera = |depth: &str, far: &str| {
            let text = format!(
                "[camera]\nnear = 0.5\nfar = {far}\ndepth = \"{depth}\"\n[[objects]]\nmesh = {{ kind = \"cube\" }}\n"
            );
            Scene::parse(Arc::new(SourceFile::new("s.toml", text)))
                .map_err(|e| e.render())
                .unwrap()
                .camera
        };
        let close = |a: f32, b: f32| (a - b).abs() < 1e-5;
        let standard = camera("standard", "40");
        let reversed = camera("reversed", "40");
        assert!(close(depth_at(&standard, 0.5), 0.0) && close(depth_at(&standard, 40.0), 1.0));
        assert!(close(depth_at(&reversed, 0.5), 1.0) && close(depth_at(&reversed, 40.0), 0.0));
        for d in [1.0, 3.0, 17.0] {
            assert!(close(depth_at(&reversed, d), 1.0 - depth_at(&standard, d)));
        }
        let standard = camera("standard", "\"infinity\"");
        let reversed = camera("reversed", "\"infinity\"");
        for d in [0.5, 5.0, 500.0] {
            // 1 − near/distance and near/distance.
            assert!(close(depth_at(&standard, d), 1.0 - 0.5 / d));
            assert!(close(depth_at(&reversed, d), 0.5 / d));
        }
        assert_eq!(standard.far, Far::Infinity);
        assert_eq!(camera("reversed", "40").depth, DepthConvention::Reversed);
    }

    #[test]
    fn bad_scenes_are_diagnostics() {
        let parse = |text: &str| {
            Scene::parse(Arc::new(SourceFile::new("s.toml", text)))
                .unwrap_err()
                .render()
        };
        assert!(parse("[[objects]]\nmesh = { kind = \"blob\" }\n").contains("s.toml:2:"));
        assert!(
            parse("size = [0, 10]\n[[objects]]\nmesh = { kind = \"cube\" }\n").contains("size")
        );
        assert!(parse("effects = [\"wind\"]\n").contains("s.toml:1:"));
        assert!(parse("").contains("no objects"));
        let cube = "[[objects]]\nmesh = { kind = \"cube\" }\n";
        assert!(parse(&format!("[camera]\nfar = \"far\"\n{cube}")).contains("s.toml:2:"));
        assert!(parse(&format!("[camera]\ndepth = \"inverted\"\n{cube}")).contains("s.toml:2:"));
        assert!(parse(&format!("[camera]\nnear = 2.0\nfar = 1.0\n{cube}")).contains("near < far"));

        // Instances: the error points at the object's `instances`.
        let instanced = |instances: &str| parse(&format!("{cube}instances = {instances}\n"));
        for (instances, says) in [
            ("0", "1 to 65536 instances"),
            ("{ count = 4, radius = 2.0 }", "a grid takes `spacing`"),
            ("{ count = 4, layout = \"hexagon\" }", "hexagon"),
            (
                "{ count = 4, spin_degrees_per_frame = [[0, 1, 0]] }",
                "lists 1 value for 4",
            ),
            (
                "{ count = 4, orbit_degrees_per_frame = [1, 2, 3] }",
                "lists 3 values for 4",
            ),
            ("{ count = 2, spacing = 1.0, speed = 3 }", "speed"),
        ] {
            let err = instanced(instances);
            assert!(
                err.contains(says) && err.contains("s.toml:3:"),
                "{instances}: {err}"
            );
        }
    }

    #[test]
    fn instances_move_only_with_object_motion() {
        let text = |effects: &str| {
            format!("effects = [{effects}]\n[[objects]]\nmesh = {{ kind = \"cube\" }}\ninstances = {{ count = 4, layout = \"ring\", orbit_degrees_per_frame = [1, -1, 2, 0], spin_degrees_per_frame = [0, 3, 0] }}\n[[objects]]\nmesh = {{ kind = \"cube\" }}\n")
        };
        let still = Scene::parse(Arc::new(SourceFile::new("s.toml", text("")))).unwrap();
        assert_eq!(
            posed(still.frame_alone(0, 1.0)),
            posed(still.frame_alone(5, 1.0))
        );
        let state = still.frame(0, 1.0);
        assert_eq!(state.instances[0].len(), 4);
        assert_eq!(state.instances[1], [Mat4::IDENTITY]);
        let moving = Scene::parse(Arc::new(SourceFile::new(
            "s.toml",
            text("\"object-motion\""),
        )))
        .unwrap();
        let (a, b) = (moving.frame(0, 1.0), moving.frame(5, 1.0));
        // Each instance moves by its own orbit and spin; the object stays.
        assert_eq!(a.objects, b.objects);
        for i in 0..4 {
            assert_ne!(a.instances[0][i], b.instances[0][i], "instance {i}");
        }
        let centre = |s: &FrameState, i: usize| s.instances[0][i].transform_point3(Vec3::ZERO);
        // Instance 3 does not orbit: only spins about its own centre.
        assert!((centre(&a, 3) - centre(&b, 3)).length() < 1e-5);
        assert!((centre(&a, 0) - centre(&b, 0)).length() > 0.1);
    }
}
