//! IR → text: writing rewritten modules with naga's back ends.
//!
//! WGSL is the default and what the tests compile with naga, Tint and wgpu;
//! SPIR-V, GLSL, MSL and HLSL go through naga's other writers for engines
//! that consume those.

#![warn(missing_docs)]

use naga::valid::ModuleInfo;

/// An output language.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum Language {
    /// WGSL, as naga writes it back (what shadecache validates and runs).
    Wgsl,
    /// SPIR-V binary.
    Spv,
    /// GLSL 4.50 core.
    Glsl,
    /// Metal Shading Language.
    Msl,
    /// HLSL shader model 5.1.
    Hlsl,
}

/// One written file: its extension and bytes.
#[derive(Clone, Debug)]
pub struct Output {
    /// File name suffix after the pass name, e.g. `.wgsl` or `.vert.glsl`.
    pub suffix: String,
    /// The file's contents.
    pub bytes: Vec<u8>,
}

impl Language {
    /// The language's name on the command line (`wgsl`, `spv`...).
    pub fn as_str(self) -> &'static str {
        match self {
            Language::Wgsl => "wgsl",
            Language::Spv => "spv",
            Language::Glsl => "glsl",
            Language::Msl => "msl",
            Language::Hlsl => "hlsl",
        }
    }
}

/// Writes `module` in `language`. GLSL has one entry point per file, so it
/// gives one output per entry point.
/// A module as WGSL text.
pub fn wgsl_text(module: &naga::Module, info: &ModuleInfo) -> Result<String, String> {
    naga::back::wgsl::write_string(module, info, naga::back::wgsl::WriterFlags::empty())
        .map_err(|err| err.to_string())
}

/// Writes `module` in `language`: the file's contents, or naga's error in
/// words.
pub fn write(
    module: &naga::Module,
    info: &ModuleInfo,
    language: Language,
) -> Result<Vec<Output>, String> {
    match language {
        Language::Wgsl => {
            let text = wgsl_text(module, info)?;
            Ok(vec![Output {
                suffix: ".wgsl".into(),
                bytes: text.into_bytes(),
            }])
        }
        Language::Spv => {
            let words = naga::back::spv::write_vec(
                module,
                info,
                &naga::back::spv::Options::default(),
                None,
            )
            .map_err(|err| err.to_string())?;
            Ok(vec![Output {
                suffix: ".spv".into(),
                bytes: words.iter().flat_map(|w| w.to_le_bytes()).collect(),
            }])
        }
        Language::Msl => {
            let pipeline = naga::back::msl::PipelineOptions::default();
            // `[[invariant]]` positions need MSL 2.1.
            let options = naga::back::msl::Options {
                lang_version: (2, 1),
                ..naga::back::msl::Options::default()
            };
            let (text, _) = naga::back::msl::write_string(module, info, &options, &pipeline)
                .map_err(|err| err.to_string())?;
            Ok(vec![Output {
                suffix: ".metal".into(),
                bytes: text.into_bytes(),
            }])
        }
        Language::Hlsl => {
            let mut text = String::new();
            let options = naga::back::hlsl::Options::default();
            let pipeline = naga::back::hlsl::PipelineOptions::default();
            let mut writer = naga::back::hlsl::Writer::new(&mut text, &options, &pipeline);
            writer
                .write(module, info, None)
                .map_err(|err| err.to_string())?;
            Ok(vec![Output {
                suffix: ".hlsl".into(),
                bytes: text.into_bytes(),
            }])
        }
        Language::Glsl => {
            let mut outputs = Vec::new();
            for entry in &module.entry_points {
                let stage = match entry.stage {
                    naga::ShaderStage::Vertex => "vert",
                    naga::ShaderStage::Fragment => "frag",
                    _ => continue,
                };
                let options = naga::back::glsl::Options {
                    version: naga::back::glsl::Version::new_gles(310),
                    ..naga::back::glsl::Options::default()
                };
                let pipeline = naga::back::glsl::PipelineOptions {
                    shader_stage: entry.stage,
                    entry_point: entry.name.clone(),
                    multiview: None,
                };
                let mut text = String::new();
                let mut writer = naga::back::glsl::Writer::new(
                    &mut text,
                    module,
                    info,
                    &options,
                    &pipeline,
                    naga::proc::BoundsCheckPolicies::default(),
                )
                .map_err(|err| err.to_string())?;
                writer.write().map_err(|err| err.to_string())?;
                outputs.push(Output {
                    suffix: format!(".{stage}.glsl"),
                    bytes: text.into_bytes(),
                });
            }
            Ok(outputs)
        }
    }
}

