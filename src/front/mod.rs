//! WGSL → IR: reading a shader file, parsing it with naga's WGSL front end and
//! validating it with every validation flag and capability.
//!
//! Everything downstream works on a [`Shader`]: the source text (kept for
//! spans, ids and diagnostics), the naga [`Module`](naga::Module) and the
//! [`ModuleInfo`] validation produced (expression
//! types, uniformity, reference counts). A shader that reaches the later
//! stages is known to be valid WGSL as far as naga can tell.
//!
//! Failures are [`Error`]s with a codespan diagnostic: a missing file, a
//! directory, bytes that are not UTF-8 (pointing at the first bad byte), a
//! parse error or a validation error (pointing at naga's spans).

#![warn(missing_docs)]

pub mod compose;
#[cfg(feature = "wesl")]
pub mod crate_package;
pub mod vertex;
#[cfg(feature = "wesl")]
pub mod wesl;

use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::Path;
use std::sync::Arc;

use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};

use crate::diagnostic::{Diagnostic, Error, SourceFile};

/// A parsed and validated WGSL shader.
#[derive(Debug)]
pub struct Shader {
    /// The source the module was parsed from (for diagnostics and node text).
    pub file: Arc<SourceFile>,
    /// The module, as naga's WGSL front end made it (composed, when it was).
    pub module: naga::Module,
    /// naga's validation of it (all checks on).
    pub info: ModuleInfo,
    /// The separate module the vertex stage came from
    /// ([`with_vertex_module`]); `None` when `file` has the whole module.
    pub vertex_file: Option<Arc<SourceFile>>,
    /// The defs its composed sources test, with the values they were
    /// composed with (the plan's `shader_defs`); empty when it was not
    /// composed.
    pub defs: Vec<crate::plan::ShaderDef>,
}

impl Shader {
    /// A copy: the same file, module and validation.
    pub fn clone_parts(&self) -> Shader {
        Shader {
            file: self.file.clone(),
            module: self.module.clone(),
            info: self.info.clone(),
            vertex_file: self.vertex_file.clone(),
            defs: self.defs.clone(),
        }
    }
}

/// Reads, parses and validates the shader at `path`.
pub fn load(path: &Path) -> Result<Shader, Error> {
    let file = read_source(path)?;
    parse(file)
}

/// Reads a WGSL file as UTF-8 text.
pub fn read_source(path: &Path) -> Result<SourceFile, Error> {
    read_text(path, TextKind::Wgsl)
}

/// What a text file read by [`read_text`] is, for its messages.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextKind {
    /// A WGSL shader or module.
    Wgsl,
    /// A scene (TOML).
    Scene,
    /// Cost weights (JSON).
    Weights,
}

impl TextKind {
    fn what(self) -> &'static str {
        match self {
            TextKind::Wgsl => "the shader",
            TextKind::Scene => "the scene",
            TextKind::Weights => "the cost weights file",
        }
    }

    fn expected(self) -> &'static str {
        match self {
            TextKind::Wgsl => "a .wgsl file",
            TextKind::Scene => "a scene's .toml file",
            TextKind::Weights => "a .json file of cost weights",
        }
    }
}

/// Reads a text file of kind `kind` as UTF-8. A leading byte-order mark
/// (editors on Windows write one) is dropped: it is no part of the text,
/// and WGSL, TOML and JSON parsers take it for a stray character.
pub fn read_text(path: &Path, kind: TextKind) -> Result<SourceFile, Error> {
    let shown = path.display().to_string();
    if path.is_dir() {
        return Err(Error::plain(
            Diagnostic::error(format!("`{shown}` is a directory, not {}", kind.expected()))
                .with_note(format!("give the path of {}", kind.expected())),
        ));
    }
    let bytes = std::fs::read(path).map_err(|err| {
        let reason = match err.kind() {
            std::io::ErrorKind::NotFound => "no such file".to_string(),
            std::io::ErrorKind::PermissionDenied => "permission denied".to_string(),
            _ => err.to_string(),
        };
        Error::plain(Diagnostic::error(format!(
            "cannot read `{shown}`: {reason}"
        )))
    })?;
    let bytes = match bytes.strip_prefix(b"\xEF\xBB\xBF") {
        Some(rest) => rest.to_vec(),
        None => bytes,
    };
    match String::from_utf8(bytes) {
        Ok(text) => Ok(SourceFile::new(shown, text)),
        Err(err) => {
            let valid_up_to = err.utf8_error().valid_up_to();
            let bad_len = err.utf8_error().error_len().unwrap_or(1);
            let text = String::from_utf8_lossy(err.as_bytes()).into_owned();
            let file = Arc::new(SourceFile::new(shown, text));
            // Lossy decoding keeps every byte before the first bad sequence
            // where it was, and puts U+FFFD (3 bytes) in its place.
            let range = valid_up_to..valid_up_to + "\u{FFFD}".len();
            Err(Error::in_file(
                file,
                Diagnostic::error(format!("{} is not valid UTF-8 text", kind.what()))
                    .with_label(range, format!("{bad_len} byte(s) that are not UTF-8"))
                    .with_note(format!(
                        "{} must be UTF-8 text: is this {}?",
                        kind.what(),
                        kind.expected()
                    )),
            ))
        }
    }
}

