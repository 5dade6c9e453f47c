//! Per-instance vertex inputs: what the simulation puts in the vertex
//! buffer that steps once per instance.
//!
//! The wgpu tutorials pass each instance's model matrix as four `vec4`
//! inputs (`model_matrix_0` … `model_matrix_3`, its columns) and its normal
//! matrix as three `vec3`; Bevy's instancing example passes a position and
//! scale (`i_pos_scale`) and a colour (`i_color`). An input is fed by its
//! name, like the mesh's inputs ([`super::mesh::VertexSource`]): a matrix
//! column by the trailing number of its name, a position, a colour
//! (a constant, listed as defaulted), an integer (0, listed). Which inputs
//! step per instance the plan says
//! ([`crate::proc::instance_locations`]).
//!
//! The transform they carry is the instance's whole world transform: the
//! object's placement times the instance's within it. A storage buffer's
//! `world_from_local` holds only the latter ([`super::storage`]), because
//! those shaders multiply the object's model uniform by it; a shader that
//! takes its model matrix as inputs has no other.

use glam::{Mat3, Mat4};

use crate::plan::{StepMode, VertexAttribute};

/// What feeds one per-instance vertex input.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InstanceSource {
    /// Column `n` of the instance's world transform (row `n` for a name
    /// that says `transpose`).
    Transform { index: usize, transposed: bool },
    /// Column `n` of the normal matrix: the inverse transpose of the
    /// transform's upper 3×3 (row `n` for `transpose`).
    NormalMatrix { index: usize, transposed: bool },
    /// The instance's world position (w = 1: a scale of 1 in Bevy's
    /// `i_pos_scale`).
    Position,
    /// A constant white.
    Colour,
    /// A constant 0 for an integer input.
    Integer,
}

impl InstanceSource {
    /// What feeds the per-instance input `attribute`, by its name; an
    /// error naming it when nothing the simulation has fits.
    pub fn of(attribute: &VertexAttribute) -> Result<InstanceSource, String> {
        let name = attribute.name.to_ascii_lowercase();
        let stem = name.trim_end_matches(|c: char| c.is_ascii_digit());
        let index: Option<usize> = name[stem.len()..].parse().ok();
        let has = |words: &[&str]| words.iter().any(|w| stem.contains(w));
        let transposed = has(&["transpose"]);
        let float = attribute.format.is_float32();
        let width = attribute.format.components() as usize;
        let cannot = |why: &str| {
            format!(
                "the simulation cannot feed per-instance vertex input @location({}) `{}` ({}): {why}",
                attribute.location, attribute.name, attribute.format
            )
        };
        if !float {
            return Ok(InstanceSource::Integer);
        }
        if has(&["normal"]) {
            return match index {
                Some(index) if index < 3 && width >= 3 => {
                    Ok(InstanceSource::NormalMatrix { index, transposed })
                }
                _ => Err(cannot(
                    "a normal matrix is fed as columns named with their index 0 to 2 (`normal_matrix_0`), each a vec3 or vec4",
                )),
            };
        }
        if has(&["model", "world", "transform", "matrix", "mat"]) {
            return match index {
                Some(index) if index < 4 && width == 4 => {
                    Ok(InstanceSource::Transform { index, transposed })
                }
                _ => Err(cannot(
                    "a model matrix is fed as four vec4 columns named with their index 0 to 3 (`model_matrix_0`)",
                )),
            };
        }
        if has(&["pos", "offset", "translation"]) {
            return Ok(InstanceSource::Position);
        }
        if has(&["col"]) {
            return Ok(InstanceSource::Colour);
        }
        Err(cannot(
            "it feeds model and normal matrix columns (`model_matrix_0`…`3`, `normal_matrix_0`…`2`), a position (`i_pos`, `offset`) or a colour (`color`)",
        ))
    }

    /// What feeds the input when it is a constant, for the list of what
    /// was defaulted; `None` for values the simulation moves.
    pub fn defaulted(self) -> Option<&'static str> {
        match self {
            InstanceSource::Colour => Some("1.0 in every component, for every instance"),
            InstanceSource::Integer => Some("0 for every instance"),
            _ => None,
        }
    }

    /// What feeds the input, in words.
    pub fn describe(self) -> String {
        let of = |transposed: bool| if transposed { "row" } else { "column" };
        match self {
            InstanceSource::Transform { index, transposed } => {
                format!("{} {index} of the instance's world transform", of(transposed))
            }
            InstanceSource::NormalMatrix { index, transposed } => format!(
                "{} {index} of the instance's normal matrix (inverse transpose of the transform's 3×3)",
                of(transposed)
            ),
            InstanceSource::Position => "the instance's world position (w = 1)".into(),
            InstanceSource::Colour => "white (defaulted)".into(),
            InstanceSource::Integer => "0 (defaulted)".into(),
        }
    }

    /// The input's value (up to four components) for an instance whose
    /// world transform is `world`.
    fn value(self, world: Mat4) -> [f32; 4] {
        let pick = |columns: [[f32; 4]; 4], index: usize, transposed: bool| {
            if transposed {
                [
                    columns[0][index],
                    columns[1][index],
                    columns[2][index],
                    columns[3][index],
                ]
            } else {
                columns[index]
            }
        };
        match self {
            InstanceSource::Transform { index, transposed } => {
                pick(world.to_cols_array_2d(), index, transposed)
            }
            InstanceSource::NormalMatrix { index, transposed } => {
                let normal = Mat3::from_mat4(world).inverse().transpose();
                let columns = Mat4::from_mat3(normal).to_cols_array_2d();
                let mut value = pick(columns, index, transposed);
                value[3] = 0.0;
                value
            }
            InstanceSource::Position => world.w_axis.to_array(),
            InstanceSource::Colour => [1.0; 4],
            InstanceSource::Integer => [0.0; 4],
        }
    }
}

