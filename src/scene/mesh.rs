//! Meshes a scene draws: procedural shapes, or an OBJ or glTF file.

use std::f32::consts::{PI, TAU};
use std::path::Path;

use glam::{Vec2, Vec3};
use serde::Deserialize;

use super::skin::{Influence, Skin};

/// A triangle mesh with per-vertex position, normal and texture coordinate,
/// and, when skinned, each vertex's joints and weights.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Mesh {
    /// Each vertex's position, in the mesh's space.
    pub positions: Vec<Vec3>,
    /// Each vertex's unit normal.
    pub normals: Vec<Vec3>,
    /// Each vertex's texture coordinate.
    pub uvs: Vec<Vec2>,
    /// Three indices a triangle, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
    /// Per vertex, for a skinned object (`super::skin`); empty: every
    /// vertex follows joint 0 alone.
    pub influences: Vec<Influence>,
}

/// How a scene describes a mesh.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case", deny_unknown_fields)]
pub enum MeshSource {
    /// A UV sphere around the origin.
    Sphere {
        /// The radius.
        #[serde(default = "one")]
        radius: f32,
        /// Rings along the first parameter.
        #[serde(default = "rings")]
        rings: u32,
        /// Segments around.
        #[serde(default = "segments")]
        segments: u32,
    },
    /// A torus around the y axis.
    Torus {
        /// The radius.
        #[serde(default = "one")]
        radius: f32,
        /// The tube's radius.
        #[serde(default = "tube")]
        tube: f32,
        /// Rings along the first parameter.
        #[serde(default = "rings")]
        rings: u32,
        /// Segments around.
        #[serde(default = "segments")]
        segments: u32,
    },
    /// A square in the xz plane, facing +y.
    Plane {
        /// The edge length.
        #[serde(default = "one")]
        size: f32,
        /// Quads along each edge.
        #[serde(default = "subdivisions")]
        subdivisions: u32,
    },
    /// A height field in the xz plane: sums of sines, for terrain.
    Terrain {
        /// The edge length.
        #[serde(default = "one")]
        size: f32,
        /// Quads along each edge.
        #[serde(default = "subdivisions")]
        subdivisions: u32,
        /// The height field's amplitude.
        #[serde(default = "height")]
        height: f32,
    },
    /// A cube around the origin.
    Cube {
        /// The edge length.
        #[serde(default = "one")]
        size: f32,
    },
    /// A closed tube along x, centred on the origin: `rings` rings along
    /// its length (enough for a skin to bend it smoothly), `segments`
    /// around.
    Cylinder {
        /// The radius.
        #[serde(default = "half")]
        radius: f32,
        /// The length along x.
        #[serde(default = "two_units")]
        length: f32,
        /// Rings along the first parameter.
        #[serde(default = "rings")]
        rings: u32,
        /// Segments around.
        #[serde(default = "segments")]
        segments: u32,
    },
    /// One triangle, for a vertex stage that places its vertices from
    /// `@builtin(vertex_index)` (a fullscreen pass): indices 0, 1, 2; its
    /// vertex data are a triangle covering the view in clip space, which
    /// such a shader does not read.
    Fullscreen,
    /// A Wavefront OBJ file.
    Obj {
        /// Its path, relative to the scene file.
        file: String,
    },
    /// A glTF 2.0 file (`.gltf` with its buffers, or `.glb`), relative to
    /// the scene file: every triangle primitive of the default scene (or
    /// of the first), placed by its nodes' transforms.
    Gltf {
        /// Its path, relative to the scene file.
        file: String,
    },
}

fn one() -> f32 {
    1.0
}
fn tube() -> f32 {
    0.35
}
fn half() -> f32 {
    0.5
}
fn two_units() -> f32 {
    2.0
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
            MeshSource::Cylinder {
                radius,
                length,
                rings,
                segments,
            } => cylinder(radius, length, rings.max(1), segments.max(3)),
            MeshSource::Fullscreen => Mesh {
                positions: vec![
                    Vec3::new(-1.0, -1.0, 0.0),
                    Vec3::new(3.0, -1.0, 0.0),
                    Vec3::new(-1.0, 3.0, 0.0),
                ],
                normals: vec![Vec3::Z; 3],
                uvs: vec![
                    Vec2::new(0.0, 1.0),
                    Vec2::new(2.0, 1.0),
                    Vec2::new(0.0, -1.0),
                ],
                indices: vec![0, 1, 2],
                influences: Vec::new(),
            },
            MeshSource::Obj { ref file } => obj(&dir.join(file))?,
            MeshSource::Gltf { ref file } => gltf(&dir.join(file))?,
        })
    }
}

