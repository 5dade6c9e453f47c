//! Shaders composed from WESL modules, as Bevy 0.20 composes its own:
//! `import` statements, `@if`/`@elif`/`@else` conditional translation and
//! `constants::` values, through the `wesl` crate (the composer Bevy's
//! `bevy_shader` uses).
//!
//! Where modules come from (the WESL spec's packages):
//! - `name::a::b` is a module of the external package `name`: `a/b.wesl`
//!   (or `.wgsl`) under the folder `--package name=DIR` names, or else
//!   under the folder `name` of an `--import-path` (a folder of packages);
//! - `package::a::b` (and `super::`) is a module of the entry shader's own
//!   package: the package whose folder the entry shader is under (Bevy's
//!   `bevy_pbr/src/render/pbr.wesl` is `bevy_pbr::render::pbr`, its
//!   `package::` is `bevy_pbr/src`), else the entry shader's folder.
//!
//! Defs follow Bevy 0.20's shader cache: `--def NAME` (or
//! `NAME=true|false`) sets the feature `NAME` for `@if`, unset features
//! are false; `--def NAME=3` or `NAME=3u` turns `NAME` on and is the
//! constant `constants::NAME`.
//!
//! The composed WGSL is parsed by naga; its mangled names
//! (`_1engine_pbr__1pbr_functions_apply_fog`) are renamed `module__item`
//! (`pbr_functions__apply_fog`) as [`super::compose`] renames naga_oil's,
//! from wesl's own source map, before the module is written and parsed
//! again (the analysis names nodes by their text).
//!
//! The `wesl` crate's own error reports name the entry module for errors
//! inside imported ones, and give an import that does not resolve no
//! place at all. Every module the composer reads passes through
//! [`Recording`], so an error is put in the module it is in: by the module
//! path wesl gives, else by the declaration it names (the one module that
//! declares it around the error's span), and an import that resolves to
//! nothing at the `import` statement that names it.

use std::borrow::Cow;
use std::cell::RefCell;
use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use wesl::error::ResolveError;
use wesl::resolver::{FileResolver, Resolver, Router, VirtualResolver};
use wesl::sourcemap::SourceMap;
use wesl::syntax::{
    GlobalDeclaration, Import, ImportContent, ModulePath, PathOrigin, TranslationUnit,
};
use wesl::{CompileOptions, Feature};

use super::compose::{Composition, ShaderDef};
use super::Shader;
use crate::diagnostic::{Diagnostic, Error, SourceFile};

/// Composes the WESL shader at `path` (read into `top`) with `composition`.
pub fn compose(top: SourceFile, path: &Path, composition: &Composition) -> Result<Shader, Error> {
    let top = Arc::new(top);
    let packages = packages(composition)?;
    let main = main_module(path, &packages);
    let root = path.parent().unwrap_or(Path::new("."));
    let resolver = Recording::new(router(root, &packages, composition), packages);
    let result = wesl::compile(&main, &options(composition), &resolver)
        .map_err(|err| located(err, &resolver, &top, composition))?;
    let composed = Arc::new(SourceFile::new(
        format!("{} (composed)", top.path),
        result.syntax.to_string(),
    ));
    let mut module = naga::front::wgsl::parse_str(&composed.text).map_err(|err| {
        Error::in_file(
            composed.clone(),
            Diagnostic::from_parse_error(&err)
                .with_note("the wesl crate composed this text, and naga does not read it as WGSL"),
        )
    })?;
    // Types are checked here first, where naga's spans are into the
    // composed text (wesl checks names, not types).
    super::validate(&module).map_err(|err| {
        Error::in_file(
            composed.clone(),
            Diagnostic::from_spanned_error(&err)
                .with_note("in the text the wesl crate composed (it checks names, not types)"),
        )
    })?;
    if let Some(map) = &result.sourcemap {
        super::compose::rename(&mut module, |name| readable(map, &main, name));
    }
    let mut tested = BTreeSet::new();
    tested_by_conditions(&top.text, &mut tested);
    for read in resolver.reads.borrow().iter() {
        if let Some(file) = &read.found {
            tested_by_conditions(&file.text, &mut tested);
        }
    }
    let mut shader = super::compose::finish(&top, module)?;
    shader.defs = composition.values_of(tested);
    Ok(shader)
}