/// Parses and validates WGSL text.
pub fn parse(file: SourceFile) -> Result<Shader, Error> {
    let file = Arc::new(file);
    let text = file.text.as_str();
    let outcome = catch_unwind(AssertUnwindSafe(|| {
        naga::front::wgsl::parse_str(text)
            .map_err(|err| too_deep(Diagnostic::from_parse_error(&err), text))
            .and_then(|module| {
                validate(&module)
                    .map(|info| (module, info))
                    .map_err(|err| located(Diagnostic::from_spanned_error(&err), &err, text))
            })
    }));
    match outcome {
        Ok(Ok((module, info))) => Ok(Shader {
            file,
            module,
            info,
            vertex_file: None,
            defs: Vec::new(),
        }),
        Ok(Err(diagnostic)) => Err(Error::in_file(file, diagnostic)),
        Err(_) => Err(Error::in_file(
            file,
            Diagnostic::error("naga could not process this shader (it panicked)")
                .with_note("this input exposes a bug in naga; please report it with the shader"),
        )),
    }
}

/// naga's parser stops at a fixed nesting depth with an error that has no
/// span ("Parser recursion limit exceeded"); point it at the deepest
/// bracket of the text, which is where the limit was reached.
fn too_deep(mut diagnostic: Diagnostic, text: &str) -> Diagnostic {
    if !diagnostic.labels.is_empty() {
        return diagnostic;
    }
    let (mut depth, mut deepest, mut at) = (0usize, 0usize, 0usize);
    for (offset, c) in text.char_indices() {
        match c {
            '(' | '[' | '{' => {
                depth += 1;
                if depth > deepest {
                    (deepest, at) = (depth, offset);
                }
            }
            ')' | ']' | '}' => depth = depth.saturating_sub(1),
            _ => {}
        }
    }
    let limit = |s: &String| s.contains("recursion limit");
    if (limit(&diagnostic.message) || diagnostic.notes.iter().any(limit)) && deepest > 0 {
        diagnostic.message = "this shader nests deeper than naga's WGSL parser allows".into();
        diagnostic
            .with_label(at..at + 1, format!("nested {deepest} deep here"))
            .with_note("naga's WGSL parser takes expressions nested only so deep: split this one with `let`s")
    } else {
        diagnostic.with_label(0..0, "while parsing this module")
    }
}

/// Some validation errors carry no span (naga keeps none for entry points).
/// Point those at the entry point's `fn NAME` or, failing that, at the top
/// of the file, so every diagnostic names a line and column.
fn located(
    mut diagnostic: Diagnostic,
    error: &naga::WithSpan<naga::valid::ValidationError>,
    text: &str,
) -> Diagnostic {
    if !diagnostic.labels.is_empty() {
        return diagnostic;
    }
    if let naga::valid::ValidationError::EntryPoint { ref name, .. } = *error.as_inner() {
        if let Some(range) = find_function_name(text, name) {
            return diagnostic.with_label(range, "in this entry point");
        }
    }
    diagnostic = diagnostic.with_label(0..0, "while validating this module");
    diagnostic
}

/// The byte range of `name` in the first `fn name` of the source. Only
/// reads the text, to place a label.
pub(crate) fn find_function_name(text: &str, name: &str) -> Option<std::ops::Range<usize>> {
    let mut from = 0;
    while let Some(at) = text[from..].find("fn") {
        let start = from + at;
        from = start + 2;
        let boundary_before = text[..start]
            .chars()
            .next_back()
            .is_none_or(|c| !(c.is_alphanumeric() || c == '_'));
        let rest = &text[from..];
        let trimmed = rest.trim_start();
        if !boundary_before || trimmed.len() == rest.len() || !trimmed.starts_with(name) {
            continue;
        }
        let after = &trimmed[name.len()..];
        if after
            .chars()
            .next()
            .is_some_and(|c| !(c.is_alphanumeric() || c == '_'))
        {
            let name_start = from + (rest.len() - trimmed.len());
            return Some(name_start..name_start + name.len());
        }
    }
    None
}

