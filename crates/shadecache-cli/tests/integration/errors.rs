//! Bad input: a diagnostic on stderr, exit status 1, never a panic.

use std::path::Path;

use crate::util::{shadecache, stderr, temp_file};

/// Runs `analyze` on `path` and checks it failed cleanly; returns stderr.
fn fails_cleanly(path: &Path, extra: &[&str]) -> String {
    let mut args = vec!["analyze".to_string(), path.display().to_string()];
    args.extend(extra.iter().map(|s| s.to_string()));
    let output = shadecache(&args);
    let err = stderr(&output);
    assert_eq!(
        output.status.code(),
        Some(1),
        "exit status for {args:?}:\n{err}"
    );
    assert!(
        err.starts_with("error"),
        "a diagnostic for {args:?}:\n{err}"
    );
    assert!(!err.contains("panicked"), "a panic for {args:?}:\n{err}");
    assert!(output.stdout.is_empty(), "nothing on stdout for {args:?}");
    err
}

fn fails_on(name: &str, contents: &[u8]) -> String {
    let (_dir, path) = temp_file(name, contents);
    fails_cleanly(&path, &[]).replace(&path.display().to_string(), name)
}

#[test]
fn syntax_error_points_at_line_and_column() {
    let source = "@fragment\nfn fs() -> @location(0) vec4<f32> {\n    let x = 1.0 +;\n    return vec4<f32>(x);\n}\n";
    let err = fails_on("syntax.wgsl", source.as_bytes());
    // Rendered exactly as codespan renders rustc-style diagnostics.
    assert_eq!(
        err,
        r#"error: expected expression, found ";"
  ┌─ syntax.wgsl:3:18
  │
3 │     let x = 1.0 +;
  │                  ^ expected expression

"#
    );
}

#[test]
fn type_error_is_a_diagnostic() {
    let source = "@fragment\nfn fs() -> @location(0) vec4<f32> {\n    let x: f32 = vec3<f32>(1.0);\n    return vec4<f32>(x);\n}\n";
    let err = fails_on("types.wgsl", source.as_bytes());
    assert!(err.contains("types.wgsl:3:"), "{err}");
}

#[test]
fn validation_error_is_a_diagnostic() {
    // Parses, but fails validation: a fragment output without a location.
    let source = "@fragment\nfn fs() -> vec4<f32> {\n    return vec4<f32>(1.0);\n}\n";
    let err = fails_on("invalid.wgsl", source.as_bytes());
    assert!(err.contains("invalid.wgsl:2:4"), "{err}");
    assert!(err.contains("must all have bindings"), "{err}");
}

#[test]
fn empty_file_has_no_fragment_entry_point() {
    let err = fails_on("empty.wgsl", b"");
    assert!(err.contains("has no fragment entry point"), "{err}");
}

#[test]
fn random_bytes_are_refused() {
    // A fixed linear congruential sequence: the same "random" bytes on
    // every machine.
    let mut state = 0x2545_f491_u32;
    let bytes: Vec<u8> = (0..4096)
        .map(|_| {
            state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (state >> 24) as u8
        })
        .collect();
    fails_on("random.wgsl", &bytes);
    // Printable garbage gets through UTF-8 decoding to the parser.
    let printable: Vec<u8> = bytes.iter().map(|b| b' ' + b % 95).collect();
    let err = fails_on("garbage.wgsl", &printable);
    assert!(err.contains("garbage.wgsl:1:"), "{err}");
}

#[test]
fn non_utf8_points_at_the_first_bad_byte() {
    let mut bytes = b"// line one\nfn f() {}\n// caf".to_vec();
    bytes.push(0xff);
    bytes.extend_from_slice(b" ok\n");
    let err = fails_on("latin1.wgsl", &bytes);
    assert!(err.contains("not valid UTF-8"), "{err}");
    assert!(err.contains("latin1.wgsl:3:7"), "{err}");
}

#[test]
fn missing_file_is_a_diagnostic() {
    let err = fails_cleanly(Path::new("corpus/does_not_exist.wgsl"), &[]);
    assert!(
        err.contains("cannot read `corpus/does_not_exist.wgsl`: no such file"),
        "{err}"
    );
}