/// Adds the features and constants `text` tests to `into`: the names in
/// its `@if(…)` and `@elif(…)` conditions, and each `constants::NAME` it
/// reads. Read from the text because the `wesl` crate does not say which
/// features a compilation looked at, and a variant must say which defs
/// it depends on.
fn tested_by_conditions(text: &str, into: &mut BTreeSet<String>) {
    let is_name = |c: char| c.is_ascii_alphanumeric() || c == '_';
    for attribute in ["@if", "@elif"] {
        let mut rest = text;
        while let Some(at) = rest.find(attribute) {
            rest = &rest[at + attribute.len()..];
            let Some(open) = rest.trim_start().strip_prefix('(') else {
                continue;
            };
            let mut depth = 1;
            let end = open
                .char_indices()
                .find(|&(_, c)| {
                    depth += match c {
                        '(' => 1,
                        ')' => -1,
                        _ => 0,
                    };
                    depth == 0
                })
                .map_or(open.len(), |(i, _)| i);
            for name in open[..end].split(|c: char| !is_name(c)) {
                let starts_as_name =
                    name.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_');
                if starts_as_name && !matches!(name, "true" | "false") {
                    into.insert(name.to_string());
                }
            }
        }
    }
    let mut rest = text;
    while let Some(at) = rest.find("constants::") {
        rest = &rest[at + "constants::".len()..];
        let name: String = rest.chars().take_while(|&c| is_name(c)).collect();
        if !name.is_empty() {
            into.insert(name);
        }
    }
}

/// The entry shader's module path: in the package whose folder it is
/// under (the innermost), else `package::stem` of its own folder.
fn main_module(path: &Path, packages: &[(String, PathBuf)]) -> ModulePath {
    let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
    let within = packages
        .iter()
        .filter_map(|(name, dir)| {
            let dir = std::path::absolute(dir).ok()?;
            let relative = absolute.strip_prefix(&dir).ok()?.with_extension("");
            let components: Vec<String> = relative
                .components()
                .map(|c| c.as_os_str().to_string_lossy().into_owned())
                .collect();
            Some((name, components))
        })
        .min_by_key(|(_, components)| components.len());
    match within {
        Some((name, components)) => ModulePath::new(PathOrigin::Package(name.clone()), components),
        None => {
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
            ModulePath::new(PathOrigin::Absolute, vec![stem])
        }
    }
}

/// `package::` at the entry shader's folder; each package at its folder;
/// `constants::` from the numeric defs.
fn router(root: &Path, packages: &[(String, PathBuf)], composition: &Composition) -> Router {
    let mut router = Router::new();
    router.mount_resolver(
        ModulePath::new(PathOrigin::Absolute, vec![]),
        FileResolver::new(root),
    );
    router.mount_resolver(
        ModulePath::new(PathOrigin::Package("constants".into()), vec![]),
        constants(composition),
    );
    for (name, dir) in packages {
        router.mount_resolver(
            ModulePath::new(PathOrigin::Package(name.clone()), vec![]),
            FileResolver::new(dir),
        );
    }
    router
}

/// The packages: those named by `--package`, then each folder under an
/// import path (a name given twice keeps its first folder).
fn packages(composition: &Composition) -> Result<Vec<(String, PathBuf)>, Error> {
    let mut found: Vec<(String, PathBuf)> = Vec::new();
    for (name, dir) in &composition.packages {
        if !dir.is_dir() {
            return Err(Error::plain(Diagnostic::error(format!(
                "`--package {name}={}`: no such folder",
                dir.display()
            ))));
        }
        found.push((name.clone(), dir.clone()));
    }
    for dir in &composition.import_paths {
        let entries = std::fs::read_dir(dir).map_err(|err| {
            Error::plain(Diagnostic::error(format!(
                "cannot read import path `{}`: {err}",
                dir.display()
            )))
        })?;
        let mut folders: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_dir())
            .collect();
        folders.sort();
        for folder in folders {
            let name = folder
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            if !found.iter().any(|(n, _)| *n == name) {
                found.push((name, folder));
            }
        }
    }
    Ok(found)
}