/// Validates a module the way every module shadecache reads or writes is
/// validated: all flags, all capabilities.
pub fn validate(
    module: &naga::Module,
) -> Result<ModuleInfo, Box<naga::WithSpan<naga::valid::ValidationError>>> {
    Validator::new(ValidationFlags::all(), Capabilities::all())
        .validate(module)
        .map_err(Box::new)
}

/// Gives a fragment-only `shader` the vertex stage of another module: its
/// vertex entry point `entry` (or its only one), with everything it reads,
/// imported on IR (`proc::import::import_vertex_stage`). Engines
/// keep the two stages in separate files (Bevy's `mesh.wgsl` and
/// `pbr.wgsl`). The resources both modules bind at one (group, binding) are
/// one resource. Errors name the vertex file.
pub fn with_vertex_module(
    shader: Shader,
    vertex: &Shader,
    entry: Option<&str>,
) -> Result<Shader, Error> {
    let fail = |diagnostic: Diagnostic| Err(Error::in_file(vertex.file.clone(), diagnostic));
    let vertices = crate::proc::entry_points_of(&vertex.module, naga::ShaderStage::Vertex);
    let names = || crate::proc::entry_point_names(&vertex.module, &vertices);
    let index = match (entry, vertices.as_slice()) {
        (_, []) => {
            return fail(
                Diagnostic::error(format!(
                    "`{}` has no vertex entry point: --vertex takes the module with the vertex stage that draws `{}`",
                    vertex.file.path, shader.file.path
                ))
                .with_label(0..0, "in this module"),
            )
        }
        (Some(name), _) => match vertices
            .iter()
            .find(|&&i| vertex.module.entry_points[i].name == name)
        {
            Some(&i) => i,
            None => {
                return fail(
                    Diagnostic::error(format!(
                        "`{}` has no vertex entry point named `{name}`; it has {}",
                        vertex.file.path,
                        names()
                    ))
                    .with_label(0..0, "in this module"),
                )
            }
        },
        (None, [only]) => *only,
        (None, _) => {
            return fail(
                Diagnostic::error(format!(
                    "`{}` has several vertex entry points ({}): name one with --vertex-entry",
                    vertex.file.path,
                    names()
                ))
                .with_label(0..0, "in this module"),
            )
        }
    };
    if !crate::proc::entry_points_of(&shader.module, naga::ShaderStage::Vertex).is_empty() {
        return Err(Error::in_file(
            shader.file.clone(),
            Diagnostic::error(format!(
                "`{}` has its own vertex stage; --vertex is for a fragment-only module (name the vertex entry point with --vertex-entry)",
                shader.file.path
            ))
            .with_label(0..0, "in this module"),
        ));
    }
    let Shader {
        file,
        mut module,
        mut defs,
        ..
    } = shader;
    // The vertex module's defs with the fragment's: one composition
    // each, the same defs given to both.
    for def in &vertex.defs {
        if !defs.iter().any(|d| d.name == def.name) {
            defs.push(def.clone());
        }
    }
    defs.sort_by(|a, b| a.name.cmp(&b.name));
    crate::proc::import::import_vertex_stage(&mut module, &vertex.module, index).map_err(
        |reason| {
            Error::in_file(
                vertex.file.clone(),
                Diagnostic::error(format!(
                    "cannot use `{}` as the vertex stage of `{}`: {reason}",
                    vertex.file.path, file.path
                ))
                .with_label(0..0, "in this module"),
            )
        },
    )?;
    let info = validate(&module).map_err(|err| {
        Error::in_file(
            vertex.file.clone(),
            Diagnostic::error(format!(
                "the vertex stage of `{}` does not fit `{}`: {}",
                vertex.file.path,
                file.path,
                Diagnostic::from_spanned_error(&err).message
            ))
            .with_label(0..0, "in this module"),
        )
    })?;
    Ok(Shader {
        file,
        module,
        info,
        vertex_file: Some(vertex.file.clone()),
        defs,
    })
}

