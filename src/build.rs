//! The build-script API: rewrite chosen shaders, nodes and variants into
//! `OUT_DIR` from a crate's `build.rs`.
//!
//! ```no_run
//! // build.rs
//! fn main() -> Result<(), shadecache::build::BuildError> {
//!     shadecache::build::Build::new()
//!         .shader("shaders/marble.wgsl")
//!         .node("nb0c12cc4")
//!         .variant(shadecache::rewrite::Variant::ThreePass)
//!         .run()?;
//!     Ok(())
//! }
//! ```
//!
//! The files land in `OUT_DIR/shadecache/<shader stem>/<node>/<variant>/`
//! (`pass1.wgsl`, ..., `plan.json`); [`include_variant!`](crate::include_variant)
//! includes one in the crate. Every input is printed as
//! `cargo::rerun-if-changed`, so the build reruns when a shader changes.
//! Failures are rendered with codespan on stderr (cargo shows them) and
//! `run` returns a short [`BuildError`].

#![warn(missing_docs)]
// Build scripts talk to cargo through stdout.
#![allow(clippy::print_stdout)]

use std::fmt;
use std::path::{Path, PathBuf};

use crate::analysis;
use crate::back::{self, Language};
use crate::diagnostic::{Color, Diagnostic, Error};
use crate::front;
use crate::rewrite::{self, Options, Variant};

pub use crate::analysis::Nodes;

#[derive(Clone, Debug)]
struct ShaderJob {
    path: PathBuf,
    /// The folder its files go in: the file stem unless `.name()` says.
    name: Option<String>,
    entry: Option<String>,
    vertex_entry: Option<String>,
    deforming_inputs: Vec<String>,
    vertex: Option<PathBuf>,
    /// The vertex stage's module in a crate's WESL package: the crate and
    /// the path under its `src/`, found at `run`.
    crate_vertex: Option<(String, PathBuf)>,
    /// The shader itself in a crate's `src/` (`path` is then under it).
    in_crate: Option<String>,
    composition: front::compose::Composition,
    /// WESL packages by their crate's name, found at `run`.
    crate_packages: Vec<String>,
    nodes: Nodes,
    variants: Vec<Variant>,
}

impl ShaderJob {
    fn new(path: PathBuf) -> Self {
        ShaderJob {
            path,
            name: None,
            entry: None,
            vertex_entry: None,
            deforming_inputs: Vec::new(),
            vertex: None,
            crate_vertex: None,
            in_crate: None,
            composition: front::compose::Composition::default(),
            crate_packages: Vec::new(),
            nodes: Nodes::Top(1),
            variants: Variant::ALL.to_vec(),
        }
    }
}

/// Where one job's shader comes from, resolved against the manifest.
struct Sources<'a> {
    path: &'a Path,
    vertex: Option<&'a Path>,
    composition: &'a front::compose::Composition,
}

/// The vertex attributes of the meshes a Bevy material is drawn on
/// ([`Build::bevy_mesh`]): positions always; [`BevyMesh::default`] has
/// normals and the first UVs, as Bevy's primitive shapes do.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BevyMesh {
    /// `Mesh::ATTRIBUTE_NORMAL`.
    pub normals: bool,
    /// `Mesh::ATTRIBUTE_UV_0`.
    pub uv_0: bool,
    /// `Mesh::ATTRIBUTE_UV_1`.
    pub uv_1: bool,
    /// `Mesh::ATTRIBUTE_TANGENT`.
    pub tangents: bool,
    /// `Mesh::ATTRIBUTE_COLOR`.
    pub colors: bool,
}

impl Default for BevyMesh {
    fn default() -> Self {
        BevyMesh {
            normals: true,
            uv_0: true,
            uv_1: false,
            tangents: false,
            colors: false,
        }
    }
}

