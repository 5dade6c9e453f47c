//! Shaders composed from modules, as Bevy composes its own: `#import`,
//! `#define_import_path`, `#ifdef`/`#else`/`#endif` and shader defs,
//! through the `naga_oil` crate.
//!
//! The modules an entry shader imports are found under `--import-path`
//! folders (every `.wgsl` there that has a `#define_import_path`), added to
//! a `naga_oil` composer callees first, and the entry shader is made into
//! one naga module. That module is written back as WGSL and parsed again:
//! the analysis names nodes by their source text, and the composed module
//! has one text only once it is written. naga_oil's decorated names
//! (`ViewX_naga_oil_mod_X...X`) become `module__item` first, so node texts
//! read like the flattened shaders Bevy's tooling prints.
//!
//! Composition errors (an `#import` that resolves to nothing, a parse or
//! validation error in an imported module) are diagnostics pointing into
//! the file they are in.

use std::collections::{BTreeMap, BTreeSet, HashMap};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use naga_oil::compose::{
    ComposableModuleDescriptor, Composer, ComposerError, ComposerErrorInner, NagaModuleDescriptor,
    ShaderDefValue, ShaderLanguage, ShaderType,
};

use super::{parse, read_source, Shader};
use crate::diagnostic::{Diagnostic, Error, SourceFile};

/// Where a composed shader's imports come from, and its shader defs.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Composition {
    /// Folders searched (recursively) for the modules `#import` names;
    /// for WESL, folders of packages (each folder under one is the
    /// package of its name).
    pub import_paths: Vec<PathBuf>,
    /// WESL packages named one by one: `name::` is the folder (as an
    /// engine's crate keeps its shaders under `src/`).
    pub packages: Vec<(String, PathBuf)>,
    /// `#ifdef` defines: `NAME` (true) or `NAME=VALUE` (a bool, an i32 or,
    /// with a `u` suffix, a u32).
    pub defs: Vec<(String, ShaderDef)>,
    /// Which composer puts the shader together; `None`: told from the
    /// file ([`ComposerKind::detect`]).
    pub composer: Option<ComposerKind>,
    /// Narrow the loaded shader's `defs` (every def the sources test) to
    /// those that change the code: each flipped alone and the shader
    /// composed again (`front::load_with`). One more composition per
    /// tested def, so only what writes plans for an engine asks for it
    /// (a build script, `shadecache rewrite`).
    pub narrow_defs: bool,
}

/// The two ways engines compose WGSL from modules.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ComposerKind {
    /// naga_oil: `#import`, `#define_import_path`, `#ifdef` (Bevy ≤ 0.19).
    NagaOil,
    /// WESL: `import …;`, `@if` (Bevy 0.20), through the `wesl` crate.
    Wesl,
}

impl ComposerKind {
    /// Parses `--composer`'s value.
    pub fn parse(text: &str) -> Result<ComposerKind, String> {
        match text {
            "naga-oil" | "naga_oil" => Ok(ComposerKind::NagaOil),
            "wesl" => Ok(ComposerKind::Wesl),
            _ => Err(format!("`{text}`: the composer is `wesl` or `naga-oil`")),
        }
    }

    /// The composer a shader file needs, `None` when it is plain WGSL: a
    /// `.wesl` file or WESL syntax is WESL; naga_oil's directives, or
    /// import paths or defs given for a plain file, are naga_oil.
    pub fn detect(path: &std::path::Path, text: &str, composition: &Composition) -> Option<Self> {
        if let Some(kind) = composition.composer {
            return Some(kind);
        }
        let wesl_file = path.extension().is_some_and(|e| e == "wesl");
        if wesl_file || uses_wesl(text) || !composition.packages.is_empty() {
            Some(ComposerKind::Wesl)
        } else if uses_directives(text) || !composition.is_empty() {
            Some(ComposerKind::NagaOil)
        } else {
            None
        }
    }
}

/// A shader def's value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShaderDef {
    /// A boolean def (`--def NAME` alone, or `NAME=true`).
    Bool(bool),
    /// A signed integer def.
    Int(i32),
    /// An unsigned integer def (a `u` suffix).
    UInt(u32),
}