/// A tube along x with flat caps, each cap its own vertices (a hard edge).
fn cylinder(radius: f32, length: f32, rings: u32, segments: u32) -> Mesh {
    let mut mesh = grid(rings, segments, |u, v| {
        let a = TAU * v;
        let n = Vec3::new(0.0, a.cos(), a.sin());
        (Vec3::new((u - 0.5) * length, 0.0, 0.0) + n * radius, n)
    });
    for side in [-1.0f32, 1.0] {
        let x = side * length * 0.5;
        let normal = Vec3::new(side, 0.0, 0.0);
        let centre = mesh.positions.len() as u32;
        mesh.positions.push(Vec3::new(x, 0.0, 0.0));
        mesh.normals.push(normal);
        mesh.uvs.push(Vec2::splat(0.5));
        for k in 0..=segments {
            let a = TAU * k as f32 / segments as f32;
            mesh.positions
                .push(Vec3::new(x, a.cos() * radius, a.sin() * radius));
            mesh.normals.push(normal);
            mesh.uvs
                .push(Vec2::new(0.5 + 0.5 * a.cos(), 0.5 + 0.5 * a.sin()));
        }
        for k in 0..segments {
            let (a, b) = (centre + 1 + k, centre + 2 + k);
            // Counter-clockwise seen from outside the cap.
            if side > 0.0 {
                mesh.indices.extend([centre, a, b]);
            } else {
                mesh.indices.extend([centre, b, a]);
            }
        }
    }
    orient_outwards(&mut mesh);
    mesh
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
        // No normals in the file.
        face_normals(&mut mesh, 0);
    }
    if mesh.indices.is_empty() {
        return Err(format!("`{}` has no triangles", path.display()));
    }
    Ok(mesh)
}

/// Area-weighted face normals for the vertices from `first` on (a part
/// whose file gives none).
fn face_normals(mesh: &mut Mesh, first: usize) {
    for n in &mut mesh.normals[first..] {
        *n = Vec3::ZERO;
    }
    for tri in mesh.indices.chunks_exact(3) {
        let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| i as usize);
        if a < first {
            continue;
        }
        let face =
            (mesh.positions[b] - mesh.positions[a]).cross(mesh.positions[c] - mesh.positions[a]);
        for i in [a, b, c] {
            mesh.normals[i] += face;
        }
    }
    for n in &mut mesh.normals[first..] {
        *n = n.normalize_or_zero();
    }
}