impl BevyMesh {
    /// The defs Bevy 0.20's `MeshPipeline::specialize` sets for these
    /// attributes (uncompressed).
    fn defs(self) -> Vec<&'static str> {
        let mut defs = vec![
            "MESH_PIPELINE",
            "VERTEX_OUTPUT_INSTANCE_INDEX",
            "VERTEX_POSITIONS",
        ];
        for (on, names) in [
            (self.normals, &["VERTEX_NORMALS"][..]),
            (self.uv_0, &["VERTEX_UVS", "VERTEX_UVS_A"]),
            (self.uv_1, &["VERTEX_UVS", "VERTEX_UVS_B"]),
            (self.tangents, &["VERTEX_TANGENTS"]),
            (self.colors, &["VERTEX_COLORS"]),
        ] {
            if on {
                for name in names {
                    if !defs.contains(name) {
                        defs.push(name);
                    }
                }
            }
        }
        defs
    }
}

/// A set of shaders to rewrite at build time.
#[derive(Clone, Debug, Default)]
pub struct Build {
    jobs: Vec<ShaderJob>,
    options: Options,
    out_dir: Option<PathBuf>,
    quiet: bool,
}

/// What a build wrote.
#[derive(Clone, Debug, Default)]
pub struct Outputs {
    /// Every file written.
    pub files: Vec<PathBuf>,
    /// (shader, node, variant, reason) of every variant refused.
    pub refused: Vec<(PathBuf, String, Variant, String)>,
    /// Every variant written, in order: per shader, its nodes (the top
    /// ranked first, or those named in their order), each node's variants.
    pub variants: Vec<WrittenVariant>,
}

/// One variant a build wrote.
#[derive(Clone, Debug)]
pub struct WrittenVariant {
    /// The shader's folder name: its `.name()`, else its file stem.
    pub shader: String,
    /// The node it caches.
    pub node: String,
    /// The variant.
    pub variant: Variant,
    /// Its files: the pass shaders and `plan.json`.
    pub files: Vec<PathBuf>,
}

/// The file, in the build's output folder, that names every variant the
/// build wrote as Rust: `shadecache_host::include_variants!()` brings it
/// into the game.
pub const VARIANTS_MODULE: &str = "variants.rs";

/// The short error a failed build returns; the diagnostics themselves have
/// been printed on stderr.
#[derive(Clone, Debug)]
pub struct BuildError {
    /// A one-line summary (the diagnostics went to stderr, rendered).
    pub message: String,
    /// Each failure, with its file and position.
    pub errors: Vec<Error>,
}

impl fmt::Display for BuildError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.message)
    }
}

impl std::error::Error for BuildError {}

impl Build {
    /// An empty set: add shaders with [`Build::shader`].
    pub fn new() -> Self {
        Build::default()
    }

    /// Adds a shader; the node and variant settings that follow apply to it.
    /// Relative paths are relative to the crate (`CARGO_MANIFEST_DIR`).
    pub fn shader(mut self, path: impl Into<PathBuf>) -> Self {
        self.jobs.push(ShaderJob::new(path.into()));
        self
    }

    /// Adds a shader that ships in a crate's `src/`, as an engine's own
    /// materials do (Bevy's `StandardMaterial` is bevy_pbr's
    /// `render/pbr.wesl`): the crate is found in the dependency graph of
    /// the package being built, as for [`Build::crate_package`]. Its
    /// files go in a folder named by [`Build::name`], else the file stem.
    pub fn crate_shader(mut self, name: impl Into<String>, path: impl Into<PathBuf>) -> Self {
        let mut job = ShaderJob::new(path.into());
        job.in_crate = Some(name.into());
        self.jobs.push(job);
        self
    }

    /// The job settings apply to. Settings made before any `.shader()` go
    /// to a job without a path, which `run` reports as an error.
    fn last(&mut self) -> &mut ShaderJob {
        if self.jobs.is_empty() {
            self.jobs.push(ShaderJob::new(PathBuf::new()));
        }
        let index = self.jobs.len() - 1;
        &mut self.jobs[index]
    }

    /// Rewrites this node of the last shader added (repeatable).
    pub fn node(mut self, id: impl Into<String>) -> Self {
        let job = self.last();
        match &mut job.nodes {
            Nodes::Ids(ids) => ids.push(id.into()),
            other => *other = Nodes::Ids(vec![id.into()]),
        }
        self
    }

