//! Filling the shader's read-only storage buffers from a scene: an array
//! of structs, one element per instance of the object drawn, member by
//! member.
//!
//! `world_from_local` (and the other simulated members) come from the
//! simulation: each element's is its instance's transform — in the
//! object's space when a uniform buffer carries the object's own
//! `world_from_local` (the shader multiplies the two), in the world
//! otherwise. Every other member comes from the object's own
//! `[objects.storage.<binding>]` table or, failing that, the scene's
//! `[storage.<binding>]` (shared by every object), as one value for every
//! instance, a list of one per instance, a cycled list or a palette
//! ([`super::instances::per_instance`]). A member the scene does not set, a
//! value of the wrong shape, or an instance count a fixed-size array
//! cannot hold is an error naming it.

use std::ops::Range;

use naga::{Module, TypeInner};

use super::instances::per_instance;
use super::layout::{self, is_padding, Member, Shape};
use super::{FrameState, Scene};
use crate::diagnostic::Error;

/// How many elements a storage buffer holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Elements {
    /// A runtime-sized array: one element per instance.
    Runtime,
    /// A fixed-size array: the object must draw this many instances.
    Fixed(u32),
    /// An array sized by a pipeline override, which a scene cannot size.
    Override,
    /// Not an array: one element, whatever the instance count.
    Single,
}

/// A read-only storage buffer of the shader and the layout of its elements.
#[derive(Clone, Debug)]
pub struct StorageBuffer {
    pub group: u32,
    pub binding: u32,
    pub name: String,
    pub elements: Elements,
    /// Bytes from one element to the next (the element's size when the
    /// buffer is not an array).
    pub stride: u32,
    /// The element's members; an element that is not a struct is one
    /// member named like the binding.
    pub members: Vec<Member>,
    /// Whether an element's `world_from_local` is relative to the object
    /// (a uniform buffer holds the object's own `world_from_local`).
    pub relative: bool,
}

impl StorageBuffer {
    /// Elements the buffer holds for an object drawing `instances`.
    pub fn len(&self, instances: u32) -> u32 {
        match self.elements {
            Elements::Runtime => instances,
            Elements::Fixed(n) => n,
            Elements::Override | Elements::Single => 1,
        }
    }

    /// Whether the buffer is an object's joint-matrix array (its element
    /// takes the role `joint_matrices`): one element per joint, whatever
    /// the instance count.
    pub fn holds_joints(&self, scene: &Scene) -> bool {
        self.members
            .iter()
            .any(|m| scene.role(&self.name, &m.name) == Some("joint_matrices"))
    }

    fn element(&self, member: &str) -> String {
        format!("`{}.{member}`", self.name)
    }
}

/// The shader's read-only storage buffers (read-write ones are not a
/// scene's to fill).
pub fn buffers(module: &Module) -> Vec<StorageBuffer> {
    let relative =
        super::uniforms::has_member(&super::uniforms::buffers(module), "world_from_local");
    let mut out = Vec::new();
    for (_, global) in module.global_variables.iter() {
        let (Some(binding), naga::AddressSpace::Storage { access }) =
            (&global.binding, global.space)
        else {
            continue;
        };
        if access.contains(naga::StorageAccess::STORE) {
            continue;
        }
        let name = global.name.clone().unwrap_or_default();
        // `struct Lights { data: array<Light> }`, as Bevy wraps its
        // storage arrays, is its array.
        let ty = match module.types[global.ty].inner {
            TypeInner::Struct { ref members, .. }
                if members.len() == 1
                    && members[0].offset == 0
                    && matches!(
                        module.types[members[0].ty].inner,
                        TypeInner::Array {
                            size: naga::ArraySize::Dynamic,
                            ..
                        }
                    ) =>
            {
                members[0].ty
            }
            _ => global.ty,
        };
        let (elements, element, stride) = match module.types[ty].inner {
            TypeInner::Array { base, size, stride } => {
                let elements = match size {
                    naga::ArraySize::Dynamic => Elements::Runtime,
                    naga::ArraySize::Constant(n) => Elements::Fixed(n.get()),
                    naga::ArraySize::Pending(_) => Elements::Override,
                };
                (elements, base, stride)
            }
            _ => (Elements::Single, global.ty, 0),
        };
        let (size, members) = layout::members(module, element, &name);
        out.push(StorageBuffer {
            group: binding.group,
            binding: binding.binding,
            name,
            elements,
            stride: if elements == Elements::Single {
                size
            } else {
                stride
            },
            members,
            relative,
        });
    }
    out
}