/// A glTF 2.0 file: the triangles of every mesh of the default scene (the
/// first scene when none is marked), each vertex moved by its node's
/// world transform (normals by the inverse transpose). Buffers may be the
/// `.glb` blob, `data:` URIs, or files beside it. Textures and materials
/// are not read: the scene gives the shader's textures.
fn gltf(path: &Path) -> Result<Mesh, String> {
    use base64::Engine;
    let fail = |what: String| format!("cannot load `{}`: {what}", path.display());
    let bytes = std::fs::read(path).map_err(|err| fail(err.to_string()))?;
    let document = gltf::Gltf::from_slice(&bytes).map_err(|err| fail(err.to_string()))?;
    let dir = path.parent().unwrap_or(Path::new("."));
    let mut buffers = Vec::new();
    for buffer in document.buffers() {
        let data = match buffer.source() {
            gltf::buffer::Source::Bin => document
                .blob
                .clone()
                .ok_or_else(|| fail("a buffer refers to a binary chunk the file lacks".into()))?,
            gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                Some(data) => {
                    let (_, encoded) = data
                        .split_once(";base64,")
                        .ok_or_else(|| fail("a data URI that is not base64".into()))?;
                    base64::engine::general_purpose::STANDARD
                        .decode(encoded)
                        .map_err(|err| fail(format!("a data URI: {err}")))?
                }
                None => std::fs::read(dir.join(uri))
                    .map_err(|err| fail(format!("buffer `{uri}`: {err}")))?,
            },
        };
        if data.len() < buffer.length() {
            return Err(fail(format!(
                "buffer {} holds {} bytes, fewer than its declared {}",
                buffer.index(),
                data.len(),
                buffer.length()
            )));
        }
        buffers.push(data);
    }
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or_else(|| fail("the file has no scene".into()))?;

    let mut mesh = Mesh::default();
    let mut stack: Vec<(gltf::Node, glam::Mat4)> =
        scene.nodes().map(|n| (n, glam::Mat4::IDENTITY)).collect();
    while let Some((node, parent)) = stack.pop() {
        let world = parent * glam::Mat4::from_cols_array_2d(&node.transform().matrix());
        let normal_matrix = glam::Mat3::from_mat4(world).inverse().transpose();
        stack.extend(node.children().map(|child| (child, world)));
        let Some(node_mesh) = node.mesh() else {
            continue;
        };
        for primitive in node_mesh.primitives() {
            if primitive.mode() != gltf::mesh::Mode::Triangles {
                continue;
            }
            let reader = primitive.reader(|b| buffers.get(b.index()).map(Vec::as_slice));
            // The reader gives nothing for an accessor whose data does not
            // fit its buffer: that is an error, not a missing attribute.
            let unreadable = |what: &str| {
                fail(format!(
                    "the {what} of a primitive of mesh {} do not fit in its buffer",
                    node_mesh.index()
                ))
            };
            let declared = |semantic: gltf::Semantic| primitive.get(&semantic).is_some();
            let Some(positions) = reader.read_positions() else {
                if declared(gltf::Semantic::Positions) {
                    return Err(unreadable("positions"));
                }
                continue;
            };
            let first = mesh.positions.len();
            mesh.positions
                .extend(positions.map(|p| world.transform_point3(Vec3::from_array(p))));
            let count = mesh.positions.len() - first;
            let has_normals = match reader.read_normals() {
                Some(normals) => {
                    mesh.normals.extend(
                        normals.map(|n| (normal_matrix * Vec3::from_array(n)).normalize_or_zero()),
                    );
                    true
                }
                None if declared(gltf::Semantic::Normals) => return Err(unreadable("normals")),
                None => {
                    mesh.normals.resize(first + count, Vec3::ZERO);
                    false
                }
            };
            match reader.read_tex_coords(0) {
                Some(uvs) => mesh.uvs.extend(uvs.into_f32().map(Vec2::from_array)),
                None if declared(gltf::Semantic::TexCoords(0)) => {
                    return Err(unreadable("texture coordinates"))
                }
                None => mesh.uvs.resize(first + count, Vec2::ZERO),
            }
            if mesh.normals.len() != first + count || mesh.uvs.len() != first + count {
                return Err(fail(format!(
                    "a primitive of mesh {} has attributes of different lengths",
                    node_mesh.index()
                )));
            }
            let indices: Vec<u32> = match reader.read_indices() {
                Some(indices) => indices.into_u32().collect(),
                None if primitive.indices().is_some() => return Err(unreadable("indices")),
                None => (0..count as u32).collect(),
            };
            if let Some(bad) = indices.iter().find(|&&i| i as usize >= count) {
                return Err(fail(format!(
                    "a primitive of mesh {} indexes vertex {bad} of {count}",
                    node_mesh.index()
                )));
            }
            // A mirroring transform flips the winding; keep triangles
            // counter-clockwise from outside, as back-face culling expects.
            let mirrored = world.determinant() < 0.0;
            for tri in indices.chunks_exact(3) {
                let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| i + first as u32);
                mesh.indices
                    .extend(if mirrored { [a, c, b] } else { [a, b, c] });
            }
            if !has_normals {
                face_normals(&mut mesh, first);
            }
        }
    }
    if mesh.indices.is_empty() {
        return Err(fail("no triangles in its scene".into()));
    }
    Ok(mesh)
}

