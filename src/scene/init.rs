//! The default scene: what `profile` renders when it is given no scene,
//! and what `scene init` writes for the user to edit.
//!
//! Both are one TOML text, so a written scene profiles exactly as no scene
//! does. It is a lit, rotating, subdivided sphere under a slowly orbiting
//! camera and light, and then, for the shader at hand:
//!
//! - `[roles]`: the shader's own members the simulation fills, inferred
//!   from the IR (`super::roles::infer`), each with a comment saying how;
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
    /// `uniform `material.roughness` = 0.5 (why)`, one line each.
    pub defaulted: Vec<String>,
    /// The roles inferred from the IR.
    pub roles: Vec<Inferred>,
}

/// The camera and light every default scene has, after its description
/// and culling.
const STAGE: &str = r#"size = [256, 256]
frames = 32
warmup = 8
effects = ["camera-motion", "object-motion", "light-motion", "time"]
seconds_per_frame = 0.016666668

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
"#;

/// What the default scene draws: a lit sphere turning.
const SPHERE: &str = r#"
[[objects]]
mesh = { kind = "sphere", radius = 1.0, rings = 48, segments = 96 }
position = [0.0, 0.0, 0.0]
scale = 1.0
rotation_degrees_per_frame = [0.0, 0.4, 0.0]
"#;

