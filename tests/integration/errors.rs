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

#[test]
fn two_fragment_entry_points_need_entry() {
    let err = fails_on("two.wgsl", TWO_FRAGMENTS.as_bytes());
    assert!(
        err.contains("2 fragment entry points: `first`, `second`"),
        "{err}"
    );
    assert!(err.contains("--entry"), "{err}");
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