/// What feeds one vertex input of the shader.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum VertexSource {
    Position,
    Normal,
    /// Perpendicular to the normal, around the sphere's axis (w = 1).
    Tangent,
    Uv,
    /// A constant white: meshes carry no colours.
    Colour,
    /// A constant for an integer input (a packed colour all ones, anything
    /// else 0): a mesh has nothing to say about them.
    Integer,
    /// An integer position (wgpu's examples pack theirs as `vec4<i32>`):
    /// the mesh's, rounded (w = 1).
    IntegerPosition,
    /// An integer normal: the mesh's × 127, rounded, as a snorm8 packing
    /// gives it.
    IntegerNormal,
    /// The scene's constant for the input (`[vertex_inputs]`).
    Constant([f32; 4]),
    /// A skinned vertex's joint indices (integers; joint 0 for a mesh
    /// without a skin).
    JointIndices,
    /// A skinned vertex's joint weights (1, 0, 0, 0 without a skin).
    JointWeights,
}

impl VertexSource {
    /// What feeds `attribute`: by its name (`position`, `normal`,
    /// `tangent`, `uv`/`tex_coord`, `color`), else by the corpus's
    /// locations (0 position, 1 normal, 2 uv). Only float inputs can be
    /// fed; a wider input than the source is padded (w = 1 for points).
    pub fn of(
        attribute: &crate::plan::VertexAttribute,
        constants: &std::collections::BTreeMap<String, super::VertexConstant>,
    ) -> Result<VertexSource, String> {
        if let (Some(constant), true) = (
            constants.get(&attribute.name),
            attribute.format.is_float32(),
        ) {
            return Ok(VertexSource::Constant(constant.components()));
        }
        let name = attribute.name.to_ascii_lowercase();
        let has = |words: &[&str]| words.iter().any(|w| name.contains(w));
        // Engines' skinning inputs: Bevy's `joint_indices`, `joint_weights`,
        // glTF's JOINTS_0, WEIGHTS_0, others' bone indices and weights.
        if has(&["weight"]) && attribute.format.is_float32() {
            return Ok(VertexSource::JointWeights);
        }
        if has(&["joint", "bone"]) && !attribute.format.is_float() {
            return Ok(VertexSource::JointIndices);
        }
        let source = VertexSource::of_mesh(&attribute.name, attribute.location);
        let float = attribute.format.is_float32();
        let integer = !attribute.format.is_float();
        match source {
            Some(source) if float => Ok(source),
            Some(VertexSource::Position) if integer => Ok(VertexSource::IntegerPosition),
            Some(VertexSource::Normal) if integer => Ok(VertexSource::IntegerNormal),
            _ if integer => Ok(VertexSource::Integer),
            _ => Err(format!(
                "the scene's mesh cannot feed vertex input @location({}) `{}` ({}): it gives float inputs named like position, normal, tangent, uv (tex_coord) or color, or at locations 0 (position), 1 (normal) and 2 (uv); give it a constant in the scene, `[vertex_inputs]` `{} = 0.5`",
                attribute.location, attribute.name, attribute.format, attribute.name
            )),
        }
    }

    /// Which of the mesh's own attributes an input named `name` at
    /// `location` takes, whatever its format: by its name (`position`,
    /// `normal`, `tangent`, `uv`/`tex_coord`, `color`), else by the
    /// corpus's locations (0 position, 1 normal, 2 uv).
    pub fn of_mesh(name: &str, location: u32) -> Option<VertexSource> {
        let name = name.to_ascii_lowercase();
        let has = |words: &[&str]| words.iter().any(|w| name.contains(w));
        let by_name = if has(&["pos"]) {
            Some(VertexSource::Position)
        } else if has(&["norm"]) {
            Some(VertexSource::Normal)
        } else if has(&["tang"]) {
            Some(VertexSource::Tangent)
        } else if has(&["uv", "tex", "coord"]) {
            Some(VertexSource::Uv)
        } else if has(&["col"]) {
            Some(VertexSource::Colour)
        } else {
            None
        };
        by_name.or(match location {
            0 => Some(VertexSource::Position),
            1 => Some(VertexSource::Normal),
            2 => Some(VertexSource::Uv),
            _ => None,
        })
    }