impl ShaderDef {
    /// Parses `NAME` or `NAME=VALUE` as `--def` takes it.
    pub fn parse(text: &str) -> Result<(String, ShaderDef), String> {
        let (name, value) = text.split_once('=').unwrap_or((text, "true"));
        // A name `#ifdef NAME` can test: a WGSL identifier.
        let identifier = name
            .chars()
            .next()
            .is_some_and(|c| c.is_alphabetic() || c == '_')
            && name.chars().all(|c| c.is_alphanumeric() || c == '_');
        if name.is_empty() {
            return Err(format!("`{text}`: the def has no name"));
        }
        if !identifier {
            return Err(format!(
                "`{text}`: a def's name is an identifier (letters, digits and `_`, not first a digit), as `#ifdef NAME` names it"
            ));
        }
        let value = match value {
            "true" => ShaderDef::Bool(true),
            "false" => ShaderDef::Bool(false),
            _ => match value.strip_suffix('u') {
                Some(digits) => digits.parse().map(ShaderDef::UInt).map_err(|_| ()),
                None => value.parse().map(ShaderDef::Int).map_err(|_| ()),
            }
            .map_err(|()| {
                format!("`{text}`: a def's value is true, false, an i32 or a u32 with a `u` suffix (`3u`)")
            })?,
        };
        Ok((name.to_string(), value))
    }

    fn value(self) -> ShaderDefValue {
        match self {
            ShaderDef::Bool(b) => ShaderDefValue::Bool(b),
            ShaderDef::Int(i) => ShaderDefValue::Int(i),
            ShaderDef::UInt(u) => ShaderDefValue::UInt(u),
        }
    }
}

impl Composition {
    /// Whether nothing is composed: no import paths, no defs, no composer.
    pub fn is_empty(&self) -> bool {
        self.import_paths.is_empty()
            && self.packages.is_empty()
            && self.defs.is_empty()
            && self.composer.is_none()
    }

    /// The file of a module of one of the named packages, by its WESL
    /// path: `bevy_pbr::render::mesh` is `render/mesh.wesl` (or `.wgsl`)
    /// in the package `bevy_pbr`'s folder. `None` when `module` is not such
    /// a path; an error naming what is missing when it is one and no
    /// package or file answers it.
    pub fn module_file(&self, module: &str) -> Option<Result<PathBuf, String>> {
        let (package, rest) = module.split_once("::")?;
        let parts: Vec<&str> = rest.split("::").collect();
        let ident =
            |part: &str| !part.is_empty() && part.chars().all(|c| c.is_alphanumeric() || c == '_');
        if !ident(package) || !parts.iter().all(|part| ident(part)) {
            return None;
        }
        let Some((_, dir)) = self.packages.iter().find(|(name, _)| name == package) else {
            let given: Vec<&str> = self.packages.iter().map(|(n, _)| n.as_str()).collect();
            return Some(Err(format!(
                "`{module}` is a module of the package `{package}`, which is not given (packages given: {}): add --package {package}",
                if given.is_empty() { "none".to_string() } else { given.join(", ") }
            )));
        };
        let stem: PathBuf = parts.iter().collect();
        let found = ["wesl", "wgsl"]
            .iter()
            .map(|ext| dir.join(stem.with_extension(ext)))
            .find(|file| file.is_file());
        Some(found.ok_or_else(|| {
            format!(
                "`{module}`: neither `{}` nor `{}` exists",
                dir.join(stem.with_extension("wesl")).display(),
                dir.join(stem.with_extension("wgsl")).display()
            )
        }))
    }

    fn shader_defs(&self) -> HashMap<String, ShaderDefValue> {
        self.defs
            .iter()
            .map(|(name, value)| (name.clone(), value.value()))
            .collect()
    }
}

/// Whether WGSL text uses naga_oil's directives.
pub fn uses_directives(text: &str) -> bool {
    text.lines().any(|line| {
        let line = line.trim_start();
        [
            "#import",
            "#define_import_path",
            "#ifdef",
            "#ifndef",
            "#if ",
            "#else",
            "#endif",
        ]
        .iter()
        .any(|d| line.starts_with(d))
    })
}

/// Whether WGSL text is WESL: it has `import …;` statements or `@if`
/// attributes (naga_oil's `#import` is not).
pub fn uses_wesl(text: &str) -> bool {
    text.lines().any(|line| {
        let line = line.trim_start();
        line.starts_with("import ") || line.contains("@if(")
    })
}

