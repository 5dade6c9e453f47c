//! The scene's side of a measured run: what every configuration draws.
//!
//! The textures the shader binds, the meshes laid out as its vertex
//! inputs, the list of what the scene gave a neutral value, and for each
//! frame the buffers (uniforms, storage, per-instance inputs) the
//! simulation fills. The reference and every variant draw the same
//! inputs; another stage that runs a shader over a scene (whole-frame
//! reuse) takes them from here too.

use std::collections::{HashMap, HashSet};
use std::path::Path;

use super::fail;
use crate::diagnostic::{Diagnostic, Error};
use crate::front::Shader;
use crate::plan::{self, Plan, VertexAttribute};
use crate::runtime::{self, FrameInputs, ObjectInputs};
use crate::scene::storage::StorageBuffer;
use crate::scene::textures::Texels;
use crate::scene::uniforms::UniformBuffer;
use crate::scene::{self, Scene};

/// What a scene gives a shader to draw.
pub(crate) struct SceneInputs<'a> {
    /// The shader's sampled textures by `[group, binding]`.
    pub textures: HashMap<[u32; 2], Texels>,
    /// Each object's mesh, laid out as the shader's per-vertex inputs.
    pub meshes: Vec<runtime::Mesh>,
    /// What nothing said the value of: the scene's neutral values and the
    /// vertex inputs fed a constant.
    pub defaulted: Vec<String>,
    scene_meshes: Vec<scene::Mesh>,
    /// The 2D depth textures that get a shadow map rendered from the
    /// light each frame.
    shadow_maps: Vec<[u32; 2]>,
    uniforms: &'a [UniformBuffer],
    storage: &'a [StorageBuffer],
    layout: &'a [VertexAttribute],
    size: [u32; 2],
}