    /// What feeds `attribute` when it is not the mesh's own values (a
    /// constant, or integers made from them), for the list of what was
    /// defaulted; `None` for the mesh's values as they are.
    /// `skinned` says whether any object of the scene has a skin: without
    /// one, joint inputs are the rigid default.
    pub fn defaulted(
        self,
        attribute: &crate::plan::VertexAttribute,
        skinned: bool,
    ) -> Option<&'static str> {
        match self {
            VertexSource::JointIndices | VertexSource::JointWeights if !skinned => {
                Some("joint 0 with weight 1 (no object has a `[objects.skin]`)")
            }
            VertexSource::Colour => Some("1.0 in every component"),
            VertexSource::IntegerPosition => {
                Some("the mesh's positions rounded to integers (w = 1)")
            }
            VertexSource::IntegerNormal => Some("the mesh's normals × 127, rounded"),
            VertexSource::Integer if packed_colour(attribute) => Some("0xffffffff (white)"),
            VertexSource::Integer => Some("0"),
            _ => None,
        }
    }
}

/// Whether an integer input is a packed colour (egui's `a_color: u32`).
fn packed_colour(attribute: &crate::plan::VertexAttribute) -> bool {
    attribute.name.to_ascii_lowercase().contains("col")
        && attribute.format == crate::plan::VertexFormat::Uint32
}

impl Mesh {
    /// Vertex bytes for the shader's per-vertex attributes, packed in
    /// `layout`'s order, each fed by its `VertexSource` (per-instance
    /// ones are `super::instance_inputs`'s).
    pub fn vertex_bytes(
        &self,
        layout: &[crate::plan::VertexAttribute],
        constants: &std::collections::BTreeMap<String, super::VertexConstant>,
    ) -> Result<Vec<u8>, String> {
        let sources: Vec<(VertexSource, usize, u32)> = layout
            .iter()
            .filter(|attribute| attribute.step == crate::plan::StepMode::Vertex)
            .map(|attribute| {
                let width = attribute.format.components() as usize;
                let word = if packed_colour(attribute) {
                    u32::MAX
                } else {
                    0
                };
                Ok((VertexSource::of(attribute, constants)?, width, word))
            })
            .collect::<Result<_, String>>()?;
        let mut bytes = Vec::new();
        for i in 0..self.positions.len() {
            let influence = self.influences.get(i).copied().unwrap_or(Influence::RIGID);
            for &(source, width, word) in &sources {
                let values: [f32; 4] = match source {
                    VertexSource::JointIndices => {
                        for joint in &influence.joints[..width.min(4)] {
                            bytes.extend(joint.to_le_bytes());
                        }
                        continue;
                    }
                    VertexSource::JointWeights => influence.weights,
                    VertexSource::Integer => {
                        for _ in 0..width.min(4) {
                            bytes.extend(word.to_le_bytes());
                        }
                        continue;
                    }
                    VertexSource::IntegerPosition | VertexSource::IntegerNormal => {
                        let (v, w, scale) = match source {
                            VertexSource::IntegerPosition => (self.positions[i], 1.0, 1.0),
                            _ => (self.normals[i], 0.0, 127.0),
                        };
                        for c in &(v * scale).extend(w).to_array()[..width.min(4)] {
                            bytes.extend((c.round() as i32).to_le_bytes());
                        }
                        continue;
                    }
                    VertexSource::Position => self.positions[i].extend(1.0).to_array(),
                    VertexSource::Normal => self.normals[i].extend(0.0).to_array(),
                    VertexSource::Tangent => {
                        let n = self.normals[i];
                        let t = Vec3::Y.cross(n);
                        let t = if t.length_squared() > 1e-8 {
                            t.normalize()
                        } else {
                            Vec3::X
                        };
                        t.extend(1.0).to_array()
                    }
                    VertexSource::Uv => [self.uvs[i].x, self.uvs[i].y, 0.0, 1.0],
                    VertexSource::Colour => [1.0; 4],
                    VertexSource::Constant(values) => values,
                };
                for v in &values[..width.min(4)] {
                    bytes.extend(v.to_le_bytes());
                }
            }
        }
        Ok(bytes)
    }

    /// How many triangles it has.
    pub fn triangles(&self) -> usize {
        self.indices.len() / 3
    }