/// Loads the shader at `path`, composed as [`compose::ComposerKind::detect`]
/// tells: with naga_oil when it uses `#import`/`#ifdef` or `composition`
/// says where its imports are ([`compose`]), with wesl when it is WESL
/// (`wesl`, the `wesl` feature). When `vertex` names a separate vertex
/// module (composed the same way), the shader gets that module's vertex
/// stage ([`with_vertex_module`]; `vertex_entry` names the entry point
/// there when it has several).
pub fn load_with(
    path: &Path,
    composition: &compose::Composition,
    vertex: Option<&Path>,
    vertex_entry: Option<&str>,
) -> Result<Shader, Error> {
    let load_one = |path: &Path| -> Result<Shader, Error> {
        let file = read_source(path)?;
        match compose::ComposerKind::detect(path, &file.text, composition) {
            None => parse(file),
            Some(compose::ComposerKind::NagaOil) => compose::compose(file, composition),
            #[cfg(feature = "wesl")]
            Some(compose::ComposerKind::Wesl) => wesl::compose(file, path, composition),
            #[cfg(not(feature = "wesl"))]
            Some(compose::ComposerKind::Wesl) => Err(Error::in_file(
                Arc::new(file),
                Diagnostic::error("a WESL shader, and shadecache was built without WESL support")
                    .with_label(0..0, "this shader")
                    .with_note("turn on the `wesl` feature of the shadecache crate"),
            )),
        }
    };
    let shader = load_one(path)?;
    let mut shader = match vertex {
        None => shader,
        Some(vertex) => with_vertex_module(shader, &load_one(vertex)?, vertex_entry)?,
    };
    if composition.narrow_defs {
        shader.defs = defs_that_change_the_code(&shader, |flipped| {
            let mut composition = composition.clone();
            // Unset is absent (naga_oil's `#ifdef` reads a `false` def as
            // defined).
            composition.defs.retain(|(name, _)| *name != flipped.0);
            if flipped.1 == compose::ShaderDef::Bool(true) {
                composition.defs.push(flipped);
            }
            load_without_narrowing(path, &composition, vertex, vertex_entry)
        });
    }
    Ok(shader)
}

/// [`load_with`] without narrowing the defs: what each flip composes.
fn load_without_narrowing(
    path: &Path,
    composition: &compose::Composition,
    vertex: Option<&Path>,
    vertex_entry: Option<&str>,
) -> Result<Shader, Error> {
    let composition = compose::Composition {
        narrow_defs: false,
        ..composition.clone()
    };
    load_with(path, &composition, vertex, vertex_entry)
}

/// The defs of `shader` (those its sources test) that change the code its
/// entry points run: each set or unset def is flipped alone and the
/// shader composed again (`compose`, given the flipped def); a def whose
/// flip leaves the compacted module (unused functions, types and globals
/// dropped) as it was is left out. A number is kept (its value may be read
/// anywhere), as is a def whose flip does not compose. Flipping one at a
/// time misses a branch only a pair of defs opens (`@if(A && B)` with
/// both off); a host that sets both where the variant set neither composes
/// code the passes lack.
fn defs_that_change_the_code(
    shader: &Shader,
    compose: impl Fn((String, compose::ShaderDef)) -> Result<Shader, Error>,
) -> Vec<crate::plan::ShaderDef> {
    use crate::plan::ShaderDefValue;
    if shader.defs.is_empty() {
        return Vec::new();
    }
    let Some(base) = compacted_text(&shader.module) else {
        return shader.defs.clone();
    };
    shader
        .defs
        .iter()
        .filter(|def| {
            let flipped = match def.value {
                ShaderDefValue::Unset => compose::ShaderDef::Bool(true),
                ShaderDefValue::Set => compose::ShaderDef::Bool(false),
                ShaderDefValue::Int(_) | ShaderDefValue::UInt(_) => return true,
            };
            match compose((def.name.clone(), flipped)) {
                Ok(other) => compacted_text(&other.module).as_deref() != Some(base.as_str()),
                Err(_) => true,
            }
        })
        .cloned()
        .collect()
}

/// The module with what its entry points do not reach dropped, as WGSL.
fn compacted_text(module: &naga::Module) -> Option<String> {
    let mut module = module.clone();
    naga::compact::compact(&mut module, naga::compact::KeepUnused::No);
    let info = validate(&module).ok()?;
    naga::back::wgsl::write_string(&module, &info, naga::back::wgsl::WriterFlags::empty()).ok()
}
