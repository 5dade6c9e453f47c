//! One module per subcommand.

pub mod analyze;
pub mod interpolate;
pub mod merge;
pub mod play;
pub mod profile;
pub mod rewrite;
pub mod scene;

use std::path::{Path, PathBuf};

use shadecache::diagnostic::Color;
use shadecache::diagnostic::{Diagnostic, Error};
use shadecache::front::compose::{ComposerKind, Composition, ShaderDef};
use shadecache::front::{self, Shader};

#[derive(Debug, clap::Subcommand)]
pub enum Command {
    /// List the values of a fragment shader that could be cached, ranked by estimated P/T.
    Analyze(analyze::Args),
    /// Write one-, two-, three-pass and deferred reprojection-cache variants of a shader, with their pass plans.
    Rewrite(rewrite::Args),
    /// Run the variants on a scene, measure time and error against the original, and write a report.
    Profile(profile::Args),
    /// Render the frames between I-frames with whole-frame reuse methods, measure their time and error against rendering every frame, and write a report.
    Interpolate(interpolate::Args),
    /// Scenes for `profile`: `scene init SHADER > scene.toml` writes the default scene to edit.
    Scene(scene::Args),
    /// Join the reports of a sweep's shards (`profile --shard K/N`) into one report and one Pareto front.
    Merge(merge::Args),
    /// Play a scene as an application would: the original, a fixed cache and the host crate's governor, each frame timed, to see what the governor does on this GPU.
    Play(play::Args),
}

impl Command {
    /// The shader a command draws on the GPU, for the commands that do.
    pub fn draws(&self) -> Option<&Path> {
        match self {
            Command::Profile(args) => Some(&args.shader),
            Command::Interpolate(args) => Some(&args.shader),
            Command::Play(args) => Some(&args.shader),
            Command::Analyze(_) | Command::Rewrite(_) | Command::Scene(_) | Command::Merge(_) => {
                None
            }
        }
    }
}

pub fn exec(command: Command, color: Color) -> Result<(), Error> {
    match command {
        Command::Analyze(args) => analyze::exec(args, color),
        Command::Rewrite(args) => rewrite::exec(args, color),
        Command::Profile(args) => profile::exec(args, color),
        Command::Interpolate(args) => interpolate::exec(args, color),
        Command::Scene(args) => scene::exec(args, color),
        Command::Merge(args) => merge::exec(args, color),
        Command::Play(args) => play::exec(args, color),
    }
}

#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub enum ColorArg {
    Auto,
    Always,
    Never,
}

impl From<ColorArg> for Color {
    fn from(arg: ColorArg) -> Color {
        match arg {
            ColorArg::Auto => Color::Auto,
            ColorArg::Always => Color::Always,
            ColorArg::Never => Color::Never,
        }
    }
}

/// Writes to stdout, treating a closed pipe (`shadecache ... | head`) as
/// the reader having seen enough rather than as an error.
pub fn write_stdout(text: &str) -> Result<(), Error> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(err) if err.kind() != std::io::ErrorKind::BrokenPipe => Err(Error::plain(
            shadecache::diagnostic::Diagnostic::error(format!("cannot write to stdout: {err}")),
        )),
        _ => Ok(()),
    }
}

/// Writes a report into `out`: its pictures (`images` writes them), then
/// `report.json` and `report.html` (`html` renders it after the pictures
/// exist: the profile's embeds them). What cannot be written is an error
/// naming it.
pub fn write_report(
    out: &Path,
    json: &impl serde::Serialize,
    images: impl FnOnce() -> Result<Vec<PathBuf>, String>,
    html: impl FnOnce() -> String,
) -> Result<(), Error> {
    let io = |path: &Path, err: String| {
        Error::plain(shadecache::diagnostic::Diagnostic::error(format!(
            "cannot write `{}`: {err}",
            path.display()
        )))
    };
    std::fs::create_dir_all(out).map_err(|e| io(out, e.to_string()))?;
    // The pictures' errors name their files.
    images().map_err(|e| Error::plain(shadecache::diagnostic::Diagnostic::error(e)))?;
    let json = serde_json::to_string_pretty(json)
        .map_err(|e| io(&out.join("report.json"), e.to_string()))?;
    std::fs::write(out.join("report.json"), json + "\n")
        .map_err(|e| io(&out.join("report.json"), e.to_string()))?;
    std::fs::write(out.join("report.html"), html())
        .map_err(|e| io(&out.join("report.html"), e.to_string()))
}

/// How to put a shader together from modules: naga_oil's `#import`s and
/// shader defs, or WESL's `import`s and features.
#[derive(Debug, Clone, clap::Args)]
pub struct ComposeArgs {
    /// Where imports are found; repeatable. naga_oil: a folder searched
    /// (recursively) for the modules `#import`s name (each with
    /// `#define_import_path`). WESL: a folder of packages, each folder
    /// under it the package of its name (`import name::a::b;` reads
    /// `DIR/name/a/b.wesl`); `package::` is the shader's own folder.
    #[arg(long = "import-path", value_name = "DIR")]
    pub import_paths: Vec<PathBuf>,

