//! Meshes a scene draws: procedural shapes, or an OBJ file.

use std::f32::consts::{PI, TAU};
use std::path::Path;

use glam::{Vec2, Vec3};
use serde::Deserialize;

/// A triangle mesh with per-vertex position, normal and texture coordinate.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<u32>,
}

/// How a scene describes a mesh.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum MeshSource {
    Sphere {
        #[serde(default = "one")]
        radius: f32,
        #[serde(default = "rings")]
        rings: u32,
        #[serde(default = "segments")]
        segments: u32,
    },
    Torus {
        #[serde(default = "one")]
        radius: f32,
        #[serde(default = "tube")]
        tube: f32,
        #[serde(default = "rings")]
        rings: u32,
        #[serde(default = "segments")]
        segments: u32,
    },
    /// A square in the xz plane, facing +y.
    Plane {
        #[serde(default = "one")]
        size: f32,
        #[serde(default = "subdivisions")]
        subdivisions: u32,
    },
    /// A height field in the xz plane: sums of sines, for terrain.
    Terrain {
        #[serde(default = "one")]
        size: f32,
        #[serde(default = "subdivisions")]
        subdivisions: u32,
        #[serde(default = "height")]
        height: f32,
    },
    Cube {
        #[serde(default = "one")]
        size: f32,
    },
    /// A Wavefront OBJ file, relative to the scene file.
    Obj { file: String },
}

fn one() -> f32 {
    1.0
}
fn tube() -> f32 {
    0.35
}
fn rings() -> u32 {
    48
}
fn segments() -> u32 {
    96
}
fn subdivisions() -> u32 {
    32
}
fn height() -> f32 {
    0.15
}

impl MeshSource {
    /// Builds the mesh; `dir` resolves relative file names.
    pub fn build(&self, dir: &Path) -> Result<Mesh, String> {
        Ok(match *self {
            MeshSource::Sphere {
                radius,
                rings,
                segments,
            } => grid(rings.max(2), segments.max(3), |u, v| {
                let (theta, phi) = (PI * v, TAU * u);
                let n = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                (n * radius, n)
            }),
            MeshSource::Torus {
                radius,
                tube,
                rings,
                segments,
            } => grid(rings.max(3), segments.max(3), |u, v| {
                let (a, b) = (TAU * u, TAU * v);
                let center = Vec3::new(a.cos(), 0.0, a.sin()) * radius;
                let n = Vec3::new(a.cos() * b.cos(), b.sin(), a.sin() * b.cos());
                (center + n * tube, n)
            }),
            MeshSource::Plane { size, subdivisions } => {
                grid(subdivisions.max(1), subdivisions.max(1), |u, v| {
                    (Vec3::new((u - 0.5) * size, 0.0, (v - 0.5) * size), Vec3::Y)
                })
            }
            MeshSource::Terrain {
                size,
                subdivisions,
                height,
            } => {
                let h = |x: f32, z: f32| {
                    height * ((x * 7.0).sin() * (z * 5.0).cos() + 0.5 * (x * 13.0 + z * 11.0).sin())
                };
                grid(subdivisions.max(1), subdivisions.max(1), |u, v| {
                    let (x, z) = ((u - 0.5) * size, (v - 0.5) * size);
                    let e = 1e-3;
                    let dx = (h(x + e, z) - h(x - e, z)) / (2.0 * e);
                    let dz = (h(x, z + e) - h(x, z - e)) / (2.0 * e);
                    (
                        Vec3::new(x, h(x, z), z),
                        Vec3::new(-dx, 1.0, -dz).normalize(),
                    )
                })
            }
            MeshSource::Cube { size } => cube(size),
            MeshSource::Obj { ref file } => obj(&dir.join(file))?,
        })
    }
}

/// A (rings × segments)-quad grid over (u, v) in [0, 1]², mapped by `at`
/// to position and normal. Triangles wind counter-clockwise seen from
/// the side the normal points to.
fn grid(rings: u32, segments: u32, at: impl Fn(f32, f32) -> (Vec3, Vec3)) -> Mesh {
    let mut mesh = Mesh::default();
    for ring in 0..=rings {
        for segment in 0..=segments {
            let (u, v) = (segment as f32 / segments as f32, ring as f32 / rings as f32);
            let (p, n) = at(u, v);
            mesh.positions.push(p);
            mesh.normals.push(n);
            mesh.uvs.push(Vec2::new(u, v));
        }
    }
    let row = segments + 1;
    for ring in 0..rings {
        for segment in 0..segments {
            let a = ring * row + segment;
            let (b, c, d) = (a + 1, a + row, a + row + 1);
            mesh.indices.extend([a, b, c, b, d, c]);
        }
    }
    orient_outwards(&mut mesh);
    mesh
}

