//! Filling the shader's uniform buffers from a scene, member by member.

use naga::Module;

use super::layout::{self, is_padding, Member, Shape};
use super::{FrameState, Scene};
use crate::analysis::range::UniformBounds;

/// A uniform buffer of the shader and where each member lives in it.
#[derive(Clone, Debug)]
pub struct UniformBuffer {
    pub group: u32,
    pub binding: u32,
    pub name: String,
    pub size: u32,
    pub members: Vec<Member>,
}

/// The shader's uniform buffers (group and binding set), with their members.
/// A uniform whose type is not a struct is one member named like the
/// variable.
pub fn buffers(module: &Module) -> Vec<UniformBuffer> {
    let mut out = Vec::new();
    for (_, global) in module.global_variables.iter() {
        let (Some(binding), naga::AddressSpace::Uniform) = (&global.binding, global.space) else {
            continue;
        };
        let name = global.name.clone().unwrap_or_default();
        let (size, members) = layout::members(module, global.ty, &name);
        out.push(UniformBuffer {
            group: binding.group,
            binding: binding.binding,
            name,
            size,
            members,
        });
    }
    out
}

/// Whether any uniform buffer has a member `name`.
pub fn has_member(buffers: &[UniformBuffer], name: &str) -> bool {
    buffers
        .iter()
        .any(|buffer| buffer.members.iter().any(|m| m.name == name))
}

/// Checks that the scene provides every member of every uniform buffer;
/// names all the missing ones at once.
pub fn check(buffers: &[UniformBuffer], scene: &Scene) -> Result<(), String> {
    let mut missing = Vec::new();
    for buffer in buffers {
        for member in &buffer.members {
            if is_padding(&member.name) || scene.role(&buffer.name, &member.name).is_some() {
                continue;
            }
            // A type a scene cannot write (an array of more than 64
            // elements: 256 lights, a cluster index) is zero, listed as
            // defaulted ([`zeroed`]).
            if member.shape == Shape::Other {
                if scene.uniforms.contains_key(&member.name) {
                    return Err(format!(
                        "uniform member `{}.{}` has a type a scene cannot write (f32, u32, i32, their vectors and f32 matrices, arrays of up to 64 of them); leave it out and it is zero",
                        buffer.name, member.name
                    ));
                }
                continue;
            }
            if !scene.uniforms.contains_key(&member.name) {
                missing.push(format!("`{}.{}`", buffer.name, member.name));
            }
        }
    }
    if missing.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "the scene does not set uniform member{} {}: add {} under [uniforms]",
            if missing.len() == 1 { "" } else { "s" },
            missing.join(", "),
            if missing.len() == 1 { "it" } else { "them" }
        ))
    }
}

/// The members of `buffers` a scene cannot write, which are zero: what
/// the report lists as defaulted.
pub fn zeroed(buffers: &[UniformBuffer]) -> Vec<String> {
    buffers
        .iter()
        .flat_map(|buffer| {
            buffer
                .members
                .iter()
                .filter(|m| m.shape == Shape::Other && !is_padding(&m.name))
                .map(move |m| {
                    format!(
                        "uniform `{}.{}` = zero (a type a scene cannot write)",
                        buffer.name, m.name
                    )
                })
        })
        .collect()
}

/// The bytes of `buffer` for frame `state` and object `object`.
pub fn fill(
    buffer: &UniformBuffer,
    scene: &Scene,
    state: &FrameState,
    object: usize,
) -> Result<Vec<u8>, String> {
    let mut bytes = vec![0u8; buffer.size as usize];
    for member in &buffer.members {
        if is_padding(&member.name) {
            continue;
        }
        if member.shape == Shape::Other {
            continue;
        }
        let role = scene.role(&buffer.name, &member.name);
        let at = layout::Placement {
            world_from_local: state.objects[object],
            previous_world_from_local: state.before().objects[object],
            object,
            element: layout::element_index(&member.name),
        };
        if let Some(floats) = role.and_then(|r| layout::simulated(r, state, at)) {
            layout::write_floats(&mut bytes, 0, member, &floats)?;
            continue;
        }
        let name = &member.name;
        let value = scene.uniform_at(name, state.frame).ok_or_else(|| {
            format!(
                "the scene does not set uniform member `{}.{name}`",
                buffer.name
            )
        })?;
        layout::write_value(&mut bytes, 0, member, value)
            .map_err(|err| format!("uniform `{name}`: {err}"))?;
    }
    Ok(bytes)
}

/// Every value the scene writes into `buffers`, for every object, over
/// frames `0..frames` and the first frame of each `[[uniform_changes]]`,
/// at `aspect`: the bounds the range analysis needs to tell whether a
/// payload computed from uniforms fits f16 in this scene.
pub fn bounds(
    buffers: &[UniformBuffer],
    scene: &Scene,
    aspect: f32,
    frames: u32,
) -> Result<UniformBounds, String> {
    let mut bounds = UniformBounds::default();
    // The frames of the run, and each frame a change of uniform values
    // starts at, which may lie past them.
    let changes = scene.uniform_changes.iter().map(|change| change.frame);
    for n in (0..frames).chain(changes.filter(|&frame| frame >= frames)) {
        let state = scene.frame(n, aspect);
        for object in 0..scene.objects.len() {
            for buffer in buffers {
                let bytes = fill(buffer, scene, &state, object)?;
                for (index, member) in buffer.members.iter().enumerate() {
                    let values = layout::read_numbers(&bytes, 0, member);
                    bounds.observe(buffer.group, buffer.binding, index as u32, &values);
                }
            }
        }
    }
    Ok(bounds)
}
