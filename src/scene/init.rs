//! The default scene: what `profile` renders when it is given no scene,
//! and what `scene init` writes for the user to edit.
//!
//! Both are one TOML text, so a written scene profiles exactly as no scene
//! does. It is a lit, rotating, subdivided sphere under a slowly orbiting
//! camera and light, and then, for the shader at hand:
//!
//! - `[roles]`: the shader's own members the simulation fills, inferred
//!   from the IR ([`super::roles::infer`]), each with a comment saying how;
//! - `[uniforms]`, `[storage.*]`, `[textures.*]`: a neutral value for
//!   everything else the shader binds — factors and colours in 0.5–1,
//!   matrices the identity, integers 0 (counts 1), textures a generated
//!   pattern (a flat normal for normal maps, the far plane for depth, a sky
//!   for cube maps) — each listed as defaulted, in the text and in
//!   [`SceneInit::defaulted`].
//!
//! A value a scene cannot write (a nested struct, an array inside a
//! uniform) is not defaulted: the scene's own checks name it, as they
//! would for a hand-written scene.

use std::fmt::Write as _;

use naga::{ImageClass, ImageDimension, Module, TypeInner};

use super::layout::{implicit_role, is_padding, Member, Shape};
use super::roles::{self, Inferred};
use super::{storage, uniforms};

/// The default scene for a shader.
#[derive(Clone, Debug)]
pub struct SceneInit {
    /// The scene as TOML, with comments.
    pub text: String,
    /// What the shader binds that the scene sets to a neutral value:
    /// `uniform `material.roughness` = 0.75`, one line each.
    pub defaulted: Vec<String>,
    /// The roles inferred from the IR.
    pub roles: Vec<Inferred>,
}

/// The geometry, camera and light every default scene has.
const STAGE: &str = r#"description = "default scene: a lit sphere turning under a slowly orbiting camera and light"
size = [256, 256]
frames = 32
warmup = 8
effects = ["camera-motion", "object-motion", "light-motion", "time"]
seconds_per_frame = 0.016666668
cull_back_faces = true

[camera]
eye = [0.0, 0.6, 3.0]
target = [0.0, 0.0, 0.0]
fov_degrees = 45.0
near = 0.1
far = 100.0
depth = "standard"
orbit_degrees_per_frame = 0.25

[light]
position = [2.0, 3.0, 2.5]
orbit_degrees_per_frame = 0.5

[[objects]]
mesh = { kind = "sphere", radius = 1.0, rings = 48, segments = 96 }
position = [0.0, 0.0, 0.0]
scale = 1.0
rotation_degrees_per_frame = [0.0, 0.4, 0.0]
"#;