    /// Chooses the nodes of the last shader added (default: the top one).
    pub fn nodes(mut self, nodes: Nodes) -> Self {
        self.last().nodes = nodes;
        self
    }

    /// Writes only this variant of the last shader added (repeatable;
    /// default: all three).
    pub fn variant(mut self, variant: Variant) -> Self {
        let job = self.last();
        if job.variants.len() == Variant::ALL.len() {
            job.variants.clear();
        }
        if !job.variants.contains(&variant) {
            job.variants.push(variant);
        }
        self
    }

    /// The vertex entry point that draws with the last shader's fragment
    /// entry point, when the module has several vertex entry points and
    /// which one cannot be inferred from what they output.
    pub fn vertex_entry(mut self, name: impl Into<String>) -> Self {
        self.last().vertex_entry = Some(name.into());
        self
    }

    /// A per-vertex input of the last shader that the application changes
    /// every frame (it deforms the mesh on the CPU): the position gets its
    /// last-frame value from a twin of its vertex buffer, which the host
    /// fills. Inputs skinned on the GPU need none.
    pub fn deforming_input(mut self, name: impl Into<String>) -> Self {
        self.last().deforming_inputs.push(name.into());
        self
    }

    /// The module with the vertex stage of the last shader, when that one
    /// is fragment-only (as engines split them); resources both bind at
    /// one (group, binding) are one. Without it, a fragment-only shader's
    /// passes take the previous clip position as an input (plan.json's
    /// `host_vertex`).
    pub fn vertex_shader(mut self, path: impl AsRef<Path>) -> Self {
        self.last().vertex = Some(path.as_ref().to_path_buf());
        self.last().crate_vertex = None;
        self
    }

    /// [`Build::vertex_shader`] from a crate's WESL package: `path` under
    /// the `src/` of the crate `name` this package depends on, found as
    /// [`Build::crate_package`] finds it. A Bevy material without a vertex
    /// shader of its own is drawn with `("bevy_pbr", "render/mesh.wesl")`.
    /// Needs the `wesl` feature.
    pub fn crate_vertex_shader(mut self, name: impl Into<String>, path: impl AsRef<Path>) -> Self {
        self.last().crate_vertex = Some((name.into(), path.as_ref().to_path_buf()));
        self.last().vertex = None;
        self
    }

    /// A folder the last shader's imports are searched in: naga_oil
    /// modules (each with `#define_import_path`) for `#import`, or WESL
    /// packages (one folder each, `name::…`) for `import`; call again for
    /// more. Relative to the manifest's folder.
    pub fn import_path(mut self, dir: impl AsRef<Path>) -> Self {
        self.last()
            .composition
            .import_paths
            .push(dir.as_ref().to_path_buf());
        self
    }

    /// A shader def for the last shader's `#ifdef`s (naga_oil), or a
    /// feature for its `@if`s or a `constants::` value (WESL).
    pub fn def(mut self, name: impl Into<String>, value: front::compose::ShaderDef) -> Self {
        self.last().composition.defs.push((name.into(), value));
        self
    }