    /// A WESL package by name: `name::a::b` is `DIR/a/b.wesl`; repeatable.
    /// A NAME alone is the `src/` of the crate of that name among the
    /// dependencies of the Cargo workspace here (Bevy's: `--package
    /// bevy_pbr`), found with `cargo metadata`. The shader is WESL when
    /// one is given.
    #[arg(long = "package", value_name = "NAME[=DIR]", value_parser = parse_package)]
    pub packages: Vec<(String, Option<PathBuf>)>,

    /// A shader def for `#ifdef` (naga_oil) or a feature for `@if` (WESL):
    /// NAME, or NAME=VALUE (true, false, an i32, or a u32 as `3u`; a WESL
    /// number is `constants::NAME`); repeatable. naga_oil's `#ifdef NAME`
    /// tests only whether NAME is defined, so NAME=false takes its branch
    /// (a warning says so): leave the def out to skip it.
    #[arg(long = "def", value_name = "NAME[=VALUE]", value_parser = ShaderDef::parse)]
    pub defs: Vec<(String, ShaderDef)>,

    /// The composer: `wesl` or `naga-oil`. Default: told from the file (a
    /// `.wesl` file, `import …;` or `@if` is WESL; `#import`/`#ifdef`,
    /// or --import-path/--def with a plain file, naga_oil).
    #[arg(long, value_name = "wesl|naga-oil", value_parser = ComposerKind::parse)]
    pub composer: Option<ComposerKind>,
}

fn parse_package(text: &str) -> Result<(String, Option<PathBuf>), String> {
    match text.split_once('=') {
        Some((name, dir)) if !name.is_empty() && !dir.is_empty() => {
            Ok((name.to_string(), Some(PathBuf::from(dir))))
        }
        None if !text.is_empty() => Ok((text.to_string(), None)),
        _ => Err(format!(
            "`{text}`: a package is NAME=DIR, or a crate's NAME"
        )),
    }
}

/// The folders of packages given by their crates' names alone, found in
/// the Cargo workspace here with one `cargo metadata`.
#[cfg(feature = "wesl")]
fn crate_packages(names: &[&str]) -> Result<Vec<PathBuf>, Error> {
    let fail = |message: String| Error::plain(Diagnostic::error(message));
    let here = std::env::current_dir().map_err(|err| {
        fail(format!(
            "cannot read the current folder to find crates: {err}"
        ))
    })?;
    let lookup = front::crate_package::Lookup::command_line(&here);
    names
        .iter()
        .map(|name| front::crate_package::source_dir(name, &lookup).map_err(fail))
        .collect()
}

#[cfg(not(feature = "wesl"))]
fn crate_packages(names: &[&str]) -> Result<Vec<PathBuf>, Error> {
    Err(Error::plain(Diagnostic::error(format!(
        "--package {}: WESL packages need this build's `wesl` feature (cargo install shadecache-cli --features wesl)",
        names.join(", ")
    ))))
}

impl ComposeArgs {
    /// The composition asked for, each package given by a crate's name
    /// found in the Cargo workspace here.
    pub fn composition(&self) -> Result<Composition, Error> {
        let by_crate: Vec<&str> = self
            .packages
            .iter()
            .filter(|(_, dir)| dir.is_none())
            .map(|(name, _)| name.as_str())
            .collect();
        let mut found = match by_crate.is_empty() {
            true => Vec::new(),
            false => crate_packages(&by_crate)?,
        }
        .into_iter();
        let packages = self
            .packages
            .iter()
            .map(|(name, dir)| {
                (
                    name.clone(),
                    dir.clone().or_else(|| found.next()).unwrap_or_default(),
                )
            })
            .collect();
        // One value a def: the second would silently win.
        for (i, (name, _)) in self.defs.iter().enumerate() {
            if self.defs[..i].iter().any(|(n, _)| n == name) {
                return Err(Error::plain(Diagnostic::error(format!(
                    "--def {name} is given twice: give each def once"
                ))));
            }
        }
        Ok(Composition {
            import_paths: self.import_paths.clone(),
            packages,
            defs: self.defs.clone(),
            composer: self.composer,
            ..Composition::default()
        })
    }
}

/// Which entry points of the shader to take, and where its other parts
/// come from: a separate vertex module, naga_oil modules.
#[derive(Debug, Clone, clap::Args)]
pub struct StageArgs {
    /// The fragment entry point, when the shader has several.
    #[arg(long, value_name = "NAME")]
    pub entry: Option<String>,

    /// The vertex entry point that draws with it, when the module has
    /// several and which cannot be inferred from what they output (with
    /// --vertex, the one in that module).
    #[arg(long, value_name = "NAME")]
    pub vertex_entry: Option<String>,