/// What it draws for a vertex stage that places its vertices by
/// `@builtin(vertex_index)` alone (a fullscreen pass): one triangle whose
/// vertex data the shader does not read.
const FULLSCREEN: &str = r#"
[[objects]]
mesh = { kind = "fullscreen" }
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
    let fullscreen = vertex.is_some_and(|v| places_by_index(module, v));
    let (description, culling, object) = if fullscreen {
        (
            "default scene: a fullscreen pass (the vertex stage places its vertices by vertex_index) under a slowly orbiting camera and light",
            "false",
            FULLSCREEN,
        )
    } else {
        (
            "default scene: a lit sphere turning under a slowly orbiting camera and light",
            "true",
            SPHERE,
        )
    };
    let mut text = format!(
        "# The default scene for {shader_name}, from `shadecache scene init`.\n\
         # Every value is spelled out: edit any of them (docs/scene-toml.md).\n\n\
         description = {description:?}\ncull_back_faces = {culling}\n{STAGE}{object}"
    );
    let role_of = |binding: &str, member: &str| -> Option<&'static str> {
        let key = roles::key(binding, member);
        inferred
            .iter()
            .find(|i| i.key == key)
            .map(|i| i.role)
            .or_else(|| implicit_role(&key))
    };

    if let Some(vertex) = vertex {
        let function = &module.entry_points[vertex].function;
        text.push_str(&instance_inputs_note(module, function));
        text.push_str(&vertex_constants(module, function));
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
            let Some((value, why)) = neutral(binding, member) else {
                return false;
            };
            let _ = writeln!(section, "# defaulted: {why}{note}");
            let _ = writeln!(section, "{} = {value}", quoted(&member.name));
            defaulted.push(format!(
                "{kind} `{}` = {value} ({why})",
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

    let mut shadow_map = false;
    for (_, global) in module.global_variables.iter() {
        let TypeInner::Image {
            dim,
            arrayed,
            class,
        } = module.types[global.ty].inner
        else {
            continue;
        };
        let name = global.name.clone().unwrap_or_default();
        let drawn = global
            .binding
            .is_some_and(|b| binds(&name, b.group, b.binding));
        if !drawn || matches!(class, ImageClass::Storage { .. }) {
            continue;
        }
        let (pattern, why) = texture_pattern(&name, dim, arrayed, class);
        let _ = write!(
            text,
            "\n# defaulted: {why}\n[textures.{}]\ngenerate = \"{pattern}\"\n",
            quoted(&name)
        );
        if pattern != "far" && pattern != "shadow-map" {
            text.push_str("size = 256\n");
        }
        shadow_map |= pattern == "shadow-map";
        defaulted.push(format!("texture `{name}` = generated \"{pattern}\""));
    }
    if shadow_map {
        // Something for the sphere to cast its shadow on.
        text.push_str(FLOOR);
    }
    SceneInit {
        text,
        defaulted,
        roles: inferred,
    }
}

/// A floor under the sphere, for a shader with a shadow map: the sphere
/// casts its shadow on it (alone, a sphere shadows only its unlit side).
const FLOOR: &str = r#"
# A floor to cast the sphere's shadow on: the shader reads a shadow map.
[[objects]]
mesh = { kind = "plane", size = 6.0, subdivisions = 8 }
position = [0.0, -1.1, 0.0]
"#;

/// Whether vertex entry point `vertex` places its vertices from
/// `@builtin(vertex_index)` alone: it takes no `@location` input.
fn places_by_index(module: &Module, vertex: usize) -> bool {
    let function = &module.entry_points[vertex].function;
    let mut locations = false;
    let mut index = false;
    let mut look = |binding: &Option<naga::Binding>| match binding {
        Some(naga::Binding::Location { .. }) => locations = true,
        Some(naga::Binding::BuiltIn(naga::BuiltIn::VertexIndex)) => index = true,
        _ => {}
    };
    for input in crate::proc::inputs(module, function) {
        look(input.binding);
    }
    index && !locations
}

/// A vertex input as the mesh's and instances' feeds look at it: only its
/// name, its location and that it is a float matter to them.
fn probe(location: u32, name: &str, step: crate::plan::StepMode) -> crate::plan::VertexAttribute {
    crate::plan::VertexAttribute {
        location,
        name: name.to_string(),
        format: crate::plan::VertexFormat::Float32x4,
        step,
        previous_of: None,
    }
}

/// `[vertex_inputs]` for the vertex entry point's per-vertex float inputs
/// the mesh has nothing for (a text renderer's per-glyph `depth`): each a
/// constant 0.5 (the run lists the inputs it feeds a constant). Empty when
/// the mesh feeds them all.
fn vertex_constants(module: &Module, function: &naga::Function) -> String {
    let per_instance = crate::proc::instance_locations(module, function);
    let mut section = String::new();
    let mut add = |name: Option<&String>,
                   ty: naga::Handle<naga::Type>,
                   binding: &Option<naga::Binding>| {
        let Some(naga::Binding::Location { location, .. }) = *binding else {
            return;
        };
        let float = match module.types[ty].inner {
            TypeInner::Scalar(s) | TypeInner::Vector { scalar: s, .. } => {
                s.kind == naga::ScalarKind::Float && s.width == 4
            }
            _ => false,
        };
        if per_instance.contains(&location) || !float {
            return;
        }
        let name = name.cloned().unwrap_or_default();
        let attribute = probe(location, &name, crate::plan::StepMode::Vertex);
        if super::mesh::VertexSource::of(&attribute, &Default::default()).is_ok() {
            return;
        }
        let _ = writeln!(
            section,
            "# defaulted: vertex input @location({location}), which the mesh has nothing for: a constant\n{} = 0.5",
            quoted(&name)
        );
    };
    for input in crate::proc::inputs(module, function) {
        add(input.name, input.ty, input.binding);
    }
    if section.is_empty() {
        section
    } else {
        format!("\n[vertex_inputs]\n{section}")
    }
}

/// A comment listing the vertex entry point's per-instance inputs and
/// what feeds each (nothing to write: they are fed by name); empty when
/// it has none.
fn instance_inputs_note(module: &Module, function: &naga::Function) -> String {
    let per_instance = crate::proc::instance_locations(module, function);
    let mut note = String::new();
    for input in crate::proc::inputs(module, function) {
        let Some(location) = crate::proc::location_of(input.binding) else {
            continue;
        };
        if !per_instance.contains(&location) {
            continue;
        }
        let name = input.name.cloned().unwrap_or_default();
        let attribute = probe(location, &name, crate::plan::StepMode::Instance);
        let what = match super::instance_inputs::InstanceSource::of(&attribute) {
            Ok(source) => source.describe(),
            Err(err) => format!("cannot be fed: {err}"),
        };
        let _ = writeln!(note, "#   @location({location}) {name}: {what}");
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

/// A scalar's default by what its name says it is: the value and why.
/// Counts and steps are whole numbers of a sensible size (a loop bound of
/// 0.75 would run once, or never); factors that weigh a term are in
/// [0, 1]; scales and intensities are 1. `None`: nothing in the name.
fn scalar_by_name(words: &[String], integer: bool) -> Option<(f64, &'static str)> {
    let has = |list: &[&str]| words.iter().any(|w| list.contains(&w.as_str()));
    Some(
        if has(&["step", "iteration", "sample", "tap", "march", "bounce"]) {
            (16.0, "a step or sample count, by its name: 16")
        } else if has(&["octave", "layer", "cascade", "level", "lod", "band"]) {
            (4.0, "a count of octaves or levels, by its name: 4")
        } else if has(&["count", "num", "len", "length"]) {
            (1.0, "a count, by its name: 1")
        } else if integer {
            if has(&[
                "flag", "flags", "mode", "index", "id", "kind", "type", "bit", "mask",
            ]) {
                (0.0, "a flag, mode or index, by its name: 0 (the first)")
            } else if has(&["size", "width", "height"]) {
                (256.0, "a size in pixels, by its name: the frame's 256")
            } else {
                return None;
            }
        } else if has(&["rough", "roughness"]) {
            (0.5, "a roughness, by its name: 0.5, in [0, 1]")
        } else if has(&["metal", "metallic", "metalness"]) {
            (0.0, "a metalness, by its name: 0 (a dielectric), in [0, 1]")
        } else if has(&["opacity", "alpha", "coverage", "visibility"]) {
            (1.0, "an opacity, by its name: 1 (opaque)")
        } else if has(&["ior"]) {
            (1.5, "an index of refraction, by its name: 1.5 (glass)")
        // `name_words` drops a plural s: `bias` reads as `bia`.
        } else if has(&["bias", "bia"]) {
            (0.005, "a bias, by its name: 0.005")
        } else if has(&["threshold", "cutoff", "epsilon", "eps"]) {
            (0.5, "a threshold, by its name: 0.5")
        } else if has(&["near"]) {
            (0.1, "a near plane, by its name: 0.1")
        } else if has(&["far"]) {
            (100.0, "a far plane, by its name: 100")
        } else if has(&["range"]) || (has(&["light"]) && has(&["radius"])) {
            (
                20.0,
                "a light's range, by its name: 20, past the default scene's extent",
            )
        } else if has(&["shininess", "exponent"]) || (has(&["specular", "spec"]) && has(&["power"]))
        {
            (32.0, "a specular exponent, by its name: 32")
        } else if has(&["ambient"]) {
            (0.1, "an ambient term, by its name: 0.1")
        } else if has(&["spread", "softness", "blur"]) {
            (1.0, "a spread, by its name: 1")
        } else if has(&[
            "exposure",
            "intensity",
            "power",
            "brightness",
            "scale",
            "frequency",
            "radius",
            "distance",
            "range",
            "gamma",
            "speed",
        ]) {
            (1.0, "a scale, intensity or distance, by its name: 1")
        } else if has(&[
            "factor",
            "amount",
            "strength",
            "weight",
            "mix",
            "blend",
            "occlusion",
            "ao",
            "specular",
            "reflectance",
            "fresnel",
        ]) {
            (
                0.75,
                "a factor that weighs a term, by its name: 0.75, in [0, 1]",
            )
        } else {
            return None;
        },
    )
}

/// A neutral value for a member, and why: scalars by their name
/// ([`scalar_by_name`]; else 0.75 for a float, 0 for an integer), colours
/// 0.8 grey (alpha 1), directions normalised, resolutions the frame's,
/// matrices the identity. `None` for a shape a scene cannot write.
fn neutral(binding: &str, member: &Member) -> Option<(String, String)> {
    // The binding's name counts too: `radius` of `light` is a light's.
    let words = crate::proc::name_words(&roles::key(binding, &member.name));
    let has = |list: &[&str]| words.iter().any(|w| list.contains(&w.as_str()));
    let direction = has(&["dir", "direction", "normal", "axis"]);
    let resolution = has(&["resolution", "viewport", "screen"]);
    let list = |values: Vec<String>| format!("[{}]", values.join(", "));
    let shape = roles::shape_name(member.shape);
    let scalar = |integer: bool| {
        let (value, why) = scalar_by_name(&words, integer).unwrap_or(if integer {
            (0.0, "an integer its name says nothing of: 0")
        } else {
            (0.75, "a factor its name says nothing of: 0.75")
        });
        (value, format!("a {shape}, {why}"))
    };
    Some(match member.shape {
        Shape::F32(1) => {
            let (value, why) = scalar(false);
            (format!("{value:?}"), why)
        }
        Shape::U32(1) | Shape::I32(1) => {
            let (value, why) = scalar(true);
            (format!("{}", value as i64), why)
        }
        // The default frame size: a scene with another size should say so.
        Shape::F32(2) if resolution => (
            "[256.0, 256.0]".into(),
            format!("a {shape}, a resolution by its name: the frame's 256×256"),
        ),
        Shape::U32(2) | Shape::I32(2) if resolution => (
            "[256, 256]".into(),
            format!("a {shape}, a resolution by its name: the frame's 256×256"),
        ),
        // A point no role fills (a fill light's position): beside the
        // camera, off the sphere, not inside it.
        Shape::F32(n @ (3 | 4)) if has(&["pos", "position", "origin"]) => (
            if n == 4 {
                "[-2.5, 2.0, 2.5, 1.0]".into()
            } else {
                "[-2.5, 2.0, 2.5]".into()
            },
            format!("a {shape}, a position by its name: up and to the left of the camera, outside the default sphere"),
        ),
        Shape::F32(n) if direction => {
            let c = 1.0 / (n.min(3) as f32).sqrt();
            let value = list(
                (0..n)
                    .map(|i| {
                        if i < 3 {
                            format!("{c:.6}")
                        } else {
                            "0.0".into()
                        }
                    })
                    .collect(),
            );
            (
                value,
                format!("a {shape}, a direction by its name: normalised"),
            )
        }
        // What a surface gives off by itself is nothing by default: a grey
        // emission would cover the lighting.
        Shape::F32(n @ (3 | 4)) if has(&["emissive", "emission", "emit", "glow"]) => (
            if n == 4 {
                "[0.0, 0.0, 0.0, 1.0]".into()
            } else {
                "[0.0, 0.0, 0.0]".into()
            },
            format!("a {shape}, an emission by its name: black (none)"),
        ),
        Shape::F32(4) => (
            "[0.8, 0.8, 0.8, 1.0]".into(),
            format!("a {shape}: a light grey, opaque"),
        ),
        Shape::F32(n) => (
            list(vec!["0.8".into(); n as usize]),
            format!("a {shape}: 0.8 each"),
        ),
        Shape::U32(n) | Shape::I32(n) => {
            let (value, why) = scalar(true);
            (
                list(vec![format!("{}", value as i64); n as usize]),
                format!("{why}, each component"),
            )
        }
        Shape::Matrix(columns, rows) => (
            list(
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
            format!("a {shape}: the identity"),
        ),
        Shape::Other => return None,
    })
}

/// The generated pattern for a texture, and why.
fn texture_pattern(
    name: &str,
    dim: ImageDimension,
    arrayed: bool,
    class: ImageClass,
) -> (&'static str, String) {
    let lower = name.to_ascii_lowercase();
    if matches!(class, ImageClass::Depth { .. }) && dim == ImageDimension::D2 && !arrayed {
        (
            "shadow-map",
            "a depth texture: a shadow map rendered from the scene's light every frame".into(),
        )
    } else if matches!(class, ImageClass::Depth { .. }) {
        (
            "far",
            "a depth array or cube: every texel at the far plane (nothing shadowed; shadow maps are rendered for one 2D depth texture)".into(),
        )
    } else if matches!(
        class,
        ImageClass::Sampled {
            kind: naga::ScalarKind::Uint | naga::ScalarKind::Sint,
            ..
        }
    ) {
        (
            "cells",
            "an integer texture: 8×8 cells of whole numbers 0 to 7".into(),
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

    /// A vertex stage that places its vertices by `vertex_index` alone (a
    /// fullscreen pass: a blit, a sky, a Mandelbrot) is drawn one
    /// triangle with back faces kept; a sphere's thousands of indices
    /// drew nothing of it (wgpu's `uniform_values` was an empty frame).
    #[test]
    fn a_vertex_stage_placing_by_index_draws_a_fullscreen_pass() {
        let module = module(
            "@vertex fn vs(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
                 let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
                 return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
             }
             @fragment fn fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
                 return vec4<f32>(sin(p.x * 0.1), cos(p.y * 0.1), 0.5, 1.0);
             }",
        );
        let init = default_scene(&module, "blit.wgsl", 1, Some(0));
        let file = std::sync::Arc::new(crate::diagnostic::SourceFile::new("b.toml", init.text));
        let scene = crate::scene::Scene::parse(file).unwrap();
        assert_eq!(scene.objects.len(), 1);
        assert_eq!(scene.objects[0].mesh, crate::scene::MeshSource::Fullscreen);
        assert!(!scene.cull_back_faces);
        let mesh = scene.objects[0]
            .mesh
            .build(std::path::Path::new("."))
            .unwrap();
        assert_eq!(mesh.indices, [0, 1, 2]);
        // A stage with vertex inputs still draws the sphere.
        let lit = default_scene(&super::tests::module(OWN_NAMES), "own.wgsl", 1, Some(0));
        assert!(lit.text.contains("kind = \"sphere\""));
    }

    /// A float vertex input the mesh has nothing for (glyphon's per-glyph
    /// `depth` at location 5) gets a constant in the default scene, which
    /// then profiles; it stopped with "give it a constant in the scene".
    #[test]
    fn an_input_the_mesh_cannot_feed_gets_a_constant() {
        let module = module(
            "struct In { @location(0) pos: vec2<f32>, @location(5) depth: f32, @location(6) id: u32 }
             struct Out { @builtin(position) p: vec4<f32>, @location(0) @interpolate(flat) id: u32 }
             @vertex fn vs(in: In) -> Out { return Out(vec4<f32>(in.pos, in.depth, 1.0), in.id); }
             @fragment fn fs(o: Out) -> @location(0) vec4<f32> { return vec4<f32>(f32(o.id)); }",
        );
        let init = default_scene(&module, "glyphs.wgsl", 1, Some(0));
        let file = std::sync::Arc::new(crate::diagnostic::SourceFile::new("g.toml", init.text));
        let scene = crate::scene::Scene::parse(file).unwrap();
        assert_eq!(
            scene.vertex_inputs.keys().collect::<Vec<_>>(),
            ["depth"],
            "the position is the mesh's, the integer id fed as integers"
        );
    }

    /// A vec3 named only `eye` is the camera's position: the default
    /// scene gives it that role, so it follows the orbiting camera every
    /// frame instead of staying at a default while the view turns (which
    /// makes view-dependent values look stabler than they are).
    #[test]
    fn eye_uniform_follows_the_orbiting_camera() {
        let module = module(
            "struct Uniforms { view_proj: mat4x4<f32>, eye: vec3<f32> }
             @group(0) @binding(0) var<uniform> u: Uniforms;
             struct Out { @builtin(position) clip: vec4<f32>, @location(0) world: vec3<f32> }
             @vertex fn vs(@location(0) p: vec3<f32>) -> Out {
                 return Out(u.view_proj * vec4<f32>(p, 1.0), p);
             }
             @fragment fn fs(in: Out) -> @location(0) vec4<f32> {
                 return vec4<f32>(normalize(u.eye - in.world), 1.0);
             }",
        );
        let init = default_scene(&module, "eye.wgsl", 1, Some(0));
        assert!(
            init.roles
                .iter()
                .any(|r| r.key == "u.eye" && r.role == "camera_position"),
            "{:?}",
            init.roles
        );
        let file = std::sync::Arc::new(crate::diagnostic::SourceFile::new("e.toml", init.text));
        let scene = crate::scene::Scene::parse(file).unwrap();
        let buffers = uniforms::buffers(&module);
        let eye_at = |frame: u32| {
            let state = scene.frame(frame, 1.0);
            let bytes = uniforms::fill(&buffers[0], &scene, &state, 0).unwrap();
            let member = buffers[0].members.iter().find(|m| m.name == "eye").unwrap();
            let eye: Vec<f32> = super::super::layout::read_numbers(&bytes, 0, member)
                .iter()
                .map(|&v| v as f32)
                .collect();
            (glam::Vec3::from_slice(&eye), state.camera_position)
        };
        let (first, camera_first) = eye_at(0);
        let (later, camera_later) = eye_at(40);
        assert!((first - camera_first).length() < 1e-5);
        assert!((later - camera_later).length() < 1e-5);
        assert!((first - later).length() > 0.05, "{first} {later}");
    }

    /// Scalars the default scene fills take values their names and types
    /// suggest, each with its reason: a step count is a whole number of
    /// sensible size (16, not 0.75 or 0), a roughness lies in [0, 1], a
    /// flag is 0, a scalar whose name says nothing keeps the old neutral
    /// value.
    #[test]
    fn scalar_defaults_by_name_and_type() {
        let module = module(
            "struct Material {
                 max_steps: u32, march_steps: f32, octaves: i32, light_count: u32,
                 roughness: f32, metallic: f32, opacity: f32, shadow_bias: f32,
                 exposure: f32, flags: u32, resolution: vec2<f32>, wobble: f32, seed: u32,
                 light_radius: f32, ambient: f32, emissive: vec3<f32>, shininess: f32,
                 light_position: vec3<f32>, fill_light_position: vec3<f32>,
             }
             @group(0) @binding(0) var<uniform> material: Material;
             @fragment fn fs() -> @location(0) vec4<f32> {
                 let m = material;
                 return vec4<f32>(f32(m.max_steps) + m.march_steps + f32(m.octaves) + f32(m.light_count)
                     + m.roughness + m.metallic + m.opacity + m.shadow_bias + m.exposure
                     + f32(m.flags) + m.resolution.x + m.wobble + f32(m.seed)
                     + m.light_radius + m.ambient + m.emissive.x + m.shininess
                     + m.light_position.x + m.fill_light_position.x);
             }",
        );
        let init = default_scene(&module, "m.wgsl", 0, None);
        let value = |member: &str| -> (String, String) {
            let line = init
                .defaulted
                .iter()
                .find(|d| d.starts_with(&format!("uniform `material.{member}` = ")))
                .expect("every member is listed as defaulted");
            let rest = line.split_once(" = ").unwrap().1;
            let (value, why) = rest.split_once(" (").unwrap();
            (value.to_string(), why.trim_end_matches(')').to_string())
        };
        for (member, expected, reason) in [
            ("max_steps", "16", "step or sample count"),
            ("march_steps", "16.0", "step or sample count"),
            ("octaves", "4", "octaves"),
            ("light_count", "1", "a count"),
            ("roughness", "0.5", "roughness"),
            ("metallic", "0.0", "metalness"),
            ("opacity", "1.0", "opacity"),
            ("shadow_bias", "0.005", "bias"),
            ("exposure", "1.0", "intensity"),
            ("flags", "0", "flag"),
            ("wobble", "0.75", "says nothing"),
            ("seed", "0", "says nothing"),
            ("light_radius", "20.0", "a light's range"),
            ("ambient", "0.1", "ambient"),
            ("emissive", "[0.0, 0.0, 0.0]", "emission"),
            ("shininess", "32.0", "specular exponent"),
            // `light_position` takes the light's role by its own name; a
            // second light is placed, not put where the first one is.
            ("fill_light_position", "[-2.5, 2.0, 2.5]", "a position"),
        ] {
            let (value, why) = value(member);
            assert_eq!(value, expected, "{member}: {why}");
            assert!(why.contains(reason), "{member}: {why}");
        }
        // A resolution is no default: the simulation fills it with the
        // frame's size, whatever size the run has.
        let parsed = crate::scene::Scene::parse(std::sync::Arc::new(
            crate::diagnostic::SourceFile::new("m.toml", init.text.clone()),
        ))
        .unwrap();
        assert_eq!(parsed.role("material", "resolution"), Some("resolution"));
        let buffers = uniforms::buffers(&module);
        let state = parsed.frame_sized(0, [320, 180]);
        let bytes = uniforms::fill(&buffers[0], &parsed, &state, 0).unwrap();
        let member = buffers[0]
            .members
            .iter()
            .find(|m| m.name == "resolution")
            .unwrap();
        assert_eq!(
            super::super::layout::read_numbers(&bytes, 0, member),
            [320.0, 180.0]
        );
        // The text says the same, and parses with those values.
        assert!(
            init.text.contains(
                "# defaulted: a u32, a step or sample count, by its name: 16\nmax_steps = 16\n"
            ),
            "{}",
            init.text
        );
        let file = std::sync::Arc::new(crate::diagnostic::SourceFile::new("m.toml", init.text));
        let scene = crate::scene::Scene::parse(file).unwrap();
        assert_eq!(scene.uniforms["max_steps"].as_integer(), Some(16));
        assert_eq!(scene.uniforms["roughness"].as_float(), Some(0.5));
    }

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
                "uniform `model.tint` = [0.8, 0.8, 0.8, 1.0] (a vec4<f32>: a light grey, opaque)",
                "uniform `model.light_count` = 1 (a u32, a count, by its name: 1)",
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