    /// The defs Bevy 0.20 composes a material's shader with for meshes
    /// with `mesh`'s vertex attributes, drawn in its forward opaque pass
    /// (what `MeshPipeline::specialize` and the material pipeline set:
    /// `MESH_PIPELINE`, `VERTEX_OUTPUT_INSTANCE_INDEX`, one `VERTEX_*` per
    /// attribute, `MATERIAL_BIND_GROUP` 3, and the light counts Bevy's
    /// `mesh_view_types` library is loaded with), for the last shader. Bevy's
    /// own list is in its specialisation code, not a table a build script
    /// can read; the plugin checks each mesh's pipeline's defs against the
    /// variant's plan at run time and leaves a mesh composed otherwise to
    /// Bevy, naming the defs that differ.
    pub fn bevy_mesh(mut self, mesh: BevyMesh) -> Self {
        use front::compose::ShaderDef;
        for name in mesh.defs() {
            self = self.def(name, ShaderDef::Bool(true));
        }
        // Bevy's defaults for a view (`ShadowFilteringMethod::Gaussian`)
        // and what its pipeline cache says of a desktop GPU's storage
        // buffers (at least 6 per stage).
        for name in [
            "SHADOW_FILTER_METHOD_GAUSSIAN",
            "AVAILABLE_STORAGE_BUFFER_BINDINGS__GE_3",
            "AVAILABLE_STORAGE_BUFFER_BINDINGS__GE_6",
        ] {
            self = self.def(name, ShaderDef::Bool(true));
        }
        // The material's group; then the numbers Bevy's view types
        // library carries as its own defs (native builds' values).
        for (name, value) in [
            ("MATERIAL_BIND_GROUP", 3),
            ("MAX_DIRECTIONAL_LIGHTS", 10),
            ("MAX_CASCADES_PER_LIGHT", 4),
            ("MAX_RECT_LIGHTS", 8),
        ] {
            self = self.def(name, ShaderDef::UInt(value));
        }
        self
    }

    /// A WESL package of the last shader by name: `name::a::b` is
    /// `dir/a/b.wesl`. Relative to the manifest's folder.
    pub fn package(mut self, name: impl Into<String>, dir: impl AsRef<Path>) -> Self {
        self.last()
            .composition
            .packages
            .push((name.into(), dir.as_ref().to_path_buf()));
        self
    }

    /// A WESL package of the last shader that ships in a crate's `src/`,
    /// as Bevy's do (`bevy_pbr::render::pbr` is bevy_pbr's
    /// `src/render/pbr.wesl`): `name` is the crate, looked up among the
    /// dependencies of this package with `cargo metadata` (one run for all
    /// of them, offline first), so the version the game builds with is
    /// the one composed. Needs the `wesl` feature.
    pub fn crate_package(mut self, name: impl Into<String>) -> Self {
        self.last().crate_packages.push(name.into());
        self
    }

    /// Which composer puts the last shader together, where the file does
    /// not tell (a `.wesl` file or WESL syntax is WESL, which needs this
    /// crate's `wesl` feature; `#import`s are naga_oil's).
    pub fn composer(mut self, composer: front::compose::ComposerKind) -> Self {
        self.last().composition.composer = Some(composer);
        self
    }

    /// The folder the last shader's files go in (`OUT_DIR/shadecache/<name>/`),
    /// and the first argument of [`include_variant!`](crate::include_variant);
    /// default its file stem. Two shaders with one stem need it.
    pub fn name(mut self, name: impl Into<String>) -> Self {
        self.last().name = Some(name.into());
        self
    }

    /// The fragment entry point of the last shader added.
    pub fn entry(mut self, name: impl Into<String>) -> Self {
        self.last().entry = Some(name.into());
        self
    }

    /// Rewrite options (refresh period and quad, cache format, ε) for all shaders.
    pub fn options(mut self, options: Options) -> Self {
        self.options = options;
        self
    }

    /// Where to write; default `$OUT_DIR/shadecache`. [`include_variant!`](crate::include_variant)
    /// reads the default only (a macro sees no run-time setting): include
    /// files written elsewhere with `include_str!`.
    pub fn out_dir(mut self, dir: impl Into<PathBuf>) -> Self {
        self.out_dir = Some(dir.into());
        self
    }

    /// Print nothing: no `cargo::` lines, no diagnostics on stderr (they
    /// are in the returned [`BuildError`]); for use outside a build script.
    pub fn quiet(mut self) -> Self {
        self.quiet = true;
        self
    }

