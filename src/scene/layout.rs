//! Writing values into the bytes of a host-shareable WGSL type, as naga
//! lays it out: the members of a struct at their offsets, matrix columns
//! at their stride. Uniform buffers ([`super::uniforms`]) and storage
//! buffers ([`super::storage`]) are both filled through it.

use glam::Mat4;
use naga::{Handle, Module, Type, TypeInner};

use super::FrameState;

/// Members the simulation fills, by name; every other member comes from
/// the scene, or takes one of [`ROLES`] through the scene's `[roles]`.
pub const SIMULATED: &[&str] = &[
    "clip_from_world",
    "world_from_local",
    "camera_position",
    "light_position",
    "light_clip_from_world",
    "time",
    "resolution",
    "previous_clip_from_world",
    "previous_clip_from_view",
    "previous_view_from_world",
    "previous_world_from_local",
    "previous_clip_from_local",
    "local_from_world_transpose_a",
    "local_from_world_transpose_b",
];

/// What the simulation can fill: each role with the shapes of member it
/// fits and what it is.
pub const ROLES: &[(&str, &str)] = &[
    (
        "clip_from_world",
        "the camera's view-projection matrix (mat4x4<f32>)",
    ),
    (
        "clip_from_view",
        "the camera's projection matrix (mat4x4<f32>)",
    ),
    ("view_from_world", "the camera's view matrix (mat4x4<f32>)"),
    (
        "view_from_clip",
        "the inverse of the camera's projection (mat4x4<f32>)",
    ),
    (
        "world_from_local",
        "the object's (or instance's) model matrix (mat4x4<f32>)",
    ),
    (
        "clip_from_local",
        "view-projection times model (mat4x4<f32>)",
    ),
    (
        "light_clip_from_world",
        "the light's view-projection matrix (mat4x4<f32>)",
    ),
    (
        "camera_position",
        "the camera's world position (vec3<f32> or vec4<f32>, w = 1)",
    ),
    (
        "light_position",
        "the light's world position (vec3<f32> or vec4<f32>, w = 1)",
    ),
    ("time", "seconds since the first frame (f32)"),
    ("resolution", "the frame's size in pixels (vec2<f32>)"),
    (
        "previous_clip_from_world",
        "last frame's view-projection (mat4x4<f32>)",
    ),
    (
        "previous_clip_from_view",
        "last frame's projection (mat4x4<f32>)",
    ),
    (
        "previous_view_from_world",
        "last frame's view matrix (mat4x4<f32>)",
    ),
    (
        "previous_world_from_local",
        "the object's (or instance's) model matrix last frame (mat4x4<f32>), as engines keep it beside this frame's",
    ),
    (
        "previous_clip_from_local",
        "last frame's view-projection times model (mat4x4<f32>)",
    ),
    (
        "local_from_world_transpose_a",
        "the first eight numbers of the model matrix's inverse transpose (the normals' matrix), packed column by column as Bevy packs them (mat2x4<f32>)",
    ),
    (
        "local_from_world_transpose_b",
        "the ninth number of that packing (f32)",
    ),
    (
        "joint_matrices",
        "a skinned object's joints' matrices, element i the model matrix times joint i's pose (an array of mat4x4<f32>, uniform or storage)",
    ),
];

/// Names engines give their joint-matrix arrays (Bevy's `joint_matrices`,
/// others' `joints`, `bones`): they take `joint_matrices` by name.
const JOINT_ARRAYS: &[&str] = &["joints", "joint_matrices", "bones", "bone_matrices"];

/// The role a member takes by its own name (the last part of a flattened
/// one: `lights[0].light_position` takes `light_position`). `key` is the
/// member's `[roles]` key, its binding's name first where it has one: an
/// element of an array in a binding named for joints is a joint's,
/// whatever the array is called (Bevy's `joint_matrices.data[3]`).
pub fn implicit_role(key: &str) -> Option<&'static str> {
    let named_for_joints =
        |part: &str| JOINT_ARRAYS.contains(&part.split('[').next().unwrap_or(part));
    let last = key.rsplit('.').next().unwrap_or(key);
    // `joints`, `joints[3]` (a storage array's element, a uniform array's),
    // or any element of an array inside a binding named for joints.
    if named_for_joints(last) || (key.ends_with(']') && key.split('.').any(named_for_joints)) {
        return Some("joint_matrices");
    }
    SIMULATED.iter().copied().find(|s| *s == last)
}

/// The element a flattened member is of its innermost array: 3 for
/// `skin.joints[3]`, 0 for a member that is not an element.
pub fn element_index(member: &str) -> usize {
    member
        .rsplit_once('[')
        .and_then(|(_, rest)| rest.strip_suffix(']'))
        .and_then(|index| index.parse().ok())
        .unwrap_or(0)
}