impl<'a> SceneInputs<'a> {
    /// Loads what `scene` (read from `scene_path`) gives the shader the
    /// reference plan draws: every resource in `used` that is not a buffer
    /// must come from the scene; a vertex input it cannot feed is an error
    /// at the input.
    pub fn new(
        shader: &Shader,
        scene: &Scene,
        scene_path: &Path,
        reference_plan: &'a Plan,
        used: &HashSet<(String, [u32; 2])>,
        (uniforms, storage): (&'a [UniformBuffer], &'a [StorageBuffer]),
        size: [u32; 2],
    ) -> Result<SceneInputs<'a>, Error> {
        let dir = scene_path.parent().unwrap_or(Path::new("."));
        let mut textures = HashMap::new();
        let mut shadow_maps = Vec::new();
        for resource in &reference_plan.bindings.original {
            if !used.contains(&(resource.name.clone(), [resource.group, resource.binding])) {
                continue;
            }
            match resource.kind {
                kind if kind.sampled().is_some() || kind == plan::ResourceKind::UintTexture => {
                    let source = scene.textures.get(&resource.name).ok_or_else(|| {
                        fail(format!(
                            "the shader binds texture `{}` (group {}, binding {}) and the scene does not provide it: add [textures.{}]",
                            resource.name, resource.group, resource.binding, resource.name
                        ))
                    })?;
                    // A depth texture is made by the runtime, every texel at
                    // the far plane, and a 2D one can take a shadow map
                    // rendered from the light; RGBA texels cannot fill it.
                    let depth = kind.sampled().filter(|t| t.depth);
                    let flat = depth.is_some_and(|t| !t.cube && !t.arrayed);
                    if depth.is_some() && !(source.is_far() || (flat && source.is_shadow_map())) {
                        return Err(fail(format!(
                            "texture `{}` is a depth texture: the scene can only give it as `generate = \"far\"`{}",
                            resource.name,
                            if flat { " or `generate = \"shadow-map\"`" } else { " (shadow maps are rendered for 2D depth textures)" }
                        )));
                    }
                    if source.is_shadow_map() && !flat {
                        return Err(fail(format!(
                            "texture `{}` is not a 2D depth texture: `generate = \"shadow-map\"` is for one (a `texture_depth_2d`)",
                            resource.name
                        )));
                    }
                    if source.is_shadow_map() {
                        shadow_maps.push([resource.group, resource.binding]);
                    }
                    textures.insert(
                        [resource.group, resource.binding],
                        source.load(dir).map_err(fail)?,
                    );
                }
                plan::ResourceKind::StorageReadWrite => {
                    return Err(fail(format!(
                        "the shader binds read-write storage `{}` (group {}, binding {}): a scene provides read-only storage only (`var<storage, read>`)",
                        resource.name, resource.group, resource.binding
                    )))
                }
                plan::ResourceKind::StorageTexture => {
                    return Err(fail(format!(
                        "the shader binds storage texture `{}` (group {}, binding {}), which a scene cannot provide",
                        resource.name, resource.group, resource.binding
                    )))
                }
                _ => {}
            }
        }
        // What the scene defaulted, and the vertex inputs the mesh feeds a
        // constant. An input it cannot feed is an error at the input.
        let mut defaulted = scene.defaulted.clone();
        defaulted.extend(scene::uniforms::zeroed(uniforms));
        let skinned = scene.objects.iter().any(|object| object.skin.is_some());
        for attribute in &reference_plan.vertex_layout {
            let at_input = |message: String| {
                let text = &shader.file.text;
                let at = attribute_span(text, attribute.location, &attribute.name).unwrap_or(0..0);
                Error::in_file(
                    shader.file.clone(),
                    Diagnostic::error(message).with_label(at, "this vertex input"),
                )
            };
            let constant = match attribute.step {
                plan::StepMode::Vertex => {
                    scene::mesh::VertexSource::of(attribute, &scene.vertex_inputs)
                        .map_err(at_input)?
                        .defaulted(attribute, skinned)
                }
                plan::StepMode::Instance => scene::instance_inputs::InstanceSource::of(attribute)
                    .map_err(at_input)?
                    .defaulted(),
            };
            if let Some(value) = constant {
                defaulted.push(format!(
                    "vertex input @location({}) `{}` = {value}",
                    attribute.location, attribute.name
                ));
            }
        }
        let scene_meshes: Vec<scene::Mesh> = scene
            .objects
            .iter()
            .map(|object| Ok(object.mesh.build(dir)?.skinned(object.skin.as_ref())))
            .collect::<Result<_, String>>()
            .map_err(fail)?;
        let layout = &reference_plan.vertex_layout;
        let meshes: Vec<runtime::Mesh> = scene_meshes
            .iter()
            .map(|mesh| {
                Ok(runtime::Mesh {
                    vertices: mesh.vertex_bytes(layout, &scene.vertex_inputs)?,
                    indices: mesh.indices.clone(),
                })
            })
            .collect::<Result<_, String>>()
            .map_err(fail)?;
        super::watch::tell(super::watch::Step::Defaulted(&defaulted));
        Ok(SceneInputs {
            textures,
            meshes,
            defaulted,
            scene_meshes,
            shadow_maps,
            uniforms,
            storage,
            layout,
            size,
        })
    }

    /// The buffers every object draws with at `frame` of `scene` (the
    /// scene itself, or one with a single effect, for the miss causes).
    pub fn frame(&self, scene: &Scene, frame: u32) -> Result<FrameInputs, Error> {
        let (uniforms, storage, layout) = (self.uniforms, self.storage, self.layout);
        let scene_meshes = &self.scene_meshes;

        let state = scene.frame_sized(frame, self.size);
        let camera = &scene.camera;
        let mut inputs = FrameInputs {
            cut: state.cut(),
            depth_range: match camera.far {
                scene::Far::Distance(far) => Some((camera.near, far)),
                scene::Far::Infinity => None,
            },
            ..FrameInputs::default()
        };
        // Each mesh as this frame deforms it (`None`: as built), for its
        // vertices and for the shadow it casts.
        let deformed: Vec<Option<scene::Mesh>> = scene_meshes
            .iter()
            .enumerate()
            .map(|(object, mesh)| scene.deformed(object, mesh, frame))
            .collect();
        if !self.shadow_maps.is_empty() {
            // Skinned meshes cast the shadow of their pose.
            let posed: Vec<Option<scene::Mesh>> = scene_meshes
                .iter()
                .enumerate()
                .map(|(object, mesh)| scene.posed(object, mesh, &state))
                .collect();
            let casters: Vec<&scene::Mesh> = scene_meshes
                .iter()
                .zip(&deformed)
                .zip(&posed)
                .map(|((mesh, deformed), posed)| {
                    posed.as_ref().or(deformed.as_ref()).unwrap_or(mesh)
                })
                .collect();
            let map = std::sync::Arc::new(scene::shadow::render(&state, &casters));
            for &key in &self.shadow_maps {
                inputs.depth_maps.insert(key, map.clone());
            }
        }
        for (object, deformed) in deformed.iter().enumerate() {
            let mut buffers = HashMap::new();
            for buffer in uniforms {
                let bytes = scene::uniforms::fill(buffer, scene, &state, object).map_err(fail)?;
                buffers.insert([buffer.group, buffer.binding], bytes);
            }
            for buffer in storage {
                let bytes = scene::storage::fill(buffer, scene, &state, object).map_err(fail)?;
                buffers.insert([buffer.group, buffer.binding], bytes);
            }
            let vertices = deformed
                .as_ref()
                .map(|m| m.vertex_bytes(layout, &scene.vertex_inputs))
                .transpose()
                .map_err(fail)?;
            let worlds = state.instance_worlds(object);
            let instance_inputs =
                scene::instance_inputs::instance_inputs(layout, &worlds).map_err(fail)?;
            inputs.objects.push(ObjectInputs {
                mesh: object,
                buffers,
                vertices,
                instances: scene.objects[object].instance_count(),
                instance_inputs,
            });
        }
        Ok(inputs)
    }
}

/// Where vertex input `name` at `location` is declared: the first
/// `@location(N)` followed by the name. naga keeps no span for entry point
/// arguments and struct members; this only reads the text, to place a
/// label.
fn attribute_span(text: &str, location: u32, name: &str) -> Option<std::ops::Range<usize>> {
    let marker = format!("@location({location})");
    text.match_indices(&marker).find_map(|(at, _)| {
        let after = at + marker.len();
        let rest = &text[after..];
        let found = rest.find(name)?;
        // The name must come before the declaration ends.
        (!rest[..found].contains([',', ';', '{', '}']))
            .then(|| after + found..after + found + name.len())
    })
}