/// One importable module found under an import path.
struct Found {
    file: Arc<SourceFile>,
    imports: Vec<String>,
    /// Other files that define the same module: an error if the module is
    /// imported ([`Found::ambiguous`]), nothing if it is not (a tree's
    /// test fixtures, a backup no shader imports).
    also: Vec<Arc<SourceFile>>,
}

impl Found {
    /// The error for importing a module two files define, naming both.
    fn ambiguous(&self, name: &str) -> Option<Error> {
        let second = self.also.first()?;
        let at = second.text.find(name).unwrap_or(0);
        Some(Error::in_file(
            second.clone(),
            Diagnostic::error(format!(
                "two modules define `{name}`: `{}` and `{}`",
                self.file.path, second.path
            ))
            .with_label(at..at + name.len(), "defined again here")
            .with_note("an import must name one module: remove or rename the copy (a backup, a vendored and a local copy)"),
        ))
    }
}

/// Composes the shader read into `top` with `composition`.
pub fn compose(top: SourceFile, composition: &Composition) -> Result<Shader, Error> {
    let top = Arc::new(top);
    let mut modules = Modules::default();
    for dir in &composition.import_paths {
        modules.collect(dir, dir, 0)?;
    }
    let found = &modules.found;
    let defs = composition.shader_defs();
    let mut composer = Composer::default();
    // Callees first: naga_oil needs a module's imports added before it.
    let (_, top_imports, _) = naga_oil::compose::get_preprocessor_data(&top.text);
    let mut added = Vec::new();
    for import in &top_imports {
        add(
            &mut composer,
            found,
            &import.import,
            &defs,
            &mut added,
            &mut Vec::new(),
        )
        .map_err(|err| {
            err.unwrap_or_else(|| not_found(&top, &import.import, composition, &modules.skipped))
        })?;
    }
    let mut module = composer
        .make_naga_module(NagaModuleDescriptor {
            source: &top.text,
            file_path: &top.path,
            shader_type: ShaderType::Wgsl,
            shader_defs: defs,
            additional_imports: &[],
        })
        .map_err(|err| composer_error(&composer, &err))?;
    rename(&mut module, readable);
    let mut tested = BTreeSet::new();
    for text in std::iter::once(&top.text).chain(added.iter().map(|name| &found[name].file.text)) {
        tested_by_directives(text, &mut tested);
    }
    let mut shader = finish(&top, module)?;
    shader.defs = composition.values_of(tested);
    Ok(shader)
}

impl Composition {
    /// The defs named in `tested`, each with its value here (unset where
    /// this composition does not set it).
    pub(crate) fn values_of(&self, tested: BTreeSet<String>) -> Vec<crate::plan::ShaderDef> {
        use crate::plan::ShaderDefValue;
        tested
            .into_iter()
            .map(|name| {
                let value = match self.defs.iter().rev().find(|(n, _)| *n == name) {
                    None | Some((_, ShaderDef::Bool(false))) => ShaderDefValue::Unset,
                    Some((_, ShaderDef::Bool(true))) => ShaderDefValue::Set,
                    Some((_, ShaderDef::Int(v))) => ShaderDefValue::Int(*v),
                    Some((_, ShaderDef::UInt(v))) => ShaderDefValue::UInt(*v),
                };
                crate::plan::ShaderDef { name, value }
            })
            .collect()
    }
}

/// Adds the defs naga_oil's directives in `text` test to `into`:
/// `#ifdef`, `#ifndef`, `#if NAME op value`, their `#else` forms, and
/// `#{NAME}` substitutions. Read from the text because naga_oil keeps the
/// defs a module tests to itself (its module sets' `effective_defs` are
/// private), and a variant must say which defs it depends on.
pub(crate) fn tested_by_directives(text: &str, into: &mut BTreeSet<String>) {
    for line in text.lines() {
        let line = line.trim_start();
        let Some(directive) = line.strip_prefix('#') else {
            continue;
        };
        let mut words = directive.split_whitespace();
        let mut word = words.next();
        if word == Some("else") {
            word = words.next();
        }
        if matches!(word, Some("ifdef" | "ifndef" | "if")) {
            if let Some(name) = words.next() {
                into.insert(name.to_string());
            }
        }
    }
    let mut rest = text;
    while let Some(at) = rest.find("#{") {
        rest = &rest[at + 2..];
        if let Some(end) = rest.find('}') {
            let name = rest[..end].trim();
            if !name.is_empty() {
                into.insert(name.to_string());
            }
        }
    }
}