#[test]
fn directory_is_a_diagnostic() {
    let err = fails_cleanly(Path::new("corpus"), &[]);
    assert!(err.contains("is a directory"), "{err}");
}

#[test]
fn no_fragment_entry_point_lists_the_entry_points() {
    let source = "@vertex\nfn vs_main(@location(0) p: vec3<f32>) -> @builtin(position) vec4<f32> {\n    return vec4<f32>(p, 1.0);\n}\n";
    let err = fails_on("vertex_only.wgsl", source.as_bytes());
    assert!(err.contains("has no fragment entry point"), "{err}");
    assert!(err.contains("`vs_main` (vertex)"), "{err}");
}

const TWO_FRAGMENTS: &str = "@fragment fn first(@location(0) x: f32) -> @location(0) vec4<f32> { return vec4<f32>(sin(x)); }\n@fragment fn second(@location(0) x: f32) -> @location(0) vec4<f32> { return vec4<f32>(cos(x)); }\n@vertex fn vs() -> @builtin(position) vec4<f32> { return vec4<f32>(0.0); }\n";

/// Without `--entry`, `analyze` takes every fragment entry point in turn
/// (it used to stop and ask for one).
#[test]
fn two_fragment_entry_points_are_analysed_in_turn() {
    let (_dir, path) = temp_file("two.wgsl", TWO_FRAGMENTS.as_bytes());
    let output = shadecache(["analyze", path.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));
    let text = crate::util::stdout(&output);
    let first = text
        .find("entry point `first`:")
        .expect("a section for `first`");
    let second = text
        .find("entry point `second`:")
        .expect("a section for `second`");
    assert!(first < second, "{text}");
    let output = shadecache(["analyze", path.to_str().unwrap(), "--format", "json"]);
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let entries: Vec<&str> = json
        .as_array()
        .expect("an array, one analysis per entry point")
        .iter()
        .map(|a| a["entry"].as_str().unwrap())
        .collect();
    assert_eq!(entries, ["first", "second"]);
    // `--entry` still narrows it to one, as one object.
    let output = shadecache([
        "analyze",
        path.to_str().unwrap(),
        "--format",
        "json",
        "--entry",
        "second",
    ]);
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    assert_eq!(json["entry"], "second");
}

#[test]
fn entry_must_name_a_fragment_entry_point() {
    let (_dir, path) = temp_file("two.wgsl", TWO_FRAGMENTS.as_bytes());
    let err = fails_cleanly(&path, &["--entry", "third"]);
    assert!(err.contains("no entry point named `third`"), "{err}");
    let err = fails_cleanly(&path, &["--entry", "vs"]);
    assert!(err.contains("is a vertex entry point"), "{err}");
}

#[test]
fn bad_weights_file_is_a_diagnostic() {
    let (_dir, weights) = temp_file(
        "weights.json",
        b"{\n  \"arithmetic\": 1.0,\n  \"sine\": 3.0\n}\n",
    );
    let err = fails_cleanly(
        Path::new("corpus/noise_marble.wgsl"),
        &["--weights", &weights.display().to_string()],
    );
    assert!(err.contains("unknown field `sine`"), "{err}");
    assert!(err.contains("weights.json:3:"), "{err}");
}

#[test]
fn usage_errors_exit_1() {
    let output = shadecache(["analyze"]);
    assert_eq!(output.status.code(), Some(1));
    let output = shadecache(["analyze", "corpus/noise_marble.wgsl", "--format", "xml"]);
    assert_eq!(output.status.code(), Some(1));
}