    /// Rewrites everything and writes it. A refused variant that was asked
    /// for by node id fails the build; with `Top`/`All`, refusals are
    /// reported as warnings.
    pub fn run(self) -> Result<Outputs, BuildError> {
        // naga's parser and lowering recurse over the expression tree; a
        // long chain is deeper than a build script's main thread allows in
        // an unoptimised build. The CLI runs its work the same way.
        const STACK: usize = 256 * 1024 * 1024;
        let quiet = self.quiet;
        let worker = std::thread::Builder::new()
            .name("shadecache-build".into())
            .stack_size(STACK)
            .spawn(move || self.run_here());
        match worker.map(|w| w.join()) {
            Ok(Ok(result)) => result,
            Ok(Err(_)) => Err(Build::failure(
                quiet,
                vec![Error::internal(Diagnostic::error(
                    "shadecache panicked; this is a bug, please report it with the input",
                ))],
            )),
            Err(err) => Err(Build::failure(
                quiet,
                vec![Error::plain(Diagnostic::error(format!(
                    "cannot start a worker thread: {err}"
                )))],
            )),
        }
    }

    fn run_here(self) -> Result<Outputs, BuildError> {
        if let Some(err) = self.check_jobs() {
            return Err(self.fail(vec![err]));
        }
        let out_dir = match self.out_dir.clone().or_else(|| {
            std::env::var_os("OUT_DIR").map(|dir| PathBuf::from(dir).join("shadecache"))
        }) {
            Some(dir) => dir,
            None => {
                return Err(self.fail(vec![Error::plain(Diagnostic::error(
                "OUT_DIR is not set: call shadecache::build from a build script, or set out_dir",
            ))]))
            }
        };
        let mut outputs = Outputs::default();
        let errors = self.each_job(|job, sources| {
            if !self.quiet {
                // Printed first, so a failing shader is watched too (a
                // folder is watched whole).
                for watched in watched(sources.path, sources.vertex, sources.composition) {
                    println!("cargo::rerun-if-changed={}", watched.display());
                }
            }
            self.job(job, sources, &out_dir, &mut outputs)
        });
        if !errors.is_empty() {
            return Err(self.fail(errors));
        }
        let module = out_dir.join(VARIANTS_MODULE);
        std::fs::create_dir_all(&out_dir)
            .and_then(|()| std::fs::write(&module, variants_module(&outputs.variants)))
            .map_err(|err| {
                self.fail(vec![Error::plain(Diagnostic::error(format!(
                    "cannot write `{}`: {err}",
                    module.display()
                )))])
            })?;
        outputs.files.push(module);
        Ok(outputs)
    }

    /// Each shader as [`Build::run`] composes it (its WESL or naga_oil
    /// modules, its vertex stage), without rewriting it: what a test
    /// profiles to measure the variants the build writes on the shader
    /// the build reads. Errors are not printed (they are in
    /// [`BuildError::errors`]). Paths resolve against `CARGO_MANIFEST_DIR`
    /// as in a build script (cargo sets it for tests too).
    pub fn composed(self) -> Result<Vec<front::Shader>, BuildError> {
        let mut shaders = Vec::new();
        let errors = self.each_job(|job, sources| {
            shaders.push(front::load_with(
                sources.path,
                sources.composition,
                sources.vertex,
                job.vertex_entry.as_deref(),
            )?);
            Ok(())
        });
        if errors.is_empty() {
            Ok(shaders)
        } else {
            Err(Build::failure(true, errors))
        }
    }