/// Writes the default scene for `module`, drawn with its vertex entry
/// point `vertex` (`None` when the module has none: then no matrix role is
/// inferred).
pub fn default_scene(
    module: &Module,
    shader_name: &str,
    fragment: usize,
    vertex: Option<usize>,
) -> SceneInit {
    // Only what the draw binds: a module may declare more than its two
    // entry points use.
    let entries: Vec<usize> = std::iter::once(fragment).chain(vertex).collect();
    let used = crate::proc::resources_used_by(module, &entries);
    let binds =
        |name: &str, group: u32, binding: u32| used.contains(&(name.to_string(), [group, binding]));
    let mut uniform_buffers = uniforms::buffers(module);
    uniform_buffers.retain(|b| binds(&b.name, b.group, b.binding));
    let mut storage_buffers = storage::buffers(module);
    storage_buffers.retain(|b| binds(&b.name, b.group, b.binding));
    let inferred = roles::infer(module, vertex, &uniform_buffers, &storage_buffers);
    let mut defaulted = Vec::new();
    let mut text = format!(
        "# The default scene for {shader_name}, from `shadecache scene init`.\n\
         # Every value is spelled out: edit any of them (docs/scene-toml.md).\n\n{STAGE}"
    );
    let role_of = |binding: &str, member: &str| -> Option<&'static str> {
        let key = roles::key(binding, member);
        inferred
            .iter()
            .find(|i| i.key == key)
            .map(|i| i.role)
            .or_else(|| implicit_role(member))
    };

    if let Some(vertex) = vertex {
        text.push_str(&instance_inputs_note(
            module,
            &module.entry_points[vertex].function,
        ));
    }

    if !inferred.is_empty() {
        text.push_str("\n# What the simulation fills, by the shader's own names.\n[roles]\n");
        for role in &inferred {
            let _ = writeln!(text, "# inferred: {}", role.how);
            let _ = writeln!(text, "{} = {:?}", quoted(&role.key), role.role);
        }
    }

    // A member no role fills gets a neutral value, written into `section`
    // and listed (whether it was is the result); `kind` and `note` say
    // where it goes.
    let mut default =
        |binding: &str, member: &Member, kind: &str, note: &str, section: &mut String| {
            if is_padding(&member.name) || role_of(binding, &member.name).is_some() {
                return false;
            }
            let Some(value) = neutral(member) else {
                return false;
            };
            let _ = writeln!(section, "# defaulted: {}{note}", what(member));
            let _ = writeln!(section, "{} = {value}", quoted(&member.name));
            defaulted.push(format!(
                "{kind} `{}` = {value}",
                roles::key(binding, &member.name)
            ));
            true
        };

    // `[uniforms]` is keyed by member name alone: a name two buffers
    // share takes one value.
    let mut section = String::new();
    let mut written = std::collections::BTreeSet::new();
    for buffer in &uniform_buffers {
        for member in &buffer.members {
            if !written.contains(&member.name)
                && default(&buffer.name, member, "uniform", "", &mut section)
            {
                written.insert(member.name.clone());
            }
        }
    }
    if !section.is_empty() {
        text.push_str("\n[uniforms]\n");
        text.push_str(&section);
    }

    for buffer in &storage_buffers {
        let mut section = String::new();
        for member in &buffer.members {
            let note = ", the same for every instance";
            default(&buffer.name, member, "storage", note, &mut section);
        }
        if !section.is_empty() {
            let _ = write!(text, "\n[storage.{}]\n{section}", quoted(&buffer.name));
        }
    }

    for (_, global) in module.global_variables.iter() {
        let TypeInner::Image { dim, class, .. } = module.types[global.ty].inner else {
            continue;
        };
        let name = global.name.clone().unwrap_or_default();
        let drawn = global
            .binding
            .is_some_and(|b| binds(&name, b.group, b.binding));
        if !drawn || matches!(class, ImageClass::Storage { .. }) {
            continue;
        }
        let (pattern, why) = texture_pattern(&name, dim, class);
        let _ = write!(
            text,
            "\n# defaulted: {why}\n[textures.{}]\ngenerate = \"{pattern}\"\n",
            quoted(&name)
        );
        if pattern != "far" {
            text.push_str("size = 256\n");
        }
        defaulted.push(format!("texture `{name}` = generated \"{pattern}\""));
    }
    SceneInit {
        text,
        defaulted,
        roles: inferred,
    }
}

/// A comment listing the vertex entry point's per-instance inputs and
/// what feeds each (nothing to write: they are fed by name); empty when
/// it has none.
fn instance_inputs_note(module: &Module, function: &naga::Function) -> String {
    let per_instance = crate::proc::instance_locations(module, function);
    let mut note = String::new();
    for argument in &function.arguments {
        let mut add = |name: Option<&String>, binding: &Option<naga::Binding>| {
            let Some(naga::Binding::Location { location, .. }) = *binding else {
                return;
            };
            if !per_instance.contains(&location) {
                return;
            }
            let name = name.cloned().unwrap_or_default();
            let attribute = crate::plan::VertexAttribute {
                location,
                name: name.clone(),
                // Only the name and the width matter here.
                format: crate::plan::VertexFormat::Float32x4,
                step: crate::plan::StepMode::Instance,
                previous_of: None,
            };
            let what = match super::instance_inputs::InstanceSource::of(&attribute) {
                Ok(source) => source.describe(),
                Err(err) => format!("cannot be fed: {err}"),
            };
            let _ = writeln!(note, "#   @location({location}) {name}: {what}");
        };
        match module.types[argument.ty].inner {
            TypeInner::Struct { ref members, .. } => {
                for member in members {
                    add(member.name.as_ref(), &member.binding);
                }
            }
            _ => add(argument.name.as_ref(), &argument.binding),
        }
    }
    if note.is_empty() {
        return note;
    }
    format!(
        "\n# Per-instance vertex inputs, fed by their names from each instance's\n\
         # world transform (the object's placement times the instance's):\n{note}"
    )
}

