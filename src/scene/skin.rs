//! Skinned meshes: a chain of joints that bends the mesh, as engines
//! animate characters.
//!
//! Engines skin on the GPU. Each vertex carries up to four joint indices
//! and their weights; each frame the application writes every joint's
//! skinning matrix (the object's model matrix times the joint's pose) into
//! a uniform or storage array, and the vertex stage blends the matrices of
//! its joints: `p' = Σᵢ wᵢ · J[jᵢ] · p`. The cache needs last frame's
//! position of the vertex, which the rewrite computes with a twin of that
//! array holding last frame's matrices (as for any buffer the position
//! reads); the indices and weights do not change.
//!
//! A scene gives an object a [`Skin`]: `joints` joints in a chain that
//! starts at `root` and runs along `along`, each `segment` long. Joint 0
//! holds the first segment still (it moves with the object); each joint
//! after it bends about `axis` through its pivot by `bend_degrees` (plus
//! `bend_degrees_per_frame` a frame with `deformation`), relative to the
//! one before, so the chain curls as an arm or a tail does. A vertex
//! belongs to the segment it lies in, and blends with the neighbouring
//! joint within `blend` segments of a boundary: the weights a skinning
//! tool would paint.

use glam::{Mat4, Vec3};
use serde::Deserialize;

use super::Mesh;

/// An object's skeleton and how it moves.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Skin {
    /// How many joints the chain has (at least 1).
    #[serde(default = "two")]
    pub joints: u32,
    /// Where the chain starts, in the mesh's space.
    #[serde(default)]
    pub root: [f32; 3],
    /// The chain's direction, in the mesh's space.
    #[serde(default = "x_axis")]
    pub along: [f32; 3],
    /// Each joint's length along the chain.
    #[serde(default = "one")]
    pub segment: f32,
    /// What each joint bends about, in the mesh's space.
    #[serde(default = "z_axis")]
    pub axis: [f32; 3],
    /// Each joint's bend relative to the one before, at frame 0.
    #[serde(default)]
    pub bend_degrees: f32,
    /// With `deformation`: degrees a frame added to each joint's bend.
    #[serde(default)]
    pub bend_degrees_per_frame: f32,
    /// The width of the weights' ramp across a boundary between two
    /// joints, in segments (0: every vertex follows one joint).
    #[serde(default = "quarter")]
    pub blend: f32,
}

fn two() -> u32 {
    2
}
fn one() -> f32 {
    1.0
}
fn quarter() -> f32 {
    0.25
}
fn x_axis() -> [f32; 3] {
    [1.0, 0.0, 0.0]
}
fn z_axis() -> [f32; 3] {
    [0.0, 0.0, 1.0]
}

/// One vertex's joints and their weights (unused slots have weight 0).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Influence {
    pub joints: [u32; 4],
    pub weights: [f32; 4],
}

impl Influence {
    /// A vertex that follows joint 0 alone: an unskinned mesh drawn by a
    /// skinning shader (with one identity joint) stays where it is.
    pub const RIGID: Influence = Influence {
        joints: [0; 4],
        weights: [1.0, 0.0, 0.0, 0.0],
    };
}

impl Skin {
    /// Checks the values a scene gave; the message names the field.
    pub fn check(&self) -> Result<(), String> {
        let finite = |v: &[f32]| v.iter().all(|x| x.is_finite());
        if self.joints == 0 || self.joints > MAX_JOINTS {
            return Err(format!(
                "`skin.joints` is {}: a chain has 1 to {MAX_JOINTS} joints",
                self.joints
            ));
        }
        for (name, v) in [("along", self.along), ("axis", self.axis)] {
            if !finite(&v) || Vec3::from(v).length() < 1e-6 {
                return Err(format!("`skin.{name}` must be a non-zero direction"));
            }
        }
        if !finite(&self.root) {
            return Err("`skin.root` must be finite".into());
        }
        if !(self.segment.is_finite() && self.segment > 0.0) {
            return Err("`skin.segment` must be a positive length".into());
        }
        if !(self.blend.is_finite() && (0.0..=1.0).contains(&self.blend)) {
            return Err("`skin.blend` is a share of a segment, from 0 to 1".into());
        }
        if !(self.bend_degrees.is_finite() && self.bend_degrees_per_frame.is_finite()) {
            return Err("`skin.bend_degrees` and `bend_degrees_per_frame` must be finite".into());
        }
        Ok(())
    }

    fn along(&self) -> Vec3 {
        Vec3::from(self.along).normalize()
    }

    /// Joint `k`'s pivot, in the mesh's space.
    fn pivot(&self, k: u32) -> Vec3 {
        Vec3::from(self.root) + self.along() * (self.segment * k as f32)
    }

    /// Every joint's pose in the mesh's space after `frames` frames of
    /// bending (0 for a still skin): joint k turns the chain from its
    /// pivot on, on top of joint k − 1's pose.
    pub fn poses(&self, frames: f32) -> Vec<Mat4> {
        let angle = (self.bend_degrees + self.bend_degrees_per_frame * frames).to_radians();
        let axis = Vec3::from(self.axis).normalize();
        let mut poses = vec![Mat4::IDENTITY];
        for k in 1..self.joints {
            let pivot = self.pivot(k);
            let bend = Mat4::from_translation(pivot)
                * Mat4::from_axis_angle(axis, angle)
                * Mat4::from_translation(-pivot);
            let parent = poses[k as usize - 1];
            poses.push(parent * bend);
        }
        poses
    }