    /// Calls `each` with every job and where its shader comes from (paths
    /// resolved against the manifest, crate packages found in the
    /// dependency graph); the errors of the jobs that failed.
    fn each_job(
        &self,
        mut each: impl FnMut(&ShaderJob, &Sources) -> Result<(), Error>,
    ) -> Vec<Error> {
        let manifest = std::env::var_os("CARGO_MANIFEST_DIR").map(PathBuf::from);
        let mut errors = Vec::new();
        let resolve = |path: &Path| match &manifest {
            Some(root) if path.is_relative() => root.join(path),
            _ => path.to_path_buf(),
        };
        // One `cargo metadata` for every job's crate packages, run when
        // the first is looked up.
        #[cfg(feature = "wesl")]
        let package_root = resolve(Path::new("."));
        #[cfg(feature = "wesl")]
        let crate_lookup = front::crate_package::Lookup::build_script(&package_root);
        #[cfg(not(feature = "wesl"))]
        let crate_lookup = ();
        for job in &self.jobs {
            let path = match &job.in_crate {
                Some(name) => match crate_package(name, &crate_lookup) {
                    Ok(dir) => dir.join(&job.path),
                    Err(err) => {
                        errors.push(err);
                        continue;
                    }
                },
                None => resolve(&job.path),
            };
            let vertex = match &job.crate_vertex {
                Some((name, under)) => match crate_package(name, &crate_lookup) {
                    Ok(dir) => Some(dir.join(under)),
                    Err(err) => {
                        errors.push(err);
                        continue;
                    }
                },
                None => job.vertex.as_deref().map(resolve),
            };
            let mut packages: Vec<(String, PathBuf)> = job
                .composition
                .packages
                .iter()
                .map(|(name, dir)| (name.clone(), resolve(dir)))
                .collect();
            let mut missing = false;
            for name in &job.crate_packages {
                match crate_package(name, &crate_lookup) {
                    Ok(dir) => packages.push((name.clone(), dir)),
                    Err(err) => {
                        errors.push(err);
                        missing = true;
                    }
                }
            }
            if missing {
                // Its imports would only fail again, less clearly.
                continue;
            }
            let composition = front::compose::Composition {
                import_paths: job
                    .composition
                    .import_paths
                    .iter()
                    .map(|p| resolve(p))
                    .collect(),
                packages,
                defs: job.composition.defs.clone(),
                composer: job.composition.composer,
                // The plans are an engine's: it checks these defs.
                narrow_defs: true,
            };
            let sources = Sources {
                path: &path,
                vertex: vertex.as_deref(),
                composition: &composition,
            };
            if let Err(err) = each(job, &sources) {
                errors.push(err);
            }
        }
        errors
    }

    /// What no shader needs to be read to see: the reference asked for as
    /// a variant, two shaders writing to one folder.
    fn check_jobs(&self) -> Option<Error> {
        if let Some(job) = self
            .jobs
            .iter()
            .find(|job| job.variants.contains(&Variant::Reference))
        {
            return Some(Error::plain(Diagnostic::error(format!(
                "`{}`: Variant::Reference is the unmodified shader, which there is nothing to write for; ask for one-pass, two-pass or three-pass",
                job.path.display()
            ))));
        }
        let mut seen: Vec<(&str, &Path)> = Vec::new();
        for job in &self.jobs {
            let name = job_name(job);
            if let Some((_, other)) = seen.iter().find(|(n, _)| *n == name) {
                return Some(Error::plain(
                    Diagnostic::error(format!(
                        "`{}` and `{}` would both be written to `{name}/`",
                        other.display(),
                        job.path.display()
                    ))
                    .with_note("give one of them its own folder with .name(\"...\")"),
                ));
            }
            seen.push((name, &job.path));
        }
        None
    }

    fn fail(&self, errors: Vec<Error>) -> BuildError {
        Build::failure(self.quiet, errors)
    }

    fn failure(quiet: bool, errors: Vec<Error>) -> BuildError {
        if !quiet {
            for err in &errors {
                err.emit_to_stderr(Color::Auto);
            }
        }
        BuildError {
            message: format!(
                "shadecache: {} error{} rewriting shaders ({})",
                errors.len(),
                if errors.len() == 1 { "" } else { "s" },
                if quiet {
                    "quiet: their diagnostics are in BuildError::errors"
                } else {
                    "see the diagnostics above"
                }
            ),
            errors,
        }
    }