/// Every prefix of every corpus shader (in steps), and every corpus shader
/// with one character deleted (in steps), goes through parse and analysis
/// without a panic: each either analyses or gives a diagnostic.
#[test]
fn damaged_corpus_shaders_never_panic() {
    use shadecache::analysis::{analyze, Options};
    use shadecache::diagnostic::SourceFile;

    let mut inputs = 0;
    for path in crate::util::corpus() {
        let source = std::fs::read_to_string(crate::util::root().join(&path)).unwrap();
        let boundaries: Vec<usize> = (0..=source.len())
            .filter(|&i| source.is_char_boundary(i))
            .collect();
        for (n, &cut) in boundaries.iter().enumerate().step_by(53) {
            let truncated = &source[..cut];
            let next = boundaries.get(n + 1).copied().unwrap_or(source.len());
            let deleted = format!("{}{}", &source[..cut], &source[next..]);
            for text in [truncated.to_string(), deleted] {
                inputs += 1;
                let outcome = std::panic::catch_unwind(|| {
                    match shadecache::front::parse(SourceFile::new("damaged.wgsl", text.clone())) {
                        Ok(shader) => analyze(&shader, &Options::default()).map(|_| ()),
                        Err(err) => Err(err),
                    }
                    .map_err(|err| err.render())
                });
                let rendered = outcome.unwrap_or_else(|_| {
                    panic!("a panic on {} damaged at byte {cut}", path.display())
                });
                if let Err(message) = rendered {
                    assert!(message.starts_with("error"), "{message}");
                }
            }
        }
    }
    assert!(inputs > 500, "{inputs} inputs");
}

/// A valid but deeply nested expression (a 2000-term sum parses to a
/// 3000-deep tree) must not overflow the stack.
#[test]
fn deep_expression_does_not_overflow_the_stack() {
    let source = format!(
        "@fragment\nfn fs(@location(0) x: f32) -> @location(0) vec4<f32> {{\n    let v = x{};\n    return vec4<f32>(v);\n}}\n",
        " + x".repeat(2000)
    );
    let (_dir, path) = temp_file("deep.wgsl", source.as_bytes());
    let output = shadecache(["analyze".as_ref(), path.as_os_str()] as [&std::ffi::OsStr; 2]);
    assert!(output.status.success(), "{}", stderr(&output));
}

/// A refresh period beyond what the refresh indicator can map (65535) is
/// refused at the command line, before anything is written.
#[test]
fn a_refresh_period_beyond_the_largest_is_refused() {
    let out = tempfile::tempdir().unwrap();
    for (command, period) in [("rewrite", "65536"), ("profile", "8,70000")] {
        let mut args = vec![
            command,
            "corpus/noise_marble.wgsl",
            "--refresh-period",
            period,
            "--out",
            out.path().to_str().unwrap(),
        ];
        if command == "profile" {
            args.extend(["--scene", "corpus/scenes/marble_sphere.toml"]);
        }
        let output = shadecache(&args);
        let err = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{command}: {err}");
        assert!(err.contains("--refresh-period"), "{command}: {err}");
        assert!(err.contains("65535"), "{command}: {err}");
    }
    assert_eq!(std::fs::read_dir(out.path()).unwrap().count(), 0);
}

/// A scene for the marble shader, with `edit` applied to its text: a
/// `(find, replace)` pair, or appended when `find` is empty.
fn marble_scene(edit: (&str, &str)) -> String {
    let base = "size = [64, 64]\nframes = 2\nwarmup = 0\n\n[camera]\neye = [0.0, 0.3, 2.6]\ntarget = [0.0, 0.0, 0.0]\nfov_degrees = 45.0\n\n[light]\nposition = [3.0, 4.0, 2.5]\n\n[[objects]]\nmesh = { kind = \"sphere\", radius = 1.0, rings = 8, segments = 8 }\nscale = 1.0\n\n[uniforms]\nmarble_frequency = 4.0\nturbulence_amount = 6.0\nlight_color = [1.0, 0.97, 0.92]\n";
    let (find, replace) = edit;
    if find.is_empty() {
        return format!("{base}{replace}");
    }
    assert!(base.contains(find), "the base scene has `{find}`");
    base.replacen(find, replace, 1)
}