/// Flips triangles whose winding disagrees with their vertex normals, so
/// every generated shape is front-facing counter-clockwise from outside.
fn orient_outwards(mesh: &mut Mesh) {
    for tri in mesh.indices.chunks_mut(3) {
        let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| i as usize);
        let face =
            (mesh.positions[b] - mesh.positions[a]).cross(mesh.positions[c] - mesh.positions[a]);
        let normal = mesh.normals[a] + mesh.normals[b] + mesh.normals[c];
        if face.dot(normal) < 0.0 {
            tri.swap(1, 2);
        }
    }
}

fn cube(size: f32) -> Mesh {
    let mut mesh = Mesh::default();
    let h = size * 0.5;
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = Vec3::ZERO;
            n[axis] = sign;
            let (t, b) = (
                Vec3::new(n.y.abs() + n.z.abs(), n.x.abs(), 0.0).normalize(),
                Vec3::new(0.0, n.z.abs(), n.x.abs() + n.y.abs()).normalize(),
            );
            let base = mesh.positions.len() as u32;
            for (du, dv) in [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)] {
                mesh.positions.push((n + t * du + b * dv) * h);
                mesh.normals.push(n);
                mesh.uvs.push(Vec2::new((du + 1.0) * 0.5, (dv + 1.0) * 0.5));
            }
            mesh.indices
                .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    orient_outwards(&mut mesh);
    mesh
}

fn obj(path: &Path) -> Result<Mesh, String> {
    let (models, _) = tobj::load_obj(
        path,
        &tobj::LoadOptions {
            triangulate: true,
            single_index: true,
            ..tobj::LoadOptions::default()
        },
    )
    .map_err(|err| format!("cannot load `{}`: {err}", path.display()))?;
    let mut mesh = Mesh::default();
    for model in models {
        let m = model.mesh;
        let base = mesh.positions.len() as u32;
        let count = m.positions.len() / 3;
        for i in 0..count {
            mesh.positions
                .push(Vec3::from_slice(&m.positions[i * 3..i * 3 + 3]));
            mesh.normals.push(if m.normals.len() >= (i + 1) * 3 {
                Vec3::from_slice(&m.normals[i * 3..i * 3 + 3])
            } else {
                Vec3::ZERO
            });
            mesh.uvs.push(if m.texcoords.len() >= (i + 1) * 2 {
                Vec2::from_slice(&m.texcoords[i * 2..i * 2 + 2])
            } else {
                Vec2::ZERO
            });
        }
        mesh.indices.extend(m.indices.iter().map(|i| base + i));
    }
    if mesh.normals.iter().all(|n| *n == Vec3::ZERO) {
        // No normals in the file: area-weighted face normals.
        for tri in mesh.indices.chunks(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| i as usize);
            let face = (mesh.positions[b] - mesh.positions[a])
                .cross(mesh.positions[c] - mesh.positions[a]);
            for i in [a, b, c] {
                mesh.normals[i] += face;
            }
        }
        for n in &mut mesh.normals {
            *n = n.normalize_or_zero();
        }
    }
    if mesh.indices.is_empty() {
        return Err(format!("`{}` has no triangles", path.display()));
    }
    Ok(mesh)
}

impl Mesh {
    /// Vertex bytes for attributes at `locations` with `formats`: location 0
    /// is the position, 1 the normal, 2 the texture coordinate.
    pub fn vertex_bytes(&self, layout: &[crate::plan::VertexAttribute]) -> Result<Vec<u8>, String> {
        let mut bytes = Vec::new();
        for i in 0..self.positions.len() {
            for attribute in layout {
                let values: &[f32] = match (attribute.location, attribute.format.as_str()) {
                    (0, "float32x3") => &self.positions[i].to_array(),
                    (1, "float32x3") => &self.normals[i].to_array(),
                    (2, "float32x2") => &self.uvs[i].to_array(),
                    (location, format) => {
                        return Err(format!(
                            "a scene mesh provides @location(0) position: float32x3, @location(1) normal: float32x3 and @location(2) uv: float32x2; the shader reads @location({location}) `{}` as {format}",
                            attribute.name
                        ))
                    }
                };
                for v in values {
                    bytes.extend(v.to_le_bytes());
                }
            }
        }
        Ok(bytes)
    }

    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }
}