    fn job(
        &self,
        job: &ShaderJob,
        sources: &Sources,
        out_dir: &Path,
        outputs: &mut Outputs,
    ) -> Result<(), Error> {
        if job.path.as_os_str().is_empty() {
            return Err(Error::plain(Diagnostic::error(
                "node, variant or entry set before any shader: call .shader(path) first",
            )));
        }
        let path = sources.path;
        let shader = front::load_with(
            path,
            sources.composition,
            sources.vertex,
            job.vertex_entry.as_deref(),
        )?;
        let analysis = analysis::analyze(
            &shader,
            &analysis::Options {
                entry: job.entry.clone(),
                ..analysis::Options::default()
            },
        )?;
        if let Some(name) = &job.vertex_entry {
            analysis.check_vertex_entry(&shader, name)?;
        }
        let stem = job_name(job);
        let explicit = matches!(job.nodes, Nodes::Ids(_));
        for candidate in analysis.select(&shader.file, &job.nodes)? {
            for &variant in &job.variants {
                let options = Options {
                    vertex_entry: job.vertex_entry.clone(),
                    deforming_inputs: job.deforming_inputs.clone(),
                    ..self.options.clone()
                };
                match rewrite::rewrite(&shader, &analysis, candidate, variant, &options) {
                    Ok(rewritten) => {
                        let dir = out_dir
                            .join(stem)
                            .join(&candidate.node.id)
                            .join(variant.as_str());
                        let files = back::write_variant(&dir, &rewritten, Language::Wgsl)?;
                        outputs.files.extend(files.iter().cloned());
                        outputs.variants.push(WrittenVariant {
                            shader: stem.to_string(),
                            node: candidate.node.id.clone(),
                            variant,
                            files,
                        });
                    }
                    Err(refusal) if explicit => {
                        return Err(Error::in_file(
                            shader.file.clone(),
                            Diagnostic::error(format!(
                                "refused: node {}, {variant}: {}",
                                candidate.node.id, refusal.reason
                            ))
                            .with_label(candidate.node.range.clone(), "this node"),
                        ));
                    }
                    Err(refusal) => {
                        if !self.quiet {
                            println!(
                                "cargo::warning=shadecache refused node {} of {}, {variant}: {}",
                                candidate.node.id,
                                path.display(),
                                refusal.reason
                            );
                        }
                        outputs.refused.push((
                            path.to_path_buf(),
                            candidate.node.id.clone(),
                            variant,
                            refusal.reason,
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// The folder of the WESL package a crate ships (its `src/`).
#[cfg(feature = "wesl")]
fn crate_package(name: &str, lookup: &front::crate_package::Lookup) -> Result<PathBuf, Error> {
    front::crate_package::source_dir(name, lookup)
        .map_err(|message| Error::plain(Diagnostic::error(message)))
}

#[cfg(not(feature = "wesl"))]
fn crate_package(name: &str, _lookup: &()) -> Result<PathBuf, Error> {
    Err(Error::plain(Diagnostic::error(format!(
        ".crate_package(\"{name}\"): WESL packages need shadecache's `wesl` feature"
    ))))
}

/// The folder a job's files go in: its `.name()`, else its file stem.
fn job_name(job: &ShaderJob) -> &str {
    job.name.as_deref().unwrap_or_else(|| {
        job.path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or("shader")
    })
}

/// A Rust identifier from a folder or variant name: `-` and other
/// characters as `_`, a leading digit after `_`.
fn identifier(name: &str) -> String {
    let mut ident: String = name
        .chars()
        .map(|c| {
            if c.is_ascii_alphanumeric() || c == '_' {
                c
            } else {
                '_'
            }
        })
        .collect();
    if ident.is_empty() || ident.starts_with(|c: char| c.is_ascii_digit()) {
        ident.insert(0, '_');
    }
    ident
}

/// The Rust module naming every variant written ([`VARIANTS_MODULE`]):
/// per shader a module of its name holding `NODE` (its first node: the
/// top-ranked candidate, or the first named) and, per node, a module per
/// variant with its `PLAN` and `SHADERS`; the first node's modules are
/// also the shader's own (`lava::one_pass::PLAN`), so a game names no
/// node id.
fn variants_module(variants: &[WrittenVariant]) -> String {
    use std::fmt::Write;
    let mut out = String::from(
        "// Written by shadecache's build-script support: every variant the build wrote.\n",
    );
    let mut shaders: Vec<&str> = Vec::new();
    for v in variants {
        if !shaders.contains(&v.shader.as_str()) {
            shaders.push(&v.shader);
        }
    }
    for shader in shaders {
        let of_shader: Vec<&WrittenVariant> =
            variants.iter().filter(|v| v.shader == shader).collect();
        let first = &of_shader[0].node;
        let _ = writeln!(
            out,
            "\n/// `{shader}`'s variants.\n#[allow(dead_code, unused_imports)]\npub mod {} {{",
            identifier(shader)
        );
        let _ = writeln!(out, "    /// The node its first variants cache: the top-ranked candidate, or the first the build named.\n    pub const NODE: &str = {first:?};\n    pub use self::{}::*;", identifier(first));
        let mut nodes: Vec<&str> = Vec::new();
        for v in &of_shader {
            if !nodes.contains(&v.node.as_str()) {
                nodes.push(&v.node);
            }
        }
        for node in nodes {
            let _ = writeln!(
                out,
                "    /// Node `{node}`'s variants.\n    pub mod {} {{",
                identifier(node)
            );
            for v in of_shader.iter().filter(|v| v.node == node) {
                let path = |file: &PathBuf| format!("{:?}", file.display().to_string());
                let plan = v.files.iter().find(|f| f.ends_with("plan.json"));
                let shaders: Vec<String> = v
                    .files
                    .iter()
                    .filter(|f| !f.ends_with("plan.json"))
                    .map(|f| {
                        let name = f
                            .file_name()
                            .map(|n| n.to_string_lossy())
                            .unwrap_or_default();
                        format!("({name:?}, include_str!({}))", path(f))
                    })
                    .collect();
                let _ = writeln!(
                    out,
                    "        /// The {} variant.\n        pub mod {} {{\n            /// Its `plan.json`.\n            pub const PLAN: &str = include_str!({});\n            /// Its pass shaders, by the file names the plan uses.\n            pub const SHADERS: &[(&str, &str)] = &[{}];\n        }}",
                    v.variant,
                    identifier(v.variant.as_str()),
                    plan.map(path).unwrap_or_else(|| "\"\"".into()),
                    shaders.join(", ")
                );
            }
            out.push_str("    }\n");
        }
        out.push_str("}\n");
    }
    out
}

/// Includes a file the build script wrote: `include_variant!("marble",
/// "nb0c12cc4", "three-pass", "pass1.wgsl")` is the text of
/// `$OUT_DIR/shadecache/marble/nb0c12cc4/three-pass/pass1.wgsl`.
#[macro_export]
macro_rules! include_variant {
    ($shader:literal, $node:literal, $variant:literal, $file:literal) => {
        include_str!(concat!(
            env!("OUT_DIR"),
            "/shadecache/",
            $shader,
            "/",
            $node,
            "/",
            $variant,
            "/",
            $file
        ))
    };
}

/// What a job's outputs depend on, for cargo to watch: the shader, its
/// vertex module, and the folders its imports come from (import paths,
/// WESL packages).
fn watched<'a>(
    path: &'a Path,
    vertex: Option<&'a Path>,
    composition: &'a front::compose::Composition,
) -> Vec<&'a Path> {
    std::iter::once(path)
        .chain(vertex)
        .chain(composition.import_paths.iter().map(PathBuf::as_path))
        .chain(composition.packages.iter().map(|(_, dir)| dir.as_path()))
        .collect()
}

#[cfg(test)]
mod watch_tests {
    use super::*;

    #[test]
    fn a_jobs_import_folders_and_packages_are_watched() {
        let composition = front::compose::Composition {
            import_paths: vec![PathBuf::from("modules")],
            packages: vec![("engine".into(), PathBuf::from("engine/src"))],
            ..Default::default()
        };
        let paths = watched(
            Path::new("m.wesl"),
            Some(Path::new("mesh.wesl")),
            &composition,
        );
        let shown: Vec<_> = paths.iter().map(|p| p.to_str().unwrap()).collect();
        assert_eq!(shown, ["m.wesl", "mesh.wesl", "modules", "engine/src"]);
    }
}
