//! Filling the shader's uniform buffers from a scene, member by member.

use naga::{Module, TypeInner};

use super::{FrameState, Scene};
use crate::analysis::range::UniformBounds;

/// Members the simulation fills; every other member comes from the
/// scene's `[uniforms]`.
pub const SIMULATED: &[&str] = &[
    "clip_from_world",
    "world_from_local",
    "camera_position",
    "light_position",
    "light_clip_from_world",
    "time",
];

/// A uniform buffer of the shader and where each member lives in it.
#[derive(Clone, Debug)]
pub struct UniformBuffer {
    pub group: u32,
    pub binding: u32,
    pub name: String,
    pub size: u32,
    pub members: Vec<Member>,
}

#[derive(Clone, Debug)]
pub struct Member {
    pub name: String,
    pub offset: u32,
    pub shape: Shape,
}

/// The shapes a scene can write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    F32(u32),
    U32(u32),
    I32(u32),
    /// columns, rows (f32)
    Matrix(u32, u32),
    Other,
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
        let inner = &module.types[global.ty].inner;
        let (size, members) = match *inner {
            TypeInner::Struct { ref members, span } => (
                span,
                members
                    .iter()
                    .map(|m| Member {
                        name: m.name.clone().unwrap_or_default(),
                        offset: m.offset,
                        shape: shape(&module.types[m.ty].inner),
                    })
                    .collect(),
            ),
            ref other => (
                inner.size(module.to_ctx()),
                vec![Member {
                    name: name.clone(),
                    offset: 0,
                    shape: shape(other),
                }],
            ),
        };
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

fn shape(inner: &TypeInner) -> Shape {
    let count = |size: Option<naga::VectorSize>| size.map_or(1, |s| s as u32);
    match *inner {
        TypeInner::Scalar(s) => scalar_shape(s, 1),
        TypeInner::Vector { size, scalar } => scalar_shape(scalar, count(Some(size))),
        TypeInner::Matrix {
            columns,
            rows,
            scalar: naga::Scalar::F32,
        } => Shape::Matrix(columns as u32, rows as u32),
        _ => Shape::Other,
    }
}

fn scalar_shape(scalar: naga::Scalar, n: u32) -> Shape {
    match (scalar.kind, scalar.width) {
        (naga::ScalarKind::Float, 4) => Shape::F32(n),
        (naga::ScalarKind::Uint, 4) => Shape::U32(n),
        (naga::ScalarKind::Sint, 4) => Shape::I32(n),
        _ => Shape::Other,
    }
}