/// Whether a member of `shape` can take `role`.
pub fn fits_role(role: &str, shape: Shape) -> bool {
    match role {
        "camera_position" | "light_position" => matches!(shape, Shape::F32(3 | 4)),
        "time" => shape == Shape::F32(1),
        "resolution" => shape == Shape::F32(2),
        "local_from_world_transpose_a" => shape == Shape::Matrix(2, 4),
        "local_from_world_transpose_b" => shape == Shape::F32(1),
        // A model matrix is affine: engines that pack it keep its top
        // three rows, as a `mat4x3` (column by column) or transposed, as a
        // `mat3x4` (Bevy's mesh storage, unpacked by `affine3_to_square`).
        "world_from_local" | "previous_world_from_local" => {
            matches!(shape, Shape::Matrix(4, 4 | 3) | Shape::Matrix(3, 4))
        }
        _ => shape == Shape::Matrix(4, 4),
    }
}

/// One member of a struct and where it lives in it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Member {
    pub name: String,
    /// Bytes from the start of the struct.
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

impl Shape {
    /// How many numbers a value of this shape has (0 for `Other`).
    pub fn components(self) -> usize {
        (match self {
            Shape::F32(n) | Shape::U32(n) | Shape::I32(n) => n,
            Shape::Matrix(columns, rows) => columns * rows,
            Shape::Other => 0,
        }) as usize
    }
}

/// The members of type `ty` and its size in bytes. A type that is not a
/// struct is one member at offset 0, named `name`. Nested structs and
/// fixed-size arrays are flattened into the members a scene can write,
/// named as WGSL reaches them: `material.base_color`, `lights[2].color`
/// (an array's elements at its stride).
pub fn members(module: &Module, ty: Handle<Type>, name: &str) -> (u32, Vec<Member>) {
    let size = module.types[ty].inner.size(module.to_ctx());
    let mut out = Vec::new();
    match module.types[ty].inner {
        TypeInner::Struct { ref members, .. } => {
            for m in members {
                let member = m.name.as_deref().unwrap_or_default();
                flatten(module, m.ty, member, m.offset, &mut out);
            }
        }
        _ => flatten(module, ty, name, 0, &mut out),
    }
    (size, out)
}

/// Arrays longer than this stay one member a scene cannot write, but for
/// arrays of matrices up to [`super::skin::MAX_JOINTS`] (Bevy's joint
/// matrices are 256).
const MAX_FLATTENED_ELEMENTS: u32 = 64;

fn flatten(module: &Module, ty: Handle<Type>, name: &str, offset: u32, out: &mut Vec<Member>) {
    match module.types[ty].inner {
        TypeInner::Struct { ref members, .. } => {
            for m in members {
                let member = m.name.as_deref().unwrap_or_default();
                let nested = format!("{name}.{member}");
                flatten(module, m.ty, &nested, offset + m.offset, out);
            }
        }
        TypeInner::Array {
            base,
            size: naga::ArraySize::Constant(n),
            stride,
        } if n.get() <= MAX_FLATTENED_ELEMENTS
            || (matches!(module.types[base].inner, TypeInner::Matrix { .. })
                && n.get() <= super::skin::MAX_JOINTS) =>
        {
            for i in 0..n.get() {
                let element = format!("{name}[{i}]");
                flatten(module, base, &element, offset + i * stride, out);
            }
        }
        ref inner => out.push(Member {
            name: name.to_string(),
            offset,
            shape: shape(inner),
        }),
    }
}