/// Validates a composed module, writes it as WGSL and parses that: the
/// analysis names nodes by their source text, and the composed module has
/// one text only once it is written.
pub(super) fn finish(top: &Arc<SourceFile>, module: naga::Module) -> Result<Shader, Error> {
    let info = super::validate(&module).map_err(|err| {
        Error::in_file(
            top.clone(),
            Diagnostic::error(format!(
                "the composed module does not validate: {}",
                Diagnostic::from_spanned_error(&err).message
            ))
            .with_label(0..0, "composed from this shader"),
        )
    })?;
    let text =
        naga::back::wgsl::write_string(&module, &info, naga::back::wgsl::WriterFlags::empty())
            .map_err(|err| {
                Error::in_file(
                    top.clone(),
                    Diagnostic::error(format!("cannot write the composed module: {err}"))
                        .with_label(0..0, "composed from this shader"),
                )
            })?;
    parse(SourceFile::new(format!("{} (composed)", top.path), text))
}

/// The defs given as `false` that `#ifdef`/`#ifndef` test in the shader
/// `top` or a module under the import paths, each with the file that
/// tests it. naga_oil's `#ifdef NAME` asks only whether NAME is defined,
/// so there `--def NAME=false` takes the branch it was meant to skip.
pub fn false_defs_tested_for_presence(
    top: &SourceFile,
    composition: &Composition,
) -> Result<Vec<(String, String)>, Error> {
    let false_defs: Vec<&str> = composition
        .defs
        .iter()
        .filter(|(_, value)| *value == ShaderDef::Bool(false))
        .map(|(name, _)| name.as_str())
        .collect();
    if false_defs.is_empty() {
        return Ok(Vec::new());
    }
    let mut modules = Modules::default();
    for dir in &composition.import_paths {
        modules.collect(dir, dir, 0)?;
    }
    let files = std::iter::once(top).chain(modules.found.values().map(|m| &*m.file));
    let mut tested = Vec::new();
    for file in files {
        for name in &false_defs {
            let tests = file.text.lines().any(|line| {
                let mut words = line.split_whitespace();
                matches!(words.next(), Some("#ifdef" | "#ifndef")) && words.next() == Some(name)
            });
            if tests && !tested.iter().any(|(n, _): &(String, String)| n == name) {
                tested.push((name.to_string(), file.path.clone()));
            }
        }
    }
    Ok(tested)
}

/// The most folders an import-path walk descends through, one inside
/// another: deeper is a link back up, not a project's layout.
pub const MAX_IMPORT_DEPTH: usize = 32;

/// The most entries (files and folders) an import-path walk looks at: a
/// project's shader folders hold hundreds; `--import-path /` millions.
pub const MAX_IMPORT_ENTRIES: usize = 100_000;

/// The modules found under the import paths, by the name each defines.
#[derive(Default)]
struct Modules {
    found: BTreeMap<String, Found>,
    /// `.wgsl` files that are not UTF-8: skipped, as nothing can import
    /// them, and named if an import does not resolve.
    skipped: Vec<PathBuf>,
    /// Folders walked, by their canonical path: a link back to one is
    /// not walked again.
    visited: std::collections::HashSet<PathBuf>,
    entries: usize,
}