/// The options Bevy 0.20 composes with (`bevy_shader`'s shader cache):
/// imports and `@if` on, `public`/`private` ignored (Bevy's modules do
/// not write them), each def a feature (a number's is on), unset features
/// off.
fn options(composition: &Composition) -> CompileOptions {
    let mut options = CompileOptions {
        imports: true,
        condcomp: true,
        visibility: false,
        ..CompileOptions::default()
    };
    options.features.default = Feature::Disable;
    for (name, def) in &composition.defs {
        let on = !matches!(def, ShaderDef::Bool(false));
        options.features.set(name, on);
    }
    options
}

/// The `constants` package, as Bevy serves it: `const NAME = VALUE;` for
/// each numeric def (`constants::MATERIAL_BIND_GROUP`).
fn constants(composition: &Composition) -> VirtualResolver<'static> {
    let text: String = composition
        .defs
        .iter()
        .filter_map(|(name, def)| match def {
            ShaderDef::Bool(_) => None,
            ShaderDef::Int(i) => Some(format!("const {name} = {i};\n")),
            ShaderDef::UInt(u) => Some(format!("const {name} = {u};\n")),
        })
        .collect();
    let mut resolver = VirtualResolver::new();
    resolver.add_module(ModulePath::new(PathOrigin::Absolute, vec![]), text.into());
    resolver
}

/// `module__item` for a name wesl mangled from another module than the
/// entry's; `None` for the entry's own names and naga's.
fn readable(map: &impl SourceMap, main: &ModulePath, name: &str) -> Option<String> {
    let entry = map.item(name)?;
    if entry.path == *main || entry.name == name {
        return None;
    }
    let module = entry
        .path
        .components
        .last()
        .cloned()
        .or(match &entry.path.origin {
            PathOrigin::Package(p) => Some(p.clone()),
            _ => None,
        })?;
    Some(format!("{module}__{}", entry.name))
}

/// One module the composer asked for: where it is and its text, or that
/// it is nowhere.
struct Read {
    path: ModulePath,
    found: Option<Arc<SourceFile>>,
}

/// A resolver that keeps what it was asked and what it gave, so errors can
/// be put in their module (module comment).
struct Recording<R> {
    inner: R,
    /// The external packages `inner` has, and their folders.
    packages: Vec<(String, PathBuf)>,
    reads: RefCell<Vec<Read>>,
}

impl<R: Resolver> Recording<R> {
    fn new(inner: R, packages: Vec<(String, PathBuf)>) -> Self {
        Recording {
            inner,
            packages,
            reads: RefCell::new(Vec::new()),
        }
    }

    fn file(&self, path: &ModulePath) -> Option<Arc<SourceFile>> {
        self.reads
            .borrow()
            .iter()
            .find(|read| read.path == *flattened(path))
            .and_then(|read| read.found.clone())
    }
}

/// A package's import of another package: wesl names the package
/// `outer/inner`; every package here is top-level, as in Bevy's shader
/// cache, so it is `inner`.
fn flattened(path: &ModulePath) -> Cow<'_, ModulePath> {
    match &path.origin {
        PathOrigin::Package(name) if name.contains('/') => {
            let inner = name.rsplit('/').next().unwrap_or(name);
            Cow::Owned(ModulePath::new(
                PathOrigin::Package(inner.to_string()),
                path.components.clone(),
            ))
        }
        _ => Cow::Borrowed(path),
    }
}