/// Where a member's value comes from: the object's own
/// `[objects.storage.<binding>]`, else the scene's `[storage.<binding>]`.
/// The flag says whether it is the scene's, shared by every object.
fn lookup<'a>(
    scene: &'a Scene,
    object: usize,
    binding: &str,
    member: &str,
) -> Option<(&'a toml::Spanned<toml::Value>, bool)> {
    let own = scene
        .objects
        .get(object)
        .and_then(|o| o.storage.get(binding))
        .and_then(|t| t.get_ref().get(member));
    let shared = scene
        .storage
        .get(binding)
        .and_then(|t| t.get_ref().get(member));
    own.map(|v| (v, false)).or(shared.map(|v| (v, true)))
}

/// Checks that the scene provides every member of every storage buffer,
/// in values of the members' shapes, for every object's instance count.
/// Errors point into the scene file where they can.
pub fn check(buffers: &[StorageBuffer], scene: &Scene) -> Result<(), Error> {
    // Members missing: the element, its binding, the objects lacking it.
    let mut missing: Vec<(String, &str, Vec<usize>)> = Vec::new();
    let mut missing_span = None;
    for buffer in buffers {
        let name = &buffer.name;
        let at = |span: Range<usize>, message: String| Err(scene.error(message, Some(span)));
        if buffer.elements == Elements::Override {
            return Err(scene.error(
                format!(
                    "storage `{name}` is an array sized by a pipeline override, which a scene cannot size"
                ),
                None,
            ));
        }
        if let Some(member) = buffer
            .members
            .iter()
            .find(|m| m.shape == Shape::Other && !is_padding(&m.name))
        {
            return Err(scene.error(
                format!(
                    "storage member {} has a type a scene cannot write (f32, u32, i32, their vectors and f32 matrices are supported)",
                    buffer.element(&member.name)
                ),
                None,
            ));
        }
        // Every table that sets this buffer's members: the scene's and the
        // objects' own.
        let tables = scene
            .storage
            .get(name)
            .into_iter()
            .chain(scene.objects.iter().filter_map(|o| o.storage.get(name)));
        for table in tables {
            for (key, value) in table.get_ref() {
                let Some(member) = buffer.members.iter().find(|m| &m.name == key) else {
                    let names: Vec<&str> = buffer.members.iter().map(|m| m.name.as_str()).collect();
                    return at(
                        value.span(),
                        format!(
                            "storage `{name}` has no member `{key}` (its elements have {})",
                            names.join(", ")
                        ),
                    );
                };
                if scene.role(name, &member.name).is_some() {
                    return at(
                        value.span(),
                        format!(
                            "storage member {} is filled by the simulation (each instance's own): remove it",
                            buffer.element(&member.name),
                        ),
                    );
                }
            }
        }
        // Per object: its instance count against the array, and every
        // value against its member's shape and that count.
        let joints = buffer.holds_joints(scene);
        for (index, object) in scene.objects.iter().enumerate() {
            let instances = object.instance_count();
            let skin_joints = object.skin.as_ref().map_or(1, |skin| skin.joints);
            if let (Elements::Fixed(n), true) = (buffer.elements, joints) {
                if n < skin_joints {
                    return Err(scene.error(
                        format!(
                            "storage `{name}` holds {n} joint matrices, and object {index}'s skin has {skin_joints} joints"
                        ),
                        None,
                    ));
                }
            } else if let Elements::Fixed(n) = buffer.elements {
                if n != instances {
                    return Err(scene.error(
                        format!(
                            "storage `{name}` holds {n} elements, and object {index} draws {instances} instance{}: set its `instances` to {n}",
                            if instances == 1 { "" } else { "s" }
                        ),
                        None,
                    ));
                }
            }
            for member in &buffer.members {
                if is_padding(&member.name) || scene.role(name, &member.name).is_some() {
                    continue;
                }
                let element = buffer.element(&member.name);
                let Some((value, shared)) = lookup(scene, index, name, &member.name) else {
                    match missing.iter_mut().find(|(e, ..)| *e == element) {
                        Some((.., objects)) => objects.push(index),
                        None => missing.push((element, name, vec![index])),
                    }
                    missing_span = missing_span
                        .or(object.storage.get(name).map(|t| t.span()))
                        .or(scene.storage.get(name).map(|t| t.span()));
                    continue;
                };
                if let Err(err) = values(buffer, member, value.get_ref(), instances) {
                    let hint = if shared && scene.objects.len() > 1 {
                        format!(
                            "; [storage.{name}] is every object's: give object {index} its own values under [objects.storage.{name}]"
                        )
                    } else {
                        String::new()
                    };
                    return at(
                        value.span(),
                        format!("storage member {element} (object {index}): {err}{hint}"),
                    );
                }
            }
        }
    }
    if missing.is_empty() {
        return Ok(());
    }
    let parts: Vec<String> = missing
        .iter()
        .map(|(element, name, objects)| {
            let which = if objects.len() == scene.objects.len() {
                String::new()
            } else {
                let list: Vec<String> = objects.iter().map(usize::to_string).collect();
                format!(
                    " for object{} {}",
                    if objects.len() == 1 { "" } else { "s" },
                    list.join(", ")
                )
            };
            format!(
                "{element}{which} (add it under [storage.{name}], for every object, or under an object's own [objects.storage.{name}])"
            )
        })
        .collect();
    Err(scene.error(
        format!(
            "the scene does not set storage member{} {}",
            if missing.len() == 1 { "" } else { "s" },
            parts.join("; ")
        ),
        missing_span,
    ))
}

