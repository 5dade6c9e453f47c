//! Choosing the fragment entry point to analyse.

use crate::diagnostic::{Diagnostic, Error};
use crate::front::Shader;

/// Returns the index of the entry point to analyse: the one named `wanted`,
/// or the module's only fragment entry point.
pub fn fragment_entry(shader: &Shader, wanted: Option<&str>) -> Result<usize, Error> {
    let entries = &shader.module.entry_points;
    let path = &shader.file.path;
    let listing = || {
        let names: Vec<String> = entries
            .iter()
            .map(|ep| format!("`{}` ({})", ep.name, stage_name(ep.stage)))
            .collect();
        if names.is_empty() {
            "the shader has no entry points".to_string()
        } else {
            format!("entry points: {}", names.join(", "))
        }
    };
    let fail = |diagnostic: Diagnostic| Err(Error::in_file(shader.file.clone(), diagnostic));

    if let Some(name) = wanted {
        return match entries.iter().position(|ep| ep.name == name) {
            Some(index) if entries[index].stage == naga::ShaderStage::Fragment => Ok(index),
            Some(index) => fail(
                Diagnostic::error(format!(
                    "`{name}` in `{path}` is a {} entry point, not a fragment one",
                    stage_name(entries[index].stage)
                ))
                .with_note(listing()),
            ),
            None => fail(
                Diagnostic::error(format!("`{path}` has no entry point named `{name}`"))
                    .with_note(listing()),
            ),
        };
    }

    let fragments: Vec<usize> = entries
        .iter()
        .enumerate()
        .filter(|(_, ep)| ep.stage == naga::ShaderStage::Fragment)
        .map(|(index, _)| index)
        .collect();
    match fragments.as_slice() {
        [only] => Ok(*only),
        [] => fail(
            Diagnostic::error(format!("`{path}` has no fragment entry point"))
                .with_note(listing())
                .with_note("shadecache caches values of a `@fragment` function"),
        ),
        several => {
            let names: Vec<String> = several
                .iter()
                .map(|&i| format!("`{}`", entries[i].name))
                .collect();
            fail(
                Diagnostic::error(format!(
                    "`{path}` has {} fragment entry points: {}",
                    several.len(),
                    names.join(", ")
                ))
                .with_note("choose one with `--entry NAME`"),
            )
        }
    }
}

/// The fragment entry points a command takes in turn: the one named
/// `wanted` (checked by [`fragment_entry`] when it is used), else every
/// fragment entry point of the module, in order. `None` stands for "the
/// module's only one" and is the whole list when the module has at most
/// one, so a module without a fragment entry point still gets
/// [`fragment_entry`]'s error.
pub(super) fn fragment_entries_to_take(
    shader: &Shader,
    wanted: Option<&str>,
) -> Vec<Option<String>> {
    if let Some(name) = wanted {
        return vec![Some(name.to_string())];
    }
    let names: Vec<String> = shader
        .module
        .entry_points
        .iter()
        .filter(|ep| ep.stage == naga::ShaderStage::Fragment)
        .map(|ep| ep.name.clone())
        .collect();
    if names.len() <= 1 {
        vec![None]
    } else {
        names.into_iter().map(Some).collect()
    }
}

/// The WGSL attribute name of a shader stage (`vertex`, `fragment`,
/// `compute`...).
pub fn stage_name(stage: naga::ShaderStage) -> &'static str {
    match stage {
        naga::ShaderStage::Vertex => "vertex",
        naga::ShaderStage::Fragment => "fragment",
        naga::ShaderStage::Compute => "compute",
        naga::ShaderStage::Task => "task",
        naga::ShaderStage::Mesh => "mesh",
        naga::ShaderStage::RayGeneration
        | naga::ShaderStage::Miss
        | naga::ShaderStage::AnyHit
        | naga::ShaderStage::ClosestHit => "ray-tracing",
    }
}