impl<R: Resolver> Resolver for Recording<R> {
    fn resolve_source<'a>(&'a self, path: &ModulePath) -> Result<Cow<'a, str>, ResolveError> {
        let path = flattened(path);
        let path = path.as_ref();
        let outcome = self.inner.resolve_source(path);
        let found = outcome.as_ref().ok().map(|text| {
            let shown = self
                .inner
                .display_name(path)
                .unwrap_or_else(|| path.to_string());
            Arc::new(SourceFile::new(shown, text.to_string()))
        });
        self.reads.borrow_mut().push(Read {
            path: path.clone(),
            found,
        });
        outcome
    }
    fn display_name(&self, path: &ModulePath) -> Option<String> {
        self.inner.display_name(&flattened(path))
    }
    fn fs_path(&self, path: &ModulePath) -> Result<PathBuf, ResolveError> {
        self.inner.fs_path(&flattened(path))
    }
}

/// A wesl error as a diagnostic in the module it is in.
fn located<R: Resolver>(
    err: wesl::Error,
    reads: &Recording<R>,
    top: &Arc<SourceFile>,
    composition: &Composition,
) -> Error {
    let diagnostic = wesl::error::Diagnostic::from(err);
    let message = diagnostic.error.to_string();
    if let Some(missing) = unresolved(&diagnostic.error, reads) {
        return unresolved_import(&missing, reads, top, composition);
    }
    let span = diagnostic.detail.span.map(|s| s.range());
    let (file, range) = match diagnostic
        .detail
        .module_path
        .as_ref()
        .and_then(|path| reads.file(path))
        .or_else(|| {
            let (decl, span) = (diagnostic.detail.declaration.as_deref()?, span.clone()?);
            declaring(reads, decl, &span)
        }) {
        Some(file) => (file, span.unwrap_or(0..0)),
        None if span.is_none() => {
            missing_item_use(&diagnostic.error, reads).unwrap_or_else(|| (top.clone(), 0..0))
        }
        None => (top.clone(), span.unwrap_or(0..0)),
    };
    let range = range.start.min(file.text.len())..range.end.min(file.text.len());
    Error::in_file(
        file,
        Diagnostic::error(format!("cannot compose the shader: {message}"))
            .with_label(range, "here"),
    )
}

/// Where a module read uses an item its module does not declare (wesl
/// gives that error no place): the first `module::item` in a read text.
fn missing_item_use<R: Resolver>(
    err: &wesl::Error,
    reads: &Recording<R>,
) -> Option<(Arc<SourceFile>, std::ops::Range<usize>)> {
    let wesl::Error::UsageError(wesl::error::UsageError::NotFound(module, item)) = err else {
        return None;
    };
    let module = flattened(module);
    let last = match (module.components.last(), &module.origin) {
        (Some(last), _) => last.clone(),
        (None, PathOrigin::Package(name)) => name.clone(),
        (None, _) => return None,
    };
    let qualified = format!("{last}::{item}");
    reads.reads.borrow().iter().find_map(|read| {
        let file = read.found.as_ref()?;
        let at = file.text.find(&qualified)?;
        Some((file.clone(), at..at + qualified.len()))
    })
}

/// The one module read that declares `decl` around `span`.
fn declaring<R: Resolver>(
    reads: &Recording<R>,
    decl: &str,
    span: &std::ops::Range<usize>,
) -> Option<Arc<SourceFile>> {
    let reads = reads.reads.borrow();
    let mut matches = reads.iter().filter_map(|read| {
        let file = read.found.as_ref()?;
        let unit: TranslationUnit = file.text.parse().ok()?;
        unit.global_declarations
            .iter()
            .any(|node| {
                let range = node.span().range();
                declared_name(node).as_deref() == Some(decl)
                    && range.start <= span.start
                    && span.end <= range.end
            })
            .then(|| file.clone())
    });
    let first = matches.next()?;
    matches.next().is_none().then_some(first)
}

fn declared_name(decl: &GlobalDeclaration) -> Option<String> {
    match decl {
        GlobalDeclaration::Declaration(d) => Some(d.ident.to_string()),
        GlobalDeclaration::TypeAlias(a) => Some(a.ident.to_string()),
        GlobalDeclaration::Struct(s) => Some(s.ident.to_string()),
        GlobalDeclaration::Function(f) => Some(f.ident.to_string()),
        _ => None,
    }
}

