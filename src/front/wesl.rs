//! Shaders composed from WESL modules, as Bevy 0.20 composes its own:
//! `import` statements, `@if`/`@elif`/`@else` conditional translation and
//! `constants::` values, through the `wesl` crate (the composer Bevy's
//! `bevy_shader` uses).
//!
//! Where modules come from (the WESL spec's packages):
//! - `package::a::b` (and `super::`) is a module of the entry shader's own
//!   package: `a/b.wesl` (or `.wgsl`) under the entry shader's folder;
//! - `name::a::b` is a module of the external package `name`: `a/b.wesl`
//!   under the folder `name` of an `--import-path` (so an engine's shader
//!   folders, one per package, are given by their parent).
//!
//! `--def NAME` (or `NAME=true|false`) sets the feature `NAME` for `@if`;
//! unset features are false. `--def NAME=3` or `NAME=3u` is a numeric
//! constant the shader imports as `constants::NAME`.
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
use std::path::{Path, PathBuf};
use std::sync::Arc;

use wesl::error::ResolveError;
use wesl::resolver::{FileResolver, Resolver, Router};
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
    let root = path.parent().unwrap_or(Path::new("."));
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let (router, packages) = router(root, &composition.import_paths)?;
    let resolver = Recording::new(router, packages);
    let main = ModulePath::new(PathOrigin::Absolute, vec![stem]);
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
    super::compose::finish(&top, module)
}

/// `package::` at the entry shader's folder; each folder under an import
/// path as the external package of its name (whose names come back too).
fn router(root: &Path, import_paths: &[PathBuf]) -> Result<(Router, Vec<String>), Error> {
    let mut router = Router::new();
    let mut names = Vec::new();
    router.mount_resolver(
        ModulePath::new(PathOrigin::Absolute, vec![]),
        FileResolver::new(root),
    );
    for dir in import_paths {
        for package in packages(dir)? {
            let name = package
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_default();
            router.mount_resolver(
                ModulePath::new(PathOrigin::Package(name.clone()), vec![]),
                FileResolver::new(&package),
            );
            names.push(name);
        }
    }
    Ok((router, names))
}

/// The package folders under `dir`, in name order.
fn packages(dir: &Path) -> Result<Vec<PathBuf>, Error> {
    let entries = std::fs::read_dir(dir).map_err(|err| {
        Error::plain(Diagnostic::error(format!(
            "cannot read import path `{}`: {err}",
            dir.display()
        )))
    })?;
    let mut found: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    found.sort();
    Ok(found)
}

/// Features for `@if` and the `constants::` package, from the defs.
fn options(composition: &Composition) -> CompileOptions {
    let mut options = CompileOptions::default();
    options.features.default = Feature::Disable;
    for (name, def) in &composition.defs {
        match *def {
            ShaderDef::Bool(on) => options.features.set(name, on),
            ShaderDef::Int(i) => options.constants.set(name, i),
            ShaderDef::UInt(u) => options.constants.set(name, u),
        }
    }
    options
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
    found: Option<(String, Arc<SourceFile>)>,
}

/// A resolver that keeps what it was asked and what it gave, so errors can
/// be put in their module (module comment).
struct Recording<R> {
    inner: R,
    /// The external packages `inner` has.
    packages: Vec<String>,
    reads: RefCell<Vec<Read>>,
}

impl<R: Resolver> Recording<R> {
    fn new(inner: R, packages: Vec<String>) -> Self {
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
            .find(|read| read.path == *path)
            .and_then(|read| read.found.as_ref().map(|(_, file)| file.clone()))
    }
}

impl<R: Resolver> Resolver for Recording<R> {
    fn resolve_source<'a>(&'a self, path: &ModulePath) -> Result<Cow<'a, str>, ResolveError> {
        let outcome = self.inner.resolve_source(path);
        let found = outcome.as_ref().ok().map(|text| {
            let shown = self
                .inner
                .display_name(path)
                .unwrap_or_else(|| path.to_string());
            let file = Arc::new(SourceFile::new(shown.clone(), text.to_string()));
            (shown, file)
        });
        self.reads.borrow_mut().push(Read {
            path: path.clone(),
            found,
        });
        outcome
    }
    fn display_name(&self, path: &ModulePath) -> Option<String> {
        self.inner.display_name(path)
    }
    fn fs_path(&self, path: &ModulePath) -> Result<PathBuf, ResolveError> {
        self.inner.fs_path(path)
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
    let file = diagnostic
        .detail
        .module_path
        .as_ref()
        .and_then(|path| reads.file(path))
        .or_else(|| {
            let (decl, span) = (diagnostic.detail.declaration.as_deref()?, span.clone()?);
            declaring(reads, decl, &span)
        })
        .unwrap_or_else(|| top.clone());
    let range = span
        .map(|r| r.start.min(file.text.len())..r.end.min(file.text.len()))
        .unwrap_or(0..0);
    Error::in_file(
        file,
        Diagnostic::error(format!("cannot compose the shader: {message}"))
            .with_label(range, "here"),
    )
}

/// The one module read that declares `decl` around `span`.
fn declaring<R: Resolver>(
    reads: &Recording<R>,
    decl: &str,
    span: &std::ops::Range<usize>,
) -> Option<Arc<SourceFile>> {
    let reads = reads.reads.borrow();
    let mut matches = reads.iter().filter_map(|read| {
        let (_, file) = read.found.as_ref()?;
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
        PathOrigin::Package(name) if !reads.packages.contains(name) => {
            let dirs: Vec<String> = composition
                .import_paths
                .iter()
                .map(|p| format!("`{}`", p.display()))
                .collect();
            if dirs.is_empty() {
                format!("no package `{name}`: no --import-path was given")
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
            let (_, file) = read.found.as_ref()?;
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
                "`package::` modules are under the entry shader's folder; a package `name::` is the folder `name` under an --import-path",
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
            .any(|module| at.join_path(&module) == *missing)
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