/// Every shader file of a variant — its passes and the classify pass — as
/// (file name, contents), the names the plan gives them.
pub fn render_variant(
    rewritten: &crate::rewrite::Rewritten,
    language: Language,
) -> Result<Vec<(String, Vec<u8>)>, crate::diagnostic::Error> {
    use crate::diagnostic::{Diagnostic, Error};
    let mut files = Vec::new();
    for pass in rewritten.passes.iter().chain([&rewritten.classify]) {
        let outputs = write(&pass.module, &pass.info, language).map_err(|err| {
            Error::plain(Diagnostic::error(format!(
                "naga cannot write {} as {}: {err}",
                pass.name,
                language.as_str()
            )))
        })?;
        for output in outputs {
            files.push((format!("{}{}", pass.name, output.suffix), output.bytes));
        }
    }
    Ok(files)
}

/// Writes a variant into `dir`: one file per pass (per entry point for
/// GLSL) and `plan.json`. Each file is written beside its final name and
/// renamed into place, so a reader never sees half a file; if any cannot
/// be written, none is left.
pub fn write_variant(
    dir: &std::path::Path,
    rewritten: &crate::rewrite::Rewritten,
    language: Language,
) -> Result<Vec<std::path::PathBuf>, crate::diagnostic::Error> {
    use crate::diagnostic::{Diagnostic, Error};
    let io_error = |path: &std::path::Path, err: std::io::Error| {
        Error::plain(Diagnostic::error(format!(
            "cannot write `{}`: {err}",
            path.display()
        )))
    };
    // Render everything before touching the file system.
    let mut files = render_variant(rewritten, language)?;
    // The plan names the files written: `pass1.spv`, or for GLSL one per
    // stage.
    let mut named = rewritten.plan.clone();
    for pass in named.passes.iter_mut().chain(named.classify.as_mut()) {
        let own: Vec<String> = files
            .iter()
            .map(|(name, _)| name.clone())
            .filter(|name| {
                name.strip_prefix(pass.name.as_str())
                    .is_some_and(|rest| rest.starts_with('.'))
            })
            .collect();
        if let Some(first) = own.first() {
            pass.shader = first.clone();
        }
        pass.stage_shaders = if own.len() > 1 { own } else { Vec::new() };
    }
    let mut plan = serde_json::to_string_pretty(&named)
        .map_err(|err| Error::plain(Diagnostic::error(format!("cannot write the plan: {err}"))))?;
    plan.push('\n');
    files.push(("plan.json".into(), plan.into_bytes()));

    // All or nothing: every file is written beside its name first, then
    // each renamed into place. A failure removes what this call wrote
    // (the `.partial` files, the files renamed, the folder if it made
    // it), so that no variant folder is left without its plan.
    let made = !dir.exists();
    std::fs::create_dir_all(dir).map_err(|err| io_error(dir, err))?;
    let staged: Vec<(std::path::PathBuf, std::path::PathBuf)> = files
        .iter()
        .map(|(name, _)| (dir.join(format!(".{name}.partial")), dir.join(name)))
        .collect();
    let undo = |upto: usize, renamed: usize| {
        for (i, (partial, path)) in staged.iter().enumerate().take(upto) {
            let _ = std::fs::remove_file(if i < renamed { path } else { partial });
        }
        if made {
            let _ = std::fs::remove_dir(dir);
        }
    };
    for (i, ((partial, _), (_, bytes))) in staged.iter().zip(&files).enumerate() {
        if let Err(err) = std::fs::write(partial, bytes) {
            undo(i + 1, 0);
            return Err(io_error(partial, err));
        }
    }
    for (i, (partial, path)) in staged.iter().enumerate() {
        if let Err(err) = std::fs::rename(partial, path) {
            undo(staged.len(), i);
            return Err(io_error(path, err));
        }
    }
    let written: Vec<std::path::PathBuf> = staged.into_iter().map(|(_, path)| path).collect();
    Ok(written)
}