/// The module path that did not resolve, when that is the error.
fn unresolved<R: Resolver>(err: &wesl::Error, reads: &Recording<R>) -> Option<ModulePath> {
    let resolve = match err {
        wesl::Error::ResolveError(e) => e,
        wesl::Error::ImportError(wesl::error::ImportError::ResolveError(e)) => e,
        _ => return None,
    };
    match resolve {
        ResolveError::FileNotFound(..) | ResolveError::ModuleNotFound(..) => reads
            .reads
            .borrow()
            .iter()
            .rev()
            .find(|read| read.found.is_none())
            .map(|read| read.path.clone()),
        _ => None,
    }
}

/// An import that resolves to nothing, at the statement that names it.
fn unresolved_import<R: Resolver>(
    missing: &ModulePath,
    reads: &Recording<R>,
    top: &Arc<SourceFile>,
    composition: &Composition,
) -> Error {
    let searched = match &missing.origin {
        PathOrigin::Package(name) if !reads.packages.iter().any(|(n, _)| n == name) => {
            let dirs: Vec<String> = composition
                .import_paths
                .iter()
                .map(|p| format!("`{}`", p.display()))
                .collect();
            if dirs.is_empty() {
                format!("no package `{name}`: neither --package {name}=DIR nor an --import-path was given")
            } else {
                format!(
                    "no package `{name}`: no folder `{name}` under {}",
                    dirs.join(", ")
                )
            }
        }
        _ => match reads.inner.fs_path(missing) {
            Err(ResolveError::FileNotFound(file, _)) => {
                format!("no file `{}`", file.display())
            }
            _ => "no module has that path".to_string(),
        },
    };
    let importer = reads
        .reads
        .borrow()
        .iter()
        .filter_map(|read| {
            let file = read.found.as_ref()?;
            let at = import_site(&file.text, &read.path, missing)?;
            Some((file.clone(), at))
        })
        .next();
    let (file, at) = importer.unwrap_or_else(|| (top.clone(), 0..0));
    Error::in_file(
        file,
        Diagnostic::error(format!("`import {missing}` does not resolve: {searched}"))
            .with_label(at, "imported here")
            .with_note(
                "a package `name::` is the folder --package name=DIR gives, or the folder `name` under an --import-path; `package::` is the entry shader's own package",
            ),
    )
}

/// Where in `text` (module `at`) an import statement names module
/// `missing`: the span of the path's last component.
fn import_site(
    text: &str,
    at: &ModulePath,
    missing: &ModulePath,
) -> Option<std::ops::Range<usize>> {
    let unit: TranslationUnit = text.parse().ok()?;
    let names = unit.imports.iter().any(|statement| {
        let Some(base) = &statement.path else {
            return false;
        };
        imported_modules(base, &statement.content)
            .into_iter()
            .any(|module| *flattened(&at.join_path(&module)) == *missing)
    });
    if !names {
        return None;
    }
    let last = missing.components.last()?;
    // The statement has no span in wesl's tree: the first `import`
    // statement in the text that names the component is it.
    let mut offset = 0;
    for statement in text.split_inclusive(';') {
        if let Some(start) = statement.find("import") {
            if let Some(within) = statement[start..].find(last.as_str()) {
                let begin = offset + start + within;
                return Some(begin..begin + last.len());
            }
        }
        offset += statement.len();
    }
    None
}

/// The module paths (relative to the importing module) an import names: an
/// item's module is its path less the item.
fn imported_modules(base: &ModulePath, content: &ImportContent) -> Vec<ModulePath> {
    match content {
        ImportContent::Item(_) => vec![base.clone()],
        ImportContent::Collection(imports) => imports
            .iter()
            .flat_map(|Import { path, content }| {
                let mut module = base.clone();
                module.components.extend(path.iter().cloned());
                imported_modules(&module, content)
            })
            .collect(),
    }
}