/// Every element's numbers for `member` of `buffer`, for an object drawing
/// `instances`.
fn values(
    buffer: &StorageBuffer,
    member: &Member,
    value: &toml::Value,
    instances: u32,
) -> Result<Vec<Vec<f64>>, String> {
    let colour = matches!(member.shape, Shape::F32(3 | 4));
    let values = per_instance(
        value,
        member.shape.components(),
        buffer.len(instances),
        colour,
    )?;
    for numbers in &values {
        layout::check_numbers(member, numbers)?;
    }
    Ok(values)
}

/// The bytes of `buffer` for frame `state` and object `object`.
pub fn fill(
    buffer: &StorageBuffer,
    scene: &Scene,
    state: &FrameState,
    object: usize,
) -> Result<Vec<u8>, String> {
    let instances = scene.objects.get(object).map_or(1, |o| o.instance_count());
    let joints = buffer.holds_joints(scene);
    let len = match (joints, buffer.elements) {
        (true, Elements::Runtime) => state.joints.get(object).map_or(1, |j| j.len() as u32),
        _ => buffer.len(instances),
    };
    let mut bytes = vec![0u8; len as usize * buffer.stride as usize];
    // An element's model matrix is relative to the object's when a uniform
    // carries the object's: by its name, or by a role in `[roles]`.
    let own = |key: &str| {
        key.strip_prefix(buffer.name.as_str())
            .is_some_and(|rest| rest.starts_with('.') || rest.starts_with('['))
    };
    let relative = buffer.relative
        || scene
            .roles
            .iter()
            .any(|(key, role)| role.get_ref() == "world_from_local" && !own(key));
    for member in &buffer.members {
        if is_padding(&member.name) {
            continue;
        }
        let given = lookup(scene, object, &buffer.name, &member.name)
            .map(|(value, _)| values(buffer, member, value.get_ref(), instances))
            .transpose()
            .map_err(|err| format!("storage member {}: {err}", buffer.element(&member.name)))?;
        for element in 0..len {
            let base = (element * buffer.stride) as usize;
            // A joint's element is no instance: the object's placement.
            let placed = |state: &FrameState| {
                let instance = state.instances[object]
                    .get(element as usize)
                    .copied()
                    .filter(|_| !joints)
                    .unwrap_or(glam::Mat4::IDENTITY);
                if relative {
                    instance
                } else {
                    state.objects[object] * instance
                }
            };
            let role = scene.role(&buffer.name, &member.name);
            let at = layout::Placement {
                world_from_local: placed(state),
                previous_world_from_local: placed(state.before()),
                object,
                element: element as usize,
            };
            if let Some(floats) = role.and_then(|r| layout::simulated(r, state, at)) {
                layout::write_floats(&mut bytes, base, member, &floats)?;
            } else if let Some(values) = &given {
                layout::write_numbers(&mut bytes, base, member, &values[element as usize])?;
            } else {
                return Err(format!(
                    "the scene does not set storage member {}",
                    buffer.element(&member.name)
                ));
            }
        }
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use std::sync::Arc;

    use super::*;
    use crate::diagnostic::SourceFile;

    const SHADER: &str = r#"
struct Frame { clip_from_world: mat4x4<f32>, world_from_local: mat4x4<f32> }
struct Instance { world_from_local: mat4x4<f32>, color: vec4<f32> }
@group(0) @binding(0) var<uniform> frame: Frame;
@group(0) @binding(1) var<storage, read> instances: array<Instance>;
@vertex
fn vs_main(@location(0) p: vec3<f32>, @builtin(instance_index) i: u32) -> @builtin(position) vec4<f32> {
    return frame.clip_from_world * frame.world_from_local * instances[i].world_from_local * vec4<f32>(p, 1.0) + instances[i].color;
}
"#;

    fn module(text: &str) -> Module {
        naga::front::wgsl::parse_str(text).unwrap()
    }

    fn scene(text: &str) -> Scene {
        Scene::parse(Arc::new(SourceFile::new("s.toml", text)))
            .map_err(|e| e.render())
            .unwrap()
    }

    fn f32_at(bytes: &[u8], offset: usize) -> f32 {
        f32::from_le_bytes(bytes[offset..offset + 4].try_into().unwrap())
    }

    /// `array<Instance>` with a mat4 and a vec4: 80-byte stride, the
    /// colour 64 bytes in, as naga's layouter computes them.
    #[test]
    fn an_instance_array_is_laid_out_as_naga_lays_it() {
        let module = module(SHADER);
        let buffers = buffers(&module);
        assert_eq!(buffers.len(), 1);
        let buffer = &buffers[0];
        assert_eq!((buffer.group, buffer.binding), (0, 1));
        assert_eq!(buffer.elements, Elements::Runtime);
        assert_eq!(buffer.stride, 80);
        assert!(buffer.relative);
        let offsets: Vec<(&str, u32, Shape)> = buffer
            .members
            .iter()
            .map(|m| (m.name.as_str(), m.offset, m.shape))
            .collect();
        assert_eq!(
            offsets,
            [
                ("world_from_local", 0, Shape::Matrix(4, 4)),
                ("color", 64, Shape::F32(4))
            ]
        );
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).unwrap();
        let (instance, _) = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("Instance"))
            .unwrap();
        assert_eq!(layouter[instance].to_stride(), buffer.stride);
    }

    /// A vec3 member followed by a scalar, and a fixed-size array: the
    /// bytes land at naga's offsets, element after element.
    #[test]
    fn fill_writes_each_instance_at_its_stride() {
        let module = module(
            r#"
struct Item { tint: vec3<f32>, level: u32, world_from_local: mat4x4<f32> }
@group(0) @binding(0) var<storage, read> items: array<Item, 3>;
@vertex
fn vs_main(@builtin(instance_index) i: u32) -> @builtin(position) vec4<f32> {
    return items[i].world_from_local * vec4<f32>(items[i].tint, f32(items[i].level));
}
"#,
        );
        let buffers = buffers(&module);
        let buffer = &buffers[0];
        assert_eq!(buffer.elements, Elements::Fixed(3));
        assert_eq!(buffer.stride, 80);
        assert!(!buffer.relative);
        let text = "effects = [\"object-motion\"]\n[[objects]]\nmesh = { kind = \"cube\" }\nposition = [5.0, 0.0, 0.0]\ninstances = { count = 3, spacing = 2.0 }\n[storage.items]\ntint = [[1, 0, 0], [0, 1, 0], [0, 0, 1]]\nlevel = 7\n";
        let three = scene(text);
        check(&buffers, &three).map_err(|e| e.render()).unwrap();
        let state = three.frame(0, 1.0);
        let bytes = fill(buffer, &three, &state, 0).unwrap();
        assert_eq!(bytes.len(), 3 * 80);
        for element in 0..3 {
            let base = element * 80;
            assert_eq!(f32_at(&bytes, base + 4 * element), 1.0);
            assert_eq!(f32_at(&bytes, base + 4 * ((element + 1) % 3)), 0.0);
            assert_eq!(
                u32::from_le_bytes(bytes[base + 12..base + 16].try_into().unwrap()),
                7
            );
            // No uniform carries the object's transform: each element's is
            // the object's times the instance's, translation in column 3.
            let layout = three.objects[0].instances.as_ref().unwrap();
            let x = f32_at(&bytes, base + 16 + 48);
            assert_eq!(x, 5.0 + layout.position(element as u32).x);
        }

        // A u32 member takes integers.
        let half = scene(&text.replace("level = 7", "level = 7.5"));
        let err = check(&buffers, &half).unwrap_err().render();
        assert!(err.contains("7.5 is not a u32"), "{err}");

        // Two instances cannot fill an array of three.
        let two = scene(
            &text
                .replace("count = 3", "count = 2")
                .replace("[[1, 0, 0], [0, 1, 0], [0, 0, 1]]", "[1, 0, 0]"),
        );
        let err = check(&buffers, &two).unwrap_err().render();
        assert!(
            err.contains("holds 3 elements") && err.contains("draws 2"),
            "{err}"
        );
    }

    /// Bevy's mesh storage keeps each mesh's model matrix as a transposed
    /// affine (`mat3x4`, unpacked by `affine3_to_square`), last frame's
    /// beside it, and the normals' matrix packed into a `mat2x4` and an
    /// `f32`: unpacked as Bevy's shaders unpack them, they are the
    /// object's model matrix, last frame's, and its inverse transpose.
    #[test]
    fn bevys_packed_mesh_transforms_unpack_to_the_objects() {
        let module = module(
            r#"
struct Mesh {
    world_from_local: mat3x4<f32>,
    previous_world_from_local: mat3x4<f32>,
    local_from_world_transpose_a: mat2x4<f32>,
    local_from_world_transpose_b: f32,
    flags: u32,
}
@group(2) @binding(0) var<storage> mesh: array<Mesh>;
@vertex
fn vs_main(@builtin(instance_index) i: u32) -> @builtin(position) vec4<f32> {
    let m = mesh[i];
    return m.world_from_local[0] + m.previous_world_from_local[0] + m.local_from_world_transpose_a[0] * m.local_from_world_transpose_b;
}
"#,
        );
        let buffers = buffers(&module);
        let text = "effects = [\"object-motion\"]\n[[objects]]\nmesh = { kind = \"cube\" }\nposition = [1.0, 2.0, 3.0]\nrotation_degrees = [10.0, 30.0, 0.0]\nscale = 2.0\nrotation_degrees_per_frame = [0.0, 5.0, 0.0]\n[storage.mesh]\nflags = 0\n";
        let bevy = scene(text);
        check(&buffers, &bevy).map_err(|e| e.render()).unwrap();
        let state = bevy.frame(1, 1.0);
        let bytes = fill(&buffers[0], &bevy, &state, 0).unwrap();
        let column = |offset: usize| {
            glam::Vec4::from_array(std::array::from_fn(|r| f32_at(&bytes, offset + 4 * r)))
        };
        // `affine3_to_square`: the three columns are the matrix's rows.
        let square = |offset: usize| {
            glam::Mat4::from_cols(
                column(offset),
                column(offset + 16),
                column(offset + 32),
                glam::Vec4::W,
            )
            .transpose()
        };
        let close = |a: glam::Mat4, b: glam::Mat4| a.abs_diff_eq(b, 1e-5);
        assert!(close(square(0), state.objects[0]), "{}", square(0));
        let before = state.before().objects[0];
        assert!(close(square(48), before), "{}", square(48));
        assert!(!close(square(0), square(48)), "the object turned");
        // `mat2x4_f32_to_mat3x3_unpack`.
        let (a0, a1, b) = (column(96), column(112), f32_at(&bytes, 128));
        let normals = glam::Mat3::from_cols(
            a0.truncate(),
            glam::Vec3::new(a0.w, a1.x, a1.y),
            glam::Vec3::new(a1.z, a1.w, b),
        );
        let expected = glam::Mat3::from_mat4(state.objects[0])
            .inverse()
            .transpose();
        assert!(normals.abs_diff_eq(expected, 1e-5), "{normals} {expected}");
    }

    #[test]
    fn what_the_scene_does_not_give_is_an_error_naming_it() {
        let module = module(SHADER);
        let buffers = buffers(&module);
        let cube = "[[objects]]\nmesh = { kind = \"cube\" }\ninstances = 4\n";
        let err = |text: &str| check(&buffers, &scene(text)).unwrap_err().render();

        let missing = err(cube);
        assert!(missing.contains("`instances.color`"), "{missing}");
        assert!(missing.contains("[storage.instances]"), "{missing}");

        let short = err(&format!(
            "{cube}[storage.instances]\ncolor = [[1, 0, 0, 1], [0, 1, 0, 1]]\n"
        ));
        assert!(short.contains("lists 2 values for 4 instances"), "{short}");
        // It points at the value.
        assert!(short.contains("s.toml:5:"), "{short}");

        let typo = err(&format!(
            "{cube}[storage.instances]\ncolor = [1, 1, 1, 1]\ncolour = 1\n"
        ));
        assert!(
            typo.contains("`colour`") && typo.contains("s.toml:6:"),
            "{typo}"
        );

        let simulated = err(&format!(
            "{cube}[storage.instances]\ncolor = [1, 1, 1, 1]\nworld_from_local = 1\n"
        ));
        assert!(
            simulated.contains("filled by the simulation"),
            "{simulated}"
        );

        let scene = scene(&format!(
            "{cube}[storage.instances]\ncolor = {{ palette = \"rainbow\" }}\n"
        ));
        check(&buffers, &scene).unwrap();
        let bytes = fill(&buffers[0], &scene, &scene.frame(0, 1.0), 0).unwrap();
        assert_eq!(bytes.len(), 4 * 80);
        // Alpha 1 for each instance, distinct hues.
        assert!((0..4).all(|i| f32_at(&bytes, i * 80 + 76) == 1.0));
        assert_ne!(bytes[64..76], bytes[80 + 64..80 + 76]);
    }

    /// An object's own table sets its members over the scene's, so objects
    /// of different instance counts can each have a list.
    #[test]
    fn an_objects_own_values_come_before_the_scenes() {
        let module = module(SHADER);
        let buffers = buffers(&module);
        let objects = "[[objects]]\nmesh = { kind = \"plane\" }\n[[objects]]\nmesh = { kind = \"cube\" }\ninstances = 2\n";
        let own = "[objects.storage.instances]\ncolor = [[1, 0, 0, 1], [0, 0, 1, 1]]\n";
        let shared = "[storage.instances]\ncolor = [0.5, 0.5, 0.5, 1]\n";

        let both = scene(&format!("{objects}{own}{shared}"));
        check(&buffers, &both).unwrap();
        let state = both.frame(0, 1.0);
        let plane = fill(&buffers[0], &both, &state, 0).unwrap();
        let cubes = fill(&buffers[0], &both, &state, 1).unwrap();
        assert_eq!((plane.len(), cubes.len()), (80, 160));
        assert_eq!(f32_at(&plane, 64), 0.5);
        assert_eq!(
            (f32_at(&cubes, 64), f32_at(&cubes, 80 + 64 + 8)),
            (1.0, 1.0)
        );
        assert_eq!(f32_at(&cubes, 80 + 64), 0.0);

        // Without the scene's, the plane has no colour: said for it alone.
        let err = check(&buffers, &scene(&format!("{objects}{own}")))
            .unwrap_err()
            .render();
        assert!(err.contains("`instances.color` for object 0"), "{err}");
        assert!(err.contains("[objects.storage.instances]"), "{err}");

        // A shared list cannot fit both objects: the error says how to give
        // each its own.
        let err = check(
            &buffers,
            &scene(&format!(
                "{objects}[storage.instances]\ncolor = [[1, 0, 0, 1], [0, 0, 1, 1]]\n"
            )),
        )
        .unwrap_err()
        .render();
        assert!(err.contains("lists 2 values for 1 instance"), "{err}");
        assert!(err.contains("give object 0 its own"), "{err}");
    }
}
