//! Shaders split and composed as engines write them: a fragment-only
//! material module and the mesh pipeline's vertex module
//! (`corpus/split/`), and a material composed from naga_oil modules
//! (`corpus/composed/`).

use std::ffi::OsStr;

use shadecache::analysis::{self};
use shadecache::front::{self};

use crate::util::{root, shadecache, stderr, temp_file, tint_validate};

const FRAGMENT: &str = "corpus/split/toon_material.wgsl";
const VERTEX: &str = "corpus/split/mesh.wgsl";

#[test]
fn vertex_naming_a_module_without_a_vertex_entry_point_is_an_error() {
    let output = shadecache([
        "rewrite",
        FRAGMENT,
        "--vertex",
        FRAGMENT,
        "--all-nodes",
        "--out",
        "/nonexistent/never-written",
    ]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(
        err.contains("has no vertex entry point: --vertex takes the module"),
        "{err}"
    );
    assert!(err.contains("toon_material.wgsl:1:1"), "{err}");
}

#[test]
fn a_binding_the_two_modules_declare_differently_is_an_error() {
    let vertex = std::fs::read_to_string(root().join(VERTEX))
        .unwrap()
        .replace(
            "@group(0) @binding(0) var<uniform> view: View;",
            "@group(0) @binding(0) var<uniform> view: mat4x4<f32>;",
        )
        .replace("view.clip_from_world", "view");
    let (_dir, path) = temp_file("mesh.wgsl", vertex.as_bytes());
    let output = shadecache([
        "rewrite".as_ref(),
        FRAGMENT.as_ref(),
        "--vertex".as_ref(),
        path.as_os_str(),
        "--all-nodes".as_ref(),
        "--out".as_ref(),
        "/nonexistent/never-written".as_ref(),
    ] as [&OsStr; 7]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(err.contains("group 0 binding 0 is `view` in the vertex module and `view` in the fragment module, of different types"), "{err}");
    assert!(err.contains("mesh.wgsl:1:1"), "{err}");
}

/// A fragment-only module profiled with no `--vertex` file is drawn by a
/// vertex stage made from its inputs' names and types (the world position,
/// the normal and the uv from the mesh), said in the report's filled-in
/// inputs; it used to be refused. `--vertex` still gives the real one.
#[test]
fn fragment_only_module_gets_a_generated_vertex_stage() {
    if crate::util::no_gpu() {
        return;
    }
    let out = tempfile::tempdir().unwrap();
    let run = |extra: &[&str], dir: &str| {
        let report = out.path().join(dir);
        let mut args = vec![
            "profile",
            FRAGMENT,
            "--quiet",
            "--nodes",
            "top:1",
            "--variant",
            "one-pass",
            "--frames",
            "2",
            "--size",
            "48x48",
            "--out",
            report.to_str().unwrap(),
        ];
        args.extend(extra);
        let output = shadecache(&args);
        assert!(output.status.success(), "{}", stderr(&output));
        let json: serde_json::Value =
            serde_json::from_slice(&std::fs::read(report.join("report.json")).unwrap()).unwrap();
        json
    };
    let generated = run(&[], "generated");
    let defaulted: Vec<&str> = generated["defaulted"]
        .as_array()
        .unwrap()
        .iter()
        .map(|d| d.as_str().unwrap())
        .collect();
    for line in [
        "vertex stage generated: @location(0) `world_position` = the world position",
        "vertex stage generated: @location(1) `world_normal` = the mesh's normal in world space",
        "vertex stage generated: @location(2) `uv` = the mesh's texture coordinate",
    ] {
        assert!(defaulted.contains(&line), "{defaulted:?}");
    }
    let check = &generated["reference_check"];
    assert!(check["problems"].as_array().unwrap().is_empty(), "{check}");
    // Camera and object motion reach it: the generated stage reads the
    // simulated matrices.
    assert!(check["changed_share"].as_f64().unwrap() > 0.05, "{check}");

    // The joined module is valid WGSL to Tint as well as naga.
    let shader = front::load(&root().join(FRAGMENT)).unwrap();
    let fragment = analysis::fragment_entry(&shader, None).unwrap();
    let (joined, _) = front::vertex::generate(&shader, fragment).unwrap();
    let text = shadecache::back::wgsl_text(&joined.module, &joined.info).unwrap();
    let (_dir, path) = temp_file("joined.wgsl", text.as_bytes());
    for result in tint_validate(&[path]) {
        assert!(result.ok, "{result:?}\n{text}");
    }

    let given = run(&["--vertex", VERTEX], "given");
    assert!(given["defaulted"]
        .as_array()
        .unwrap()
        .iter()
        .all(|d| !d.as_str().unwrap().starts_with("vertex stage generated")));
}

const COMPOSED: &str = "corpus/composed/ripple_material.wgsl";
const MODULES: &str = "corpus/composed/modules";

#[test]
fn an_import_that_does_not_resolve_is_an_error_at_the_import() {
    let output = shadecache(["analyze", COMPOSED]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(
        err.contains("`#import engine::view` does not resolve"),
        "{err}"
    );
    assert!(err.contains("ripple_material.wgsl:6:9"), "{err}");
}

#[test]
fn an_error_in_an_imported_module_points_into_it() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["view.wgsl", "lighting.wgsl"] {
        let text = std::fs::read_to_string(root().join(MODULES).join(name)).unwrap();
        let text = text.replace(
            "let distance = length(to_light);",
            "let distance = length(to_light;",
        );
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let output = shadecache([
        "analyze".as_ref(),
        COMPOSED.as_ref(),
        "--import-path".as_ref(),
        dir.path().as_os_str(),
    ] as [&OsStr; 4]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    let line = std::fs::read_to_string(dir.path().join("lighting.wgsl"))
        .unwrap()
        .lines()
        .position(|l| l.contains("length(to_light;"))
        .unwrap()
        + 1;
    assert!(err.contains(&format!("lighting.wgsl:{line}:")), "{err}");
}