pub fn shape(inner: &TypeInner) -> Shape {
    match *inner {
        TypeInner::Scalar(s) => scalar_shape(s, 1),
        TypeInner::Vector { size, scalar } => scalar_shape(scalar, size as u32),
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

/// Where a simulated value is written: the draw's placement, its object,
/// and which element of an array (a joint's index).
#[derive(Clone, Copy, Debug)]
pub struct Placement {
    pub world_from_local: Mat4,
    /// The same placement in the frame before.
    pub previous_world_from_local: Mat4,
    pub object: usize,
    pub element: usize,
}

/// The value of a simulated member `name` in frame `state`, for a draw
/// placed by `world_from_local`; `None` when the simulation does not fill
/// `name`. `previous_<name>` is `<name>` in the frame before.
pub fn simulated(name: &str, state: &FrameState, at: Placement) -> Option<Vec<f32>> {
    if let Some(now) = name.strip_prefix("previous_") {
        let before = Placement {
            world_from_local: at.previous_world_from_local,
            ..at
        };
        return simulated(now, state.before(), before);
    }
    let world_from_local = at.world_from_local;
    Some(match name {
        "joint_matrices" => {
            let pose = state
                .joints
                .get(at.object)
                .and_then(|joints| joints.get(at.element))
                .copied()
                .unwrap_or(Mat4::IDENTITY);
            (world_from_local * pose).to_cols_array().to_vec()
        }
        "clip_from_world" => state.clip_from_world.to_cols_array().to_vec(),
        "clip_from_view" => state.clip_from_view.to_cols_array().to_vec(),
        "view_from_world" => state.view_from_world.to_cols_array().to_vec(),
        "view_from_clip" => state.clip_from_view.inverse().to_cols_array().to_vec(),
        "world_from_local" => world_from_local.to_cols_array().to_vec(),
        "local_from_world_transpose_a" | "local_from_world_transpose_b" => {
            let [x, y, z] = glam::Mat3::from_mat4(world_from_local)
                .inverse()
                .transpose()
                .to_cols_array_2d();
            if name.ends_with("_a") {
                vec![x[0], x[1], x[2], y[0], y[1], y[2], z[0], z[1]]
            } else {
                vec![z[2]]
            }
        }
        "clip_from_local" => (state.clip_from_world * world_from_local)
            .to_cols_array()
            .to_vec(),
        "light_clip_from_world" => state.light_clip_from_world.to_cols_array().to_vec(),
        // A vec4 member takes a point: w = 1 (a vec3 drops it).
        "camera_position" => state.camera_position.extend(1.0).to_array().to_vec(),
        "light_position" => state.light_position.extend(1.0).to_array().to_vec(),
        "time" => vec![state.time],
        "resolution" => state.resolution.to_array().to_vec(),
        _ => return None,
    })
}

/// Whether a member is padding, left zero.
pub fn is_padding(name: &str) -> bool {
    name.starts_with('_')
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

/// The numbers of `member` as [`write_floats`] and [`write_numbers`] lay
/// them out `base` bytes into `bytes` (padding skipped); none for a shape a
/// scene cannot write.
pub fn read_numbers(bytes: &[u8], base: usize, member: &Member) -> Vec<f64> {
    let word = |at: usize| -> Option<[u8; 4]> { bytes.get(at..at + 4)?.try_into().ok() };
    let base = base + member.offset as usize;
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

fn put(bytes: &mut [u8], offset: usize, word: [u8; 4]) {
    if let Some(slot) = bytes.get_mut(offset..offset + 4) {
        slot.copy_from_slice(&word);
    }
}

/// Writes f32s in the member's layout, `base` bytes into `bytes` (matrix
/// columns padded to 16 bytes when they have three rows, as WGSL lays them
/// out). A 16-float value given to a smaller matrix fills its top-left.
pub fn write_floats(
    bytes: &mut [u8],
    base: usize,
    member: &Member,
    floats: &[f32],
) -> Result<(), String> {
    let base = base + member.offset as usize;
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
            // Simulated matrices are 4×4; a smaller member takes its
            // top-left, but for a `mat3x4`: only an affine matrix fits one
            // (`fits_role`), transposed, its top three rows as columns (the
            // first three columns would drop its translation).
            let transposed = floats.len() == 16 && (columns, rows) == (3, 4);
            for c in 0..columns as usize {
                for r in 0..rows as usize {
                    let value = if transposed {
                        floats[r * 4 + c]
                    } else if floats.len() == 16 {
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

/// The numbers of a TOML value: a number, an array of numbers, or an array
/// of arrays (matrix columns), flattened in order.
pub fn numbers(value: &toml::Value) -> Result<Vec<f64>, String> {
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
    let mut out = Vec::new();
    flatten(value, &mut out)?;
    Ok(out)
}

/// Checks that `numbers` are one value of the member's shape: as many as
/// it has components, integers in range for integer members.
pub fn check_numbers(member: &Member, numbers: &[f64]) -> Result<(), String> {
    let expected = member.shape.components();
    if numbers.len() != expected {
        return Err(format!(
            "expected {expected} number(s), found {}",
            numbers.len()
        ));
    }
    let (integer, range, ty) = match member.shape {
        Shape::U32(_) => (true, (0.0, f64::from(u32::MAX)), "a u32"),
        Shape::I32(_) => (true, (f64::from(i32::MIN), f64::from(i32::MAX)), "an i32"),
        Shape::Other => return Err("unsupported member type".into()),
        _ => (false, (f64::MIN, f64::MAX), ""),
    };
    match numbers
        .iter()
        .find(|v| integer && (v.fract() != 0.0 || **v < range.0 || **v > range.1))
    {
        Some(v) => Err(format!("{v} is not {ty}")),
        None => Ok(()),
    }
}

/// Writes one value of the member's shape, given as its numbers, `base`
/// bytes into `bytes`, after [`check_numbers`].
pub fn write_numbers(
    bytes: &mut [u8],
    base: usize,
    member: &Member,
    numbers: &[f64],
) -> Result<(), String> {
    check_numbers(member, numbers)?;
    let at = base + member.offset as usize;
    match member.shape {
        Shape::U32(_) => {
            for (i, v) in numbers.iter().enumerate() {
                put(bytes, at + i * 4, (*v as u32).to_le_bytes());
            }
        }
        Shape::I32(_) => {
            for (i, v) in numbers.iter().enumerate() {
                put(bytes, at + i * 4, (*v as i32).to_le_bytes());
            }
        }
        _ => {
            let floats: Vec<f32> = numbers.iter().map(|&v| v as f32).collect();
            write_floats(bytes, base, member, &floats)?;
        }
    }
    Ok(())
}

/// Writes a TOML value in the member's shape, `base` bytes into `bytes`.
pub fn write_value(
    bytes: &mut [u8],
    base: usize,
    member: &Member,
    value: &toml::Value,
) -> Result<(), String> {
    write_numbers(bytes, base, member, &numbers(value)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bevy's skinned-mesh uniform, `var<uniform> joint_matrices:
    /// SkinnedMesh` with `data: array<mat4x4<f32>, 256u>`: every element is
    /// a member the simulation fills, and each takes `joint_matrices` by the
    /// binding's name; a storage array named `joints` by its own; other
    /// matrices keep theirs.
    #[test]
    fn bevys_joint_matrices_take_the_joint_role() {
        let module = naga::front::wgsl::parse_str(
            "struct SkinnedMesh { data: array<mat4x4<f32>, 256u> }
             @group(2) @binding(1) var<uniform> joint_matrices: SkinnedMesh;",
        )
        .unwrap();
        let (_, skin) = members(
            &module,
            module.global_variables.iter().next().unwrap().1.ty,
            "joint_matrices",
        );
        assert_eq!(skin.len(), 256);
        assert_eq!(skin[255].name, "data[255]");
        assert_eq!(skin[255].offset, 255 * 64);
        assert_eq!(
            implicit_role("joint_matrices.data[255]"),
            Some("joint_matrices")
        );
        assert_eq!(element_index("data[255]"), 255);
        assert_eq!(implicit_role("joints"), Some("joint_matrices"));
        assert_eq!(implicit_role("bones[3]"), Some("joint_matrices"));
        assert_eq!(implicit_role("joint_matrices.count"), None);
        assert_eq!(
            implicit_role("view.clip_from_world"),
            Some("clip_from_world")
        );
    }

    #[test]
    fn nested_structs_and_arrays_are_members_named_as_wgsl_reaches_them() {
        let module = naga::front::wgsl::parse_str(
            "struct Light { view_proj: mat4x4<f32>, color: vec4<f32> }
             struct Lights { count: u32, items: array<Light, 2>, weights: array<vec4<f32>, 2> }
             @group(0) @binding(0) var<uniform> lights: Lights;
             @group(0) @binding(1) var<uniform> plain: array<Light, 2>;",
        )
        .unwrap();
        let ty = |name: &str| {
            module
                .global_variables
                .iter()
                .find(|(_, g)| g.name.as_deref() == Some(name))
                .unwrap()
                .1
                .ty
        };
        let (size, flattened) = members(&module, ty("lights"), "lights");
        let named: Vec<(&str, u32, Shape)> = flattened
            .iter()
            .map(|m| (m.name.as_str(), m.offset, m.shape))
            .collect();
        assert_eq!(
            named,
            [
                ("count", 0, Shape::U32(1)),
                ("items[0].view_proj", 16, Shape::Matrix(4, 4)),
                ("items[0].color", 80, Shape::F32(4)),
                ("items[1].view_proj", 96, Shape::Matrix(4, 4)),
                ("items[1].color", 160, Shape::F32(4)),
                ("weights[0]", 176, Shape::F32(4)),
                ("weights[1]", 192, Shape::F32(4)),
            ]
        );
        assert_eq!(size, 208);
        let (_, plain) = members(&module, ty("plain"), "plain");
        assert_eq!(plain[2].name, "plain[1].view_proj");
        assert_eq!(
            implicit_role("items[0].clip_from_world"),
            Some("clip_from_world")
        );
    }
}