/// The default scene for `shader`: its fragment entry point `entry` (or
/// its only one), drawn with vertex entry point `vertex_entry` (or the one
/// that pairs with it; none when the module has no vertex stage).
pub fn for_shader(
    shader: &crate::front::Shader,
    entry: Option<&str>,
    vertex_entry: Option<&str>,
) -> Result<SceneInit, crate::diagnostic::Error> {
    let fragment = crate::analysis::fragment_entry(shader, entry)?;
    let vertex = crate::proc::vertex_entry(&shader.module, fragment, vertex_entry).ok();
    Ok(default_scene(
        &shader.module,
        &shader.file.path,
        fragment,
        vertex,
    ))
}

/// A TOML key, quoted when it is not a bare key.
fn quoted(key: &str) -> String {
    let bare = !key.is_empty()
        && key
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
    if bare {
        key.to_string()
    } else {
        format!("{key:?}")
    }
}

/// What a defaulted member is, for the comment above it.
fn what(member: &Member) -> String {
    format!("a {}", roles::shape_name(member.shape))
}

/// A neutral value for a member: factors 0.75, colours 0.8 grey (alpha 1),
/// directions normalised, matrices the identity, integers 0 and counts 1.
/// `None` for a shape a scene cannot write.
fn neutral(member: &Member) -> Option<String> {
    let words = crate::analysis::name_words(&member.name);
    let has = |list: &[&str]| words.iter().any(|w| list.contains(&w.as_str()));
    let count = has(&["count", "num", "len", "length", "size"]);
    let direction = has(&["dir", "direction", "normal", "axis"]);
    let resolution = has(&["resolution", "viewport", "screen"]);
    let list = |values: Vec<String>| format!("[{}]", values.join(", "));
    Some(match member.shape {
        Shape::F32(1) => "0.75".into(),
        // The default frame size: a scene with another size should say so.
        Shape::F32(2) if resolution => "[256.0, 256.0]".into(),
        Shape::F32(n) if direction => {
            let c = 1.0 / (n.min(3) as f32).sqrt();
            list(
                (0..n)
                    .map(|i| {
                        if i < 3 {
                            format!("{c:.6}")
                        } else {
                            "0.0".into()
                        }
                    })
                    .collect(),
            )
        }
        Shape::F32(4) => "[0.8, 0.8, 0.8, 1.0]".into(),
        Shape::F32(n) => list(vec!["0.8".into(); n as usize]),
        Shape::U32(1) | Shape::I32(1) => (if count { "1" } else { "0" }).into(),
        Shape::U32(n) | Shape::I32(n) => {
            list(vec![(if count { "1" } else { "0" }).into(); n as usize])
        }
        Shape::Matrix(columns, rows) => list(
            (0..columns)
                .map(|c| {
                    list(
                        (0..rows)
                            .map(|r| if r == c { "1.0".into() } else { "0.0".into() })
                            .collect(),
                    )
                })
                .collect(),
        ),
        Shape::Other => return None,
    })
}

