//! WESL packages that ship inside a Rust crate, found by the crate's name.
//!
//! Bevy 0.20 keeps each crate's shaders under its `src/`, and its shader
//! cache names them by crate: `bevy_pbr::render::pbr` is
//! `bevy_pbr/src/render/pbr.wesl`. A game's material imports them the
//! same way, so composing it needs each of those crates' `src/` folders,
//! which lie in cargo's registry at paths that differ per machine and per
//! version. `--package bevy_pbr` (and [`crate::build::Build::crate_package`])
//! asks cargo instead: the crate of that name in the dependency graph of
//! the Cargo workspace around a folder (the current one for the CLI, the
//! manifest's for a build script), through `cargo metadata`.

use std::cell::OnceCell;
use std::path::{Path, PathBuf};

use cargo_metadata::{Metadata, MetadataCommand, Package, PackageId};

/// Where `cargo metadata` runs, and how; it runs once, however many crates
/// are looked up.
#[derive(Debug)]
pub struct Lookup<'a> {
    /// A folder inside the workspace whose dependencies are searched.
    from: &'a Path,
    /// Try without the network first: a build script's dependencies are
    /// downloaded already, and a cargo that fetched while the build holds
    /// the package cache would wait on it. What offline cannot read is
    /// fetched then ([`run_metadata`]).
    offline: bool,
    /// The target triple whose dependencies count (a build script's
    /// `TARGET`; the host's, [`host_triple`], for the CLI). Without it
    /// cargo reads every platform's dependencies, which offline it may
    /// not have downloaded.
    platform: Option<String>,
    /// The metadata, once read.
    metadata: OnceCell<Result<Metadata, String>>,
}

impl<'a> Lookup<'a> {
    /// For a build script in `manifest`: offline first, for cargo's
    /// `TARGET` (the host's outside a build script).
    pub fn build_script(manifest: &'a Path) -> Self {
        let platform = std::env::var("TARGET").ok().or_else(host_triple);
        Lookup::new(manifest, true, platform)
    }

    /// For the command line in `folder`: the host's dependencies, with the
    /// network.
    pub fn command_line(folder: &'a Path) -> Self {
        Lookup::new(folder, false, host_triple())
    }

    fn new(from: &'a Path, offline: bool, platform: Option<String>) -> Self {
        Lookup {
            from,
            offline,
            platform,
            metadata: OnceCell::new(),
        }
    }

    /// The workspace's metadata, read on first use.
    fn metadata(&self) -> Result<&Metadata, String> {
        self.metadata
            .get_or_init(|| {
                run_metadata(self).map_err(|err| {
                    format!(
                        "`cargo metadata` in {} failed: {}",
                        self.from.display(),
                        first_line(&err.to_string())
                    )
                })
            })
            .as_ref()
            .map_err(Clone::clone)
    }
}

/// The triple of the toolchain's host, from `rustc -vV` (`$RUSTC` where
/// cargo set it); `None` where that does not run.
pub fn host_triple() -> Option<String> {
    let rustc = std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into());
    let output = std::process::Command::new(rustc).arg("-vV").output().ok()?;
    String::from_utf8(output.stdout)
        .ok()?
        .lines()
        .find_map(|line| line.strip_prefix("host: "))
        .map(|host| host.trim().to_string())
}