impl Modules {
    /// Every `.wgsl` under `dir` that defines an import path, `depth`
    /// folders below the import path `root`. Bounded: each folder once
    /// (links to `.` or `..` included), at most [`MAX_IMPORT_DEPTH`]
    /// deep and [`MAX_IMPORT_ENTRIES`] in all. Two files that define the
    /// same module are kept, an error naming both if it is imported.
    fn collect(&mut self, root: &Path, dir: &Path, depth: usize) -> Result<(), Error> {
        let cannot = |err: std::io::Error| {
            Error::plain(Diagnostic::error(format!(
                "cannot read import path `{}`: {err}",
                dir.display()
            )))
        };
        let canonical = std::fs::canonicalize(dir).map_err(cannot)?;
        if !self.visited.insert(canonical) {
            return Ok(());
        }
        let too_big = |what: String| {
            Error::plain(
                Diagnostic::error(format!(
                    "the import path `{}` is too large to search: {what}",
                    root.display()
                ))
                .with_note("--import-path names the folder of the shader modules, not a project's or the disk's root"),
            )
        };
        if depth > MAX_IMPORT_DEPTH {
            return Err(too_big(format!(
                "`{}` is more than {MAX_IMPORT_DEPTH} folders down",
                dir.display()
            )));
        }
        let entries = std::fs::read_dir(dir).map_err(cannot)?;
        let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
        self.entries += paths.len();
        if self.entries > MAX_IMPORT_ENTRIES {
            return Err(too_big(format!(
                "it holds more than {MAX_IMPORT_ENTRIES} files and folders"
            )));
        }
        paths.sort();
        for path in paths {
            if path.is_dir() {
                self.collect(root, &path, depth + 1)?;
            } else if path.extension().is_some_and(|e| e == "wgsl") {
                // A file that is not UTF-8 defines nothing an import can
                // name: skipped (read again only then, to tell that error
                // from the others).
                let file = match read_source(&path) {
                    Ok(file) => Arc::new(file),
                    Err(_)
                        if std::fs::read(&path).is_ok_and(|b| std::str::from_utf8(&b).is_err()) =>
                    {
                        self.skipped.push(path);
                        continue;
                    }
                    Err(err) => return Err(err),
                };
                let (name, imports, _) = naga_oil::compose::get_preprocessor_data(&file.text);
                let Some(name) = name else { continue };
                if let Some(first) = self.found.get_mut(&name) {
                    first.also.push(file);
                    continue;
                }
                let imports = imports.into_iter().map(|i| i.import).collect();
                let also = Vec::new();
                self.found.insert(
                    name,
                    Found {
                        imports,
                        file,
                        also,
                    },
                );
            }
        }
        Ok(())
    }
}

/// Adds module `name` and, first, what it imports. `Err(None)`: `name`
/// is not under any import path (the caller knows where it was named).
fn add(
    composer: &mut Composer,
    found: &BTreeMap<String, Found>,
    name: &str,
    defs: &HashMap<String, ShaderDefValue>,
    added: &mut Vec<String>,
    stack: &mut Vec<String>,
) -> Result<(), Option<Error>> {
    if added.iter().any(|a| a == name) || composer.contains_module(name) {
        return Ok(());
    }
    // `#import a::b::c` may name an item of module `a::b`.
    let (module_name, module) = match found.get(name) {
        Some(module) => (name.to_string(), module),
        None => match name
            .rsplit_once("::")
            .and_then(|(m, _)| found.get_key_value(m))
        {
            Some((m, module)) => (m.clone(), module),
            None => return Err(None),
        },
    };
    if added.contains(&module_name) {
        return Ok(());
    }
    if let Some(err) = module.ambiguous(&module_name) {
        return Err(Some(err));
    }
    if stack.contains(&module_name) {
        return Err(Some(Error::in_file(
            module.file.clone(),
            Diagnostic::error(format!(
                "`{module_name}` imports itself through {}",
                stack.join(" → ")
            ))
            .with_label(0..0, "in this module"),
        )));
    }
    stack.push(module_name.clone());
    for import in &module.imports {
        add(composer, found, import, defs, added, stack).map_err(|err| {
            Some(err.unwrap_or_else(|| {
                let at = module.file.text.find(import.as_str()).unwrap_or(0);
                Error::in_file(
                    module.file.clone(),
                    Diagnostic::error(format!(
                        "`#import {import}` does not resolve: no module under the import paths defines it"
                    ))
                    .with_label(at..at + import.len(), "imported here"),
                )
            }))
        })?;
    }
    stack.pop();
    let outcome = composer
        .add_composable_module(ComposableModuleDescriptor {
            source: &module.file.text,
            file_path: &module.file.path,
            language: ShaderLanguage::Wgsl,
            as_name: None,
            additional_imports: &[],
            shader_defs: defs.clone(),
        })
        .map(|_| ());
    if let Err(err) = outcome {
        return Err(Some(composer_error(composer, &err)));
    }
    added.push(module_name);
    Ok(())
}

