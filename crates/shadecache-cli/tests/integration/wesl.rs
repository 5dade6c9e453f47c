//! Shaders composed from WESL modules, as Bevy 0.20 composes its own
//! (`corpus/wesl/`): a fragment-only material that imports the engine
//! package's view bindings, vertex output and PBR helpers, its own
//! package's noise, and the engine's vertex module.

use std::ffi::OsStr;
use std::path::Path;

use crate::util::{root, shadecache, stderr};

/// `shadecache analyze` on the copy's material; its stderr, after
/// checking the exit status is 1.
fn analyze_error(wesl: &Path) -> String {
    let output = shadecache([
        "analyze".as_ref(),
        wesl.join("lava_material.wesl").as_os_str(),
        "--package".as_ref(),
        format!("engine_pbr={}", wesl.join("packages/engine_pbr").display()).as_ref(),
        "--def".as_ref(),
        "MATERIAL_BIND_GROUP=2".as_ref(),
    ] as [&OsStr; 6]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    err
}

/// Where an error must point: at a text's first characters, or only at
/// its line (a parse error's column is the parser's).
enum At<'a> {
    Text(&'a str),
    Line(&'a str),
}

/// Edits `file` (relative to `corpus/wesl`) in a copy with `edit`, runs
/// `analyze` on the copy's material, and checks the error says `says` and
/// points into `file` at `at`, as codespan prints it (`file:line:col`).
fn assert_error_at(file: &str, edit: impl Fn(&str) -> String, says: &str, at: At) {
    let (_dir, wesl) = shadecache_test_support::edited_wesl(file, edit);
    let err = analyze_error(&wesl);
    assert!(err.contains(says), "`{says}` in {err}");
    let (needle, with_column) = match at {
        At::Text(needle) => (needle, true),
        At::Line(needle) => (needle, false),
    };
    let text = std::fs::read_to_string(wesl.join(file)).unwrap();
    let offset = text.find(needle).expect("the needle is in the file");
    let line = text[..offset].matches('\n').count() + 1;
    let col = offset - text[..offset].rfind('\n').map_or(0, |n| n + 1) + 1;
    let place = if with_column {
        format!("{file}:{line}:{col}")
    } else {
        format!("{file}:{line}:")
    };
    assert!(err.contains(&place), "{place} in {err}");
}

/// An import that resolves to nothing is an error at the `import`
/// statement that names it, in the module that has it: an imported
/// package module, the entry module, and a package no import path has.
/// An error inside an imported module points into that module, not into
/// the entry shader (where the wesl crate's own report puts it), and so
/// does a `constants::` no def gives.
#[test]
fn wesl_bad_import_points_into_the_module() {
    let functions = "packages/engine_pbr/render/pbr_functions.wesl";
    // In a package module.
    assert_error_at(
        functions,
        |text| {
            text.replacen(
                "import package::render::view_bindings::view;",
                "import package::render::view_bindings::view;\nimport package::render::lights::shade;",
                1,
            )
            .replacen(
                "let ambient = 0.03 * in.base_color;",
                "let ambient = shade(in.base_color);",
                1,
            )
        },
        "`import engine_pbr::render::lights` does not resolve: no file",
        At::Text("lights::shade"),
    );
    // In the entry module, from a package that is not there.
    assert_error_at(
        "lava_material.wesl",
        |text| {
            text.replacen(
                "import package::noise::fbm;",
                "import package::noise::fbm;\nimport engine_sky::atmosphere::sky;",
                1,
            )
            .replacen(
                "let lit = apply_pbr_lighting(pbr)",
                "let lit = sky(pbr.base_color)",
                1,
            )
        },
        "no package `engine_sky`",
        At::Text("atmosphere::sky"),
    );
    // A name no module declares, inside the material's own noise module.
    assert_error_at(
        "noise.wesl",
        |text| text.replacen("mix(hash3(i), ", "mix(hash4(i), ", 1),
        "hash4",
        At::Text("hash4(i)"),
    );
    // A constant no def gives, used in a package module.
    assert_error_at(
        "packages/engine_pbr/render/view_bindings.wesl",
        |text| text.replacen("@group(0)", "@group(constants::VIEW_BIND_GROUP)", 1),
        "no declaration `VIEW_BIND_GROUP`",
        At::Text("constants::VIEW"),
    );
    // A syntax error in a package module.
    assert_error_at(
        functions,
        |text| {
            text.replacen(
                "let n = normalize(in.world_normal);",
                "let n = normalize(in.world_normal;",
                1,
            )
        },
        "cannot compose the shader",
        At::Line("let n = normalize"),
    );
}

/// `shadecache` run in `dir`.
fn shadecache_in(dir: &Path, args: &[&OsStr]) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_shadecache"))
        .args(args)
        .current_dir(dir)
        .env("NO_COLOR", "1")
        .output()
        .expect("the shadecache binary runs")
}

/// A game's material imports an engine's shaders by the engine crate's
/// name, as a Bevy 0.20 material imports `bevy_pbr::…`; `--package NAME`
/// alone finds that crate's `src/` among the game's dependencies with
/// `cargo metadata`, so the user never spells a registry path. Here the
/// engine is a path dependency laid out as Bevy's crates are (its
/// shaders under `src/render/`). A crate the game does not depend on is an
/// error that says what to give instead.
#[test]
fn a_wesl_package_is_found_by_its_crates_name() {
    let dir = tempfile::tempdir().unwrap();
    let (engine, game) = (dir.path().join("engine_pbr"), dir.path().join("game"));
    let corpus = root().join("corpus/wesl");
    std::fs::create_dir_all(engine.join("src/render")).unwrap();
    std::fs::create_dir_all(game.join("src")).unwrap();
    std::fs::write(
        engine.join("Cargo.toml"),
        "[package]\nname = \"engine_pbr\"\nversion = \"0.1.0\"\nedition = \"2021\"\n",
    )
    .unwrap();
    std::fs::write(engine.join("src/lib.rs"), "").unwrap();
    for module in std::fs::read_dir(corpus.join("packages/engine_pbr/render")).unwrap() {
        let module = module.unwrap().path();
        std::fs::copy(
            &module,
            engine.join("src/render").join(module.file_name().unwrap()),
        )
        .unwrap();
    }
    std::fs::write(
        game.join("Cargo.toml"),
        "[package]\nname = \"game\"\nversion = \"0.1.0\"\nedition = \"2021\"\n\n[dependencies]\nengine_pbr = { path = \"../engine_pbr\" }\n",
    )
    .unwrap();
    std::fs::write(game.join("src/main.rs"), "fn main() {}\n").unwrap();
    for file in ["lava_material.wesl", "noise.wesl"] {
        std::fs::copy(corpus.join(file), game.join(file)).unwrap();
    }

    let analyze = |package: &str| {
        shadecache_in(
            &game,
            &[
                "analyze".as_ref(),
                "lava_material.wesl".as_ref(),
                "--package".as_ref(),
                package.as_ref(),
                "--def".as_ref(),
                "MATERIAL_BIND_GROUP=2".as_ref(),
                "--format".as_ref(),
                "json".as_ref(),
            ],
        )
    };
    let found = analyze("engine_pbr");
    assert_eq!(found.status.code(), Some(0), "{}", stderr(&found));
    let by_dir = analyze(&format!("engine_pbr={}", engine.join("src").display()));
    assert_eq!(
        found.stdout, by_dir.stdout,
        "the crate's src/ is the package"
    );

    let missing = analyze("engine_sky");
    let err = stderr(&missing);
    assert_eq!(missing.status.code(), Some(1), "{err}");
    assert!(err.contains("no crate `engine_sky`"), "{err}");
    assert!(err.contains("engine_sky=DIR"), "{err}");
}

/// `--vertex` names the engine's vertex module by its WESL path in a
/// package given with `--package`, as a material imports it
/// (`bevy_pbr::render::mesh`): the variant rewritten is the one its file's
/// path gives, with no registry path spelled. A package not given, and a
/// module the package lacks, are errors that say so.
#[test]
fn vertex_module_is_named_by_its_wesl_path() {
    let wesl = root().join("corpus/wesl");
    let package = format!("engine_pbr={}", wesl.join("packages/engine_pbr").display());
    let dir = tempfile::tempdir().unwrap();
    let rewrite = |vertex: &OsStr, package: Option<&str>, out: &str| {
        let out = dir.path().join(out);
        let mut args: Vec<&OsStr> = vec![
            "rewrite".as_ref(),
            "corpus/wesl/lava_material.wesl".as_ref(),
            "--def".as_ref(),
            "MATERIAL_BIND_GROUP=2".as_ref(),
            "--all-nodes".as_ref(),
            "--variant".as_ref(),
            "one-pass".as_ref(),
            "--vertex".as_ref(),
            vertex,
            "--out".as_ref(),
            out.as_os_str(),
        ];
        if let Some(package) = package {
            args.extend::<[&OsStr; 2]>(["--package".as_ref(), package.as_ref()]);
        }
        (shadecache_in(&root(), &args), out)
    };
    let (by_path, path_out) = rewrite(
        wesl.join("packages/engine_pbr/render/mesh.wesl")
            .as_os_str(),
        Some(&package),
        "by-path",
    );
    assert!(by_path.status.success(), "{}", stderr(&by_path));
    let (by_module, module_out) = rewrite(
        "engine_pbr::render::mesh".as_ref(),
        Some(&package),
        "by-module",
    );
    assert!(by_module.status.success(), "{}", stderr(&by_module));
    let written = files_under(&path_out);
    assert!(
        written.iter().any(|(name, _)| name.ends_with("plan.json")),
        "{written:?}"
    );
    assert_eq!(files_under(&module_out), written);

    let (without, _) = rewrite("engine_pbr::render::mesh".as_ref(), None, "without");
    let err = stderr(&without);
    assert_eq!(without.status.code(), Some(1), "{err}");
    assert!(
        err.contains("the package `engine_pbr`, which is not given")
            && err.contains("add --package engine_pbr"),
        "{err}"
    );
    let (missing, _) = rewrite(
        "engine_pbr::render::skinning".as_ref(),
        Some(&package),
        "missing",
    );
    let err = stderr(&missing);
    assert_eq!(missing.status.code(), Some(1), "{err}");
    assert!(
        err.contains("--vertex `engine_pbr::render::skinning`: neither")
            && err.contains("skinning.wesl"),
        "{err}"
    );
}

/// Every file under `dir` but the output folder's own list, by its path
/// under `dir`, with its bytes, in order.
fn files_under(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut files = Vec::new();
    let mut folders = vec![dir.to_path_buf()];
    while let Some(folder) = folders.pop() {
        for entry in std::fs::read_dir(&folder).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                folders.push(path);
            } else if path.file_name() != Some(".shadecache-out".as_ref()) {
                let name = path.strip_prefix(dir).unwrap().display().to_string();
                files.push((name, std::fs::read(&path).unwrap()));
            }
        }
    }
    files.sort();
    files
}
