//! Checking a scene against a shader before a measured run: what the
//! draw binds and the scene fills, the frame counts, instancing.

use std::collections::HashSet;

use super::fail;
use crate::analysis::{self, Analysis};
use crate::diagnostic::Error;
use crate::front::Shader;
use crate::plan;
use crate::scene::storage::StorageBuffer;
use crate::scene::uniforms::UniformBuffer;
use crate::scene::{self, Scene};

/// What a shader binds on a scene, checked: the resources its draw binds,
/// the uniform and storage buffers the scene fills, and the analysis of
/// its fragment entry point bounded by the scene's values.
pub(crate) struct SceneBindings {
    pub aspect: f32,
    /// The name and (group, binding) of every resource the draw binds.
    pub used: HashSet<(String, [u32; 2])>,
    pub uniforms: Vec<UniformBuffer>,
    pub storage: Vec<StorageBuffer>,
    pub analysis: Analysis,
}

/// Checks `scene` against what `shader` reads (its fragment entry point
/// `entry` and the vertex entry point drawing with it), for `frames`
/// frames at `size`.
pub(crate) fn scene_bindings(
    shader: &Shader,
    scene: &Scene,
    (entry, vertex_entry): (Option<&str>, Option<&str>),
    size: [u32; 2],
    frames: u32,
) -> Result<SceneBindings, Error> {
    // The scene must provide every uniform the shader reads; the values it
    // gives bound the candidates' values (whether a payload fits f16 here).
    // What the draw binds: the resources of the fragment entry point and
    // of the vertex entry point drawing with it (a module may declare more).
    let used = used_bindings(shader, entry, vertex_entry)?;
    let mut uniforms = scene::uniforms::buffers(&shader.module);
    uniforms.retain(|b| used.contains(&(b.name.clone(), [b.group, b.binding])));
    let mut storage = scene::storage::buffers(&shader.module);
    storage.retain(|b| used.contains(&(b.name.clone(), [b.group, b.binding])));
    scene.check_names(&shader.module)?;
    scene::roles::check(&uniforms, &storage, scene)?;
    scene::uniforms::check(&uniforms, scene).map_err(fail)?;
    let mut analysis = analysis::analyze(
        shader,
        &analysis::Options {
            entry: entry.map(str::to_string),
            ..analysis::Options::default()
        },
    )?;
    let aspect = size[0] as f32 / size[1] as f32;
    analysis.bound_uniforms(
        shader,
        &scene::uniforms::bounds(&uniforms, scene, aspect, frames).map_err(fail)?,
    );
    Ok(SceneBindings {
        aspect,
        used,
        uniforms,
        storage,
        analysis,
    })
}

/// The frame size and counts asked of a run, within the bounds a scene's
/// own keep ([`scene::bounds`]): a library caller's options are checked as
/// the command line's are.
pub(crate) fn check_counts(size: [u32; 2], frames: u32, warmup: u32) -> Result<(), Error> {
    use scene::bounds::{MAX_FRAMES, MAX_SIZE};
    if size.iter().any(|&side| side == 0 || side > MAX_SIZE) {
        return Err(fail(format!(
            "size {}×{} is not between 1 and {MAX_SIZE} pixels a side",
            size[0], size[1]
        )));
    }
    if frames == 0 || frames > MAX_FRAMES {
        return Err(fail(format!(
            "{frames} frames: a run measures 1 to {MAX_FRAMES}"
        )));
    }
    if warmup > MAX_FRAMES {
        return Err(fail(format!(
            "{warmup} warm-up frames: at most {MAX_FRAMES}"
        )));
    }
    Ok(())
}

/// The name and (group, binding) of every resource the fragment entry
/// point chosen by `options` and its vertex entry point use.
fn used_bindings(
    shader: &Shader,
    entry: Option<&str>,
    vertex_entry: Option<&str>,
) -> Result<std::collections::HashSet<(String, [u32; 2])>, Error> {
    let module = &shader.module;
    let fragment = analysis::fragment_entry(shader, entry)?;
    let vertex = crate::proc::vertex_entry(module, fragment, vertex_entry).ok();
    let entries: Vec<usize> = std::iter::once(fragment).chain(vertex).collect();
    Ok(crate::proc::resources_used_by(module, &entries))
}

/// An object drawn as several instances needs a shader that tells them
/// apart: one that reads `@builtin(instance_index)` in its vertex stage,
/// or takes per-instance vertex inputs. Otherwise every instance would be
/// drawn at the same place.
pub(crate) fn check_instancing(
    shader: &Shader,
    scene: &Scene,
    layout: &[plan::VertexAttribute],
) -> Result<(), Error> {
    let Some((index, object)) = scene
        .objects
        .iter()
        .enumerate()
        .find(|(_, o)| o.instance_count() > 1)
    else {
        return Ok(());
    };
    let module = &shader.module;
    let reads_instance_index = module
        .entry_points
        .iter()
        .filter(|ep| ep.stage == naga::ShaderStage::Vertex)
        .flat_map(|ep| &ep.function.arguments)
        .any(|argument| {
            crate::proc::has_binding(module, &argument.binding, argument.ty, |b| {
                matches!(b, naga::Binding::BuiltIn(naga::BuiltIn::InstanceIndex))
            })
        });
    if reads_instance_index || layout.iter().any(|a| a.step == plan::StepMode::Instance) {
        return Ok(());
    }
    Err(scene.error(
        format!(
            "object {index} draws {} instances, and the shader's vertex stage neither reads @builtin(instance_index) nor takes per-instance inputs: every instance would be drawn at the same place",
            object.instance_count()
        ),
        None,
    ))
}