    /// The joints and weights of a vertex at `position` (mesh space).
    pub fn influence(&self, position: Vec3) -> Influence {
        let last = self.joints - 1;
        let s = (position - Vec3::from(self.root)).dot(self.along()) / self.segment;
        let joint = s.floor().clamp(0.0, last as f32) as u32;
        let half = self.blend * 0.5;
        // Within `half` of a boundary, blend with the joint across it.
        let (low, t) = if joint < last && s > (joint + 1) as f32 - half {
            (joint, (s - ((joint + 1) as f32 - half)) / self.blend)
        } else if joint > 0 && s < joint as f32 + half {
            (joint - 1, (s - (joint as f32 - half)) / self.blend)
        } else {
            return Influence {
                joints: [joint, 0, 0, 0],
                weights: [1.0, 0.0, 0.0, 0.0],
            };
        };
        let t = t.clamp(0.0, 1.0);
        let high = t * t * (3.0 - 2.0 * t);
        Influence {
            joints: [low, low + 1, 0, 0],
            weights: [1.0 - high, high, 0.0, 0.0],
        }
    }
}

/// The most joints a chain has: Bevy's skinned-mesh uniform holds 256.
pub const MAX_JOINTS: u32 = 256;

/// `mesh` posed by `poses` (mesh space), as a skinning vertex stage does:
/// each position and normal blended by its influence's joints. For what
/// the CPU needs of the posed mesh (silhouettes in tests, shadow casters).
pub fn pose(mesh: &Mesh, poses: &[Mat4]) -> Mesh {
    let mut out = mesh.clone();
    let joint = |j: u32| poses.get(j as usize).copied().unwrap_or(Mat4::IDENTITY);
    for (i, influence) in mesh.influences.iter().enumerate() {
        let blended = influence
            .joints
            .iter()
            .zip(influence.weights)
            .fold(Mat4::ZERO, |sum, (&j, w)| sum + joint(j) * w);
        out.positions[i] = blended.transform_point3(mesh.positions[i]);
        out.normals[i] = blended
            .transform_vector3(mesh.normals[i])
            .normalize_or_zero();
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn arm() -> Skin {
        Skin {
            joints: 2,
            root: [-1.0, 0.0, 0.0],
            along: [1.0, 0.0, 0.0],
            segment: 1.0,
            axis: [0.0, 0.0, 1.0],
            bend_degrees: 0.0,
            bend_degrees_per_frame: 90.0,
            blend: 0.5,
        }
    }

    /// Each vertex follows the joint of its segment; across a boundary the
    /// weights ramp from one joint to the next and always sum to 1.
    #[test]
    fn weights_follow_the_segments_and_sum_to_one() {
        let skin = arm();
        let at = |x: f32| skin.influence(Vec3::new(x, 0.3, 0.0));
        assert_eq!(
            at(-0.9),
            Influence {
                joints: [0, 0, 0, 0],
                weights: [1.0, 0.0, 0.0, 0.0]
            }
        );
        assert_eq!(at(0.9).joints[0], 1);
        assert_eq!(at(0.9).weights[0], 1.0);
        let middle = at(0.0);
        assert_eq!(middle.joints[..2], [0, 1]);
        assert!((middle.weights[0] - 0.5).abs() < 1e-6, "{middle:?}");
        for x in [-0.3, -0.2, 0.1, 0.24] {
            let w = at(x).weights;
            assert!((w.iter().sum::<f32>() - 1.0).abs() < 1e-6, "{x}: {w:?}");
        }
        assert!(at(-0.2).weights[1] < at(0.1).weights[1]);
    }

    /// The second joint turns what lies past its pivot about the axis by
    /// the bend; the first does not move.
    #[test]
    fn a_bent_joint_turns_the_chain_about_its_pivot() {
        let skin = arm();
        let poses = skin.poses(1.0);
        assert_eq!(poses[0], Mat4::IDENTITY);
        let tip = poses[1].transform_point3(Vec3::new(1.0, 0.0, 0.0));
        assert!((tip - Vec3::new(0.0, 1.0, 0.0)).length() < 1e-5, "{tip}");
        let mesh = Mesh {
            positions: vec![Vec3::new(-1.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0)],
            normals: vec![Vec3::Y; 2],
            uvs: vec![glam::Vec2::ZERO; 2],
            indices: vec![],
            influences: vec![
                skin.influence(Vec3::new(-1.0, 0.0, 0.0)),
                skin.influence(Vec3::new(1.0, 0.0, 0.0)),
            ],
        };
        let posed = pose(&mesh, &poses);
        assert_eq!(posed.positions[0], Vec3::new(-1.0, 0.0, 0.0));
        assert!((posed.positions[1] - Vec3::new(0.0, 1.0, 0.0)).length() < 1e-5);
        assert!((posed.normals[1] - Vec3::new(-1.0, 0.0, 0.0)).length() < 1e-5);
    }

    #[test]
    fn bad_skins_are_errors_naming_the_field() {
        let mut skin = arm();
        skin.joints = 0;
        assert!(skin.check().unwrap_err().contains("skin.joints"));
        let mut skin = arm();
        skin.along = [0.0; 3];
        assert!(skin.check().unwrap_err().contains("skin.along"));
        let mut skin = arm();
        skin.segment = -1.0;
        assert!(skin.check().unwrap_err().contains("skin.segment"));
    }
}