/// Checks that the scene provides every member of every uniform buffer;
/// names all the missing ones at once.
pub fn check(buffers: &[UniformBuffer], scene: &Scene) -> Result<(), String> {
    let mut missing = Vec::new();
    for buffer in buffers {
        for member in &buffer.members {
            if member.name.starts_with('_') || SIMULATED.contains(&member.name.as_str()) {
                continue;
            }
            if !scene.uniforms.contains_key(&member.name) {
                missing.push(format!("`{}.{}`", buffer.name, member.name));
            }
            if member.shape == Shape::Other {
                return Err(format!(
                    "uniform member `{}.{}` has a type a scene cannot write (f32, u32, i32, their vectors and f32 matrices are supported)",
                    buffer.name, member.name
                ));
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

/// The bytes of `buffer` for frame `state` and object `object`.
pub fn fill(
    buffer: &UniformBuffer,
    scene: &Scene,
    state: &FrameState,
    object: usize,
) -> Result<Vec<u8>, String> {
    let mut bytes = vec![0u8; buffer.size as usize];
    for member in &buffer.members {
        if member.name.starts_with('_') {
            continue;
        }
        let floats: Vec<f32> = match member.name.as_str() {
            "clip_from_world" => state.clip_from_world.to_cols_array().to_vec(),
            "world_from_local" => state.objects[object].to_cols_array().to_vec(),
            "light_clip_from_world" => state.light_clip_from_world.to_cols_array().to_vec(),
            "camera_position" => state.camera_position.to_array().to_vec(),
            "light_position" => state.light_position.to_array().to_vec(),
            "time" => vec![state.time],
            name => {
                let value = scene.uniforms.get(name).ok_or_else(|| {
                    format!(
                        "the scene does not set uniform member `{}.{name}`",
                        buffer.name
                    )
                })?;
                write_value(&mut bytes, member, value)
                    .map_err(|err| format!("uniform `{name}`: {err}"))?;
                continue;
            }
        };
        write_floats(&mut bytes, member, &floats)?;
    }
    Ok(bytes)
}

fn put(bytes: &mut [u8], offset: usize, word: [u8; 4]) {
    if let Some(slot) = bytes.get_mut(offset..offset + 4) {
        slot.copy_from_slice(&word);
    }
}

/// Bytes between a matrix's columns: WGSL aligns a column of three or four
/// f32 to 16 bytes, of two to 8.
fn column_stride(rows: u32) -> usize {
    if rows == 2 {
        8
    } else {
        16
    }
}

/// Writes f32s in the member's layout (matrix columns padded to 16 bytes
/// when they have three rows, as WGSL lays them out).
fn write_floats(bytes: &mut [u8], member: &Member, floats: &[f32]) -> Result<(), String> {
    let base = member.offset as usize;
    match member.shape {
        Shape::F32(n) => {
            for i in 0..n as usize {
                put(
                    bytes,
                    base + i * 4,
                    floats.get(i).copied().unwrap_or(0.0).to_le_bytes(),
                );
            }
        }
        Shape::Matrix(columns, rows) => {
            let stride = column_stride(rows);
            // Simulated matrices are 4×4; a smaller member takes its top-left.
            for c in 0..columns as usize {
                for r in 0..rows as usize {
                    let value = if floats.len() == 16 {
                        floats[c * 4 + r]
                    } else {
                        floats.get(c * rows as usize + r).copied().unwrap_or(0.0)
                    };
                    put(bytes, base + c * stride + r * 4, value.to_le_bytes());
                }
            }
        }
        _ => return Err(format!("`{}` is not a float member", member.name)),
    }
    Ok(())
}

fn write_value(bytes: &mut [u8], member: &Member, value: &toml::Value) -> Result<(), String> {
    // Flatten numbers, arrays and arrays of arrays (matrix columns).
    fn flatten(value: &toml::Value, out: &mut Vec<f64>) -> Result<(), String> {
        match value {
            toml::Value::Integer(i) => out.push(*i as f64),
            toml::Value::Float(f) => out.push(*f),
            toml::Value::Boolean(b) => out.push(if *b { 1.0 } else { 0.0 }),
            toml::Value::Array(items) => {
                for item in items {
                    flatten(item, out)?;
                }
            }
            other => {
                return Err(format!(
                    "expected a number or an array of numbers, found {}",
                    other.type_str()
                ))
            }
        }
        Ok(())
    }
    let mut numbers = Vec::new();
    flatten(value, &mut numbers)?;
    let expected = match member.shape {
        Shape::F32(n) | Shape::U32(n) | Shape::I32(n) => n,
        Shape::Matrix(c, r) => c * r,
        Shape::Other => 0,
    } as usize;
    if numbers.len() != expected {
        return Err(format!(
            "expected {expected} number(s), found {}",
            numbers.len()
        ));
    }
    let base = member.offset as usize;
    match member.shape {
        Shape::F32(_) | Shape::Matrix(..) => {
            let floats: Vec<f32> = numbers.iter().map(|&v| v as f32).collect();
            write_floats(bytes, member, &floats)?;
        }
        Shape::U32(_) => {
            for (i, v) in numbers.iter().enumerate() {
                if *v < 0.0 || v.fract() != 0.0 {
                    return Err(format!("{v} is not a u32"));
                }
                put(bytes, base + i * 4, (*v as u32).to_le_bytes());
            }
        }
        Shape::I32(_) => {
            for (i, v) in numbers.iter().enumerate() {
                if v.fract() != 0.0 {
                    return Err(format!("{v} is not an i32"));
                }
                put(bytes, base + i * 4, (*v as i32).to_le_bytes());
            }
        }
        Shape::Other => return Err("unsupported member type".into()),
    }
    Ok(())
}

/// Every value the scene writes into `buffers`, for every object, over
/// frames `0..frames` at `aspect`: the bounds the range analysis needs to
/// tell whether a payload computed from uniforms fits f16 in this scene.
pub fn bounds(
    buffers: &[UniformBuffer],
    scene: &Scene,
    aspect: f32,
    frames: u32,
) -> Result<UniformBounds, String> {
    let mut bounds = UniformBounds::default();
    for n in 0..frames {
        let state = scene.frame(n, aspect);
        for object in 0..scene.objects.len() {
            for buffer in buffers {
                let bytes = fill(buffer, scene, &state, object)?;
                for (index, member) in buffer.members.iter().enumerate() {
                    let values = read_member(&bytes, member);
                    bounds.observe(buffer.group, buffer.binding, index as u32, &values);
                }
            }
        }
    }
    Ok(bounds)
}

/// The numbers of `member` in `bytes`, as written by [`fill`] (padding
/// skipped); none for a shape a scene cannot write.
fn read_member(bytes: &[u8], member: &Member) -> Vec<f64> {
    let word = |at: usize| -> Option<[u8; 4]> { bytes.get(at..at + 4)?.try_into().ok() };
    let base = member.offset as usize;
    let at: Vec<usize> = match member.shape {
        Shape::F32(n) | Shape::U32(n) | Shape::I32(n) => {
            (0..n as usize).map(|i| base + i * 4).collect()
        }
        Shape::Matrix(columns, rows) => {
            let stride = column_stride(rows);
            (0..columns as usize)
                .flat_map(|c| (0..rows as usize).map(move |r| base + c * stride + r * 4))
                .collect()
        }
        Shape::Other => Vec::new(),
    };
    at.into_iter()
        .filter_map(word)
        .map(|w| match member.shape {
            Shape::U32(_) => f64::from(u32::from_le_bytes(w)),
            Shape::I32(_) => f64::from(i32::from_le_bytes(w)),
            _ => f64::from(f32::from_le_bytes(w)),
        })
        .collect()
}