/// An `#import` of the entry shader that nothing under the import paths
/// defines.
fn not_found(
    top: &Arc<SourceFile>,
    import: &str,
    composition: &Composition,
    skipped: &[PathBuf],
) -> Error {
    let at = top.text.find(import).unwrap_or(0);
    let searched = if composition.import_paths.is_empty() {
        "no --import-path was given".to_string()
    } else {
        format!(
            "searched {}",
            composition
                .import_paths
                .iter()
                .map(|p| format!("`{}`", p.display()))
                .collect::<Vec<_>>()
                .join(", ")
        )
    };
    let mut diagnostic = Diagnostic::error(format!(
        "`#import {import}` does not resolve: no module defines it ({searched})"
    ))
    .with_label(at..at + import.len(), "imported here")
    .with_note(
        "a module is a .wgsl file under an --import-path folder with `#define_import_path NAME`",
    );
    for path in skipped.iter().take(4) {
        diagnostic = diagnostic.with_note(format!(
            "`{}` was skipped: it is not UTF-8 text",
            path.display()
        ));
    }
    Error::in_file(top.clone(), diagnostic)
}

/// A composer error as a diagnostic in the file it is in.
fn composer_error(composer: &Composer, err: &ComposerError) -> Error {
    // naga_oil's offsets are into its preprocessed text of the module
    // (directives blanked, lines kept), shown under the module's path.
    // (`path` and `source` look the module up in the composer: errors
    // naming a module come only from modules it holds; the others carry
    // their text.)
    let path = err.source.path(composer).clone();
    let file = Arc::new(SourceFile::new(
        path,
        err.source.source(composer).to_string(),
    ));
    let offset = err.source.offset();
    // naga_oil keeps the module's index in a span's bits from
    // `SPAN_SHIFT` (21, private to it) up.
    const SPAN_SHIFT: usize = 21;
    let local = |at: usize| {
        (at & ((1 << SPAN_SHIFT) - 1))
            .saturating_sub(offset)
            .min(file.text.len())
    };
    let (message, range) = match &err.inner {
        ComposerErrorInner::ImportNotFound(name, at) => (
            format!(
                "`#import {name}` does not resolve: no module under the import paths defines it"
            ),
            *at..*at,
        ),
        ComposerErrorInner::WgslParseError(e) => (
            e.message().to_string(),
            e.labels()
                .next()
                .and_then(|(span, _)| span.to_range())
                .map_or(0..0, |r| local(r.start)..local(r.end)),
        ),
        ComposerErrorInner::ShaderValidationError(v)
        | ComposerErrorInner::HeaderValidationError(v) => (
            format!("{}", v.as_inner()),
            v.spans()
                .next()
                .and_then(|(span, _)| span.to_range())
                .map_or(0..0, |r| local(r.start)..local(r.end)),
        ),
        other => (other.to_string(), 0..0),
    };
    let range = range.start.min(file.text.len())
        ..range
            .end
            .min(file.text.len())
            .max(range.start.min(file.text.len()));
    Error::in_file(
        file,
        Diagnostic::error(format!("cannot compose the shader: {message}"))
            .with_label(range, "here"),
    )
}

/// Renames the module's functions, globals, constants and types that
/// `readable` has a name for (a composer's decorated names).
pub(super) fn rename(module: &mut naga::Module, readable: impl Fn(&str) -> Option<String>) {
    let rename = |name: &mut Option<String>| {
        if let Some(n) = name.as_mut() {
            if let Some(readable) = readable(n) {
                *n = readable;
            }
        }
    };
    for (_, f) in module.functions.iter_mut() {
        rename(&mut f.name);
    }
    for (_, g) in module.global_variables.iter_mut() {
        rename(&mut g.name);
    }
    for (_, c) in module.constants.iter_mut() {
        rename(&mut c.name);
    }
    let handles: Vec<_> = module.types.iter().map(|(h, _)| h).collect();
    for handle in handles {
        let ty = &module.types[handle];
        if let Some(name) = ty.name.as_deref().and_then(&readable) {
            let renamed = naga::Type {
                name: Some(name),
                inner: ty.inner.clone(),
            };
            module.types.replace(handle, renamed);
        }
    }
}

const DECORATION: &str = "X_naga_oil_mod_X";