    /// Paints `skin`'s weights on every vertex, where it lies.
    pub fn skinned(mut self, skin: Option<&Skin>) -> Mesh {
        if let Some(skin) = skin {
            self.influences = self.positions.iter().map(|&p| skin.influence(p)).collect();
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use base64::Engine;

    /// `mesh` as a glTF document: one buffer (positions, normals unless
    /// `normals` is false, uvs, u32 indices) given by `uri`, or inline as a
    /// data URI; one mesh under a parent node translated by `translation`
    /// with a child node scaled by `scale`.
    fn to_gltf(mesh: &Mesh, normals: bool, translation: Vec3, scale: f32) -> (String, Vec<u8>) {
        let mut data = Vec::new();
        let mut views = Vec::new();
        let mut accessors = Vec::new();
        let mut attributes = Vec::new();
        let mut push = |floats: Vec<f32>, kind: &str, name: &str, count: usize| {
            let offset = data.len();
            for f in &floats {
                data.extend(f.to_le_bytes());
            }
            views.push(format!(
                r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{}}}"#,
                floats.len() * 4
            ));
            let (min, max) = if name == "POSITION" {
                let lo = mesh.positions.iter().fold(Vec3::MAX, |a, &b| a.min(b));
                let hi = mesh.positions.iter().fold(Vec3::MIN, |a, &b| a.max(b));
                (
                    format!(r#","min":[{},{},{}]"#, lo.x, lo.y, lo.z),
                    format!(r#","max":[{},{},{}]"#, hi.x, hi.y, hi.z),
                )
            } else {
                (String::new(), String::new())
            };
            accessors.push(format!(
                r#"{{"bufferView":{},"componentType":5126,"count":{count},"type":"{kind}"{min}{max}}}"#,
                views.len() - 1
            ));
            attributes.push(format!(r#""{name}":{}"#, accessors.len() - 1));
        };
        let n = mesh.positions.len();
        push(
            mesh.positions.iter().flat_map(|p| p.to_array()).collect(),
            "VEC3",
            "POSITION",
            n,
        );
        if normals {
            push(
                mesh.normals.iter().flat_map(|p| p.to_array()).collect(),
                "VEC3",
                "NORMAL",
                n,
            );
        }
        push(
            mesh.uvs.iter().flat_map(|p| p.to_array()).collect(),
            "VEC2",
            "TEXCOORD_0",
            n,
        );
        let offset = data.len();
        for i in &mesh.indices {
            data.extend(i.to_le_bytes());
        }
        views.push(format!(
            r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{}}}"#,
            mesh.indices.len() * 4
        ));
        accessors.push(format!(
            r#"{{"bufferView":{},"componentType":5125,"count":{},"type":"SCALAR"}}"#,
            views.len() - 1,
            mesh.indices.len()
        ));
        let json = format!(
            r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
"nodes":[{{"translation":[{},{},{}],"children":[1]}},{{"scale":[{scale},{scale},{scale}],"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{{}}},"indices":{}}}]}}],
"accessors":[{}],"bufferViews":[{}],
"buffers":[{{"byteLength":{},"uri":"URI"}}]}}"#,
            translation.x,
            translation.y,
            translation.z,
            attributes.join(","),
            accessors.len() - 1,
            accessors.join(","),
            views.join(","),
            data.len()
        );
        (json, data)
    }

    /// Writes `name.gltf` with its buffer in `name.bin` beside it.
    fn write_with_side_buffer(dir: &Path, name: &str, json: &str, data: &[u8]) {
        std::fs::write(dir.join(format!("{name}.bin")), data).unwrap();
        std::fs::write(
            dir.join(format!("{name}.gltf")),
            json.replace("URI", &format!("{name}.bin")),
        )
        .unwrap();
    }

    fn load(dir: &Path, name: &str) -> Result<Mesh, String> {
        MeshSource::Gltf { file: name.into() }.build(dir)
    }

    #[test]
    fn a_gltf_cube_loads_placed_by_its_nodes() {
        let cube = cube(1.0);
        let (json, data) = to_gltf(&cube, true, Vec3::new(0.0, 1.0, 0.0), 2.0);
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64::engine::general_purpose::STANDARD.encode(&data)
        );
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("cube.gltf"), json.replace("URI", &uri)).unwrap();
        let loaded = load(dir.path(), "cube.gltf").unwrap();
        assert_eq!(loaded.indices, cube.indices);
        assert_eq!(loaded.uvs, cube.uvs);
        for (got, want) in loaded.positions.iter().zip(&cube.positions) {
            assert!(got.distance(*want * 2.0 + Vec3::Y) < 1e-6, "{got} {want}");
        }
        for (got, want) in loaded.normals.iter().zip(&cube.normals) {
            assert!(got.distance(*want) < 1e-6, "{got} {want}");
        }
    }

    /// A mirroring node (scale −1) flips the winding back, so triangles
    /// stay counter-clockwise seen from outside (back-face culling).
    #[test]
    fn a_mirroring_node_keeps_triangles_facing_outwards() {
        let (json, data) = to_gltf(&cube(1.0), true, Vec3::ZERO, -1.0);
        let dir = tempfile::tempdir().unwrap();
        write_with_side_buffer(dir.path(), "cube", &json, &data);
        let loaded = load(dir.path(), "cube.gltf").unwrap();
        for tri in loaded.indices.chunks(3) {
            let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| loaded.positions[i as usize]);
            let face = (b - a).cross(c - a);
            let centre = (a + b + c) / 3.0;
            assert!(face.dot(centre) > 0.0, "a triangle faces inwards");
            assert!(face.dot(loaded.normals[tri[0] as usize]) > 0.0);
        }
    }