/// This frame's per-instance input records, as the runtime takes them
/// ([`crate::runtime::ObjectInputs::instance_inputs`]): for each
/// instance's world transform in `worlds`, the layout's per-instance
/// inputs that are not twins, packed in order. Empty when the layout has
/// none.
pub fn instance_inputs(layout: &[VertexAttribute], worlds: &[Mat4]) -> Result<Vec<u8>, String> {
    let inputs: Vec<(InstanceSource, usize, bool)> = layout
        .iter()
        .filter(|a| a.step == StepMode::Instance && a.previous_of.is_none())
        .map(|a| {
            let float = a.format.is_float32();
            let width = a.format.components() as usize;
            Ok((InstanceSource::of(a)?, width, float))
        })
        .collect::<Result<_, String>>()?;
    let mut bytes = Vec::new();
    if inputs.is_empty() {
        return Ok(bytes);
    }
    for &world in worlds {
        for &(source, width, float) in &inputs {
            for &v in &source.value(world)[..width] {
                if float {
                    bytes.extend(v.to_le_bytes());
                } else {
                    bytes.extend((v as i32).to_le_bytes());
                }
            }
        }
    }
    Ok(bytes)
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;

    fn input(location: u32, name: &str, format: &str) -> VertexAttribute {
        VertexAttribute {
            location,
            name: name.into(),
            format: format.parse().unwrap(),
            step: StepMode::Instance,
            previous_of: None,
        }
    }

    #[test]
    fn tutorial_matrices_are_columns_of_the_transform() {
        let world = Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0))
            * Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0));
        let mut layout: Vec<VertexAttribute> = (0..4)
            .map(|i| input(5 + i, &format!("model_matrix_{i}"), "float32x4"))
            .collect();
        layout.extend((0..3).map(|i| input(9 + i, &format!("normal_matrix_{i}"), "float32x3")));
        // A twin and a per-vertex input are not in the records.
        layout.push(VertexAttribute {
            previous_of: Some(5),
            ..input(12, "previous_model_matrix_0", "float32x4")
        });
        layout.push(VertexAttribute {
            step: StepMode::Vertex,
            ..input(0, "position", "float32x3")
        });
        let bytes = instance_inputs(&layout, &[world]).unwrap();
        let floats: Vec<f32> = bytes
            .chunks(4)
            .map(|c| f32::from_le_bytes(c.try_into().unwrap()))
            .collect();
        assert_eq!(floats.len(), 16 + 9);
        assert_eq!(&floats[..16], &world.to_cols_array());
        // The normal matrix undoes the scale: x is halved.
        assert_eq!(&floats[16..19], &[0.5, 0.0, 0.0]);
        assert_eq!(&floats[19..25], &[0.0, 1.0, 0.0, 0.0, 0.0, 1.0]);
    }

    #[test]
    fn bevy_position_and_colour_are_fed() {
        let world = Mat4::from_translation(Vec3::new(4.0, 5.0, 6.0));
        let pos = InstanceSource::of(&input(3, "i_pos_scale", "float32x4")).unwrap();
        assert_eq!(pos, InstanceSource::Position);
        assert_eq!(pos.value(world), [4.0, 5.0, 6.0, 1.0]);
        let colour = InstanceSource::of(&input(4, "i_color", "float32x4")).unwrap();
        assert!(colour.defaulted().is_some());
    }

    #[test]
    fn inputs_the_simulation_cannot_feed_are_named() {
        for (name, format) in [
            ("bone_weight", "float32"),
            ("model_matrix", "float32x4"),
            ("model_matrix_4", "float32x4"),
            ("normal_matrix_3", "float32x3"),
        ] {
            let err = InstanceSource::of(&input(7, name, format)).unwrap_err();
            assert!(err.contains(&format!("@location(7) `{name}`")), "{err}");
        }
    }
}