    /// The module with the vertex stage, for a fragment-only shader
    /// (engines keep the stages in separate files); resources both bind at
    /// one (group, binding) are one. A file, or a module of a --package by
    /// its WESL path: Bevy's mesh vertex stage is `bevy_pbr::render::mesh`
    /// with `--package bevy_pbr`.
    #[arg(long, value_name = "FILE.wgsl|PACKAGE::MODULE")]
    pub vertex: Option<PathBuf>,

    #[command(flatten)]
    pub compose: ComposeArgs,
}

impl StageArgs {
    /// Loads `shader`: composed from modules where it imports them, given
    /// the vertex stage of `--vertex` where it has none.
    /// The scene at `path`, with the path; without one, the default
    /// scene for `shader` (what `shadecache scene init` writes).
    pub fn scene(
        &self,
        shader: &Shader,
        path: Option<&Path>,
    ) -> Result<(shadecache::scene::Scene, PathBuf), Error> {
        Ok(match path {
            Some(path) => (shadecache::scene::Scene::load(path)?, path.to_path_buf()),
            None => (
                shadecache::scene::Scene::default_for(
                    shader,
                    self.entry.as_deref(),
                    self.vertex_entry.as_deref(),
                )?,
                PathBuf::from("default scene"),
            ),
        })
    }

    /// The shader and scene a run draws: `shader` itself, or, for a
    /// fragment-only module given no `--vertex`, the module joined to a
    /// vertex stage made from its inputs' names and types (what feeds each
    /// input is listed with the scene's defaulted values); and the scene
    /// at `path` or the default one for it, with the motion of a game
    /// when `game_motion` ([`Scene::with_game_motion`](shadecache::scene::Scene::with_game_motion)).
    pub fn drawn(
        &self,
        shader: Shader,
        path: Option<&Path>,
        game_motion: bool,
    ) -> Result<(Shader, shadecache::scene::Scene, PathBuf), Error> {
        let (shader, generated) = if shadecache::rewrite::vertex::is_fragment_only(&shader.module) {
            let fragment = shadecache::analysis::fragment_entry(&shader, self.entry.as_deref())?;
            front::vertex::generate(&shader, fragment)?
        } else {
            (shader, Vec::new())
        };
        let (mut scene, scene_path) = self.scene(&shader, path)?;
        if game_motion && path.is_none() {
            scene = scene.with_game_motion();
        }
        scene.defaulted.extend(generated);
        Ok((shader, scene, scene_path))
    }

    pub fn load(&self, shader: &Path) -> Result<Shader, Error> {
        self.load_composed(shader, self.compose.composition()?)
    }

    /// [`Stages::load`] for a shader whose plans go to an engine: its
    /// defs narrowed to those that change the code (`plan.json`'s
    /// `shader_defs`).
    pub fn load_for_plans(&self, shader: &Path) -> Result<Shader, Error> {
        let composition = Composition {
            narrow_defs: true,
            ..self.compose.composition()?
        };
        self.load_composed(shader, composition)
    }

    fn load_composed(&self, shader: &Path, composition: Composition) -> Result<Shader, Error> {
        let vertex = self
            .vertex
            .as_deref()
            .map(|vertex| vertex_file(vertex, &composition))
            .transpose()?;
        let loaded = front::load_with(
            shader,
            &composition,
            vertex.as_deref(),
            self.vertex_entry.as_deref(),
        )?;
        warn_false_defs(shader, &composition);
        Ok(loaded)
    }
}

/// The file of `--vertex`: the path given, or where it names no file and
/// reads as a package's module (`bevy_pbr::render::mesh`), that module's.
fn vertex_file(vertex: &Path, composition: &Composition) -> Result<PathBuf, Error> {
    let module = vertex.to_str().filter(|_| !vertex.exists());
    match module.and_then(|module| composition.module_file(module)) {
        None => Ok(vertex.to_path_buf()),
        Some(found) => {
            found.map_err(|message| Error::plain(Diagnostic::error(format!("--vertex {message}"))))
        }
    }
}

/// Warns of each `--def NAME=false` that `#ifdef NAME` tests: naga_oil
/// asks there only whether NAME is defined, so the def turns the branch
/// on.
pub fn warn_false_defs(shader: &Path, composition: &Composition) {
    let false_def = |(_, value): &(String, ShaderDef)| *value == ShaderDef::Bool(false);
    if !composition.defs.iter().any(false_def) {
        return;
    }
    let Ok(top) = front::read_source(shader) else {
        return;
    };
    let tested = shadecache::front::compose::false_defs_tested_for_presence(&top, composition)
        .unwrap_or_default();
    for (name, file) in tested {
        eprintln!(
            "warning: --def {name}=false defines {name}, and `#ifdef {name}` in `{file}` asks only whether it is defined: its branch is taken. Leave the def out to skip it (`#if {name} == true` reads the value)"
        );
    }
}