/// `module__item` for a naga_oil decorated name
/// (`itemX_naga_oil_mod_X<base32>X`, `module` the last segment of the
/// module's path); `None` for a plain one.
fn readable(name: &str) -> Option<String> {
    let at = name.find(DECORATION)?;
    let encoded = name[at + DECORATION.len()..].strip_suffix('X')?;
    let decoded = data_encoding::BASE32_NOPAD
        .decode(encoded.as_bytes())
        .ok()?;
    let path = String::from_utf8(decoded).ok()?;
    let last = path.rsplit("::").next().unwrap_or(&path);
    Some(format!(
        "{}__{}",
        last.replace(|c: char| !c.is_alphanumeric(), "_"),
        &name[..at]
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defs_parse_as_naga_oil_takes_them() {
        assert_eq!(
            ShaderDef::parse("SHADOWS"),
            Ok(("SHADOWS".into(), ShaderDef::Bool(true)))
        );
        assert_eq!(
            ShaderDef::parse("MAX_LIGHTS=4u"),
            Ok(("MAX_LIGHTS".into(), ShaderDef::UInt(4)))
        );
        assert_eq!(
            ShaderDef::parse("BIAS=-2"),
            Ok(("BIAS".into(), ShaderDef::Int(-2)))
        );
        assert_eq!(
            ShaderDef::parse("FOG=false"),
            Ok(("FOG".into(), ShaderDef::Bool(false)))
        );
        assert!(ShaderDef::parse("X=1.5").is_err());
        assert!(ShaderDef::parse("=1").is_err());
        assert_eq!(
            ShaderDef::parse(""),
            Err("``: the def has no name".to_string())
        );
        assert!(ShaderDef::parse("A B=1")
            .unwrap_err()
            .contains("identifier"));
        assert!(ShaderDef::parse("1A").is_err());
        assert!(ShaderDef::parse("é_2=1").is_ok());
    }

    /// A folder of modules with a module and a non-UTF-8 file nothing
    /// imports, and a shader importing the module.
    fn modules_folder() -> (tempfile::TempDir, SourceFile) {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(
            dir.path().join("m.wgsl"),
            "#define_import_path walk::m\nfn half(x: f32) -> f32 { return x * 0.5; }\n",
        )
        .unwrap();
        std::fs::write(dir.path().join("junk.wgsl"), b"\xff\xfe\x00binary").unwrap();
        let top = SourceFile::new(
            "top.wgsl",
            "#import walk::m::half\n@fragment fn fs() -> @location(0) vec4<f32> { return vec4<f32>(half(1.0)); }\n",
        );
        (dir, top)
    }

    fn composed(top: &SourceFile, dir: &Path) -> Result<Shader, Error> {
        compose(
            top.clone(),
            &Composition {
                import_paths: vec![dir.to_path_buf()],
                ..Composition::default()
            },
        )
    }

    /// Links back to the folder (two, so that an unvisited walk doubles
    /// at each level) are each walked once; a folder deeper than the
    /// bound is an error naming it, not minutes of walking; a file that
    /// is not UTF-8 and that nothing imports is skipped.
    #[cfg(unix)]
    #[test]
    fn import_path_walk_is_bounded() {
        let (dir, top) = modules_folder();
        std::os::unix::fs::symlink(".", dir.path().join("a")).unwrap();
        std::os::unix::fs::symlink(".", dir.path().join("b")).unwrap();
        // Without the visited set, the walk doubles at each level until
        // the bound on entries stops it with an error.
        let shader = composed(&top, dir.path());
        let render = shader.as_ref().err().map(Error::render);
        assert!(
            shader.is_ok_and(|s| !s.module.functions.is_empty()),
            "{render:?}"
        );

        let mut deep = dir.path().to_path_buf();
        for i in 0..=MAX_IMPORT_DEPTH {
            deep = deep.join(format!("d{i}"));
        }
        std::fs::create_dir_all(&deep).unwrap();
        let err = composed(&top, dir.path()).err().unwrap().render();
        assert!(err.contains("is too large to search"), "{err}");
        assert!(
            err.contains(&format!("more than {MAX_IMPORT_DEPTH} folders down")),
            "{err}"
        );

        // The skipped file is named where an import does not resolve.
        std::fs::remove_dir_all(dir.path().join("d0")).unwrap();
        let missing = SourceFile::new(
            "top.wgsl",
            "#import walk::gone::f\n@fragment fn fs() -> @location(0) vec4<f32> { return vec4<f32>(f(1.0)); }\n",
        );
        let err = composed(&missing, dir.path()).err().unwrap().render();
        assert!(
            err.contains("junk.wgsl` was skipped: it is not UTF-8"),
            "{err}"
        );
    }

    /// Two files defining one module that a shader imports: an error
    /// naming both, not the later one silently (a backup or a vendored
    /// copy beside the real one); one that nothing imports is no error.
    #[test]
    fn duplicate_import_path_is_an_error() {
        let (dir, top) = modules_folder();
        std::fs::write(
            dir.path().join("m.old.wgsl"),
            "#define_import_path walk::m\nfn half(x: f32) -> f32 { return x * 2.0; }\n",
        )
        .unwrap();
        let err = composed(&top, dir.path()).err().unwrap().render();
        assert!(err.contains("two modules define `walk::m`"), "{err}");
        assert!(
            err.contains("m.old.wgsl") && err.contains("m.wgsl`"),
            "{err}"
        );

        // A module two files define that nothing imports (a tree's test
        // fixtures) is no error.
        std::fs::remove_file(dir.path().join("m.old.wgsl")).unwrap();
        for copy in ["fixture_a.wgsl", "fixture_b.wgsl"] {
            std::fs::write(dir.path().join(copy), "#define_import_path walk::fixture\n").unwrap();
        }
        let render = composed(&top, dir.path()).err().map(|e| e.render());
        assert!(render.is_none(), "{render:?}");
    }

    /// `--def FOG=false` where a module tests `#ifdef FOG` is found, with
    /// the file; `#if FOG == false` reads the value and is not.
    #[test]
    fn a_false_def_tested_for_presence_is_found() {
        let (dir, _) = modules_folder();
        std::fs::write(
            dir.path().join("fog.wgsl"),
            "#define_import_path walk::fog\n#ifdef FOG\nfn fog() {}\n#endif\n",
        )
        .unwrap();
        let composition = Composition {
            import_paths: vec![dir.path().to_path_buf()],
            defs: vec![
                ("FOG".into(), ShaderDef::Bool(false)),
                ("RAIN".into(), ShaderDef::Bool(false)),
            ],
            ..Composition::default()
        };
        let top = SourceFile::new("top.wgsl", "#if RAIN == false\n#endif\n");
        let found = false_defs_tested_for_presence(&top, &composition).unwrap();
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].0, "FOG");
        assert!(found[0].1.ends_with("fog.wgsl"));
    }

    #[test]
    fn wesl_text_is_told_from_naga_oil_text() {
        assert!(uses_wesl("import package::noise::fbm;\nfn f() {}"));
        assert!(uses_wesl("fn f() { @if(FOG) { } }"));
        assert!(!uses_wesl("#import engine::view\nfn f() {}"));
        assert!(!uses_wesl("fn important() {}"));
        let plain = Composition::default();
        let at = |p: &str| std::path::PathBuf::from(p);
        assert_eq!(
            ComposerKind::detect(&at("m.wesl"), "fn f() {}", &plain),
            Some(ComposerKind::Wesl)
        );
        assert_eq!(
            ComposerKind::detect(&at("m.wgsl"), "fn f() {}", &plain),
            None
        );
        assert_eq!(
            ComposerKind::detect(&at("m.wgsl"), "#ifdef A\n#endif", &plain),
            Some(ComposerKind::NagaOil)
        );
        let told = Composition {
            composer: Some(ComposerKind::NagaOil),
            ..Composition::default()
        };
        assert_eq!(
            ComposerKind::detect(&at("m.wesl"), "fn f() {}", &told),
            Some(ComposerKind::NagaOil)
        );
    }

    #[test]
    fn decorated_names_read_as_module_and_item() {
        let encoded = data_encoding::BASE32_NOPAD.encode(b"my_engine::lighting");
        assert_eq!(
            readable(&format!("shadeX_naga_oil_mod_X{encoded}X")).as_deref(),
            Some("lighting__shade")
        );
        assert_eq!(readable("plain"), None);
    }
}