/// Runs `profile` on the marble shader with `scene` (and `extra`
/// arguments): it must fail with exit 1 before writing anything, and
/// name `at` (`scene.toml:LINE:COLUMN`) and `says`.
fn scene_fails(case: &str, scene: &str, extra: &[&str], says: &str, at: &str) {
    let (dir, path) = temp_file("scene.toml", scene.as_bytes());
    let out = dir.path().join("report");
    let mut args = vec![
        "profile".to_string(),
        "corpus/noise_marble.wgsl".into(),
        "--scene".into(),
        path.display().to_string(),
        "--out".into(),
        out.display().to_string(),
        "--quiet".into(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    let output = shadecache(&args);
    let err = stderr(&output).replace(&path.display().to_string(), "scene.toml");
    assert_eq!(output.status.code(), Some(1), "{case}: {err}");
    assert!(err.contains(says), "{case}: expected `{says}` in\n{err}");
    assert!(err.contains(at), "{case}: expected `{at}` in\n{err}");
    assert!(!err.contains("panicked"), "{case}: {err}");
    assert!(!out.exists(), "{case}: nothing is written");
}

/// Each value a scene could give that renders nothing, garbage, or never
/// ends is an error at the value, with exit 1 and nothing written
/// (docs/scene-toml.md states the bounds).
#[test]
fn scene_values_are_bounded_and_finite() {
    let cases: &[(&str, (&str, &str), &str, &str)] = &[
        (
            "nan_camera",
            ("eye = [0.0, 0.3, 2.6]", "eye = [0.0, nan, 2.6]"),
            "`nan` is not a finite number",
            "scene.toml:6:13",
        ),
        (
            "infinite_light",
            ("position = [3.0, 4.0, 2.5]", "position = [inf, 4.0, 2.5]"),
            "`inf` is not a finite number",
            "scene.toml:11:13",
        ),
        (
            "beyond_f32_mesh_radius",
            ("radius = 1.0", "radius = 1e39"),
            "`1e39` is not a finite number",
            "scene.toml:14:36",
        ),
        (
            "nan_uniform",
            ("marble_frequency = 4.0", "marble_frequency = -nan"),
            "`-nan` is not a finite number",
            "scene.toml:18:20",
        ),
        (
            "zero_field_of_view",
            ("fov_degrees = 45.0", "fov_degrees = 0.0"),
            "strictly between 0 and 180",
            "scene.toml:8:15",
        ),
        (
            "half_turn_field_of_view",
            ("fov_degrees = 45.0", "fov_degrees = 180.0"),
            "strictly between 0 and 180",
            "scene.toml:8:15",
        ),
        (
            "eye_at_target",
            ("eye = [0.0, 0.3, 2.6]", "eye = [0.0, 0.0, 0.0]"),
            "eye is at its target",
            "scene.toml:6:7",
        ),
        (
            "eye_straight_above",
            ("eye = [0.0, 0.3, 2.6]", "eye = [0.0, 3.0, 0.0]"),
            "straight up or down",
            "scene.toml:6:7",
        ),
        (
            "huge_sphere",
            (
                "rings = 8, segments = 8",
                "rings = 100000, segments = 100000",
            ),
            "10000000000 quads",
            "scene.toml:14:8",
        ),
        (
            "huge_warmup",
            ("warmup = 0", "warmup = 4000000000"),
            "warmup = 4000000000 is above 10000",
            "scene.toml:3:10",
        ),
        (
            "zero_frames",
            ("frames = 2", "frames = 0"),
            "frames = 0 is not between 1 and 10000",
            "scene.toml:2:10",
        ),
        (
            "three_element_size",
            ("size = [64, 64]", "size = [64, 64, 3]"),
            "two numbers of pixels",
            "scene.toml:1:8",
        ),
        (
            "zero_scale",
            ("scale = 1.0", "scale = 0.0"),
            "scale is 0",
            "scene.toml:15:9",
        ),
        (
            "negative_radius",
            ("radius = 1.0", "radius = -1.0"),
            "`radius` is -1",
            "scene.toml:14:8",
        ),
        (
            "texture_source_neither_file_nor_pattern",
            ("", "\n[textures.albedo]\nsize = 64\n"),
            "a texture needs `file",
            "scene.toml:22:",
        ),
    ];
    for (case, edit, says, at) in cases {
        scene_fails(case, &marble_scene(*edit), &[], says, at);
    }
    // The bad value reported is TOML's own spelling, not serde's enum.
    let (dir, path) = temp_file(
        "scene.toml",
        marble_scene(("", "\n[textures.x]\ngenerate = 3\n")).as_bytes(),
    );
    let output = shadecache([
        "profile",
        "corpus/noise_marble.wgsl",
        "--scene",
        path.to_str().unwrap(),
        "--out",
        dir.path().join("r").to_str().unwrap(),
    ]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(!err.contains("untagged"), "{err}");
}

/// The command line's counts are bounded as a scene's are: no silent
/// change of 0 to 1, no hang on four billion frames, no cosine of 5.
#[test]
fn command_line_counts_are_bounded() {
    let out = tempfile::tempdir().unwrap();
    let report = out.path().join("r");
    let report = report.to_str().unwrap();
    for (args, says) in [
        (
            vec!["profile", "corpus/noise_marble.wgsl", "--frames", "0"],
            "from 1 to 10000",
        ),
        (
            vec![
                "profile",
                "corpus/noise_marble.wgsl",
                "--frames",
                "4000000000",
            ],
            "from 1 to 10000",
        ),
        (
            vec![
                "profile",
                "corpus/noise_marble.wgsl",
                "--warmup",
                "4000000000",
            ],
            "from 0 to 10000",
        ),
        (
            vec!["interpolate", "corpus/noise_marble.wgsl", "--frames", "0"],
            "from 1 to 10000",
        ),
        (
            vec![
                "interpolate",
                "corpus/noise_marble.wgsl",
                "--min-cosine",
                "5",
            ],
            "from -1 to 1",
        ),
    ] {
        let mut args = args.clone();
        args.extend(["--out", report]);
        let output = shadecache(&args);
        let err = stderr(&output);
        assert_eq!(output.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    assert!(!Path::new(report).exists());
}

/// A `[uniforms]` key or a `[textures]` table the shader does not have is
/// a misspelling until shown otherwise: an error at the key that lists
/// what the shader has.
#[test]
fn unknown_uniform_or_texture_key_is_an_error() {
    scene_fails(
        "misspelt_uniform",
        &marble_scene(("marble_frequency = 4.0", "marble_freqency = 4.0")),
        &[],
        "[uniforms] sets `marble_freqency`, which the shader does not have",
        "scene.toml:18:19",
    );
    scene_fails(
        "unbound_texture",
        &marble_scene(("", "\n[textures.albedo]\ngenerate = \"checker\"\n")),
        &[],
        "[textures.albedo] names a texture the shader does not bind",
        "scene.toml:22:1",
    );
}

/// A `--vertex-entry` that names nothing is one error before anything is
/// rewritten, not the same refusal for each of the shader's nodes and
/// variants (1,836 on the marble shader) and exit 0.
#[test]
fn one_bad_flag_is_one_error_not_a_thousand_refusals() {
    let out = tempfile::tempdir().unwrap();
    let dir = out.path().join("variants");
    let output = shadecache([
        "rewrite",
        "corpus/noise_marble.wgsl",
        "--all-nodes",
        "--vertex-entry",
        "nope",
        "--out",
        dir.to_str().unwrap(),
    ]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert_eq!(err.matches("error").count(), 1, "{err}");
    assert!(!err.contains("refused"), "{err}");
    assert!(err.contains("no entry point named `nope`"), "{err}");
    assert!(!dir.exists());
}

/// Files of the wrong kind are named for what they were meant to be; a
/// byte-order mark is no part of the text; a too-deep expression is
/// located.
#[test]
fn wrong_files_are_named_for_their_role() {
    let binary: Vec<u8> = (0..64u8).map(|b| b.wrapping_mul(37) | 0x80).collect();
    let (dir, scene) = temp_file("scene.toml", &binary);
    let output = shadecache([
        "profile",
        "corpus/noise_marble.wgsl",
        "--scene",
        scene.to_str().unwrap(),
        "--out",
        dir.path().join("r").to_str().unwrap(),
    ]);
    let err = stderr(&output);
    assert_eq!(output.status.code(), Some(1), "{err}");
    assert!(err.contains("the scene is not valid UTF-8"), "{err}");
    let weights = dir.path().join("weights.json");
    std::fs::write(&weights, &binary).unwrap();
    let err = fails_cleanly(
        Path::new("corpus/noise_marble.wgsl"),
        &["--weights", weights.to_str().unwrap()],
    );
    assert!(
        err.contains("the cost weights file is not valid UTF-8"),
        "{err}"
    );
    for weight in ["-1", "1e300"] {
        std::fs::write(&weights, format!("{{\"texture_sample\": {weight}}}")).unwrap();
        let err = fails_cleanly(
            Path::new("corpus/noise_marble.wgsl"),
            &["--weights", weights.to_str().unwrap()],
        );
        assert!(err.contains("weights go from 0 to"), "{err}");
        assert!(err.contains("weights.json:1:2"), "{err}");
    }

    let mut bom = b"\xEF\xBB\xBF".to_vec();
    bom.extend(std::fs::read(crate::util::root().join("corpus/noise_marble.wgsl")).unwrap());
    let (_bom_dir, path) = temp_file("bom.wgsl", &bom);
    let output = shadecache(["analyze", path.to_str().unwrap()]);
    assert!(output.status.success(), "{}", stderr(&output));

    let source = format!(
        "@fragment fn f() -> @location(0) vec4<f32> {{\n    let x = {}1.0{};\n    return vec4<f32>(x);\n}}\n",
        "(".repeat(500),
        ")".repeat(500)
    );
    let err = fails_on("nested.wgsl", source.as_bytes());
    assert!(
        err.contains("nests deeper than naga's WGSL parser allows"),
        "{err}"
    );
    assert!(err.contains("nested.wgsl:2:"), "{err}");
}

/// A fragment stage that writes `@builtin(frag_depth)` (an infinite grid
/// placing its lines itself) cannot be cached: the cache tests rasterised
/// depth. `rewrite` and `profile` say so once, at the entry point, with
/// why and what the user can do, before any node is tried: it was one
/// refusal per node and variant (380 on bevy_infinite_grid's grid) and
/// exit 0.
#[test]
fn frag_depth_writer_cached_or_refused_with_reason() {
    let source = "struct View { clip_from_world: mat4x4<f32>, camera_position: vec3<f32> }
@group(0) @binding(0) var<uniform> view: View;
struct Out { @builtin(position) clip: vec4<f32>, @location(0) world: vec3<f32> }
@vertex fn vs(@location(0) p: vec3<f32>) -> Out { return Out(view.clip_from_world * vec4<f32>(p, 1.0), p); }
struct FragOut { @location(0) color: vec4<f32>, @builtin(frag_depth) depth: f32 }
@fragment fn fs(in: Out) -> FragOut {
    let cell = abs(fract(in.world.xz * 4.0) - 0.5);
    let line = smoothstep(0.45, 0.5, max(cell.x, cell.y)) * exp(-length(in.world - view.camera_position) * 0.1);
    let clip = view.clip_from_world * vec4<f32>(in.world, 1.0);
    return FragOut(vec4<f32>(vec3<f32>(line), 1.0), clip.z / clip.w);
}
";
    let (dir, path) = temp_file("grid.wgsl", source.as_bytes());
    let out = dir.path().join("out");
    for command in ["rewrite", "profile"] {
        let mut args = vec![
            command,
            path.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
        ];
        if command == "rewrite" {
            args.push("--all-nodes");
        } else {
            args.push("--quiet");
        }
        let output = shadecache(&args);
        let err = stderr(&output).replace(path.to_str().unwrap(), "grid.wgsl");
        assert_eq!(output.status.code(), Some(1), "{command}: {err}");
        assert_eq!(err.matches("error").count(), 1, "{command}: {err}");
        assert!(!err.contains("refused: node"), "{command}: {err}");
        assert!(
            err.contains(
                "entry point `fs` cannot be cached: the fragment stage writes @builtin(frag_depth)"
            ),
            "{command}: {err}"
        );
        assert!(
            err.contains("profile a copy whose fragment stage returns the colour alone"),
            "{command}: {err}"
        );
        assert!(err.contains("grid.wgsl:6:14"), "{command}: {err}");
        assert!(!out.exists(), "{command}");
    }
}