/// The `src/` folder of the crate `name` in the dependency graph of the
/// workspace around `lookup.from`: the WESL package `name::`. An error
/// says what is missing and what to give instead (`NAME=DIR`).
pub fn source_dir(name: &str, lookup: &Lookup) -> Result<PathBuf, String> {
    let metadata = lookup.metadata().map_err(|err| {
        format!("cannot find the crate `{name}` for its WESL package: {err}; give the package's folder as {name}=DIR")
    })?;
    let crate_name = name.replace('-', "_");
    let named: Vec<&Package> = metadata
        .packages
        .iter()
        .filter(|p| p.name.replace('-', "_") == crate_name)
        .collect();
    let package = match named.as_slice() {
        [] => {
            return Err(format!(
                "no crate `{name}` in the dependencies of the Cargo workspace at {}; add it as a dependency, or give the package's folder as {name}=DIR",
                metadata.workspace_root
            ))
        }
        [one] => *one,
        several => pick(several, metadata.resolve.as_ref()).ok_or_else(|| {
            let versions: Vec<String> = several.iter().map(|p| p.version.to_string()).collect();
            format!(
                "the Cargo workspace at {} depends on several versions of `{name}` ({}); give the package's folder as {name}=DIR",
                metadata.workspace_root,
                versions.join(", ")
            )
        })?,
    };
    let dir = package
        .manifest_path
        .parent()
        .map(|root| root.join("src").into_std_path_buf())
        .ok_or_else(|| format!("`{}` has no folder", package.manifest_path))?;
    if dir.is_dir() {
        Ok(dir)
    } else {
        Err(format!(
            "the crate `{name}` {} has no `src/` folder at {}; give the package's folder as {name}=DIR",
            package.version,
            dir.display()
        ))
    }
}

/// `cargo metadata` for `lookup`. Offline first (for a build script); where that fails, once
/// more with the network: cargo's metadata lists packages a build never
/// downloads (a dependency under a `cfg` it cannot decide without the
/// build's own flags, such as rustix's `errno`), and offline it cannot
/// read their manifests.
fn run_metadata(lookup: &Lookup) -> Result<Metadata, cargo_metadata::Error> {
    let run = |offline: bool| {
        let mut command = MetadataCommand::new();
        command.current_dir(lookup.from);
        let mut options = Vec::new();
        if offline {
            options.push("--offline".to_string());
        }
        if let Some(platform) = &lookup.platform {
            options.extend(["--filter-platform".to_string(), platform.clone()]);
        }
        command.other_options(options);
        command.exec()
    };
    match lookup.offline {
        true => run(true).or_else(|_| run(false)),
        false => run(false),
    }
}

/// Of several versions of one crate, the one the workspace's root package
/// depends on directly, where there is one such.
fn pick<'a>(
    several: &[&'a Package],
    resolve: Option<&cargo_metadata::Resolve>,
) -> Option<&'a Package> {
    let resolve = resolve?;
    let root = resolve.root.as_ref()?;
    let deps: Vec<&PackageId> = resolve
        .nodes
        .iter()
        .find(|node| &node.id == root)?
        .dependencies
        .iter()
        .collect();
    let direct: Vec<&&Package> = several.iter().filter(|p| deps.contains(&&p.id)).collect();
    match direct.as_slice() {
        [one] => Some(**one),
        _ => None,
    }
}

fn first_line(text: &str) -> &str {
    text.lines()
        .find(|line| !line.trim().is_empty())
        .unwrap_or(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lookup() -> Lookup<'static> {
        Lookup::build_script(Path::new(env!("CARGO_MANIFEST_DIR")))
    }

    /// A crate of the graph is found by its name (a dash or an underscore
    /// alike), and its package is its `src/`.
    #[test]
    fn a_dependency_crates_source_folder_is_its_package() {
        let lookup = lookup();
        let dir = source_dir("shadecache-plan", &lookup).unwrap();
        assert!(dir.ends_with("crates/shadecache-plan/src"), "{dir:?}");
        assert!(dir.join("lib.rs").is_file());
        assert_eq!(source_dir("shadecache_plan", &lookup).unwrap(), dir);
    }

    /// A crate the workspace does not depend on, and a folder outside any
    /// workspace, are errors that say what to give instead.
    #[test]
    fn a_crate_not_in_the_graph_is_an_error_naming_the_way_out() {
        let err = source_dir("bevy_not_a_dependency", &lookup()).unwrap_err();
        assert!(err.contains("no crate `bevy_not_a_dependency`"), "{err}");
        assert!(err.contains("bevy_not_a_dependency=DIR"), "{err}");
        let outside = std::env::temp_dir();
        let err = source_dir("bevy_pbr", &Lookup::build_script(&outside)).unwrap_err();
        assert!(err.contains("`cargo metadata`"), "{err}");
        assert!(err.contains("bevy_pbr=DIR"), "{err}");
    }
}