    #[test]
    fn a_gltf_without_normals_gets_face_normals_from_a_side_file() {
        let cube = cube(1.0);
        let (json, data) = to_gltf(&cube, false, Vec3::ZERO, 1.0);
        let dir = tempfile::tempdir().unwrap();
        write_with_side_buffer(dir.path(), "cube", &json, &data);
        let loaded = load(dir.path(), "cube.gltf").unwrap();
        // The cube's faces have their own vertices: the face normals are
        // the cube's normals.
        for (got, want) in loaded.normals.iter().zip(&cube.normals) {
            assert!(got.distance(*want) < 1e-6, "{got} {want}");
        }
    }

    #[test]
    fn bad_gltf_files_are_errors_naming_them() {
        let dir = tempfile::tempdir().unwrap();
        let err = load(dir.path(), "missing.gltf").unwrap_err();
        assert!(err.contains("missing.gltf"), "{err}");
        std::fs::write(dir.path().join("junk.gltf"), "{ not json").unwrap();
        let err = load(dir.path(), "junk.gltf").unwrap_err();
        assert!(err.contains("junk.gltf"), "{err}");
        // An index past the vertices.
        let mut cube = cube(1.0);
        cube.indices[5] = 1000;
        let (json, data) = to_gltf(&cube, true, Vec3::ZERO, 1.0);
        write_with_side_buffer(dir.path(), "bad", &json, &data);
        let err = load(dir.path(), "bad.gltf").unwrap_err();
        assert!(err.contains("indexes vertex 1000"), "{err}");
        // Accessors reaching past their buffer views: an error naming
        // what does not fit, not a mesh without it.
        let (json, data) = to_gltf(&super::cube(1.0), true, Vec3::ZERO, 1.0);
        // The cube's accessors in order: positions, normals, uvs (24 each).
        for (nth, what) in [(0, "positions"), (1, "normals"), (2, "texture coordinates")] {
            let pieces: Vec<&str> = json.split("\"count\":24,").collect();
            assert_eq!(pieces.len(), 4);
            let mut long = String::new();
            for (i, piece) in pieces.iter().enumerate() {
                long.push_str(piece);
                if i + 1 < pieces.len() {
                    long.push_str(if i == nth {
                        "\"count\":100000,"
                    } else {
                        "\"count\":24,"
                    });
                }
            }
            write_with_side_buffer(dir.path(), "long", &long, &data);
            let err = load(dir.path(), "long.gltf").unwrap_err();
            assert!(
                err.contains(what) && err.contains("do not fit"),
                "{what}: {err}"
            );
        }
        // A buffer file shorter than declared.
        std::fs::write(dir.path().join("bad.bin"), &data[..10]).unwrap();
        let err = load(dir.path(), "bad.gltf").unwrap_err();
        assert!(err.contains("bad.gltf"), "{err}");
    }
}