/// The generated pattern for a texture, and why.
fn texture_pattern(name: &str, dim: ImageDimension, class: ImageClass) -> (&'static str, String) {
    let lower = name.to_ascii_lowercase();
    if matches!(class, ImageClass::Depth { .. }) {
        (
            "far",
            "a depth texture: every texel at the far plane (nothing shadowed)".into(),
        )
    } else if dim == ImageDimension::Cube {
        ("sky", "a cube texture: a sky gradient on every face".into())
    } else if lower.contains("normal") {
        ("flat-normal", "a normal map, by its name: flat".into())
    } else if [
        "rough",
        "metal",
        "occlusion",
        "ao",
        "mask",
        "noise",
        "height",
    ]
    .iter()
    .any(|w| lower.contains(w))
    {
        ("noise", "a factor map, by its name: smooth noise".into())
    } else {
        ("checker", "a colour texture: 8×8 checks".into())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn module(source: &str) -> Module {
        naga::front::wgsl::parse_str(source).unwrap()
    }

    const OWN_NAMES: &str = r#"
struct Camera { view_proj: mat4x4<f32>, eye_position: vec3<f32> }
struct Model { world: mat4x4<f32>, tint: vec4<f32>, light_count: u32 }
@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<uniform> model: Model;
@group(0) @binding(2) var albedo: texture_2d<f32>;
@group(0) @binding(3) var normal_map: texture_2d<f32>;
@group(0) @binding(4) var samp: sampler;
struct Out { @builtin(position) clip: vec4<f32>, @location(0) world: vec3<f32> }
@vertex fn vs(@location(0) pos: vec3<f32>) -> Out {
    var out: Out;
    var world: vec4<f32>;
    world = model.world * vec4<f32>(pos, 1.0);
    out.world = world.xyz;
    out.clip = camera.view_proj * world;
    return out;
}
@fragment fn fs(in: Out) -> @location(0) vec4<f32> {
    let v = normalize(camera.eye_position - in.world);
    return textureSample(albedo, samp, v.xy) * model.tint * f32(model.light_count)
        + textureSample(normal_map, samp, v.xy);
}
"#;

    #[test]
    fn own_matrix_names_are_inferred_from_the_position_chain() {
        let module = module(OWN_NAMES);
        let init = default_scene(&module, "own.wgsl", 1, Some(0));
        let roles: Vec<(&str, &str)> = init
            .roles
            .iter()
            .map(|r| (r.key.as_str(), r.role))
            .collect();
        assert_eq!(
            roles,
            [
                ("camera.view_proj", "clip_from_world"),
                ("model.world", "world_from_local"),
                ("camera.eye_position", "camera_position"),
            ]
        );
        assert!(
            init.roles[0].how.contains("applied last"),
            "{:?}",
            init.roles
        );
    }

    #[test]
    fn every_other_binding_is_defaulted_and_listed() {
        let module = module(OWN_NAMES);
        let init = default_scene(&module, "own.wgsl", 1, Some(0));
        assert_eq!(
            init.defaulted,
            [
                "uniform `model.tint` = [0.8, 0.8, 0.8, 1.0]",
                "uniform `model.light_count` = 1",
                "texture `albedo` = generated \"checker\"",
                "texture `normal_map` = generated \"flat-normal\"",
            ]
        );
        // The text is a scene that parses.
        let file = std::sync::Arc::new(crate::diagnostic::SourceFile::new("init.toml", init.text));
        let scene = crate::scene::Scene::parse(file).unwrap();
        assert_eq!(scene.role("camera", "view_proj"), Some("clip_from_world"));
        assert_eq!(
            scene.role("camera", "clip_from_world"),
            Some("clip_from_world")
        );
        assert_eq!(scene.uniforms["light_count"].as_integer(), Some(1));
    }

    /// Bevy's shape: the world position stored into a member of the
    /// output, the clip position computed from that member.
    #[test]
    fn the_chain_is_followed_through_members_of_the_output() {
        let source = "struct Cam { vp: mat4x4<f32> }
             struct Obj { xform: mat4x4<f32> }
             @group(0) @binding(0) var<uniform> cam: Cam;
             @group(0) @binding(1) var<uniform> obj: Obj;
             struct Out { @builtin(position) position: vec4<f32>, @location(0) world_position: vec4<f32> }
             @vertex fn vs(@location(0) p: vec3<f32>) -> Out {
                 var out: Out;
                 out.world_position = obj.xform * vec4<f32>(p, 1.0);
                 out.position = cam.vp * out.world_position;
                 return out;
             }";
        let init = default_scene(&module(source), "bevy.wgsl", 0, Some(0));
        let roles: Vec<(&str, &str, bool)> = init
            .roles
            .iter()
            .map(|r| (r.key.as_str(), r.role, r.how.starts_with("applied")))
            .collect();
        assert_eq!(
            roles,
            [
                ("cam.vp", "clip_from_world", true),
                ("obj.xform", "world_from_local", true)
            ]
        );
    }

    #[test]
    fn a_single_matrix_is_clip_from_local_and_three_split_the_camera() {
        let one = module(
            "@group(0) @binding(0) var<uniform> u_mvp: mat4x4<f32>;
             @vertex fn vs(@location(0) p: vec3<f32>) -> @builtin(position) vec4<f32> {
                 return u_mvp * vec4<f32>(p, 1.0);
             }",
        );
        let init = default_scene(&one, "one.wgsl", 0, Some(0));
        assert_eq!(init.roles[0].key, "u_mvp");
        assert_eq!(init.roles[0].role, "clip_from_local");
        let three = module(
            "struct M { proj: mat4x4<f32>, view: mat4x4<f32>, model: mat4x4<f32> }
             @group(0) @binding(0) var<uniform> m: M;
             @vertex fn vs(@location(0) p: vec3<f32>) -> @builtin(position) vec4<f32> {
                 return m.proj * m.view * m.model * vec4<f32>(p, 1.0);
             }",
        );
        let roles: Vec<&str> = default_scene(&three, "three.wgsl", 0, Some(0))
            .roles
            .iter()
            .map(|r| r.role)
            .collect();
        assert_eq!(
            roles,
            ["clip_from_view", "view_from_world", "world_from_local"]
        );
    }
}
